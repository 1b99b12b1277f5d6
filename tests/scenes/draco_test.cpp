// SPDX-License-Identifier: Apache-2.0
// KHR_draco_mesh_compression: meshes compressed here with Draco's own encoder, written into
// glTF and GLB files the way exporters write them (accessors without bufferViews, indices in the
// Draco data), and loaded back through the public API.
#include "gltf_builder.h"

#include "sharcbake/scene_loader.h"

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

using nlohmann::json;
using test::GltfBuilder;
using test::TempDir;

/// A unit quad in z = 0 as two triangles, with normals +Z and UVs = (x, y).
struct DracoQuad {
    std::vector<uint8_t> bytes;
    int position_id = -1, normal_id = -1, uv_id = -1;
    int points = 0;
};

DracoQuad encodeQuad(int position_bits) {
    const std::array<std::array<float, 3>, 6> corners = {
        {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
    draco::TriangleSoupMeshBuilder builder;
    builder.Start(2);
    DracoQuad quad;
    quad.position_id = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    quad.normal_id = builder.AddAttribute(draco::GeometryAttribute::NORMAL, 3, draco::DT_FLOAT32);
    quad.uv_id = builder.AddAttribute(draco::GeometryAttribute::TEX_COORD, 2, draco::DT_FLOAT32);
    const float normal[3] = {0, 0, 1};
    for (int f = 0; f < 2; ++f) {
        const auto& a = corners[size_t(3 * f)];
        const auto& b = corners[size_t(3 * f + 1)];
        const auto& c = corners[size_t(3 * f + 2)];
        builder.SetAttributeValuesForFace(quad.position_id, draco::FaceIndex(f), a.data(), b.data(), c.data());
        builder.SetAttributeValuesForFace(quad.normal_id, draco::FaceIndex(f), normal, normal, normal);
        builder.SetAttributeValuesForFace(quad.uv_id, draco::FaceIndex(f), a.data(), b.data(), c.data());
    }
    std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
    EXPECT_TRUE(mesh);
    quad.points = int(mesh->num_points());
    // What the attribute ids become in the file: Draco's unique ids.
    quad.position_id = int(mesh->attribute(quad.position_id)->unique_id());
    quad.normal_id = int(mesh->attribute(quad.normal_id)->unique_id());
    quad.uv_id = int(mesh->attribute(quad.uv_id)->unique_id());
    draco::Encoder encoder;
    encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, position_bits);
    encoder.SetAttributeQuantization(draco::GeometryAttribute::TEX_COORD, 12);
    draco::EncoderBuffer buffer;
    const draco::Status status = encoder.EncodeMeshToBuffer(*mesh, &buffer);
    EXPECT_TRUE(status.ok()) << status.error_msg_string();
    quad.bytes.assign(buffer.data(), buffer.data() + buffer.size());
    return quad;
}

/// The quad as an exporter writes it: accessors with counts and types but no bufferView (their
/// data is in the Draco bufferView), an indices accessor likewise, the extension naming the ids.
GltfBuilder dracoQuadFile(const DracoQuad& quad, bool required, std::vector<uint8_t> bytes = {}) {
    if (bytes.empty()) bytes = quad.bytes;
    GltfBuilder b;
    const int view = b.addView(bytes.data(), bytes.size());
    const auto accessor = [&](const char* type, int component, int count) {
        b.doc["accessors"].push_back({{"componentType", component}, {"count", count}, {"type", type}});
        return int(b.doc["accessors"].size()) - 1;
    };
    const int position = accessor("VEC3", test::kFloat, quad.points);
    b.doc["accessors"][size_t(position)]["min"] = {0, 0, 0};
    b.doc["accessors"][size_t(position)]["max"] = {1, 1, 0};
    const json prim = {
        {"attributes",
         {{"POSITION", position},
          {"NORMAL", accessor("VEC3", test::kFloat, quad.points)},
          {"TEXCOORD_0", accessor("VEC2", test::kFloat, quad.points)}}},
        {"indices", accessor("SCALAR", test::kUnsignedShort, 6)},
        {"mode", 4},
        {"extensions",
         {{"KHR_draco_mesh_compression",
           {{"bufferView", view},
            {"attributes",
             {{"POSITION", quad.position_id}, {"NORMAL", quad.normal_id}, {"TEXCOORD_0", quad.uv_id}}}}}}}};
    b.setScene({b.addMeshNode(prim, {{"translation", {0, 0, 2}}})});
    b.doc["extensionsUsed"] = {"KHR_draco_mesh_compression"};
    if (required) b.doc["extensionsRequired"] = {"KHR_draco_mesh_compression"};
    return b;
}

void expectQuad(const Scene& scene, float tolerance) {
    ASSERT_EQ(scene.triangles.size(), 2u);
    float area = 0.0f;
    for (const glm::uvec3& t : scene.triangles) {
        const glm::vec3 a = scene.positions[t.x], b = scene.positions[t.y], c = scene.positions[t.z];
        const glm::vec3 n = glm::cross(b - a, c - a);
        EXPECT_GT(n.z, 0.0f) << "counter-clockwise seen from +Z";
        area += 0.5f * glm::length(n);
        for (uint32_t v : {t.x, t.y, t.z}) {
            const glm::vec3 p = scene.positions[v];
            EXPECT_NEAR(p.z, 2.0f, tolerance);  // the node's translation applies
            EXPECT_TRUE(std::abs(p.x) < tolerance || std::abs(p.x - 1) < tolerance) << p.x;
            EXPECT_TRUE(std::abs(p.y) < tolerance || std::abs(p.y - 1) < tolerance) << p.y;
            EXPECT_NEAR(scene.normals[v].z, 1.0f, 1e-3f);
            ASSERT_EQ(scene.texcoords0.size(), scene.positions.size());
            EXPECT_NEAR(scene.texcoords0[v].x, p.x, 1e-3f);  // UV = (x, y) survived the compression
            EXPECT_NEAR(scene.texcoords0[v].y, p.y, 1e-3f);
        }
    }
    EXPECT_NEAR(area, 1.0f, 4 * tolerance);
}

TEST(Draco, CompressedQuadLoadsFromGltfAndGlb) {
    TempDir dir;
    const DracoQuad quad = encodeQuad(14);
    const GltfBuilder b = dracoQuadFile(quad, true);
    const Scene gltf = loadGltf(b.writeEmbedded(dir, "draco.gltf"));
    expectQuad(gltf, 1e-3f);
    const Scene glb = loadGltf(b.writeGlb(dir, "draco.glb"));
    expectQuad(glb, 1e-3f);
    for (const std::string& w : glb.stats.warnings) EXPECT_EQ(w.find("KHR_draco"), std::string::npos) << w;
    // The file read is recorded as the scene's source, as for any other file.
    ASSERT_FALSE(glb.source_files.empty());
    EXPECT_NE(glb.source_files[0].find("draco.glb"), std::string::npos);
}

TEST(Draco, ExternalBufferBesideTheFileLoads) {
    TempDir dir;
    const GltfBuilder b = dracoQuadFile(encodeQuad(11), false);
    expectQuad(loadGltf(b.writeExternal(dir, "draco_external.gltf", "draco.bin")), 2e-3f);
}

TEST(Draco, CorruptDataIsRefusedNamingThePrimitive) {
    TempDir dir;
    const DracoQuad quad = encodeQuad(14);
    std::vector<uint8_t> corrupt = quad.bytes;
    for (size_t i = 8; i < corrupt.size(); ++i) corrupt[i] = uint8_t(corrupt[i] * 131 + 7);
    const GltfBuilder b = dracoQuadFile(quad, true, corrupt);
    try {
        loadGltf(b.writeEmbedded(dir, "corrupt.gltf"));
        ADD_FAILURE() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find("corrupt.gltf"), std::string::npos) << msg;
        EXPECT_NE(msg.find("primitive 0 KHR_draco_mesh_compression"), std::string::npos) << msg;
    }
}

