// SPDX-License-Identifier: Apache-2.0
// Image I/O: EXR round trips (exact floats, metadata, layout), EXRs written directly with
// OpenEXR (half, data-window offset, missing channels, Y-only, luminance/chroma), error paths
// (unwritable, missing, corrupt, no temporary left behind), PNG previews and tone mapping; PFM and
// Radiance HDR from other renderers (byte layouts written here, and files ImageMagick wrote).
#include "sharcbake/image.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfStringAttribute.h>
#include <ImfTiledOutputFile.h>
#include <half.h>
#include <stb_image.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include <sys/resource.h>
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

/// Writes one float channel, `values` row by row over the data window `data`, with OpenEXR
/// itself (not writeExr, which always writes R, G, B).
void writeFloatChannelExr(const std::string& path, const std::string& channel, const Imath::Box2i& data,
                          Imf::Compression compression, const std::vector<float>& values) {
    Imf::Header header(data, data);
    header.compression() = compression;
    header.channels().insert(channel, Imf::Channel(Imf::FLOAT));
    Imf::FrameBuffer frame;
    frame.insert(channel, Imf::Slice::Make(Imf::FLOAT, values.data(), data));
    Imf::OutputFile out(path.c_str(), header);
    out.setFrameBuffer(frame);
    out.writePixels(data.max.y - data.min.y + 1);
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
    writeFloatChannelExr(path, "Y", Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(w - 1, h - 1)), Imf::ZIP_COMPRESSION,
                         y_values);
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

/// Where `name` (an attribute name, its type name and their zero bytes) starts in `bytes`.
size_t findAttribute(const std::vector<unsigned char>& bytes, const std::string& name_and_type) {
    const auto at = std::search(bytes.begin(), bytes.end(), name_and_type.begin(), name_and_type.end());
    return at == bytes.end() ? std::string::npos : size_t(at - bytes.begin());
}

void storeInt32(std::vector<unsigned char>& bytes, size_t at, int32_t value) {
    for (int i = 0; i < 4; ++i) bytes[at + size_t(i)] = static_cast<unsigned char>(uint32_t(value) >> (8 * i));
}

// OpenEXR 3.1 allocates what a header attribute claims before it reads it: a fuzzed 519-byte file
// made it allocate and clear 1.7 GB for 6 s. checkExrHeaders refuses such a file at once, and a
// data window of more pixels than sharcbake reads, naming what is wrong.
TEST_F(ImageTest, ExrHeadersThatClaimMoreThanTheFileHoldsAreRefusedBeforeOpenExrReadsThem) {
    const std::string whole_path = file("whole.exr");
    writeExr(whole_path, patternImage(8, 8), {{"note", "a string attribute"}});
    const std::vector<unsigned char> whole = readBytes(whole_path);
    EXPECT_NO_THROW(checkExrHeaders(whole_path));

    std::vector<unsigned char> claims = whole;
    const std::string note("note\0string\0", 12);
    const size_t at = findAttribute(claims, note);
    ASSERT_NE(at, std::string::npos);
    storeInt32(claims, at + note.size(), 0x7fffff00);
    const std::string claims_path = file("claims.exr");
    writeBytes(claims_path, claims.data(), claims.size());
    for (const std::string& message :
         {imageErrorOf([&] { readExr(claims_path); }), imageErrorOf([&] { readLinearImage(claims_path); })}) {
        EXPECT_NE(message.find(claims_path), std::string::npos) << message;
        EXPECT_NE(message.find("header attribute 'note' (string) claims 2147483392 bytes where the file has"),
                  std::string::npos)
            << message;
    }
    storeInt32(claims, at + note.size(), -5);  // a negative size
    writeBytes(claims_path, claims.data(), claims.size());
    EXPECT_NE(imageErrorOf([&] { readExr(claims_path); }).find("'note' (string) claims -5 bytes"), std::string::npos);

    // 20000 x 20000 pixels, of which the file holds 64: refused before 4.8 GB are allocated.
    std::vector<unsigned char> wide = whole;
    const std::string window("dataWindow\0box2i\0", 17);
    const size_t window_at = findAttribute(wide, window);
    ASSERT_NE(window_at, std::string::npos);
    storeInt32(wide, window_at + window.size() + 4 + 8, 19999);   // max.x
    storeInt32(wide, window_at + window.size() + 4 + 12, 19999);  // max.y
    const std::string wide_path = file("wide.exr");
    writeBytes(wide_path, wide.data(), wide.size());
    const std::string message = imageErrorOf([&] { readExr(wide_path); });
    EXPECT_NE(message.find("20000x20000 is more pixels than sharcbake reads (134,217,728, e.g. 16384x8192)"),
              std::string::npos)
        << message;
}

