// SPDX-License-Identifier: Apache-2.0
#include "sharc/grid_fit.h"

#include <algorithm>
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

/// The farthest coordinate of the scene from the origin, along any axis.
double farthestCoordinate(const Scene& scene) {
    const glm::vec3 m = glm::max(glm::abs(scene.bounds_min), glm::abs(scene.bounds_max));
    return double(std::max({m.x, m.y, m.z})) + double(kHashGridPositionBias);
}

}  // namespace

double visibleSurfaceArea(const Scene& scene) {
    double area = 0.0;
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3 tri = scene.triangles[t];
        const glm::dvec3 p0(scene.positions[tri.x]), p1(scene.positions[tri.y]), p2(scene.positions[tri.z]);
        const double a = 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
        if (!std::isfinite(a)) continue;
        const bool double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
        area += double_sided ? 2.0 * a : a;
    }
    return area;
}

GridFit fitLevelBias(const Scene& scene, const HashGridParameters& grid, uint64_t voxel_budget) {
    GridFit fit;
    fit.surface_area = visibleSurfaceArea(scene);
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

    char text[320];
    if (fit.limited_by_range) {
        std::snprintf(text, sizeof text,
                      "level bias %g: finest voxels %.4g wide, the smallest the 17-bit grid allows %.4g units from "
                      "the origin (%.3g units^2 of visible surface, about %.3g voxels at level 1; the budget would "
                      "allow finer)",
                      double(fit.level_bias), double(fit.finest_voxel_size), farthestCoordinate(scene), fit.surface_area,
                      fit.estimated_voxels);
    } else {
        std::snprintf(text, sizeof text,
                      "level bias %g: finest voxels %.4g wide, so the %.3g units^2 of visible surface take about "
                      "%.3g voxels at level 1 (budget %llu); cameras closer than %.4g use level 1",
                      double(fit.level_bias), double(fit.finest_voxel_size), fit.surface_area, fit.estimated_voxels,
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
