// SPDX-License-Identifier: Apache-2.0
/// @file format.h
/// @brief The .sharc byte layout as constants and plain structs (SPEC.md §F "File layout").
///
/// Only cache_format/ reads or writes these bytes; tools and engines use runtime.h (CacheView)
/// and cache_file.h (CacheData). The structs document the layout and are checked with
/// static_assert; the code reads fields with memcpy at the offsets below, so no struct is ever
/// overlaid on untrusted memory.
#pragma once

#include "sharcbake/runtime_export.h"

#include <cstddef>
#include <cstdint>

namespace sharcbake {

// ------------------------------------------------------------------------------------------------
// Identifier and versions (SPEC §F.2, §F.9)
// ------------------------------------------------------------------------------------------------

/// 16-byte identifier: 0xAB "SHARCBAKE" 0xBB CR LF 0x1A LF 0x00 (KTX/PNG style: the non-ASCII
/// bytes catch 7-bit transfers, CR LF / LF catch line-ending conversion, 0x1A stops DOS `type`).
inline constexpr uint8_t kCacheIdentifier[16] = {0xAB, 'S',  'H',  'A',  'R',  'C',  'B',  'A',
                                                 'K',  'E',  0xBB, '\r', '\n', 0x1A, '\n', 0x00};

/// The bake checkpoint's identifier (SPEC §C.1): "SHARCCKPT" in the same frame, so that a
/// checkpoint is never read as a cache and readers can say what it is.
inline constexpr uint8_t kCheckpointIdentifier[16] = {0xAB, 'S', 'H', 'A', 'R', 'C', 'C', 'K',
                                                      'P',  'T', 0xBB, '\r', '\n', 0x1A, '\n', 0x00};

inline constexpr uint16_t kCacheVersionMajor = 1;  ///< incompatible changes
inline constexpr uint16_t kCacheVersionMinor = 2;  ///< compatible additions (1.1: RSCL, VMAT; 1.2: ANCR)

/// Notable format versions (OpenVDB style), for version-gated reading code.
enum CacheFormatVersion : uint32_t {
    kCacheFormatInterim = 0x0001,  ///< 0.1: "SHRCBAKE" + one CRC; not readable (re-bake)
    kCacheFormat_1_0 = 0x0100,     ///< 1.0: identifier, header, section table, GRID/KEYS/VOXL/LEVL/META
    kCacheFormat_1_1 = 0x0101,     ///< 1.1: RSCL, the radiance scale for GPU buffers (SPEC §F.8a)
    kCacheFormat_1_2 = 0x0102,     ///< 1.2: ANCR, where wrapped grid coordinates decode (SPEC §F.8c)
};

// ------------------------------------------------------------------------------------------------
// Header (SPEC §F.3): 64 bytes at offset 0, identifier included.
// ------------------------------------------------------------------------------------------------

struct CacheFileHeader {
    uint8_t identifier[16];
    uint16_t version_major;
    uint16_t version_minor;
    uint32_t header_size;           ///< 64 in 1.0; a later minor may grow it (multiple of 8)
    uint32_t flags;                 ///< required-feature bits; none defined, must be 0
    uint32_t section_count;         ///< entries in the section table
    uint64_t section_table_offset;  ///< == header_size
    uint64_t file_size;             ///< total bytes of the file
    uint32_t section_entry_size;    ///< 32 in 1.0
    uint32_t reserved0;             ///< 0
    uint32_t reserved1;             ///< 0
    uint32_t header_crc32;  ///< CRC-32 of bytes [0, 60), [64, header_size) and the section table
};
static_assert(sizeof(CacheFileHeader) == 64, "SPEC §F.3: header is 64 bytes");
static_assert(offsetof(CacheFileHeader, version_major) == 16);
static_assert(offsetof(CacheFileHeader, header_size) == 20);
static_assert(offsetof(CacheFileHeader, section_table_offset) == 32);
static_assert(offsetof(CacheFileHeader, file_size) == 40);
static_assert(offsetof(CacheFileHeader, section_entry_size) == 48);
static_assert(offsetof(CacheFileHeader, header_crc32) == 60);

inline constexpr uint32_t kCacheHeaderSize = 64;
inline constexpr uint32_t kCacheHeaderCrcOffset = 60;
inline constexpr uint32_t kCacheMaxSections = 4096;  ///< sanity bound for the table (V7)

// ------------------------------------------------------------------------------------------------
// Section table (SPEC §F.4): section_count entries of 32 bytes right after the header.
// ------------------------------------------------------------------------------------------------

struct CacheSectionEntry {
    uint32_t type;    ///< four ASCII characters, first character in the lowest byte
    uint32_t flags;   ///< bit 0: REQUIRED; other bits 0
    uint64_t offset;  ///< from the start of the file, multiple of 8
    uint64_t length;  ///< bytes of section data (padding excluded)
    uint32_t crc32;   ///< CRC-32 of the section's `length` bytes
    uint32_t reserved;  ///< 0
};
static_assert(sizeof(CacheSectionEntry) == 32, "SPEC §F.4: section entries are 32 bytes");
static_assert(offsetof(CacheSectionEntry, crc32) == 24);

inline constexpr uint32_t kCacheSectionEntrySize = 32;
inline constexpr uint32_t kCacheSectionRequired = 1u;
inline constexpr uint32_t kCacheAlignment = 8;

constexpr uint32_t cacheFourCC(char a, char b, char c, char d) {
    return uint32_t(uint8_t(a)) | uint32_t(uint8_t(b)) << 8 | uint32_t(uint8_t(c)) << 16 |
           uint32_t(uint8_t(d)) << 24;
}
inline constexpr uint32_t kSectionGrid = cacheFourCC('G', 'R', 'I', 'D');
inline constexpr uint32_t kSectionKeys = cacheFourCC('K', 'E', 'Y', 'S');
inline constexpr uint32_t kSectionVoxels = cacheFourCC('V', 'O', 'X', 'L');
inline constexpr uint32_t kSectionLevels = cacheFourCC('L', 'E', 'V', 'L');
inline constexpr uint32_t kSectionMetadata = cacheFourCC('M', 'E', 'T', 'A');
inline constexpr uint32_t kSectionRadianceScale = cacheFourCC('R', 'S', 'C', 'L');  ///< 1.1
inline constexpr uint32_t kSectionVoxelMaterials = cacheFourCC('V', 'M', 'A', 'T');  ///< 1.1
inline constexpr uint32_t kSectionGridAnchor = cacheFourCC('A', 'N', 'C', 'R');      ///< 1.2

// ------------------------------------------------------------------------------------------------
// Sections (SPEC §F.5 - §F.8)
// ------------------------------------------------------------------------------------------------

/// GRID: every parameter that feeds a key or a slot (64 bytes in 1.0).
struct CacheGridSection {
    uint32_t position_bits;  ///< 17
    uint32_t level_bits;     ///< 9
    uint32_t normal_bits;    ///< 3
    uint32_t bucket_size;    ///< 16
    uint32_t hash_function;  ///< kCacheHashJenkins32Xor
    uint32_t lod_policy;     ///< kCacheLodCameraDistance
    float logarithm_base;    ///< b > 1
    float scene_scale;       ///< S > 0
    float level_bias;        ///< beta
    uint32_t bake_capacity;  ///< slots of the baking table (informative, >= 1)
    float position_bias;     ///< 1e-4f
    float normal_bias;       ///< 1e-3f
    uint64_t voxel_count;    ///< entries in KEYS and VOXL
    uint32_t level_count;    ///< entries in LEVL
    uint32_t reserved;       ///< 0
};
static_assert(sizeof(CacheGridSection) == 64, "SPEC §F.5: GRID is 64 bytes");
static_assert(offsetof(CacheGridSection, logarithm_base) == 24);
static_assert(offsetof(CacheGridSection, voxel_count) == 48);

inline constexpr uint32_t kCacheGridSize = 64;
inline constexpr uint32_t kCacheHashJenkins32Xor = 1;   ///< J(lo 32) ^ J(hi 32), SPEC §H.7
inline constexpr uint32_t kCacheLodCameraDistance = 1;  ///< level from camera distance, SPEC §H.3

/// VOXL entry: float32 mean radiance and sample weight (16 bytes; 24 with the key).
struct CacheVoxelRecord {
    float radiance[3];
    float sample_weight;
};
static_assert(sizeof(CacheVoxelRecord) == 16, "SPEC §F.6: voxel records are 16 bytes");

/// LEVL entry: a level present and its voxel count.
struct CacheLevelRecord {
    uint32_t level;
    uint32_t voxel_count;
};
static_assert(sizeof(CacheLevelRecord) == 8, "SPEC §F.7: level records are 8 bytes");

/// RSCL (1.1): the factor GPU buffers apply to the radiance (SPEC §F.8a). Written only when it is
/// not 1, and then REQUIRED: a reader that cannot apply it must not make buffers at the wrong
/// brightness.
struct CacheRadianceScaleSection {
    float radiance_scale;  ///< finite, > 0, != 1
    uint32_t reserved;     ///< 0
};
static_assert(sizeof(CacheRadianceScaleSection) == 8, "SPEC §F.8a: RSCL is 8 bytes");
inline constexpr uint32_t kCacheRadianceScaleSize = 8;

/// VMAT record (1.1), one per voxel in KEYS order (SPEC §F.8b): what SHaRC builds that keep
/// emission or the material apart need to read the voxel.
struct CacheVoxelMaterialRecord {
    float emission[3];      ///< mean emitted radiance of the voxel's surface, >= 0
    float demodulation[3];  ///< mean SHaRC demodulation factor of the voxel's surface, > 0
};
static_assert(sizeof(CacheVoxelMaterialRecord) == 24, "SPEC §F.8b: VMAT records are 24 bytes");
inline constexpr uint32_t kCacheVoxelMaterialRecordSize = 24;

/// ANCR (1.2): the point near which keys decode (SPEC §F.8c, HashGridKeyDecoder). Written only
/// when the scene reaches beyond the 17-bit grid range around the origin; optional, since lookups
/// never decode keys.
struct CacheGridAnchorSection {
    float anchor[3];    ///< finite
    uint32_t reserved;  ///< 0
};
static_assert(sizeof(CacheGridAnchorSection) == 16, "SPEC §F.8c: ANCR is 16 bytes");
inline constexpr uint32_t kCacheGridAnchorSize = 16;

/// @brief CRC-32 (ISO-HDLC / zlib / PNG: reflected polynomial 0xEDB88320, init and xorout
/// 0xFFFFFFFF). Pass the previous result as `crc` to continue over several ranges.
SHARCBAKE_RUNTIME_API uint32_t cacheCrc32(const void* data, size_t size, uint32_t crc = 0);

}  // namespace sharcbake
