// SPDX-License-Identifier: Apache-2.0
// EXT_texture_webp: images encoded here with libwebp's encoder (lossless, so the texels are
// known exactly) and referenced the ways exporters do: with a PNG fallback in `source`, and
// WebP only (the extension required).
#include "gltf_builder.h"
#include "png_bytes.h"

#include "sharcbake/scene_loader.h"

#include <gtest/gtest.h>
#include <webp/encode.h>

#include <cmath>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

using nlohmann::json;
using test::GltfBuilder;
using test::TempDir;

std::vector<uint8_t> webp(const std::vector<uint8_t>& rgba, int width, int height) {
    uint8_t* out = nullptr;
    const size_t size = WebPEncodeLosslessRGBA(rgba.data(), width, height, width * 4, &out);
    std::vector<uint8_t> bytes(out, out + size);
    WebPFree(out);
    return bytes;
}

/// An image: its bytes and MIME type, stored in a bufferView (as in a GLB) or in a file beside
/// the scene (as a .gltf exporter writes it).
struct ImageData {
    std::vector<uint8_t> bytes;
    const char* mime;
};

/// A triangle whose material's base colour texture is texture 0, over the given images.
Scene loadTextured(const TempDir& dir, const std::vector<ImageData>& images, const json& texture, bool required,
                   bool external = false) {
    GltfBuilder b;
    for (size_t i = 0; i < images.size(); ++i) {
        if (external) {
            const std::string name = "image" + std::to_string(i) +
                                     (std::string(images[i].mime) == "image/webp" ? ".webp" : ".png");
            test::writeFile(dir.file(name), images[i].bytes.data(), images[i].bytes.size());
            b.doc["images"].push_back({{"uri", name}});
        } else {
            b.doc["images"].push_back({{"bufferView", b.addView(images[i].bytes.data(), images[i].bytes.size())},
                                       {"mimeType", images[i].mime}});
        }
    }
    b.doc["textures"] = json::array({texture});
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int uv = b.addData(std::vector<float>{0, 0, 1, 0, 0, 1}, test::kFloat, "VEC2");
    const int material = b.addMaterial({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    b.setScene({b.addMeshNode({{"attributes", {{"POSITION", pos}, {"TEXCOORD_0", uv}}}, {"material", material}})});
    b.doc["extensionsUsed"] = {"EXT_texture_webp"};
    if (required) b.doc["extensionsRequired"] = {"EXT_texture_webp"};
    return loadGltf(external ? b.writeExternal(dir, "webp.gltf", "webp.bin") : b.writeGlb(dir, "webp.glb"));
}

TEST(Webp, TheWebpImageIsReadAndTheFallbackIgnored) {
    TempDir dir;
    // 2x1: linear-exact texels (0 and 255 map to 0 and 1 through sRGB) and an alpha.
    const std::vector<uint8_t> texels = {255, 0, 0, 255, 0, 0, 255, 128};
    const std::vector<uint8_t> grey = {128, 128, 128, 255, 128, 128, 128, 255};
    const std::vector<ImageData> images = {{test::png(2, 1, grey), "image/png"}, {webp(texels, 2, 1), "image/webp"}};
    for (const bool external : {false, true}) {
        const Scene scene = loadTextured(dir, images,
                                         {{"source", 0}, {"extensions", {{"EXT_texture_webp", {{"source", 1}}}}}},
                                         false, external);
        const Material& m = scene.materials.at(0);
        ASSERT_TRUE(m.base_color_texture.isSet()) << (external ? "external" : "GLB");
        const Texture& t = scene.textures.at(size_t(m.base_color_texture.texture));
        ASSERT_EQ(t.width, 2);
        ASSERT_EQ(t.height, 1);
        EXPECT_EQ(t.texel(0), glm::vec4(1, 0, 0, 1));
        EXPECT_EQ(glm::vec3(t.texel(1)), glm::vec3(0, 0, 1));
        EXPECT_NEAR(t.texel(1).a, 128 / 255.0f, 1e-6f);  // alpha stays linear
        for (const std::string& w : scene.stats.warnings) EXPECT_EQ(w.find("image"), std::string::npos) << w;
    }
}

TEST(Webp, DataUriOfTypeWebpIsRead) {
    // tinygltf refuses the type image/webp in a data: URI; the loader reads the bytes by content.
    TempDir dir;
    const std::vector<uint8_t> texels = {255, 0, 0, 255, 0, 0, 255, 128};
    GltfBuilder b;
    b.doc["images"] = json::array({{{"uri", "data:image/webp;base64," + test::base64(webp(texels, 2, 1))}}});
    b.doc["textures"] = json::array({{{"extensions", {{"EXT_texture_webp", {{"source", 0}}}}}}});
    const int pos = b.addPositions({0, 0, 0, 1, 0, 0, 0, 1, 0});
    const int material = b.addMaterial({{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}});
    b.setScene({b.addMeshNode({{"attributes", {{"POSITION", pos}}}, {"material", material}})});
    b.doc["extensionsUsed"] = {"EXT_texture_webp"};
    b.doc["extensionsRequired"] = {"EXT_texture_webp"};
    const Scene scene = loadGltf(b.writeEmbedded(dir, "webp_data_uri.gltf"));
    const Material& m = scene.materials.at(0);
    ASSERT_TRUE(m.base_color_texture.isSet());
    const Texture& t = scene.textures.at(size_t(m.base_color_texture.texture));
    ASSERT_EQ(t.width, 2);
    EXPECT_EQ(t.texel(0), glm::vec4(1, 0, 0, 1));
    EXPECT_NEAR(t.texel(1).a, 128 / 255.0f, 1e-6f);
}

TEST(Webp, WebpOnlyRequiredLoadsAndOversizeIsRefusedBeforeDecoding) {
    TempDir dir;
    const std::vector<uint8_t> texels(4 * 4 * 4, 255);
    const Scene scene = loadTextured(dir, {{webp(texels, 4, 4), "image/webp"}},
                                     {{"extensions", {{"EXT_texture_webp", {{"source", 0}}}}}}, true);
    ASSERT_TRUE(scene.materials.at(0).base_color_texture.isSet());
    EXPECT_EQ(scene.textures.at(size_t(scene.materials.at(0).base_color_texture.texture)).width, 4);

    // 9000 x 1 texels: above the default limit of 8192 per side, refused from the header.
    const std::vector<uint8_t> wide(9000 * 4, 200);
    try {
        loadTextured(dir, {{webp(wide, 9000, 1), "image/webp"}},
                     {{"extensions", {{"EXT_texture_webp", {{"source", 0}}}}}}, true);
        ADD_FAILURE() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("9000x1 texels, above the limit"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace sharcbake