// Corrupted files: 300 random mutations of the Draco bytes (1 to 32 bytes changed, or the tail
// zeroed) each load or are refused with a SceneLoadError; nothing else escapes, nothing crashes.
TEST(Draco, MutatedDataLoadsOrIsRefusedCleanly) {
    TempDir dir;
    const DracoQuad quad = encodeQuad(14);
    std::mt19937 rng(11);
    int refused = 0;
    for (int i = 0; i < 300; ++i) {
        std::vector<uint8_t> bytes = quad.bytes;
        const int changes = 1 << (rng() % 6);
        for (int c = 0; c < changes; ++c) bytes[rng() % bytes.size()] = uint8_t(rng());
        if (rng() % 10 == 0) std::fill(bytes.begin() + std::ptrdiff_t(rng() % bytes.size()), bytes.end(), uint8_t(0));
        const GltfBuilder b = dracoQuadFile(quad, true, bytes);
        try {
            const Scene scene = loadGltf(b.writeGlb(dir, "mutated.glb"));
            for (const glm::vec3& p : scene.positions)
                ASSERT_TRUE(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z));
        } catch (const SceneLoadError&) {
            ++refused;
        }
    }
    EXPECT_GT(refused, 0);
}

TEST(Draco, AnAttributeIdTheDataLacksIsRefused) {
    TempDir dir;
    DracoQuad quad = encodeQuad(14);
    quad.normal_id = 17;
    const GltfBuilder b = dracoQuadFile(quad, true);
    try {
        loadGltf(b.writeEmbedded(dir, "missing_attribute.gltf"));
        ADD_FAILURE() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("NORMAL names Draco attribute 17"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace sharcbake
