// SPDX-License-Identifier: Apache-2.0
// The C interface (runtime_c.h): thin wrappers over CacheView that catch everything.
#include "sharcbake/runtime_c.h"

#include "sharcbake/runtime.h"
#include "sharcbake/sdk_target.h"

#include <cstdio>
#include <cstring>
#include <new>
#include <optional>
#include <string>
#include <vector>

struct sharcbake_cache {
    sharcbake::CacheView view;
    /// Turns the view's keys into places (sharcbake_cache_voxel_location), near its anchor.
    std::optional<sharcbake::HashGridKeyDecoder> decoder;
};

namespace {

using sharcbake::CacheError;
using sharcbake::CacheFileStatus;
using sharcbake::CacheView;
using sharcbake::Float3;

static_assert(sizeof(sharcbake_packed_data) == sizeof(sharcbake::SharcPackedData), "layouts agree");
static_assert(int(SHARCBAKE_INVALID_ARGUMENT) == int(CacheFileStatus::kInvalidArgument), "status values agree");
static_assert(int(SHARCBAKE_TRAILING_BYTES) == int(CacheFileStatus::kTrailingBytes), "status values agree");

void copyMessage(const std::string& text, char* out, size_t size) {
    if (!out || size == 0) return;
    const size_t n = text.size() < size - 1 ? text.size() : size - 1;
    std::memcpy(out, text.data(), n);
    out[n] = '\0';
}

sharcbake_status finishOpen(CacheFileStatus status, CacheView& view, const CacheError& error, sharcbake_cache** out,
                            uint32_t* rule, char* message, size_t message_size) {
    if (rule) *rule = error.rule;
    copyMessage(error.message, message, message_size);
    if (status != CacheFileStatus::kOk) return sharcbake_status(status);
    sharcbake_cache* cache = new (std::nothrow) sharcbake_cache;
    if (!cache) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
    try {
        cache->decoder.emplace(view.gridParameters(), view.gridAnchor());
    } catch (const std::bad_alloc&) {
        delete cache;
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
    cache->view = std::move(view);
    *out = cache;
    return SHARCBAKE_OK;
}

Float3 f3(const float* v) { return Float3{v[0], v[1], v[2]}; }

static_assert(int(SHARCBAKE_SDK_1_6) == int(sharcbake::SharcSdkTarget::kSdk1_6), "targets agree");
static_assert(int(SHARCBAKE_SDK_1_7) == int(sharcbake::SharcSdkTarget::kSdk1_7), "targets agree");
static_assert(int(SHARCBAKE_SDK_1_8_3) == int(sharcbake::SharcSdkTarget::kSdk1_8_3), "targets agree");

sharcbake::GpuBufferOptions gpuOptions(const sharcbake_gpu_options& o) {
    sharcbake::GpuBufferOptions options;
    options.capacity = o.capacity;
    options.sdk_target = sharcbake::SharcSdkTarget(o.sdk_target);
    options.build.sh_encoding = (o.build_flags & SHARCBAKE_BUILD_SH_ENCODING) != 0;
    options.build.compact_keys = (o.build_flags & SHARCBAKE_BUILD_COMPACT_KEYS) != 0;
    options.build.material_demodulation = (o.build_flags & SHARCBAKE_BUILD_MATERIAL_DEMODULATION) != 0;
    options.build.separate_emissive = (o.build_flags & SHARCBAKE_BUILD_SEPARATE_EMISSIVE) != 0;
    options.accumulated_frame_num = o.accumulated_frame_num;
    options.max_sample_count = o.max_sample_count;
    options.radiance_scale = o.radiance_scale;
    return options;
}

void fillReport(const sharcbake::GpuRadianceReport& r, uint64_t inserted, uint64_t failed, sharcbake_gpu_report* out) {
    if (!out) return;
    *out = sharcbake_gpu_report{};
    out->inserted = inserted;
    out->failed_inserts = failed;
    out->clipped_voxels = r.clipped_voxels;
    out->flushed_voxels = r.flushed_voxels;
    out->radiance_scale = r.radiance_scale;
    out->brightest = r.brightest;
    out->fitting_radiance_scale = r.fitting_radiance_scale;
}

/// A known target and build flags, or unknown ones refused with a message (the C++ API maps
/// unknown targets to the default and has no flag word; a C caller passing garbage, or flags of an
/// SDK build this library does not know, should hear about it, not get buffers for another build).
bool knownTarget(const sharcbake_gpu_options& o, char* message, size_t message_size) {
    constexpr uint32_t kKnownFlags = SHARCBAKE_BUILD_SH_ENCODING | SHARCBAKE_BUILD_COMPACT_KEYS |
                                     SHARCBAKE_BUILD_MATERIAL_DEMODULATION | SHARCBAKE_BUILD_SEPARATE_EMISSIVE;
    if ((o.build_flags & ~kKnownFlags) != 0) {
        char text[96];
        std::snprintf(text, sizeof text, "unknown build_flags bits 0x%x (known: SHARCBAKE_BUILD_*, 0x%x)",
                      unsigned(o.build_flags & ~kKnownFlags), unsigned(kKnownFlags));
        copyMessage(text, message, message_size);
        return false;
    }
    if (sharcbake::isKnownSharcSdkTarget(sharcbake::SharcSdkTarget(o.sdk_target))) return true;
    copyMessage("unknown sdk_target " + std::to_string(o.sdk_target), message, message_size);
    return false;
}

/// Runs `find(&target, &text)` (a function answering with an SDK target and a message) for the C
/// interface: the message copied out, `*target` set only on success, exceptions caught.
template <typename Find>
sharcbake_status answerWithTarget(Find&& find, sharcbake_sdk_target* target, char* message, size_t message_size) {
    try {
        sharcbake::SharcSdkTarget t{};
        std::string text;
        const CacheFileStatus status = find(&t, &text);
        copyMessage(text, message, message_size);
        if (status == CacheFileStatus::kOk) *target = sharcbake_sdk_target(t);
        return sharcbake_status(status);
    } catch (...) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
}

}  // namespace

extern "C" {

sharcbake_status sharcbake_cache_open_file(const char* path, int map, sharcbake_cache** out, uint32_t* rule,
                                           char* message, size_t message_size) {
    // Every failure sets what the header promises (*out NULL, rule 0, a message), the argument
    // checks too: a caller printing its uninitialised buffer would print garbage.
    if (out) *out = nullptr;
    if (rule) *rule = 0;
    if (!out || !path) {
        copyMessage(!out ? "out is NULL" : "path is NULL", message, message_size);
        return SHARCBAKE_INVALID_ARGUMENT;
    }
    try {
        CacheView view;
        CacheError error;
        const CacheFileStatus status = CacheView::openFile(
            path, &view, &error, map ? CacheView::FileMode::kMap : CacheView::FileMode::kRead);
        return finishOpen(status, view, error, out, rule, message, message_size);
    } catch (...) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
}

sharcbake_status sharcbake_cache_open_memory(const void* data, size_t size, sharcbake_cache** out, uint32_t* rule,
                                             char* message, size_t message_size) {
    if (rule) *rule = 0;
    if (!out) {
        copyMessage("out is NULL", message, message_size);
        return SHARCBAKE_INVALID_ARGUMENT;
    }
    *out = nullptr;
    try {
        CacheView view;
        CacheError error;
        const CacheFileStatus status = CacheView::openMemory(data, size, &view, &error);
        return finishOpen(status, view, error, out, rule, message, message_size);
    } catch (...) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
}

void sharcbake_cache_close(sharcbake_cache* cache) { delete cache; }

const char* sharcbake_status_string(sharcbake_status status) {
    return sharcbake::toString(CacheFileStatus(status));
}

uint64_t sharcbake_cache_voxel_count(const sharcbake_cache* cache) { return cache ? cache->view.voxelCount() : 0; }

uint32_t sharcbake_cache_level_count(const sharcbake_cache* cache) {
    return cache ? uint32_t(cache->view.levels().size()) : 0;
}

int sharcbake_cache_level(const sharcbake_cache* cache, uint32_t index, uint32_t* level, uint32_t* voxel_count) {
    if (!cache || index >= cache->view.levels().size()) return 0;
    if (level) *level = cache->view.levels()[index].level;
    if (voxel_count) *voxel_count = cache->view.levels()[index].voxel_count;
    return 1;
}

void sharcbake_cache_grid(const sharcbake_cache* cache, float* logarithm_base, float* scene_scale, float* level_bias,
                          uint32_t* bake_capacity) {
    if (!cache) return;
    const sharcbake::HashGridParameters p = cache->view.gridParameters();
    if (logarithm_base) *logarithm_base = p.logarithm_base;
    if (scene_scale) *scene_scale = p.scene_scale;
    if (level_bias) *level_bias = p.level_bias;
    if (bake_capacity) *bake_capacity = cache->view.bakeCapacity();
}

int sharcbake_cache_voxel(const sharcbake_cache* cache, uint64_t index, uint64_t* key, float radiance[3],
                          float* sample_weight) {
    if (!cache || index >= cache->view.voxelCount()) return 0;
    const sharcbake::CacheVoxel v = cache->view.voxel(index);
    if (key) *key = v.key;
    if (radiance) std::memcpy(radiance, v.radiance, sizeof v.radiance);
    if (sample_weight) *sample_weight = v.sample_weight;
    return 1;
}

int sharcbake_cache_voxel_location(const sharcbake_cache* cache, uint64_t index, float center[3], float* size,
                                   uint32_t* level, uint32_t* normal_bits) {
    if (!cache || index >= cache->view.voxelCount()) return 0;
    const uint64_t key = cache->view.voxel(index).key;
    const sharcbake::HashGridCell cell = cache->decoder->decode(key);
    if (center) {
        const Float3 c = cache->decoder->voxelCenter(key);
        center[0] = c.x;
        center[1] = c.y;
        center[2] = c.z;
    }
    if (size) *size = sharcbake::voxelSize(cell.level, cache->view.gridParameters());
    if (level) *level = cell.level;
    if (normal_bits) *normal_bits = cell.normal_bits;
    return 1;
}

sharcbake_status sharcbake_cache_build_lookup_index(sharcbake_cache* cache) {
    if (!cache) return SHARCBAKE_INVALID_ARGUMENT;
    return sharcbake_status(cache->view.buildLookupIndex());
}

void sharcbake_cache_grid_anchor(const sharcbake_cache* cache, float anchor[3]) {
    if (!cache || !anchor) return;
    const Float3& a = cache->view.gridAnchor();
    anchor[0] = a.x;
    anchor[1] = a.y;
    anchor[2] = a.z;
}

int sharcbake_cache_metadata(const sharcbake_cache* cache, const char* key, char* value, size_t value_size) {
    if (!cache || !key) return 0;
    bool found = false;
    const std::string_view v = cache->view.metadata(key, &found);
    if (found && value && value_size > 0) {
        const size_t n = v.size() < value_size - 1 ? v.size() : value_size - 1;
        std::memcpy(value, v.data(), n);
        value[n] = '\0';
    }
    return found ? 1 : 0;
}

int sharcbake_cache_lookup(const sharcbake_cache* cache, const float position[3], const float normal[3],
                           const float camera_position[3], float radiance[3]) {
    if (!cache || !position || !normal || !camera_position) return 0;
    Float3 r;
    if (!cache->view.lookup(f3(position), f3(normal), f3(camera_position), &r)) return 0;
    if (radiance) {
        radiance[0] = r.x;
        radiance[1] = r.y;
        radiance[2] = r.z;
    }
    return 1;
}

int sharcbake_cache_lookup_nearest_level(const sharcbake_cache* cache, const float position[3],
                                         const float normal[3], const float camera_position[3], float radiance[3],
                                         uint32_t* level_used) {
    if (!cache || !position || !normal || !camera_position) return 0;
    Float3 r;
    if (!cache->view.lookupNearestLevel(f3(position), f3(normal), f3(camera_position), &r, level_used)) return 0;
    if (radiance) {
        radiance[0] = r.x;
        radiance[1] = r.y;
        radiance[2] = r.z;
    }
    return 1;
}

size_t sharcbake_cache_lookup_batch(const sharcbake_cache* cache, size_t count, const float* positions,
                                    const float* normals, const float camera_position[3], float* radiance,
                                    uint8_t* hits, int nearest_level) {
    if (!cache || !positions || !normals || !camera_position || !radiance) return 0;
    static_assert(sizeof(Float3) == 3 * sizeof(float), "Float3 is three packed floats");
    return cache->view.lookupBatch(count, reinterpret_cast<const Float3*>(positions),
                                   reinterpret_cast<const Float3*>(normals), f3(camera_position),
                                   reinterpret_cast<Float3*>(radiance), hits, nearest_level != 0);
}

sharcbake_status sharcbake_cache_gpu_buffers(const sharcbake_cache* cache, uint32_t capacity,
                                             uint32_t accumulated_frame_num, uint64_t* hash_entries,
                                             sharcbake_packed_data* resolved, uint64_t* failed_inserts) {
    if (!cache || !hash_entries || !resolved) return SHARCBAKE_INVALID_ARGUMENT;
    try {
        sharcbake::GpuBufferOptions options;
        options.capacity = capacity;
        options.accumulated_frame_num = accumulated_frame_num;
        sharcbake::GpuBuffers buffers;
        const CacheFileStatus status = cache->view.gpuBuffers(options, &buffers);
        if (status != CacheFileStatus::kOk) return sharcbake_status(status);
        std::memcpy(hash_entries, buffers.hash_entries.data(), size_t(capacity) * sizeof(uint64_t));
        std::memcpy(resolved, buffers.resolved.data(), size_t(capacity) * sizeof(sharcbake_packed_data));
        if (failed_inserts) *failed_inserts = buffers.failed_inserts;
        return SHARCBAKE_OK;
    } catch (...) {
        return SHARCBAKE_IO_ERROR;
    }
}

void sharcbake_gpu_options_init(sharcbake_gpu_options* options) {
    if (!options) return;
    const sharcbake::GpuBufferOptions d;
    options->capacity = d.capacity;
    options->sdk_target = uint32_t(d.sdk_target);
    options->build_flags = 0;
    options->accumulated_frame_num = d.accumulated_frame_num;
    options->max_sample_count = d.max_sample_count;
    options->radiance_scale = d.radiance_scale;
}

float sharcbake_cache_gpu_radiance_scale(const sharcbake_cache* cache) {
    return cache ? cache->view.gpuRadianceScale() : 0.0f;
}

sharcbake_status sharcbake_cache_gpu_buffers_ex(const sharcbake_cache* cache, const sharcbake_gpu_options* options,
                                                uint64_t* hash_entries, sharcbake_packed_data* resolved,
                                                sharcbake_gpu_report* report, char* message, size_t message_size) {
    copyMessage("", message, message_size);
    if (!cache || !options || !hash_entries || !resolved) return SHARCBAKE_INVALID_ARGUMENT;
    if (!knownTarget(*options, message, message_size)) return SHARCBAKE_INVALID_ARGUMENT;
    try {
        sharcbake::GpuBuffers buffers;
        CacheError error;
        const CacheFileStatus status = cache->view.gpuBuffers(gpuOptions(*options), &buffers, &error);
        copyMessage(error.message, message, message_size);
        if (status != CacheFileStatus::kOk) return sharcbake_status(status);
        std::memcpy(hash_entries, buffers.hash_entries.data(), size_t(buffers.capacity) * sizeof(uint64_t));
        std::memcpy(resolved, buffers.resolved.data(), size_t(buffers.capacity) * sizeof(sharcbake_packed_data));
        fillReport(buffers.radiance, buffers.inserted, buffers.failed_inserts, report);
        return SHARCBAKE_OK;
    } catch (...) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
}

sharcbake_status sharcbake_cache_gpu_insert_list(const sharcbake_cache* cache, const sharcbake_gpu_options* options,
                                                 uint64_t* keys, sharcbake_packed_data* values,
                                                 sharcbake_gpu_report* report, char* message, size_t message_size) {
    copyMessage("", message, message_size);
    if (!cache || !options || ((!keys || !values) && cache->view.voxelCount() > 0)) return SHARCBAKE_INVALID_ARGUMENT;
    if (!knownTarget(*options, message, message_size)) return SHARCBAKE_INVALID_ARGUMENT;
    try {
        sharcbake::GpuInsertList list;
        CacheError error;
        const CacheFileStatus status = cache->view.gpuInsertList(gpuOptions(*options), &list, &error);
        copyMessage(error.message, message, message_size);
        if (status != CacheFileStatus::kOk) return sharcbake_status(status);
        if (!list.keys.empty()) {
            std::memcpy(keys, list.keys.data(), list.keys.size() * sizeof(uint64_t));
            std::memcpy(values, list.values.data(), list.values.size() * sizeof(sharcbake_packed_data));
        }
        fillReport(list.radiance, list.keys.size(), 0, report);
        return SHARCBAKE_OK;
    } catch (...) {
        copyMessage("out of memory", message, message_size);
        return SHARCBAKE_IO_ERROR;
    }
}

sharcbake_status sharcbake_sdk_target_for_release(const char* release, sharcbake_sdk_target* target, char* message,
                                                  size_t message_size) {
    copyMessage("", message, message_size);
    if (!release || !target) return SHARCBAKE_INVALID_ARGUMENT;
    return answerWithTarget(
        [&](sharcbake::SharcSdkTarget* t, std::string* text) {
            return sharcbake::sharcSdkTargetForRelease(release, t, text);
        },
        target, message, message_size);
}

sharcbake_status sharcbake_identify_sdk_target(float logarithm_base, float scene_scale, float level_bias,
                                               uint32_t capacity, const sharcbake_sdk_observation* observations,
                                               size_t count, sharcbake_sdk_target* target, char* message,
                                               size_t message_size) {
    copyMessage("", message, message_size);
    if (!target || (!observations && count > 0)) {
        copyMessage("sharcbake_identify_sdk_target: target and observations must not be NULL", message, message_size);
        return SHARCBAKE_INVALID_ARGUMENT;
    }
    return answerWithTarget(
        [&](sharcbake::SharcSdkTarget* t, std::string* text) {
        sharcbake::HashGridParameters grid;
        grid.logarithm_base = logarithm_base;
        grid.scene_scale = scene_scale;
        grid.level_bias = level_bias;
        grid.capacity = capacity;
        std::vector<sharcbake::SharcSdkObservation> seen(count);
        for (size_t i = 0; i < count; ++i) {
            const sharcbake_sdk_observation& o = observations[i];
            seen[i].position = sharcbake::Float3{o.position[0], o.position[1], o.position[2]};
            seen[i].normal = sharcbake::Float3{o.normal[0], o.normal[1], o.normal[2]};
            seen[i].camera = sharcbake::Float3{o.camera[0], o.camera[1], o.camera[2]};
            seen[i].key = o.key;
            seen[i].slot = o.slot;
        }
        return sharcbake::identifySharcSdkTarget(grid, seen.data(), seen.size(), t, text);
        },
        target, message, message_size);
}

uint32_t sharcbake_resolve_frames_kept(uint32_t stale_frame_num_max) {
    return sharcbake::sharcResolveFramesKept(stale_frame_num_max);
}

}  // extern "C"
