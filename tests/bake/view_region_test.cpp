// SPDX-License-Identifier: Apache-2.0
// Level coverage: --view-region parsing, the level each deposit goes to, the coarser levels built
// when the cache is written, and the level-bias fit to the scene's units.
#include "sharc/grid_fit.h"
#include "sharc/view_region.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
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
    // A box beyond +-1e9 (rays from inside it failed Embree's ray.valid() assertion) is refused,
    // naming free for cameras anywhere; one at the limit is a box.
    try {
        parseViewRegion("box:-1e30,-1e30,-1e30,1e30,1e30,1e30");
        ADD_FAILURE() << "a box to 1e30 was accepted";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("beyond +-1e9"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("give free"), std::string::npos) << e.what();
    }
    EXPECT_EQ(parseViewRegion("box:-1e9,-1e9,-1e9,1e9,1e9,1e9").kind, ViewRegion::Kind::Box);
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

    // Cache feedback reads the bake camera's own level (here 2), but never below the deposits'.
    EXPECT_EQ(decodeHashGridKey(free.feedbackKey(p, n, bake_camera)).level, 2u);
    EXPECT_EQ(decodeHashGridKey(DepositLevels(grid, parseViewRegion("distance:9"), lo, hi).feedbackKey(p, n, bake_camera)).level,
              3u);
    EXPECT_EQ(decodeHashGridKey(free.feedbackKey(p, n, Float3{1e6f, 0.0f, 0.0f})).level, free.coarsestLevel());

    ViewRegion sdk;
    sdk.kind = ViewRegion::Kind::BakeCamera;
    const DepositLevels camera_only(grid, sdk, lo, hi);
    EXPECT_EQ(level(camera_only), 2u);  // 5 from the bake camera
    EXPECT_EQ(camera_only.coarsestLevel(), 0u);
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

namespace {

Scene moved(Scene scene, glm::vec3 offset) {
    for (glm::vec3& p : scene.positions) p += offset;
    scene.bounds_min += offset;
    scene.bounds_max += offset;
    return scene;
}

}  // namespace

// Keys decode near an anchor at the scene's centre (HashGridKeyDecoder), so a scene away from the
// origin keeps its voxels while float32 resolves them there (20 float steps a voxel); beyond,
// float precision decides.
TEST(GridFit, FarFromTheOriginFloatPrecisionWins) {
    const GridFit home = fitLevelBias(square(1.0f), HashGridParameters{}, 1u << 16);
    EXPECT_EQ(gridAnchorFor(square(1.0f), home.finest_voxel_size).x, 0.0f);  // the origin: no ANCR section
    const Scene away_scene = moved(square(1.0f), glm::vec3(1e3f, 0.0f, 0.0f));
    const GridFit away = fitLevelBias(away_scene, HashGridParameters{}, 1u << 16);
    EXPECT_FALSE(away.limited_by_range);
    EXPECT_EQ(away.level_bias, home.level_bias);
    EXPECT_GT(1e3f / away.finest_voxel_size, 65536.0f);  // beyond the 17 bits: decoded near the anchor
    EXPECT_EQ(gridAnchorFor(away_scene, away.finest_voxel_size).x,
              1e3f + 0.5f * (square(1.0f).bounds_min.x + square(1.0f).bounds_max.x));
    const GridFit far = fitLevelBias(moved(square(1.0f), glm::vec3(1e6f, 0.0f, 0.0f)), HashGridParameters{}, 1u << 16);
    EXPECT_TRUE(far.limited_by_range);
    EXPECT_EQ(far.range_limit, GridFit::RangeLimit::kFloatPrecision);
    EXPECT_GE(far.finest_voxel_size, 20.0f * 0.0625f);  // float32 spacing at 1e6
    EXPECT_NE(far.reason.find("float32"), std::string::npos) << far.reason;
}

