// SPDX-License-Identifier: Apache-2.0
/// @file hash_grid.h
/// @brief The SHaRC hash grid: (position, normal, camera) -> 64-bit key -> 32-bit hash -> bucket.
///
/// Keys and hashes are bit-exact with the current SHaRC SDK (1.7.2 / 1.8.x, default 64-bit keys,
/// `HASH_GRID_USE_NORMALS = 1`). The normative description, the float32 evaluation order and the
/// test vectors are in cache_format/SPEC.md, section "Hash grid"; the section numbers quoted in
/// this file ("SPEC §H.n") point there.
///
/// The runtime has no third-party dependency and throws no exceptions. Every function here is
/// safe for any input value, including NaN/Inf positions and degenerate parameters: such inputs
/// give a defined (documented) key, never undefined behaviour.
#pragma once

#include "sharcbake/runtime_export.h"
#include "sharcbake/zeroed_array.h"

#include <atomic>
#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

namespace sharcbake {

/// Plain 3-component float vector (no GLM in the runtime's interface).
struct Float3 {
    float x, y, z;
};

/// Plain 3-component signed integer vector (grid cell coordinates).
struct Int3 {
    int32_t x, y, z;
};

// ------------------------------------------------------------------------------------------------
// Constants (SPEC §H.1). Names follow the SDK's HASH_GRID_* / SHARC_* constants.
// ------------------------------------------------------------------------------------------------

inline constexpr uint32_t kHashGridPositionBits = 17;  ///< bits per grid coordinate
inline constexpr uint32_t kHashGridLevelBits = 9;      ///< level field width (10 before SDK 1.7)
inline constexpr uint32_t kHashGridNormalBits = 3;     ///< normal sign bits x, y, z
inline constexpr uint32_t kHashGridLevelOffset = 3 * kHashGridPositionBits;                // 51
inline constexpr uint32_t kHashGridNormalOffset = kHashGridLevelOffset + kHashGridLevelBits;  // 60
inline constexpr uint32_t kHashGridUserBit = 63;  ///< reserved (SDK responsive lighting); 0 here
inline constexpr uint32_t kHashGridPositionMask = (1u << kHashGridPositionBits) - 1;  // 0x1FFFF
inline constexpr uint32_t kHashGridLevelMask = (1u << kHashGridLevelBits) - 1;        // 511
inline constexpr uint32_t kHashGridNormalMask = (1u << kHashGridNormalBits) - 1;      // 7
inline constexpr uint32_t kHashGridLevelMin = 1;                   ///< level 0 is never produced
inline constexpr uint32_t kHashGridLevelMax = kHashGridLevelMask;  ///< 511

inline constexpr float kHashGridPositionBias = 1e-4f;  ///< added to every position component
inline constexpr float kHashGridNormalBias = 1e-3f;    ///< added to every normal component
inline constexpr float kHashGridMinDistance2 = 1e-10f;  ///< lower clamp of squared distance

inline constexpr uint32_t kHashGridBucketSize = 16;  ///< HASH_GRID_HASH_MAP_BUCKET_SIZE
inline constexpr uint64_t kHashGridInvalidKey = 0;   ///< empty slot
inline constexpr uint32_t kHashGridInvalidIndex = 0xFFFFFFFFu;  ///< "no slot"

inline constexpr float kHashGridDefaultLogarithmBase = 2.0f;  ///< SHARC_GRID_LOGARITHM_BASE
inline constexpr float kHashGridDefaultSceneScale = 50.0f;    ///< RTXGI sample value
inline constexpr float kHashGridDefaultLevelBias = 0.0f;      ///< SHARC_GRID_LEVEL_BIAS
inline constexpr uint32_t kHashGridDefaultCapacity = 1u << 22;  ///< 4 Mi entries

// ------------------------------------------------------------------------------------------------
// Parameters
// ------------------------------------------------------------------------------------------------

/// Every value that feeds a key or a slot. Plain aggregate; copy freely.
///
/// The same `camera_position` must be used by everything that builds keys for one table
/// (insert and lookup), otherwise levels and keys differ (SPEC §H.2).
struct HashGridParameters {
    Float3 camera_position{0.0f, 0.0f, 0.0f};             ///< LOD centre `c`
    float logarithm_base = kHashGridDefaultLogarithmBase;  ///< `b`, must be > 1
    float scene_scale = kHashGridDefaultSceneScale;        ///< `S`, must be > 0
    float level_bias = kHashGridDefaultLevelBias;          ///< `beta`
    uint32_t capacity = kHashGridDefaultCapacity;          ///< table slots `N`, >= 1
    uint32_t bucket_size = kHashGridBucketSize;  ///< probe window; SDK-compatible only when 16
};

/// Outcome of parameter validation and table construction.
enum class HashGridStatus : uint32_t {
    kOk = 0,
    kInvalidCapacity,    ///< capacity == 0
    kInvalidBucketSize,  ///< bucket_size == 0
    kInvalidLogBase,     ///< logarithm_base not finite or <= 1
    kInvalidSceneScale,  ///< scene_scale not finite or <= 0
    kInvalidLevelBias,   ///< level_bias not finite
    kInvalidCamera,      ///< camera_position has a NaN/Inf component
    /// The voxel size formula (voxelSize, binary32) has no finite, positive value at level 1:
    /// S * b^beta is not finite or below FLT_MIN (a bias of 200 makes b^beta infinite, a scale of
    /// 1e-40 is subnormal), or the finest voxel itself overflows. Every level's voxel is then 0,
    /// infinite or NaN wide, and all points share one cell.
    kUnrepresentableVoxelSize,
};

/// @brief Human-readable name of a status ("ok", "invalid capacity", ...). Never null.
SHARCBAKE_RUNTIME_API const char* toString(HashGridStatus status);

/// @brief Checks parameters for values that make levels or voxel sizes meaningless.
///
/// The key functions accept any parameters (the result is still defined), but a baker should
/// refuse parameters for which this returns anything but kOk. Checks each parameter alone, then
/// that level 1's voxel size is finite and positive (kUnrepresentableVoxelSize). Capacities below the bucket size
/// are valid (see bucketBase()), although the SDK itself requires N >= 16.
SHARCBAKE_RUNTIME_API HashGridStatus validateHashGridParameters(const HashGridParameters& params);

// ------------------------------------------------------------------------------------------------
// Key construction (SPEC §H.2 - §H.6)
// ------------------------------------------------------------------------------------------------

/// @brief Level of detail of a point: clamp(floor(log_b |c - p| + beta), 1, 511).
///
/// Like the SDK's HashGridGetLevel this takes the position as given; hashGridKey() applies the
/// +1e-4 position bias first and then calls this. Evaluated in float32 as in SPEC §H.3.
/// NaN distances give level 1; an infinite distance gives 511.
SHARCBAKE_RUNTIME_API uint32_t gridLevel(const Float3& position, const HashGridParameters& params);

/// @brief Voxel edge length of a level: b^L / (S * b^beta), float32 as in SPEC §H.4.
/// May be +Inf or NaN for absurd levels/biases (b^L overflows float); callers get a defined key.
SHARCBAKE_RUNTIME_API float voxelSize(uint32_t level, const HashGridParameters& params);

/// @brief floor(position / voxel_size) per component, converted to int32 with saturation
/// (NaN -> 0, below INT32_MIN -> INT32_MIN, above INT32_MAX -> INT32_MAX). SPEC §H.5.
SHARCBAKE_RUNTIME_API Int3 quantisePosition(const Float3& position, float voxel_size);

/// A key's decoded fields (or a cell before packing).
struct HashGridCell {
    Int3 grid;             ///< grid coordinates; after decoding: sign-extended 17-bit values
    uint32_t level;        ///< 1..511 for valid keys
    uint32_t normal_bits;  ///< bit0 = x negative, bit1 = y negative, bit2 = z negative
    bool user_bit;         ///< bit 63 (SDK responsive-lighting marker); false for our keys
};

/// @brief The cell a point falls in: position bias, level, voxel size and quantisation.
/// Returns the full (unmasked) int32 grid coordinates; normal_bits = 0, user_bit = false.
SHARCBAKE_RUNTIME_API HashGridCell gridCell(const Float3& position, const HashGridParameters& params);

/// @brief The 3 normal sign bits: bit i is set unless (n_i + 1e-3) >= 0 (so NaN sets the bit).
SHARCBAKE_RUNTIME_API uint32_t normalBits(const Float3& normal);

/// @brief Packs fields into a key: x, y, z masked to 17 bits (two's complement), level masked to
/// 9 bits, normal bits masked to 3 bits, user bit at 63. Never fails; the caller is responsible
/// for passing level >= 1 if the key must be non-zero.
SHARCBAKE_RUNTIME_API uint64_t packHashGridKey(const Int3& grid, uint32_t level, uint32_t normal_bits,
                                               bool user_bit = false);

/// @brief The SHaRC key of a surface point (HashGridComputeSpatialHash). Never 0: the level
/// field is always in 1..511 (SPEC §H.6).
SHARCBAKE_RUNTIME_API uint64_t hashGridKey(const Float3& position, const Float3& normal,
                                           const HashGridParameters& params);

/// @brief hashGridKey() for fixed grid parameters and any camera position, without a logarithm
/// or a power per key: the voxel size of every level and, since the SPEC §H.3 level only grows
/// with the squared distance, the squared distance where each level starts are computed once.
/// The keys are hashGridKey()'s bit for bit (tested over every level boundary).
class SHARCBAKE_RUNTIME_API HashGridKeyer {
public:
    /// Keys for the default HashGridParameters.
    HashGridKeyer() : HashGridKeyer(HashGridParameters{}) {}
    /// `params.camera_position` is not used: key() takes the camera.
    explicit HashGridKeyer(const HashGridParameters& params);

