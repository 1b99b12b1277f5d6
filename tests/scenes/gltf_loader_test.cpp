// SPDX-License-Identifier: Apache-2.0
/// @file gltf_loader_test.cpp
/// @brief loadGltf on small glTF / GLB files written by the tests themselves.
#include "gltf_builder.h"
#include "load_expectations.h"
#include "png_bytes.h"

#include "sharcbake/scene_loader.h"

#include <gtest/gtest.h>

#include <algorithm>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>

namespace sharcbake {
namespace {

using nlohmann::json;
using test::GltfBuilder;
using test::TempDir;

constexpr float kEps = 1e-5f;

void expectVec3Near(const glm::vec3& actual, const glm::vec3& expected, float eps = kEps) {
    EXPECT_NEAR(actual.x, expected.x, eps) << "x";
    EXPECT_NEAR(actual.y, expected.y, eps) << "y";
    EXPECT_NEAR(actual.z, expected.z, eps) << "z";
}

/// Runs `load` and returns the SceneLoadError message, failing the test if nothing throws.
template <class F>
std::string loadErrorOf(F&& load) {
    try {
        load();
    } catch (const SceneLoadError& e) {
        return e.what();
    }
    ADD_FAILURE() << "expected SceneLoadError";
    return {};
}

/// Warnings that contain every one of `parts`.
size_t warningsWith(const Scene& scene, const std::vector<std::string>& parts) {
    size_t n = 0;
    for (const std::string& w : scene.stats.warnings) {
        bool all = true;
        for (const std::string& part : parts) all = all && w.find(part) != std::string::npos;
        n += all ? 1 : 0;
    }
    return n;
}

glm::vec3 geometricNormal(const Scene& s, size_t tri) {
    const glm::uvec3 t = s.triangles[tri];
    return glm::normalize(glm::cross(s.positions[t.y] - s.positions[t.x], s.positions[t.z] - s.positions[t.x]));
}

/// A unit right triangle in the XY plane facing +Z, with normals.
json unitTrianglePrimitive(GltfBuilder& b) {
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int nrm = b.addPositions({0, 0, 1, 0, 0, 1, 0, 0, 1});
    return {{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}};
}

// ------------------------------------------------------------------------------------ geometry

TEST(GltfLoader, NodeHierarchyAccumulatesTranslationRotationScale) {
    TempDir dir;
    GltfBuilder b;
    // A tilted triangle with its true normal, so the inverse transpose is exercised by the
    // non-uniform scale below.
    const int pos = b.addPositions({1, 0, 0, 0, 1, 0, 0, 0, 1});
    const float k = 1.0f / std::sqrt(3.0f);
    const int nrm = b.addPositions({k, k, k, k, k, k, k, k, k});
    const int child = b.addMeshNode({{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}},
                                    {{"translation", {0, 1, 0}}, {"scale", {2, 1, 1}}});
    const float s = std::sqrt(0.5f);  // 90 degrees about +Y: (x, y, z) -> (z, y, -x)
    const int parent = b.addNode({{"translation", {10, 0, 0}}, {"rotation", {0, s, 0, s}}, {"children", {child}}});
    b.setScene({parent});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "hierarchy.gltf"));

    ASSERT_EQ(scene.triangles.size(), 1u);
    const glm::uvec3 t = scene.triangles[0];
    // child: scale then translate; parent: rotate then translate.
    expectVec3Near(scene.positions[t.x], {10, 1, -2});
    expectVec3Near(scene.positions[t.y], {10, 2, 0});
    expectVec3Near(scene.positions[t.z], {11, 1, 0});
    // Normal of the scaled plane x/2 + y + z = 1 is (0.5, 1, 1), rotated to (1, 1, -0.5).
    const glm::vec3 expectedNormal = glm::normalize(glm::vec3(1, 1, -0.5f));
    for (uint32_t v : {t.x, t.y, t.z}) expectVec3Near(scene.normals[v], expectedNormal);
    expectVec3Near(geometricNormal(scene, 0), expectedNormal);
    expectVec3Near(scene.bounds_min, {10, 1, -2});
    expectVec3Near(scene.bounds_max, {11, 2, 0});
}

TEST(GltfLoader, MatrixNodeTransform) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    // Column-major: translation (0, 0, 5) in elements 12..14, uniform scale 3.
    const int node = b.addMeshNode(prim, {{"matrix", {3, 0, 0, 0, 0, 3, 0, 0, 0, 0, 3, 0, 0, 0, 5, 1}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "matrix.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    expectVec3Near(scene.bounds_min, {0, 0, 5});
    expectVec3Near(scene.bounds_max, {3, 3, 5});
}

/// Animations are not played: the mesh stays where its node's translation puts it, and the
/// warning names how many nodes move and which cameras among them (an animated walkthrough
/// camera, or an object baked in a pose the artist was not looking at, said nothing).
TEST(GltfLoader, AnimationsAreNotPlayedAndSaySo) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int mesh_node = b.addMeshNode(prim, {{"translation", {-2, 0, 0}}});
    const int camera_node = b.addNode({{"camera", 0}, {"name", "WalkCam"}, {"translation", {0, 0, 5}}});
    b.doc["cameras"] = json::array({{{"type", "perspective"}, {"perspective", {{"yfov", 0.8}, {"znear", 0.1}}}}});
    const int times = b.addData(std::vector<float>{0.0f, 1.0f}, test::kFloat, "SCALAR");
    const int moves = b.addData(std::vector<float>{-2, 0, 0, 2, 0, 0}, test::kFloat, "VEC3");
    b.doc["animations"] = json::array(
        {{{"samplers", json::array({{{"input", times}, {"output", moves}}})},
          {"channels",
           json::array({{{"sampler", 0}, {"target", {{"node", mesh_node}, {"path", "translation"}}}},
                        {{"sampler", 0}, {"target", {{"node", camera_node}, {"path", "translation"}}}}})}}});
    b.setScene({mesh_node, camera_node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "animated.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    EXPECT_FLOAT_EQ(scene.bounds_min.x, -2.0f) << "the node's own translation, not an animated one";
    const auto warning =
        std::find_if(scene.stats.warnings.begin(), scene.stats.warnings.end(), [](const std::string& w) {
            return w.find(
                       "1 animation moves 2 nodes (cameras among them: node 1 'WalkCam'); animations are not played") !=
                   std::string::npos;
        });
    EXPECT_NE(warning, scene.stats.warnings.end()) << ::testing::PrintToString(scene.stats.warnings);
}

TEST(GltfLoader, MirroringTransformFlipsWinding) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int node = b.addMeshNode(prim, {{"scale", {-1, 1, 1}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "mirror.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    // The shading normal stays +Z and the winding must still agree with it.
    expectVec3Near(scene.normals[scene.triangles[0].x], {0, 0, 1});
    expectVec3Near(geometricNormal(scene, 0), {0, 0, 1});
}

TEST(GltfLoader, IndexedU8U16U32AndNonIndexed) {
    TempDir dir;
    GltfBuilder b;
    const std::vector<float> quad = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const std::vector<uint8_t> i8 = {0, 1, 2, 0, 2, 3};
    const std::vector<uint16_t> i16 = {0, 1, 2, 0, 2, 3};
    const std::vector<uint32_t> i32 = {0, 1, 2, 0, 2, 3};
    json prims = json::array();
    prims.push_back({{"attributes", {{"POSITION", b.addPositions(quad)}}},
                     {"indices", b.addData(i8, test::kUnsignedByte, "SCALAR")}});
    prims.push_back({{"attributes", {{"POSITION", b.addPositions(quad)}}},
                     {"indices", b.addData(i16, test::kUnsignedShort, "SCALAR")}});
    prims.push_back({{"attributes", {{"POSITION", b.addPositions(quad)}}},
                     {"indices", b.addData(i32, test::kUnsignedInt, "SCALAR")}});
    prims.push_back({{"attributes", {{"POSITION", b.addPositions({0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 0, 1, 1, 1, 1, 0, 1, 1})}}},
                     {"mode", 4}});
    b.addMesh(prims, "Quads");
    b.addNode({{"mesh", 0}});
    b.setScene({0});
    const Scene scene = loadGltf(b.writeExternal(dir, "indexed.gltf", "indexed.bin"));
    EXPECT_EQ(scene.triangles.size(), 8u);
    EXPECT_EQ(scene.stats.triangles_loaded, 8u);
    EXPECT_EQ(scene.stats.degenerate_triangles_dropped, 0u);
    for (size_t i = 0; i < scene.triangles.size(); ++i) expectVec3Near(geometricNormal(scene, i), {0, 0, 1});
    ASSERT_EQ(scene.normals.size(), scene.positions.size());  // flat normals generated
    for (const glm::vec3& n : scene.normals) expectVec3Near(n, {0, 0, 1});
}

TEST(GltfLoader, InterleavedStrideAndNormalizedTexcoords) {
    TempDir dir;
    GltfBuilder b;
    // position xyz + normal xyz per vertex: a byteStride of 24 shared by two accessors.
    const std::vector<float> interleaved = {0, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 1, 0, 0, 0, 1};
    const int view = b.addView(interleaved.data(), interleaved.size() * sizeof(float), 24);
    const int pos = b.addAccessor(view, test::kFloat, 3, "VEC3", 0);
    const int nrm = b.addAccessor(view, test::kFloat, 3, "VEC3", 12);
    const std::vector<uint16_t> uv = {0, 0, 65535, 0, 0, 32768};
    const int tex = b.addData(uv, test::kUnsignedShort, "VEC2", true);
    const int node = b.addMeshNode({{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}, {"TEXCOORD_0", tex}}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "stride.gltf"));
    ASSERT_EQ(scene.positions.size(), 3u);
    expectVec3Near(scene.positions[1], {1, 0, 0});
    expectVec3Near(scene.positions[2], {0, 1, 0});
    expectVec3Near(scene.normals[2], {0, 0, 1});
    ASSERT_EQ(scene.texcoords0.size(), 3u);
    EXPECT_NEAR(scene.texcoords0[1].x, 1.0f, kEps);
    EXPECT_NEAR(scene.texcoords0[2].y, 32768.0f / 65535.0f, kEps);
    EXPECT_TRUE(scene.texcoords1.empty());
}

TEST(GltfLoader, StripAndFanBecomeConsistentlyWoundTriangles) {
    TempDir dir;
    GltfBuilder b;
    // Strip zig-zag along +X, fan around the origin; both in the XY plane facing +Z.
    const int strip = b.addPositions({0, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 2, 0, 0});
    const int fan = b.addPositions({0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, 1, 0});
    b.addMesh(json::array({{{"attributes", {{"POSITION", strip}}}, {"mode", 5}},
                           {{"attributes", {{"POSITION", fan}}}, {"mode", 6}}}));
    b.addNode({{"mesh", 0}});
    b.setScene({0});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "strip.gltf"));
    ASSERT_EQ(scene.triangles.size(), 6u);  // 3 from the strip, 3 from the fan
    for (size_t i = 0; i < scene.triangles.size(); ++i) {
        SCOPED_TRACE(i);
        // The strip starts clockwise (0,0)->(0,1)->(1,0), so its triangles all face -Z.
        expectVec3Near(geometricNormal(scene, i), i < 3 ? glm::vec3(0, 0, -1) : glm::vec3(0, 0, 1));
    }
}

TEST(GltfLoader, PointsAndLinesSkippedAndCounted) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    b.addMesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"mode", 0}},
                           {{"attributes", {{"POSITION", pos}}}, {"mode", 1}},
                           {{"attributes", {{"POSITION", pos}}}}}));
    b.addNode({{"mesh", 0}});
    b.setScene({0});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "lines.gltf"));
    EXPECT_EQ(scene.stats.primitives_skipped, 2u);
    EXPECT_EQ(scene.triangles.size(), 1u);
}

TEST(GltfLoader, DegenerateTrianglesDroppedAndCounted) {
    TempDir dir;
    GltfBuilder b;
    // Vertices 3, 4, 5 are collinear.
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 2, 1, 0, 2, 2, 0, 2});
    const std::vector<uint16_t> idx = {0, 1, 2, 0, 0, 1, 3, 4, 5};
    const int node = b.addMeshNode({{"attributes", {{"POSITION", pos}}},
                                    {"indices", b.addData(idx, test::kUnsignedShort, "SCALAR")}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "degenerate.gltf"));
    EXPECT_EQ(scene.triangles.size(), 1u);
    EXPECT_EQ(scene.stats.triangles_loaded, 1u);
    EXPECT_EQ(scene.stats.degenerate_triangles_dropped, 2u);
    // Bounds cover only the kept triangle, not the dropped ones at z = 2.
    expectVec3Near(scene.bounds_max, {1, 1, 0});
}

// Tiny, well-shaped triangles are kept down to where float can hold their normal: a fuzzed file
// scaled instances by 1e-43, whose float normals came out NaN and failed an Embree assertion.
TEST(GltfLoader, TrianglesTooSmallForAFloatNormalAreDropped) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int mesh = b.addMesh(json::array({{{"attributes", {{"POSITION", pos}}}}}));
    std::vector<int> roots;
    for (const double scale : {1e-6, 1e-9, 1e-20, 1e-43}) {  // edges of these lengths, at (10, 10, 10)
        roots.push_back(b.addNode({{"mesh", mesh}, {"translation", {10, 10, 10}}, {"scale", {scale, scale, scale}}}));
    }
    b.setScene(roots);
    const Scene scene = loadGltf(b.writeEmbedded(dir, "tiny.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);  // the 1e-6 triangle; at 10 the 1e-9 one is flat in float
    EXPECT_EQ(scene.stats.degenerate_triangles_dropped, 3u);
    const glm::uvec3 t = scene.triangles[0];
    const glm::vec3 n = glm::normalize(
        glm::cross(scene.positions[t.y] - scene.positions[t.x], scene.positions[t.z] - scene.positions[t.x]));
    EXPECT_NEAR(n.z, 1.0f, 1e-6f);

    // At the origin float holds a 1e-8 triangle's corners and its normal; not a 1e-20 one's normal.
    GltfBuilder near;
    const int near_pos = near.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int near_mesh = near.addMesh(json::array({{{"attributes", {{"POSITION", near_pos}}}}}));
    std::vector<int> near_roots;
    for (const double scale : {1e-8, 1e-20}) {
        near_roots.push_back(near.addNode({{"mesh", near_mesh}, {"scale", {scale, scale, scale}}}));
    }
    near.setScene(near_roots);
    const Scene origin = loadGltf(near.writeEmbedded(dir, "tiny_origin.gltf"));
    EXPECT_EQ(origin.triangles.size(), 1u);
    EXPECT_EQ(origin.stats.degenerate_triangles_dropped, 1u);
    // Named apart from flat ones, with the fix: a room scaled by 1e-10 was refused as "24
    // degenerate triangles ... have no area", which they do.
    EXPECT_EQ(origin.stats.triangles_too_small_for_float, 1u);
    EXPECT_EQ(warningsWith(origin, {"1 triangle is too small for float32", "scale it up"}), 1u)
        << ::testing::PrintToString(origin.stats.warnings);
    // At (10, 10, 10) none is too small for a normal: float rounding collapses the 1e-9 one (named
    // as such: move towards the origin), and the others are flat even in double there.
    EXPECT_EQ(scene.stats.triangles_too_small_for_float, 0u);
    EXPECT_EQ(scene.stats.triangles_collapsed_by_rounding, 1u);
}

TEST(GltfLoader, AnEmitterOnlyOnTrianglesWithoutAreaIsNamed) {
    // A lamp modelled as a collapsed plane: its triangles are dropped, and "no emissive surfaces"
    // alone read as if its emission had not been loaded.
    TempDir dir;
    GltfBuilder b;
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0});
    const std::vector<uint16_t> lamp = {0, 1, 2};   // collinear
    const std::vector<uint16_t> floor = {0, 1, 3};  // a real triangle, not emissive
    const int emissive = b.addMaterial({{"name", "lamp"}, {"emissiveFactor", {1, 1, 1}}});
    const int plain = b.addMaterial({{"name", "floor"}});
    b.setScene({b.addMeshNode({{"attributes", {{"POSITION", pos}}},
                               {"indices", b.addData(lamp, test::kUnsignedShort, "SCALAR")},
                               {"material", emissive}}),
                b.addMeshNode({{"attributes", {{"POSITION", pos}}},
                               {"indices", b.addData(floor, test::kUnsignedShort, "SCALAR")},
                               {"material", plain}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "flat_lamp.gltf"));
    std::string named;
    for (const std::string& w : scene.stats.warnings) {
        if (w.find("no area") != std::string::npos) named += w;
    }
    EXPECT_NE(named.find("'lamp' emits light, but all 1 of its triangles were dropped as degenerate"),
              std::string::npos)
        << named;
    EXPECT_EQ(named.find("'floor'"), std::string::npos) << named;
}

// A model placed far from the origin by its node: its triangles have area in the file's double
// precision transforms, and rounding the world positions to float collapses the small ones. They
// are counted apart from triangles modelled flat, and one warning says why and what to do.
TEST(GltfLoader, TrianglesCollapsedByFloatRoundingAreNamed) {
    TempDir dir;
    GltfBuilder b;
    // A 0.2 m triangle, a 100 m one, and one modelled flat (collinear), 1e7 m out along x.
    const int pos = b.addPositions({0, 0, 0, 0.2f, 0, 0, 0, 0.2f, 0,  //
                                    0, 0, 0, 100,  0, 0, 0, 100,  0,  //
                                    0, 0, 1, 1,    0, 1, 2, 0,    1});
    const int mesh_node = b.addMeshNode({{"attributes", {{"POSITION", pos}}}});
    const int root = b.addNode({{"translation", {1e7, 0, 0}}, {"children", {mesh_node}}});
    b.setScene({root});
    const Scene far = loadGltf(b.writeEmbedded(dir, "far.gltf"));
    EXPECT_EQ(far.triangles.size(), 1u);  // the 100 m triangle keeps its area at 1-unit float steps
    EXPECT_EQ(far.stats.degenerate_triangles_dropped, 2u);
    EXPECT_EQ(far.stats.triangles_collapsed_by_rounding, 1u);  // not the collinear one
    const auto named = std::find_if(far.stats.warnings.begin(), far.stats.warnings.end(), [](const std::string& w) {
        return w.find("1 triangles collapsed") != std::string::npos &&
               w.find("1e+07 from the origin") != std::string::npos &&
               w.find("move it towards the origin") != std::string::npos;
    });
    EXPECT_NE(named, far.stats.warnings.end()) << testing::PrintToString(far.stats.warnings);

    // The same model at the origin: only the collinear triangle is dropped, and nothing is said.
    GltfBuilder near_origin;
    const int near_pos = near_origin.addPositions(
        {0, 0, 0, 0.2f, 0, 0, 0, 0.2f, 0, 0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 1, 1, 0, 1, 2, 0, 1});
    near_origin.setScene({near_origin.addMeshNode({{"attributes", {{"POSITION", near_pos}}}})});
    const Scene home = loadGltf(near_origin.writeEmbedded(dir, "home.gltf"));
    EXPECT_EQ(home.triangles.size(), 2u);
    EXPECT_EQ(home.stats.triangles_collapsed_by_rounding, 0u);
    for (const std::string& w : home.stats.warnings) EXPECT_EQ(w.find("collapsed"), std::string::npos) << w;
}

// An emissive face exported twice (here once with the other winding) is two lights on one
// surface: the light doubles, and the loader says so; a plain duplicated face is left alone.
TEST(GltfLoader, CoincidentEmissiveTrianglesAreNamed) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0, 5, 0, 0, 6, 0, 0, 5, 1, 0});
    const std::vector<uint16_t> idx = {0, 1, 2, 0, 2, 1, 3, 4, 5, 3, 4, 5};
    b.addMaterial({{"emissiveFactor", {1, 1, 1}}});
    b.addMaterial({{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}}}});
    const int indices = b.addData(idx, test::kUnsignedShort, "SCALAR");
    const int lit = b.addMeshNode({{"attributes", {{"POSITION", pos}}}, {"indices", indices}, {"material", 0}});
    b.setScene({lit});
    const Scene twice = loadGltf(b.writeEmbedded(dir, "twice.gltf"));
    EXPECT_EQ(twice.triangles.size(), 4u);
    const auto named = [](const Scene& scene) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(), [](const std::string& w) {
            return w.find("2 emissive triangles lie exactly on another") != std::string::npos;
        });
    };
    EXPECT_EQ(named(twice), 1) << testing::PrintToString(twice.stats.warnings);

    GltfBuilder plain;
    const int plain_pos = plain.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    plain.addMaterial({{"pbrMetallicRoughness", {{"baseColorFactor", {1, 1, 1, 1}}}}});
    const std::vector<uint16_t> plain_idx = {0, 1, 2, 0, 1, 2};
    plain.setScene({plain.addMeshNode({{"attributes", {{"POSITION", plain_pos}}},
                                       {"indices", plain.addData(plain_idx, test::kUnsignedShort, "SCALAR")},
                                       {"material", 0}})});
    const Scene unlit = loadGltf(plain.writeEmbedded(dir, "plain.gltf"));
    for (const std::string& w : unlit.stats.warnings) EXPECT_EQ(w.find("emissive triangles"), std::string::npos) << w;
}

