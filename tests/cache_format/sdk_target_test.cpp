// SPDX-License-Identifier: Apache-2.0
// GPU buffers per SHaRC SDK release (SPEC.md §G): every target's buffers are found by an emulation
// of that release's query, insert lists by an emulation of its insert, baked voxels survive an
// emulation of its Resolve for exactly the frames stated, refused build options say why, and the
// fp16 conversion reports what it clips.
//
// The emulations below are written from the SDK's description (SPEC §G, docs/engine_guide.md),
// not from the library: their own Jenkins hash, key packing, bucket rules and scans. Only the
// level and the grid cell of a point come from the library (gridCell), which the hash-grid
// vectors check against the SDK's own code and which no release changes.
#include "sharcbake/sdk_target.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/cache_merge.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime.h"
#include "sharcbake/runtime_c.h"

#include "synthetic_cache.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

// ------------------------------------------------------------------------------------------------
// Emulation of the SDK, one release family at a time (written from the description)
// ------------------------------------------------------------------------------------------------

struct Release {
    const char* name;
    SharcSdkTarget target;   ///< the library's name for it (the emulation does not use it)
    uint32_t level_bits;     ///< 10 up to 1.6.x, 9 from 1.7.2
    bool reduced_modulo;     ///< 1.8.3+: base = hash % (N - 15); before: min(hash % N, N - 16)
    uint32_t stop_at_empty;  ///< lookups give up at this empty slot (1.7.2+: the 4th), 0 = never
};

const Release kReleases[] = {
    {"1.6.3", SharcSdkTarget::kSdk1_6, 10, false, 0},
    {"1.7.2", SharcSdkTarget::kSdk1_7, 9, false, 4},
    {"1.8.3", SharcSdkTarget::kSdk1_8_3, 9, true, 4},
};

uint32_t jenkins(uint32_t a) {  // burtleburtle.net's 32-bit integer hash, as the SDK describes it
    a = (a + 0x7ed55d16u) + (a << 12);
    a = (a ^ 0xc761c23cu) ^ (a >> 19);
    a = (a + 0x165667b1u) + (a << 5);
    a = (a + 0xd3a2646cu) ^ (a << 9);
    a = (a + 0xfd7046c5u) + (a << 3);
    a = (a ^ 0xb55a4f09u) ^ (a >> 16);
    return a;
}

uint32_t hash32(uint64_t key) { return jenkins(uint32_t(key)) ^ jenkins(uint32_t(key >> 32)); }

/// The release's key: 17 bits per coordinate, then the level, then three normal sign bits.
uint64_t releaseKey(const Release& r, const Float3& p, const Float3& n, const Float3& camera, HashGridParameters grid) {
    grid.camera_position = camera;
    const HashGridCell cell = gridCell(p, grid);  // level and cell: the library's, checked by vectors
    const uint64_t mask17 = 0x1FFFF;
    const uint64_t normal_bits = (n.x + 1e-3f >= 0.0f ? 0u : 1u) | (n.y + 1e-3f >= 0.0f ? 0u : 2u) |
                                 (n.z + 1e-3f >= 0.0f ? 0u : 4u);
    return (uint64_t(uint32_t(cell.grid.x)) & mask17) | (uint64_t(uint32_t(cell.grid.y)) & mask17) << 17 |
           (uint64_t(uint32_t(cell.grid.z)) & mask17) << 34 | uint64_t(cell.level) << 51 |
           normal_bits << (51 + r.level_bits);
}

uint32_t releaseBase(const Release& r, uint64_t key, uint32_t capacity) {
    const uint32_t h = hash32(key);
    if (r.reduced_modulo) return h % (capacity - 15);
    return std::min(h % capacity, capacity - 16);
}

constexpr uint32_t kMiss = 0xFFFFFFFFu;

/// The release's lookup: the first slot of the bucket holding the key.
uint32_t releaseFind(const Release& r, const std::vector<uint64_t>& table, uint64_t key) {
    const uint32_t base = releaseBase(r, key, uint32_t(table.size()));
    uint32_t empty = 0;
    for (uint32_t k = 0; k < 16; ++k) {
        if (table[base + k] == key) return base + k;
        if (table[base + k] == 0 && ++empty == r.stop_at_empty) return kMiss;
    }
    return kMiss;
}

/// The release's insert (what the engine's compute pass runs): claim the first empty slot, or
/// stop at the key itself.
uint32_t releaseInsert(const Release& r, std::vector<uint64_t>& table, uint64_t key) {
    const uint32_t base = releaseBase(r, key, uint32_t(table.size()));
    for (uint32_t k = 0; k < 16; ++k) {
        if (table[base + k] == 0 || table[base + k] == key) {
            table[base + k] = key;
            return base + k;
        }
    }
    return kMiss;
}

/// The release's query: a usable entry has a sample count > 0.
bool releaseQuery(const Release& r, const std::vector<uint64_t>& table, const std::vector<SharcPackedData>& resolved,
                  uint64_t key, Float3* radiance) {
    const uint32_t slot = releaseFind(r, table, key);
    if (slot == kMiss || !(halfToFloat(resolved[slot].radiance[3]) > 0.0f)) return false;
    *radiance = Float3{halfToFloat(resolved[slot].radiance[0]), halfToFloat(resolved[slot].radiance[1]),
                       halfToFloat(resolved[slot].radiance[2])};
    return true;
}

/// This frame's deposits into one entry: `samples` samples of mean `value`.
struct Deposit {
    uint32_t samples = 0;
    float value = 0.0f;
};

/// One Resolve pass over the table, per the description: staleness, eviction, the no-sample add
/// of 1 + 2^16 to the 32-bit counter word, the frame cap with exponential forgetting, the blend.
/// (Recovery probe, adjacent levels and fade acceleration are off: a static camera, no holes.)
void releaseResolve(std::vector<uint64_t>& table, std::vector<SharcPackedData>& resolved,
                    const std::vector<Deposit>& deposits, uint32_t accumulation_frame_num,
                    uint32_t stale_frame_num_max) {
    for (size_t i = 0; i < table.size(); ++i) {
        if (table[i] == 0) continue;
        SharcPackedData& e = resolved[i];
        const uint32_t n = deposits.empty() ? 0 : deposits[i].samples;
        uint32_t frames = (e.sample_data & 0xFFFFu) + 1;
        const uint32_t stale = n != 0 ? 0 : (e.sample_data >> 16) + 1;
        if (stale >= std::clamp(stale_frame_num_max, 8u, 1024u)) {
            table[i] = 0;
            e = SharcPackedData{{0, 0, 0, 0}, 0, 0};
            continue;
        }
        if (n == 0) {
            e.sample_data += 0x10001u;  // one 32-bit add: frames + 1, stale + 1
            continue;
        }
        float count = halfToFloat(e.radiance[3]);
        const float cap = float(std::clamp(accumulation_frame_num, 1u, 1024u));
        if (float(frames) > cap) {
            count *= cap / float(frames);
            frames = uint32_t(cap);
        }
        for (int c = 0; c < 3; ++c) {
            const float mean = (count * halfToFloat(e.radiance[c]) + float(n) * deposits[i].value) / (count + float(n));
            e.radiance[c] = floatToHalf(std::min(mean, 65504.0f));
        }
        e.radiance[3] = floatToHalf(std::min(count + float(n), 65504.0f));
        e.sample_data = frames | stale << 16;
    }
}

