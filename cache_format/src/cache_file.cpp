// SPDX-License-Identifier: Apache-2.0
// Writing the .sharc byte layout (SPEC.md §F), and readCacheFile over CacheView (runtime.cpp).
#include "sharcbake/cache_file.h"

#include "container.h"
#include "sharcbake/format.h"
#include "sharcbake/runtime.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include <cerrno>

#include <fcntl.h>
#include <unistd.h>

namespace sharcbake {
namespace {

static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE 754 floats expected");

/// CRC-32 tables for slicing-by-16 (16 KiB, built once): opening a cache is mostly this CRC.
struct Crc32Tables {
    uint32_t t[16][256];
    Crc32Tables() {
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[0][i] = c;
        }
        for (uint32_t i = 0; i < 256; ++i) {
            for (int s = 1; s < 16; ++s) t[s][i] = (t[s - 1][i] >> 8) ^ t[0][t[s - 1][i] & 0xFFu];
        }
    }
};

}  // namespace

uint32_t cacheCrc32(const void* data, size_t size, uint32_t crc) {
    static const Crc32Tables tables;
    const auto& t = tables.t;
    const uint8_t* p = static_cast<const uint8_t*>(data);
    crc = ~crc;
    while (size >= 16) {  // little-endian slicing-by-16: 16 independent lookups per step
        uint32_t w0, w1, w2, w3;
        std::memcpy(&w0, p, 4);
        std::memcpy(&w1, p + 4, 4);
        std::memcpy(&w2, p + 8, 4);
        std::memcpy(&w3, p + 12, 4);
        w0 ^= crc;
        crc = t[15][w0 & 0xFFu] ^ t[14][(w0 >> 8) & 0xFFu] ^ t[13][(w0 >> 16) & 0xFFu] ^ t[12][w0 >> 24] ^
              t[11][w1 & 0xFFu] ^ t[10][(w1 >> 8) & 0xFFu] ^ t[9][(w1 >> 16) & 0xFFu] ^ t[8][w1 >> 24] ^
              t[7][w2 & 0xFFu] ^ t[6][(w2 >> 8) & 0xFFu] ^ t[5][(w2 >> 16) & 0xFFu] ^ t[4][w2 >> 24] ^
              t[3][w3 & 0xFFu] ^ t[2][(w3 >> 8) & 0xFFu] ^ t[1][(w3 >> 16) & 0xFFu] ^ t[0][w3 >> 24];
        p += 16;
        size -= 16;
    }
    while (size >= 8) {  // little-endian slicing-by-8
        uint32_t lo, hi;
        std::memcpy(&lo, p, 4);
        std::memcpy(&hi, p + 4, 4);
        lo ^= crc;
        crc = t[7][lo & 0xFFu] ^ t[6][(lo >> 8) & 0xFFu] ^ t[5][(lo >> 16) & 0xFFu] ^ t[4][lo >> 24] ^
              t[3][hi & 0xFFu] ^ t[2][(hi >> 8) & 0xFFu] ^ t[1][(hi >> 16) & 0xFFu] ^ t[0][hi >> 24];
        p += 8;
        size -= 8;
    }
    while (size--) crc = t[0][(crc ^ *p++) & 0xFFu] ^ (crc >> 8);
    return ~crc;
}

HashGridParameters CacheData::gridParameters() const {
    HashGridParameters p;
    p.logarithm_base = logarithm_base;
    p.scene_scale = scene_scale;
    p.level_bias = level_bias;
    p.bucket_size = bucket_size;
    p.capacity = bake_capacity;
    return p;
}

const char* toString(CacheFileStatus status) {
    switch (status) {
        case CacheFileStatus::kOk: return "ok";
        case CacheFileStatus::kIoError: return "I/O error";
        case CacheFileStatus::kBadMagic: return "not a sharcbake cache file";
        case CacheFileStatus::kUnsupportedVersion: return "unsupported version";
        case CacheFileStatus::kTruncated: return "truncated file";
        case CacheFileStatus::kCorrupt: return "corrupt file";
        case CacheFileStatus::kInvalidData: return "invalid cache data";
        case CacheFileStatus::kChecksumMismatch: return "checksum mismatch";
        case CacheFileStatus::kUnsupportedFeature: return "unsupported feature";
        case CacheFileStatus::kTrailingBytes: return "trailing bytes";
        case CacheFileStatus::kInvalidArgument: return "invalid argument";
    }
    return "unknown status";
}

void sortVoxels(std::vector<CacheVoxel>& voxels) {
    std::sort(voxels.begin(), voxels.end(), [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; });
}

