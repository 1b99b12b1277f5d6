// SPDX-License-Identifier: Apache-2.0
// Degenerate input and table pressure: zero-area and needle triangles, NaN/Inf positions and
// normals, a camera on a surface, odd capacities, a closed scene with no light, and a table far
// too small. Expected: no NaN/Inf in the cache, no crash, a clear message, and every loss counted.
// (Empty and sky-only scenes are refused by the command line: cli_stability_test.sh.)
#include "gltf_builder.h"
#include "stability_support.h"

#include <gtest/gtest.h>

#include <limits>

namespace sharcbake::stability {
namespace {

/// A closed 2 m box, double-sided, faces wound outwards (as a cube modelled and scaled up into a
/// room has them), Lambertian albedo 0.5, emitting 1 on every face: L = 2 everywhere inside.
struct BoxBuilder {
    test::GltfBuilder gltf;
    std::vector<float> positions{-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1, -1, 2, -1, 1, 2, -1, 1, 2, 1, -1, 2, 1};
    std::vector<uint16_t> indices{0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6, 0, 4, 5, 0, 5, 1,
                                  1, 5, 6, 1, 6, 2, 2, 6, 7, 2, 7, 3, 3, 7, 4, 3, 4, 0};
    /// Optional: a horizontal 1 m quad floating at y = 1 with these vertex normals (4 x xyz).
    std::vector<float> quad_normals;

    std::string write(const test::TempDir& dir) {
        // Specular 0: a Lambertian albedo of exactly 0.5. glTF's default dielectric layer (F0 0.04)
        // reflects a few percent more, about 2% more radiance in this furnace.
        const int material = gltf.addMaterial(
            {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1.0}}, {"metallicFactor", 0.0}}},
             {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0.0}}}}},
             {"emissiveFactor", {1.0, 1.0, 1.0}},
             {"doubleSided", true}});
        nlohmann::json primitives = nlohmann::json::array(
            {{{"attributes", {{"POSITION", gltf.addPositions(positions)}}},
              {"indices", gltf.addData(indices, test::kUnsignedShort, "SCALAR")},
              {"material", material}}});
        if (!quad_normals.empty()) {
            const std::vector<float> quad{-0.5f, 1, -0.5f, 0.5f, 1, -0.5f, 0.5f, 1, 0.5f, -0.5f, 1, 0.5f};
            const std::vector<uint16_t> quad_indices{0, 2, 1, 0, 3, 2};
            primitives.push_back({{"attributes", {{"POSITION", gltf.addPositions(quad)},
                                                  {"NORMAL", gltf.addPositions(quad_normals)}}},
                                  {"indices", gltf.addData(quad_indices, test::kUnsignedShort, "SCALAR")},
                                  {"material", material}});
        }
        const int node = gltf.addNode({{"mesh", gltf.addMesh(primitives)}});
        const int camera = gltf.addNode({{"camera", 0}, {"translation", {0.3, 1.1, 0.2}}});
        gltf.doc["cameras"] = nlohmann::json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.9}, {"znear", 0.01}}}}});
        gltf.setScene({node, camera});
        return gltf.writeEmbedded(dir, "box.gltf");
    }
    /// Appends a triangle of three new vertices.
    void addTriangle(std::initializer_list<float> xyz) {
        const uint16_t base = uint16_t(positions.size() / 3);
        positions.insert(positions.end(), xyz);
        indices.insert(indices.end(), {base, uint16_t(base + 1), uint16_t(base + 2)});
    }
};

void expectFurnaceAnswer(SmallBake& bake, double expected, double tolerance, const char* what) {
    const double measured = sampleWeightedMean(bake.cache());
    const StabilityReport report = bake.report();
    std::printf("[stability] %s: expected %g, measured %g (tolerance %g%%), NaN/Inf dropped %llu\n", what, expected,
                measured, 100.0 * tolerance, (unsigned long long)report.non_finite_dropped);
    EXPECT_NEAR(measured, expected, tolerance * expected) << what;
    EXPECT_TRUE(cacheIsFinite(bake.cache())) << what;
    EXPECT_EQ(report.non_finite_dropped, 0u) << what;
}

BakeConfig boxConfig() {
    BakeConfig config;
    config.iterations = 128;
    config.scene_scale = 10.0f;
    return config;
}