// ------------------------------------------------------------------------------------------------
// Test caches
// ------------------------------------------------------------------------------------------------

/// A cache of `live` voxels at random points seen from the origin, each with its own radiance;
/// `points`/`normals` hold a point and normal of every voxel, in the file's (key) order.
struct TestCache {
    CacheData data;
    std::vector<uint8_t> bytes;
    CacheView view;
    std::vector<Float3> points, normals;
};

/// Encodes `data` into `bytes` and opens `view` on them (ASSERT_NO_FATAL_FAILURE at the call).
void encodeAndOpen(const CacheData& data, std::vector<uint8_t>* bytes, CacheView* view) {
    std::string message;
    ASSERT_EQ(encodeCacheFile(data, bytes, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(CacheView::openMemory(bytes->data(), bytes->size(), view, nullptr), CacheFileStatus::kOk);
}

void makeTestCache(size_t live, TestCache* out, uint32_t seed = 18) {
    std::mt19937 random(seed);
    std::vector<Float3> points, normals;
    CacheData data = makeSyntheticCache(live, 1u << 16, random, points, normals);
    std::map<uint64_t, size_t> drawn;
    const HashGridParameters grid = data.gridParameters();
    for (size_t i = 0; i < points.size(); ++i) drawn[hashGridKey(points[i], normals[i], grid)] = i;
    out->points.clear();
    out->normals.clear();
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        CacheVoxel& v = data.voxels[i];
        const size_t at = drawn.at(v.key);
        out->points.push_back(points[at]);
        out->normals.push_back(normals[at]);
        v.radiance[0] = 0.25f + 0.001f * float(i);
        v.radiance[1] = 3.0f;
        v.radiance[2] = float(i % 7);
        v.sample_weight = 8.0f + float(i % 5);
    }
    out->data = std::move(data);
    encodeAndOpen(out->data, &out->bytes, &out->view);
}

void expectHalfNear(float got, float want) { EXPECT_NEAR(got, want, std::max(want, 1.0f) * 1e-3f); }

// ------------------------------------------------------------------------------------------------
// Targets, keys and buckets
// ------------------------------------------------------------------------------------------------

TEST(SdkTarget, DefaultIsTheLayoutBuffersAlwaysHad) {
    EXPECT_EQ(GpuBufferOptions{}.sdk_target, SharcSdkTarget::kSdk1_7);
    EXPECT_EQ(kSharcSdkTargetDefault, SharcSdkTarget::kSdk1_7);
    // The 1.7 target places keys exactly as the library's own table does (what gpuBuffers did
    // before targets existed).
    TestCache cache;
    makeTestCache(3000, &cache);
    for (uint32_t capacity : {4096u, 10007u, 1u << 16}) {
        GpuBufferOptions options;
        options.capacity = capacity;
        GpuBuffers buffers;
        ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
        HashGridTable table;
        ASSERT_EQ(HashGridTable::create(capacity, &table), HashGridStatus::kOk);
        for (const CacheVoxel& v : cache.data.voxels) table.insert(v.key);
        for (uint32_t i = 0; i < capacity; ++i) EXPECT_EQ(buffers.hash_entries[i], table.keyAt(i)) << i;
    }
}

TEST(SdkTarget, KeyLayoutsMoveOnlyLevelAndNormalBits) {
    // SPEC §H.9 vector 15: level 1, all normal bits set.
    EXPECT_EQ(sharcSdkKey(0x700800300018000Cull, SharcSdkTarget::kSdk1_7), 0x700800300018000Cull);
    EXPECT_EQ(sharcSdkKey(0x700800300018000Cull, SharcSdkTarget::kSdk1_8_3), 0x700800300018000Cull);
    EXPECT_EQ(sharcSdkKey(0x700800300018000Cull, SharcSdkTarget::kSdk1_6), 0xE00800300018000Cull);
    // Vector 4: level 9, normal x negative.
    EXPECT_EQ(sharcSdkKey(0x1048000000000061ull, SharcSdkTarget::kSdk1_6), 0x2048000000000061ull);
    // Every key of a cache, against the emulation's packing of the voxel's point.
    TestCache cache;
    makeTestCache(2000, &cache);
    const HashGridParameters grid = cache.data.gridParameters();
    for (const Release& r : kReleases) {
        for (size_t i = 0; i < cache.data.voxels.size(); ++i) {
            ASSERT_EQ(sharcSdkKey(cache.data.voxels[i].key, r.target),
                      releaseKey(r, cache.points[i], cache.normals[i], {0, 0, 0}, grid))
                << r.name << " voxel " << i;
        }
    }
}

TEST(SdkTarget, BucketBasesFollowEachReleasesRule) {
    std::mt19937 random(7);
    for (uint32_t capacity : {16u, 17u, 1000u, 4096u, 10007u, 1u << 22}) {
        for (int i = 0; i < 2000; ++i) {
            const uint64_t key = (uint64_t(random()) << 32 | random()) | 1ull << 51;
            for (const Release& r : kReleases) {
                const uint32_t base = sharcSdkBucketBase(hashGridHash(key), capacity, r.target);
                ASSERT_EQ(base, releaseBase(r, key, capacity)) << r.name << " N = " << capacity;
                ASSERT_LE(base + 16, capacity);
            }
        }
    }
    EXPECT_EQ(sharcSdkBucketBase(123u, 15u, SharcSdkTarget::kSdk1_8_3), kHashGridInvalidIndex);
    EXPECT_EQ(sharcSdkBucketBase(123u, 0u, SharcSdkTarget::kSdk1_7), kHashGridInvalidIndex);
    EXPECT_EQ(sharcSdkBucketBase(123u, 5u, SharcSdkTarget::kSdk1_7), 0u);  // the library's N < 16 convention
}

TEST(SdkTarget, ReleaseNamesMapToTargets) {
    SharcSdkTarget t{};
    std::string message;
    const auto target = [&](const std::string& release) {
        t = SharcSdkTarget(0);
        return sharcSdkTargetForRelease(release, &t, &message);
    };
    EXPECT_EQ(target("1.6.3"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_6);
    EXPECT_EQ(target("1.6.5"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_6);
    EXPECT_EQ(target("1.7.2"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_7);
    EXPECT_TRUE(message.empty()) << message;
    // 1.7.0 and 1.7.1 get 1.7.2's layout, which was verified; they were not, and the note says so.
    for (const char* early : {"1.7.0", "1.7.1", "1.7"}) {
        EXPECT_EQ(target(early), CacheFileStatus::kOk) << early;
        EXPECT_EQ(t, SharcSdkTarget::kSdk1_7) << early;
        EXPECT_NE(message.find("assumed"), std::string::npos) << early << ": " << message;
    }
    EXPECT_EQ(target("v1.8.0.0"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_7);
    EXPECT_EQ(target("1.8.2"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_7);
    EXPECT_NE(message.find("not verified"), std::string::npos) << message;
    EXPECT_EQ(target("1.8.3"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_8_3);
    EXPECT_NE(message.find("unverified"), std::string::npos) << message;
    EXPECT_EQ(target("1.8.4"), CacheFileStatus::kOk);
    EXPECT_EQ(t, SharcSdkTarget::kSdk1_8_3);
    for (const char* old : {"1.6.2", "1.6.0", "1.5.1", "1.4.3", "1.0"}) {
        EXPECT_EQ(target(old), CacheFileStatus::kUnsupportedFeature) << old;
        EXPECT_NE(message.find("layout"), std::string::npos) << message;
    }
    EXPECT_EQ(target("1.9.0"), CacheFileStatus::kUnsupportedFeature);
    EXPECT_NE(message.find("identifySharcSdkTarget"), std::string::npos) << message;
    for (const char* bad : {"", "1", "1.8.", "1..8", "x1.8", "1.8.2.0.1", "1.8.2b"}) {
        EXPECT_EQ(target(bad), CacheFileStatus::kInvalidArgument) << bad;
    }
}

// ------------------------------------------------------------------------------------------------
// Buffers and insert lists, found by each release's query
// ------------------------------------------------------------------------------------------------

TEST(SdkTarget, BuffersAreFoundByTheirReleasesQuery) {
    TestCache cache;
    makeTestCache(4236, &cache);
    const HashGridParameters grid = cache.data.gridParameters();
    for (const Release& r : kReleases) {
        for (uint32_t capacity : {1u << 13, 10007u, 1u << 16}) {
            GpuBufferOptions options;
            options.capacity = capacity;
            options.sdk_target = r.target;
            GpuBuffers buffers;
            ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
            EXPECT_EQ(buffers.sdk_target, r.target);
            uint64_t hits = 0;
            for (size_t i = 0; i < cache.data.voxels.size(); ++i) {
                const uint64_t key = releaseKey(r, cache.points[i], cache.normals[i], {0, 0, 0}, grid);
                Float3 radiance{};
                if (!releaseQuery(r, buffers.hash_entries, buffers.resolved, key, &radiance)) continue;
                ++hits;
                const CacheVoxel& v = cache.data.voxels[i];
                expectHalfNear(radiance.x, v.radiance[0]);
                expectHalfNear(radiance.y, v.radiance[1]);
                expectHalfNear(radiance.z, v.radiance[2]);
            }
            EXPECT_EQ(hits, buffers.inserted) << r.name << " N = " << capacity;
            EXPECT_EQ(buffers.inserted + buffers.failed_inserts, cache.data.voxels.size());
            if (capacity >= (1u << 16)) {  // 6% load; near 40% (10007 slots) a bucket may be full
                EXPECT_EQ(buffers.failed_inserts, 0u) << r.name << " N = " << capacity;
            }
        }
    }
}

TEST(SdkTarget, BuffersForOneReleaseAreNotFoundByAnother) {
    // Why the target matters: keys and hashes can agree and the lookups still miss. (A voxel
    // whose normal has no negative component has the same key in the 1.6 and 1.7 layouts, and so
    // is found across them when the bucket rule agrees: those are left out of the count.)
    TestCache cache;
    makeTestCache(4236, &cache);
    const HashGridParameters grid = cache.data.gridParameters();
    const uint32_t capacity = 1u << 16;
    for (const Release& built : kReleases) {
        GpuBufferOptions options;
        options.capacity = capacity;
        options.sdk_target = built.target;
        GpuBuffers buffers;
        ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
        for (const Release& engine : kReleases) {
            if (engine.target == built.target) continue;
            uint64_t hits = 0, counted = 0;
            for (size_t i = 0; i < cache.data.voxels.size(); ++i) {
                if (built.level_bits != engine.level_bits && normalBits(cache.normals[i]) == 0) continue;
                ++counted;
                Float3 radiance{};
                const uint64_t key = releaseKey(engine, cache.points[i], cache.normals[i], {0, 0, 0}, grid);
                hits += releaseQuery(engine, buffers.hash_entries, buffers.resolved, key, &radiance) ? 1 : 0;
            }
            EXPECT_GT(counted, cache.data.voxels.size() * 3 / 4);
            EXPECT_LT(hits, counted / 50) << "built for " << built.name << ", read by " << engine.name;
        }
    }
}

TEST(SdkTarget, InsertListsAreFoundAfterTheEnginesOwnInsert) {
    // The engine's compute pass: one thread per entry in any order, its SDK's insert, then the
    // value at the slot it got; here into a table that live entries already half fill.
    TestCache cache;
    makeTestCache(3000, &cache);
    const HashGridParameters grid = cache.data.gridParameters();
    std::mt19937 random(3);
    for (const Release& r : kReleases) {
        GpuBufferOptions options;
        options.sdk_target = r.target;
        options.capacity = 0;  // ignored by insert lists
        GpuInsertList list;
        ASSERT_EQ(cache.view.gpuInsertList(options, &list), CacheFileStatus::kOk);
        ASSERT_EQ(list.keys.size(), cache.data.voxels.size());
        ASSERT_EQ(list.values.size(), cache.data.voxels.size());
        const uint32_t capacity = 12289;
        std::vector<uint64_t> table(capacity, 0);
        std::vector<SharcPackedData> resolved(capacity, SharcPackedData{{0, 0, 0, 0}, 0, 0});
        for (int live = 0; live < 3000; ++live) {
            const uint64_t key = ((uint64_t(random()) << 32 | random()) & ~(0x3FFull << 51)) | 3ull << 51;
            (void)releaseInsert(r, table, key);
        }
        std::vector<size_t> order(list.keys.size());
        for (size_t i = 0; i < order.size(); ++i) order[i] = i;
        std::shuffle(order.begin(), order.end(), random);
        uint64_t failed = 0;
        for (size_t i : order) {
            const uint32_t slot = releaseInsert(r, table, list.keys[i]);
            if (slot == kMiss) {
                ++failed;
                continue;
            }
            resolved[slot] = list.values[i];
        }
        uint64_t hits = 0;
        for (size_t i = 0; i < cache.data.voxels.size(); ++i) {
            const uint64_t key = releaseKey(r, cache.points[i], cache.normals[i], {0, 0, 0}, grid);
            ASSERT_EQ(key, list.keys[i]);
            Float3 radiance{};
            if (!releaseQuery(r, table, resolved, key, &radiance)) continue;
            ++hits;
            expectHalfNear(radiance.x, cache.data.voxels[i].radiance[0]);
        }
        EXPECT_EQ(hits + failed, cache.data.voxels.size()) << r.name;
        EXPECT_LT(failed, cache.data.voxels.size() / 100) << r.name;
    }
}

TEST(SdkTarget, CapacityBelowTheRulesMinimumIsRefused) {
    TestCache cache;
    makeTestCache(10, &cache);
    GpuBufferOptions options;
    options.capacity = 15;
    options.sdk_target = SharcSdkTarget::kSdk1_8_3;
    GpuBuffers buffers;
    CacheError error;
    EXPECT_EQ(cache.view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kInvalidArgument);
    EXPECT_NE(error.message.find("16"), std::string::npos) << error.message;
    options.capacity = 16;
    EXPECT_EQ(cache.view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kOk);
}

/// An sdk_target that is none of the enumerators is the caller's mistake in both APIs (C++ said
/// kUnsupportedFeature, C SHARCBAKE_INVALID_ARGUMENT).
TEST(SdkTarget, UnknownTargetIsAnInvalidArgument) {
    TestCache cache;
    makeTestCache(10, &cache);
    for (const uint32_t unknown : {0u, 4u, 99u}) {
        GpuBufferOptions options;
        options.sdk_target = SharcSdkTarget(unknown);
        GpuBuffers buffers;
        GpuInsertList list;
        CacheError error;
        EXPECT_EQ(cache.view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kInvalidArgument) << unknown;
        EXPECT_NE(error.message.find("unknown sdk_target " + std::to_string(unknown)), std::string::npos)
            << error.message;
        EXPECT_EQ(cache.view.gpuInsertList(options, &list, &error), CacheFileStatus::kInvalidArgument) << unknown;
        EXPECT_NE(error.message.find("unknown sdk_target"), std::string::npos) << error.message;
    }
}

// ------------------------------------------------------------------------------------------------
// Identifying the engine's release
// ------------------------------------------------------------------------------------------------

/// What an engine running `r` would report for 16 points (its key, and its insert's slot in an
/// empty table). `compact` emulates a 32-bit-key build (x, y, z 8 bits, level 5, normals 3).
std::vector<SharcSdkObservation> observe(const Release& r, const HashGridParameters& grid, bool compact = false,
                                         bool on_a_floor = false) {
    std::mt19937 random(11);
    std::uniform_real_distribution<float> coordinate(-30.0f, 30.0f);
    std::vector<uint64_t> table(grid.capacity, 0);
    std::vector<SharcSdkObservation> out;
    for (int i = 0; i < 16; ++i) {
        SharcSdkObservation o;
        o.position = Float3{coordinate(random), coordinate(random), coordinate(random)};
        o.normal = Float3{coordinate(random), coordinate(random), coordinate(random)};
        if (on_a_floor) o.normal = Float3{0.0f, 1.0f, 0.0f};
        o.camera = Float3{coordinate(random) * 0.1f, 1.0f, 0.0f};
        o.key = releaseKey(r, o.position, o.normal, o.camera, grid);
        if (compact) {
            HashGridParameters g = grid;
            g.camera_position = o.camera;
            const HashGridCell cell = gridCell(o.position, g);
            o.key = (uint32_t(cell.grid.x) & 0xFFu) | (uint32_t(cell.grid.y) & 0xFFu) << 8 |
                    (uint32_t(cell.grid.z) & 0xFFu) << 16 | (cell.level & 31u) << 24 | normalBits(o.normal) << 29;
        }
        o.slot = releaseInsert(r, table, o.key);
        out.push_back(o);
    }
    return out;
}

TEST(SdkTarget, IdentifiesTheReleaseFromTheEnginesObservations) {
    HashGridParameters grid;
    grid.capacity = 100003;
    for (const Release& r : kReleases) {
        const std::vector<SharcSdkObservation> seen = observe(r, grid);
        SharcSdkTarget target{};
        std::string message;
        ASSERT_EQ(identifySharcSdkTarget(grid, seen.data(), seen.size(), &target, &message), CacheFileStatus::kOk)
            << r.name << ": " << message;
        EXPECT_EQ(target, r.target) << r.name;
    }
    SharcSdkTarget target{};
    std::string message;
    const std::vector<SharcSdkObservation> compact = observe(kReleases[1], grid, true);
    EXPECT_EQ(identifySharcSdkTarget(grid, compact.data(), compact.size(), &target, &message),
              CacheFileStatus::kUnsupportedFeature);
    EXPECT_NE(message.find("compact"), std::string::npos) << message;
    // Slots outside every known bucket: an unknown rule.
    std::vector<SharcSdkObservation> unknown = observe(kReleases[1], grid);
    for (SharcSdkObservation& o : unknown) o.slot = (o.slot + grid.capacity / 2) % grid.capacity;
    EXPECT_EQ(identifySharcSdkTarget(grid, unknown.data(), unknown.size(), &target, &message),
              CacheFileStatus::kUnsupportedFeature);
    EXPECT_NE(message.find("outside the bucket"), std::string::npos) << message;
    EXPECT_EQ(identifySharcSdkTarget(grid, unknown.data(), 3, &target, &message), CacheFileStatus::kInvalidArgument);
    // Probes on a floor (no normal with a negative component) set no normal bit, where the 1.6 and
    // 1.7 layouts differ: both fit, and the message says which probes tell them apart.
    const std::vector<SharcSdkObservation> floor = observe(kReleases[1], grid, false, true);
    EXPECT_EQ(identifySharcSdkTarget(grid, floor.data(), floor.size(), &target, &message),
              CacheFileStatus::kUnsupportedFeature);
    EXPECT_NE(message.find("normals have a negative component"), std::string::npos) << message;
}

// The C entry point gives what the C++ one gives, for the same observations.
TEST(SdkTarget, IdentifiesTheReleaseThroughTheCInterface) {
    HashGridParameters grid;
    grid.capacity = 100003;
    grid.level_bias = 2.515625f;
    const auto toC = [](const std::vector<SharcSdkObservation>& seen) {
        std::vector<sharcbake_sdk_observation> out(seen.size());
        for (size_t i = 0; i < seen.size(); ++i) {
            const SharcSdkObservation& o = seen[i];
            out[i] = sharcbake_sdk_observation{{o.position.x, o.position.y, o.position.z},
                                               {o.normal.x, o.normal.y, o.normal.z},
                                               {o.camera.x, o.camera.y, o.camera.z},
                                               o.slot,
                                               o.key};
        }
        return out;
    };
    const auto identify = [&](const std::vector<sharcbake_sdk_observation>& seen, size_t count,
                              sharcbake_sdk_target* target, char* message, size_t size) {
        return sharcbake_identify_sdk_target(grid.logarithm_base, grid.scene_scale, grid.level_bias, grid.capacity,
                                             seen.data(), count, target, message, size);
    };
    char message[512];
    for (const Release& r : kReleases) {
        const std::vector<sharcbake_sdk_observation> seen = toC(observe(r, grid));
        sharcbake_sdk_target target{};
        ASSERT_EQ(identify(seen, seen.size(), &target, message, sizeof message), SHARCBAKE_OK)
            << r.name << ": " << message;
        EXPECT_EQ(uint32_t(target), uint32_t(r.target)) << r.name;
    }
    // The C++ function's refusals and their reasons come through.
    sharcbake_sdk_target target = SHARCBAKE_SDK_1_6;
    const std::vector<sharcbake_sdk_observation> floor = toC(observe(kReleases[1], grid, false, true));
    EXPECT_EQ(identify(floor, floor.size(), &target, message, sizeof message), SHARCBAKE_UNSUPPORTED_FEATURE);
    EXPECT_NE(std::string(message).find("normals have a negative component"), std::string::npos) << message;
    EXPECT_EQ(target, SHARCBAKE_SDK_1_6);  // untouched on failure
    EXPECT_EQ(identify(floor, 3, &target, message, sizeof message), SHARCBAKE_INVALID_ARGUMENT);
    EXPECT_NE(std::string(message).find("4 observations"), std::string::npos) << message;
    // NULL arguments are refused with a message, not dereferenced.
    EXPECT_EQ(identify(floor, floor.size(), nullptr, message, sizeof message), SHARCBAKE_INVALID_ARGUMENT);
    EXPECT_NE(std::string(message).find("NULL"), std::string::npos) << message;
    EXPECT_EQ(sharcbake_identify_sdk_target(grid.logarithm_base, grid.scene_scale, grid.level_bias, grid.capacity,
                                            nullptr, 16, &target, nullptr, 0),
              SHARCBAKE_INVALID_ARGUMENT);
}

// ------------------------------------------------------------------------------------------------
// Build options
// ------------------------------------------------------------------------------------------------

TEST(SdkTarget, BuildOptionsTheBakeCannotServeAreRefusedWithAReason) {
    TestCache cache;
    makeTestCache(10, &cache);
    struct Case {
        void (*set)(SharcBuildOptions&);
        const char* define;
        const char* reason;
        uint32_t c_flag;
    };
    const Case cases[] = {
        {[](SharcBuildOptions& b) { b.sh_encoding = true; }, "SHARC_ENABLE_SH_ENCODING", "direction",
         SHARCBAKE_BUILD_SH_ENCODING},
        {[](SharcBuildOptions& b) { b.compact_keys = true; }, "HASH_GRID_COMPACT", "17-bit",
         SHARCBAKE_BUILD_COMPACT_KEYS},
        {[](SharcBuildOptions& b) { b.material_demodulation = true; }, "SHARC_MATERIAL_DEMODULATION", "albedo",
         SHARCBAKE_BUILD_MATERIAL_DEMODULATION},
        {[](SharcBuildOptions& b) { b.separate_emissive = true; }, "SHARC_SEPARATE_EMISSIVE", "emission",
         SHARCBAKE_BUILD_SEPARATE_EMISSIVE},
    };
    sharcbake_cache* c = nullptr;
    ASSERT_EQ(sharcbake_cache_open_memory(cache.bytes.data(), cache.bytes.size(), &c, nullptr, nullptr, 0),
              SHARCBAKE_OK);
    for (const Case& k : cases) {
        GpuBufferOptions options;
        options.capacity = 64;
        k.set(options.build);
        GpuBuffers buffers;
        GpuInsertList list;
        CacheError error;
        EXPECT_EQ(cache.view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kUnsupportedFeature);
        EXPECT_NE(error.message.find(k.define), std::string::npos) << error.message;
        EXPECT_NE(error.message.find(k.reason), std::string::npos) << error.message;
        EXPECT_EQ(cache.view.gpuInsertList(options, &list, &error), CacheFileStatus::kUnsupportedFeature);
        EXPECT_NE(error.message.find(k.define), std::string::npos) << error.message;

        sharcbake_gpu_options o;
        sharcbake_gpu_options_init(&o);
        o.capacity = 64;
        o.build_flags = k.c_flag;
        std::vector<uint64_t> keys(64);
        std::vector<sharcbake_packed_data> resolved(64);
        char message[1024];
        EXPECT_EQ(sharcbake_cache_gpu_buffers_ex(c, &o, keys.data(), resolved.data(), nullptr, message, sizeof message),
                  SHARCBAKE_UNSUPPORTED_FEATURE);
        EXPECT_NE(std::string(message).find(k.define), std::string::npos) << message;
    }
    sharcbake_cache_close(c);
}

// ------------------------------------------------------------------------------------------------
// Resolve: eviction and frame counters (SPEC §G.4)
// ------------------------------------------------------------------------------------------------

TEST(SdkResolve, BakedVoxelsSurviveExactlyTheFramesStated) {
    TestCache cache;
    makeTestCache(200, &cache);
    for (uint32_t stale : {0u, 8u, 60u, 64u, 1024u, 5000u}) {
        const uint32_t kept = sharcResolveFramesKept(stale);
        EXPECT_EQ(kept, std::clamp(stale, 8u, 1024u) - 1);
        EXPECT_EQ(sharcbake_resolve_frames_kept(stale), kept);
        for (uint32_t frame_num : {0u, 1u, 32u, 65535u}) {
            GpuBufferOptions options;
            options.capacity = 1024;
            options.accumulated_frame_num = frame_num;
            GpuBuffers buffers;
            ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
            std::vector<uint64_t> table = buffers.hash_entries;
            std::vector<SharcPackedData> resolved = buffers.resolved;
            for (uint32_t frame = 1; frame <= kept; ++frame) releaseResolve(table, resolved, {}, 32, stale);
            EXPECT_EQ(uint64_t(std::count_if(table.begin(), table.end(), [](uint64_t k) { return k != 0; })),
                      buffers.inserted)
                << "stale " << stale << ", frame number " << frame_num << ": evicted before frame " << kept;
            for (const SharcPackedData& e : resolved) {
                if (e.radiance[3] != 0) {
                    EXPECT_EQ(e.sample_data >> 16, kept);  // the stale counter
                }
            }
            releaseResolve(table, resolved, {}, 32, stale);
            EXPECT_TRUE(std::all_of(table.begin(), table.end(), [](uint64_t k) { return k == 0; }))
                << "stale " << stale << ": still there after frame " << kept + 1;
        }
    }
}

TEST(SdkResolve, FrameNumbersNearTheTopWouldCarryIntoTheStaleCounter) {
    // Why accumulated_frame_num is clamped to 64511: with 65535 the first sample-less Resolve
    // carries into the stale counter (+2 instead of +1) and the voxel is evicted a frame early.
    TestCache cache;
    makeTestCache(50, &cache);
    GpuBufferOptions options;
    options.capacity = 1024;
    options.accumulated_frame_num = 0xFFFFu;
    GpuBuffers buffers;
    ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
    std::vector<uint64_t> table = buffers.hash_entries;
    std::vector<SharcPackedData> resolved = buffers.resolved, unclamped = buffers.resolved;
    for (SharcPackedData& e : unclamped) {
        if (e.radiance[3] != 0) {
            EXPECT_EQ(e.sample_data, kSharcMaxBakedFrameNum);
            e.sample_data = 0xFFFFu;
        }
    }
    std::vector<uint64_t> unclamped_table = table;
    const uint32_t kept = sharcResolveFramesKept(1024);
    for (uint32_t frame = 1; frame <= kept; ++frame) {
        releaseResolve(table, resolved, {}, 32, 1024);
        releaseResolve(unclamped_table, unclamped, {}, 32, 1024);
    }
    EXPECT_EQ(uint64_t(std::count_if(table.begin(), table.end(), [](uint64_t k) { return k != 0; })), buffers.inserted);
    EXPECT_TRUE(std::all_of(unclamped_table.begin(), unclamped_table.end(), [](uint64_t k) { return k == 0; }));
}

TEST(SdkResolve, VoxelsTheEngineSamplesStayAndBlendTheBakedMean) {
    TestCache cache;
    makeTestCache(200, &cache);
    const uint32_t stale = 64, accumulation = 32;
    GpuBufferOptions options;
    options.capacity = 1024;
    GpuBuffers buffers;
    ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
    std::vector<uint64_t> table = buffers.hash_entries;
    std::vector<SharcPackedData> resolved = buffers.resolved;
    const std::vector<SharcPackedData> baked = buffers.resolved;
    // The engine's update paths reach even slots every `stale - 1` frames, odd slots never.
    std::vector<Deposit> none(table.size()), some(table.size());
    for (size_t i = 0; i < table.size(); i += 2) some[i] = Deposit{2, 10.0f};
    bool first = true;
    for (uint32_t frame = 1; frame <= 3 * stale; ++frame) {
        const bool sampled = frame % (stale - 1) == 5;
        releaseResolve(table, resolved, sampled ? some : none, accumulation, stale);
        if (sampled && first) {
            first = false;
            // frames (1 + 5 no-sample frames + this one) stay below the cap: the baked weight counts whole.
            for (size_t i = 0; i < table.size(); i += 2) {
                if (buffers.hash_entries[i] == 0) continue;
                const float s = halfToFloat(baked[i].radiance[3]);
                expectHalfNear(halfToFloat(resolved[i].radiance[3]), s + 2.0f);
                expectHalfNear(halfToFloat(resolved[i].radiance[1]),
                               (s * halfToFloat(baked[i].radiance[1]) + 20.0f) / (s + 2.0f));
            }
        }
    }
    for (size_t i = 0; i < table.size(); ++i) {
        EXPECT_EQ(table[i] != 0, i % 2 == 0 && buffers.hash_entries[i] != 0) << i;
    }
}

// ------------------------------------------------------------------------------------------------
// Radiance scale and fp16 (SPEC §G.6)
// ------------------------------------------------------------------------------------------------

CacheData brightCache(float bright, float dim) {
    CacheData data;
    data.bake_capacity = 64;
    const HashGridParameters grid = data.gridParameters();
    for (int i = 0; i < 4; ++i) {
        CacheVoxel v;
        v.key = hashGridKey(Float3{float(i), 1.0f, 2.0f}, Float3{0, 1, 0}, grid);
        v.radiance[0] = i == 0 ? bright : 1.0f;
        v.radiance[1] = i == 1 ? dim : 2.0f;
        v.radiance[2] = 0.5f;
        v.sample_weight = 4.0f;
        data.voxels.push_back(v);
    }
    sortVoxels(data.voxels);
    return data;
}

TEST(GpuRadianceScale, ClippingIsReportedWithTheScaleThatFixesIt) {
    const CacheData data = brightCache(1.0e6f, 1.0f);
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(data, &bytes, &view));
    GpuBufferOptions options;
    options.capacity = 64;
    GpuBuffers buffers;
    CacheError error;
    ASSERT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kOk);
    EXPECT_EQ(buffers.radiance.radiance_scale, 1.0f);
    EXPECT_EQ(buffers.radiance.clipped_voxels, 1u);
    EXPECT_EQ(buffers.radiance.brightest, 1.0e6f);
    EXPECT_EQ(buffers.radiance.fitting_radiance_scale, 0.0625f);  // 65504 / 1e6 = 0.0655 -> 2^-4
    EXPECT_NE(buffers.radiance.warning.find("65504"), std::string::npos) << buffers.radiance.warning;
    EXPECT_NE(buffers.radiance.warning.find("0.0625"), std::string::npos) << buffers.radiance.warning;
    EXPECT_EQ(error.message, buffers.radiance.warning);

    options.radiance_scale = buffers.radiance.fitting_radiance_scale;
    ASSERT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kOk);
    EXPECT_EQ(buffers.radiance.clipped_voxels, 0u);
    EXPECT_TRUE(buffers.radiance.warning.empty()) << buffers.radiance.warning;
    float brightest = 0.0f, sum = 0.0f;
    for (const SharcPackedData& e : buffers.resolved) {
        brightest = std::max(brightest, halfToFloat(e.radiance[0]));
        sum += halfToFloat(e.radiance[2]);
    }
    EXPECT_NEAR(brightest, 62500.0f, 32.0f);  // fp16 spacing at 2^15..2^16 is 32
    EXPECT_FLOAT_EQ(sum, 4 * 0.5f * 0.0625f);

    GpuInsertList list;
    ASSERT_EQ(view.gpuInsertList(options, &list, &error), CacheFileStatus::kOk);
    EXPECT_EQ(list.radiance.fitting_radiance_scale, 0.0625f);
    for (float bad : {-1.0f, NAN, INFINITY}) {
        options.radiance_scale = bad;
        EXPECT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kInvalidArgument) << bad;
    }
    // So is a sample-count cap that caps nothing meaningful (it fell back to 65504 silently);
    // infinity caps at 65504.
    options.radiance_scale = 0.0f;
    for (float bad : {-1.0f, 0.0f, NAN}) {
        options.max_sample_count = bad;
        EXPECT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kInvalidArgument) << bad;
        EXPECT_NE(error.message.find("max sample count must be > 0"), std::string::npos) << error.message;
        EXPECT_EQ(view.gpuInsertList(options, &list, &error), CacheFileStatus::kInvalidArgument) << bad;
    }
    options.max_sample_count = INFINITY;
    EXPECT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kOk);
}

TEST(GpuRadianceScale, LightTooDimForFp16IsReported) {
    CacheData data = brightCache(1.0f, 1.0f);
    for (CacheVoxel& v : data.voxels)
        for (float& c : v.radiance) c *= 1.0e-9f;  // a scene in the wrong units: all below fp16
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(data, &bytes, &view));
    GpuInsertList list;
    ASSERT_EQ(view.gpuInsertList(GpuBufferOptions{}, &list, nullptr), CacheFileStatus::kOk);
    EXPECT_EQ(list.radiance.flushed_voxels, 4u);
    EXPECT_EQ(list.radiance.clipped_voxels, 0u);
    EXPECT_NE(list.radiance.warning.find("stored as 0"), std::string::npos) << list.radiance.warning;
    EXPECT_NE(list.radiance.warning.find("100% of the cache's light"), std::string::npos) << list.radiance.warning;
    EXPECT_NE(list.radiance.warning.find("up to the fitting one"), std::string::npos) << list.radiance.warning;
}

