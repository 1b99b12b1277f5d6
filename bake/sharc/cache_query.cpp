// SPDX-License-Identifier: Apache-2.0
#include "sharc/cache_query.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
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

BakedCache::BakedCache(CacheView view, glm::vec3 camera_position, CacheLookup mode)
    : view_(std::move(view)), mode_(mode) {
    setUp(camera_position);
}

BakedCache::BakedCache(const CacheData& data, glm::vec3 camera_position, CacheLookup mode) : mode_(mode) {
    std::string message;
    CacheFileStatus status;
    if (std::is_sorted(data.voxels.begin(), data.voxels.end(),
                       [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; })) {
        status = encodeCacheFile(data, &bytes_, &message);
    } else {  // a hand-built CacheData: the file holds voxels sorted by key
        CacheData sorted = data;
        sortVoxels(sorted.voxels);
        status = encodeCacheFile(sorted, &bytes_, &message);
    }
    if (status != CacheFileStatus::kOk) throw std::invalid_argument("cannot encode the cache: " + message);
    CacheError error;
    if (CacheView::openMemory(bytes_.data(), bytes_.size(), &view_, &error) != CacheFileStatus::kOk) {
        throw std::invalid_argument("the encoded cache does not validate: " + error.message);
    }
    setUp(camera_position);
}

void BakedCache::setUp(glm::vec3 camera_position) {
    params_ = view_.gridParameters(Float3{camera_position.x, camera_position.y, camera_position.z});
    keyer_ = HashGridKeyer(params_);
    for (const CacheLevel& level : view_.levels()) levels_.push_back(level.level);
}

void BakedCache::setCamera(glm::vec3 camera_position) {
    params_.camera_position = Float3{camera_position.x, camera_position.y, camera_position.z};
    counts_.reset();
}

uint64_t BakedCache::key(glm::vec3 position, glm::vec3 normal) const {
    return view_.keyFor(Float3{position.x, position.y, position.z}, Float3{normal.x, normal.y, normal.z},
                        params_.camera_position);
}

std::optional<CacheVoxel> BakedCache::find(uint64_t key) const {
    const uint64_t index = view_.findKey(key);
    if (index >= view_.voxelCount()) return std::nullopt;
    const CacheVoxel v = view_.voxel(index);
    if (!(v.sample_weight > 0.0f)) return std::nullopt;
    return v;
}

bool BakedCache::lookup(const CacheQuery& query, glm::vec3& radiance) const {
    const uint64_t k = key(query.position, query.geometric_normal);
    const uint32_t wanted = decodeHashGridKey(k).level;
    if (!cacheQueryEligible(query.segment_length, query.cone_roughness, keyer_.voxelSizeAt(wanted))) {
        counts_.add(kRefused);
        return false;
    }
    std::optional<CacheVoxel> v = find(k);
    if (!v && mode_ == CacheLookup::NearestLevel) {
        // The levels present by distance from the camera's, the finer first on ties.
        const Float3 p{query.position.x, query.position.y, query.position.z};
        const Float3 n{query.geometric_normal.x, query.geometric_normal.y, query.geometric_normal.z};
        uint32_t best_distance = UINT32_MAX;
        for (uint32_t level : levels_) {
            const uint32_t distance = level > wanted ? level - wanted : wanted - level;
            if (distance == 0 || distance >= best_distance) continue;
            if (std::optional<CacheVoxel> found = find(keyer_.keyAtLevel(p, n, level))) {
                v = found;
                best_distance = distance;
            }
        }
        if (v) counts_.add(kNearestLevelHits);
    }
    if (!v) {
        counts_.add(kMisses);
        return false;
    }
    counts_.add(kHits);
    radiance = glm::vec3(v->radiance[0], v->radiance[1], v->radiance[2]);
    return true;
}

}  // namespace sharcbake
