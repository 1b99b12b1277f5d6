// SPDX-License-Identifier: Apache-2.0
// OpenEXR files: 32-bit float RGB, ZIP compression, provenance as string attributes.
#include "image_internal.h"
#include "sharcbake/image.h"

#include <ImfArray.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>
#include <ImfRgbaFile.h>
#include <ImfStringAttribute.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <new>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

/// An Imf::OStream that collects the file in memory, so that the bytes reach the disk through
/// detail::writeFileAtomically (temporary file + fsync + rename) with every error checked.
/// (Imf::OutputFile writes its line-offset table in its destructor and swallows errors there.)
class MemoryOStream final : public Imf::OStream {
public:
    explicit MemoryOStream(const std::string& name) : Imf::OStream(name.c_str()) {}

    void write(const char c[], int n) override {
        if (n <= 0) return;
        const size_t end = pos_ + size_t(n);
        if (end > bytes_.size()) bytes_.resize(end);
        std::memcpy(bytes_.data() + pos_, c, size_t(n));
        pos_ = end;
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = size_t(pos); }

    const std::vector<char>& bytes() const { return bytes_; }

private:
    std::vector<char> bytes_;
    size_t pos_ = 0;
};

[[noreturn]] void throwReadError(const std::string& path, const std::string& reason) {
    throw ImageError("cannot read EXR '" + path + "': " + reason);
}

uint32_t littleEndian32(const unsigned char* bytes) {
    return uint32_t(bytes[0]) | uint32_t(bytes[1]) << 8 | uint32_t(bytes[2]) << 16 | uint32_t(bytes[3]) << 24;
}

/// Luminance/chroma files (Y, RY, BY; possibly sub-sampled) are converted by OpenEXR's RGBA
/// interface. Precision is half, which is what such files store.
Image readLuminanceChroma(const std::string& path, const Imath::Box2i& dw) {
    Imf::RgbaInputFile file(path.c_str());
    const int width = dw.max.x - dw.min.x + 1;
    const int height = dw.max.y - dw.min.y + 1;
    Imf::Array2D<Imf::Rgba> rgba(height, width);
    const auto base = reinterpret_cast<intptr_t>(&rgba[0][0]) -
                      (intptr_t(dw.min.x) + intptr_t(dw.min.y) * intptr_t(width)) *
                          intptr_t(sizeof(Imf::Rgba));
    file.setFrameBuffer(reinterpret_cast<Imf::Rgba*>(base), 1, size_t(width));
    file.readPixels(dw.min.y, dw.max.y);
    Image image(width, height);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const Imf::Rgba& p = rgba[y][x];
            image.at(x, y) = glm::vec3(float(p.r), float(p.g), float(p.b));
        }
    }
    return image;
}

/// The prefix of the channels that hold the picture: "" for plain R, G, B (or Y), otherwise
/// "LAYER." for a layered file without them (Blender's multilayer EXR: "ViewLayer.Combined.R",
/// "ViewLayer.Depth.Z", ...): the only layer with R, G and B channels, or else the one ending in
/// "Combined" (Blender's beauty pass) if exactly one does. Anything else is an error naming the
/// layers, so that a comparison never reads a pass nobody asked for.
std::string pictureLayer(const std::string& path, const Imf::ChannelList& channels) {
    if (channels.findChannel("R") || channels.findChannel("G") || channels.findChannel("B") ||
        channels.findChannel("Y")) {
        return "";
    }
    std::vector<std::string> rgb_layers;
    for (auto it = channels.begin(); it != channels.end(); ++it) {
        const std::string name = it.name();
        if (name.size() < 3 || name.compare(name.size() - 2, 2, ".R") != 0) continue;
        const std::string prefix = name.substr(0, name.size() - 1);  // "LAYER."
        if (channels.findChannel(prefix + "G") && channels.findChannel(prefix + "B")) rgb_layers.push_back(prefix);
    }
    if (rgb_layers.size() == 1) return rgb_layers.front();
    std::vector<std::string> combined;
    for (const std::string& prefix : rgb_layers) {
        const std::string layer = prefix.substr(0, prefix.size() - 1);
        if (layer == "Combined" || (layer.size() > 9 && layer.compare(layer.size() - 9, 9, ".Combined") == 0)) {
            combined.push_back(prefix);
        }
    }
    if (combined.size() == 1) return combined.front();
    std::string names;
    for (const std::string& prefix : rgb_layers)
        names += (names.empty() ? "" : ", ") + prefix.substr(0, prefix.size() - 1);
    if (rgb_layers.empty()) {
        for (auto it = channels.begin(); it != channels.end(); ++it)
            names += (names.empty() ? "" : ", ") + std::string(it.name());
        throwReadError(path, "no R, G, B or Y channels and no layer with them (channels: " +
                                 (names.empty() ? std::string("none") : detail::printable(names)) + ")");
    }
    throwReadError(path, "several layers hold R, G and B (" + detail::printable(names) +
                             ") and none is the single 'Combined' pass; save the picture alone (a plain RGB EXR)");
}

}  // namespace