TEST(GpuRadianceScale, NearBlackVoxelsAmongLitOnesAreCountedButNotWarnedAbout) {
    // One channel of one voxel in four at 1e-9 beside channels of 0.5 to 2: stored as 0, and a
    // billionth of the light: nothing visible changes, so no warning.
    const CacheData data = brightCache(1.0f, 1.0e-9f);
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(data, &bytes, &view));
    GpuInsertList list;
    ASSERT_EQ(view.gpuInsertList(GpuBufferOptions{}, &list, nullptr), CacheFileStatus::kOk);
    EXPECT_EQ(list.radiance.flushed_voxels, 1u);
    EXPECT_TRUE(list.radiance.warning.empty()) << list.radiance.warning;
}

// ------------------------------------------------------------------------------------------------
// Voxel materials (VMAT, SPEC §F.8b): separate emissive and material demodulation (SPEC §G.3)
// ------------------------------------------------------------------------------------------------

/// brightCache's four voxels with materials: voxel 0 an emitter, the others coloured surfaces.
CacheData cacheWithMaterials() {
    CacheData data = brightCache(6.0f, 0.25f);
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        CacheVoxelMaterial m;
        m.emission[0] = i == 0 ? 5.0f : 0.0f;
        m.emission[1] = i == 0 ? 1.5f : 0.0f;
        m.emission[2] = 0.0f;
        m.demodulation[0] = 0.8f;
        m.demodulation[1] = 0.05f + 0.1f * float(i);
        m.demodulation[2] = 0.35f;
        data.voxel_materials.push_back(m);
    }
    return data;
}

