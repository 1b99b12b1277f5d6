// SPDX-License-Identifier: Apache-2.0
// Free-space exploration (the default roaming camera) on rooms as other tools write them: walls
// wound outwards (a cube scaled up into a room), double-sided or not, with and without a glTF
// camera, and closed objects inside the room that the camera must not enter; and a lone object
// under the sky, which the camera also looks at from around.
#include "sharc/camera_path.h"
#include "sharc/baker.h"
#include "sharc/coverage.h"
#include "sharc/grid_fit.h"
#include "sharc/hit_rate.h"
#include "sharcbake/scene_loader.h"
#include "tracing/lights.h"
#include "tracing/sampling.h"
#include "tracing/tracer.h"

#include "gltf_builder.h"
#include "test_bake_scene.h"
#include "test_rooms.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <optional>
#include <set>
#include <tuple>
#include <utility>

namespace sharcbake {
namespace {

/// The 12 triangles of an axis-aligned box from `lo` to `hi`, wound outwards (seen from outside,
/// counter-clockwise), or inwards with `inwards`; with `split` > 1, each face is split into
/// split x split quads (2 split^2 triangles).
void addBox(std::vector<float>& positions, std::vector<uint32_t>& indices, glm::vec3 lo, glm::vec3 hi, bool inwards,
            uint32_t split = 1) {
    const auto corner = [&](int c) {
        return glm::vec3((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
    };
    // Each face's corners counter-clockwise seen from outside.
    const int faces[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (const auto& f : faces) {
        const uint32_t base = uint32_t(positions.size() / 3);
        const glm::vec3 origin = corner(f[0]), u = corner(f[1]) - origin, v = corner(f[3]) - origin;
        for (uint32_t j = 0; j <= split; ++j) {
            for (uint32_t i = 0; i <= split; ++i) {
                const glm::vec3 p = origin + (float(i) / float(split)) * u + (float(j) / float(split)) * v;
                positions.insert(positions.end(), {p.x, p.y, p.z});
            }
        }
        for (uint32_t j = 0; j < split; ++j) {
            for (uint32_t i = 0; i < split; ++i) {
                const uint32_t q0 = base + j * (split + 1) + i, q1 = q0 + 1, q3 = q0 + split + 1, q2 = q3 + 1;
                const uint32_t quad[6] = {q0, q1, q2, q0, q2, q3};
                for (int k = 0; k < 6; ++k) indices.push_back(quad[inwards ? 5 - k : k]);
            }
        }
    }
}

struct RoomOptions {
    bool double_sided = false;
    bool walls_inwards = false;
    bool camera = true;
    bool closed_cube = false;  ///< a closed 1 m cube (wound outwards) on the floor
    float ground_half = 0.0f;  ///< > 0: a ground plane this far out each way, facing up, under the room
    bool box_outside = false;  ///< a closed 2 m box (wound outwards) 4 m beyond the +X wall: nothing reaches it
    uint32_t split = 1;        ///< each wall split into split x split quads (a finely meshed room)
    bool lamp = false;         ///< a small emissive panel (30 cm) under the ceiling, facing down
};

constexpr glm::vec3 kRoomMin{-2.0f, 0.0f, -2.5f}, kRoomMax{2.0f, 3.0f, 2.5f};
constexpr glm::vec3 kCubeMin{0.5f, 0.0f, -1.5f}, kCubeMax{1.5f, 1.0f, -0.5f};
constexpr glm::vec3 kOutsideMin{6.0f, 0.0f, -1.0f}, kOutsideMax{8.0f, 2.0f, 1.0f};
constexpr glm::vec3 kLampCenter{-1.0f, 2.9f, 1.0f};

Scene loadRoom(const test::TempDir& dir, const RoomOptions& options) {
    test::GltfBuilder gltf;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addBox(positions, indices, kRoomMin, kRoomMax, options.walls_inwards, options.split);
    if (options.closed_cube) addBox(positions, indices, kCubeMin, kCubeMax, false);
    if (options.box_outside) addBox(positions, indices, kOutsideMin, kOutsideMax, false);
    if (options.ground_half > 0.0f) {
        const float h = options.ground_half, y = kRoomMin.y - 0.01f;
        const uint32_t base = uint32_t(positions.size() / 3);
        for (const glm::vec2 corner : {glm::vec2(-h, -h), glm::vec2(-h, h), glm::vec2(h, h), glm::vec2(h, -h)}) {
            positions.insert(positions.end(), {corner.x, y, corner.y});
        }
        for (const uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) indices.push_back(base + k);  // facing +Y
    }
    const int material = gltf.addMaterial(
        {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}, {"doubleSided", options.double_sided}});
    nlohmann::json primitives = nlohmann::json::array(
        {{{"attributes", {{"POSITION", gltf.addPositions(positions)}}},
          {"indices", gltf.addData(indices, test::kUnsignedInt, "SCALAR")},
          {"material", material}}});
    if (options.lamp) {
        std::vector<float> lamp;
        for (const glm::vec2 corner : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
            const glm::vec3 p = kLampCenter + 0.15f * glm::vec3(corner.x, 0.0f, corner.y);
            lamp.insert(lamp.end(), {p.x, p.y, p.z});
        }
        const std::vector<uint32_t> lamp_indices{0, 1, 2, 0, 2, 3};  // facing -Y, at the floor
        const int emissive = gltf.addMaterial(
            {{"emissiveFactor", {1.0, 1.0, 1.0}},
             {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 20.0}}}}},
             {"doubleSided", options.double_sided}});
        primitives.push_back({{"attributes", {{"POSITION", gltf.addPositions(lamp)}}},
                              {"indices", gltf.addData(lamp_indices, test::kUnsignedInt, "SCALAR")},
                              {"material", emissive}});
    }
    const int mesh = gltf.addMesh(primitives);
    std::vector<int> roots{gltf.addNode({{"mesh", mesh}})};
    if (options.camera) {
        gltf.doc["cameras"] = nlohmann::json::array(
            {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.01}}}}});
        roots.push_back(gltf.addNode({{"camera", 0}, {"translation", {-1.0, 1.6, 1.8}}}));
    }
    gltf.setScene(roots);
    return loadGltf(gltf.writeEmbedded(dir, "room.gltf"));
}

bool inside(glm::vec3 p, glm::vec3 lo, glm::vec3 hi) {
    return p.x > lo.x && p.x < hi.x && p.y > lo.y && p.y < hi.y && p.z > lo.z && p.z < hi.z;
}

struct Explored {
    ExplorationResult result;
    bool has_path = false;
    std::vector<CameraPose> waypoints;  ///< the exploring camera's path
};

Explored explore(const Scene& scene) {
    const Tracer tracer(scene);
    Explored out;
    const std::optional<CameraPath> path = exploringCameraPath(tracer, scene, 32, 7, &out.result);
    out.has_path = path.has_value();
    if (path) out.waypoints = path->waypoints();
    return out;
}

/// Every explored point, and every waypoint of the path, lies inside the room, none inside the
/// cube, and there are enough of them.
void expectPointsFillTheRoom(const Explored& e, const char* what) {
    ASSERT_TRUE(e.has_path) << what;
    EXPECT_EQ(e.result.points.size(), 32u) << what;
    std::vector<glm::vec3> positions = e.result.points;
    for (const CameraPose& pose : e.waypoints) positions.push_back(pose.position);
    for (const glm::vec3& p : positions) {
        EXPECT_TRUE(inside(p, kRoomMin, kRoomMax)) << what << ": (" << p.x << ", " << p.y << ", " << p.z << ")";
        EXPECT_FALSE(inside(p, kCubeMin, kCubeMax)) << what << ": (" << p.x << ", " << p.y << ", " << p.z << ")";
    }
}

TEST(ExploreFreeSpace, RoomWoundInwardsUsesTheWinding) {
    test::TempDir dir;
    const Explored e = explore(loadRoom(dir, {false, true, true, true}));
    expectPointsFillTheRoom(e, "single-sided room wound inwards");
    EXPECT_FALSE(e.result.winding_ignored);
    // The winding alone rejects the cube's inside: fewer candidates are free than with it ignored.
    EXPECT_LT(e.result.free, e.result.candidates);
}

TEST(ExploreFreeSpace, DoubleSidedRoomWoundOutwardsIsExplored) {
    // Blender's default: backface culling off, so doubleSided; a room made from a scaled cube
    // keeps its normals pointing out. Before, every point inside counted as inside a solid.
    test::TempDir dir;
    const Explored e = explore(loadRoom(dir, {true, false, true, true}));
    expectPointsFillTheRoom(e, "double-sided room wound outwards");
    EXPECT_FALSE(e.result.winding_ignored);  // double-sided faces do not vote
}

TEST(ExploreFreeSpace, SingleSidedRoomWoundOutwardsTrustsTheCamera) {
    test::TempDir dir;
    const Explored e = explore(loadRoom(dir, {false, false, true, true}));
    expectPointsFillTheRoom(e, "single-sided room wound outwards, with a camera");
    EXPECT_TRUE(e.result.winding_ignored);
    EXPECT_EQ(e.result.cameras_in_solids, std::vector<uint32_t>{0});  // the bake names it
}

TEST(ExploreFreeSpace, ACameraInsideAClosedObjectIsNamed) {
    // A room wound inwards, its camera, and a second camera inside the closed cube by mistake: the
    // winding puts that one in a solid, is ignored for the scene, and the bake's Camera line names
    // the camera instead of "a glTF camera".
    test::TempDir dir;
    Scene scene = loadRoom(dir, {false, true, true, true});
    Camera stray;
    stray.position = 0.5f * (kCubeMin + kCubeMax);
    scene.cameras.push_back(stray);
    const Explored e = explore(scene);
    ASSERT_TRUE(e.has_path);
    EXPECT_TRUE(e.result.winding_ignored);
    EXPECT_EQ(e.result.cameras_in_solids, std::vector<uint32_t>{1});
    // Without the stray camera the winding holds, and no camera is named.
    const Explored room = explore(loadRoom(dir, {false, true, true, true}));
    EXPECT_FALSE(room.result.winding_ignored);
    EXPECT_TRUE(room.result.cameras_in_solids.empty());
}

