// SPDX-License-Identifier: Apache-2.0
// The checkpoint file (SPEC.md §C) and cache merging (cache_merge.h): round trips, every
// damaged byte rejected, and merges that refuse what cannot be combined.
#include "sharcbake/cache_merge.h"
#include "sharcbake/checkpoint_file.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

CheckpointData smallCheckpoint() {
    CheckpointData data;
    data.iterations_done = 7;
    data.capacity = 64;
    data.radiance_scale = 1073741824.0;
    CheckpointSlot a;
    a.slot = 3;
    a.key = 0x0000123456789ABCull;
    a.mean[0] = 1.5f;
    a.mean[1] = 0.25f;
    a.mean[2] = 2.0f;
    a.frames = 6;
    a.weight = 123.5;
    a.last_iteration = 6;
    a.total_samples = 140;
    a.feedback[0] = 1.25f;
    a.feedback[1] = 0.5f;
    a.feedback[2] = 3.0f;
    CheckpointSlot b = a;
    b.slot = 40;
    b.key = 0x0000223456789ABDull;
    b.weight = 0.0;  // a key whose samples were all dropped: kept, it holds its slot
    data.slots = {a, b};
    data.settings = {{"scene_hash", "fnv1a64:0123456789abcdef"}, {"seed", "4"}, {"scene_note", "h\xC3\xA9"}};
    data.counts = {{"paths", 1000}, {"deposits", 5000}};
    data.amounts = {{"clamped_energy.r", 0.125}};
    return data;
}

void expectEqual(const CheckpointData& a, const CheckpointData& b) {
    EXPECT_EQ(a.iterations_done, b.iterations_done);
    EXPECT_EQ(a.capacity, b.capacity);
    EXPECT_EQ(a.bucket_size, b.bucket_size);
    EXPECT_EQ(a.radiance_scale, b.radiance_scale);
    ASSERT_EQ(a.slots.size(), b.slots.size());
    for (size_t i = 0; i < a.slots.size(); ++i) {
        EXPECT_EQ(a.slots[i].slot, b.slots[i].slot);
        EXPECT_EQ(a.slots[i].key, b.slots[i].key);
        EXPECT_EQ(0, std::memcmp(a.slots[i].mean, b.slots[i].mean, sizeof a.slots[i].mean));
        EXPECT_EQ(a.slots[i].frames, b.slots[i].frames);
        EXPECT_EQ(a.slots[i].weight, b.slots[i].weight);
        EXPECT_EQ(a.slots[i].last_iteration, b.slots[i].last_iteration);
        EXPECT_EQ(a.slots[i].total_samples, b.slots[i].total_samples);
        EXPECT_EQ(0, std::memcmp(a.slots[i].feedback, b.slots[i].feedback, sizeof a.slots[i].feedback));
    }
    EXPECT_EQ(a.settings, b.settings);
    EXPECT_EQ(a.counts, b.counts);
    EXPECT_EQ(a.amounts, b.amounts);
}

TEST(CheckpointFile, RoundTripsEveryField) {
    std::vector<uint8_t> bytes;
    std::string message;
    ASSERT_EQ(encodeCheckpoint(smallCheckpoint(), &bytes, &message), CacheFileStatus::kOk) << message;
    CheckpointData read;
    ASSERT_EQ(decodeCheckpoint(bytes.data(), bytes.size(), &read, &message), CacheFileStatus::kOk) << message;
    expectEqual(smallCheckpoint(), read);
}

TEST(CheckpointFile, EveryChangedByteAndEveryPrefixIsRejected) {
    std::vector<uint8_t> bytes;
    ASSERT_EQ(encodeCheckpoint(smallCheckpoint(), &bytes, nullptr), CacheFileStatus::kOk);
    std::string message;
    for (size_t i = 0; i < bytes.size(); ++i) {
        std::vector<uint8_t> damaged = bytes;
        damaged[i] ^= 0x10;
        EXPECT_NE(decodeCheckpoint(damaged.data(), damaged.size(), nullptr, &message), CacheFileStatus::kOk)
            << "byte " << i << " changed and still accepted";
    }
    for (size_t n = 0; n < bytes.size(); ++n) {
        EXPECT_NE(decodeCheckpoint(bytes.data(), n, nullptr, &message), CacheFileStatus::kOk) << "prefix " << n;
    }
    // A file cut within its identifier, an empty one included, is truncated (it said "not a
    // sharcbake checkpoint"); other bytes there are not a checkpoint.
    for (const size_t n : {size_t(0), size_t(5)}) {
        EXPECT_EQ(decodeCheckpoint(bytes.data(), n, nullptr, &message), CacheFileStatus::kTruncated) << n;
        EXPECT_NE(message.find("ends within the checkpoint identifier"), std::string::npos) << message;
    }
    const std::vector<uint8_t> text = {'g', 'a', 'r', 'b', 'a', 'g', 'e', '\n'};
    EXPECT_EQ(decodeCheckpoint(text.data(), text.size(), nullptr, &message), CacheFileStatus::kBadMagic);
}

