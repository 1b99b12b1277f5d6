// SPDX-License-Identifier: Apache-2.0
#include "reports/image_error.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace sharcbake {

namespace {

/// The measures' epsilons, as shares of the reference's mean m (errorScale): r^2 + (0.1 m)^2 under
/// a squared error, |r| + 0.01 m under an absolute one.
constexpr double kSquaredEpsilonShare = 0.1;
constexpr double kAbsoluteEpsilonShare = 0.01;

/// What a relative measure divides by, per reference value r, for a reference of scale m.
struct Denominators {
    explicit Denominators(double m)
        : squared_epsilon((kSquaredEpsilonShare * m) * (kSquaredEpsilonShare * m)),
          absolute_epsilon(kAbsoluteEpsilonShare * m) {}
    double squared(double r) const { return r * r + squared_epsilon; }
    double absolute(double r) const { return std::abs(r) + absolute_epsilon; }
    double squared_epsilon;
    double absolute_epsilon;
};

void requireSameSize(const Image& image, const Image& reference) {
    if (image.width != reference.width || image.height != reference.height) {
        throw std::invalid_argument("image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                    " but the reference is " + std::to_string(reference.width) + "x" +
                                    std::to_string(reference.height));
    }
}

bool finite(glm::vec3 x) { return std::isfinite(x.x) && std::isfinite(x.y) && std::isfinite(x.z); }

/// Mean relative error of the kComparisonTile^2 tile means (pixels non-finite in either image
/// left out of both).
double tileMeanRelativeError(const Image& image, const Image& reference, const Denominators& divide) {
    double sum = 0.0;
    uint64_t terms = 0;
    for (int ty = 0; ty < image.height; ty += kComparisonTile) {
        for (int tx = 0; tx < image.width; tx += kComparisonTile) {
            glm::dvec3 x(0.0), r(0.0);
            int pixels = 0;
            for (int y = ty; y < std::min(ty + kComparisonTile, image.height); ++y) {
                for (int px = tx; px < std::min(tx + kComparisonTile, image.width); ++px) {
                    const size_t i = size_t(y) * size_t(image.width) + size_t(px);
                    if (!finite(image.pixels[i]) || !finite(reference.pixels[i])) continue;
                    x += glm::dvec3(image.pixels[i]);
                    r += glm::dvec3(reference.pixels[i]);
                    ++pixels;
                }
            }
            if (pixels == 0) continue;
            x /= double(pixels);
            r /= double(pixels);
            for (int c = 0; c < 3; ++c) sum += std::abs(x[c] - r[c]) / divide.absolute(r[c]);
            terms += 3;
        }
    }
    return terms ? sum / double(terms) : 0.0;
}

}  // namespace

double errorScale(const Image& reference, bool* fallback) {
    // Over the finite pixels: compareImages counts a NaN or infinite one as a full error of its
    // own, and it must not take the scale of every other pixel with it.
    double sum = 0.0;
    size_t counted = 0;
    for (const glm::vec3& r : reference.pixels) {
        if (!finite(r)) continue;
        sum += double(r.x) + double(r.y) + double(r.z);
        ++counted;
    }
    const double mean = counted == 0 ? 0.0 : sum / (3.0 * double(counted));
    const bool usable = std::isfinite(mean) && mean > 0.0;
    if (fallback) *fallback = !usable;
    return usable ? mean : 1.0;
}

ImageComparison compareImages(const Image& image, const Image& reference, const std::vector<uint8_t>* mask) {
    requireSameSize(image, reference);
    if (mask && mask->size() != reference.pixels.size()) {
        throw std::invalid_argument("the image mask has " + std::to_string(mask->size()) + " pixels, the images " +
                                    std::to_string(reference.pixels.size()));
    }
    ImageComparison e;
    e.scale = errorScale(reference, &e.scale_is_fallback);
    const Denominators divide(e.scale);
    double sum_image = 0.0, sum_reference = 0.0;
    const size_t n = image.pixels.size();
    for (size_t i = 0; i < n; ++i) {
        const glm::vec3 x = image.pixels[i];
        const glm::vec3 r = reference.pixels[i];
        if (!finite(r)) {  // no answer to measure against there
            ++e.reference_non_finite_pixels;
            continue;
        }
        const bool masked = !mask || (*mask)[i] != 0;
        e.masked_pixels += masked ? 1 : 0;
        if (!finite(x)) {
            ++e.non_finite_pixels;
            e.relative_mse += 3.0;
            e.mean_relative_error += 3.0;
            e.masked_relative_mse += masked ? 3.0 : 0.0;
            e.masked_mean_relative_error += masked ? 3.0 : 0.0;
            continue;
        }
        for (int c = 0; c < 3; ++c) {
            const double d = double(x[c]) - double(r[c]);
            const double squared = d * d / divide.squared(double(r[c]));
            const double relative = std::abs(d) / divide.absolute(double(r[c]));
            e.relative_mse += squared;
            e.mean_relative_error += relative;
            if (masked) {
                e.masked_relative_mse += squared;
                e.masked_mean_relative_error += relative;
            }
            sum_image += double(x[c]);
            sum_reference += double(r[c]);
        }
    }
    const double count = 3.0 * double(std::max<uint64_t>(n - e.reference_non_finite_pixels, 1));
    e.relative_mse /= count;
    e.mean_relative_error /= count;
    const double masked_count = 3.0 * double(std::max<uint64_t>(e.masked_pixels, 1));
    e.masked_relative_mse /= masked_count;
    e.masked_mean_relative_error /= masked_count;
    e.tile_mean_relative_error = tileMeanRelativeError(image, reference, divide);
    // A black reference has no relative bias: 0 read as "no bias" for an image of 1 against it.
    e.relative_bias = sum_reference > 0.0 ? (sum_image - sum_reference) / sum_reference
                                          : std::numeric_limits<double>::quiet_NaN();
    return e;
}

RelativeMseSplit splitRelativeMse(const Image& a, uint32_t a_samples, const Image& b, uint32_t b_samples,
                                  const Image& reference) {
    requireSameSize(a, reference);
    requireSameSize(b, reference);
    const double n = double(a_samples) + double(b_samples);
    const double a_weight = double(a_samples) / n, b_weight = double(b_samples) / n;
    const double noise_weight = a_weight * b_weight;
    const Denominators divide(errorScale(reference));
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
            const double scale = 1.0 / divide.squared(r);
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