TEST(ExploreFreeSpace, SingleSidedRoomWoundOutwardsWithoutACameraIsExplored) {
    // No camera: the start is the room's centre, which the winding puts inside a solid, as it
    // does every other point; the winding is then ignored and reachability decides. The lamp
    // says it is a room: without light inside, it is the dark inside of a closed object
    // (TheDarkInsideOfAClosedModelIsSeenFromAround).
    test::TempDir dir;
    RoomOptions options{false, false, false, true};
    options.lamp = true;
    const Explored e = explore(loadRoom(dir, options));
    expectPointsFillTheRoom(e, "single-sided room wound outwards, no camera");
    EXPECT_TRUE(e.result.winding_ignored);
    EXPECT_FALSE(e.result.dark_enclosure);
}

TEST(ExploreFreeSpace, AClosedRoomBesideALargeGroundPlaneIsExploredFromItsCamera) {
    // A 4 m room and its camera beside a 10 km site: random points in the bounds almost never
    // fall inside the room, and the camera stayed at its one position (1 of 513 points), leaving
    // the room's far side unreached. Points around the camera at shrinking scales fill the room.
    test::TempDir dir;
    RoomOptions options{false, true, true, true};
    options.ground_half = 5000.0f;
    const Explored e = explore(loadRoom(dir, options));
    expectPointsFillTheRoom(e, "closed room beside a 10 km ground plane");
}

/// The surface the exploring camera's waypoints (32 points, seed 7) see, as the bake estimates
/// it for the grid fit.
SeenSurface seenByExploringCamera(const Scene& scene) {
    const Tracer tracer(scene);
    const CameraPath path = exploringCameraPath(tracer, scene, 32, 7).value();
    std::vector<glm::vec3> viewpoints;
    for (const CameraPose& pose : path.waypoints()) viewpoints.push_back(pose.position);
    return surfaceSeenFrom(tracer, viewpoints, 4096, 0);
}

TEST(GridFit, ARoomBesideALargeGroundPlaneIsFittedToWhatItsCamerasSee) {
    // The whole visible surface (1e8 m^2 of ground) in the voxel budget gave 27 m voxels, so every
    // lookup from the room's camera was refused (each bounce shorter than its voxel).
    test::TempDir dir;
    RoomOptions options{false, true, true, false};
    options.ground_half = 5000.0f;
    const Scene scene = loadRoom(dir, options);
    const SeenSurface seen = seenByExploringCamera(scene);
    const glm::vec3 size = kRoomMax - kRoomMin;
    const double room_area = 2.0 * (size.x * size.y + size.x * size.z + size.y * size.z);  // 94 m^2, inside
    EXPECT_NEAR(seen.area, room_area, 1e-3 * room_area);  // every wall's triangles are hit; the ground never
    EXPECT_LT(seen.fraction, 1e-5);

    const HashGridParameters grid{};
    const GridFit whole = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    const GridFit fitted = fitLevelBias(scene, grid, kDefaultVoxelBudget, &seen);
    EXPECT_FALSE(whole.fitted_to_seen);
    EXPECT_GT(whole.finest_voxel_size, 20.0f);
    EXPECT_TRUE(fitted.fitted_to_seen);
    EXPECT_DOUBLE_EQ(fitted.scene_surface_area, whole.surface_area);
    // The room's 94 m^2 in the budget would be 2.7 cm voxels; the 17-bit grid range around the
    // ground's 5 km corner allows 8.5 cm, which still serves the room.
    EXPECT_LT(fitted.finest_voxel_size, 0.1f);
    EXPECT_TRUE(fitted.limited_by_range);
    EXPECT_NE(fitted.reason.find("out of its sight"), std::string::npos) << fitted.reason;
}

TEST(GridFit, VoxelsWiderThanTheRoomAroundACameraAreWarnedAboutWithTheFix) {
    // A room on a ground 2 km wide whose roaming camera gets out (a window: the fit counts the whole
    // surface, not the room's): 5.6 m voxels around a camera whose walls are 2 m away.
    test::TempDir dir;
    RoomOptions options{false, true, true, false};
    options.ground_half = 1000.0f;
    const Scene scene = loadRoom(dir, options);
    const Tracer tracer(scene);
    const HashGridParameters grid{};
    GridFit whole = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    EXPECT_GT(whole.finest_voxel_size, 5.0f);
    HashGridParameters fitted = grid;
    fitted.level_bias = whole.level_bias;
    const ViewRegion free;
    const std::string warning = checkVoxelsAroundCameras(tracer, fitted, free, &whole, kDefaultVoxelBudget, nullptr);
    EXPECT_NE(warning.find("the voxels around camera"), std::string::npos) << warning;
    EXPECT_NE(warning.find("wide, are wider than 1/8 of the distance to what it sees"), std::string::npos) << warning;
    EXPECT_NE(warning.find("--view-region gltf"), std::string::npos) << warning;
    // With the glTF cameras as the region, the fix is the budget that makes the voxels fine enough.
    ViewRegion at_camera;
    at_camera.kind = ViewRegion::Kind::Points;
    at_camera.points = {scene.cameras[0].position};
    const GridFit near = fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &at_camera);
    fitted.level_bias = near.level_bias;
    const std::string region_warning = checkVoxelsAroundCameras(tracer, fitted, at_camera, &near, kDefaultVoxelBudget,
                                                                nullptr);
    EXPECT_NE(region_warning.find("--voxel-budget"), std::string::npos) << region_warning;
    EXPECT_NE(region_warning.find("makes them"), std::string::npos) << region_warning;
    EXPECT_EQ(region_warning.find("--view-region gltf"), std::string::npos) << region_warning;
    // A bias given by hand: the fix is a bias, whose voxels are fine enough.
    fitted.level_bias = whole.level_bias;
    const std::string hand = checkVoxelsAroundCameras(tracer, fitted, free, nullptr, kDefaultVoxelBudget, nullptr);
    EXPECT_NE(hand.find("because of --level-bias"), std::string::npos) << hand;
    EXPECT_NE(hand.find("or --level-bias auto"), std::string::npos) << hand;
    // The same room alone: voxels of a few centimetres, nothing to say.
    test::TempDir alone_dir;
    const Scene alone = loadRoom(alone_dir, {false, true, true, false});
    const Tracer alone_tracer(alone);
    const GridFit room_fit = fitLevelBias(alone, grid, kDefaultVoxelBudget);
    fitted.level_bias = room_fit.level_bias;
    EXPECT_EQ(checkVoxelsAroundCameras(alone_tracer, fitted, free, &room_fit, kDefaultVoxelBudget, nullptr), "");
}

/// A 4 m room `distance` from the origin along x, with a camera inside, and its fit.
struct FarRoom {
    Scene scene = emptyTestScene();
    GridFit fit;
    std::string warning;
    explicit FarRoom(float distance) {
        scene.materials.emplace_back();
        const glm::vec3 offset(distance, 0.0f, 0.0f);
        addInwardBox(scene, offset + glm::vec3(-2.0f, 0.0f, -2.0f), offset + glm::vec3(2.0f, 3.0f, 2.0f), 0);
        Camera camera;
        camera.name = "inside";
        camera.position = offset + glm::vec3(0.0f, 1.5f, 0.0f);
        scene.cameras.push_back(camera);
        const Tracer tracer(scene);
        const HashGridParameters grid{};
        fit = fitLevelBias(scene, grid, kDefaultVoxelBudget);
        HashGridParameters fitted = grid;
        fitted.level_bias = fit.level_bias;
        warning = checkVoxelsAroundCameras(tracer, fitted, ViewRegion{}, &fit, kDefaultVoxelBudget, nullptr);
    }
};

TEST(GridFit, VoxelsMadeWideByTheGridRangeNameTheOriginAsTheFix) {
    // 1000 km from the origin float32 positions are 6 cm apart, and voxels of 20 such steps are
    // 1.25 m wide: too wide for a 4 m room.
    const FarRoom far(1e6f);
    ASSERT_TRUE(far.fit.limited_by_range);
    EXPECT_EQ(far.fit.range_limit, GridFit::RangeLimit::kFloatPrecision);
    EXPECT_NE(far.fit.reason.find("float32"), std::string::npos) << far.fit.reason;
    EXPECT_NE(far.warning.find("the voxels around camera 'inside'"), std::string::npos) << far.warning;
    EXPECT_NE(far.warning.find("towards the origin"), std::string::npos) << far.warning;
    EXPECT_EQ(far.warning.find("--view-region gltf"), std::string::npos) << far.warning;
}

TEST(GridFit, ARoomFarFromTheOriginKeepsTheVoxelsItHasAtTheOrigin) {
    // 100 km out, SHaRC's 17-bit coordinates around the origin allowed only 1.7 m voxels; around
    // an anchor in the room the room's own budget decides, as at the origin.
    const FarRoom near(0.0f), far(1e5f);
    EXPECT_FALSE(near.fit.limited_by_range);
    EXPECT_EQ(gridAnchorFor(near.scene, near.fit.finest_voxel_size).x, 0.0f);
    const Float3 anchor = gridAnchorFor(far.scene, far.fit.finest_voxel_size);
    EXPECT_EQ(anchor.x, 1e5f);  // the centre of the room's bounds
    EXPECT_EQ(anchor.y, 1.5f);
    EXPECT_LT(far.fit.finest_voxel_size, 0.2f);
    EXPECT_LE(far.fit.finest_voxel_size, 1.5f * near.fit.finest_voxel_size + 0.16f);
    EXPECT_EQ(far.warning, "");
}

