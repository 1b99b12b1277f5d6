// SPDX-License-Identifier: Apache-2.0
// SHaRC hash grid: keys, hash, buckets and the CPU key table. Written from the algorithm
// description (docs/sharc_algorithm.md §2) and cache_format/SPEC.md "Hash grid";
// every float operation below is one IEEE-754 binary32 operation in the order SPEC §H.3-§H.5
// prescribes, because a different order or a fused multiply-add changes keys near cell and level
// boundaries.
#include "sharcbake/hash_grid.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>

// Bit-exact keys need plain binary32 arithmetic: no value-changing optimisations, no excess
// precision. (CMake also builds this file with -ffp-contract=off so a*b+c is never fused.)
#if defined(__FAST_MATH__)
#error "hash_grid.cpp must not be compiled with -ffast-math: SHaRC keys would not be bit-exact"
#endif
#if defined(FLT_EVAL_METHOD) && (FLT_EVAL_METHOD == 1 || FLT_EVAL_METHOD == 2)
#error "hash_grid.cpp needs FLT_EVAL_METHOD == 0 (SSE float arithmetic, no x87 excess precision)"
#endif

namespace sharcbake {
namespace {

// Rounds a double to binary32 without undefined behaviour on overflow (a plain cast of a double
// outside the float range is UB in C++). Values at or above the midpoint between FLT_MAX and
// 2^128 round to infinity, exactly as IEEE round-to-nearest-even does.
float roundToFloat(double value) {
    constexpr double kOverflowThreshold = 0x1.ffffffp127;  // (FLT_MAX + 2^128) / 2
    if (value >= kOverflowThreshold) return INFINITY;
    if (value <= -kOverflowThreshold) return -INFINITY;
    return static_cast<float>(value);  // NaN stays NaN
}

// log2 and exp2 in binary32, correctly rounded in practice: the double result is within 1 double
// ulp, so rounding it to float gives the correctly rounded float except in vanishingly rare
// double-rounding cases (SPEC §H.3, "transcendentals").
float log2F32(float x) { return roundToFloat(std::log2(static_cast<double>(x))); }
float exp2F32(float x) { return roundToFloat(std::exp2(static_cast<double>(x))); }

// HLSL pow(x, y) is lowered by DXC to exp2(y * log2(x)); we use the same decomposition.
float powF32(float x, float y) { return exp2F32(y * log2F32(x)); }

// HLSL max/min are IEEE maxNum/minNum on the GPU: a NaN operand yields the other operand.
float maxNum(float a, float b) { return std::isnan(a) ? b : (a >= b ? a : b); }
float minNum(float a, float b) { return std::isnan(a) ? b : (a <= b ? a : b); }

// floor(value) converted to int32 like GPU hardware: saturating, NaN -> 0 (in C++ an
// out-of-range conversion is UB). By truncation and a step down for negative fractions, since
// std::floor is a library call on x86-64 without SSE4.1; a float at or beyond 2^23 in magnitude
// is an integer already, so the truncation is exact wherever a fraction exists.
int32_t floorToInt32(float value) {
    if (std::isnan(value)) return 0;
    if (value <= -2147483648.0f) return INT32_MIN;
    if (value >= 2147483648.0f) return INT32_MAX;
    const int32_t truncated = static_cast<int32_t>(value);
    return static_cast<float>(truncated) > value ? truncated - 1 : truncated;
}

// SDK debug palette: R from bits 0-9, G from bits 11-21, B from bits 22-31.
Float3 colorFromHash(uint32_t hash) {
    return Float3{static_cast<float>(hash & 0x3FFu) / 1023.0f,
                  static_cast<float>((hash >> 11) & 0x7FFu) / 2047.0f,
                  static_cast<float>((hash >> 22) & 0x7FFu) / 2047.0f};
}

int32_t signExtend17(uint32_t field) {
    // (field ^ sign) - sign maps [0, 2^17) onto [-2^16, 2^16) without implementation-defined shifts.
    const int32_t sign = 1 << (kHashGridPositionBits - 1);
    return (static_cast<int32_t>(field & kHashGridPositionMask) ^ sign) - sign;
}

}  // namespace

const char* toString(HashGridStatus status) {
    switch (status) {
        case HashGridStatus::kOk: return "ok";
        case HashGridStatus::kInvalidCapacity: return "invalid capacity (must be >= 1)";
        case HashGridStatus::kInvalidBucketSize: return "invalid bucket size (must be >= 1)";
        case HashGridStatus::kInvalidLogBase: return "invalid logarithm base (must be finite and > 1)";
        case HashGridStatus::kInvalidSceneScale: return "invalid scene scale (must be finite and > 0)";
        case HashGridStatus::kInvalidLevelBias: return "invalid level bias (must be finite)";
        case HashGridStatus::kInvalidCamera: return "invalid camera position (must be finite)";
        case HashGridStatus::kUnrepresentableVoxelSize:
            return "voxel sizes not representable in float32 (scene scale x base^bias must be finite and at least "
                   "1.2e-38, and the finest voxel, base / that, finite)";
    }
    return "unknown status";
}

HashGridStatus validateHashGridParameters(const HashGridParameters& params) {
    if (params.capacity == 0) return HashGridStatus::kInvalidCapacity;
    if (params.bucket_size == 0) return HashGridStatus::kInvalidBucketSize;
    if (!std::isfinite(params.logarithm_base) || !(params.logarithm_base > 1.0f)) {
        return HashGridStatus::kInvalidLogBase;
    }
    if (!std::isfinite(params.scene_scale) || !(params.scene_scale > 0.0f)) {
        return HashGridStatus::kInvalidSceneScale;
    }
    if (!std::isfinite(params.level_bias)) return HashGridStatus::kInvalidLevelBias;
    const Float3& c = params.camera_position;
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.z)) {
        return HashGridStatus::kInvalidCamera;
    }
    // Each value fine alone, their voxel size may still have no binary32 value: voxelSize divides
    // b^L by S * b^beta, and every level's size is 0, infinite or NaN when that is.
    const float denominator = params.scene_scale * powF32(params.logarithm_base, params.level_bias);
    const float finest = voxelSize(kHashGridLevelMin, params);
    if (!std::isfinite(denominator) || !(denominator >= FLT_MIN) || !std::isfinite(finest) || !(finest > 0.0f)) {
        return HashGridStatus::kUnrepresentableVoxelSize;
    }
    return HashGridStatus::kOk;
}

