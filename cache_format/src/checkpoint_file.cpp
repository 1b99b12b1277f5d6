// SPDX-License-Identifier: Apache-2.0
// The checkpoint file (SPEC.md §C): the .sharc container (header §F.3, section table §F.4,
// CRC-32s) under the checkpoint identifier, with STAT, SLOT, SETT and CNTR sections.
#include "sharcbake/checkpoint_file.h"

#include "sharcbake/format.h"
#include "container.h"
#include "utf8.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string_view>
#include <unordered_set>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake {
namespace {

constexpr uint16_t kCheckpointVersionMajor = 2;
constexpr uint16_t kCheckpointVersionMinor = 0;

constexpr uint32_t kSectionState = cacheFourCC('S', 'T', 'A', 'T');
constexpr uint32_t kSectionSlots = cacheFourCC('S', 'L', 'O', 'T');
constexpr uint32_t kSectionSettings = cacheFourCC('S', 'E', 'T', 'T');
constexpr uint32_t kSectionCounters = cacheFourCC('C', 'N', 'T', 'R');
constexpr uint32_t kSectionOrder[4] = {kSectionState, kSectionSlots, kSectionSettings, kSectionCounters};

constexpr uint32_t kStateSize = 32;
constexpr uint32_t kSlotRecordSize = 64;
constexpr uint32_t kCounterUnsigned = 1;
constexpr uint32_t kCounterReal = 2;

/// Bounds-checked little-endian reader over one section.
struct ByteReader {
    const uint8_t* data;
    uint64_t size;
    uint64_t at = 0;
    bool ok = true;
    template <typename T> T get() {
        T value{};
        if (!ok || size - at < sizeof(T)) {
            ok = false;
            return value;
        }
        std::memcpy(&value, data + at, sizeof(T));
        at += sizeof(T);
        return value;
    }
    std::string text(uint32_t length, bool* utf8_ok) {
        if (!ok || size - at < length) {
            ok = false;
            return {};
        }
        std::string s(reinterpret_cast<const char*>(data + at), length);
        if (!isValidUtf8(data + at, length)) *utf8_ok = false;
        at += length;
        return s;
    }
};


bool validSettingsText(const std::vector<std::pair<std::string, std::string>>& settings, std::string* problem) {
    std::unordered_set<std::string_view> keys;  // linear, not quadratic, in the entry count
    keys.reserve(settings.size());
    for (size_t i = 0; i < settings.size(); ++i) {
        const auto& [key, value] = settings[i];
        if (key.empty() || !isValidUtf8(reinterpret_cast<const uint8_t*>(key.data()), key.size()) ||
            !isValidUtf8(reinterpret_cast<const uint8_t*>(value.data()), value.size())) {
            *problem = "setting " + std::to_string(i) + ": keys must be non-empty and text valid UTF-8";
            return false;
        }
        if (!keys.insert(key).second) {
            *problem = "duplicate setting \"" + key + "\"";
            return false;
        }
    }
    return true;
}

template <typename Value>
bool uniqueNames(const std::vector<std::pair<std::string, Value>>& list, std::unordered_set<std::string_view>& seen,
                 std::string* problem) {
    for (const auto& [name, value] : list) {
        (void)value;
        if (name.empty() || !isValidUtf8(reinterpret_cast<const uint8_t*>(name.data()), name.size())) {
            *problem = "counter names must be non-empty UTF-8";
            return false;
        }
        if (!seen.insert(name).second) {
            *problem = "duplicate counter \"" + name + "\"";
            return false;
        }
    }
    return true;
}

/// Rules C8-C11 on the decoded data (shared by the writer, which refuses what a reader rejects).
bool validateContent(const CheckpointData& data, std::string* problem) {
    if (data.capacity == 0 || data.bucket_size == 0 || data.bucket_size > data.capacity) {
        *problem = "C8: capacity and bucket size must be >= 1, the bucket size <= the capacity";
        return false;
    }
    if (data.iterations_done > kCheckpointMaxIterations) {
        *problem = "C8: iterations_done " + std::to_string(data.iterations_done) + " is above " +
                   std::to_string(kCheckpointMaxIterations);
        return false;
    }
    if (!std::isfinite(data.radiance_scale) || !(data.radiance_scale > 0.0)) {
        *problem = "C8: the radiance scale must be finite and > 0";
        return false;
    }
    for (size_t i = 0; i < data.slots.size(); ++i) {
        const CheckpointSlot& s = data.slots[i];
        const std::string name = "C9: slot record " + std::to_string(i);
        if (s.slot >= data.capacity || (i > 0 && data.slots[i - 1].slot >= s.slot)) {
            *problem = name + ": slots must be strictly increasing and below the capacity";
            return false;
        }
        if (s.key == kHashGridInvalidKey) {
            *problem = name + ": key 0 marks an empty slot and is never stored";
            return false;
        }
        for (float c : s.mean) {
            if (!std::isfinite(c) || c < 0.0f) {
                *problem = name + ": mean radiance must be finite and >= 0";
                return false;
            }
        }
        for (float c : s.feedback) {
            if (!std::isfinite(c) || c < 0.0f) {
                *problem = name + ": feedback radiance must be finite and >= 0";
                return false;
            }
        }
        // The cache file keeps a voxel's weight in float32: a weight beyond its range resumed, baked
        // every iteration and then failed to write the cache (exit 4).
        if (!std::isfinite(s.weight) || s.weight < 0.0 || s.weight > double(std::numeric_limits<float>::max())) {
            *problem = name + ": weight must be finite, >= 0 and within float32's range (the cache stores it so)";
            return false;
        }
    }
    std::string text_problem;
    if (!validSettingsText(data.settings, &text_problem)) {
        *problem = "C10: " + text_problem;
        return false;
    }
    std::unordered_set<std::string_view> seen;
    if (!uniqueNames(data.counts, seen, &text_problem) || !uniqueNames(data.amounts, seen, &text_problem)) {
        *problem = "C11: " + text_problem;
        return false;
    }
    return true;
}

}  // namespace