TEST(GridFit, AStreetCameraInAWideCityIsToldBothBudgets) {
    // A street 3 m wide among 10 m blocks, in a city of 60 x 60 blocks on a 2 km ground. Cameras
    // anywhere need every surface at level 1; cameras at the street camera need the far blocks
    // only at the levels of their distances, whose count no bias lowers: neither fits the default
    // budget, so the warning names the budget each needs, the one near the glTF cameras first.
    Scene scene = emptyTestScene();
    scene.materials.emplace_back();
    addInwardBox(scene, glm::vec3(-1000.0f, -1.0f, -1000.0f), glm::vec3(1000.0f, 0.0f, 1000.0f), 0);
    for (int i = -30; i < 30; ++i)
        for (int j = -30; j < 30; ++j)
            addInwardBox(scene, glm::vec3(8.0f * float(i) - 2.5f, 0.0f, 8.0f * float(j) - 2.5f),
                         glm::vec3(8.0f * float(i) + 2.5f, 10.0f, 8.0f * float(j) + 2.5f), 0);
    Camera camera;
    camera.name = "street";
    camera.position = glm::vec3(4.0f, 1.7f, 4.0f);
    scene.cameras.push_back(camera);
    const Tracer tracer(scene);
    const HashGridParameters grid{};
    const GridFit fit = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    HashGridParameters fitted = grid;
    fitted.level_bias = fit.level_bias;
    const std::string warning = checkVoxelsAroundCameras(tracer, fitted, ViewRegion{}, &fit, kDefaultVoxelBudget,
                                                         nullptr);
    ASSERT_NE(warning.find("the voxels around camera 'street'"), std::string::npos) << warning;
    const auto budgetAfter = [&](const std::string& text) {
        const size_t at = warning.find(text);
        return at == std::string::npos ? uint64_t(0) : std::stoull(warning.substr(at + text.size()));
    };
    const uint64_t near_budget = budgetAfter("--view-region gltf --voxel-budget ");
    const uint64_t anywhere_budget = budgetAfter("for cameras anywhere, --voxel-budget ");
    EXPECT_GT(near_budget, kDefaultVoxelBudget) << warning;
    EXPECT_GT(anywhere_budget, 4 * near_budget) << warning;
    std::printf("[voxel warning] city of 60 x 60 blocks: --view-region gltf needs %llu voxels, anywhere %llu\n",
                (unsigned long long)near_budget, (unsigned long long)anywhere_budget);
    // Each named fix, applied, leaves nothing to warn about; a quarter of it does not.
    ViewRegion at_camera;
    at_camera.kind = ViewRegion::Kind::Points;
    at_camera.points = {camera.position};
    for (const uint64_t budget : {near_budget, near_budget / 4}) {
        const GridFit near = fitLevelBias(scene, grid, budget, nullptr, &at_camera);
        fitted.level_bias = near.level_bias;
        EXPECT_EQ(checkVoxelsAroundCameras(tracer, fitted, at_camera, &near, budget, nullptr).empty(),
                  budget == near_budget)
            << budget;
    }
    for (const uint64_t budget : {anywhere_budget, anywhere_budget / 4}) {
        const GridFit anywhere = fitLevelBias(scene, grid, budget);
        fitted.level_bias = anywhere.level_bias;
        EXPECT_EQ(checkVoxelsAroundCameras(tracer, fitted, ViewRegion{}, &anywhere, budget, nullptr).empty(),
                  budget == anywhere_budget)
            << budget;
    }
}

TEST(GridFit, ACameraAtAWallOfAHugeGroundIsToldTheBudgetBeyondWhichOnlyTheGridRangeDecides) {
    // A camera 5 cm from a wall on a ground 10 km wide wants voxels of a few centimetres. Kept to
    // the glTF camera, a larger budget makes them finer until SHaRC's 17-bit keys cannot tell
    // finer cells apart across 10 km; the warning names that budget, the width it gets (which a
    // fit with it gets) and the range as the reason, not a budget that cannot help.
    Scene scene = emptyTestScene();
    scene.materials.emplace_back();
    addInwardBox(scene, glm::vec3(-5000.0f, -1.0f, -5000.0f), glm::vec3(5000.0f, 0.0f, 5000.0f), 0);
    addInwardBox(scene, glm::vec3(-5.0f, 0.0f, 0.05f), glm::vec3(5.0f, 4.0f, 8.0f), 0);
    Camera camera;
    camera.name = "at the wall";
    camera.position = glm::vec3(0.0f, 1.7f, 0.0f);
    scene.cameras.push_back(camera);
    const Tracer tracer(scene);
    const HashGridParameters grid{};
    ViewRegion at_camera;
    at_camera.kind = ViewRegion::Kind::Points;
    at_camera.points = {camera.position};
    const GridFit near = fitLevelBias(scene, grid, kDefaultVoxelBudget, nullptr, &at_camera);
    EXPECT_FALSE(near.limited_by_range);
    HashGridParameters fitted = grid;
    fitted.level_bias = near.level_bias;
    const std::string warning = checkVoxelsAroundCameras(tracer, fitted, at_camera, &near, kDefaultVoxelBudget,
                                                         nullptr);
    const std::string named = "the view region's cameras ask for. --voxel-budget ";
    const size_t at = warning.find(named);
    ASSERT_NE(at, std::string::npos) << warning;
    EXPECT_NE(warning.find("the smallest the 17-bit grid allows across a scene 1e+04 units wide; baking the parts"),
              std::string::npos)
        << warning;
    size_t used = 0;
    const std::string rest = warning.substr(at + named.size());
    const uint64_t budget = std::stoull(rest, &used);
    const std::string width_text = " makes them ";
    ASSERT_EQ(rest.substr(used, width_text.size()), width_text) << warning;
    const float named_width = std::stof(rest.substr(used + width_text.size()));
    // The named budget is the first the range stops, and four times it gets nothing finer.
    const auto widthWith = [&](uint64_t voxels, bool range_decides) {
        const GridFit with = fitLevelBias(scene, grid, voxels, nullptr, &at_camera);
        EXPECT_EQ(with.limited_by_range, range_decides) << voxels;
        EXPECT_EQ(with.range_limit, GridFit::RangeLimit::kSceneSize) << voxels;
        HashGridParameters budget_grid = grid;
        budget_grid.level_bias = with.level_bias;
        const std::string still = checkVoxelsAroundCameras(tracer, budget_grid, at_camera, &with, voxels, nullptr);
        const std::string around = "the voxels around camera 'at the wall', ";
        EXPECT_EQ(still.find(around), 0u) << still;
        return std::stof(still.substr(around.size()));
    };
    EXPECT_NEAR(widthWith(budget, true), named_width, 0.01f * named_width);
    EXPECT_NEAR(widthWith(4 * budget, true), named_width, 0.01f * named_width);
    EXPECT_GT(widthWith(budget / 4, false), 1.02f * named_width);
    std::printf("[voxel warning] %s\n", warning.c_str());
}

TEST(GridFit, ARoomItsCamerasSeeWholeKeepsTheWholeSurfaceFit) {
    // The seen surface replaces the whole only when it is a small part: a room explored from its
    // camera sees all of it, and its fit is the one without the estimate, bit for bit.
    test::TempDir dir;
    const Scene scene = loadRoom(dir, {false, true, true, true});
    const SeenSurface seen = seenByExploringCamera(scene);
    EXPECT_GT(seen.fraction, 0.9);  // the cube's floor-facing side is hidden
    const HashGridParameters grid{};
    const GridFit whole = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    const GridFit fitted = fitLevelBias(scene, grid, kDefaultVoxelBudget, &seen);
    EXPECT_FALSE(fitted.fitted_to_seen);
    EXPECT_EQ(fitted.level_bias, whole.level_bias);
    EXPECT_EQ(fitted.reason, whole.reason);
}

TEST(GridFit, AFinelyMeshedRoomWoundOutwardsKeepsTheWholeSurfaceFit) {
    // The room its camera sees whole, single-sided and wound outwards (a Blender cube scaled up,
    // backface culling on), each wall in 2 x 100 x 100 triangles: the rays from the viewpoints hit
    // a few thousand of its 120,000 triangles, and the points spread by area counted the front
    // sides alone, which face out. The seen part read 13% of the room, and the grid was fitted to
    // it: voxels 2.7 times finer than the budget asks, 7 times the voxels. The backs of the walls,
    // which the paths reach, are seen from inside.
    test::TempDir dir;
    RoomOptions options{false, false, true, false};
    options.split = 100;
    const Scene scene = loadRoom(dir, options);
    const SeenSurface seen = seenByExploringCamera(scene);
    EXPECT_GT(seen.fraction, 0.9);
    const HashGridParameters grid{};
    const GridFit whole = fitLevelBias(scene, grid, kDefaultVoxelBudget);
    const GridFit fitted = fitLevelBias(scene, grid, kDefaultVoxelBudget, &seen);
    EXPECT_FALSE(fitted.fitted_to_seen);
    EXPECT_EQ(fitted.level_bias, whole.level_bias);
}

TEST(GridFit, AClosedDoubleSidedRoomGetsTheVoxelsOfTheSameRoomSingleSided) {
    // Blender writes double-sided materials: the walls' outer sides doubled the visible surface,
    // though no camera inside reaches them, and the room got voxels sqrt(2) wider, half the
    // level-1 voxels the fit's line promised. The sides the viewpoints never see are left out.
    test::TempDir single_dir, double_dir;
    const Scene single_sided = loadRoom(single_dir, {false, true, true, false});
    const Scene double_sided = loadRoom(double_dir, {true, true, true, false});
    const HashGridParameters grid{};
    const SeenSurface single_seen = seenByExploringCamera(single_sided);
    const SeenSurface double_seen = seenByExploringCamera(double_sided);
    EXPECT_EQ(single_seen.unseen_double_sided_area, 0.0);
    const double room_area = visibleSurfaceArea(single_sided);
    EXPECT_NEAR(double_seen.unseen_double_sided_area, room_area, 0.05 * room_area) << "the outer sides";
    const GridFit single_fit = fitLevelBias(single_sided, grid, kDefaultVoxelBudget, &single_seen);
    const GridFit double_fit = fitLevelBias(double_sided, grid, kDefaultVoxelBudget, &double_seen);
    EXPECT_FALSE(double_fit.fitted_to_seen);
    EXPECT_NEAR(double_fit.surface_area, room_area, 0.05 * room_area);
    EXPECT_NEAR(double_fit.level_bias, single_fit.level_bias, 2.0 / 64.0);
    EXPECT_NE(double_fit.reason.find("less the sides of double-sided surfaces"), std::string::npos)
        << double_fit.reason;
    // Without the estimate (a level bias checked by hand) both sides count, as before.
    EXPECT_DOUBLE_EQ(fitLevelBias(double_sided, grid, kDefaultVoxelBudget).surface_area, 2.0 * room_area);
}

TEST(ExploreFreeSpace, ExplorationIsAPureFunctionOfTheSeed) {
    test::TempDir dir;
    const Scene scene = loadRoom(dir, {true, false, true, true});
    const Explored a = explore(scene), b = explore(scene);
    ASSERT_EQ(a.result.points.size(), b.result.points.size());
    for (size_t i = 0; i < a.result.points.size(); ++i) EXPECT_EQ(a.result.points[i], b.result.points[i]);
}