/// The process's peak resident memory so far, in bytes.
uint64_t peakResidentBytes() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return uint64_t(usage.ru_maxrss) * 1024;  // Linux reports kilobytes
}

// Rows are read in strips (exrRowsPerStrip: 256 rows at this width): an image of 600 rows whose
// data window starts at y = -37, with 1, 16 and 32 rows a chunk (no compression, ZIP, PIZ),
// reads back exactly across the strips' seams.
TEST_F(ImageTest, ExrOfSeveralStripsReadsBackExactly) {
    const int w = 7, h = 600;
    ASSERT_LT(exrRowsPerStrip(w), h);
    const Imath::Box2i data(Imath::V2i(4, -37), Imath::V2i(4 + w - 1, -37 + h - 1));
    std::vector<float> red(size_t(w) * h);
    for (size_t i = 0; i < red.size(); ++i) red[i] = float(i) * 0.25f;
    for (const Imf::Compression compression : {Imf::NO_COMPRESSION, Imf::ZIP_COMPRESSION, Imf::PIZ_COMPRESSION}) {
        const std::string path = file("strips.exr");
        writeFloatChannelExr(path, "R", data, compression, red);
        const Image image = readExr(path);
        ASSERT_EQ(image.width, w);
        ASSERT_EQ(image.height, h);
        for (int y = 0; y < h; ++y) {
            for (int x = 0; x < w; ++x) {
                ASSERT_EQ(image.at(x, y), glm::vec3(red[size_t(y) * w + x], 0.0f, 0.0f))
                    << "compression " << int(compression) << " at " << x << "," << y;
            }
        }
    }
}

// A header may claim up to 2^27 pixels in a file that holds 64. Rows are allocated as OpenEXR
// decodes them, a few million pixels at a time, so such a file fails at its first damaged row
// without clearing the whole image first (a fuzzed 634-byte file took over 10 s so under ASan).
// Here 16 rows of 2^20 pixels (192 MiB as floats) whose one chunk of rows is damaged (its
// compressed bytes overwritten).
TEST_F(ImageTest, ExrThatClaimsMorePixelsThanItHoldsFailsBeforeItsRowsAreAllocated) {
    const std::string whole_path = file("whole.exr");
    writeExr(whole_path, patternImage(8, 8));
    std::vector<unsigned char> wide = readBytes(whole_path);
    const std::string window("dataWindow\0box2i\0", 17);
    const size_t window_at = findAttribute(wide, window);
    ASSERT_NE(window_at, std::string::npos);
    storeInt32(wide, window_at + window.size() + 4 + 8, (1 << 20) - 1);  // max.x
    storeInt32(wide, window_at + window.size() + 4 + 12, 15);            // max.y
    std::fill(wide.end() - 64, wide.end(), 0xa5);                        // the chunk's last bytes
    const std::string wide_path = file("wide.exr");
    writeBytes(wide_path, wide.data(), wide.size());
    const uint64_t peak_before = peakResidentBytes();
    const std::string message = imageErrorOf([&] { readLinearImage(wide_path); });
    EXPECT_NE(message.find(wide_path), std::string::npos) << message;
    EXPECT_LT(peakResidentBytes() - peak_before, uint64_t(128) << 20) << "the whole image was allocated";

    EXPECT_EQ(exrRowsPerStrip(1 << 24), 1);
    EXPECT_EQ(exrRowsPerStrip(16384), 256);
    EXPECT_EQ(exrRowsPerStrip(100000), 32);  // 3.2 M pixels; 64 rows would be 6.4 M
    EXPECT_EQ(exrRowsPerStrip(1), 256);
}