TEST(GltfLoader, SparseAccessorSubstitutesValues) {
    TempDir dir;
    GltfBuilder b;
    const std::vector<float> base = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const int pos = b.addPositions(base);
    const std::vector<uint8_t> sparseIdx = {2};
    const std::vector<float> sparseVal = {0, 5, 0};
    const int idxView = b.addView(sparseIdx.data(), sparseIdx.size());
    const int valView = b.addView(sparseVal.data(), sparseVal.size() * sizeof(float));
    b.doc["accessors"][pos]["sparse"] = {{"count", 1},
                                         {"indices", {{"bufferView", idxView}, {"componentType", test::kUnsignedByte}}},
                                         {"values", {{"bufferView", valView}}}};
    const int node = b.addMeshNode({{"attributes", {{"POSITION", pos}}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "sparse.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    expectVec3Near(scene.bounds_max, {1, 5, 0});
}

TEST(GltfLoader, MorphTargetsApplyAtTheirDefaultWeights) {
    // Blender exports shape keys as morph targets with their current values as the mesh's
    // weights; viewers show the mesh at those weights (a node's own weights win).
    TempDir dir;
    GltfBuilder b;
    const json base = unitTrianglePrimitive(b);
    const int lift = b.addPositions({0, 0, 1, 0, 0, 1, 0, 0, 1});     // +Z for every vertex
    const int shift = b.addPositions({2, 0, 0, 2, 0, 0, 2, 0, 0});    // +X for every vertex
    const int tilt = b.addPositions({0, 1, -1, 0, 1, -1, 0, 1, -1});  // normal displacement
    json prim = base;
    prim["targets"] = json::array({{{"POSITION", lift}, {"NORMAL", tilt}}, {{"POSITION", shift}}});
    const int mesh = b.addMesh(json::array({prim}));
    b.doc["meshes"][mesh]["weights"] = {0.5, 0.0};
    const int at_mesh_weights = b.addNode({{"mesh", mesh}});
    const int at_node_weights = b.addNode({{"mesh", mesh}, {"weights", {0.0, 1.0}}, {"translation", {0, 0, 10}}});
    b.setScene({at_mesh_weights, at_node_weights});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "morph.gltf"));
    ASSERT_EQ(scene.triangles.size(), 2u);
    // The mesh's weights: half the lift, and the normal tilted by half its displacement.
    const glm::uvec3 first = scene.triangles[0];
    expectVec3Near(scene.positions[first.x], {0, 0, 0.5f});
    expectVec3Near(scene.positions[first.y], {1, 0, 0.5f});
    expectVec3Near(scene.normals[first.x], glm::normalize(glm::vec3(0, 0.5f, 0.5f)));
    // The node's weights: the whole shift, no lift.
    const glm::uvec3 second = scene.triangles[1];
    expectVec3Near(scene.positions[second.x], {2, 0, 10});
    expectVec3Near(scene.positions[second.y], {3, 0, 10});
    expectVec3Near(scene.normals[second.x], {0, 0, 1});
}

TEST(GltfLoaderErrors, MorphTargetOfAnotherLengthIsRefused) {
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    prim["targets"] = json::array({{{"POSITION", b.addPositions({0, 0, 1, 0, 0, 1})}}});
    const int mesh = b.addMesh(json::array({prim}));
    b.doc["meshes"][mesh]["weights"] = {1.0};
    b.setScene({b.addNode({{"mesh", mesh}})});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "short_target.gltf")); });
    EXPECT_NE(msg.find("morph target 0 POSITION has 2 elements but POSITION has 3"), std::string::npos) << msg;
}

/// A triangle skinned to two joints: vertices 0 and 1 follow joint 0, vertex 2 joint 1 (with
/// weight `w2`). The joints' nodes are returned through `joint0` and `joint1`; the mesh's own
/// node is far away, which skinning ignores.
int addSkinnedTriangle(GltfBuilder& b, int& joint0, int& joint1, float w2 = 1.0f, int inverse_bind = -1) {
    json prim = unitTrianglePrimitive(b);
    const std::vector<uint8_t> joints = {0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0};
    prim["attributes"]["JOINTS_0"] = b.addData(joints, test::kUnsignedByte, "VEC4");
    prim["attributes"]["WEIGHTS_0"] = b.addData(std::vector<float>{1, 0, 0, 0, 1, 0, 0, 0, w2, 0, 0, 0}, test::kFloat,
                                                "VEC4");
    const int mesh = b.addMesh(json::array({prim}));
    joint0 = b.addNode({{"name", "root"}});
    joint1 = b.addNode({{"name", "tip"}, {"translation", {0, 0, 5}}});
    b.doc["nodes"][joint0]["children"] = {joint1};
    json skin = {{"joints", {joint0, joint1}}};
    if (inverse_bind >= 0) skin["inverseBindMatrices"] = inverse_bind;
    b.doc["skins"] = json::array({skin});
    return b.addNode({{"mesh", mesh}, {"skin", 0}, {"translation", {100, 0, 0}}});
}

TEST(GltfLoader, SkinnedMeshIsPosedByItsJoints) {
    // The tip joint sits 5 units up with no inverse bind matrices: its vertex moves with it, and
    // the mesh node's own transform is not used (glTF 2.0, "Skins").
    TempDir dir;
    GltfBuilder b;
    int root = 0, tip = 0;
    const int skinned = addSkinnedTriangle(b, root, tip);
    b.setScene({skinned, root});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "skin.gltf"));
    ASSERT_EQ(scene.triangles.size(), 1u);
    const glm::uvec3 t = scene.triangles[0];
    expectVec3Near(scene.positions[t.x], {0, 0, 0});
    expectVec3Near(scene.positions[t.y], {1, 0, 0});
    expectVec3Near(scene.positions[t.z], {0, 1, 5});
    // Weights that do not sum to 1 are normalised.
    GltfBuilder heavy;
    const int heavy_skinned = addSkinnedTriangle(heavy, root, tip, 2.0f);
    heavy.setScene({heavy_skinned, root});
    const Scene normalised = loadGltf(heavy.writeEmbedded(dir, "heavy.gltf"));
    expectVec3Near(normalised.positions[normalised.triangles[0].z], {0, 1, 5});
    // A vertex without any weight stays where its node puts it, with a warning.
    GltfBuilder loose;
    const int loose_skinned = addSkinnedTriangle(loose, root, tip, 0.0f);
    loose.setScene({loose_skinned, root});
    const Scene unweighted = loadGltf(loose.writeEmbedded(dir, "loose.gltf"));
    expectVec3Near(unweighted.positions[unweighted.triangles[0].z], {100, 1, 0});
    EXPECT_TRUE(
        std::any_of(unweighted.stats.warnings.begin(), unweighted.stats.warnings.end(), [](const std::string& w) {
            return w.find("1 skinned vertices have no joint weight") != std::string::npos;
        }));
}

TEST(GltfLoader, SkinAtItsBindPoseLeavesTheMeshWhereItIs) {
    // Inverse bind matrices that undo the joints' transforms: the rest pose is the bind pose.
    TempDir dir;
    GltfBuilder b;
    const std::vector<float> inverse = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0,  1,   // root
                                        1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, -5, 1};  // tip: -5 in z
    const int ibm = b.addData(inverse, test::kFloat, "MAT4");
    int root = 0, tip = 0;
    const int skinned = addSkinnedTriangle(b, root, tip, 1.0f, ibm);
    b.setScene({skinned, root});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "bind.gltf"));
    const glm::uvec3 t = scene.triangles[0];
    expectVec3Near(scene.positions[t.z], {0, 1, 0});
    expectVec3Near(scene.normals[t.z], {0, 0, 1});
}

TEST(GltfLoaderErrors, SkinJointIndexOutOfRangeIsRefused) {
    TempDir dir;
    GltfBuilder b;
    int root = 0, tip = 0;
    const int skinned = addSkinnedTriangle(b, root, tip);
    b.doc["skins"][0]["joints"] = {root};  // vertex 2 names joint 1 of a one-joint skin
    b.setScene({skinned, root});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "bad_joint.gltf")); });
    EXPECT_NE(msg.find("vertex 2 has joint 1"), std::string::npos) << msg;
}

TEST(GltfLoader, NanNormalReplacedByGeometricNormalWithWarning) {
    TempDir dir;
    GltfBuilder b;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int nrm = b.addPositions({0, 0, 1, nan, nan, nan, 0, 0, 0});
    const int node = b.addMeshNode({{"attributes", {{"POSITION", pos}, {"NORMAL", nrm}}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "nan_normal.gltf"));
    ASSERT_EQ(scene.normals.size(), 3u);
    for (const glm::vec3& n : scene.normals) expectVec3Near(n, {0, 0, 1});
    // (The mesh has no material: that is warned about too.)
    EXPECT_TRUE(std::any_of(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                            [](const std::string& w) { return w.find("2 NaN") != std::string::npos; }));
}

TEST(GltfLoader, GlbMatchesGltf) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int node = b.addMeshNode(prim, {{"translation", {1, 2, 3}}});
    b.setScene({node});
    const Scene a = loadGltf(b.writeEmbedded(dir, "scene.gltf"));
    const Scene g = loadGltf(b.writeGlb(dir, "scene.glb"));
    ASSERT_EQ(g.triangles.size(), 1u);
    ASSERT_EQ(a.positions.size(), g.positions.size());
    for (size_t i = 0; i < a.positions.size(); ++i) expectVec3Near(g.positions[i], a.positions[i]);
    expectVec3Near(g.bounds_min, {1, 2, 3});
}

TEST(GltfLoader, DefaultSceneChosenAndAllRootsWithoutScenes) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int n0 = b.addMeshNode(prim, {{"translation", {100, 0, 0}}});
    const int n1 = b.addMeshNode(prim, {{"translation", {-100, 0, 0}}});
    b.doc["scenes"] = json::array({{{"nodes", {n0}}}, {{"nodes", {n1}}}});
    b.doc["scene"] = 1;
    const Scene chosen = loadGltf(b.writeEmbedded(dir, "two_scenes.gltf"));
    ASSERT_EQ(chosen.triangles.size(), 1u);
    EXPECT_NEAR(chosen.bounds_min.x, -100.0f, kEps);

    b.doc.erase("scenes");
    b.doc.erase("scene");
    const Scene all = loadGltf(b.writeEmbedded(dir, "no_scenes.gltf"));
    EXPECT_EQ(all.triangles.size(), 2u);
}

// A loaded scene without meshes loaded as "0 triangles" without a word (render drew the sky, bake
// said "no triangles"), though the file's meshes sat in another scene; a "scene" index the file
// lacks fell back to scene 0 silently. Both are warned, naming the scenes.
TEST(GltfLoader, ASceneWithoutTheFilesMeshesAndAMissingDefaultSceneAreSaid) {
    TempDir dir;
    GltfBuilder b;
    const int mesh_node = b.addMeshNode(unitTrianglePrimitive(b));
    const int empty_node = b.addNode({{"name", "Empty"}});
    b.doc["scenes"] = json::array({{{"nodes", {empty_node}}}, {{"name", "Main"}, {"nodes", {mesh_node}}}});
    b.doc["scene"] = 0;
    const Scene first = loadGltf(b.writeEmbedded(dir, "empty_first.gltf"));
    EXPECT_EQ(first.triangles.size(), 0u);
    EXPECT_EQ(warningsWith(first, {"scene 0, the one loaded, places none of the file's 1 mesh (it lists 1 root node, "
                                   "none with a mesh); scene 1 'Main' places them: make it the file's \"scene\""}),
              1u)
        << ::testing::PrintToString(first.stats.warnings);

    b.doc["scenes"] = json::array({{{"nodes", json::array()}}});  // the mesh's node in no scene
    const Scene orphan = loadGltf(b.writeEmbedded(dir, "orphan.gltf"));
    EXPECT_EQ(warningsWith(orphan, {"scene 0, the one loaded, places none of the file's 1 mesh (it lists no root "
                                    "nodes); they are on nodes no scene lists"}),
              1u)
        << ::testing::PrintToString(orphan.stats.warnings);

    b.doc["scenes"] = json::array({{{"nodes", {mesh_node}}}});
    b.doc["scene"] = 5;
    const Scene fallback = loadGltf(b.writeEmbedded(dir, "scene_5.gltf"));
    EXPECT_EQ(fallback.triangles.size(), 1u);
    EXPECT_EQ(warningsWith(fallback, {"the file's \"scene\" is 5, but it has 1 scene: scene 0 is loaded"}), 1u)
        << ::testing::PrintToString(fallback.stats.warnings);
    EXPECT_EQ(warningsWith(fallback, {"places none"}), 0u);
}

TEST(GltfLoader, ANodeListedTwiceIsLoadedOnceWithAWarning) {
    // glTF wants each of a scene's root nodes, and each of a node's children, listed once. A root
    // listed twice was loaded twice: its light shone twice as brightly and its meshes lay on
    // themselves, without a word.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array({{{"type", "point"}, {"intensity", 683.0}}});
    const json prim = unitTrianglePrimitive(b);
    const int lamp = b.addMeshNode(prim, {{"name", "Lamp"}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    const int leg = b.addMeshNode(prim, {{"name", "Leg"}, {"translation", {0, 0, 5}}});
    const int table = b.addNode({{"name", "Table"}, {"children", {leg, leg}}});
    b.setScene({lamp, table, lamp, lamp});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "twice.gltf"));
    EXPECT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.triangles.size(), 2u);
    const auto warnings = [&](const char* a, const char* b) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(), [&](const std::string& w) {
            return w.find(a) != std::string::npos && w.find(b) != std::string::npos;
        });
    };
    EXPECT_EQ(warnings("node 0 'Lamp'", "3 times"), 1) << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warnings("node 1 'Leg'", "'Table'"), 1) << testing::PrintToString(scene.stats.warnings);
}

TEST(GltfLoader, ANodeWithTwoParentsIsLoadedUnderEachWithAWarning) {
    // glTF allows a node one parent. A node that two nodes list as their child, or a root that a
    // node also lists, sits at two places: it is loaded at each, as before, and now said.
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int gear = b.addMeshNode(prim, {{"name", "Gear"}});
    const int left = b.addNode({{"name", "Left"}, {"children", {gear}}});
    const int right = b.addNode({{"name", "Right"}, {"translation", {10, 0, 0}}, {"children", {gear}}});
    const int lone = b.addMeshNode(prim, {{"name", "Lone"}, {"translation", {0, 10, 0}}});
    const int holder = b.addNode({{"translation", {0, 0, 10}}, {"children", {lone}}});
    b.setScene({left, right, lone, holder});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "parents.gltf"));
    EXPECT_EQ(scene.triangles.size(), 4u);
    EXPECT_NEAR(scene.bounds_max.x, 11.0f, kEps);
    EXPECT_NEAR(scene.bounds_max.z, 10.0f, kEps);
    const auto warned = [&](std::initializer_list<const char*> parts) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(), [&](const std::string& w) {
            return std::all_of(parts.begin(), parts.end(),
                               [&](const char* p) { return w.find(p) != std::string::npos; });
        });
    };
    EXPECT_EQ(warned({"node 0 'Gear'", "node 1 'Left'", "node 2 'Right'"}), 1)
        << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warned({"node 3 'Lone'", "root", "node 4"}), 1) << testing::PrintToString(scene.stats.warnings);
}

// ------------------------------------------------------------------------------------ errors

TEST(GltfLoaderErrors, IndexOutOfRangeNamesFileMeshAndIndex) {
    TempDir dir;
    GltfBuilder b;
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const std::vector<uint16_t> idx = {0, 1, 7};
    b.addMesh(json::array({{{"attributes", {{"POSITION", pos}}}, {"indices", b.addData(idx, test::kUnsignedShort, "SCALAR")}}}),
              "Floor");
    b.addNode({{"mesh", 0}});
    b.setScene({0});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "bad_index.gltf")); });
    EXPECT_NE(msg.find("bad_index.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'Floor'"), std::string::npos) << msg;
    EXPECT_NE(msg.find("index 7"), std::string::npos) << msg;
    EXPECT_NE(msg.find("3 vertices"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, AnAccessorOfTheWrongTypeIsNamedInGltfsWords) {
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    b.doc["accessors"][prim["attributes"]["POSITION"].get<int>()]["type"] = "VEC2";
    b.setScene({b.addMeshNode(prim)});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "vec2.gltf")); });
    EXPECT_NE(msg.find("POSITION (accessor 0): has type VEC2, expected VEC3"), std::string::npos) << msg;
}

