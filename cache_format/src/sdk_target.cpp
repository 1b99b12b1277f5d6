// SPDX-License-Identifier: Apache-2.0
// SHaRC SDK targets (SPEC.md §G): key layouts, bucket rules, build options, Resolve's stale
// limit, and identifying an engine's release from what its SDK computed.
#include "sharcbake/sdk_target.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <vector>

namespace sharcbake {
namespace {

// SPEC §G.1. The bases say how each row is known; docs/engine_guide.md repeats them for engines.
constexpr SharcSdkLayout kLayouts[] = {
    {SharcSdkTarget::kSdk1_6, "1.6.3 - 1.6.x", 10, 51, 61, 1023, SharcBucketRule::kClampedModulo, 16, 0, 1,
     "described: the SDK 1.6.3 headers as documented (10 level bits, normal bits 61-63, the bucket rule of "
     "1.5.1 - 1.8.2); not checked against SDK code, tested only against an emulation of that description"},
    {SharcSdkTarget::kSdk1_7, "1.7.2 - 1.8.2", 9, 51, 60, 511, SharcBucketRule::kClampedModulo, 16, 2, 1,
     "verified for 1.7.2 - 1.8.0: keys, hashes and bucket bases against vectors computed from the SDK's 1.7-era "
     "hash-grid code, and buffers found by an independent emulation of its query; 1.8.2 from the description of "
     "its source only"},
    {SharcSdkTarget::kSdk1_8_3, "1.8.3 and later 1.8", 9, 51, 60, 511, SharcBucketRule::kReducedModulo, 16, 2, 16,
     "unverified: the bucket rule hash % (N - 15) comes from a third-party port of the 1.8.3 headers; the rest "
     "as 1.7.2 - 1.8.2"},
};

constexpr uint64_t kPositionFields = (uint64_t(1) << 51) - 1;  // bits 0-50: x, y, z (17 bits each)

std::string hex64(uint64_t v) {
    char buf[24];
    std::snprintf(buf, sizeof buf, "0x%016llX", static_cast<unsigned long long>(v));
    return buf;
}

void setMessage(std::string* message, const std::string& text) {
    if (message) *message = text;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
// Targets
// ------------------------------------------------------------------------------------------------

bool isKnownSharcSdkTarget(SharcSdkTarget target) {
    return target == SharcSdkTarget::kSdk1_6 || target == SharcSdkTarget::kSdk1_7 ||
           target == SharcSdkTarget::kSdk1_8_3;
}

const SharcSdkLayout& sharcSdkLayout(SharcSdkTarget target) {
    for (const SharcSdkLayout& layout : kLayouts) {
        if (layout.target == target) return layout;
    }
    return kLayouts[1];
}

const char* toString(SharcSdkTarget target) {
    switch (target) {
        case SharcSdkTarget::kSdk1_6: return "SHaRC SDK 1.6.3 - 1.6.x";
        case SharcSdkTarget::kSdk1_7: return "SHaRC SDK 1.7.2 - 1.8.2";
        case SharcSdkTarget::kSdk1_8_3: return "SHaRC SDK 1.8.3 and later 1.8";
    }
    return "unknown SHaRC SDK target";
}

CacheFileStatus sharcSdkTargetForRelease(const std::string& release, SharcSdkTarget* out, std::string* message) {
    if (message) message->clear();
    if (!out) return CacheFileStatus::kInvalidArgument;
    // "1.8.2", "v1.8.2.0", "1.6": two to four dot-separated numbers.
    size_t at = (!release.empty() && (release[0] == 'v' || release[0] == 'V')) ? 1 : 0;
    uint32_t parts[4] = {0, 0, 0, 0};
    size_t count = 0;
    bool well_formed = true;
    while (well_formed && at < release.size()) {
        const size_t start = at;
        uint32_t value = 0;
        while (at < release.size() && std::isdigit(static_cast<unsigned char>(release[at])) && at - start < 6) {
            value = value * 10 + uint32_t(release[at++] - '0');
        }
        well_formed = at > start && count < 4 && (at == release.size() || release[at] == '.');
        if (well_formed) parts[count++] = value;
        if (at < release.size() && ++at == release.size()) well_formed = false;  // a trailing dot
    }
    if (!well_formed || count < 2) {
        setMessage(message, "SDK release \"" + release + "\": expected a version such as 1.8.2");
        return CacheFileStatus::kInvalidArgument;
    }
    const uint32_t major = parts[0], minor = parts[1], patch = parts[2];
    const std::string name = std::to_string(major) + "." + std::to_string(minor) + "." + std::to_string(patch);
    if (major != 1 || minor > 8) {
        setMessage(message, "SDK " + name +
                                " is newer than the releases this library knows (up to 1.8.x): run "
                                "identifySharcSdkTarget with a few points computed by the engine's SDK");
        return CacheFileStatus::kUnsupportedFeature;
    }
    if (minor < 6 || (minor == 6 && patch < 3)) {
        setMessage(message, "SDK " + name +
                                " keeps its voxel data in another layout (1.6.0 - 1.6.2: float32 sums with x16 "
                                "sample counts; up to 1.5.x: two integer voxel-data buffers, up to 1.4.x 32-slot "
                                "buckets); the library makes the 1.6.3+ resolved layout only: update the SDK");
        return CacheFileStatus::kUnsupportedFeature;
    }
    if (minor == 6) {
        *out = SharcSdkTarget::kSdk1_6;
        setMessage(message,
                   "1.6.3 - 1.6.x: described, not verified against SDK code (identifySharcSdkTarget checks it)");
    } else if (minor == 7 || patch < 3) {
        *out = SharcSdkTarget::kSdk1_7;
        if (minor == 7 && patch < 2) {
            setMessage(message, name +
                                    ": assumed to have 1.7.2's layout, which was verified; this release was not "
                                    "(identifySharcSdkTarget checks it)");
        } else if (minor == 8 && patch >= 1) {
            setMessage(message, name +
                                    ": from the description of 1.8.2's source, not verified against SDK code "
                                    "(identifySharcSdkTarget checks it)");
        }
    } else {
        *out = SharcSdkTarget::kSdk1_8_3;
        setMessage(message,
                   "1.8.3+: bucket rule from a third-party port, unverified (identifySharcSdkTarget checks it)");
    }
    return CacheFileStatus::kOk;
}

uint64_t sharcSdkKey(uint64_t file_key, SharcSdkTarget target) {
    if (target != SharcSdkTarget::kSdk1_6) return file_key;
    const uint64_t level = (file_key >> kHashGridLevelOffset) & kHashGridLevelMask;
    const uint64_t normal_bits = (file_key >> kHashGridNormalOffset) & kHashGridNormalMask;
    const SharcSdkLayout& layout = sharcSdkLayout(target);
    return (file_key & kPositionFields) | level << layout.level_offset | normal_bits << layout.normal_offset;
}

uint32_t sharcSdkBucketBase(uint32_t hash, uint32_t capacity, SharcSdkTarget target) {
    if (capacity == 0) return kHashGridInvalidIndex;
    if (sharcSdkLayout(target).bucket_rule == SharcBucketRule::kReducedModulo) {
        const uint32_t window = kHashGridBucketSize - 1;  // N - 15 bases, each window inside the table
        return capacity < kHashGridBucketSize ? kHashGridInvalidIndex : hash % (capacity - window);
    }
    return bucketBase(hash, capacity, kHashGridBucketSize);
}

// ------------------------------------------------------------------------------------------------
// Build options
// ------------------------------------------------------------------------------------------------

CacheFileStatus checkSharcBuildOptions(const SharcBuildOptions& options, SharcSdkTarget target,
                                       bool cache_has_voxel_materials, std::string* message) {
    std::string refused;
    const auto refuse = [&](const char* text) {
        if (!refused.empty()) refused += "; ";
        refused += text;
    };
    if (options.sh_encoding) {
        refuse(
            "SHARC_ENABLE_SH_ENCODING=1 is not supported: its resolved entries hold 24 bytes of directional "
            "(SH) radiance, and a bake stores one mean per voxel without direction; build the SDK with SH "
            "encoding off (the default)");
    }
    if (options.compact_keys) {
        refuse(
            "HASH_GRID_COMPACT=1 is not supported: its 32-bit keys hold 8-bit coordinates and 5-bit levels, "
            "baked keys have 17-bit coordinates (8 bits make distinct voxels share a key once the scene "
            "scale exceeds about 64); build the SDK with 64-bit keys (the default)");
    }
    if (options.material_demodulation && !cache_has_voxel_materials) {
        refuse(
            "SHARC_MATERIAL_DEMODULATION=1 needs a cache that keeps each voxel's demodulation factor: the engine "
            "multiplies what it reads by the hit's factor, and this cache's radiance cannot be demodulated "
            "(it has no VMAT section), so surfaces would be multiplied by their albedo twice; re-bake with "
            "'sharcbake bake --voxel-materials', or build the SDK with demodulation off");
    }
    if (options.separate_emissive && !cache_has_voxel_materials) {
        refuse(
            "SHARC_SEPARATE_EMISSIVE=1 needs a cache that keeps each voxel's emission: the engine adds the hit's "
            "emission to what it reads, and this cache's radiance includes emission that cannot be taken out "
            "(it has no VMAT section), so emitters would count twice; re-bake with "
            "'sharcbake bake --voxel-materials', or build the SDK with separate emissive off");
    }
    if (!isKnownSharcSdkTarget(target)) refuse("unknown SDK target");
    if (refused.empty()) {
        if (message) message->clear();
        return CacheFileStatus::kOk;
    }
    setMessage(message, std::string(toString(target)) + ": " + refused);
    return CacheFileStatus::kUnsupportedFeature;
}

// ------------------------------------------------------------------------------------------------
// Resolve
// ------------------------------------------------------------------------------------------------

uint32_t sharcResolveFramesKept(uint32_t stale_frame_num_max) {
    return std::clamp(stale_frame_num_max, kSharcStaleFrameNumMin, kSharcStaleFrameNumMax) - 1;
}

// ------------------------------------------------------------------------------------------------
// Identifying the engine's release
// ------------------------------------------------------------------------------------------------

CacheFileStatus identifySharcSdkTarget(const HashGridParameters& grid, const SharcSdkObservation* observations,
                                       size_t count, SharcSdkTarget* out, std::string* message) {
    if (message) message->clear();
    if (!out || (!observations && count > 0)) return CacheFileStatus::kInvalidArgument;
    if (count < 4) {
        setMessage(message, "identifySharcSdkTarget: needs at least 4 observations (16 recommended)");
        return CacheFileStatus::kInvalidArgument;
    }
    if (validateHashGridParameters(grid) != HashGridStatus::kOk || grid.capacity < kHashGridBucketSize) {
        setMessage(message, std::string("identifySharcSdkTarget: grid parameters: ") +
                                (grid.capacity < kHashGridBucketSize ? "capacity below 16"
                                                                     : toString(validateHashGridParameters(grid))));
        return CacheFileStatus::kInvalidArgument;
    }
    std::vector<uint64_t> file_keys(count);
    for (size_t i = 0; i < count; ++i) {
        HashGridParameters params = grid;
        params.camera_position = observations[i].camera;
        file_keys[i] = hashGridKey(observations[i].position, observations[i].normal, params);
        if (((file_keys[i] >> kHashGridLevelOffset) & kHashGridLevelMask) == kHashGridLevelMax) {
            setMessage(message, "identifySharcSdkTarget: observation " + std::to_string(i) +
                                    " is at the last level (511), where the layouts clamp differently; use points "
                                    "at ordinary distances from the camera");
            return CacheFileStatus::kInvalidArgument;
        }
    }
    std::vector<SharcSdkTarget> matches;
    std::string why;  // the first mismatch of each target
    for (const SharcSdkLayout& layout : kLayouts) {
        std::string mismatch;
        for (size_t i = 0; i < count && mismatch.empty(); ++i) {
            const SharcSdkObservation& o = observations[i];
            const uint64_t expected = sharcSdkKey(file_keys[i], layout.target);
            if (o.key != expected) {
                mismatch = "observation " + std::to_string(i) + " key " + hex64(o.key) + " is not " + hex64(expected);
                continue;
            }
            const uint32_t base = sharcSdkBucketBase(hashGridHash(o.key), grid.capacity, layout.target);
            if (o.slot < base || o.slot - base >= layout.bucket_size) {
                mismatch = "observation " + std::to_string(i) + " slot " + std::to_string(o.slot) +
                           " is outside the bucket [" + std::to_string(base) + ", " +
                           std::to_string(base + layout.bucket_size - 1) + "]";
            }
        }
        if (mismatch.empty()) {
            matches.push_back(layout.target);
        } else {
            why += std::string(why.empty() ? "" : "; ") + layout.releases + ": " + mismatch;
        }
    }
    if (matches.size() == 1) {
        *out = matches[0];
        setMessage(message,
                   std::string("matches ") + toString(matches[0]) + " (" + sharcSdkLayout(matches[0]).basis + ")");
        return CacheFileStatus::kOk;
    }
    if (matches.empty()) {
        setMessage(message, "no known SDK layout reproduces the observations (" + why +
                                "); compact 32-bit keys, other grid parameters than the engine's (the capacity "
                                "must be the scratch table's), or a release with another bucket rule?");
    } else {
        // 1.6 and 1.7 keys differ only where a normal bit is set: probes whose normals have no
        // negative component (a floor, walls facing +x) cannot tell them apart.
        setMessage(message,
                   "the observations fit more than one release; add observations whose normals have a negative "
                   "component (a ceiling, walls facing -x or -z): the releases' keys differ only in the normal bits");
    }
    return CacheFileStatus::kUnsupportedFeature;
}

Float3 sharcDemodulationFactor(const Float3& diffuse_albedo, const Float3& specular_f0) {
    const float d[3] = {diffuse_albedo.x, diffuse_albedo.y, diffuse_albedo.z};
    const float f0[3] = {specular_f0.x, specular_f0.y, specular_f0.z};
    // The specular term's scale: the luminance of F0 + (1 - F0) / 21, Schlick's Fresnel averaged
    // over the hemisphere (1/21 is the cosine-weighted mean of (1 - cos)^5 times 2).
    float average_fresnel[3];
    for (int c = 0; c < 3; ++c) average_fresnel[c] = f0[c] + (1.0f - f0[c]) / 21.0f;
    const float luminance = 0.2126f * average_fresnel[0] + 0.7152f * average_fresnel[1] + 0.0722f * average_fresnel[2];
    float m[3];
    for (int c = 0; c < 3; ++c) m[c] = std::max(d[c], 0.05f) + std::max(f0[c], 0.02f) * luminance;
    return Float3{m[0], m[1], m[2]};
}

}  // namespace sharcbake