// OpenEXR allocates what one chunk (a tile, or the rows compressed together) decodes to before
// reading it: a chunk of more than 256 MiB is refused first, naming its shape.
TEST_F(ImageTest, ExrWhoseChunkDecodesToMoreThan256MiBIsRefused) {
    const std::string whole_path = file("whole.exr");
    writeExr(whole_path, patternImage(8, 8));  // ZIP: 16 rows a chunk; R, G, B float
    std::vector<unsigned char> wide = readBytes(whole_path);
    const std::string window("dataWindow\0box2i\0", 17);
    const size_t window_at = findAttribute(wide, window);
    ASSERT_NE(window_at, std::string::npos);
    storeInt32(wide, window_at + window.size() + 4 + 8, (1 << 21) - 1);  // 16 x 2^21 x 12 = 384 MiB
    const std::string wide_path = file("wide.exr");
    writeBytes(wide_path, wide.data(), wide.size());
    std::string message = imageErrorOf([&] { readExr(wide_path); });
    EXPECT_NE(message.find("a chunk of 16 rows 2097152 pixels wide of 12 bytes a pixel decodes to 384 MiB, more "
                           "than the 256 MiB sharcbake reads"),
              std::string::npos)
        << message;
    storeInt32(wide, window_at + window.size() + 4 + 8, (1 << 20) - 1);  // 192 MiB: OpenEXR's to judge
    writeBytes(wide_path, wide.data(), wide.size());
    EXPECT_NO_THROW(checkExrHeaders(wide_path));

    const std::string tiled_path = file("tiled.exr");
    {
        Imf::Header header(8, 8);
        header.channels().insert("R", Imf::Channel(Imf::HALF));
        header.setTileDescription(Imf::TileDescription(4, 4));
        Imf::TiledOutputFile out(tiled_path.c_str(), header);
        std::vector<half> pixels(64, half(1.0f));
        Imf::FrameBuffer frame;
        frame.insert("R",
                     Imf::Slice(Imf::HALF, reinterpret_cast<char*>(pixels.data()), sizeof(half), 8 * sizeof(half)));
        out.setFrameBuffer(frame);
        out.writeTiles(0, 1, 0, 1);
    }
    EXPECT_EQ(readExr(tiled_path).pixels.size(), 64u);
    std::vector<unsigned char> tiled = readBytes(tiled_path);
    const std::string tiles("tiles\0tiledesc\0", 15);
    const size_t tiles_at = findAttribute(tiled, tiles);
    ASSERT_NE(tiles_at, std::string::npos);
    storeInt32(tiled, tiles_at + tiles.size() + 4, 1 << 16);      // x size
    storeInt32(tiled, tiles_at + tiles.size() + 4 + 4, 1 << 16);  // y size: 2^32 half pixels
    writeBytes(tiled_path, tiled.data(), tiled.size());
    message = imageErrorOf([&] { readExr(tiled_path); });
    EXPECT_NE(message.find("a tile of 65536x65536 pixels of 2 bytes a pixel decodes to 8192 MiB"), std::string::npos)
        << message;
}