TEST(CheckpointFile, WriterRefusesStateAReaderWouldReject) {
    std::vector<uint8_t> bytes;
    std::string message;
    CheckpointData data = smallCheckpoint();
    data.slots[1].slot = data.slots[0].slot;  // not strictly increasing
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    data = smallCheckpoint();
    data.slots[0].slot = data.capacity;  // outside the table
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    data = smallCheckpoint();
    data.slots[0].mean[1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    data = smallCheckpoint();
    data.slots[0].feedback[2] = std::numeric_limits<float>::infinity();
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    data = smallCheckpoint();
    data.slots[0].weight = 1e300;  // finite, but no cache can store it (float32)
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("within float32's range"), std::string::npos) << message;
    data = smallCheckpoint();
    data.settings.push_back(data.settings[0]);  // duplicate key
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("duplicate"), std::string::npos) << message;
}

// The checkpoint golden (format 2.0): written when SHARCBAKE_UPDATE_GOLDENS is set; otherwise the
// writer must reproduce it byte for byte and the reader must read it back. Goldens are kept forever.
const std::string kCheckpointGoldenPath = std::string(SHARCBAKE_GOLDEN_DIR) + "/small.v2.0.ckpt";

TEST(CheckpointGolden, WriterReproducesGolden) {
    std::vector<uint8_t> bytes;
    std::string message;
    ASSERT_EQ(encodeCheckpoint(smallCheckpoint(), &bytes, &message), CacheFileStatus::kOk) << message;
    if (std::getenv("SHARCBAKE_UPDATE_GOLDENS")) {
        std::ofstream out(kCheckpointGoldenPath, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
        ASSERT_TRUE(out.good());
    }
    std::ifstream in(kCheckpointGoldenPath, std::ios::binary);
    const std::vector<uint8_t> golden((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_FALSE(golden.empty()) << kCheckpointGoldenPath << " is missing; run with SHARCBAKE_UPDATE_GOLDENS=1";
    EXPECT_EQ(bytes, golden) << "the writer no longer reproduces " << kCheckpointGoldenPath
                             << "; if intended, add a golden for the new checkpoint version";
}

TEST(CheckpointGolden, GoldenReadsBack) {
    CheckpointData read;
    std::string message;
    ASSERT_EQ(readCheckpointFile(kCheckpointGoldenPath, &read, &message), CacheFileStatus::kOk) << message;
    expectEqual(smallCheckpoint(), read);
}

// Issue 19: a CRC-valid checkpoint may not carry counters the bake cannot honour (rule C8).
TEST(CheckpointFile, CountersAreBounded) {
    std::vector<uint8_t> bytes;
    std::string message;
    CheckpointData data = smallCheckpoint();
    data.iterations_done = kCheckpointMaxIterations;
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kOk) << message;
    data.iterations_done = 0xFFFFFFFFu;
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("C8"), std::string::npos) << message;
    data = smallCheckpoint();
    data.bucket_size = data.capacity + 1;
    EXPECT_EQ(encodeCheckpoint(data, &bytes, &message), CacheFileStatus::kInvalidData);
}

TEST(CheckpointFile, ACacheFileIsNotACheckpoint) {
    CacheData cache;
    cache.bake_capacity = 16;
    std::vector<uint8_t> bytes;
    ASSERT_EQ(encodeCacheFile(cache, &bytes, nullptr), CacheFileStatus::kOk);
    std::string message;
    EXPECT_EQ(decodeCheckpoint(bytes.data(), bytes.size(), nullptr, &message), CacheFileStatus::kBadMagic);
    EXPECT_NE(message.find("not a checkpoint"), std::string::npos) << message;
}

CacheData shard(std::vector<CacheVoxel> voxels, const std::string& scene_hash = "fnv1a64:1") {
    CacheData data;
    data.bake_capacity = 1024;
    data.version_major = 1;
    data.voxels = std::move(voxels);
    data.metadata = {{"scene_hash", scene_hash}};
    return data;
}

CacheVoxel voxel(uint64_t key, float radiance, float weight) {
    CacheVoxel v;
    v.key = key;
    v.radiance[0] = v.radiance[1] = v.radiance[2] = radiance;
    v.sample_weight = weight;
    return v;
}

TEST(CacheMerge, SampleWeightedMeanPerVoxelAndOrderIndependent) {
    const uint64_t k1 = (uint64_t(1) << 51) | 5, k2 = (uint64_t(1) << 51) | 9, k3 = (uint64_t(2) << 51) | 1;
    const CacheData a = shard({voxel(k1, 1.0f, 1.0f), voxel(k2, 4.0f, 2.0f)});
    const CacheData b = shard({voxel(k1, 3.0f, 3.0f), voxel(k3, 7.0f, 5.0f)});
    const CacheData c = shard({voxel(k2, 0.1f, 0.7f)});
    CacheData ab, ba, abc, cba;
    std::string message;
    ASSERT_EQ(mergeCaches({a, b}, {"scene_hash"}, &ab, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(mergeCaches({b, a}, {"scene_hash"}, &ba, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(ab.voxels.size(), 3u);
    EXPECT_EQ(ab.voxels[0].key, k1);
    EXPECT_FLOAT_EQ(ab.voxels[0].radiance[0], (1.0f * 1.0f + 3.0f * 3.0f) / 4.0f);
    EXPECT_FLOAT_EQ(ab.voxels[0].sample_weight, 4.0f);
    EXPECT_EQ(ab.voxels[1].radiance[0], 4.0f);  // only in a: copied
    EXPECT_EQ(ab.voxels[2].radiance[0], 7.0f);  // only in b: copied
    ASSERT_EQ(mergeCaches({a, b, c}, {"scene_hash"}, &abc, &message), CacheFileStatus::kOk);
    ASSERT_EQ(mergeCaches({c, b, a}, {"scene_hash"}, &cba, &message), CacheFileStatus::kOk);
    std::vector<uint8_t> bytes_ab, bytes_ba, bytes_abc, bytes_cba;
    ASSERT_EQ(encodeCacheFile(ab, &bytes_ab, &message), CacheFileStatus::kOk) << message;
    ASSERT_EQ(encodeCacheFile(ba, &bytes_ba, &message), CacheFileStatus::kOk);
    ASSERT_EQ(encodeCacheFile(abc, &bytes_abc, &message), CacheFileStatus::kOk);
    ASSERT_EQ(encodeCacheFile(cba, &bytes_cba, &message), CacheFileStatus::kOk);
    EXPECT_EQ(bytes_ab, bytes_ba);
    EXPECT_EQ(bytes_abc, bytes_cba);
}

TEST(CacheMerge, RefusesDifferentGridsScenesAndVersions) {
    const CacheData a = shard({voxel((uint64_t(1) << 51) | 5, 1.0f, 1.0f)});
    CacheData out;
    std::string message;
    CacheData b = a;
    b.scene_scale = a.scene_scale * 2.0f;
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("scene scale"), std::string::npos) << message;
    b = a;
    b.logarithm_base = 3.0f;
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("logarithm base"), std::string::npos) << message;
    b = a;
    b.level_bias = 1.0f;
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    b = a;
    b.bucket_size = 8;
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    b = a;
    b.grid_anchor = Float3{1e4f, 0.0f, 0.0f};  // keys decode elsewhere: not one bake's shards
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("anchor"), std::string::npos) << message;
    b = shard(a.voxels, "fnv1a64:2");
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("scene_hash"), std::string::npos) << message;
    b = a;
    b.metadata.clear();  // a cache that does not say which scene it is from
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    b = a;
    b.version_minor = 1;
    EXPECT_EQ(mergeCaches({a, b}, {"scene_hash"}, &out, &message), CacheFileStatus::kInvalidData);
    EXPECT_NE(message.find("version"), std::string::npos) << message;
    EXPECT_EQ(mergeCaches({}, {}, &out, &message), CacheFileStatus::kInvalidData);
}

}  // namespace
}  // namespace sharcbake
