// SPDX-License-Identifier: Apache-2.0
// CacheView: opening and validating a .sharc file (SPEC.md §F, rules V1..V21), lookups and GPU
// buffers. Reads every field with memcpy from validated offsets; never trusts a count before
// checking it against the bytes that hold it.
#include "sharcbake/runtime.h"

#include "container.h"
#include "file_bytes.h"
#include "utf8.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>
#include <unordered_set>
#include <new>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__linux__)
#include <sys/mman.h>  // madvise(MADV_HUGEPAGE) for large lookup indexes
#endif

namespace sharcbake {
namespace {

template <typename T> T load(const uint8_t* p) {
    T value;
    std::memcpy(&value, p, sizeof(T));  // little-endian host (checked in openMemory)
    return value;
}

std::string fourccText(uint32_t type) {
    std::string s;
    for (int i = 0; i < 4; ++i) {
        const char c = char((type >> (8 * i)) & 0xFFu);
        if (c >= 0x20 && c < 0x7F) {
            s += c;
        } else {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02X", unsigned(uint8_t(c)));
            s += buf;
        }
    }
    return s;
}

/// A float as "%g" writes it ("1e-40", "50"); std::to_string's fixed notation makes 1e-40 "0.000000".
std::string compactText(float value) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", double(value));
    return buf;
}

CacheFileStatus fail(CacheError* error, CacheFileStatus status, uint32_t rule, const std::string& message) {
    if (error) {
        error->status = status;
        error->rule = rule;
        error->message.clear();
        if (rule) {  // (built step by step: GCC 12 warns falsely (-Wrestrict) on "V" + to_string)
            error->message += 'V';
            error->message += std::to_string(rule);
            error->message += ": ";
        }
        error->message += message;
    }
    return status;
}

bool finiteNonNegative(float v) { return std::isfinite(v) && v >= 0.0f; }

/// The lookup index's slot is (key x multiplier) >> shift. Keys are the file's, so a crafted file
/// can hold keys that all land on one slot under a known multiplier (k0 + i / multiplier), and
/// linear probing then made building the index quadratic: 13 s for a valid 3.8 MB file of 160,000
/// such keys, and lookups as long as the cluster. The build gives up on a multiplier whose probes
/// run long and takes the next; keys that defeat every one keep the binary search.
constexpr uint64_t kIndexMultipliers[] = {
    0x9E3779B97F4A7C15ull,  // 2^64 / golden ratio
    0xBF58476D1CE4E5B9ull,  // splitmix64's two multipliers
    0x94D049BB133111EBull,
    0xD6E8FEB86659FD93ull,  // another odd constant with well-mixed high bits
};
/// Random keys at the index's load (at most 2/3) probe about 2 slots per insertion on average
/// and far fewer than 512 at most, even for millions of keys.
constexpr uint64_t kIndexProbesPerKey = 16;
constexpr uint64_t kIndexLongestProbe = 512;

}  // namespace

// ------------------------------------------------------------------------------------------------
// fp16
// ------------------------------------------------------------------------------------------------

uint16_t floatToHalf(float value) {
    uint32_t x;
    std::memcpy(&x, &value, 4);
    const uint16_t sign = uint16_t((x >> 16) & 0x8000u);
    uint32_t a = x & 0x7FFFFFFFu;
    if (a > 0x7F800000u) return uint16_t(sign | 0x7E00u);  // NaN (quiet)
    if (a >= 0x47800000u) return uint16_t(sign | 0x7C00u);  // >= 65536 (and Inf): Inf
    if (a < 0x38800000u) {                                  // below 2^-14: subnormal or zero
        float f;
        std::memcpy(&f, &a, 4);
        return uint16_t(sign | uint16_t(std::nearbyint(f * 16777216.0f)));  // exact scale, RNE
    }
    const uint32_t odd = (a >> 13) & 1u;
    a += 0xC8000FFFu + odd;  // rebias exponent by -112 and round to nearest even
    return uint16_t(sign | uint16_t(a >> 13));
}

float halfToFloat(uint16_t h) {
    const uint32_t sign = uint32_t(h & 0x8000u) << 16;
    const uint32_t exponent = (h >> 10) & 0x1Fu;
    const uint32_t mantissa = h & 0x3FFu;
    float f;
    if (exponent == 0) {
        f = std::ldexp(float(mantissa), -24);
        uint32_t bits;
        std::memcpy(&bits, &f, 4);
        bits |= sign;
        std::memcpy(&f, &bits, 4);
        return f;
    }
    uint32_t bits = exponent == 31 ? (sign | 0x7F800000u | mantissa << 13)
                                   : (sign | (exponent + 112u) << 23 | mantissa << 13);
    std::memcpy(&f, &bits, 4);
    return f;
}

// ------------------------------------------------------------------------------------------------
// Lifetime
// ------------------------------------------------------------------------------------------------

CacheView::~CacheView() { reset(); }

CacheView::CacheView(CacheView&& other) noexcept { *this = std::move(other); }

CacheView& CacheView::operator=(CacheView&& other) noexcept {
    if (this == &other) return *this;
    reset();
    data_ = other.data_;
    size_ = other.size_;
    owned_ = std::move(other.owned_);  // the buffer (and pointers into it) moves unchanged
    mapping_ = other.mapping_;
    mapping_size_ = other.mapping_size_;
    version_major_ = other.version_major_;
    version_minor_ = other.version_minor_;
    header_size_ = other.header_size_;
    sections_ = std::move(other.sections_);
    logarithm_base_ = other.logarithm_base_;
    scene_scale_ = other.scene_scale_;
    level_bias_ = other.level_bias_;
    bucket_size_ = other.bucket_size_;
    bake_capacity_ = other.bake_capacity_;
    gpu_radiance_scale_ = other.gpu_radiance_scale_;
    grid_anchor_ = other.grid_anchor_;
    voxel_count_ = other.voxel_count_;
    keys_ = other.keys_;
    voxels_ = other.voxels_;
    voxel_materials_ = other.voxel_materials_;
    levels_ = std::move(other.levels_);
    metadata_ = std::move(other.metadata_);
    keyer_ = std::move(other.keyer_);
    index_ = std::move(other.index_);
    index_slots_ = other.index_slots_;
    index_shift_ = other.index_shift_;
    index_multiplier_ = other.index_multiplier_;
    other.data_ = nullptr;
    other.mapping_ = nullptr;
    other.mapping_size_ = 0;
    other.reset();
    return *this;
}

void CacheView::reset() {
    releaseFileMapping(mapping_, mapping_size_);
    mapping_ = nullptr;
    mapping_size_ = 0;
    owned_.clear();
    owned_.shrink_to_fit();
    data_ = nullptr;
    size_ = 0;
    version_major_ = version_minor_ = 0;
    header_size_ = 0;
    sections_.clear();
    // The grid's fields too: a view whose open failed, or that was moved from, reported the
    // previous cache's grid, which an engine reloading a cache could take for the new one's.
    logarithm_base_ = 2.0f;
    scene_scale_ = 50.0f;
    level_bias_ = 0.0f;
    bucket_size_ = kHashGridBucketSize;
    bake_capacity_ = 0;
    gpu_radiance_scale_ = 1.0f;
    grid_anchor_ = Float3{0.0f, 0.0f, 0.0f};
    voxel_count_ = 0;
    keys_ = voxels_ = voxel_materials_ = nullptr;
    levels_.clear();
    metadata_.clear();
    keyer_ = HashGridKeyer();
    index_.reset();
    index_slots_ = 0;
    index_shift_ = 64;
    index_multiplier_ = 0;
}

// ------------------------------------------------------------------------------------------------
// Opening
// ------------------------------------------------------------------------------------------------

