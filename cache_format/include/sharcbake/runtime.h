// SPDX-License-Identifier: Apache-2.0
/// @file runtime.h
/// @brief Runtime access to a baked .sharc cache: open + validate, lookups, iteration, statistics,
/// and SHaRC GPU buffers for a warm start.
///
/// Safe for untrusted input: opening validates every rule of SPEC.md §F.10 before any accessor can
/// be used, and no accessor reads outside the validated buffer. No exceptions are thrown (an
/// allocation failure inside gpuBuffers()/openFile() is reported as a status); no third-party
/// dependencies. A CacheView is immutable after opening, so concurrent lookups are safe.
#pragma once

#include "sharcbake/cache_types.h"
#include "sharcbake/format.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime_export.h"
#include "sharcbake/sdk_target.h"

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace sharcbake {

/// Why an open or validation failed: the status, the SPEC rule number (V1..) and a message.
struct CacheError {
    CacheFileStatus status = CacheFileStatus::kOk;
    uint32_t rule = 0;    ///< SPEC §F.10 rule, 0 when not a file rule (I/O, argument)
    std::string message;  ///< "V11: section KEYS: checksum mismatch ..."
};

/// A section as listed in the table.
struct CacheSectionInfo {
    uint32_t type = 0;  ///< fourcc (first character in the low byte)
    bool required = false;
    bool known = false;  ///< a section this reader understands
    uint64_t offset = 0;
    uint64_t length = 0;
    uint32_t crc32 = 0;
};

/// Aggregate numbers over all voxels (CacheView::stats()).
struct CacheStats {
    uint64_t voxels = 0;
    uint32_t levels = 0;
    float radiance_min[3] = {0, 0, 0};
    float radiance_max[3] = {0, 0, 0};
    double radiance_mean[3] = {0, 0, 0};  ///< unweighted mean over voxels
    float weight_min = 0.0f;
    float weight_max = 0.0f;
    double weight_total = 0.0;
    double bytes_per_voxel = 0.0;  ///< file size / voxels (0 when empty)
};

/// SHaRC `SharcPackedData` (resolved buffer entry, 16 bytes; SDK 1.6.3 - 1.8.x default build).
struct SharcPackedData {
    uint16_t radiance[4];      ///< fp16 mean R, G, B and effective sample count (each <= 65504)
    uint32_t sample_data;      ///< bits 0-15 accumulatedFrameNum, bits 16-31 staleFrameNum
    uint32_t sample_data_ext;  ///< fade-acceleration mask; 0
};
static_assert(sizeof(SharcPackedData) == 16, "SharcPackedData is 16 bytes");

/// Options for CacheView::gpuBuffers() and CacheView::gpuInsertList().
struct GpuBufferOptions {
    uint32_t capacity = kHashGridDefaultCapacity;  ///< slots N of the runtime table (>= 1; gpuBuffers only)
    /// accumulatedFrameNum stored for every entry (clamped to 0..kSharcMaxBakedFrameNum, 64511, so
    /// that Resolve's frame count never carries into the stale counter). The SDK's resolve scales
    /// the history by A/F once F exceeds its accumulation frame count A; 1 keeps the baked weight
    /// intact for A frames, larger values let new frames take over sooner (SPEC §G.4).
    uint32_t accumulated_frame_num = 1;
    /// The sample count stored is min(sample_weight, max_sample_count, 65504): caps how strongly
    /// the baked mean resists new frames. Must be > 0 (NaN, 0 and negative values are kInvalidArgument).
    float max_sample_count = 65504.0f;
    /// The SDK release the engine runs: its key layout and bucket rule (SPEC §G.1).
    SharcSdkTarget sdk_target = kSharcSdkTargetDefault;
    /// The engine's SDK build options (SPEC §G.3): SH encoding and compact keys are refused
    /// (kUnsupportedFeature); material demodulation and separate emissive are served from a cache
    /// with voxel materials (VMAT, SPEC §F.8b) and refused without one.
    SharcBuildOptions build;
    /// Factor applied to the radiance before it goes to fp16 (SPEC §G.6): > 0 uses this value, 0
    /// uses the cache's own (SPEC §F.8a RSCL; 1 when the file has none). Negative or NaN:
    /// kInvalidArgument.
    float radiance_scale = 0.0f;
};

/// How the radiance fared on its way to fp16 (SPEC §G.6).
struct GpuRadianceReport {
    float radiance_scale = 1.0f;  ///< the factor applied
    float brightest = 0.0f;       ///< largest channel stored (after the build's emission and demodulation), before scaling
    /// Largest power of two at which the brightest channel still fits fp16 (<= 65504); 0 when
    /// every voxel is black.
    float fitting_radiance_scale = 0.0f;
    uint64_t clipped_voxels = 0;  ///< voxels with a channel above 65504 after scaling (stored 65504)
    uint64_t flushed_voxels = 0;  ///< voxels with a channel > 0 that fp16 stores as 0
    std::string warning;          ///< empty, or what clipped and the scale that fixes it
};

/// Buffers for a GPU SHaRC implementation (SDK 1.6.3+ resolved layout), `capacity` entries each.
struct GpuBuffers {
    uint32_t capacity = 0;
    SharcSdkTarget sdk_target = kSharcSdkTargetDefault;  ///< whose layout and rule placed the keys
    std::vector<uint64_t> hash_entries;     ///< keys placed by SHaRC's insert rule, 0 = empty
    std::vector<SharcPackedData> resolved;  ///< resolved data at the key's slot, zero elsewhere
    /// The SDK's accumulation buffer (uint4 per entry) starts at zero; not materialised here.
    uint64_t inserted = 0;
    uint64_t failed_inserts = 0;  ///< voxels dropped because their bucket was full
    GpuRadianceReport radiance;
};

/// Keys and resolved entries for the engine to insert itself, with its SDK's own insert function
/// (a compute pass; docs/engine_guide.md §4): no bucket rule is assumed. One entry per voxel, in
/// file (key) order; `keys[i]` is in the target's key layout.
struct GpuInsertList {
    SharcSdkTarget sdk_target = kSharcSdkTargetDefault;
    std::vector<uint64_t> keys;
    std::vector<SharcPackedData> values;
    GpuRadianceReport radiance;
};

/// Float to IEEE binary16, round to nearest even, overflow -> Inf, NaN kept (quiet).
SHARCBAKE_RUNTIME_API uint16_t floatToHalf(float value);
/// IEEE binary16 to float (exact).
SHARCBAKE_RUNTIME_API float halfToFloat(uint16_t value);

/// Read-only view of a validated cache.
class SHARCBAKE_RUNTIME_API CacheView {
public:
    enum class FileMode { kRead, kMap };  ///< read into an owned buffer, or mmap (POSIX)

    CacheView() = default;
    ~CacheView();
    CacheView(CacheView&& other) noexcept;
    CacheView& operator=(CacheView&& other) noexcept;
    CacheView(const CacheView&) = delete;
    CacheView& operator=(const CacheView&) = delete;

    /// @brief Validates `size` bytes at `data` and views them without copying; the caller keeps
    /// the memory alive and unchanged while the view is used. Any alignment is accepted.
    /// On failure `*out` is reset and `error` (optional) says which rule failed.
    static CacheFileStatus openMemory(const void* data, size_t size, CacheView* out, CacheError* error);

    /// @brief Reads (or maps) a file, then validates it as openMemory(). I/O errors: kIoError;
    /// a path that is not a regular file (a FIFO, a device) is refused without blocking.
    /// kMap: the process gets SIGBUS if the file is truncated while the view is open (POSIX
    /// mmap); for files that others may change or that come from untrusted places, use kRead.
    static CacheFileStatus openFile(const std::string& path, CacheView* out, CacheError* error,
                                    FileMode mode = FileMode::kRead);

    bool isOpen() const { return data_ != nullptr; }

    // Header and table -------------------------------------------------------------------------
    uint16_t versionMajor() const { return version_major_; }
    uint16_t versionMinor() const { return version_minor_; }
    uint64_t fileSize() const { return size_; }
    uint32_t headerSize() const { return header_size_; }
    const std::vector<CacheSectionInfo>& sections() const { return sections_; }

    // Grid ---------------------------------------------------------------------------------------
    /// Grid parameters with the given camera (LOD centre); capacity = the bake's capacity.
    HashGridParameters gridParameters(const Float3& camera_position = {0, 0, 0}) const;
    uint32_t bakeCapacity() const { return bake_capacity_; }
    /// The factor GPU buffers apply to the radiance unless told otherwise (SPEC §F.8a, section
    /// RSCL; 1 when the file has none). Lookups are not scaled: they return the file's radiance.
    float gpuRadianceScale() const { return gpu_radiance_scale_; }
    /// The point near which this cache's keys decode (SPEC §F.8c, section ANCR; the origin when
    /// the file has none): pass it to HashGridKeyDecoder to find where a voxel is. Lookups do not
    /// need it.
    const Float3& gridAnchor() const { return grid_anchor_; }

    // Voxels (sorted by key) ---------------------------------------------------------------------
    uint64_t voxelCount() const { return voxel_count_; }
    uint64_t key(uint64_t index) const;         ///< index < voxelCount()
    CacheVoxel voxel(uint64_t index) const;     ///< index < voxelCount()
    /// Whether the file keeps each voxel's emission and demodulation factor (SPEC §F.8b, VMAT).
    bool hasVoxelMaterials() const { return voxel_materials_ != nullptr; }
    /// The voxel's VMAT record (index < voxelCount()); no emission and factor 1 without VMAT.
    CacheVoxelMaterial voxelMaterial(uint64_t index) const;
    /// Index of `key`, or voxelCount() when absent (hash index if built, else binary search).
    uint64_t findKey(uint64_t key) const;
    /// The SHaRC key of (position, normal) for a camera: identical to hashGridKey() with this
    /// cache's parameters, with the per-level voxel sizes and the squared distances where each
    /// level starts precomputed at open (no logarithm per query).
    uint64_t keyFor(const Float3& position, const Float3& normal, const Float3& camera_position) const;
    /// keyFor() of `count` points into `keys`, four at a time with SIMD where the CPU has SSE2
    /// (the same IEEE binary32 operations per lane, so the same keys).
    void keysFor(size_t count, const Float3* positions, const Float3* normals, const Float3& camera_position,
                 uint64_t* keys) const;

    /// @brief Builds an in-memory hash index so lookups cost O(1) instead of a binary search:
    /// open addressing with each key stored next to its radiance, so a hit reads one cache line
    /// and not the file (24 bytes x 1.5..3 per voxel; huge pages where Linux offers them). Call
    /// once before sharing the view between threads. kIoError if the allocation fails (lookups
    /// then keep working). Linear in the voxels for any file: keys crafted to collide in the
    /// index leave it unbuilt (kOk, hasLookupIndex() false) and lookups on the binary search.
    CacheFileStatus buildLookupIndex();
    bool hasLookupIndex() const { return index_slots_ != 0; }
    CacheStats stats() const;

    // Levels -------------------------------------------------------------------------------------
    const std::vector<CacheLevel>& levels() const { return levels_; }

    // Metadata -----------------------------------------------------------------------------------
    size_t metadataCount() const { return metadata_.size(); }
    std::string_view metadataKey(size_t i) const { return metadata_[i].first; }
    std::string_view metadataValue(size_t i) const { return metadata_[i].second; }
    /// Value of `key`, or an empty view with *found = false.
    std::string_view metadata(std::string_view key, bool* found = nullptr) const;

    // Lookups --------------------------------------------------------------------------------------
    /// @brief Exact SHaRC query: the key of (position, normal) seen from `camera_position`, then
    /// a binary search. Returns true and the mean radiance on a hit; false (radiance untouched)
    /// when that voxel is not in the cache.
    bool lookup(const Float3& position, const Float3& normal, const Float3& camera_position,
                Float3* radiance) const;

    /// @brief Like lookup(), but when the camera's level is missing tries the levels present in
    /// order of distance from it (finer first on ties) at the same point and normal.
    /// `*level_used` (optional) receives the level that hit.
    bool lookupNearestLevel(const Float3& position, const Float3& normal, const Float3& camera_position,
                            Float3* radiance, uint32_t* level_used = nullptr) const;

    /// @brief `count` lookups (exact, or nearest-level when `nearest_level`). `hits` (optional)
    /// receives 1/0 per query; misses leave radiance[i] as (0, 0, 0). Returns the number of hits.
    size_t lookupBatch(size_t count, const Float3* positions, const Float3* normals,
                       const Float3& camera_position, Float3* radiance, uint8_t* hits = nullptr,
                       bool nearest_level = false) const;

    // GPU ----------------------------------------------------------------------------------------
    /// @brief SHaRC hash-entries and resolved buffers for a table of options.capacity slots:
    /// keys in the layout of options.sdk_target, inserted in file (key) order with that release's
    /// bucket rule + linear probe (SPEC §G.2). Voxels whose bucket is full are counted in
    /// failed_inserts. Errors: kInvalidArgument (capacity 0, or below 16 for SDK 1.8.3+; a bad
    /// radiance scale; an sdk_target that is none of SharcSdkTarget's enumerators; null out),
    /// kUnsupportedFeature (a build option the library cannot serve; the message says why),
    /// kIoError (allocation failed). A clipping warning is in
    /// out->radiance.warning (and in `error->message` with status kOk).
    CacheFileStatus gpuBuffers(const GpuBufferOptions& options, GpuBuffers* out, CacheError* error = nullptr) const;

    /// @brief The voxels as (key, resolved entry) pairs for the engine's own insert pass: no
    /// capacity and no bucket rule involved (options.capacity is ignored). Same errors and
    /// warnings as gpuBuffers().
    CacheFileStatus gpuInsertList(const GpuBufferOptions& options, GpuInsertList* out,
                                  CacheError* error = nullptr) const;

    /// @brief What gpuBuffers() would report about fp16 at `radiance_scale` (0 or an invalid
    /// value: the cache's own), without making any buffer.
    GpuRadianceReport gpuRadianceCheck(float radiance_scale = 0.0f) const;

private:
    void reset();
    // Validation, one function per group of SPEC §F.10's rules (runtime.cpp).
    struct SectionTable {
        uint64_t offset = 0;
        uint32_t count = 0;
        uint64_t end = 0;
    };
    struct KnownSections {
        const CacheSectionInfo* grid = nullptr;
        const CacheSectionInfo* keys = nullptr;
        const CacheSectionInfo* voxels = nullptr;
        const CacheSectionInfo* levels = nullptr;
        const CacheSectionInfo* meta = nullptr;
        const CacheSectionInfo* radiance_scale = nullptr;  ///< RSCL (1.1)
        const CacheSectionInfo* voxel_materials = nullptr;  ///< VMAT (1.1)
        const CacheSectionInfo* grid_anchor = nullptr;      ///< ANCR (1.2)
    };
    CacheFileStatus parse(CacheError* error);
    CacheFileStatus parseHeader(CacheError* error, SectionTable* table);
    CacheFileStatus parseSections(const SectionTable& table, CacheError* error, KnownSections* found);
    CacheFileStatus parseGrid(const CacheSectionInfo& grid, CacheError* error, uint64_t* voxel_count,
                              uint32_t* level_count);
    CacheFileStatus parseVoxels(const KnownSections& found, uint64_t voxel_count, uint32_t level_count,
                                CacheError* error);
    CacheFileStatus parseMetadata(const CacheSectionInfo* meta, CacheError* error);
    CacheFileStatus parseRadianceScale(const CacheSectionInfo* section, CacheError* error);
    CacheFileStatus parseVoxelMaterials(const CacheSectionInfo* section, CacheError* error);
    CacheFileStatus parseGridAnchor(const CacheSectionInfo* section, CacheError* error);

    const uint8_t* data_ = nullptr;
    uint64_t size_ = 0;
    std::vector<uint8_t> owned_;  ///< FileMode::kRead
    void* mapping_ = nullptr;     ///< FileMode::kMap
    size_t mapping_size_ = 0;

    uint16_t version_major_ = 0, version_minor_ = 0;
    uint32_t header_size_ = 0;
    std::vector<CacheSectionInfo> sections_;
    float logarithm_base_ = 2.0f, scene_scale_ = 50.0f, level_bias_ = 0.0f;
    uint32_t bucket_size_ = kHashGridBucketSize;
    uint32_t bake_capacity_ = 0;
    float gpu_radiance_scale_ = 1.0f;
    Float3 grid_anchor_{0.0f, 0.0f, 0.0f};
    uint64_t voxel_count_ = 0;
    const uint8_t* keys_ = nullptr;    ///< voxel_count_ little-endian u64
    const uint8_t* voxels_ = nullptr;  ///< voxel_count_ records of 16 bytes
    const uint8_t* voxel_materials_ = nullptr;  ///< VMAT: voxel_count_ records of 24 bytes, or null
    std::vector<CacheLevel> levels_;
    std::vector<std::pair<std::string_view, std::string_view>> metadata_;
    HashGridKeyer keyer_;  ///< this cache's grid: keys without a logarithm per query

    /// A lookup-index slot: key, radiance and voxel index side by side (key 0 = empty; KEYS
    /// never holds 0, rule V15).
    struct IndexSlot {
        uint64_t key;
        float radiance[3];
        uint32_t voxel;
    };
    struct FreeDeleter {
        void operator()(IndexSlot* p) const;
    };
    std::unique_ptr<IndexSlot[], FreeDeleter> index_;
    size_t index_slots_ = 0;                ///< a power of two, or 0 without an index
    uint32_t index_shift_ = 64;             ///< slot = (key * index_multiplier_) >> shift
    uint64_t index_multiplier_ = 0;         ///< the first of the build's multipliers whose probes ran short

    size_t homeSlot(uint64_t key) const { return size_t((key * index_multiplier_) >> index_shift_); }
    const IndexSlot* findSlot(uint64_t key) const;  ///< nullptr when absent; needs the index
};

}  // namespace sharcbake
