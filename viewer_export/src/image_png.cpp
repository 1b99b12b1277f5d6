// SPDX-License-Identifier: Apache-2.0
// Tone-mapped 8-bit sRGB PNG previews (stb_image_write from Debian's libstb).
#include "image_internal.h"
#include "sharcbake/image.h"

// Debian's libstb.so carries the stb implementation, so no STB_IMAGE_WRITE_IMPLEMENTATION here.
#include <stb_image_write.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

/// Narkowicz's fit of the ACES filmic curve ("ACES Filmic Tone Mapping Curve", 2015), applied to
/// the exposed value as is (no 0.6 pre-scale).
float acesNarkowicz(float x) {
    constexpr float a = 2.51f, b = 0.03f, c = 2.43f, d = 0.59f, e = 0.14f;
    return (x * (a * x + b)) / (x * (c * x + d) + e);
}

/// sRGB opto-electronic transfer function (IEC 61966-2-1); exactly 1 at 1 (in float,
/// 1.055 - 0.055 would round to 0.99999994).
float srgbOetf(float x) {
    if (x >= 1.0f) return 1.0f;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

/// One channel. Non-finite and negative values are handled first, deterministically:
/// NaN -> 0, negative (including -Inf) -> 0, +Inf -> 1 (whatever the operator).
float toneMapChannel(float linear, float scale, ToneMap tone_map) {
    float x = linear * scale;
    if (std::isnan(x) || x <= 0.0f) return 0.0f;
    if (std::isinf(x)) return 1.0f;
    switch (tone_map) {
        case ToneMap::Clamp: x = std::min(x, 1.0f); break;
        case ToneMap::Reinhard: x = x / (1.0f + x); break;
        case ToneMap::Aces: x = acesNarkowicz(x); break;
    }
    if (!(x >= 0.0f)) return 0.0f;  // paranoia: NaN from the operator
    x = std::min(x, 1.0f);
    return std::clamp(srgbOetf(x), 0.0f, 1.0f);
}

void appendBytes(void* context, void* data, int size) {
    auto* out = static_cast<std::vector<unsigned char>*>(context);
    const auto* bytes = static_cast<const unsigned char*>(data);
    if (size > 0) out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

glm::vec3 toneMapPixel(glm::vec3 linear, float exposure_stops, ToneMap tone_map) {
    // exp2 of a NaN exposure is NaN, which maps every channel to 0.
    const float scale = std::exp2(exposure_stops);
    return glm::vec3(toneMapChannel(linear.r, scale, tone_map), toneMapChannel(linear.g, scale, tone_map),
                     toneMapChannel(linear.b, scale, tone_map));
}

void writePng(const std::string& path, const Image& image, float exposure_stops, ToneMap tone_map) {
    detail::checkImageShape(path, image, "PNG");
    if (image.width > INT_MAX / 3) {
        throw ImageError("cannot write PNG '" + path + "': image is too wide (" + std::to_string(image.width) + ")");
    }
    std::vector<unsigned char> rgb;
    std::vector<unsigned char> png;
    try {
        rgb.resize(image.pixels.size() * 3);
        for (size_t i = 0; i < image.pixels.size(); ++i) {
            const glm::vec3 v = toneMapPixel(image.pixels[i], exposure_stops, tone_map);
            for (int c = 0; c < 3; ++c) rgb[3 * i + size_t(c)] = static_cast<unsigned char>(v[c] * 255.0f + 0.5f);
        }
    } catch (const std::bad_alloc&) {
        throw ImageError("cannot write PNG '" + path + "': out of memory");
    }
    const int ok = stbi_write_png_to_func(appendBytes, &png, image.width, image.height, 3, rgb.data(),
                                          image.width * 3);
    if (ok == 0 || png.empty()) throw ImageError("cannot write PNG '" + path + "': PNG encoding failed");
    detail::writeFileAtomically(path, png.data(), png.size());
}

}  // namespace sharcbake
