// SPDX-License-Identifier: Apache-2.0
/// @file cache_file.h
/// @brief The baked cache as data (what a .sharc file holds) and reading/writing it.
///
/// The byte layout is specified in cache_format/SPEC.md; only cache_file.cpp knows it.
/// No exceptions: every function returns a CacheFileStatus and fills a message.
#pragma once

#include "sharcbake/hash_grid.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {

/// One live voxel: its SHaRC key and the resolved radiance.
struct CacheVoxel {
    uint64_t key = 0;
    float radiance[3] = {0.0f, 0.0f, 0.0f};  ///< mean outgoing radiance, emission included
    float sample_weight = 0.0f;              ///< effective sample count of the resolved mean
};

/// Everything a cache file holds.
struct CacheData {
    /// Grid parameters that feed the key (the camera position is per query, stored as 0).
    float logarithm_base = kHashGridDefaultLogarithmBase;
    float scene_scale = kHashGridDefaultSceneScale;
    float level_bias = kHashGridDefaultLevelBias;
    uint32_t bucket_size = kHashGridBucketSize;
    uint32_t bake_capacity = 0;  ///< table capacity used by the bake (informative)
    /// Voxels sorted by key, keys unique and non-zero.
    std::vector<CacheVoxel> voxels;
    /// Provenance and settings as ordered key/value text (writer, scene, settings, timings).
    std::vector<std::pair<std::string, std::string>> metadata;

    HashGridParameters gridParameters() const;
};

enum class CacheFileStatus : uint32_t {
    kOk = 0,
    kIoError,           ///< the file could not be opened, read, written or renamed
    kBadMagic,          ///< not a sharcbake cache
    kUnsupportedVersion,
    kTruncated,         ///< shorter than its header says
    kCorrupt,           ///< checksum mismatch or a field out of range
    kInvalidData,       ///< (writing) voxels not sorted/unique, or a zero key
};

const char* toString(CacheFileStatus status);

/// Writes `data` to `path` atomically: to a temporary file beside it, then rename.
CacheFileStatus writeCacheFile(const std::string& path, const CacheData& data, std::string* message);

/// Reads and validates a cache file.
CacheFileStatus readCacheFile(const std::string& path, CacheData* data, std::string* message);

/// Sorts voxels by key (the canonical order files store).
void sortVoxels(std::vector<CacheVoxel>& voxels);

}  // namespace sharcbake
