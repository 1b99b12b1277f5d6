// SPDX-License-Identifier: Apache-2.0
/// @file light_leaks.h
/// @brief Emitters that will leak light through the cache: an emissive surface nearer to another
/// surface facing the same way than a voxel is wide. SHaRC averages everything in a voxel with the
/// same normal octant, so the two share voxels and the other surface takes on the emitter's
/// radiance around it (the lamp 1 mm below a ceiling lights the ceiling's voxels beside it).
/// Found from the geometry and the grid before baking, so the artist can move the emitter.
#pragma once

#include "sharcbake/hash_grid.h"
#include "tracing/tracer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// One emissive material whose surface shares voxels with another surface.
struct EmitterLeak {
    uint32_t material = 0;
    std::string material_label;  ///< "material 'Light'", or "material #3" without a name
    /// Share of the material's emissive area (of the points tested) whose voxel, seen from the
    /// nearest camera, also holds a surface behind it facing the same way that shows beside it.
    double area_share = 0.0;
    float median_gap = 0.0f;  ///< median distance to that surface, scene units
    float voxel_size = 0.0f;  ///< median width of those voxels
};

struct LightLeakReport {
    std::vector<EmitterLeak> leaks;  ///< materials at or above kLeakAreaShare, largest share first
    uint32_t emissive_materials = 0;
    uint32_t points = 0;  ///< emitter points tested
    /// One warning line for a leak: which emitter, how near, which voxels, and what to do.
    static std::string describe(const EmitterLeak& leak);
};

/// The camera of `cameras` (not empty) nearest `point`: the one whose voxels there are finest.
glm::vec3 nearestCamera(glm::vec3 point, const std::vector<glm::vec3>& cameras);

/// A material is reported when at least this share of its emissive area leaks.
inline constexpr double kLeakAreaShare = 0.01;

/// Tests `points_per_material` area-spread points of every emissive material (fewer where many
/// materials emit: 65,536 in all, at least 16 each; front side, and
/// the back too where the material is double-sided): a ray from the point into the surface's
/// back finds the nearest surface that is not emissive, seen from a side that light reaches (the
/// front, or either side of a double-sided material), and whose key normal falls in the
/// emitter's octant, within a voxel's width. It leaks when SHaRC gives both points the same key
/// for the nearest of `cameras` (the scene's own views) and that surface shows beside the
/// emitter within the voxel: one voxel holds the emitter and the surface around it (the
/// emitter's edge band). Deterministic; a few tens of microseconds per point.
LightLeakReport findLightLeaks(const Tracer& tracer, const HashGridParameters& grid,
                               const std::vector<glm::vec3>& cameras, uint32_t points_per_material = 256,
                               uint32_t seed = 0);

}  // namespace sharcbake
