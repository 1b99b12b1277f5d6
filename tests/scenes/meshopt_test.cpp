// SPDX-License-Identifier: Apache-2.0
// EXT_meshopt_compression (gltfpack's compression): bufferViews compressed here with
// meshoptimizer's own encoders, written the way gltfpack writes them (the compressed bytes in one
// buffer, a "fallback" buffer without data that the views claim to live in), and loaded back.
// tests/scenes/meshopt_gltfpack.sh loads files gltfpack itself wrote.
#include "gltf_builder.h"
#include "load_expectations.h"

#include "sharcbake/scene_loader.h"

#include <gtest/gtest.h>
#include <meshoptimizer.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

using nlohmann::json;
using test::GltfBuilder;
using test::TempDir;

/// Two triangles of a unit quad at z = 3: positions as 16-byte float4 (stride 16), indices as
/// u16 triangles, both meshopt-compressed into buffer 0; buffer 1 is the fallback, without data.
GltfBuilder compressedQuad(std::vector<uint8_t>* vertex_stream = nullptr) {
    const float positions[4][4] = {{0, 0, 3, 0}, {1, 0, 3, 0}, {1, 1, 3, 0}, {0, 1, 3, 0}};
    const unsigned int triangles[6] = {0, 1, 2, 0, 2, 3};
    std::vector<uint8_t> vertices(meshopt_encodeVertexBufferBound(4, 16));
    vertices.resize(meshopt_encodeVertexBuffer(vertices.data(), vertices.size(), positions, 4, 16));
    std::vector<uint8_t> indices(meshopt_encodeIndexBufferBound(6, 4));
    indices.resize(meshopt_encodeIndexBuffer(indices.data(), indices.size(), triangles, 6));
    if (vertex_stream) *vertex_stream = vertices;

    GltfBuilder b;
    const int vertex_view = b.addView(vertices.data(), vertices.size());
    const int index_view = b.addView(indices.data(), indices.size());
    // The views as gltfpack writes them: in the fallback buffer, with the compressed bytes
    // described by the extension.
    json& views = b.doc["bufferViews"];
    const auto compressed = [&](int view, size_t length, int stride, int count, const char* mode) {
        json ext = {{"buffer", 0},
                    {"byteOffset", views[size_t(view)]["byteOffset"]},
                    {"byteLength", views[size_t(view)]["byteLength"]},
                    {"byteStride", stride},
                    {"count", count},
                    {"mode", mode}};
        views[size_t(view)] = {{"buffer", 1},
                               {"byteOffset", 0},
                               {"byteLength", length},
                               {"extensions", {{"EXT_meshopt_compression", ext}}}};
        if (std::string(mode) == "ATTRIBUTES") views[size_t(view)]["byteStride"] = stride;
    };
    compressed(vertex_view, 64, 16, 4, "ATTRIBUTES");
    compressed(index_view, 12, 2, 6, "TRIANGLES");
    const int position = b.addAccessor(vertex_view, test::kFloat, 4, "VEC3");
    b.doc["accessors"][size_t(position)]["min"] = {0, 0, 3};
    b.doc["accessors"][size_t(position)]["max"] = {1, 1, 3};
    const int index = b.addAccessor(index_view, test::kUnsignedShort, 6, "SCALAR");
    b.setScene({b.addMeshNode({{"attributes", {{"POSITION", position}}}, {"indices", index}})});
    b.doc["extensionsUsed"] = {"EXT_meshopt_compression"};
    b.doc["extensionsRequired"] = {"EXT_meshopt_compression"};
    return b;
}

/// Writes the builder's document with its binary as buffer 0 and a fallback buffer 1.
std::string writeWithFallback(const GltfBuilder& b, const TempDir& dir, const std::string& name, bool glb) {
    const GltfBuilder& copy = b;
    json fallback = {{"byteLength", 76}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}};
    if (glb) {
        const std::string path = copy.writeGlb(dir, name);
        // writeGlb wrote one buffer, the binary chunk: add the fallback to its JSON chunk.
        std::ifstream in(path, std::ios::binary);
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        uint32_t json_size = 0;
        std::memcpy(&json_size, bytes.data() + 12, 4);
        json doc = json::parse(bytes.substr(20, json_size));
        doc["buffers"].push_back(fallback);
        std::string text = doc.dump();
        while (text.size() % 4 != 0) text += ' ';
        const std::string rest = bytes.substr(20 + json_size);
        std::string out = bytes.substr(0, 20);
        const uint32_t total = uint32_t(20 + text.size() + rest.size()), chunk = uint32_t(text.size());
        std::memcpy(out.data() + 8, &total, 4);
        std::memcpy(out.data() + 12, &chunk, 4);
        test::writeFile(path, out + text + rest);
        return path;
    }
    json d = copy.doc;
    d["buffers"] = json::array(
        {{{"byteLength", copy.bin.size()}, {"uri", "data:application/octet-stream;base64," + test::base64(copy.bin)}},
         fallback});
    const std::string path = dir.file(name);
    test::writeFile(path, d.dump(2));
    return path;
}

