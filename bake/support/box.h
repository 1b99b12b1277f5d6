// SPDX-License-Identifier: Apache-2.0
/// @file box.h
/// @brief Whether a point lies in an axis-aligned box, for the checks that keep work to a region.
#pragma once

#include <glm/glm.hpp>

namespace sharcbake {

/// Whether `p` lies in the closed box [lo, hi] (false where a coordinate is NaN).
inline bool insideBox(glm::vec3 p, glm::vec3 lo, glm::vec3 hi) {
    return glm::all(glm::greaterThanEqual(p, lo)) && glm::all(glm::lessThanEqual(p, hi));
}

}  // namespace sharcbake