TEST(CameraPathAtGltfCameras, StandsAtEachCameraLookingItsOwnWayAndAround) {
    Scene scene = emptyTestScene();
    for (const glm::vec3 position : {glm::vec3(1.0f, 1.5f, 0.0f), glm::vec3(9.0f, 1.5f, 0.0f)}) {
        Camera camera;
        camera.position = position;
        camera.forward = glm::vec3(0.0f, 0.0f, -1.0f);
        scene.cameras.push_back(camera);
    }
    const CameraPath path = atGltfCameraPositions(scene, 7);
    ASSERT_EQ(path.waypoints().size(), 4u);
    std::set<std::tuple<float, float, float>> directions;
    for (uint32_t iteration = 0; iteration < 64; ++iteration) {
        const CameraPose pose = path.poseAt(iteration);
        // Never between the cameras (a glide would cross the walls between two rooms).
        EXPECT_EQ(pose.position, scene.cameras[(iteration / 2) % 2].position) << iteration;
        if (iteration % 2 == 0) {
            EXPECT_EQ(pose.forward, scene.cameras[(iteration / 2) % 2].forward) << iteration;
        } else {
            directions.insert({pose.forward.x, pose.forward.y, pose.forward.z});
        }
        EXPECT_EQ(pose.position, atGltfCameraPositions(scene, 7).poseAt(iteration).position);
        EXPECT_EQ(pose.forward, atGltfCameraPositions(scene, 7).poseAt(iteration).forward);
    }
    EXPECT_EQ(directions.size(), 32u);  // a new direction every time it looks around
}

/// A lone table under a white sky: a 2 x 1 m top, 10 cm thick, on four 90 cm legs, nothing else.
/// Its bounds end at the top's upper face, so no free point inside them sees that face.
Scene loadTable(const test::TempDir& dir, bool camera, glm::vec3 camera_position = glm::vec3(0.0f, 1.5f, 3.0f)) {
    test::GltfBuilder gltf;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addBox(positions, indices, {-1.0f, 0.9f, -0.5f}, {1.0f, 1.0f, 0.5f}, false);
    for (float x : {-0.9f, 0.8f}) {
        for (float z : {-0.4f, 0.3f}) addBox(positions, indices, {x, 0.0f, z}, {x + 0.1f, 0.9f, z + 0.1f}, false);
    }
    const int material = gltf.addMaterial({{"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}});
    const int mesh = gltf.addMesh(
        nlohmann::json::array({{{"attributes", {{"POSITION", gltf.addPositions(positions)}}},
                                {"indices", gltf.addData(indices, test::kUnsignedInt, "SCALAR")},
                                {"material", material}}}));
    std::vector<int> roots{gltf.addNode({{"mesh", mesh}})};
    if (camera) {
        gltf.doc["cameras"] = nlohmann::json::array(
            {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.01}}}}});
        roots.push_back(
            gltf.addNode({{"camera", 0}, {"translation", {camera_position.x, camera_position.y, camera_position.z}}}));
    }
    gltf.setScene(roots);
    Scene scene = loadGltf(gltf.writeEmbedded(dir, "table.gltf"));
    scene.sky.uniform = glm::vec3(1.0f);
    return scene;
}

/// One mesh of `positions` and `indices` with a double-sided material (Blender's default), and a
/// camera at `camera` if given, written to `name` in `dir` and loaded.
Scene loadDoubleSidedMesh(const test::TempDir& dir, const std::vector<float>& positions,
                          const std::vector<uint32_t>& indices, const std::string& name,
                          std::optional<glm::vec3> camera = std::nullopt) {
    test::GltfBuilder gltf;
    const int material = gltf.addMaterial({{"doubleSided", true}});
    const int mesh = gltf.addMesh(
        nlohmann::json::array({{{"attributes", {{"POSITION", gltf.addPositions(positions)}}},
                                {"indices", gltf.addData(indices, test::kUnsignedInt, "SCALAR")},
                                {"material", material}}}));
    std::vector<int> roots{gltf.addNode({{"mesh", mesh}})};
    if (camera) {
        gltf.doc["cameras"] = nlohmann::json::array(
            {{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.01}}}}});
        roots.push_back(gltf.addNode({{"camera", 0}, {"translation", {camera->x, camera->y, camera->z}}}));
    }
    gltf.setScene(roots);
    return loadGltf(gltf.writeEmbedded(dir, name));
}

/// Gives triangles [first, end) a copy of the first material that emits `emission`.
void makeEmissive(Scene& scene, uint32_t first, uint32_t end, glm::vec3 emission) {
    Material glow = scene.materials.front();
    glow.emissive = emission;
    scene.materials.push_back(glow);
    for (uint32_t t = first; t < end; ++t) scene.triangle_materials[t] = uint32_t(scene.materials.size() - 1);
}

/// Two closed boxes wound outwards, double-sided (loadDoubleSidedMesh), without a camera.
Scene loadTwoBoxes(const test::TempDir& dir, glm::vec3 a_min, glm::vec3 a_max, glm::vec3 b_min, glm::vec3 b_max,
                   const std::string& name) {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addBox(positions, indices, a_min, a_max, false);
    addBox(positions, indices, b_min, b_max, false);
    return loadDoubleSidedMesh(dir, positions, indices, name);
}

TEST(ExploreFreeSpace, TheInsideOfAClosedDoubleSidedObjectIsNotExplored) {
    // Blender's default material is double-sided. A closed T of two boxes without a camera: the
    // centre of its bounds lies inside the bar, and with no single-sided face to vote, its inside
    // looked free; the path was the inside of the T, and nothing outside got a voxel.
    constexpr glm::vec3 kBarMin{0.0f, 0.8f, 0.0f}, kBarMax{3.0f, 2.0f, 1.0f};
    constexpr glm::vec3 kStemMin{1.0f, 0.0f, 0.0f}, kStemMax{2.0f, 0.8f, 1.0f};
    test::TempDir dir;
    const Scene scene = loadTwoBoxes(dir, kBarMin, kBarMax, kStemMin, kStemMax, "t.gltf");
    const Explored e = explore(scene);
    ASSERT_TRUE(e.has_path);
    EXPECT_GE(e.result.points.size(), 16u);
    for (const glm::vec3& p : e.result.points) {
        EXPECT_FALSE(inside(p, kBarMin, kBarMax) || inside(p, kStemMin, kStemMax))
            << "(" << p.x << ", " << p.y << ", " << p.z << ")";
    }
    EXPECT_EQ(e.result.views_around, e.result.points.size());  // open around: seen from outside too
}

TEST(ExploreFreeSpace, TheInsideOfADoubleSidedModelOpenThroughAGapIsNotExplored) {
    // Blender writes its default material double-sided, and models keep their normals pointing
    // out. A box with a hole in one face, as Suzanne's head is open behind its eyes, on a ground,
    // with a camera that sees into it through the hole: its inside is reachable, and with no
    // single-sided face to vote it was free space, so the bake and the hit rate's sample views
    // stood inside the head (a fifth of those views, at under 1% each). The backs of double-sided
    // faces now vote where the cameras stand in free space by them. The camera stands on the
    // hole's axis: its -Z probe meets the back of the far wall inside, and that one back face
    // against a single front (the ground below) put the camera inside a solid, so double-sided
    // faces lost their vote and the head was explored again. Cameras are now probed along 64
    // directions, where the head's outside outweighs the hole.
    constexpr glm::vec3 kHeadMin{0.0f, 0.0f, 0.0f}, kHeadMax{2.0f, 2.0f, 2.0f};
    test::TempDir dir;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addBox(positions, indices, kHeadMin, kHeadMax, false, 3);
    // The +Z face is the last 9 quads; its middle one (indices 4 of 9) is the hole.
    const size_t face = indices.size() - 9 * 6;
    indices.erase(indices.begin() + std::ptrdiff_t(face + 4 * 6), indices.begin() + std::ptrdiff_t(face + 5 * 6));
    const uint32_t base = uint32_t(positions.size() / 3);
    positions.insert(positions.end(), {-2.0f, 0.0f, -2.0f, 4.0f, 0.0f, -2.0f, 4.0f, 0.0f, 4.0f, -2.0f, 0.0f, 4.0f});
    indices.insert(indices.end(), {base, base + 2, base + 1, base, base + 3, base + 2});  // facing up
    constexpr glm::vec3 kCamera{1.0f, 1.0f, 5.0f};
    const Scene scene = loadDoubleSidedMesh(dir, positions, indices, "head.gltf", kCamera);
    const Tracer tracer(scene);
    ASSERT_TRUE(visibleOneWay(tracer, kCamera, glm::vec3(1.0f, 1.0f, 1.0f)))
        << "the camera sees into the box through the hole";
    RayHit far_wall;
    ASSERT_TRUE(tracer.intersect(Ray{kCamera, glm::vec3(0.0f, 0.0f, -1.0f)}, far_wall));
    ASSERT_NEAR(far_wall.t, 5.0f, 1e-4f) << "the -Z probe meets the inside of the far wall";
    const Explored e = explore(scene);
    ASSERT_TRUE(e.has_path);
    EXPECT_GE(e.result.points.size(), 16u);
    EXPECT_FALSE(e.result.winding_ignored);
    for (const glm::vec3& p : e.result.points) {
        EXPECT_FALSE(inside(p, kHeadMin, kHeadMax)) << "(" << p.x << ", " << p.y << ", " << p.z << ")";
    }
}

TEST(ExploreFreeSpace, ADoubleSidedRoomWoundOutwardsWithoutACameraKeepsTheSingleSidedVote) {
    // The same vote in a room of double-sided walls wound outwards (a cube scaled up), without a
    // camera to try it on, around an open tub wound inwards: the walls' backs put the room inside
    // a solid, but the tub's fronts leave the points inside it free, and the path would have kept
    // to the tub. Where fewer than a quarter of the free points single-sided faces find are left,
    // those vote alone, as before, and the path fills the room.
    constexpr glm::vec3 kTubMin{-1.0f, 0.0f, -1.0f}, kTubMax{1.0f, 0.6f, 1.0f};
    test::TempDir dir;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addBox(positions, indices, kRoomMin, kRoomMax, false);
    const size_t tub = indices.size();
    addBox(positions, indices, kTubMin, kTubMax, true);
    // Faces come -X, +X, -Y, +Y, -Z, +Z, two triangles each: the tub has no top.
    indices.erase(indices.begin() + std::ptrdiff_t(tub + 3 * 6), indices.begin() + std::ptrdiff_t(tub + 4 * 6));
    Scene room = loadDoubleSidedMesh(dir, positions, indices, "room.gltf");
    PunctualLight bulb;  // a room, lit from within
    bulb.position = kLampCenter;
    bulb.intensity = glm::vec3(5.0f);
    room.lights.push_back(bulb);
    const Explored e = explore(room);
    ASSERT_TRUE(e.has_path);
    EXPECT_EQ(e.result.points.size(), 32u);
    EXPECT_FALSE(e.result.winding_ignored);
    EXPECT_FALSE(e.result.dark_enclosure);
    int above_tub = 0;
    for (const CameraPose& pose : e.waypoints) above_tub += pose.position.y > kTubMax.y;
    EXPECT_GT(above_tub, 16) << "the room above the tub is explored";
}

