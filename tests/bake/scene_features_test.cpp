// SPDX-License-Identifier: Apache-2.0
// What scenes from other tools carry, from the glTF to the traced surface: vertex colours
// (COLOR_0), tangent-space normal maps (with TANGENT or tangents computed from the UVs), UV
// transforms (KHR_texture_transform), alpha cut-outs (MASK, and BLEND as a stochastic cut-out),
// unlit materials (KHR_materials_unlit) and the occlusion map that is dropped with a warning. Each case is a 2 m quad at y = 0 facing +Y, with u along +X and v along +Z.
#include "gltf_builder.h"
#include "png_bytes.h"
#include "sharcbake/scene_loader.h"
#include "test_bake_scene.h"
#include "tracing/bsdf.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/render.h"
#include "tracing/surface.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>

namespace sharcbake {
namespace {

using nlohmann::json;

using test::png;

/// One quad whose material and extra attributes each test sets.
struct QuadScene {
    test::GltfBuilder gltf;
    json material = {{"pbrMetallicRoughness", {{"metallicFactor", 0.0}}}};
    json extra_attributes = json::object();
    json node = json::object();
    std::vector<int> other_roots;  ///< more nodes in the scene besides the quad

    /// Adds `image` (PNG bytes) as texture `index` order; returns the texture index.
    int addTexture(const std::vector<uint8_t>& image, bool nearest = false) {
        gltf.doc["images"].push_back({{"uri", "data:image/png;base64," + test::base64(image)}});
        json sampler = {{"wrapS", 33071}, {"wrapT", 33071}};  // clamp to edge
        if (nearest) sampler["magFilter"] = 9728;
        gltf.doc["samplers"].push_back(sampler);
        const int index = int(gltf.doc["textures"].size());
        gltf.doc["textures"].push_back({{"source", index}, {"sampler", index}});
        return index;
    }

    Scene load(const std::string& name = "quad.gltf") {
        const std::vector<float> positions{-1, 0, -1, 1, 0, -1, 1, 0, 1, -1, 0, 1};
        const std::vector<float> uvs{0, 0, 1, 0, 1, 1, 0, 1};
        const std::vector<uint16_t> indices{0, 2, 1, 0, 3, 2};
        json attributes = {{"POSITION", gltf.addPositions(positions)},
                           {"NORMAL", gltf.addPositions({0, 1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0})},
                           {"TEXCOORD_0", gltf.addData(uvs, test::kFloat, "VEC2")}};
        attributes.update(extra_attributes);
        const int mat = gltf.addMaterial(material);
        json primitive = {{"attributes", attributes},
                          {"indices", gltf.addData(indices, test::kUnsignedShort, "SCALAR")},
                          {"material", mat}};
        std::vector<int> roots = other_roots;
        roots.push_back(gltf.addMeshNode(primitive, node));
        gltf.setScene(roots);
        return loadGltf(gltf.writeEmbedded(dir, name));
    }

