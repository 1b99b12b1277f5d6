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
    /// Share of surface area with no voxel at the finest level the cache holds. A coarser voxel
    /// summed from reached surface nearby covers a point no path reached, so where every
    /// deposit goes to the finest level (the default view region) this is the area no path
    /// reached; with `bake-camera` deposits go to other levels too and it counts more.
    double unreached_finest_area = 0.0;
    uint32_t finest_level = 0;    ///< that level (0: no levels)
    double total_area = 0.0;      ///< world units squared
};

/// Tests `points` surface points, distributed by area (deterministic), on the sides a camera
/// can see (the front; both sides for double-sided materials), at each of `levels` (the cache's,
/// from levelsPresent()).
CoverageReport measureCoverage(const Scene& scene, const SharcCache& cache, const std::vector<uint32_t>& levels,
                               uint32_t points);

}  // namespace sharcbake
