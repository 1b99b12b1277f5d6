// SPDX-License-Identifier: Apache-2.0
// The .sharc file format (SPEC.md §F) and the runtime library: round trip, golden file, reject
// tests (every prefix, every flipped byte, versions, sections, trailing bytes), lookups and GPU
// buffers. Links only sharcbake_runtime.
#include "sharcbake/cache_file.h"
#include "sharcbake/cache_merge.h"
#include "sharcbake/format.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime.h"
#include "sharcbake/runtime_c.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <csignal>
#include <chrono>

#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake {
namespace {

const std::string kGoldenPath = std::string(SHARCBAKE_GOLDEN_DIR) + "/small.v1.0.sharc";  ///< format 1.0, kept
const std::string kGolden11Path = std::string(SHARCBAKE_GOLDEN_DIR) + "/small.v1.1.sharc";  ///< format 1.1, kept
const std::string kGolden12Path = std::string(SHARCBAKE_GOLDEN_DIR) + "/small.v1.2.sharc";

// ------------------------------------------------------------------------------------------------
// Helpers
// ------------------------------------------------------------------------------------------------

/// The deterministic cache behind the golden file: 5 levels, all 8 normal octants, metadata.
/// Never change it without bumping the golden file's name (goldens are kept forever).
CacheData goldenData() {
    CacheData data;
    data.logarithm_base = 2.0f;
    data.scene_scale = 50.0f;
    data.level_bias = 0.0f;
    data.bucket_size = 16;
    data.bake_capacity = 4096;
    const float distances[5] = {1.0f, 3.0f, 6.0f, 12.0f, 24.0f};  // levels 1, 1, 2, 3, 4
    const Float3 dirs[4] = {{1, 0, 0}, {0, 0.6f, 0.8f}, {-0.48f, 0.6f, -0.64f}, {0, -1, 0}};
    std::map<uint64_t, CacheVoxel> by_key;
    for (int i = 0; i < 40; ++i) {
        const float d = distances[i % 5] + 0.37f * float(i / 5);
        const Float3 dir = dirs[i % 4];
        const Float3 p{dir.x * d + 0.11f * float(i), dir.y * d, dir.z * d - 0.05f * float(i)};
        const Float3 n{(i & 1) ? -1.0f : 1.0f, (i & 2) ? -1.0f : 1.0f, (i & 4) ? -1.0f : 1.0f};
        HashGridParameters params = data.gridParameters();
        CacheVoxel v;
        v.key = hashGridKey(p, n, params);
        v.radiance[0] = 0.125f * float(i);
        v.radiance[1] = 0.5f + 0.25f * float(i % 7);
        v.radiance[2] = 1.0f / float(i + 1);
        v.sample_weight = 1.0f + float(i) * 3.5f;
        by_key.emplace(v.key, v);
    }
    for (const auto& kv : by_key) data.voxels.push_back(kv.second);
    data.metadata = {{"writer", "sharcbake golden generator"},
                     {"scene_hash", "fnv1a64:0123456789abcdef"},
                     {"iterations", "16"},
                     {"seed", "7"},
                     {"bake_settings", "--iterations 16 --seed 7"},
                     {"bake_seconds", "0"},
                     {"note", "UTF-8 \xC3\xA9\xE2\x82\xAC"}};
    return data;
}

/// The golden cache of format 1.1: goldenData() with a GPU radiance scale, so the file has RSCL.
CacheData goldenData11() {
    CacheData data = goldenData();
    data.gpu_radiance_scale = 0.25f;
    return data;
}

/// goldenData11 with a grid anchor (ANCR, format 1.2), as a scene 10 km from the origin has.
CacheData goldenData12() {
    CacheData data = goldenData11();
    data.grid_anchor = Float3{1.0e4f, 0.5f, -3.0f};
    return data;
}

std::vector<uint8_t> encode(const CacheData& data) {
    std::vector<uint8_t> bytes;
    std::string message;
    EXPECT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kOk) << message;
    return bytes;
}