namespace {

/// SPEC §H.3 steps 2-4: the level of a squared distance.
uint32_t levelFromDistance2(float distance2, float log2_base, float level_bias) {
    // 2) Clamp (SDK 1.7+): never log(0); a NaN distance becomes 1e-10 (maxNum), i.e. level 1.
    distance2 = maxNum(distance2, kHashGridMinDistance2);
    // 3) 0.5 * log_b(d^2) + beta with log_b(x) = log2(x) / log2(b) (SPEC §H.3 on log vs log2).
    const float log_ratio = log2F32(distance2) / log2_base;
    const float level = 0.5f * log_ratio + level_bias;
    // 4) clamp to [1, 511] (NaN -> 1), then truncate.
    const float clamped = minNum(maxNum(level, static_cast<float>(kHashGridLevelMin)),
                                 static_cast<float>(kHashGridLevelMax));
    return static_cast<uint32_t>(clamped);
}

/// 1) Squared distance, dot(c - p, c - p) evaluated as (dx*dx + dy*dy) + dz*dz, unfused.
float distance2(const Float3& camera, const Float3& position) {
    const float dx = camera.x - position.x;
    const float dy = camera.y - position.y;
    const float dz = camera.z - position.z;
    float d2 = dx * dx;
    d2 = d2 + dy * dy;
    d2 = d2 + dz * dz;
    return d2;
}

uint32_t floatBits(float f) {
    uint32_t bits;
    std::memcpy(&bits, &f, 4);
    return bits;
}

float bitsFloat(uint32_t bits) {
    float f;
    std::memcpy(&f, &bits, 4);
    return f;
}

}  // namespace

