// SPDX-License-Identifier: Apache-2.0
// Image I/O: EXR round trips (exact floats, metadata, layout), EXRs written directly with
// OpenEXR (half, data-window offset, missing channels, Y-only, luminance/chroma), error paths
// (unwritable, missing, corrupt, no temporary left behind), PNG previews and tone mapping.
#include "sharcbake/image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfStringAttribute.h>
#include <half.h>
#include <stb_image.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

namespace sharcbake {
namespace {

namespace fs = std::filesystem;

class ImageTest : public ::testing::Test {
protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("sharcbake_image_test_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    std::string file(const std::string& name) const { return (dir_ / name).string(); }

    /// Names of the entries in the test folder.
    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
        return names;
    }

    bool anyTemporaryLeft() const {
        for (const std::string& name : entries()) {
            if (name.find(".tmp-") != std::string::npos) return true;
        }
        return false;
    }

    fs::path dir_;
};

uint32_t bits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}

std::vector<unsigned char> readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::string& path, const void* data, size_t size) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(static_cast<const char*>(data), std::streamsize(size));
}

/// Runs @p fn, expects ImageError, returns its message.
template <typename Fn>
std::string imageErrorOf(Fn&& fn) {
    try {
        fn();
    } catch (const ImageError& e) {
        return e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "expected ImageError, got another exception: " << e.what();
        return {};
    }
    ADD_FAILURE() << "expected ImageError, nothing was thrown";
    return {};
}

/// A w x h image whose every value is distinct and some are awkward floats.
Image patternImage(int w, int h) {
    Image image(w, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float base = float(y * w + x);
            image.at(x, y) = glm::vec3(base * 0.1f + 1e-3f, -base * 3.7f, std::ldexp(1.0f + base, 20 - (x + y) % 40));
        }
    }
    return image;
}

void expectBitwiseEqual(const Image& a, const Image& b) {
    ASSERT_EQ(a.width, b.width);
    ASSERT_EQ(a.height, b.height);
    ASSERT_EQ(a.pixels.size(), b.pixels.size());
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(bits(a.pixels[i][c]), bits(b.pixels[i][c])) << "pixel " << i << " channel " << c;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// EXR

TEST_F(ImageTest, ExrRoundTripIsExactAndKeepsMetadata) {
    Image image = patternImage(6, 6);
    image.at(0, 0) = glm::vec3(std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::max(),
                               std::numeric_limits<float>::lowest());
    image.at(1, 0) = glm::vec3(std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                               std::numeric_limits<float>::quiet_NaN());
    image.at(2, 0) = glm::vec3(-0.0f, 0.0f, 1.0f / 3.0f);
    const ImageMetadata metadata = {
        {"sharcbake:software", "sharcbake 0.1.0"},
        {"sharcbake:scene", "scenes/cornell_box/cornell_box.gltf"},
        {"sharcbake:integrator", "path tracer, NEE + MIS"},
        {"sharcbake:empty", ""},
        {"a_rather_long_attribute_name_beyond_31_characters", "caf\xc3\xa9 \xe2\x9c\x93"},
    };
    const std::string path = file("round_trip.exr");
    writeExr(path, image, metadata);

    ImageMetadata read_metadata = {{"stale", "entry"}};
    const Image back = readExr(path, &read_metadata);
    expectBitwiseEqual(image, back);
    EXPECT_EQ(read_metadata, metadata);  // exactly the string attributes of the file
    EXPECT_FALSE(anyTemporaryLeft());

    // The file itself: 32-bit float R, G, B, ZIP compression, metadata as string attributes.
    Imf::InputFile exr(path.c_str());
    EXPECT_EQ(exr.header().compression(), Imf::ZIP_COMPRESSION);
    int channel_count = 0;
    for (auto it = exr.header().channels().begin(); it != exr.header().channels().end(); ++it) {
        ++channel_count;
        EXPECT_EQ(it.channel().type, Imf::FLOAT) << it.name();
    }
    EXPECT_EQ(channel_count, 3);
    EXPECT_NE(exr.header().channels().findChannel("R"), nullptr);
    EXPECT_NE(exr.header().channels().findChannel("G"), nullptr);
    EXPECT_NE(exr.header().channels().findChannel("B"), nullptr);
    const auto* software = exr.header().findTypedAttribute<Imf::StringAttribute>("sharcbake:software");
    ASSERT_NE(software, nullptr);
    EXPECT_EQ(software->value(), "sharcbake 0.1.0");

    // Reading without metadata works too.
    expectBitwiseEqual(image, readExr(path));
}

TEST_F(ImageTest, ExrNonSquareKeepsRowZeroAtTheTop) {
    for (const auto& [w, h] : {std::pair{13, 2}, std::pair{1, 9}, std::pair{7, 1}}) {
        const Image image = patternImage(w, h);
        const std::string path = file("non_square_" + std::to_string(w) + "x" + std::to_string(h) + ".exr");
        writeExr(path, image);
        const Image back = readExr(path);
        expectBitwiseEqual(image, back);

        // Check the layout against OpenEXR directly: file row y (from the top) is image row y.
        Imf::InputFile exr(path.c_str());
        const Imath::Box2i dw = exr.header().dataWindow();
        EXPECT_EQ(dw.min.x, 0);
        EXPECT_EQ(dw.min.y, 0);
        EXPECT_EQ(dw.max.x, w - 1);
        EXPECT_EQ(dw.max.y, h - 1);
        std::vector<float> green(size_t(w) * size_t(h));
        Imf::FrameBuffer frame;
        frame.insert("G", Imf::Slice::Make(Imf::FLOAT, green.data(), dw));
        exr.setFrameBuffer(frame);
        exr.readPixels(dw.min.y, dw.max.y);
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                ASSERT_EQ(bits(green[size_t(y) * size_t(w) + size_t(x)]), bits(image.at(x, y).g)) << x << "," << y;
            }
        }
    }
}