void writeExr(const std::string& path, const Image& image, const ImageMetadata& metadata) {
    detail::checkImageShape(path, image, "EXR");
    std::vector<char> bytes;
    try {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.channels().insert("R", Imf::Channel(Imf::FLOAT));
        header.channels().insert("G", Imf::Channel(Imf::FLOAT));
        header.channels().insert("B", Imf::Channel(Imf::FLOAT));
        for (const auto& [name, value] : metadata) {
            if (name.empty()) throw ImageError("cannot write EXR '" + path + "': empty metadata name");
            if (header.find(name) != header.end()) {
                throw ImageError("cannot write EXR '" + path + "': metadata name '" + name +
                                 "' clashes with a standard EXR header attribute");
            }
            header.insert(name, Imf::StringAttribute(value));
        }

        const Imath::Box2i dw = header.dataWindow();
        const char* first = reinterpret_cast<const char*>(image.pixels.data());
        const size_t x_stride = sizeof(glm::vec3);
        const size_t y_stride = x_stride * size_t(image.width);
        Imf::FrameBuffer frame;
        frame.insert("R", Imf::Slice::Make(Imf::FLOAT, first + 0 * sizeof(float), dw, x_stride, y_stride));
        frame.insert("G", Imf::Slice::Make(Imf::FLOAT, first + 1 * sizeof(float), dw, x_stride, y_stride));
        frame.insert("B", Imf::Slice::Make(Imf::FLOAT, first + 2 * sizeof(float), dw, x_stride, y_stride));

        MemoryOStream stream(path);
        {
            Imf::OutputFile file(stream, header);
            file.setFrameBuffer(frame);
            file.writePixels(image.height);
        }  // The destructor writes the line-offset table.
        bytes = stream.bytes();
    } catch (const ImageError&) {
        throw;
    } catch (const std::exception& e) {
        throw ImageError("cannot write EXR '" + path + "': " + e.what());
    }
    detail::writeFileAtomically(path, bytes.data(), bytes.size());
}