uint32_t gridLevel(const Float3& position, const HashGridParameters& params) {
    return levelFromDistance2(distance2(params.camera_position, position), log2F32(params.logarithm_base),
                              params.level_bias);
}

HashGridKeyer::HashGridKeyer(const HashGridParameters& params)
    : log2_base_(log2F32(params.logarithm_base)), level_bias_(params.level_bias) {
    voxel_size_.resize(kHashGridLevelMax + 1);
    for (uint32_t level = 0; level <= kHashGridLevelMax; ++level) voxel_size_[level] = voxelSize(level, params);
    // Where each level starts, by bisection over the bit patterns of the clamped squared
    // distance (positive floats order like their bits; +Inf is the largest).
    level_start_.assign(kHashGridLevelMax + 2, 0xFFFFFFFFu);
    const uint32_t lowest = floatBits(kHashGridMinDistance2), highest = floatBits(INFINITY);
    const uint32_t top = levelFromDistance2(INFINITY, log2_base_, level_bias_);
    for (uint32_t level = 0; level <= top; ++level) {
        uint32_t lo = lowest, hi = highest;  // invariant: the level at hi is >= level
        while (lo < hi) {
            const uint32_t mid = lo + (hi - lo) / 2;
            if (levelFromDistance2(bitsFloat(mid), log2_base_, level_bias_) >= level) {
                hi = mid;
            } else {
                lo = mid + 1;
            }
        }
        level_start_[level] = lo;
    }
}

uint64_t HashGridKeyer::key(const Float3& position, const Float3& normal, const Float3& camera) const {
    const Float3 biased{position.x + kHashGridPositionBias, position.y + kHashGridPositionBias,
                        position.z + kHashGridPositionBias};
    const uint32_t level = levelOf(distance2(camera, biased));
    return packHashGridKey(quantisePosition(biased, voxel_size_[level]), level, normalBits(normal), false);
}

uint64_t HashGridKeyer::keyAtLevel(const Float3& position, const Float3& normal, uint32_t level) const {
    const Float3 biased{position.x + kHashGridPositionBias, position.y + kHashGridPositionBias,
                        position.z + kHashGridPositionBias};
    return packHashGridKey(quantisePosition(biased, voxel_size_[level]), level, normalBits(normal), false);
}

float voxelSize(uint32_t level, const HashGridParameters& params) {
    const float b = params.logarithm_base;
    const float numerator = powF32(b, static_cast<float>(level));
    const float denominator = params.scene_scale * powF32(b, params.level_bias);
    return numerator / denominator;
}

Int3 quantisePosition(const Float3& position, float voxel_size) {
    return Int3{floorToInt32(position.x / voxel_size), floorToInt32(position.y / voxel_size),
                floorToInt32(position.z / voxel_size)};
}

HashGridCell gridCell(const Float3& position, const HashGridParameters& params) {
    const Float3 biased{position.x + kHashGridPositionBias, position.y + kHashGridPositionBias,
                        position.z + kHashGridPositionBias};
    const uint32_t level = gridLevel(biased, params);
    const float size = voxelSize(level, params);
    return HashGridCell{quantisePosition(biased, size), level, 0u, false};
}

uint32_t normalBits(const Float3& normal) {
    // "(n + bias) >= 0 ? 0 : bit" - written this way so that NaN sets the bit, as in the SDK.
    uint32_t bits = 0;
    if (!(normal.x + kHashGridNormalBias >= 0.0f)) bits |= 1u;
    if (!(normal.y + kHashGridNormalBias >= 0.0f)) bits |= 2u;
    if (!(normal.z + kHashGridNormalBias >= 0.0f)) bits |= 4u;
    return bits;
}

