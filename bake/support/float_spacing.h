// SPDX-License-Identifier: Apache-2.0
/// @file float_spacing.h
/// @brief How far apart float32 values are at a coordinate: what positions there can resolve.
#pragma once

#include <cmath>
#include <limits>

namespace sharcbake {

/// Float32 spacing at the scene's far corner above this share of the finest voxel makes hit
/// points jitter between voxels (docs/sharc_algorithm.md §10.9: about 20 % at 1e5 units, S = 50):
/// the stability report warns above it, and --level-bias auto keeps voxels at or below it.
inline constexpr double kPrecisionWarningShare = 0.05;

/// Distance from |x| (rounded to float32) to the next float32 towards +infinity.
inline double floatSpacing(double x) {
    const float f = float(std::abs(x));
    return double(std::nextafter(f, std::numeric_limits<float>::infinity())) - double(f);
}

}  // namespace sharcbake