float half(uint16_t bits) { return halfToFloat(bits); }

TEST(VoxelMaterials, AreStoredReadBackAndMerged) {
    const CacheData data = cacheWithMaterials();
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(data, &bytes, &view));
    ASSERT_TRUE(view.hasVoxelMaterials());
    for (uint64_t i = 0; i < view.voxelCount(); ++i) {
        const CacheVoxelMaterial m = view.voxelMaterial(i);
        EXPECT_EQ(std::memcmp(&m, &data.voxel_materials[size_t(i)], sizeof m), 0) << i;
    }
    bool optional_vmat = false;
    for (const CacheSectionInfo& s : view.sections()) {
        optional_vmat = optional_vmat || (s.type == kSectionVoxelMaterials && !s.required && s.known);
    }
    EXPECT_TRUE(optional_vmat) << "VMAT is optional: a reader that skips it still makes the plain buffers";

    // Without materials: no section, and the plain values.
    CacheData plain = data;
    plain.voxel_materials.clear();
    std::vector<uint8_t> plain_bytes;
    CacheView plain_view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(plain, &plain_bytes, &plain_view));
    EXPECT_EQ(bytes.size() - plain_bytes.size(), data.voxels.size() * 24 + kCacheSectionEntrySize);  // records + table entry
    EXPECT_FALSE(plain_view.hasVoxelMaterials());

    // Merging: shards' means weighted by sample weight; all inputs keep materials or none.
    CacheData other = data;
    for (CacheVoxel& v : other.voxels) v.sample_weight = 12.0f;  // 3x data's weight of 4
    for (CacheVoxelMaterial& m : other.voxel_materials) m.demodulation[2] = 0.75f;
    CacheData merged;
    std::string message;
    ASSERT_EQ(mergeCaches({data, other}, {}, &merged, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(merged.voxel_materials.size(), merged.voxels.size());
    EXPECT_FLOAT_EQ(merged.voxel_materials[0].demodulation[2], 0.25f * 0.35f + 0.75f * 0.75f);
    EXPECT_EQ(mergeCaches({data, plain}, {}, &merged, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("voxel materials"), std::string::npos) << message;
}

TEST(VoxelMaterials, TheWriterRefusesWhatTheReaderWould) {
    CacheData data = cacheWithMaterials();
    std::vector<uint8_t> bytes;
    std::string message;
    data.voxel_materials.pop_back();
    EXPECT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("one per voxel"), std::string::npos) << message;
    for (const float bad : {-1.0f, NAN, INFINITY}) {
        data = cacheWithMaterials();
        data.voxel_materials[1].emission[2] = bad;
        EXPECT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kInvalidData) << bad;
        data = cacheWithMaterials();
        data.voxel_materials[2].demodulation[0] = bad == -1.0f ? 0.0f : bad;
        EXPECT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kInvalidData) << bad;
    }
}