// OpenEXR reads a channel list up to its empty name and a fixed-size value (int, box, enum) by
// its type, whatever size the file declares; checkExrHeaders must walk the same bytes, or it
// checks other bytes than OpenEXR trusts. A fuzzed file whose channel list claimed 55 bytes and
// held 19 had OpenEXR take a string's size from bytes the check had skipped as a name, and clear
// 1.9 GB for over 10 s. A declared size that disagrees with what the value holds is refused.
TEST_F(ImageTest, ExrAttributeSizesThatDisagreeWithTheirValuesAreRefused) {
    const std::string whole_path = file("whole.exr");
    writeExr(whole_path, patternImage(8, 8), {{"note", "a string attribute"}});
    const std::vector<unsigned char> whole = readBytes(whole_path);

    const std::string channels("channels\0chlist\0", 16);
    const size_t channels_at = findAttribute(whole, channels);
    ASSERT_NE(channels_at, std::string::npos);
    const int32_t channels_size = 3 * (2 + 16) + 1;  // "R", "G", "B", each with its 16 bytes; end
    std::vector<unsigned char> longer = whole;
    storeInt32(longer, channels_at + channels.size(), channels_size + 36);
    const std::string longer_path = file("longer_chlist.exr");
    writeBytes(longer_path, longer.data(), longer.size());
    std::string message = imageErrorOf([&] { readLinearImage(longer_path); });
    EXPECT_NE(message.find("header attribute 'channels' (chlist) claims 91 bytes where its channels take 55"),
              std::string::npos)
        << message;

    std::vector<unsigned char> shorter = whole;  // the list runs past what the file declares
    storeInt32(shorter, channels_at + channels.size(), channels_size - 20);
    const std::string shorter_path = file("shorter_chlist.exr");
    writeBytes(shorter_path, shorter.data(), shorter.size());
    message = imageErrorOf([&] { readExr(shorter_path); });
    EXPECT_NE(message.find("'channels' (chlist) claims 35 bytes where its channels run past them"), std::string::npos)
        << message;

    std::vector<unsigned char> compression = whole;
    const std::string compression_name("compression\0compression\0", 24);
    const size_t compression_at = findAttribute(compression, compression_name);
    ASSERT_NE(compression_at, std::string::npos);
    storeInt32(compression, compression_at + compression_name.size(), 4);
    const std::string compression_path = file("compression.exr");
    writeBytes(compression_path, compression.data(), compression.size());
    message = imageErrorOf([&] { readExr(compression_path); });
    EXPECT_NE(message.find("'compression' (compression) claims 4 bytes where a compression is 1"), std::string::npos)
        << message;

    // The file as written passes, and so does an attribute of a type OpenEXR does not know (read
    // by its declared size).
    EXPECT_NO_THROW(checkExrHeaders(whole_path));
    std::vector<unsigned char> unknown = whole;
    const std::string note("note\0string\0", 12);
    const size_t note_at = findAttribute(unknown, note);
    ASSERT_NE(note_at, std::string::npos);
    std::copy_n("mytype", 6, unknown.begin() + std::ptrdiff_t(note_at + 5));
    const std::string unknown_path = file("unknown_type.exr");
    writeBytes(unknown_path, unknown.data(), unknown.size());
    EXPECT_NO_THROW(checkExrHeaders(unknown_path));
    EXPECT_EQ(readExr(unknown_path).pixels.size(), 64u);
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

// ------------------------------------------------------------------------------------------------
// readLinearImage: PFM and Radiance HDR
// ------------------------------------------------------------------------------------------------

/// `header` then `floats` as float32 in the given byte order.
std::vector<unsigned char> pfmBytes(const std::string& header, const std::vector<float>& floats, bool little_endian) {
    std::vector<unsigned char> bytes(header.begin(), header.end());
    for (const float f : floats) {
        const uint32_t u = bits(f);
        for (int k = 0; k < 4; ++k) bytes.push_back(uint8_t(u >> (little_endian ? 8 * k : 24 - 8 * k)));
    }
    return bytes;
}

TEST_F(ImageTest, PfmColourAndGreyInEitherByteOrderRowsFromTheBottomUp) {
    // 2 x 2 RGB, little-endian (negative scale, as pbrt writes): the file's first row is the
    // image's bottom row.
    const std::vector<float> rgb = {1, 2, 3, 4, 5, 6, /* top: */ 7, 8, 9, 10, 11, 12};
    const std::vector<unsigned char> little = pfmBytes("PF\n2 2\n-1.0\n", rgb, true);
    writeBytes(file("a.pfm"), little.data(), little.size());
    const Image a = readLinearImage(file("a.pfm"));
    ASSERT_EQ(a.width, 2);
    ASSERT_EQ(a.height, 2);
    EXPECT_EQ(a.at(0, 0), glm::vec3(7, 8, 9));
    EXPECT_EQ(a.at(1, 0), glm::vec3(10, 11, 12));
    EXPECT_EQ(a.at(0, 1), glm::vec3(1, 2, 3));
    EXPECT_EQ(a.at(1, 1), glm::vec3(4, 5, 6));
    // The same big-endian (positive scale), and a grey "Pf" file replicated into RGB.
    const std::vector<unsigned char> big = pfmBytes("PF 2 2 1\n", rgb, false);
    writeBytes(file("b.pfm"), big.data(), big.size());
    expectBitwiseEqual(a, readLinearImage(file("b.pfm")));
    const std::vector<unsigned char> grey = pfmBytes("Pf\n1 2\n-1\n", {0.25f, 0.75f}, true);
    writeBytes(file("g.pfm"), grey.data(), grey.size());
    const Image g = readLinearImage(file("g.pfm"));
    EXPECT_EQ(g.at(0, 0), glm::vec3(0.75f));
    EXPECT_EQ(g.at(0, 1), glm::vec3(0.25f));
}

TEST_F(ImageTest, BrokenPfmFilesSayWhatIsWrong) {
    std::vector<unsigned char> bytes = pfmBytes("PF\n2 2\n-1.0\n", std::vector<float>(12, 1.0f), true);
    bytes.resize(bytes.size() - 5);
    writeBytes(file("short.pfm"), bytes.data(), bytes.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("short.pfm")); }).find("truncated"), std::string::npos);
    const std::string zero_scale = "PF\n2 2\n0\n";
    writeBytes(file("scale.pfm"), zero_scale.data(), zero_scale.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("scale.pfm")); }).find("scale"), std::string::npos);
    const std::string huge = "PF\n1048576 1048576\n-1\n";
    writeBytes(file("huge.pfm"), huge.data(), huge.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("huge.pfm")); }).find("is more pixels than sharcbake reads"), std::string::npos);
    const std::string negative = "PF\n-2 2\n-1\n";
    writeBytes(file("negative.pfm"), negative.data(), negative.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("negative.pfm")); }).find("width and height"), std::string::npos);
}

