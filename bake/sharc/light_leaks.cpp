// SPDX-License-Identifier: Apache-2.0
#include "sharc/light_leaks.h"

#include "sharc/grid_points.h"
#include "support/median.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace sharcbake {
namespace {

/// Points for all emissive materials together, and the fewest one material gets.
constexpr uint64_t kPointBudget = 1u << 16;
constexpr uint32_t kMinPointsPerMaterial = 16;

/// A probe passes at most this many emissive surfaces (the emitter itself, stacked emitters)
/// before it gives up.
constexpr int kMaxEmissiveCrossings = 4;

/// The nearest surface behind an emitter that could share its voxels.
struct SurfaceBehind {
    bool found = false;
    float gap = 0.0f;  ///< distance from the emitter
    glm::vec3 position{0.0f};
    glm::vec3 key_normal{0.0f};  ///< geometric normal towards the emitter, as a ray from it sees it
};

/// The nearest surface behind the emitter at `point` (its emitting side faces `emitting`): not
/// emissive, seen from a side light reaches, with its key normal in the emitter's octant. Not
/// found when there is none within `reach` or another surface hides it.
SurfaceBehind surfaceBehind(const Tracer& tracer, glm::vec3 point, glm::vec3 emitting, float reach,
                            bool pass_emitters = true) {
    const Scene& scene = tracer.scene();
    const uint32_t octant = normalBits(toFloat3(emitting));
    // From just in front of the emitter, so that a surface flush with it is found too: the
    // emitter's own hit (and any other emitter's) is passed over.
    const float lead = std::max(reach * 1e-3f, floatSteps(point, 16.0f));
    const glm::vec3 start = point + emitting * lead;
    glm::vec3 origin = start;
    for (int crossing = 0; crossing <= kMaxEmissiveCrossings; ++crossing) {
        const float travelled = glm::dot(origin - start, -emitting);
        const float t_max = reach + lead - travelled;
        if (!(t_max > 0.0f)) break;
        RayHit ray_hit;
        if (!tracer.intersect(Ray{origin, -emitting, t_max}, ray_hit)) break;
        const SurfaceHit hit = makeSurfaceHit(scene, ray_hit, -emitting);
        const Material& m = scene.materials[hit.material];
        if (m.isEmissive()) {
            if (!pass_emitters) break;
            // Just past it, by a few float steps rather than offsetRayOrigin's fixed offset near
            // the origin, which in a scene in kilometres would step past a ceiling 1 mm behind.
            origin = hit.position - emitting * floatSteps(hit.position, 4.0f);
            continue;
        }
        const bool lit_side = hit.front_face || m.double_sided;
        if (lit_side && normalBits(toFloat3(hit.geometric_normal)) == octant) {
            return SurfaceBehind{true, std::max(0.0f, glm::dot(hit.position - start, -emitting) - lead), hit.position,
                                 hit.geometric_normal};
        }
        break;  // the nearest non-emissive surface hides whatever lies further back
    }
    return SurfaceBehind{};
}

/// Offsets in the emitter's plane, in voxel widths, where the surface behind it is looked for
/// beside it: eight directions at two distances.
constexpr int kBesideDirections = 8;
constexpr float kBesideRadii[] = {0.5f, 1.0f};

/// Whether the surface behind the emitter point `point` shows beside the emitter within the
/// voxel keyed `key` (as the nearest camera `camera` keys it): a probe from in front of the
/// emitter's plane, a little aside, meets that surface first, not an emitter. A screen that
/// exactly covers the face of its own body hides the face: the voxel holds the screen alone, and
/// nothing around it takes on its light.
bool showsBeside(const Tracer& tracer, const HashGridKeyer& keyer, glm::vec3 point, glm::vec3 emitting, float voxel,
                 float gap, uint64_t key, glm::vec3 camera) {
    const Frame frame(emitting);
    for (const float radius : kBesideRadii) {
        for (int k = 0; k < kBesideDirections; ++k) {
            const float angle = 6.2831853f * float(k) / float(kBesideDirections);
            const glm::vec3 aside = point + voxel * radius * (std::cos(angle) * frame.t + std::sin(angle) * frame.b);
            const SurfaceBehind beside = surfaceBehind(tracer, aside, emitting, gap + voxel, false);
            if (beside.found &&
                keyer.key(toFloat3(beside.position), toFloat3(beside.key_normal), toFloat3(camera)) == key) {
                return true;
            }
        }
    }
    return false;
}

/// One material's points tested, and where they leak, the gaps and voxel widths.
struct MaterialPoints {
    uint32_t tested = 0, leaking = 0;
    std::vector<float> gaps, voxels;
};

/// Tests `count` points of one emissive material, stratified over its triangles' area
/// (`cumulative`: their running area sums) and uniform within each.
MaterialPoints testMaterial(const Tracer& tracer, const HashGridKeyer& keyer, const std::vector<glm::vec3>& cameras,
                            uint32_t material, const std::vector<uint32_t>& triangles,
                            const std::vector<double>& cumulative, uint32_t count, uint32_t seed) {
    const Scene& scene = tracer.scene();
    const Material& m = scene.materials[material];
    const double total = cumulative.back();
    MaterialPoints result;
    for (uint32_t i = 0; i < count; ++i) {
        const uint32_t stream = hashCombine(seed, i);
        const double target = (double(i) + double(bitsToUnitFloat(hashCombine(stream, 0)))) / count * total;
        const size_t k =
            std::min(size_t(std::upper_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin()),
                     cumulative.size() - 1);
        float b1 = bitsToUnitFloat(hashCombine(stream, 1)), b2 = bitsToUnitFloat(hashCombine(stream, 2));
        if (b1 + b2 > 1.0f) {
            b1 = 1.0f - b1;
            b2 = 1.0f - b2;
        }
        const EmitterPoint e = makeEmitterPoint(scene, triangles[k], b1, b2);
        if (!(e.emission.x > 0.0f || e.emission.y > 0.0f || e.emission.z > 0.0f)) continue;  // a dark texel
        ++result.tested;
        // Both points keyed as SHaRC keys them from the nearest camera: the same key is the same
        // voxel, and then the surface beside the emitter takes on its light.
        const glm::vec3 camera = nearestCamera(e.position, cameras);
        const float voxel = keyer.voxelSizeAt(keyer.levelOf(glm::dot(e.position - camera, e.position - camera)));
        if (!(voxel > 0.0f) || !std::isfinite(voxel)) continue;
        for (const float side : {1.0f, -1.0f}) {
            if (side < 0.0f && !m.double_sided) break;
            const glm::vec3 emitting = e.face_normal * side;
            const SurfaceBehind behind = surfaceBehind(tracer, e.position, emitting, voxel);
            if (!behind.found) continue;
            const uint64_t emitter_key = keyer.key(toFloat3(e.position), toFloat3(emitting), toFloat3(camera));
            if (keyer.key(toFloat3(behind.position), toFloat3(behind.key_normal), toFloat3(camera)) != emitter_key) {
                continue;
            }
            if (!showsBeside(tracer, keyer, e.position, emitting, voxel, behind.gap, emitter_key, camera)) continue;
            ++result.leaking;
            result.gaps.push_back(behind.gap);
            result.voxels.push_back(voxel);
            break;
        }
    }
    return result;
}

}  // namespace

