// SPDX-License-Identifier: Apache-2.0
// What the reader and the writer share: the container's CRC-32 (SPEC §F.3) and status names.
#include "sharcbake/cache_types.h"
#include "sharcbake/format.h"

#include <cstring>

namespace sharcbake {
namespace {

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

}  // namespace sharcbake