/// A Radiance HDR file: the header lines, a blank line, the resolution line, then `pixels`.
std::vector<unsigned char> hdrBytes(const std::string& header, const std::string& resolution,
                                    const std::vector<unsigned char>& pixels) {
    const std::string text = "#?RADIANCE\n" + header + "\n\n" + resolution + "\n";
    std::vector<unsigned char> bytes(text.begin(), text.end());
    bytes.insert(bytes.end(), pixels.begin(), pixels.end());
    return bytes;
}

TEST_F(ImageTest, RadianceHdrFlatAndOldRunLengthPixelsWithExposure) {
    // RGBE (128, 64, 32, 129): mantissa centres (m + 0.5) * 2^(129 - 136): 1.00390625,
    // 0.50390625, 0.25390625. (1, 1, 1, 2) repeats the previous pixel twice; e = 0 is black.
    // EXPOSURE=2 says the values were doubled: they are halved back.
    const std::vector<unsigned char> pixels = {128, 64, 32, 129, 1, 1, 1, 2, 0, 0, 0, 0};
    const std::vector<unsigned char> bytes = hdrBytes("FORMAT=32-bit_rle_rgbe\nEXPOSURE=2", "-Y 1 +X 4", pixels);
    writeBytes(file("flat.hdr"), bytes.data(), bytes.size());
    const Image image = readLinearImage(file("flat.hdr"));
    ASSERT_EQ(image.width, 4);
    ASSERT_EQ(image.height, 1);
    const glm::vec3 first = glm::vec3(1.00390625f, 0.50390625f, 0.25390625f) / 2.0f;
    EXPECT_EQ(image.at(0, 0), first);
    EXPECT_EQ(image.at(1, 0), first);
    EXPECT_EQ(image.at(2, 0), first);
    EXPECT_EQ(image.at(3, 0), glm::vec3(0.0f));
}

