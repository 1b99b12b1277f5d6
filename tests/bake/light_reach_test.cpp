// SPDX-License-Identifier: Apache-2.0
// Scenes with lights whose light never reaches what the cameras see: the probe before a bake
// finds them, and the diagnosis names what stops each light.
#include "tracing/light_reach.h"
#include "test_rooms.h"
#include "tracing/lights.h"
#include "tracing/sampling.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

namespace sharcbake {
namespace {

constexpr uint32_t kSeed = 7;

/// A 4 x 3 x 4 room of grey walls facing into it, the material named "wall".
Scene greyRoom() {
    Scene scene = emptyTestScene();
    addInwardBox(scene, glm::vec3(-2.0f, 0.0f, -2.0f), glm::vec3(2.0f, 3.0f, 2.0f), addGreyWallMaterial(scene));
    return scene;
}

/// Rays in 1024 directions from each of two places in the room: what the views see.
std::vector<Ray> viewRays() {
    std::vector<Ray> rays;
    for (const glm::vec3 from : {glm::vec3(-1.0f, 1.5f, -1.0f), glm::vec3(1.0f, 1.2f, 0.5f)}) {
        for (uint32_t i = 0; i < 1024; ++i) rays.push_back(Ray{from, sphericalFibonacciDirection(i, 1024)});
    }
    return rays;
}

/// The probe's verdict and the diagnosis for a scene.
struct Verdict {
    bool lit;
    std::string why;
};
Verdict judge(const Scene& scene, bool closed = true) {
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    const std::vector<Ray> rays = viewRays();
    const LightProbe probe = probeLight(tracer, lights, rays, kSeed);
    // A scene closed around the views that stays dark: the probe traced all the rays, and every one
    // met a surface.
    if (closed && !probe.met_light) {
        EXPECT_EQ(probe.paths, rays.size());
        EXPECT_EQ(probe.surface_hits, probe.paths);
    }
    return {probe.met_light, whyNoLightArrives(tracer, rays)};
}

PunctualLight pointLight(const char* name, glm::vec3 position) {
    PunctualLight light;
    light.name = name;
    light.position = position;
    light.intensity = glm::vec3(10.0f);
    return light;
}

TEST(LightReach, ASunInsideAClosedDomeIsNamedWithTheDomesMaterial) {
    // Blender users model a sky dome as a sphere around the scene; without emission it keeps the
    // sun out, and the whole cache is 0.
    Scene scene = greyRoom();
    Material dome;
    dome.name = "sky dome";
    dome.double_sided = true;
    scene.materials.push_back(dome);
    addInwardBox(scene, glm::vec3(-50.0f), glm::vec3(50.0f), 1);
    PunctualLight sun;
    sun.name = "Sun";
    sun.type = LightType::Directional;
    sun.direction = glm::vec3(0.0f, -1.0f, 0.0f);
    sun.intensity = glm::vec3(3.0f);
    scene.lights.push_back(sun);
    // The room has no roof (its fourth face) here: the dome is what blocks the sun.
    scene.triangles.erase(scene.triangles.begin() + 6, scene.triangles.begin() + 8);
    scene.triangle_materials.erase(scene.triangle_materials.begin() + 6, scene.triangle_materials.begin() + 8);
    const Verdict dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("directional light 'Sun': every ray towards it"), std::string::npos) << dark.why;
    EXPECT_NE(dark.why.find("first by material 'sky dome'"), std::string::npos) << dark.why;
    EXPECT_NE(dark.why.find("sky dome without an emissive or unlit material"), std::string::npos) << dark.why;

    // Without the dome the sun comes in through the open roof.
    scene.triangles.resize(10);
    scene.triangle_materials.resize(10);
    const Verdict lit = judge(scene, false);
    EXPECT_TRUE(lit.lit);
    EXPECT_NE(lit.why.find("some are lit directly"), std::string::npos) << lit.why;