// tinygltf says "'type' property is missing." of any object; the message names the object.
TEST(GltfLoaderErrors, AMissingRequiredPropertyNamesItsObject) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b))});
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"type", "point"}}, {{"name", "Sun"}, {"intensity", 2.0}}});
    std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "no_type.gltf")); });
    EXPECT_NE(msg.find("light 1 'Sun' (KHR_lights_punctual) lacks \"type\", which glTF requires of it"),
              std::string::npos)
        << msg;

    b.doc.erase("extensions");
    b.doc.erase("extensionsUsed");
    b.doc["accessors"][1].erase("count");
    msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "no_count.gltf")); });
    EXPECT_NE(msg.find("accessor 1 lacks \"count\""), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, MissingBufferFile) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    const std::string path = b.writeExternal(dir, "no_bin.gltf", "missing.bin", /*writeBin=*/false);
    // A file that is not there, not a malformed scene (the command exits 2, not 3), said in the
    // words a missing image's warning uses (tinygltf's own: "File not found : missing.bin").
    test::expectMissingBuffer(path, "missing.bin");
}

// A 0-byte buffer file (an interrupted copy; sample-model mirrors without their large files) said
// "File read error : PATH : File is empty : PATH".
TEST(GltfLoaderErrors, AnEmptyBinFileIsNamed) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b))});
    const std::string path = b.writeExternal(dir, "empty_bin.gltf", "empty.bin");
    test::writeFile(dir.file("empty.bin"), b.bin.data(), 0);
    EXPECT_EQ(loadErrorOf([&] { loadGltf(path); }),
              path +
                  ": buffer file 'empty.bin' is empty (0 bytes): the scene's geometry is not in it (an "
                  "interrupted copy or download?)");
}

TEST(GltfLoaderErrors, ShortBinFile) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    const std::string path = b.writeExternal(dir, "short_bin.gltf", "short.bin");
    test::writeFile(dir.file("short.bin"), b.bin.data(), b.bin.size() / 2);  // truncated
    const std::string msg = loadErrorOf([&] { loadGltf(path); });
    EXPECT_NE(msg.find("short_bin.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("short.bin"), std::string::npos) << msg;
}

// tinygltf quotes a data: URI it cannot decode whole (kilobytes of base64) and says nothing of
// why; the message names the buffer, shortens the URI and gives the sizes that disagree.
TEST(GltfLoaderErrors, DataUriOfAnotherLengthIsNamedShortly) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    const std::vector<uint8_t> padding(1500, 7);
    b.addView(padding.data(), padding.size());
    const std::string path = b.writeEmbedded(dir, "long.gltf");
    json doc = json::parse(std::ifstream(path));
    const std::string uri = doc["buffers"][0]["uri"];
    const size_t bytes = doc["buffers"][0]["byteLength"];
    doc["buffers"][0]["byteLength"] = bytes + 16;
    test::writeFile(path, doc.dump());
    const std::string msg = loadErrorOf([&] { loadGltf(path); });
    EXPECT_LT(msg.size(), 400u) << msg;
    EXPECT_EQ(msg.find(uri), std::string::npos) << msg;
    EXPECT_NE(msg.find("buffer 0: data: URI " + uri.substr(0, 60) + "..."), std::string::npos) << msg;
    EXPECT_NE(msg.find("holds " + std::to_string(bytes) + " bytes, but the buffer's byteLength is " +
                       std::to_string(bytes + 16)),
              std::string::npos)
        << msg;

    // Data that is not base64: said so, just as shortly.
    doc["buffers"][0]["byteLength"] = bytes;
    doc["buffers"][0]["uri"] = "data:application/octet-stream;base64,%%" + uri.substr(uri.find(',') + 1);
    test::writeFile(path, doc.dump());
    const std::string garbled = loadErrorOf([&] { loadGltf(path); });
    EXPECT_LT(garbled.size(), 400u) << garbled;
    EXPECT_NE(garbled.find("is not base64 data of a type tinygltf decodes"), std::string::npos) << garbled;

    // A media type tinygltf does not know is read as a file name: the message quotes it short too.
    doc["buffers"][0]["uri"] = "data:application/x-unknown;base64," + uri.substr(uri.find(',') + 1);
    test::writeFile(path, doc.dump());
    const std::string unknown = loadErrorOf([&] { loadGltf(path); });
    EXPECT_LT(unknown.size(), 400u) << unknown;
    EXPECT_NE(unknown.find("data:application/x-unknown;base64,"), std::string::npos) << unknown;
}

TEST(GltfLoaderErrors, MissingSceneFile) {
    TempDir dir;
    const std::string msg = loadErrorOf([&] { loadGltf(dir.file("nothing_here.gltf")); });
    EXPECT_NE(msg.find("nothing_here.gltf"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, BufferViewPastEndOfBuffer) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    b.doc["bufferViews"][1]["byteLength"] = 4096;  // the buffer holds 72 bytes
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "short.gltf")); });
    EXPECT_NE(msg.find("short.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("short buffer"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, AccessorPastEndOfBufferView) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    b.doc["accessors"][0]["count"] = 4;  // the view holds 3 vertices
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "overrun.gltf")); });
    EXPECT_NE(msg.find("overrun.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("out of buffer range"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, NanPosition) {
    TempDir dir;
    GltfBuilder b;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const int pos = b.addPositions({0, 0, 0, 1, nan, 0, 0, 1, 0});
    const int node = b.addMeshNode({{"attributes", {{"POSITION", pos}}}});
    b.setScene({node});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "nan.gltf")); });
    EXPECT_NE(msg.find("nan.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("vertex 1"), std::string::npos) << msg;
    EXPECT_NE(msg.find("NaN"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, UnknownRequiredExtension) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    b.doc["extensionsUsed"] = {"KHR_texture_basisu"};
    b.doc["extensionsRequired"] = {"KHR_texture_basisu"};
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "basisu.gltf")); });
    EXPECT_NE(msg.find("basisu.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("KHR_texture_basisu"), std::string::npos) << msg;
}

// Other 3D formats given by mistake are named from their first bytes, with how to convert them:
// the JSON parser's error said nothing of the kind (a binary STL's: "JSON nested more than 256
// levels deep").
TEST(GltfLoaderErrors, OtherModelFormatsAreNamedWithHowToConvertThem) {
    TempDir dir;
    // A binary STL whose header starts with "solid", as some exporters write it, and whose
    // triangles' bytes read as '[' to a JSON scanner.
    std::string binary_stl = "solid written by a CAD tool";
    binary_stl.resize(80, ' ');
    const uint32_t triangles = 300;
    binary_stl.append(reinterpret_cast<const char*>(&triangles), 4);
    binary_stl.append(50 * triangles, '[');
    const std::vector<std::array<std::string, 3>> files = {
        {"room.obj", "# Blender v3.4 OBJ File\nmtllib room.mtl\no Room\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
         "an OBJ file"},
        {"bare.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "an OBJ file"},
        {"part.stl", "solid part\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n", "an STL file"},
        {"part_bin.stl", binary_stl, "an STL file"},
        {"part_bin.dat", binary_stl, "an STL file"},  // by its size: 84 + 50 bytes a triangle
        {"scan.ply", "ply\nformat ascii 1.0\nelement vertex 3\n", "a PLY file"},
        {"room.dae",
         "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<COLLADA "
         "xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">\n",
         "a Collada file"},
        {"rig.fbx", std::string("Kaydara FBX Binary  \0\x1a\0", 23) + std::string(64, '['), "an FBX file"},
        {"rig_ascii.fbx", "; FBX 7.4.0 project file\n; Created by Blender FBX Exporter\n", "an FBX file"},
    };
    for (const auto& [name, bytes, kind] : files) {
        test::writeFile(dir.file(name), bytes);
        const std::string msg = loadErrorOf([&] { loadGltf(dir.file(name)); });
        EXPECT_NE(msg.find(dir.file(name) + ": " + kind + ", not glTF 2.0: convert it, e.g. `assimp export " +
                           dir.file(name)),
                  std::string::npos)
            << msg;
        EXPECT_NE(msg.find(" -f glb2` or Blender's glTF exporter"), std::string::npos) << msg;
    }
    // The bytes decide, not the name: glTF named .obj loads, and text that is none of these gets
    // the parser's error.
    GltfBuilder b;
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b))});
    EXPECT_EQ(loadGltf(b.writeEmbedded(dir, "misnamed.obj")).triangles.size(), 1u);
    EXPECT_EQ(loadGltf(b.writeGlb(dir, "misnamed.stl")).triangles.size(), 1u);
    test::writeFile(dir.file("notes.gltf"), "vertex shader notes\n");
    EXPECT_NE(loadErrorOf([&] { loadGltf(dir.file("notes.gltf")); }).find("glTF parse failed"), std::string::npos);
}

// glTF 2.0 requires asset.version; a 2.x loader reads 2.y files unless minVersion asks for more.
TEST(GltfLoaderErrors, VersionsOtherThanGltf2AreRefusedNamingTheVersion) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    const auto errorFor = [&](const json& asset, const std::string& name) {
        b.doc["asset"] = asset;
        return loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, name)); });
    };
    std::string msg = errorFor({{"version", "1.0"}}, "v1.gltf");
    EXPECT_NE(msg.find("v1.gltf: glTF 1.0 files are not supported"), std::string::npos) << msg;
    EXPECT_NE(msg.find("re-export"), std::string::npos) << msg;
    msg = errorFor({{"version", "3.0"}}, "v3.gltf");
    EXPECT_NE(msg.find("glTF 3.0 files are not supported (asset.version '3.0')"), std::string::npos) << msg;
    msg = errorFor({{"version", "2.0"}, {"minVersion", "2.1"}}, "min21.gltf");
    EXPECT_NE(msg.find("needs glTF 2.1 or later"), std::string::npos) << msg;
    msg = errorFor({{"version", "two"}}, "word.gltf");
    EXPECT_NE(msg.find("asset.version 'two' is not a glTF version"), std::string::npos) << msg;
    msg = errorFor({{"generator", "by hand"}}, "none.gltf");
    EXPECT_NE(msg.find("asset.version is missing"), std::string::npos) << msg;

    // A later 2.x file without minVersion is readable by a 2.0 loader; so is minVersion 2.0.
    b.doc["asset"] = {{"version", "2.1"}, {"minVersion", "2.0"}};
    EXPECT_EQ(loadGltf(b.writeEmbedded(dir, "v21.gltf")).triangles.size(), 1u);
}

// A glTF 1.0 file as 1.0 exporters wrote it (objects by id, a scene named by a string): tinygltf
// cannot read it, and the error says why instead of what tinygltf tripped over.
TEST(GltfLoaderErrors, Gltf1FileIsRefusedAsGltf1) {
    TempDir dir;
    const json doc = {{"asset", {{"version", "1.0"}}},
                      {"scene", "defaultScene"},
                      {"scenes", {{"defaultScene", {{"nodes", {"node_1"}}}}}},
                      {"nodes", {{"node_1", {{"meshes", {"mesh_1"}}}}}},
                      {"meshes", {{"mesh_1", {{"primitives", json::array()}}}}}};
    const std::string path = dir.file("old.gltf");
    test::writeFile(path, doc.dump());
    const std::string msg = loadErrorOf([&] { loadGltf(path); });
    EXPECT_NE(msg.find("glTF 1.0 files are not supported"), std::string::npos) << msg;

    // Binary glTF 1.0 (KHR_binary_glTF): a GLB header of version 1.
    GltfBuilder b;
    b.setScene({});
    const std::string glb = b.writeGlb(dir, "old.glb");
    std::string bytes;
    {
        std::ifstream in(glb, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    bytes[4] = 1;
    test::writeFile(glb, bytes);
    const std::string glb_msg = loadErrorOf([&] { loadGltf(glb); });
    EXPECT_NE(glb_msg.find("binary glTF version 1"), std::string::npos) << glb_msg;
}

// A GLB cut short (an interrupted download or copy) got tinygltf's "Invalid glTF binary." alone;
// the message says what the header promised and what the file holds.
TEST(GltfLoaderErrors, AGlbCutShortSaysSo) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b))});
    const std::string glb = b.writeGlb(dir, "whole.glb");
    std::string bytes;
    {
        std::ifstream in(glb, std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    ASSERT_GT(bytes.size(), 100u);
    const std::string whole = std::to_string(bytes.size());
    EXPECT_NO_THROW(loadGltf(glb));

    const std::string cut = dir.file("cut.glb");
    test::writeFile(cut, bytes.substr(0, bytes.size() - 40));
    EXPECT_EQ(loadErrorOf([&] { loadGltf(cut); }),
              cut + ": the GLB header says the file is " + whole + " bytes, but it has " +
                  std::to_string(bytes.size() - 40) +
                  ": the file is cut short (an interrupted download or copy?) or its header is wrong");

    const std::string header_only = dir.file("header.glb");
    test::writeFile(header_only, bytes.substr(0, 12));
    EXPECT_EQ(loadErrorOf([&] { loadGltf(header_only); }),
              header_only + ": a GLB file of 12 bytes, shorter than its headers (20 bytes): the file is cut short");

    std::string long_json = bytes;  // the JSON chunk claims more than the file's own length
    const uint32_t claimed = uint32_t(bytes.size());
    std::memcpy(long_json.data() + 12, &claimed, 4);
    const std::string long_path = dir.file("long_json.glb");
    test::writeFile(long_path, long_json);
    const std::string msg = loadErrorOf([&] { loadGltf(long_path); });
    EXPECT_NE(msg.find("the GLB's JSON chunk says it is " + whole + " bytes, but only " +
                       std::to_string(bytes.size() - 20) + " follow it"),
              std::string::npos)
        << msg;
}

TEST(GltfLoaderErrors, UsedButUnsupportedExtensionOnlyWarns) {
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial({{"extensions", {{"KHR_materials_sheen", {{"sheenColorFactor", {1, 1, 1}}}}}}});
    const int node = b.addMeshNode(prim);
    b.setScene({node});
    b.doc["extensionsUsed"] = {"KHR_materials_sheen"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "sheen.gltf"));
    EXPECT_EQ(scene.triangles.size(), 1u);
    bool warned = false;
    for (const std::string& w : scene.stats.warnings) warned |= w.find("KHR_materials_sheen") != std::string::npos;
    EXPECT_TRUE(warned);
}

// ------------------------------------------------------------------------------ GPU instancing

std::vector<std::array<glm::vec3, 3>> trianglesOf(const Scene& scene) {
    std::vector<std::array<glm::vec3, 3>> out;
    for (const glm::uvec3& t : scene.triangles)
        out.push_back({scene.positions[t.x], scene.positions[t.y], scene.positions[t.z]});
    return out;
}

TEST(GpuInstancing, EachInstanceIsTheMeshByItsTrsAfterTheNode) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const float h = std::sqrt(0.5f);  // 90 degrees about +Z: (x, y, z, w) = (0, 0, h, h)
    const json attributes = {
        {"TRANSLATION", b.addData(std::vector<float>{0, 0, 0, 5, 0, 0, 0, 5, 0}, test::kFloat, "VEC3")},
        {"ROTATION", b.addData(std::vector<float>{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, h, h}, test::kFloat, "VEC4")},
        {"SCALE", b.addData(std::vector<float>{1, 1, 1, 1, 1, 1, 2, 2, 2}, test::kFloat, "VEC3")}};
    const int node = b.addMeshNode(prim, {{"translation", {0, 0, 10}},
                                          {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", attributes}}}}}});
    b.setScene({node});
    b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
    b.doc["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "instanced.gltf"));
    const auto triangles = trianglesOf(scene);
    ASSERT_EQ(triangles.size(), 3u);  // the instances only: the node itself draws nothing more
    const std::array<std::array<glm::vec3, 3>, 3> expected = {{
        {glm::vec3(0, 0, 10), glm::vec3(1, 0, 10), glm::vec3(0, 1, 10)},
        {glm::vec3(5, 0, 10), glm::vec3(6, 0, 10), glm::vec3(5, 1, 10)},
        {glm::vec3(0, 5, 10), glm::vec3(0, 7, 10), glm::vec3(-2, 5, 10)},  // scaled by 2, then turned
    }};
    for (size_t i = 0; i < 3; ++i)
        for (size_t v = 0; v < 3; ++v) expectVec3Near(triangles[i][v], expected[i][v]);
    for (const std::string& w : scene.stats.warnings)
        EXPECT_EQ(w.find("EXT_mesh_gpu_instancing"), std::string::npos) << w;
    EXPECT_EQ(scene.bounds_min.x, -2.0f);
}

TEST(GpuInstancing, NormalizedShortRotationsAndTranslationOnly) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    const int16_t h = 23170;  // round(sqrt(0.5) * 32767)
    const json rotated = {{"ROTATION", b.addData(std::vector<int16_t>{0, 0, h, h}, test::kShort, "VEC4", true)}};
    const json moved = {{"TRANSLATION", b.addData(std::vector<float>{0, 0, 1, 0, 0, 2}, test::kFloat, "VEC3")}};
    const int a = b.addMeshNode(prim, {{"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", rotated}}}}}});
    const int c = b.addNode({{"mesh", 0}, {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", moved}}}}}});
    b.setScene({a, c});
    b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
    const auto triangles = trianglesOf(loadGltf(b.writeEmbedded(dir, "short.gltf")));
    ASSERT_EQ(triangles.size(), 3u);
    expectVec3Near(triangles[0][1], {0, 1, 0}, 1e-4f);  // (1, 0, 0) turned 90 degrees about +Z
    expectVec3Near(triangles[0][2], {-1, 0, 0}, 1e-4f);
    expectVec3Near(triangles[1][0], {0, 0, 1});
    expectVec3Near(triangles[2][0], {0, 0, 2});
}

TEST(GpuInstancing, MalformedInstancesAreRefusedNamingTheNode) {
    TempDir dir;
    const auto errorFor = [&](const std::function<json(GltfBuilder&)>& extension) {
        GltfBuilder b;
        const json prim = unitTrianglePrimitive(b);
        const int node = b.addMeshNode(prim, {{"extensions", {{"EXT_mesh_gpu_instancing", extension(b)}}}});
        b.setScene({node});
        b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
        return loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "bad.gltf")); });
    };
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const std::string mismatch = errorFor([](GltfBuilder& b) {
        return json{{"attributes",
                     {{"TRANSLATION", b.addData(std::vector<float>{0, 0, 0, 1, 0, 0}, test::kFloat, "VEC3")},
                      {"SCALE", b.addData(std::vector<float>{1, 1, 1}, test::kFloat, "VEC3")}}}};
    });
    EXPECT_NE(mismatch.find("node 0 EXT_mesh_gpu_instancing"), std::string::npos) << mismatch;
    EXPECT_NE(mismatch.find("SCALE has 1 elements"), std::string::npos) << mismatch;
    const std::string not_finite = errorFor([&](GltfBuilder& b) {
        return json{
            {"attributes", {{"TRANSLATION", b.addData(std::vector<float>{0, 0, 0, nan, 0, 0}, test::kFloat, "VEC3")}}}};
    });
    EXPECT_NE(not_finite.find("instance 1 has a NaN or infinite TRANSLATION"), std::string::npos) << not_finite;
    const std::string zero_rotation = errorFor([](GltfBuilder& b) {
        return json{{"attributes", {{"ROTATION", b.addData(std::vector<float>{0, 0, 0, 0}, test::kFloat, "VEC4")}}}};
    });
    EXPECT_NE(zero_rotation.find("instance 0 has a zero"), std::string::npos) << zero_rotation;
    const std::string empty = errorFor([](GltfBuilder&) { return json{{"attributes", json::object()}}; });
    EXPECT_NE(empty.find("none of TRANSLATION, ROTATION and SCALE"), std::string::npos) << empty;
    const std::string no_attributes = errorFor([](GltfBuilder&) { return json::object(); });
    EXPECT_NE(no_attributes.find("none of TRANSLATION, ROTATION and SCALE"), std::string::npos) << no_attributes;
}

