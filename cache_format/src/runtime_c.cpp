// SPDX-License-Identifier: Apache-2.0
// The C interface (runtime_c.h): thin wrappers over CacheView that catch everything.
#include "sharcbake/runtime_c.h"

#include "sharcbake/runtime.h"

#include <cstring>
#include <new>

struct sharcbake_cache {
    sharcbake::CacheView view;
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
    cache->view = std::move(view);
    *out = cache;
    return SHARCBAKE_OK;
}

Float3 f3(const float* v) { return Float3{v[0], v[1], v[2]}; }

}  // namespace

extern "C" {

sharcbake_status sharcbake_cache_open_file(const char* path, int map, sharcbake_cache** out, uint32_t* rule,
                                           char* message, size_t message_size) {
    if (!out || !path) return SHARCBAKE_INVALID_ARGUMENT;
    *out = nullptr;
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
    if (!out) return SHARCBAKE_INVALID_ARGUMENT;
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

}  // extern "C"
