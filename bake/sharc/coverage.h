// SPDX-License-Identifier: Apache-2.0
/// @file coverage.h
/// @brief Which surfaces the bake reached: the share of surface area with no cache voxel at
/// any level present in the cache.
#pragma once

#include "sharc/sharc_cache.h"
#include "sharc/view_region.h"
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
    /// Share of surface area with no voxel at the level the bake deposits there (DepositLevels):
    /// the area no update path reached, for every view region but `bake-camera`. The same as
    /// unreached_finest_area for the default region; for `gltf`, `path` and `box` a point's
    /// deposits go to the level of its distance to the region, so a surface far from the
    /// cameras has no finest voxel however well it was reached. 0 without `deposit_levels`.
    double unreached_deposit_area = 0.0;
    double total_area = 0.0;      ///< world units squared
};

/// Tests `points` surface points, distributed by area (deterministic), at each of `levels` (the
/// cache's, from levelsPresent()), and with `deposit_levels` at the level the bake deposits there.
/// A point is reached where either of its sides has a voxel: paths shade the back of a
/// single-sided surface too (only its emission is one-sided), so the inside of a room whose
/// single-sided walls face out is reached on their backs.
CoverageReport measureCoverage(const Scene& scene, const SharcCache& cache, const std::vector<uint32_t>& levels,
                               uint32_t points, const DepositLevels* deposit_levels = nullptr);

}  // namespace sharcbake