namespace {

/// The bytes OpenEXR 3.1 reads for a value of a type whose reader ignores the size the file
/// declares (it reads the type's own layout), or -1 for a type read by its declared size.
int fixedValueBytes(const std::string& type) {
    static const std::map<std::string, int> kFixed = {{"box2i", 16},      {"box2f", 16},   {"chromaticities", 32},
                                                      {"compression", 1}, {"double", 8},   {"envmap", 1},
                                                      {"float", 4},       {"int", 4},      {"keycode", 28},
                                                      {"lineOrder", 1},   {"m33f", 36},    {"m33d", 72},
                                                      {"m44f", 64},       {"m44d", 128},   {"rational", 8},
                                                      {"tiledesc", 9},    {"timecode", 8}, {"v2i", 8},
                                                      {"v2f", 8},         {"v2d", 16},     {"v3i", 12},
                                                      {"v3f", 12},        {"v3d", 24},     {"deepImageState", 1}};
    const auto it = kFixed.find(type);
    return it == kFixed.end() ? -1 : it->second;
}

/// What checkExrHeaders gathers from one part's header: what OpenEXR sizes its buffers by.
struct ExrPartShape {
    int64_t width = 0, height = 0;            // of the data window; 0 where the header has none
    int compression = -1;                     // OpenEXR's Compression enum; -1 where absent
    int64_t bytes_per_pixel = 0;              // of all channels, as stored
    int64_t tile_width = 0, tile_height = 0;  // 0 for scan lines
};

/// Rows per chunk of a scan-line file under `compression` (OpenEXR's enum); 256 (the most any
/// compression takes) for one OpenEXR will refuse anyway.
int64_t rowsPerChunk(int compression) {
    switch (compression) {
        case 0:  // none
        case 1:  // RLE
        case 2:  // ZIPS
            return 1;
        case 3:  // ZIP
        case 5:  // PXR24
            return 16;
        case 4:  // PIZ
        case 6:  // B44
        case 7:  // B44A
        case 8:  // DWAA
            return 32;
        default:  // DWAB (9) and unknown
            return 256;
    }
}

/// The most one chunk of an image (a tile, or a scan-line file's rows that are compressed
/// together) may decode to: OpenEXR 3.1 allocates buffers of that size before it reads a chunk,
/// so a 634-byte file claiming 16 rows 6.8 M pixels wide made it take 1.3 GB (and 8 s under
/// ASan) before finding no pixels. 2^28 bytes: 256 rows (DWAB) of 16384 pixels of 16 float
/// channels.
constexpr uint64_t kMaxChunkBytes = uint64_t(1) << 28;

}  // namespace

