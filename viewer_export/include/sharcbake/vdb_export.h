// SPDX-License-Identifier: Apache-2.0
/// @file vdb_export.h
/// @brief A baked .sharc cache as OpenVDB grids, for vdb_view / vdb_render, Houdini and Blender.
///
/// The cache is read only through the runtime library (CacheView). Grid layout (docs/design.md §4.3):
///
///  * One grid set per SHaRC level present, each with its own transform: a linear transform of
///    voxel size s = voxelSize(level) translated by 0.5·s − 1e-4, so VDB index g (the key's grid
///    coordinate) has its centre at world (g + 0.5)·s − 1e-4, the centre of the points the cache
///    voxel holds: SHaRC quantises p + 1e-4 (its position bias) into [g·s, (g+1)·s). World units
///    are the scene's glTF units (metres, +Y up), times the options' length scale (1 unless asked).
///  * Per level L the grids `levelL_density` (float, luminance of radiance × scale; fog volume),
///    `levelL_color` (Vec3S, radiance × scale), `levelL_radiance` (Vec3S, unscaled mean radiance)
///    and `levelL_samples` (float, effective sample count), as chosen by the channels.
///  * First in the file, always: `density` (float) and `color` (Vec3S), the merged finest level
///    exported. vdb_render renders the first float grid; Blender's importer looks for these names.
///  * Normal octants: SHaRC keeps up to 8 entries per cell and level (one per sign octant of the
///    surface normal). By default they are merged into one VDB voxel: radiance is the
///    sample-weighted mean Σ wᵢ·rᵢ / Σ wᵢ (plain mean when every weight is 0) and samples is
///    Σ wᵢ. With split_normals each octant present gets its own grid set instead, named
///    `levelL_x<s>_y<s>_z<s>_<channel>` with each sign `pos` or `neg`, e.g.
///    `level3_xpos_yneg_zpos_density` (`neg` when that normal component is negative: key normal
///    bit set).
///  * Axes: glTF's +Y up by default; with VdbUpAxis::kZ every transform is turned +90 degrees
///    about X (glTF (x, y, z) is written at (x, -z, y)) for Z-up viewers such as Blender. The
///    file's `sharcbake_up_axis` metadata says which.
///  * Only non-empty grids are written. Every stored cache entry is an active voxel (even a black
///    one); inactive voxels have the background value 0.
#pragma once

#include "sharcbake/runtime.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// The up axis of the written world: glTF's (the default) or a Z-up viewer's.
enum class VdbUpAxis { kY, kZ };

struct VdbExportOptions {
    std::vector<uint32_t> levels;  ///< levels to export; empty = every level present
    bool density = true;           ///< levelL_density
    bool color = true;             ///< levelL_color
    bool radiance = true;          ///< levelL_radiance
    bool samples = true;           ///< levelL_samples
    float scale = 1.0f;            ///< display scale applied to density and color
    bool split_normals = false;    ///< one grid set per normal octant instead of merging
    VdbUpAxis up = VdbUpAxis::kY;  ///< kZ: turn the world +90 degrees about X for Z-up viewers
    /// Every world position and voxel edge is multiplied by this: 1000 writes a model in metres
    /// as millimetres, whose micrometre voxels OpenVDB's transforms refuse in metres.
    double length_scale = 1.0;
    std::string source_path;       ///< recorded in the file metadata
    std::string writer = "sharcbake";  ///< recorded in the file metadata
};

/// One grid written, in file order.
struct VdbGridInfo {
    std::string name;
    uint32_t level = 0;
    int32_t octant = -1;  ///< normal bits 0..7, or -1 when octants are merged
    uint64_t active_voxels = 0;
    float voxel_size = 0.0f;  ///< the level's voxel edge, in scene units
};

enum class VdbExportStatus {
    kOk,
    kInvalidArgument,  ///< the request: a level the cache lacks, a scale or length scale not finite and > 0,
                       ///< a scale beyond float32 for the brightest voxel
    kIoError,
    kUnrepresentable,  ///< a valid cache VDB cannot hold: no voxels, a voxel size out of VDB's range
};

/// @brief Writes the grids of `cache` to `out_path` (.vdb). kInvalidArgument: a requested level
/// is not in the cache, the scale is not finite or takes the brightest voxel beyond float32, or
/// the length scale is not finite and positive;
/// kUnrepresentable: the cache holds no voxels or a voxel size OpenVDB cannot take at the length
/// scale (the message names the levels that fit and a length scale at which all of them do);
/// kIoError: the file could not be written. `grids` (optional) receives what was written;
/// `message` the reason.
VdbExportStatus exportCacheToVdb(const CacheView& cache, const std::string& out_path, const VdbExportOptions& options,
                                 std::vector<VdbGridInfo>* grids, std::string* message);

/// Luminance used for the density grids (Rec. 709 / sRGB primaries).
inline float radianceLuminance(const float rgb[3]) { return 0.2126f * rgb[0] + 0.7152f * rgb[1] + 0.0722f * rgb[2]; }

}  // namespace sharcbake