TEST_F(ImageTest, ExrOverwritesAnExistingFile) {
    const std::string path = file("overwrite.exr");
    writeExr(path, patternImage(4, 4), {{"k", "first"}});
    const Image second = patternImage(3, 5);
    writeExr(path, second, {{"k", "second"}});
    ImageMetadata metadata;
    expectBitwiseEqual(second, readExr(path, &metadata));
    EXPECT_EQ(metadata.at("k"), "second");
    EXPECT_EQ(entries(), std::vector<std::string>{"overwrite.exr"});
}

TEST_F(ImageTest, ReadsHalfFloatExrWithDataWindowOffsetAndMissingChannel) {
    // Written with OpenEXR directly: HALF R and G, no B, data window not at the origin,
    // plus a non-string attribute that must not show up in the metadata.
    const std::string path = file("half.exr");
    const int w = 5, h = 3;
    const Imath::Box2i display(Imath::V2i(0, 0), Imath::V2i(19, 19));
    const Imath::Box2i data(Imath::V2i(3, -2), Imath::V2i(3 + w - 1, -2 + h - 1));
    std::vector<half> r(size_t(w) * h), g(size_t(w) * h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            r[size_t(y) * w + x] = half(float(x) + 0.5f * float(y));  // exactly representable
            g[size_t(y) * w + x] = half(-0.25f * float(x + 1) * float(y + 1));
        }
    }
    {
        Imf::Header header(display, data);
        header.compression() = Imf::PIZ_COMPRESSION;
        header.channels().insert("R", Imf::Channel(Imf::HALF));
        header.channels().insert("G", Imf::Channel(Imf::HALF));
        header.insert("owner", Imf::StringAttribute("test"));
        Imf::FrameBuffer frame;
        frame.insert("R", Imf::Slice::Make(Imf::HALF, r.data(), data));
        frame.insert("G", Imf::Slice::Make(Imf::HALF, g.data(), data));
        Imf::OutputFile out(path.c_str(), header);
        out.setFrameBuffer(frame);
        out.writePixels(h);
    }
    ImageMetadata metadata;
    const Image image = readExr(path, &metadata);
    ASSERT_EQ(image.width, w);
    ASSERT_EQ(image.height, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            EXPECT_EQ(image.at(x, y).r, float(x) + 0.5f * float(y)) << x << "," << y;
            EXPECT_EQ(image.at(x, y).g, -0.25f * float(x + 1) * float(y + 1)) << x << "," << y;
            EXPECT_EQ(bits(image.at(x, y).b), bits(0.0f)) << x << "," << y;
        }
    }
    EXPECT_EQ(metadata, (ImageMetadata{{"owner", "test"}}));
}

