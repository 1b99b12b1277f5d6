// SPDX-License-Identifier: Apache-2.0
#include "image_error.h"

#include <cmath>
#include <stdexcept>

namespace sharcbake {

ImageComparison compareImages(const Image& image, const Image& reference) {
    if (image.width != reference.width || image.height != reference.height) {
        throw std::invalid_argument("image is " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                                    " but the reference is " + std::to_string(reference.width) + "x" +
                                    std::to_string(reference.height));
    }
    constexpr double kEpsilon = 1e-2;
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

}  // namespace sharcbake