TEST(PredictionViews, ASceneWithoutCamerasIsAlsoPredictedFromRendersAutomaticCamera) {
    test::TempDir dir;
    const Scene lone = loadTable(dir, false);
    const Tracer lone_tracer(lone);
    const std::vector<PredictionView> views = predictionViews(lone_tracer, ViewRegion{}, 8, 1);
    ASSERT_FALSE(views.empty());
    const Camera automatic = automaticCamera(lone, glm::radians(45.0f));
    EXPECT_TRUE(views.front().declared);
    EXPECT_EQ(views.front().camera.position, automatic.position);
    EXPECT_EQ(views.front().camera.forward, automatic.forward);
    EXPECT_FLOAT_EQ(views.front().camera.yfov, automatic.yfov);
    // It sees the whole table: the automatic camera frames the bounding sphere.
    EXPECT_NEAR(glm::distance(automatic.position, 0.5f * (lone.bounds_min + lone.bounds_max)),
                framingDistance(lone, automatic.yfov), 1e-4f);
    // A scene with a camera is predicted from it instead.
    const Scene with_camera = loadTable(dir, true);
    const Tracer tracer(with_camera);
    const std::vector<PredictionView> camera_views = predictionViews(tracer, ViewRegion{}, 8, 1);
    ASSERT_FALSE(camera_views.empty());
    EXPECT_EQ(camera_views.front().camera.position, with_camera.cameras.front().position);
    for (const PredictionView& v : camera_views) EXPECT_EQ(v.camera.name.find("automatic"), std::string::npos);
}

TEST(ViewsAroundScene, LookAtTheSurfaceFromJustOutsideTheBoundingSphere) {
    test::TempDir dir;
    const Scene scene = loadTable(dir, false);
    const Tracer tracer(scene);
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float radius = boundingRadius(scene);
    const std::vector<CameraPose> views = viewsAroundScene(scene, 64, 5);
    ASSERT_EQ(views.size(), 64u);
    glm::vec3 direction_sum(0.0f);
    for (const CameraPose& v : views) {
        const glm::vec3 offset = v.position - center;
        EXPECT_NEAR(glm::length(offset), 1.5f * radius, 1e-4f * radius);
        EXPECT_NEAR(glm::dot(v.forward, v.up), 0.0f, 1e-5f);
        EXPECT_NEAR(v.yfov, 0.25f * kPi, 1e-6f);
        // It looks at a point of the table, so the view's centre ray meets the table.
        RayHit hit;
        EXPECT_TRUE(tracer.intersect(Ray{v.position, v.forward}, hit));
        direction_sum += glm::normalize(offset);
    }
    // Spread over the whole sphere: the directions nearly cancel.
    EXPECT_LT(glm::length(direction_sum) / 64.0f, 0.05f);
    // A pure function of the seed.
    const std::vector<CameraPose> again = viewsAroundScene(scene, 64, 5);
    for (size_t i = 0; i < views.size(); ++i) EXPECT_EQ(views[i].forward, again[i].forward);
}

TEST(ExploreFreeSpace, LoneObjectWithoutACameraIsAlsoSeenFromAround) {
    test::TempDir dir;
    const Scene scene = loadTable(dir, false);
    const Tracer tracer(scene);
    ExplorationResult result;
    const std::optional<CameraPath> path = exploringCameraPath(tracer, scene, 16, 7, &result);
    ASSERT_TRUE(path.has_value());
    EXPECT_GE(result.escaped_fraction, kOpenSceneEscapedFraction);
    ASSERT_EQ(result.views_around, result.points.size());
    // Free points and views from around alternate; the views keep their direction on every visit.
    const std::vector<CameraPose> around = viewsAroundScene(scene, result.views_around, 7);
    ASSERT_EQ(path->waypoints().size(), 2 * result.points.size());
    for (uint32_t i = 0; i < result.points.size(); ++i) {
        EXPECT_EQ(path->poseAt(2 * i).position, result.points[i]);
        for (uint32_t lap = 0; lap < 2; ++lap) {
            const CameraPose view = path->poseAt(2 * i + 1 + lap * uint32_t(path->waypoints().size()));
            EXPECT_EQ(view.position, around[i].position);
            EXPECT_EQ(view.forward, around[i].forward);
        }
    }
}

TEST(ExploreFreeSpace, ClosedRoomsAndCamerasWithinTheBoundsGetNoViewsFromAround) {
    test::TempDir dir;
    RoomOptions lit_room{true, false, false, true};
    lit_room.lamp = true;
    const Explored room = explore(loadRoom(dir, lit_room));
    ASSERT_TRUE(room.has_path);
    EXPECT_LT(room.result.escaped_fraction, 0.05f) << "a closed room without a camera";
    EXPECT_EQ(room.result.views_around, 0u);
    expectPointsFillTheRoom(room, "a closed double-sided room lit from within, no camera");
    // A camera within the scene's bounds (under the table, as one in a street or a room with an
    // open side) keeps the bake's paths around it.
    const Explored under = explore(loadTable(dir, true, glm::vec3(0.0f, 0.5f, 0.0f)));
    ASSERT_TRUE(under.has_path);
    EXPECT_GE(under.result.escaped_fraction, kOpenSceneEscapedFraction);
    EXPECT_FALSE(under.result.cameras_outside);
    EXPECT_EQ(under.result.views_around, 0u);
    // One outside them looks at the table from outside, as Blender's default camera looks at its
    // cube: the table is seen from around too, or its far side would have no finest voxel.
    const Explored table = explore(loadTable(dir, true));
    ASSERT_TRUE(table.has_path);
    EXPECT_TRUE(table.result.cameras_outside);
    EXPECT_EQ(table.result.views_around, table.result.points.size());
}

TEST(ExploreFreeSpace, TheDarkInsideOfAClosedModelIsSeenFromAround) {
    // A closed housing wound outwards with a part inside it, under the sky, without a camera, as
    // CAD tools export an assembly. The housing's bounds hold nothing but its inside: the winding
    // put every point inside a solid, the fallback ignored it, and the path explored the housing's
    // black inside; the grid was fitted to the part, and the bake predicted 0.1% from views
    // standing inside. No light reaches there and no runtime camera stands there.
    constexpr glm::vec3 kShellMin{-1.0f, 0.0f, -1.0f}, kShellMax{1.0f, 2.0f, 1.0f};
    constexpr glm::vec3 kPartMin{-0.3f, 0.5f, -0.3f}, kPartMax{0.3f, 1.1f, 0.3f};
    test::TempDir dir;
    const Scene loaded = loadTwoBoxes(dir, kShellMin, kShellMax, kPartMin, kPartMax, "housing.gltf");
    for (const bool double_sided : {false, true}) {
        Scene scene = loaded;
        for (Material& m : scene.materials) m.double_sided = double_sided;
        scene.sky.uniform = glm::vec3(1.0f);
        const char* what = double_sided ? "double-sided housing" : "single-sided housing";
        const Explored e = explore(scene);
        ASSERT_TRUE(e.has_path) << what;
        EXPECT_TRUE(e.result.dark_enclosure) << what;
        EXPECT_EQ(e.result.escaped_fraction, 0.0f) << what;
        // The views from around alone: every waypoint outside the housing, each keeping its aim.
        ASSERT_GT(e.result.views_around, 0u) << what;
        EXPECT_EQ(e.waypoints.size(), e.result.views_around) << what;
        for (const CameraPose& pose : e.waypoints) {
            EXPECT_FALSE(inside(pose.position, kShellMin, kShellMax))
                << what << ": (" << pose.position.x << ", " << pose.position.y << ", " << pose.position.z << ")";
        }
        // The hit rate is predicted from outside too: render's automatic camera and views from
        // around, none inside.
        const Tracer tracer(scene);
        const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 8, 1);
        EXPECT_EQ(views.size(), 9u) << what;
        for (const PredictionView& view : views) {
            EXPECT_FALSE(inside(view.camera.position, kShellMin, kShellMax)) << what << ": " << view.camera.name;
        }
    }
    // Finely meshed, as CAD exports are (64 x 64 quads a face): a probe that slips between two
    // triangles at a shared edge seemed to leave the scene, and one such leak made the housing's
    // inside count as known free space.
    {
        std::vector<float> positions;
        std::vector<uint32_t> indices;
        addBox(positions, indices, kShellMin, kShellMax, false, 64);
        Scene fine = loadDoubleSidedMesh(dir, positions, indices, "fine_housing.gltf");
        fine.sky.uniform = glm::vec3(1.0f);
        const Explored e = explore(fine);
        ASSERT_TRUE(e.has_path);
        EXPECT_TRUE(e.result.dark_enclosure) << "a finely meshed closed box";
        EXPECT_EQ(e.result.escaped_fraction, 0.0f);
        for (const CameraPose& pose : e.waypoints) EXPECT_FALSE(inside(pose.position, kShellMin, kShellMax));
    }
    // Light inside makes the shell a room, explored from inside, around the part: a lamp (a closed
    // box modelled around the camera's space), or the shell's own glow (a sky dome modelled as an
    // emissive mesh, double-sided as Blender writes it, around a model).
    Scene lamp = loaded;
    PunctualLight bulb;
    bulb.position = glm::vec3(0.0f, 1.7f, 0.0f);
    bulb.intensity = glm::vec3(5.0f);
    lamp.lights.push_back(bulb);
    Scene dome = loaded;
    makeEmissive(dome, 0, 12, glm::vec3(0.5f, 0.7f, 1.0f));  // the shell
    for (const auto& [scene, what] : {std::pair<const Scene&, const char*>{lamp, "a lamp inside"},
                                      std::pair<const Scene&, const char*>{dome, "a glowing shell"}}) {
        const Explored e = explore(scene);
        ASSERT_TRUE(e.has_path) << what;
        EXPECT_FALSE(e.result.dark_enclosure) << what;
        EXPECT_EQ(e.result.views_around, 0u) << what;
        ASSERT_FALSE(e.waypoints.empty()) << what;
        for (const CameraPose& pose : e.waypoints) {
            EXPECT_TRUE(inside(pose.position, kShellMin, kShellMax)) << what;
            EXPECT_FALSE(inside(pose.position, kPartMin, kPartMax)) << what;
        }
    }
}

