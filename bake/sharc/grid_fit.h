// SPDX-License-Identifier: Apache-2.0
/// @file grid_fit.h
/// @brief Fitting SHaRC's grid to a scene's units (`--level-bias auto`, the default).
///
/// A SHaRC voxel at camera distance d is about d/S wide (S = scene scale) whatever the units,
/// except near the camera: the level is clamped at 1, so every point closer than
/// b^(2 - level_bias) gets level 1's voxel, b^(1 - level_bias) / S. With the SDK's level bias 0
/// that is 0.04 units for S = 50: a model a few millimetres across (in metres) fits in one voxel,
/// and a room modelled in millimetres has level 1 voxels of 0.04 mm. The units therefore enter
/// only through the level bias. The fit sets it so that level 1, the finest level, has voxels of
/// sqrt(visible surface area / voxel budget): the whole surface at the finest level fits the
/// budget, any camera closer than level 1's distances still asks for level 1, and the same scene
/// in other units gets the same voxels (scaled) and the same level structure.
#pragma once

#include "sharcbake/hash_grid.h"
#include "sharcbake/scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// The default voxel budget: level 1 of the whole visible surface in at most this many voxels
/// (each coarser level adds about a quarter of the level below it).
inline constexpr uint64_t kDefaultVoxelBudget = 1u << 17;

/// The surface a camera can see: triangle area, double-sided triangles counted twice (SHaRC keys
/// the two sides apart). World units squared.
double visibleSurfaceArea(const Scene& scene);

struct GridFit {
    float level_bias = 0.0f;
    float finest_voxel_size = 0.0f;      ///< voxelSize(1) with that bias
    double surface_area = 0.0;           ///< visibleSurfaceArea
    double estimated_voxels = 0.0;       ///< surface_area / finest_voxel_size^2 (flat surfaces)
    bool limited_by_range = false;       ///< the 17-bit grid range forced larger voxels
    std::string reason;                  ///< one line for the bake's output
};

/// Fits `grid.level_bias` (rounded down to 1/64, so voxels are never finer than the budget asks)
/// so that level 1 holds the scene's visible surface in about `voxel_budget` voxels, and never
/// finer than the 17-bit grid allows around the scene's farthest coordinate.
GridFit fitLevelBias(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget);

/// For grid parameters given by hand: warnings (each with the fix) when the scene spans too few
/// voxels at `finest_level` (a coarse, blurry cache) or far more than `voxel_budget`.
std::vector<std::string> checkGridForScene(const Scene& scene, const HashGridParameters& grid, uint32_t finest_level,
                                           uint64_t voxel_budget);

/// For a scene scale given by hand: a warning (with the fix) when it is far from what SHaRC means
/// by it, voxels about distance/S wide. Below 4 a voxel spans a quarter of its distance from the
/// camera and more (a blurry cache; usually an attempt to convert units, which the level bias does);
/// above 4096 voxels are a few thousandths of the distance (a cache far larger than the view needs).
/// Empty when it is sensible.
std::string checkSceneScale(float scene_scale);

}  // namespace sharcbake
