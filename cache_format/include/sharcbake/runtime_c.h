/* SPDX-License-Identifier: Apache-2.0 */
/**
 * @file runtime_c.h
 * @brief Plain C interface over sharcbake::CacheView (runtime.h): open + validate a .sharc
 * cache, look up radiance, iterate voxels, build SHaRC GPU buffers.
 *
 * Every function is safe for untrusted files, never throws across the boundary and reports
 * failures as a sharcbake_status (the values of sharcbake::CacheFileStatus) plus, where a
 * message buffer is given, a NUL-terminated message (truncated to fit).
 */
#ifndef SHARCBAKE_RUNTIME_C_H
#define SHARCBAKE_RUNTIME_C_H

#include "sharcbake/runtime_export.h"

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sharcbake_status {
    SHARCBAKE_OK = 0,
    SHARCBAKE_IO_ERROR = 1,
    SHARCBAKE_BAD_MAGIC = 2,
    SHARCBAKE_UNSUPPORTED_VERSION = 3,
    SHARCBAKE_TRUNCATED = 4,
    SHARCBAKE_CORRUPT = 5,
    SHARCBAKE_INVALID_DATA = 6,
    SHARCBAKE_CHECKSUM_MISMATCH = 7,
    SHARCBAKE_UNSUPPORTED_FEATURE = 8,
    SHARCBAKE_TRAILING_BYTES = 9,
    SHARCBAKE_INVALID_ARGUMENT = 10
} sharcbake_status;

/** An open, validated cache. */
typedef struct sharcbake_cache sharcbake_cache;

/** SHaRC SharcPackedData (SDK 1.6.3 - 1.8.x): fp16 x4 (mean RGB, sample count), sampleData, sampleDataExt. */
typedef struct sharcbake_packed_data {
    uint16_t radiance[4];
    uint32_t sample_data;
    uint32_t sample_data_ext;
} sharcbake_packed_data;

/** Reads (map = 0) or maps (map != 0) a file and validates it. *out is NULL on failure.
 * A mapped file truncated while open raises SIGBUS on access: map only files nobody changes;
 * untrusted or shared files should be read (map = 0).
 *  `rule` (optional) receives the SPEC validation rule number (0 if none). */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_open_file(const char* path, int map, sharcbake_cache** out,
                                                                 uint32_t* rule, char* message, size_t message_size);
/** Validates `size` bytes at `data` and views them without copying (keep them alive). */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_open_memory(const void* data, size_t size, sharcbake_cache** out,
                                                                   uint32_t* rule, char* message, size_t message_size);
/** Builds the in-memory lookup index (CacheView::buildLookupIndex): each lookup then reads one
 *  slot next to its radiance instead of binary-searching the file's keys, and batched lookups
 *  overlap their memory misses (24 bytes x 1.5..3 per voxel). Call once after opening, before
 *  other threads use the cache. SHARCBAKE_IO_ERROR if the memory cannot be had (lookups keep
 *  working, unindexed); SHARCBAKE_INVALID_ARGUMENT for NULL. Linear in the voxels for any file: keys
 *  crafted to collide in the index leave it unbuilt (SHARCBAKE_OK), lookups then binary-search. */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_build_lookup_index(sharcbake_cache* cache);
/** Closes a cache (NULL is allowed). */
SHARCBAKE_RUNTIME_API void sharcbake_cache_close(sharcbake_cache* cache);

/** Human-readable status name; never NULL. */
SHARCBAKE_RUNTIME_API const char* sharcbake_status_string(sharcbake_status status);

SHARCBAKE_RUNTIME_API uint64_t sharcbake_cache_voxel_count(const sharcbake_cache* cache);
SHARCBAKE_RUNTIME_API uint32_t sharcbake_cache_level_count(const sharcbake_cache* cache);
/** Level `index` (ascending) and its voxel count; 0 if out of range. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_level(const sharcbake_cache* cache, uint32_t index, uint32_t* level,
                                                uint32_t* voxel_count);
/** Grid parameters: log base, scene scale, level bias, bake capacity (any pointer may be NULL). */
SHARCBAKE_RUNTIME_API void sharcbake_cache_grid(const sharcbake_cache* cache, float* logarithm_base, float* scene_scale,
                                                float* level_bias, uint32_t* bake_capacity);