// Writes the sections in the order of SPEC §F.4: GRID, KEYS, VOXL, LEVL, META.
CacheFileStatus encodeCacheFile(const CacheData& data, std::vector<uint8_t>* out, std::string* message) {
    if (!out) return fail(CacheFileStatus::kInvalidArgument, message, "encodeCacheFile: null output");
    if (!hostIsLittleEndian()) return fail(CacheFileStatus::kUnsupportedFeature, message, "big-endian hosts are not supported");
    // The writer refuses what a reader would reject (SPEC §F.10), with a writer-side message.
    std::array<uint32_t, kHashGridLevelMax + 1> per_level{};
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        const CacheVoxel& v = data.voxels[i];
        const uint32_t level = uint32_t(v.key >> kHashGridLevelOffset) & kHashGridLevelMask;
        if (v.key == kHashGridInvalidKey || (i > 0 && data.voxels[i - 1].key >= v.key) || level == 0 ||
            (v.key >> kHashGridUserBit) != 0) {
            return fail(CacheFileStatus::kInvalidData, message,
                        "voxels must have non-zero keys with level >= 1 and bit 63 clear, in strictly increasing order "
                        "(voxel " + std::to_string(i) + ")");
        }
        for (float c : v.radiance) {
            if (!std::isfinite(c) || c < 0.0f) {
                return fail(CacheFileStatus::kInvalidData, message,
                            "voxel " + std::to_string(i) + ": radiance must be finite and >= 0");
            }
        }
        if (!std::isfinite(v.sample_weight) || !(v.sample_weight > 0.0f)) {
            return fail(CacheFileStatus::kInvalidData, message,
                        "voxel " + std::to_string(i) + ": sample weight must be finite and > 0 (only live voxels are stored)");
        }
        ++per_level[level];
    }
    if (validateHashGridParameters(data.gridParameters()) != HashGridStatus::kOk || data.bake_capacity == 0) {
        return fail(CacheFileStatus::kInvalidData, message,
                    std::string("grid parameters: ") + toString(validateHashGridParameters(data.gridParameters())));
    }
    for (size_t i = 0; i < data.metadata.size(); ++i) {
        const auto& [key, value] = data.metadata[i];
        if (key.empty() || key.size() > 0xFFFFFFFFu || value.size() > 0xFFFFFFFFu) {
            return fail(CacheFileStatus::kInvalidData, message, "metadata keys must be non-empty");
        }
        for (size_t j = 0; j < i; ++j) {
            if (data.metadata[j].first == key) {
                return fail(CacheFileStatus::kInvalidData, message, "duplicate metadata key \"" + key + "\"");
            }
        }
    }
    std::vector<CacheLevel> levels;
    for (uint32_t l = 1; l <= kHashGridLevelMax; ++l) {
        if (per_level[l]) levels.push_back(CacheLevel{l, per_level[l]});
    }

    constexpr uint32_t kSections = 5;
    std::vector<uint8_t>& bytes = *out;
    bytes.clear();
    bytes.reserve(kCacheHeaderSize + kSections * kCacheSectionEntrySize + 64 + data.voxels.size() * 24 +
                  levels.size() * 8 + 4096);
    ContainerWriter container(bytes, kCacheIdentifier, kCacheVersionMajor, kCacheVersionMinor, kSections);
    ByteWriter& w = container.out();
    const auto begin = [&](uint32_t type, uint32_t flags) { container.beginSection(type, flags); };
    const auto end = [&] { container.endSection(); };
    // 3) GRID (SPEC §F.5).
    begin(kSectionGrid, kCacheSectionRequired);
    w.put(kHashGridPositionBits);
    w.put(kHashGridLevelBits);
    w.put(kHashGridNormalBits);
    w.put(data.bucket_size);
    w.put(kCacheHashJenkins32Xor);
    w.put(kCacheLodCameraDistance);
    w.put(data.logarithm_base);
    w.put(data.scene_scale);
    w.put(data.level_bias);
    w.put(data.bake_capacity);
    w.put(kHashGridPositionBias);
    w.put(kHashGridNormalBias);
    w.put(uint64_t(data.voxels.size()));
    w.put(uint32_t(levels.size()));
    w.put(uint32_t(0));
    end();
    // 4) KEYS (SPEC §F.6).
    begin(kSectionKeys, kCacheSectionRequired);
    for (const CacheVoxel& v : data.voxels) w.put(v.key);
    end();
    // 5) VOXL (SPEC §F.6).
    begin(kSectionVoxels, kCacheSectionRequired);
    for (const CacheVoxel& v : data.voxels) {
        w.put(v.radiance[0]);
        w.put(v.radiance[1]);
        w.put(v.radiance[2]);
        w.put(v.sample_weight);
    }
    end();
    // 6) LEVL (SPEC §F.7).
    begin(kSectionLevels, kCacheSectionRequired);
    for (const CacheLevel& l : levels) {
        w.put(l.level);
        w.put(l.voxel_count);
    }
    end();
    // 7) META (SPEC §F.8), optional.
    begin(kSectionMetadata, 0);
    w.put(uint32_t(data.metadata.size()));
    w.put(uint32_t(0));
    for (const auto& [key, value] : data.metadata) {
        w.put(uint32_t(key.size()));
        w.put(uint32_t(value.size()));
        w.putBytes(key.data(), key.size());
        w.putBytes(value.data(), value.size());
    }
    end();
    // 8) Table entries, file size, checksums.
    container.finish();
    // Metadata text is validated as UTF-8 by the reader: check here, on the encoded bytes.
    CacheView view;
    CacheError error;
    if (CacheView::openMemory(bytes.data(), bytes.size(), &view, &error) != CacheFileStatus::kOk) {
        return fail(CacheFileStatus::kInvalidData, message, "the data cannot be stored: " + error.message);
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus writeFileAtomically(const std::string& path, const std::string& temporary,
                                    const std::vector<uint8_t>& bytes, std::string* message) {
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return fail(CacheFileStatus::kIoError, message, temporary + ": cannot create: " + std::strerror(errno));
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            ::close(fd);
            std::remove(temporary.c_str());
            return fail(CacheFileStatus::kIoError, message, temporary + ": write failed (disk full?)");
        }
        done += size_t(n);
    }
    const bool synced = ::fsync(fd) == 0;
    const bool closed = ::close(fd) == 0;
    if (!synced || !closed) {
        std::remove(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message, temporary + ": fsync or close failed");
    }
    if (std::rename(temporary.c_str(), path.c_str()) != 0) {
        std::remove(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message, path + ": cannot rename the temporary file into place");
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus writeCacheFile(const std::string& path, const CacheData& data, std::string* message) {
    std::vector<uint8_t> bytes;
    const CacheFileStatus encoded = encodeCacheFile(data, &bytes, message);
    if (encoded != CacheFileStatus::kOk) {
        if (message) *message = path + ": " + *message;
        return encoded;
    }
    // A per-process temporary name: two bakes writing the same output do not write one file.
    const CacheFileStatus written = writeFileAtomically(path, path + ".tmp-" + std::to_string(::getpid()), bytes, message);
    if (written != CacheFileStatus::kOk) return written;
    // Re-open what landed on disk and validate it (KTX habit); keep the file for the bug report.
    CacheView view;
    CacheError error;
    const CacheFileStatus reread = CacheView::openFile(path, &view, &error);
    if (reread != CacheFileStatus::kOk) {
        return fail(reread == CacheFileStatus::kIoError ? CacheFileStatus::kIoError : CacheFileStatus::kCorrupt,
                    message, "the file written does not validate (kept for inspection): " + error.message);
    }
    if (view.fileSize() != bytes.size() || view.voxelCount() != data.voxels.size()) {
        return fail(CacheFileStatus::kIoError, message, path + ": the file read back differs from what was written");
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus readCacheFile(const std::string& path, CacheData* data, std::string* message) {
    CacheView view;
    CacheError error;
    const CacheFileStatus status = CacheView::openFile(path, &view, &error);
    if (status != CacheFileStatus::kOk) return fail(status, message, error.message);
    if (!data) return CacheFileStatus::kOk;
    CacheData result;
    const HashGridParameters p = view.gridParameters();
    result.logarithm_base = p.logarithm_base;
    result.scene_scale = p.scene_scale;
    result.level_bias = p.level_bias;
    result.bucket_size = p.bucket_size;
    result.bake_capacity = view.bakeCapacity();
    result.version_major = view.versionMajor();
    result.version_minor = view.versionMinor();
    result.voxels.resize(size_t(view.voxelCount()));
    for (uint64_t i = 0; i < view.voxelCount(); ++i) result.voxels[size_t(i)] = view.voxel(i);
    result.levels = view.levels();
    result.metadata.reserve(view.metadataCount());
    for (size_t i = 0; i < view.metadataCount(); ++i) {
        result.metadata.emplace_back(std::string(view.metadataKey(i)), std::string(view.metadataValue(i)));
    }
    *data = std::move(result);
    return CacheFileStatus::kOk;
}

}  // namespace sharcbake