TEST_F(ImageTest, RadianceHdrAdaptiveRunLengthAndBottomUpRows) {
    // Width 8 in the adaptive scheme: per channel, a run of 8 (136 = 128 + 8) or literals. Two
    // rows, "+Y": the file's first row is the bottom one.
    std::vector<unsigned char> pixels;
    for (int row = 0; row < 2; ++row) {
        pixels.insert(pixels.end(), {2, 2, 0, 8});
        pixels.insert(pixels.end(), {136, uint8_t(100 + row)});           // R: a run
        pixels.insert(pixels.end(), {8, 0, 10, 20, 30, 40, 50, 60, 70});  // G: literals
        pixels.insert(pixels.end(), {4, 1, 2, 3, 4, 132, 9});             // B: literals, then a run
        pixels.insert(pixels.end(), {136, 136});                          // E: 2^(136 - 136) = 1
    }
    const std::vector<unsigned char> bytes = hdrBytes("FORMAT=32-bit_rle_rgbe", "+Y 2 +X 8", pixels);
    writeBytes(file("rle.hdr"), bytes.data(), bytes.size());
    const Image image = readLinearImage(file("rle.hdr"));
    ASSERT_EQ(image.width, 8);
    ASSERT_EQ(image.height, 2);
    EXPECT_EQ(image.at(0, 1), glm::vec3(100.5f, 0.5f, 1.5f));  // the file's first row, at the bottom
    EXPECT_EQ(image.at(7, 0), glm::vec3(101.5f, 70.5f, 9.5f));
    EXPECT_EQ(image.at(3, 0), glm::vec3(101.5f, 30.5f, 4.5f));
    // Cut short, and a run past the row's end, are errors that say so.
    std::vector<unsigned char> cut = bytes;
    cut.resize(cut.size() - 3);
    writeBytes(file("cut.hdr"), cut.data(), cut.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("cut.hdr")); }).find("truncated"), std::string::npos);
    std::vector<unsigned char> overrun = pixels;
    overrun[4] = 137;  // a run of 9 in a row of 8
    const std::vector<unsigned char> bad = hdrBytes("FORMAT=32-bit_rle_rgbe", "-Y 2 +X 8", overrun);
    writeBytes(file("bad.hdr"), bad.data(), bad.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("bad.hdr")); }).find("bad run"), std::string::npos);
    // XYZE pixels and an unusual orientation are refused by name.
    const std::vector<unsigned char> xyze = hdrBytes("FORMAT=32-bit_rle_xyze", "-Y 1 +X 1", {1, 1, 1, 128});
    writeBytes(file("xyze.hdr"), xyze.data(), xyze.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("xyze.hdr")); }).find("xyze"), std::string::npos);
    const std::vector<unsigned char> turned = hdrBytes("FORMAT=32-bit_rle_rgbe", "+X 1 -Y 1", {1, 1, 1, 128});
    writeBytes(file("turned.hdr"), turned.data(), turned.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("turned.hdr")); }).find("resolution line"), std::string::npos);
}

TEST_F(ImageTest, LinearImagesWrittenByImageMagickMatchTheExrTheyCameFrom) {
    // Files another tool wrote (fixtures/README.md): ImageMagick 6.9.11 converted sharcbake's EXR
    // to Radiance HDR and PFM.
    const std::string fixtures = SHARCBAKE_IMAGE_FIXTURES;
    const Image exr = readLinearImage(fixtures + "/suzanne_32x24.exr");
    expectBitwiseEqual(exr, readExr(fixtures + "/suzanne_32x24.exr"));
    const Image pfm = readLinearImage(fixtures + "/suzanne_32x24_imagemagick.pfm");
    const Image hdr = readLinearImage(fixtures + "/suzanne_32x24_imagemagick.hdr");
    ASSERT_EQ(pfm.width, exr.width);
    ASSERT_EQ(pfm.height, exr.height);
    ASSERT_EQ(hdr.width, exr.width);
    ASSERT_EQ(hdr.height, exr.height);
    double exr_sum = 0.0, hdr_sum = 0.0;
    for (size_t i = 0; i < exr.pixels.size(); ++i) {
        for (int c = 0; c < 3; ++c) {
            const float r = exr.pixels[i][c];
            EXPECT_NEAR(pfm.pixels[i][c], r, 1e-3f * r + 1e-5f) << "pixel " << i;  // read as half
            EXPECT_NEAR(hdr.pixels[i][c], r, 0.01f * r + 1e-4f) << "pixel " << i;  // 8-bit mantissas
            exr_sum += r;
            hdr_sum += hdr.pixels[i][c];
        }
    }
    EXPECT_NEAR(hdr_sum / exr_sum, 1.0, 0.005);  // measured +0.23%: ImageMagick rounds its mantissas
}

