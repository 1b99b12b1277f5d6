// SPDX-License-Identifier: Apache-2.0
/// @file equirect_exr.cpp
/// @brief Reads an equirectangular environment map from OpenEXR into a linear float Texture.
#include "sharcbake/image.h"
#include "sharcbake/scene_loader.h"

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <Iex.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

[[noreturn]] void failExr(const std::string& path, const std::string& what) {
    throw SceneLoadError(path + ": " + what);
}

std::string channelNames(const Imf::ChannelList& channels) {
    std::string names;
    for (auto it = channels.begin(); it != channels.end(); ++it) {
        if (!names.empty()) names += ", ";
        names += it.name();
    }
    return names.empty() ? "none" : names;
}

/// Which channels to read: colour (R, G, B and maybe A) or luminance only (Y).
struct ChannelLayout {
    bool luminance = false;
    bool alpha = false;
};

ChannelLayout chooseChannels(const std::string& path, const Imf::ChannelList& channels) {
    ChannelLayout layout;
    const bool rgb = channels.findChannel("R") && channels.findChannel("G") && channels.findChannel("B");
    if (rgb) {
        layout.alpha = channels.findChannel("A") != nullptr;
        return layout;
    }
    if (channels.findChannel("Y")) {
        // Luminance-only (or luminance/chroma) files: grey sky from Y. Chroma (RY, BY) is
        // ignored because the Y channel alone is the radiance a grey map needs.
        layout.luminance = true;
        layout.alpha = channels.findChannel("A") != nullptr;
        return layout;
    }
    failExr(path, "no R,G,B or Y channels to read as an environment map (channels: " +
                      channelNames(channels) + ")");
}

/// Binds float slices for the chosen channels straight into the RGBA texel array. OpenEXR
/// converts half and uint channels to float, and fills channels absent from the file with
/// the slice's fill value (alpha = 1).
Imf::FrameBuffer makeFrameBuffer(const ChannelLayout& layout, const Imath::Box2i& window,
                                 std::vector<glm::vec4>& texels) {
    const int width = window.max.x - window.min.x + 1;
    const size_t xStride = sizeof(glm::vec4);
    const size_t yStride = xStride * static_cast<size_t>(width);
    // OpenEXR addresses pixels by their data-window coordinates, so the base pointer is moved
    // back by the window origin (the pointer arithmetic is OpenEXR's documented convention).
    char* base = reinterpret_cast<char*>(texels.data()) -
                 static_cast<ptrdiff_t>(window.min.x) * static_cast<ptrdiff_t>(xStride) -
                 static_cast<ptrdiff_t>(window.min.y) * static_cast<ptrdiff_t>(yStride);
    auto slice = [&](int component, double fill) {
        return Imf::Slice(Imf::FLOAT, base + component * sizeof(float), xStride, yStride, 1, 1, fill);
    };
    Imf::FrameBuffer fb;
    if (layout.luminance) {
        fb.insert("Y", slice(0, 0.0));
    } else {
        fb.insert("R", slice(0, 0.0));
        fb.insert("G", slice(1, 0.0));
        fb.insert("B", slice(2, 0.0));
    }
    fb.insert("A", slice(3, 1.0));
    return fb;
}

/// A sky with NaN or infinity would poison every path that escapes, so refuse it; negative
/// radiance is meaningless and comes from filtered/compressed HDRIs, so clamp it to zero.
void checkAndClampTexels(const std::string& path, std::vector<glm::vec4>& texels, bool luminance) {
    size_t nonFinite = 0;
    for (glm::vec4& t : texels) {
        if (luminance) t = glm::vec4(t.x, t.x, t.x, t.w);
        for (int c = 0; c < 3; ++c) {
            if (!std::isfinite(t[c])) ++nonFinite;
            t[c] = std::max(t[c], 0.0f);
        }
    }
    if (nonFinite > 0)
        failExr(path, std::to_string(nonFinite) + " colour values are NaN or infinite");
}

}  // namespace

Texture loadEquirectExr(const std::string& path) {
    if (!std::filesystem::exists(path)) failExr(path, "file not found");
    try {
        checkExrHeaders(path);  // damage OpenEXR would first allocate for, and maps of over 2^27 texels
        Imf::InputFile file(path.c_str());
        const Imath::Box2i window = file.header().dataWindow();
        const int64_t width64 = int64_t(window.max.x) - window.min.x + 1;
        const int64_t height64 = int64_t(window.max.y) - window.min.y + 1;
        if (width64 <= 0 || height64 <= 0) failExr(path, "empty data window");
        if (width64 > std::numeric_limits<int>::max() || height64 > std::numeric_limits<int>::max())
            failExr(path, "the data window is wider or taller than 2^31 texels");
        const int width = int(width64);
        const int height = int(height64);

        const ChannelLayout layout = chooseChannels(path, file.header().channels());
        Texture tex;
        tex.name = std::filesystem::path(path).filename().string();
        tex.width = width;
        tex.height = height;
        // Longitude wraps around; latitude stops at the poles.
        tex.wrap_s = WrapMode::Repeat;
        tex.wrap_t = WrapMode::ClampToEdge;

        // Texels are allocated as OpenEXR decodes their rows, a strip at a time, so that a
        // damaged header of 2^27 texels in a small file costs no 2 GB clear before OpenEXR finds
        // the rows missing. The reserved capacity (address space only) keeps the frame buffer's
        // pointer valid while the rows grow.
        tex.texels.reserve(static_cast<size_t>(width) * height);
        file.setFrameBuffer(makeFrameBuffer(layout, window, tex.texels));
        const int rows_per_strip = exrRowsPerStrip(width);
        for (int64_t y = window.min.y; y <= window.max.y; y += rows_per_strip) {
            const int64_t last = std::min<int64_t>(window.max.y, y + rows_per_strip - 1);
            tex.texels.resize(static_cast<size_t>(last - window.min.y + 1) * width, glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
            file.readPixels(int(y), int(last));
        }
        checkAndClampTexels(path, tex.texels, layout.luminance);
        return tex;
    } catch (const SceneLoadError&) {
        throw;
    } catch (const ImageError& e) {
        throw SceneLoadError(e.what());
    } catch (const std::exception& e) {
        // Iex exceptions derive from std::exception; their text says what OpenEXR disliked.
        failExr(path, std::string("cannot read OpenEXR file: ") + e.what());
    }
}

}  // namespace sharcbake