CacheFileStatus CacheView::openMemory(const void* data, size_t size, CacheView* out, CacheError* error) {
    if (error) *error = CacheError{};
    if (!out) return fail(error, CacheFileStatus::kInvalidArgument, 0, "openMemory: null output view");
    out->reset();
    if (!data && size > 0) return fail(error, CacheFileStatus::kInvalidArgument, 0, "openMemory: null data");
    if (!hostIsLittleEndian()) {
        return fail(error, CacheFileStatus::kUnsupportedFeature, 0, "big-endian hosts are not supported");
    }
    CacheView view;
    view.data_ = static_cast<const uint8_t*>(data);
    view.size_ = size;
    CacheFileStatus status;
    try {
        status = view.parse(error);
    } catch (const std::bad_alloc&) {
        status = fail(error, CacheFileStatus::kIoError, 0, "out of memory while opening the cache");
    }
    if (status != CacheFileStatus::kOk) return status;
    *out = std::move(view);
    return CacheFileStatus::kOk;
}

CacheFileStatus CacheView::openFile(const std::string& path, CacheView* out, CacheError* error, FileMode mode) {
    if (error) *error = CacheError{};
    if (!out) return fail(error, CacheFileStatus::kInvalidArgument, 0, "openFile: null output view");
    out->reset();
    FileBytes bytes;
    std::string message;
    if (loadFileBytes(path, mode == FileMode::kMap, &bytes, &message) != CacheFileStatus::kOk) {
        return fail(error, CacheFileStatus::kIoError, 0, message);
    }
    CacheView view;
    view.owned_ = std::move(bytes.owned);
    view.mapping_ = bytes.mapping;
    view.mapping_size_ = bytes.mapping_size;
    view.data_ = view.mapping_ ? static_cast<const uint8_t*>(view.mapping_)
                               : (view.owned_.empty() ? nullptr : view.owned_.data());
    view.size_ = bytes.size;
    if (!view.data_) {
        static const uint8_t kEmpty = 0;
        view.data_ = &kEmpty;  // empty file: parse() rejects it (V1)
    }
    if (!hostIsLittleEndian()) {
        return fail(error, CacheFileStatus::kUnsupportedFeature, 0, "big-endian hosts are not supported");
    }
    CacheFileStatus status;
    try {
        status = view.parse(error);
    } catch (const std::bad_alloc&) {
        status = fail(error, CacheFileStatus::kIoError, 0, "out of memory while opening the cache");
    }
    if (status != CacheFileStatus::kOk) {
        if (error) error->message = path + ": " + error->message;
        return status;
    }
    *out = std::move(view);
    return CacheFileStatus::kOk;
}

namespace {

/// V1 - V2: the identifier, naming what the file is when it is not a cache, and a whole header.
CacheFileStatus checkIdentifier(const uint8_t* d, uint64_t size, CacheError* error) {
    using S = CacheFileStatus;
    const size_t id_bytes = size_t(std::min<uint64_t>(size, sizeof kCacheIdentifier));
    // id_bytes == 0 (openMemory(nullptr, 0)): memcmp on a null pointer is UB even for 0 bytes.
    if (id_bytes > 0 && std::memcmp(d, kCacheIdentifier, id_bytes) != 0) {
        if (size >= 8 && std::memcmp(d, "SHRCBAKE", 8) == 0) {
            return fail(error, S::kUnsupportedVersion, 1,
                        "interim format 0.1 (before the versioned layout) is not readable; re-bake the cache");
        }
        if (size >= sizeof kCheckpointIdentifier &&
            std::memcmp(d, kCheckpointIdentifier, sizeof kCheckpointIdentifier) == 0) {
            return fail(error, S::kBadMagic, 1,
                        "a sharcbake bake checkpoint, not a cache: continue the bake with "
                        "'sharcbake bake --resume FILE', which writes the cache");
        }
        return fail(error, S::kBadMagic, 1, "not a sharcbake cache file (identifier mismatch)");
    }
    if (size < kCacheHeaderSize) {
        return fail(error, S::kTruncated, 2,
                    "truncated: " + std::to_string(size) + " bytes, the header alone is " +
                        std::to_string(kCacheHeaderSize));
    }
    return S::kOk;
}

/// V3 - V4: a major version this reader reads, and a declared size equal to the actual one.
CacheFileStatus checkVersionAndSize(const ContainerHeader& header, uint64_t size, CacheError* error) {
    using S = CacheFileStatus;
    if (header.version_major != kCacheVersionMajor) {
        return fail(error, S::kUnsupportedVersion, 3,
                    "format version " + std::to_string(header.version_major) + "." +
                        std::to_string(header.version_minor) + " is not supported (this reader reads " +
                        std::to_string(kCacheVersionMajor) + ".x)");
    }
    if (header.file_size > size) {
        return fail(error, S::kTruncated, 4,
                    "truncated: the header declares " + std::to_string(header.file_size) + " bytes, " +
                        std::to_string(size) + " present");
    }
    if (header.file_size < size) {
        return fail(error, S::kTrailingBytes, 4,
                    std::to_string(size - header.file_size) + " trailing bytes after the declared end (" +
                        std::to_string(header.file_size) + " bytes)");
    }
    return S::kOk;
}

/// V5: header size, and a section table right after the header that fits in the file.
CacheFileStatus checkTableGeometry(const ContainerHeader& header, uint64_t size, CacheError* error) {
    using S = CacheFileStatus;
    if (header.header_size < kCacheHeaderSize || header.header_size % kCacheAlignment != 0 ||
        header.header_size > size || (header.version_minor == 0 && header.header_size != kCacheHeaderSize)) {
        return fail(error, S::kCorrupt, 5, "bad header size " + std::to_string(header.header_size));
    }
    if (header.table_offset != header.header_size || header.entry_size != kCacheSectionEntrySize ||
        header.section_count == 0 || header.section_count > kCacheMaxSections ||
        header.table_offset + uint64_t(header.section_count) * kCacheSectionEntrySize > size) {
        return fail(error, S::kCorrupt, 5,
                    "bad section table (offset " + std::to_string(header.table_offset) + ", " +
                        std::to_string(header.section_count) + " entries of " + std::to_string(header.entry_size) +
                        " bytes)");
    }
    return S::kOk;
}

/// V6 - V7: the header and table checksum, then no unknown flags and zero reserved fields.
CacheFileStatus checkChecksumAndFlags(const uint8_t* d, const ContainerHeader& header, CacheError* error) {
    using S = CacheFileStatus;
    const uint32_t crc = ContainerHeader::computeCrc32(d, header.tableEnd());
    if (crc != header.header_crc32) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "header/section-table checksum mismatch (stored %08X, computed %08X)",
                      header.header_crc32, crc);
        return fail(error, S::kChecksumMismatch, 6, buf);
    }
    if (header.flags != 0) {
        char buf[80];
        std::snprintf(buf, sizeof buf, "unknown required header flags 0x%08X", header.flags);
        return fail(error, S::kUnsupportedFeature, 7, buf);
    }
    if (header.reserved[0] != 0 || header.reserved[1] != 0) {
        return fail(error, S::kCorrupt, 7, "reserved header fields are not zero");
    }
    return S::kOk;
}

}  // namespace

// The numbered steps follow SPEC §F.10; each failure cites its rule.
/// V1 - V7: identifier, header, version, size, table geometry, header checksum, flags.
CacheFileStatus CacheView::parseHeader(CacheError* error, SectionTable* table) {
    using S = CacheFileStatus;
    if (const S status = checkIdentifier(data_, size_, error); status != S::kOk) return status;
    const ContainerHeader header = ContainerHeader::read(data_);
    version_major_ = header.version_major;
    version_minor_ = header.version_minor;
    if (const S status = checkVersionAndSize(header, size_, error); status != S::kOk) return status;
    header_size_ = header.header_size;
    if (const S status = checkTableGeometry(header, size_, error); status != S::kOk) return status;
    *table = SectionTable{header.table_offset, header.section_count, header.tableEnd()};
    return checkChecksumAndFlags(data_, header, error);
}

