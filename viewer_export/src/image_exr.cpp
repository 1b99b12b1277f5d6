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

/// A header attribute's name as it may be printed: control and non-ASCII bytes as '?'.
std::string printableName(const std::string& name) {
    std::string out = name;
    for (char& c : out) {
        if (c < 0x20 || c > 0x7e) c = '?';
    }
    return out;
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
                                 (names.empty() ? std::string("none") : names) + ")");
    }
    throwReadError(path, "several layers hold R, G and B (" + names +
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

void checkExrHeaders(const std::string& path) {
    // OpenEXR 3.1 sizes an attribute's value by what the file claims before reading it: a
    // 500-byte file whose string attribute claims 2 GB made `compare` allocate and clear 1.7 GB
    // for 8 s before OpenEXR found the end of the file. An attribute is a name, a type name (each
    // ended by a zero byte), a 32-bit little-endian size and that many bytes; a header ends with
    // an empty name; a multi-part file has one header per part and an empty header after them.
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
    std::string name;
    std::string type;
    bool first_header = true;
    for (;;) {
        while (readName(name) && !name.empty()) {
            if (!readName(type)) return;
            unsigned char size_bytes[4] = {};
            if (!in.read(reinterpret_cast<char*>(size_bytes), sizeof(size_bytes))) return;
            const int32_t size = int32_t(littleEndian32(size_bytes));
            const uint64_t left = file_size - std::min<uint64_t>(file_size, uint64_t(in.tellg()));
            if (size < 0 || uint64_t(size) > left) {
                throwReadError(path, "header attribute '" + printableName(name) + "' (" + printableName(type) +
                                         ") claims " + std::to_string(size) + " bytes where the file has " +
                                         std::to_string(left) + " left: the file is damaged or cut short");
            }
            if (first_header && name == "dataWindow" && type == "box2i" && size == 16) {
                unsigned char box[16] = {};
                if (!in.read(reinterpret_cast<char*>(box), sizeof(box))) return;
                const int64_t width = int64_t(int32_t(littleEndian32(box + 8))) - int32_t(littleEndian32(box)) + 1;
                const int64_t height = int64_t(int32_t(littleEndian32(box + 12))) - int32_t(littleEndian32(box + 4)) +
                                       1;
                if (width > 0 && height > 0 && uint64_t(width) * uint64_t(height) > detail::kMaxImagePixels) {
                    throwReadError(path, std::to_string(width) + "x" + std::to_string(height) + " is " +
                                             detail::kTooManyPixels);
                }
                continue;
            }
            in.seekg(size, std::ios::cur);
        }
        if (!in || !name.empty() || !multi_part || in.peek() == 0) return;
        first_header = false;
    }
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
            image = Image(width, height);
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
            file.readPixels(dw.min.y, dw.max.y);
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
