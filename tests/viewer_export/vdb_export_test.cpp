// SPDX-License-Identifier: Apache-2.0
// sharcbake_vdb: a cache with known voxels on two levels, exported and read back with OpenVDB.
#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/runtime.h"
#include "sharcbake/vdb_export.h"

#include <gtest/gtest.h>
#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {
namespace {

namespace fs = std::filesystem;

CacheVoxel makeVoxel(Int3 g, uint32_t level, uint32_t normal_bits, float r, float gr, float b, float w) {
    CacheVoxel v;
    v.key = packHashGridKey(g, level, normal_bits);
    v.radiance[0] = r;
    v.radiance[1] = gr;
    v.radiance[2] = b;
    v.sample_weight = w;
    return v;
}

class VdbExportTest : public ::testing::Test {
protected:
    void SetUp() override {
        openvdb::initialize();
        dir_ = fs::temp_directory_path() /
               ("sharcbake_vdb_" + std::to_string(getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir_);
        CacheData data;
        data.bake_capacity = 1024;
        // Level 3: one cell seen from two normal octants, one cell seen from one.
        data.voxels.push_back(makeVoxel({1, 2, -3}, 3, 0, 1.0f, 0.0f, 0.0f, 3.0f));
        data.voxels.push_back(makeVoxel({1, 2, -3}, 3, 5, 0.0f, 1.0f, 0.0f, 1.0f));
        data.voxels.push_back(makeVoxel({-5, 0, 7}, 3, 2, 0.5f, 0.5f, 0.5f, 0.5f));
        // Level 5: a cell at the origin and one at the most negative 17-bit coordinate.
        data.voxels.push_back(makeVoxel({0, 0, 0}, 5, 1, 2.0f, 4.0f, 8.0f, 10.0f));
        data.voxels.push_back(makeVoxel({-65536, 3, 100}, 5, 7, 1.0f, 1.0f, 1.0f, 2.0f));
        sortVoxels(data.voxels);
        data.metadata = {{"scene", "test_scene.gltf"}, {"iterations", "4"}};
        cache_path_ = (dir_ / "test.sharc").string();
        std::string message;
        ASSERT_EQ(writeCacheFile(cache_path_, data, &message), CacheFileStatus::kOk) << message;
        CacheError error;
        ASSERT_EQ(CacheView::openFile(cache_path_, &view_, &error), CacheFileStatus::kOk) << error.message;
    }
    void TearDown() override { fs::remove_all(dir_); }

    std::vector<openvdb::GridBase::Ptr> exportAndRead(const VdbExportOptions& options, openvdb::MetaMap::Ptr* meta = nullptr,
                                                      std::vector<VdbGridInfo>* info = nullptr) {
        const std::string out = (dir_ / "out.vdb").string();
        std::string message;
        EXPECT_EQ(exportCacheToVdb(view_, out, options, info, &message), VdbExportStatus::kOk) << message;
                std::ifstream in(out, std::ios::binary);
        openvdb::io::Stream stream(in);
        openvdb::GridPtrVecPtr grids = stream.getGrids();
        if (meta) *meta = stream.getMetadata();
        return std::vector<openvdb::GridBase::Ptr>(grids->begin(), grids->end());
    }

    static std::vector<std::string> names(const std::vector<openvdb::GridBase::Ptr>& grids) {
        std::vector<std::string> n;
        for (const auto& g : grids) n.push_back(g->getName());
        return n;
    }

    static openvdb::GridBase::Ptr find(const std::vector<openvdb::GridBase::Ptr>& grids, const std::string& name) {
        for (const auto& g : grids) {
            if (g->getName() == name) return g;
        }
        ADD_FAILURE() << "no grid " << name;
        return nullptr;
    }

    fs::path dir_;
    std::string cache_path_;
    CacheView view_;
};

TEST_F(VdbExportTest, GridNamesOrderAndCounts) {
    VdbExportOptions options;
    std::vector<VdbGridInfo> info;
    const auto grids = exportAndRead(options, nullptr, &info);
    const std::vector<std::string> expected = {
        "density",         "color",          "level3_density", "level3_color",    "level3_radiance",
        "level3_samples",  "level5_density", "level5_color",   "level5_radiance", "level5_samples"};
    // Written in this order (the exporter's summary); OpenVDB's readers return them by name.
    std::vector<std::string> written;
    for (const VdbGridInfo& g : info) written.push_back(g.name);
    EXPECT_EQ(written, expected);
    std::vector<std::string> sorted = expected;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(names(grids), sorted);
    // The first grid written is a float grid (vdb_render renders the first float grid).
    EXPECT_TRUE(openvdb::gridPtrCast<openvdb::FloatGrid>(find(grids, written[0])) != nullptr);
    EXPECT_TRUE(openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "color")) != nullptr);
    // io::File (vdb_print, vdb_render) lists grids by name: the first float grid is still density.
    openvdb::io::File file((dir_ / "out.vdb").string());
    file.open();
    std::string first_float;
    const openvdb::GridPtrVecPtr by_name = file.getGrids();
    for (const auto& g : *by_name) {
        if (first_float.empty() && g->isType<openvdb::FloatGrid>()) first_float = g->getName();
    }
    file.close();
    EXPECT_EQ(first_float, "density");
    for (const auto& g : grids) {
        EXPECT_EQ(g->activeVoxelCount(), 2u) << g->getName();  // octants merged: 2 cells per level
        const int level = g->metaValue<int32_t>("sharcbake_level");
        EXPECT_EQ(level, g->getName().rfind("level5", 0) == 0 ? 5 : 3) << g->getName();
    }
}

