// SPDX-License-Identifier: Apache-2.0
#include "sharc/grid_fit.h"

#include "tracing/sampling.h"
#include "tracing/surface_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>

namespace sharcbake {
namespace {

/// Fewer level-1 voxels than this over the whole scene means the cache cannot tell its surfaces
/// apart (a 6 mm model in one 4 cm voxel); more than kTooManyFactor x the budget means a file and
/// a runtime table far larger than the scene needs.
constexpr double kTooFewVoxels = 256.0;
constexpr double kTooManyFactor = 16.0;
/// The grid coordinates are 17-bit signed (|g| < 65536); keep the farthest point of the scene
/// within 90% of that at level 1.
constexpr double kGridRange = 0.9 * 65536.0;

/// A triangle's area in double precision, 0 where it is not finite.
double triangleAreaOf(const Scene& scene, size_t t) {
    const glm::uvec3 tri = scene.triangles[t];
    const glm::dvec3 p0(scene.positions[tri.x]), p1(scene.positions[tri.y]), p2(scene.positions[tri.z]);
    const double a = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    return std::isfinite(a) ? a : 0.0;
}

/// The farthest coordinate of the scene from the origin, along any axis.
double farthestCoordinate(const Scene& scene) {
    const glm::vec3 m = glm::max(glm::abs(scene.bounds_min), glm::abs(scene.bounds_max));
    return double(std::max({m.x, m.y, m.z})) + double(kHashGridPositionBias);
}

}  // namespace

double visibleSurfaceArea(const Scene& scene) {
    double area = 0.0;
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const double a = triangleAreaOf(scene, t);
        const bool double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
        area += double_sided ? 2.0 * a : a;
    }
    return area;
}

namespace {

/// Directions from each viewpoint for the surface it sees (seenTriangleArea).
constexpr uint32_t kDirectionsPerViewpoint = 256;

/// What points spread by area say of the visible surface's sides (shares of visibleSurfaceArea).
struct PointSides {
    double seen = 0.0;                 ///< sides seen from a viewpoint
    double unseen_double_sided = 0.0;  ///< sides of double-sided surfaces seen from none
};

/// Which sides of `points` are seen from a viewpoint. Unbiased, but a part of the surface too
/// small to receive a point (a room beside a 10 km ground plane) reads as 0.
PointSides seenSidesOfPoints(const Tracer& tracer, const std::vector<glm::vec3>& viewpoints,
                             const std::vector<SurfacePoint>& points) {
    // Both ways (visibleBothWays): a ray slipping through a shared edge would count a point of a
    // 10 km ground plane as seen from inside a closed room (1/4096 of the plane's area).
    const auto seenFromAny = [&](glm::vec3 position, glm::vec3 side) {
        const glm::vec3 origin = offsetRayOrigin(position, side);
        return std::any_of(viewpoints.begin(), viewpoints.end(), [&](const glm::vec3& v) {
            return glm::dot(v - origin, side) > 0.0f && visibleBothWays(tracer, origin, v);
        });
    };
    // Sides seen, double-sided sides unseen and sides there, summed over the points: integers, so
    // the sums do not depend on how the points are split between threads. A single-sided surface
    // is one side (visibleSurfaceArea counts it once), seen from either: paths shade its back too,
    // and a room modelled from a cube, its normals out, is seen from inside on the backs of its
    // walls.
    struct Counts {
        uint64_t seen = 0, unseen_double_sided = 0, sides = 0;
    };
    const Counts counts = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, points.size()), Counts{},
        [&](const tbb::blocked_range<size_t>& range, Counts sum) {
            for (size_t i = range.begin(); i != range.end(); ++i) {
                const SurfacePoint& p = points[i];
                if (p.double_sided) {
                    const uint64_t seen = uint64_t(seenFromAny(p.position, p.normal)) +
                                          uint64_t(seenFromAny(p.position, -p.normal));
                    sum.seen += seen;
                    sum.unseen_double_sided += 2 - seen;
                    sum.sides += 2;
                } else {
                    sum.seen += seenFromAny(p.position, p.normal) || seenFromAny(p.position, -p.normal);
                    sum.sides += 1;
                }
            }
            return sum;
        },
        [](Counts a, Counts b) {
            return Counts{a.seen + b.seen, a.unseen_double_sided + b.unseen_double_sided, a.sides + b.sides};
        });
    PointSides result;
    if (counts.sides == 0) return result;
    result.seen = double(counts.seen) / double(counts.sides);
    result.unseen_double_sided = double(counts.unseen_double_sided) / double(counts.sides);
    return result;
}