TEST(ExploreFreeSpace, TheInsideOfAGlowingObjectInALitRoomIsNotExplored) {
    // A closed room of double-sided walls without a camera, lit by a lamp, around a large glowing
    // block (a light fixture modelled as a closed emissive mesh, double-sided as Blender writes
    // it). No free point is known, so the sets light reaches are kept: the block's inside is lit by
    // its own walls, but no camera stands there; the room is kept, the block's inside is not.
    constexpr glm::vec3 kBlockMin{-1.5f, 0.5f, -2.0f}, kBlockMax{0.5f, 2.5f, 0.5f};
    test::TempDir dir;
    Scene scene = loadTwoBoxes(dir, kRoomMin, kRoomMax, kBlockMin, kBlockMax, "glowing_block.gltf");
    makeEmissive(scene, 12, 24, glm::vec3(1.0f, 0.8f, 0.6f));  // the block
    PunctualLight bulb;
    bulb.position = kLampCenter;
    bulb.intensity = glm::vec3(5.0f);
    scene.lights.push_back(bulb);
    const Explored e = explore(scene);
    ASSERT_TRUE(e.has_path);
    EXPECT_FALSE(e.result.dark_enclosure);
    ASSERT_FALSE(e.waypoints.empty());
    int in_block = 0;
    for (const CameraPose& pose : e.waypoints) in_block += inside(pose.position, kBlockMin, kBlockMax);
    EXPECT_EQ(in_block, 0) << "of " << e.waypoints.size() << " waypoints";
}

TEST(ExploreFreeSpace, ViewsFromAroundReachTheSurfaceNoFreePointSees) {
    // The same bake with the free-space points alone (the path before views from around) and
    // with the default path: without the views from around, the table's upper face and the
    // outer faces no free point sees (half the surface) never get a finest-level voxel.
    test::TempDir dir;
    const Scene scene = loadTable(dir, false);
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    ExplorationResult explored;
    const CameraPath with_views = exploringCameraPath(tracer, scene, 16, 3, &explored).value();
    std::vector<CameraPose> points_only;
    for (const glm::vec3& p : explored.points) points_only.push_back(CameraPose{p});
    const CameraPath without_views(points_only, true, 1, 0.0f, 3);
    BakeSettings settings;
    settings.width = settings.height = 320;
    settings.sharc.grid.capacity = 1u << 18;
    const auto unreachedFinest = [&](const CameraPath& path) {
        Baker baker(tracer, lights, path, settings, SharcCache::chooseRadianceScale(estimateMaxRadiance(tracer)));
        for (int i = 0; i < 128; ++i) baker.runIteration();
        const CoverageReport report = measureCoverage(scene, baker.cache(), levelsPresent(baker.cache()), 4000);
        return report.unreached_finest_area;
    };
    const double before = unreachedFinest(without_views), after = unreachedFinest(with_views);
    std::printf("[views around] surface without a finest voxel: free points only %.4f, with views from around %.4f\n",
                before, after);
    EXPECT_GT(before, 0.4);           // measured 0.46
    EXPECT_LT(after, 0.1 * before);   // measured 0.027
}

TEST(Coverage, ASingleSidedRoomWoundOutwardsIsReachedFromInside) {
    // A Blender cube scaled into a room, backface culling on: single-sided walls whose winding
    // faces out, seen from inside. The path tracer shades their backs and SHaRC keys the normal
    // towards the ray, so every voxel sits on a back side; coverage tested the fronts alone and
    // said 100% of the surface was never reached (29% without a voxel at any level) of a room
    // its camera found whole.
    test::TempDir dir;
    BakeSettings settings;
    settings.width = settings.height = 320;
    settings.sharc.grid.capacity = 1u << 18;
    const auto coverageOf = [&](const RoomOptions& options, const char* what) {
        const TestBakeScene bake(loadRoom(dir, options));
        const std::unique_ptr<Baker> baker = bake.makeBaker(settings);
        for (int i = 0; i < 32; ++i) baker->runIteration();
        const CoverageReport r = measureCoverage(bake.scene, baker->cache(), levelsPresent(baker->cache()), 4000,
                                                 &baker->depositLevels());
        std::printf("[coverage] %s: no voxel at any level %.4f, at the deposit level %.4f\n", what, r.unreached_area,
                    r.unreached_deposit_area);
        return r;
    };
    RoomOptions options{false, false, true, false};  // single-sided, wound outwards, a camera inside
    const CoverageReport outwards = coverageOf(options, "single-sided room wound outwards");
    EXPECT_LT(outwards.unreached_area, 0.01);
    EXPECT_LT(outwards.unreached_deposit_area, 0.05);
    // The same room wound inwards, and double-sided wound outwards, read the same.
    const CoverageReport inwards = coverageOf({false, true, true, false}, "single-sided room wound inwards");
    EXPECT_LT(inwards.unreached_deposit_area, 0.05);
    const CoverageReport both = coverageOf({true, false, true, false}, "double-sided room wound outwards");
    EXPECT_LT(both.unreached_deposit_area, 0.05);
    // A closed box outside the room, which no path reaches from either side, still reads unreached
    // at the level the bake deposits there: its 24 m^2 of the 118 m^2 in all (the coarsest
    // voxels, summed from the room, cover it, as they cover any surface near reached surface).
    options.box_outside = true;
    const CoverageReport with_box = coverageOf(options, "the room and a closed box outside it");
    const glm::vec3 room = kRoomMax - kRoomMin, box = kOutsideMax - kOutsideMin;
    const double box_area = 2.0 * (box.x * box.y + box.x * box.z + box.y * box.z);
    const double box_share = box_area / (box_area + 2.0 * (room.x * room.y + room.x * room.z + room.y * room.z));
    EXPECT_NEAR(with_box.unreached_deposit_area, box_share, 0.03);
}

/// `iterations` iterations of a small bake (64x64 paths, 2^16 slots), as the file would hold them.
CacheData smallBake(const TestBakeScene& scene, int iterations) {
    BakeSettings settings;
    settings.width = settings.height = 64;
    settings.sharc.grid.capacity = 1u << 16;
    const std::unique_ptr<Baker> baker = scene.makeBaker(settings);
    for (int i = 0; i < iterations; ++i) baker->runIteration();
    return toCacheData(baker->cache());
}

TEST(PredictHitRate, ACameraThatSeesASmallModelIsReplayedAtAHigherResolution) {
    // The table seen from 3 m: most of the camera's 64x64 pixels see sky and most bounces from
    // the table leave it, so its own rate rested on a few dozen lookups. It is replayed at larger
    // sizes until it has enough; region samples keep the prediction's size.
    test::TempDir dir;
    const TestBakeScene bake(loadTable(dir, true));
    const Tracer& tracer = *bake.tracer;
    const CacheData data = smallBake(bake, 4);
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 4, 1);
    ASSERT_TRUE(views.front().declared);
    const HitRatePrediction small = predictHitRate(tracer, data, ViewRegion{}, {views.front()}, 16, 16);
    const HitRatePrediction normal = predictHitRate(tracer, data, ViewRegion{}, views);
    ASSERT_EQ(normal.views.size(), views.size());
    // At the default 64x64 the camera saw 27 lookups, at 256x256 444: it is replayed up to
    // 1024x1024, which gives it enough.
    EXPECT_GE(normal.views.front().eligible, kDeclaredViewMinLookups);
    // From 16x16 (256 pixels) the replays stop at 16 times the size each way, 256x256.
    EXPECT_GT(small.views.front().eligible, 256u);
    EXPECT_LT(small.views.front().eligible, kDeclaredViewMinLookups);
    for (size_t v = 1; v < normal.views.size(); ++v) {
        EXPECT_FALSE(normal.views[v].view.declared);
        EXPECT_LE(normal.views[v].eligible, 64u * 64u);  // one lookup per pixel at most
    }
}

// Blender artists frame an interior from outside, the near clip plane past the wall. The bake
// explores from where that camera's view begins, inside the room; its own views, in the roaming
// camera and in the hit-rate prediction, look through its clip; every other view has none.
TEST(PredictHitRate, ACutawayCameraOutsideAClosedRoomIsPredictedThroughItsClip) {
    const TestBakeScene bake(cutawayRoom());
    const Tracer& tracer = *bake.tracer;
    const Camera& cutaway = bake.scene.cameras.at(0);
    const glm::vec3 start = viewStart(tracer, cutaway);
    EXPECT_NEAR(glm::distance(start, glm::vec3(0.0f, 1.0f, 0.8f)), 0.0f, 1e-6f);
    Camera unclipped = cutaway;
    unclipped.znear = 0.0f;
    EXPECT_EQ(viewStart(tracer, unclipped), cutaway.position);
    Camera past_everything = cutaway;  // a near plane beyond the room looks into nothing
    past_everything.znear = 10.0f;
    EXPECT_EQ(viewStart(tracer, past_everything), cutaway.position);
    for (const CameraPose& pose : bake.path->waypoints()) {
        EXPECT_TRUE(glm::all(glm::lessThan(glm::abs(pose.position - glm::vec3(0.0f, 1.0f, 0.0f)), glm::vec3(1.0f))))
            << "a waypoint outside the room at " << pose.position.x << ", " << pose.position.y << ", "
            << pose.position.z;
        EXPECT_EQ(pose.znear, 0.0f);
    }
    const CameraPath at_camera = atGltfCameraPositions(bake.scene, 1);
    EXPECT_EQ(at_camera.poseAt(0).znear, 0.8f);  // the camera's own view
    EXPECT_EQ(at_camera.poseAt(1).znear, 0.0f);  // turned: no camera's view
    EXPECT_EQ(toCamera(at_camera.poseAt(0)).znear, 0.8f);

    const CacheData data = smallBake(bake, 4);
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 0, 1);
    ASSERT_EQ(views.size(), 1u);
    const HitRatePrediction through_clip = predictHitRate(tracer, data, ViewRegion{}, views);
    // Outside the room, or unclipped, the camera's first bounces met nothing lit: no lookups. Through
    // its clip it sees the room the bake explored; 4 short iterations answer about 15% of them.
    EXPECT_GT(through_clip.eligible, 1000u);
    EXPECT_GT(through_clip.hits, through_clip.eligible / 20);
}