CacheFileStatus encodeCheckpoint(const CheckpointData& data, std::vector<uint8_t>* out, std::string* message) {
    if (!out) return fail(CacheFileStatus::kInvalidArgument, message, "encodeCheckpoint: null output");
    if (!hostIsLittleEndian()) return fail(CacheFileStatus::kUnsupportedFeature, message, "big-endian hosts are not supported");
    std::string problem;
    if (!validateContent(data, &problem)) return fail(CacheFileStatus::kInvalidData, message, problem);

    constexpr uint32_t kSections = 4;
    std::vector<uint8_t>& bytes = *out;
    bytes.clear();
    bytes.reserve(kCacheHeaderSize + kSections * kCacheSectionEntrySize + kStateSize +
                  data.slots.size() * kSlotRecordSize + 4096);
    ContainerWriter container(bytes, kCheckpointIdentifier, kCheckpointVersionMajor, kCheckpointVersionMinor,
                              kSections);
    ByteWriter& w = container.out();
    for (uint32_t section = 0; section < kSections; ++section) {
        container.beginSection(kSectionOrder[section], kCacheSectionRequired);
        switch (kSectionOrder[section]) {
            case kSectionState:
                w.put(data.iterations_done);
                w.put(data.capacity);
                w.put(data.bucket_size);
                w.put(uint32_t(0));
                w.put(uint64_t(data.slots.size()));
                w.put(data.radiance_scale);
                break;
            case kSectionSlots:
                for (const CheckpointSlot& s : data.slots) {
                    w.put(s.slot);
                    w.put(s.frames);
                    w.put(s.key);
                    w.put(s.mean[0]);
                    w.put(s.mean[1]);
                    w.put(s.mean[2]);
                    w.put(s.last_iteration);
                    w.put(s.weight);
                    w.put(s.total_samples);
                    w.put(s.feedback[0]);
                    w.put(s.feedback[1]);
                    w.put(s.feedback[2]);
                    w.put(uint64_t(0));
                }
                break;
            case kSectionSettings:
                w.put(uint32_t(data.settings.size()));
                w.put(uint32_t(0));
                for (const auto& [key, value] : data.settings) {
                    w.put(uint32_t(key.size()));
                    w.put(uint32_t(value.size()));
                    w.putText(key);
                    w.putText(value);
                }
                break;
            case kSectionCounters:
                w.put(uint32_t(data.counts.size() + data.amounts.size()));
                w.put(uint32_t(0));
                for (const auto& [name, value] : data.counts) {
                    w.put(uint32_t(name.size()));
                    w.put(kCounterUnsigned);
                    w.put(value);
                    w.putText(name);
                }
                for (const auto& [name, value] : data.amounts) {
                    w.put(uint32_t(name.size()));
                    w.put(kCounterReal);
                    w.put(value);
                    w.putText(name);
                }
                break;
        }
        container.endSection();
    }
    container.finish();
    return CacheFileStatus::kOk;
}