void expectQuad(const Scene& scene) {
    ASSERT_EQ(scene.triangles.size(), 2u);
    for (const glm::vec3& p : scene.positions) {
        EXPECT_EQ(p.z, 3.0f);
        EXPECT_TRUE(p.x == 0.0f || p.x == 1.0f);
        EXPECT_TRUE(p.y == 0.0f || p.y == 1.0f);
    }
    EXPECT_EQ(scene.bounds_min, glm::vec3(0, 0, 3));
    EXPECT_EQ(scene.bounds_max, glm::vec3(1, 1, 3));
}

TEST(Meshopt, CompressedViewsLoadFromGltfAndGlb) {
    TempDir dir;
    const GltfBuilder b = compressedQuad();
    expectQuad(loadGltf(writeWithFallback(b, dir, "quad.gltf", false)));
    const Scene glb = loadGltf(writeWithFallback(b, dir, "quad.glb", true));
    expectQuad(glb);
    ASSERT_FALSE(glb.source_files.empty());
    EXPECT_NE(glb.source_files[0].find("quad.glb"), std::string::npos);
}

// Corrupted files: 300 random mutations of the compressed bytes each load or are refused with a
// SceneLoadError; nothing else escapes, nothing crashes (meshoptimizer's decoders are written for
// untrusted input; this checks the loader around them).
TEST(Meshopt, MutatedDataLoadsOrIsRefusedCleanly) {
    TempDir dir;
    std::mt19937 rng(13);
    int refused = 0;
    for (int i = 0; i < 300; ++i) {
        GltfBuilder b = compressedQuad();
        const int changes = 1 << (rng() % 5);
        for (int c = 0; c < changes; ++c) b.bin[rng() % b.bin.size()] = uint8_t(rng());
        try {
            loadGltf(writeWithFallback(b, dir, "mutated.glb", true));
        } catch (const SceneLoadError&) {
            ++refused;
        }
    }
    EXPECT_GT(refused, 0);
}

TEST(Meshopt, CorruptOrImpossibleViewsAreRefusedNamingTheView) {
    TempDir dir;
    const auto errorOf = [&](GltfBuilder b, const std::string& name) {
        try {
            loadGltf(writeWithFallback(b, dir, name, false));
        } catch (const SceneLoadError& e) {
            return std::string(e.what());
        }
        ADD_FAILURE() << "expected SceneLoadError for " << name;
        return std::string();
    };
    GltfBuilder corrupt = compressedQuad();
    for (size_t i = 1; i < 8; ++i) corrupt.bin[i] ^= 0x5A;
    const std::string corrupted = errorOf(corrupt, "corrupt.gltf");
    EXPECT_NE(corrupted.find("bufferView 0 EXT_meshopt_compression: meshoptimizer could not decode it"),
              std::string::npos)
        << corrupted;

    GltfBuilder huge = compressedQuad();
    huge.doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = 4000000000u;
    const std::string too_big = errorOf(huge, "huge.gltf");
    EXPECT_NE(too_big.find("is not a valid size"), std::string::npos) << too_big;

    GltfBuilder mode = compressedQuad();
    mode.doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["mode"] = "VERTICES";
    const std::string unknown_mode = errorOf(mode, "mode.gltf");
    EXPECT_NE(unknown_mode.find("unknown mode"), std::string::npos) << unknown_mode;
    EXPECT_NE(unknown_mode.find("VERTICES"), std::string::npos) << unknown_mode;

    GltfBuilder filter = compressedQuad();
    filter.doc["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["filter"] = "QUATERNION";  // stride 16
    EXPECT_NE(errorOf(filter, "filter.gltf").find("is not one EXT_meshopt_compression defines"), std::string::npos);

    GltfBuilder outside = compressedQuad();
    outside.doc["bufferViews"][1]["extensions"]["EXT_meshopt_compression"]["byteOffset"] = 100000;
    EXPECT_NE(errorOf(outside, "outside.gltf").find("missing or short buffer"), std::string::npos);
}

// The compressed bytes in an external .bin (gltfpack without -c embedding): the loader reads that
// buffer itself, before tinygltf, so its missing file is reported by the loader's own path, in the
// words and with the kind tinygltf's path uses (the command exits 2, a file not there).
TEST(Meshopt, ExternalCompressedBufferLoadsAndItsMissingFileIsNamed) {
    TempDir dir;
    const GltfBuilder b = compressedQuad();
    json d = b.doc;
    d["buffers"] = json::array(
        {{{"byteLength", b.bin.size()}, {"uri", "quad packed.bin"}},
         {{"byteLength", 76}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}}});
    const std::string path = dir.file("external.gltf");
    test::writeFile(path, d.dump(2));
    test::writeFile(dir.file("quad packed.bin"), b.bin.data(), b.bin.size());
    d["buffers"][0]["uri"] = "quad%20packed.bin";  // a URI's percent-encoding names the same file
    const std::string encoded = dir.file("encoded.gltf");
    test::writeFile(encoded, d.dump(2));
    for (const std::string& file : {path, encoded}) {
        const Scene scene = loadGltf(file);
        expectQuad(scene);
        EXPECT_EQ(scene.source_files.size(), 2u);  // the .gltf and the buffer it read
    }

    std::filesystem::remove(dir.file("quad packed.bin"));
    test::expectMissingBuffer(path, "quad packed.bin");
}

}  // namespace
}  // namespace sharcbake