/// V8 - V11: the sections back to back with zero padding, their checksums and types, the
/// required ones present.
CacheFileStatus CacheView::parseSections(const SectionTable& table, CacheError* error, KnownSections* found) {
    using S = CacheFileStatus;
    const uint8_t* d = data_;
    const uint64_t size = size_;
    *found = KnownSections{};
    const uint64_t table_offset = table.offset;
    const uint32_t section_count = table.count;
    // V8, V9, V10: section entries, layout, checksums, types.
    sections_.clear();
    sections_.reserve(section_count);
    uint64_t expected_offset = align8(table.end);
    const CacheSectionInfo*& grid = found->grid;
    const CacheSectionInfo*& keys = found->keys;
    const CacheSectionInfo*& voxels = found->voxels;
    const CacheSectionInfo*& levels = found->levels;
    const CacheSectionInfo*& meta = found->meta;
    for (uint32_t i = 0; i < section_count; ++i) {
        const ContainerEntry entry = ContainerEntry::read(d, table_offset, i);
        CacheSectionInfo s;
        s.type = entry.type;
        const uint32_t sflags = entry.flags;
        s.offset = entry.offset;
        s.length = entry.length;
        s.crc32 = entry.crc32;
        s.required = (sflags & kCacheSectionRequired) != 0;
        const std::string name = "section " + std::to_string(i) + " (" + fourccText(s.type) + ")";
        if ((sflags & ~kCacheSectionRequired) != 0 || entry.reserved != 0) {
            return fail(error, S::kCorrupt, 8, name + ": unknown flag bits or non-zero reserved field");
        }
        if (s.offset != expected_offset || s.offset > size || s.length > size - s.offset) {
            return fail(error, S::kCorrupt, 8,
                        name + ": offset " + std::to_string(s.offset) + " length " + std::to_string(s.length) +
                            " (expected offset " + std::to_string(expected_offset) + ", file " +
                            std::to_string(size) + " bytes)");
        }
        const uint64_t end = s.offset + s.length;
        expected_offset = align8(end);
        if (expected_offset > size) {
            return fail(error, S::kCorrupt, 8, name + ": padding after the section runs past the end of the file");
        }
        for (uint64_t p = end; p < expected_offset; ++p) {
            if (d[p] != 0) return fail(error, S::kCorrupt, 8, name + ": non-zero padding byte at " + std::to_string(p));
        }
        if (cacheCrc32(d + s.offset, size_t(s.length)) != s.crc32) {
            return fail(error, S::kChecksumMismatch, 9, name + ": checksum mismatch");
        }
        const CacheSectionInfo** slot = nullptr;
        switch (s.type) {
            case kSectionGrid: slot = &grid; break;
            case kSectionKeys: slot = &keys; break;
            case kSectionVoxels: slot = &voxels; break;
            case kSectionLevels: slot = &levels; break;
            case kSectionMetadata: slot = &meta; break;
            case kSectionRadianceScale: slot = &found->radiance_scale; break;
            case kSectionVoxelMaterials: slot = &found->voxel_materials; break;
            case kSectionGridAnchor: slot = &found->grid_anchor; break;
            default: break;
        }
        s.known = slot != nullptr;
        if (!s.known && s.required) {
            return fail(error, S::kUnsupportedFeature, 10, name + ": unknown section marked REQUIRED");
        }
        sections_.push_back(s);
        if (slot) {
            if (*slot) return fail(error, S::kCorrupt, 10, name + ": section type appears twice");
            *slot = &sections_.back();  // reserve() above: pointers stay valid
        }
    }
    if (expected_offset != size) {
        return fail(error, S::kCorrupt, 8,
                    "the last section ends at " + std::to_string(expected_offset) + ", the file at " +
                        std::to_string(size));
    }
    // V11: required sections.
    for (const auto& [section, type] : {std::pair{grid, "GRID"}, std::pair{keys, "KEYS"},
                                        std::pair{voxels, "VOXL"}, std::pair{levels, "LEVL"}}) {
        if (!section) return fail(error, S::kCorrupt, 11, std::string("missing section ") + type);
        if (!section->required) return fail(error, S::kCorrupt, 11, std::string("section ") + type + " not marked REQUIRED");
    }

    return S::kOk;
}

/// V12 - V13: the GRID section's constants and parameters.
CacheFileStatus CacheView::parseGrid(const CacheSectionInfo& grid_section, CacheError* error, uint64_t* voxel_count,
                                     uint32_t* level_count) {
    using S = CacheFileStatus;
    const CacheSectionInfo* grid = &grid_section;
    const uint8_t* d = data_;
    // V12: GRID constants.
    if (grid->length < kCacheGridSize || (version_minor_ == 0 && grid->length != kCacheGridSize)) {
        return fail(error, S::kCorrupt, 12, "GRID: length " + std::to_string(grid->length) + ", expected 64");
    }
    const uint8_t* g = d + grid->offset;
    const uint32_t position_bits = load<uint32_t>(g + 0), level_bits = load<uint32_t>(g + 4),
                   normal_bits = load<uint32_t>(g + 8);
    bucket_size_ = load<uint32_t>(g + 12);
    const uint32_t hash_function = load<uint32_t>(g + 16), lod_policy = load<uint32_t>(g + 20);
    logarithm_base_ = load<float>(g + 24);
    scene_scale_ = load<float>(g + 28);
    level_bias_ = load<float>(g + 32);
    bake_capacity_ = load<uint32_t>(g + 36);
    const float position_bias = load<float>(g + 40), normal_bias = load<float>(g + 44);
    *voxel_count = load<uint64_t>(g + 48);
    *level_count = load<uint32_t>(g + 56);
    if (position_bits != kHashGridPositionBits || level_bits != kHashGridLevelBits ||
        normal_bits != kHashGridNormalBits || position_bias != kHashGridPositionBias ||
        normal_bias != kHashGridNormalBias) {
        return fail(error, S::kUnsupportedFeature, 12,
                    "GRID: key layout " + std::to_string(position_bits) + "/" + std::to_string(level_bits) + "/" +
                        std::to_string(normal_bits) + " bits or biases differ from SHaRC 1.7+ (17/9/3, 1e-4, 1e-3)");
    }
    if (hash_function != kCacheHashJenkins32Xor) {
        return fail(error, S::kUnsupportedFeature, 12, "GRID: unknown hash function " + std::to_string(hash_function));
    }
    if (lod_policy != kCacheLodCameraDistance) {
        return fail(error, S::kUnsupportedFeature, 12, "GRID: unknown LOD policy " + std::to_string(lod_policy));
    }
    if (load<uint32_t>(g + 60) != 0) return fail(error, S::kCorrupt, 12, "GRID: reserved field is not zero");
    // V13: GRID parameters.
    const HashGridStatus grid_status = validateHashGridParameters(gridParameters());
    if (grid_status != HashGridStatus::kOk) {
        return fail(error, S::kCorrupt, 13,
                    std::string("GRID: ") + toString(grid_status) + " (bucket size " + std::to_string(bucket_size_) +
                        ", capacity " + std::to_string(bake_capacity_) + ", log base " + compactText(logarithm_base_) +
                        ", scene scale " + compactText(scene_scale_) + ", level bias " + compactText(level_bias_) +
                        ")");
    }
    return S::kOk;
}