TEST_F(ImageTest, ReadsLuminanceOnlyExrAsGrey) {
    const std::string path = file("y.exr");
    const int w = 3, h = 2;
    const std::vector<float> y_values = {0.0f, 0.75f, 3.0f, 1e6f, -2.5f, 0.125f};
    {
        Imf::Header header(w, h);
        header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
        Imf::FrameBuffer frame;
        frame.insert("Y", Imf::Slice::Make(Imf::FLOAT, y_values.data(), header.dataWindow()));
        Imf::OutputFile out(path.c_str(), header);
        out.setFrameBuffer(frame);
        out.writePixels(h);
    }
    const Image image = readExr(path);
    ASSERT_EQ(image.width, w);
    ASSERT_EQ(image.height, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const float v = y_values[size_t(y) * w + x];
            EXPECT_EQ(image.at(x, y), glm::vec3(v)) << x << "," << y;
        }
    }
}

/// Writes a w x h float EXR with the given channels; channel k holds value(k) + pixel index.
void writeChannels(const std::string& path, int w, int h, const std::vector<std::string>& names) {
    Imf::Header header(w, h);
    std::vector<std::vector<float>> planes;
    for (size_t k = 0; k < names.size(); ++k) {
        header.channels().insert(names[k], Imf::Channel(Imf::FLOAT));
        planes.emplace_back(size_t(w) * h);
        for (size_t i = 0; i < planes.back().size(); ++i) planes.back()[i] = float(100 * (k + 1) + i);
    }
    Imf::FrameBuffer frame;
    for (size_t k = 0; k < names.size(); ++k) {
        frame.insert(names[k], Imf::Slice::Make(Imf::FLOAT, planes[k].data(), header.dataWindow()));
    }
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(h);
}

TEST_F(ImageTest, ReadsBlenderMultilayerExrFromItsCombinedPass) {
    // Blender's "OpenEXR MultiLayer": no plain R, G, B; the picture is "<view layer>.Combined".
    const std::string path = file("multilayer.exr");
    const std::vector<std::string> names = {"ViewLayer.Combined.A", "ViewLayer.Combined.B", "ViewLayer.Combined.G",
                                            "ViewLayer.Combined.R", "ViewLayer.Depth.Z",    "ViewLayer.Normal.X",
                                            "ViewLayer.DiffCol.R",  "ViewLayer.DiffCol.G",  "ViewLayer.DiffCol.B"};
    writeChannels(path, 3, 2, names);  // channel k holds 100 (k + 1) + pixel
    const Image image = readExr(path);
    ASSERT_EQ(image.width, 3);
    for (int i = 0; i < 6; ++i) {
        EXPECT_EQ(image.pixels[size_t(i)], glm::vec3(400.0f + i, 300.0f + i, 200.0f + i)) << i;  // R, G, B of Combined
    }
    // A single RGB layer of any name is the picture.
    writeChannels(path, 2, 2, {"beauty.B", "beauty.G", "beauty.R", "depth.Z"});
    EXPECT_EQ(readExr(path).pixels[1], glm::vec3(301.0f, 201.0f, 101.0f));
}

