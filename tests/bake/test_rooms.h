// SPDX-License-Identifier: Apache-2.0
/// @file test_rooms.h
/// @brief Rooms built in code for the bake tests: closed boxes whose walls face into them.
#pragma once

#include "sharcbake/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <limits>

namespace sharcbake {

/// An empty scene whose bounds grow as boxes are added.
inline Scene emptyTestScene() {
    Scene scene;
    scene.bounds_min = glm::vec3(std::numeric_limits<float>::max());
    scene.bounds_max = glm::vec3(-std::numeric_limits<float>::max());
    return scene;
}

/// Appends the box [lo, hi], its twelve triangles wound to face into it, in `material`.
inline void addInwardBox(Scene& scene, glm::vec3 lo, glm::vec3 hi, uint32_t material) {
    const uint32_t base = uint32_t(scene.positions.size());
    for (int i = 0; i < 8; ++i)
        scene.positions.push_back(glm::vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
    // Quads (a, b, c, d) wound to face into the box.
    const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& f : faces) {
        scene.triangles.push_back(glm::uvec3(base + f[0], base + f[1], base + f[2]));
        scene.triangles.push_back(glm::uvec3(base + f[0], base + f[2], base + f[3]));
        scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
    }
    scene.bounds_min = glm::min(scene.bounds_min, lo);
    scene.bounds_max = glm::max(scene.bounds_max, hi);
}

}  // namespace sharcbake
