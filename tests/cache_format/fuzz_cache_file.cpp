// SPDX-License-Identifier: Apache-2.0
/// @file fuzz_cache_file.cpp
/// @brief libFuzzer harness for the runtime's .sharc reader (CacheView::openMemory and every
/// accessor on a cache that validates, and the C API's that wrap them). Built and run by
/// sanitized_runtime_test.sh:
///   clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -Icache_format/include \
///       tests/cache_format/fuzz_cache_file.cpp cache_format/src/*.cpp -o fuzz_cache_file
///   ./fuzz_cache_file CORPUS_COPY -max_total_time=60      (seed: tests/cache_format/golden/)
///
/// Each input is opened twice: as given (exercises the rejection paths) and with its section and
/// header CRCs repaired, so that mutations get past the checksums into the structural rules and
/// the accessors instead of dying at V-rule "checksum mismatch".
#include "sharcbake/format.h"
#include "sharcbake/runtime.h"
#include "sharcbake/runtime_c.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

using namespace sharcbake;

namespace {

template <typename T>
T loadLE(const uint8_t* p) {
    T v;
    std::memcpy(&v, p, sizeof(T));
    return v;
}

template <typename T>
void storeLE(uint8_t* p, T v) {
    std::memcpy(p, &v, sizeof(T));
}

/// Best effort: recompute each in-bounds section CRC, then the header CRC. Never reads out of
/// bounds; leaves the bytes alone where the layout does not fit.
void repairChecksums(std::vector<uint8_t>& b) {
    const uint64_t size = b.size();
    if (size < kCacheHeaderSize) return;
    const uint32_t count = loadLE<uint32_t>(b.data() + 28);
    const uint64_t table = loadLE<uint64_t>(b.data() + 32);
    if (count > kCacheMaxSections || table < kCacheHeaderSize || table > size) return;
    if (uint64_t(count) * kCacheSectionEntrySize > size - table) return;
    for (uint32_t i = 0; i < count; ++i) {
        uint8_t* e = b.data() + table + uint64_t(i) * kCacheSectionEntrySize;
        const uint64_t off = loadLE<uint64_t>(e + 8);
        const uint64_t len = loadLE<uint64_t>(e + 16);
        if (off <= size && len <= size - off) storeLE<uint32_t>(e + 24, cacheCrc32(b.data() + off, size_t(len)));
    }
    const uint64_t table_end = table + uint64_t(count) * kCacheSectionEntrySize;
    uint32_t crc = cacheCrc32(b.data(), kCacheHeaderCrcOffset);
    crc = cacheCrc32(b.data() + kCacheHeaderSize, size_t(table_end - kCacheHeaderSize), crc);
    storeLE<uint32_t>(b.data() + kCacheHeaderCrcOffset, crc);
}

/// Floats derived from the input (any bit pattern, NaN and Inf included).
struct ByteStream {
    const uint8_t* data;
    size_t size;
    size_t pos = 0;
    float nextFloat() {
        uint32_t bits = 0;
        for (int i = 0; i < 4; ++i) bits = bits << 8 | (size ? data[pos++ % size] : 0u);
        float f;
        std::memcpy(&f, &bits, sizeof f);
        return f;
    }
    Float3 nextFloat3() { return {nextFloat(), nextFloat(), nextFloat()}; }
};

volatile float g_sink;  // keeps results observable

void exercise(const uint8_t* data, size_t size) {
    CacheView view;
    CacheError error;
    if (CacheView::openMemory(data, size, &view, &error) != CacheFileStatus::kOk) return;

    const CacheStats st = view.stats();
    g_sink = float(st.weight_total + st.bytes_per_voxel);
    (void)view.sections();
    (void)view.levels();
    (void)view.gridParameters({1.0f, 2.0f, 3.0f});
    for (size_t i = 0; i < view.metadataCount(); ++i) {
        g_sink = float(view.metadataKey(i).size() + view.metadataValue(i).size());
        (void)view.metadata(view.metadataKey(i));
    }

    const uint64_t n = view.voxelCount();
    const uint64_t limit = n < 4096 ? n : 4096;
    for (uint64_t i = 0; i < limit; ++i) {
        const CacheVoxel v = view.voxel(i);
        if (view.key(i) != v.key || view.findKey(v.key) >= n) __builtin_trap();
        g_sink = v.radiance[0] + v.sample_weight;
    }
    (void)view.findKey(0);
    (void)view.findKey(~0ull);

    ByteStream in{data, size};
    Float3 fixed_pos[] = {{0, 0, 0}, {1.5f, -2.0f, 3.25f}, {1e30f, -1e30f, 0}, {-0.0f, 1e-38f, 5}};
    Float3 fixed_nrm[] = {{0, 1, 0}, {0, 0, -1}, {1, 0, 0}, {0.577f, 0.577f, 0.577f}};
    Float3 radiance{};
    uint32_t level = 0;
    for (int pass = 0; pass < 2; ++pass) {
        for (int q = 0; q < 4; ++q) {
            (void)view.lookup(fixed_pos[q], fixed_nrm[q], {0, 0, 0}, &radiance);
            (void)view.lookupNearestLevel(fixed_pos[q], fixed_nrm[q], {10, 10, 10}, &radiance, &level);
            const Float3 p = in.nextFloat3(), nrm = in.nextFloat3(), cam = in.nextFloat3();
            (void)view.keyFor(p, nrm, cam);
            (void)view.lookup(p, nrm, cam, &radiance);
            (void)view.lookupNearestLevel(p, nrm, cam, &radiance, &level);
            (void)view.lookupNearestLevel(p, nrm, cam, &radiance, nullptr);
        }
        constexpr size_t kBatch = 8;
        Float3 positions[kBatch], normals[kBatch], out[kBatch];
        uint8_t hits[kBatch];
        for (size_t i = 0; i < kBatch; ++i) {
            positions[i] = in.nextFloat3();
            normals[i] = in.nextFloat3();
        }
        const Float3 cam = in.nextFloat3();
        (void)view.lookupBatch(kBatch, positions, normals, cam, out, hits, false);
        (void)view.lookupBatch(kBatch, positions, normals, cam, out, nullptr, true);
        if (pass == 0 && view.buildLookupIndex() != CacheFileStatus::kOk) break;  // 2nd pass: hash index
    }

    for (uint32_t capacity : {1u, 7u, 64u, 1000u}) {
        GpuBufferOptions options;
        options.capacity = capacity;
        options.accumulated_frame_num = capacity * 100u;
        options.max_sample_count = in.nextFloat();
        options.sdk_target = SharcSdkTarget(1 + capacity % 3);  // every release's layout and rule
        options.radiance_scale = capacity == 64u ? in.nextFloat() : 0.0f;
        GpuBuffers buffers;
        if (view.gpuBuffers(options, &buffers, &error) == CacheFileStatus::kOk) {
            if (buffers.hash_entries.size() != capacity || buffers.resolved.size() != capacity) __builtin_trap();
            if (buffers.inserted + buffers.failed_inserts != n) __builtin_trap();
        }
        GpuInsertList list;
        if (view.gpuInsertList(options, &list, &error) == CacheFileStatus::kOk) {
            if (list.keys.size() != n || list.values.size() != n) __builtin_trap();
        }
    }

    // The C API over the same bytes: it opens what CacheView opened, and places every voxel
    // (keys decoded near the file's anchor).
    sharcbake_cache* cache = nullptr;
    if (sharcbake_cache_open_memory(data, size, &cache, nullptr, nullptr, 0) != SHARCBAKE_OK) __builtin_trap();
    float anchor[3], center[3], voxel_size = 0.0f;
    uint32_t voxel_level = 0, normal_bits = 0;
    sharcbake_cache_grid_anchor(cache, anchor);
    for (uint64_t i = 0; i < limit; ++i) {
        if (!sharcbake_cache_voxel_location(cache, i, center, &voxel_size, &voxel_level, &normal_bits))
            __builtin_trap();
        g_sink = center[0] + center[1] + center[2] + voxel_size + anchor[0];
    }
    if (sharcbake_cache_voxel_location(cache, n, center, nullptr, nullptr, nullptr)) __builtin_trap();
    sharcbake_cache_close(cache);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    exercise(data, size);
    std::vector<uint8_t> repaired(data, data + size);
    repairChecksums(repaired);
    exercise(repaired.data(), repaired.size());
    return 0;
}