TEST_F(ImageTest, LayeredExrWithoutOnePictureIsRefusedNamingTheLayers) {
    const std::string path = file("ambiguous.exr");
    writeChannels(path, 2, 2, {"diffuse.R", "diffuse.G", "diffuse.B", "specular.R", "specular.G", "specular.B"});
    try {
        readExr(path);
        ADD_FAILURE() << "two RGB layers were read as one picture";
    } catch (const ImageError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("diffuse, specular"), std::string::npos) << message;
        EXPECT_NE(message.find(path), std::string::npos) << message;
    }
    writeChannels(path, 2, 2, {"Z", "alpha.A"});
    try {
        readExr(path);
        ADD_FAILURE() << "a depth-only file was read as a picture";
    } catch (const ImageError& e) {
        EXPECT_NE(std::string(e.what()).find("channels: Z, alpha.A"), std::string::npos) << e.what();
    }
}

TEST_F(ImageTest, ReadsLuminanceChromaExr) {
    // RgbaOutputFile with WRITE_YC stores Y, RY, BY (chroma sub-sampled); a grey image comes back grey.
    const std::string path = file("yc.exr");
    const int w = 8, h = 6;
    std::vector<Imf::Rgba> pixels(size_t(w) * h);
    for (int i = 0; i < w * h; ++i) pixels[size_t(i)] = Imf::Rgba(half(0.5f), half(0.5f), half(0.5f), half(1.0f));
    {
        Imf::RgbaOutputFile out(path.c_str(), w, h, Imf::WRITE_YC);
        out.setFrameBuffer(pixels.data(), 1, size_t(w));
        out.writePixels(h);
    }
    const Image image = readExr(path);
    ASSERT_EQ(image.width, w);
    ASSERT_EQ(image.height, h);
    for (const glm::vec3& p : image.pixels) {
        EXPECT_NEAR(p.r, 0.5f, 0.01f);
        EXPECT_NEAR(p.g, 0.5f, 0.01f);
        EXPECT_NEAR(p.b, 0.5f, 0.01f);
    }
}

