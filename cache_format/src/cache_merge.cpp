// SPDX-License-Identifier: Apache-2.0
#include "sharcbake/cache_merge.h"

#include <algorithm>
#include <cstring>
#include <tuple>

namespace sharcbake {
namespace {

CacheFileStatus fail(std::string* message, const std::string& text) {
    if (message) *message = text;
    return CacheFileStatus::kInvalidData;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

const std::string* findMetadata(const CacheData& data, const std::string& key) {
    for (const auto& entry : data.metadata) {
        if (entry.first == key) return &entry.second;
    }
    return nullptr;
}

/// The first way `other` cannot be merged with `first`, or an empty string.
std::string incompatibility(const CacheData& first, const CacheData& other, const std::vector<std::string>& keys) {
    if (first.version_major != other.version_major || first.version_minor != other.version_minor) {
        return "format version " + std::to_string(other.version_major) + "." + std::to_string(other.version_minor) +
               " differs from " + std::to_string(first.version_major) + "." + std::to_string(first.version_minor);
    }
    for (const std::string& key : keys) {
        const std::string* a = findMetadata(first, key);
        const std::string* b = findMetadata(other, key);
        if (!a || !b || *a != *b) {
            return "metadata \"" + key + "\" differs: \"" + (b ? *b : std::string("<missing>")) + "\" vs \"" +
                   (a ? *a : std::string("<missing>")) + "\"";
        }
    }
    // After the metadata: another scene (whose fitted grid differs too) is named as such.
    // Bit-exact: the keys of two caches name the same voxels only if every parameter that feeds
    // the key is identical.
    if (!sameBits(first.logarithm_base, other.logarithm_base)) return "grid logarithm base differs";
    if (!sameBits(first.scene_scale, other.scene_scale)) return "grid scene scale differs";
    if (!sameBits(first.level_bias, other.level_bias)) return "grid level bias differs";
    if (first.bucket_size != other.bucket_size) return "grid bucket size differs";
    if (!sameBits(first.gpu_radiance_scale, other.gpu_radiance_scale)) return "GPU radiance scale differs";
    // The anchor comes from the scene's bounds: shards of one bake share it.
    if (!sameBits(first.grid_anchor.x, other.grid_anchor.x) || !sameBits(first.grid_anchor.y, other.grid_anchor.y) ||
        !sameBits(first.grid_anchor.z, other.grid_anchor.z)) {
        return "grid anchor (ANCR) differs";
    }
    if (first.voxel_materials.empty() != other.voxel_materials.empty()) {
        return std::string(other.voxel_materials.empty() ? "it has no" : "it has") +
               " voxel materials (VMAT, bake --voxel-materials) and input 1 " +
               (other.voxel_materials.empty() ? "has" : "has none");
    }
    return {};
}

/// A voxel and its material (VMAT; defaults when the inputs keep none).
struct Entry {
    CacheVoxel voxel;
    CacheVoxelMaterial material;
};

/// The voxel that several inputs hold under one key: radiance and material means weighted by
/// sample weight (shards estimate the material means from their own surface points), summed in
/// a fixed order so the result does not depend on the order of the inputs. One entry is kept as is.
Entry combine(std::vector<Entry>& same_key) {
    if (same_key.size() == 1) return same_key[0];
    std::sort(same_key.begin(), same_key.end(), [](const Entry& x, const Entry& y) {
        const CacheVoxel& a = x.voxel;
        const CacheVoxel& b = y.voxel;
        return std::tie(a.sample_weight, a.radiance[0], a.radiance[1], a.radiance[2]) <
               std::tie(b.sample_weight, b.radiance[0], b.radiance[1], b.radiance[2]);
    });
    double weight = 0.0, sum[3] = {0.0, 0.0, 0.0}, emission[3] = {0.0, 0.0, 0.0}, factor[3] = {0.0, 0.0, 0.0};
    for (const Entry& e : same_key) {
        const double w = double(e.voxel.sample_weight);
        weight += w;
        for (int c = 0; c < 3; ++c) {
            sum[c] += w * double(e.voxel.radiance[c]);
            emission[c] += w * double(e.material.emission[c]);
            factor[c] += w * double(e.material.demodulation[c]);
        }
    }
    Entry result;
    result.voxel.key = same_key[0].voxel.key;
    result.voxel.sample_weight = float(weight);
    for (int c = 0; c < 3; ++c) {
        result.voxel.radiance[c] = float(sum[c] / weight);
        result.material.emission[c] = float(emission[c] / weight);
        result.material.demodulation[c] = float(factor[c] / weight);
    }
    return result;
}

/// The first reason the inputs cannot be merged, or an empty string.
std::string inputsProblem(const std::vector<CacheData>& inputs, const std::vector<std::string>& keys_that_must_agree) {
    for (size_t i = 1; i < inputs.size(); ++i) {
        const std::string problem = incompatibility(inputs[0], inputs[i], keys_that_must_agree);
        if (!problem.empty()) return "input " + std::to_string(i + 1) + " vs input 1: " + problem;
    }
    for (size_t i = 0; i < inputs.size(); ++i) {
        const std::vector<CacheVoxel>& v = inputs[i].voxels;
        for (size_t k = 1; k < v.size(); ++k) {
            if (v[k - 1].key >= v[k].key) return "input " + std::to_string(i + 1) + ": voxels not sorted by key";
        }
        if (!inputs[i].voxel_materials.empty() && inputs[i].voxel_materials.size() != v.size()) {
            return "input " + std::to_string(i + 1) + ": voxel materials do not match the voxels";
        }
    }
    return {};
}

}  // namespace

CacheFileStatus mergeCaches(const std::vector<CacheData>& inputs, const std::vector<std::string>& keys_that_must_agree,
                            CacheData* out, std::string* message) {
    if (!out) return CacheFileStatus::kInvalidArgument;
    if (inputs.empty()) return fail(message, "nothing to merge");
    if (const std::string problem = inputsProblem(inputs, keys_that_must_agree); !problem.empty()) {
        return fail(message, problem);
    }
    const bool materials = !inputs[0].voxel_materials.empty();

    CacheData merged;
    merged.logarithm_base = inputs[0].logarithm_base;
    merged.scene_scale = inputs[0].scene_scale;
    merged.level_bias = inputs[0].level_bias;
    merged.bucket_size = inputs[0].bucket_size;
    merged.gpu_radiance_scale = inputs[0].gpu_radiance_scale;
    merged.grid_anchor = inputs[0].grid_anchor;
    merged.version_major = inputs[0].version_major;
    merged.version_minor = inputs[0].version_minor;
    for (const CacheData& input : inputs) merged.bake_capacity = std::max(merged.bake_capacity, input.bake_capacity);

    // k-way merge of the key-sorted voxel lists.
    std::vector<size_t> next(inputs.size(), 0);
    std::vector<Entry> same_key;
    same_key.reserve(inputs.size());
    for (;;) {
        uint64_t key = ~uint64_t(0);
        bool any = false;
        for (size_t i = 0; i < inputs.size(); ++i) {
            if (next[i] < inputs[i].voxels.size()) {
                key = std::min(key, inputs[i].voxels[next[i]].key);
                any = true;
            }
        }
        if (!any) break;
        same_key.clear();
        for (size_t i = 0; i < inputs.size(); ++i) {
            if (next[i] < inputs[i].voxels.size() && inputs[i].voxels[next[i]].key == key) {
                same_key.push_back(Entry{inputs[i].voxels[next[i]],
                                         materials ? inputs[i].voxel_materials[next[i]] : CacheVoxelMaterial{}});
                ++next[i];
            }
        }
        const Entry voxel = combine(same_key);
        merged.voxels.push_back(voxel.voxel);
        if (materials) merged.voxel_materials.push_back(voxel.material);
    }
    *out = std::move(merged);
    return CacheFileStatus::kOk;
}

}  // namespace sharcbake