TEST_F(VdbExportTest, TransformsPutVoxelCentresWhereTheirPointsAre) {
    // A key's cell holds the points p whose p + 1e-4 (SHaRC's position bias) falls in it: its
    // centre in the world is voxelCenter() (the SDK's, bias kept) less the bias.
    const auto grids = exportAndRead(VdbExportOptions{});
    const HashGridParameters params = view_.gridParameters();
    for (uint64_t i = 0; i < view_.voxelCount(); ++i) {
        const HashGridCell c = decodeHashGridKey(view_.key(i));
        const Float3 centre = voxelCenter(view_.key(i), params);
        const auto grid = find(grids, "level" + std::to_string(c.level) + "_radiance");
        ASSERT_TRUE(grid);
        EXPECT_NEAR(grid->voxelSize()[0], voxelSize(c.level, params), 1e-7);
        const openvdb::Vec3d world = grid->indexToWorld(openvdb::Coord(c.grid.x, c.grid.y, c.grid.z));
        const float expected[3] = {centre.x - kHashGridPositionBias, centre.y - kHashGridPositionBias,
                                   centre.z - kHashGridPositionBias};
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(world[k], expected[k], 1e-6 * std::max(1.0, std::abs(double(expected[k])))) << i << " " << k;
        }
        EXPECT_TRUE(grid->transform().isLinear());
    }
}

TEST_F(VdbExportTest, ZUpTurnsTheWorldForZUpViewers) {
    VdbExportOptions options;
    options.up = VdbUpAxis::kZ;
    openvdb::MetaMap::Ptr meta;
    const auto grids = exportAndRead(options, &meta);
    EXPECT_EQ(meta->metaValue<std::string>("sharcbake_up_axis"), "z");
    const HashGridParameters params = view_.gridParameters();
    for (uint64_t i = 0; i < view_.voxelCount(); ++i) {
        const HashGridCell c = decodeHashGridKey(view_.key(i));
        const Float3 centre = voxelCenter(view_.key(i), params);
        const auto grid = find(grids, "level" + std::to_string(c.level) + "_radiance");
        ASSERT_TRUE(grid);
        EXPECT_NEAR(grid->voxelSize()[0], voxelSize(c.level, params), 1e-6);
        // glTF (x, y, z) is Blender's (x, -z, y); the centre of the voxel's points, as above.
        const openvdb::Vec3d world = grid->indexToWorld(openvdb::Coord(c.grid.x, c.grid.y, c.grid.z));
        const float b = kHashGridPositionBias;
        const float expected[3] = {centre.x - b, -(centre.z - b), centre.y - b};
        for (int k = 0; k < 3; ++k) {
            EXPECT_NEAR(world[k], expected[k], 1e-5 * std::max(1.0, std::abs(double(expected[k])))) << i << " " << k;
        }
    }
}

