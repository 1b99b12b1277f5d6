// SPDX-License-Identifier: Apache-2.0
/// @file image_error.h
/// @brief Error of an image against a reference image of the same camera and resolution.
#pragma once

#include "sharcbake/image.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// Error measures, per pixel and channel, averaged over all of them:
/// - relative MSE: (x - r)^2 / (r^2 + (0.1 m)^2), the usual measure for rendering comparisons;
/// - mean relative error: |x - r| / (|r| + 0.01 m);
/// - mean (signed) bias relative to the reference mean: (mean x - mean r) / mean r.
/// m is the reference's mean over pixels and channels (errorScale), so the epsilons keep black
/// reference pixels from dominating in any radiance units: scaling both images by the same factor
/// leaves every measure as it was, and a reference of mean 1 has both epsilons 0.01.
/// Two more see past per-pixel noise and past pixels the cache plays no part in:
/// - tile mean relative error: both images averaged over kComparisonTile^2-pixel tiles first,
///   which divides a render's noise variance by the tile's pixel count and keeps what is smooth
///   (a cache's bias, a light leak);
/// - masked: only the pixels of the mask (for a render through a cache: pixels whose camera ray
///   hits a surface that does not emit, where everything but emission comes from the cache).
struct ImageComparison {
    double relative_mse = 0.0;
    double mean_relative_error = 0.0;
    double relative_bias = 0.0;      ///< NaN where the reference's sum is not positive (a black one)
    uint64_t non_finite_pixels = 0;  ///< pixels of the test image with NaN/Inf (counted as error 1)
    /// Pixels of the reference with NaN/Inf: nothing to measure against, so left out of every
    /// measure (and of the count they average over).
    uint64_t reference_non_finite_pixels = 0;
    double tile_mean_relative_error = 0.0;
    double masked_relative_mse = 0.0;         ///< as relative_mse, over the mask (all pixels without one)
    double masked_mean_relative_error = 0.0;  ///< as mean_relative_error, over the mask
    uint64_t masked_pixels = 0;               ///< pixels in the mask
    double scale = 1.0;                       ///< m, errorScale(reference)
    bool scale_is_fallback = false;           ///< the reference had no mean to take m from (m = 1)
};

/// The scale m of the measures' epsilons: the reference's mean over its finite pixels and their
/// channels (a NaN or infinite pixel is a full error of its own in compareImages). A reference
/// whose mean is not a positive number (black, or no finite pixel) has no scale of its own and gets m = 1, i.e. absolute epsilons of 0.01: the measures stay finite,
/// are 0 for a black image and grow with the image's brightness, in its units (borrowing the
/// image's own mean instead would give every image the same mean relative error, 100, against
/// a black reference). `fallback`, when given, says whether m fell back to 1.
double errorScale(const Image& reference, bool* fallback = nullptr);

/// Tile edge, in pixels, of ImageComparison::tile_mean_relative_error (partial tiles at the
/// right and bottom edges count as tiles).
constexpr int kComparisonTile = 8;

/// Compares `image` with `reference`; `mask` (width x height, non-zero = include), when given,
/// selects the pixels of the masked measures. Throws std::invalid_argument if sizes differ.
ImageComparison compareImages(const Image& image, const Image& reference,
                              const std::vector<uint8_t>* mask = nullptr);

/// The relative MSE of a Monte Carlo render made of two independent renders `a` and `b` (of
/// `a_samples` and `b_samples` samples per pixel; the render is their sample-weighted mean c),
/// split into the render's own noise and the rest. Per pixel and channel, with d = a - b,
/// Var(c) = E[d^2] a_samples b_samples / (a_samples + b_samples)^2, so
///   (c - r)^2 - d^2 a_samples b_samples / n^2
/// estimates, without bias, the squared error of what the renders converge to (for a render
/// through a cache: the cache's own error) plus the reference's noise. Normalised like
/// ImageComparison::relative_mse (the same m, from `reference`). The rest is a difference of two noisy means and may come out
/// negative; its standard error over the pixels says how far it can be trusted (fireflies make it
/// large).
struct RelativeMseSplit {
    double total = 0.0;                ///< relative MSE of c
    double noise = 0.0;                ///< the part that is c's own noise
    double rest = 0.0;                 ///< total - noise (unbiased, not clamped)
    double rest_standard_error = 0.0;  ///< standard error of `rest` over the pixels
};

/// Throws std::invalid_argument if the sizes differ.
RelativeMseSplit splitRelativeMse(const Image& a, uint32_t a_samples, const Image& b, uint32_t b_samples,
                                  const Image& reference);

}  // namespace sharcbake
