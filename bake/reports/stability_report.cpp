// SPDX-License-Identifier: Apache-2.0
#include "reports/stability_report.h"

#include "support/float_spacing.h"
#include "support/text_format.h"
#include "tracing/tracer.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sharcbake {
namespace {

double channelSum(const glm::dvec3& v) { return v.x + v.y + v.z; }

void addWarnings(StabilityReport& r) {
    const uint64_t failed_for_capacity = r.failed_inserts - std::min(r.failed_inserts, r.failed_inserts_equal_halves);
    if (failed_for_capacity > 0) {
        r.warnings.push_back(
            formatted("%.0f deposits found their hash bucket full and were dropped: %.3g%% of the "
                      "deposited energy is missing from the cache; raise --capacity (%.1f%% of the "
                      "slots are in use)",
                      double(failed_for_capacity),
                      100.0 * r.share(r.failed_insert_energy) * double(failed_for_capacity) / double(r.failed_inserts),
                      r.capacity ? 100.0 * double(r.occupied_slots) / double(r.capacity) : 0.0));
    }
    if (r.failed_inserts_equal_halves > 0) {
        // Keys x | y << 17 | z << 34 | level << 51 have equal halves where y = 4 x level (plus the
        // normal's bits) and x = 4 z: a diagonal row of voxels on a surface that sits at that grid
        // row, which another voxel size moves.
        r.warnings.push_back(formatted(
            "%.0f deposits fell on voxels whose keys SHaRC's hash sends to one bucket (a key whose two 32-bit halves "
            "are equal hashes to 0), which was full: %.3g%% of the deposited energy is missing from the cache. No "
            "--capacity holds them, and a runtime with the SDK's hash cannot either (lookups there miss and are "
            "traced). Such keys are a diagonal row of voxels on a surface at grid row 4 x level (the floor of a tiny "
            "scene, whose finest voxels are narrower than SHaRC's 1e-4 position bias, can sit there); another "
            "--level-bias (a step of 1/64 changes the voxel sizes) or --scene-scale moves the surface off it",
            double(r.failed_inserts_equal_halves),
            100.0 * r.share(r.failed_insert_energy) * double(r.failed_inserts_equal_halves) /
                double(r.failed_inserts)));
    }
    if (r.clamped_deposits > 0) {
        // The scale puts the brightest radiance the scene's emission, sky and punctual lights give
        // at 2^40 steps, whatever its magnitude in float32 (chooseRadianceScale), and one deposit
        // holds 2^62: only radiance 2^22 times that brightest one is clamped, never bright emission.
        r.warnings.push_back(
            formatted("%.0f deposits carried radiance above %.3g, the most one deposit holds (2^62 fixed-point steps "
                      "at scale %g, which puts %.3g, at least the brightest radiance the scene's emission, sky and "
                      "punctual lights give, at 2^40 steps), ",
                      double(r.clamped_deposits), r.radiance_scale > 0.0 ? 0x1p62 / r.radiance_scale : 0.0,
                      r.radiance_scale, r.radiance_scale > 0.0 ? 0x1p40 / r.radiance_scale : 0.0) +
            formatted("and were clamped, removing %.3g%% of the deposited energy: something made radiance 2^22 times "
                      "what the lights give (a punctual light almost touching a surface, or an extreme path weight)",
                      100.0 * r.share(r.clamped_energy)));
    }
    if (r.deposits > 0 && double(r.sub_step_deposits) > kSubStepWarningShare * double(r.deposits)) {
        // The scale puts the brightest radiance the scene can make at 2^40 steps (chooseRadianceScale).
        r.warnings.push_back(
            formatted("%.3g%% of deposits carried less than one fixed-point step (radiance below "
                      "%.3g, where the brightest radiance the scene's lights give, %.3g, is 2^40 steps): "
                      "dithered rounding keeps them on average, but the voxels they feed hold a few steps "
                      "at most and read as noise or 0. The scene's radiance spans more than the fixed point "
                      "holds: a small, very bright emitter (or a point or spot light, whose radiance counts as "
                      "seen from an eighth of its distance to the nearest surface) sets the scale far above what these "
                      "surfaces receive. Give such an "
                      "emitter more area and less radiance (the same power), or bake the dim part as a "
                      "scene of its own",
                      100.0 * double(r.sub_step_deposits) / double(r.deposits),
                      r.radiance_scale > 0.0 ? 1.0 / r.radiance_scale : 0.0,
                      r.radiance_scale > 0.0 ? 0x1p40 / r.radiance_scale : 0.0));
    }
    if (r.saturated_sums > 0) {
        r.warnings.push_back(formatted(
            "%.0f deposits met a voxel sum already at its 72-bit ceiling (2^72 fixed-point "
            "steps in one iteration, a summed radiance of %.3g at scale %g); those voxels are "
            "darker than they should be",
            double(r.saturated_sums), r.radiance_scale > 0.0 ? 0x1p72 / r.radiance_scale : 0.0, r.radiance_scale));
    }
    if (r.non_finite_dropped > 0) {
        // Radiance within 2^20 of float32's largest overflows where a path sums it with other light
        // or carries it over a bounce or two: then the scene's brightness, not a material, made them.
        const double brightest = r.radiance_scale > 0.0 ? 0x1p40 / r.radiance_scale : 0.0;
        if (brightest > double(std::numeric_limits<float>::max()) * 0x1p-20) {
            r.warnings.push_back(
                formatted("%.0f NaN/Inf radiance values were dropped (the cache holds none): the "
                          "scene's brightest radiance, up to %.3g, is within 2^20 of float32's "
                          "largest (%.3g), and radiance that adds to it or carries it overflows; "
                          "scale the scene's emission down",
                          double(r.non_finite_dropped), brightest, double(std::numeric_limits<float>::max())));
        } else {
            r.warnings.push_back(
                formatted("%.0f NaN/Inf radiance values were dropped (a material, light or sky "
                          "produced them); the cache holds none",
                          double(r.non_finite_dropped)));
        }
    }
    if (r.orphan_sums > 0) {
        r.warnings.push_back(
            formatted("%.0f voxel sums had radiance but no sample and were dropped (a bug in the "
                      "update pass)",
                      double(r.orphan_sums)));
    }
    if (r.grid_coordinates_wrap) {
        r.warnings.push_back(
            formatted("the scene reaches %.0f grid cells from the grid anchor at level %.0f, beyond "
                      "the key's 17-bit range (+-65536): keys stay unique near the camera, but voxel "
                      "positions decoded from keys (export-vdb) wrap; lower --level-bias or --scene-scale "
                      "(wider voxels), or use --level-bias auto",
                      double(r.max_grid_coordinate), double(r.finest_level)));
    }
    if (r.finest_voxel_size > 0.0 && r.ray_offset > r.finest_voxel_size) {
        // The guard is a few float32 roundings of the coordinates (rayOffsetFor): only the
        // scene's distance from the origin makes it large against the scene's own voxels.
        r.warnings.push_back(
            formatted("the tracer moves ray origins up to %.3g off surfaces at the scene's far corner "
                      "(%g float32 roundings of its coordinates there, its self-intersection guard), "
                      "more than the finest voxel (%.3g): light leaks through walls thinner than "
                      "that; move the scene towards the origin",
                      r.ray_offset, double(kRayOffsetRoundings), r.finest_voxel_size));
    } else if (r.largest_side > 0.0 && r.ray_offset > double(kRayOffsetWarningShare) * r.largest_side) {
        // The grid fit widens the voxels far out (precision), so they can exceed an offset that is
        // already a large part of the scene: a 4-unit room 1e7 out baked 30% dark, with 20-unit
        // voxels and an offset of 19, and only render warned.
        r.warnings.push_back(formatted(
            "the tracer moves ray origins up to %.3g off surfaces at the scene's far corner "
            "(%g float32 roundings of its coordinates there, its self-intersection guard), %.3g%% of "
            "the scene's largest side (%.3g): light leaks through its walls and corners darken; move "
            "the scene towards the origin",
            r.ray_offset, double(kRayOffsetRoundings), 100.0 * r.ray_offset / r.largest_side, r.largest_side));
    }
    if (r.largest_side > 0.0 && r.largest_side < kBiasVoxelsAcrossScene * r.bias_distance_voxel_size) {
        // A 4 mm room in metres scaled by 1e-3 again (4e-6 across): its lookups all fell at the
        // level of the bias's 1.7e-4, in voxels 3.3e-6 wide, and a render through the cache found
        // 8 hits among 112,573 refused lookups, while the bake said "no problems found".
        r.warnings.push_back(
            formatted("the scene is only %.3g across, and SHaRC adds 1e-4 to every coordinate before choosing a "
                      "voxel: every lookup's level follows a distance of about 1.7e-4 whatever the camera's, in voxels "
                      "%.3g wide (%.0f%% of the scene), so a runtime refuses most lookups (bounces shorter than their "
                      "voxel). Scale the scene up (export it in smaller units, e.g. millimetres for metres: a scale "
                      "of 1000 on its root node) and use the same units in the engine",
                      r.largest_side, r.bias_distance_voxel_size, 100.0 * r.bias_distance_voxel_size / r.largest_side));
    }
    if (r.float_spacing > kPositionBiasWarningFactor * double(kHashGridPositionBias)) {
        // Centring a scene puts its far corner at half its largest side; when the corner is no
        // farther than the whole side, moving gains at most 2x: the scene's own size is the cause
        // (a site exported in millimetres, say).
        const bool own_size = r.far_corner_distance <= r.largest_side;
        r.warnings.push_back(
            formatted("float32 spacing at the scene's far corner (%.3g) is %.0f times SHaRC's position "
                      "bias (1e-4): surfaces lying on voxel boundaries split between two voxels, which "
                      "then average light from both sides; ",
                      r.float_spacing, r.float_spacing / double(kHashGridPositionBias)) +
            (own_size ? "the scene is very large in its units (the bias is an absolute 1e-4, made "
                        "for metres): scale it down (millimetres to metres: a scale of 0.001 on its "
                        "root node, or the exporter's unit setting)"
                      : "move the scene towards the origin"));
    }
    if (r.precisionShare() > kPrecisionWarningShare) {
        r.warnings.push_back(
            formatted("float32 spacing at the scene's far corner (%.3g from the origin) is %.3g, "
                      "%.3g%% of the finest voxel (%.3g): hit points there jitter between voxels; "
                      "move the scene towards the origin or lower --scene-scale",
                      r.far_corner_distance, r.float_spacing, 100.0 * r.precisionShare(), r.finest_voxel_size));
    }
}

}  // namespace