// A strip 200 km long and 1 m wide: 2^16 voxels each way from its centre allow 1.7 m voxels,
// though the budget would give 0.2 m.
TEST(GridFit, ALongSceneIsLimitedByTheGridRange) {
    Scene strip = square(1.0f);
    for (glm::vec3& p : strip.positions) p.x *= 2e5f;
    strip.bounds_min.x *= 2e5f;
    strip.bounds_max.x *= 2e5f;
    const GridFit fit = fitLevelBias(strip, HashGridParameters{}, 1u << 22);
    EXPECT_TRUE(fit.limited_by_range);
    EXPECT_EQ(fit.range_limit, GridFit::RangeLimit::kSceneSize);
    EXPECT_GE(fit.finest_voxel_size, 0.5f * (strip.bounds_max.x - strip.bounds_min.x) / 65536.0f);
    EXPECT_NE(fit.reason.find("17-bit"), std::string::npos) << fit.reason;
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

namespace {

/// The voxels a square ground of side `size` in y = 0 takes where each point is at the level a
/// camera at `camera` asks for there: a sum over 1 x 1 cells (the fit's estimate, by another road).
double groundVoxelsFromCamera(float size, glm::vec3 camera, HashGridParameters grid, float level_bias) {
    grid.level_bias = level_bias;
    const HashGridKeyer keyer(grid);
    const int cells = int(size);
    double voxels = 0.0;
    for (int i = 0; i < cells; ++i) {
        for (int j = 0; j < cells; ++j) {
            const glm::vec3 p(float(i) + 0.5f, 0.0f, float(j) + 0.5f);
            const double voxel = double(keyer.voxelSizeAt(keyer.levelOf(glm::dot(p - camera, p - camera))));
            voxels += 1.0 / (voxel * voxel);
        }
    }
    return voxels * double(size) * double(size) / (double(cells) * double(cells));
}

}  // namespace

TEST(GridFit, CamerasKeptToPlacesGetTheFinestVoxelsTheirDistancesAllow) {
    // A camera 1.7 m above a ground 2 km wide: level 1 for all of it would be 5.5 m voxels; the
    // camera asks for level 1 only near it.
    const float size = 2000.0f;
    const Scene scene = square(size);
    const HashGridParameters grid;
    const GridFit anywhere = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    ViewRegion one_camera;
    one_camera.kind = ViewRegion::Kind::Points;
    one_camera.points = {glm::vec3(1000.0f, 1.7f, 1000.0f)};
    const GridFit near = fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &one_camera);
    EXPECT_FALSE(anywhere.fitted_to_view_distances);
    EXPECT_TRUE(near.fitted_to_view_distances);
    EXPECT_GT(anywhere.finest_voxel_size, 5.0f);
    EXPECT_LT(near.finest_voxel_size, anywhere.finest_voxel_size / 4.0f);
    EXPECT_NE(near.reason.find("at the levels the view region's cameras ask for"), std::string::npos) << near.reason;
    // The estimate is what the camera's levels take, summed cell by cell; and it fits the budget.
    const double counted = groundVoxelsFromCamera(size, one_camera.points[0], grid, near.level_bias);
    std::printf(
        "[grid fit] 2 km ground, one camera: finest voxels %.3g (level 1 everywhere: %.3g), estimated %.4g "
        "voxels, counted %.4g\n",
        double(near.finest_voxel_size), double(anywhere.finest_voxel_size), near.estimated_voxels, counted);
    EXPECT_NEAR(near.estimated_voxels, counted, 0.1 * counted);
    EXPECT_LE(counted, 1.1 * double(kDefaultVoxelBudget));
    // A 1/64 finer bias would not fit.
    EXPECT_GT(groundVoxelsFromCamera(size, one_camera.points[0], grid, near.level_bias + 1.0f / 64.0f),
              0.9 * double(kDefaultVoxelBudget));

    // A box region around the same place: the same kind of fit.
    ViewRegion box;
    box.kind = ViewRegion::Kind::Box;
    box.box_min = glm::vec3(990.0f, 1.0f, 990.0f);
    box.box_max = glm::vec3(1010.0f, 2.0f, 1010.0f);
    const GridFit in_box = fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &box);
    EXPECT_TRUE(in_box.fitted_to_view_distances);
    EXPECT_LT(in_box.finest_voxel_size, anywhere.finest_voxel_size / 2.0f);
    EXPECT_GE(in_box.finest_voxel_size, near.finest_voxel_size);  // more ground near its cameras

    // Free space and the bake camera's own levels keep the fit of level 1 everywhere.
    for (const ViewRegion::Kind kind : {ViewRegion::Kind::FreeSpace, ViewRegion::Kind::BakeCamera}) {
        ViewRegion region;
        region.kind = kind;
        EXPECT_EQ(fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &region).level_bias, anywhere.level_bias);
    }
    // A camera 100 m above a 10 m square asks for level 1 nowhere: beyond level 1's reach the
    // count no longer grows with the bias, and the fit keeps level 1 for all of it (2.8 cm voxels)
    // instead of running on to the grid range.
    ViewRegion high;
    high.kind = ViewRegion::Kind::Points;
    high.points = {glm::vec3(5.0f, 100.0f, 5.0f)};
    const GridFit from_high = fitLevelBias(square(10.0f), grid, kDefaultVoxelBudget, nullptr, &high);
    EXPECT_EQ(from_high.level_bias, fitLevelBias(square(10.0f), grid, kDefaultVoxelBudget).level_bias);
    EXPECT_FALSE(from_high.limited_by_range);
    // Cameras kept 1 m away from everything already use level 1 within 1 m: nothing finer fits.
    ViewRegion distance;
    distance.kind = ViewRegion::Kind::Distance;
    distance.min_distance = 1.0f;
    EXPECT_EQ(fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &distance).level_bias, anywhere.level_bias);
}
