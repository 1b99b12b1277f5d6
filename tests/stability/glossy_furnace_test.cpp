// SPDX-License-Identifier: Apache-2.0
// Stiff transport through glossy and grazing lobes: the Cornell box opened to a uniform sky of
// radiance 1, every surface white (base colour 1) with a specular layer, no emission. An
// energy-conserving BRDF reflects all it receives, so every surface and every pixel has radiance
// exactly 1 however many bounces a path makes inside the box (a white furnace). The shipped
// furnaces are pure Lambert (specularFactor 0); these cases exercise glTF's default layer
// (F0 0.04), a half metal, a rough metal and Blender's black specular colour (F0 0, F90 1: a
// grazing-only layer), through plain path tracing and through the cache.
#include "tracing/render.h"
#include "stability_support.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace sharcbake::stability {
namespace {

struct Lobe {
    const char* name;
    float roughness;
    float metallic;
    float specular_weight;
    glm::vec3 specular_colour;
    float clearcoat = 0.0f;  ///< KHR_materials_clearcoat factor, at roughness 0.2
};

void PrintTo(const Lobe& l, std::ostream* out) { *out << l.name; }

Scene whiteFurnace(const Lobe& lobe) {
    Scene scene = loadGltf(scenePath("cornell_box"));
    for (Material& m : scene.materials) {
        m.base_color = glm::vec3(1.0f);
        m.roughness = lobe.roughness;
        m.metallic = lobe.metallic;
        m.specular = lobe.specular_weight;
        m.specular_color = lobe.specular_colour;
        m.clearcoat = lobe.clearcoat;
        m.clearcoat_roughness = 0.2f;
        m.emissive = glm::vec3(0.0f);
        m.double_sided = true;
    }
    scene.lights.clear();
    scene.sky.uniform = glm::vec3(1.0f);
    return scene;
}

struct ImageStats {
    double mean = 0.0;
    double max = 0.0;
};

ImageStats renderFurnace(const Scene& scene, uint32_t seed) {
    const Tracer tracer(scene);
    const LightSampler lights(tracer);
    const PathTracer path_tracer(tracer, lights, PathTracerSettings{});
    TraceCounters counters;
    const int size = 24;
    const Image image = renderImage(CameraRays(scene.cameras.front(), size, size), ImageRenderSettings{size, size, 64, seed},
                                    [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, counters); },
                                    nullptr);
    ImageStats stats;
    for (const glm::vec3& p : image.pixels) {
        stats.mean += double(p.x);
        stats.max = std::max(stats.max, double(p.x));
    }
    stats.mean /= double(image.pixels.size());
    return stats;
}

class GlossyFurnace : public ::testing::TestWithParam<Lobe> {};
class GlossyFurnaceCache : public ::testing::TestWithParam<Lobe> {};

TEST_P(GlossyFurnace, PathTracingSeesRadianceOneWithoutFireflies) {
    const Scene scene = whiteFurnace(GetParam());
    const ImageStats a = renderFurnace(scene, 1), b = renderFurnace(scene, 2);
    std::printf("[stability] white furnace, %s: path tracing mean %.4f / %.4f (two seeds), brightest pixel %.3f\n",
                GetParam().name, a.mean, b.mean, std::max(a.max, b.max));
    EXPECT_NEAR(a.mean, 1.0, 0.02);
    EXPECT_NEAR(b.mean, 1.0, 0.02);
    EXPECT_NEAR(a.mean, b.mean, 0.02 * a.mean);
    EXPECT_LE(a.max, 5.0 * a.mean);
    EXPECT_LE(b.max, 5.0 * b.mean);
}

TEST_P(GlossyFurnaceCache, TheCacheConvergesToRadianceOne) {
    BakeConfig config;
    config.resolution = 48;
    config.scene_scale = 5.0f;  // coarse voxels: many samples each
    SmallBake bake(whiteFurnace(GetParam()), config);
    double mean = 0.0;
    while (bake.baker->iterationsDone() < 512) {
        bake.run(64);
        mean = sampleWeightedMean(bake.cache(), 64);
        if (std::abs(mean - 1.0) <= 0.02) break;
    }
    std::printf("[stability] white furnace, %s: cache mean %.4f after %u iterations\n", GetParam().name, mean,
                bake.baker->iterationsDone());
    EXPECT_NEAR(mean, 1.0, 0.02);
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
    EXPECT_EQ(bake.report().clamped_deposits, 0u);
}

const Lobe kLobes[] = {
    {"default_layer", 0.3f, 0.0f, 1.0f, glm::vec3(1.0f)},           // glTF's default dielectric layer
    {"half_metal", 0.3f, 0.5f, 1.0f, glm::vec3(1.0f)},              // metallic 0.5
    {"blender_black_specular", 0.5f, 0.0f, 1.0f, glm::vec3(0.0f)},  // F0 0, F90 1: grazing only
    {"clearcoat", 0.5f, 0.0f, 1.0f, glm::vec3(1.0f), 1.0f},         // a full coat over the default layer
};
/// And for the cache, a white rough metal: it absorbs nothing and its samples carry up to 1.43x
/// the albedo (the multiple-scattering mixture), so single paths that stay in the box for dozens
/// of bounces have heavy-tailed weights that 64 spp cannot bound; the cache averages them.
const Lobe kCacheLobes[] = {
    kLobes[0], kLobes[1], kLobes[2], kLobes[3], {"rough_metal", 0.9f, 1.0f, 1.0f, glm::vec3(1.0f)},
};

INSTANTIATE_TEST_SUITE_P(Stability, GlossyFurnace, ::testing::ValuesIn(kLobes),
                         [](const auto& info) { return std::string(info.param.name); });
INSTANTIATE_TEST_SUITE_P(Stability, GlossyFurnaceCache, ::testing::ValuesIn(kCacheLobes),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace sharcbake::stability
