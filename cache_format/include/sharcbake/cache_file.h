// SPDX-License-Identifier: Apache-2.0
/// @file cache_file.h
/// @brief The baked cache as data (what a .sharc file holds) and reading/writing it.
///
/// The byte layout is specified in cache_format/SPEC.md; only cache_file.cpp knows it.
/// No exceptions: every function returns a CacheFileStatus and fills a message.
#pragma once

#include "sharcbake/cache_types.h"
#include "sharcbake/hash_grid.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {

/// Everything a cache file holds.
struct CacheData {
    /// Grid parameters that feed the key (the camera position is per query, stored as 0).
    float logarithm_base = kHashGridDefaultLogarithmBase;
    float scene_scale = kHashGridDefaultSceneScale;
    float level_bias = kHashGridDefaultLevelBias;
    uint32_t bucket_size = kHashGridBucketSize;
    uint32_t bake_capacity = 0;  ///< table capacity used by the bake (informative)
    /// Factor GPU buffers apply to the radiance by default (SPEC §F.8a, section RSCL): the engine's
    /// SHaRC radiance units per scene unit. Finite, > 0; 1 writes no RSCL section.
    float gpu_radiance_scale = 1.0f;
    /// The point near which keys decode (SPEC §F.8c, section ANCR; HashGridKeyDecoder): the
    /// centre of the scene where it reaches beyond the 17-bit grid range around the origin.
    /// Finite; the origin writes no ANCR section.
    Float3 grid_anchor{0.0f, 0.0f, 0.0f};
    /// Voxels sorted by key, keys unique and non-zero.
    std::vector<CacheVoxel> voxels;
    /// Empty, or one entry per voxel in the same order (SPEC §F.8b, section VMAT): for GPU buffers
    /// of SHaRC builds with separate emissive or material demodulation.
    std::vector<CacheVoxelMaterial> voxel_materials;
    /// Provenance and settings as ordered key/value text (writer, scene, settings, timings).
    /// Keys must be unique and non-empty, keys and values valid UTF-8 (SPEC §F.8).
    std::vector<std::pair<std::string, std::string>> metadata;
    /// Levels present, ascending, with voxel counts. Filled by readCacheFile(); the writer derives
    /// them from the keys and ignores this field.
    std::vector<CacheLevel> levels;
    /// Format version of the file read (readCacheFile); the writer always writes the current one.
    uint16_t version_major = 0;
    uint16_t version_minor = 0;

    HashGridParameters gridParameters() const;
};


/// Where an output named `path` really goes. `target` is `path`, or the file a symbolic link at
/// `path` points to (so the link stays a link and its target is replaced); `temporary` is the
/// per-process file beside `target` that the bytes are written to first. Fails (kIoError, saying
/// what) when `path` is a dangling link or exists and is not a regular file: a device such as
/// /dev/null, a FIFO, a socket or a folder is never replaced. Also removes temporaries of the same
/// naming (`target` + ".tmp-PID") left by processes that no longer run (killed during a write).
CacheFileStatus prepareOutputFile(const std::string& path, std::string* target, std::string* temporary,
                                  std::string* message);

/// Puts a finished `temporary` in place of `target` (both from prepareOutputFile): fsync, the
/// mode of the file it replaces (if any), rename, fsync of the folder. On failure `temporary` is
/// removed and `target` is untouched.
CacheFileStatus commitOutputFile(const std::string& temporary, const std::string& target, std::string* message);

/// prepareOutputFile, every byte of `data` written to the temporary (a short write, e.g. a full
/// disk, fails with kIoError), then commitOutputFile: readers see the old file or the new one,
/// never a part, and nothing of the old file is lost on failure.
CacheFileStatus writeFileAtomically(const std::string& path, const void* data, size_t size, std::string* message);

/// Writes `data` to `path` atomically (temporary file beside it, then rename) in the current
/// format version, then re-opens the file and validates it (SPEC §F.10). Voxels must be sorted by
/// key, unique, non-zero, with finite radiance >= 0 and finite weight > 0 (only live voxels).
CacheFileStatus writeCacheFile(const std::string& path, const CacheData& data, std::string* message);

/// Serialises `data` into `bytes` (what writeCacheFile writes), without touching the disk.
CacheFileStatus encodeCacheFile(const CacheData& data, std::vector<uint8_t>* bytes, std::string* message);

/// Reads and fully validates a cache file (every rule of SPEC §F.10). The message names the
/// violated rule ("V11: ...").
CacheFileStatus readCacheFile(const std::string& path, CacheData* data, std::string* message);

/// Sorts voxels by key (the canonical order files store).
void sortVoxels(std::vector<CacheVoxel>& voxels);

}  // namespace sharcbake
