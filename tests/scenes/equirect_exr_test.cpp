// SPDX-License-Identifier: Apache-2.0
/// @file equirect_exr_test.cpp
/// @brief loadEquirectExr on EXR files written here with OpenEXR.
#include "gltf_builder.h"

#include "sharcbake/scene_loader.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfOutputFile.h>
#include <half.h>

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

namespace sharcbake {
namespace {

using test::TempDir;

/// Writes float channels named in `names` from interleaved `values` (names.size() per pixel).
void writeExr(const std::string& path, int width, int height, const std::vector<std::string>& names,
              const std::vector<float>& values) {
    Imf::Header header(width, height);
    for (const std::string& n : names) header.channels().insert(n, Imf::Channel(Imf::FLOAT));
    const size_t n = names.size();
    Imf::FrameBuffer fb;
    for (size_t c = 0; c < n; ++c)
        fb.insert(names[c], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(const_cast<float*>(values.data() + c)),
                                       sizeof(float) * n, sizeof(float) * n * width));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(fb);
    file.writePixels(height);
}

TEST(EquirectExr, RgbaFloatTexelsAndWrapModes) {
    TempDir dir;
    const std::string path = dir.file("sky.exr");
    // 2x2: row 0 (top) = (1,2,3,1), (4,5,6,0.5); row 1 = (0.25,0,0,1), (10,20,30,1)
    writeExr(path, 2, 2, {"R", "G", "B", "A"},
             {1, 2, 3, 1, 4, 5, 6, 0.5f, 0.25f, 0, 0, 1, 10, 20, 30, 1});
    const Texture t = loadEquirectExr(path);
    ASSERT_EQ(t.width, 2);
    ASSERT_EQ(t.height, 2);
    EXPECT_EQ(t.texels[0], glm::vec4(1, 2, 3, 1));
    EXPECT_EQ(t.texels[1], glm::vec4(4, 5, 6, 0.5f));
    EXPECT_EQ(t.texels[2], glm::vec4(0.25f, 0, 0, 1));
    EXPECT_EQ(t.texels[3], glm::vec4(10, 20, 30, 1));
    EXPECT_EQ(t.wrap_s, WrapMode::Repeat);       // longitude wraps
    EXPECT_EQ(t.wrap_t, WrapMode::ClampToEdge);  // latitude stops at the poles
    EXPECT_EQ(t.name, "sky.exr");
}

TEST(EquirectExr, HalfRgbWithoutAlpha) {
    TempDir dir;
    const std::string path = dir.file("half.exr");
    // Half channels (what most HDRIs use): the loader asks OpenEXR for float slices.
    const std::vector<half> rgb = {half(0.5f), half(2.0f), half(1024.0f)};
    Imf::Header header(1, 1);
    Imf::FrameBuffer fb;
    for (int c = 0; c < 3; ++c) {
        const char* name[] = {"R", "G", "B"};
        header.channels().insert(name[c], Imf::Channel(Imf::HALF));
        fb.insert(name[c], Imf::Slice(Imf::HALF, reinterpret_cast<char*>(const_cast<half*>(&rgb[c])),
                                       3 * sizeof(half), 3 * sizeof(half)));
    }
    {
        Imf::OutputFile file(path.c_str(), header);
        file.setFrameBuffer(fb);
        file.writePixels(1);
    }
    const Texture t = loadEquirectExr(path);
    EXPECT_EQ(t.texels.at(0), glm::vec4(0.5f, 2.0f, 1024.0f, 1.0f));
}

TEST(EquirectExr, LuminanceOnlyBecomesGrey) {
    TempDir dir;
    const std::string path = dir.file("grey.exr");
    writeExr(path, 2, 1, {"Y"}, {0.75f, 3.0f});
    const Texture t = loadEquirectExr(path);
    EXPECT_EQ(t.texels.at(0), glm::vec4(0.75f, 0.75f, 0.75f, 1.0f));
    EXPECT_EQ(t.texels.at(1), glm::vec4(3.0f, 3.0f, 3.0f, 1.0f));
}

TEST(EquirectExr, MissingFileNamesFile) {
    TempDir dir;
    try {
        loadEquirectExr(dir.file("absent.exr"));
        FAIL() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("absent.exr"), std::string::npos) << e.what();
    }
}

TEST(EquirectExr, NotAnExrFile) {
    TempDir dir;
    const std::string path = dir.file("fake.exr");
    test::writeFile(path, "this is not an EXR");
    EXPECT_THROW(loadEquirectExr(path), SceneLoadError);
}

TEST(EquirectExr, NoColourChannelsIsAnError) {
    TempDir dir;
    const std::string path = dir.file("depth.exr");
    writeExr(path, 1, 1, {"Z"}, {1.0f});
    try {
        loadEquirectExr(path);
        FAIL() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        EXPECT_NE(std::string(e.what()).find("Z"), std::string::npos) << e.what();
    }
}

