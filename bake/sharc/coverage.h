// SPDX-License-Identifier: Apache-2.0
/// @file coverage.h
/// @brief Which surfaces the bake reached: the share of surface area with no cache voxel at
/// any level present in the cache.
#pragma once

#include "sharc/sharc_cache.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/scene.h"

#include <cstdint>
#include <vector>

namespace sharcbake {

/// Levels that occur among the cache's live keys, ascending.
std::vector<uint32_t> levelsPresent(const SharcCache& cache);
/// Levels that occur among a cache file's voxels, ascending.
std::vector<uint32_t> levelsPresent(const CacheData& data);

struct CoverageReport {
    uint32_t points = 0;          ///< surface points tested (area-weighted)
    double unreached_area = 0.0;  ///< share of surface area in [0, 1] with no voxel at any level
    double total_area = 0.0;      ///< world units squared
};

/// Tests `points` surface points, distributed by area (deterministic), on the sides a camera
/// can see (the front; both sides for double-sided materials), at each of `levels` (the cache's,
/// from levelsPresent()).
CoverageReport measureCoverage(const Scene& scene, const SharcCache& cache, const std::vector<uint32_t>& levels,
                               uint32_t points);

}  // namespace sharcbake