TEST_F(VdbExportTest, ValuesAndOctantMerging) {
    VdbExportOptions options;
    options.scale = 2.0f;
    const auto grids = exportAndRead(options);
    auto rad = openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "level3_radiance"));
    auto col = openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "level3_color"));
    auto den = openvdb::gridPtrCast<openvdb::FloatGrid>(find(grids, "level3_density"));
    auto smp = openvdb::gridPtrCast<openvdb::FloatGrid>(find(grids, "level3_samples"));
    ASSERT_TRUE(rad && col && den && smp);
    const openvdb::Coord merged(1, 2, -3);
    // Sample-weighted mean: (3·(1,0,0) + 1·(0,1,0)) / 4.
    EXPECT_TRUE(rad->tree().isValueOn(merged));
    EXPECT_NEAR(rad->tree().getValue(merged)[0], 0.75f, 1e-6f);
    EXPECT_NEAR(rad->tree().getValue(merged)[1], 0.25f, 1e-6f);
    EXPECT_NEAR(rad->tree().getValue(merged)[2], 0.0f, 1e-6f);
    EXPECT_NEAR(col->tree().getValue(merged)[0], 1.5f, 1e-6f);
    EXPECT_NEAR(smp->tree().getValue(merged), 4.0f, 1e-6f);
    EXPECT_NEAR(den->tree().getValue(merged), 2.0f * (0.2126f * 0.75f + 0.7152f * 0.25f), 1e-6f);
    // A single entry passes through unchanged.
    const openvdb::Coord single(-5, 0, 7);
    EXPECT_TRUE(smp->tree().isValueOn(single));
    EXPECT_NEAR(smp->tree().getValue(single), 0.5f, 1e-6f);
    EXPECT_NEAR(rad->tree().getValue(single)[1], 0.5f, 1e-6f);
    // Empty space is inactive background.
    EXPECT_FALSE(rad->tree().isValueOn(openvdb::Coord(0, 0, 0)));
    // Level 5, including the sign-extended coordinate.
    auto rad5 = openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "level5_radiance"));
    ASSERT_TRUE(rad5);
    EXPECT_NEAR(rad5->tree().getValue(openvdb::Coord(0, 0, 0))[2], 8.0f, 1e-6f);
    EXPECT_TRUE(rad5->tree().isValueOn(openvdb::Coord(-65536, 3, 100)));
    // The aliases are the finest level (3).
    auto density = openvdb::gridPtrCast<openvdb::FloatGrid>(find(grids, "density"));
    ASSERT_TRUE(density);
    EXPECT_EQ(density->tree().getValue(merged), den->tree().getValue(merged));
    EXPECT_EQ(density->voxelSize(), den->voxelSize());
    EXPECT_FLOAT_EQ(density->metaValue<float>("sharcbake_scale"), 2.0f);
}

TEST_F(VdbExportTest, SplitNormalsWritesOneGridSetPerOctant) {
    VdbExportOptions options;
    options.split_normals = true;
    const auto grids = exportAndRead(options);
    EXPECT_EQ(grids.size(), 2u + 5u * 4u);  // aliases + (3 octants on level 3, 2 on level 5) × 4
    EXPECT_EQ(find(grids, "density")->activeVoxelCount(), 2u);  // aliases stay merged
    auto a = openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "level3_xpos_ypos_zpos_radiance"));
    auto b = openvdb::gridPtrCast<openvdb::Vec3SGrid>(find(grids, "level3_xneg_ypos_zneg_radiance"));
    ASSERT_TRUE(a && b);
    EXPECT_EQ(a->activeVoxelCount(), 1u);
    EXPECT_NEAR(a->tree().getValue(openvdb::Coord(1, 2, -3))[0], 1.0f, 1e-6f);
    EXPECT_NEAR(b->tree().getValue(openvdb::Coord(1, 2, -3))[1], 1.0f, 1e-6f);
    EXPECT_TRUE(find(grids, "level3_xpos_yneg_zpos_samples"));
    EXPECT_TRUE(find(grids, "level5_xneg_yneg_zneg_density"));
}