// A damaged map is refused before OpenEXR allocates what its header claims (an attribute larger
// than the file; a window of 2^28 texels in a file of one): as a SceneLoadError naming the file.
TEST(EquirectExr, HeaderThatClaimsMoreThanTheFileIsRefusedAtOnce) {
    TempDir dir;
    const std::string path = dir.file("sky.exr");
    writeExr(path, 1, 1, {"R", "G", "B"}, {1.0f, 1.0f, 1.0f});
    std::ifstream in(path, std::ios::binary);
    const std::vector<char> whole((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    auto patched = [&](const std::string& attribute, size_t offset, int32_t value) {
        std::vector<char> bytes = whole;
        const auto at = std::search(bytes.begin(), bytes.end(), attribute.begin(), attribute.end());
        EXPECT_NE(at, bytes.end()) << attribute;
        std::memcpy(&*at + attribute.size() + offset, &value, 4);  // little-endian, as on this machine
        const std::string damaged = dir.file("damaged.exr");
        test::writeFile(damaged, bytes.data(), bytes.size());
        try {
            loadEquirectExr(damaged);
        } catch (const SceneLoadError& e) {
            EXPECT_NE(std::string(e.what()).find(damaged), std::string::npos) << e.what();
            return std::string(e.what());
        }
        ADD_FAILURE() << "expected SceneLoadError";
        return std::string();
    };
    const std::string compression("compression\0compression\0", 24);
    EXPECT_NE(patched(compression, 0, 1 << 30).find("header attribute 'compression' (compression) claims 1073741824"),
              std::string::npos);
    const std::string window("dataWindow\0box2i\0", 17);
    const std::string refused = patched(window, 4 + 12, 1 << 28);  // max.y
    EXPECT_NE(refused.find("1x268435457 is more pixels than sharcbake reads"), std::string::npos) << refused;
}

// Texels are read in strips of rows (256 at this width): a 3 x 600 map reads back exactly across
// the seams, with A = 1 where the file has none.
TEST(EquirectExr, MapOfSeveralStripsReadsBackExactly) {
    TempDir dir;
    const std::string path = dir.file("tall.exr");
    const int width = 3, height = 600;
    std::vector<float> values(size_t(width) * height * 3);
    for (size_t i = 0; i < values.size(); ++i) values[i] = float(i) * 0.5f;
    writeExr(path, width, height, {"R", "G", "B"}, values);
    const Texture t = loadEquirectExr(path);
    ASSERT_EQ(t.texels.size(), size_t(width) * height);
    for (size_t i = 0; i < t.texels.size(); ++i) {
        ASSERT_EQ(t.texels[i], glm::vec4(values[3 * i], values[3 * i + 1], values[3 * i + 2], 1.0f)) << i;
    }
}

// A map that claims 16 rows of 2^20 texels (within what is read), holds one and has its chunk's
// compressed bytes damaged fails at its first row: texels are allocated as their rows decode, not
// 256 MiB up front.
TEST(EquirectExr, MapThatClaimsMoreTexelsThanItHoldsFailsBeforeTheyAreAllocated) {
    TempDir dir;
    const std::string path = dir.file("sky.exr");
    writeExr(path, 1, 1, {"R", "G", "B"}, {1.0f, 1.0f, 1.0f});
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string window("dataWindow\0box2i\0", 17);
    const auto at = std::search(bytes.begin(), bytes.end(), window.begin(), window.end());
    ASSERT_NE(at, bytes.end());
    const int32_t max_xy[2] = {(1 << 20) - 1, 15};  // little-endian, as on this machine
    std::memcpy(&*at + window.size() + 4 + 8, max_xy, sizeof(max_xy));
    std::fill(bytes.end() - 8, bytes.end(), char(0xa5));  // the chunk's last compressed bytes
    const std::string damaged = dir.file("damaged.exr");
    test::writeFile(damaged, bytes.data(), bytes.size());
    rusage before{};
    getrusage(RUSAGE_SELF, &before);
    EXPECT_THROW(loadEquirectExr(damaged), SceneLoadError);
    rusage after{};
    getrusage(RUSAGE_SELF, &after);
    EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 128 * 1024) << "kilobytes: the whole map was allocated";
}

TEST(EquirectExr, NonFiniteRadianceIsAnError) {
    TempDir dir;
    const std::string path = dir.file("inf.exr");
    writeExr(path, 1, 1, {"R", "G", "B"}, {1.0f, std::numeric_limits<float>::infinity(), 0.0f});
    EXPECT_THROW(loadEquirectExr(path), SceneLoadError);
}

}  // namespace
}  // namespace sharcbake
