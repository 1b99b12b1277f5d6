// SPDX-License-Identifier: Apache-2.0
// The .sharc byte layout (SPEC.md, "File layout"). Everything that knows the bytes is here.
#include "sharcbake/cache_file.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include <unistd.h>

namespace sharcbake {
namespace {

constexpr char kMagic[8] = {'S', 'H', 'R', 'C', 'B', 'A', 'K', 'E'};
constexpr uint16_t kVersionMajor = 0;
constexpr uint16_t kVersionMinor = 1;
constexpr size_t kVoxelBytes = 24;

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), table-driven.
uint32_t crc32(const uint8_t* data, size_t size) {
    static const auto table = [] {
        std::vector<uint32_t> t(256);
        for (uint32_t i = 0; i < 256; ++i) {
            uint32_t c = i;
            for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
            t[i] = c;
        }
        return t;
    }();
    uint32_t crc = 0xFFFFFFFFu;
    for (size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
    return crc ^ 0xFFFFFFFFu;
}

/// Little-endian writer into a byte vector.
struct ByteWriter {
    std::vector<uint8_t> bytes;
    template <typename T> void put(T value) {
        const size_t at = bytes.size();
        bytes.resize(at + sizeof(T));
        std::memcpy(bytes.data() + at, &value, sizeof(T));  // the host is little-endian (checked)
    }
    void putString(const std::string& s) {
        put(uint32_t(s.size()));
        const size_t at = bytes.size();
        bytes.resize(at + s.size());
        if (!s.empty()) std::memcpy(bytes.data() + at, s.data(), s.size());
    }
};

/// Bounds-checked little-endian reader.
struct ByteReader {
    const uint8_t* data;
    size_t size;
    size_t offset = 0;
    template <typename T> bool get(T& value) {
        if (size - offset < sizeof(T)) return false;
        std::memcpy(&value, data + offset, sizeof(T));
        offset += sizeof(T);
        return true;
    }
    bool getString(std::string& s) {
        uint32_t length = 0;
        if (!get(length) || size - offset < length) return false;
        s.assign(reinterpret_cast<const char*>(data + offset), length);
        offset += length;
        return true;
    }
};

static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE 754 floats expected");

bool isLittleEndian() {
    const uint16_t one = 1;
    uint8_t first;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

CacheFileStatus fail(CacheFileStatus status, std::string* message, const std::string& text) {
    if (message) *message = text;
    return status;
}

}  // namespace

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
    }
    return "unknown status";
}

void sortVoxels(std::vector<CacheVoxel>& voxels) {
    std::sort(voxels.begin(), voxels.end(), [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; });
}

CacheFileStatus writeCacheFile(const std::string& path, const CacheData& data, std::string* message) {
    if (!isLittleEndian()) return fail(CacheFileStatus::kIoError, message, "big-endian hosts are not supported");
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        if (data.voxels[i].key == kHashGridInvalidKey || (i > 0 && data.voxels[i - 1].key >= data.voxels[i].key)) {
            return fail(CacheFileStatus::kInvalidData, message, "voxels must have non-zero keys in strictly increasing order");
        }
    }
    ByteWriter w;
    w.bytes.assign(std::begin(kMagic), std::end(kMagic));
    w.put(kVersionMajor);
    w.put(kVersionMinor);
    w.put(data.logarithm_base);
    w.put(data.scene_scale);
    w.put(data.level_bias);
    w.put(data.bucket_size);
    w.put(data.bake_capacity);
    w.put(uint64_t(data.voxels.size()));
    w.put(uint32_t(data.metadata.size()));
    for (const auto& [key, value] : data.metadata) {
        w.putString(key);
        w.putString(value);
    }
    for (const CacheVoxel& v : data.voxels) {
        w.put(v.key);
        w.put(v.radiance[0]);
        w.put(v.radiance[1]);
        w.put(v.radiance[2]);
        w.put(v.sample_weight);
    }
    w.put(crc32(w.bytes.data(), w.bytes.size()));

    const std::string temporary = path + ".tmp-" + std::to_string(::getpid());
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        if (!out) return fail(CacheFileStatus::kIoError, message, path + ": cannot create " + temporary);
        out.write(reinterpret_cast<const char*>(w.bytes.data()), std::streamsize(w.bytes.size()));
        out.flush();
        if (!out) {
            out.close();
            std::remove(temporary.c_str());
            return fail(CacheFileStatus::kIoError, message, path + ": write failed (disk full?)");
        }
    }
    if (std::rename(temporary.c_str(), path.c_str()) != 0) {
        std::remove(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message, path + ": cannot rename the temporary file into place");
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus readCacheFile(const std::string& path, CacheData* data, std::string* message) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(CacheFileStatus::kIoError, message, path + ": cannot open");
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.size() < sizeof kMagic || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0) {
        return fail(CacheFileStatus::kBadMagic, message, path + ": not a sharcbake cache file (bad magic)");
    }
    ByteReader r{bytes.data(), bytes.size(), sizeof kMagic};
    uint16_t major = 0, minor = 0;
    if (!r.get(major) || !r.get(minor)) return fail(CacheFileStatus::kTruncated, message, path + ": truncated header");
    if (major != kVersionMajor) {
        return fail(CacheFileStatus::kUnsupportedVersion, message,
                    path + ": format version " + std::to_string(major) + "." + std::to_string(minor) + " is not supported");
    }
    if (bytes.size() < r.offset + 4) return fail(CacheFileStatus::kTruncated, message, path + ": truncated");
    uint32_t stored_crc = 0;
    std::memcpy(&stored_crc, bytes.data() + bytes.size() - 4, 4);
    if (crc32(bytes.data(), bytes.size() - 4) != stored_crc) {
        return fail(CacheFileStatus::kCorrupt, message, path + ": checksum mismatch (truncated or corrupted)");
    }
    r.size = bytes.size() - 4;
    CacheData result;
    uint64_t voxel_count = 0;
    uint32_t metadata_count = 0;
    if (!r.get(result.logarithm_base) || !r.get(result.scene_scale) || !r.get(result.level_bias) ||
        !r.get(result.bucket_size) || !r.get(result.bake_capacity) || !r.get(voxel_count) || !r.get(metadata_count)) {
        return fail(CacheFileStatus::kTruncated, message, path + ": truncated header");
    }
    for (uint32_t i = 0; i < metadata_count; ++i) {
        std::string key, value;
        if (!r.getString(key) || !r.getString(value)) return fail(CacheFileStatus::kCorrupt, message, path + ": bad metadata");
        result.metadata.emplace_back(std::move(key), std::move(value));
    }
    if (voxel_count > (r.size - r.offset) / kVoxelBytes || (r.size - r.offset) != voxel_count * kVoxelBytes) {
        return fail(CacheFileStatus::kCorrupt, message, path + ": voxel count does not match the file size");
    }
    result.voxels.resize(size_t(voxel_count));
    for (CacheVoxel& v : result.voxels) {
        r.get(v.key);
        r.get(v.radiance[0]);
        r.get(v.radiance[1]);
        r.get(v.radiance[2]);
        r.get(v.sample_weight);
    }
    if (data) *data = std::move(result);
    return CacheFileStatus::kOk;
}

}  // namespace sharcbake