/** Voxel `index` (sorted by key); returns 0 if out of range. Output pointers may be NULL. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_voxel(const sharcbake_cache* cache, uint64_t index, uint64_t* key,
                                                float radiance[3], float* sample_weight);
/** Where voxel `index` (sorted by key) lies, for tools that draw or export voxels: its centre in
 *  world units (float32, as the SDK's HashGridGetPositionFromKey: the +1e-4 position bias is not
 *  removed), its edge length, its level and its 3 normal sign bits (bit 0 set: x < 0, bit 1: y,
 *  bit 2: z). A key keeps 17 bits of each grid coordinate; they are decoded to the cell nearest
 *  the file's grid anchor, so voxels of a scene far from the origin are placed where they were
 *  baked. Lookups never need this. Returns 0 if out of range; output pointers may be NULL. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_voxel_location(const sharcbake_cache* cache, uint64_t index, float center[3],
                                                         float* size, uint32_t* level, uint32_t* normal_bits);
/** The grid anchor keys are decoded near (SPEC F.8c): the centre of the scene's bounds for a
 *  scene that reaches beyond 2^16 voxels of the origin, else the origin. */
SHARCBAKE_RUNTIME_API void sharcbake_cache_grid_anchor(const sharcbake_cache* cache, float anchor[3]);
/** Metadata value of `key` (NUL-terminated copy into `value`); returns 1 if present. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_metadata(const sharcbake_cache* cache, const char* key, char* value,
                                                   size_t value_size);

/** Exact SHaRC lookup; 1 on a hit (radiance written), 0 on a miss. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_lookup(const sharcbake_cache* cache, const float position[3],
                                                 const float normal[3], const float camera_position[3],
                                                 float radiance[3]);
/** Lookup falling back to the nearest level present; `level_used` may be NULL. */
SHARCBAKE_RUNTIME_API int sharcbake_cache_lookup_nearest_level(const sharcbake_cache* cache, const float position[3],
                                                               const float normal[3], const float camera_position[3],
                                                               float radiance[3], uint32_t* level_used);
/** `count` lookups: positions/normals/radiance are 3*count floats; hits (optional) count bytes.
 *  Returns the number of hits. */
SHARCBAKE_RUNTIME_API size_t sharcbake_cache_lookup_batch(const sharcbake_cache* cache, size_t count,
                                                          const float* positions, const float* normals,
                                                          const float camera_position[3], float* radiance,
                                                          uint8_t* hits, int nearest_level);

/** Fills `hash_entries` (capacity u64) and `resolved` (capacity entries) for a SHaRC table of
 *  `capacity` slots, for SDK 1.7.2 - 1.8.2 (sharcbake_cache_gpu_buffers_ex names other releases).
 *  accumulated_frame_num: see GpuBufferOptions. `failed_inserts` optional. */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_gpu_buffers(const sharcbake_cache* cache, uint32_t capacity,
                                                                   uint32_t accumulated_frame_num,
                                                                   uint64_t* hash_entries,
                                                                   sharcbake_packed_data* resolved,
                                                                   uint64_t* failed_inserts);

/* SHaRC SDK targets, build options and GPU buffers for them (SPEC.md section G) ------------ */

/** The SDK release family an engine runs (sharcbake::SharcSdkTarget). */
typedef enum sharcbake_sdk_target {
    SHARCBAKE_SDK_1_6 = 1,  /**< 1.6.3 - 1.6.x: 10 level bits; base = min(hash % N, N - 16) */
    SHARCBAKE_SDK_1_7 = 2,  /**< 1.7.2 - 1.8.2: the file's layout; base = min(hash % N, N - 16) (default) */
    SHARCBAKE_SDK_1_8_3 = 3 /**< 1.8.3 and later 1.8: base = hash % (N - 15) (unverified) */
} sharcbake_sdk_target;

/** SDK build options (bit flags). SH encoding and compact keys are refused with
 * SHARCBAKE_UNSUPPORTED_FEATURE; material demodulation and separate emissive are served from a
 * cache baked with voxel materials (VMAT, SPEC §F.8b) and refused without one. */
enum {
    SHARCBAKE_BUILD_SH_ENCODING = 1,           /**< SHARC_ENABLE_SH_ENCODING=1 */
    SHARCBAKE_BUILD_COMPACT_KEYS = 2,          /**< HASH_GRID_COMPACT=1 */
    SHARCBAKE_BUILD_MATERIAL_DEMODULATION = 4, /**< SHARC_MATERIAL_DEMODULATION=1 */
    SHARCBAKE_BUILD_SEPARATE_EMISSIVE = 8      /**< SHARC_SEPARATE_EMISSIVE=1 */
};