std::vector<uint8_t> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::vector<uint8_t>((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

CacheFileStatus openBytes(const std::vector<uint8_t>& bytes, CacheError* error = nullptr, CacheView* view = nullptr) {
    CacheView local;
    return CacheView::openMemory(bytes.data(), bytes.size(), view ? view : &local, error);
}

std::string tempPath(const char* name) {
    return ::testing::TempDir() + "sharcbake_" + std::to_string(::getpid()) + "_" + name;
}

template <typename T> T get(const std::vector<uint8_t>& b, size_t at) {
    T v;
    std::memcpy(&v, b.data() + at, sizeof v);
    return v;
}
template <typename T> void set(std::vector<uint8_t>& b, size_t at, T v) { std::memcpy(b.data() + at, &v, sizeof v); }

void fixHeaderCrc(std::vector<uint8_t>& b) {
    const uint32_t header_size = get<uint32_t>(b, 20);
    const uint32_t count = get<uint32_t>(b, 28);
    uint32_t crc = cacheCrc32(b.data(), kCacheHeaderCrcOffset);
    crc = cacheCrc32(b.data() + kCacheHeaderSize, header_size - kCacheHeaderSize + count * kCacheSectionEntrySize, crc);
    set(b, kCacheHeaderCrcOffset, crc);
}

struct RawSection {
    uint32_t type, flags;
    std::vector<uint8_t> data;
};

std::vector<RawSection> splitSections(const std::vector<uint8_t>& b) {
    std::vector<RawSection> out;
    const uint32_t count = get<uint32_t>(b, 28);
    for (uint32_t i = 0; i < count; ++i) {
        const size_t e = kCacheHeaderSize + i * kCacheSectionEntrySize;
        const uint64_t offset = get<uint64_t>(b, e + 8), length = get<uint64_t>(b, e + 16);
        out.push_back({get<uint32_t>(b, e), get<uint32_t>(b, e + 4),
                       std::vector<uint8_t>(b.begin() + long(offset), b.begin() + long(offset + length))});
    }
    return out;
}

/// Lays sections out exactly as SPEC §F.4 requires, with valid checksums.
std::vector<uint8_t> assemble(uint16_t major, uint16_t minor, const std::vector<RawSection>& sections) {
    std::vector<uint8_t> b(kCacheHeaderSize + sections.size() * kCacheSectionEntrySize, 0);
    std::memcpy(b.data(), kCacheIdentifier, 16);
    set(b, 16, major);
    set(b, 18, minor);
    set(b, 20, kCacheHeaderSize);
    set(b, 28, uint32_t(sections.size()));
    set(b, 32, uint64_t(kCacheHeaderSize));
    set(b, 48, kCacheSectionEntrySize);
    for (size_t i = 0; i < sections.size(); ++i) {
        b.resize((b.size() + 7) & ~size_t(7), 0);
        const size_t e = kCacheHeaderSize + i * kCacheSectionEntrySize;
        set(b, e, sections[i].type);
        set(b, e + 4, sections[i].flags);
        set(b, e + 8, uint64_t(b.size()));
        set(b, e + 16, uint64_t(sections[i].data.size()));
        set(b, e + 24, cacheCrc32(sections[i].data.data(), sections[i].data.size()));
        b.insert(b.end(), sections[i].data.begin(), sections[i].data.end());
    }
    b.resize((b.size() + 7) & ~size_t(7), 0);
    set(b, 40, uint64_t(b.size()));
    fixHeaderCrc(b);
    return b;
}

Float3 normalFromBits(uint32_t bits) {
    return Float3{(bits & 1) ? -1.0f : 1.0f, (bits & 2) ? -1.0f : 1.0f, (bits & 4) ? -1.0f : 1.0f};
}

/// A camera whose distance to `p` gives level `level` (b = 2, beta = 0: L = floor(log2 d)).
Float3 cameraForLevel(const Float3& p, uint32_t level) {
    return Float3{p.x - 1.5f * std::ldexp(1.0f, int(level)), p.y, p.z};
}

// ------------------------------------------------------------------------------------------------
// Round trip and golden file
// ------------------------------------------------------------------------------------------------

TEST(CacheFile, Crc32MatchesTheBitwiseDefinition) {
    // The table-driven CRC (16, 8 and 1 bytes per step) against the polynomial bit by bit, for
    // every length and split point that reaches each path; plus the standard check value.
    auto bitwise = [](const uint8_t* p, size_t n, uint32_t crc) {
        crc = ~crc;
        for (size_t i = 0; i < n; ++i) {
            crc ^= p[i];
            for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
        }
        return ~crc;
    };
    EXPECT_EQ(cacheCrc32("123456789", 9), 0xCBF43926u);
    std::vector<uint8_t> bytes(100);
    std::mt19937 rng(3);
    for (uint8_t& b : bytes) b = uint8_t(rng());
    for (size_t n = 0; n <= bytes.size(); ++n) {
        ASSERT_EQ(cacheCrc32(bytes.data(), n), bitwise(bytes.data(), n, 0)) << n;
        const size_t split = n / 3;
        ASSERT_EQ(cacheCrc32(bytes.data() + split, n - split, cacheCrc32(bytes.data(), split)), bitwise(bytes.data(), n, 0));
    }
}

TEST(CacheFile, RoundTripThroughDisk) {
    const CacheData data = goldenData();
    ASSERT_GT(data.voxels.size(), 30u);
    const std::string path = tempPath("roundtrip.sharc");
    std::string message;
    ASSERT_EQ(writeCacheFile(path, data, &message), CacheFileStatus::kOk) << message;
    CacheData back;
    ASSERT_EQ(readCacheFile(path, &back, &message), CacheFileStatus::kOk) << message;
    EXPECT_EQ(back.version_major, kCacheVersionMajor);
    EXPECT_EQ(back.version_minor, kCacheVersionMinor);
    EXPECT_EQ(back.logarithm_base, data.logarithm_base);
    EXPECT_EQ(back.scene_scale, data.scene_scale);
    EXPECT_EQ(back.level_bias, data.level_bias);
    EXPECT_EQ(back.bucket_size, data.bucket_size);
    EXPECT_EQ(back.bake_capacity, data.bake_capacity);
    EXPECT_EQ(back.gpu_radiance_scale, 1.0f);
    ASSERT_EQ(back.voxels.size(), data.voxels.size());
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        EXPECT_EQ(back.voxels[i].key, data.voxels[i].key);
        EXPECT_EQ(std::memcmp(back.voxels[i].radiance, data.voxels[i].radiance, 12), 0);
        EXPECT_EQ(back.voxels[i].sample_weight, data.voxels[i].sample_weight);
    }
    EXPECT_EQ(back.metadata, data.metadata);
    uint64_t level_total = 0;
    for (const CacheLevel& l : back.levels) level_total += l.voxel_count;
    EXPECT_EQ(level_total, data.voxels.size());
    EXPECT_GE(back.levels.size(), 4u);
    // Deterministic: the same data gives the same bytes; at most 32 bytes per voxel plus overhead.
    const std::vector<uint8_t> on_disk = readBytes(path);
    EXPECT_EQ(on_disk, encode(data));
    EXPECT_LE(on_disk.size(), 512 + 24 * data.voxels.size() + 8 * back.levels.size());
    std::remove(path.c_str());
}

TEST(CacheFile, EmptyCacheRoundTrips) {
    CacheData data;
    data.bake_capacity = 16;
    const std::vector<uint8_t> bytes = encode(data);
    CacheView view;
    CacheError error;
    ASSERT_EQ(openBytes(bytes, &error, &view), CacheFileStatus::kOk) << error.message;
    EXPECT_EQ(view.voxelCount(), 0u);
    EXPECT_TRUE(view.levels().empty());
    Float3 r;
    EXPECT_FALSE(view.lookup({1, 2, 3}, {0, 1, 0}, {0, 0, 0}, &r));
    EXPECT_FALSE(view.lookupNearestLevel({1, 2, 3}, {0, 1, 0}, {0, 0, 0}, &r));
}

// Writes the golden when SHARCBAKE_UPDATE_GOLDENS is set; otherwise the writer must reproduce it.
// (small.v1.0.sharc and small.v1.1.sharc, of formats 1.0 and 1.1, are no longer written:
// GoldenReadsBack keeps them readable.)
TEST(CacheFileGolden, WriterReproducesGolden) {
    const std::vector<uint8_t> bytes = encode(goldenData12());
    if (std::getenv("SHARCBAKE_UPDATE_GOLDENS")) {
        std::ofstream out(kGolden12Path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        ASSERT_TRUE(out.good());
    }
    const std::vector<uint8_t> golden = readBytes(kGolden12Path);
    ASSERT_FALSE(golden.empty()) << kGolden12Path << " is missing; run with SHARCBAKE_UPDATE_GOLDENS=1";
    EXPECT_EQ(bytes, golden)
        << "the writer no longer reproduces " << kGolden12Path
        << ". If the change is intended, add a new golden for the new format version "
           "(goldens are kept forever) and verify, then regenerate with SHARCBAKE_UPDATE_GOLDENS=1";
}

TEST(CacheFileGolden, GoldenReadsBack) {
    // Every golden stays readable: 1.0 (no RSCL: scale 1), 1.1 (RSCL 0.25; VOXL is not scaled) and
    // 1.2 (ANCR: the anchor; without it the origin).
    struct Golden {
        std::string path;
        uint16_t minor;
        float scale;
        size_t sections;
        Float3 anchor;
    };
    for (const Golden& g :
         {Golden{kGoldenPath, 0, 1.0f, 5, {0.0f, 0.0f, 0.0f}}, Golden{kGolden11Path, 1, 0.25f, 6, {0.0f, 0.0f, 0.0f}},
          Golden{kGolden12Path, 2, 0.25f, 7, goldenData12().grid_anchor}}) {
        CacheData back;
        std::string message;
        ASSERT_EQ(readCacheFile(g.path, &back, &message), CacheFileStatus::kOk) << message;
        EXPECT_EQ(back.version_major, 1);
        EXPECT_EQ(back.version_minor, g.minor);
        EXPECT_EQ(back.gpu_radiance_scale, g.scale);
        EXPECT_EQ(back.grid_anchor.x, g.anchor.x);
        EXPECT_EQ(back.grid_anchor.y, g.anchor.y);
        EXPECT_EQ(back.grid_anchor.z, g.anchor.z);
        const CacheData expected = goldenData();
        ASSERT_EQ(back.voxels.size(), expected.voxels.size());
        for (size_t i = 0; i < expected.voxels.size(); ++i) {
            EXPECT_EQ(back.voxels[i].key, expected.voxels[i].key);
            EXPECT_EQ(back.voxels[i].radiance[0], expected.voxels[i].radiance[0]);
            EXPECT_EQ(back.voxels[i].sample_weight, expected.voxels[i].sample_weight);
        }
        EXPECT_EQ(back.metadata, expected.metadata);
        CacheView view;
        CacheError error;
        ASSERT_EQ(CacheView::openFile(g.path, &view, &error, CacheView::FileMode::kMap), CacheFileStatus::kOk)
            << error.message;
        ASSERT_EQ(view.sections().size(), g.sections);
        EXPECT_EQ(view.metadata("seed"), "7");
        EXPECT_EQ(view.gpuRadianceScale(), g.scale);
        if (g.sections >= 6) {
            EXPECT_EQ(view.sections()[5].type, kSectionRadianceScale);
            EXPECT_TRUE(view.sections()[5].required);
        }
        if (g.sections == 7) {
            EXPECT_EQ(view.sections()[6].type, kSectionGridAnchor);
            EXPECT_FALSE(view.sections()[6].required);
        }
        EXPECT_EQ(view.gridAnchor().x, g.anchor.x);
    }
}

// ------------------------------------------------------------------------------------------------
// Reject tests (SPEC §F.10)
// ------------------------------------------------------------------------------------------------

TEST(CacheFileReject, EveryPrefixIsRejected) {
    const std::vector<uint8_t> bytes = encode(goldenData());
    for (size_t n = 0; n < bytes.size(); ++n) {
        const std::vector<uint8_t> prefix(bytes.begin(), bytes.begin() + long(n));
        CacheError error;
        const CacheFileStatus status = openBytes(prefix, &error);
        EXPECT_NE(status, CacheFileStatus::kOk) << "prefix of " << n << " bytes accepted";
        if (n >= kCacheHeaderSize) {
            EXPECT_EQ(status, CacheFileStatus::kTruncated) << n << ": " << error.message;
        }
    }
}

TEST(CacheFileReject, EveryFlippedByteIsRejected) {
    for (const std::vector<uint8_t>& bytes : {encode(goldenData()), encode(goldenData11()), encode(goldenData12())}) {
        ASSERT_EQ(openBytes(bytes), CacheFileStatus::kOk);
        for (size_t i = 0; i < bytes.size(); ++i) {
            for (uint8_t mask : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
                std::vector<uint8_t> bad = bytes;
                bad[i] ^= mask;
                CacheError error;
                EXPECT_NE(openBytes(bad, &error), CacheFileStatus::kOk)
                    << "byte " << i << " ^ " << int(mask) << " accepted";
                EXPECT_FALSE(error.message.empty());
            }
        }
    }
}

TEST(CacheFileReject, FlippedBytesNameTheRightRule) {
    const std::vector<uint8_t> bytes = encode(goldenData());
    const std::vector<RawSection> sections = splitSections(bytes);
    // Header and table bytes: checksum rule V6 (or an earlier structural rule).
    {
        std::vector<uint8_t> bad = bytes;
        bad[kCacheHeaderSize + 4] ^= 0x10;  // first table entry's flags
        CacheError error;
        EXPECT_EQ(openBytes(bad, &error), CacheFileStatus::kChecksumMismatch);
        EXPECT_EQ(error.rule, 6u);
    }
    // One byte in the middle of each section: V9 names the section.
    for (uint32_t i = 0; i < sections.size(); ++i) {
        const size_t e = kCacheHeaderSize + i * kCacheSectionEntrySize;
        std::vector<uint8_t> bad = bytes;
        bad[get<uint64_t>(bytes, e + 8) + get<uint64_t>(bytes, e + 16) / 2] ^= 0x04;
        CacheError error;
        EXPECT_EQ(openBytes(bad, &error), CacheFileStatus::kChecksumMismatch) << i;
        EXPECT_EQ(error.rule, 9u) << error.message;
    }
}

TEST(CacheFileReject, WrongMagic) {
    std::vector<uint8_t> bytes = encode(goldenData());
    bytes[1] = 'X';
    CacheError error;
    EXPECT_EQ(openBytes(bytes, &error), CacheFileStatus::kBadMagic);
    EXPECT_EQ(error.rule, 1u);
    std::vector<uint8_t> text = {'h', 'e', 'l', 'l', 'o'};
    EXPECT_EQ(openBytes(text), CacheFileStatus::kBadMagic);
    std::vector<uint8_t> interim = {'S', 'H', 'R', 'C', 'B', 'A', 'K', 'E', 0, 0, 1, 0};
    EXPECT_EQ(openBytes(interim), CacheFileStatus::kUnsupportedVersion);
}

TEST(CacheFileReject, NewerMajorIsRejectedNewerMinorRead) {
    std::vector<uint8_t> bytes = encode(goldenData());
    std::vector<uint8_t> major = bytes;
    set(major, 16, uint16_t(2));
    fixHeaderCrc(major);
    CacheError error;
    EXPECT_EQ(openBytes(major, &error), CacheFileStatus::kUnsupportedVersion);
    EXPECT_EQ(error.rule, 3u);
    std::vector<uint8_t> zero = bytes;
    set(zero, 16, uint16_t(0));
    fixHeaderCrc(zero);
    EXPECT_EQ(openBytes(zero), CacheFileStatus::kUnsupportedVersion);
    std::vector<uint8_t> minor = bytes;
    set(minor, 18, uint16_t(7));
    fixHeaderCrc(minor);
    CacheView view;
    ASSERT_EQ(openBytes(minor, &error, &view), CacheFileStatus::kOk) << error.message;
    EXPECT_EQ(view.versionMinor(), 7);
}

TEST(CacheFileReject, UnknownSections) {
    const std::vector<uint8_t> bytes = encode(goldenData());
    std::vector<RawSection> sections = splitSections(bytes);
    ASSERT_EQ(assemble(1, kCacheVersionMinor, sections), bytes);  // the test's layout is the writer's
    sections.insert(sections.begin() + 2, RawSection{cacheFourCC('X', 'T', 'R', 'A'), 0, {1, 2, 3, 4, 5}});
    CacheView view;
    CacheError error;
    // Unknown optional section (a later minor's addition): skipped.
    ASSERT_EQ(openBytes(assemble(1, 1, sections), &error, &view), CacheFileStatus::kOk) << error.message;
    EXPECT_EQ(view.voxelCount(), goldenData().voxels.size());
    EXPECT_EQ(view.sections().size(), 6u);
    EXPECT_FALSE(view.sections()[2].known);
    // Unknown REQUIRED section: rejected.
    sections[2].flags = kCacheSectionRequired;
    EXPECT_EQ(openBytes(assemble(1, 1, sections), &error), CacheFileStatus::kUnsupportedFeature);
    EXPECT_EQ(error.rule, 10u);
    // Duplicate and missing known sections.
    std::vector<RawSection> dup = splitSections(bytes);
    dup.push_back(dup[0]);
    EXPECT_EQ(openBytes(assemble(1, 0, dup), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 10u);
    std::vector<RawSection> missing = splitSections(bytes);
    missing.erase(missing.begin() + 3);  // LEVL
    EXPECT_EQ(openBytes(assemble(1, 0, missing), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 11u);
    std::vector<RawSection> no_meta = splitSections(bytes);
    no_meta.pop_back();  // META is optional
    EXPECT_EQ(openBytes(assemble(1, 0, no_meta), &error), CacheFileStatus::kOk) << error.message;
}

TEST(CacheFileReject, TrailingBytes) {
    std::vector<uint8_t> bytes = encode(goldenData());
    for (size_t extra : {1, 8, 100}) {
        std::vector<uint8_t> bad = bytes;
        bad.resize(bytes.size() + extra, 0);
        CacheError error;
        EXPECT_EQ(openBytes(bad, &error), CacheFileStatus::kTrailingBytes);
        EXPECT_EQ(error.rule, 4u);
    }
}

TEST(CacheFileReject, SemanticRulesWithValidChecksums) {
    const std::vector<uint8_t> bytes = encode(goldenData());
    auto mutate = [&](uint32_t section, size_t at, auto value) {
        std::vector<RawSection> s = splitSections(bytes);
        set(s[section].data, at, value);
        return assemble(1, 0, s);
    };
    CacheError error;
    EXPECT_EQ(openBytes(mutate(0, 0, uint32_t(16)), &error), CacheFileStatus::kUnsupportedFeature);  // 16 bits
    EXPECT_EQ(error.rule, 12u);
    EXPECT_EQ(openBytes(mutate(0, 16, uint32_t(2)), &error), CacheFileStatus::kUnsupportedFeature);  // hash id
    EXPECT_EQ(openBytes(mutate(0, 24, 1.0f), &error), CacheFileStatus::kCorrupt);  // log base 1
    EXPECT_EQ(error.rule, 13u);
    EXPECT_EQ(openBytes(mutate(0, 28, std::numeric_limits<float>::quiet_NaN()), &error), CacheFileStatus::kCorrupt);
    // Each parameter fine alone, but no level has a voxel size: 50 x 2^200 overflows float32, so
    // every voxel is 0 wide. Such a file passed validation; the message names the cause.
    EXPECT_EQ(openBytes(mutate(0, 32, 200.0f), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 13u);
    EXPECT_NE(error.message.find("voxel sizes not representable"), std::string::npos) << error.message;
    EXPECT_NE(error.message.find("level bias 200"), std::string::npos) << error.message;
    EXPECT_EQ(openBytes(mutate(0, 28, 1e-40f), &error), CacheFileStatus::kCorrupt);  // a subnormal scale
    EXPECT_NE(error.message.find("scene scale 9.99995e-41"), std::string::npos) << error.message;
    EXPECT_EQ(openBytes(mutate(0, 48, uint64_t(1) << 60), &error), CacheFileStatus::kCorrupt);  // voxel count
    EXPECT_EQ(error.rule, 14u);
    // Keys out of order.
    {
        std::vector<RawSection> s = splitSections(bytes);
        std::swap_ranges(s[1].data.begin(), s[1].data.begin() + 8, s[1].data.begin() + 8);
        EXPECT_EQ(openBytes(assemble(1, 0, s), &error), CacheFileStatus::kCorrupt);
        EXPECT_EQ(error.rule, 15u);
    }
    EXPECT_EQ(openBytes(mutate(2, 4, -1.0f), &error), CacheFileStatus::kCorrupt);  // negative radiance
    EXPECT_EQ(error.rule, 16u);
    EXPECT_EQ(openBytes(mutate(2, 12, 0.0f), &error), CacheFileStatus::kCorrupt);  // weight 0
    EXPECT_EQ(openBytes(mutate(2, 0, std::numeric_limits<float>::infinity()), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(openBytes(mutate(3, 4, uint32_t(1)), &error), CacheFileStatus::kCorrupt);  // level count wrong
    EXPECT_EQ(error.rule, 17u);
    EXPECT_EQ(openBytes(mutate(4, 0, uint32_t(1000)), &error), CacheFileStatus::kCorrupt);  // metadata count
    EXPECT_EQ(error.rule, 18u);
    EXPECT_EQ(openBytes(mutate(4, 16, uint8_t(0xFF)), &error), CacheFileStatus::kCorrupt);  // bad UTF-8
    EXPECT_EQ(error.rule, 18u);
    // Header fields under a valid checksum.
    std::vector<uint8_t> flags = bytes;
    set(flags, 24, uint32_t(1));
    fixHeaderCrc(flags);
    EXPECT_EQ(openBytes(flags, &error), CacheFileStatus::kUnsupportedFeature);
    EXPECT_EQ(error.rule, 7u);
    std::vector<uint8_t> count = bytes;
    set(count, 28, uint32_t(0));
    fixHeaderCrc(count);
    EXPECT_EQ(openBytes(count, &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 5u);
}

TEST(CacheFileReject, RadianceScaleRule19) {
    const std::vector<uint8_t> bytes = encode(goldenData11());
    const std::vector<RawSection> sections = splitSections(bytes);
    ASSERT_EQ(sections.size(), 6u);
    ASSERT_EQ(sections[5].type, kSectionRadianceScale);
    ASSERT_EQ(assemble(1, kCacheVersionMinor, sections), bytes);
    auto with = [&](auto change, uint16_t minor = 1) {
        std::vector<RawSection> s = sections;
        change(s[5]);
        return assemble(1, minor, s);
    };
    CacheError error;
    for (float bad : {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        EXPECT_EQ(openBytes(with([&](RawSection& r) { set(r.data, 0, bad); }), &error), CacheFileStatus::kCorrupt)
            << bad;
        EXPECT_EQ(error.rule, 19u) << error.message;
    }
    EXPECT_EQ(openBytes(with([](RawSection& r) { set(r.data, 4, uint32_t(1)); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 19u);
    EXPECT_EQ(openBytes(with([](RawSection& r) { r.flags = 0; }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 19u);
    EXPECT_EQ(openBytes(with([](RawSection& r) { r.data.resize(4); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 19u);
    EXPECT_EQ(openBytes(with([](RawSection& r) { r.data.resize(12, 0); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 19u);
    // A later minor may append fields; a 1.0-marked file with RSCL is read as it says.
    CacheView view;
    ASSERT_EQ(openBytes(with([](RawSection& r) { r.data.resize(12, 0); }, 2), &error, &view), CacheFileStatus::kOk)
        << error.message;
    EXPECT_EQ(view.gpuRadianceScale(), 0.25f);
    ASSERT_EQ(openBytes(assemble(1, 0, sections), &error, &view), CacheFileStatus::kOk) << error.message;
    EXPECT_EQ(view.gpuRadianceScale(), 0.25f);
    // Twice: V10.
    std::vector<RawSection> twice = sections;
    twice.push_back(sections[5]);
    EXPECT_EQ(openBytes(assemble(1, 1, twice), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 10u);
}

TEST(CacheFileReject, GridAnchorRule21) {
    const std::vector<uint8_t> bytes = encode(goldenData12());
    const std::vector<RawSection> sections = splitSections(bytes);
    ASSERT_EQ(sections.size(), 7u);
    ASSERT_EQ(sections[6].type, kSectionGridAnchor);
    ASSERT_EQ(sections[6].flags, 0u);  // optional: lookups do not need it
    ASSERT_EQ(assemble(1, kCacheVersionMinor, sections), bytes);
    auto with = [&](auto change, uint16_t minor = 2) {
        std::vector<RawSection> s = sections;
        change(s[6]);
        return assemble(1, minor, s);
    };
    CacheError error;
    for (size_t at : {size_t(0), size_t(4), size_t(8)}) {
        for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(),
                          -std::numeric_limits<float>::infinity()}) {
            EXPECT_EQ(openBytes(with([&](RawSection& r) { set(r.data, at, bad); }), &error), CacheFileStatus::kCorrupt)
                << at << " " << bad;
            EXPECT_EQ(error.rule, 21u) << error.message;
        }
    }
    EXPECT_EQ(openBytes(with([](RawSection& r) { set(r.data, 12, uint32_t(1)); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 21u);
    EXPECT_EQ(openBytes(with([](RawSection& r) { r.data.resize(12); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 21u);
    EXPECT_EQ(openBytes(with([](RawSection& r) { r.data.resize(24, 0); }), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 21u);
    // A later minor may append fields.
    CacheView view;
    ASSERT_EQ(openBytes(with([](RawSection& r) { r.data.resize(24, 0); }, 3), &error, &view), CacheFileStatus::kOk)
        << error.message;
    EXPECT_EQ(view.gridAnchor().x, 1.0e4f);
    EXPECT_EQ(view.gridAnchor().z, -3.0f);
    // Twice: V10.
    std::vector<RawSection> twice = sections;
    twice.push_back(sections[6]);
    EXPECT_EQ(openBytes(assemble(1, 2, twice), &error), CacheFileStatus::kCorrupt);
    EXPECT_EQ(error.rule, 10u);
    // The writer refuses an anchor a reader would reject; the origin writes no section.
    CacheData data = goldenData12();
    data.grid_anchor.y = std::numeric_limits<float>::infinity();
    std::vector<uint8_t> out;
    std::string message;
    EXPECT_EQ(encodeCacheFile(data, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("anchor"), std::string::npos) << message;
    EXPECT_EQ(splitSections(encode(goldenData11())).size(), 6u);
}

TEST(CacheFile, GpuRadianceScaleIsRecordedAndAppliedToGpuBuffersOnly) {
    const CacheData data = goldenData11();
    const std::vector<uint8_t> bytes = encode(data);
    CacheView view;
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    EXPECT_EQ(view.versionMinor(), kCacheVersionMinor);
    EXPECT_EQ(view.gpuRadianceScale(), 0.25f);
    const CacheVoxel& v = data.voxels[7];
    Float3 radiance{};
    ASSERT_TRUE(view.lookup(voxelCenter(v.key, data.gridParameters()),
                            normalFromBits(decodeHashGridKey(v.key).normal_bits),
                            cameraForLevel(voxelCenter(v.key, data.gridParameters()), decodeHashGridKey(v.key).level),
                            &radiance));
    EXPECT_EQ(radiance.y, v.radiance[1]);  // lookups keep the scene's units
    GpuBufferOptions options;
    options.capacity = 4096;
    GpuInsertList list;
    ASSERT_EQ(view.gpuInsertList(options, &list), CacheFileStatus::kOk);
    EXPECT_EQ(list.radiance.radiance_scale, 0.25f);
    EXPECT_EQ(halfToFloat(list.values[7].radiance[1]), halfToFloat(floatToHalf(v.radiance[1] * 0.25f)));
    options.radiance_scale = 1.0f;  // the caller's scale wins
    ASSERT_EQ(view.gpuInsertList(options, &list), CacheFileStatus::kOk);
    EXPECT_EQ(halfToFloat(list.values[7].radiance[1]), halfToFloat(floatToHalf(v.radiance[1])));
    EXPECT_EQ(view.gpuRadianceCheck().radiance_scale, 0.25f);
    EXPECT_EQ(view.gpuRadianceCheck(2.0f).radiance_scale, 2.0f);
    // Scale 1 writes no RSCL; the writer refuses scales a reader would reject.
    CacheView plain;
    const std::vector<uint8_t> plain_bytes = encode(goldenData());
    ASSERT_EQ(openBytes(plain_bytes, nullptr, &plain), CacheFileStatus::kOk);
    EXPECT_EQ(plain.sections().size(), 5u);
    EXPECT_EQ(plain.gpuRadianceScale(), 1.0f);
    for (float bad : {0.0f, -2.0f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        CacheData invalid = goldenData();
        invalid.gpu_radiance_scale = bad;
        std::vector<uint8_t> out;
        EXPECT_EQ(encodeCacheFile(invalid, &out, nullptr), CacheFileStatus::kInvalidData) << bad;
    }
    // Shards must agree on it; the merge keeps it.
    CacheData merged;
    std::string message;
    EXPECT_EQ(mergeCaches({goldenData11(), goldenData()}, {}, &merged, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("GPU radiance scale"), std::string::npos) << message;
    ASSERT_EQ(mergeCaches({goldenData11(), goldenData11()}, {}, &merged, &message), CacheFileStatus::kOk) << message;
    EXPECT_EQ(merged.gpu_radiance_scale, 0.25f);
}

TEST(CacheFile, WriterRefusesInvalidData) {
    std::vector<uint8_t> bytes;
    std::string message;
    CacheData unsorted = goldenData();
    std::swap(unsorted.voxels[0], unsorted.voxels[1]);
    EXPECT_EQ(encodeCacheFile(unsorted, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData zero = goldenData();
    zero.voxels[0].key = 0;
    EXPECT_EQ(encodeCacheFile(zero, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData nan = goldenData();
    nan.voxels[3].radiance[1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(encodeCacheFile(nan, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData dead = goldenData();
    dead.voxels[3].sample_weight = 0.0f;
    EXPECT_EQ(encodeCacheFile(dead, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData dup = goldenData();
    dup.metadata.push_back(dup.metadata[0]);
    EXPECT_EQ(encodeCacheFile(dup, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData utf = goldenData();
    utf.metadata.push_back({"bad", "\xC3"});
    EXPECT_EQ(encodeCacheFile(utf, &bytes, &message), CacheFileStatus::kInvalidData);
    CacheData grid = goldenData();
    grid.scene_scale = -1.0f;
    EXPECT_EQ(encodeCacheFile(grid, &bytes, &message), CacheFileStatus::kInvalidData);
}

TEST(CacheFile, IoErrors) {
    CacheView view;
    CacheError error;
    EXPECT_EQ(CacheView::openFile("/nonexistent/x.sharc", &view, &error), CacheFileStatus::kIoError);
    EXPECT_EQ(CacheView::openFile("/tmp", &view, &error), CacheFileStatus::kIoError);
    std::string message;
    EXPECT_EQ(writeCacheFile("/nonexistent/dir/x.sharc", goldenData(), &message), CacheFileStatus::kIoError);
}

// Issue 19: validating metadata was quadratic in the entry count (71 s for a 2.2 MB cache).
// 200,000 entries: linear takes well under a second; quadratic would take minutes.
TEST(CacheFile, ManyMetadataEntriesValidateInLinearTime) {
    CacheData data = goldenData();
    data.metadata.clear();
    for (int i = 0; i < 200000; ++i) data.metadata.emplace_back(std::string(1, 'k').append(std::to_string(i)), "v");
    const auto start = std::chrono::steady_clock::now();
    const std::vector<uint8_t> bytes = encode(data);
    CacheView view;
    CacheError error;
    ASSERT_EQ(openBytes(bytes, &error, &view), CacheFileStatus::kOk) << error.message;
    EXPECT_EQ(view.metadataCount(), 200000u);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 10.0);
    data.metadata.emplace_back("k7", "again");
    std::vector<uint8_t> refused;
    std::string message;
    EXPECT_EQ(encodeCacheFile(data, &refused, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("duplicate metadata key \"k7\""), std::string::npos) << message;
}

// Issue 19: the one atomic write every output uses never destroys the previous file or a device.
TEST(CacheFile, AtomicWriteKeepsTheOldFileOnAShortWrite) {
    const std::string path = tempPath("atomic.bin");
    const std::string old_bytes = "the previous file";
    std::string message;
    ASSERT_EQ(writeFileAtomically(path, old_bytes.data(), old_bytes.size(), &message), CacheFileStatus::kOk) << message;
    // A file size limit makes write() fail with EFBIG, as a full disk fails with ENOSPC.
    struct rlimit saved {};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
    const auto previous_handler = std::signal(SIGXFSZ, SIG_IGN);
    struct rlimit small = saved;
    small.rlim_cur = 4096;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    const std::vector<uint8_t> big(1 << 20, 7);
    const CacheFileStatus status = writeFileAtomically(path, big.data(), big.size(), &message);
    ::setrlimit(RLIMIT_FSIZE, &saved);
    std::signal(SIGXFSZ, previous_handler);
    EXPECT_EQ(status, CacheFileStatus::kIoError);
    EXPECT_NE(message.find("write failed"), std::string::npos) << message;
    const std::vector<uint8_t> after = readBytes(path);
    EXPECT_EQ(std::string(after.begin(), after.end()), old_bytes);
    EXPECT_NE(::access((path + ".tmp-" + std::to_string(::getpid())).c_str(), F_OK), 0) << "temporary left behind";
    // Devices and FIFOs are refused, not replaced.
    EXPECT_EQ(writeFileAtomically("/dev/null", "x", 1, &message), CacheFileStatus::kIoError);
    EXPECT_NE(message.find("a device"), std::string::npos) << message;
    std::remove(path.c_str());
}

// A symbolic link stays a link (its target is replaced), the target's mode is kept, and a
// temporary left by a process that no longer runs is removed.
TEST(CacheFile, AtomicWriteFollowsLinksKeepsModeAndCleansStaleTemporaries) {
    const std::string target = tempPath("linked_target.bin"), link = tempPath("link.bin");
    std::remove(target.c_str());
    std::remove(link.c_str());
    ASSERT_EQ(::symlink(target.c_str(), link.c_str()), 0);
    std::string message;
    ASSERT_EQ(writeFileAtomically(link, "one", 3, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(::chmod(target.c_str(), 0600), 0);
    const std::string stale = target + ".tmp-999999999";  // no such process (pids are < 2^22)
    std::ofstream(stale) << "left by a killed writer";
    ASSERT_EQ(writeFileAtomically(link, "two", 3, &message), CacheFileStatus::kOk) << message;
    struct stat info {};
    ASSERT_EQ(::lstat(link.c_str(), &info), 0);
    EXPECT_TRUE(S_ISLNK(info.st_mode));
    ASSERT_EQ(::stat(target.c_str(), &info), 0);
    EXPECT_EQ(info.st_mode & 0777, 0600u);
    const std::vector<uint8_t> bytes = readBytes(target);
    EXPECT_EQ(std::string(bytes.begin(), bytes.end()), "two");
    EXPECT_NE(::access(stale.c_str(), F_OK), 0) << "the stale temporary was not removed";
    std::remove(link.c_str());
    std::remove(target.c_str());
}

// ------------------------------------------------------------------------------------------------
// Runtime
// ------------------------------------------------------------------------------------------------

TEST(Runtime, LookupReturnsEachVoxelAtItsCentre) {
    const CacheData data = goldenData();
    const std::vector<uint8_t> bytes = encode(data);
    CacheView view;
    CacheError error;
    ASSERT_EQ(openBytes(bytes, &error, &view), CacheFileStatus::kOk) << error.message;
    for (const CacheVoxel& v : data.voxels) {
        const HashGridCell cell = decodeHashGridKey(v.key);
        const Float3 centre = voxelCenter(v.key, view.gridParameters());
        const Float3 camera = cameraForLevel(centre, cell.level);
        const Float3 normal = normalFromBits(cell.normal_bits);
        ASSERT_EQ(hashGridKey(centre, normal, view.gridParameters(camera)), v.key);
        Float3 r{-1, -1, -1};
        ASSERT_TRUE(view.lookup(centre, normal, camera, &r));
        EXPECT_EQ(r.x, v.radiance[0]);
        EXPECT_EQ(r.y, v.radiance[1]);
        EXPECT_EQ(r.z, v.radiance[2]);
        uint32_t level = 0;
        ASSERT_TRUE(view.lookupNearestLevel(centre, normal, camera, &r, &level));
        EXPECT_EQ(level, cell.level);
        EXPECT_EQ(r.x, v.radiance[0]);
        // Opposite normal octant: a different key, a miss unless that voxel exists too.
        const uint64_t other = packHashGridKey(cell.grid, cell.level, cell.normal_bits ^ 7u);
        EXPECT_EQ(view.lookup(centre, normalFromBits(cell.normal_bits ^ 7u), camera, &r), view.findKey(other) != view.voxelCount());
    }
    EXPECT_EQ(view.findKey(1), view.voxelCount());
}

TEST(Runtime, KeyForMatchesHashGridKey) {
    const float params[][3] = {{2.0f, 50.0f, 0.0f}, {3.0f, 50.0f, 0.0f}, {4.0f, 10.0f, 1.5f}, {1.01f, 50.0f, -5.0f}};
    std::mt19937 rng(99);
    std::uniform_real_distribution<float> small(-5.0f, 5.0f), wide(-3000.0f, 3000.0f);
    const float specials[] = {0.0f, -0.0f, 1e-4f, -1e-4f, 3.9999f, 4.0f, 1e30f, -1e30f,
                              std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
    for (const auto& q : params) {
        CacheData data;
        data.logarithm_base = q[0];
        data.scene_scale = q[1];
        data.level_bias = q[2];
        data.bake_capacity = 16;
        const std::vector<uint8_t> bytes = encode(data);
        CacheView view;
        ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
        for (int i = 0; i < 20000; ++i) {
            auto r = [&](int k) {
                if (i % 7 == 0 && k == 0) return specials[size_t(i / 7) % 10];
                return (i & 1) ? wide(rng) : small(rng);
            };
            const Float3 p{r(0), r(1), r(2)}, n{small(rng), small(rng), small(rng)}, c{r(3), r(4), r(5)};
            ASSERT_EQ(view.keyFor(p, n, c), hashGridKey(p, n, view.gridParameters(c)))
                << p.x << " " << p.y << " " << p.z << " camera " << c.x << " " << c.y << " " << c.z;
        }
        // keysFor (four lanes at a time, then a scalar tail) gives the same keys, specials too.
        for (int round = 0; round < 4; ++round) {
            const Float3 camera = round == 0 ? Float3{0, 0, 0} : Float3{small(rng), wide(rng), small(rng)};
            std::vector<Float3> positions, normals;
            for (int i = 0; i < 4001; ++i) {
                auto r = [&](int k) {
                    if (i % 5 == 0 && k == i % 3) return specials[size_t(i / 5) % 10];
                    return (i & 1) ? wide(rng) : small(rng);
                };
                positions.push_back({r(0), r(1), r(2)});
                normals.push_back(i % 11 == 0 ? Float3{specials[size_t(i) % 10], -0.001f, 0.0f}
                                              : Float3{small(rng), small(rng), small(rng)});
            }
            std::vector<uint64_t> keys(positions.size());
            view.keysFor(positions.size(), positions.data(), normals.data(), camera, keys.data());
            for (size_t i = 0; i < positions.size(); ++i) {
                ASSERT_EQ(keys[i], hashGridKey(positions[i], normals[i], view.gridParameters(camera)))
                    << i << ": " << positions[i].x << " " << positions[i].y << " " << positions[i].z;
            }
        }
        // keyFor finds the level from precomputed distance thresholds: sweep a few ULPs across
        // every level boundary within 1e6 of the camera.
        const Float3 camera{0.0f, 0.0f, 0.0f}, normal{0.0f, 1.0f, 0.0f};
        for (uint32_t level = 1; level <= 511; ++level) {
            const double boundary = std::pow(double(q[0]), double(level) - double(q[2]));
            if (boundary > 1e6) break;
            float x = float(boundary) - kHashGridPositionBias;
            for (int step = 0; step < 8; ++step) x = std::nextafter(x, 0.0f);
            for (int step = 0; step < 16; ++step, x = std::nextafter(x, INFINITY)) {
                const Float3 points[4] = {{x, 0.0f, 0.0f}, {0.0f, -x, 0.0f}, {x * 0.6f, 0.0f, x * 0.8f}, {-x, 0.0f, 0.0f}};
                const Float3 normals[4] = {normal, normal, normal, normal};
                uint64_t keys[4];
                view.keysFor(4, points, normals, camera, keys);
                for (int k = 0; k < 4; ++k) {
                    const uint64_t expected = hashGridKey(points[k], normal, view.gridParameters(camera));
                    ASSERT_EQ(view.keyFor(points[k], normal, camera), expected)
                        << "base " << q[0] << " bias " << q[2] << " level " << level << " x " << x;
                    ASSERT_EQ(keys[k], expected) << "keysFor, base " << q[0] << " level " << level << " x " << x;
                }
            }
        }
    }
}

TEST(Runtime, LookupIndexGivesTheSameAnswers) {
    const CacheData data = goldenData();
    const std::vector<uint8_t> bytes = encode(data);
    CacheView plain, indexed;
    ASSERT_EQ(openBytes(bytes, nullptr, &plain), CacheFileStatus::kOk);
    ASSERT_EQ(openBytes(bytes, nullptr, &indexed), CacheFileStatus::kOk);
    ASSERT_EQ(indexed.buildLookupIndex(), CacheFileStatus::kOk);
    EXPECT_TRUE(indexed.hasLookupIndex());
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        EXPECT_EQ(indexed.findKey(data.voxels[i].key), i);
        EXPECT_EQ(indexed.findKey(data.voxels[i].key + 1), plain.findKey(data.voxels[i].key + 1));
    }
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> coord(-30.0f, 30.0f);
    for (int i = 0; i < 5000; ++i) {
        const Float3 p{coord(rng), coord(rng), coord(rng)}, n{coord(rng), coord(rng), coord(rng)};
        Float3 a{0, 0, 0}, b{0, 0, 0};
        uint32_t la = 0, lb = 0;
        EXPECT_EQ(plain.lookupNearestLevel(p, n, {0, 0, 0}, &a, &la), indexed.lookupNearestLevel(p, n, {0, 0, 0}, &b, &lb));
        EXPECT_EQ(la, lb);
        EXPECT_EQ(a.x, b.x);
    }
    // The pipelined batch path (index built, exact lookups) agrees with single plain lookups,
    // for hits (voxel centres) and misses (random points).
    std::vector<Float3> positions, normals;
    for (const CacheVoxel& v : data.voxels) {
        const HashGridCell cell = decodeHashGridKey(v.key);
        const Float3 centre = voxelCenter(v.key, plain.gridParameters());
        positions.push_back(centre);
        normals.push_back(normalFromBits(cell.normal_bits));
    }
    for (int i = 0; i < 100; ++i) {
        positions.push_back({coord(rng), coord(rng), coord(rng)});
        normals.push_back({coord(rng), coord(rng), coord(rng)});
    }
    const Float3 camera{0.3f, -0.2f, 0.1f};
    std::vector<Float3> out(positions.size());
    std::vector<uint8_t> hit(positions.size());
    const size_t count = indexed.lookupBatch(positions.size(), positions.data(), normals.data(), camera, out.data(),
                                             hit.data());
    size_t expected = 0;
    for (size_t i = 0; i < positions.size(); ++i) {
        Float3 r{0, 0, 0};
        const bool h = plain.lookup(positions[i], normals[i], camera, &r);
        expected += h ? 1 : 0;
        EXPECT_EQ(hit[i] != 0, h) << i;
        EXPECT_EQ(out[i].x, r.x);
        EXPECT_EQ(out[i].z, r.z);
    }
    EXPECT_EQ(count, expected);
    EXPECT_GT(count, 0u);
    CacheView moved(std::move(indexed));
    EXPECT_TRUE(moved.hasLookupIndex());
    EXPECT_EQ(moved.findKey(data.voxels[3].key), 3u);
}

/// Keys k0 + i / M (mod 2^64) all have the home slot of k0 under the index multiplier M (their
/// products are k0 x M + i), so linear probing made the build quadratic: 40,000 of them took
/// 0.7 s, 160,000 13 s (a valid 3.8 MB file). The build now moves on to another multiplier.
TEST(Runtime, LookupIndexBuildIsLinearForKeysCraftedToCollide) {
    constexpr uint64_t kFirstMultiplier = 0x9E3779B97F4A7C15ull;
    uint64_t inverse = kFirstMultiplier;  // Newton's iteration for M^-1 mod 2^64
    for (int i = 0; i < 6; ++i) inverse *= 2 - kFirstMultiplier * inverse;
    ASSERT_EQ(inverse * kFirstMultiplier, 1u);
    CacheData data;
    data.bake_capacity = 1u << 22;
    for (uint64_t i = 0; data.voxels.size() < 160000; ++i) {
        const uint64_t key = 0x0123456789ABCDEFull * inverse + i * inverse;
        if ((key >> 63) != 0 || decodeHashGridKey(key).level == 0) continue;  // keys a file may hold
        CacheVoxel v;
        v.key = key;
        v.radiance[0] = v.radiance[1] = v.radiance[2] = float(i % 7);
        v.sample_weight = 1.0f;
        data.voxels.push_back(v);
    }
    sortVoxels(data.voxels);
    const std::vector<uint8_t> bytes = encode(data);
    CacheView view;
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(view.buildLookupIndex(), CacheFileStatus::kOk);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_LT(seconds, 2.0) << "the build is quadratic in colliding keys again (13 s before the fix)";
    EXPECT_TRUE(view.hasLookupIndex()) << "another multiplier spreads these keys";
    for (size_t i = 0; i < data.voxels.size(); ++i) ASSERT_EQ(view.findKey(data.voxels[i].key), i);
    EXPECT_EQ(view.findKey(data.voxels[0].key + inverse * 3 + 1), view.voxelCount()) << "an absent key";
}

/// "On failure *out is reset": the grid too. A failed reopen and a moved-from view reported the
/// previous cache's scene scale, level bias and capacity, which an engine reloading a cache could
/// take for the new one's.
TEST(Runtime, FailedOpenAndMoveLeaveNoGridBehind) {
    CacheData data = goldenData();
    data.scene_scale = 7.0f;
    data.level_bias = 2.5f;
    const std::vector<uint8_t> bytes = encode(data);
    const CacheView fresh;
    const auto expectFresh = [&](const CacheView& view, const char* what) {
        const HashGridParameters a = view.gridParameters(), b = fresh.gridParameters();
        EXPECT_FALSE(view.isOpen()) << what;
        EXPECT_EQ(a.logarithm_base, b.logarithm_base) << what;
        EXPECT_EQ(a.scene_scale, b.scene_scale) << what;
        EXPECT_EQ(a.level_bias, b.level_bias) << what;
        EXPECT_EQ(a.bucket_size, b.bucket_size) << what;
        EXPECT_EQ(view.bakeCapacity(), fresh.bakeCapacity()) << what;
        EXPECT_EQ(view.voxelCount(), 0u) << what;
    };
    CacheView view;
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    ASSERT_EQ(view.gridParameters().scene_scale, 7.0f);
    const std::vector<uint8_t> garbage(bytes.size(), 0x5A);
    EXPECT_NE(openBytes(garbage, nullptr, &view), CacheFileStatus::kOk);
    expectFresh(view, "after a failed open");
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    const CacheView moved(std::move(view));
    EXPECT_EQ(moved.gridParameters().level_bias, 2.5f);
    expectFresh(view, "moved from");  // NOLINT(bugprone-use-after-move): what a moved-from view says
}

TEST(Runtime, NearestLevelFallsBackWhenTheLevelIsMissing) {
    const CacheData data = goldenData();
    CacheView view;
    const std::vector<uint8_t> bytes = encode(data);
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    const uint32_t top = view.levels().back().level;
    const CacheVoxel& v = *std::find_if(data.voxels.begin(), data.voxels.end(), [&](const CacheVoxel& x) {
        return decodeHashGridKey(x.key).level == top;
    });
    const HashGridCell cell = decodeHashGridKey(v.key);
    const Float3 centre = voxelCenter(v.key, view.gridParameters());
    const Float3 normal = normalFromBits(cell.normal_bits);
    const Float3 far_camera = cameraForLevel(centre, top + 3);  // a level no voxel has
    Float3 r;
    EXPECT_FALSE(view.lookup(centre, normal, far_camera, &r));
    uint32_t level = 0;
    ASSERT_TRUE(view.lookupNearestLevel(centre, normal, far_camera, &r, &level));
    EXPECT_EQ(level, top);
    EXPECT_EQ(r.x, v.radiance[0]);
    // Batched lookups agree with single ones.
    std::vector<Float3> positions, normals;
    for (const CacheVoxel& x : data.voxels) {
        positions.push_back(voxelCenter(x.key, view.gridParameters()));
        normals.push_back(normalFromBits(decodeHashGridKey(x.key).normal_bits));
    }
    std::vector<Float3> out(positions.size());
    std::vector<uint8_t> hits(positions.size());
    const size_t hit_count = view.lookupBatch(positions.size(), positions.data(), normals.data(), {0, 0, 0},
                                              out.data(), hits.data(), true);
    EXPECT_EQ(hit_count, positions.size());  // nearest level always finds the voxel itself or a neighbour
    for (size_t i = 0; i < positions.size(); ++i) {
        Float3 single{0, 0, 0};
        EXPECT_EQ(view.lookupNearestLevel(positions[i], normals[i], {0, 0, 0}, &single), hits[i] != 0);
        EXPECT_EQ(single.x, out[i].x);
    }
}

TEST(Runtime, StatsAndIteration) {
    const CacheData data = goldenData();
    CacheView view;
    const std::vector<uint8_t> bytes = encode(data);
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    const CacheStats s = view.stats();
    EXPECT_EQ(s.voxels, data.voxels.size());
    EXPECT_EQ(s.levels, view.levels().size());
    EXPECT_EQ(s.radiance_min[0], 0.0f);
    EXPECT_EQ(s.weight_min, 1.0f);
    EXPECT_LE(s.bytes_per_voxel, 32.0 + 600.0 / double(data.voxels.size()));
    for (uint64_t i = 0; i < view.voxelCount(); ++i) EXPECT_EQ(view.voxel(i).key, data.voxels[i].key);
}

TEST(Runtime, GpuBuffersPlaceEveryKeyFindably) {
    const CacheData data = goldenData();
    CacheView view;
    const std::vector<uint8_t> bytes = encode(data);
    ASSERT_EQ(openBytes(bytes, nullptr, &view), CacheFileStatus::kOk);
    for (uint32_t capacity : {4096u, 64u, 40u, 16u, 5u}) {
        GpuBufferOptions options;
        options.capacity = capacity;
        options.accumulated_frame_num = 3;
        GpuBuffers buffers;
        ASSERT_EQ(view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
        ASSERT_EQ(buffers.hash_entries.size(), capacity);
        ASSERT_EQ(buffers.resolved.size(), capacity);
        EXPECT_EQ(buffers.inserted + buffers.failed_inserts, data.voxels.size());
        if (capacity >= 4096) {
            EXPECT_EQ(buffers.failed_inserts, 0u);
        }
        // The same insertion order into the CPU table gives the same slots.
        HashGridTable table;
        ASSERT_EQ(HashGridTable::create(capacity, &table), HashGridStatus::kOk);
        for (const CacheVoxel& v : data.voxels) table.insert(v.key);
        uint64_t found = 0;
        for (const CacheVoxel& v : data.voxels) {
            // HashGridTable-style find on the exported buffer.
            const uint32_t base = bucketBase(hashGridHash(v.key), capacity);
            uint32_t slot = kHashGridInvalidIndex;
            for (uint32_t p = 0; p < bucketProbeCount(capacity); ++p) {
                if (buffers.hash_entries[base + p] == v.key) {
                    slot = base + p;
                    break;
                }
            }
            const std::optional<uint32_t> cpu = table.find(v.key);
            ASSERT_EQ(cpu.has_value(), slot != kHashGridInvalidIndex);
            if (slot == kHashGridInvalidIndex) continue;
            ++found;
            EXPECT_EQ(*cpu, slot);
            const SharcPackedData& p = buffers.resolved[slot];
            for (int c = 0; c < 3; ++c) {
                EXPECT_NEAR(halfToFloat(p.radiance[c]), v.radiance[c], 1e-3f * std::max(1.0f, v.radiance[c]));
            }
            EXPECT_NEAR(halfToFloat(p.radiance[3]), v.sample_weight, 1e-3f * v.sample_weight);
            EXPECT_EQ(p.sample_data, 3u);
        }
        EXPECT_EQ(found, buffers.inserted);
        for (uint32_t i = 0; i < capacity; ++i) {
            if (buffers.hash_entries[i] == 0) {
                EXPECT_EQ(buffers.resolved[i].radiance[3], 0);
            }
        }
    }
    GpuBufferOptions zero;
    zero.capacity = 0;
    GpuBuffers buffers;
    EXPECT_EQ(view.gpuBuffers(zero, &buffers), CacheFileStatus::kInvalidArgument);
}

TEST(Runtime, HalfConversion) {
    EXPECT_EQ(floatToHalf(0.0f), 0x0000);
    EXPECT_EQ(floatToHalf(-0.0f), 0x8000);
    EXPECT_EQ(floatToHalf(1.0f), 0x3C00);
    EXPECT_EQ(floatToHalf(65504.0f), 0x7BFF);
    EXPECT_EQ(floatToHalf(65520.0f), 0x7C00);
    EXPECT_EQ(floatToHalf(1e9f), 0x7C00);
    EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -24)), 0x0001);
    EXPECT_EQ(floatToHalf(std::ldexp(1.0f, -26)), 0x0000);
    EXPECT_EQ(floatToHalf(1.0f + std::ldexp(1.0f, -11)), 0x3C00);  // tie -> even
    EXPECT_EQ(floatToHalf(1.0f + 3 * std::ldexp(1.0f, -11)), 0x3C02);
    for (uint32_t h = 0; h < 0x7C00; ++h) EXPECT_EQ(floatToHalf(halfToFloat(uint16_t(h))), h);
}

TEST(Runtime, MemoryAndMappedViewsAgree) {
    const std::string path = tempPath("mapped.sharc");
    std::string message;
    ASSERT_EQ(writeCacheFile(path, goldenData(), &message), CacheFileStatus::kOk) << message;
    CacheView a, b;
    ASSERT_EQ(CacheView::openFile(path, &a, nullptr, CacheView::FileMode::kMap), CacheFileStatus::kOk);
    ASSERT_EQ(CacheView::openFile(path, &b, nullptr, CacheView::FileMode::kRead), CacheFileStatus::kOk);
    CacheView moved(std::move(b));
    ASSERT_EQ(a.voxelCount(), moved.voxelCount());
    for (uint64_t i = 0; i < a.voxelCount(); ++i) EXPECT_EQ(a.voxel(i).key, moved.voxel(i).key);
    EXPECT_EQ(moved.metadata("iterations"), "16");
    std::remove(path.c_str());
}

TEST(RuntimeC, VoxelLocationsAreTheBakedPlacesAlsoFarFromTheOrigin) {
    // A 2 m patch 10 km out in 4 cm voxels (level 1 at scene scale 50): grid coordinates near
    // 250 000 that the keys keep only modulo 2^17. Located near the file's anchor, each voxel's
    // centre is where its key was made, and looking up that centre finds the voxel.
    CacheData data = goldenData();
    const Float3 site{10000.3f, 2.0f, -3.0f};
    data.grid_anchor = site;
    data.voxels.clear();
    std::map<uint64_t, CacheVoxel> by_key;
    std::map<uint64_t, Float3> baked_at;
    for (int i = 0; i < 64; ++i) {
        const Float3 p{site.x + 0.031f * float(i % 8), site.y - 0.029f * float(i / 8), site.z + 0.017f * float(i)};
        const Float3 n = normalFromBits(uint32_t(i) % 8);
        CacheVoxel v;
        v.key = hashGridKeyAtLevel(p, n, 1 + uint32_t(i) % 4, data.gridParameters());
        v.radiance[0] = float(i);
        v.radiance[1] = 1.0f;
        v.radiance[2] = 2.0f;
        v.sample_weight = 4.0f;
        by_key.emplace(v.key, v);
        baked_at.emplace(v.key, p);
    }
    for (const auto& kv : by_key) data.voxels.push_back(kv.second);
    const std::vector<uint8_t> bytes = encode(data);
    sharcbake_cache* cache = nullptr;
    ASSERT_EQ(sharcbake_cache_open_memory(bytes.data(), bytes.size(), &cache, nullptr, nullptr, 0), SHARCBAKE_OK);
    float anchor[3] = {0, 0, 0};
    sharcbake_cache_grid_anchor(cache, anchor);
    EXPECT_EQ(anchor[0], site.x);
    EXPECT_EQ(anchor[2], site.z);
    for (uint64_t i = 0; i < data.voxels.size(); ++i) {
        const CacheVoxel& v = data.voxels[i];
        float c[3], size = 0.0f;
        uint32_t level = 0, normal_bits = 9;
        ASSERT_EQ(sharcbake_cache_voxel_location(cache, i, c, &size, &level, &normal_bits), 1);
        EXPECT_EQ(level, decodeHashGridKey(v.key).level);
        EXPECT_EQ(normal_bits, decodeHashGridKey(v.key).normal_bits);
        EXPECT_EQ(size, voxelSize(level, data.gridParameters()));
        const Float3 p = baked_at.at(v.key);
        // The centre is within half a voxel (plus the SDK's 1e-4 bias and a float step) per axis.
        const float reach = 0.5f * size + 2e-3f;
        EXPECT_LE(std::fabs(c[0] - p.x), reach) << i;
        EXPECT_LE(std::fabs(c[1] - p.y), reach) << i;
        EXPECT_LE(std::fabs(c[2] - p.z), reach) << i;
        // Where the cell index passed 2^16 (levels 1 and 2 here), voxelCenter() without the anchor
        // puts the voxel thousands of metres away: the test can tell.
        if (site.x / size >= 65536.0f) {
            EXPECT_GT(std::fabs(voxelCenter(v.key, data.gridParameters()).x - p.x), 1000.0f) << i;
        }
        const Float3 camera = cameraForLevel(Float3{c[0], c[1], c[2]}, level);
        const Float3 n = normalFromBits(normal_bits);
        const float cam[3] = {camera.x, camera.y, camera.z}, nrm[3] = {n.x, n.y, n.z};
        float r[3] = {-1, -1, -1};
        ASSERT_EQ(sharcbake_cache_lookup(cache, c, nrm, cam, r), 1) << i;
        EXPECT_EQ(r[0], v.radiance[0]);
    }
    EXPECT_EQ(sharcbake_cache_voxel_location(cache, data.voxels.size(), nullptr, nullptr, nullptr, nullptr), 0);
    sharcbake_cache_close(cache);

    // Without an anchor the locations are voxelCenter()'s, and the anchor reads as the origin.
    const CacheData golden = goldenData();
    const std::vector<uint8_t> golden_bytes = encode(golden);
    ASSERT_EQ(sharcbake_cache_open_memory(golden_bytes.data(), golden_bytes.size(), &cache, nullptr, nullptr, 0),
              SHARCBAKE_OK);
    sharcbake_cache_grid_anchor(cache, anchor);
    EXPECT_EQ(anchor[0], 0.0f);
    for (uint64_t i = 0; i < golden.voxels.size(); ++i) {
        float c[3];
        ASSERT_EQ(sharcbake_cache_voxel_location(cache, i, c, nullptr, nullptr, nullptr), 1);
        const Float3 expected = voxelCenter(golden.voxels[i].key, golden.gridParameters());
        EXPECT_EQ(c[0], expected.x);
        EXPECT_EQ(c[1], expected.y);
        EXPECT_EQ(c[2], expected.z);
    }
    sharcbake_cache_close(cache);
}

TEST(RuntimeC, OpenLookupGpuBuffers) {
    const CacheData data = goldenData();
    const std::vector<uint8_t> bytes = encode(data);
    sharcbake_cache* cache = nullptr;
    char message[256];
    uint32_t rule = 99;
    ASSERT_EQ(sharcbake_cache_open_memory(bytes.data(), bytes.size(), &cache, &rule, message, sizeof message),
              SHARCBAKE_OK);
    EXPECT_EQ(rule, 0u);
    EXPECT_EQ(sharcbake_cache_voxel_count(cache), data.voxels.size());
    const CacheVoxel& v = data.voxels[5];
    const HashGridCell cell = decodeHashGridKey(v.key);
    HashGridParameters params = data.gridParameters();
    const Float3 c = voxelCenter(v.key, params);
    const Float3 cam = cameraForLevel(c, cell.level);
    const Float3 n = normalFromBits(cell.normal_bits);
    const float pos[3] = {c.x, c.y, c.z}, nrm[3] = {n.x, n.y, n.z}, camera[3] = {cam.x, cam.y, cam.z};
    float r[3];
    ASSERT_EQ(sharcbake_cache_lookup(cache, pos, nrm, camera, r), 1);
    EXPECT_EQ(r[0], v.radiance[0]);
    // Indexed, every voxel answers as before, singly and in a batch; a miss stays a miss.
    std::vector<float> positions, normals;
    for (const CacheVoxel& voxel : data.voxels) {
        const HashGridCell voxel_cell = decodeHashGridKey(voxel.key);
        const Float3 centre = voxelCenter(voxel.key, params);
        const Float3 voxel_normal = normalFromBits(voxel_cell.normal_bits);
        positions.insert(positions.end(), {centre.x, centre.y, centre.z});
        normals.insert(normals.end(), {voxel_normal.x, voxel_normal.y, voxel_normal.z});
    }
    const float far_camera[3] = {1000.0f, 0.0f, 0.0f};
    std::vector<float> unindexed(positions.size()), indexed(positions.size());
    std::vector<uint8_t> unindexed_hits(data.voxels.size()), indexed_hits(data.voxels.size());
    const size_t hits = sharcbake_cache_lookup_batch(cache, data.voxels.size(), positions.data(), normals.data(),
                                                     far_camera, unindexed.data(), unindexed_hits.data(), 1);
    EXPECT_EQ(hits, data.voxels.size());  // the nearest level answers each
    ASSERT_EQ(sharcbake_cache_build_lookup_index(cache), SHARCBAKE_OK);
    EXPECT_EQ(sharcbake_cache_build_lookup_index(nullptr), SHARCBAKE_INVALID_ARGUMENT);
    r[0] = -1.0f;
    ASSERT_EQ(sharcbake_cache_lookup(cache, pos, nrm, camera, r), 1);
    EXPECT_EQ(r[0], v.radiance[0]);
    EXPECT_EQ(sharcbake_cache_lookup(cache, pos, nrm, far_camera, r), 0);
    EXPECT_EQ(sharcbake_cache_lookup_batch(cache, data.voxels.size(), positions.data(), normals.data(), far_camera,
                                           indexed.data(), indexed_hits.data(), 1),
              hits);
    EXPECT_EQ(indexed, unindexed);
    EXPECT_EQ(indexed_hits, unindexed_hits);
    char value[32];
    EXPECT_EQ(sharcbake_cache_metadata(cache, "seed", value, sizeof value), 1);
    EXPECT_STREQ(value, "7");
    std::vector<uint64_t> keys(256);
    std::vector<sharcbake_packed_data> resolved(256);
    uint64_t failed = 99;
    EXPECT_EQ(sharcbake_cache_gpu_buffers(cache, 256, 1, keys.data(), resolved.data(), &failed), SHARCBAKE_OK);
    EXPECT_EQ(failed, 0u);
    sharcbake_cache_close(cache);

    std::vector<uint8_t> bad = bytes;
    bad[100] ^= 1;
    cache = reinterpret_cast<sharcbake_cache*>(1);
    EXPECT_EQ(sharcbake_cache_open_memory(bad.data(), bad.size(), &cache, &rule, message, sizeof message),
              SHARCBAKE_CHECKSUM_MISMATCH);
    EXPECT_EQ(cache, nullptr);
    EXPECT_EQ(rule, 6u);
    EXPECT_EQ(std::string(message).substr(0, 3), "V6:");
    EXPECT_EQ(sharcbake_cache_open_file("/nonexistent.sharc", 0, &cache, &rule, message, sizeof message),
              SHARCBAKE_IO_ERROR);
    // Invalid arguments set what the header promises too: *out NULL, rule 0, a message.
    cache = reinterpret_cast<sharcbake_cache*>(1);
    rule = 99;
    std::snprintf(message, sizeof message, "SENTINEL");
    EXPECT_EQ(sharcbake_cache_open_file(nullptr, 0, &cache, &rule, message, sizeof message),
              SHARCBAKE_INVALID_ARGUMENT);
    EXPECT_EQ(cache, nullptr);
    EXPECT_EQ(rule, 0u);
    EXPECT_STREQ(message, "path is NULL");
    rule = 99;
    EXPECT_EQ(sharcbake_cache_open_memory(bytes.data(), bytes.size(), nullptr, &rule, message, sizeof message),
              SHARCBAKE_INVALID_ARGUMENT);
    EXPECT_EQ(rule, 0u);
    EXPECT_STREQ(message, "out is NULL");
}

}  // namespace
}  // namespace sharcbake