TEST(DegenerateInput, ZeroAreaTrianglesAreDroppedAndNeedlesAreHarmless) {
    BoxBuilder box;
    box.addTriangle({0, 1, 0, 0.5f, 1, 0, 1, 1, 0});                  // collinear: zero area
    box.addTriangle({0, 1, 0, 0, 1, 0, 0, 1.5f, 0});                  // two equal corners
    box.addTriangle({-0.5f, 1, 0, 0.5f, 1, 0, 0.5f, 1.000001f, 0});  // needle: 1 m x 1 um
    test::TempDir dir;
    Scene scene = loadGltf(box.write(dir));
    EXPECT_EQ(scene.stats.degenerate_triangles_dropped, 2u);
    EXPECT_EQ(scene.triangles.size(), 13u);  // the box and the needle
    SmallBake bake(std::move(scene), boxConfig());
    bake.run();
    expectFurnaceAnswer(bake, 2.0, 0.01, "box with a needle");
}

TEST(DegenerateInput, NanOrInfinitePositionIsRefusedNamingTheVertex) {
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        BoxBuilder box;
        box.positions[7] = bad;  // vertex 2, y
        test::TempDir dir;
        const std::string path = box.write(dir);
        try {
            loadGltf(path);
            ADD_FAILURE() << "a NaN/Inf vertex was accepted";
        } catch (const SceneLoadError& e) {
            const std::string message = e.what();
            EXPECT_NE(message.find("vertex 2 is NaN or infinite"), std::string::npos) << message;
        }
    }
}

TEST(DegenerateInput, NanAndInfiniteNormalsAreReplacedByTheGeometricNormal) {
    BoxBuilder box;
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    box.quad_normals = {nan, 1, 0, 0, inf, 0, 0, 0, 0, 0, 1, 0};  // NaN, Inf, zero length, fine
    test::TempDir dir;
    Scene scene = loadGltf(box.write(dir));
    ASSERT_FALSE(scene.stats.warnings.empty());
    EXPECT_NE(scene.stats.warnings.front().find("3 NaN, infinite or zero normals replaced"), std::string::npos)
        << scene.stats.warnings.front();
    for (const glm::vec3& n : scene.normals) EXPECT_TRUE(isFiniteColor(n));
    SmallBake bake(std::move(scene), boxConfig());
    bake.run();
    expectFurnaceAnswer(bake, 2.0, 0.01, "box with repaired normals");
}

/// What the loader would refuse, handed straight to the baker (a library user's scene): a
/// zero-area triangle and NaN vertex normals. No NaN may reach the cache.
TEST(DegenerateInput, DegenerateGeometryPastTheLoaderLeavesNoNanInTheCache) {
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, 0.5f, 1.0f);
    const uint32_t base = uint32_t(scene.positions.size());
    for (const glm::vec3 p : {glm::vec3(0, 1, 0), glm::vec3(1, 1, 0), glm::vec3(2, 1, 0)}) {
        scene.positions.push_back(p);
        if (!scene.normals.empty()) scene.normals.push_back(glm::vec3(std::numeric_limits<float>::quiet_NaN()));
        if (!scene.texcoords0.empty()) scene.texcoords0.push_back(glm::vec2(0.0f));
        if (!scene.texcoords1.empty()) scene.texcoords1.push_back(glm::vec2(0.0f));
    }
    scene.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
    scene.triangle_materials.push_back(0);
    for (size_t v = 0; v < scene.normals.size(); v += 5) scene.normals[v] = glm::vec3(std::numeric_limits<float>::quiet_NaN());
    SmallBake bake(std::move(scene), boxConfig());
    bake.run();
    expectFurnaceAnswer(bake, 2.0, 0.02, "furnace with NaN normals and a zero-area triangle");
}

/// The camera exactly on the floor (distance 0 to the first hits: SHaRC's level needs log(0),
/// clamped to d^2 >= 1e-10), looking along the floor, into it, and away from it.
TEST(DegenerateInput, CameraOnASurfaceGivesFiniteVoxels) {
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, 0.5f, 1.0f);
    const glm::vec3 on_floor(0.25f, 0.0f, 0.75f);  // the room's floor is y = 0
    std::vector<CameraPose> poses;
    for (const glm::vec3 forward : {glm::vec3(1, 0, 0), glm::vec3(0, -1, 0), glm::vec3(0, 1, 0)}) {
        CameraPose pose;
        pose.position = on_floor;
        pose.forward = forward;
        pose.up = std::abs(forward.y) > 0.5f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0);
        poses.push_back(pose);
    }
    SmallBake bake(std::move(scene), boxConfig(), poses);
    bake.run();
    EXPECT_GT(bake.cache().liveEntries(), 0u);
    expectFurnaceAnswer(bake, 2.0, 0.03, "camera on the floor");
}

