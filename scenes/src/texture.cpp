// SPDX-License-Identifier: Apache-2.0
/// @file texture.cpp
/// @brief Texture::sample: bilinear or nearest lookup with glTF wrap modes, over float or 8-bit
/// texels (decoded through 256-entry tables); UvTransform.
#include "sharcbake/scene.h"

#include <algorithm>
#include <cmath>

namespace sharcbake {
namespace {

/// Brings a texture coordinate into a small range before scaling by the texture size, so a
/// huge coordinate (tiling by 1e9) cannot overflow the integer texel index. The reduced value
/// maps to the same texels as the original under the wrap mode.
double reduceCoordinate(double c, WrapMode mode) {
    if (!std::isfinite(c)) return 0.0;  // a NaN uv must not become an out-of-range index
    switch (mode) {
    case WrapMode::Repeat: return c - std::floor(c);                      // [0, 1)
    case WrapMode::MirroredRepeat: return c - 2.0 * std::floor(c * 0.5);  // [0, 2): one period
    case WrapMode::ClampToEdge: return std::clamp(c, -1.0, 2.0);          // beyond is all edge
    }
    return c;
}

/// Maps an integer texel index (possibly just outside [0, n)) into [0, n).
int wrapIndex(int64_t i, int n, WrapMode mode) {
    switch (mode) {
    case WrapMode::Repeat: {
        int64_t m = i % n;
        return static_cast<int>(m < 0 ? m + n : m);
    }
    case WrapMode::MirroredRepeat: {
        const int64_t period = 2 * static_cast<int64_t>(n);
        int64_t m = i % period;
        if (m < 0) m += period;
        return static_cast<int>(m < n ? m : period - 1 - m);
    }
    case WrapMode::ClampToEdge: return static_cast<int>(std::clamp<int64_t>(i, 0, n - 1));
    }
    return 0;
}

}  // namespace

UvTransform UvTransform::fromGltf(glm::vec2 offset, float rotation, glm::vec2 scale) {
    UvTransform t;
    if (offset == glm::vec2(0.0f) && rotation == 0.0f && scale == glm::vec2(1.0f)) return t;
    // glTF's translation * rotation * scale, with the rotation as the extension's reference
    // implementations and sample model read it (u' = u cos + v sin, v' = v cos - u sin): the
    // specification's example, offset [0, 1], rotation pi/2 and scale 0.5, then maps the unit
    // square onto the image's lower-left quadrant, as it says.
    const float c = std::cos(rotation), s = std::sin(rotation);
    t.column_u = glm::vec2(c, -s) * scale.x;
    t.column_v = glm::vec2(s, c) * scale.y;
    t.offset = offset;
    t.identity = false;
    return t;
}

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

const std::array<float, 256>& srgb8ToLinear() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = srgbToLinear(i / 255.0f);
        return t;
    }();
    return table;
}

const std::array<float, 256>& unorm8ToFloat() {
    static const std::array<float, 256> table = [] {
        std::array<float, 256> t{};
        for (int i = 0; i < 256; ++i) t[size_t(i)] = i / 255.0f;
        return t;
    }();
    return table;
}

size_t Texture::texelCount() const {
    if (encoding == TexelEncoding::Float) return texels.size();
    return texels8 ? texels8->size() : 0;
}

namespace {

/// The lookup itself, over any storage: `fetch(index)` gives texel `index` as linear RGBA. The
/// filtering arithmetic is the same for every encoding (the decoded corners are mixed as floats),
/// so an 8-bit texture samples to the same bits as the float texture it replaces.
template <typename Fetch>
glm::vec4 filtered(const Texture& t, glm::vec2 uv, const Fetch& fetch) {
    const double u = reduceCoordinate(uv.x, t.wrap_s);
    const double v = reduceCoordinate(uv.y, t.wrap_t);
    auto texel = [&](int64_t x, int64_t y) -> glm::vec4 {
        const int xi = wrapIndex(x, t.width, t.wrap_s);
        const int yi = wrapIndex(y, t.height, t.wrap_t);
        return fetch(static_cast<size_t>(yi) * t.width + xi);
    };

    if (t.nearest) {
        return texel(static_cast<int64_t>(std::floor(u * t.width)), static_cast<int64_t>(std::floor(v * t.height)));
    }
    // Texel centres sit at half-integer coordinates, so shift by half a texel before
    // splitting into the integer corner and the interpolation weights.
    const double x = u * t.width - 0.5;
    const double y = v * t.height - 0.5;
    const double x0 = std::floor(x);
    const double y0 = std::floor(y);
    const float fx = static_cast<float>(x - x0);
    const float fy = static_cast<float>(y - y0);
    const auto ix = static_cast<int64_t>(x0);
    const auto iy = static_cast<int64_t>(y0);
    const glm::vec4 top = glm::mix(texel(ix, iy), texel(ix + 1, iy), fx);
    const glm::vec4 bottom = glm::mix(texel(ix, iy + 1), texel(ix + 1, iy + 1), fx);
    return glm::mix(top, bottom, fy);
}

/// An RGBA8 texel decoded through `colour` (R, G, B) and the linear table (A).
struct Decode8 {
    const std::vector<glm::u8vec4>& texels;
    const std::array<float, 256>& colour;
    const std::array<float, 256>& linear;
    glm::vec4 operator()(size_t index) const {
        const glm::u8vec4 t = texels[index];
        return {colour[t.x], colour[t.y], colour[t.z], linear[t.w]};
    }
};

}  // namespace

glm::vec4 Texture::sample(glm::vec2 uv) const {
    // An empty texture is neutral: textures multiply factors, so white changes nothing.
    if (width <= 0 || height <= 0 || texelCount() < static_cast<size_t>(width) * height) return glm::vec4(1.0f);
    switch (encoding) {
        case TexelEncoding::Srgb8: return filtered(*this, uv, Decode8{*texels8, srgb8ToLinear(), unorm8ToFloat()});
        case TexelEncoding::Linear8: return filtered(*this, uv, Decode8{*texels8, unorm8ToFloat(), unorm8ToFloat()});
        case TexelEncoding::Float: break;
    }
    return filtered(*this, uv, [this](size_t index) -> const glm::vec4& { return texels[index]; });
}

}  // namespace sharcbake
