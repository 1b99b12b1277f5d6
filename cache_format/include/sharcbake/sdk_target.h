// SPDX-License-Identifier: Apache-2.0
/// @file sdk_target.h
/// @brief Which SHaRC SDK release a GPU engine runs, and what that changes for the buffers the
/// runtime library makes for it: the key layout, the bucket rule, the build options it can serve,
/// and how long the SDK's Resolve pass keeps a baked voxel that receives no samples.
///
/// A `.sharc` file stores keys in the SDK 1.7.2+ layout (SPEC §H.6). Releases differ in where the
/// level and normal bits sit and in how a key's 16-slot bucket is placed, so buffers built for
/// one release are not found by another (keys and hashes may agree and every lookup still miss).
/// Nothing in a cache says which release an engine runs: the engine names it here
/// (SharcSdkTarget), or measures it once with identifySharcSdkTarget(). What is verified and what
/// is written from the SDK's description only: SPEC §G and docs/engine_guide.md.
#pragma once

#include "sharcbake/cache_types.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime_export.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace sharcbake {

// ------------------------------------------------------------------------------------------------
// Targets (SPEC §G.1)
// ------------------------------------------------------------------------------------------------

/// An SDK release family: one key layout and one bucket rule. The enumerator names the first
/// release of the family.
enum class SharcSdkTarget : uint32_t {
    /// SDK 1.6.3 - 1.6.x: 10 level bits (51-60), normal bits 61-63;
    /// base = min(hash % N, N - 16); lookups scan all 16 slots.
    kSdk1_6 = 1,
    /// SDK 1.7.2 - 1.8.2 (the file's own layout; the default, what gpuBuffers always made):
    /// 9 level bits (51-59), normal bits 60-62; base = min(hash % N, N - 16).
    kSdk1_7 = 2,
    /// SDK 1.8.3 and later 1.8 releases: the 1.7 key layout; base = hash % (N - 15).
    /// Written from a third-party port of the 1.8.3 headers: unverified.
    kSdk1_8_3 = 3,
};

/// The target gpuBuffers() uses when none is named: the layout the library has always produced.
inline constexpr SharcSdkTarget kSharcSdkTargetDefault = SharcSdkTarget::kSdk1_7;

/// How a release places a key's bucket (its window of 16 contiguous, non-wrapping slots).
enum class SharcBucketRule : uint32_t {
    kClampedModulo = 1,  ///< base = min(hash % N, N - 16)  (SDK 1.5.1 - 1.8.2)
    kReducedModulo = 2,  ///< base = hash % (N - 15)        (SDK 1.8.3+, unverified)
};

/// What a target means, as constants (SPEC §G.1's table).
struct SharcSdkLayout {
    SharcSdkTarget target;
    const char* releases;    ///< "1.7.2 - 1.8.2"
    uint32_t level_bits;     ///< 10 (1.6) or 9 (1.7+)
    uint32_t level_offset;   ///< 51
    uint32_t normal_offset;  ///< 61 (1.6) or 60 (1.7+)
    uint32_t level_max;      ///< 1023 or 511: the SDK's level clamp
    SharcBucketRule bucket_rule;
    uint32_t bucket_size;  ///< 16
    /// The SDK's lookup gives up at this many empty slots of the bucket (0: scans all 16).
    /// SharcCommon.h 1.7.2+ sets HASH_GRID_LIMIT_EMPTY_SLOTS 2, which stops at the 4th.
    uint32_t lookup_empty_slot_limit;
    uint32_t min_capacity;  ///< smallest table the rule is defined for (16 for kReducedModulo)
    const char* basis;      ///< how the layout is known: "verified: ..." or "described: ..."
};

/// The constants of `target`; an unknown value gives the default target's (gpuBuffers() and
/// gpuInsertList() refuse one: kInvalidArgument).
SHARCBAKE_RUNTIME_API const SharcSdkLayout& sharcSdkLayout(SharcSdkTarget target);
/// "SHaRC SDK 1.7.2 - 1.8.2" etc.; "unknown SHaRC SDK target" for other values. Never null.
SHARCBAKE_RUNTIME_API const char* toString(SharcSdkTarget target);
/// True for the three enumerators.
SHARCBAKE_RUNTIME_API bool isKnownSharcSdkTarget(SharcSdkTarget target);

/// @brief The target for an SDK release written "1.8.2", "v1.8.2.0" or "1.6": kOk and `*out`, or
/// kUnsupportedFeature with a message that says why (1.6.0 - 1.6.2 and older use other buffer
/// layouts that the library does not make; releases newer than 1.8.x are unknown).
/// `message` (optional) also receives a note when the mapping rests on the description only, or
/// on an assumption (1.7.0 and 1.7.1, unverified, are given 1.7.2's layout).
SHARCBAKE_RUNTIME_API CacheFileStatus sharcSdkTargetForRelease(const std::string& release, SharcSdkTarget* out, std::string* message);

/// @brief A file key (SPEC §H.6 layout) in `target`'s layout: the 17-bit coordinates stay, the
/// level and normal bits move (1.6: level at 51-60, normals at 61-63). Keys of the other targets
/// are returned unchanged. Level 511, the 1.7+ clamp, is kept as 511 (SPEC §G.2).
SHARCBAKE_RUNTIME_API uint64_t sharcSdkKey(uint64_t file_key, SharcSdkTarget target);

