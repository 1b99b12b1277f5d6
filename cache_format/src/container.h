// SPDX-License-Identifier: Apache-2.0
// The container that caches and checkpoints share (SPEC §F.1 - §F.4, §C.1): reading its header
// and section table, and writing its bytes. The field offsets live here only; each format checks
// its own rules over what ContainerHeader and ContainerEntry read. Internal to cache_format/.
#pragma once

#include "sharcbake/cache_types.h"
#include "sharcbake/format.h"

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace sharcbake {

inline bool hostIsLittleEndian() {
    const uint16_t one = 1;
    uint8_t first;
    std::memcpy(&first, &one, 1);
    return first == 1;
}

inline uint64_t align8(uint64_t v) { return (v + 7u) & ~uint64_t(7); }

inline CacheFileStatus fail(CacheFileStatus status, std::string* message, const std::string& text) {
    if (message) *message = text;
    return status;
}

template <typename T> T loadLittleEndian(const uint8_t* p) {
    T value;
    std::memcpy(&value, p, sizeof(T));
    return value;
}

/// The container header's fields (SPEC §F.2), read from at least kCacheHeaderSize bytes.
struct ContainerHeader {
    uint16_t version_major = 0, version_minor = 0;
    uint32_t header_size = 0;
    uint32_t flags = 0;
    uint32_t section_count = 0;
    uint64_t table_offset = 0;
    uint64_t file_size = 0;
    uint32_t entry_size = 0;
    uint32_t reserved[2] = {0, 0};
    uint32_t header_crc32 = 0;

    static ContainerHeader read(const uint8_t* d) {
        ContainerHeader h;
        h.version_major = loadLittleEndian<uint16_t>(d + 16);
        h.version_minor = loadLittleEndian<uint16_t>(d + 18);
        h.header_size = loadLittleEndian<uint32_t>(d + 20);
        h.flags = loadLittleEndian<uint32_t>(d + 24);
        h.section_count = loadLittleEndian<uint32_t>(d + 28);
        h.table_offset = loadLittleEndian<uint64_t>(d + 32);
        h.file_size = loadLittleEndian<uint64_t>(d + 40);
        h.entry_size = loadLittleEndian<uint32_t>(d + 48);
        h.reserved[0] = loadLittleEndian<uint32_t>(d + 52);
        h.reserved[1] = loadLittleEndian<uint32_t>(d + 56);
        h.header_crc32 = loadLittleEndian<uint32_t>(d + kCacheHeaderCrcOffset);
        return h;
    }
    /// The end of the section table (valid once the geometry has been checked).
    uint64_t tableEnd() const { return table_offset + uint64_t(section_count) * kCacheSectionEntrySize; }
    /// The CRC-32 the header should hold: the header without its CRC field, then the table.
    static uint32_t computeCrc32(const uint8_t* d, uint64_t table_end) {
        const uint32_t crc = cacheCrc32(d, kCacheHeaderCrcOffset);
        return cacheCrc32(d + kCacheHeaderSize, size_t(table_end - kCacheHeaderSize), crc);
    }
};

/// One entry of the section table (SPEC §F.3).
struct ContainerEntry {
    uint32_t type = 0, flags = 0;
    uint64_t offset = 0, length = 0;
    uint32_t crc32 = 0, reserved = 0;

    static ContainerEntry read(const uint8_t* d, uint64_t table_offset, uint32_t index) {
        const uint8_t* e = d + table_offset + uint64_t(index) * kCacheSectionEntrySize;
        ContainerEntry entry;
        entry.type = loadLittleEndian<uint32_t>(e);
        entry.flags = loadLittleEndian<uint32_t>(e + 4);
        entry.offset = loadLittleEndian<uint64_t>(e + 8);
        entry.length = loadLittleEndian<uint64_t>(e + 16);
        entry.crc32 = loadLittleEndian<uint32_t>(e + 24);
        entry.reserved = loadLittleEndian<uint32_t>(e + 28);
        return entry;
    }
};

/// Little-endian writer appending to a byte vector (callers check hostIsLittleEndian()).
struct ByteWriter {
    std::vector<uint8_t>& bytes;
    template <typename T> void put(T value) {
        const size_t at = bytes.size();
        bytes.resize(at + sizeof(T));
        std::memcpy(bytes.data() + at, &value, sizeof(T));
    }
    void putBytes(const void* data, size_t size) {
        const size_t at = bytes.size();
        bytes.resize(at + size);
        if (size) std::memcpy(bytes.data() + at, data, size);
    }
    void putText(const std::string& text) { putBytes(text.data(), text.size()); }
    void pad8() { bytes.resize(size_t(align8(bytes.size()))); }
    template <typename T> void patch(size_t at, T value) { std::memcpy(bytes.data() + at, &value, sizeof(T)); }
};

/// Writes a container into `bytes` (cleared): the identifier and header, a section table of
/// `section_count` entries, then the sections one by one (begin, write through out(), end),
/// each at a multiple of 8 with zero padding; finish() fills in the table, the file size and
/// the CRCs. The caller writes exactly `section_count` sections.
class ContainerWriter {
public:
    ContainerWriter(std::vector<uint8_t>& bytes, const uint8_t (&identifier)[16], uint16_t version_major,
                    uint16_t version_minor, uint32_t section_count)
        : writer_{bytes}, section_count_(section_count) {
        bytes.clear();
        writer_.putBytes(identifier, sizeof identifier);
        writer_.put(version_major);
        writer_.put(version_minor);
        writer_.put(kCacheHeaderSize);
        writer_.put(uint32_t(0));  // flags
        writer_.put(section_count);
        writer_.put(uint64_t(kCacheHeaderSize));  // section table offset
        writer_.put(uint64_t(0));                 // file size (finish)
        writer_.put(kCacheSectionEntrySize);
        writer_.put(uint32_t(0));
        writer_.put(uint32_t(0));
        writer_.put(uint32_t(0));  // header CRC (finish)
        bytes.resize(kCacheHeaderSize + size_t(section_count) * kCacheSectionEntrySize, 0);
        writer_.pad8();
    }

    ByteWriter& out() { return writer_; }

    void beginSection(uint32_t type, uint32_t flags) { sections_.push_back({type, flags, writer_.bytes.size(), 0}); }

    void endSection() {
        sections_.back().length = writer_.bytes.size() - sections_.back().offset;
        writer_.pad8();
    }

    void finish() {
        std::vector<uint8_t>& bytes = writer_.bytes;
        for (size_t i = 0; i < sections_.size() && i < section_count_; ++i) {
            const size_t e = kCacheHeaderSize + i * kCacheSectionEntrySize;
            const Section& s = sections_[i];
            writer_.patch(e, s.type);
            writer_.patch(e + 4, s.flags);
            writer_.patch(e + 8, uint64_t(s.offset));
            writer_.patch(e + 16, uint64_t(s.length));
            writer_.patch(e + 24, cacheCrc32(bytes.data() + s.offset, s.length));
            writer_.patch(e + 28, uint32_t(0));
        }
        writer_.patch(40, uint64_t(bytes.size()));
        uint32_t crc = cacheCrc32(bytes.data(), kCacheHeaderCrcOffset);
        crc = cacheCrc32(bytes.data() + kCacheHeaderSize, size_t(section_count_) * kCacheSectionEntrySize, crc);
        writer_.patch(kCacheHeaderCrcOffset, crc);
    }

private:
    struct Section {
        uint32_t type, flags;
        size_t offset, length;
    };
    ByteWriter writer_;
    uint32_t section_count_;
    std::vector<Section> sections_;
};

}  // namespace sharcbake