TEST_F(ImageTest, WriteExrToMissingFolderThrowsNamingThePath) {
    const std::string path = file("no_such_folder/out.exr");
    const std::string message = imageErrorOf([&] { writeExr(path, patternImage(2, 2)); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_TRUE(entries().empty());
}

TEST_F(ImageTest, WriteExrOverAFolderThrowsAndLeavesNoTemporary) {
    // The temporary file can be created, the final rename cannot: the temporary must go.
    const std::string path = file("a_folder.exr");
    fs::create_directory(path);
    const std::string message = imageErrorOf([&] { writeExr(path, patternImage(2, 2)); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_FALSE(anyTemporaryLeft());
    EXPECT_EQ(entries(), std::vector<std::string>{"a_folder.exr"});
    EXPECT_TRUE(fs::is_directory(path));
}

TEST_F(ImageTest, WriteExrRejectsBadImagesAndMetadata) {
    const std::string path = file("bad.exr");
    EXPECT_NE(imageErrorOf([&] { writeExr(path, Image()); }).find(path), std::string::npos);
    Image inconsistent(3, 3);
    inconsistent.pixels.pop_back();
    EXPECT_NE(imageErrorOf([&] { writeExr(path, inconsistent); }).find(path), std::string::npos);
    // A name that is a standard header attribute would corrupt the file's own description.
    EXPECT_NE(imageErrorOf([&] { writeExr(path, patternImage(2, 2), {{"channels", "x"}}); }).find(path),
              std::string::npos);
    EXPECT_NE(imageErrorOf([&] { writeExr(path, patternImage(2, 2), {{"", "x"}}); }).find(path), std::string::npos);
    EXPECT_TRUE(entries().empty());
}

TEST_F(ImageTest, ReadingAMissingExrThrowsNamingThePath) {
    const std::string path = file("missing.exr");
    const std::string message = imageErrorOf([&] { readExr(path); });
    EXPECT_NE(message.find(path), std::string::npos) << message;
}

TEST_F(ImageTest, ReadingACorruptExrThrowsNamingThePath) {
    const std::string garbage_path = file("garbage.exr");
    const std::string garbage = "this is not an OpenEXR file, not even close";
    writeBytes(garbage_path, garbage.data(), garbage.size());
    std::string message = imageErrorOf([&] { readExr(garbage_path); });
    EXPECT_NE(message.find(garbage_path), std::string::npos) << message;

    const std::string empty_path = file("empty.exr");
    writeBytes(empty_path, "", 0);
    message = imageErrorOf([&] { readExr(empty_path); });
    EXPECT_NE(message.find(empty_path), std::string::npos) << message;

    // A valid file cut short: the header survives, the pixels do not.
    const std::string whole_path = file("whole.exr");
    writeExr(whole_path, patternImage(64, 64));
    const std::vector<unsigned char> whole = readBytes(whole_path);
    ASSERT_GT(whole.size(), 600u);
    const std::string truncated_path = file("truncated.exr");
    writeBytes(truncated_path, whole.data(), whole.size() / 2);
    message = imageErrorOf([&] { readExr(truncated_path); });
    EXPECT_NE(message.find(truncated_path), std::string::npos) << message;
}

// ---------------------------------------------------------------------------------------------
// PNG

TEST_F(ImageTest, PngIsWrittenAndDecodes) {
    const int w = 7, h = 3;
    Image image(w, h);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) image.at(x, y) = glm::vec3(float(x) / float(w - 1), float(y) * 0.5f, 4.0f);
    }
    image.at(0, 0) = glm::vec3(std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f);
    const std::string path = file("preview.png");
    writePng(path, image, 0.5f, ToneMap::Reinhard);
    EXPECT_FALSE(anyTemporaryLeft());

    const std::vector<unsigned char> bytes = readBytes(path);
    ASSERT_GT(bytes.size(), 33u);
    const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    EXPECT_EQ(std::memcmp(bytes.data(), signature, 8), 0);
    EXPECT_EQ(std::memcmp(bytes.data() + 12, "IHDR", 4), 0);
    auto be32 = [&](size_t at) {
        return (uint32_t(bytes[at]) << 24) | (uint32_t(bytes[at + 1]) << 16) | (uint32_t(bytes[at + 2]) << 8) |
               uint32_t(bytes[at + 3]);
    };
    EXPECT_EQ(be32(16), uint32_t(w));
    EXPECT_EQ(be32(20), uint32_t(h));

    int dw = 0, dh = 0, channels = 0;
    unsigned char* decoded = stbi_load_from_memory(bytes.data(), int(bytes.size()), &dw, &dh, &channels, 3);
    ASSERT_NE(decoded, nullptr) << stbi_failure_reason();
    EXPECT_EQ(dw, w);
    EXPECT_EQ(dh, h);
    EXPECT_EQ(channels, 3);
    for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
            const glm::vec3 expected = toneMapPixel(image.at(x, y), 0.5f, ToneMap::Reinhard);
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(int(decoded[(size_t(y) * w + x) * 3 + size_t(c)]), int(std::lround(expected[c] * 255.0f)))
                    << x << "," << y << " channel " << c;
            }
        }
    }
    // NaN -> 0, +Inf -> 255, negative -> 0.
    EXPECT_EQ(decoded[0], 0);
    EXPECT_EQ(decoded[1], 255);
    EXPECT_EQ(decoded[2], 0);
    stbi_image_free(decoded);
}

TEST_F(ImageTest, PngErrorsNameThePathAndLeaveNoTemporary) {
    const std::string missing = file("no_such_folder/out.png");
    std::string message = imageErrorOf([&] { writePng(missing, patternImage(2, 2)); });
    EXPECT_NE(message.find(missing), std::string::npos) << message;

    const std::string folder = file("a_folder.png");
    fs::create_directory(folder);
    message = imageErrorOf([&] { writePng(folder, patternImage(2, 2)); });
    EXPECT_NE(message.find(folder), std::string::npos) << message;
    EXPECT_FALSE(anyTemporaryLeft());

    const std::string empty = file("empty.png");
    message = imageErrorOf([&] { writePng(empty, Image()); });
    EXPECT_NE(message.find(empty), std::string::npos) << message;
    EXPECT_EQ(entries(), std::vector<std::string>{"a_folder.png"});
}