TEST(PredictHitRate, LookupsRefusedByVoxelsLargerThanTheViewAreCounted) {
    // Voxels 41 m wide in a 4 m room: every bounce is shorter than its voxel, so SHaRC's tests
    // refuse every lookup. The prediction counted only eligible lookups and reported "no first
    // bounce hits a surface"; it now counts the refused ones, which the bake names as the cause.
    test::TempDir dir;
    const TestBakeScene bake(loadRoom(dir, {false, true, true, false}));
    const Tracer& tracer = *bake.tracer;
    BakeSettings settings;
    settings.width = settings.height = 64;
    settings.sharc.grid.capacity = 1u << 16;
    settings.sharc.grid.level_bias = -10.0f;  // level 1: 2^11 / 50 = 41 m
    const std::unique_ptr<Baker> baker = bake.makeBaker(settings);
    for (int i = 0; i < 2; ++i) baker->runIteration();
    const CacheData data = toCacheData(baker->cache());
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 0, 1);
    ASSERT_EQ(views.size(), 1u);
    ASSERT_TRUE(views.front().declared);
    const HitRatePrediction refused = predictHitRate(tracer, data, ViewRegion{}, views);
    EXPECT_EQ(refused.eligible, 0u);
    EXPECT_GT(refused.refused, 1000u);  // replayed up to 1024x1024 for want of eligible lookups
    EXPECT_EQ(refused.views.front().refused, refused.refused);
    // With the room's own fit (about 3 cm voxels) nearly every lookup is eligible.
    settings.sharc.grid.level_bias = fitLevelBias(bake.scene, settings.sharc.grid, kDefaultVoxelBudget).level_bias;
    const std::unique_ptr<Baker> fitted = bake.makeBaker(settings);
    for (int i = 0; i < 2; ++i) fitted->runIteration();
    const HitRatePrediction eligible = predictHitRate(tracer, toCacheData(fitted->cache()), ViewRegion{}, views);
    EXPECT_GT(eligible.eligible, 20u * eligible.refused);
}

TEST(RefusedLookups, EachCameraWeighsItsOwnLookupsAndOneLeftWithoutIsNamed) {
    // The room's camera and one inside the closed 1 m cube, on level-1 voxels 1 m wide: every
    // bounce in the cube (at most sqrt(3) m) is shorter than sqrt(3) voxels and refused; about 60%
    // of the room's pass. The cube's camera was replayed until 1000 lookups were eligible (up to
    // 1024x1024 pixels), which gave its refusals 256 times the room's weight: the share read 99%.
    test::TempDir dir;
    Scene scene = loadRoom(dir, {false, true, true, true});
    ASSERT_EQ(scene.cameras.size(), 1u);
    Camera cupboard;
    cupboard.name = "cupboard";
    cupboard.position = 0.5f * (kCubeMin + kCubeMax);
    scene.cameras.push_back(cupboard);
    const Tracer tracer(scene);
    HashGridParameters grid;
    grid.level_bias = 1.0f - std::log2(grid.scene_scale);  // level 1: 2^(1 - bias) / scale = 1 m
    const RefusedLookups refused = refusedLookups(tracer, grid, gridAnchorFor(scene, 1.0f));
    EXPECT_EQ(refused.unserved, 1u);
    EXPECT_EQ(refused.first_unserved, "camera 'cupboard'");
    EXPECT_GT(refused.share, 0.55);  // about the mean of the two cameras' shares (0.68),
    EXPECT_LT(refused.share, 0.8);   // not the cupboard's 256-fold (above 0.99)
    // On the room's own fit (about 3 cm voxels) the cupboard's bounces pass too.
    grid.level_bias = fitLevelBias(scene, grid, kDefaultVoxelBudget).level_bias;
    const RefusedLookups fitted = refusedLookups(tracer, grid,
                                                 gridAnchorFor(scene, voxelSize(kHashGridLevelMin, grid)));
    EXPECT_EQ(fitted.unserved, 0u);
    EXPECT_LT(fitted.share, 0.1);
}

TEST(PredictHitRate, ReplaysStopAtTheirPixelBudget) {
    // Forty glTF cameras that each see the small table: replays stop once they would exceed
    // kReplayPixelBudget (each camera's take 256x256 + 1024x1024 pixels), so a scene with
    // hundreds of cameras is not predicted at a million pixels each.
    test::TempDir dir;
    Scene scene = loadTable(dir, true);
    const Camera camera = scene.cameras.front();
    scene.cameras.assign(40, camera);
    const TestBakeScene bake(std::move(scene));
    const Tracer& tracer = *bake.tracer;
    const CacheData data = smallBake(bake, 1);
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 0, 1);
    ASSERT_EQ(views.size(), 40u);
    const HitRatePrediction prediction = predictHitRate(tracer, data, ViewRegion{}, views);
    size_t replayed_fully = 0;
    for (const ViewHitRate& v : prediction.views) replayed_fully += v.eligible >= kDeclaredViewMinLookups;
    const uint64_t per_view = 256u * 256u + 1024u * 1024u;
    EXPECT_EQ(replayed_fully, size_t(kReplayPixelBudget / per_view));
    EXPECT_LT(prediction.views.back().eligible, kDeclaredViewMinLookups);
}

TEST(AutomaticCamera, LooksIntoAClosedRoomFromInsideAndAtAnOpenSceneFromOutside) {
    // A closed room without a camera: from outside, render's automatic camera saw only the outer
    // sides of its walls (black, and never baked). It now stands inside, near the wall behind,
    // looking level along the room's longer axis.
    test::TempDir dir;
    const Scene room = loadRoom(dir, {false, true, false, true});
    const Tracer room_tracer(room);
    const Camera room_view = automaticCamera(room_tracer, 0.8f);
    EXPECT_TRUE(inside(room_view.position, kRoomMin, kRoomMax))
        << room_view.position.x << ", " << room_view.position.y << ", " << room_view.position.z;
    EXPECT_FLOAT_EQ(room_view.forward.y, 0.0f);
    EXPECT_FLOAT_EQ(std::abs(room_view.forward.z), 1.0f);  // the room is 5 m along Z, 4 m along X
    EXPECT_EQ(room_view.name, "automatic");
    // A lone object under the sky is looked at from outside, as before.
    const Scene table = loadTable(dir, false);
    const Tracer table_tracer(table);
    const Camera outside = automaticCamera(table_tracer, 0.8f);
    const Camera framing = automaticCamera(table, 0.8f);
    EXPECT_EQ(outside.position, framing.position);
    EXPECT_EQ(outside.forward, framing.forward);
}

/// A UV sphere as Blender makes one (32 segments, 16 rings), wound outwards.
void addSphere(std::vector<float>& positions, std::vector<uint32_t>& indices, glm::vec3 center, float radius) {
    constexpr uint32_t kSegments = 32, kRings = 16;
    const uint32_t base = uint32_t(positions.size() / 3);
    const auto add = [&](glm::vec3 p) { positions.insert(positions.end(), {p.x, p.y, p.z}); };
    add(center + glm::vec3(0.0f, radius, 0.0f));      // base: the north pole
    add(center - glm::vec3(0.0f, radius, 0.0f));      // base + 1: the south pole
    for (uint32_t ring = 1; ring < kRings; ++ring) {  // base + 2 + (ring - 1) * kSegments + segment
        const float polar = kPi * float(ring) / float(kRings);
        for (uint32_t segment = 0; segment < kSegments; ++segment) {
            // A third of a segment off the axes: no probe from the centre grazes an edge, where
            // Embree's test (not watertight) may let it through.
            const float azimuth = 2.0f * kPi * (float(segment) + 0.3f) / float(kSegments);
            add(center + radius * glm::vec3(std::sin(polar) * std::cos(azimuth), std::cos(polar),
                                            std::sin(polar) * std::sin(azimuth)));
        }
    }
    const auto vertex = [&](uint32_t ring, uint32_t segment) {
        return base + 2 + (ring - 1) * kSegments + segment % kSegments;
    };
    for (uint32_t segment = 0; segment < kSegments; ++segment) {
        indices.insert(indices.end(), {base, vertex(1, segment + 1), vertex(1, segment)});
        indices.insert(indices.end(), {base + 1, vertex(kRings - 1, segment), vertex(kRings - 1, segment + 1)});
        for (uint32_t ring = 1; ring + 1 < kRings; ++ring) {
            const uint32_t a = vertex(ring, segment), b = vertex(ring, segment + 1);
            const uint32_t c = vertex(ring + 1, segment), d = vertex(ring + 1, segment + 1);
            indices.insert(indices.end(), {a, b, d, a, d, c});
        }
    }
}

/// A lone 1 m UV sphere at (0, 1.2, 0), double-sided as Blender's default material and assimp's
/// PLY material make it, optionally standing on a 10 m ground plane, under a white sky.
Scene loadLoneSphere(const test::TempDir& dir, bool ground) {
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addSphere(positions, indices, {0.0f, 1.2f, 0.0f}, 1.0f);
    if (ground) {
        const uint32_t base = uint32_t(positions.size() / 3);
        for (const glm::vec2 corner : {glm::vec2(-5, -5), glm::vec2(-5, 5), glm::vec2(5, 5), glm::vec2(5, -5)}) {
            positions.insert(positions.end(), {corner.x, 0.0f, corner.y});
        }
        for (const uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) indices.push_back(base + k);  // facing +Y
    }
    Scene scene = loadDoubleSidedMesh(dir, positions, indices, ground ? "sphere_on_plane.gltf" : "sphere.gltf");
    scene.sky.uniform = glm::vec3(1.0f);
    return scene;
}

void expectFramedFromOutside(const Scene& scene, const char* what) {
    const Tracer tracer(scene);
    const Camera automatic = automaticCamera(tracer, glm::radians(kAutomaticCameraFovDegrees));
    const Camera framing = automaticCamera(scene, glm::radians(kAutomaticCameraFovDegrees));
    EXPECT_EQ(automatic.position, framing.position) << what;
    EXPECT_EQ(automatic.forward, framing.forward) << what;
    // The bake predicts its hit rate from the same view.
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 0, 1);
    ASSERT_EQ(views.size(), 1u) << what;
    EXPECT_EQ(views.front().camera.position, framing.position) << what;
}