TEST(GpuInstancing, InstancesThatWouldMakeBillionsOfTrianglesAreRefusedBeforeReading) {
    // 2048 instances (24 KB of translations) of a mesh declaring 65,536 triangles: 2^27 in all.
    TempDir dir;
    GltfBuilder b;
    const int positions = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const uint32_t few[3] = {0, 1, 2};  // the count is refused before anything is read
    const int indices = b.addAccessor(b.addView(few, sizeof few), test::kUnsignedInt, 3 * 65536, "SCALAR");
    const json attributes = {{"TRANSLATION", b.addData(std::vector<float>(3 * 2048, 0.0f), test::kFloat, "VEC3")}};
    const int node = b.addMeshNode({{"attributes", {{"POSITION", positions}}}, {"indices", indices}},
                                   {{"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", attributes}}}}}});
    b.setScene({node});
    b.doc["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "many.gltf")); });
    EXPECT_NE(msg.find("2048 instances of a mesh of up to 65536 triangles"), std::string::npos) << msg;
}

TEST(GltfLoaderErrors, KnownRequiredExtensionAccepted) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    b.doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    b.doc["extensionsRequired"] = {"KHR_materials_emissive_strength"};
    EXPECT_NO_THROW(loadGltf(b.writeEmbedded(dir, "known.gltf")));
}

// ------------------------------------------------------------------------------------ materials

TEST(GltfLoaderMaterials, BlendersBlackSpecularColourMeansNoSpecular) {
    TempDir dir;
    GltfBuilder b;
    json black = unitTrianglePrimitive(b);
    black["material"] = b.addMaterial({{"name", "Matte"},
                                       {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}},
                                       {"extensions", {{"KHR_materials_specular", {{"specularColorFactor", {0.0, 0.0, 0.0}}}}}}});
    json dim = unitTrianglePrimitive(b);
    dim["material"] = b.addMaterial({{"name", "Dim"},
                                     {"pbrMetallicRoughness", {{"metallicFactor", 0.0}}},
                                     {"extensions", {{"KHR_materials_specular", {{"specularColorFactor", {0.0, 0.1, 0.0}}}}}}});
    b.setScene({b.addMeshNode(black), b.addMeshNode(dim)});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "blender_specular.gltf"));
    EXPECT_FLOAT_EQ(scene.materials[0].specular, 0.0f);  // no layer at all
    EXPECT_FLOAT_EQ(scene.materials[1].specular, 1.0f);  // a colour: as the extension says
    ASSERT_EQ(scene.stats.warnings.size(), 1u);
    EXPECT_NE(scene.stats.warnings[0].find("no specular reflection"), std::string::npos);
}

TEST(GltfLoaderMaterials, MeshWithoutAMaterialIsWarnedAbout) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b))});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "no_material.gltf"));
    ASSERT_EQ(scene.stats.warnings.size(), 1u);
    EXPECT_NE(scene.stats.warnings[0].find("white metal"), std::string::npos);
    EXPECT_FLOAT_EQ(scene.materials.back().metallic, 1.0f);  // glTF's default, kept
}

// A Blender export with Materials = None leaves every mesh without one: the warning counts them all.
TEST(GltfLoaderMaterials, PrimitivesWithoutAMaterialAreCountedInOneWarning) {
    TempDir dir;
    GltfBuilder b;
    const json prim = unitTrianglePrimitive(b);
    json with_material = prim;
    with_material["material"] = b.addMaterial({{"pbrMetallicRoughness", {{"metallicFactor", 0}}}});
    const int walls = b.addNode({{"mesh", b.addMesh(json::array({with_material, prim, prim}), "walls")}});
    const int lamp = b.addMesh(json::array({prim}), "lamp");  // placed twice: its primitive counts once
    b.setScene({walls, b.addNode({{"mesh", lamp}}), b.addNode({{"mesh", lamp}, {"translation", {0, 0, 1}}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "no_materials.gltf"));
    EXPECT_EQ(warningsWith(scene, {"3 primitives in 2 meshes have no material (first: mesh 0 'walls' primitive 1): "
                                   "glTF's default applies, a white metal"}),
              1u)
        << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"no material"}), 1u);
}

TEST(GltfLoaderMaterials, FactorsAndExtensionsParsed) {
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial(
        {{"name", "Lamp"},
         {"pbrMetallicRoughness", {{"baseColorFactor", {0.5, 0.25, 0.125, 1.0}}, {"metallicFactor", 0.0}, {"roughnessFactor", 0.3}}},
         {"emissiveFactor", {1.0, 0.5, 0.0}},
         {"doubleSided", true},
         {"extensions",
          {{"KHR_materials_emissive_strength", {{"emissiveStrength", 40.0}}},
           {"KHR_materials_specular", {{"specularFactor", 0.25}, {"specularColorFactor", {0.5, 0.75, 1.0}}}},
           {"KHR_materials_ior", {{"ior", 1.33}}}}}});
    const int lit = b.addMeshNode(prim);
    const int plain = b.addMeshNode(unitTrianglePrimitive(b));  // no material: default appended
    b.setScene({lit, plain});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "materials.gltf"));

    ASSERT_EQ(scene.materials.size(), 2u);
    const Material& m = scene.materials[0];
    EXPECT_EQ(m.name, "Lamp");
    expectVec3Near(m.base_color, {0.5f, 0.25f, 0.125f});
    EXPECT_FLOAT_EQ(m.metallic, 0.0f);
    EXPECT_FLOAT_EQ(m.roughness, 0.3f);
    expectVec3Near(m.emissive, {1.0f, 0.5f, 0.0f});
    EXPECT_FLOAT_EQ(m.emissive_strength, 40.0f);
    EXPECT_FLOAT_EQ(m.specular, 0.25f);
    expectVec3Near(m.specular_color, {0.5f, 0.75f, 1.0f});
    EXPECT_FLOAT_EQ(m.ior, 1.33f);
    EXPECT_TRUE(m.double_sided);
    EXPECT_TRUE(m.isEmissive());

    const Material& d = scene.materials[1];  // glTF default material
    expectVec3Near(d.base_color, {1, 1, 1});
    EXPECT_FLOAT_EQ(d.metallic, 1.0f);
    EXPECT_FLOAT_EQ(d.roughness, 1.0f);
    EXPECT_FALSE(d.isEmissive());
    ASSERT_EQ(scene.triangle_materials.size(), 2u);
    EXPECT_EQ(scene.triangle_materials[0], 0u);
    EXPECT_EQ(scene.triangle_materials[1], 1u);
}

TEST(GltfLoaderMaterials, FactorsOutsideGltfsRangesAreClampedWithAWarning) {
    // A base colour above 1 reflects more light than reaches the surface: light would grow with
    // every bounce of the bake. Emission above 1 stays (older exporters write bright lights so).
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial(
        {{"name", "Hot"},
         {"pbrMetallicRoughness",
          {{"baseColorFactor", {1.5, -0.2, 0.5, 1.0}}, {"metallicFactor", 1.3}, {"roughnessFactor", -0.1}}},
         {"emissiveFactor", {-1.0, 2.0, 0.0}},
         {"extensions", {{"KHR_materials_specular", {{"specularFactor", 4.0}}}}}});
    const int plain = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({b.addMeshNode(prim), plain});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "ranges.gltf"));
    const Material& m = scene.materials.at(0);
    expectVec3Near(m.base_color, {1.0f, 0.0f, 0.5f});
    EXPECT_FLOAT_EQ(m.metallic, 1.0f);
    EXPECT_FLOAT_EQ(m.roughness, 0.0f);
    expectVec3Near(m.emissive, {0.0f, 2.0f, 0.0f});
    EXPECT_FLOAT_EQ(m.specular, 1.0f);
    size_t warnings = 0;
    for (const std::string& w : scene.stats.warnings) {
        if (w.find("outside glTF's ranges clamped") == std::string::npos) continue;
        ++warnings;
        EXPECT_NE(w.find("'Hot'"), std::string::npos) << w;
        EXPECT_NE(w.find("base colour (1.5, -0.2, 0.5) -> (1, 0, 0.5)"), std::string::npos) << w;
        EXPECT_NE(w.find("emissive (-1, 2, 0) -> (0, 2, 0)"), std::string::npos) << w;
    }
    EXPECT_EQ(warnings, 1u);  // one for the material, none for the default one
}

TEST(GltfLoaderMaterials, MalformedValuesAreSaidAndReplaced) {
    // Values of the wrong type or length, and an alphaCutoff below glTF's minimum, were read
    // silently as defaults (or, for the cutoff, as a MASK that hides nothing).
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial(
        {{"name", "Odd"},
         {"pbrMetallicRoughness", {{"baseColorFactor", {0.2, 0.3}}}},
         {"alphaMode", "MASK"},
         {"alphaCutoff", -1.0},
         {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", "bright"}}}}}});
    const int node = b.addMeshNode(prim);
    b.doc["nodes"][node]["rotation"] = {0.0, 0.0, 0.0, 0.0};
    const int tilted = b.addMeshNode(unitTrianglePrimitive(b));
    b.doc["nodes"][tilted]["rotation"] = {0.0, 0.0, 0.0, 2.0};
    b.setScene({node, tilted});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "malformed.gltf"));
    const Material& m = scene.materials.at(0);
    expectVec3Near(m.base_color, {1.0f, 1.0f, 1.0f});
    EXPECT_FLOAT_EQ(m.alpha_cutoff, 0.0f);
    EXPECT_FLOAT_EQ(m.emissive_strength, 1.0f);
    const auto warned = [&](const std::string& text) {
        for (const std::string& w : scene.stats.warnings)
            if (w.find(text) != std::string::npos) return true;
        return false;
    };
    EXPECT_TRUE(
        warned("tinygltf: Array length of `baseColorFactor` parameter in pbrMetallicRoughness must be 4, "
               "but got 2 (the default is used)"));
    EXPECT_TRUE(warned("'Odd': alphaCutoff -1 is below glTF's minimum 0; 0 used"));
    EXPECT_TRUE(warned("'Odd': emissiveStrength is not a number; 1 used"));
    EXPECT_TRUE(warned("rotation (0, 0, 0, 0) is no unit quaternion; no rotation used"));
    EXPECT_TRUE(warned("rotation of length 2 is no unit quaternion; normalised"));
    // Both triangles stay where an identity rotation puts them (a normalised (0, 0, 0, 2) is one).
    expectVec3Near(scene.bounds_min, {0, 0, 0});
    expectVec3Near(scene.bounds_max, {1, 1, 0});
}

TEST(GltfLoaderMaterials, EmissionBeyondFloat32IsLeftOutNamingFieldAndValue) {
    // glTF's numbers are doubles; emission is traced in float32. An emissiveStrength of 1e39 was
    // loaded as 1 with a warning that it was "clamped" (float32 made it infinity, and the
    // fallback for infinity is 1): 39 orders of magnitude off. A factor of 1e39 became 0 with a
    // warning naming "inf", and a product overflowing float32 (each factor finite) was kept as an
    // infinite emission, which the bake drops as NaN/Inf. 1e37 fits and is kept as it is.
    TempDir dir;
    GltfBuilder b;
    const auto emissive = [&](const std::string& name, json factor, double strength) {
        json prim = unitTrianglePrimitive(b);
        prim["material"] = b.addMaterial(
            {{"name", name},
             {"emissiveFactor", factor},
             {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", strength}}}}}});
        const int material = prim["material"];
        return b.addMeshNode(prim, {{"translation", {2 * material, 0, 0}}});  // side by side
    };
    const int strong = emissive("Strong", {1.0, 1.0, 1.0}, 1e39);
    const int wide = emissive("Wide", {1e39, 0.5, 0.0}, 1.0);
    const int product = emissive("Product", {2.0, 1.0, 0.5}, 3e38);
    const int bright = emissive("Bright", {1.0, 0.5, 0.25}, 1e37);
    b.doc["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    b.setScene({strong, wide, product, bright});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "beyond_float.gltf"));
    ASSERT_EQ(scene.materials.size(), 4u);
    for (size_t i = 0; i < 3; ++i) {
        SCOPED_TRACE(scene.materials[i].name);
        EXPECT_FALSE(scene.materials[i].isEmissive());
        expectVec3Near(scene.materials[i].emissive, {0, 0, 0});
    }
    EXPECT_TRUE(scene.materials[3].isEmissive());
    EXPECT_EQ(scene.materials[3].emissive_strength, 1e37f);
    expectVec3Near(scene.materials[3].emissive, {1.0f, 0.5f, 0.25f});
    const auto said = [&](const std::string& text) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                             [&](const std::string& w) { return w.find(text) != std::string::npos; });
    };
    const std::string beyond =
        " is beyond float32's range (at most 3.40282e+38), so the material's emission is left out";
    EXPECT_EQ(said("material 0 'Strong': emissiveStrength 1e+39" + beyond), 1)
        << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(said("material 1 'Wide': emissiveFactor (1e+39, 0.5, 0)" + beyond), 1);
    EXPECT_EQ(said("material 2 'Product': emissiveFactor (2, 1, 0.5) x emissiveStrength 3e+38 = 6e+38" + beyond), 1);
    EXPECT_EQ(said("'Bright'"), 0);
    EXPECT_EQ(said("clamped"), 0);
    EXPECT_EQ(said("inf"), 0);
}

TEST(GltfLoaderMaterials, SceneWithoutMaterialsGetsDefault) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "empty.gltf"));
    EXPECT_TRUE(scene.empty());
    EXPECT_EQ(scene.materials.size(), 1u);
    expectVec3Near(scene.bounds_min, {0, 0, 0});
}

/// A 2x2 RGBA PNG: row 0 = (0, 128, 255, 255), (255, 0, 0, 128); row 1 = grey 64, white.
std::vector<uint8_t> tinyPng() {
    return test::png(2, 2, {0, 128, 255, 255, 255, 0, 0, 128, 64, 64, 64, 255, 255, 255, 255, 255});
}

/// The unit triangle with TEXCOORD_0 = its (x, y), and tinyPng as image 0 and texture 0.
json tinyPngTexturedTriangle(GltfBuilder& b) {
    b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(tinyPng())}}});
    b.doc["textures"] = json::array({{{"source", 0}}});
    json prim = unitTrianglePrimitive(b);
    prim["attributes"]["TEXCOORD_0"] = b.addData(std::vector<float>{0, 0, 1, 0, 0, 1}, test::kFloat, "VEC2");
    return prim;
}

// Sample-model collections and Substance exports give every material an occlusion map: VC.glb
// (glTF-Sample-Models) has 147 such materials, and a line for each buried the warnings that matter.
TEST(GltfLoaderMaterials, AWarningManyMaterialsShareIsWrittenOnce) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    std::vector<int> nodes;
    for (int i = 0; i < 5; ++i) {
        json material = {{"name", "Scrape" + std::to_string(i)}, {"occlusionTexture", {{"index", 0}}}};
        if (i >= 3) {  // alpha 0.5 keeps BLEND from being settled as opaque
            material["alphaMode"] = "BLEND";
            material["pbrMetallicRoughness"] = {{"baseColorFactor", {1, 1, 1, 0.5}}};
        }
        prim["material"] = b.addMaterial(material);
        nodes.push_back(b.addMeshNode(prim));
    }
    b.setScene(nodes);
    const Scene scene = loadGltf(b.writeEmbedded(dir, "occlusion_maps.gltf"));
    EXPECT_EQ(warningsWith(scene, {"occlusionTexture ignored"}), 1u) << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"material 0 'Scrape0' and 4 other materials: occlusionTexture ignored (the path "
                                   "tracer computes occlusion from the geometry)"}),
              1u);
    EXPECT_EQ(warningsWith(scene, {"material 3 'Scrape3' and 1 other material: alphaMode BLEND is traced as a "
                                   "stochastic cut-out"}),
              1u)
        << ::testing::PrintToString(scene.stats.warnings);
    // One material keeps the form it always had.
    GltfBuilder one;
    json single = tinyPngTexturedTriangle(one);
    single["material"] = one.addMaterial({{"name", "Lone"}, {"occlusionTexture", {{"index", 0}}}});
    one.setScene({one.addMeshNode(single)});
    const Scene lone = loadGltf(one.writeEmbedded(dir, "one_occlusion_map.gltf"));
    EXPECT_EQ(warningsWith(lone, {"material 0 'Lone': occlusionTexture ignored"}), 1u)
        << ::testing::PrintToString(lone.stats.warnings);
}

