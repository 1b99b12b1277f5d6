// SPDX-License-Identifier: Apache-2.0
/// @file cache_query.h
/// @brief A baked .sharc cache as a RadianceCache for the path tracer (`render --cache`): SHaRC's
/// Query (docs/sharc_algorithm.md §6) with the application-side eligibility tests of the SDK sample.
#pragma once

#include "tracing/path_tracer.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"

#include <glm/glm.hpp>

#include <atomic>
#include <cstdint>
#include <vector>

namespace sharcbake {

/// SHaRC's app-side eligibility of a secondary hit for a cache query (the primary hit is never
/// queried; PathTracer skips it). Both tests must pass:
///  - segment length: t > s * sqrt(3), s the voxel size at the hit's level;
///  - cone footprint: r = min(cone_roughness, 0.99), a = r^2,
///    footprint = t * sqrt(0.5 a^2 / (1 - a^2)) > s.
bool cacheQueryEligible(float segment_length, float cone_roughness, float voxel_size);

/// How a lookup treats a voxel missing at the level the camera's distance picks.
enum class CacheLookup : uint8_t {
    Exact,         ///< SHaRC's query: a miss is a miss (what a GPU runtime with the SDK gets)
    NearestLevel,  ///< then the nearest level the cache holds at the same point (the runtime
                   ///< library's lookupNearestLevel: finer first on ties)
};

/// Read-only view of a baked cache keyed with the render camera's position as the LOD centre.
/// lookup() is thread-safe; its counters are relaxed atomics.
class BakedCache : public RadianceCache {
public:
    /// @param data             the cache (voxels sorted by key, as readCacheFile returns them)
    /// @param camera_position  the render camera's position (the LOD centre of every key)
    BakedCache(CacheData data, glm::vec3 camera_position, CacheLookup mode = CacheLookup::Exact);

    /// Moves the LOD centre to another camera and zeroes the counters (not while lookups run).
    void setCamera(glm::vec3 camera_position);

    /// Eligibility tests, then find the key; true (and the voxel's radiance) if it has samples.
    bool lookup(const CacheQuery& query, glm::vec3& radiance) const override;

    /// The key of a surface point (normal facing the incoming ray) with this cache's parameters.
    uint64_t key(glm::vec3 position, glm::vec3 normal) const;
    /// Binary search of the sorted voxels; nullptr if the key is absent or has no samples.
    const CacheVoxel* find(uint64_t key) const;

    const CacheData& data() const { return data_; }
    const HashGridParameters& parameters() const { return params_; }

    /// Lookups refused by the eligibility tests, and eligible lookups that found no voxel.
    uint64_t refused() const { return refused_.load(std::memory_order_relaxed); }
    uint64_t misses() const { return misses_.load(std::memory_order_relaxed); }
    /// Eligible lookups that returned a value (PathTracer counts the same as cache_hits).
    uint64_t hits() const { return hits_.load(std::memory_order_relaxed); }
    /// Of the hits, those answered from another level than the camera's (CacheLookup::NearestLevel).
    uint64_t nearestLevelHits() const { return nearest_level_hits_.load(std::memory_order_relaxed); }
    /// The levels the cache holds, ascending.
    const std::vector<uint32_t>& levels() const { return levels_; }

private:
    CacheData data_;
    HashGridParameters params_;
    HashGridKeyer keyer_;  ///< params_ without a logarithm per query
    CacheLookup mode_;
    std::vector<uint32_t> levels_;
    mutable std::atomic<uint64_t> refused_{0};
    mutable std::atomic<uint64_t> nearest_level_hits_{0};
    mutable std::atomic<uint64_t> misses_{0};
    mutable std::atomic<uint64_t> hits_{0};
};

}  // namespace sharcbake