/// V14 - V17: KEYS, VOXL and LEVL agree with the counts, keys ascend, values are finite, the
/// level list matches the keys.
CacheFileStatus CacheView::parseVoxels(const KnownSections& found, uint64_t voxel_count, uint32_t level_count,
                                       CacheError* error) {
    using S = CacheFileStatus;
    const uint8_t* d = data_;
    const uint64_t size = size_;
    const CacheSectionInfo* keys = found.keys;
    const CacheSectionInfo* voxels = found.voxels;
    const CacheSectionInfo* levels = found.levels;
    // V14: section lengths agree with the counts.
    if (voxel_count > size / 24 || keys->length != voxel_count * 8 || voxels->length != voxel_count * 16 ||
        level_count > kHashGridLevelMax || levels->length != uint64_t(level_count) * 8) {
        return fail(error, S::kCorrupt, 14,
                    "section lengths (KEYS " + std::to_string(keys->length) + ", VOXL " +
                        std::to_string(voxels->length) + ", LEVL " + std::to_string(levels->length) +
                        ") do not match " + std::to_string(voxel_count) + " voxels and " +
                        std::to_string(level_count) + " levels");
    }
    voxel_count_ = voxel_count;
    keys_ = d + keys->offset;
    voxels_ = d + voxels->offset;
    // V15: keys.
    std::array<uint64_t, kHashGridLevelMax + 1> per_level{};
    uint64_t previous = 0;
    for (uint64_t i = 0; i < voxel_count; ++i) {
        const uint64_t k = load<uint64_t>(keys_ + i * 8);
        const uint32_t level = uint32_t(k >> kHashGridLevelOffset) & kHashGridLevelMask;
        if (k <= previous || level < kHashGridLevelMin || (k >> kHashGridUserBit) != 0) {
            char buf[120];
            std::snprintf(buf, sizeof buf, "KEYS: key %llu (0x%016llX) is zero, out of order, level 0 or has bit 63 set",
                          (unsigned long long)i, (unsigned long long)k);
            return fail(error, S::kCorrupt, 15, buf);
        }
        previous = k;
        ++per_level[level];
    }
    // V16: voxel values.
    for (uint64_t i = 0; i < voxel_count; ++i) {
        const uint8_t* v = voxels_ + i * 16;
        const float r = load<float>(v), gr = load<float>(v + 4), b = load<float>(v + 8), w = load<float>(v + 12);
        if (!finiteNonNegative(r) || !finiteNonNegative(gr) || !finiteNonNegative(b) || !std::isfinite(w) ||
            !(w > 0.0f)) {
            return fail(error, S::kCorrupt, 16,
                        "VOXL: voxel " + std::to_string(i) + " has non-finite or negative radiance or weight <= 0");
        }
    }
    // V17: levels.
    levels_.clear();
    levels_.reserve(level_count);
    const uint8_t* l = d + levels->offset;
    uint32_t previous_level = 0;
    for (uint32_t i = 0; i < level_count; ++i) {
        CacheLevel level{load<uint32_t>(l + i * 8), load<uint32_t>(l + i * 8 + 4)};
        if (level.level <= previous_level || level.level > kHashGridLevelMax || level.voxel_count == 0 ||
            per_level[level.level] != level.voxel_count) {
            return fail(error, S::kCorrupt, 17,
                        "LEVL: entry " + std::to_string(i) + " (level " + std::to_string(level.level) + ", " +
                            std::to_string(level.voxel_count) + " voxels) is out of order or does not match KEYS");
        }
        previous_level = level.level;
        per_level[level.level] = 0;
        levels_.push_back(level);
    }
    for (uint32_t level = 0; level <= kHashGridLevelMax; ++level) {
        if (per_level[level] != 0) {
            return fail(error, S::kCorrupt, 17, "LEVL: level " + std::to_string(level) + " has keys but is not listed");
        }
    }
    return S::kOk;
}

/// V18: the optional META section.
CacheFileStatus CacheView::parseMetadata(const CacheSectionInfo* meta, CacheError* error) {
    using S = CacheFileStatus;
    const uint8_t* d = data_;
    // V18: metadata.
    metadata_.clear();
    if (meta) {
        const uint8_t* m = d + meta->offset;
        const uint64_t n = meta->length;
        if (n < 8 || load<uint32_t>(m + 4) != 0) {
            return fail(error, S::kCorrupt, 18, "META: missing entry count or non-zero reserved field");
        }
        const uint32_t count = load<uint32_t>(m);
        if (count > n / 8) return fail(error, S::kCorrupt, 18, "META: entry count exceeds the section");
        uint64_t at = 8;
        metadata_.reserve(count);
        std::unordered_set<std::string_view> keys;  // linear, not quadratic, in the entry count
        keys.reserve(count);
        for (uint32_t i = 0; i < count; ++i) {
            if (n - at < 8) return fail(error, S::kCorrupt, 18, "META: entry " + std::to_string(i) + " truncated");
            const uint32_t klen = load<uint32_t>(m + at), vlen = load<uint32_t>(m + at + 4);
            at += 8;
            if (klen == 0 || klen > n - at || vlen > n - at - klen) {
                return fail(error, S::kCorrupt, 18, "META: entry " + std::to_string(i) + " has a bad length");
            }
            if (!isValidUtf8(m + at, klen) || !isValidUtf8(m + at + klen, vlen)) {
                return fail(error, S::kCorrupt, 18, "META: entry " + std::to_string(i) + " is not valid UTF-8");
            }
            std::string_view key(reinterpret_cast<const char*>(m + at), klen);
            std::string_view value(reinterpret_cast<const char*>(m + at + klen), vlen);
            at += uint64_t(klen) + vlen;
            if (!keys.insert(key).second) {
                return fail(error, S::kCorrupt, 18, "META: duplicate key \"" + std::string(key) + "\"");
            }
            metadata_.emplace_back(key, value);
        }
        if (at != n) return fail(error, S::kCorrupt, 18, "META: bytes after the last entry");
    }
    return S::kOk;
}

/// V19: the optional RSCL section (format 1.1).
CacheFileStatus CacheView::parseRadianceScale(const CacheSectionInfo* section, CacheError* error) {
    gpu_radiance_scale_ = 1.0f;
    if (!section) return CacheFileStatus::kOk;
    if (section->length < kCacheRadianceScaleSize ||
        (version_minor_ <= 1 && section->length != kCacheRadianceScaleSize)) {
        return fail(error, CacheFileStatus::kCorrupt, 19,
                    "RSCL: length " + std::to_string(section->length) + ", expected 8");
    }
    if (!section->required) return fail(error, CacheFileStatus::kCorrupt, 19, "RSCL: not marked REQUIRED");
    const float scale = load<float>(data_ + section->offset);
    if (!std::isfinite(scale) || !(scale > 0.0f) || load<uint32_t>(data_ + section->offset + 4) != 0) {
        return fail(error, CacheFileStatus::kCorrupt, 19,
                    "RSCL: the radiance scale must be finite and > 0 and the reserved field 0");
    }
    gpu_radiance_scale_ = scale;
    return CacheFileStatus::kOk;
}

/// V20: the optional VMAT section (format 1.1): one record per voxel, valid values.
CacheFileStatus CacheView::parseVoxelMaterials(const CacheSectionInfo* section, CacheError* error) {
    voxel_materials_ = nullptr;
    if (!section) return CacheFileStatus::kOk;
    if (section->length != voxel_count_ * kCacheVoxelMaterialRecordSize) {
        return fail(error, CacheFileStatus::kCorrupt, 20,
                    "VMAT: length " + std::to_string(section->length) + ", expected " +
                        std::to_string(voxel_count_ * kCacheVoxelMaterialRecordSize) + " (24 bytes per voxel)");
    }
    const uint8_t* records = data_ + section->offset;
    for (uint64_t i = 0; i < voxel_count_; ++i) {
        CacheVoxelMaterial m;
        std::memcpy(&m, records + i * kCacheVoxelMaterialRecordSize, kCacheVoxelMaterialRecordSize);
        if (!validVoxelMaterial(m)) {
            return fail(error, CacheFileStatus::kCorrupt, 20,
                        "VMAT: voxel " + std::to_string(i) +
                            ": emission must be finite and >= 0, the demodulation factor finite and > 0");
        }
    }
    voxel_materials_ = records;
    return CacheFileStatus::kOk;
}