void checkExrHeaders(const std::string& path) {
    // OpenEXR 3.1 sizes what it allocates by what the file claims, before reading it: an
    // attribute's value by its declared size (a 500-byte file whose string attribute claimed 2 GB
    // made `compare` allocate and clear 1.7 GB for 8 s before OpenEXR found the end of the file),
    // buffers by the data window, channels and compression. An attribute is a name, a type name
    // (each ended by a zero byte), a 32-bit little-endian size and that many bytes; a header ends
    // with an empty name; a multi-part file has one header per part and an empty header after
    // them. This walk must read the bytes OpenEXR reads, or it checks other bytes than OpenEXR
    // then trusts: a channel list is read up to its empty name and a fixed-size value (an int, a
    // box) by its type, whatever size the file declares. A declared size that disagrees with
    // those bytes is damage, refused here (a fuzzed file whose channel list claimed 55 bytes and
    // held 19 had OpenEXR read a string's size from where this walk saw a name).
    std::error_code error;
    const uint64_t file_size = std::filesystem::file_size(path, error);
    std::ifstream in(path, std::ios::binary);
    if (error || !in) return;  // OpenEXR names what is wrong with the file
    unsigned char start[8] = {};
    if (!in.read(reinterpret_cast<char*>(start), sizeof(start))) return;
    const bool multi_part = (start[5] & 0x10) != 0;  // version flag bit 12
    // A name longer than 255 characters is damage that OpenEXR reports itself.
    auto readName = [&](std::string& name) {
        name.clear();
        for (int c = in.get(); c != EOF; c = in.get()) {
            if (c == 0) return true;
            if (name.size() == 255) return false;
            name.push_back(char(c));
        }
        return false;
    };
    auto refuseSize = [&](const std::string& name, const std::string& type, int32_t size, const std::string& holds) {
        throwReadError(path, "header attribute '" + detail::printable(name) + "' (" + detail::printable(type) +
                                 ") claims " + std::to_string(size) + " bytes where " + holds +
                                 ": the file is damaged or cut short");
    };
    std::string name;
    std::string type;
    std::vector<unsigned char> value;
    for (int part = 0;; ++part) {
        ExrPartShape shape;
        while (readName(name) && !name.empty()) {
            if (!readName(type)) return;
            unsigned char size_bytes[4] = {};
            if (!in.read(reinterpret_cast<char*>(size_bytes), sizeof(size_bytes))) return;
            const int32_t size = int32_t(littleEndian32(size_bytes));
            const uint64_t left = file_size - std::min<uint64_t>(file_size, uint64_t(in.tellg()));
            if (size < 0 || uint64_t(size) > left) {
                refuseSize(name, type, size, "the file has " + std::to_string(left) + " left");
            }
            const int fixed = fixedValueBytes(type);
            if (fixed >= 0 && size != fixed) refuseSize(name, type, size, "a " + type + " is " + std::to_string(fixed));
            value.resize(size_t(size));
            if (!in.read(reinterpret_cast<char*>(value.data()), size)) return;
            if (type == "chlist") {
                // Each channel: its name, a zero byte, then 16 bytes: the pixel type (0 uint,
                // 1 half, 2 float), pLinear, 3 reserved bytes, x and y sampling. An empty name ends.
                size_t at = 0;
                for (;;) {
                    const auto end = std::find(value.begin() + std::ptrdiff_t(at), value.end(), 0);
                    if (end == value.end()) refuseSize(name, type, size, "its channels run past them");
                    const size_t name_length = size_t(end - value.begin()) - at;
                    at += name_length + 1;
                    if (name_length == 0) break;
                    if (at + 16 > value.size()) refuseSize(name, type, size, "its channels run past them");
                    shape.bytes_per_pixel += littleEndian32(value.data() + at) == 1 ? 2 : 4;
                    at += 16;
                }
                if (at != value.size()) refuseSize(name, type, size, "its channels take " + std::to_string(at));
            } else if (name == "dataWindow" && type == "box2i") {
                shape.width = int64_t(int32_t(littleEndian32(&value[8]))) - int32_t(littleEndian32(&value[0])) + 1;
                shape.height = int64_t(int32_t(littleEndian32(&value[12]))) - int32_t(littleEndian32(&value[4])) + 1;
            } else if (name == "compression" && type == "compression") {
                shape.compression = value[0];
            } else if (name == "tiles" && type == "tiledesc") {
                shape.tile_width = littleEndian32(&value[0]);
                shape.tile_height = littleEndian32(&value[4]);
            }
        }
        if (!in || !name.empty()) return;
        const std::string where = multi_part ? " (part " + std::to_string(part) + ")" : std::string();
        if (shape.width > 0 && shape.height > 0 &&
            uint64_t(shape.width) * uint64_t(shape.height) > detail::kMaxImagePixels) {
            throwReadError(path, std::to_string(shape.width) + "x" + std::to_string(shape.height) + where + " is " +
                                     detail::kTooManyPixels);
        }
        const bool tiled = shape.tile_width > 0 || shape.tile_height > 0;
        const double chunk_pixels = tiled ? double(shape.tile_width) * double(shape.tile_height)
                                          : double(rowsPerChunk(shape.compression)) *
                                                double(std::max<int64_t>(shape.width, 0));
        const double chunk_bytes = chunk_pixels * double(shape.bytes_per_pixel);
        if (chunk_bytes > double(kMaxChunkBytes)) {
            const std::string chunk = tiled ? "a tile of " + std::to_string(shape.tile_width) + "x" +
                                                  std::to_string(shape.tile_height) + " pixels"
                                            : "a chunk of " + std::to_string(rowsPerChunk(shape.compression)) +
                                                  " rows " + std::to_string(shape.width) + " pixels wide";
            throwReadError(path, chunk + where + " of " + std::to_string(shape.bytes_per_pixel) +
                                     " bytes a pixel decodes to " + std::to_string(int64_t(chunk_bytes / 1048576.0)) +
                                     " MiB, more than the 256 MiB sharcbake reads (256 rows 16384 pixels wide of 16 "
                                     "float channels)");
        }
        if (!multi_part || in.peek() == 0) return;
    }
}

int exrRowsPerStrip(int width) {
    constexpr int64_t kPixelsPerStrip = int64_t(1) << 22;
    int rows = 256;
    while (rows > 1 && int64_t(rows) * width > kPixelsPerStrip) rows /= 2;
    return rows;
}

