// SPDX-License-Identifier: Apache-2.0
#include "sharc/grid_fit.h"

#include "support/box.h"
#include "support/float_spacing.h"
#include "support/median.h"
#include "tracing/sampling.h"
#include "tracing/surface_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <tuple>

namespace sharcbake {
namespace {

/// Fewer level-1 voxels than this over the whole scene means the cache cannot tell its surfaces
/// apart (a 6 mm model in one 4 cm voxel); more than kTooManyFactor x the budget means a file and
/// a runtime table far larger than the scene needs.
constexpr double kTooFewVoxels = 256.0;
constexpr double kTooManyFactor = 16.0;
/// Keys keep 17 bits of each grid coordinate and decode to the cell within 65536 cells of the
/// grid anchor's (HashGridKeyDecoder); keep every point of the scene within 90% of that at level 1.
constexpr double kGridRange = 0.9 * 65536.0;

/// The level bias whose level-1 voxels are `size` wide, unrounded: voxelSize(1) = b^(1 - bias) / S
/// = size  <=>  bias = 1 - log_b(S * size).
double biasForLevelOneVoxel(const HashGridParameters& grid, double size) {
    return 1.0 - std::log(double(grid.scene_scale) * size) / std::log(double(grid.logarithm_base));
}

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

/// The largest distance along any axis from the centre of the scene's bounds to its bounds.
double halfExtent(const Scene& scene) {
    const glm::dvec3 extent = glm::dvec3(scene.bounds_max) - glm::dvec3(scene.bounds_min);
    return 0.5 * std::max({extent.x, extent.y, extent.z}) + double(kHashGridPositionBias);
}

/// The finest level-1 voxel the grid can give the scene, and why (GridFit::range_limit).
std::pair<double, GridFit::RangeLimit> finestVoxelAllowed(const Scene& scene) {
    const double around_anchor = halfExtent(scene) / kGridRange;
    // Nor finer than float32 positions resolve there: the spacing at most kPrecisionWarningShare
    // of a voxel (20 float steps), as the stability report asks.
    const double float_steps = floatSpacing(farthestCoordinate(scene)) / kPrecisionWarningShare;
    return around_anchor >= float_steps ? std::pair{around_anchor, GridFit::RangeLimit::kSceneSize}
                                        : std::pair{float_steps, GridFit::RangeLimit::kFloatPrecision};
}

/// What sets the finest voxels where the grid range does, for the "Grid:" line and the voxel
/// warning.
std::string rangeLimitText(const Scene& scene, GridFit::RangeLimit limit) {
    char text[160];
    if (limit == GridFit::RangeLimit::kSceneSize) {
        std::snprintf(text, sizeof text, "the smallest the 17-bit grid allows across a scene %.4g units wide",
                      2.0 * halfExtent(scene));
    } else {
        std::snprintf(text, sizeof text, "the smallest float32 positions %.4g units from the origin resolve",
                      farthestCoordinate(scene));
    }
    return text;
}

}  // namespace

Float3 gridAnchorFor(const Scene& scene, float finest_voxel_size) {
    if (farthestCoordinate(scene) <= kGridRange * double(finest_voxel_size)) return Float3{0.0f, 0.0f, 0.0f};
    const glm::dvec3 centre = 0.5 * (glm::dvec3(scene.bounds_min) + glm::dvec3(scene.bounds_max));
    return Float3{float(centre.x), float(centre.y), float(centre.z)};
}

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
    const auto seenFromAny = [&](const SurfacePoint& p, glm::vec3 side) {
        const glm::vec3 origin = offsetRayOrigin(p.position, side, p.ray_offset);
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
                    const uint64_t seen = uint64_t(seenFromAny(p, p.normal)) + uint64_t(seenFromAny(p, -p.normal));
                    sum.seen += seen;
                    sum.unseen_double_sided += 2 - seen;
                    sum.sides += 2;
                } else {
                    sum.seen += seenFromAny(p, p.normal) || seenFromAny(p, -p.normal);
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

/// Points spread over the surface by its distance from a view region, and what each stands for.
struct DistanceSamples {
    std::vector<float> distance2;  ///< from the point to the nearest place a region camera may be
    std::vector<double> weight;    ///< the share of the scene's area the point stands for (sum 1)
};

/// Points per shell of distance (regionDistanceSamples).
constexpr uint32_t kPointsPerShell = 512;
constexpr uint32_t kMostShells = 40;

/// The squared distance from `p` to the nearest place of a Points or Box region.
float distance2ToRegion(glm::vec3 p, const ViewRegion& region) {
    if (region.kind == ViewRegion::Kind::Box) {
        const glm::vec3 outside = glm::max(glm::max(region.box_min - p, p - region.box_max), glm::vec3(0.0f));
        return glm::dot(outside, outside);
    }
    float nearest2 = std::numeric_limits<float>::infinity();
    for (const glm::vec3 q : region.points) nearest2 = std::min(nearest2, glm::dot(p - q, p - q));
    return nearest2;
}

/// The surface sampled in shells around a Points or Box region: boxes around the region growing
/// twofold until they hold the scene, each sampled by area, each sample weighted by the area of
/// the shell it falls in (its box less the one inside it). Spread by area over the whole scene,
/// a house on a ground two kilometres wide got no point at all, and it is the part that costs.
DistanceSamples regionDistanceSamples(const Scene& scene, const ViewRegion& region, uint32_t seed) {
    DistanceSamples samples;
    glm::vec3 core_min(std::numeric_limits<float>::infinity()), core_max(-std::numeric_limits<float>::infinity());
    if (region.kind == ViewRegion::Kind::Box) {
        core_min = region.box_min;
        core_max = region.box_max;
    } else {
        for (const glm::vec3 q : region.points) {
            core_min = glm::min(core_min, q);
            core_max = glm::max(core_max, q);
        }
    }
    const double total = surfaceArea(scene);
    if (!(core_min.x <= core_max.x) || !(total > 0.0)) return samples;
    const glm::vec3 scene_extent = scene.bounds_max - scene.bounds_min;
    const glm::vec3 core_extent = core_max - core_min;
    float margin = std::max({std::max({core_extent.x, core_extent.y, core_extent.z}) / 8.0f,
                             std::max({scene_extent.x, scene_extent.y, scene_extent.z}) / 4096.0f, 1e-30f});
    double inner_area = 0.0;
    glm::vec3 inner_min(0.0f), inner_max(-1.0f);  // empty
    for (uint32_t shell = 0; shell < kMostShells; ++shell, margin *= 2.0f) {
        const glm::vec3 box_min = core_min - margin, box_max = core_max + margin;
        const bool holds_scene = glm::all(glm::lessThanEqual(box_min, scene.bounds_min)) &&
                                 glm::all(glm::greaterThanEqual(box_max, scene.bounds_max));
        const double area = holds_scene ? total : std::min(total, surfaceAreaInBox(scene, box_min, box_max));
        const double shell_area = std::max(area - inner_area, 0.0);
        if (shell_area > 0.0) {
            const std::vector<SurfacePoint> points = sampleSurfacePointsInBox(scene, box_min, box_max, kPointsPerShell,
                                                                              seed + shell);
            size_t in_shell = 0;
            for (const SurfacePoint& p : points) in_shell += !insideBox(p.position, inner_min, inner_max);
            // A shell too thin for its box's points is stood for by all of them (nearer, so finer:
            // it counts no fewer voxels than it has).
            const bool all = in_shell == 0;
            const size_t used = all ? points.size() : in_shell;
            for (const SurfacePoint& p : points) {
                if (!all && insideBox(p.position, inner_min, inner_max)) continue;
                samples.distance2.push_back(distance2ToRegion(p.position, region));
                samples.weight.push_back(shell_area / total / double(used));
            }
        }
        inner_area = area;
        inner_min = box_min;
        inner_max = box_max;
        if (holds_scene) break;
    }
    return samples;
}

/// Voxels of `surface_area` where each sample's share is at the level a camera at its distance
/// asks for, in level-1 voxels of that bias.
double voxelsAtViewDistances(double surface_area, const DistanceSamples& samples, HashGridParameters grid,
                             float level_bias) {
    grid.level_bias = level_bias;
    const HashGridKeyer keyer(grid);
    double voxels = 0.0;
    for (size_t i = 0; i < samples.distance2.size(); ++i) {
        const double size = double(keyer.voxelSizeAt(keyer.levelOf(samples.distance2[i])));
        voxels += samples.weight[i] / (size * size);
    }
    return surface_area * voxels;
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

namespace {

/// fitLevelBias, drawing the region's distance samples into `samples` where they are first needed
/// and reusing them where given: the voxel warning fits one region for several budgets.
GridFit fitLevelBiasReusing(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget,
                            const SeenSurface* seen, const ViewRegion* region,
                            std::optional<DistanceSamples>& samples) {
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
    const auto [range_limit, range_reason] = finestVoxelAllowed(scene);
    if (!(size > range_limit)) {
        fit.limited_by_range = size < range_limit;
        if (fit.limited_by_range) fit.range_limit = range_reason;
        size = std::max(range_limit, 1e-30);
    }
    const double b = double(grid.logarithm_base);
    // Rounded down to 1/64: the voxels are at least `size` and the bias prints exactly.
    fit.level_bias = float(std::floor(biasForLevelOneVoxel(grid, size) * 64.0) / 64.0);
    const bool keeps_cameras_to_places = region && (region->kind == ViewRegion::Kind::Points ||
                                                    region->kind == ViewRegion::Kind::Box ||
                                                    region->kind == ViewRegion::Kind::Distance);
    if (keeps_cameras_to_places && !fit.limited_by_range) {
        // Level 1 everywhere is the coarsest such a region can need; finer biases, in 1/64 steps,
        // while the surface at its cameras' levels fits the budget (the count only grows with the
        // bias, but for steps within a level: the search finds one bias where it fits). Never
        // finer than the grid range allows.
        if (!samples) {
            samples = region->kind == ViewRegion::Kind::Distance
                          ? DistanceSamples{{region->min_distance * region->min_distance}, {1.0}}
                          : regionDistanceSamples(scene, *region, 0x5eedu);
        }
        const double finest_exact = biasForLevelOneVoxel(grid, std::max(range_limit, 1e-30));
        // Nor finer than the nearest surface needs: level 1 reaches b^(2 - bias), and once that is
        // nearer than every surface no point asks for it, the count stops growing, and the bias
        // would run on to the grid range (0.3 mm voxels at level 1 for an outdoor scene whose
        // camera stands 6.6 m from the nearest surface; levels 9 to 12 used).
        float nearest2 = std::numeric_limits<float>::infinity();
        for (const float d2 : samples->distance2) nearest2 = std::min(nearest2, d2);
        double useful_exact = finest_exact;
        if (nearest2 > 0.0f && std::isfinite(nearest2))
            useful_exact = std::min(useful_exact, 2.0 - 0.5 * std::log(double(nearest2)) / std::log(b));
        const int64_t most_steps = std::clamp<int64_t>(int64_t(std::floor((useful_exact - fit.level_bias) * 64.0)), 0,
                                                       64 * 64);
        const auto fits = [&](int64_t steps) {
            return voxelsAtViewDistances(fit.surface_area, *samples, grid, fit.level_bias + float(steps) / 64.0f) <=
                   budget;
        };
        int64_t lo = 0, hi = most_steps;  // fits(lo) holds: level 1 everywhere fits the budget
        if (!samples->distance2.empty() && hi > 0) {
            while (lo < hi) {
                const int64_t mid = lo + (hi - lo + 1) / 2;
                if (fits(mid)) {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
            fit.fitted_to_view_distances = lo > 0;
            fit.level_bias += float(lo) / 64.0f;
            // Stopped by the grid range with budget to spare: the range, not the budget, decides.
            if (lo == most_steps && useful_exact == finest_exact && fits(most_steps + 1)) {
                fit.limited_by_range = true;
                fit.range_limit = range_reason;
            }
        }
    }
    HashGridParameters fitted = grid;
    fitted.level_bias = fit.level_bias;
    fit.finest_voxel_size = voxelSize(kHashGridLevelMin, fitted);
    fit.estimated_voxels = fit.surface_area / (double(fit.finest_voxel_size) * double(fit.finest_voxel_size));
    if (fit.fitted_to_view_distances)
        fit.estimated_voxels = voxelsAtViewDistances(fit.surface_area, *samples, grid, fit.level_bias);

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
    char text[640];
    if (fit.limited_by_range) {
        const std::string limit = rangeLimitText(scene, fit.range_limit);
        std::snprintf(text, sizeof text,
                      "level bias %.9g: finest voxels %.4g wide, %s (%s, about %.3g voxels at %s; the budget "
                      "would allow finer)",
                      double(fit.level_bias), double(fit.finest_voxel_size), limit.c_str(), surface,
                      fit.estimated_voxels,
                      fit.fitted_to_view_distances ? "the levels the view region's cameras ask for" : "level 1");
    } else if (fit.fitted_to_view_distances) {
        std::snprintf(text, sizeof text,
                      "level bias %.9g: finest voxels %.4g wide, so the %s take about %.3g voxels at the levels the "
                      "view region's cameras ask for (budget %llu; level 1 for all of it would need voxels %.3g "
                      "times wider); cameras closer than %.4g use level 1",
                      double(fit.level_bias), double(fit.finest_voxel_size), surface, fit.estimated_voxels,
                      (unsigned long long)voxel_budget, size / double(fit.finest_voxel_size),
                      double(fit.finest_voxel_size) * b * double(grid.scene_scale));
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

}  // namespace

GridFit fitLevelBias(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget, const SeenSurface* seen,
                     const ViewRegion* region) {
    std::optional<DistanceSamples> samples;
    return fitLevelBiasReusing(scene, grid, voxel_budget, seen, region, samples);
}

namespace {

/// The glTF camera with the median space around it (the median distance of rays in 64 directions
/// to what they hit; cameras that see open sky in most directions have none to compare): one
/// camera against a wall among hundreds says nothing of the scene's voxels.
std::pair<const Camera*, float> typicalCamera(const Tracer& tracer) {
    constexpr uint32_t kDirections = 64;
    std::vector<std::pair<float, const Camera*>> rooms;
    for (const Camera& camera : tracer.scene().cameras) {
        std::vector<float> distances = hitDistancesAround(tracer, camera.position, kDirections);
        if (distances.size() < kDirections / 2) continue;
        rooms.emplace_back(median(std::move(distances)), &camera);
    }
    if (rooms.empty()) return {nullptr, 0.0f};
    // The lower median, and among equal rooms the first camera: the same on every run.
    std::stable_sort(rooms.begin(), rooms.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const auto& [room, camera] = rooms[(rooms.size() - 1) / 2];
    return {camera, room};
}

/// The voxel a lookup `distance` from its camera gets.
float voxelAtDistance(const HashGridParameters& grid, float distance) {
    const HashGridKeyer keyer(grid);
    return keyer.voxelSizeAt(keyer.levelOf(distance * distance));
}

}  // namespace

VoxelsAroundCameras voxelsAroundCameras(const Tracer& tracer, const HashGridParameters& grid) {
    VoxelsAroundCameras around;
    if (tracer.scene().cameras.empty()) return around;
    std::tie(around.camera, around.distance) = typicalCamera(tracer);
    if (!around.camera) return around;
    around.widest = around.distance / kDistancePerVoxelAroundCameras;
    return around.on(grid);
}

VoxelsAroundCameras VoxelsAroundCameras::on(const HashGridParameters& grid) const {
    VoxelsAroundCameras around = *this;
    around.voxel = camera ? voxelAtDistance(grid, distance) : 0.0f;
    return around;
}

std::string checkVoxelsAroundCameras(const Tracer& tracer, const HashGridParameters& grid, const ViewRegion& region,
                                     const GridFit* fit, uint64_t voxel_budget, const SeenSurface* seen) {
    const Scene& scene = tracer.scene();
    const VoxelsAroundCameras around = voxelsAroundCameras(tracer, grid);
    if (!around.tooWide()) return {};
    const Camera* typical = around.camera;
    const float room = around.distance, enough = around.widest, voxel = around.voxel;
    char why[400], fix[480];
    // Each region's distance samples are drawn once for all the budgets tried.
    const auto fitWithBudget = [&](uint64_t budget, const ViewRegion* fit_region,
                                   std::optional<DistanceSamples>& samples, GridFit& budget_fit) {
        budget_fit = fitLevelBiasReusing(scene, grid, budget, seen, fit_region, samples);
        HashGridParameters fitted = grid;
        fitted.level_bias = budget_fit.level_bias;
        return voxelAtDistance(fitted, room);
    };
    // The smallest of 4, 16, ... 4096 times the budget (at most 2^28) that makes the voxels fine
    // enough, or 0; `largest` and `reached` are then the last budget tried and its voxels' width,
    // and `largest_fit` its fit, which stops the search where the grid range decided it: past the
    // range a larger budget changes nothing.
    uint64_t largest = 0;
    GridFit largest_fit;
    const auto budgetFor = [&](const ViewRegion* fit_region, std::optional<DistanceSamples>& samples, float& reached) {
        uint64_t budget = voxel_budget;
        for (int step = 0; step < 6; ++step) {
            budget *= 4;
            if (budget > (uint64_t(1) << 28)) break;
            largest = budget;
            reached = fitWithBudget(budget, fit_region, samples, largest_fit);
            if (reached <= enough) return budget;
            if (largest_fit.limited_by_range) break;
        }
        return uint64_t(0);
    };
    // Why no budget makes the voxels finer than `largest` does, and what would.
    const auto rangeNote = [&](GridFit::RangeLimit limit) {
        return rangeLimitText(scene, limit) + (limit == GridFit::RangeLimit::kSceneSize
                                                   ? "; baking the parts the cameras see as separate scenes allows "
                                                     "finer ones"
                                                   : "; moving the scene towards the origin allows finer ones");
    };
    if (fit && fit->limited_by_range && fit->range_limit == GridFit::RangeLimit::kSceneSize) {
        std::snprintf(why, sizeof why,
                      "They are that wide because SHaRC's keys tell cells apart only within 65536 voxels, and the "
                      "scene is %.4g units wide.",
                      2.0 * halfExtent(scene));
        std::snprintf(fix, sizeof fix,
                      "Baking the parts the cameras see as separate scenes (or leaving out what they never see) "
                      "allows finer ones");
    } else if (fit && fit->limited_by_range) {
        std::snprintf(why, sizeof why,
                      "They are that wide because float32 positions %.4g units from the origin are %.3g apart, and "
                      "a voxel must span several of those steps.",
                      farthestCoordinate(scene), floatSpacing(farthestCoordinate(scene)));
        std::snprintf(fix, sizeof fix, "Moving the scene (and its cameras) towards the origin allows finer ones");
    } else if (!fit) {
        std::snprintf(why, sizeof why, "They are that wide because of --level-bias %g.", double(grid.level_bias));
        // Level 1's voxels at most `enough`, in 1/64 steps.
        const double bias = std::ceil(biasForLevelOneVoxel(grid, double(enough)) * 64.0) / 64.0;
        HashGridParameters finer = grid;
        finer.level_bias = float(bias);
        std::snprintf(fix, sizeof fix,
                      "--level-bias %g makes them %.3g wide (or --level-bias auto fits them to the "
                      "scene)",
                      bias, double(voxelAtDistance(finer, room)));
    } else if (region.kind == ViewRegion::Kind::FreeSpace) {
        std::snprintf(why, sizeof why,
                      "They are that wide because --view-region free lets a runtime camera stand "
                      "anywhere the roaming camera reaches, so all %.3g units^2 it sees get level 1 within "
                      "--voxel-budget %llu.",
                      fit->surface_area, (unsigned long long)voxel_budget);
        const ViewRegion at_cameras = atGltfCameras(scene);
        std::optional<DistanceSamples> at_cameras_samples, no_samples;
        GridFit at_cameras_fit;
        const float at_cameras_voxel = fitWithBudget(voxel_budget, &at_cameras, at_cameras_samples, at_cameras_fit);
        if (at_cameras_voxel <= enough) {
            std::snprintf(fix, sizeof fix,
                          "If the runtime's cameras stay near the glTF cameras, --view-region gltf fits the voxels to "
                          "their distances (%.3g wide here)",
                          double(at_cameras_voxel));
        } else {
            // Both ways to finer voxels, where each exists: keeping the cameras near the glTF
            // cameras needs far fewer voxels where those see a small part of the scene up close
            // (a street camera in a city 2 km wide: 16 times the budget, against 1024 times for
            // cameras anywhere), and the same where they see all of it.
            float at_cameras_reached = 0.0f, free_reached = 0.0f;
            const uint64_t at_cameras_budget = budgetFor(&at_cameras, at_cameras_samples, at_cameras_reached);
            const uint64_t free_budget = budgetFor(nullptr, no_samples, free_reached);
            char anywhere[160] = "";
            if (free_budget)
                std::snprintf(anywhere, sizeof anywhere, "--voxel-budget %llu makes them %.3g wide",
                              (unsigned long long)free_budget, double(free_reached));
            if (at_cameras_budget && (!free_budget || at_cameras_budget < free_budget)) {
                std::snprintf(fix, sizeof fix,
                              "If the runtime's cameras stay near the glTF cameras, --view-region gltf --voxel-budget "
                              "%llu fits the voxels to their distances (%.3g wide here; %.3g in the present "
                              "budget)%s%s",
                              (unsigned long long)at_cameras_budget, double(at_cameras_reached),
                              double(at_cameras_voxel), free_budget ? "; for cameras anywhere, " : "", anywhere);
            } else if (free_budget) {
                std::snprintf(fix, sizeof fix, "%s", anywhere);
            } else {
                char alone[320] = "";
                if (largest)
                    std::snprintf(alone, sizeof alone, " (--voxel-budget %llu alone: %.3g wide%s%s)",
                                  (unsigned long long)largest, double(free_reached),
                                  largest_fit.limited_by_range ? ", " : "",
                                  largest_fit.limited_by_range ? rangeNote(largest_fit.range_limit).c_str() : "");
                std::snprintf(fix, sizeof fix,
                              "A view region that keeps the runtime's cameras near where they will be "
                              "(--view-region gltf, path or box) and a larger --voxel-budget make them finer%s",
                              alone);
            }
        }
    } else {
        std::snprintf(why, sizeof why,
                      "They are that wide because --voxel-budget %llu holds the surface at the levels the view "
                      "region's cameras ask for.",
                      (unsigned long long)voxel_budget);
        float reached = 0.0f;
        std::optional<DistanceSamples> region_samples;
        if (const uint64_t budget = budgetFor(&region, region_samples, reached)) {
            std::snprintf(fix, sizeof fix, "--voxel-budget %llu makes them %.3g wide", (unsigned long long)budget,
                          double(reached));
        } else if (largest && largest_fit.limited_by_range) {
            std::snprintf(fix, sizeof fix, "--voxel-budget %llu makes them %.3g wide, %s", (unsigned long long)largest,
                          double(reached), rangeNote(largest_fit.range_limit).c_str());
        } else if (largest) {
            std::snprintf(fix, sizeof fix,
                          "A larger --voxel-budget makes them finer, though not that fine within 2^28 voxels "
                          "(--voxel-budget %llu: %.3g wide)",
                          (unsigned long long)largest, double(reached));
        } else {
            std::snprintf(fix, sizeof fix, "A larger --voxel-budget makes them finer");
        }
    }
    char text[1400];
    std::snprintf(text, sizeof text,
                  "the voxels around %s, %.3g wide, are wider than 1/%g of the distance to what it sees (a median "
                  "%.3g): through the cache its view blurs together what shares a voxel, and light leaks through "
                  "walls thinner than one. %s %s",
                  cameraLabel(*typical).c_str(), double(voxel), double(kDistancePerVoxelAroundCameras), double(room),
                  why, fix);
    return text;
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