TEST_F(VdbExportTest, LevelsAndChannelsSelectGrids) {
    VdbExportOptions options;
    options.levels = {5};
    options.color = options.radiance = options.samples = false;
    const auto grids = exportAndRead(options);
    EXPECT_EQ(names(grids), (std::vector<std::string>{"color", "density", "level5_density"}));
    EXPECT_EQ(find(grids, "density")->metaValue<int32_t>("sharcbake_level"), 5);
}

TEST_F(VdbExportTest, FileMetadataRecordsTheBake) {
    VdbExportOptions options;
    options.source_path = cache_path_;
    options.writer = "test writer";
    openvdb::MetaMap::Ptr meta;
    exportAndRead(options, &meta);
    ASSERT_TRUE(meta);
    EXPECT_EQ(meta->metaValue<std::string>("sharcbake_source"), cache_path_);
    EXPECT_EQ(meta->metaValue<std::string>("sharcbake_writer"), "test writer");
    EXPECT_EQ(meta->metaValue<std::string>("units"), "glTF metres, +Y up");
    EXPECT_EQ(meta->metaValue<std::string>("sharcbake_bake_scene"), "test_scene.gltf");
    EXPECT_EQ(meta->metaValue<std::string>("sharcbake_format_version"),
              std::to_string(view_.versionMajor()) + "." + std::to_string(view_.versionMinor()));
}

TEST_F(VdbExportTest, Errors) {
    std::string message;
    VdbExportOptions options;
    options.levels = {4};
    EXPECT_EQ(exportCacheToVdb(view_, (dir_ / "x.vdb").string(), options, nullptr, &message),
              VdbExportStatus::kInvalidArgument);
    EXPECT_NE(message.find("levels present: 3,5"), std::string::npos) << message;
    EXPECT_EQ(exportCacheToVdb(view_, (dir_ / "missing_dir" / "x.vdb").string(), VdbExportOptions{}, nullptr, &message),
              VdbExportStatus::kIoError);
}

/// Encodes `data` as a cache file in `bytes` and opens `view` on them (it reads them in place).
void openInMemory(const CacheData& data, std::vector<uint8_t>& bytes, CacheView& view) {
    std::string message;
    ASSERT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kOk) << message;
    CacheError error;
    ASSERT_EQ(CacheView::openMemory(bytes.data(), bytes.size(), &view, &error), CacheFileStatus::kOk) << error.message;
}

/// The `level1_radiance` grid and the file metadata of the export at `path`, which is then removed.
std::pair<openvdb::Vec3SGrid::Ptr, openvdb::MetaMap::Ptr> readLevelOneRadianceAndRemove(const std::string& path) {
    openvdb::io::File file(path);
    file.open();
    const auto grid = openvdb::gridPtrCast<openvdb::Vec3SGrid>(file.readGrid("level1_radiance"));
    const openvdb::MetaMap::Ptr meta = file.getMetadata();
    file.close();
    std::remove(path.c_str());
    return {grid, meta};
}

// Issue 19: a valid cache that VDB cannot hold is kUnrepresentable (export-vdb exit 3), not a
// usage error; nothing is written.
TEST(VdbExportUnrepresentable, EmptyCache) {
    CacheData data;
    data.bake_capacity = 16;
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(openInMemory(data, bytes, view));
    std::string message;
    const std::string out = ::testing::TempDir() + "sharcbake_empty_" + std::to_string(::getpid()) + ".vdb";
    EXPECT_EQ(exportCacheToVdb(view, out, VdbExportOptions{}, nullptr, &message), VdbExportStatus::kUnrepresentable);
    EXPECT_NE(message.find("no voxels"), std::string::npos) << message;
    EXPECT_NE(::access(out.c_str(), F_OK), 0) << "a file was written";
}

// --scale multiplies radiance into float32 grids: a scale that takes the brightest voxel beyond
// float32's range wrote infinities (exit 0); it is refused naming the largest scale that fits.
TEST(VdbExportScale, OneBeyondFloat32IsRefusedNamingTheLargestThatFits) {
    CacheData data;
    data.bake_capacity = 1024;
    data.voxels.push_back(makeVoxel({1, 2, 3}, 1, 0, 1e30f, 2.0f, 3.0f, 1.0f));
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(openInMemory(data, bytes, view));
    std::string message;
    const std::string out = ::testing::TempDir() + "sharcbake_bright_" + std::to_string(::getpid()) + ".vdb";
    VdbExportOptions options;
    options.scale = 1e10f;
    EXPECT_EQ(exportCacheToVdb(view, out, options, nullptr, &message), VdbExportStatus::kInvalidArgument);
    EXPECT_NE(message.find("Use a scale of at most 3.4e+08"), std::string::npos) << message;
    EXPECT_NE(::access(out.c_str(), F_OK), 0) << "a file was written";
    options.scale = 3e8f;
    EXPECT_EQ(exportCacheToVdb(view, out, options, nullptr, &message), VdbExportStatus::kOk) << message;
    std::remove(out.c_str());
}