TEST_F(ImageTest, CorruptOrCutHdrAndPfmFilesFailCleanly) {
    // Every byte of ImageMagick's HDR and of the PFM's header changed, and the HDR cut at every
    // length: each file reads or throws ImageError, nothing else.
    const std::string fixtures = SHARCBAKE_IMAGE_FIXTURES;
    const auto readsOrRefuses = [&](const std::vector<unsigned char>& bytes, const std::string& what) {
        writeBytes(file("x"), bytes.data(), bytes.size());
        try {
            (void)readLinearImage(file("x"));
        } catch (const ImageError&) {
        } catch (const std::exception& e) {
            ADD_FAILURE() << what << ": " << e.what();
        }
    };
    const std::vector<unsigned char> hdr = readBytes(fixtures + "/suzanne_32x24_imagemagick.hdr");
    for (size_t i = 0; i < hdr.size(); ++i) {
        std::vector<unsigned char> changed = hdr;
        changed[i] ^= 0x5A;
        readsOrRefuses(changed, "HDR byte " + std::to_string(i) + " changed");
        readsOrRefuses(std::vector<unsigned char>(hdr.begin(), hdr.begin() + std::ptrdiff_t(i)),
                       "HDR cut to " + std::to_string(i) + " bytes");
    }
    const std::vector<unsigned char> pfm = readBytes(fixtures + "/suzanne_32x24_imagemagick.pfm");
    for (size_t i = 0; i < 32; ++i) {
        std::vector<unsigned char> changed = pfm;
        changed[i] ^= 0x5A;
        readsOrRefuses(changed, "PFM byte " + std::to_string(i) + " changed");
    }
    // A run-length HDR of a few bytes can claim any size: refused before the pixels are made.
    const std::vector<unsigned char> huge = hdrBytes("FORMAT=32-bit_rle_rgbe", "-Y 1048576 +X 1048576", {});
    writeBytes(file("huge.hdr"), huge.data(), huge.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("huge.hdr")); }).find("is more pixels than sharcbake reads"), std::string::npos);
    // Within that, rows the file cannot hold (each takes 4 bytes or more) are refused before the
    // image is allocated (a fuzzed file claiming 900,000 rows cleared 1.6 GB first), and a file
    // whose rows end early fails without its claimed size allocated.
    const std::string nul_inside("-Y 4\0\0\0 +X 4", 12);  // the fuzzed file's height was "0900000\0\0..."
    const std::vector<unsigned char> nul = hdrBytes("FORMAT=32-bit_rle_rgbe", nul_inside,
                                                    std::vector<unsigned char>(64, 9));
    writeBytes(file("nul.hdr"), nul.data(), nul.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("nul.hdr")); }).find("is not \"-Y height +X width\""),
              std::string::npos);
    // The same in a PFM's scale: "-1.0\0x" was read as -1.
    std::string nul_scale("PF\n2 1\n-1.0\0x\n", 14);
    nul_scale.append(2 * 3 * sizeof(float), '\0');
    writeBytes(file("nul.pfm"), nul_scale.data(), nul_scale.size());
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("nul.pfm")); }).find("the header's scale '-1.0?x' is not a"),
              std::string::npos);
    const std::vector<unsigned char> tall = hdrBytes("FORMAT=32-bit_rle_rgbe", "-Y 900000 +X 4", {10, 20, 30, 130});
    writeBytes(file("tall.hdr"), tall.data(), tall.size());
    const std::string message = imageErrorOf([&] { readLinearImage(file("tall.hdr")); });
    EXPECT_NE(message.find("claims 900000 rows where the 4 bytes after it hold at most 1 (truncated)"),
              std::string::npos)
        << message;
    std::vector<unsigned char> cut = hdrBytes("FORMAT=32-bit_rle_rgbe", "-Y 128 +X 1000000", {});
    cut.resize(cut.size() + 128 * 4, 7);  // 128 flat pixels: the first row cut short
    writeBytes(file("cut.hdr"), cut.data(), cut.size());
    const uint64_t peak_before = peakResidentBytes();
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("cut.hdr")); }).find("truncated"), std::string::npos);
    EXPECT_LT(peakResidentBytes() - peak_before, uint64_t(256) << 20) << "the claimed 1.5 GB were allocated";
}

TEST_F(ImageTest, DisplayImagesAreRefusedWithTheReason) {
    const Image image = patternImage(4, 3);
    writePng(file("preview.png"), image);
    const std::string message = imageErrorOf([&] { readLinearImage(file("preview.png")); });
    EXPECT_NE(message.find("a PNG image"), std::string::npos) << message;
    EXPECT_NE(message.find("not radiance"), std::string::npos) << message;
    const unsigned char jpeg[] = {0xFF, 0xD8, 0xFF, 0xE0, 0, 16};
    writeBytes(file("photo.jpg"), jpeg, sizeof jpeg);
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("photo.jpg")); }).find("a JPEG image"), std::string::npos);
    writeBytes(file("empty.exr"), "", 0);
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("empty.exr")); }).find("empty"), std::string::npos);
    EXPECT_NE(imageErrorOf([&] { readLinearImage(file("missing.exr")); }).find("cannot open"), std::string::npos);
    // An EXR goes to readExr.
    writeExr(file("data.exr"), image);
    expectBitwiseEqual(image, readLinearImage(file("data.exr")));
}

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