// ---------------------------------------------------------------------------------------------
// Tone mapping

float srgb(float x) { return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f; }

TEST(ToneMap, KnownValues) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    for (ToneMap op : {ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces}) {
        EXPECT_EQ(toneMapPixel(glm::vec3(0.0f), 0.0f, op), glm::vec3(0.0f));
        EXPECT_EQ(toneMapPixel(glm::vec3(nan), 0.0f, op), glm::vec3(0.0f));
        EXPECT_EQ(toneMapPixel(glm::vec3(inf), 0.0f, op), glm::vec3(1.0f));
        EXPECT_EQ(toneMapPixel(glm::vec3(-inf), 0.0f, op), glm::vec3(0.0f));
        EXPECT_EQ(toneMapPixel(glm::vec3(-0.5f), 0.0f, op), glm::vec3(0.0f));
        EXPECT_EQ(toneMapPixel(glm::vec3(1.0f), nan, op), glm::vec3(0.0f));
        // Channels are independent.
        const glm::vec3 mixed = toneMapPixel(glm::vec3(nan, inf, 0.0f), 0.0f, op);
        EXPECT_EQ(mixed, glm::vec3(0.0f, 1.0f, 0.0f));
        // Monotone and within [0, 1].
        float previous = 0.0f;
        for (float x = 0.0f; x < 100.0f; x = x * 1.5f + 0.01f) {
            const float v = toneMapPixel(glm::vec3(x), 0.0f, op).r;
            EXPECT_GE(v, previous) << x;
            EXPECT_LE(v, 1.0f) << x;
            previous = v;
        }
    }
    // Clamp: 1 -> 1, above 1 -> 1, 0.5 -> sRGB(0.5) = 0.7354.
    EXPECT_EQ(toneMapPixel(glm::vec3(1.0f), 0.0f, ToneMap::Clamp), glm::vec3(1.0f));
    EXPECT_EQ(toneMapPixel(glm::vec3(7.0f), 0.0f, ToneMap::Clamp), glm::vec3(1.0f));
    EXPECT_NEAR(toneMapPixel(glm::vec3(0.5f), 0.0f, ToneMap::Clamp).g, 0.7354f, 1e-4f);
    // The linear segment of the sRGB curve.
    EXPECT_NEAR(toneMapPixel(glm::vec3(0.002f), 0.0f, ToneMap::Clamp).b, 12.92f * 0.002f, 1e-6f);
    // Exposure in stops: 0.25 at +1 stop is 0.5; 2 at -2 stops is 0.5.
    EXPECT_NEAR(toneMapPixel(glm::vec3(0.25f), 1.0f, ToneMap::Clamp).r, 0.7354f, 1e-4f);
    EXPECT_NEAR(toneMapPixel(glm::vec3(2.0f), -2.0f, ToneMap::Clamp).r, 0.7354f, 1e-4f);
    // Reinhard: 1 -> 0.5 before the sRGB curve.
    EXPECT_NEAR(toneMapPixel(glm::vec3(1.0f), 0.0f, ToneMap::Reinhard).r, 0.7354f, 1e-4f);
    // ACES (Narkowicz): 1 -> 2.54 / 3.16, then sRGB; huge -> ~1.
    EXPECT_NEAR(toneMapPixel(glm::vec3(1.0f), 0.0f, ToneMap::Aces).r, srgb(2.54f / 3.16f), 1e-5f);
    EXPECT_NEAR(toneMapPixel(glm::vec3(1e6f), 0.0f, ToneMap::Aces).r, 1.0f, 1e-5f);
    // A finite value that overflows with the exposure behaves like +Inf.
    EXPECT_EQ(toneMapPixel(glm::vec3(3e38f), 10.0f, ToneMap::Reinhard), glm::vec3(1.0f));
}

}  // namespace
}  // namespace sharcbake
