// SPDX-License-Identifier: Apache-2.0
/// @file stability_report.h
/// @brief What happened numerically in a bake, for the "Stability" section of `sharcbake bake`
/// and the "stability" object of --stats-json: energy the fixed-point accumulation clamped or
/// saturated, NaN/Inf samples dropped, failed inserts and the energy they lost, and whether
/// float32 positions and SHaRC's 17-bit grid coordinates hold at the scene's extent.
/// Every problem found becomes one warning line that says what it costs and what to change.
#pragma once

#include "sharc/sharc_cache.h"
#include "sharc/sharc_update.h"
#include "support/float_spacing.h"
#include "support/json.h"
#include "tracing/scene_reflectance.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace sharcbake {

/// Float32 spacing above this multiple of SHaRC's 1e-4 position bias (beyond ~16k units from
/// the origin) no longer keeps surfaces that lie on voxel boundaries on one side of them
/// (docs/sharc_algorithm.md §10.9); the bias is part of the bit-exact key and cannot follow the scene.
inline constexpr double kPositionBiasWarningFactor = 16.0;
/// A scene fewer than this many voxels of the position bias's distance across
/// (StabilityReport::bias_distance_voxel_size) is warned about: its lookups are mostly refused.
/// A room 4e-5 across is 19 such voxels and renders through its cache as at 4 m; at 4e-6, 1.2.
inline constexpr double kBiasVoxelsAcrossScene = 4.0;

/// Above this share of deposits below one fixed-point step the dim part of the scene is mostly
/// rounding noise (a room lit at 1e-6 beside a 1e12 emitter read 0 in every voxel).
inline constexpr double kSubStepWarningShare = 0.01;

struct StabilityReport {
    // Energy (radiance x weight summed over deposits, all channels).
    uint64_t deposits = 0;
    double deposited_energy = 0.0;     ///< every finite deposit, before any change
    uint64_t clamped_deposits = 0;     ///< single deposits above the fixed-point ceiling
    uint64_t sub_step_deposits = 0;    ///< deposits below one fixed-point step in every channel
    double clamped_energy = 0.0;       ///< removed by that ceiling
    uint64_t saturated_sums = 0;       ///< deposits into a voxel sum already at its ceiling
    uint64_t failed_inserts = 0;       ///< deposits dropped because their bucket was full
    /// Of those, deposits whose key's two 32-bit halves are equal: SHaRC's hash sends every such
    /// key to one bucket, so no capacity holds more than a bucket of them (keyHalvesAreEqual).
    uint64_t failed_inserts_equal_halves = 0;
    double failed_insert_energy = 0.0;
    // Values replaced or dropped.
    uint64_t non_finite_dropped = 0;   ///< NaN/Inf radiance (update pass + commit)
    uint64_t negative_clamped = 0;     ///< negative channel values set to 0
    uint64_t resample_emission_clamped = 0;  ///< cached means below their own emission share
    uint64_t orphan_sums = 0;          ///< radiance without a sample, dropped at resolve
    double radiance_scale = 0.0;       ///< fixed-point units per unit radiance

    // Table.
    uint32_t capacity = 0;
    uint64_t occupied_slots = 0;
    bool capacity_power_of_two = true;

    // Coordinates, for the levels present in the cache.
    double far_corner_distance = 0.0;  ///< largest |coordinate| of the scene bounds
    double largest_side = 0.0;         ///< largest side of the scene bounds (chooses the warnings' advice)
    double float_spacing = 0.0;        ///< float32 spacing (ulp) at that coordinate
    double ray_offset = 0.0;           ///< how far the tracer moves ray origins off a surface there
    uint32_t finest_level = 0;         ///< 0 when the cache is empty
    double finest_voxel_size = 0.0;
    /// The voxel of a lookup at the distance of SHaRC's position bias alone (|(1e-4, 1e-4, 1e-4)|,
    /// 1.7e-4): every key adds the bias before choosing its level, so in a scene much smaller than
    /// that every lookup's level follows that distance, whatever the camera's.
    double bias_distance_voxel_size = 0.0;
    /// Largest |cell index - the grid anchor's| the scene's bounds reach, at any level present.
    int64_t max_grid_coordinate = 0;
    bool grid_coordinates_wrap = false;  ///< beyond the 17-bit signed key field

    // Light transport: how long light stays in the scene (SceneReflectance), -1 when not measured.
    double scene_reflectance = -1.0;

    std::vector<std::string> warnings;

    double share(double energy) const { return deposited_energy > 0.0 ? energy / deposited_energy : 0.0; }
    double precisionShare() const { return finest_voxel_size > 0.0 ? float_spacing / finest_voxel_size : 0.0; }
};

/// Builds the report and its warnings from a finished bake's counters and the scene's bounds.
/// `levels` are the levels present in the cache (levelsPresent()).
StabilityReport makeStabilityReport(const SharcCache& cache, const UpdateCounters& update, glm::vec3 bounds_min,
                                    glm::vec3 bounds_max, const std::vector<uint32_t>& levels);

/// Records the scene's reflectance in the report, with a warning when light stays in the scene
/// for a hundred bounces or more: the cache gains bounces only through its own feedback,
/// iteration after iteration, and reads dark until it has them (a closed room of white walls
/// baked 512 iterations came out 11% dark, "no problems found").
void addSceneReflectance(StabilityReport& report, const SceneReflectance& reflectance);

/// The "Stability" section of the bake summary: one line per group, then each warning.
void printStabilitySection(std::FILE* out, const StabilityReport& report);

/// The "stability" object of --stats-json.
Json stabilityJson(const StabilityReport& report);

}  // namespace sharcbake
