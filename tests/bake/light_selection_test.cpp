// SPDX-License-Identifier: Apache-2.0
// Light selection by where light arrives: the grid's shares, and a sampler that spends its
// shadow rays on the lights a point can see while its estimates stay unbiased.
#include "sharcbake/scene_loader.h"
#include "test_rooms.h"
#include "tracing/light_grid.h"
#include "tracing/lights.h"
#include "tracing/sampling.h"
#include "tracing/surface_points.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>
#include <string>

namespace sharcbake {
namespace {

TEST(LightSelectionGrid, CellsAreCubesAlongTheLongestAxisAndOutsidePointsTakeTheNearest) {
    const LightSelectionGrid grid(glm::vec3(0.0f), glm::vec3(8.0f, 2.0f, 0.0f), 16);
    EXPECT_EQ(grid.dimensions(), glm::uvec3(16u, 4u, 1u));
    EXPECT_EQ(grid.slotCount(), 16u * 4u * 6u);
    EXPECT_FLOAT_EQ(grid.cellSize(), 0.5f);
    EXPECT_EQ(grid.cellOf(glm::vec3(0.25f, 0.25f, 0.0f)), 0u);
    EXPECT_EQ(grid.cellOf(glm::vec3(1.25f, 0.75f, 0.0f)), 16u + 2u);
    EXPECT_EQ(grid.cellOf(glm::vec3(-5.0f, -5.0f, -5.0f)), 0u);
    EXPECT_EQ(grid.cellOf(glm::vec3(100.0f, 100.0f, 100.0f)), grid.cellCount() - 1);
    EXPECT_EQ(grid.cellOf(glm::vec3(std::numeric_limits<float>::quiet_NaN())), 0u);
    // Slots: the six directions by a normal's largest component.
    EXPECT_EQ(grid.slotOf(glm::vec3(1.25f, 0.75f, 0.0f), glm::vec3(0.1f, -0.9f, 0.3f)), (16u + 2u) * 6u + 3u);
    EXPECT_EQ(LightSelectionGrid::directionOf(glm::vec3(1.0f, 0.0f, 0.0f)), 0u);
    EXPECT_EQ(LightSelectionGrid::directionOf(glm::vec3(-1.0f, 0.5f, 0.0f)), 1u);
    EXPECT_EQ(LightSelectionGrid::directionOf(glm::vec3(0.0f, 0.0f, -2.0f)), 5u);
    EXPECT_EQ(LightSelectionGrid::directionOf(glm::vec3(std::numeric_limits<float>::quiet_NaN())), 0u);
}

TEST(LightSelectionGrid, ADetailBoxTakesThePointsInsideItInFinerCellsNumberedAfterTheCoarseOnes) {
    const LightSelectionGrid grid(glm::vec3(-1000.0f, 0.0f, -1000.0f), glm::vec3(1000.0f, 10.0f, 1000.0f), 32,
                                  glm::vec3(0.0f), glm::vec3(16.0f, 4.0f, 8.0f), 32);
    EXPECT_EQ(grid.dimensions(), glm::uvec3(32u, 1u, 32u));
    EXPECT_EQ(grid.detailDimensions(), glm::uvec3(32u, 8u, 16u));
    EXPECT_FLOAT_EQ(grid.detailCellSize(), 0.5f);
    const uint32_t coarse = 32u * 32u;
    EXPECT_EQ(grid.cellCount(), coarse + 32u * 8u * 16u);
    EXPECT_EQ(grid.slotCount(), grid.cellCount() * 6u);
    EXPECT_EQ(grid.cellOf(glm::vec3(0.25f, 0.25f, 0.25f)), coarse);
    EXPECT_EQ(grid.cellOf(glm::vec3(1.25f, 0.75f, 0.25f)), coarse + 32u + 2u);
    EXPECT_EQ(grid.cellOf(glm::vec3(16.0f, 4.0f, 8.0f)), grid.cellCount() - 1);  // the box's far corner is in it
    // Just outside the box: the coarse cell there (62.5 wide, the middle of 32 along x and z).
    EXPECT_EQ(grid.cellOf(glm::vec3(16.5f, 1.0f, 1.0f)), 16u * 32u + 16u);
    EXPECT_EQ(grid.cellOf(glm::vec3(-0.5f, 1.0f, 1.0f)), 16u * 32u + 15u);
    EXPECT_LT(grid.cellOf(glm::vec3(std::numeric_limits<float>::quiet_NaN())), coarse);
}

TEST(LightSelectionGrid, SharesAreTheWeightsNormalisedAndPickedInProportion) {
    LightSelectionGrid grid(glm::vec3(0.0f), glm::vec3(2.0f, 1.0f, 1.0f), 2);
    ASSERT_EQ(grid.slotCount(), 12u);
    grid.setWeights({{{7, 3.0}, {2, 1.0}, {5, 0.0}}, {{1, 0.0}, {4, -1.0}}});
    EXPECT_EQ(grid.slotsWithShares(), 1u);
    ASSERT_TRUE(grid.hasShares(0));
    EXPECT_FALSE(grid.hasShares(1));  // no positive weight: selection by power there
    EXPECT_FLOAT_EQ(grid.probability(0, 7), 0.75f);
    EXPECT_FLOAT_EQ(grid.probability(0, 2), 0.25f);
    EXPECT_EQ(grid.probability(0, 5), 0.0f);
    EXPECT_EQ(grid.probability(0, 3), 0.0f);
    int sevens = 0;
    constexpr int kDraws = 4000;
    for (int i = 0; i < kDraws; ++i) {
        float remapped = -1.0f;
        const float u = (float(i) + 0.5f) / float(kDraws);
        const LightSelectionGrid::Share& share = grid.pick(0, u, remapped);
        sevens += share.group == 7;
        EXPECT_GE(remapped, 0.0f);
        EXPECT_LT(remapped, 1.0f);
    }
    EXPECT_EQ(sevens, 3000);
    float remapped = 0.0f;
    EXPECT_EQ(grid.pick(0, 0x1.fffffep-1f, remapped).group, 7u);
}

/// Two closed rooms side by side, 5 cm apart: room A (x < 0) has a bright ceiling panel, room
/// B (x > 0.05) only a dim bulb. By power, a point in B would pick the panel it cannot see 99%
/// of the time.
/// A grey diffuse material named "wall".
Material wallMaterial(float albedo) {
    Material wall;
    wall.name = "wall";
    wall.base_color = glm::vec3(albedo);
    wall.metallic = 0.0f;
    return wall;
}

/// Appends the quad (a, b, c, d), two triangles facing the side it winds counter-clockwise to.
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t material) {
    const uint32_t base = uint32_t(scene.positions.size());
    scene.positions.insert(scene.positions.end(), {a, b, c, d});
    scene.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
    scene.triangles.push_back(glm::uvec3(base, base + 2, base + 3));
    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
    scene.bounds_min = glm::min(scene.bounds_min, glm::min(glm::min(a, b), glm::min(c, d)));
    scene.bounds_max = glm::max(scene.bounds_max, glm::max(glm::max(a, b), glm::max(c, d)));
}

PunctualLight pointLight(const char* name, glm::vec3 position, float intensity) {
    PunctualLight light;
    light.name = name;
    light.position = position;
    light.intensity = glm::vec3(intensity);
    return light;
}

Scene twoRoomsOneBright() {
    Scene scene = emptyTestScene();
    const Material wall = wallMaterial(0.7f);
    scene.materials.push_back(wall);
    Material panel = wall;
    panel.name = "panel";
    panel.emissive = glm::vec3(1.0f);
    panel.emissive_strength = 50.0f;
    scene.materials.push_back(panel);
    addInwardBox(scene, glm::vec3(-2.0f, 0.0f, -1.0f), glm::vec3(0.0f, 2.0f, 1.0f), 0);
    addInwardBox(scene, glm::vec3(0.05f, 0.0f, -1.0f), glm::vec3(2.05f, 2.0f, 1.0f), 0);
    // Facing down (-Y): counter-clockwise seen from below.
    addQuad(scene, glm::vec3(-1.3f, 1.95f, -0.3f), glm::vec3(-0.7f, 1.95f, -0.3f), glm::vec3(-0.7f, 1.95f, 0.3f),
            glm::vec3(-1.3f, 1.95f, 0.3f), 1u);
    scene.lights.push_back(pointLight("bulb", glm::vec3(1.05f, 1.0f, 0.0f), 0.02f));
    return scene;
}

const glm::vec3 kUp(0.0f, 1.0f, 0.0f);

SurfaceHit floorPoint(glm::vec3 position) {
    SurfaceHit hit;
    hit.position = position;
    hit.geometric_normal = hit.shading_normal = hit.face_normal = glm::vec3(0.0f, 1.0f, 0.0f);
    return hit;
}

/// The mean and variance of the one-sample direct-light estimate (radiance x cosine / pdf,
/// occlusion tested) at a floor point.
std::pair<double, double> directLightEstimate(const Tracer& tracer, const LightSampler& lights, glm::vec3 at,
                                              uint32_t samples) {
    const SurfaceHit hit = floorPoint(at);
    double sum = 0.0, sum2 = 0.0;
    for (uint32_t i = 0; i < samples; ++i) {
        PixelSampler sampler(3u, 0u, i);
        const glm::vec2 u_select = sampler.next2D();
        const glm::vec2 u = sampler.next2D();
        LightSample light;
        double value = 0.0;
        if (lights.sample(hit, u_select.x, u, light)) {
            const float cosine = glm::dot(hit.geometric_normal, light.wi);
            Ray shadow;
            if (cosine > 0.0f &&
                shadowRayTo(hit.position, hit.geometric_normal, hit.ray_offset, light.wi, light.distance, shadow) &&
                !tracer.occluded(shadow))
                value = double(luminance(light.radiance)) * double(cosine) / double(light.pdf);
        }
        sum += value;
        sum2 += value * value;
    }
    const double mean = sum / samples;
    return {mean, sum2 / samples - mean * mean};
}

TEST(SpatialLightSelection, APointPicksTheLightsItsRoomSees) {
    const Scene scene = twoRoomsOneBright();
    const Tracer tracer(scene);
    const LightSampler by_power(scene);
    const LightSampler learned(tracer);
    const SpatialLightSelection& spatial = learned.spatialSelection();
    EXPECT_EQ(spatial.groups, 2u);  // the panel (one piece of two triangles) and the bulb
    ASSERT_TRUE(spatial.active());
    EXPECT_GT(spatial.shadow_rays, 10000u);
    const size_t bulb = learned.entryCount() - 1;  // area lights come first, then punctual ones
    const glm::vec3 in_b(1.5f, 0.0f, 0.4f), in_a(-1.5f, 0.0f, 0.4f);
    EXPECT_LT(by_power.selectionPmf(bulb, in_b, kUp), 0.01f);
    // Room B's cells list only the bulb: all but the power share picks it.
    EXPECT_GT(learned.selectionPmf(bulb, in_b, kUp), 0.75f);
    // Room A sees both; the panel gives it far more.
    EXPECT_LT(learned.selectionPmf(bulb, in_a, kUp), 0.05f);
    // Every point's probabilities sum to one.
    for (const glm::vec3 at : {in_a, in_b, glm::vec3(0.02f, 1.0f, 0.0f), glm::vec3(50.0f, -3.0f, 0.0f)}) {
        double total = 0.0;
        for (size_t e = 0; e < learned.entryCount(); ++e) total += learned.selectionPmf(e, at, kUp);
        EXPECT_NEAR(total, 1.0, 1e-5) << at.x;
    }
}

/// A closed 4 x 2.5 x 4 m room lit by a dim bulb, on a sunlit ground 200 m wide: the grid's
/// cells are 6.25 m, so the cell holding the room's floor holds more sunlit ground and roof.
Scene roomOnSunlitGround() {
    Scene scene = emptyTestScene();
    scene.materials.push_back(wallMaterial(0.5f));
    addInwardBox(scene, glm::vec3(0.5f, 0.0f, 0.5f), glm::vec3(4.5f, 2.5f, 4.5f), 0);
    // The ground, facing up.
    addQuad(scene, glm::vec3(-100.0f, -0.01f, -100.0f), glm::vec3(-100.0f, -0.01f, 100.0f),
            glm::vec3(100.0f, -0.01f, 100.0f), glm::vec3(100.0f, -0.01f, -100.0f), 0u);
    scene.lights.push_back(pointLight("bulb", glm::vec3(2.5f, 2.0f, 2.5f), 0.05f));
    PunctualLight sun;
    sun.name = "sun";
    sun.type = LightType::Directional;
    sun.direction = glm::normalize(glm::vec3(0.3f, -1.0f, 0.2f));
    sun.intensity = glm::vec3(150.0f);
    scene.lights.push_back(sun);
    return scene;
}

TEST(SpatialLightSelection, EachPointOfASlotHasAnEqualSayInItsShares) {
    Scene scene = roomOnSunlitGround();
    // A camera at the ground's far corner: the cameras and lamps span the scene, so there is no
    // detail box, and the room shares its coarse cell with the ground.
    Camera far_away;
    far_away.position = glm::vec3(-95.0f, 1.5f, -95.0f);
    scene.cameras.push_back(far_away);
    const Tracer tracer(scene);
    const LightSampler by_power(scene);
    const LightSampler learned(tracer);
    ASSERT_TRUE(learned.spatialSelection().active());
    ASSERT_EQ(learned.spatialSelection().detail_cells.x, 0u);
    const size_t bulb = learned.entryCount() - 2;
    const glm::vec3 floor_inside(2.0f, 0.0f, 3.0f);
    EXPECT_LT(by_power.selectionPmf(bulb, floor_inside, kUp), 1e-3f);
    // The floor's slot also holds the ground outside and the roof, 30000 times brighter under
    // the sun: summed raw, their light made power look right for the whole slot, which left the
    // bulb 1e-7 of the floor's picks. Each point's own shares averaged give the bulb about the
    // floor's part of the slot's points (0.25 measured).
    const float picked = learned.selectionPmf(bulb, floor_inside, kUp);
    std::printf("[light selection] the bulb's share of the floor's picks: %.3g (by power %.3g)\n", double(picked),
                double(by_power.selectionPmf(bulb, floor_inside, kUp)));
    EXPECT_GT(picked, 0.15f);
}

TEST(SurfacePointsInBox, SpreadByAreaOverTheClippedSurfacesInside) {
    Scene scene = roomOnSunlitGround();  // the ground's two triangles are 200 m wide
    const glm::vec3 lo(-3.0f, -1.0f, -3.0f), hi(3.0f, 1.0f, 3.0f);
    constexpr uint32_t kCount = 20000;
    const std::vector<SurfacePoint> points = sampleSurfacePointsInBox(scene, lo, hi, kCount, 3u);
    ASSERT_EQ(points.size(), kCount);
    // Inside the box: the ground's 6 x 6 m and the room's 2.5 x 2.5 m floor corner (its floor is
    // [0.5, 4.5]^2 at y = 0) and the walls' 1 m strips in x = 0.5 and z = 0.5 up to y = 1.
    const double ground = 36.0, floor = 2.5 * 2.5, walls = 2.0 * 2.5 * 1.0;
    uint32_t on_ground = 0, on_floor = 0, on_walls = 0;
    for (const SurfacePoint& p : points) {
        ASSERT_TRUE(glm::all(glm::greaterThanEqual(p.position, lo - 1e-4f)) &&
                    glm::all(glm::lessThanEqual(p.position, hi + 1e-4f)))
            << p.position.x << " " << p.position.y << " " << p.position.z;
        // The point lies on its triangle at its barycentrics.
        const glm::uvec3 tri = scene.triangles[p.triangle];
        const glm::vec3 at = (1.0f - p.barycentrics.x - p.barycentrics.y) * scene.positions[tri.x] +
                             p.barycentrics.x * scene.positions[tri.y] + p.barycentrics.y * scene.positions[tri.z];
        ASSERT_NEAR(glm::length(at - p.position), 0.0f, 1e-4f);
        if (p.position.y < -0.005f) ++on_ground;
        else if (std::abs(p.position.y) < 1e-4f) ++on_floor;
        else ++on_walls;
    }
    const double total = ground + floor + walls;
    // Within 5 standard deviations of a binomial share.
    for (const auto& [count, area] :
         {std::pair(on_ground, ground), std::pair(on_floor, floor), std::pair(on_walls, walls)}) {
        const double share = area / total;
        EXPECT_NEAR(double(count) / kCount, share, 5.0 * std::sqrt(share * (1.0 - share) / kCount)) << area;
    }
    EXPECT_TRUE(sampleSurfacePointsInBox(scene, glm::vec3(500.0f), glm::vec3(501.0f), kCount, 3u).empty());
}

TEST(SpatialLightSelection, ARoomOnAGroundAKilometreWideGetsCellsOfItsOwnSize) {
    Scene scene = roomOnSunlitGround();
    // Widen the ground to 2 km: the coarse cells are 62.5 m, the whole room one of them.
    for (size_t v = scene.positions.size() - 4; v < scene.positions.size(); ++v) scene.positions[v] *= 10.0f;
    scene.bounds_min = glm::vec3(-1000.0f, -0.1f, -1000.0f);
    scene.bounds_max = glm::vec3(1000.0f, 2.5f, 1000.0f);
    Camera camera;
    camera.name = "inside";
    camera.position = glm::vec3(1.0f, 1.5f, 1.0f);
    scene.cameras.push_back(camera);
    const Tracer tracer(scene);
    const LightSampler learned(tracer);
    const SpatialLightSelection& spatial = learned.spatialSelection();
    ASSERT_TRUE(spatial.active());
    EXPECT_FLOAT_EQ(spatial.cell_size, 62.5f);
    // The box holds the room (the rays from the camera and the bulb find its walls) and a margin.
    ASSERT_GT(spatial.detail_cells.x, 0u) << spatial.describe();
    EXPECT_LE(spatial.detail_min.x, 0.5f);
    EXPECT_GE(spatial.detail_max.x, 4.5f);
    EXPECT_LE(spatial.detail_min.y, 0.0f);
    EXPECT_LT(spatial.detail_max.x - spatial.detail_min.x, 10.0f);
    EXPECT_LT(spatial.detail_cell_size, 0.3f);
    EXPECT_NE(spatial.describe().find("over the"), std::string::npos) << spatial.describe();
    // The floor picks the bulb, and its estimate is the bulb's analytic light: intensity x cos /
    // distance^2 (the sun cannot reach it).
    const size_t bulb = learned.entryCount() - 2;
    const glm::vec3 floor_inside(2.0f, 0.0f, 3.0f);
    EXPECT_GT(learned.selectionPmf(bulb, floor_inside, kUp), 0.7f);
    constexpr uint32_t kSamples = 1u << 16;
    const auto [mean, variance] = directLightEstimate(tracer, learned, floor_inside, kSamples);
    const glm::vec3 to_bulb = scene.lights[0].position - floor_inside;
    const double analytic = double(scene.lights[0].intensity.x) * double(to_bulb.y) /
                            std::pow(double(glm::length(to_bulb)), 3.0);
    EXPECT_NEAR(mean, analytic, 3.0 * std::sqrt(variance / kSamples) + 1e-3 * analytic);
    // By power the bulb is picked 1e-8 of the time: its estimate would be 0 at these samples.
    const LightSampler by_power(scene);
    EXPECT_LT(by_power.selectionPmf(bulb, floor_inside, kUp), 1e-6f);
    // A scene whose cameras and lamps spread over most of it gets no detail box.
    const Scene rooms = twoRoomsOneBright();
    const Tracer rooms_tracer(rooms);
    EXPECT_EQ(LightSampler(rooms_tracer).spatialSelection().detail_cells.x, 0u);
}

TEST(SpatialLightSelection, EstimatesStayUnbiasedWithFarLessNoiseWhereAPowerfulLightIsHidden) {
    const Scene scene = twoRoomsOneBright();
    const Tracer tracer(scene);
    const LightSampler by_power(scene);
    const LightSampler learned(tracer);
    constexpr uint32_t kSamples = 1u << 17;
    for (const glm::vec3 at :
         {glm::vec3(1.5f, 0.0f, 0.4f), glm::vec3(-1.5f, 0.0f, 0.4f), glm::vec3(0.3f, 0.0f, -0.6f)}) {
        const auto [power_mean, power_variance] = directLightEstimate(tracer, by_power, at, kSamples);
        const auto [learned_mean, learned_variance] = directLightEstimate(tracer, learned, at, kSamples);
        ASSERT_GT(power_mean, 0.0);
        // Within 3 standard errors of the power estimate (the noisier), and 2% besides.
        const double tolerance = 3.0 * std::sqrt(power_variance / kSamples) + 0.02 * power_mean;
        EXPECT_NEAR(learned_mean, power_mean, tolerance) << "at x = " << at.x;
        std::printf("[light selection] x %+.1f: mean %.5g (by power %.5g), variance %.3g (by power %.3g)\n",
                    double(at.x), learned_mean, power_mean, learned_variance, power_variance);
        if (at.x > 0.05f) {
            // Room B: by power, 99% of picks go to the hidden panel.
            EXPECT_LT(learned_variance * 20.0, power_variance) << "at x = " << at.x;
        }
    }
}

TEST(SpatialLightSelection, TheEmitterAndSkyPdfsMatchWhatSampleReturns) {
    Scene scene = twoRoomsOneBright();
    // Open room A's floor to a sky below (its two floor triangles removed) so the sky is a light.
    scene.triangles.erase(scene.triangles.begin() + 4, scene.triangles.begin() + 6);
    scene.triangle_materials.erase(scene.triangle_materials.begin() + 4, scene.triangle_materials.begin() + 6);
    scene.sky.uniform = glm::vec3(0.3f);
    const Tracer tracer(scene);
    const LightSampler lights(tracer);
    ASSERT_TRUE(lights.spatialSelection().active());
    ASSERT_TRUE(lights.hasSky());
    uint32_t emitter_checks = 0, sky_checks = 0;
    for (const glm::vec3 at :
         {glm::vec3(-1.0f, 1.0f, 0.2f), glm::vec3(-0.2f, 0.5f, 0.5f), glm::vec3(1.0f, 0.5f, 0.0f)}) {
        SurfaceHit hit = floorPoint(at);
        hit.geometric_normal = hit.shading_normal = glm::vec3(0.0f, -1.0f, 0.0f);  // a point facing down at the sky
        for (uint32_t i = 0; i < 512; ++i) {
            PixelSampler sampler(5u, 1u, i);
            const glm::vec2 u_select = sampler.next2D();
            LightSample light;
            if (!lights.sample(hit, u_select.x, sampler.next2D(), light) || light.is_delta) continue;
            if (std::isfinite(light.distance)) {
                RayHit ray_hit;
                ASSERT_TRUE(tracer.intersect(Ray{at, light.wi}, ray_hit));
                const SurfaceHit emitter = makeSurfaceHit(scene, ray_hit, light.wi);
                if (scene.triangle_materials[emitter.triangle] != 1u) continue;  // occluded on the way
                EXPECT_NEAR(lights.pdfEmitter(at, hit.shading_normal, emitter), light.pdf, 1e-3f * light.pdf);
                ++emitter_checks;
            } else {
                EXPECT_NEAR(lights.pdfSky(at, hit.shading_normal, light.wi), light.pdf, 1e-4f * light.pdf);
                ++sky_checks;
            }
        }
    }
    EXPECT_GT(emitter_checks, 50u);
    EXPECT_GT(sky_checks, 50u);
}

TEST(SpatialLightSelection, OneGroupOfLightsSelectsByPowerAsBefore) {
    const Scene scene = loadGltf(std::string(SHARCBAKE_SCENES_DIR) + "/cornell_box/cornell_box.gltf");
    const Tracer tracer(scene);
    const LightSampler by_power(scene);
    const LightSampler learned(tracer);
    EXPECT_EQ(learned.spatialSelection().groups, 1u);  // the ceiling light, two triangles of one piece
    EXPECT_FALSE(learned.spatialSelection().active());
    EXPECT_EQ(learned.spatialSelection().describe(), "by power (the lights make one group)");
    for (size_t e = 0; e < learned.entryCount(); ++e)
        EXPECT_EQ(learned.selectionPmf(e, glm::vec3(0.1f), kUp), by_power.selectionPmf(e, glm::vec3(0.1f), kUp));
}

TEST(SpatialLightSelection, TheLineSaysWhySelectionStaysByPower) {
    Scene dark = twoRoomsOneBright();
    dark.lights.clear();
    dark.materials[1].emissive = glm::vec3(0.0f);
    const Tracer dark_tracer(dark);
    EXPECT_EQ(LightSampler(dark_tracer).spatialSelection().describe(), "by power (no lights)");
    Scene bulb_only = twoRoomsOneBright();
    bulb_only.materials[1].emissive = glm::vec3(0.0f);
    const Tracer bulb_tracer(bulb_only);
    EXPECT_EQ(LightSampler(bulb_tracer).spatialSelection().describe(), "by power (the lights make one group)");
    const Scene scene = twoRoomsOneBright();
    const Tracer tracer(scene);
    const std::string learned = LightSampler(tracer).spatialSelection().describe();
    EXPECT_EQ(learned.rfind("by where light arrives in ", 0), 0u) << learned;
    EXPECT_NE(learned.find("; 2 light groups;"), std::string::npos) << learned;
}

TEST(SpatialLightSelection, TheSameOnAnyThreadCount) {
    const Scene scene = twoRoomsOneBright();
    const Tracer tracer(scene);
    const LightSampler many(tracer);
    std::optional<LightSampler> one;
    tbb::task_arena(1).execute([&] { one.emplace(tracer); });
    EXPECT_EQ(one->spatialSelection().shadow_rays, many.spatialSelection().shadow_rays);
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> coordinate(-2.5f, 2.5f);
    for (int i = 0; i < 2000; ++i) {
        const glm::vec3 at(coordinate(rng), coordinate(rng) + 1.0f, coordinate(rng));
        for (size_t e = 0; e < many.entryCount(); ++e)
            ASSERT_EQ(one->selectionPmf(e, at, kUp), many.selectionPmf(e, at, kUp));
    }
}

}  // namespace
}  // namespace sharcbake
