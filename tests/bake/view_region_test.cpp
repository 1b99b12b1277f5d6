// SPDX-License-Identifier: Apache-2.0
// Level coverage: --view-region parsing, the level each deposit goes to, the coarser levels built
// when the cache is written, and the level-bias fit to the scene's units.
#include "grid_fit.h"
#include "view_region.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <set>

using namespace sharcbake;

TEST(ViewRegion, ParsesEveryFormAndRefusesOthers) {
    EXPECT_EQ(parseViewRegion("free").kind, ViewRegion::Kind::FreeSpace);
    EXPECT_EQ(parseViewRegion("bake-camera").kind, ViewRegion::Kind::BakeCamera);
    const ViewRegion gltf = parseViewRegion("gltf");
    EXPECT_EQ(gltf.kind, ViewRegion::Kind::Points);
    EXPECT_EQ(gltf.source, "gltf");
    const ViewRegion box = parseViewRegion("box:1,2,3,-1,-2,-3");
    EXPECT_EQ(box.kind, ViewRegion::Kind::Box);
    EXPECT_EQ(box.box_min, glm::vec3(-1, -2, -3));
    EXPECT_EQ(box.box_max, glm::vec3(1, 2, 3));
    const ViewRegion near = parseViewRegion("distance:0.5");
    EXPECT_EQ(near.min_distance, 0.5f);
    EXPECT_EQ(near.max_distance, 0.0f);
    const ViewRegion range = parseViewRegion("distance:0.5:20");
    EXPECT_EQ(range.max_distance, 20.0f);
    for (const char* bad : {"", "everywhere", "box:1,2,3", "box:1,2,3,4,5,nan", "distance:0", "distance:-1",
                            "distance:5:2", "distance:1:2:3", "box:1,2,3,4,5,6,7"}) {
        EXPECT_THROW(parseViewRegion(bad), std::invalid_argument) << bad;
    }
}

TEST(DepositLevels, EachRegionPicksTheFinestLevelItsCamerasAskFor) {
    HashGridParameters grid;  // base 2, scale 50, bias 0: level L from distance 2^L
    const glm::vec3 lo(-10.0f), hi(10.0f);
    const Float3 bake_camera{0.0f, 0.0f, 0.0f};
    const glm::vec3 p(5.0f, 0.0f, 0.0f), n(0.0f, 1.0f, 0.0f);
    const auto level = [&](const DepositLevels& levels) { return decodeHashGridKey(levels.key(p, n, bake_camera)).level; };

    const DepositLevels free(grid, ViewRegion{}, lo, hi);
    EXPECT_EQ(level(free), 1u);
    EXPECT_EQ(free.finestLevel(), 1u);
    // Free space covers cameras far outside the scene: up to voxels twice its size.
    EXPECT_GE(voxelSize(free.coarsestLevel(), grid), 2.0f * glm::length(hi - lo));
    EXPECT_LT(voxelSize(free.coarsestLevel() - 1, grid), 2.0f * glm::length(hi - lo));

    ViewRegion distance = parseViewRegion("distance:9");  // level floor(log2 9) = 3
    EXPECT_EQ(level(DepositLevels(grid, distance, lo, hi)), 3u);
    distance = parseViewRegion("distance:9:40");
    EXPECT_EQ(DepositLevels(grid, distance, lo, hi).coarsestLevel(), 5u);  // 40.4 -> level 5

    ViewRegion points;
    points.kind = ViewRegion::Kind::Points;
    points.points = {glm::vec3(5.0f, 17.0f, 0.0f), glm::vec3(-9.0f, 0.0f, 0.0f)};  // 17 and 14 away
    EXPECT_EQ(level(DepositLevels(grid, points, lo, hi)), 3u);                   // floor(log2 14) = 3

    const ViewRegion box = parseViewRegion("box:4,-1,-1,6,1,1");  // holds p: finest level
    EXPECT_EQ(level(DepositLevels(grid, box, lo, hi)), 1u);
    const ViewRegion far_box = parseViewRegion("box:-1,40,-1,1,50,1");  // ~40 away: level 5
    EXPECT_EQ(level(DepositLevels(grid, far_box, lo, hi)), 5u);

    ViewRegion sdk;
    sdk.kind = ViewRegion::Kind::BakeCamera;
    const DepositLevels camera_only(grid, sdk, lo, hi);
    EXPECT_EQ(level(camera_only), 2u);  // 5 from the bake camera
    EXPECT_EQ(camera_only.coarsestLevel(), 0u);
}

