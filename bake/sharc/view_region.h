// SPDX-License-Identifier: Apache-2.0
/// @file view_region.h
/// @brief Which SHaRC levels the bake fills, so that the cache answers the runtime's cameras.
///
/// SHaRC picks the level of a lookup from the distance between the surface point and the
/// *runtime* camera: level = floor(log_b(distance) + level_bias), at least 1. A bake that fills
/// each point only at the level of its own roaming camera's distance misses every lookup from a
/// camera at another distance. So the bake deposits each path vertex at the finest level that a
/// camera of the declared view region can ask for there (the "deposit level"), and every voxel
/// feeds its coarser voxels in the cache (SharcSettings::coarsest_level): each coarser level
/// accumulates the same samples, with its own history, as if every deposit had been made there
/// too. With a power-of-two logarithm base the levels nest exactly (coarserKey).
///
/// Cache feedback reads the level the roaming camera itself would ask for (feedbackKey), as the
/// SDK does: a voxel of the finest level receives a sample only every few iterations, and light
/// gains a bounce per feedback step, so reading the finest level would slow stiff transport down
/// by that factor.
///
/// The finest level is level 1, and the grid fit (grid_fit.h) sizes level 1 to the voxel budget:
/// a camera closer than level 1's distances still asks for level 1 (SHaRC clamps there), so no
/// camera distance asks for a level finer than the cache holds.
#pragma once

#include "sharcbake/hash_grid.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

struct Scene;

/// Where the runtime's cameras may be when they look the cache up (`--view-region`).
struct ViewRegion {
    enum class Kind : uint8_t {
        FreeSpace,   ///< anywhere in the scene: every point gets every level from level 1 up
        Points,      ///< at given camera positions (the glTF cameras, a camera path's waypoints)
        Box,         ///< anywhere inside an axis-aligned box
        Distance,    ///< anywhere at least `min_distance` from the surfaces it looks up
        BakeCamera,  ///< the SDK's rule: only the roaming bake camera's own level (no coverage)
    };
    Kind kind = Kind::FreeSpace;
    std::vector<glm::vec3> points;  ///< Points
    glm::vec3 box_min{0.0f}, box_max{0.0f};  ///< Box
    float min_distance = 0.0f;      ///< Distance
    float max_distance = 0.0f;      ///< Distance: the farthest a camera looks up (0 = the scene's size)
    std::string source;             ///< what declared it ("glTF cameras", a file name), for describe()

    /// "free space", "3 points (glTF cameras)", "box (x,y,z)-(x,y,z)", "distance >= 2.5", "bake camera".
    std::string describe() const;
};

/// Parses --view-region: "free", "box:x0,y0,z0,x1,y1,z1", "distance:MIN" or "distance:MIN:MAX",
/// "bake-camera". "gltf", "path" and "auto" need the scene's cameras / the path file and are
/// resolved by the caller (gltf and path return Kind::Points with no points and `source` set to
/// "gltf" / "path"; auto returns Kind::FreeSpace with `source` "auto").
/// Throws std::invalid_argument with a message naming the accepted forms.
ViewRegion parseViewRegion(const std::string& text);

/// The region at the scene's glTF cameras (`--view-region gltf`): Kind::Points at their positions,
/// `source` "the glTF cameras".
ViewRegion atGltfCameras(const Scene& scene);

/// The level each path vertex is deposited at, and the levels the written cache covers.
class DepositLevels {
public:
    /// @param grid          the cache's grid parameters (camera position unused)
    /// @param region        where runtime cameras may be
    /// @param bounds_min/max the scene's bounds (the farthest a camera in free space looks)
    DepositLevels(const HashGridParameters& grid, const ViewRegion& region, glm::vec3 bounds_min, glm::vec3 bounds_max);

    /// The key a path vertex deposits into: its position and facing normal at the finest level a
    /// region camera can ask for there (the bake camera's own level for Kind::BakeCamera).
    uint64_t key(glm::vec3 position, glm::vec3 facing_normal, const Float3& bake_camera) const;

    /// The key cache resampling reads at a path vertex: the bake camera's own level (SHaRC's
    /// rule), but no finer than the deposit level and no coarser than coarsestLevel().
    uint64_t feedbackKey(glm::vec3 position, glm::vec3 facing_normal, const Float3& bake_camera) const;

    /// The coarsest level a region camera can ask for anywhere in the scene; the written cache
    /// holds every level from the deposits' up to this one. 0 for Kind::BakeCamera (no coverage
    /// levels are added).
    uint32_t coarsestLevel() const { return coarsest_level_; }
    /// The finest level any deposit can have (1 unless the region keeps cameras away).
    uint32_t finestLevel() const { return finest_level_; }
    const HashGridKeyer& keyer() const { return keyer_; }
    const ViewRegion& region() const { return region_; }

private:
    /// The level for a squared distance (the SDK's rule, precomputed thresholds).
    uint32_t levelOfPoint(const Float3& biased) const;

    ViewRegion region_;
    HashGridKeyer keyer_;
    uint32_t fixed_level_ = 0;  ///< FreeSpace / Distance: one level for every point
    uint32_t finest_level_ = 1;
    uint32_t coarsest_level_ = 0;
};


}  // namespace sharcbake