/// V21: the optional ANCR section (format 1.2): a finite anchor.
CacheFileStatus CacheView::parseGridAnchor(const CacheSectionInfo* section, CacheError* error) {
    grid_anchor_ = Float3{0.0f, 0.0f, 0.0f};
    if (!section) return CacheFileStatus::kOk;
    if (section->length < kCacheGridAnchorSize || (version_minor_ <= 2 && section->length != kCacheGridAnchorSize)) {
        return fail(error, CacheFileStatus::kCorrupt, 21,
                    "ANCR: length " + std::to_string(section->length) + ", expected 16");
    }
    const Float3 anchor{load<float>(data_ + section->offset), load<float>(data_ + section->offset + 4),
                        load<float>(data_ + section->offset + 8)};
    if (!std::isfinite(anchor.x) || !std::isfinite(anchor.y) || !std::isfinite(anchor.z) ||
        load<uint32_t>(data_ + section->offset + 12) != 0) {
        return fail(error, CacheFileStatus::kCorrupt, 21, "ANCR: the anchor must be finite and the reserved field 0");
    }
    grid_anchor_ = anchor;
    return CacheFileStatus::kOk;
}

/// Validates the whole file, rule by rule in SPEC §F.10's order (V1 - V21), and fills the view.
CacheFileStatus CacheView::parse(CacheError* error) {
    SectionTable table;
    KnownSections found;
    uint64_t voxel_count = 0;
    uint32_t level_count = 0;
    CacheFileStatus status = parseHeader(error, &table);
    if (status == CacheFileStatus::kOk) status = parseSections(table, error, &found);
    if (status == CacheFileStatus::kOk) status = parseGrid(*found.grid, error, &voxel_count, &level_count);
    if (status == CacheFileStatus::kOk) status = parseVoxels(found, voxel_count, level_count, error);
    if (status == CacheFileStatus::kOk) status = parseMetadata(found.meta, error);
    if (status == CacheFileStatus::kOk) status = parseRadianceScale(found.radiance_scale, error);
    if (status == CacheFileStatus::kOk) status = parseVoxelMaterials(found.voxel_materials, error);
    if (status == CacheFileStatus::kOk) status = parseGridAnchor(found.grid_anchor, error);
    if (status != CacheFileStatus::kOk) return status;
    // Query acceleration (not validation): voxel sizes and level thresholds.
    keyer_ = HashGridKeyer(gridParameters());
    return CacheFileStatus::kOk;
}

// ------------------------------------------------------------------------------------------------
// Accessors
// ------------------------------------------------------------------------------------------------

HashGridParameters CacheView::gridParameters(const Float3& camera_position) const {
    HashGridParameters p;
    p.camera_position = camera_position;
    p.logarithm_base = logarithm_base_;
    p.scene_scale = scene_scale_;
    p.level_bias = level_bias_;
    p.capacity = bake_capacity_;
    p.bucket_size = bucket_size_;
    return p;
}

uint64_t CacheView::key(uint64_t index) const { return load<uint64_t>(keys_ + index * 8); }

CacheVoxelMaterial CacheView::voxelMaterial(uint64_t index) const {
    CacheVoxelMaterial m;
    if (voxel_materials_) std::memcpy(&m, voxel_materials_ + index * kCacheVoxelMaterialRecordSize, sizeof m);
    return m;
}

CacheVoxel CacheView::voxel(uint64_t index) const {
    CacheVoxel v;
    v.key = key(index);
    std::memcpy(v.radiance, voxels_ + index * 16, 12);
    v.sample_weight = load<float>(voxels_ + index * 16 + 12);
    return v;
}

void CacheView::FreeDeleter::operator()(IndexSlot* p) const { std::free(p); }

CacheFileStatus CacheView::buildLookupIndex() {
    if (!data_ || voxel_count_ >= 0xFFFFFFFFu) return CacheFileStatus::kInvalidArgument;
    index_.reset();
    index_slots_ = 0;
    uint32_t bits = 4;
    while ((uint64_t(1) << bits) < voxel_count_ + voxel_count_ / 2 && bits < 40) ++bits;  // load <= 2/3
    const size_t slots = size_t(1) << bits;
    // Random lookups into tens of MiB miss the TLB as well as the caches: large tables go on
    // 2 MiB-aligned memory and ask Linux for transparent huge pages (advice only).
    constexpr size_t kHugePage = size_t(2) << 20;
    const size_t bytes = slots * sizeof(IndexSlot);
    const size_t alignment = bytes >= kHugePage ? kHugePage : 64;
    const size_t rounded = (bytes + alignment - 1) / alignment * alignment;
    void* memory = std::aligned_alloc(alignment, rounded);
    if (!memory) return CacheFileStatus::kIoError;
#ifdef MADV_HUGEPAGE
    if (alignment == kHugePage) ::madvise(memory, rounded, MADV_HUGEPAGE);
#endif
    std::unique_ptr<IndexSlot[], FreeDeleter> table(static_cast<IndexSlot*>(memory));
    const uint32_t shift = 64 - bits;
    const size_t mask = slots - 1;
    // Linear in the voxels whatever the keys: each multiplier gets a bounded number of probes.
    const auto fill = [&](uint64_t multiplier) {
        std::memset(table.get(), 0, rounded);
        uint64_t probes = 0;
        for (uint64_t i = 0; i < voxel_count_; ++i) {
            const uint64_t k = key(i);
            size_t slot = size_t((k * multiplier) >> shift);
            for (uint64_t run = 0; table[slot].key != 0; ++run) {
                if (run == kIndexLongestProbe || ++probes > kIndexProbesPerKey * voxel_count_) return false;
                slot = (slot + 1) & mask;
            }
            IndexSlot& s = table[slot];
            s.key = k;
            std::memcpy(s.radiance, voxels_ + i * 16, 12);
            s.voxel = uint32_t(i);  // voxel_count <= file size / 24 < 2^32 - 1 for files < 96 GiB
        }
        return true;
    };
    for (const uint64_t multiplier : kIndexMultipliers) {
        if (!fill(multiplier)) continue;
        index_ = std::move(table);
        index_slots_ = slots;
        index_shift_ = shift;
        index_multiplier_ = multiplier;
        return CacheFileStatus::kOk;
    }
    return CacheFileStatus::kOk;  // keys crafted to collide: lookups keep the binary search
}

const CacheView::IndexSlot* CacheView::findSlot(uint64_t k) const {
    // Linear probing ends at the key or at an empty slot; the load factor (<= 2/3) keeps one.
    const size_t mask = index_slots_ - 1;
    for (size_t slot = homeSlot(k);; slot = (slot + 1) & mask) {
        const IndexSlot& s = index_[slot];
        if (s.key == k) return &s;
        if (s.key == 0) return nullptr;
    }
}

uint64_t CacheView::keyFor(const Float3& p, const Float3& n, const Float3& c) const {
    return keyer_.key(p, n, c);
}

