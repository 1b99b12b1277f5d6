// SPDX-License-Identifier: Apache-2.0
/// @file cache_types.h
/// @brief What the runtime library and the writer share: a voxel, a level, and the status every
/// call of both returns.
#pragma once

#include "sharcbake/runtime_export.h"

#include <cmath>
#include <cstdint>

namespace sharcbake {

/// One live voxel: its SHaRC key and the resolved radiance.
struct CacheVoxel {
    uint64_t key = 0;
    float radiance[3] = {0.0f, 0.0f, 0.0f};  ///< mean outgoing radiance, emission included
    float sample_weight = 0.0f;              ///< effective sample count of the resolved mean
};

/// What a SHaRC build that keeps emission or the material apart needs to read a voxel (section
/// VMAT, SPEC §F.8b): means over the voxel's surface, by area.
struct CacheVoxelMaterial {
    float emission[3] = {0.0f, 0.0f, 0.0f};      ///< emitted radiance (included in the radiance)
    float demodulation[3] = {1.0f, 1.0f, 1.0f};  ///< SHaRC demodulation factor (SPEC §G.3)
};

/// SPEC §F.8b's values: emission finite and >= 0, demodulation factor finite and > 0.
inline bool validVoxelMaterial(const CacheVoxelMaterial& m) {
    for (int c = 0; c < 3; ++c) {
        if (!(m.emission[c] >= 0.0f) || !std::isfinite(m.emission[c])) return false;
        if (!(m.demodulation[c] > 0.0f) || !std::isfinite(m.demodulation[c])) return false;
    }
    return true;
}

/// A level present in the cache and how many voxels it holds.
struct CacheLevel {
    uint32_t level = 0;        ///< 1..511
    uint32_t voxel_count = 0;  ///< > 0
};

enum class CacheFileStatus : uint32_t {
    kOk = 0,
    kIoError,           ///< the file could not be opened, read, written or renamed
    kBadMagic,          ///< not a sharcbake cache
    kUnsupportedVersion,
    kTruncated,         ///< shorter than its header says
    kCorrupt,           ///< a field out of range or inconsistent (SPEC validation rule cited)
    kInvalidData,       ///< (writing) voxels not sorted/unique, a zero key, bad values or metadata
    kChecksumMismatch,  ///< a CRC-32 of the header/table or of a section does not match
    kUnsupportedFeature,  ///< an unknown REQUIRED section, header flag, hash function or LOD policy
    kTrailingBytes,     ///< bytes after the end the header declares
    kInvalidArgument,   ///< API misuse (null pointer, capacity 0, ...)
};

SHARCBAKE_RUNTIME_API const char* toString(CacheFileStatus status);

}  // namespace sharcbake