    /// The SPEC §H.3 level of a squared camera distance (clamped as gridLevel() does). Inline:
    /// batched queries call it per lane.
    uint32_t levelOf(float distance2) const {
        distance2 = (distance2 != distance2 || distance2 < kHashGridMinDistance2) ? kHashGridMinDistance2 : distance2;
        uint32_t bits;
        std::memcpy(&bits, &distance2, 4);
        // A first guess from the float's exponent and mantissa (log2 to within 0.09), then steps
        // to the exact level along the thresholds.
        const float approximate_log2 = float(int32_t(bits >> 23) - 127) + float(bits & 0x7FFFFFu) * 0x1p-23f;
        float guess = 0.5f * approximate_log2 / log2_base_ + level_bias_;
        guess = guess != guess || guess < 1.0f ? 1.0f : (guess > 511.0f ? 511.0f : guess);
        uint32_t level = uint32_t(guess);
        while (level < kHashGridLevelMax && bits >= level_start_[level + 1]) ++level;
        while (level > kHashGridLevelMin && bits < level_start_[level]) --level;
        return level;
    }
    /// voxelSize(level) for these parameters; level <= kHashGridLevelMax.
    float voxelSizeAt(uint32_t level) const { return voxel_size_[level]; }
    /// hashGridKey(position, normal, params with camera_position = camera).
    uint64_t key(const Float3& position, const Float3& normal, const Float3& camera) const;
    /// hashGridKeyAtLevel(position, normal, level, params); level in 1..511.
    uint64_t keyAtLevel(const Float3& position, const Float3& normal, uint32_t level) const;

private:
    float log2_base_;
    float level_bias_;
    std::vector<float> voxel_size_;  ///< voxelSize(L) for L = 0..511
    /// level_start_[L]: bits of the smallest clamped squared distance whose level is >= L
    /// (L = 1..512; 0xFFFFFFFF when no float reaches L).
    std::vector<uint32_t> level_start_;
};

/// @brief The key the point would have at an explicit `level` (hashGridKey() with the level
/// chosen by the caller instead of by the camera distance): bias, voxelSize(level), quantise,
/// normal bits, pack. For lookups at levels other than the camera's (coverage, fallbacks).
SHARCBAKE_RUNTIME_API uint64_t hashGridKeyAtLevel(const Float3& position, const Float3& normal, uint32_t level,
                                                  const HashGridParameters& params);

/// @brief The key of the voxel one level coarser (level + 1, same normal bits) that holds `key`'s
/// voxel: what a camera one level further away asks for at the same surface point.
///
/// When the logarithm base is a power of two (2, 4, ...; SDK default 2), voxels nest exactly:
/// voxelSize(L + 1) is exactly b * voxelSize(L) in float32, so every point of the voxel has the
/// returned key at level + 1 (grid coordinates floor-divided by b). For other bases a coarse voxel
/// straddles fine ones and the voxel's centre decides. Grid coordinates that wrapped at 17 bits
/// are divided as decodeHashGridKey() gives them (the parent of a wrapped cell is then wrong, as
/// its position already is); HashGridKeyDecoder::coarserKey() unwraps them around an anchor
/// first. Level 511 (the last) returns 0 (no coarser level).
SHARCBAKE_RUNTIME_API uint64_t coarserKey(uint64_t key, const HashGridParameters& params);

/// @brief Decodes a key: grid coordinates sign-extended from 17 bits, level, normal bits and the
/// user bit. Exact inverse of packHashGridKey() for coordinates in [-65536, 65535].
SHARCBAKE_RUNTIME_API HashGridCell decodeHashGridKey(uint64_t key);

/// @brief Centre of a key's voxel in world units: (g + 0.5) * voxelSize(level), float32, as the
/// SDK's HashGridGetPositionFromKey. The +1e-4 bias is not removed. Coordinates that wrapped at
/// 17 bits decode to the wrapped cell (SPEC §H.6); HashGridKeyDecoder decodes them near an anchor.
SHARCBAKE_RUNTIME_API Float3 voxelCenter(uint64_t key, const HashGridParameters& params);

/// @brief Decodes keys into the cells they were made from, also where the scene lies beyond the
/// 17-bit grid range around the origin (SPEC §H.6a).
///
/// A key keeps the low 17 bits of each grid coordinate, so it names its cell only up to multiples
/// of 2^17 cells: a 1 m room 10 km from the origin in 2 mm voxels has coordinates near 5 million,
/// and keys that hash and look up correctly (keys never need decoding), but decodeHashGridKey()
/// would put its voxels 5 million mod 2^17 cells from the origin. The decoder picks, per axis,
/// the cell within [-2^16, 2^16) cells of the anchor's own cell at the key's level. With the
/// anchor at the origin it decodes exactly as decodeHashGridKey(), voxelCenter() and coarserKey();
/// a bake whose scene reaches beyond that range records the centre of the scene's bounds as the
/// file's anchor (SPEC §F.8c; CacheView::gridAnchor()).
class SHARCBAKE_RUNTIME_API HashGridKeyDecoder {
public:
    explicit HashGridKeyDecoder(const HashGridParameters& params, const Float3& anchor = Float3{0.0f, 0.0f, 0.0f});