StabilityReport makeStabilityReport(const SharcCache& cache, const UpdateCounters& update, glm::vec3 bounds_min,
                                    glm::vec3 bounds_max, const std::vector<uint32_t>& levels) {
    const NumericsCounters& n = cache.numerics();
    StabilityReport r;
    r.deposits = n.deposits;
    r.deposited_energy = channelSum(n.deposited_energy);
    r.clamped_deposits = n.clamped_deposits;
    r.sub_step_deposits = n.sub_step_deposits;
    r.clamped_energy = channelSum(n.clamped_energy);
    r.saturated_sums = n.saturated_sums;
    r.failed_inserts = n.failed_inserts;
    r.failed_inserts_equal_halves = n.failed_inserts_equal_halves;
    r.failed_insert_energy = channelSum(n.failed_insert_energy);
    r.non_finite_dropped = n.non_finite_deposits + update.non_finite;
    r.negative_clamped = n.negative_deposits;
    r.resample_emission_clamped = update.clamped_propagation;
    r.orphan_sums = n.orphan_sums;
    r.radiance_scale = cache.radianceScale();
    r.capacity = cache.capacity();
    r.occupied_slots = cache.liveEntries();
    r.capacity_power_of_two = r.capacity != 0 && (r.capacity & (r.capacity - 1)) == 0;

    const glm::vec3 extent = glm::max(glm::abs(bounds_min), glm::abs(bounds_max));
    r.far_corner_distance = double(std::max({extent.x, extent.y, extent.z}));
    const glm::vec3 sides = glm::max(bounds_max - bounds_min, glm::vec3(0.0f));
    r.largest_side = double(std::max({sides.x, sides.y, sides.z}));
    r.float_spacing = floatSpacing(r.far_corner_distance);
    r.ray_offset = double(largestRayOffset(float(r.far_corner_distance)));
    const HashGridParameters& grid = cache.settings().grid;
    const Float3& anchor = cache.settings().grid_anchor;
    const double anchor_coordinates[3] = {double(anchor.x), double(anchor.y), double(anchor.z)};
    for (uint32_t level : levels) {
        const double size = double(voxelSize(level, grid));
        if (!(size > 0.0)) continue;
        if (r.finest_level == 0) {  // levels ascend: the first is the finest
            r.finest_level = level;
            r.finest_voxel_size = size;
        }
        // Cells from the anchor's cell, where keys decode (HashGridKeyDecoder). Positions are
        // biased before quantisation, exactly as the key does it.
        for (int axis = 0; axis < 3; ++axis) {
            const double anchor_cell = std::floor(anchor_coordinates[axis] / size);
            for (const float bound : {bounds_min[axis], bounds_max[axis]}) {
                const double cell = std::floor((double(bound) + double(kHashGridPositionBias)) / size);
                const double cells = std::abs(cell - anchor_cell);
                r.max_grid_coordinate = std::max(r.max_grid_coordinate, int64_t(std::min(cells, 9.0e18)));
            }
        }
    }
    {
        HashGridParameters at_origin = grid;
        at_origin.camera_position = Float3{0.0f, 0.0f, 0.0f};
        const Float3 bias{kHashGridPositionBias, kHashGridPositionBias, kHashGridPositionBias};
        r.bias_distance_voxel_size = double(voxelSize(gridLevel(bias, at_origin), grid));
    }
    constexpr int64_t kMaxSignedCoordinate = int64_t(1) << (kHashGridPositionBits - 1);
    r.grid_coordinates_wrap = r.max_grid_coordinate >= kMaxSignedCoordinate;
    addWarnings(r);
    return r;
}