    // A sun shining upwards (a Z-up exporter's, or a flipped one) lights no floor.
    scene.lights[0].direction = glm::vec3(0.0f, 1.0f, 0.0f);
    const Verdict upwards = judge(scene, false);
    EXPECT_FALSE(upwards.lit);
    EXPECT_NE(upwards.why.find("directional light 'Sun': every one of them faces away from it (it shines towards (0, "
                               "1, 0))"),
              std::string::npos)
        << upwards.why;
}

TEST(LightReach, ALampInsideAClosedBulbIsToldItStandsInsideWhatBlocksIt) {
    Scene scene = greyRoom();
    Material bulb;
    bulb.name = "frosted";
    scene.materials.push_back(bulb);
    // A closed 10 cm bulb hanging under the ceiling, its outside facing the room.
    const glm::vec3 lamp(0.0f, 2.5f, 0.0f);
    const uint32_t first = uint32_t(scene.triangles.size());
    addInwardBox(scene, lamp - 0.05f, lamp + 0.05f, 1);
    for (size_t t = first; t < scene.triangles.size(); ++t) std::swap(scene.triangles[t].y, scene.triangles[t].z);
    scene.lights.push_back(pointLight("Lamp", lamp));
    const Verdict dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("point light 'Lamp': every ray towards it"), std::string::npos) << dark.why;
    EXPECT_NE(dark.why.find("first by material 'frosted'"), std::string::npos) << dark.why;
    EXPECT_NE(dark.why.find("stands inside a closed bulb"), std::string::npos) << dark.why;

    // The same lamp beside the bulb lights the room.
    scene.lights[0].position = lamp + glm::vec3(0.5f, 0.0f, 0.0f);
    EXPECT_TRUE(judge(scene).lit);
}

TEST(LightReach, ALampInAnotherClosedRoomIsBlockedByTheWallsNotABulb) {
    Scene scene = greyRoom();
    addInwardBox(scene, glm::vec3(3.0f, 0.0f, -2.0f), glm::vec3(7.0f, 3.0f, 2.0f), 0);
    scene.lights.push_back(pointLight("Next door", glm::vec3(5.0f, 2.5f, 0.0f)));
    const Verdict dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("point light 'Next door': every ray towards it"), std::string::npos) << dark.why;
    EXPECT_EQ(dark.why.find("bulb"), std::string::npos) << dark.why;
}

TEST(LightReach, ASpotAimedIntoAWallAndALampBeyondItsRangeAreToldApart) {
    Scene scene = greyRoom();
    // A spot 1 mm from a wall, aimed at it with a 0.01 rad cone: it lights a spot 10 um wide.
    PunctualLight spot = pointLight("Spot", glm::vec3(1.999f, 1.5f, 0.0f));
    spot.type = LightType::Spot;
    spot.direction = glm::vec3(1.0f, 0.0f, 0.0f);
    spot.outer_cone_angle = 0.01f;
    scene.lights.push_back(spot);
    Verdict dark = judge(scene);
    EXPECT_NE(dark.why.find("spot light 'Spot': those facing it all lie outside its cone"), std::string::npos)
        << dark.why;

    scene.lights = {pointLight("Short", glm::vec3(0.0f, 2.9f, 0.0f))};
    scene.lights[0].range = 0.05f;
    dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("point light 'Short': those facing it all lie beyond its range (0.05)"), std::string::npos)
        << dark.why;
}

TEST(LightReach, AClosedRoomUnderTheSkyAndEmittersNextDoorAreNamed) {
    Scene scene = greyRoom();
    scene.sky.uniform = glm::vec3(1.0f);
    Verdict dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("no ray from them leaves the scene"), std::string::npos) << dark.why;

    // A room next door whose walls glow.
    scene.sky = Sky{};
    Material glow;
    glow.name = "glow";
    glow.emissive = glm::vec3(5.0f);
    glow.double_sided = true;
    scene.materials.push_back(glow);
    addInwardBox(scene, glm::vec3(3.0f, 0.0f, -2.0f), glm::vec3(7.0f, 3.0f, 2.0f), 1);
    dark = judge(scene);
    EXPECT_FALSE(dark.lit);
    EXPECT_NE(dark.why.find("none of them sees an emissive surface"), std::string::npos) << dark.why;

    // A glowing box in the room itself lights it.
    addInwardBox(scene, glm::vec3(-1.5f, 0.5f, 1.0f), glm::vec3(-1.0f, 1.0f, 1.5f), 1);
    EXPECT_TRUE(judge(scene).lit);
}

}  // namespace
}  // namespace sharcbake