// What an engine built with the option reads at a hit of the voxel (the SDK's query with
// SHARC_SEPARATE_EMISSIVE / SHARC_MATERIAL_DEMODULATION, docs/sharc_algorithm.md §6): the stored
// value times the hit's factor, plus the hit's emission. Here the hit has the voxel's mean
// material, so the engine must read back the plain radiance (fp16 both ways).
TEST(VoxelMaterials, EachBuildReadsBackThePlainRadiance) {
    const CacheData data = cacheWithMaterials();
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(encodeAndOpen(data, &bytes, &view));
    GpuInsertList plain;
    ASSERT_EQ(view.gpuInsertList(GpuBufferOptions{}, &plain, nullptr), CacheFileStatus::kOk);
    for (const bool emissive : {false, true}) {
        for (const bool demodulation : {false, true}) {
            GpuBufferOptions options;
            options.build.separate_emissive = emissive;
            options.build.material_demodulation = demodulation;
            options.capacity = 64;
            GpuInsertList list;
            GpuBuffers buffers;
            CacheError error;
            ASSERT_EQ(view.gpuInsertList(options, &list, &error), CacheFileStatus::kOk) << error.message;
            ASSERT_EQ(view.gpuBuffers(options, &buffers, &error), CacheFileStatus::kOk) << error.message;
            for (size_t i = 0; i < list.keys.size(); ++i) {
                const CacheVoxelMaterial& m = data.voxel_materials[i];
                for (int c = 0; c < 3; ++c) {
                    const float stored = half(list.values[i].radiance[c]);
                    const float read = stored * (demodulation ? m.demodulation[c] : 1.0f) +
                                       (emissive ? m.emission[c] : 0.0f);
                    const float expected = half(plain.values[i].radiance[c]);
                    EXPECT_NEAR(read, expected, 2e-3f * expected + 1e-6f)
                        << "voxel " << i << " channel " << c << " emissive " << emissive << " demod " << demodulation;
                    if (emissive && m.emission[c] > 0.0f && !demodulation) {
                        EXPECT_LT(stored, expected) << "the emission is taken out";
                    }
                }
                EXPECT_EQ(list.values[i].radiance[3], plain.values[i].radiance[3]) << "the sample count stays";
            }
            // The buffers hold the same entries as the list.
            for (size_t slot = 0; slot < buffers.hash_entries.size(); ++slot) {
                if (buffers.hash_entries[slot] == 0) continue;
                const auto it = std::find(list.keys.begin(), list.keys.end(), buffers.hash_entries[slot]);
                ASSERT_NE(it, list.keys.end());
                EXPECT_EQ(std::memcmp(&buffers.resolved[slot], &list.values[size_t(it - list.keys.begin())],
                                      sizeof(SharcPackedData)), 0);
            }
        }
    }
}