    /// decodeHashGridKey(), with grid coordinates the cell nearest the anchor's.
    HashGridCell decode(uint64_t key) const;
    /// voxelCenter() of the decoded cell: (g + 0.5) * voxelSize(level) in float32.
    Float3 voxelCenter(uint64_t key) const;
    /// coarserKey() of the decoded cell: exact nesting for power-of-two bases also where the
    /// coordinates wrapped.
    uint64_t coarserKey(uint64_t key) const;
    const Float3& anchor() const { return anchor_; }

private:
    float logarithm_base_;
    Float3 anchor_;
    std::vector<float> voxel_size_;  ///< voxelSize(L) for L = 0..511
    std::vector<Int3> anchor_cell_;  ///< the anchor's cell at level L = 0..511
};

// ------------------------------------------------------------------------------------------------
// Hash and bucket (SPEC §H.7)
// ------------------------------------------------------------------------------------------------

/// @brief Bob Jenkins' 32-bit integer hash (six shift/add/xor steps, wrap-around arithmetic).
SHARCBAKE_RUNTIME_API uint32_t jenkins32(uint32_t value);

/// @brief The SDK's Hash32: jenkins32(low 32 bits) XOR jenkins32(high 32 bits).
SHARCBAKE_RUNTIME_API uint32_t hashGridHash(uint64_t key);

/// @brief Number of slots probed in a table of `capacity` slots: min(bucket_size, capacity).
SHARCBAKE_RUNTIME_API uint32_t bucketProbeCount(uint32_t capacity, uint32_t bucket_size = kHashGridBucketSize);

/// @brief First slot of a hash's bucket: min(hash % N, N - bucket_size) for N >= bucket_size
/// (identical to the SDK for N >= 16 and bucket_size 16). For 0 < N < bucket_size the bucket is
/// the whole table and the base is 0 (the SDK would underflow here). N == 0 returns
/// kHashGridInvalidIndex. The window [base, base + bucketProbeCount(N)) always lies inside [0, N).
SHARCBAKE_RUNTIME_API uint32_t bucketBase(uint32_t hash, uint32_t capacity, uint32_t bucket_size = kHashGridBucketSize);

/// @brief Debug colour of a key: colorFromHash(hashGridHash(key)) * colorFromHash(jenkins32(L)),
/// with colorFromHash(h) = ((h & 0x3FF) / 1023, ((h >> 11) & 0x7FF) / 2047,
/// ((h >> 22) & 0x7FF) / 2047) in float32. L is the key's level. (The SDK's
/// HashGridDebugColoredHash recomputes L from the unbiased position, which can differ from the
/// key's level within ~1e-4 of a level boundary; see SPEC §H.8.)
SHARCBAKE_RUNTIME_API Float3 hashDebugColor(uint64_t key);

// ------------------------------------------------------------------------------------------------
// CPU hash table (SPEC §H.7)
// ------------------------------------------------------------------------------------------------

/// @brief Lock-free key table with SHaRC's bucket rule: linear probing inside a bounded,
/// non-wrapping window of min(bucket_size, N) slots, 64-bit CAS from 0, key 0 = empty.
///
/// insert() and find() are thread-safe with respect to each other. Two threads inserting the same
/// key always get the same slot. A full bucket makes insert() return std::nullopt and increments
/// failedInserts(); a failed insert never yields an index (unlike SDK <= 1.6, which returned 0 or
/// N - 1). Slot assignment depends on insertion order when keys share a bucket.
/// Not copyable or movable-while-in-use; create with create().
class SHARCBAKE_RUNTIME_API HashGridTable {
public:
    HashGridTable() = default;

