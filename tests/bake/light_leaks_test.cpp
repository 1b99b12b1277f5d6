// SPDX-License-Identifier: Apache-2.0
// Light leaks: an emitter that shares SHaRC voxels with a surface behind it facing the same way.
#include "sharc/light_leaks.h"

#include <gtest/gtest.h>

namespace sharcbake {
namespace {

/// Appends a square of side `side` centred on `centre` in the plane y = centre.y, facing -Y
/// (down) or +Y, with a material of its own.
void addSquare(Scene& scene, glm::vec3 centre, float side, bool facing_down, float emission, bool double_sided) {
    Material m;
    m.name = emission > 0.0f ? "lamp" : "ceiling";
    m.base_color = glm::vec3(0.5f);
    m.metallic = 0.0f;
    m.emissive = glm::vec3(emission > 0.0f ? 1.0f : 0.0f);
    m.emissive_strength = emission > 0.0f ? emission : 1.0f;
    m.double_sided = double_sided;
    const uint32_t material = uint32_t(scene.materials.size());
    scene.materials.push_back(m);
    const uint32_t base = uint32_t(scene.positions.size());
    const float h = 0.5f * side;
    for (glm::vec2 d : {glm::vec2(-h, -h), glm::vec2(-h, h), glm::vec2(h, -h), glm::vec2(h, h)}) {
        scene.positions.push_back(centre + glm::vec3(d.x, 0.0f, d.y));
    }
    // Counter-clockwise seen from below faces -Y.
    if (facing_down) {
        scene.triangles.push_back(glm::uvec3(base, base + 2, base + 1));
        scene.triangles.push_back(glm::uvec3(base + 2, base + 3, base + 1));
    } else {
        scene.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
        scene.triangles.push_back(glm::uvec3(base + 2, base + 1, base + 3));
    }
    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
    scene.bounds_min = glm::min(scene.bounds_min, centre - glm::vec3(h, 0.0f, h));
    scene.bounds_max = glm::max(scene.bounds_max, centre + glm::vec3(h, 0.0f, h));
}

/// A ceiling at a height off any voxel boundary and a lamp `gap` below it, both facing down
/// unless told otherwise, seen from a camera one unit below.
Scene lampUnderCeiling(float gap, bool ceiling_faces_down = true, bool lamp_faces_down = true,
                       bool lamp_double_sided = false) {
    Scene scene;
    scene.bounds_min = glm::vec3(std::numeric_limits<float>::max());
    scene.bounds_max = glm::vec3(-std::numeric_limits<float>::max());
    constexpr float kCeiling = 1.0137f;
    addSquare(scene, glm::vec3(0.0f, kCeiling, 0.0f), 2.0f, ceiling_faces_down, 0.0f, false);
    // Off the voxel grid's boundaries: a lamp whose edges fall on them fills whole voxels, and
    // no voxel holds it and the ceiling beside it.
    addSquare(scene, glm::vec3(0.013f, kCeiling - gap, 0.017f), 0.4f, lamp_faces_down, 10.0f, lamp_double_sided);
    return scene;
}

const std::vector<glm::vec3> kCameras = {glm::vec3(0.0f)};

/// The voxel SHaRC gives the lamp from the camera (1 unit away, default grid).
float lampVoxel(const HashGridParameters& grid) {
    const HashGridKeyer keyer(grid);
    return keyer.voxelSizeAt(keyer.levelOf(1.0f));
}

TEST(LightLeaks, ALampJustBelowACeilingSharesItsVoxels) {
    const HashGridParameters grid;
    const float voxel = lampVoxel(grid);
    ASSERT_GT(voxel, 0.01f);
    const Scene scene = lampUnderCeiling(0.001f);
    const Tracer tracer(scene);
    const LightLeakReport report = findLightLeaks(tracer, grid, kCameras, 256);
    EXPECT_EQ(report.emissive_materials, 1u);
    EXPECT_EQ(report.points, 256u);
    ASSERT_EQ(report.leaks.size(), 1u);
    const EmitterLeak& leak = report.leaks.front();
    EXPECT_EQ(leak.material_label, "material 'lamp'");
    // The voxels along its edge, which hold the lamp and the ceiling beside it: 19% of its area
    // (the edges fall 0.013-0.027 into their voxel columns of 0.04).
    EXPECT_GT(leak.area_share, 0.12);
    EXPECT_LT(leak.area_share, 0.26);
    EXPECT_NEAR(leak.median_gap, 0.001f, 2e-4f);
    EXPECT_FLOAT_EQ(leak.voxel_size, voxel);
    const std::string text = LightLeakReport::describe(leak);
    EXPECT_NE(text.find("material 'lamp'"), std::string::npos) << text;
    EXPECT_NE(text.find("light leak"), std::string::npos) << text;
    // A long material name (exporters write paths into them) does not cut the advice short.
    EmitterLeak named = leak;
    named.material_label = "material '" + std::string(300, 'x') + "'";
    const std::string long_text = LightLeakReport::describe(named);
    EXPECT_NE(long_text.find("remove the surface behind it"), std::string::npos) << long_text;
}

TEST(LightLeaks, AFlushLampIsFoundAndAVoxelAwayIsNot) {
    const HashGridParameters grid;
    const float voxel = lampVoxel(grid);
    {
        const Scene flush = lampUnderCeiling(0.0f);
        const Tracer tracer(flush);
        const LightLeakReport report = findLightLeaks(tracer, grid, kCameras, 256);
        ASSERT_EQ(report.leaks.size(), 1u) << "a lamp modelled into the ceiling's plane";
        EXPECT_LT(report.leaks.front().median_gap, 1e-4f);
    }
    const Scene apart = lampUnderCeiling(1.01f * voxel);
    const Tracer tracer(apart);
    EXPECT_TRUE(findLightLeaks(tracer, grid, kCameras, 256).leaks.empty()) << "a voxel apart never shares one";
}

TEST(LightLeaks, OnlySurfacesFacingTheEmittersWayShareItsVoxels) {
    const HashGridParameters grid;
    {
        // The ceiling's back faces the lamp: the inside of a closed object, never lit.
        const Scene scene = lampUnderCeiling(0.001f, /*ceiling_faces_down=*/false);
        const Tracer tracer(scene);
        EXPECT_TRUE(findLightLeaks(tracer, grid, kCameras, 256).leaks.empty());
    }
    {
        // A single-sided lamp facing up lights the ceiling: the surface behind it is the floor
        // side, and there is none; its back (facing the ceiling's way) does not emit.
        const Scene scene = lampUnderCeiling(0.001f, true, /*lamp_faces_down=*/false);
        const Tracer tracer(scene);
        EXPECT_TRUE(findLightLeaks(tracer, grid, kCameras, 256).leaks.empty());
    }
    {
        // The same lamp double-sided emits downwards too: it leaks again.
        const Scene scene = lampUnderCeiling(0.001f, true, false, /*lamp_double_sided=*/true);
        const Tracer tracer(scene);
        EXPECT_EQ(findLightLeaks(tracer, grid, kCameras, 256).leaks.size(), 1u);
    }
}

TEST(LightLeaks, FarCamerasSeeCoarserVoxelsThatLeakFurther) {
    // 5 cm below the ceiling: separate in the voxels of a camera 1 unit away, shared in those of
    // one 100 units away.
    HashGridParameters grid;
    const Scene scene = lampUnderCeiling(0.05f);
    const Tracer tracer(scene);
    ASSERT_LT(lampVoxel(grid), 0.05f);
    EXPECT_TRUE(findLightLeaks(tracer, grid, kCameras, 256).leaks.empty());
    const LightLeakReport far = findLightLeaks(tracer, grid, {glm::vec3(0.0f, -100.0f, 0.0f)}, 256);
    ASSERT_EQ(far.leaks.size(), 1u);
    EXPECT_GT(far.leaks.front().voxel_size, 0.05f);
}

TEST(LightLeaks, DeterministicAndEmptyWithoutEmittersOrCameras) {
    const HashGridParameters grid;
    const Scene scene = lampUnderCeiling(0.001f);
    const Tracer tracer(scene);
    const LightLeakReport a = findLightLeaks(tracer, grid, kCameras, 128, 7);
    const LightLeakReport b = findLightLeaks(tracer, grid, kCameras, 128, 7);
    ASSERT_EQ(a.leaks.size(), b.leaks.size());
    EXPECT_EQ(a.leaks.front().area_share, b.leaks.front().area_share);
    EXPECT_EQ(a.leaks.front().median_gap, b.leaks.front().median_gap);
    EXPECT_EQ(findLightLeaks(tracer, grid, {}, 128).points, 0u);

    Scene dark = lampUnderCeiling(0.001f);
    for (Material& m : dark.materials) m.emissive = glm::vec3(0.0f);
    const Tracer dark_tracer(dark);
    const LightLeakReport none = findLightLeaks(dark_tracer, grid, kCameras, 128);
    EXPECT_EQ(none.emissive_materials, 0u);
    EXPECT_TRUE(none.leaks.empty());
}

}  // namespace
}  // namespace sharcbake
