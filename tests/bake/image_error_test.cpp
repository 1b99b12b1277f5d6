// SPDX-License-Identifier: Apache-2.0
// Image error measures (sharcbake compare, bake --report): exact values on small images, and the
// render-noise estimate against the true variance of a simulated Monte Carlo render.
#include "reports/image_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
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
    const Image reference = filled(4, 3, glm::vec3(2.0f));
    const Image image = filled(4, 3, glm::vec3(2.5f));
    const ImageComparison e = compareImages(image, reference);
    EXPECT_NEAR(e.relative_mse, 0.25 / (4.0 + 1e-2), 1e-9);
    EXPECT_NEAR(e.mean_relative_error, 0.5 / (2.0 + 1e-2), 1e-9);
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
    // Per pixel, the left tile is off by 0.7 or 0.3 (mean 0.5); over its tile, by 0.2.
    EXPECT_NEAR(e.mean_relative_error, 0.5 * (0.5 / 2.01), 1e-6);
    EXPECT_NEAR(e.tile_mean_relative_error, 0.5 * (0.2 / 2.01), 1e-6);
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
        // (1 + bias)^2 / n (the epsilon of the measure is negligible against these values).
        const double expected_noise = (1.0 + bias) * (1.0 + bias) / double(n);
        const RelativeMseSplit split = splitRelativeMse(a, halves.first, b, halves.second, truth);
        EXPECT_NEAR(split.noise / expected_noise, 1.0, 0.05) << halves.first << "+" << halves.second;
        EXPECT_NEAR(split.total, compareImages(mean, truth).relative_mse, 1e-6 * split.total);
        EXPECT_NEAR(split.rest, bias * bias, 0.25 * bias * bias) << halves.first << "+" << halves.second;
        // The standard error is what the spread of the rest over seeds shows (about 1e-4 here).
        EXPECT_GT(split.rest_standard_error, 2e-5);
        EXPECT_LT(split.rest_standard_error, 0.1 * bias * bias);
    }
}

}  // namespace
}  // namespace sharcbake
