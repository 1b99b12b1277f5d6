// SPDX-License-Identifier: Apache-2.0
/// @file texture_test.cpp
/// @brief Texture::sample: filtering, wrap modes, the v = 0 top-row convention, and 8-bit texels
/// sampling to the same bits as the float texels they replaced.
#include "sharcbake/scene.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

namespace sharcbake {
namespace {

/// A 4x1 texture whose red channel is the texel index: 0, 1, 2, 3.
Texture ramp(WrapMode wrap, bool nearest) {
    Texture t;
    t.width = 4;
    t.height = 1;
    for (int i = 0; i < 4; ++i) t.texels.emplace_back(static_cast<float>(i), 0.0f, 0.0f, 1.0f);
    t.wrap_s = t.wrap_t = wrap;
    t.nearest = nearest;
    return t;
}

float red(const Texture& t, float u) { return t.sample({u, 0.5f}).x; }

TEST(TextureSample, NearestPicksTexelContainingUv) {
    const Texture t = ramp(WrapMode::Repeat, true);
    EXPECT_FLOAT_EQ(red(t, 0.01f), 0.0f);
    EXPECT_FLOAT_EQ(red(t, 0.26f), 1.0f);
    EXPECT_FLOAT_EQ(red(t, 0.99f), 3.0f);
}

TEST(TextureSample, BilinearInterpolatesBetweenTexelCentres) {
    const Texture t = ramp(WrapMode::ClampToEdge, false);
    EXPECT_FLOAT_EQ(red(t, 0.125f), 0.0f);  // centre of texel 0
    EXPECT_FLOAT_EQ(red(t, 0.375f), 1.0f);  // centre of texel 1
    EXPECT_NEAR(red(t, 0.25f), 0.5f, 1e-6f);  // half way
    EXPECT_NEAR(red(t, 0.3125f), 0.75f, 1e-6f);
}

TEST(TextureSample, RepeatWrapsAround) {
    const Texture t = ramp(WrapMode::Repeat, false);
    EXPECT_NEAR(red(t, 1.375f), red(t, 0.375f), 1e-5f);
    EXPECT_NEAR(red(t, -0.625f), red(t, 0.375f), 1e-5f);
    // Across the seam, the left edge blends the last and first texels.
    EXPECT_NEAR(red(t, 0.0f), 1.5f, 1e-6f);
    EXPECT_NEAR(red(t, 1e6f + 0.375f), 1.0f, 1e-2f);  // huge uv must not overflow
}

TEST(TextureSample, ClampToEdgeHoldsEdgeTexels) {
    const Texture t = ramp(WrapMode::ClampToEdge, false);
    EXPECT_FLOAT_EQ(red(t, -3.0f), 0.0f);
    EXPECT_FLOAT_EQ(red(t, 0.0f), 0.0f);
    EXPECT_FLOAT_EQ(red(t, 1.0f), 3.0f);
    EXPECT_FLOAT_EQ(red(t, 5.0f), 3.0f);
}

TEST(TextureSample, MirroredRepeatReflects) {
    const Texture t = ramp(WrapMode::MirroredRepeat, true);
    EXPECT_FLOAT_EQ(red(t, 1.1f), 3.0f);   // just past 1 mirrors back onto the last texel
    EXPECT_FLOAT_EQ(red(t, 1.3f), 2.0f);
    EXPECT_FLOAT_EQ(red(t, 1.9f), 0.0f);
    EXPECT_FLOAT_EQ(red(t, 2.1f), 0.0f);   // period 2: back to forwards
    EXPECT_FLOAT_EQ(red(t, -0.1f), 0.0f);  // mirror at 0
    EXPECT_FLOAT_EQ(red(t, -0.3f), 1.0f);
    const Texture b = ramp(WrapMode::MirroredRepeat, false);
    EXPECT_NEAR(red(b, 1.0f), 3.0f, 1e-6f);  // the mirror seam blends texel 3 with itself
}

TEST(TextureSample, VZeroIsTopRow) {
    Texture t;
    t.width = 1;
    t.height = 2;
    t.texels = {glm::vec4(1, 0, 0, 1), glm::vec4(0, 1, 0, 1)};  // row 0 red, row 1 green
    t.nearest = true;
    EXPECT_FLOAT_EQ(t.sample({0.5f, 0.1f}).x, 1.0f);
    EXPECT_FLOAT_EQ(t.sample({0.5f, 0.9f}).y, 1.0f);
}

TEST(TextureSample, IndependentWrapPerAxis) {
    Texture t;
    t.width = 2;
    t.height = 2;
    t.texels = {glm::vec4(0), glm::vec4(1), glm::vec4(2), glm::vec4(3)};
    t.nearest = true;
    t.wrap_s = WrapMode::Repeat;
    t.wrap_t = WrapMode::ClampToEdge;
    EXPECT_FLOAT_EQ(t.sample({1.25f, 7.0f}).x, 2.0f);  // s wraps to column 0, t clamps to row 1
}

TEST(TextureSample, EmptyTextureIsNeutralWhite) {
    const Texture t;
    EXPECT_EQ(t.sample({0.3f, 0.7f}), glm::vec4(1.0f));
}

TEST(TextureSample, NanUvDoesNotCrash) {
    const Texture t = ramp(WrapMode::Repeat, false);
    const glm::vec4 v = t.sample({std::nanf(""), std::nanf("")});
    EXPECT_TRUE(std::isfinite(v.x));
}

/// sRGB to linear as the loader converted every texel when textures were stored as floats.
float referenceSrgb(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

TEST(TextureSample, EightBitTablesAreTheFloatConversion) {
    for (int i = 0; i < 256; ++i) {
        EXPECT_EQ(srgb8ToLinear()[size_t(i)], referenceSrgb(i / 255.0f)) << i;
        EXPECT_EQ(unorm8ToFloat()[size_t(i)], i / 255.0f) << i;
    }
}

/// A 16x16 RGBA8 image holding every code in each channel, in different places per channel, as
/// an 8-bit texture read as `encoding` and as the float texture the loader used to make of it.
std::pair<Texture, Texture> eightBitAndFloat(TexelEncoding encoding, WrapMode wrap, bool nearest) {
    auto texels8 = std::make_shared<std::vector<glm::u8vec4>>();
    Texture reference;
    const bool srgb = encoding == TexelEncoding::Srgb8;
    auto colour = [&](uint8_t c) { return srgb ? referenceSrgb(c / 255.0f) : c / 255.0f; };
    for (int i = 0; i < 256; ++i) {
        const glm::u8vec4 t(uint8_t(i), uint8_t(255 - i), uint8_t(i * 7), uint8_t(i * 13));
        texels8->push_back(t);
        reference.texels.emplace_back(colour(t.x), colour(t.y), colour(t.z), t.w / 255.0f);  // alpha linear
    }
    Texture eight;
    eight.encoding = encoding;
    eight.texels8 = texels8;
    for (Texture* t : {&eight, &reference}) {
        t->width = t->height = 16;
        t->wrap_s = t->wrap_t = wrap;
        t->nearest = nearest;
    }
    return {eight, reference};
}

TEST(TextureSample, EightBitTexelsSampleBitForBitAsFloatTexels) {
    for (const TexelEncoding encoding : {TexelEncoding::Srgb8, TexelEncoding::Linear8}) {
        for (const WrapMode wrap : {WrapMode::Repeat, WrapMode::ClampToEdge, WrapMode::MirroredRepeat}) {
            for (const bool nearest : {false, true}) {
                const auto [eight, reference] = eightBitAndFloat(encoding, wrap, nearest);
                ASSERT_EQ(eight.texelCount(), 256u);
                for (size_t i = 0; i < 256; ++i) ASSERT_EQ(eight.texel(i), reference.texels[i]) << i;
                // Bilinear weights of every kind: texel centres, edges, seams, outside [0, 1].
                for (int y = -20; y <= 52; ++y) {
                    for (int x = -20; x <= 52; ++x) {
                        const glm::vec2 uv(x * 0.0371f, y * 0.0293f);
                        const glm::vec4 a = eight.sample(uv), b = reference.sample(uv);
                        ASSERT_EQ(std::memcmp(&a, &b, sizeof a), 0)
                            << "encoding " << int(encoding) << " wrap " << int(wrap) << " nearest " << nearest << " uv "
                            << uv.x << ", " << uv.y;
                    }
                }
            }
        }
    }
}

TEST(TextureSample, EightBitTextureWithoutTexelsIsNeutralWhite) {
    Texture t;
    t.width = t.height = 2;
    t.encoding = TexelEncoding::Srgb8;
    EXPECT_EQ(t.texelCount(), 0u);
    EXPECT_EQ(t.sample({0.3f, 0.7f}), glm::vec4(1.0f));
}

}  // namespace
}  // namespace sharcbake
