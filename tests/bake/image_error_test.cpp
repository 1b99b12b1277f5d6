// SPDX-License-Identifier: Apache-2.0
// Image error measures (sharcbake compare, bake --report): exact values on small images, the same
// values in any radiance units, and the render-noise estimate against the true variance of a
// simulated Monte Carlo render.
#include "reports/image_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

Image filled(int width, int height, glm::vec3 value) {
    Image image;
    image.width = width;
    image.height = height;
    image.pixels.assign(size_t(width) * size_t(height), value);
    return image;
}

TEST(CompareImages, ExactOnAConstantOffset) {
    // The reference's mean m = 2: the epsilons are (0.1 m)^2 = 0.04 and 0.01 m = 0.02.
    const Image reference = filled(4, 3, glm::vec3(2.0f));
    const Image image = filled(4, 3, glm::vec3(2.5f));
    const ImageComparison e = compareImages(image, reference);
    EXPECT_EQ(e.scale, 2.0);
    EXPECT_FALSE(e.scale_is_fallback);
    EXPECT_NEAR(e.relative_mse, 0.25 / (4.0 + 0.04), 1e-9);
    EXPECT_NEAR(e.mean_relative_error, 0.5 / (2.0 + 0.02), 1e-9);
    EXPECT_NEAR(e.relative_bias, 0.25, 1e-9);
    EXPECT_EQ(e.non_finite_pixels, 0u);
}

// Noise that alternates pixel by pixel averages out over 8x8 tiles; a bias does not. A mask
// that keeps only the unbiased half measures nothing there.
TEST(CompareImages, TilesAverageNoiseAwayAndTheMaskSelectsPixels) {
    const int width = 16, height = 8;
    const Image reference = filled(width, height, glm::vec3(2.0f));
    Image image = reference;
    std::vector<uint8_t> right_half(size_t(width) * size_t(height), 0);
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const size_t i = size_t(y) * size_t(width) + size_t(x);
            const float noise = (x + y) % 2 == 0 ? 0.5f : -0.5f;
            // Left tile: noise around a 10% bias. Right tile: exact.
            image.pixels[i] = x < 8 ? glm::vec3(2.2f + noise) : glm::vec3(2.0f);
            right_half[i] = x >= 8 ? 1 : 0;
        }
    }
    const ImageComparison e = compareImages(image, reference, &right_half);
    // Per pixel, the left tile is off by 0.7 or 0.3 (mean 0.5); over its tile, by 0.2. The
    // reference's mean is 2, so both divide by 2 + 0.02.
    EXPECT_NEAR(e.mean_relative_error, 0.5 * (0.5 / 2.02), 1e-6);
    EXPECT_NEAR(e.tile_mean_relative_error, 0.5 * (0.2 / 2.02), 1e-6);
    EXPECT_EQ(e.masked_pixels, uint64_t(width * height / 2));
    EXPECT_NEAR(e.masked_mean_relative_error, 0.0, 1e-9);
    EXPECT_NEAR(e.masked_relative_mse, 0.0, 1e-9);
    // Without a mask the masked measures are the plain ones.
    const ImageComparison all = compareImages(image, reference);
    EXPECT_EQ(all.masked_pixels, uint64_t(width * height));
    EXPECT_NEAR(all.masked_mean_relative_error, all.mean_relative_error, 1e-12);
    std::vector<uint8_t> wrong_size(3, 1);
    EXPECT_THROW(compareImages(image, reference, &wrong_size), std::invalid_argument);
}

/// An image pair with some of everything: a reference of varied pixels (black ones among them),
/// an image off by varied amounts, one non-finite pixel, and a mask of about half the pixels.
struct VariedPair {
    Image image, reference;
    std::vector<uint8_t> mask;
};

