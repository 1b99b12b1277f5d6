// SPDX-License-Identifier: Apache-2.0
#include "sharc/cache_query.h"

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

BakedCache::BakedCache(CacheData data, glm::vec3 camera_position, CacheLookup mode)
    : data_(std::move(data)), mode_(mode) {
    params_ = data_.gridParameters();
    params_.camera_position = Float3{camera_position.x, camera_position.y, camera_position.z};
    keyer_ = HashGridKeyer(params_);
    for (const CacheLevel& level : data_.levels) levels_.push_back(level.level);
    if (levels_.empty()) {
        for (const CacheVoxel& v : data_.voxels) levels_.push_back(decodeHashGridKey(v.key).level);
        std::sort(levels_.begin(), levels_.end());
        levels_.erase(std::unique(levels_.begin(), levels_.end()), levels_.end());
    }
    // readCacheFile returns sorted voxels; sort anyway so a hand-built CacheData also works.
    if (!std::is_sorted(data_.voxels.begin(), data_.voxels.end(),
                        [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; })) {
        sortVoxels(data_.voxels);
    }
}

void BakedCache::setCamera(glm::vec3 camera_position) {
    params_.camera_position = Float3{camera_position.x, camera_position.y, camera_position.z};
    refused_ = 0;
    misses_ = 0;
    hits_ = 0;
    nearest_level_hits_ = 0;
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
    if (!v && mode_ == CacheLookup::NearestLevel) {
        // The levels present by distance from the camera's, the finer first on ties.
        const uint32_t wanted = decodeHashGridKey(k).level;
        const Float3 p{query.position.x, query.position.y, query.position.z};
        const Float3 n{query.geometric_normal.x, query.geometric_normal.y, query.geometric_normal.z};
        uint32_t best_distance = UINT32_MAX;
        for (uint32_t level : levels_) {
            const uint32_t distance = level > wanted ? level - wanted : wanted - level;
            if (distance == 0 || distance >= best_distance) continue;
            if (const CacheVoxel* found = find(keyer_.keyAtLevel(p, n, level))) {
                v = found;
                best_distance = distance;
            }
        }
        if (v) nearest_level_hits_.fetch_add(1, std::memory_order_relaxed);
    }
    if (!v) {
        misses_.fetch_add(1, std::memory_order_relaxed);
        return false;
    }
    hits_.fetch_add(1, std::memory_order_relaxed);
    radiance = glm::vec3(v->radiance[0], v->radiance[1], v->radiance[2]);
    return true;
}

}  // namespace sharcbake