float srgb(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

// ------------------------------------------------------------------------ KHR_materials_clearcoat

TEST(Clearcoat, FactorsAndTexturesAreReadAsBlenderWritesThem) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    // As Blender 3.4 exports Principled Clearcoat 0.7, Clearcoat Roughness 0.15 (plus textures).
    prim["material"] = b.addMaterial(
        {{"pbrMetallicRoughness",
          {{"baseColorFactor", {0.5, 0.3, 0.1, 1}}, {"metallicFactor", 0}, {"roughnessFactor", 0.5}}},
         {"extensions",
          {{"KHR_materials_clearcoat",
            {{"clearcoatFactor", 0.7},
             {"clearcoatRoughnessFactor", 0.15},
             {"clearcoatTexture", {{"index", 0}}},
             {"clearcoatRoughnessTexture", {{"index", 0}}},
             {"clearcoatNormalTexture", {{"index", 0}}}}}}}});
    b.setScene({b.addMeshNode(prim)});
    b.doc["extensionsUsed"] = {"KHR_materials_clearcoat"};
    b.doc["extensionsRequired"] = {"KHR_materials_clearcoat"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "clearcoat.gltf"));
    const Material& m = scene.materials.at(0);
    EXPECT_FLOAT_EQ(m.clearcoat, 0.7f);
    EXPECT_FLOAT_EQ(m.clearcoat_roughness, 0.15f);
    ASSERT_TRUE(m.clearcoat_texture.isSet());
    ASSERT_TRUE(m.clearcoat_roughness_texture.isSet());
    // Both are data (linear): texel 0's green 128 stays 128/255.
    EXPECT_NEAR(scene.textures[size_t(m.clearcoat_roughness_texture.texture)].texel(0).g, 128 / 255.0f, 1e-6f);
    bool normal_warned = false, unsupported = false;
    for (const std::string& w : scene.stats.warnings) {
        normal_warned |= w.find("clearcoatNormalTexture ignored") != std::string::npos;
        unsupported |= w.find("not supported") != std::string::npos;
    }
    EXPECT_TRUE(normal_warned);
    EXPECT_FALSE(unsupported);
}

// ------------------------------------------------------------- KHR_materials_pbrSpecularGlossiness

TEST(SpecularGlossiness, FactorsBecomeADielectricWithThatF0AndRoughness) {
    TempDir dir;
    GltfBuilder b;
    json prim = unitTrianglePrimitive(b);
    // The metallic-roughness part is only a fallback for viewers without the extension.
    prim["material"] = b.addMaterial(
        {{"pbrMetallicRoughness", {{"baseColorFactor", {1, 0, 0, 1}}, {"metallicFactor", 1}, {"roughnessFactor", 0}}},
         {"extensions",
          {{"KHR_materials_pbrSpecularGlossiness",
            {{"diffuseFactor", {0.5, 0.25, 0.125, 0.8}},
             {"specularFactor", {0.1, 0.2, 0.3}},
             {"glossinessFactor", 0.7}}}}}});
    b.setScene({b.addMeshNode(prim)});
    b.doc["extensionsUsed"] = {"KHR_materials_pbrSpecularGlossiness"};
    b.doc["extensionsRequired"] = {"KHR_materials_pbrSpecularGlossiness"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "specgloss.gltf"));
    const Material& m = scene.materials.at(0);
    expectVec3Near(m.base_color, {0.5f, 0.25f, 0.125f});
    EXPECT_FLOAT_EQ(m.base_alpha, 0.8f);
    EXPECT_EQ(m.metallic, 0.0f);
    EXPECT_NEAR(m.roughness, 0.3f, 1e-6f);
    EXPECT_EQ(m.ior, 1.5f);
    EXPECT_EQ(m.specular, 1.0f);
    // The BSDF's dielectric F0 is min(((ior - 1) / (ior + 1))^2 x specular colour, 1): the
    // specular factor itself.
    const float r = (m.ior - 1.0f) / (m.ior + 1.0f);
    expectVec3Near(glm::min(r * r * m.specular_color, glm::vec3(1.0f)), {0.1f, 0.2f, 0.3f}, 1e-6f);
    // Read, not ignored; its fallback here (a red metal) is another material, which is said.
    for (const std::string& w : scene.stats.warnings) {
        EXPECT_EQ(w.find("not supported"), std::string::npos) << w;
        if (w.find("pbrSpecularGlossiness") != std::string::npos) {
            EXPECT_NE(w.find("fallback"), std::string::npos) << w;
        }
    }

    // Absent factors are the extension's defaults: white diffuse, white specular, glossiness 1.
    GltfBuilder d;
    json plain = unitTrianglePrimitive(d);
    plain["material"] = d.addMaterial({{"extensions", {{"KHR_materials_pbrSpecularGlossiness", json::object()}}}});
    d.setScene({d.addMeshNode(plain)});
    const Material& white = loadGltf(d.writeEmbedded(dir, "defaults.gltf")).materials.at(0);
    expectVec3Near(white.base_color, {1, 1, 1});
    EXPECT_EQ(white.metallic, 0.0f);
    EXPECT_EQ(white.roughness, 0.0f);
    expectVec3Near(glm::min(0.04f * white.specular_color, glm::vec3(1.0f)), {1, 1, 1}, 1e-6f);
}

TEST(SpecularGlossiness, AFallbackThatDescribesAnotherMaterialIsWarnedAbout) {
    // assimp writes OBJ's `Ks 0.5` as specularFactor 0.5 (F0 0.5, ten times a dielectric's) and
    // its fallback as a plain dielectric, and `Tr 1` as an opaque diffuse over a transparent
    // fallback: viewers without the extension show another material than the render.
    const auto load = [](const json& fallback, const json& extension, const char* name) {
        TempDir dir;
        GltfBuilder b;
        json prim = unitTrianglePrimitive(b);
        json material = {{"name", name}, {"extensions", {{"KHR_materials_pbrSpecularGlossiness", extension}}}};
        if (!fallback.is_null()) material["pbrMetallicRoughness"] = fallback;
        prim["material"] = b.addMaterial(material);
        b.setScene({b.addMeshNode(prim)});
        b.doc["extensionsUsed"] = {"KHR_materials_pbrSpecularGlossiness"};
        std::string found;
        for (const std::string& w : loadGltf(b.writeEmbedded(dir, std::string(name) + ".gltf")).stats.warnings) {
            if (w.find("fallback") != std::string::npos) found += w;
        }
        return found;
    };
    const json dielectric = {{"baseColorFactor", {0.6, 0.6, 0.6, 1}}, {"metallicFactor", 0}};
    const std::string ks = load(dielectric,
                                {{"diffuseFactor", {0.6, 0.6, 0.6, 1}}, {"specularFactor", {0.5, 0.5, 0.5}}}, "ks");
    EXPECT_NE(ks.find("material 0 'ks'"), std::string::npos) << ks;
    EXPECT_NE(ks.find("specular reflectance (F0) 0.5 against 0.04"), std::string::npos) << ks;
    EXPECT_NE(ks.find("the extension is used"), std::string::npos) << ks;
    const std::string tr = load({{"baseColorFactor", {0.6, 0.6, 0.6, 0}}, {"metallicFactor", 0}},
                                {{"diffuseFactor", {0.6, 0.6, 0.6, 1}}, {"specularFactor", {0.04, 0.04, 0.04}}}, "tr");
    EXPECT_NE(tr.find("alpha 1 against 0"), std::string::npos) << tr;
    // A fallback that agrees (what careful exporters write) says nothing.
    EXPECT_EQ(load(dielectric, {{"diffuseFactor", {0.6, 0.6, 0.6, 1}}, {"specularFactor", {0.04, 0.04, 0.04}}},
                   "agrees"),
              "");
    // Nor does a material that writes no fallback (glTF-Sample-Models' SpecGlossVsMetalRough):
    // glTF's defaults (white metal) stand in, which no one wrote.
    EXPECT_EQ(load(nullptr, {{"diffuseFactor", {0.6, 0.6, 0.6, 1}}, {"specularFactor", {0.5, 0.5, 0.5}}}, "none"), "");
}

TEST(SpecularGlossiness, AFallbackWhoseValuesComeFromTexturesIsNotComparedByItsFactors) {
    // As Corset's spec-gloss variant (glTF-Sample-Models) writes it: a fallback of textures over
    // the default factors (metallic 1 times an ORM texture) and an extension of textures. Its
    // factors say "diffuse 1 against 0", which is no difference anyone would see.
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    prim["material"] = b.addMaterial(
        {{"name", "corset"},
         {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}}}}},
         {"extensions",
          {{"KHR_materials_pbrSpecularGlossiness",
            {{"diffuseTexture", {{"index", 0}}}, {"specularGlossinessTexture", {{"index", 0}}}}}}}});
    b.setScene({b.addMeshNode(prim)});
    b.doc["extensionsUsed"] = {"KHR_materials_pbrSpecularGlossiness"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "corset.gltf"));
    EXPECT_EQ(warningsWith(scene, {"fallback"}), 0u) << ::testing::PrintToString(scene.stats.warnings);
}

TEST(SpecularGlossiness, TexturesGiveDiffuseSpecularColourAndRoughnessFromAlpha) {
    TempDir dir;
    GltfBuilder b;
    // tinyPng: row 0 = (0, 128, 255, A 255), (255, 0, 0, A 128); row 1 = grey 64 and white, A 255.
    json prim = tinyPngTexturedTriangle(b);
    prim["material"] = b.addMaterial({{"extensions",
                                       {{"KHR_materials_pbrSpecularGlossiness",
                                         {{"diffuseTexture", {{"index", 0}}},
                                          {"specularGlossinessTexture", {{"index", 0}}},
                                          {"glossinessFactor", 0.5}}}}}});
    b.setScene({b.addMeshNode(prim)});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "specgloss_textured.gltf"));
    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.base_color_texture.isSet());
    ASSERT_TRUE(m.specular_color_texture.isSet());
    ASSERT_TRUE(m.metallic_roughness_texture.isSet());
    EXPECT_EQ(m.base_color_texture.texture, m.specular_color_texture.texture);  // both the sRGB decode
    EXPECT_EQ(m.roughness, 1.0f);                                               // the texture holds 1 - 0.5 A
    const Texture& colour = scene.textures[m.specular_color_texture.texture];
    EXPECT_NEAR(colour.texel(0).y, srgb(128 / 255.0f), 1e-6f);
    const Texture& rough = scene.textures[m.metallic_roughness_texture.texture];
    ASSERT_EQ(rough.texelCount(), 4u);
    EXPECT_NEAR(rough.texel(0).g, 0.5f, 1e-6f);                        // A 255: glossiness 0.5
    EXPECT_NEAR(rough.texel(1).g, 1.0f - 0.5f * 128 / 255.0f, 1e-6f);  // A 128, linear
    EXPECT_EQ(rough.texel(1).b, 0.0f);                                 // metallic 0
    EXPECT_EQ(m.metallic, 0.0f);
}

TEST(GltfLoaderMaterials, BaseColourTextureDecodedFromSrgbAndDataTextureLinear) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    b.doc["samplers"] = json::array({{{"magFilter", 9728}, {"wrapS", 33071}, {"wrapT", 33648}}});
    b.doc["textures"][0]["sampler"] = 0;
    prim["material"] = b.addMaterial({{"pbrMetallicRoughness",
                                       {{"baseColorTexture", {{"index", 0}}},
                                        {"metallicRoughnessTexture", {{"index", 0}, {"texCoord", 1}}}}}});
    const int node = b.addMeshNode(prim);
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "textured.gltf"));

    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.base_color_texture.isSet());
    ASSERT_TRUE(m.metallic_roughness_texture.isSet());
    EXPECT_EQ(m.base_color_texture.texcoord, 0u);
    EXPECT_EQ(m.metallic_roughness_texture.texcoord, 1u);
    ASSERT_EQ(scene.textures.size(), 2u);  // read as sRGB and as linear, over one copy of the texels

    const Texture& colour = scene.textures[m.base_color_texture.texture];
    ASSERT_EQ(colour.width, 2);
    ASSERT_EQ(colour.height, 2);
    EXPECT_NEAR(colour.texel(0).y, srgb(128 / 255.0f), 1e-6f);
    EXPECT_NEAR(colour.texel(0).z, 1.0f, 1e-6f);
    EXPECT_NEAR(colour.texel(1).w, 128 / 255.0f, 1e-6f);  // alpha stays linear
    EXPECT_NEAR(colour.texel(2).x, srgb(64 / 255.0f), 1e-6f);
    EXPECT_EQ(colour.wrap_s, WrapMode::ClampToEdge);
    EXPECT_EQ(colour.wrap_t, WrapMode::MirroredRepeat);
    EXPECT_TRUE(colour.nearest);
    // v = 0 is the top row of the image.
    EXPECT_NEAR(colour.sample({0.25f, 0.25f}).y, srgb(128 / 255.0f), 1e-6f);
    EXPECT_NEAR(colour.sample({0.25f, 0.75f}).x, srgb(64 / 255.0f), 1e-6f);

    const Texture& data = scene.textures[m.metallic_roughness_texture.texture];
    EXPECT_EQ(colour.encoding, TexelEncoding::Srgb8);
    EXPECT_EQ(data.encoding, TexelEncoding::Linear8);
    EXPECT_EQ(colour.texels8, data.texels8);  // shared
    EXPECT_NEAR(data.texel(0).y, 128 / 255.0f, 1e-6f);
    EXPECT_NEAR(data.texel(2).x, 64 / 255.0f, 1e-6f);
    ASSERT_EQ(scene.texcoords0.size(), scene.positions.size());
    EXPECT_TRUE(scene.texcoords1.empty());
}

/// Big-endian helpers for the hand-written PNG below.
void put32be(std::vector<uint8_t>& out, uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
}

uint32_t crc32(const uint8_t* data, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; ++i) {
        c ^= data[i];
        for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

void pngChunk(std::vector<uint8_t>& png, const char* type, const std::vector<uint8_t>& body) {
    put32be(png, static_cast<uint32_t>(body.size()));
    std::vector<uint8_t> typed(type, type + 4);
    typed.insert(typed.end(), body.begin(), body.end());
    png.insert(png.end(), typed.begin(), typed.end());
    put32be(png, crc32(typed.data(), typed.size()));
}

/// A 1x1 16-bit RGB PNG (stb_image_write only writes 8-bit), zlib with one stored block.
std::vector<uint8_t> png16(uint16_t r, uint16_t g, uint16_t b) {
    const std::vector<uint8_t> raw = {0,  // filter type None
                                      uint8_t(r >> 8), uint8_t(r), uint8_t(g >> 8), uint8_t(g), uint8_t(b >> 8), uint8_t(b)};
    std::vector<uint8_t> z = {0x78, 0x01, 0x01, uint8_t(raw.size()), 0, uint8_t(~raw.size()), 0xFF};
    z.insert(z.end(), raw.begin(), raw.end());
    uint32_t a = 1, bsum = 0;  // Adler-32
    for (uint8_t v : raw) {
        a = (a + v) % 65521;
        bsum = (bsum + a) % 65521;
    }
    put32be(z, (bsum << 16) | a);
    std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    std::vector<uint8_t> ihdr;
    put32be(ihdr, 1);
    put32be(ihdr, 1);
    ihdr.insert(ihdr.end(), {16, 2, 0, 0, 0});  // 16 bits, truecolour, deflate, no filter, no interlace
    pngChunk(png, "IHDR", ihdr);
    pngChunk(png, "IDAT", z);
    pngChunk(png, "IEND", {});
    return png;
}

TEST(GltfLoaderMaterials, SixteenBitTextureKeepsPrecision) {
    TempDir dir;
    GltfBuilder b;
    b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(png16(1000, 32768, 65535))}}});
    b.doc["textures"] = json::array({{{"source", 0}}});
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial({{"pbrMetallicRoughness",
                                       {{"baseColorTexture", {{"index", 0}}}, {"metallicRoughnessTexture", {{"index", 0}}}}}});
    const int node = b.addMeshNode(prim);
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "png16.gltf"));
    const Material& m = scene.materials.at(0);
    const glm::vec4 colour = scene.textures.at(m.base_color_texture.texture).texel(0);
    const glm::vec4 data = scene.textures.at(m.metallic_roughness_texture.texture).texel(0);
    EXPECT_NEAR(data.x, 1000 / 65535.0f, 1e-7f);  // finer than any 8-bit code
    EXPECT_NEAR(data.y, 32768 / 65535.0f, 1e-7f);
    EXPECT_NEAR(colour.x, srgb(1000 / 65535.0f), 1e-7f);
    EXPECT_NEAR(colour.z, 1.0f, 1e-6f);
    EXPECT_FLOAT_EQ(colour.w, 1.0f);
}

TEST(GltfLoaderMaterials, SpecularTexturesAndEmissiveTextureReferenced) {
    TempDir dir;
    GltfBuilder b;
    b.doc["images"] = json::array({{{"uri", "data:image/png;base64," + test::base64(tinyPng())}}});
    b.doc["textures"] = json::array({{{"source", 0}}});
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial(
        {{"emissiveTexture", {{"index", 0}}},
         {"extensions",
          {{"KHR_materials_specular",
            {{"specularTexture", {{"index", 0}}}, {"specularColorTexture", {{"index", 0}, {"texCoord", 1}}}}}}}});
    const int node = b.addMeshNode(prim);
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "specular.gltf"));
    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.emissive_texture.isSet());
    ASSERT_TRUE(m.specular_texture.isSet());
    ASSERT_TRUE(m.specular_color_texture.isSet());
    EXPECT_EQ(m.specular_color_texture.texcoord, 1u);
    EXPECT_EQ(m.emissive_texture.texture, m.specular_color_texture.texture);  // both sRGB, shared
    EXPECT_NE(m.specular_texture.texture, m.specular_color_texture.texture);  // linear vs sRGB
    EXPECT_FLOAT_EQ(m.specular, 1.0f);
    EXPECT_EQ(scene.textures.size(), 2u);
}

// assimp lists FB_ngon_encoding in every file it writes and puts it on every primitive: a note of
// how its polygons were triangulated, which changes nothing here. And a file can list extensions
// that no object carries (assimp keeps the list of the file it converted): nothing is ignored.
TEST(GltfLoader, ExtensionsThatChangeNothingAreNotWarnedAbout) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    prim["extensions"] = {{"FB_ngon_encoding", json::object()}};
    // An unknown extension where the loader reads nothing of it: inside a known one's texture.
    prim["material"] = b.addMaterial(
        {{"extensions",
          {{"KHR_materials_specular",
            {{"specularTexture", {{"index", 0}, {"extensions", {{"EXT_nested_example", {{"level", 2}}}}}}}}}}}});
    b.setScene({b.addMeshNode(prim)});
    b.doc["extensionsUsed"] = {"KHR_materials_specular", "FB_ngon_encoding", "KHR_materials_volume",
                               "EXT_nested_example"};
    const Scene scene = loadGltf(b.writeGlb(dir, "assimp.glb"));
    EXPECT_EQ(warningsWith(scene, {"FB_ngon_encoding"}), 0u) << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"KHR_materials_volume"}), 0u);
    // Named with the object that carries it (a texture reference counts as its material).
    EXPECT_EQ(warningsWith(scene, {"extension 'EXT_nested_example' (on material 0) is not supported and is ignored"}),
              1u)
        << ::testing::PrintToString(scene.stats.warnings);
}