uint64_t packHashGridKey(const Int3& grid, uint32_t level, uint32_t normal_bits, bool user_bit) {
    auto field = [](int32_t v) {
        return static_cast<uint64_t>(static_cast<uint32_t>(v) & kHashGridPositionMask);
    };
    return field(grid.x) | (field(grid.y) << kHashGridPositionBits) |
           (field(grid.z) << (2 * kHashGridPositionBits)) |
           (static_cast<uint64_t>(level & kHashGridLevelMask) << kHashGridLevelOffset) |
           (static_cast<uint64_t>(normal_bits & kHashGridNormalMask) << kHashGridNormalOffset) |
           (static_cast<uint64_t>(user_bit ? 1u : 0u) << kHashGridUserBit);
}

uint64_t hashGridKey(const Float3& position, const Float3& normal,
                     const HashGridParameters& params) {
    const HashGridCell cell = gridCell(position, params);
    return packHashGridKey(cell.grid, cell.level, normalBits(normal), false);
}

uint64_t hashGridKeyAtLevel(const Float3& position, const Float3& normal, uint32_t level,
                            const HashGridParameters& params) {
    const Float3 biased{position.x + kHashGridPositionBias, position.y + kHashGridPositionBias,
                        position.z + kHashGridPositionBias};
    return packHashGridKey(quantisePosition(biased, voxelSize(level, params)), level, normalBits(normal), false);
}

HashGridCell decodeHashGridKey(uint64_t key) {
    HashGridCell cell;
    cell.grid.x = signExtend17(static_cast<uint32_t>(key));
    cell.grid.y = signExtend17(static_cast<uint32_t>(key >> kHashGridPositionBits));
    cell.grid.z = signExtend17(static_cast<uint32_t>(key >> (2 * kHashGridPositionBits)));
    cell.level = static_cast<uint32_t>(key >> kHashGridLevelOffset) & kHashGridLevelMask;
    cell.normal_bits = static_cast<uint32_t>(key >> kHashGridNormalOffset) & kHashGridNormalMask;
    cell.user_bit = ((key >> kHashGridUserBit) & 1u) != 0;
    return cell;
}

namespace {

/// (g + 0.5) * size per axis. |g| < 2^24 for any cell a float position quantises to finely enough
/// to matter, so the int -> float conversion is exact there.
Float3 cellCenter(const Int3& g, float size) {
    return Float3{(static_cast<float>(g.x) + 0.5f) * size, (static_cast<float>(g.y) + 0.5f) * size,
                  (static_cast<float>(g.z) + 0.5f) * size};
}

/// SPEC §H.8a on a decoded cell: the key of the level-(L + 1) voxel holding it. `size` and
/// `coarser_size` are voxelSize(L) and voxelSize(L + 1).
uint64_t coarserKeyOfCell(const HashGridCell& cell, float logarithm_base, float size, float coarser_size) {
    if (cell.level >= kHashGridLevelMax) return kHashGridInvalidKey;
    const uint32_t level = cell.level + 1;
    // A power-of-two base b = 2^k: floor(p / (b s)) == floor(floor(p / s) / b), exactly in float32
    // because b s is exact and dividing by a power of two commutes with rounding.
    int exponent = 0;
    const float mantissa = std::frexp(logarithm_base, &exponent);
    if (mantissa == 0.5f && exponent >= 2) {
        const int shift = exponent - 1;
        // floor(g / 2^shift) for either sign (C++17 leaves >> of a negative value to the compiler).
        const auto floorShift = [shift](int32_t v) { return v >= 0 ? v >> shift : -((-(v + 1)) >> shift) - 1; };
        const Int3 g{floorShift(cell.grid.x), floorShift(cell.grid.y), floorShift(cell.grid.z)};
        return packHashGridKey(g, level, cell.normal_bits, cell.user_bit);
    }
    return packHashGridKey(quantisePosition(cellCenter(cell.grid, size), coarser_size), level, cell.normal_bits,
                           cell.user_bit);
}

/// The coordinate congruent to a 17-bit field (mod 2^17) within [-2^16, 2^16) of `anchor`,
/// saturated to int32 (only an anchor within 2^16 of the int32 limits can reach them).
int32_t unwrapNear(uint32_t field, int32_t anchor) {
    const uint32_t offset_field = (field - static_cast<uint32_t>(anchor)) & kHashGridPositionMask;
    const int64_t value = int64_t(anchor) + int64_t(signExtend17(offset_field));
    return static_cast<int32_t>(std::clamp<int64_t>(value, INT32_MIN, INT32_MAX));
}

}  // namespace