// A model a millimetre across has micrometre voxels at its finest levels, which OpenVDB's
// transforms refuse; its coarser levels fit. The refusal names them, and exporting them works.
TEST(VdbExportUnrepresentable, MicrometreVoxelsNameTheLevelsThatFit) {
    CacheData data;
    data.bake_capacity = 1024;
    data.level_bias = 14.0f;  // voxel size b^L / (S b^bias): level 1 2.4e-6, level 5 3.9e-5
    data.voxels.push_back(makeVoxel({1, 2, 3}, 1, 0, 1.0f, 1.0f, 1.0f, 1.0f));
    data.voxels.push_back(makeVoxel({0, 0, 0}, 5, 0, 1.0f, 1.0f, 1.0f, 1.0f));
    sortVoxels(data.voxels);
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(openInMemory(data, bytes, view));
    std::string message;
    const std::string out = ::testing::TempDir() + "sharcbake_tiny_" + std::to_string(::getpid()) + ".vdb";
    EXPECT_EQ(exportCacheToVdb(view, out, VdbExportOptions{}, nullptr, &message), VdbExportStatus::kUnrepresentable);
    EXPECT_NE(message.find("level 1: voxel size 2.44e-06"), std::string::npos) << message;
    EXPECT_NE(message.find("--levels 5"), std::string::npos) << message;
    VdbExportOptions coarse;
    coarse.levels = {5};
    EXPECT_EQ(exportCacheToVdb(view, out, coarse, nullptr, &message), VdbExportStatus::kOk) << message;
    std::remove(out.c_str());
}

// The refusal also names a length scale at which every level fits; written at it, each voxel's
// centre is the cache's, scaled, and the file says so.
TEST(VdbExportUnrepresentable, MicrometreVoxelsFitAtTheLengthScaleNamed) {
    openvdb::initialize();
    CacheData data;
    data.bake_capacity = 1024;
    data.level_bias = 14.0f;  // level 1: 2.44e-6 wide
    const HashGridParameters params = data.gridParameters();
    const Float3 p{1.0e-4f, 2.0e-4f, -3.0e-4f};
    data.voxels.push_back(CacheVoxel{hashGridKeyAtLevel(p, Float3{0, 1, 0}, 1, params), {1.0f, 1.0f, 1.0f}, 1.0f});
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(openInMemory(data, bytes, view));
    std::string message;
    const std::string out = ::testing::TempDir() + "sharcbake_scaled_" + std::to_string(::getpid()) + ".vdb";
    ASSERT_EQ(exportCacheToVdb(view, out, VdbExportOptions{}, nullptr, &message), VdbExportStatus::kUnrepresentable);
    const std::string named = "--length-scale ";
    const size_t at = message.find(named);
    ASSERT_NE(at, std::string::npos) << message;
    EXPECT_EQ(message.find("--levels"), std::string::npos) << message;  // no level fits unscaled
    VdbExportOptions scaled;
    scaled.length_scale = std::stod(message.substr(at + named.size()));
    EXPECT_GE(scaled.length_scale, 10.0);
    EXPECT_LE(scaled.length_scale, 1000.0);
    ASSERT_EQ(exportCacheToVdb(view, out, scaled, nullptr, &message), VdbExportStatus::kOk) << message;
    const auto [grid, meta] = readLevelOneRadianceAndRemove(out);
    ASSERT_TRUE(grid);
    ASSERT_EQ(grid->activeVoxelCount(), 1u);
    const openvdb::Vec3d centre = grid->indexToWorld(grid->cbeginValueOn().getCoord());
    const double size = double(voxelSize(1, params));
    EXPECT_NEAR(centre.x() / scaled.length_scale, double(p.x), 0.5 * size);
    EXPECT_NEAR(centre.y() / scaled.length_scale, double(p.y), 0.5 * size);
    EXPECT_NEAR(centre.z() / scaled.length_scale, double(p.z), 0.5 * size);
    EXPECT_NEAR(grid->voxelSize().x(), size * scaled.length_scale, 1e-6 * size * scaled.length_scale);
    EXPECT_EQ(meta->metaValue<double>("sharcbake_length_scale"), scaled.length_scale);
    // The grid's voxel size metadata is in VDB units, as its transform (a viewer's emission per
    // voxel width divides by it; it gave the scene's, 1/length_scale of that); the scene's own is
    // beside it.
    EXPECT_FLOAT_EQ(grid->metaValue<float>("sharcbake_voxel_size"), float(grid->voxelSize().x()));
    EXPECT_EQ(grid->metaValue<float>("sharcbake_scene_voxel_size"), float(size));
    EXPECT_NE(meta->metaValue<std::string>("units").find("one VDB unit is 1/"), std::string::npos);
    // Not finite or not positive: refused as a request.
    for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity()}) {
        scaled.length_scale = bad;
        EXPECT_EQ(exportCacheToVdb(view, out, scaled, nullptr, &message), VdbExportStatus::kInvalidArgument) << bad;
    }
}

