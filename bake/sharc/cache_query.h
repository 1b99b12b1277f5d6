// SPDX-License-Identifier: Apache-2.0
/// @file cache_query.h
/// @brief A baked .sharc cache as a RadianceCache for the path tracer (`render --cache`): SHaRC's
/// Query (docs/sharc_algorithm.md §6) with the application-side eligibility tests of the SDK sample.
#pragma once

#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime.h"
#include "support/sharded_counts.h"
#include "tracing/path_tracer.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
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

/// A baked cache as the path tracer's RadianceCache, keyed with the render camera's position as
/// the LOD centre. Every lookup goes through the runtime library (CacheView), the code engines
/// ship: a file is opened by it, and a cache in memory (the bake's own, measured by its report)
/// is first encoded exactly as the file would be. lookup() is thread-safe; its counters are
/// sharded per thread (ShardedCounts), so counting costs the rendering threads no waiting.
class BakedCache : public RadianceCache {
public:
    /// A cache file opened by the runtime library (`render --cache`).
    BakedCache(CacheView view, glm::vec3 camera_position, CacheLookup mode = CacheLookup::Exact);
    /// A cache in memory, encoded as writeCacheFile would write it and opened from those bytes.
    /// Throws std::invalid_argument with the encoder's or validator's message if it is not a
    /// valid cache.
    BakedCache(const CacheData& data, glm::vec3 camera_position, CacheLookup mode = CacheLookup::Exact);

    /// Moves the LOD centre to another camera and zeroes the counters (not while lookups run).
    void setCamera(glm::vec3 camera_position);

    /// Eligibility tests, then find the key; true (and the voxel's radiance) if it has samples.
    bool lookup(const CacheQuery& query, glm::vec3& radiance) const override;

    /// The key of a surface point (normal facing the incoming ray) with this cache's parameters.
    uint64_t key(glm::vec3 position, glm::vec3 normal) const;
    /// The voxel of `key`, if the cache holds it with samples.
    std::optional<CacheVoxel> find(uint64_t key) const;

    const CacheView& view() const { return view_; }
    /// The cache's grid parameters with the current camera as LOD centre.
    const HashGridParameters& parameters() const { return params_; }

    /// Lookups refused by the eligibility tests, and eligible lookups that found no voxel.
    uint64_t refused() const { return counts_.total(kRefused); }
    uint64_t misses() const { return counts_.total(kMisses); }
    /// Eligible lookups that returned a value (PathTracer counts the same as cache_hits).
    uint64_t hits() const { return counts_.total(kHits); }
    /// Of the hits, those answered from another level than the camera's (CacheLookup::NearestLevel).
    uint64_t nearestLevelHits() const { return counts_.total(kNearestLevelHits); }
    /// The levels the cache holds, ascending.
    const std::vector<uint32_t>& levels() const { return levels_; }

private:
    void setUp(glm::vec3 camera_position);

    std::vector<uint8_t> bytes_;  ///< the encoded cache the view reads (in-memory constructor)
    CacheView view_;
    HashGridParameters params_;
    HashGridKeyer keyer_;  ///< the grid's voxel sizes and level keys, without a logarithm per query
    CacheLookup mode_;
    std::vector<uint32_t> levels_;
    enum Count : size_t { kRefused, kNearestLevelHits, kMisses, kHits };
    mutable ShardedCounts<4> counts_;  ///< added to by every rendering thread at once
};

}  // namespace sharcbake