TEST(DegenerateInput, CapacityZeroIsRefusedAndAnyOtherCapacityWorks) {
    SharcSettings settings;
    settings.grid.capacity = 0;
    EXPECT_THROW(SharcCache(settings, 1.0), std::invalid_argument);
    for (const uint32_t capacity : {50000u, 65537u}) {  // not powers of two: slot = hash mod capacity
        Scene scene = loadGltf(scenePath("furnace_rho050"));
        makeFurnace(scene, 0.5f, 1.0f);
        BakeConfig config = boxConfig();
        config.capacity = capacity;
        SmallBake bake(std::move(scene), config);
        bake.run();
        const StabilityReport report = bake.report();
        EXPECT_FALSE(report.capacity_power_of_two);
        EXPECT_EQ(report.capacity, capacity);
        EXPECT_EQ(report.failed_inserts, 0u);
        expectFurnaceAnswer(bake, 2.0, 0.02, "furnace, capacity not a power of two");
    }
}

TEST(DegenerateInput, ClosedSceneWithNoLightIsExactlyBlack) {
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, 0.5f, 0.0f);
    SmallBake bake(std::move(scene), boxConfig());
    EXPECT_FALSE(bake.lights->hasLights());
    bake.run();
    uint64_t voxels = 0;
    for (uint32_t slot = 0; slot < bake.cache().capacity(); ++slot) {
        if (bake.cache().table().keyAt(slot) == kHashGridInvalidKey) continue;
        ++voxels;
        EXPECT_EQ(bake.cache().resolved()[slot].mean, glm::vec3(0.0f));
    }
    std::printf("[stability] closed scene, no light: %llu voxels, all exactly 0\n", (unsigned long long)voxels);
    EXPECT_GT(voxels, 0u);
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
}

/// A table far too small: 64 slots (4 buckets) for a Cornell box that needs thousands. Every
/// failed insert is counted with its energy, the report says how much is lost, and nothing is
/// written outside the table (the sanitized run checks that too).
TEST(TablePressure, FailedInsertsAndTheirEnergyAreCountedAndReported) {
    Scene scene = loadGltf(scenePath("cornell_box"));
    BakeConfig config;
    config.iterations = 32;
    config.capacity = 64;
    config.scene_scale = 20.0f;
    SmallBake bake(std::move(scene), config);
    bake.run();
    const StabilityReport report = bake.report();
    const double lost = report.share(report.failed_insert_energy);
    std::printf("[stability] table pressure: %llu of %llu deposits failed to insert, %.1f%% of the energy lost, "
                "%llu of %u slots used\n",
                (unsigned long long)report.failed_inserts, (unsigned long long)report.deposits, 100.0 * lost,
                (unsigned long long)report.occupied_slots, report.capacity);
    EXPECT_EQ(report.occupied_slots, 64u);
    EXPECT_GT(report.failed_inserts, report.deposits / 2);
    EXPECT_GT(lost, 0.5);
    EXPECT_LE(lost, 1.0);
    ASSERT_FALSE(report.warnings.empty());
    EXPECT_NE(report.warnings.front().find("raise --capacity"), std::string::npos) << report.warnings.front();
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
    // The energy that did arrive: what the cache holds is the deposited minus the failed share.
    EXPECT_GT(report.deposited_energy, report.failed_insert_energy);
}