// The numbered checks follow SPEC §C.4; each failure cites its rule.
namespace {

/// The four sections a checkpoint must hold, in kSectionOrder (STAT, SLOT, SETT, CNTR).
struct CheckpointSections {
    const uint8_t* data[4] = {nullptr, nullptr, nullptr, nullptr};
    uint64_t length[4] = {0, 0, 0, 0};
};

/// C1 - C7: identifier, version, header and table geometry, checksums, the sections back to
/// back with zero padding, the four required ones once each.
CacheFileStatus readCheckpointFrame(const uint8_t* d, size_t size, CheckpointSections* sections, std::string* message) {
    using S = CacheFileStatus;
    // C1: identifier. A file that ends within it (an empty one: a copy or a write cut short) is
    // truncated, not "not a checkpoint".
    if (size < sizeof kCheckpointIdentifier && (size == 0 || std::memcmp(d, kCheckpointIdentifier, size) == 0)) {
        return fail(S::kTruncated, message,
                    "C1: the file ends within the checkpoint identifier (" + std::to_string(size) + " bytes)");
    }
    if (size < sizeof kCheckpointIdentifier || std::memcmp(d, kCheckpointIdentifier, sizeof kCheckpointIdentifier) != 0) {
        if (size >= sizeof kCacheIdentifier && std::memcmp(d, kCacheIdentifier, sizeof kCacheIdentifier) == 0) {
            return fail(S::kBadMagic, message, "C1: this is a .sharc cache, not a checkpoint (give the file --checkpoint wrote)");
        }
        return fail(S::kBadMagic, message, "C1: not a sharcbake checkpoint (identifier mismatch)");
    }
    // C2: header present; C3: version.
    if (size < kCacheHeaderSize) return fail(S::kTruncated, message, "C2: truncated header");
    const ContainerHeader header = ContainerHeader::read(d);
    const uint16_t major = header.version_major, minor = header.version_minor;
    if (major != kCheckpointVersionMajor) {
        return fail(S::kUnsupportedVersion, message,
                    "C3: checkpoint version " + std::to_string(major) + "." + std::to_string(minor) +
                        " is not supported (this reader reads " + std::to_string(kCheckpointVersionMajor) + ".x)");
    }
    // C4: declared size and header/table geometry.
    const uint64_t file_size = header.file_size;
    if (file_size != size) {
        return fail(file_size > size ? S::kTruncated : S::kTrailingBytes, message,
                    "C4: the header declares " + std::to_string(file_size) + " bytes, the file has " + std::to_string(size));
    }
    const uint32_t header_size = header.header_size;
    const uint32_t section_count = header.section_count;
    if (header_size != kCacheHeaderSize || header.table_offset != header_size ||
        header.entry_size != kCacheSectionEntrySize ||
        section_count == 0 || section_count > kCacheMaxSections ||
        header_size + uint64_t(section_count) * kCacheSectionEntrySize > size) {
        return fail(S::kCorrupt, message, "C4: bad header or section table geometry");
    }
    const uint64_t table_end = header.tableEnd();
    // C5: header + table checksum.
    if (ContainerHeader::computeCrc32(d, table_end) != header.header_crc32) {
        return fail(S::kChecksumMismatch, message, "C5: header checksum mismatch");
    }
    if (header.flags != 0) return fail(S::kUnsupportedFeature, message, "C5: unknown header flags");
    if (header.reserved[0] != 0 || header.reserved[1] != 0) {
        return fail(S::kCorrupt, message, "C5: reserved header fields are not zero");
    }
    // C6: sections back to back, zero padding, checksums; C7: the four required sections once each.
    const uint8_t** found = sections->data;
    uint64_t* found_length = sections->length;
    uint64_t expected = align8(table_end);
    for (uint32_t i = 0; i < section_count; ++i) {
        const ContainerEntry entry = ContainerEntry::read(d, header_size, i);
        const uint32_t type = entry.type, flags = entry.flags;
        const uint64_t offset = entry.offset, length = entry.length;
        const std::string name = "section " + std::to_string(i);
        if ((flags & ~kCacheSectionRequired) != 0 || entry.reserved != 0 || offset != expected || offset > size ||
            length > size - offset || align8(offset + length) > size) {
            return fail(S::kCorrupt, message, "C6: " + name + ": bad flags, offset or length");
        }
        for (uint64_t p = offset + length; p < align8(offset + length); ++p) {
            if (d[p] != 0) return fail(S::kCorrupt, message, "C6: " + name + ": non-zero padding");
        }
        if (cacheCrc32(d + offset, size_t(length)) != entry.crc32) {
            return fail(S::kChecksumMismatch, message, "C6: " + name + ": checksum mismatch");
        }
        expected = align8(offset + length);
        bool known = false;
        for (int k = 0; k < 4; ++k) {
            if (type != kSectionOrder[k]) continue;
            if (found[k]) return fail(S::kCorrupt, message, "C7: " + name + " appears twice");
            found[k] = d + offset;
            found_length[k] = length;
            known = true;
        }
        if (!known && (flags & kCacheSectionRequired)) {
            return fail(S::kUnsupportedFeature, message, "C7: " + name + " is an unknown required section");
        }
    }
    if (expected != size) return fail(S::kCorrupt, message, "C6: bytes after the last section");
    for (int k = 0; k < 4; ++k) {
        if (!found[k]) return fail(S::kCorrupt, message, "C7: a required section (STAT, SLOT, SETT, CNTR) is missing");
    }
    return S::kOk;
}

/// C8: STAT.
CacheFileStatus readState(const CheckpointSections& sections, CheckpointData& result, uint64_t* slot_count,
                          std::string* message) {
    using S = CacheFileStatus;
    const uint8_t* const* found = sections.data;
    const uint64_t* found_length = sections.length;
    // C8: STAT.
    if (found_length[0] != kStateSize) return fail(S::kCorrupt, message, "C8: STAT must be 32 bytes");
    ByteReader state{found[0], found_length[0]};
    result.iterations_done = state.get<uint32_t>();
    result.capacity = state.get<uint32_t>();
    result.bucket_size = state.get<uint32_t>();
    const uint32_t reserved = state.get<uint32_t>();
    *slot_count = state.get<uint64_t>();
    result.radiance_scale = state.get<double>();
    if (reserved != 0) return fail(S::kCorrupt, message, "C8: STAT reserved field is not zero");
    return S::kOk;
}

/// C9: SLOT.
CacheFileStatus readSlots(const CheckpointSections& sections, uint64_t slot_count, CheckpointData& result,
                          std::string* message) {
    using S = CacheFileStatus;
    const uint8_t* const* found = sections.data;
    const uint64_t* found_length = sections.length;
    // C9: SLOT.
    if (slot_count > result.capacity || found_length[1] != slot_count * kSlotRecordSize) {
        return fail(S::kCorrupt, message, "C9: SLOT holds " + std::to_string(found_length[1]) + " bytes for " +
                                               std::to_string(slot_count) + " records");
    }
    ByteReader slots{found[1], found_length[1]};
    result.slots.resize(size_t(slot_count));
    for (CheckpointSlot& s : result.slots) {
        s.slot = slots.get<uint32_t>();
        s.frames = slots.get<uint32_t>();
        s.key = slots.get<uint64_t>();
        for (float& c : s.mean) c = slots.get<float>();
        s.last_iteration = slots.get<uint32_t>();
        s.weight = slots.get<double>();
        s.total_samples = slots.get<uint32_t>();
        for (float& c : s.feedback) c = slots.get<float>();
        if (slots.get<uint64_t>() != 0) return fail(S::kCorrupt, message, "C9: slot record reserved field is not zero");
    }
    return S::kOk;
}

/// C10: SETT, filling its section exactly.
CacheFileStatus readSettings(const CheckpointSections& sections, CheckpointData& result, std::string* message) {
    using S = CacheFileStatus;
    const uint8_t* const* found = sections.data;
    const uint64_t* found_length = sections.length;
    ByteReader settings{found[2], found_length[2]};
    bool utf8_ok = true;
    const uint32_t setting_count = settings.get<uint32_t>();
    if (settings.get<uint32_t>() != 0 || setting_count > found_length[2] / 8) {
        return fail(S::kCorrupt, message, "C10: bad SETT header");
    }
    for (uint32_t i = 0; i < setting_count && settings.ok; ++i) {
        const uint32_t key_length = settings.get<uint32_t>(), value_length = settings.get<uint32_t>();
        std::string key = settings.text(key_length, &utf8_ok);
        std::string value = settings.text(value_length, &utf8_ok);
        result.settings.emplace_back(std::move(key), std::move(value));
    }
    if (!settings.ok || settings.at != settings.size || !utf8_ok) {
        return fail(S::kCorrupt, message, "C10: SETT entries do not fill the section exactly or are not UTF-8");
    }
    return S::kOk;
}

/// C11: CNTR, filling its section exactly.
CacheFileStatus readCounters(const CheckpointSections& sections, CheckpointData& result, std::string* message) {
    using S = CacheFileStatus;
    const uint8_t* const* found = sections.data;
    const uint64_t* found_length = sections.length;
    bool utf8_ok = true;
    ByteReader counters{found[3], found_length[3]};
    const uint32_t counter_count = counters.get<uint32_t>();
    if (counters.get<uint32_t>() != 0 || counter_count > found_length[3] / 16) {
        return fail(S::kCorrupt, message, "C11: bad CNTR header");
    }
    for (uint32_t i = 0; i < counter_count && counters.ok; ++i) {
        const uint32_t name_length = counters.get<uint32_t>(), kind = counters.get<uint32_t>();
        const uint64_t bits = counters.get<uint64_t>();
        std::string name = counters.text(name_length, &utf8_ok);
        if (kind == kCounterUnsigned) {
            result.counts.emplace_back(std::move(name), bits);
        } else if (kind == kCounterReal) {
            double value;
            std::memcpy(&value, &bits, 8);
            result.amounts.emplace_back(std::move(name), value);
        } else {
            return fail(S::kCorrupt, message, "C11: counter " + std::to_string(i) + " has unknown kind " + std::to_string(kind));
        }
    }
    if (!counters.ok || counters.at != counters.size || !utf8_ok) {
        return fail(S::kCorrupt, message, "C11: CNTR entries do not fill the section exactly or are not UTF-8");
    }
    return S::kOk;
}

}  // namespace