    /// @brief Allocates `capacity` empty slots. Errors: kInvalidCapacity (capacity == 0),
    /// kInvalidBucketSize (bucket_size == 0). On error `*out` is left unchanged.
    static HashGridStatus create(uint32_t capacity, HashGridTable* out,
                                 uint32_t bucket_size = kHashGridBucketSize);

    /// @brief Inserts `key` (or finds it if present) and returns its slot.
    /// @return the slot, or std::nullopt if the bucket is full or key == 0 (not a valid key) or
    /// the table was never created. Every nullopt increments failedInserts().
    std::optional<uint32_t> insert(uint64_t key);

    /// @brief First slot in the key's bucket holding `key`, scanning the whole window (no early
    /// exit on empty slots). std::nullopt if absent or key == 0.
    std::optional<uint32_t> find(uint64_t key) const;

    /// @brief Asks the CPU to start loading the bucket window that starts at slot `base` (from
    /// bucketBase; a hint, no effect on results). Code that looks up many keys prefetches a batch
    /// of them first, so that their cache misses overlap instead of following one another.
    void prefetchBucket(uint32_t base) const;

    /// Key stored in `slot` (0 = empty). `slot` must be < capacity().
    uint64_t keyAt(uint32_t slot) const { return keys_[slot].load(std::memory_order_acquire); }

    /// @brief Writes 0 into `slot` (eviction). `slot` must be < capacity().
    void clearSlot(uint32_t slot) { keys_[slot].store(kHashGridInvalidKey, std::memory_order_release); }

    uint32_t capacity() const { return static_cast<uint32_t>(keys_.size()); }
    uint32_t bucketSize() const { return bucket_size_; }
    /// Number of insert() calls that returned std::nullopt.
    uint64_t failedInserts() const { return failed_inserts_.load(std::memory_order_relaxed); }
    /// Number of non-empty slots (O(N) scan; not synchronised with concurrent inserts).
    uint32_t occupiedSlots() const;

    HashGridTable(HashGridTable&& other) noexcept;
    HashGridTable& operator=(HashGridTable&& other) noexcept;
    HashGridTable(const HashGridTable&) = delete;
    HashGridTable& operator=(const HashGridTable&) = delete;

private:
    ZeroedArray<std::atomic<uint64_t>> keys_;  ///< kHashGridInvalidKey (0) = empty: calloc'd, touched lazily
    uint32_t bucket_size_ = kHashGridBucketSize;
    std::atomic<uint64_t> failed_inserts_{0};
};

}  // namespace sharcbake