TEST(VoxelMaterials, DemodulationFactorIsTheSdkSamples) {
    // A red Lambert-with-coat dielectric: F0 = 0.04, luminance(0.04 + 0.96/21) = 0.0857...
    const Float3 m = sharcDemodulationFactor(Float3{0.63f, 0.01f, 0.05f}, Float3{0.04f, 0.04f, 0.04f});
    const float coat = 0.04f * (0.04f + 0.96f / 21.0f);
    EXPECT_NEAR(m.x, 0.63f + coat, 1e-6f);
    EXPECT_NEAR(m.y, 0.05f + coat, 1e-6f) << "diffuse albedo clamped at 0.05";
    EXPECT_NEAR(m.z, 0.05f + coat, 1e-6f);
    // A gold-like metal: no diffuse (0.05 floor), F0 per channel times the luminance of its average.
    const Float3 f0{1.0f, 0.78f, 0.34f};
    const float lum = 0.2126f * (1.0f) + 0.7152f * (0.78f + 0.22f / 21.0f) + 0.0722f * (0.34f + 0.66f / 21.0f);
    const Float3 g = sharcDemodulationFactor(Float3{0, 0, 0}, f0);
    EXPECT_NEAR(g.x, 0.05f + 1.0f * lum, 1e-6f);
    EXPECT_NEAR(g.y, 0.05f + 0.78f * lum, 1e-6f);
    EXPECT_NEAR(g.z, 0.05f + 0.34f * lum, 1e-6f);
}