Float3 voxelCenter(uint64_t key, const HashGridParameters& params) {
    const HashGridCell cell = decodeHashGridKey(key);
    return cellCenter(cell.grid, voxelSize(cell.level, params));
}

uint64_t coarserKey(uint64_t key, const HashGridParameters& params) {
    const HashGridCell cell = decodeHashGridKey(key);
    if (cell.level >= kHashGridLevelMax) return kHashGridInvalidKey;
    return coarserKeyOfCell(cell, params.logarithm_base, voxelSize(cell.level, params),
                            voxelSize(cell.level + 1, params));
}

HashGridKeyDecoder::HashGridKeyDecoder(const HashGridParameters& params, const Float3& anchor)
    : logarithm_base_(params.logarithm_base), anchor_(anchor) {
    voxel_size_.resize(kHashGridLevelMax + 1);
    anchor_cell_.resize(kHashGridLevelMax + 1);
    for (uint32_t level = 0; level <= kHashGridLevelMax; ++level) {
        voxel_size_[level] = voxelSize(level, params);
        anchor_cell_[level] = quantisePosition(anchor, voxel_size_[level]);
    }
}

HashGridCell HashGridKeyDecoder::decode(uint64_t key) const {
    HashGridCell cell = decodeHashGridKey(key);
    const Int3& a = anchor_cell_[cell.level];
    cell.grid.x = unwrapNear(static_cast<uint32_t>(key), a.x);
    cell.grid.y = unwrapNear(static_cast<uint32_t>(key >> kHashGridPositionBits), a.y);
    cell.grid.z = unwrapNear(static_cast<uint32_t>(key >> (2 * kHashGridPositionBits)), a.z);
    return cell;
}

Float3 HashGridKeyDecoder::voxelCenter(uint64_t key) const {
    const HashGridCell cell = decode(key);
    return cellCenter(cell.grid, voxel_size_[cell.level]);
}

uint64_t HashGridKeyDecoder::coarserKey(uint64_t key) const {
    const HashGridCell cell = decode(key);
    if (cell.level >= kHashGridLevelMax) return kHashGridInvalidKey;
    return coarserKeyOfCell(cell, logarithm_base_, voxel_size_[cell.level], voxel_size_[cell.level + 1]);
}

uint32_t jenkins32(uint32_t a) {
    // burtleburtle.net integer hash; uint32_t arithmetic wraps as the shader's uint does.
    a = (a + 0x7ED55D16u) + (a << 12);
    a = (a ^ 0xC761C23Cu) ^ (a >> 19);
    a = (a + 0x165667B1u) + (a << 5);
    a = (a + 0xD3A2646Cu) ^ (a << 9);
    a = (a + 0xFD7046C5u) + (a << 3);
    a = (a ^ 0xB55A4F09u) ^ (a >> 16);
    return a;
}

uint32_t hashGridHash(uint64_t key) {
    return jenkins32(static_cast<uint32_t>(key)) ^ jenkins32(static_cast<uint32_t>(key >> 32));
}

uint32_t bucketProbeCount(uint32_t capacity, uint32_t bucket_size) {
    const uint32_t size = bucket_size == 0 ? 1u : bucket_size;
    return capacity < size ? capacity : size;
}

uint32_t bucketBase(uint32_t hash, uint32_t capacity, uint32_t bucket_size) {
    if (capacity == 0) return kHashGridInvalidIndex;
    const uint32_t slot = hash % capacity;
    const uint32_t last_base = capacity - bucketProbeCount(capacity, bucket_size);  // no underflow
    return slot < last_base ? slot : last_base;
}

