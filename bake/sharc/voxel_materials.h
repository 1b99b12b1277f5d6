// SPDX-License-Identifier: Apache-2.0
/// @file voxel_materials.h
/// @brief Each voxel's mean emission and SHaRC demodulation factor (the cache file's VMAT
/// section): what an engine whose SHaRC build keeps emission apart (SHARC_SEPARATE_EMISSIVE) or
/// demodulates materials (SHARC_MATERIAL_DEMODULATION) needs to read a baked voxel.
///
/// Such an engine reads `stored + emission(hit)` or `stored * factor(hit)`. Storing
/// `(radiance - mean emission) / mean factor` makes those reads average, over the voxel's
/// surface, to the baked radiance; where one material fills the voxel they are exact.
#pragma once

#include "sharcbake/cache_file.h"
#include "sharcbake/scene.h"
#include "tracing/surface.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace sharcbake {

/// The SHaRC sample's demodulation factor of a material at a point (sharcDemodulationFactor of
/// its diffuse albedo and its specular F0, metal and dielectric mixed by metallic).
glm::vec3 demodulationFactor(const ShadingMaterial& material);

struct VoxelMaterialStats {
    uint64_t points = 0;  ///< surface points sampled (each keyed at every level)
    /// Voxels no point landed in (slivers of surface); they take their nearest coarser voxel's
    /// means, or no emission and the scene's mean factor when no coarser voxel has any.
    uint64_t voxels_from_coarser = 0;
    uint64_t voxels_from_scene_mean = 0;
};

/// @brief One VoxelMaterial per voxel of `data` (same order): means, by area, over the surface
/// points that key into the voxel. Points are spread over the scene by area (about
/// `points_per_voxel` per voxel, at most 2^23 in all), keyed on their front side, and on both
/// sides for double-sided materials (the back of a single-sided surface is not meant to be seen);
/// voxels those leave empty then take the backs of single-sided surfaces (without emission, which
/// is one-sided): the inside of a room wound outwards, which its cameras see on the backs.
/// The same scene and cache give the same result for any thread count.
std::vector<CacheVoxelMaterial> computeVoxelMaterials(const Scene& scene, const CacheData& data,
                                                      VoxelMaterialStats* stats = nullptr,
                                                      uint32_t points_per_voxel = 16);

}  // namespace sharcbake
