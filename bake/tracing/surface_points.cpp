// SPDX-License-Identifier: Apache-2.0
#include "tracing/surface_points.h"

#include "tracing/distribution.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <algorithm>
#include <array>

namespace sharcbake {
namespace {

float triangleArea(const Scene& scene, size_t t) {
    const glm::uvec3 tri = scene.triangles[t];
    return 0.5f * glm::length(glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                         scene.positions[tri.z] - scene.positions[tri.x]));
}

/// A corner of a triangle clipped to a box: its position and its barycentrics (b1, b2) in the
/// triangle.
struct ClippedCorner {
    glm::vec3 position;
    glm::vec2 barycentrics;
};
/// A convex polygon has at most 3 + 6 corners after clipping by the box's six planes.
using ClippedPolygon = std::array<ClippedCorner, 9>;

/// Clips triangle t to the box (Sutherland-Hodgman, one plane at a time); the corner count.
uint32_t clipTriangle(const Scene& scene, size_t t, glm::vec3 box_min, glm::vec3 box_max, ClippedPolygon& polygon) {
    const glm::uvec3 tri = scene.triangles[t];
    polygon[0] = {scene.positions[tri.x], glm::vec2(0.0f, 0.0f)};
    polygon[1] = {scene.positions[tri.y], glm::vec2(1.0f, 0.0f)};
    polygon[2] = {scene.positions[tri.z], glm::vec2(0.0f, 1.0f)};
    uint32_t count = 3;
    for (int plane = 0; plane < 6 && count > 0; ++plane) {
        const int axis = plane / 2;
        const bool is_min = plane % 2 == 0;
        const float bound = is_min ? box_min[axis] : box_max[axis];
        // Signed distance inside the plane: >= 0 keeps the corner.
        const auto inside = [&](const ClippedCorner& c) {
            return is_min ? c.position[axis] - bound : bound - c.position[axis];
        };
        ClippedPolygon kept;
        uint32_t kept_count = 0;
        for (uint32_t i = 0; i < count; ++i) {
            const ClippedCorner& a = polygon[i];
            const ClippedCorner& b = polygon[(i + 1) % count];
            const float da = inside(a), db = inside(b);
            if (da >= 0.0f) kept[kept_count++] = a;
            if ((da >= 0.0f) != (db >= 0.0f)) {
                const float f = da / (da - db);
                kept[kept_count++] = {a.position + f * (b.position - a.position),
                                      a.barycentrics + f * (b.barycentrics - a.barycentrics)};
            }
        }
        polygon = kept;
        count = kept_count;
    }
    return count;
}

float fanTriangleArea(const ClippedPolygon& polygon, uint32_t k) {
    return 0.5f * glm::length(glm::cross(polygon[k + 1].position - polygon[0].position,
                                         polygon[k + 2].position - polygon[0].position));
}

/// Uniform numbers in [0, 1) by index, a different sequence per seed (seed 0 gives the points
/// coverage reports have always used).
auto seededUniform(uint32_t seed) {
    const uint32_t offset = seed * 0x9e3779b9u;
    return [offset](uint32_t index) { return bitsToUnitFloat(hashUint32(index + offset)); };
}

SurfacePoint surfacePoint(const Scene& scene, uint32_t t, glm::vec2 b) {
    const glm::uvec3 tri = scene.triangles[t];
    const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
    SurfacePoint point;
    point.position = (1.0f - b.x - b.y) * p0 + b.x * p1 + b.y * p2;
    point.normal = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    point.ray_offset = rayOffsetFor(p0, p1, p2, point.normal);
    point.triangle = t;
    point.barycentrics = b;
    point.double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
    return point;
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
    const auto uniform = seededUniform(seed);
    points.reserve(count);
    for (uint32_t i = 0; i < count; ++i) {
        // Stratified in the area CDF, then uniform in the triangle.
        const float u = (float(i) + uniform(i * 3 + 1)) / float(count);
        const uint32_t t = uint32_t(by_area.sampleDiscrete(std::min(u, kOneMinusEpsilon)));
        const glm::vec2 b = sampleUniformTriangle({uniform(i * 3 + 2), uniform(i * 3 + 3)});
        if (isCutOut(scene, t, b.x, b.y)) continue;  // a hole in an alpha-masked surface is no surface
        points.push_back(surfacePoint(scene, t, b));
    }
    return points;
}

namespace {

/// The triangles that reach into the box and the area of each one's part inside it.
struct ClippedAreas {
    std::vector<uint32_t> triangles;
    std::vector<float> areas;
};
ClippedAreas clippedAreas(const Scene& scene, glm::vec3 box_min, glm::vec3 box_max) {
    ClippedAreas clipped;
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3 tri = scene.triangles[t];
        const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
        const glm::vec3 lo = glm::min(p0, glm::min(p1, p2)), hi = glm::max(p0, glm::max(p1, p2));
        if (glm::any(glm::greaterThan(lo, box_max)) || glm::any(glm::lessThan(hi, box_min))) continue;
        // Inside the box whole: no clipping.
        float area = 0.0f;
        if (glm::all(glm::greaterThanEqual(lo, box_min)) && glm::all(glm::lessThanEqual(hi, box_max))) {
            area = triangleArea(scene, t);
        } else {
            ClippedPolygon polygon;
            const uint32_t corners = clipTriangle(scene, t, box_min, box_max, polygon);
            for (uint32_t k = 0; k + 2 < corners; ++k) area += fanTriangleArea(polygon, k);
        }
        if (!(area > 0.0f)) continue;
        clipped.triangles.push_back(uint32_t(t));
        clipped.areas.push_back(area);
    }
    return clipped;
}

}  // namespace

