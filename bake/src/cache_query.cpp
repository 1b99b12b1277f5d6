// SPDX-License-Identifier: Apache-2.0
#include "cache_query.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace sharcbake {

bool cacheQueryEligible(float segment_length, float cone_roughness, float voxel_size) {
    const float t = segment_length;
    const float s = voxel_size;
    if (!(t > s * std::sqrt(3.0f))) return false;  // also refuses NaN and infinite voxels
    const float r = std::min(std::max(cone_roughness, 0.0f), 0.99f);
    const float a = r * r;
    const float a2 = a * a;
    const float footprint = t * std::sqrt(0.5f * a2 / (1.0f - a2));
    return footprint > s;
}

BakedCache::BakedCache(CacheData data, glm::vec3 camera_position) : data_(std::move(data)) {
    params_ = data_.gridParameters();
    params_.camera_position = Float3{camera_position.x, camera_position.y, camera_position.z};
    keyer_ = HashGridKeyer(params_);
    // readCacheFile returns sorted voxels; sort anyway so a hand-built CacheData also works.
    if (!std::is_sorted(data_.voxels.begin(), data_.voxels.end(),
                        [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; })) {
        sortVoxels(data_.voxels);
    }
}

uint64_t BakedCache::key(glm::vec3 position, glm::vec3 normal) const {
    return keyer_.key(Float3{position.x, position.y, position.z}, Float3{normal.x, normal.y, normal.z},
                      params_.camera_position);
}

const CacheVoxel* BakedCache::find(uint64_t key) const {
    const auto it = std::lower_bound(data_.voxels.begin(), data_.voxels.end(), key,
                                     [](const CacheVoxel& v, uint64_t k) { return v.key < k; });
    if (it == data_.voxels.end() || it->key != key || !(it->sample_weight > 0.0f)) return nullptr;
    return &*it;
}

bool BakedCache::lookup(const CacheQuery& query, glm::vec3& radiance) const {
    const uint64_t k = key(query.position, query.geometric_normal);
    const float s = keyer_.voxelSizeAt(decodeHashGridKey(k).level);
    if (!cacheQueryEligible(query.segment_length, query.cone_roughness, s)) {
        refused_.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    const CacheVoxel* v = find(k);
    if (!v) {
        misses_.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    hits_.fetch_add(1, std::memory_order_relaxed);
    radiance = glm::vec3(v->radiance[0], v->radiance[1], v->radiance[2]);
    return true;
}

}  // namespace sharcbake