VariedPair variedPair(int width, int height) {
    VariedPair pair;
    pair.reference = filled(width, height, glm::vec3(0.0f));
    pair.image = pair.reference;
    pair.mask.assign(size_t(width) * size_t(height), 0);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    for (size_t i = 0; i < pair.reference.pixels.size(); ++i) {
        const glm::vec3 r = i % 11 == 0 ? glm::vec3(0.0f) : glm::vec3(uniform(random), 3.0f * uniform(random), 0.2f);
        pair.reference.pixels[i] = r;
        pair.image.pixels[i] = r * (0.5f + uniform(random)) + glm::vec3(0.05f * uniform(random));
        pair.mask[i] = uniform(random) < 0.5f ? 1 : 0;
    }
    pair.image.pixels[5] = glm::vec3(std::numeric_limits<float>::infinity());
    return pair;
}

Image scaled(Image image, float factor) {
    for (glm::vec3& p : image.pixels) p *= factor;
    return image;
}

void expectRelativelyNear(double value, double expected, double tolerance, const std::string& what) {
    EXPECT_NEAR(value, expected, tolerance * std::abs(expected) + 1e-15) << what;
}

// Scenes come in any units (physical glTF lights give radiances of hundreds, a dim scene 1e-4):
// the same pair of images in other units must read the same error.
TEST(CompareImages, TheSameInAnyRadianceUnits) {
    const VariedPair pair = variedPair(24, 16);
    const ImageComparison unit = compareImages(pair.image, pair.reference, &pair.mask);
    const Image half_a = scaled(pair.image, 0.8f), half_b = scaled(pair.image, 1.5f);
    const RelativeMseSplit unit_split = splitRelativeMse(half_a, 3, half_b, 5, pair.reference);
    EXPECT_GT(unit.relative_mse, 0.0);
    EXPECT_GT(unit_split.noise, 0.0);
    for (const float factor : {1e-4f, 1e4f}) {
        const std::string what = "scaled by " + std::to_string(factor);
        const ImageComparison e = compareImages(scaled(pair.image, factor), scaled(pair.reference, factor), &pair.mask);
        // Floats scaled by 1e-4 or 1e4 round in their last bit: the measures agree to about 1e-7.
        expectRelativelyNear(e.relative_mse, unit.relative_mse, 1e-6, what);
        expectRelativelyNear(e.mean_relative_error, unit.mean_relative_error, 1e-6, what);
        // The bias is a difference of two means, near 0 here: it keeps their rounding, ~1e-7 of 1.
        EXPECT_NEAR(e.relative_bias, unit.relative_bias, 1e-6) << what;
        expectRelativelyNear(e.tile_mean_relative_error, unit.tile_mean_relative_error, 1e-6, what);
        expectRelativelyNear(e.masked_relative_mse, unit.masked_relative_mse, 1e-6, what);
        expectRelativelyNear(e.masked_mean_relative_error, unit.masked_mean_relative_error, 1e-6, what);
        EXPECT_EQ(e.non_finite_pixels, unit.non_finite_pixels) << what;
        expectRelativelyNear(e.scale, unit.scale * factor, 1e-6, what);
        const RelativeMseSplit split = splitRelativeMse(scaled(half_a, factor), 3, scaled(half_b, factor), 5,
                                                        scaled(pair.reference, factor));
        expectRelativelyNear(split.total, unit_split.total, 1e-6, what);
        expectRelativelyNear(split.noise, unit_split.noise, 1e-6, what);
        expectRelativelyNear(split.rest, unit_split.rest, 1e-6, what);
        expectRelativelyNear(split.rest_standard_error, unit_split.rest_standard_error, 1e-6, what);
    }
    // An image exactly twice a furnace's uniform reference reads the same at radiance 2e-3 as at 2:
    // (x - r)^2 / (r^2 + (0.1 r)^2) = 1 / 1.01, and |x - r| / (|r| + 0.01 r) = 1 / 1.01.
    for (const float radiance : {2e-3f, 2.0f}) {
        const ImageComparison e = compareImages(filled(8, 8, glm::vec3(2.0f * radiance)),
                                                filled(8, 8, glm::vec3(radiance)));
        EXPECT_NEAR(e.relative_mse, 1.0 / 1.01, 1e-6) << radiance;
        EXPECT_NEAR(e.mean_relative_error, 1.0 / 1.01, 1e-6) << radiance;
        EXPECT_NEAR(e.relative_bias, 1.0, 1e-6) << radiance;
    }
}