void CacheView::keysFor(size_t count, const Float3* positions, const Float3* normals, const Float3& c,
                        uint64_t* keys) const {
    size_t i = 0;
#if defined(__SSE2__)
    // SPEC §H.2 - §H.6 on four points per step. Every SSE operation below is the IEEE binary32
    // operation keyFor() performs, lane by lane and in the same order, so the keys are the same.
    {
        const __m128 bias = _mm_set1_ps(kHashGridPositionBias);
        const __m128 min_distance2 = _mm_set1_ps(kHashGridMinDistance2);
        const __m128 normal_bias = _mm_set1_ps(kHashGridNormalBias);
        const __m128 zero = _mm_setzero_ps();
        const __m128 two31 = _mm_set1_ps(2147483648.0f);
        const __m128 minus_two31 = _mm_set1_ps(-2147483648.0f);
        const __m128i int_max = _mm_set1_epi32(INT32_MAX);
        const __m128i int_min = _mm_set1_epi32(INT32_MIN);
        // floor(q), then saturation to int32 with NaN -> 0 (floorToInt32 in hash_grid.cpp).
        auto floorToInt = [&](__m128 q) {
            __m128i t = _mm_cvttps_epi32(q);  // truncation; out of range or NaN gives INT32_MIN
            t = _mm_add_epi32(t, _mm_castps_si128(_mm_cmpgt_ps(_mm_cvtepi32_ps(t), q)));  // -1 below
            const __m128i high = _mm_castps_si128(_mm_cmpge_ps(q, two31));
            const __m128i low = _mm_castps_si128(_mm_cmple_ps(q, minus_two31));
            const __m128i nan = _mm_castps_si128(_mm_cmpunord_ps(q, q));
            t = _mm_or_si128(_mm_andnot_si128(high, t), _mm_and_si128(high, int_max));
            t = _mm_or_si128(_mm_andnot_si128(low, t), _mm_and_si128(low, int_min));
            return _mm_andnot_si128(nan, t);
        };
        for (; i + 4 <= count; i += 4) {
            const Float3* p = positions + i;
            const Float3* n = normals + i;
            const __m128 bx = _mm_add_ps(_mm_setr_ps(p[0].x, p[1].x, p[2].x, p[3].x), bias);
            const __m128 by = _mm_add_ps(_mm_setr_ps(p[0].y, p[1].y, p[2].y, p[3].y), bias);
            const __m128 bz = _mm_add_ps(_mm_setr_ps(p[0].z, p[1].z, p[2].z, p[3].z), bias);
            const __m128 dx = _mm_sub_ps(_mm_set1_ps(c.x), bx);
            const __m128 dy = _mm_sub_ps(_mm_set1_ps(c.y), by);
            const __m128 dz = _mm_sub_ps(_mm_set1_ps(c.z), bz);
            __m128 d2 = _mm_mul_ps(dx, dx);
            d2 = _mm_add_ps(d2, _mm_mul_ps(dy, dy));
            d2 = _mm_add_ps(d2, _mm_mul_ps(dz, dz));
            const __m128 keep = _mm_cmpge_ps(d2, min_distance2);  // false for NaN
            d2 = _mm_or_ps(_mm_and_ps(keep, d2), _mm_andnot_ps(keep, min_distance2));
            alignas(16) float distance2[4], size[4];
            alignas(16) int32_t gx[4], gy[4], gz[4];
            uint32_t level[4];
            _mm_store_ps(distance2, d2);
            for (int j = 0; j < 4; ++j) {
                level[j] = keyer_.levelOf(distance2[j]);
                size[j] = keyer_.voxelSizeAt(level[j]);
            }
            const __m128 s = _mm_load_ps(size);
            _mm_store_si128(reinterpret_cast<__m128i*>(gx), floorToInt(_mm_div_ps(bx, s)));
            _mm_store_si128(reinterpret_cast<__m128i*>(gy), floorToInt(_mm_div_ps(by, s)));
            _mm_store_si128(reinterpret_cast<__m128i*>(gz), floorToInt(_mm_div_ps(bz, s)));
            // Normal bit set unless (n + 1e-3) >= 0 (so NaN sets it).
            auto negative = [&](__m128 v) {
                return ~unsigned(_mm_movemask_ps(_mm_cmpge_ps(_mm_add_ps(v, normal_bias), zero)));
            };
            const unsigned nx = negative(_mm_setr_ps(n[0].x, n[1].x, n[2].x, n[3].x));
            const unsigned ny = negative(_mm_setr_ps(n[0].y, n[1].y, n[2].y, n[3].y));
            const unsigned nz = negative(_mm_setr_ps(n[0].z, n[1].z, n[2].z, n[3].z));
            for (int j = 0; j < 4; ++j) {
                const uint32_t bits = ((nx >> j) & 1u) | ((ny >> j) & 1u) << 1 | ((nz >> j) & 1u) << 2;
                keys[i + size_t(j)] = packHashGridKey(Int3{gx[j], gy[j], gz[j]}, level[j], bits);
            }
        }
    }
#endif
    for (; i < count; ++i) keys[i] = keyFor(positions[i], normals[i], c);
}

uint64_t CacheView::findKey(uint64_t k) const {
    if (index_slots_ != 0) {
        const IndexSlot* s = findSlot(k);
        return s ? s->voxel : voxel_count_;
    }
    uint64_t lo = 0, n = voxel_count_;
    while (n > 0) {  // lower_bound, branch-light
        const uint64_t half = n / 2;
        if (load<uint64_t>(keys_ + (lo + half) * 8) < k) {
            lo += half + 1;
            n -= half + 1;
        } else {
            n = half;
        }
    }
    return (lo < voxel_count_ && load<uint64_t>(keys_ + lo * 8) == k) ? lo : voxel_count_;
}

std::string_view CacheView::metadata(std::string_view k, bool* found) const {
    for (const auto& kv : metadata_) {
        if (kv.first == k) {
            if (found) *found = true;
            return kv.second;
        }
    }
    if (found) *found = false;
    return {};
}

CacheStats CacheView::stats() const {
    CacheStats s;
    s.voxels = voxel_count_;
    s.levels = uint32_t(levels_.size());
    if (voxel_count_ == 0) return s;
    s.bytes_per_voxel = double(size_) / double(voxel_count_);
    for (int c = 0; c < 3; ++c) {
        s.radiance_min[c] = INFINITY;
        s.radiance_max[c] = 0.0f;
    }
    s.weight_min = INFINITY;
    for (uint64_t i = 0; i < voxel_count_; ++i) {
        const CacheVoxel v = voxel(i);
        for (int c = 0; c < 3; ++c) {
            s.radiance_min[c] = std::min(s.radiance_min[c], v.radiance[c]);
            s.radiance_max[c] = std::max(s.radiance_max[c], v.radiance[c]);
            s.radiance_mean[c] += v.radiance[c];
        }
        s.weight_min = std::min(s.weight_min, v.sample_weight);
        s.weight_max = std::max(s.weight_max, v.sample_weight);
        s.weight_total += v.sample_weight;
    }
    for (double& m : s.radiance_mean) m /= double(voxel_count_);
    return s;
}

// ------------------------------------------------------------------------------------------------
// Lookups
// ------------------------------------------------------------------------------------------------

bool CacheView::lookup(const Float3& position, const Float3& normal, const Float3& camera_position,
                       Float3* radiance) const {
    if (!data_) return false;
    const uint64_t k = keyFor(position, normal, camera_position);
    if (index_slots_ != 0) {
        const IndexSlot* s = findSlot(k);
        if (s && radiance) std::memcpy(radiance, s->radiance, 12);
        return s != nullptr;
    }
    const uint64_t index = findKey(k);
    if (index == voxel_count_) return false;
    if (radiance) std::memcpy(radiance, voxels_ + index * 16, 12);
    return true;
}

