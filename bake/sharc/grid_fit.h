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

#include "sharc/view_region.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/scene.h"
#include "tracing/tracer.h"

#include <glm/glm.hpp>

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

/// The part of the visible surface that cameras at some viewpoints see directly: what a bake whose
/// roaming camera stays there can reach, and what runtime cameras there ask for.
struct SeenSurface {
    double area = 0.0;      ///< world units squared, both sides of double-sided surfaces counted
    double fraction = 1.0;  ///< of visibleSurfaceArea
    /// The sides of double-sided surfaces that no viewpoint sees (the outside of a closed room of
    /// double-sided walls, the underside of a ground plane), world units squared.
    double unseen_double_sided_area = 0.0;
    uint32_t samples = 0;  ///< surface points tested
};

/// Estimates SeenSurface from `samples` points spread over the surface by area: a point's side
/// (each side of a double-sided surface) counts as seen when an unoccluded segment joins it to any
/// viewpoint in front of it; a single-sided point, when either side is (paths shade the back of
/// a single-sided surface too). Deterministic for a seed; parallel over the points.
SeenSurface surfaceSeenFrom(const Tracer& tracer, const std::vector<glm::vec3>& viewpoints, uint32_t samples,
                            uint32_t seed);

/// The fit uses the seen surface instead of the whole visible surface when the viewpoints see
/// less than this share of it (a room beside a large ground plane: 1% or less). Above it the whole
/// surface is the fit, as it always was: a closed room of double-sided walls (Blender's default
/// material) shows its cameras about half of its surface, the inner sides, and a threshold near
/// that share would flip the fit between bakes of similar rooms.
inline constexpr double kFitToSeenBelow = 0.25;

struct GridFit {
    float level_bias = 0.0f;
    float finest_voxel_size = 0.0f;      ///< voxelSize(1) with that bias
    double surface_area = 0.0;           ///< visibleSurfaceArea
    double estimated_voxels = 0.0;       ///< surface_area / finest_voxel_size^2 (flat surfaces)
    bool limited_by_range = false;       ///< the grid's range or float precision forced larger voxels
    /// What limited them: the scene's size against the 17-bit grid range around the anchor, or
    /// float32 precision at its farthest coordinate (voxels at least 20 float steps wide there).
    enum class RangeLimit { kSceneSize, kFloatPrecision } range_limit = RangeLimit::kSceneSize;
    bool fitted_to_seen = false;         ///< surface_area is the part the viewpoints see (SeenSurface)
    /// Sides of double-sided surfaces no viewpoint sees, left out of surface_area (where it is not
    /// fitted to the seen part alone).
    double unseen_sides_left_out = 0.0;
    double scene_surface_area = 0.0;     ///< visibleSurfaceArea, seen or not
    /// The view region keeps its cameras to some places (points, a box, a distance), and each part
    /// of the surface was counted at the level they ask for there, not at level 1.
    bool fitted_to_view_distances = false;
    std::string reason;                  ///< one line for the bake's output
};

/// Where a cache's keys decode (HashGridKeyDecoder; the file's ANCR section): the origin while
/// every point of the scene lies within 90% of 2^16 level-1 voxels of `finest_voxel_size` from it
/// (the file then needs no anchor), else the centre of the scene's bounds, so that a room 10 km
/// from the origin keeps voxels as fine as the same room at the origin.
Float3 gridAnchorFor(const Scene& scene, float finest_voxel_size);

/// Fits `grid.level_bias` (rounded down to 1/64, so voxels are never finer than the budget asks)
/// so that level 1 holds the scene's visible surface in about `voxel_budget` voxels, never finer
/// than the 17-bit grid tells apart across the scene (2^16 voxels each way from its centre) nor
/// than float32 positions resolve at its farthest coordinate (20 float steps). With `seen` below
/// kFitToSeenBelow of that surface, level 1 holds the seen part instead: the roaming camera never
/// reaches the rest, and a 4 m room beside a 10 km ground plane keeps voxels for the room. Above
/// it, the sides of double-sided surfaces `seen` says no viewpoint sees are left out: a closed room
/// of double-sided walls (Blender's default material) gets the voxels of the same room
/// single-sided, not voxels sqrt(2) wider for outer sides no camera reaches.
///
/// With a `region` that keeps the runtime's cameras to some places (the glTF cameras, a path's
/// waypoints, a box, a least distance), each part of the surface is counted at the finest level
/// those cameras ask for there (the level the bake deposits it at), so a house whose cameras stand
/// in its rooms, on a ground two kilometres wide, gets level-1 voxels for its rooms and coarse ones
/// for the far ground, instead of level 1 for all of it in the same budget.
GridFit fitLevelBias(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget,
                     const SeenSurface* seen = nullptr, const ViewRegion* region = nullptr);

/// A camera's lookups need voxels no wider than this fraction of the distance to what it sees: a
/// flat of 4 m rooms whose cameras see their walls a median 1.14 m away, baked with voxels of
/// 0.76 / 0.38 / 0.19 / 0.095 / 0.048 m (`--level-bias` -4.25 to -0.25), renders through the cache
/// with a relative MSE of 1.28 / 0.215 / 0.021 / 0.0079 / 0.0062 in its dimmest room: light leaks
/// through its 10 cm partitions until the voxels are a few times thinner than the room.
constexpr float kDistancePerVoxelAroundCameras = 8.0f;

/// The voxels the typical glTF camera's lookups get at the distance of what it sees (the median
/// distance of rays in 64 directions to what they hit, for the camera with the median such
/// distance), against the widest they may be: that distance / kDistancePerVoxelAroundCameras.
/// `camera` is null where no glTF camera has surfaces around it in most directions (or there is
/// none): nothing to compare.
struct VoxelsAroundCameras {
    const Camera* camera = nullptr;
    float distance = 0.0f;  ///< the median distance to what the camera sees
    float voxel = 0.0f;     ///< the voxel width its lookups at that distance get
    float widest = 0.0f;    ///< distance / kDistancePerVoxelAroundCameras
    bool tooWide() const { return camera && voxel > widest; }
    /// The same camera and distance, with the voxel `grid` gives its lookups there.
    VoxelsAroundCameras on(const HashGridParameters& grid) const;
};
VoxelsAroundCameras voxelsAroundCameras(const Tracer& tracer, const HashGridParameters& grid);

/// A warning (with the fix) when the voxels a glTF camera's lookups get at the distance of what
/// it sees (the median distance of rays in 64 directions to what they hit) are wider than 1/8 of
/// that distance: a house whose rooms the roaming camera can leave for a ground two kilometres wide
/// gets voxels wider than its rooms, and voxels of about a room's size leak light between rooms
/// and around lamps. `fit` is the fit that set `grid`'s level bias (null for a bias given by
/// hand); the fix is the view region and budget, the budget, or the bias that make the voxels
/// fine enough. Empty otherwise.
std::string checkVoxelsAroundCameras(const Tracer& tracer, const HashGridParameters& grid, const ViewRegion& region,
                                     const GridFit* fit, uint64_t voxel_budget, const SeenSurface* seen);

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