// ------------------------------------------------------------------------------------------------
// C API
// ------------------------------------------------------------------------------------------------

TEST(SdkTargetC, BuffersInsertListsAndReleases) {
    TestCache cache;
    makeTestCache(500, &cache);
    sharcbake_cache* c = nullptr;
    ASSERT_EQ(sharcbake_cache_open_memory(cache.bytes.data(), cache.bytes.size(), &c, nullptr, nullptr, 0),
              SHARCBAKE_OK);
    EXPECT_EQ(sharcbake_cache_gpu_radiance_scale(c), 1.0f);
    sharcbake_gpu_options o;
    sharcbake_gpu_options_init(&o);
    EXPECT_EQ(o.sdk_target, uint32_t(SHARCBAKE_SDK_1_7));
    EXPECT_EQ(o.capacity, 1u << 22);
    o.capacity = 4096;
    o.sdk_target = SHARCBAKE_SDK_1_6;
    std::vector<uint64_t> keys(o.capacity);
    std::vector<sharcbake_packed_data> resolved(o.capacity);
    sharcbake_gpu_report report{};
    char message[512];
    ASSERT_EQ(sharcbake_cache_gpu_buffers_ex(c, &o, keys.data(), resolved.data(), &report, message, sizeof message),
              SHARCBAKE_OK);
    EXPECT_EQ(report.inserted + report.failed_inserts, 500u);
    EXPECT_STREQ(message, "");
    GpuBufferOptions options;
    options.capacity = o.capacity;
    options.sdk_target = SharcSdkTarget::kSdk1_6;
    GpuBuffers buffers;
    ASSERT_EQ(cache.view.gpuBuffers(options, &buffers), CacheFileStatus::kOk);
    EXPECT_EQ(keys, buffers.hash_entries);

    std::vector<uint64_t> list_keys(500);
    std::vector<sharcbake_packed_data> values(500);
    ASSERT_EQ(sharcbake_cache_gpu_insert_list(c, &o, list_keys.data(), values.data(), &report, nullptr, 0),
              SHARCBAKE_OK);
    EXPECT_EQ(report.inserted, 500u);
    EXPECT_EQ(list_keys[0], sharcSdkKey(cache.data.voxels[0].key, SharcSdkTarget::kSdk1_6));

    // Flags of an SDK build this library does not know are refused, not read as another build.
    o.build_flags = 0xFFFFFFF0u;
    EXPECT_EQ(sharcbake_cache_gpu_buffers_ex(c, &o, keys.data(), resolved.data(), &report, message, sizeof message),
              SHARCBAKE_INVALID_ARGUMENT);
    EXPECT_NE(std::string(message).find("build_flags"), std::string::npos) << message;
    EXPECT_EQ(sharcbake_cache_gpu_insert_list(c, &o, list_keys.data(), values.data(), &report, nullptr, 0),
              SHARCBAKE_INVALID_ARGUMENT);
    o.build_flags = 0;
    o.sdk_target = 99;
    EXPECT_EQ(sharcbake_cache_gpu_buffers_ex(c, &o, keys.data(), resolved.data(), &report, message, sizeof message),
              SHARCBAKE_INVALID_ARGUMENT);
    sharcbake_sdk_target t{};
    EXPECT_EQ(sharcbake_sdk_target_for_release("1.8.3", &t, message, sizeof message), SHARCBAKE_OK);
    EXPECT_EQ(t, SHARCBAKE_SDK_1_8_3);
    EXPECT_EQ(sharcbake_sdk_target_for_release("1.5.1", &t, message, sizeof message), SHARCBAKE_UNSUPPORTED_FEATURE);
    sharcbake_cache_close(c);
}

}  // namespace
}  // namespace sharcbake
