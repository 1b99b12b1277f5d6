// SPDX-License-Identifier: Apache-2.0
/// @file image_error.h
/// @brief Error of an image against a reference image of the same camera and resolution.
#pragma once

#include "sharcbake/image.h"

#include <cstdint>
#include <string>

namespace sharcbake {

/// Error measures, per pixel and channel, averaged over all of them:
/// - relative MSE: (x - r)^2 / (r^2 + epsilon), the usual measure for rendering comparisons;
/// - mean relative error: |x - r| / (|r| + epsilon);
/// - mean (signed) bias relative to the reference mean: (mean x - mean r) / mean r.
/// epsilon = 1e-2 keeps black reference pixels from dominating.
struct ImageComparison {
    double relative_mse = 0.0;
    double mean_relative_error = 0.0;
    double relative_bias = 0.0;
    uint64_t non_finite_pixels = 0;  ///< pixels of the test image with NaN/Inf (counted as error 1)
};

/// Compares `image` with `reference`. Throws std::invalid_argument if the sizes differ.
ImageComparison compareImages(const Image& image, const Image& reference);

}  // namespace sharcbake
