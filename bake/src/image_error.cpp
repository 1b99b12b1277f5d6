// SPDX-License-Identifier: Apache-2.0
#include "image_error.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sharcbake {

namespace {

constexpr double kEpsilon = 1e-2;

void requireSameSize(const Image& image, const Image& reference) {
    if (image.width != reference.width || image.height != reference.height) {
        throw std::invalid_argument("image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                    " but the reference is " + std::to_string(reference.width) + "x" +
                                    std::to_string(reference.height));
    }
}

}  // namespace

ImageComparison compareImages(const Image& image, const Image& reference) {
    requireSameSize(image, reference);
    ImageComparison e;
    double sum_image = 0.0, sum_reference = 0.0;
    const size_t n = image.pixels.size();
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 x = image.pixels[i];
        const glm::vec3 r = reference.pixels[i];
        if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z)) {
            ++e.non_finite_pixels;
            e.relative_mse += 3.0;
            e.mean_relative_error += 3.0;
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            const double d = double(x[c]) - double(r[c]);
            e.relative_mse += d * d / (double(r[c]) * double(r[c]) + kEpsilon);
            e.mean_relative_error += std::abs(d) / (std::abs(double(r[c])) + kEpsilon);
            sum_image += double(x[c]);
            sum_reference += double(r[c]);
        }
    }
    const double count = 3.0 * double(std::max<size_t>(n, 1));
    e.relative_mse /= count;
    e.mean_relative_error /= count;
    e.relative_bias = sum_reference > 0.0 ? (sum_image - sum_reference) / sum_reference : 0.0;
    return e;
}

RelativeMseSplit splitRelativeMse(const Image& a, uint32_t a_samples, const Image& b, uint32_t b_samples,
                                  const Image& reference) {
    requireSameSize(a, reference);
    requireSameSize(b, reference);
    const double n = double(a_samples) + double(b_samples);
    const double a_weight = double(a_samples) / n, b_weight = double(b_samples) / n;
    const double noise_weight = a_weight * b_weight;
    RelativeMseSplit split;
    double sum_rest_squares = 0.0;
    for (size_t i = 0; i < reference.pixels.size(); ++i) {
        // Per pixel (its channels together, as they share the pixel's samples), so that the
        // standard error counts independent terms.
        double pixel_total = 0.0, pixel_noise = 0.0;
        for (int c = 0; c < 3; ++c) {
            const double x = double(a.pixels[i][c]), y = double(b.pixels[i][c]), r = double(reference.pixels[i][c]);
            const double mean = a_weight * x + b_weight * y;
            if (!std::isfinite(mean)) {
                pixel_total += 1.0;  // as compareImages counts a non-finite pixel
                continue;
            }
            const double scale = 1.0 / (r * r + kEpsilon);
            pixel_total += (mean - r) * (mean - r) * scale;
            pixel_noise += noise_weight * (x - y) * (x - y) * scale;
        }
        split.total += pixel_total / 3.0;
        split.noise += pixel_noise / 3.0;
        const double pixel_rest = (pixel_total - pixel_noise) / 3.0;
        sum_rest_squares += pixel_rest * pixel_rest;
    }
    const double count = double(std::max<size_t>(reference.pixels.size(), 1));
    split.total /= count;
    split.noise /= count;
    split.rest = split.total - split.noise;
    const double variance = std::max(0.0, sum_rest_squares / count - split.rest * split.rest);
    split.rest_standard_error = std::sqrt(variance / std::max(count - 1.0, 1.0));
    return split;
}

}  // namespace sharcbake
