// SPDX-License-Identifier: Apache-2.0
/// @file surface_points.h
/// @brief Points spread over a scene's surfaces by area, for measures that must not depend on
/// where a camera went (coverage, the probe reference of the error report).
#pragma once

#include "sharcbake/scene.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace sharcbake {

struct SurfacePoint {
    glm::vec3 position;
    glm::vec3 normal;  ///< geometric, unit, the triangle's front side
    float ray_offset = 0.0f;  ///< rayOffsetFor the triangle
    uint32_t triangle = 0;
    glm::vec2 barycentrics{0.0f};  ///< (b1, b2) of vertices 1 and 2 in the triangle
    bool double_sided = false;  ///< the material is seen from both sides
};

/// Up to `count` points, stratified in the scene's area and uniform within each triangle; those
/// that fall in the holes of alpha cut-outs are left out. The same scene, count and seed give
/// the same points. Empty for an empty scene; degenerate triangles (no area) are never picked.
std::vector<SurfacePoint> sampleSurfacePoints(const Scene& scene, uint32_t count, uint32_t seed = 0);

/// Up to `count` points spread the same way over the parts of the surfaces inside the box
/// [box_min, box_max] (each triangle clipped to it): a small region of a large scene gets as
/// many points as the whole scene would.
std::vector<SurfacePoint> sampleSurfacePointsInBox(const Scene& scene, glm::vec3 box_min, glm::vec3 box_max,
                                                   uint32_t count, uint32_t seed = 0);

/// The area of the surfaces inside the box (each triangle clipped to it), world units squared.
double surfaceAreaInBox(const Scene& scene, glm::vec3 box_min, glm::vec3 box_max);

/// The scene's total surface area (world units squared).
double surfaceArea(const Scene& scene);

}  // namespace sharcbake