namespace {

CacheData dataWith(std::vector<CacheVoxel> voxels) {
    CacheData data;
    data.voxels = std::move(voxels);
    return data;
}

CacheVoxel voxel(uint64_t key, float r, float g, float b, float weight) {
    CacheVoxel v;
    v.key = key;
    v.radiance[0] = r;
    v.radiance[1] = g;
    v.radiance[2] = b;
    v.sample_weight = weight;
    return v;
}

}  // namespace

TEST(AddCoarserLevels, CoarseVoxelsAreTheWeightedMeansOfTheFineOnes) {
    // Four level-1 voxels: three share a level-2 parent (x 0, 1 -> 0; y 0, 1 -> 0), one is apart,
    // one has another normal octant. A deposit made directly at level 2 joins its children.
    const uint64_t a = packHashGridKey(Int3{0, 0, 0}, 1, 0);
    const uint64_t b = packHashGridKey(Int3{1, 1, 0}, 1, 0);
    const uint64_t c = packHashGridKey(Int3{-1, 0, 0}, 1, 0);  // parent x = -1
    const uint64_t d = packHashGridKey(Int3{0, 0, 0}, 1, 2);   // other normal octant
    const uint64_t direct = packHashGridKey(Int3{0, 0, 0}, 2, 0);
    CacheData data = dataWith({voxel(a, 1, 2, 3, 1), voxel(b, 3, 2, 1, 3), voxel(c, 5, 5, 5, 2), voxel(d, 7, 7, 7, 1),
                               voxel(direct, 10, 10, 10, 4)});
    addCoarserLevels(data, 3);
    std::map<uint64_t, CacheVoxel> by_key;
    for (const CacheVoxel& v : data.voxels) by_key[v.key] = v;
    EXPECT_TRUE(std::is_sorted(data.voxels.begin(), data.voxels.end(),
                               [](const CacheVoxel& x, const CacheVoxel& y) { return x.key < y.key; }));
    // Level 2, octant 0, cell 0: a, b and the direct deposit.
    const CacheVoxel& parent = by_key.at(direct);
    EXPECT_FLOAT_EQ(parent.sample_weight, 8.0f);
    EXPECT_FLOAT_EQ(parent.radiance[0], (1 * 1 + 3 * 3 + 10 * 4) / 8.0f);
    EXPECT_FLOAT_EQ(parent.radiance[2], (3 * 1 + 1 * 3 + 10 * 4) / 8.0f);
    EXPECT_FLOAT_EQ(by_key.at(packHashGridKey(Int3{-1, 0, 0}, 2, 0)).radiance[0], 5.0f);
    EXPECT_FLOAT_EQ(by_key.at(packHashGridKey(Int3{0, 0, 0}, 2, 2)).radiance[0], 7.0f);
    // Level 3: cells 0 and -1 of level 2 have parents 0 and -1.
    EXPECT_FLOAT_EQ(by_key.at(packHashGridKey(Int3{0, 0, 0}, 3, 0)).sample_weight, 8.0f);
    EXPECT_FLOAT_EQ(by_key.at(packHashGridKey(Int3{-1, 0, 0}, 3, 0)).sample_weight, 2.0f);
    EXPECT_EQ(data.voxels.size(), 5u + 3u + 3u - 1u);  // the direct level-2 voxel was already there
    EXPECT_FALSE(by_key.count(packHashGridKey(Int3{0, 0, 0}, 4, 0)));  // not beyond the coarsest level
}

TEST(AddCoarserLevels, DoesNotDependOnTheInputOrder) {
    std::mt19937 rng(23);
    std::uniform_int_distribution<int32_t> cell(-40, 40);
    std::uniform_real_distribution<float> value(0.0f, 3.0f);
    std::vector<CacheVoxel> voxels;
    std::set<uint64_t> keys;
    while (voxels.size() < 3000) {
        const uint64_t key = packHashGridKey(Int3{cell(rng), cell(rng), cell(rng)}, 1, uint32_t(cell(rng)) & 7u);
        if (keys.insert(key).second) voxels.push_back(voxel(key, value(rng), value(rng), value(rng), 1.0f + value(rng)));
    }
    CacheData sorted = dataWith(voxels);
    std::shuffle(voxels.begin(), voxels.end(), rng);
    CacheData shuffled = dataWith(voxels);
    addCoarserLevels(sorted, 6);
    addCoarserLevels(shuffled, 6);
    ASSERT_EQ(sorted.voxels.size(), shuffled.voxels.size());
    for (size_t i = 0; i < sorted.voxels.size(); ++i) {
        ASSERT_EQ(sorted.voxels[i].key, shuffled.voxels[i].key);
        ASSERT_EQ(std::memcmp(&sorted.voxels[i], &shuffled.voxels[i], sizeof(CacheVoxel)), 0);
    }
    // Total weight is kept on every level.
    std::map<uint32_t, double> weight;
    for (const CacheVoxel& v : sorted.voxels) weight[decodeHashGridKey(v.key).level] += v.sample_weight;
    for (uint32_t level = 2; level <= 6; ++level) EXPECT_NEAR(weight[level], weight[1], 1e-6 * weight[1]);
}