/// Validates a checkpoint rule by rule (SPEC §C, C1 - C11) and decodes it.
CacheFileStatus decodeCheckpoint(const uint8_t* d, size_t size, CheckpointData* data, std::string* message) {
    using S = CacheFileStatus;
    if (!d && size > 0) return fail(S::kInvalidArgument, message, "decodeCheckpoint: null data");
    if (!hostIsLittleEndian()) return fail(S::kUnsupportedFeature, message, "big-endian hosts are not supported");
    CheckpointSections sections;
    CheckpointData result;
    uint64_t slot_count = 0;
    CacheFileStatus status = readCheckpointFrame(d, size, &sections, message);
    if (status == S::kOk) status = readState(sections, result, &slot_count, message);
    if (status == S::kOk) status = readSlots(sections, slot_count, result, message);
    if (status == S::kOk) status = readSettings(sections, result, message);
    if (status == S::kOk) status = readCounters(sections, result, message);
    if (status != S::kOk) return status;
    std::string problem;
    if (!validateContent(result, &problem)) return fail(S::kCorrupt, message, problem);
    if (data) *data = std::move(result);
    return S::kOk;
}

CacheFileStatus writeCheckpointFile(const std::string& path, const CheckpointData& data, std::string* message) {
    std::vector<uint8_t> bytes;
    const CacheFileStatus encoded = encodeCheckpoint(data, &bytes, message);
    if (encoded != CacheFileStatus::kOk) {
        if (message) *message = path + ": " + *message;
        return encoded;
    }
    // A per-process temporary beside the target; one left by a killed process is removed by the
    // next write (prepareOutputFile), and a half-written checkpoint never appears at `path`.
    return writeFileAtomically(path, bytes.data(), bytes.size(), message);
}

CacheFileStatus readCheckpointFile(const std::string& path, CheckpointData* data, std::string* message) {
    struct stat info {};
    if (::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
        return fail(CacheFileStatus::kIoError, message, path + ": not a regular file (a FIFO, device or folder)");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) return fail(CacheFileStatus::kIoError, message, path + ": cannot open");
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) return fail(CacheFileStatus::kIoError, message, path + ": read failed");
    const CacheFileStatus status = decodeCheckpoint(bytes.data(), bytes.size(), data, message);
    if (status != CacheFileStatus::kOk && message) *message = path + ": " + *message;
    return status;
}

}  // namespace sharcbake