bool CacheView::lookupNearestLevel(const Float3& position, const Float3& normal, const Float3& camera_position,
                                   Float3* radiance, uint32_t* level_used) const {
    if (!data_ || levels_.empty()) return false;
    const HashGridParameters params = gridParameters(camera_position);
    // SPEC §H.2 steps 1-2: biased position, level from the camera.
    const Float3 biased{position.x + kHashGridPositionBias, position.y + kHashGridPositionBias,
                        position.z + kHashGridPositionBias};
    const uint32_t wanted = gridLevel(biased, params);
    const uint32_t bits = normalBits(normal);
    // Levels present, nearest first: walk outwards from the insertion point (finer on ties).
    const auto it = std::lower_bound(levels_.begin(), levels_.end(), wanted,
                                     [](const CacheLevel& l, uint32_t v) { return l.level < v; });
    ptrdiff_t up = it - levels_.begin();  // first level >= wanted
    ptrdiff_t down = up - 1;              // last level < wanted
    const ptrdiff_t n = ptrdiff_t(levels_.size());
    while (down >= 0 || up < n) {
        ptrdiff_t pick;
        if (up >= n) {
            pick = down--;
        } else if (down < 0) {
            pick = up++;
        } else if (levels_[size_t(up)].level - wanted < wanted - levels_[size_t(down)].level) {
            pick = up++;
        } else {
            pick = down--;  // finer level on ties
        }
        const uint32_t level = levels_[size_t(pick)].level;
        const Int3 grid = quantisePosition(biased, keyer_.voxelSizeAt(level));
        const uint64_t index = findKey(packHashGridKey(grid, level, bits));
        if (index != voxel_count_) {
            if (radiance) std::memcpy(radiance, voxels_ + index * 16, 12);
            if (level_used) *level_used = level;
            return true;
        }
    }
    return false;
}

size_t CacheView::lookupBatch(size_t count, const Float3* positions, const Float3* normals,
                              const Float3& camera_position, Float3* radiance, uint8_t* hits,
                              bool nearest_level) const {
    if (!positions || !normals || !radiance) return 0;
    size_t hit_count = 0;
    if (!nearest_level && index_slots_ != 0) {
        // Software-pipelined exact lookups: the keys of the next block of queries are computed
        // (keysFor, SIMD) and the cache lines of their home slots prefetched before the current
        // block is probed, so a block's misses are in flight while the other block works.
        // A hit reads only the index, never the file.
        constexpr size_t kBlock = 16;
        uint64_t block_keys[2][kBlock];
        auto prepare = [&](size_t start, uint64_t* keys) {
            const size_t n = std::min(kBlock, count - start);
            keysFor(n, positions + start, normals + start, camera_position, keys);
            for (size_t j = 0; j < n; ++j) {
                const uintptr_t home = reinterpret_cast<uintptr_t>(&index_[homeSlot(keys[j])]);
                __builtin_prefetch(reinterpret_cast<const void*>(home));
                if ((home & 63u) + sizeof(IndexSlot) > 64u) {
                    __builtin_prefetch(reinterpret_cast<const void*>(home + sizeof(IndexSlot) - 1));
                }
            }
        };
        if (count > 0) prepare(0, block_keys[0]);
        for (size_t i = 0; i < count; ++i) {
            const size_t block = (i / kBlock) & 1u;
            if (i % kBlock == 0 && i + kBlock < count) prepare(i + kBlock, block_keys[block ^ 1u]);
            const uint64_t k = block_keys[block][i % kBlock];
            const IndexSlot* s = findSlot(k);
            const bool hit = s != nullptr;
            Float3 value{0.0f, 0.0f, 0.0f};
            if (hit) std::memcpy(&value, s->radiance, 12);
            radiance[i] = value;
            if (hits) hits[i] = hit ? 1 : 0;
            hit_count += hit ? 1 : 0;
        }
        return hit_count;
    }
    for (size_t i = 0; i < count; ++i) {
        Float3 value{0.0f, 0.0f, 0.0f};
        const bool hit = nearest_level ? lookupNearestLevel(positions[i], normals[i], camera_position, &value)
                                       : lookup(positions[i], normals[i], camera_position, &value);
        radiance[i] = value;
        if (hits) hits[i] = hit ? 1 : 0;
        hit_count += hit ? 1 : 0;
    }
    return hit_count;
}

// ------------------------------------------------------------------------------------------------
// GPU buffers
// ------------------------------------------------------------------------------------------------

namespace {

/// What gpuBuffers() and gpuInsertList() share: the checked options and the packing of a voxel
/// into the SDK's resolved entry (SPEC §G.4, §G.6).
/// The share of the cache's light (its channels' values summed) that may be stored as 0 in fp16
/// without a warning.
constexpr double kFlushedLightShareWarned = 0.001;

struct GpuPacker {
    float scale = 1.0f;
    float max_count = 65504.0f;
    uint32_t frames = 1;
    bool separate_emissive = false;  ///< store radiance - the voxel's emission (SPEC §G.3)
    bool demodulate = false;         ///< store radiance / the voxel's demodulation factor (SPEC §G.3)
    GpuRadianceReport report;
    double light = 0.0;          ///< every stored channel's value, summed
    double flushed_light = 0.0;  ///< the values of the channels stored as 0, summed

    /// What the engine's build keeps in the voxel: the whole radiance, less the emission it adds
    /// back itself, divided by the factor it multiplies back itself.
    float storedRadiance(const CacheVoxel& v, const CacheVoxelMaterial& m, int c) const {
        float value = v.radiance[c];
        if (separate_emissive) value = std::max(value - m.emission[c], 0.0f);
        if (demodulate) value /= m.demodulation[c];
        return value;
    }

    SharcPackedData pack(const CacheVoxel& v, const CacheVoxelMaterial& material) {
        SharcPackedData packed{{0, 0, 0, 0}, 0, 0};
        bool clipped = false, flushed = false;
        for (int c = 0; c < 3; ++c) {
            const float stored = storedRadiance(v, material, c);
            const float scaled = stored * scale;  // may overflow to +Inf: clipped below
            clipped = clipped || scaled > 65504.0f;
            packed.radiance[c] = floatToHalf(std::min(scaled, 65504.0f));
            const bool lost = stored > 0.0f && packed.radiance[c] == 0;
            flushed = flushed || lost;
            light += std::max(double(stored), 0.0);
            flushed_light += lost ? double(stored) : 0.0;
            report.brightest = std::max(report.brightest, stored);
        }
        report.clipped_voxels += clipped ? 1 : 0;
        report.flushed_voxels += flushed ? 1 : 0;
        packed.radiance[3] = floatToHalf(std::min(v.sample_weight, max_count));
        if (packed.radiance[3] == 0) packed.radiance[3] = 1;  // weight > 0 stays usable (> threshold 0)
        packed.sample_data = frames;  // staleFrameNum (bits 16-31) = 0: the longest life Resolve gives
        packed.sample_data_ext = 0;
        return packed;
    }