std::string LightLeakReport::describe(const EmitterLeak& leak) {
    // The material's name goes in outside the buffer: a long one would cut the advice short.
    char text[640];
    std::snprintf(text, sizeof text,
                  ": %.0f%% of its area shares voxels (%.3g units wide, as the nearest view keys them) with a "
                  "surface facing the same way %.3g units behind it (median) that shows around its edge, so renders "
                  "through the cache show the emitter's light on that surface around it (a light leak, brighter "
                  "than path tracing). Move the emitter at least %.3g away from the surface, or remove the surface "
                  "behind it",
                  100.0 * leak.area_share, double(leak.voxel_size), double(leak.median_gap), double(leak.voxel_size));
    return "emissive " + leak.material_label + text;
}

glm::vec3 nearestCamera(glm::vec3 point, const std::vector<glm::vec3>& cameras) {
    glm::vec3 nearest = cameras.front();
    float nearest2 = std::numeric_limits<float>::infinity();
    for (const glm::vec3& camera : cameras) {
        const glm::vec3 d = point - camera;
        if (glm::dot(d, d) < nearest2) {
            nearest2 = glm::dot(d, d);
            nearest = camera;
        }
    }
    return nearest;
}

LightLeakReport findLightLeaks(const Tracer& tracer, const HashGridParameters& grid,
                               const std::vector<glm::vec3>& cameras, uint32_t points_per_material, uint32_t seed) {
    LightLeakReport report;
    const Scene& scene = tracer.scene();
    if (cameras.empty() || points_per_material == 0) return report;
    // Each emissive material's triangles, with their cumulative areas for sampling by area.
    std::vector<std::vector<uint32_t>> triangles(scene.materials.size());
    std::vector<std::vector<double>> cumulative(scene.materials.size());
    for (uint32_t t = 0; t < uint32_t(scene.triangles.size()); ++t) {
        const uint32_t material = scene.triangle_materials[t];
        if (!scene.materials[material].isEmissive()) continue;
        const glm::uvec3 tri = scene.triangles[t];
        const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
        const double area = 0.5 * double(glm::length(glm::cross(p1 - p0, p2 - p0)));
        if (!(area > 0.0) || !std::isfinite(area)) continue;
        triangles[material].push_back(t);
        cumulative[material].push_back((cumulative[material].empty() ? 0.0 : cumulative[material].back()) + area);
    }
    std::vector<uint32_t> emissive;
    for (uint32_t material = 0; material < uint32_t(scene.materials.size()); ++material) {
        if (!triangles[material].empty()) emissive.push_back(material);
    }
    report.emissive_materials = uint32_t(emissive.size());
    if (emissive.empty()) return report;
    // A city of lit windows, each its own material, shares a budget: fewer points each.
    const uint32_t points = std::min(points_per_material,
                                     std::max(kMinPointsPerMaterial, uint32_t(kPointBudget / emissive.size())));
    const HashGridKeyer keyer(grid);
    std::vector<MaterialPoints> results(emissive.size());
    tbb::parallel_for(size_t(0), emissive.size(), [&](size_t j) {
        const uint32_t material = emissive[j];
        results[j] = testMaterial(tracer, keyer, cameras, material, triangles[material], cumulative[material], points,
                                  hashCombine(seed, material));
    });
    for (size_t j = 0; j < emissive.size(); ++j) {
        const MaterialPoints& r = results[j];
        report.points += r.tested;
        if (r.tested == 0) continue;
        const double share = double(r.leaking) / double(r.tested);
        if (share < kLeakAreaShare) continue;
        report.leaks.push_back(
            EmitterLeak{emissive[j], materialLabel(scene, emissive[j]), share, median(r.gaps), median(r.voxels)});
    }
    std::stable_sort(report.leaks.begin(), report.leaks.end(),
                     [](const EmitterLeak& a, const EmitterLeak& b) { return a.area_share > b.area_share; });
    return report;
}

}  // namespace sharcbake