// A warning of an ignored extension named no object: with 40 materials the user could not find
// the one. It names the first carrier and counts the others.
TEST(GltfLoader, AnIgnoredExtensionNamesTheObjectsCarryingIt) {
    TempDir dir;
    GltfBuilder b;
    const json sheen = {{"KHR_materials_sheen", {{"sheenColorFactor", {1, 1, 1}}}}};
    b.addMaterial({{"name", "Plain"}});
    json prim = unitTrianglePrimitive(b);
    prim["material"] = b.addMaterial({{"name", "Velvet"}, {"extensions", sheen}});
    const int velvet = b.addMeshNode(prim);
    prim["material"] = b.addMaterial({{"name", "Cloth"}, {"extensions", sheen}});
    const int cloth = b.addMeshNode(prim);
    prim["material"] = b.addMaterial({{"extensions", sheen}});
    const int third = b.addMeshNode(prim);
    b.setScene({velvet, cloth, third});
    b.doc["extensionsUsed"] = {"KHR_materials_sheen"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "sheen.gltf"));
    EXPECT_EQ(warningsWith(scene, {"extension 'KHR_materials_sheen' (on material 1 'Velvet' and 2 other objects) is "
                                   "not supported and is ignored"}),
              1u)
        << ::testing::PrintToString(scene.stats.warnings);
}

// ------------------------------------------------------------------ images that cannot be decoded

/// KTX2's identifier and a few bytes: what KHR_texture_basisu's images start with (never decoded).
std::vector<uint8_t> ktx2Bytes() {
    return {0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, '\r', '\n', 0x1A, '\n', 0, 0, 0, 0, 1, 0, 0, 0};
}

TEST(GltfLoaderImages, UndecodableImageWarnsAndDropsOnlyItsTextures) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);  // image 0, texture 0: a good PNG
    std::vector<uint8_t> truncated = tinyPng();
    truncated.resize(truncated.size() / 2);
    test::writeFile(dir.file("truncated.png"), truncated.data(), truncated.size());
    const std::vector<uint8_t> text = {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'};
    b.doc["images"].push_back({{"uri", "truncated.png"}});                                // image 1
    b.doc["images"].push_back({{"uri", "data:image/png;base64," + test::base64(text)}});  // image 2
    b.doc["images"].push_back({{"bufferView", b.addView(text.data(), text.size())}, {"mimeType", "image/png"}});  // 3
    // data: URIs tinygltf itself refuses, which failed the whole parse: a type it does not
    // know, and no payload.
    b.doc["images"].push_back({{"uri", "data:image/ktx2;base64," + test::base64(ktx2Bytes())}});  // image 4
    b.doc["images"].push_back({{"uri", "data:image/png;base64,"}});                               // image 5
    b.doc["textures"].push_back({{"source", 1}});                                                 // texture 1
    b.doc["textures"].push_back({{"source", 2}});  // texture 2; image 3 is used by no texture
    b.doc["textures"].push_back({{"source", 4}});  // texture 3
    b.doc["textures"].push_back({{"source", 5}});  // texture 4
    prim["material"] = b.addMaterial(
        {{"pbrMetallicRoughness",
          {{"baseColorFactor", {0.5, 0.25, 1, 1}},
           {"baseColorTexture", {{"index", 1}}},
           {"metallicRoughnessTexture", {{"index", 0}}}}},
         {"emissiveFactor", {1, 1, 1}},
         {"emissiveTexture", {{"index", 2}}},
         {"normalTexture", {{"index", 3}}},
         {"extensions", {{"KHR_materials_specular", {{"specularTexture", {{"index", 4}}}}}}}});
    b.setScene({b.addMeshNode(prim)});
    const Scene scene = loadGltf(b.writeExternal(dir, "undecodable.gltf", "undecodable.bin"));

    const Material& m = scene.materials.at(0);
    EXPECT_FALSE(m.base_color_texture.isSet());  // the factor alone, as for a missing image
    EXPECT_FALSE(m.emissive_texture.isSet());
    EXPECT_FALSE(m.normal_texture.isSet());
    EXPECT_FALSE(m.specular_texture.isSet());
    expectVec3Near(m.base_color, {0.5f, 0.25f, 1.0f});
    ASSERT_TRUE(m.metallic_roughness_texture.isSet());  // the good image is still read
    EXPECT_EQ(scene.textures.at(size_t(m.metallic_roughness_texture.texture)).width, 2);
    // One warning per broken image, naming it and saying why, used or not.
    EXPECT_EQ(warningsWith(scene, {"image 1 'truncated.png' cannot be decoded: stb_image", "ignored"}), 1u)
        << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"image 2 cannot be decoded: stb_image"}), 1u);
    EXPECT_EQ(warningsWith(scene, {"image 3 cannot be decoded: stb_image"}), 1u);
    EXPECT_EQ(warningsWith(scene, {"image 5 cannot be decoded: its data: URI holds no base64 data"}), 1u);
    // And each texture dropped says where.
    EXPECT_EQ(warningsWith(scene, {"texture 1: image 1 'truncated.png' could not be decoded; texture ignored"}), 1u);
    EXPECT_EQ(warningsWith(scene, {"texture 2: image 2 could not be decoded; texture ignored"}), 1u);
    // A KTX2 image (here behind a data: URI type tinygltf does not know) is not decoded at all.
    EXPECT_EQ(warningsWith(scene, {"texture 3: image 4 is a KTX2 (Basis Universal) image", "texture ignored"}), 1u);
    EXPECT_EQ(warningsWith(scene, {"image 4 cannot be decoded"}), 0u);
    EXPECT_EQ(warningsWith(scene, {"texture 4: image 5 could not be decoded; texture ignored"}), 1u);
}

// tinygltf hands an image's bufferView bytes to the decoder without checking that the view lies
// inside its buffer (a fuzzed file read past the buffer's end this way). Such an image is left
// undecoded with a warning, as a missing file is; a view that fits still decodes, in a GLB too.
TEST(GltfLoaderImages, ImageWhoseBufferViewRunsPastItsBufferIsNotRead) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    const std::vector<uint8_t> png = tinyPng();
    const int good_view = b.addView(png.data(), png.size());
    const int short_view = b.addView(png.data(), png.size());
    b.doc["bufferViews"][size_t(short_view)]["byteLength"] = png.size() + 64;            // 64 bytes past the buffer
    b.doc["images"].push_back({{"bufferView", good_view}, {"mimeType", "image/png"}});   // image 1
    b.doc["images"].push_back({{"bufferView", short_view}, {"mimeType", "image/png"}});  // image 2
    b.doc["textures"].push_back({{"source", 1}});                                        // texture 1
    b.doc["textures"].push_back({{"source", 2}});                                        // texture 2
    prim["material"] = b.addMaterial(
        {{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 1}}}, {"metallicRoughnessTexture", {{"index", 2}}}}},
         {"emissiveTexture", {{"index", 0}}}});
    b.setScene({b.addMeshNode(prim)});
    for (const std::string& path : {b.writeEmbedded(dir, "views.gltf"), b.writeGlb(dir, "views.glb")}) {
        const Scene scene = loadGltf(path);
        const Material& m = scene.materials.at(0);
        ASSERT_TRUE(m.base_color_texture.isSet()) << path;
        EXPECT_EQ(scene.textures.at(size_t(m.base_color_texture.texture)).width, 2);
        EXPECT_TRUE(m.emissive_texture.isSet());
        EXPECT_FALSE(m.metallic_roughness_texture.isSet());
        const std::string end = std::to_string(b.doc["bufferViews"][size_t(short_view)]["byteOffset"].get<size_t>() +
                                               png.size() + 64);
        EXPECT_EQ(warningsWith(
                      scene, {"image 2 cannot be decoded: bufferView " + std::to_string(short_view) + " spans bytes [",
                              ", " + end + ") but buffer 0 holds only " + std::to_string(b.bin.size()) + " bytes",
                              "textures using it are ignored"}),
                  1u)
            << ::testing::PrintToString(scene.stats.warnings);
    }
}

// A 0-byte image file is an image that cannot be decoded, like any other: tinygltf refuses an empty
// file before the loader's decoder sees it (here as a missing image, with its own "File read
// error" lines; in some versions as a failed parse), so the loader catches it at the read.
TEST(GltfLoaderImages, EmptyImageFileWarnsAndDropsItsTextures) {
    TempDir dir;
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);  // image 0, texture 0: a good PNG
    test::writeFile(dir.file("empty.png"), "");
    b.doc["images"].push_back({{"uri", "empty.png"}});  // image 1
    b.doc["textures"].push_back({{"source", 1}});       // texture 1
    prim["material"] = b.addMaterial({{"pbrMetallicRoughness",
                                       {{"baseColorFactor", {0.5, 0.25, 1, 1}},
                                        {"baseColorTexture", {{"index", 1}}},
                                        {"metallicRoughnessTexture", {{"index", 0}}}}}});
    b.setScene({b.addMeshNode(prim)});
    const std::string path = b.writeExternal(dir, "empty_image.gltf", "empty_image.bin");
    Scene scene;
    ASSERT_NO_THROW(scene = loadGltf(path));

    const Material& m = scene.materials.at(0);
    EXPECT_FALSE(m.base_color_texture.isSet());  // the factor alone
    expectVec3Near(m.base_color, {0.5f, 0.25f, 1.0f});
    EXPECT_TRUE(m.metallic_roughness_texture.isSet());  // the good image is still read
    EXPECT_EQ(warningsWith(scene, {"image 1 'empty.png' cannot be decoded: the file is empty", "ignored"}), 1u)
        << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"texture 1: image 1 'empty.png' could not be decoded; texture ignored"}), 1u);
    EXPECT_EQ(warningsWith(scene, {"tinygltf"}), 0u) << "the loader's warning, not tinygltf's file-read lines";
    // The file was read: it is one of the scene's files (and the scene's hash changes when it is filled).
    EXPECT_NE(std::find(scene.source_files.begin(), scene.source_files.end(), dir.file("empty.png")),
              scene.source_files.end());
}

/// Makes `folder` the current directory until destroyed.
class InFolder {
public:
    explicit InFolder(const std::string& folder) : previous_(std::filesystem::current_path()) {
        std::filesystem::current_path(folder);
    }
    ~InFolder() {
        std::error_code error;
        std::filesystem::current_path(previous_, error);
    }
    InFolder(const InFolder&) = delete;
    InFolder& operator=(const InFolder&) = delete;

private:
    std::filesystem::path previous_;
};

// tinygltf looks for a URI's file beside the scene, then in the current directory: a scene moved
// away from its textures was told it read outside its folder when the current directory held a
// file of that name (the sandbox refused it), and "File not found" elsewhere. Only the scene's
// folder is searched, and the warning says where.
TEST(GltfLoaderImages, AMissingImageIsNotFoundBesideTheSceneWhateverTheCurrentDirectory) {
    TempDir dir;
    std::filesystem::create_directories(dir.file("moved"));
    std::filesystem::create_directories(dir.file("tex dir"));
    const std::vector<uint8_t> png = tinyPng();
    test::writeFile(dir.file("tex dir/checker.png"), png.data(), png.size());
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);                       // image 0, texture 0: a good PNG
    b.doc["images"].push_back({{"uri", "tex dir/checker.png"}});  // image 1, as assimp writes it
    b.doc["textures"].push_back({{"source", 1}});                 // texture 1
    prim["material"] = b.addMaterial(
        {{"pbrMetallicRoughness",
          {{"baseColorTexture", {{"index", 1}}}, {"metallicRoughnessTexture", {{"index", 0}}}}}});
    b.setScene({b.addMeshNode(prim)});
    const std::string path = b.writeGlb(dir, "moved/scene.glb");
    const std::string folder = std::filesystem::canonical(dir.file("moved")).string();

    const auto expectNotFound = [&](const std::string& scene_path, const std::string& current) {
        InFolder in(current);
        const Scene scene = loadGltf(scene_path);
        SCOPED_TRACE("current directory " + current + ", scene " + scene_path);
        EXPECT_FALSE(scene.materials.at(0).base_color_texture.isSet());
        EXPECT_TRUE(scene.materials.at(0).metallic_roughness_texture.isSet());
        EXPECT_EQ(warningsWith(scene, {"image 1 'tex dir/checker.png' not found beside the scene (looked in " + folder +
                                       "); textures using it are ignored"}),
                  1u)
            << ::testing::PrintToString(scene.stats.warnings);
        EXPECT_EQ(warningsWith(scene, {"texture 1: image 1 'tex dir/checker.png' not found; texture ignored"}), 1u);
        EXPECT_EQ(warningsWith(scene, {"outside the scene's folder"}), 0u);
        EXPECT_EQ(warningsWith(scene, {"decoded"}), 0u);
        EXPECT_EQ(warningsWith(scene, {"tinygltf"}), 0u) << "the loader's warning, not tinygltf's lines";
        EXPECT_EQ(scene.source_files, std::vector<std::string>{scene_path});
    };
    expectNotFound(path, dir.file(""));  // the current directory holds "tex dir/checker.png"
    expectNotFound("moved/scene.glb", dir.file(""));
    expectNotFound(path, dir.file("moved"));
    expectNotFound(path, dir.file("tex dir"));
}

// assimp copies an MTL's Windows path into the URI as written (`map_Kd tex dir\checker.png`), and
// '\' is a letter of file names here: where no file has the name as written, '\' is read as '/',
// and the file must still be inside the scene's folder.
TEST(GltfLoaderImages, AWindowsPathIsReadWithForwardSlashesInsideTheScenesFolder) {
    TempDir dir;
    std::filesystem::create_directories(dir.file("scene/tex dir"));
    const std::vector<uint8_t> png = tinyPng();
    test::writeFile(dir.file("scene/tex dir/checker.png"), png.data(), png.size());
    test::writeFile(dir.file("secret.png"), png.data(), png.size());
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    b.doc["images"].push_back({{"uri", "tex dir\\checker.png"}});  // image 1: there with '/'
    b.doc["images"].push_back({{"uri", "..\\secret.png"}});        // image 2: outside the folder
    b.doc["images"].push_back({{"uri", "tex dir\\absent.png"}});   // image 3: nowhere
    for (int image = 1; image <= 3; ++image) b.doc["textures"].push_back({{"source", image}});
    prim["material"] = b.addMaterial({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 1}}}}},
                                      {"emissiveFactor", {1, 1, 1}},
                                      {"emissiveTexture", {{"index", 2}}},
                                      {"normalTexture", {{"index", 3}}}});
    b.setScene({b.addMeshNode(prim)});
    const std::string path = b.writeEmbedded(dir, "scene/scene.gltf");
    InFolder in(dir.file("scene/tex dir"));  // holds a checker.png too: never read
    const Scene scene = loadGltf(path);

    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.base_color_texture.isSet()) << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(scene.textures.at(size_t(m.base_color_texture.texture)).width, 2);
    EXPECT_EQ(
        warningsWith(scene, {"'tex dir\\checker.png'", "read 'tex dir/checker.png'", "'\\' as a folder separator"}), 1u)
        << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_NE(std::find(scene.source_files.begin(), scene.source_files.end(), dir.file("scene/tex dir/checker.png")),
              scene.source_files.end());
    // The sandbox holds for the path read with '/'.
    EXPECT_FALSE(m.emissive_texture.isSet());
    EXPECT_EQ(warningsWith(scene, {"secret.png", "outside the scene's folder"}), 1u);
    EXPECT_EQ(std::find(scene.source_files.begin(), scene.source_files.end(), dir.file("secret.png")),
              scene.source_files.end());
    // Found neither way: not found, as written.
    EXPECT_FALSE(m.normal_texture.isSet());
    EXPECT_EQ(warningsWith(scene, {"image 3 'tex dir\\absent.png' not found beside the scene"}), 1u);
}

/// A triangle whose base colour texture is texture 0 = `texture`, over a PNG (image 0) and a
/// KTX2 image (image 1, in a bufferView as a GLB holds it), with KHR_texture_basisu used or
/// required.
std::string basisuScene(const TempDir& dir, const json& texture, bool required) {
    GltfBuilder b;
    json prim = tinyPngTexturedTriangle(b);
    const std::vector<uint8_t> ktx2 = ktx2Bytes();
    b.doc["images"].push_back({{"bufferView", b.addView(ktx2.data(), ktx2.size())}, {"mimeType", "image/ktx2"}});
    b.doc["textures"] = json::array({texture});
    prim["material"] = b.addMaterial({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    b.setScene({b.addMeshNode(prim)});
    b.doc["extensionsUsed"] = {"KHR_texture_basisu"};
    if (required) b.doc["extensionsRequired"] = {"KHR_texture_basisu"};
    return b.writeGlb(dir, "basisu.glb");
}

TEST(GltfLoaderImages, BasisuTextureReadsItsPngFallback) {
    TempDir dir;
    const Scene scene = loadGltf(
        basisuScene(dir, {{"source", 0}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}}, false));
    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.base_color_texture.isSet());
    const Texture& t = scene.textures.at(size_t(m.base_color_texture.texture));
    ASSERT_EQ(t.width, 2);  // tinyPng
    EXPECT_NEAR(t.texel(0).y, srgb(128 / 255.0f), 1e-6f);
    // One note that the KTX2 image is skipped; nothing about undecodable images or the extension.
    ASSERT_EQ(scene.stats.warnings.size(), 1u) << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"texture 0: KHR_texture_basisu image 1", "not decoded", "fallback image 0"}), 1u)
        << scene.stats.warnings[0];

    // Without a fallback the texture is dropped, with a warning, and the scene still loads.
    const Scene only = loadGltf(basisuScene(dir, {{"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}}, false));
    EXPECT_FALSE(only.materials.at(0).base_color_texture.isSet());
    EXPECT_EQ(warningsWith(only, {"texture 0 has only a KHR_texture_basisu image 1", "no PNG or JPEG fallback"}), 1u)
        << ::testing::PrintToString(only.stats.warnings);
}

TEST(GltfLoaderImages, RequiredBasisuIsRefusedSayingKtx2IsNotSupported) {
    TempDir dir;
    const std::string msg = loadErrorOf([&] {
        loadGltf(basisuScene(dir, {{"source", 0}, {"extensions", {{"KHR_texture_basisu", {{"source", 1}}}}}}, true));
    });
    EXPECT_NE(msg.find("KHR_texture_basisu"), std::string::npos) << msg;
    EXPECT_NE(msg.find("KTX2 / Basis Universal textures are not supported"), std::string::npos) << msg;
}

// ------------------------------------------------------------------------------------ lights etc.

// The cone warning said "light ''" for a light without a name; it names the light by index and
// node, as the other light warnings do.
TEST(GltfLoaderLights, AnUnnamedSpotsBadConeIsNamedByIndexAndNode) {
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"type", "spot"}, {"intensity", 683.0}, {"spot", {{"innerConeAngle", 0.8}, {"outerConeAngle", 0.5}}}}});
    const int lamp = b.addNode({{"name", "Lamp"}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b)), lamp});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "cone.gltf"));
    EXPECT_EQ(warningsWith(scene, {"light 0 on node 0 'Lamp': spot cone angles (inner 0.800000, outer 0.500000) "
                                   "outside 0 <= inner < outer <= pi/2; clamped"}),
              1u)
        << ::testing::PrintToString(scene.stats.warnings);
}