TEST(AutomaticCamera, FramesAClosedDoubleSidedModelLitFromOutside) {
    // The centre of a lone double-sided sphere's bounds is free (double-sided faces do not vote),
    // no probe ray from it leaves, and the camera outside cannot see it: it passed for a room, and
    // render's camera stood inside the sphere. Nothing lights that inside: the image was black,
    // and the bake predicted a 0% hit rate from it.
    test::TempDir dir;
    const Scene sphere = loadLoneSphere(dir, false);
    expectFramedFromOutside(sphere, "a lone sphere under the sky");
    expectFramedFromOutside(loadLoneSphere(dir, true), "a sphere on a ground plane under the sky");
    // Lit by lamps around it instead of the sky, it is still looked at from outside.
    Scene lamps = sphere;
    lamps.sky = Sky{};
    for (const glm::vec3 position : {glm::vec3(3.0f, 3.0f, 0.0f), glm::vec3(-3.0f, 1.0f, 2.0f)}) {
        PunctualLight lamp;
        lamp.position = position;
        lamp.intensity = glm::vec3(10.0f);
        lamps.lights.push_back(lamp);
    }
    PunctualLight sun;
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(-1.0f, -2.0f, -0.5f));
    sun.intensity = glm::vec3(3.0f);
    lamps.lights.push_back(sun);
    expectFramedFromOutside(lamps, "a lone sphere lit by lamps and the sun");

    // A glowing sphere (double-sided emission) lights its own inside: no room either. From inside,
    // the view was a white wall and the render ran 300 times longer.
    Scene glowing = loadLoneSphere(dir, false);
    glowing.sky = Sky{};
    for (Material& m : glowing.materials) m.emissive = glm::vec3(1.0f, 0.5f, 0.2f);
    expectFramedFromOutside(glowing, "a lone glowing sphere");
}

TEST(AutomaticCamera, FramesWhatADomeHoldsFromInsideIt) {
    // A sky dome modelled as a glowing sphere 20 m wide around a sphere on a ground plane (as
    // scenes from model stores have one), no camera: the centre of the bounds lies on the ground,
    // so no room was found, and the camera framed the dome from 100 m away. It saw the dome's
    // outer side alone, which the bake, exploring the lit space inside, never reaches.
    test::TempDir dir;
    std::vector<float> positions;
    std::vector<uint32_t> indices;
    addSphere(positions, indices, {0.0f, 1.2f, 0.0f}, 1.0f);
    const uint32_t ball_end = uint32_t(indices.size() / 3);
    for (const glm::vec2 corner : {glm::vec2(-5, -5), glm::vec2(-5, 5), glm::vec2(5, 5), glm::vec2(5, -5)})
        positions.insert(positions.end(), {corner.x, 0.0f, corner.y});
    for (const uint32_t k : {0u, 1u, 2u, 0u, 2u, 3u}) indices.push_back(uint32_t(positions.size() / 3) - 4 + k);
    const uint32_t content_end = uint32_t(indices.size() / 3);
    addSphere(positions, indices, {0.0f, 0.0f, 0.0f}, 20.0f);
    Scene dome = loadDoubleSidedMesh(dir, positions, indices, "dome.gltf");
    makeEmissive(dome, content_end, uint32_t(dome.triangles.size()), glm::vec3(0.4f, 0.6f, 1.0f));
    const Tracer tracer(dome);
    const Camera view = automaticCamera(tracer, glm::radians(kAutomaticCameraFovDegrees));
    const glm::vec3 content_center(0.0f, 1.1f, 0.0f);  // of the ground and the ball: y from 0 to 2.2
    EXPECT_LT(glm::length(view.position), 0.95f * 20.0f)
        << view.position.x << ", " << view.position.y << ", " << view.position.z;
    EXPECT_GT(glm::distance(view.position, content_center), 5.0f * std::sqrt(2.0f));  // outside the content
    EXPECT_GT(glm::dot(view.forward, glm::normalize(content_center - view.position)), 0.9999f);
    EXPECT_EQ(view.name, "automatic");
    // Not from a point the bake never reaches: it sees the ball, and the ball is not emissive.
    RayHit hit;
    ASSERT_TRUE(tracer.intersect(Ray{view.position, view.forward}, hit));
    EXPECT_LT(hit.triangle, content_end);
    // The bake predicts its hit rate from the same view.
    const std::vector<PredictionView> views = predictionViews(tracer, ViewRegion{}, 0, 1);
    ASSERT_EQ(views.size(), 1u);
    EXPECT_EQ(views.front().camera.position, view.position);

    // A lamp is no dome: a glowing ball above the ball lights it, but rays from the sides meet the
    // ball (and the ground) first, so the scene is framed from outside.
    std::vector<float> lamp_positions;
    std::vector<uint32_t> lamp_indices;
    addSphere(lamp_positions, lamp_indices, {0.0f, 1.2f, 0.0f}, 1.0f);
    addSphere(lamp_positions, lamp_indices, {0.0f, 2.6f, 0.0f}, 0.3f);
    Scene lamp = loadDoubleSidedMesh(dir, lamp_positions, lamp_indices, "lamp.gltf");
    makeEmissive(lamp, ball_end, uint32_t(lamp.triangles.size()), glm::vec3(5.0f));
    expectFramedFromOutside(lamp, "a ball under a glowing ball");
}

TEST(AutomaticCamera, LooksFromInsideAClosedDoubleSidedRoomLitFromWithin) {
    // The same closed double-sided walls (Blender's default, a cube scaled into a room, wound
    // outwards) around a room with furniture: a lamp inside says it is a room, under a sky or not.
    test::TempDir dir;
    RoomOptions options{true, false, false, true};
    options.lamp = true;
    Scene room = loadRoom(dir, options);
    room.sky.uniform = glm::vec3(1.0f);
    const auto expectInside = [](const Scene& scene, const char* what) {
        const Tracer tracer(scene);
        const Camera view = automaticCamera(tracer, glm::radians(kAutomaticCameraFovDegrees));
        EXPECT_TRUE(inside(view.position, kRoomMin, kRoomMax))
            << what << ": " << view.position.x << ", " << view.position.y << ", " << view.position.z;
        EXPECT_FALSE(inside(view.position, kCubeMin, kCubeMax)) << what;
        EXPECT_FLOAT_EQ(view.forward.y, 0.0f) << what;
    };
    expectInside(room, "a 30 cm emissive panel under the ceiling");
    // A point light in place of the panel (Blender's lamps are punctual lights).
    Scene bulb = loadRoom(dir, {true, false, false, true});
    PunctualLight light;
    light.position = kLampCenter;
    light.intensity = glm::vec3(5.0f);
    bulb.lights.push_back(light);
    expectInside(bulb, "a point light under the ceiling");
    // Single-sided walls wound outwards (the scaled cube with backface culling on) put the centre
    // inside a solid by their winding; the lamp says it is a room all the same.
    RoomOptions single_sided{false, false, false, true};
    single_sided.lamp = true;
    expectInside(loadRoom(dir, single_sided), "single-sided walls wound outwards, with the panel");
    // With neither, only the sky lights the room, from outside: it is framed from outside,
    // where the sky lights its walls, as the sphere is.
    Scene unlit = loadRoom(dir, {true, false, false, true});
    unlit.sky.uniform = glm::vec3(1.0f);
    expectFramedFromOutside(unlit, "a closed double-sided room without lights inside");
}

/// readCameraPathFile's message for a file of `text`, or "" when it reads.
std::string cameraPathError(const test::TempDir& dir, const std::string& text) {
    const std::string path = dir.file("path.txt");
    std::FILE* f = std::fopen(path.c_str(), "wb");
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
    try {
        readCameraPathFile(path);
        return "";
    } catch (const CameraPathError& e) {
        return e.what();
    }
}

TEST(CameraPathFile, WaypointsReadWithSpacesOrCommasAndRefusedNamingTheLine) {
    test::TempDir dir;
    const std::string path = dir.file("path.txt");
    std::FILE* f = std::fopen(path.c_str(), "wb");
    // Comments, blank lines, CRLF line ends, spaces and tabs, and --look-at's commas.
    std::fputs("# eye then target\r\n\n0 1 5   0 1 0\r\n\t2,1,5,0,1,0,45\n3, 1, 5, 0, 1, 0\n", f);
    std::fclose(f);
    const std::vector<CameraPose> poses = readCameraPathFile(path);
    ASSERT_EQ(poses.size(), 3u);
    EXPECT_EQ(poses[0].position, glm::vec3(0, 1, 5));
    EXPECT_NEAR(poses[0].forward.z, -1.0f, 1e-6f);
    EXPECT_NEAR(poses[0].yfov, 90.0f * kPi / 180.0f, 1e-6f);
    EXPECT_EQ(poses[1].position, glm::vec3(2, 1, 5));
    EXPECT_NEAR(poses[1].yfov, 45.0f * kPi / 180.0f, 1e-6f);
    EXPECT_EQ(poses[2].position, glm::vec3(3, 1, 5));

    const auto refused = [&](const std::string& text, const std::string& message) {
        const std::string error = cameraPathError(dir, text);
        EXPECT_NE(error.find(message), std::string::npos) << "file \"" << text << "\": " << error;
    };
    refused("0 1 5 0 1 0\n1 2 3\n", "path.txt:2: expected \"px py pz tx ty tz [fov_degrees]\"");
    refused("0 1 5 0 1 nan\n", "path.txt:1: expected");
    refused("0 1 5 0 1 0 180\n", "path.txt:1: field of view must be in (0, 180) degrees");
    refused("0 1 5 0 1 0 60 extra\n", "path.txt:1: unexpected \"extra\"");
    refused("# only\n0 1 5 0 1 5\n", "path.txt:2: the eye and the target are the same point");
    // Eye and target 2e19 apart were called "the same point" (their distance overflowed float).
    refused("1e19 0 0 -1e19 0 0\n", "path.txt:1: a coordinate beyond +-1e9, where nothing of a scene may lie");
    refused("# nothing\n\n", "path.txt: the camera path file has no waypoint");
}

}  // namespace
}  // namespace sharcbake