/** Options of sharcbake_cache_gpu_buffers_ex / _gpu_insert_list; fill with sharcbake_gpu_options_init. */
typedef struct sharcbake_gpu_options {
    uint32_t capacity;              /**< table slots (buffers only) */
    uint32_t sdk_target;            /**< a sharcbake_sdk_target */
    uint32_t build_flags;           /**< SHARCBAKE_BUILD_* of the engine's SDK build; other bits are refused */
    uint32_t accumulated_frame_num; /**< stored accumulatedFrameNum (clamped to 64511) */
    float
        max_sample_count; /**< cap of the stored sample count: > 0 (else SHARCBAKE_INVALID_ARGUMENT), at most 65504 is stored */
    float radiance_scale;           /**< > 0: this factor; 0: the cache's own (1 if none) */
} sharcbake_gpu_options;

/** What happened on the way to fp16 (sharcbake::GpuRadianceReport) and to the table. */
typedef struct sharcbake_gpu_report {
    uint64_t inserted;            /**< voxels placed (buffers) or listed (insert list) */
    uint64_t failed_inserts;      /**< voxels whose bucket was full (buffers only) */
    uint64_t clipped_voxels;      /**< a channel above 65504 after scaling */
    uint64_t flushed_voxels;      /**< a channel > 0 stored as 0 */
    float radiance_scale;         /**< the factor applied */
    float brightest;              /**< largest channel before scaling */
    float fitting_radiance_scale; /**< largest power of two that keeps the brightest channel */
    uint32_t reserved;
} sharcbake_gpu_report;

/** Defaults: capacity 2^22, SDK 1.7.2 - 1.8.2, no build options, frame number 1, no cap, the cache's scale. */
SHARCBAKE_RUNTIME_API void sharcbake_gpu_options_init(sharcbake_gpu_options* options);

/** The cache's radiance scale for GPU buffers (section RSCL; 1 without one); 0 for NULL. */
SHARCBAKE_RUNTIME_API float sharcbake_cache_gpu_radiance_scale(const sharcbake_cache* cache);

/** Buffers for options->capacity slots in the target's layout. `report` (optional) is filled on
 *  success; `message` (optional) receives the error, or on success the clipping warning (empty
 *  when none). */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_gpu_buffers_ex(
    const sharcbake_cache* cache, const sharcbake_gpu_options* options, uint64_t* hash_entries,
    sharcbake_packed_data* resolved, sharcbake_gpu_report* report, char* message, size_t message_size);

/** One (key, resolved entry) per voxel (sharcbake_cache_voxel_count entries each), for the
 *  engine's own insert pass; options->capacity is ignored. Reports as above. */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_cache_gpu_insert_list(const sharcbake_cache* cache,
                                                                       const sharcbake_gpu_options* options,
                                                                       uint64_t* keys, sharcbake_packed_data* values,
                                                                       sharcbake_gpu_report* report, char* message,
                                                                       size_t message_size);

/** The target of an SDK release ("1.8.2"); SHARCBAKE_UNSUPPORTED_FEATURE with a reason otherwise. */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_sdk_target_for_release(const char* release,
                                                                        sharcbake_sdk_target* target, char* message,
                                                                        size_t message_size);

/** What the engine's own SDK computed for one probe point (sharcbake::SharcSdkObservation). */
typedef struct sharcbake_sdk_observation {
    float position[3];
    float normal[3];
    float camera[3]; /**< the camera position the key was computed from */
    uint32_t slot;   /**< the slot the SDK's insert returned, in an empty table of `capacity` slots */
    uint64_t key;    /**< the 64-bit key the SDK computed */
} sharcbake_sdk_observation;

/** Which target reproduces every observation (sharcbake::identifySharcSdkTarget): the key layout
 *  from the keys, the bucket rule from the slots. The grid is the engine's: logarithm base, scene
 *  scale, level bias and table capacity. Needs at least 4 observations (16 distinct points
 *  recommended), some of them with a normal that has a negative component (only those tell 1.6
 *  from 1.7). SHARCBAKE_OK and `*target` when exactly one target fits; otherwise
 *  SHARCBAKE_UNSUPPORTED_FEATURE or SHARCBAKE_INVALID_ARGUMENT and a reason in `message`. */
SHARCBAKE_RUNTIME_API sharcbake_status sharcbake_identify_sdk_target(float logarithm_base, float scene_scale,
                                                                     float level_bias, uint32_t capacity,
                                                                     const sharcbake_sdk_observation* observations,
                                                                     size_t count, sharcbake_sdk_target* target,
                                                                     char* message, size_t message_size);

/** Frames a baked entry survives the SDK's Resolve without samples: clamp(stale, 8, 1024) - 1. */
SHARCBAKE_RUNTIME_API uint32_t sharcbake_resolve_frames_kept(uint32_t stale_frame_num_max);

#ifdef __cplusplus
}
#endif

#endif /* SHARCBAKE_RUNTIME_C_H */