double surfaceAreaInBox(const Scene& scene, glm::vec3 box_min, glm::vec3 box_max) {
    double area = 0.0;
    for (const float a : clippedAreas(scene, box_min, box_max).areas) area += double(a);
    return area;
}

std::vector<SurfacePoint> sampleSurfacePointsInBox(const Scene& scene, glm::vec3 box_min, glm::vec3 box_max,
                                                   uint32_t count, uint32_t seed) {
    std::vector<SurfacePoint> points;
    if (scene.empty() || count == 0) return points;
    // Each triangle's part inside the box is clipped again when a point lands on it: keeping the
    // polygons would cost 180 bytes per triangle.
    const ClippedAreas clipped = clippedAreas(scene, box_min, box_max);
    const std::vector<uint32_t>& clipped_triangles = clipped.triangles;
    const std::vector<float>& areas = clipped.areas;
    if (areas.empty()) return points;
    const Distribution1D by_area(areas);
    const auto uniform = seededUniform(seed);
    points.reserve(count);
    for (uint32_t i = 0; i < count; ++i) {
        // Stratified in the clipped area, then a triangle of the polygon's fan by area, then
        // uniform in it.
        const float u = (float(i) + uniform(i * 4 + 1)) / float(count);
        const size_t c = by_area.sampleDiscrete(std::min(u, kOneMinusEpsilon));
        const uint32_t t = clipped_triangles[c];
        ClippedPolygon polygon;
        const uint32_t corners = clipTriangle(scene, t, box_min, box_max, polygon);
        float pick = uniform(i * 4 + 2) * areas[c];
        uint32_t k = 0;
        for (; k + 3 < corners; ++k) {
            const float area = fanTriangleArea(polygon, k);
            if (pick < area) break;
            pick -= area;
        }
        const glm::vec2 f = sampleUniformTriangle({uniform(i * 4 + 3), uniform(i * 4 + 4)});
        const glm::vec2 b = (1.0f - f.x - f.y) * polygon[0].barycentrics + f.x * polygon[k + 1].barycentrics +
                            f.y * polygon[k + 2].barycentrics;
        if (isCutOut(scene, t, b.x, b.y)) continue;
        points.push_back(surfacePoint(scene, t, b));
    }
    return points;
}

}  // namespace sharcbake