namespace {

/// A square of side `size` (two triangles) in the plane y = 0, single-sided.
Scene square(float size) {
    Scene scene;
    scene.positions = {{0, 0, 0}, {size, 0, 0}, {size, 0, size}, {0, 0, size}};
    scene.triangles = {{0, 2, 1}, {0, 3, 2}};
    scene.materials.resize(1);
    scene.triangle_materials = {0, 0};
    scene.bounds_min = glm::vec3(0.0f);
    scene.bounds_max = glm::vec3(size, 0.0f, size);
    return scene;
}

}  // namespace

TEST(GridFit, TheFinestLevelHoldsTheSurfaceInTheBudgetInAnyUnits) {
    const HashGridParameters grid;
    for (const float size : {1e-3f, 1.0f, 1e3f}) {
        const Scene scene = square(size);
        const GridFit fit = fitLevelBias(scene, grid, 1u << 16);
        EXPECT_NEAR(fit.surface_area, double(size) * size, 1e-6 * double(size) * size);
        // At most the budget, and within the 1/64 rounding of the bias (2^(1/64) in size).
        EXPECT_LE(fit.estimated_voxels, double(1u << 16) * 1.0001);
        EXPECT_GE(fit.estimated_voxels, double(1u << 16) / std::pow(2.0, 2.0 / 64.0) * 0.9999);
        EXPECT_FALSE(fit.limited_by_range);
        HashGridParameters fitted = grid;
        fitted.level_bias = fit.level_bias;
        EXPECT_EQ(voxelSize(1, fitted), fit.finest_voxel_size);
        EXPECT_EQ(fit.level_bias * 64.0f, std::floor(fit.level_bias * 64.0f));
        EXPECT_TRUE(checkGridForScene(scene, fitted, 1, 1u << 16).empty()) << size;
    }
    // The same scene 1000x larger needs a bias log2(1000) smaller.
    EXPECT_NEAR(fitLevelBias(square(1.0f), grid, 1u << 16).level_bias -
                    fitLevelBias(square(1e3f), grid, 1u << 16).level_bias,
                std::log2(1000.0), 1.0 / 32.0);
}

TEST(GridFit, FarFromTheOriginTheGridRangeWins) {
    Scene scene = square(1.0f);
    for (glm::vec3& p : scene.positions) p += glm::vec3(1e6f, 0.0f, 0.0f);
    scene.bounds_min += glm::vec3(1e6f, 0.0f, 0.0f);
    scene.bounds_max += glm::vec3(1e6f, 0.0f, 0.0f);
    const GridFit fit = fitLevelBias(scene, HashGridParameters{}, 1u << 16);
    EXPECT_TRUE(fit.limited_by_range);
    EXPECT_LT(1e6f / fit.finest_voxel_size, 65536.0f);
    EXPECT_NE(fit.reason.find("17-bit"), std::string::npos);
}

TEST(GridFit, WrongUnitsAreWarnedAbout) {
    const HashGridParameters sdk;  // bias 0: 4 cm voxels near the camera
    EXPECT_FALSE(checkGridForScene(square(0.01f), sdk, 1, 1u << 17).empty());  // 1 cm: a voxel or two
    EXPECT_FALSE(checkGridForScene(square(1e5f), sdk, 1, 1u << 17).empty());   // 100 km in 4 cm voxels
    EXPECT_TRUE(checkGridForScene(square(20.0f), sdk, 1, 1u << 17).empty());
}

TEST(GridFit, SceneScalesFarFromSharcsMeaningAreWarnedAbout) {
    EXPECT_FALSE(checkSceneScale(0.05f).empty());
    EXPECT_FALSE(checkSceneScale(1e5f).empty());
    EXPECT_TRUE(checkSceneScale(50.0f).empty());
    EXPECT_TRUE(checkSceneScale(5.0f).empty());
}