// A reference of mean 1 has epsilons of 0.01, absolute, as the measures had before they scaled
// with the reference: the values are those of the formulas with 0.01 written out.
TEST(CompareImages, AReferenceOfMeanOneGivesAbsoluteEpsilons) {
    const int width = 16, height = 8;
    Image reference = filled(width, height, glm::vec3(0.0f)), image = reference;
    std::vector<uint8_t> mask(size_t(width) * size_t(height), 0);
    for (size_t i = 0; i < reference.pixels.size(); ++i) {
        // Channel values 0.25, 1 and 1.75 in turn (exact in float), mean 1; the image is off by
        // varied amounts.
        reference.pixels[i] = glm::vec3(0.25f + 0.75f * float(i % 3), 1.0f, 1.75f - 0.75f * float(i % 3));
        image.pixels[i] = reference.pixels[i] * glm::vec3(1.25f, 0.5f, 1.0f) + glm::vec3(0.125f * float(i % 4));
        mask[i] = i % 3 == 0 ? 1 : 0;
    }
    double squared = 0.0, absolute = 0.0, masked_squared = 0.0, masked_absolute = 0.0;
    uint64_t masked = 0;
    for (size_t i = 0; i < reference.pixels.size(); ++i) {
        masked += mask[i];
        for (int c = 0; c < 3; ++c) {
            const double x = image.pixels[i][c], r = reference.pixels[i][c];
            squared += (x - r) * (x - r) / (r * r + 0.01);
            absolute += std::abs(x - r) / (std::abs(r) + 0.01);
            masked_squared += mask[i] ? (x - r) * (x - r) / (r * r + 0.01) : 0.0;
            masked_absolute += mask[i] ? std::abs(x - r) / (std::abs(r) + 0.01) : 0.0;
        }
    }
    const double terms = 3.0 * double(reference.pixels.size());
    const ImageComparison e = compareImages(image, reference, &mask);
    EXPECT_EQ(e.scale, 1.0);
    EXPECT_FALSE(e.scale_is_fallback);
    EXPECT_NEAR(e.relative_mse, squared / terms, 1e-12);
    EXPECT_NEAR(e.mean_relative_error, absolute / terms, 1e-12);
    EXPECT_EQ(e.masked_pixels, masked);
    EXPECT_NEAR(e.masked_relative_mse, masked_squared / (3.0 * double(masked)), 1e-12);
    EXPECT_NEAR(e.masked_mean_relative_error, masked_absolute / (3.0 * double(masked)), 1e-12);
}

