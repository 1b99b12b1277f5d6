// SPDX-License-Identifier: Apache-2.0
#include "tracing/surface_points.h"

#include "tracing/distribution.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <algorithm>

namespace sharcbake {
namespace {

float triangleArea(const Scene& scene, size_t t) {
    const glm::uvec3 tri = scene.triangles[t];
    return 0.5f * glm::length(glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                         scene.positions[tri.z] - scene.positions[tri.x]));
}

}  // namespace

double surfaceArea(const Scene& scene) {
    double area = 0.0;
    for (size_t t = 0; t < scene.triangles.size(); ++t) area += double(triangleArea(scene, t));
    return area;
}

std::vector<SurfacePoint> sampleSurfacePoints(const Scene& scene, uint32_t count, uint32_t seed) {
    std::vector<SurfacePoint> points;
    if (scene.empty() || count == 0) return points;
    std::vector<float> areas(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) areas[t] = triangleArea(scene, t);
    const Distribution1D by_area(areas);
    // Seed 0 gives the points coverage reports have always used.
    const uint32_t offset = seed * 0x9e3779b9u;
    const auto uniform = [offset](uint32_t index) { return bitsToUnitFloat(hashUint32(index + offset)); };
    points.reserve(count);
    for (uint32_t i = 0; i < count; ++i) {
        // Stratified in the area CDF, then uniform in the triangle.
        const float u = (float(i) + uniform(i * 3 + 1)) / float(count);
        const uint32_t t = uint32_t(by_area.sampleDiscrete(std::min(u, kOneMinusEpsilon)));
        const glm::vec2 b = sampleUniformTriangle({uniform(i * 3 + 2), uniform(i * 3 + 3)});
        if (isCutOut(scene, t, b.x, b.y)) continue;  // a hole in an alpha-masked surface is no surface
        const glm::uvec3 tri = scene.triangles[t];
        const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
        SurfacePoint point;
        point.position = (1.0f - b.x - b.y) * p0 + b.x * p1 + b.y * p2;
        point.normal = glm::normalize(glm::cross(p1 - p0, p2 - p0));
        point.triangle = t;
        point.barycentrics = b;
        point.double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
        points.push_back(point);
    }
    return points;
}

}  // namespace sharcbake