// What is wrong with a light itself is said once, at its first node: a lamp placed by two nodes
// gave each warning twice, once per node.
TEST(GltfLoaderLights, ALightOnTwoNodesIsWarnedAboutOnce) {
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"type", "spot"},
          {"intensity", 683.0},
          {"color", {2.0, 1.0, 1.0}},
          {"spot", {{"innerConeAngle", 0.8}, {"outerConeAngle", 0.5}}}}});
    const json placed = {{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}};
    json left = placed, right = placed;
    left["name"] = "Left";
    right["name"] = "Right";
    right["translation"] = {2.0, 0.0, 0.0};
    const int left_node = b.addNode(left), right_node = b.addNode(right);
    b.setScene({b.addMeshNode(unitTrianglePrimitive(b)), left_node, right_node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "two_lamps.gltf"));
    ASSERT_EQ(scene.lights.size(), 2u);
    EXPECT_EQ(scene.lights[1].outer_cone_angle, 0.5f);  // clamped at the second node too
    EXPECT_EQ(scene.lights[1].intensity, scene.lights[0].intensity);
    EXPECT_EQ(warningsWith(scene, {"spot cone angles"}), 1u) << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"light 0 on node 0 'Left': colour (2, 1, 1)", "clamped"}), 1u)
        << ::testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(warningsWith(scene, {"'Right'"}), 0u) << ::testing::PrintToString(scene.stats.warnings);
}

TEST(GltfLoaderLights, PhotometricToRadiometric) {
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "bulb"}, {"type", "point"}, {"intensity", 683.0}, {"color", {1.0, 0.5, 0.25}}, {"range", 7.0}},
         {{"name", "sun"}, {"type", "directional"}, {"intensity", 683.0}},
         {{"name", "spot"},
          {"type", "spot"},
          {"intensity", 1366.0},
          {"spot", {{"innerConeAngle", 0.2}, {"outerConeAngle", 0.5}}}}});
    const float s = std::sqrt(0.5f);
    const int bulb = b.addNode({{"translation", {1, 2, 3}}, {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    // Rotated -90 degrees about X: -Z turns into -Y (the sun shines straight down).
    const int sun = b.addNode({{"rotation", {-s, 0, 0, s}}, {"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    const int spotChild = b.addNode({{"extensions", {{"KHR_lights_punctual", {{"light", 2}}}}}});
    const int spotParent = b.addNode({{"translation", {0, 4, 0}}, {"children", {spotChild}}});
    b.setScene({bulb, sun, spotParent});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "lights.gltf"));

    ASSERT_EQ(scene.lights.size(), 3u);
    const PunctualLight& p = scene.lights[0];
    EXPECT_EQ(p.type, LightType::Point);
    expectVec3Near(p.intensity, {1.0f, 0.5f, 0.25f});  // 683 cd = 1 W/sr, times colour
    expectVec3Near(p.position, {1, 2, 3});
    EXPECT_FLOAT_EQ(p.range, 7.0f);

    const PunctualLight& d = scene.lights[1];
    EXPECT_EQ(d.type, LightType::Directional);
    expectVec3Near(d.intensity, {1, 1, 1});  // 683 lux = 1 W/m^2
    expectVec3Near(d.direction, {0, -1, 0});
    EXPECT_FLOAT_EQ(d.range, 0.0f);

    const PunctualLight& sp = scene.lights[2];
    EXPECT_EQ(sp.type, LightType::Spot);
    expectVec3Near(sp.intensity, {2, 2, 2});
    expectVec3Near(sp.position, {0, 4, 0});
    expectVec3Near(sp.direction, {0, 0, -1});
    EXPECT_FLOAT_EQ(sp.inner_cone_angle, 0.2f);
    EXPECT_FLOAT_EQ(sp.outer_cone_angle, 0.5f);
}

TEST(GltfLoaderLights, AZeroScaleKeepsTheDirectionOfTheNodesRotation) {
    // Scaling a node to zero is how some tools hide an object; glTF orients a light by its node's
    // rotation and leaves its properties to no scale. A sun scaled [1, 1, 0] and rotated to shine
    // down shone along -Z (its collapsed -Z axis had no direction), and the room it lit was black.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Sun"}, {"type", "directional"}, {"intensity", 683.0}},
         {{"name", "Spot"}, {"type", "spot"}, {"intensity", 683.0}, {"spot", json::object()}},
         {{"name", "Child sun"}, {"type", "directional"}},
         {{"name", "Matrix sun"}, {"type", "directional"}},
         {{"name", "Hidden spot"}, {"type", "spot"}, {"spot", json::object()}},
         {{"name", "Hidden bulb"}, {"type", "point"}}});
    const auto light = [](int index) { return json{{"KHR_lights_punctual", {{"light", index}}}}; };
    const float s = std::sqrt(0.5f);
    const json down = {-s, 0, 0, s};  // -90 degrees about X: -Z turns into -Y
    std::vector<int> roots;
    roots.push_back(b.addNode({{"rotation", down}, {"scale", {1, 1, 0}}, {"extensions", light(0)}}));
    roots.push_back(
        b.addNode({{"translation", {1, 2, 3}}, {"rotation", down}, {"scale", {0, 0, 0}}, {"extensions", light(1)}}));
    // Scaled to zero above the light: the parent's rotation turns the child.
    const int child = b.addNode({{"extensions", light(2)}});
    roots.push_back(b.addNode({{"rotation", down}, {"scale", {1, 1, 0}}, {"children", {child}}}));
    // A matrix (column-major) turning -Z into -Y with a scale of 2, 3, 4, under a parent scaled to
    // zero: the matrix's rotation orients the light.
    const int scaled = b.addNode(
        {{"matrix", {2, 0, 0, 0, 0, 0, -3, 0, 0, 4, 0, 0, 0, 0, 0, 1}}, {"extensions", light(3)}});
    roots.push_back(b.addNode({{"scale", {0, 0, 0}}, {"children", {scaled}}}));
    // The same rotation with Z scaled to zero in a matrix: a singular matrix has no orientation,
    // so the spot has no direction. A point light needs none.
    const json flat = {1, 0, 0, 0, 0, 0, -1, 0, 0, 0, 0, 0, 0, 5, 0, 1};
    roots.push_back(b.addNode({{"name", "Flat"}, {"matrix", flat}, {"extensions", light(4)}}));
    roots.push_back(b.addNode({{"matrix", flat}, {"extensions", light(5)}}));
    b.setScene(roots);
    const Scene scene = loadGltf(b.writeEmbedded(dir, "hidden_lights.gltf"));

    ASSERT_EQ(scene.lights.size(), 5u) << testing::PrintToString(scene.stats.warnings);
    for (size_t i = 0; i < 4; ++i) {
        SCOPED_TRACE(scene.lights[i].name);
        expectVec3Near(scene.lights[i].direction, {0, -1, 0});
    }
    expectVec3Near(scene.lights[0].intensity, {1, 1, 1});  // unscaled
    expectVec3Near(scene.lights[1].position, {1, 2, 3});
    EXPECT_EQ(scene.lights[4].name, "Hidden bulb");
    expectVec3Near(scene.lights[4].position, {0, 5, 0});
    const auto said = std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(), [](const std::string& w) {
        return w.find("'Hidden spot'") != std::string::npos && w.find("'Flat'") != std::string::npos &&
               w.find("singular") != std::string::npos && w.find("skipped") != std::string::npos;
    });
    EXPECT_EQ(said, 1) << testing::PrintToString(scene.stats.warnings);
}

TEST(GltfLoaderLights, ALightIsLabelledByItsNodesNameAsBlenderNamesTheObject) {
    // Blender names the node after the object ("Desk lamp") and the light after its data
    // ("Point"): messages name the object, with the light's own name where it differs.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Point"}, {"type", "point"}, {"intensity", 683.0}},
         {{"name", "Sun"}, {"type", "directional"}},
         {{"type", "spot"}, {"spot", json::object()}}});
    const auto light = [](int index) { return json{{"KHR_lights_punctual", {{"light", index}}}}; };
    b.setScene({b.addNode({{"name", "Desk lamp"}, {"extensions", light(0)}}),
                b.addNode({{"name", "Sun"}, {"extensions", light(1)}}), b.addNode({{"extensions", light(2)}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "named.gltf"));
    ASSERT_EQ(scene.lights.size(), 3u);
    EXPECT_EQ(scene.lights[0].node_name, "Desk lamp");
    EXPECT_EQ(lightLabel(scene, 0), "point light 'Desk lamp' (glTF light 'Point')");
    EXPECT_EQ(lightLabel(scene, 1), "directional light 'Sun'");
    EXPECT_EQ(lightLabel(scene, 2), "spot light #2");
}

TEST(GltfLoaderLights, ALightOfAnUnknownTypeIsSkippedWithAWarning) {
    // KHR_lights_punctual's schema takes any string as a light's type, for types to come; one
    // such light refused the whole file ("unknown type 'area'", exit 3). It is now left out and
    // named, once however many nodes place it, and the rest of the scene loads.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Bulb"}, {"type", "point"}, {"intensity", 683.0}}, {{"name", "Panel"}, {"type", "area"}}});
    const auto light = [](int index) { return json{{"KHR_lights_punctual", {{"light", index}}}}; };
    const int bulb = b.addNode({{"extensions", light(0)}});
    const int panel = b.addNode({{"name", "Ceiling panel"}, {"extensions", light(1)}});
    const int again = b.addNode({{"translation", {1, 0, 0}}, {"extensions", light(1)}});
    b.setScene({bulb, panel, again});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "area.gltf"));
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_EQ(scene.lights[0].name, "Bulb");
    const auto named = std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                                     [](const std::string& w) {
                                         return w.find("'Panel'") != std::string::npos &&
                                                w.find("'area'") != std::string::npos &&
                                                w.find("skipped") != std::string::npos;
                                     });
    EXPECT_EQ(named, 1) << testing::PrintToString(scene.stats.warnings);
}

TEST(GltfLoaderLights, SpotConesClampedToValidRange) {
    TempDir dir;
    GltfBuilder b;
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"type", "spot"}, {"spot", {{"innerConeAngle", 0.9}, {"outerConeAngle", 2.0}}}}});
    const int node = b.addNode({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    b.setScene({node});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "spot.gltf"));
    ASSERT_EQ(scene.lights.size(), 1u);
    EXPECT_FLOAT_EQ(scene.lights[0].outer_cone_angle, 1.5707963f);
    EXPECT_FLOAT_EQ(scene.lights[0].inner_cone_angle, 0.9f);
    expectVec3Near(scene.lights[0].intensity, glm::vec3(1.0f / 683.0f));  // default intensity 1 cd
    EXPECT_FALSE(scene.stats.warnings.empty());
}

TEST(GltfLoaderLights, NegativeColourAndIntensityAreClampedWithAWarning) {
    // A negative light would take light away from every surface it reaches.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Dark"}, {"type", "point"}, {"color", {1.5, -1.0, 0.5}}, {"intensity", 683.0}},
         {{"name", "Minus"}, {"type", "point"}, {"intensity", -683.0}}});
    const int a = b.addNode({{"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    const int c = b.addNode({{"extensions", {{"KHR_lights_punctual", {{"light", 1}}}}}});
    b.setScene({a, c});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "negative.gltf"));
    ASSERT_EQ(scene.lights.size(), 2u);
    expectVec3Near(scene.lights[0].intensity, {1.0f, 0.0f, 0.5f});
    expectVec3Near(scene.lights[1].intensity, {0.0f, 0.0f, 0.0f});
    size_t warnings = 0;
    for (const std::string& w : scene.stats.warnings)
        warnings += w.find("clamped into KHR_lights_punctual") != std::string::npos;
    EXPECT_EQ(warnings, 2u);
}

TEST(GltfLoaderLights, ValuesBeyondFloat32AreNamedAsTheFileGivesThem) {
    // glTF's numbers are doubles; lights are float32. An intensity whose W/sr has no float32 made
    // an infinite light (its power, and the brightest radiance the bake's fixed point is scaled
    // to, infinite too): it is skipped, named once however many nodes place it. A colour of 1e39
    // clamps to 1 as any colour above 1 does; its warning named it "inf".
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Blinding"}, {"type", "point"}, {"intensity", 1e45}},
         {{"name", "Vivid"}, {"type", "point"}, {"intensity", 683.0}, {"color", {1e39, 0.5, 0.25}}},
         {{"name", "Strong"}, {"type", "point"}, {"intensity", 1e40}}});
    const auto light = [](int index) { return json{{"KHR_lights_punctual", {{"light", index}}}}; };
    const int blinding = b.addNode({{"extensions", light(0)}});
    const int again = b.addNode({{"translation", {1, 0, 0}}, {"extensions", light(0)}});
    const int vivid = b.addNode({{"extensions", light(1)}});
    const int strong = b.addNode({{"extensions", light(2)}});
    b.setScene({blinding, again, vivid, strong});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "intense.gltf"));
    ASSERT_EQ(scene.lights.size(), 2u) << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(scene.lights[0].name, "Vivid");
    expectVec3Near(scene.lights[0].intensity, {1.0f, 0.5f, 0.25f});
    EXPECT_EQ(scene.lights[1].name, "Strong");
    EXPECT_FLOAT_EQ(scene.lights[1].intensity.x, float(1e40 / 683.0));
    const auto said = [&](const std::string& text) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                             [&](const std::string& w) { return w.find(text) != std::string::npos; });
    };
    EXPECT_EQ(said("light 0 'Blinding' on node 0: intensity 1e+45 (1.46413e+42 after dividing by 683 lm/W) is "
                   "beyond float32's range (at most 3.40282e+38); skipped"),
              1)
        << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(said("light 1 'Vivid' on node 2: colour (1e+39, 0.5, 0.25) and intensity 683 clamped into "
                   "KHR_lights_punctual's ranges (colour [0, 1], intensity at least 0): (1, 0.5, 0.25), 683"),
              1);
    EXPECT_EQ(said("inf"), 0);
}

TEST(GltfLoaderLights, ANodeTransformBeyondTheWorldLimitSkipsTheLightNamingLightAndNode) {
    // A light at infinity or NaN (a translation beyond float32's range, or scales along the path
    // overflowing a double) was kept: its distance to every point was infinite or NaN, so it lit
    // nothing and nothing said why. One within float32 but beyond about 1.8e18 made its shadow
    // rays fail Embree's ray.valid() assertion (SIGABRT). Point and spot lights beyond +-1e9 m,
    // where no vertex may lie, are skipped, naming the light and its node; a directional light's
    // position means nothing, so a sun is kept wherever its node is.
    TempDir dir;
    GltfBuilder b;
    b.doc["extensionsUsed"] = {"KHR_lights_punctual"};
    b.doc["extensions"]["KHR_lights_punctual"]["lights"] = json::array(
        {{{"name", "Far bulb"}, {"type", "point"}, {"intensity", 683.0}},
         {{"name", "Huge spot"}, {"type", "spot"}, {"intensity", 683.0}, {"spot", json::object()}},
         {{"name", "Far sun"}, {"type", "directional"}, {"intensity", 683.0}},
         {{"name", "Bulb"}, {"type", "point"}, {"intensity", 683.0}},
         {{"name", "Astronomical bulb"}, {"type", "point"}, {"intensity", 683.0}}});
    const auto light = [](int index) { return json{{"KHR_lights_punctual", {{"light", index}}}}; };
    std::vector<int> roots;
    roots.push_back(b.addNode({{"name", "Far away"}, {"translation", {1e39, 0, 0}}, {"extensions", light(0)}}));
    // 1e200 under 1e200: the world matrix overflows a double (infinity, and NaN where it meets 0).
    const int spot = b.addNode({{"name", "Spot holder"}, {"scale", {1e200, 1e200, 1e200}}, {"extensions", light(1)}});
    roots.push_back(b.addNode({{"scale", {1e200, 1e200, 1e200}}, {"children", {spot}}}));
    const int sun = b.addNode({{"name", "Sun holder"}, {"translation", {0, -1e39, 0}}, {"extensions", light(2)}});
    roots.push_back(sun);
    roots.push_back(b.addNode({{"translation", {1, 2, 3}}, {"extensions", light(3)}}));
    roots.push_back(b.addNode({{"name", "Sun distance"}, {"translation", {0, 1.5e11, 0}}, {"extensions", light(4)}}));
    b.setScene(roots);
    const Scene scene = loadGltf(b.writeEmbedded(dir, "far_lights.gltf"));
    ASSERT_EQ(scene.lights.size(), 2u) << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(scene.lights[0].name, "Far sun");
    expectVec3Near(scene.lights[0].position, {0, 0, 0});
    EXPECT_EQ(scene.lights[1].name, "Bulb");
    expectVec3Near(scene.lights[1].position, {1, 2, 3});
    const auto said = [&](const std::string& text) {
        return std::count_if(scene.stats.warnings.begin(), scene.stats.warnings.end(),
                             [&](const std::string& w) { return w.find(text) != std::string::npos; });
    };
    EXPECT_EQ(said("light 0 'Far bulb' on node 0 'Far away': the node's transform puts the light at (1e+39, 0, 0), "
                   "beyond +-1e9 m, where nothing of a scene may lie (a sun is a directional light); skipped"),
              1)
        << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(said("light 1 'Huge spot' on node 1 'Spot holder': the node's world transform is not finite"), 1);
    EXPECT_EQ(said("light 4 'Astronomical bulb' on node 5 'Sun distance': the node's transform puts the light at "
                   "(0, 1.5e+11, 0), beyond +-1e9 m"),
              1)
        << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(said("'Far sun'"), 0);
}