/// @brief First slot of the bucket of `hash` in a table of `capacity` slots under `target`'s rule.
/// kClampedModulo: bucketBase() (for N < 16 the bucket is the whole table, base 0: sharcbake's
/// convention; the SDK itself needs N >= 16). kReducedModulo: hash % (N - 15), and
/// kHashGridInvalidIndex for N < 16. N == 0 gives kHashGridInvalidIndex.
SHARCBAKE_RUNTIME_API uint32_t sharcSdkBucketBase(uint32_t hash, uint32_t capacity, SharcSdkTarget target);

// ------------------------------------------------------------------------------------------------
// Build options (SPEC §G.3)
// ------------------------------------------------------------------------------------------------

/// The SDK's compile-time options that change what the resolved buffer holds or how keys look.
/// All off is the SDK's default build. SH encoding and compact keys are never served; material
/// demodulation and separate emissive are served from a cache that keeps each voxel's emission
/// and demodulation factor (section VMAT, `sharcbake bake --voxel-materials`; SPEC §G.3).
struct SharcBuildOptions {
    bool sh_encoding = false;            ///< SHARC_ENABLE_SH_ENCODING (1.8.0+)
    bool compact_keys = false;           ///< HASH_GRID_COMPACT (1.7.2+): 32-bit keys
    bool material_demodulation = false;  ///< SHARC_MATERIAL_DEMODULATION (1.5.1+)
    bool separate_emissive = false;      ///< SHARC_SEPARATE_EMISSIVE
};

/// @brief kOk for a build the library can serve on `target` from a cache with or without voxel
/// materials (CacheView::hasVoxelMaterials()), else kUnsupportedFeature and a message naming the
/// option, why baked data would read wrong, and what to change.
SHARCBAKE_RUNTIME_API CacheFileStatus checkSharcBuildOptions(const SharcBuildOptions& options, SharcSdkTarget target,
                                                             bool cache_has_voxel_materials, std::string* message);

/// @brief The demodulation factor of SHaRC's sample application for a surface with this diffuse
/// albedo and specular reflectance at normal incidence F0, per channel:
/// max(diffuse, 0.05) + max(F0, 0.02) * luminance(F0 + (1 - F0) / 21), with Rec. 709 luminance.
/// The bake stores each voxel's mean of it (VMAT); an engine built with
/// SHARC_MATERIAL_DEMODULATION must give the SDK the same factor (SPEC §G.3).
SHARCBAKE_RUNTIME_API Float3 sharcDemodulationFactor(const Float3& diffuse_albedo, const Float3& specular_f0);

// ------------------------------------------------------------------------------------------------
// Resolve (SPEC §G.4)
// ------------------------------------------------------------------------------------------------

inline constexpr uint32_t kSharcStaleFrameNumMin = 8;     ///< SHARC_STALE_FRAME_NUM_MIN
inline constexpr uint32_t kSharcStaleFrameNumMax = 1024;  ///< SHARC_STALE_FRAME_NUM_MAX
/// Largest accumulatedFrameNum the library stores: Resolve adds 1 to the 16-bit frame counter
/// (in the same 32-bit add as the stale counter) on every frame without samples, for up to 1024
/// frames; above 65535 - 1024 the carry would reach the stale counter and evict the voxel early.
inline constexpr uint32_t kSharcMaxBakedFrameNum = 0xFFFFu - kSharcStaleFrameNumMax;  // 64511

/// @brief Frames an entry written by gpuBuffers() (stale counter 0) survives the SDK's Resolve
/// when the engine's own update paths never deposit into it: clamp(stale_frame_num_max, 8, 1024)
/// - 1. It is evicted by the next Resolve. An entry that receives samples resets its counter.
SHARCBAKE_RUNTIME_API uint32_t sharcResolveFramesKept(uint32_t stale_frame_num_max);

// ------------------------------------------------------------------------------------------------
// Identifying the engine's release (SPEC §G.5)
// ------------------------------------------------------------------------------------------------

/// What an engine's own SDK computed for one probe point: the key of (position, normal) seen from
/// `camera`, and the slot its insert function returned in an empty table of the given capacity.
struct SharcSdkObservation {
    Float3 position;
    Float3 normal;
    Float3 camera;
    uint64_t key = 0;   ///< as the SDK computed it (64-bit)
    uint32_t slot = 0;  ///< as the SDK's insert returned it
};

/// @brief Which target reproduces every observation: the key layout from the keys, the bucket
/// rule from the slots (a slot must lie in its key's bucket). `grid` gives the logarithm base,
/// scene scale, level bias and capacity the engine used (its camera_position is ignored: each
/// observation has its own). Needs at least 4 observations at levels below 511; 16 distinct
/// points make a wrong match practically impossible. kOk and `*out` when exactly one target
/// fits; kUnsupportedFeature with a message naming what matched and what did not otherwise
/// (compact 32-bit keys, an unknown rule); kInvalidArgument for bad arguments.
SHARCBAKE_RUNTIME_API CacheFileStatus identifySharcSdkTarget(const HashGridParameters& grid, const SharcSdkObservation* observations,
                                       size_t count, SharcSdkTarget* out, std::string* message);

}  // namespace sharcbake