/// The visible area of the triangles that rays from the viewpoints hit (each side once): exact for
/// a few large triangles, however small their share, where spread points miss them; short of the
/// truth on a fine mesh whose triangles outnumber the rays, and over it where a large triangle is
/// only partly in sight.
double seenTriangleArea(const Tracer& tracer, const std::vector<glm::vec3>& viewpoints) {
    const Scene& scene = tracer.scene();
    std::vector<std::atomic<uint8_t>> sides(scene.triangles.size());  // bit 0 front, bit 1 back
    tbb::parallel_for(size_t(0), viewpoints.size(), [&](size_t v) {
        for (uint32_t i = 0; i < kDirectionsPerViewpoint; ++i) {
            const glm::vec3 direction = sphericalFibonacciDirection(i, kDirectionsPerViewpoint);
            RayHit hit;
            if (!tracer.intersect(Ray{viewpoints[v], direction}, hit)) continue;
            const glm::uvec3 tri = scene.triangles[hit.triangle];
            const glm::vec3 n = glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                           scene.positions[tri.z] - scene.positions[tri.x]);
            sides[hit.triangle].fetch_or(glm::dot(n, direction) < 0.0f ? 1 : 2, std::memory_order_relaxed);
        }
    });
    double area = 0.0;
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const uint8_t seen = sides[t].load(std::memory_order_relaxed);
        if (!seen) continue;
        const double a = triangleAreaOf(scene, t);
        // A single-sided surface counts once, whichever side a ray hit (visibleSurfaceArea counts it
        // once).
        const bool double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
        area += double_sided ? a * double((seen & 1) + (seen >> 1)) : a;
    }
    return area;
}

}  // namespace

SeenSurface surfaceSeenFrom(const Tracer& tracer, const std::vector<glm::vec3>& viewpoints, uint32_t samples,
                            uint32_t seed) {
    SeenSurface seen;
    const Scene& scene = tracer.scene();
    const std::vector<SurfacePoint> points = sampleSurfacePoints(scene, samples, seed);
    seen.samples = uint32_t(points.size());
    if (points.empty() || viewpoints.empty()) return seen;
    // The larger of two estimates, each short of the truth where the other is not: points spread
    // by area (a fine mesh) and triangles hit by rays from the viewpoints (a small part of a
    // scene made of a few large triangles).
    const double total = visibleSurfaceArea(scene);
    const PointSides sides = seenSidesOfPoints(tracer, viewpoints, points);
    seen.area = std::min(total, std::max(sides.seen * total, seenTriangleArea(tracer, viewpoints)));
    seen.fraction = total > 0.0 ? seen.area / total : 1.0;
    seen.unseen_double_sided_area = sides.unseen_double_sided * total;
    return seen;
}