// A black reference has no scale: the epsilons fall back to 0.01, absolute, so nothing divides
// by zero, a black image reads no error and a brighter one more.
TEST(CompareImages, ABlackReferenceDividesByNoZero) {
    const Image black = filled(9, 7, glm::vec3(0.0f));
    const ImageComparison none = compareImages(black, black);
    EXPECT_TRUE(none.scale_is_fallback);
    EXPECT_EQ(none.scale, 1.0);
    EXPECT_EQ(none.relative_mse, 0.0);
    EXPECT_EQ(none.mean_relative_error, 0.0);
    EXPECT_EQ(none.tile_mean_relative_error, 0.0);
    EXPECT_TRUE(std::isnan(none.relative_bias));  // no mean to be relative to
    const ImageComparison grey = compareImages(filled(9, 7, glm::vec3(0.5f)), black);
    EXPECT_TRUE(grey.scale_is_fallback);
    EXPECT_NEAR(grey.relative_mse, 0.25 / 0.01, 1e-9);
    EXPECT_NEAR(grey.mean_relative_error, 0.5 / 0.01, 1e-9);
    EXPECT_NEAR(grey.tile_mean_relative_error, 0.5 / 0.01, 1e-9);
    EXPECT_NEAR(grey.masked_relative_mse, grey.relative_mse, 1e-12);
    EXPECT_TRUE(std::isnan(grey.relative_bias));  // it read +0%, "no bias", for an image of 0.5
    const RelativeMseSplit split = splitRelativeMse(filled(9, 7, glm::vec3(0.4f)), 4, filled(9, 7, glm::vec3(0.6f)), 4,
                                                    black);
    EXPECT_NEAR(split.total, 0.25 / 0.01, 1e-5);  // 0.4f and 0.6f round
    EXPECT_NEAR(split.noise, 0.25 * 0.04 / 0.01, 1e-5);
    EXPECT_TRUE(std::isfinite(split.rest_standard_error));
    // A NaN pixel in the reference is left out of the measures (compareImages), and the scale is
    // the other pixels' mean: it does not fall back to 1 for the whole image.
    Image poisoned = filled(4, 4, glm::vec3(3e-3f));
    poisoned.pixels[3].y = std::numeric_limits<float>::quiet_NaN();
    bool fallback = true;
    EXPECT_NEAR(errorScale(poisoned, &fallback), 3e-3, 1e-9);
    EXPECT_FALSE(fallback);
    Image all_nan = filled(2, 2, glm::vec3(std::numeric_limits<float>::quiet_NaN()));
    EXPECT_EQ(errorScale(all_nan, &fallback), 1.0);
    EXPECT_TRUE(fallback);
    EXPECT_EQ(errorScale(filled(4, 4, glm::vec3(-1.0f)), &fallback), 1.0);
    EXPECT_TRUE(fallback);
    EXPECT_EQ(errorScale(filled(4, 4, glm::vec3(3e-5f)), &fallback), double(3e-5f));
    EXPECT_FALSE(fallback);
}

// A reference pixel with NaN or infinity has no answer to measure against: it is left out of
// every measure and of the count they average over, and counted. An infinite one made the
// relative MSE NaN while the bias ignored it; a NaN one made both NaN.
TEST(CompareImages, NonFiniteReferencePixelsAreLeftOutAndCounted) {
    const Image image = filled(4, 4, glm::vec3(2.5f));
    const ImageComparison clean = compareImages(image, filled(4, 4, glm::vec3(2.0f)));
    for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
        Image reference = filled(4, 4, glm::vec3(2.0f));
        reference.pixels[5].x = bad;
        reference.pixels[9] = glm::vec3(-bad);
        const ImageComparison e = compareImages(image, reference);
        EXPECT_EQ(e.reference_non_finite_pixels, 2u);
        EXPECT_EQ(e.non_finite_pixels, 0u);
        EXPECT_NEAR(e.relative_mse, clean.relative_mse, 1e-12) << bad;
        EXPECT_NEAR(e.mean_relative_error, clean.mean_relative_error, 1e-12) << bad;
        EXPECT_NEAR(e.relative_bias, clean.relative_bias, 1e-12) << bad;
        EXPECT_NEAR(e.tile_mean_relative_error, clean.tile_mean_relative_error, 1e-12) << bad;
        EXPECT_EQ(e.masked_pixels, 14u);
    }
}

TEST(CompareImages, RefusesDifferentSizes) {
    EXPECT_THROW(compareImages(filled(4, 3, glm::vec3(1.0f)), filled(3, 4, glm::vec3(1.0f))), std::invalid_argument);
    EXPECT_THROW(splitRelativeMse(filled(4, 3, glm::vec3(1.0f)), 1, filled(4, 3, glm::vec3(1.0f)), 1,
                                  filled(3, 4, glm::vec3(1.0f))),
                 std::invalid_argument);
}