    /// The fitting scale and the warning, once every voxel is packed.
    void finish() {
        if (report.brightest > 0.0f) {
            int exponent = 0;
            std::frexp(65504.0 / double(report.brightest), &exponent);  // 65504 / brightest = m 2^e, m in [0.5, 1)
            report.fitting_radiance_scale = float(std::ldexp(1.0, std::min(exponent - 1, 127)));
        }
        char buf[512];
        if (report.clipped_voxels > 0) {
            std::snprintf(buf, sizeof buf,
                          "%llu voxels have a channel above fp16's 65504 after radiance scale %g (brightest channel "
                          "%g) and are clipped; a radiance scale of %g or less keeps them (bake "
                          "--gpu-radiance-scale, or GpuBufferOptions::radiance_scale: the engine's radiance must be "
                          "in the same scaled units)",
                          static_cast<unsigned long long>(report.clipped_voxels), double(report.radiance_scale),
                          double(report.brightest), double(report.fitting_radiance_scale));
            report.warning = buf;
        }
        // Near-black voxels stored as 0 change nothing visible, however many there are (a sunlit
        // room's shadowed voxels outside, 1.5% of them, twenty decades below the sun); a scene
        // whose light is below fp16's range (wrong units, a scale far too small) loses what it
        // shows. So the warning weighs the light lost, not the voxels.
        if (flushed_light > kFlushedLightShareWarned * light) {
            std::snprintf(
                buf, sizeof buf,
                "%s%llu voxels with light are stored as 0 in fp16 (below 6e-8 after radiance scale %g), "
                "%.3g%% of the cache's light; %s",
                report.warning.empty() ? "" : "; ", static_cast<unsigned long long>(report.flushed_voxels),
                double(report.radiance_scale), 100.0 * flushed_light / light,
                report.fitting_radiance_scale > report.radiance_scale
                    ? "a larger radiance scale (up to the fitting one, which clips nothing) keeps more of them"
                    : "the cache's light spans more than fp16's range");
            report.warning += buf;
        }
    }
};

/// Checks the options shared by gpuBuffers() and gpuInsertList() (`what` names the caller).
CacheFileStatus prepareGpuPacker(const GpuBufferOptions& options, const CacheView& view, const char* what,
                                 GpuPacker* packer, CacheError* error) {
    // An enumerator the library does not have is a caller's mistake, as the C API says.
    if (!isKnownSharcSdkTarget(options.sdk_target)) {
        return fail(error, CacheFileStatus::kInvalidArgument, 0,
                    std::string(what) + ": unknown sdk_target " + std::to_string(uint32_t(options.sdk_target)));
    }
    std::string refused;
    const CacheFileStatus build =
        checkSharcBuildOptions(options.build, options.sdk_target, view.hasVoxelMaterials(), &refused);
    if (build != CacheFileStatus::kOk) return fail(error, build, 0, std::string(what) + ": " + refused);
    if (!(options.radiance_scale >= 0.0f) || !std::isfinite(options.radiance_scale)) {
        return fail(error, CacheFileStatus::kInvalidArgument, 0,
                    std::string(what) + ": radiance scale must be finite and > 0 (0: the cache's own)");
    }
    // NaN, 0 or a negative cap fell back to 65504 without a word (a NaN radiance scale is refused).
    if (!(options.max_sample_count > 0.0f)) {
        return fail(error, CacheFileStatus::kInvalidArgument, 0,
                    std::string(what) + ": max sample count must be > 0 (at most 65504 is stored)");
    }
    packer->scale = options.radiance_scale > 0.0f ? options.radiance_scale : view.gpuRadianceScale();
    packer->separate_emissive = options.build.separate_emissive;
    packer->demodulate = options.build.material_demodulation;
    packer->report.radiance_scale = packer->scale;
    packer->max_count = std::min(options.max_sample_count, 65504.0f);
    packer->frames = std::min(options.accumulated_frame_num, kSharcMaxBakedFrameNum);
    return CacheFileStatus::kOk;
}

}  // namespace

CacheFileStatus CacheView::gpuBuffers(const GpuBufferOptions& options, GpuBuffers* out, CacheError* error) const {
    if (error) *error = CacheError{};
    if (!out) return fail(error, CacheFileStatus::kInvalidArgument, 0, "gpuBuffers: null output");
    if (!data_) return fail(error, CacheFileStatus::kInvalidArgument, 0, "gpuBuffers: the view is not open");
    if (options.capacity == 0) return fail(error, CacheFileStatus::kInvalidArgument, 0, "gpuBuffers: capacity 0");
    GpuPacker packer;  // first: it refuses an unknown sdk_target, whose layout the next check reads
    const CacheFileStatus prepared = prepareGpuPacker(options, *this, "gpuBuffers", &packer, error);
    if (prepared != CacheFileStatus::kOk) return prepared;
    const SharcSdkLayout& layout = sharcSdkLayout(options.sdk_target);
    if (options.capacity < layout.min_capacity) {
        return fail(error, CacheFileStatus::kInvalidArgument, 0,
                    "gpuBuffers: capacity " + std::to_string(options.capacity) + " is below " +
                        std::to_string(layout.min_capacity) + ", the least " + toString(options.sdk_target) +
                        "'s bucket rule is defined for");
    }
    GpuBuffers result;
    try {
        result.hash_entries.assign(options.capacity, kHashGridInvalidKey);
        result.resolved.assign(options.capacity, SharcPackedData{{0, 0, 0, 0}, 0, 0});
    } catch (const std::bad_alloc&) {
        return fail(error, CacheFileStatus::kIoError, 0,
                    "gpuBuffers: out of memory for " + std::to_string(options.capacity) + " entries");
    }
    result.capacity = options.capacity;
    result.sdk_target = layout.target;
    // SPEC §G.2: the SDK's 16-slot bucket whatever the bake's table used (GRID bucket_size).
    const uint32_t probes = bucketProbeCount(options.capacity, layout.bucket_size);
    for (uint64_t i = 0; i < voxel_count_; ++i) {
        const CacheVoxel v = voxel(i);
        const uint64_t sdk_key = sharcSdkKey(v.key, layout.target);
        const uint32_t base = sharcSdkBucketBase(hashGridHash(sdk_key), options.capacity, layout.target);
        uint32_t slot = kHashGridInvalidIndex;
        for (uint32_t p = 0; p < probes; ++p) {
            const uint64_t held = result.hash_entries[base + p];
            if (held == kHashGridInvalidKey || held == sdk_key) {
                slot = base + p;
                break;
            }
        }
        if (slot == kHashGridInvalidIndex) {
            ++result.failed_inserts;
            continue;
        }
        result.hash_entries[slot] = sdk_key;
        result.resolved[slot] = packer.pack(v, voxelMaterial(i));
        ++result.inserted;
    }
    packer.finish();
    result.radiance = std::move(packer.report);
    if (error) error->message = result.radiance.warning;
    *out = std::move(result);
    return CacheFileStatus::kOk;
}

GpuRadianceReport CacheView::gpuRadianceCheck(float radiance_scale) const {
    GpuPacker packer;
    packer.scale = std::isfinite(radiance_scale) && radiance_scale > 0.0f ? radiance_scale : gpuRadianceScale();
    packer.report.radiance_scale = packer.scale;
    for (uint64_t i = 0; i < voxel_count_; ++i) (void)packer.pack(voxel(i), CacheVoxelMaterial{});
    packer.finish();
    return packer.report;
}

CacheFileStatus CacheView::gpuInsertList(const GpuBufferOptions& options, GpuInsertList* out, CacheError* error) const {
    if (error) *error = CacheError{};
    if (!out) return fail(error, CacheFileStatus::kInvalidArgument, 0, "gpuInsertList: null output");
    if (!data_) return fail(error, CacheFileStatus::kInvalidArgument, 0, "gpuInsertList: the view is not open");
    GpuPacker packer;
    const CacheFileStatus prepared = prepareGpuPacker(options, *this, "gpuInsertList", &packer, error);
    if (prepared != CacheFileStatus::kOk) return prepared;
    GpuInsertList result;
    result.sdk_target = sharcSdkLayout(options.sdk_target).target;
    try {
        result.keys.resize(size_t(voxel_count_));
        result.values.resize(size_t(voxel_count_));
    } catch (const std::bad_alloc&) {
        return fail(error, CacheFileStatus::kIoError, 0,
                    "gpuInsertList: out of memory for " + std::to_string(voxel_count_) + " voxels");
    }
    for (uint64_t i = 0; i < voxel_count_; ++i) {
        const CacheVoxel v = voxel(i);
        result.keys[size_t(i)] = sharcSdkKey(v.key, result.sdk_target);
        result.values[size_t(i)] = packer.pack(v, voxelMaterial(i));
    }
    packer.finish();
    result.radiance = std::move(packer.report);
    if (error) error->message = result.radiance.warning;
    *out = std::move(result);
    return CacheFileStatus::kOk;
}

}  // namespace sharcbake