/// The precision warnings' advice depends on the cause. The ray offset: the tracer's guard is a
/// few float32 roundings of the coordinates, so a scene tiny in its units is as safe as the same
/// scene in larger units (no warning; with the fixed guard near the origin it had, it was told to
/// scale up), and only one far from the origin is told to move. The float spacing: a scene whose
/// own size puts its far corner there must scale down; one far from the origin must move.
/// Voxel sizes of the grid fit's choices for a 1 mm Cornell box and for larger scenes.
TEST(ExtremeScaleAdvice, TinySceneIsSafeHugeOneIsToldToScaleDownAndAFarOneToMove) {
    SharcSettings settings;
    settings.grid.capacity = 1024;
    settings.grid.scene_scale = 50.0f;
    settings.grid.level_bias = 12.48f;  // level 1 about 7e-6 wide: the grid fit's choice for a 1 mm box
    const SharcCache tiny_cache(settings, 1.0);
    const StabilityReport tiny =
        makeStabilityReport(tiny_cache, UpdateCounters{}, glm::vec3(0.0f), glm::vec3(1e-3f), {1});
    EXPECT_LT(tiny.ray_offset, 0.01 * tiny.finest_voxel_size);
    EXPECT_TRUE(tiny.warnings.empty()) << tiny.warnings.front();

    settings.grid.level_bias = -2.0f;  // level 1 several centimetres wide
    const SharcCache far_cache(settings, 1.0);
    const StabilityReport far =
        makeStabilityReport(far_cache, UpdateCounters{}, glm::vec3(1e6f, 0.0f, 0.0f), glm::vec3(1e6f + 1.0f, 1.0f, 1.0f), {1});
    EXPECT_GT(far.ray_offset, far.finest_voxel_size);
    bool move_advice = false;
    for (const std::string& w : far.warnings) move_advice |= w.find("ray origins") != std::string::npos &&
                                                             w.find("towards the origin") != std::string::npos;
    EXPECT_TRUE(move_advice);

    // Float spacing against SHaRC's 1e-4 position bias: a 100 km scene around the origin (CAD in
    // millimetres of a 100 m site) is told to scale down; a 1 unit scene 1e6 away, to move.
    const StabilityReport huge =
        makeStabilityReport(far_cache, UpdateCounters{}, glm::vec3(-5e4f), glm::vec3(5e4f), {1});
    const auto advice = [](const StabilityReport& report, const char* text) {
        for (const std::string& w : report.warnings) {
            if (w.find("position bias") != std::string::npos && w.find(text) != std::string::npos) return true;
        }
        return false;
    };
    EXPECT_TRUE(advice(huge, "scale it down"));
    EXPECT_FALSE(advice(huge, "towards the origin"));
    EXPECT_TRUE(advice(far, "towards the origin"));
    EXPECT_FALSE(advice(far, "scale it down"));

    // A 4-unit room 1e7 out: the grid fit's voxels there (20 units) exceed the ray offset (19),
    // which is still 476% of the room; it baked 30% dark and only render warned.
    settings.grid.level_bias = -8.97f;  // level 1 about 20 units wide
    const SharcCache distant_cache(settings, 1.0);
    const StabilityReport distant = makeStabilityReport(distant_cache, UpdateCounters{}, glm::vec3(1e7f, 0.0f, 0.0f),
                                                        glm::vec3(1e7f + 4.0f, 4.0f, 4.0f), {1});
    EXPECT_LT(distant.ray_offset, distant.finest_voxel_size);
    bool offset_named = false;
    for (const std::string& w : distant.warnings)
        offset_named |= w.find("of the scene's largest side (4)") != std::string::npos &&
                        w.find("towards the origin") != std::string::npos;
    EXPECT_TRUE(offset_named);

    // A room 4e-6 across (4 m scaled by 1e-6), with the bias the grid fit gives it: every lookup's
    // level follows the position bias's 1.7e-4, in voxels 3.3e-6 wide, and a render through its
    // cache found 8 hits among 112,573 refused lookups while the bake found no problem. At 4e-5
    // (19 such voxels across) renders hit as at 4 m: no warning.
    const auto biasWarning = [&](float side, float level_bias) {
        settings.grid.level_bias = level_bias;
        const SharcCache cache(settings, 1.0);
        const StabilityReport report = makeStabilityReport(cache, UpdateCounters{}, glm::vec3(-0.5f * side),
                                                           glm::vec3(0.5f * side), {1});
        for (const std::string& w : report.warnings) {
            if (w.find("SHaRC adds 1e-4 to every coordinate") != std::string::npos) return w;
        }
        return std::string();
    };
    const std::string micro = biasWarning(4e-6f, 20.5625f);
    EXPECT_NE(micro.find("in voxels 3.31e-06 wide (83% of the scene)"), std::string::npos) << micro;
    EXPECT_NE(micro.find("Scale the scene up"), std::string::npos) << micro;
    EXPECT_EQ(biasWarning(4e-5f, 17.25f), "");
    EXPECT_EQ(biasWarning(1e-3f, 12.48f), "");
}

}  // namespace
}  // namespace sharcbake::stability
