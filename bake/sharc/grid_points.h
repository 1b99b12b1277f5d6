// SPDX-License-Identifier: Apache-2.0
/// @file grid_points.h
/// @brief What the checks that key surface points as SHaRC does share: glm vectors as the hash
/// grid's Float3, and distances of a few float32 steps, which move a point in any units.
#pragma once

#include "sharcbake/hash_grid.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>

namespace sharcbake {

inline Float3 toFloat3(glm::vec3 v) { return Float3{v.x, v.y, v.z}; }

/// `steps` float32 steps at `point`'s largest coordinate: a distance that moves it in any units.
inline float floatSteps(glm::vec3 point, float steps) {
    const float largest = std::max({std::abs(point.x), std::abs(point.y), std::abs(point.z), 1e-30f});
    return steps * largest * 0x1p-23f;
}

}  // namespace sharcbake