void addSceneReflectance(StabilityReport& r, const SceneReflectance& reflectance) {
    if (reflectance.points == 0) return;
    r.scene_reflectance = reflectance.reflectance;
    if (!(reflectance.reflectance > kStiffReflectance)) return;
    r.warnings.push_back(
        reflectance.describe() +
        (reflectance.unbounded()
             ? "; the cache's values grow with every iteration and say how long it baked, not what the scene "
               "looks like; give the surfaces an albedo below 1 (base colour) or open the scene"
             : ": update paths carry a few of those bounces and the cache's feedback the rest, iteration after "
               "iteration, so the cache converges slowly and reads dark until it has; --resampling end "
               "--propagation-depth 16 --max-bounces 17 carries 16 bounces per iteration (docs/baking.md, "
               "\"Stiff scenes\"); compare a render through the cache with a reference before trusting it"));
}

void printStabilitySection(std::FILE* out, const StabilityReport& r) {
    std::fprintf(out, "Stability:\n");
    std::fprintf(out, "  energy: %llu deposits, %.6g deposited (fixed-point scale %g)\n", (unsigned long long)r.deposits,
                 r.deposited_energy, r.radiance_scale);
    std::fprintf(out, "  clamped: %llu deposits, %.3g energy (%.3g%%); saturated sums %llu; below one step %llu\n",
                 (unsigned long long)r.clamped_deposits, r.clamped_energy, 100.0 * r.share(r.clamped_energy),
                 (unsigned long long)r.saturated_sums, (unsigned long long)r.sub_step_deposits);
    std::fprintf(out,
                 "  failed inserts: %llu deposits (%llu on keys of equal halves), %.3g energy (%.3g%%); %llu of %u "
                 "slots in use%s\n",
                 (unsigned long long)r.failed_inserts, (unsigned long long)r.failed_inserts_equal_halves,
                 r.failed_insert_energy, 100.0 * r.share(r.failed_insert_energy), (unsigned long long)r.occupied_slots,
                 r.capacity, r.capacity_power_of_two ? "" : " (not a power of two: fine here, SHaRC recommends one)");
    std::fprintf(out, "  dropped or replaced: NaN/Inf %llu, negative %llu, resampled below emission %llu, "
                      "orphan sums %llu\n",
                 (unsigned long long)r.non_finite_dropped, (unsigned long long)r.negative_clamped,
                 (unsigned long long)r.resample_emission_clamped, (unsigned long long)r.orphan_sums);
    if (r.finest_level > 0) {
        std::fprintf(out,
                     "  coordinates: far corner %.6g, float32 spacing %.3g = %.3g%% of the finest voxel "
                     "(%.3g, level %u), ray offset %.3g; grid cells up to %lld of +-65536 from the anchor\n",
                     r.far_corner_distance, r.float_spacing, 100.0 * r.precisionShare(), r.finest_voxel_size,
                     r.finest_level, r.ray_offset, (long long)r.max_grid_coordinate);
    }
    if (r.scene_reflectance >= 0.0) {
        std::fprintf(out,
                     "  light transport: the surfaces send %.3g%% of the light reaching them back onto the scene\n",
                     100.0 * r.scene_reflectance);
    }
    for (const std::string& w : r.warnings) std::fprintf(out, "  warning: %s\n", w.c_str());
    if (r.warnings.empty()) std::fprintf(out, "  no problems found\n");
}

