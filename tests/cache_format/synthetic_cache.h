// SPDX-License-Identifier: Apache-2.0
// A cache of `live` voxels at random points (camera at the origin), for the query benchmarks of
// the runtime (cache_runtime_bench) and of the whole project (micro_bench). Runtime library only.
#pragma once

#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"

#include <random>
#include <unordered_set>
#include <vector>

namespace sharcbake {

/// Draws points and normals from `random` until `live` distinct keys exist; returns the cache
/// (sorted, radiance 0.5, 4 samples each) and the point and normal of every voxel, in the order
/// drawn.
inline CacheData makeSyntheticCache(size_t live, uint32_t capacity, std::mt19937& random, std::vector<Float3>& points,
                                    std::vector<Float3>& normals) {
    CacheData data;
    data.bake_capacity = capacity;
    const HashGridParameters params = data.gridParameters();  // camera at the origin
    std::uniform_real_distribution<float> coord(-40.0f, 40.0f);
    std::unordered_set<uint64_t> seen;
    points.clear();
    normals.clear();
    while (data.voxels.size() < live) {
        const Float3 p{coord(random), coord(random), coord(random)};
        const Float3 n{coord(random), coord(random), coord(random)};
        const uint64_t key = hashGridKey(p, n, params);
        if (!seen.insert(key).second) continue;
        CacheVoxel v;
        v.key = key;
        v.radiance[0] = v.radiance[1] = v.radiance[2] = 0.5f;
        v.sample_weight = 4.0f;
        data.voxels.push_back(v);
        points.push_back(p);
        normals.push_back(n);
    }
    sortVoxels(data.voxels);
    return data;
}

}  // namespace sharcbake