    test::TempDir dir;
};

/// The surface a ray straight down (or up, from below) meets at (x, z).
std::optional<SurfaceHit> hitAt(const Scene& scene, const Tracer& tracer, float x, float z, bool from_below = false) {
    const Ray ray{glm::vec3(x, from_below ? -1.0f : 1.0f, z), glm::vec3(0.0f, from_below ? 1.0f : -1.0f, 0.0f)};
    RayHit hit;
    if (!tracer.intersect(ray, hit)) return std::nullopt;
    return makeSurfaceHit(scene, hit, ray.direction);
}

bool passesThrough(const Tracer& tracer, float x, float z) {
    return !tracer.occluded(Ray{glm::vec3(x, 1.0f, z), glm::vec3(0.0f, -1.0f, 0.0f), 2.0f});
}

void expectNear(glm::vec3 actual, glm::vec3 expected, float tolerance) {
    EXPECT_NEAR(actual.x, expected.x, tolerance) << "x";
    EXPECT_NEAR(actual.y, expected.y, tolerance) << "y";
    EXPECT_NEAR(actual.z, expected.z, tolerance) << "z";
}

bool warnedAbout(const Scene& scene, const std::string& text) {
    return std::any_of(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                       [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

TEST(VertexColors, MultiplyTheBaseColor) {
    QuadScene quad;
    quad.material["pbrMetallicRoughness"]["baseColorFactor"] = {0.5, 1.0, 1.0, 1.0};
    const std::vector<uint8_t> rgba{255, 128, 0, 255, 255, 128, 0, 255, 255, 128, 0, 255, 255, 128, 0, 255};
    quad.extra_attributes["COLOR_0"] = quad.gltf.addData(rgba, test::kUnsignedByte, "VEC4", true);
    const Scene scene = quad.load();
    ASSERT_EQ(scene.colors.size(), 4u);
    expectNear(glm::vec3(scene.colors[2]), {1.0f, 128.0f / 255.0f, 0.0f}, 1e-6f);
    const Tracer tracer(scene);
    const auto hit = hitAt(scene, tracer, 0.3f, -0.2f);
    ASSERT_TRUE(hit);
    expectNear(evaluateMaterial(scene, *hit).base_color, {0.5f, 128.0f / 255.0f, 0.0f}, 1e-6f);
    EXPECT_TRUE(scene.stats.warnings.empty());
}

TEST(VertexColors, FloatRgbAndPrimitivesWithoutColorsStayWhite) {
    QuadScene quad;
    quad.extra_attributes["COLOR_0"] = quad.gltf.addData(std::vector<float>{0.25f, 0.5f, 1.0f, 0.25f, 0.5f, 1.0f,
                                                                            0.25f, 0.5f, 1.0f, 0.25f, 0.5f, 1.0f},
                                                         test::kFloat, "VEC3");
    // A second quad without COLOR_0, half a metre up: its vertices are back-filled white.
    const int plain = quad.gltf.addMaterial({{"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.8, 0.8, 1}}}}});
    const std::vector<uint16_t> indices{0, 2, 1, 0, 3, 2};
    quad.other_roots.push_back(quad.gltf.addMeshNode(
        {{"attributes", {{"POSITION", quad.gltf.addPositions({-1, 0.5f, -1, 1, 0.5f, -1, 1, 0.5f, 1, -1, 0.5f, 1})}}},
         {"indices", quad.gltf.addData(indices, test::kUnsignedShort, "SCALAR")},
         {"material", plain}}));
    const Scene scene = quad.load();
    ASSERT_EQ(scene.colors.size(), scene.positions.size());
    const Tracer tracer(scene);
    const auto lower = hitAt(scene, tracer, 0.1f, 0.1f, true);
    ASSERT_TRUE(lower);
    expectNear(evaluateMaterial(scene, *lower).base_color, {0.25f, 0.5f, 1.0f}, 1e-6f);
    const auto top = hitAt(scene, tracer, 0.1f, 0.1f);
    ASSERT_TRUE(top);
    expectNear(evaluateMaterial(scene, *top).base_color, {0.8f, 0.8f, 0.8f}, 1e-6f);
}

/// A 1x1 normal map holding the unit vector n (x, y, z in [-1, 1]).
std::vector<uint8_t> normalTexel(glm::vec3 n) {
    const auto encode = [](float c) { return uint8_t(std::lround((c * 0.5f + 0.5f) * 255.0f)); };
    return png(1, 1, {encode(n.x), encode(n.y), encode(n.z), 255});
}

TEST(NormalMaps, TiltTheShadingNormalWithComputedTangents) {
    // Tangent-space +X is the direction of growing u (+X here); +Y is the image's up, where v
    // falls (-Z here); +Z is the surface normal (+Y).
    struct Case {
        glm::vec3 texel;
        float scale;
        glm::vec3 expected;
    };
    for (const Case& c : {Case{{0.6f, 0.0f, 0.8f}, 1.0f, {0.6f, 0.8f, 0.0f}},
                          Case{{0.0f, 0.6f, 0.8f}, 1.0f, {0.0f, 0.8f, -0.6f}},
                          Case{{0.6f, 0.0f, 0.8f}, 0.5f, glm::normalize(glm::vec3(0.3f, 0.8f, 0.0f))}}) {
        QuadScene quad;
        quad.material["normalTexture"] = {{"index", quad.addTexture(normalTexel(c.texel))}, {"scale", c.scale}};
        const Scene scene = quad.load();
        ASSERT_EQ(scene.tangents.size(), 4u);
        expectNear(glm::vec3(scene.tangents[0]), {1.0f, 0.0f, 0.0f}, 1e-6f);
        EXPECT_EQ(scene.tangents[0].w, 1.0f);
        const Tracer tracer(scene);
        const auto hit = hitAt(scene, tracer, 0.2f, 0.4f);
        ASSERT_TRUE(hit);
        // 8-bit texels: about 0.4% per component.
        expectNear(hit->shading_normal, c.expected, 0.01f);
        expectNear(hit->geometric_normal, {0.0f, 1.0f, 0.0f}, 0.0f);  // keys and offsets keep the true surface
    }
}

TEST(NormalMaps, GivenTangentsAndTheBackOfADoubleSidedSurface) {
    QuadScene quad;
    quad.material["doubleSided"] = true;
    quad.material["normalTexture"] = {{"index", quad.addTexture(normalTexel({0.6f, 0.0f, 0.8f}))}};
    // TANGENT along -X with w = -1: the map's +X now points to -X.
    quad.extra_attributes["TANGENT"] =
        quad.gltf.addData(std::vector<float>{-1, 0, 0, -1, -1, 0, 0, -1, -1, 0, 0, -1, -1, 0, 0, -1}, test::kFloat,
                          "VEC4");
    const Scene scene = quad.load();
    const Tracer tracer(scene);
    const auto front = hitAt(scene, tracer, 0.2f, 0.4f);
    ASSERT_TRUE(front);
    expectNear(front->shading_normal, {-0.6f, 0.8f, 0.0f}, 0.01f);
    // From below, the same bent normal turned towards the viewer.
    const auto back = hitAt(scene, tracer, 0.2f, 0.4f, true);
    ASSERT_TRUE(back);
    EXPECT_FALSE(back->front_face);
    expectNear(back->shading_normal, {0.6f, -0.8f, 0.0f}, 0.01f);
}

TEST(NormalMaps, AMapSteeperThanTheSurfaceStaysAboveIt) {
    QuadScene quad;
    quad.material["normalTexture"] = {{"index", quad.addTexture(normalTexel({1.0f, 0.0f, 0.0f}))}, {"scale", 3.0}};
    const Scene scene = quad.load();
    const Tracer tracer(scene);
    const auto hit = hitAt(scene, tracer, 0.0f, 0.0f);
    ASSERT_TRUE(hit);
    EXPECT_GT(glm::dot(hit->shading_normal, hit->geometric_normal), 0.0f);
    EXPECT_NEAR(glm::length(hit->shading_normal), 1.0f, 1e-5f);
}

/// A 4x4 data texture (metallic-roughness, read linearly) whose texel (column, row) holds
/// green = 16 column + row + 1 (out of 255): which texel a lookup read is plain to see.
std::vector<uint8_t> numberedTexels() {
    std::vector<uint8_t> rgba;
    for (int row = 0; row < 4; ++row)
        for (int column = 0; column < 4; ++column) rgba.insert(rgba.end(), {0, uint8_t(16 * column + row + 1), 0, 255});
    return rgba;
}

/// The (column, row) of the numbered texel the metallic-roughness lookup at (u, v) read.
glm::ivec2 texelReadAt(const Scene& scene, const Tracer& tracer, float u, float v) {
    const auto hit = hitAt(scene, tracer, 2.0f * u - 1.0f, 2.0f * v - 1.0f);
    if (!hit) return glm::ivec2(-1);
    const int number = int(std::lround(evaluateMaterial(scene, *hit).roughness * 255.0f)) - 1;
    return glm::ivec2(number / 16, number % 16);
}

TEST(TextureTransforms, TheSpecificationsExampleReadsTheLowerLeftQuadrantTurned) {
    // KHR_texture_transform's example: offset [0, 1], rotation pi/2, scale 0.5 "utilizes only the
    // lower left quadrant of the source image, rotated clockwise 90 degrees": uv' = (v/2, 1 - u/2).
    QuadScene quad;
    const int texture = quad.addTexture(png(4, 4, numberedTexels()), true);
    quad.material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
        {"index", texture},
        {"extensions",
         {{"KHR_texture_transform", {{"offset", {0.0, 1.0}}, {"rotation", 1.57079632679}, {"scale", {0.5, 0.5}}}}}}};
    quad.gltf.doc["extensionsUsed"] = {"KHR_texture_transform"};
    quad.gltf.doc["extensionsRequired"] = {"KHR_texture_transform"};
    const Scene scene = quad.load();
    EXPECT_TRUE(scene.stats.warnings.empty());
    const Tracer tracer(scene);
    struct Case {
        glm::vec2 uv;
        glm::ivec2 texel;  ///< floor(4 uv')
    };
    for (const Case& c : {Case{{0.1f, 0.3f}, {0, 3}}, Case{{0.7f, 0.2f}, {0, 2}}, Case{{0.45f, 0.9f}, {1, 3}},
                          Case{{0.9f, 0.6f}, {1, 2}}}) {
        const glm::ivec2 read = texelReadAt(scene, tracer, c.uv.x, c.uv.y);
        EXPECT_EQ(read, c.texel) << "uv " << c.uv.x << ", " << c.uv.y;
    }
}

TEST(TextureTransforms, TilingWithRepeatAndTheExtensionsTexCoord) {
    QuadScene quad;
    const int texture = quad.addTexture(png(4, 4, numberedTexels()), true);
    quad.gltf.doc["samplers"][texture]["wrapS"] = 10497;  // REPEAT
    quad.gltf.doc["samplers"][texture]["wrapT"] = 10497;
    // The extension's texCoord (1) overrides the textureInfo's (0); TEXCOORD_1 runs u backwards.
    quad.extra_attributes["TEXCOORD_1"] =
        quad.gltf.addData(std::vector<float>{1, 0, 0, 0, 0, 1, 1, 1}, test::kFloat, "VEC2");
    quad.material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
        {"index", texture},
        {"texCoord", 0},
        {"extensions", {{"KHR_texture_transform", {{"offset", {0.25, 0.0}}, {"scale", {3.0, 1.0}}, {"texCoord", 1}}}}}};
    const Scene scene = quad.load();
    EXPECT_EQ(scene.materials.at(0).metallic_roughness_texture.texcoord, 1u);
    const Tracer tracer(scene);
    // uv' = (3 (1 - u) + 0.25, v), wrapped into [0, 1).
    for (const float u : {0.05f, 0.3f, 0.55f, 0.8f}) {
        const float wrapped = 3.0f * (1.0f - u) + 0.25f - std::floor(3.0f * (1.0f - u) + 0.25f);
        EXPECT_EQ(texelReadAt(scene, tracer, u, 0.6f), glm::ivec2(int(4.0f * wrapped), 2)) << "u " << u;
    }
}

TEST(TextureTransforms, AMalformedTransformIsIgnoredWithAWarning) {
    QuadScene quad;
    const int texture = quad.addTexture(png(4, 4, numberedTexels()), true);
    quad.material["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {
        {"index", texture}, {"extensions", {{"KHR_texture_transform", {{"scale", {2.0}}, {"texCoord", 1}}}}}};
    const Scene scene = quad.load();
    EXPECT_TRUE(warnedAbout(scene, "KHR_texture_transform needs offset and scale as two finite numbers"));
    EXPECT_EQ(scene.materials.at(0).metallic_roughness_texture.texcoord, 0u);  // the transform's texCoord too
    const Tracer tracer(scene);
    EXPECT_EQ(texelReadAt(scene, tracer, 0.3f, 0.6f), glm::ivec2(1, 2));  // the plain UVs
}

TEST(TextureTransforms, ANormalMapTurnsWithItsUvs) {
    // Rotated by pi/2, u' = v grows along +Z: the map's +X (0.6, 0, 0.8) now tilts the normal
    // towards +Z, whether the tangents are computed from the turned UVs or given (along +X for
    // the untransformed UVs) and turned.
    for (const bool given_tangents : {false, true}) {
        QuadScene quad;
        quad.material["normalTexture"] = {
            {"index", quad.addTexture(normalTexel({0.6f, 0.0f, 0.8f}))},
            {"extensions", {{"KHR_texture_transform", {{"rotation", 1.5707963267948966}}}}}};
        if (given_tangents) {
            quad.extra_attributes["TANGENT"] = quad.gltf.addData(
                std::vector<float>{1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1, 1, 0, 0, 1}, test::kFloat, "VEC4");
        }
        const Scene scene = quad.load();
        ASSERT_EQ(scene.tangents.size(), 4u);
        expectNear(glm::vec3(scene.tangents[0]), {0.0f, 0.0f, 1.0f}, 1e-6f);
        const Tracer tracer(scene);
        const auto hit = hitAt(scene, tracer, 0.2f, 0.4f);
        ASSERT_TRUE(hit);
        expectNear(hit->shading_normal, {0.0f, 0.8f, 0.6f}, 0.01f);
    }
    // The map's +Y (image up) follows falling v' = u: towards +X.
    QuadScene quad;
    quad.material["normalTexture"] = {{"index", quad.addTexture(normalTexel({0.0f, 0.6f, 0.8f}))},
                                      {"extensions", {{"KHR_texture_transform", {{"rotation", 1.5707963267948966}}}}}};
    const Scene scene = quad.load();
    const Tracer tracer(scene);
    const auto hit = hitAt(scene, tracer, 0.2f, 0.4f);
    ASSERT_TRUE(hit);
    expectNear(hit->shading_normal, {0.6f, 0.8f, 0.0f}, 0.01f);
}

TEST(EmitterPoints, AreBitForBitTheFullSurfacePointsEmission) {
    // Light sampling reads emitters through makeEmitterPoint; it must give exactly what the full
    // surface point and material give, or caches would depend on which path computed a light.
    QuadScene quad;
    quad.material["emissiveFactor"] = {0.9, 0.7, 0.3};
    quad.material["emissiveTexture"] = {
        {"index", quad.addTexture(png(4, 4, numberedTexels()))},
        {"extensions", {{"KHR_texture_transform", {{"offset", {0.1, 0.2}}, {"rotation", 0.3}, {"scale", {2.0, 1.5}}}}}}};
    quad.material["extensions"] = {{"KHR_materials_emissive_strength", {{"emissiveStrength", 7.0}}}};
    quad.material["doubleSided"] = true;
    const Scene scene = quad.load();
    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (uint32_t triangle = 0; triangle < scene.triangles.size(); ++triangle) {
        for (int i = 0; i < 200; ++i) {
            float b1 = uniform(random), b2 = uniform(random);
            if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
            const EmitterPoint e = makeEmitterPoint(scene, triangle, b1, b2);
            const SurfaceHit point = makeSurfacePoint(scene, triangle, b1, b2);
            const ShadingMaterial material = evaluateMaterial(scene, point);
            EXPECT_EQ(e.position, point.position);
            EXPECT_EQ(e.face_normal, point.face_normal);
            EXPECT_EQ(e.emission, material.emission);
            EXPECT_EQ(e.double_sided, material.double_sided);
            EXPECT_GT(e.emission.x + e.emission.y + e.emission.z, 0.0f);
        }
    }
}

TEST(AlphaCutouts, MaskFactorBelowTheCutoffLetsRaysThrough) {
    for (const double alpha : {0.3, 0.7}) {
        QuadScene quad;
        quad.material["alphaMode"] = "MASK";
        quad.material["pbrMetallicRoughness"]["baseColorFactor"] = {1.0, 1.0, 1.0, alpha};
        const Scene scene = quad.load();
        const Tracer tracer(scene);
        const bool cut = alpha < 0.5;
        EXPECT_EQ(!hitAt(scene, tracer, 0.1f, 0.2f).has_value(), cut) << alpha;
        EXPECT_EQ(passesThrough(tracer, 0.1f, 0.2f), cut) << alpha;
        EXPECT_EQ(scene.materials[0].alpha_mode, AlphaMode::Mask);
    }
}

TEST(AlphaCutouts, MaskTextureCutsOutPerTexel) {
    QuadScene quad;
    quad.material["alphaMode"] = "MASK";
    quad.material["alphaCutoff"] = 0.25;
    // Left texel (u < 0.5, x < 0) opaque, right texel transparent.
    quad.material["pbrMetallicRoughness"]["baseColorTexture"] = {
        {"index", quad.addTexture(png(2, 1, {200, 200, 200, 255, 200, 200, 200, 0}), true)}};
    const Scene scene = quad.load();
    const Tracer tracer(scene);
    for (const float z : {-0.7f, 0.0f, 0.6f}) {
        EXPECT_TRUE(hitAt(scene, tracer, -0.5f, z)) << z;
        EXPECT_FALSE(passesThrough(tracer, -0.5f, z)) << z;
        EXPECT_FALSE(hitAt(scene, tracer, 0.5f, z)) << z;
        EXPECT_TRUE(passesThrough(tracer, 0.5f, z)) << z;
    }
}

TEST(AlphaCutouts, BlendTransmitsOneMinusAlphaDeterministically) {
    QuadScene quad;
    quad.material["alphaMode"] = "BLEND";
    quad.material["pbrMetallicRoughness"]["baseColorFactor"] = {1.0, 1.0, 1.0, 0.3};
    const Scene scene = quad.load();
    EXPECT_TRUE(warnedAbout(scene, "stochastic cut-out"));
    const Tracer tracer(scene);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> coordinate(-0.99f, 0.99f);
    constexpr int kRays = 20000;
    int through = 0;
    for (int i = 0; i < kRays; ++i) {
        const float x = coordinate(rng), z = coordinate(rng);
        const bool passes = passesThrough(tracer, x, z);
        through += passes;
        ASSERT_EQ(passes, !hitAt(scene, tracer, x, z).has_value()) << "closest hit and occlusion agree";
        ASSERT_EQ(passes, passesThrough(tracer, x, z)) << "the same point gives the same answer";
    }
    // Binomial standard deviation sqrt(0.7 * 0.3 / 20000) = 0.0032: 5 sigma.
    EXPECT_NEAR(double(through) / kRays, 0.7, 0.016);
}

TEST(AlphaCutouts, MaterialsThatAreOpaqueEverywhereAreTracedAsOpaque) {
    for (const char* mode : {"BLEND", "MASK"}) {
        QuadScene quad;
        quad.material["alphaMode"] = mode;
        const Scene scene = quad.load();
        EXPECT_EQ(scene.materials[0].alpha_mode, AlphaMode::Opaque) << mode;
        EXPECT_TRUE(scene.stats.warnings.empty()) << mode;
    }
}

/// The share of 20000 rays straight down through random points of the quad that pass it; each
/// point's answer is checked to be the same for closest-hit and occlusion rays, and repeatable.
double passingShare(const Scene& scene) {
    const Tracer tracer(scene);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> coordinate(-0.99f, 0.99f);
    constexpr int kRays = 20000;
    int through = 0;
    for (int i = 0; i < kRays; ++i) {
        const float x = coordinate(rng), z = coordinate(rng);
        const bool passes = passesThrough(tracer, x, z);
        through += passes;
        EXPECT_EQ(passes, !hitAt(scene, tracer, x, z).has_value()) << "closest hit and occlusion agree";
        EXPECT_EQ(passes, passesThrough(tracer, x, z)) << "the same point gives the same answer";
    }
    return double(through) / kRays;
}

TEST(Transmission, GlassLetsItsTransmissionFactorOfRaysThrough) {
    // Binomial standard deviation at most sqrt(0.25 / 20000) = 0.0035: 0.018 is 5 sigma.
    for (const double factor : {1.0, 0.6, 0.25}) {
        QuadScene quad;
        quad.material["extensions"] = {{"KHR_materials_transmission", {{"transmissionFactor", factor}}}};
        quad.gltf.doc["extensionsUsed"] = {"KHR_materials_transmission"};
        quad.gltf.doc["extensionsRequired"] = {"KHR_materials_transmission"};
        const Scene scene = quad.load();
        EXPECT_FLOAT_EQ(scene.materials.at(0).transmission, float(factor));
        EXPECT_TRUE(warnedAbout(scene, "KHR_materials_transmission is traced as thin see-through glass"));
        EXPECT_FALSE(warnedAbout(scene, "is not supported"));
        EXPECT_NEAR(passingShare(scene), factor, 0.018) << factor;
    }
}

TEST(Transmission, TextureAndBlendAlphaCombine) {
    // The texture's R (0 on the left half, 1 on the right: u grows along +X) scales the factor,
    // and BLEND alpha 0.5 makes half of what transmission leaves opaque see-through as well.
    QuadScene quad;
    const int texture = quad.addTexture(png(2, 1, {0, 0, 0, 255, 255, 255, 255, 255}), true);
    quad.material["extensions"] = {
        {"KHR_materials_transmission", {{"transmissionFactor", 0.5}, {"transmissionTexture", {{"index", texture}}}}}};
    quad.material["alphaMode"] = "BLEND";
    quad.material["pbrMetallicRoughness"]["baseColorFactor"] = {1.0, 1.0, 1.0, 0.5};
    const Scene scene = quad.load();
    ASSERT_TRUE(scene.materials.at(0).transmission_texture.isSet());
    // Left half: opacity 0.5 (alpha) x 1 (no transmission): 0.5 through. Right half: 0.5 x 0.5
    // = 0.25 opaque: 0.75 through. Over the quad: 0.625.
    EXPECT_NEAR(passingShare(scene), 0.625, 0.018);
}

TEST(Transmission, AbsentOrZeroKeepsTheSurfaceOpaque) {
    QuadScene quad;
    quad.material["extensions"] = {{"KHR_materials_transmission", {{"transmissionFactor", 0.0}}}};
    const Scene scene = quad.load();
    EXPECT_FALSE(scene.materials.at(0).cutsOut());
    EXPECT_TRUE(scene.stats.warnings.empty());
    EXPECT_EQ(passingShare(scene), 0.0);
}

/// The sRGB transfer function to linear light (IEC 61966-2-1), as colour textures are decoded.
float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

/// A scene of nothing but one spot light at (0, 0, 1) shining down -Z.
Scene spotOnly(float inner, float outer, float intensity = 1.0f) {
    Scene scene;
    PunctualLight spot;
    spot.name = "Spot";
    spot.type = LightType::Spot;
    spot.position = {0.0f, 0.0f, 1.0f};
    spot.direction = {0.0f, 0.0f, -1.0f};
    spot.intensity = glm::vec3(intensity);
    spot.inner_cone_angle = inner;
    spot.outer_cone_angle = outer;
    scene.lights.push_back(spot);
    return scene;
}

/// The radiance a spotOnly light sends to a point of the z = 0 plane facing it.
glm::vec3 spotRadianceAt(const LightSampler& lights, glm::vec3 point) {
    SurfaceHit at;
    at.position = point;
    LightSample sample;
    return lights.sample(at, 0.5f, {0.5f, 0.5f}, sample) ? sample.radiance : glm::vec3(0.0f);
}

// glTF allows any spot cone above 0 rad. In float, the cosine of an angle below about 3e-4 rad is
// 1: the light had no power (left out: "no lights") and its cone no width.
TEST(SpotLights, NarrowConesLightTheirDisc) {
    const Scene needle = spotOnly(0.0f, 1e-6f);
    const LightSampler needle_lights(needle);
    ASSERT_TRUE(needle_lights.hasLights());
    EXPECT_TRUE(needle_lights.darkLights().empty());
    expectNear(spotRadianceAt(needle_lights, {0.0f, 0.0f, 0.0f}), glm::vec3(1.0f), 1e-5f);  // on the axis, 1 m
    EXPECT_EQ(spotRadianceAt(needle_lights, {1e-5f, 0.0f, 0.0f}), glm::vec3(0.0f));         // 10x outside

    // A milliradian cone, 0.5 mrad off its axis: halfway in angle, 3/4 of the way in 1 - cos,
    // squared (the extension's ramp); the sample code's 0.001 floor would give 1.4e-7.
    const Scene narrow = spotOnly(0.0f, 1e-3f);
    const LightSampler narrow_lights(narrow);
    expectNear(spotRadianceAt(narrow_lights, {5e-4f, 0.0f, 0.0f}), glm::vec3(0.5625f), 2e-3f);

    // Cones whose cosines are far apart are unchanged: the ramp between 30 and 45 degrees.
    const Scene wide = spotOnly(0.5235988f, 0.7853982f);
    const LightSampler wide_lights(wide);
    const float off = std::tan(0.6544985f);  // 37.5 degrees off the axis, 1 m below
    const float cos_d = std::cos(0.6544985f), cos_i = std::cos(0.5235988f), cos_o = std::cos(0.7853982f);
    const float t = (cos_d - cos_o) / (cos_i - cos_o);
    expectNear(spotRadianceAt(wide_lights, {off, 0.0f, 0.0f}), glm::vec3(t * t * cos_d * cos_d), 1e-4f);
}

TEST(SpotLights, LightsThatGiveNoLightAreListed) {
    const Scene dark = spotOnly(0.0f, 0.5f, 0.0f);
    const LightSampler lights(dark);
    EXPECT_FALSE(lights.hasLights());
    EXPECT_EQ(lights.darkLights(), std::vector<uint32_t>{0});
}

TEST(Unlit, ShowsItsBaseColourAsEmissionAndReflectsNothing) {
    QuadScene quad;
    // Base colour factor x texture (sRGB) x vertex colour, as a viewer shows it; the alpha stays.
    quad.material["pbrMetallicRoughness"] = {{"baseColorFactor", {0.5, 0.25, 1.0, 0.8}},
                                             {"baseColorTexture",
                                              {{"index", quad.addTexture(png(1, 1, {200, 100, 50, 255}))}}},
                                             {"metallicFactor", 1.0},
                                             {"roughnessFactor", 0.2}};
    quad.material["alphaMode"] = "MASK";
    quad.material["extensions"] = {{"KHR_materials_unlit", json::object()}};
    quad.gltf.doc["extensionsUsed"] = {"KHR_materials_unlit"};
    quad.gltf.doc["extensionsRequired"] = {"KHR_materials_unlit"};
    quad.extra_attributes["COLOR_0"] = quad.gltf.addData(std::vector<float>{0.5f, 1.0f, 1.0f, 0.5f, 1.0f, 1.0f, 0.5f,
                                                                            1.0f, 1.0f, 0.5f, 1.0f, 1.0f},
                                                         test::kFloat, "VEC3");
    const Scene scene = quad.load();
    EXPECT_TRUE(scene.stats.warnings.empty()) << scene.stats.warnings.front();
    const Material& m = scene.materials.at(0);
    EXPECT_TRUE(m.unlit);
    EXPECT_TRUE(m.isEmissive());
    EXPECT_EQ(m.alpha_mode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(m.base_alpha, 0.8f);  // above the cut-off: the quad stays solid
    const Tracer tracer(scene);
    const auto hit = hitAt(scene, tracer, 0.3f, -0.2f);
    ASSERT_TRUE(hit);
    const ShadingMaterial shading = evaluateMaterial(scene, *hit);
    const float r = 0.5f * srgbToLinear(200.0f / 255.0f) * 0.5f, g = 0.25f * srgbToLinear(100.0f / 255.0f),
                b = 1.0f * srgbToLinear(50.0f / 255.0f);
    expectNear(shading.emission, {r, g, b}, 1e-4f);
    expectNear(shading.base_color, {0.0f, 0.0f, 0.0f}, 0.0f);
    const GltfBsdf bsdf(shading, *hit);
    expectNear(bsdf.albedo(glm::vec3(0.0f, 1.0f, 0.0f)), {0.0f, 0.0f, 0.0f}, 0.0f);
    expectNear(bsdf.albedo(glm::normalize(glm::vec3(0.9f, 0.1f, 0.0f))), {0.0f, 0.0f, 0.0f}, 0.0f);
    // Light sampling sees it as an emitter, with the full surface point's emission bit for bit.
    EXPECT_TRUE(LightSampler(scene).hasEmissiveTriangles());
    for (uint32_t triangle = 0; triangle < scene.triangles.size(); ++triangle) {
        const EmitterPoint e = makeEmitterPoint(scene, triangle, 0.25f, 0.5f);
        EXPECT_EQ(e.emission, evaluateMaterial(scene, makeSurfacePoint(scene, triangle, 0.25f, 0.5f)).emission);
    }
}

/// A closed 2 m box whose floor is white-ish Lambertian (albedo 0.5, no specular layer) and whose
/// five other faces are unlit with colour L, facing in. The floor sees only them, so its
/// outgoing radiance is exactly 0.5 L; the unlit faces show L and reflect nothing.
Scene unlitDomeOverALambertianFloor(const test::TempDir& dir, glm::vec3 dome) {
    test::GltfBuilder b;
    const int floor_material = b.addMaterial(
        {{"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.5, 0.5, 1}}, {"metallicFactor", 0.0}}},
         {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0.0}}}}}});
    const int dome_material = b.addMaterial(
        {{"pbrMetallicRoughness", {{"baseColorFactor", {dome.x, dome.y, dome.z, 1}}}},
         {"extensions", {{"KHR_materials_unlit", json::object()}}}});
    b.doc["extensionsUsed"] = {"KHR_materials_unlit", "KHR_materials_specular"};
    std::vector<int> roots;
    const glm::vec3 normals[6] = {{0, 1, 0}, {0, -1, 0}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const glm::vec3& n : normals) {  // inward normals; face centre at -n
        const glm::vec3 t1 = std::abs(n.y) > 0.5f ? glm::vec3(1, 0, 0) : glm::vec3(0, 1, 0);
        const glm::vec3 t2 = glm::cross(n, t1);  // t1 x t2 = n: counter-clockwise seen from inside
        std::vector<float> positions;
        for (const glm::vec2 c : {glm::vec2(-1, -1), glm::vec2(1, -1), glm::vec2(1, 1), glm::vec2(-1, 1)}) {
            const glm::vec3 p = -n + c.x * t1 + c.y * t2;
            positions.insert(positions.end(), {p.x, p.y, p.z});
        }
        roots.push_back(b.addMeshNode(
            {{"attributes", {{"POSITION", b.addPositions(positions)}}},
             {"indices", b.addData(std::vector<uint16_t>{0, 1, 2, 0, 2, 3}, test::kUnsignedShort, "SCALAR")},
             {"material", n.y > 0.5f ? floor_material : dome_material}}));
    }
    b.setScene(roots);
    return loadGltf(b.writeEmbedded(dir, "unlit_dome.gltf"));
}

TEST(Unlit, ADomeLightsTheSceneAsASkyWouldInPathTracing) {
    test::TempDir dir;
    const glm::vec3 dome{0.2f, 0.4f, 0.8f};
    const Scene scene = unlitDomeOverALambertianFloor(dir, dome);
    EXPECT_TRUE(scene.stats.warnings.empty()) << scene.stats.warnings.front();
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    const PathTracer path_tracer(tracer, lights, PathTracerSettings{});
    const auto meanSeen = [&](glm::vec3 forward, uint32_t spp) {
        Camera camera;
        camera.forward = forward;
        camera.up = std::abs(forward.y) > 0.5f ? glm::vec3(0, 0, -1) : glm::vec3(0, 1, 0);
        camera.yfov = 0.5f;
        TraceCounters counters;
        const Image image = renderImage(
            CameraRays(camera, 16, 16), ImageRenderSettings{16, 16, spp, 3},
            [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, counters); },
            nullptr);
        glm::dvec3 sum(0.0);
        for (const glm::vec3& p : image.pixels) sum += glm::dvec3(p);
        return glm::vec3(sum / double(image.pixels.size()));
    };
    expectNear(meanSeen({0, -1, 0}, 256), 0.5f * dome, 0.01f * dome.z);  // the floor: 0.5 L
    expectNear(meanSeen({1, 0, 0}, 4), dome, 1e-5f);                     // a wall: L, nothing more
}

/// The mean radiance of a bake's floor voxels (bottom layer of cells, away from the sides, where
/// cells can hold floor and dome together: the key keeps only the normal's signs, which the floor,
/// facing +Y, shares with the dome's faces facing +X and +Z), and the largest relative error of
/// its dome voxels (every other cell) against the dome's colour.
struct DomeBakeResult {
    glm::dvec3 floor_mean{0.0};
    uint32_t floor_voxels = 0, dome_voxels = 0;
    double worst_floor_error = 0.0, worst_dome_error = 0.0;
};

DomeBakeResult bakeUnlitDome(const Scene& scene, glm::vec3 dome, bool cache_resampling) {
    const TestBakeScene bake{Scene(scene)};
    BakeSettings settings;
    settings.width = settings.height = 96;
    settings.sharc.grid.capacity = 1u << 16;
    settings.sharc.grid.scene_scale = 5.0f;  // coarse voxels: a few hundred in the box
    settings.sharc.cache_resampling = cache_resampling;
    const std::unique_ptr<Baker> baker = bake.makeBaker(settings);
    for (int i = 0; i < 256; ++i) baker->runIteration();
    const SharcCache& cache = baker->cache();
    std::map<uint32_t, std::pair<glm::ivec3, glm::ivec3>> level_bounds;  // each level's extreme cells
    for (uint32_t slot = 0; slot < cache.capacity(); ++slot) {
        if (cache.table().keyAt(slot) == 0) continue;
        const HashGridCell cell = decodeHashGridKey(cache.table().keyAt(slot));
        const glm::ivec3 grid(cell.grid.x, cell.grid.y, cell.grid.z);
        auto [it, fresh] = level_bounds.try_emplace(cell.level, grid, grid);
        it->second.first = glm::min(it->second.first, grid);
        it->second.second = glm::max(it->second.second, grid);
    }
    DomeBakeResult result;
    const glm::vec3 floor = 0.5f * dome;
    for (uint32_t slot = 0; slot < cache.capacity(); ++slot) {
        const ResolvedEntry& r = cache.resolved()[slot];
        if (cache.table().keyAt(slot) == 0 || r.total_samples < 64) continue;
        const HashGridCell cell = decodeHashGridKey(cache.table().keyAt(slot));
        const auto& [low, high] = level_bounds.at(cell.level);
        const bool bottom = cell.grid.y == low.y;
        const bool side = cell.grid.x == low.x || cell.grid.x == high.x || cell.grid.z == low.z ||
                          cell.grid.z == high.z;
        if (bottom && side) continue;
        const glm::vec3 expected = bottom ? floor : dome;
        double error = 0.0;
        for (int c = 0; c < 3; ++c) error = std::max(error, std::abs(double(r.mean[c]) / expected[c] - 1.0));
        if (bottom) {
            result.floor_mean += glm::dvec3(r.mean);
            ++result.floor_voxels;
            result.worst_floor_error = std::max(result.worst_floor_error, error);
        } else {
            ++result.dome_voxels;
            result.worst_dome_error = std::max(result.worst_dome_error, error);
        }
    }
    if (result.floor_voxels) result.floor_mean /= double(result.floor_voxels);
    return result;
}

TEST(Unlit, ADomeLightsTheSceneAsASkyWouldInTheBakedCache) {
    test::TempDir dir;
    const glm::vec3 dome{0.2f, 0.4f, 0.8f};
    const Scene scene = unlitDomeOverALambertianFloor(dir, dome);
    // Without cache resampling every floor sample carries its own bounce to the dome: exact
    // transport. A path that had crossed the dome (which reflects nothing) once died at the next
    // floor vertex, so that floor voxel kept its direct light alone: the floor came out 20% dark.
    // With resampling (the default) paths also read the dome's cells at the floor's edge, which
    // hold floor and dome together: a small spatial bias, SHaRC's own.
    for (const bool resampling : {false, true}) {
        const DomeBakeResult result = bakeUnlitDome(scene, dome, resampling);
        SCOPED_TRACE(resampling ? "cache resampling" : "no cache resampling");
        ASSERT_GT(result.floor_voxels, 10u);
        ASSERT_GT(result.dome_voxels, 10u);
        for (int c = 0; c < 3; ++c)
            EXPECT_NEAR(result.floor_mean[c], 0.5 * dome[c], (resampling ? 0.03 : 0.015) * 0.5 * dome[c]);
        EXPECT_LT(result.worst_floor_error, 0.1);   // one voxel's noise (a short history window)
        EXPECT_LT(result.worst_dome_error, 0.005);  // the dome shows its colour and nothing else
    }
}

TEST(OcclusionMaps, AreDroppedWithAWarning) {
    QuadScene quad;
    quad.material["occlusionTexture"] = {{"index", quad.addTexture(png(1, 1, {128, 128, 128, 255}))}};
    const Scene scene = quad.load();
    EXPECT_TRUE(warnedAbout(scene, "occlusionTexture ignored"));
}

// A sky map is looked up bilinearly, so one bright texel lights the half texel around it in its
// eight neighbours too; light sampling must reach every direction it lights (else those are lit
// through BSDF samples alone, as fireflies), and its pdf must integrate to 1 over the sphere.
TEST(SkyMap, LightSamplingReachesEveryDirectionTheMapLights) {
    Scene scene = loadGltf(scenePath("cornell_box"));
    Texture map;
    map.width = 32;
    map.height = 16;
    map.texels.assign(size_t(map.width) * size_t(map.height), glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    map.wrap_t = WrapMode::ClampToEdge;
    const int sun_x = 0, sun_y = 5;  // on the seam, where u wraps
    map.texels[size_t(sun_y) * size_t(map.width) + size_t(sun_x)] = glm::vec4(1e6f, 1e6f, 1e6f, 1.0f);
    scene.sky.map = map;
    const LightSampler lights(scene);
    const glm::vec3 normal(0.0f, 1.0f, 0.0f);  // a map's pdf does not depend on the surface
    int lit = 0;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            for (const float inset : {0.3f, 0.5f, 0.7f}) {  // inside the cell, off its centre too
                const float u = (float(sun_x + dx) + inset) / float(map.width);
                const glm::vec3 direction = equirectToDirection(
                    glm::vec2(u < 0.0f ? u + 1.0f : u, (float(sun_y + dy) + inset) / float(map.height)));
                if (!(maxComponent(lights.skyRadiance(direction)) > 0.0f)) continue;
                ++lit;
                EXPECT_GT(lights.pdfSky(glm::vec3(0.0f), normal, direction), 0.0f)
                    << "cell " << dx << ", " << dy << " inset " << inset;
            }
        }
    }
    EXPECT_GE(lit, 9);  // the sun's own cell, and the half texel of each neighbour nearest it
    // The pdf over directions integrates to 1 (a grid over the sphere, sin-weighted).
    double integral = 0.0;
    constexpr int kSteps = 512;
    for (int j = 0; j < kSteps; ++j) {
        for (int i = 0; i < 2 * kSteps; ++i) {
            const glm::vec2 uv((float(i) + 0.5f) / float(2 * kSteps), (float(j) + 0.5f) / float(kSteps));
            const double sin_theta = std::sin(kPi * double(uv.y));
            integral += double(lights.pdfSky(glm::vec3(0.0f), normal, equirectToDirection(uv))) * sin_theta *
                        (2.0 * kPi / (2 * kSteps)) * (kPi / kSteps);
        }
    }
    // pdfSky includes the sky's share of light selection; with the Cornell box's panel beside it
    // that share is below 1, so the integral is that share.
    EXPECT_GT(integral, 0.0);
    EXPECT_LE(integral, 1.0 + 1e-3);
}

// KHR_lights_punctual's range: the inverse square law times the extension's recommended
// clamp(1 - (d/range)^4, 0, 1), nothing beyond. (The squared window, UE4's, gave 0.64 of the
// spec's light at two thirds of the range.)
TEST(PunctualLights, RangeWindowsTheInverseSquareLawAsTheExtensionRecommends) {
    Scene scene = loadGltf(scenePath("cornell_box"));
    scene.lights.clear();
    PunctualLight bulb;
    bulb.type = LightType::Point;
    bulb.position = glm::vec3(0.0f, 10.0f, 0.0f);
    bulb.intensity = glm::vec3(4.0f);
    bulb.range = 1.5f;
    scene.lights.push_back(bulb);
    for (Material& m : scene.materials) m.emissive = glm::vec3(0.0f);  // the light alone
    const LightSampler lights(scene);
    for (const float d : {0.5f, 1.0f, 1.4f, 1.6f}) {
        SurfaceHit at;
        at.position = bulb.position - glm::vec3(0.0f, d, 0.0f);
        at.geometric_normal = at.shading_normal = at.face_normal = glm::vec3(0.0f, 1.0f, 0.0f);
        LightSample sample;
        const bool lit = lights.sample(at, 0.5f, glm::vec2(0.5f), sample);
        const float ratio = d / bulb.range;
        const float expected = 4.0f / (d * d) * std::max(0.0f, 1.0f - ratio * ratio * ratio * ratio);
        if (d > bulb.range) {
            EXPECT_FALSE(lit && sample.radiance.x > 0.0f) << d;
            continue;
        }
        ASSERT_TRUE(lit) << d;
        EXPECT_NEAR(sample.radiance.x * sample.pdf, expected, 1e-4f * expected) << d;  // pdf: selection only
    }
}

/// Appends a one-sided emissive square at height y (side `side`, centred on the Y axis) that
/// faces the origin, with a material of its own emitting `emission`.
void addEmissiveSquare(Scene& scene, float y, float side, float emission) {
    Material m;
    m.emissive = glm::vec3(1.0f);
    m.emissive_strength = emission;
    const uint32_t material = uint32_t(scene.materials.size());
    scene.materials.push_back(m);
    const uint32_t base = uint32_t(scene.positions.size());
    const float h = 0.5f * side;
    for (glm::vec2 c : {glm::vec2(-h, -h), glm::vec2(h, -h), glm::vec2(h, h), glm::vec2(-h, h)})
        scene.positions.push_back(glm::vec3(c.x, y, c.y));
    // Counter-clockwise seen from the origin: the front faces it.
    if (y > 0.0f) {
        scene.triangles.push_back(glm::uvec3(base, base + 1, base + 2));
        scene.triangles.push_back(glm::uvec3(base, base + 2, base + 3));
    } else {
        scene.triangles.push_back(glm::uvec3(base, base + 2, base + 1));
        scene.triangles.push_back(glm::uvec3(base, base + 3, base + 2));
    }
    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
}

// Next-event estimation chooses a light in proportion to its power, pi x area x luminance. A
// 1e37 emitter of 100 m^2 has a power beyond float32 (1.6e39): it was infinity, which the
// selection reads as no power, so the brightest light in the scene was never chosen and every
// shadow ray went to a light 37 orders of magnitude dimmer.
TEST(LightSelection, APowerBeyondFloat32StillChoosesTheBrightestLight) {
    Scene scene;
    addEmissiveSquare(scene, 1.0f, 10.0f, 1e37f);  // the ceiling: 1e37 over 100 m^2
    addEmissiveSquare(scene, -1.0f, 1.0f, 1.0f);   // the floor: 1 over 1 m^2
    scene.bounds_min = glm::vec3(-5.0f, -1.0f, -5.0f);
    scene.bounds_max = glm::vec3(5.0f, 1.0f, 5.0f);
    const LightSampler lights(scene);
    SurfaceHit at;
    at.shading_normal = at.geometric_normal = at.face_normal = glm::vec3(0.0f, 1.0f, 0.0f);
    int ceiling = 0, floor = 0;
    for (int i = 0; i < 64; ++i) {
        LightSample sample;
        ASSERT_TRUE(lights.sample(at, (float(i) + 0.5f) / 64.0f, glm::vec2(0.3f, 0.4f), sample)) << i;
        (sample.wi.y > 0.0f ? ceiling : floor) += 1;
    }
    EXPECT_EQ(ceiling, 64);
    EXPECT_EQ(floor, 0);
    // Its power is the two triangles' pi x 50 x 1e37 each: the ceiling's pdf for a hit straight
    // above, 1 m away, is its selection probability (all but 1e-38 of it) over its 100 m^2.
    SurfaceHit above;
    above.position = glm::vec3(0.0f, 1.0f, 0.0f);
    above.face_normal = glm::vec3(0.0f, -1.0f, 0.0f);
    above.triangle = 0;
    EXPECT_FLOAT_EQ(lights.pdfEmitter(glm::vec3(0.0f), glm::vec3(0.0f, 1.0f, 0.0f), above), 0.5f / 50.0f);
}

}  // namespace
}  // namespace sharcbake