Json stabilityJson(const StabilityReport& r) {
    return {
        {"deposits", r.deposits},
        {"deposited_energy", r.deposited_energy},
        {"radiance_scale", r.radiance_scale},
        {"clamped_deposits", r.clamped_deposits},
        {"sub_step_deposits", r.sub_step_deposits},
        {"clamped_energy", r.clamped_energy},
        {"clamped_energy_share", r.share(r.clamped_energy)},
        {"saturated_sums", r.saturated_sums},
        {"failed_inserts", r.failed_inserts},
        {"failed_inserts_equal_halves", r.failed_inserts_equal_halves},
        {"failed_insert_energy", r.failed_insert_energy},
        {"failed_insert_energy_share", r.share(r.failed_insert_energy)},
        {"non_finite_dropped", r.non_finite_dropped},
        {"negative_clamped", r.negative_clamped},
        {"resample_emission_clamped", r.resample_emission_clamped},
        {"orphan_sums", r.orphan_sums},
        {"capacity", r.capacity},
        {"occupied_slots", r.occupied_slots},
        {"capacity_power_of_two", r.capacity_power_of_two},
        {"far_corner_distance", r.far_corner_distance},
        {"float_spacing", r.float_spacing},
        {"ray_offset", r.ray_offset},
        {"finest_level", r.finest_level},
        {"finest_voxel_size", r.finest_voxel_size},
        {"float_spacing_share_of_finest_voxel", r.precisionShare()},
        {"max_grid_coordinate", r.max_grid_coordinate},
        {"grid_coordinates_wrap", r.grid_coordinates_wrap},
        {"scene_reflectance", r.scene_reflectance},
        {"warnings", r.warnings},
    };
}

}  // namespace sharcbake