Float3 hashDebugColor(uint64_t key) {
    const Float3 a = colorFromHash(hashGridHash(key));
    const Float3 b = colorFromHash(jenkins32(decodeHashGridKey(key).level));
    return Float3{a.x * b.x, a.y * b.y, a.z * b.z};
}

// ------------------------------------------------------------------------------------------------
// HashGridTable
// ------------------------------------------------------------------------------------------------

HashGridStatus HashGridTable::create(uint32_t capacity, HashGridTable* out, uint32_t bucket_size) {
    if (capacity == 0) return HashGridStatus::kInvalidCapacity;
    if (bucket_size == 0) return HashGridStatus::kInvalidBucketSize;
    HashGridTable table;
    static_assert(kHashGridInvalidKey == 0, "empty slots are the zero bytes of a fresh ZeroedArray");
    table.keys_ = ZeroedArray<std::atomic<uint64_t>>(capacity);
    table.bucket_size_ = bucket_size;
    *out = std::move(table);
    return HashGridStatus::kOk;
}

HashGridTable::HashGridTable(HashGridTable&& other) noexcept
    : keys_(std::move(other.keys_)),
      bucket_size_(other.bucket_size_),
      failed_inserts_(other.failed_inserts_.load(std::memory_order_relaxed)) {}

HashGridTable& HashGridTable::operator=(HashGridTable&& other) noexcept {
    keys_ = std::move(other.keys_);
    bucket_size_ = other.bucket_size_;
    failed_inserts_.store(other.failed_inserts_.load(std::memory_order_relaxed),
                          std::memory_order_relaxed);
    return *this;
}

std::optional<uint32_t> HashGridTable::insert(uint64_t key) {
    const uint32_t n = capacity();
    if (key != kHashGridInvalidKey && n != 0) {
        const uint32_t base = bucketBase(hashGridHash(key), n, bucket_size_);
        const uint32_t probes = bucketProbeCount(n, bucket_size_);
        for (uint32_t k = 0; k < probes; ++k) {
            uint64_t expected = kHashGridInvalidKey;
            // Claim an empty slot, or stop at our own key (possibly written by a racing thread).
            if (keys_[base + k].compare_exchange_strong(expected, key, std::memory_order_acq_rel,
                                                        std::memory_order_acquire) ||
                expected == key) {
                return base + k;
            }
        }
    }
    failed_inserts_.fetch_add(1, std::memory_order_relaxed);
    return std::nullopt;
}

std::optional<uint32_t> HashGridTable::find(uint64_t key) const {
    const uint32_t n = capacity();
    if (key == kHashGridInvalidKey || n == 0) return std::nullopt;
    const uint32_t base = bucketBase(hashGridHash(key), n, bucket_size_);
    const uint32_t probes = bucketProbeCount(n, bucket_size_);
    for (uint32_t k = 0; k < probes; ++k) {
        if (keys_[base + k].load(std::memory_order_acquire) == key) return base + k;
    }
    return std::nullopt;
}

void HashGridTable::prefetchBucket(uint32_t base) const {
    const uint32_t n = capacity();
    if (base >= n) return;
    const uint32_t last = std::min(n - 1, base + bucketProbeCount(n, bucket_size_) - 1);
#if defined(__GNUC__) || defined(__clang__)
    // A 16-slot window spans two or three 64-byte lines: its first and last slot cover both ends.
    __builtin_prefetch(&keys_[base]);
    __builtin_prefetch(&keys_[last]);
#else
    (void)last;
#endif
}

uint32_t HashGridTable::occupiedSlots() const {
    uint32_t count = 0;
    for (const auto& slot : keys_) {
        if (slot.load(std::memory_order_relaxed) != kHashGridInvalidKey) ++count;
    }
    return count;
}

}  // namespace sharcbake
