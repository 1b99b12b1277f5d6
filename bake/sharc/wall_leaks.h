// SPDX-License-Identifier: Apache-2.0
/// @file wall_leaks.h
/// @brief Walls thinner than a voxel: surfaces on the two sides of a partition that face the same
/// way (the floors of two rooms) share SHaRC voxels where a voxel spans the partition, and once the
/// roaming camera reaches both sides, lookups on one side read the other side's light (a dim room
/// beside a bright one behind a 0.1 mm wall read 60 times too bright). Found before baking, from
/// the geometry, the grid, the scene's views and the roaming camera's waypoints.
#pragma once

#include "sharcbake/hash_grid.h"
#include "tracing/tracer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

struct WallLeakReport {
    uint32_t points = 0;      ///< surface points tested (both sides of each)
    uint32_t seen_sides = 0;  ///< sides the roaming camera's waypoints see (emitters left out)
    uint32_t leaking_sides = 0;
    /// Of the seen sides, the share whose voxel (from the nearest view) also holds a seen side
    /// beyond an occluder: no free-space point near the voxel sees both.
    double share = 0.0;
    float voxel_size = 0.0f;  ///< median width of those voxels
    /// One warning line, or "" below kWallLeakShare.
    std::string describe() const;
};

/// A scene is warned about when at least this share of the seen surface, and this many sides,
/// leak. Low, because the harm is not the area: the dim side's own lookups spread the light they
/// read (two rooms whose shared strip is 0.5% of their surface, as this check measures it: the
/// dim one 60 times too bright).
inline constexpr double kWallLeakShare = 0.0005;
inline constexpr uint32_t kWallLeakSides = 4;

/// Tests `points` area-spread surface points, each side a waypoint of `waypoints` sees (the
/// nearest few are tried): sides keyed alike from the nearest of `cameras` (the scene's views)
/// and facing alike that no one waypoint sees, that see neither each other nor any common point
/// within 25 voxels
/// sit on two sides of a wall thinner than the voxel. A table leg or a low divider between two
/// floor points does not count (one waypoint sees both, or the space above them does).
/// Deterministic.
WallLeakReport findWallLeaks(const Tracer& tracer, const HashGridParameters& grid,
                             const std::vector<glm::vec3>& cameras, const std::vector<glm::vec3>& waypoints,
                             uint32_t points = 16384, uint32_t seed = 0);

}  // namespace sharcbake