TEST(GltfLoaderCameras, ACameraBeyondTheWorldLimitIsSkipped) {
    // A camera 1e20 m out made every camera ray fail Embree's ray.valid() assertion (SIGABRT in
    // bake and render). Beyond +-1e9 m, where no vertex may lie, it is skipped with a warning.
    TempDir dir;
    GltfBuilder b;
    // So is an orthographic view wider than that: its rays start across it.
    b.doc["cameras"] = json::array(
        {{{"name", "Lost"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 0.1}}}},
         {{"name", "Kept"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 0.1}}}},
         {{"name", "Wide"},
          {"type", "orthographic"},
          {"orthographic", {{"xmag", 2e20}, {"ymag", 1e20}, {"znear", 0.1}, {"zfar", 10}}}}});
    const int lost = b.addNode({{"name", "Orbit"}, {"camera", 0}, {"translation", {0, 1e20, 3}}});
    const int kept = b.addNode({{"camera", 1}, {"translation", {0, 1e9, 3}}});  // at the limit: kept
    const int wide = b.addNode({{"camera", 2}, {"translation", {0, 0, 3}}});
    b.setScene({lost, kept, wide});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "far_camera.gltf"));
    ASSERT_EQ(scene.cameras.size(), 1u) << testing::PrintToString(scene.stats.warnings);
    EXPECT_EQ(scene.cameras[0].name, "Kept");
    EXPECT_EQ(scene.cameras[0].index, 0);
    ASSERT_EQ(scene.stats.warnings.size(), 2u) << testing::PrintToString(scene.stats.warnings);
    EXPECT_NE(scene.stats.warnings[0].find("camera 'Orbit' (glTF camera 'Lost'): the node's transform puts the camera "
                                           "at (0, 1e+20, 3), beyond +-1e9 m"),
              std::string::npos)
        << scene.stats.warnings[0];
    EXPECT_NE(scene.stats.warnings[1].find("camera 'Wide': orthographic xmag 2e+20 and ymag 1e+20 must be non-zero "
                                           "and at most 1e9; skipped"),
              std::string::npos)
        << scene.stats.warnings[1];
}

TEST(GltfLoaderLights, MissingLightIndexIsAnError) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addNode({{"name", "lamp"}, {"extensions", {{"KHR_lights_punctual", {{"light", 3}}}}}});
    b.setScene({node});
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "nolight.gltf")); });
    EXPECT_NE(msg.find("nolight.gltf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("'lamp'"), std::string::npos) << msg;
}

TEST(GltfLoaderCameras, PerspectiveAndOrthographicParsed) {
    TempDir dir;
    GltfBuilder b;
    b.doc["cameras"] = json::array({{{"name", "Main"},
                                     {"type", "perspective"},
                                     {"perspective", {{"yfov", 0.6}, {"znear", 0.1}, {"aspectRatio", 1.5}}}},
                                    {{"name", "Iso"},
                                     {"type", "orthographic"},
                                     {"orthographic", {{"xmag", 4}, {"ymag", -2}, {"znear", 0.1}, {"zfar", 10}}}},
                                    {{"type", "perspective"}, {"perspective", {{"yfov", 0.9}, {"znear", 0.1}}}},
                                    {{"name", "Flat"},
                                     {"type", "orthographic"},
                                     {"orthographic", {{"xmag", 0}, {"ymag", 1}, {"znear", 0.1}, {"zfar", 10}}}}});
    const float s = std::sqrt(0.5f);  // 90 degrees about +Y: forward -Z becomes -X
    const int main = b.addNode({{"camera", 0}, {"translation", {1, 2, 3}}, {"rotation", {0, s, 0, s}}});
    const int ortho = b.addNode({{"camera", 1}, {"translation", {0, 10, 0}}});
    const int plain = b.addNode({{"camera", 2}, {"name", "NodeName"}});
    const int flat = b.addNode({{"camera", 3}});
    b.setScene({main, ortho, plain, flat});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "cameras.gltf"));

    ASSERT_EQ(scene.cameras.size(), 3u);
    const Camera& c = scene.cameras[0];
    EXPECT_EQ(c.name, "Main");
    expectVec3Near(c.position, {1, 2, 3});
    expectVec3Near(c.forward, {-1, 0, 0});
    expectVec3Near(c.up, {0, 1, 0});
    EXPECT_FLOAT_EQ(c.yfov, 0.6f);
    ASSERT_TRUE(c.aspect_ratio.has_value());
    EXPECT_FLOAT_EQ(*c.aspect_ratio, 1.5f);
    EXPECT_FALSE(c.orthographic_half_height.has_value());

    // Orthographic: half height ymag (a negative one read by its size), aspect xmag / ymag.
    const Camera& iso = scene.cameras[1];
    EXPECT_EQ(iso.name, "Iso");
    expectVec3Near(iso.position, {0, 10, 0});
    ASSERT_TRUE(iso.orthographic_half_height.has_value());
    EXPECT_FLOAT_EQ(*iso.orthographic_half_height, 2.0f);
    ASSERT_TRUE(iso.aspect_ratio.has_value());
    EXPECT_FLOAT_EQ(*iso.aspect_ratio, 2.0f);

    EXPECT_EQ(scene.cameras[2].name, "");
    EXPECT_EQ(scene.cameras[2].node_name, "NodeName");
    EXPECT_FALSE(scene.cameras[2].aspect_ratio.has_value());
    // xmag 0 is invalid in glTF: skipped, with a warning naming the camera.
    bool warned = false;
    for (const std::string& w : scene.stats.warnings) warned |= w.find("'Flat'") != std::string::npos;
    EXPECT_TRUE(warned);
}

// Blender names the node after the object and the glTF camera after its camera data; users know
// the first. Both are kept, with the camera's index, and messages name a camera by them.
TEST(GltfLoaderCameras, NodeAndCameraNamesAndIndexKept) {
    TempDir dir;
    GltfBuilder b;
    const json perspective = {{"yfov", 0.6}, {"znear", 0.1}};
    b.doc["cameras"] = json::array({{{"name", "Camera"}, {"type", "perspective"}, {"perspective", perspective}},
                                    {{"name", "Camera.001"}, {"type", "perspective"}, {"perspective", perspective}},
                                    {{"type", "perspective"}, {"perspective", perspective}}});
    const int persp = b.addNode({{"camera", 0}, {"name", "Persp"}});
    const int ortho = b.addNode({{"camera", 1}, {"name", "Ortho"}});
    const int same = b.addNode({{"camera", 0}, {"name", "Camera"}});
    const int nameless = b.addNode({{"camera", 2}});
    b.setScene({persp, ortho, same, nameless});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "blender_names.gltf"));
    ASSERT_EQ(scene.cameras.size(), 4u);
    for (size_t i = 0; i < scene.cameras.size(); ++i) EXPECT_EQ(scene.cameras[i].index, int32_t(i));
    EXPECT_EQ(scene.cameras[0].node_name, "Persp");
    EXPECT_EQ(scene.cameras[0].name, "Camera");
    EXPECT_EQ(cameraLabel(scene.cameras[0]), "camera 'Persp' (glTF camera 'Camera')");
    EXPECT_EQ(cameraListEntry(scene.cameras[1]), "#1 node 'Ortho', glTF camera 'Camera.001'");
    EXPECT_EQ(cameraLabel(scene.cameras[2]), "camera 'Camera'");
    EXPECT_EQ(cameraLabel(scene.cameras[3]), "camera #3");
    EXPECT_EQ(cameraListEntry(scene.cameras[3]), "#3 (no names)");
}

// An aspect ratio no real frame has (1e-6 would make a 64-wide image 64 million rows tall) is
// ignored with a warning naming the camera; the image's size gives the aspect then.
TEST(GltfLoaderCameras, AbsurdAspectRatioIgnoredWithAWarning) {
    TempDir dir;
    GltfBuilder b;
    b.doc["cameras"] = json::array({{{"name", "Thin"},
                                     {"type", "perspective"},
                                     {"perspective", {{"yfov", 0.6}, {"znear", 0.1}, {"aspectRatio", 1e-6}}}},
                                    {{"name", "Wide"},
                                     {"type", "perspective"},
                                     {"perspective", {{"yfov", 0.6}, {"znear", 0.1}, {"aspectRatio", 4.0}}}},
                                    {{"name", "Strip"},
                                     {"type", "orthographic"},
                                     {"orthographic", {{"xmag", 1e4}, {"ymag", 1}, {"znear", 0.1}, {"zfar", 9}}}}});
    b.setScene({b.addNode({{"camera", 0}}), b.addNode({{"camera", 1}}), b.addNode({{"camera", 2}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "aspect.gltf"));
    ASSERT_EQ(scene.cameras.size(), 3u);
    EXPECT_FALSE(scene.cameras[0].aspect_ratio.has_value());
    ASSERT_TRUE(scene.cameras[1].aspect_ratio.has_value());
    EXPECT_FLOAT_EQ(*scene.cameras[1].aspect_ratio, 4.0f);
    EXPECT_FALSE(scene.cameras[2].aspect_ratio.has_value());
    EXPECT_FLOAT_EQ(*scene.cameras[2].orthographic_half_height, 1.0f);
    std::string warnings;
    for (const std::string& w : scene.stats.warnings) warnings += w + "\n";
    EXPECT_NE(warnings.find("camera 'Thin': aspectRatio 1e-06 is outside [0.01, 100]"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("camera 'Strip': xmag / ymag 10000 is outside"), std::string::npos) << warnings;
    EXPECT_EQ(warnings.find("'Wide'"), std::string::npos) << warnings;
}

// The clip planes (Blender's clip start and end): a perspective camera's zfar may be absent (an
// infinite projection); an orthographic camera has both.
TEST(GltfLoaderCameras, ClipPlanesRead) {
    TempDir dir;
    GltfBuilder b;
    b.doc["cameras"] = json::array(
        {{{"name", "Near"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 0.8}}}},
         {{"name", "Both"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 0.1}, {"zfar", 100}}}},
         {{"name", "Iso"},
          {"type", "orthographic"},
          {"orthographic", {{"xmag", 2}, {"ymag", 1}, {"znear", 0}, {"zfar", 30}}}}});
    // Given in the camera node's space: a node scaled x3 puts the near plane 3 times as far.
    b.setScene(
        {b.addNode({{"camera", 0}, {"scale", {3, 3, 3}}}), b.addNode({{"camera", 1}}), b.addNode({{"camera", 2}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "clip.gltf"));
    ASSERT_EQ(scene.cameras.size(), 3u);
    EXPECT_FLOAT_EQ(scene.cameras[0].znear, 2.4f);
    EXPECT_FALSE(scene.cameras[0].zfar.has_value());
    EXPECT_FLOAT_EQ(scene.cameras[1].znear, 0.1f);
    ASSERT_TRUE(scene.cameras[1].zfar.has_value());
    EXPECT_FLOAT_EQ(*scene.cameras[1].zfar, 100.0f);
    EXPECT_FLOAT_EQ(scene.cameras[2].znear, 0.0f);
    ASSERT_TRUE(scene.cameras[2].zfar.has_value());
    EXPECT_FLOAT_EQ(*scene.cameras[2].zfar, 30.0f);
    EXPECT_TRUE(scene.stats.warnings.empty()) << scene.stats.warnings.front();
}

// Bad clip planes are warned about, naming the camera, and dropped: the camera is kept and sees
// from its position, or without end.
TEST(GltfLoaderCameras, InvalidClipPlanesDroppedWithAWarning) {
    TempDir dir;
    GltfBuilder b;
    b.doc["cameras"] = json::array(
        {{{"name", "Behind"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", -1}}}},
         {{"name", "Inverted"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 5}, {"zfar", 2}}}},
         {{"name", "FlatOrtho"},
          {"type", "orthographic"},
          {"orthographic", {{"xmag", 1}, {"ymag", 1}, {"znear", 0}, {"zfar", 0}}}},
         {{"name", "Huge"}, {"type", "perspective"}, {"perspective", {{"yfov", 0.6}, {"znear", 1e300}}}}});
    b.setScene({b.addNode({{"camera", 0}}), b.addNode({{"camera", 1}}), b.addNode({{"camera", 2}}),
                b.addNode({{"camera", 3}})});
    const Scene scene = loadGltf(b.writeEmbedded(dir, "bad_clip.gltf"));
    ASSERT_EQ(scene.cameras.size(), 4u);
    EXPECT_FLOAT_EQ(scene.cameras[0].znear, 0.0f);
    EXPECT_FLOAT_EQ(scene.cameras[1].znear, 5.0f);  // the near plane is fine; the far one is not
    EXPECT_FALSE(scene.cameras[1].zfar.has_value());
    EXPECT_FALSE(scene.cameras[2].zfar.has_value());
    EXPECT_FLOAT_EQ(scene.cameras[3].znear, 0.0f);
    std::string warnings;
    for (const std::string& w : scene.stats.warnings) warnings += w + "\n";
    EXPECT_NE(warnings.find("camera 'Behind': invalid znear -1"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("camera 'Inverted': invalid zfar 2 (must be greater than znear 5)"), std::string::npos)
        << warnings;
    EXPECT_NE(warnings.find("camera 'FlatOrtho': invalid zfar 0"), std::string::npos) << warnings;
    EXPECT_NE(warnings.find("camera 'Huge': invalid znear 1e+300"), std::string::npos) << warnings;
}

TEST(GltfLoaderSky, UniformRadianceFromRootExtras) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({});
    const Scene black = loadGltf(b.writeEmbedded(dir, "black.gltf"));
    EXPECT_TRUE(black.sky.isBlack());

    b.doc["extras"] = {{"sharcbake", {{"sky_radiance", {0.5, 1.0, 2.0}}}}};
    const Scene sky = loadGltf(b.writeEmbedded(dir, "sky.gltf"));
    expectVec3Near(sky.sky.uniform, {0.5f, 1.0f, 2.0f});
    EXPECT_FALSE(sky.sky.isBlack());

    b.doc["extras"] = {{"sharcbake", {{"sky_radiance", {1.0, 2.0}}}}};
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "bad_sky.gltf")); });
    EXPECT_NE(msg.find("sky_radiance"), std::string::npos) << msg;
}

TEST(GltfLoaderSky, BlendersSceneCustomPropertiesGiveTheSkyToo) {
    // Blender 3.4 writes a scene's custom properties to scenes[i].extras, not the root's: the sky
    // set there was dropped ("sky black"), with only the generic "no lights" warning.
    TempDir dir;
    GltfBuilder b;
    b.setScene({});
    b.doc["scenes"][0]["extras"] = {{"sharcbake", {{"sky_radiance", {0.25, 0.5, 1.0}}}}};
    expectVec3Near(loadGltf(b.writeEmbedded(dir, "scene_sky.gltf")).sky.uniform, {0.25f, 0.5f, 1.0f});
    // The root's keys win where both have them.
    b.doc["extras"] = {{"sharcbake", {{"sky_radiance", {2.0, 2.0, 2.0}}}}};
    expectVec3Near(loadGltf(b.writeEmbedded(dir, "both_sky.gltf")).sky.uniform, {2.0f, 2.0f, 2.0f});
}

TEST(GltfLoaderKnownAnswer, ExpectedRadianceFromRootExtras) {
    TempDir dir;
    GltfBuilder b;
    b.setScene({});
    EXPECT_FALSE(loadGltf(b.writeEmbedded(dir, "none.gltf")).known_radiance.has_value());

    b.doc["extras"] = {{"sharcbake", {{"expected_radiance", 10.0}}}};
    const Scene scalar = loadGltf(b.writeEmbedded(dir, "scalar.gltf"));
    ASSERT_TRUE(scalar.known_radiance.has_value());
    expectVec3Near(*scalar.known_radiance, {10.0f, 10.0f, 10.0f});

    b.doc["extras"] = {{"sharcbake", {{"expected_radiance", {1.0, 2.0, 3.0}}}}};
    const Scene rgb = loadGltf(b.writeEmbedded(dir, "rgb.gltf"));
    ASSERT_TRUE(rgb.known_radiance.has_value());
    expectVec3Near(*rgb.known_radiance, {1.0f, 2.0f, 3.0f});

    b.doc["extras"] = {{"sharcbake", {{"expected_radiance", -1.0}}}};
    const std::string msg = loadErrorOf([&] { loadGltf(b.writeEmbedded(dir, "bad.gltf")); });
    EXPECT_NE(msg.find("expected_radiance"), std::string::npos) << msg;
}

TEST(GltfLoaderKnownAnswer, FurnaceScenesCarryTheirAnswer) {
    const Scene furnace = loadGltf(std::string(SHARCBAKE_SCENES_DIR) + "/furnace_rho090/furnace_rho090.gltf");
    ASSERT_TRUE(furnace.known_radiance.has_value());
    expectVec3Near(*furnace.known_radiance, {10.0f, 10.0f, 10.0f});
}

// ------------------------------------------------------------------------- source files

TEST(GltfLoaderSourceFiles, TheFileThenItsExternalBuffersAndImages) {
    TempDir dir;
    GltfBuilder b;
    const int node = b.addMeshNode(unitTrianglePrimitive(b));
    b.setScene({node});
    const std::string embedded = b.writeEmbedded(dir, "embedded.gltf");
    EXPECT_EQ(loadGltf(embedded).source_files, std::vector<std::string>{embedded});
    const std::string glb = b.writeGlb(dir, "scene.glb");
    EXPECT_EQ(loadGltf(glb).source_files, std::vector<std::string>{glb});
    // URIs are percent-encoded (Blender writes "my%20mesh.bin" for "my mesh.bin").
    const std::string external = b.writeExternal(dir, "external.gltf", "my%20mesh.bin", /*writeBin=*/false);
    test::writeFile(dir.file("my mesh.bin"), b.bin.data(), b.bin.size());
    const Scene scene = loadGltf(external);
    ASSERT_EQ(scene.triangles.size(), 1u);
    EXPECT_EQ(scene.source_files, (std::vector<std::string>{external, dir.file("my mesh.bin")}));
    // The files are the ones the parser read, with its URI decoding ('+' is a space to it too).
    const std::string plus = b.writeExternal(dir, "plus.gltf", "my+mesh.bin", /*writeBin=*/false);
    EXPECT_EQ(loadGltf(plus).source_files, (std::vector<std::string>{plus, dir.file("my mesh.bin")}));

    const std::string quad = std::string(SHARCBAKE_SCENES_DIR) + "/textured_quad/textured_quad.gltf";
    const Scene textured = loadGltf(quad);
    ASSERT_EQ(textured.source_files.size(), 3u);
    EXPECT_EQ(textured.source_files[0], quad);
    EXPECT_NE(textured.source_files[1].find("textured_quad.bin"), std::string::npos);
    EXPECT_NE(textured.source_files[2].find("textured_quad.png"), std::string::npos);

    // A missing image loads with a warning (texture ignored) and is not among the files.
    const std::string folder = std::string(SHARCBAKE_SCENES_DIR) + "/textured_quad/";
    std::filesystem::copy_file(folder + "textured_quad.gltf", dir.file("quad.gltf"));
    std::filesystem::copy_file(folder + "textured_quad.bin", dir.file("textured_quad.bin"));
    const Scene without_image = loadGltf(dir.file("quad.gltf"));
    EXPECT_EQ(without_image.source_files, (std::vector<std::string>{dir.file("quad.gltf"), dir.file("textured_quad.bin")}));
}

}  // namespace
}  // namespace sharcbake