GridFit fitLevelBias(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget,
                     const SeenSurface* seen) {
    GridFit fit;
    fit.scene_surface_area = visibleSurfaceArea(scene);
    fit.surface_area = fit.scene_surface_area;
    if (seen && seen->samples > 0 && seen->area > 0.0 && seen->fraction < kFitToSeenBelow) {
        fit.surface_area = seen->area;
        fit.fitted_to_seen = true;
    } else if (seen && seen->samples > 0 && seen->unseen_double_sided_area > 0.0 &&
               seen->unseen_double_sided_area < fit.surface_area) {
        fit.surface_area -= seen->unseen_double_sided_area;
        fit.unseen_sides_left_out = seen->unseen_double_sided_area;
    }
    const double budget = double(std::max<uint64_t>(voxel_budget, 1));
    double size = std::sqrt(fit.surface_area / budget);
    const double range_limit = farthestCoordinate(scene) / kGridRange;
    if (!(size > range_limit)) {
        fit.limited_by_range = size < range_limit;
        size = std::max(range_limit, 1e-30);
    }
    // voxelSize(1) = b^(1 - bias) / S = size  <=>  bias = 1 - log_b(S * size).
    const double b = double(grid.logarithm_base);
    const double exact = 1.0 - std::log(double(grid.scene_scale) * size) / std::log(b);
    // Rounded down to 1/64: the voxels are at least `size` and the bias prints exactly.
    fit.level_bias = float(std::floor(exact * 64.0) / 64.0);
    HashGridParameters fitted = grid;
    fitted.level_bias = fit.level_bias;
    fit.finest_voxel_size = voxelSize(kHashGridLevelMin, fitted);
    fit.estimated_voxels = fit.surface_area / (double(fit.finest_voxel_size) * double(fit.finest_voxel_size));

    char surface[160];
    if (fit.fitted_to_seen) {
        std::snprintf(surface, sizeof surface,
                      "%.3g units^2 of surface the cameras' free space sees (%.2g%% of the scene's %.3g; the rest is "
                      "out of its sight)",
                      fit.surface_area, 100.0 * fit.surface_area / fit.scene_surface_area, fit.scene_surface_area);
    } else if (fit.unseen_sides_left_out > 0.0) {
        std::snprintf(surface, sizeof surface,
                      "%.3g units^2 of visible surface (the scene's %.3g less the sides of double-sided surfaces no "
                      "camera's free space sees)",
                      fit.surface_area, fit.scene_surface_area);
    } else {
        std::snprintf(surface, sizeof surface, "%.3g units^2 of visible surface", fit.surface_area);
    }
    char text[480];
    if (fit.limited_by_range) {
        std::snprintf(text, sizeof text,
                      "level bias %.9g: finest voxels %.4g wide, the smallest the 17-bit grid allows %.4g units from "
                      "the origin (%s, about %.3g voxels at level 1; the budget would allow finer)",
                      double(fit.level_bias), double(fit.finest_voxel_size), farthestCoordinate(scene), surface,
                      fit.estimated_voxels);
    } else {
        std::snprintf(text, sizeof text,
                      "level bias %.9g: finest voxels %.4g wide, so the %s take about %.3g voxels at level 1 (budget "
                      "%llu); cameras closer than %.4g use level 1",
                      double(fit.level_bias), double(fit.finest_voxel_size), surface, fit.estimated_voxels,
                      (unsigned long long)voxel_budget, double(fit.finest_voxel_size) * b * double(grid.scene_scale));
    }
    fit.reason = text;
    return fit;
}

std::vector<std::string> checkGridForScene(const Scene& scene, const HashGridParameters& grid, uint32_t finest_level,
                                           uint64_t voxel_budget) {
    std::vector<std::string> warnings;
    const double area = visibleSurfaceArea(scene);
    const double size = double(voxelSize(finest_level, grid));
    const double voxels = area / (size * size);
    const GridFit fit = fitLevelBias(scene, grid, voxel_budget);
    char text[400];
    if (voxels < kTooFewVoxels) {
        std::snprintf(text, sizeof text,
                      "the scene's %.3g units^2 of surface span only about %.0f voxels at level %u (voxels %.4g wide; "
                      "the scene is %.4g units across): the cache cannot tell its surfaces apart. Are the units "
                      "right? Use --level-bias auto (here %g) or a larger --level-bias",
                      area, voxels, finest_level, size, double(glm::length(scene.bounds_max - scene.bounds_min)),
                      double(fit.level_bias));
        warnings.push_back(text);
    } else if (voxels > kTooManyFactor * double(voxel_budget)) {
        std::snprintf(text, sizeof text,
                      "the scene's %.3g units^2 of surface span about %.3g voxels at level %u (voxels %.4g wide), "
                      "%.0fx the voxel budget %llu: a large file and runtime table. Are the units right? Use "
                      "--level-bias auto (here %g) or a smaller --level-bias",
                      area, voxels, finest_level, size, voxels / double(voxel_budget), (unsigned long long)voxel_budget,
                      double(fit.level_bias));
        warnings.push_back(text);
    }
    return warnings;
}

std::string checkSceneScale(float scene_scale) {
    const char* cost = scene_scale < 4.0f      ? "a blurry cache"
                       : scene_scale > 4096.0f ? "far more voxels than a view can use"
                                               : nullptr;
    if (!cost) return {};
    char text[320];
    std::snprintf(text, sizeof text,
                  "--scene-scale %g makes voxels about 1/%g of their distance from the camera wide: %s. SHaRC's "
                  "scene scale is the same in any units (the units are fitted by --level-bias auto); use "
                  "--scene-scale auto (50)",
                  double(scene_scale), double(scene_scale), cost);
    return text;
}

}  // namespace sharcbake