TEST(RenderNoise, ExactForTwoSymmetricHalves) {
    // a = r + d, b = r - d with equal sample counts: the mean is r, all of the error is noise.
    const Image reference = filled(2, 2, glm::vec3(1.0f));
    const Image a = filled(2, 2, glm::vec3(1.2f));
    const Image b = filled(2, 2, glm::vec3(0.8f));
    const RelativeMseSplit split = splitRelativeMse(a, 8, b, 8, reference);
    EXPECT_NEAR(split.total, 0.0, 1e-12);
    EXPECT_NEAR(split.noise, 0.04 / (1.0 + 1e-2), 1e-6);
    EXPECT_NEAR(split.rest, -split.noise, 1e-12);  // unbiased, so not clamped
    // Two equal renders off by a constant: no noise, all of the error is the rest.
    const RelativeMseSplit offset = splitRelativeMse(a, 8, a, 24, reference);
    EXPECT_NEAR(offset.noise, 0.0, 1e-12);
    EXPECT_NEAR(offset.rest, 0.04 / (1.0 + 1e-2), 1e-6);
    EXPECT_NEAR(offset.rest_standard_error, 0.0, 1e-9);
}

TEST(RenderNoise, MatchesTheVarianceOfASimulatedRender) {
    // Pixels of a noisy, biased "render": each sample is truth * (1 + bias) plus exponential noise,
    // so the render's relative MSE is bias^2 plus its variance. The estimate from two halves must
    // find the variance part, for equal and unequal halves.
    const int width = 128, height = 96;
    const double bias = 0.05;
    for (const auto& halves : {std::pair<uint32_t, uint32_t>{64, 64}, std::pair<uint32_t, uint32_t>{24, 104}}) {
        std::mt19937_64 random(42);
        Image truth = filled(width, height, glm::vec3(0.0f));
        for (size_t i = 0; i < truth.pixels.size(); ++i) truth.pixels[i] = glm::vec3(0.5f + float(i % 7), 1.0f, 3.0f);
        const auto render = [&](uint32_t samples) {
            Image image = truth;
            for (size_t i = 0; i < image.pixels.size(); ++i) {
                for (int c = 0; c < 3; ++c) {
                    std::exponential_distribution<double> sample(1.0 / (double(truth.pixels[i][c]) * (1.0 + bias)));
                    double sum = 0.0;
                    for (uint32_t s = 0; s < samples; ++s) sum += sample(random);
                    image.pixels[i][c] = float(sum / samples);
                }
            }
            return image;
        };
        const Image a = render(halves.first), b = render(halves.second);
        const uint32_t n = halves.first + halves.second;
        Image mean = a;
        for (size_t i = 0; i < mean.pixels.size(); ++i) {
            mean.pixels[i] = (a.pixels[i] * float(halves.first) + b.pixels[i] * float(halves.second)) / float(n);
        }
        // Exponential samples: variance = mean^2, so the n-sample mean has relative variance
        // (1 + bias)^2 / n, and its bias is bias^2, each term times r^2 / (r^2 + (0.1 m)^2) for
        // the measure's epsilon (m = 2.5, the truth's mean: the 0.5 pixels count 0.8, the rest
        // 0.94-1).
        const double epsilon = 0.01 * errorScale(truth) * errorScale(truth);
        double weight = 0.0;
        for (const glm::vec3& r : truth.pixels) {
            for (int c = 0; c < 3; ++c) weight += double(r[c]) * double(r[c]) / (double(r[c]) * double(r[c]) + epsilon);
        }
        weight /= 3.0 * double(truth.pixels.size());
        const double expected_noise = (1.0 + bias) * (1.0 + bias) / double(n) * weight;
        const RelativeMseSplit split = splitRelativeMse(a, halves.first, b, halves.second, truth);
        EXPECT_NEAR(split.noise / expected_noise, 1.0, 0.05) << halves.first << "+" << halves.second;
        EXPECT_NEAR(split.total, compareImages(mean, truth).relative_mse, 1e-6 * split.total);
        EXPECT_NEAR(split.rest, bias * bias * weight, 0.25 * bias * bias) << halves.first << "+" << halves.second;
        // The standard error is what the spread of the rest over seeds shows (about 1e-4 here).
        EXPECT_GT(split.rest_standard_error, 2e-5);
        EXPECT_LT(split.rest_standard_error, 0.1 * bias * bias);
    }
}

}  // namespace
}  // namespace sharcbake