Image readExr(const std::string& path, ImageMetadata* metadata) {
    try {
        checkExrHeaders(path);
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        const int64_t width64 = int64_t(dw.max.x) - int64_t(dw.min.x) + 1;
        const int64_t height64 = int64_t(dw.max.y) - int64_t(dw.min.y) + 1;
        if (width64 <= 0 || height64 <= 0 || width64 > std::numeric_limits<int>::max() ||
            height64 > std::numeric_limits<int>::max()) {
            throwReadError(path, "invalid data window");
        }
        const int width = int(width64);
        const int height = int(height64);

        ImageMetadata attributes;
        if (metadata != nullptr) {
            for (auto it = header.begin(); it != header.end(); ++it) {
                if (std::strcmp(it.attribute().typeName(), Imf::StringAttribute::staticTypeName()) == 0) {
                    attributes[it.name()] = static_cast<const Imf::StringAttribute&>(it.attribute()).value();
                }
            }
        }

        const Imf::ChannelList& channels = header.channels();
        const std::string layer = pictureLayer(path, channels);
        const std::string rgb_names[3] = {layer + "R", layer + "G", layer + "B"};
        const Imf::Channel* rgb[3] = {channels.findChannel(rgb_names[0]), channels.findChannel(rgb_names[1]),
                                      channels.findChannel(rgb_names[2])};
        const Imf::Channel* luminance = channels.findChannel("Y");
        const bool has_rgb = rgb[0] != nullptr || rgb[1] != nullptr || rgb[2] != nullptr;
        const bool has_chroma = channels.findChannel("RY") != nullptr || channels.findChannel("BY") != nullptr;

        Image image;
        if (!has_rgb && luminance != nullptr && has_chroma) {
            image = readLuminanceChroma(path, dw);
        } else {
            // Rows are allocated as OpenEXR decodes them, a strip at a time: a damaged header of
            // 108 M pixels (16 rows 6.8 M wide) in a 634-byte file made clearing the whole image
            // up front take over 10 s under ASan before OpenEXR found no pixels. The reserved capacity is address
            // space only, and keeps the frame buffer's pointer valid while the rows grow.
            image.width = width;
            image.height = height;
            image.pixels.reserve(size_t(width) * size_t(height));
            char* first = reinterpret_cast<char*>(image.pixels.data());
            const size_t x_stride = sizeof(glm::vec3);
            const size_t y_stride = x_stride * size_t(width);
            Imf::FrameBuffer frame;
            auto insert = [&](const std::string& name, const Imf::Channel* channel, int component) {
                if (channel->xSampling != 1 || channel->ySampling != 1) {
                    throwReadError(path, "sub-sampled channel '" + name + "' is not supported");
                }
                frame.insert(name, Imf::Slice::Make(Imf::FLOAT, first + size_t(component) * sizeof(float), dw,
                                                    x_stride, y_stride));
            };
            const bool luminance_only = !has_rgb && luminance != nullptr;
            if (luminance_only) {
                insert("Y", luminance, 0);
            } else {
                for (int c = 0; c < 3; ++c) {
                    if (rgb[c] != nullptr) insert(rgb_names[c], rgb[c], c);  // missing: stays 0
                }
            }
            file.setFrameBuffer(frame);
            const int rows_per_strip = exrRowsPerStrip(width);
            for (int64_t y = dw.min.y; y <= dw.max.y; y += rows_per_strip) {
                const int64_t last = std::min<int64_t>(dw.max.y, y + rows_per_strip - 1);
                image.pixels.resize(size_t(last - dw.min.y + 1) * size_t(width), glm::vec3(0.0f));
                file.readPixels(int(y), int(last));
            }
            if (luminance_only) {
                for (glm::vec3& p : image.pixels) p = glm::vec3(p.r);
            }
        }
        if (metadata != nullptr) *metadata = std::move(attributes);
        return image;
    } catch (const ImageError&) {
        throw;
    } catch (const std::bad_alloc&) {
        throwReadError(path, "out of memory (image too large?)");
    } catch (const std::exception& e) {
        throwReadError(path, e.what());
    }
}

}  // namespace sharcbake
