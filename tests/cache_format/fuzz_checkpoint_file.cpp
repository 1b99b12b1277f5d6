// SPDX-License-Identifier: Apache-2.0
/// @file fuzz_checkpoint_file.cpp
/// @brief libFuzzer harness for the checkpoint reader (decodeCheckpoint, SPEC.md §C), beside
/// fuzz_cache_file.cpp. Built and run by sanitized_runtime_test.sh on the golden checkpoint:
///   clang++ -std=c++17 -g -O1 -fsanitize=fuzzer,address,undefined -Icache_format/include \
///       tests/cache_format/fuzz_checkpoint_file.cpp cache_format/src/*.cpp -o fuzz_checkpoint_file
///
/// Each input is decoded as given and with its CRCs repaired (so mutations reach the structural
/// rules C6-C11). Whatever decodes must also satisfy what a resume relies on: the writer accepts
/// it again and re-encoding gives a checkpoint that decodes to the same values (traps otherwise),
/// and every counter is within the bounds of rule C8/C9.
#include "sharcbake/checkpoint_file.h"
#include "sharcbake/format.h"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
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

/// Best effort, as in fuzz_cache_file.cpp: each in-bounds section CRC, then the header CRC.
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

bool sameSlots(const CheckpointData& a, const CheckpointData& b) {
    if (a.slots.size() != b.slots.size()) return false;
    for (size_t i = 0; i < a.slots.size(); ++i) {
        const CheckpointSlot &x = a.slots[i], &y = b.slots[i];
        if (x.slot != y.slot || x.key != y.key || x.frames != y.frames || x.last_iteration != y.last_iteration ||
            x.total_samples != y.total_samples || std::memcmp(&x.weight, &y.weight, sizeof x.weight) != 0 ||
            std::memcmp(x.mean, y.mean, sizeof x.mean) != 0 || std::memcmp(x.feedback, y.feedback, sizeof x.feedback) != 0) {
            return false;
        }
    }
    return true;
}

void exercise(const uint8_t* data, size_t size) {
    CheckpointData decoded;
    std::string message;
    if (decodeCheckpoint(data, size, &decoded, &message) != CacheFileStatus::kOk) {
        if (message.empty()) __builtin_trap();  // every refusal says why
        return;
    }
    // Bounds a resume relies on (C8, C9).
    if (decoded.iterations_done > kCheckpointMaxIterations || decoded.capacity == 0 || decoded.bucket_size == 0 ||
        decoded.bucket_size > decoded.capacity || decoded.slots.size() > decoded.capacity) {
        __builtin_trap();
    }
    for (size_t i = 0; i < decoded.slots.size(); ++i) {
        if (decoded.slots[i].slot >= decoded.capacity || decoded.slots[i].key == 0) __builtin_trap();
        if (i > 0 && decoded.slots[i].slot <= decoded.slots[i - 1].slot) __builtin_trap();
    }
    // What the reader accepts, the writer writes, and it reads back the same.
    std::vector<uint8_t> again;
    if (encodeCheckpoint(decoded, &again, &message) != CacheFileStatus::kOk) __builtin_trap();
    CheckpointData twice;
    if (decodeCheckpoint(again.data(), again.size(), &twice, &message) != CacheFileStatus::kOk) __builtin_trap();
    if (twice.iterations_done != decoded.iterations_done || twice.capacity != decoded.capacity ||
        twice.bucket_size != decoded.bucket_size || twice.settings != decoded.settings ||
        twice.counts != decoded.counts || !sameSlots(twice, decoded)) {
        __builtin_trap();
    }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    exercise(data, size);
    std::vector<uint8_t> repaired(data, data + size);
    repairChecksums(repaired);
    exercise(repaired.data(), repaired.size());
    return 0;
}
