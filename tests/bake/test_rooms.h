// SPDX-License-Identifier: Apache-2.0
/// @file test_rooms.h
/// @brief Rooms built in code for the bake tests: closed boxes whose walls face into them.
#pragma once

#include "sharcbake/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <utility>

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

/// Appends the grey (0.8) material "wall" the test rooms are built of; returns its index.
inline uint32_t addGreyWallMaterial(Scene& scene) {
    Material wall;
    wall.name = "wall";
    wall.base_color = glm::vec3(0.8f);
    scene.materials.push_back(wall);
    return uint32_t(scene.materials.size() - 1);
}

/// Appends the box [lo, hi], its twelve triangles wound to face out of it, in `material`.
inline void addOutwardBox(Scene& scene, glm::vec3 lo, glm::vec3 hi, uint32_t material) {
    const size_t first = scene.triangles.size();
    addInwardBox(scene, lo, hi, material);
    for (size_t t = first; t < scene.triangles.size(); ++t) std::swap(scene.triangles[t].y, scene.triangles[t].z);
}

/// A closed room 2 x 2 x 2 m (x and z in [-1, 1], y in [0, 2]) with walls 0.2 m thick, grey
/// inside and out, lit only by a point light inside; and its glTF camera "Cutaway" 0.4 m in front
/// of the front wall's outer side (z = 1.6), looking in (-Z), with its near clip plane past the wall
/// (znear 0.8: the plane at z = 0.8, inside the room), as Blender artists frame an interior.
inline Scene cutawayRoom() {
    Scene scene = emptyTestScene();
    const uint32_t wall = addGreyWallMaterial(scene);
    addInwardBox(scene, glm::vec3(-1.0f, 0.0f, -1.0f), glm::vec3(1.0f, 2.0f, 1.0f), wall);
    addOutwardBox(scene, glm::vec3(-1.2f, -0.2f, -1.2f), glm::vec3(1.2f, 2.2f, 1.2f), wall);
    PunctualLight lamp;
    lamp.name = "lamp";
    lamp.position = glm::vec3(0.3f, 1.6f, -0.2f);
    lamp.intensity = glm::vec3(10.0f);
    scene.lights.push_back(lamp);
    Camera camera;
    camera.name = "Cutaway";
    camera.index = 0;
    camera.position = glm::vec3(0.0f, 1.0f, 1.6f);
    camera.forward = glm::vec3(0.0f, 0.0f, -1.0f);
    camera.yfov = 0.9f;
    camera.znear = 0.8f;
    scene.cameras.push_back(camera);
    return scene;
}

}  // namespace sharcbake