// A room 10 km from the origin in 1 cm voxels: its cells lie near 10^6, beyond the 17 bits a key
// keeps. The file's anchor (ANCR) puts every voxel back in the room; decoded around the origin
// (as before the anchor) they landed up to 1.3 km away.
TEST(VdbExportFarFromTheOrigin, VoxelsStayInTheRoom) {
    openvdb::initialize();
    CacheData data;
    data.bake_capacity = 1024;
    data.level_bias = 1.0f - std::log2(data.scene_scale * 0.01f);  // level-1 voxels 1 cm wide
    data.grid_anchor = Float3{1.0e4f, 1.5f, -2.0f};
    const HashGridParameters params = data.gridParameters();
    ASSERT_NEAR(voxelSize(1, params), 0.01f, 1e-6f);
    for (int i = 0; i < 64; ++i) {
        const Float3 p{1.0e4f + 0.03f * float(i % 8) - 0.1f, 1.5f + 0.05f * float(i / 8), -2.0f + 0.02f * float(i)};
        data.voxels.push_back(CacheVoxel{hashGridKeyAtLevel(p, Float3{0, 1, 0}, 1, params), {1.0f, 1.0f, 1.0f}, 1.0f});
    }
    sortVoxels(data.voxels);
    data.voxels.erase(std::unique(data.voxels.begin(), data.voxels.end(),
                                  [](const CacheVoxel& a, const CacheVoxel& b) { return a.key == b.key; }),
                      data.voxels.end());
    std::vector<uint8_t> bytes;
    CacheView view;
    ASSERT_NO_FATAL_FAILURE(openInMemory(data, bytes, view));
    ASSERT_NE(decodeHashGridKey(data.voxels[0].key).grid.x, quantisePosition(data.grid_anchor, 0.01f).x);
    const std::string out = ::testing::TempDir() + "sharcbake_far_" + std::to_string(::getpid()) + ".vdb";
    std::string message;
    ASSERT_EQ(exportCacheToVdb(view, out, VdbExportOptions{}, nullptr, &message), VdbExportStatus::kOk) << message;
    const auto [grid, meta] = readLevelOneRadianceAndRemove(out);
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->activeVoxelCount(), data.voxels.size());
    for (auto it = grid->cbeginValueOn(); it; ++it) {
        const openvdb::Vec3d world = grid->indexToWorld(it.getCoord());
        EXPECT_NEAR(world.x(), 1.0e4, 0.2) << it.getCoord();
        EXPECT_NEAR(world.y(), 1.5 + 0.2, 0.25) << it.getCoord();
        EXPECT_NEAR(world.z(), -2.0 + 0.64, 0.7) << it.getCoord();
    }
    const openvdb::Vec3s anchor = meta->metaValue<openvdb::Vec3s>("sharcbake_grid_anchor");
    EXPECT_EQ(anchor.x(), 1.0e4f);
}

}  // namespace
}  // namespace sharcbake
