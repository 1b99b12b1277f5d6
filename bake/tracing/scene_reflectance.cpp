// SPDX-License-Identifier: Apache-2.0
#include "tracing/scene_reflectance.h"

#include "tracing/bsdf.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"
#include "tracing/surface_points.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <vector>

namespace sharcbake {
namespace {

constexpr uint32_t kDirectionsPerSide = 8;
/// Light samples drawn from a side to tell whether light reaches it directly.
constexpr uint32_t kLightSamplesPerSide = 8;
/// Rounds of passing light on from lit triangle sides to the sides whose rays land on them.
constexpr int kSpreadRounds = 8;
/// Light samples nearer than this cosine to the side's plane do not count: a point of an emitter
/// in the side's own plane (a wall's other triangles, seen along its outside) lights nothing.
constexpr float kGrazingCosine = 1e-3f;

/// What one side of a surface point does with the light reaching it.
struct SideShare {
    /// Its albedo (light arriving along its normal) times the share of cosine-distributed rays
    /// leaving it that hit the scene again.
    double share = 0.0;
    /// Light reaches the side directly: it emits, a light sample drawn from it is unblocked, or
    /// one of its reflected rays escapes to a sky. (estimateSceneReflectance adds the light that
    /// reaches it after bounces.)
    bool lit = false;
    /// The triangle sides its reflected rays land on: 2 x triangle + 1 for a back.
    std::array<uint32_t, kDirectionsPerSide> landings{};
    uint32_t landed = 0;
};

/// Tests of light reaching points; escapes and unblocked samples are confirmed by a ray back,
/// since Embree's triangle test is not watertight (even robust, at shared vertices) and a ray from
/// inside a closed mesh now and then slips out.
class LightTests {
public:
    LightTests(const Tracer& tracer, const LightSampler& lights)
        : tracer_(tracer), lights_(lights), sky_(lights.hasSky()) {}

    /// A ray from `from` along `d` leaves the scene and a sky lights it.
    bool escapes(glm::vec3 from, glm::vec3 d) const { return sky_ && leavesScene(tracer_, from, d); }

    /// Of `samples` light samples drawn at `hit` (seen through `bsdf`), one is unblocked.
    bool sampleReaches(const SurfaceHit& hit, const GltfBsdf& bsdf, uint32_t samples, uint32_t stream) const {
        for (uint32_t k = 0; k < samples; ++k) {
            const uint32_t light_stream = hashCombine(stream, 0x11u + k);
            const ShadowQuery q = prepareDirectLight(lights_, hit, bsdf, hit.shading_normal,
                                                     bitsToUnitFloat(hashCombine(light_stream, 0)),
                                                     glm::vec2(bitsToUnitFloat(hashCombine(light_stream, 1)),
                                                               bitsToUnitFloat(hashCombine(light_stream, 2))));
            if (!q.needed || !(maxComponent(q.unoccluded) > 0.0f)) continue;
            if (!(glm::dot(q.ray.direction, hit.geometric_normal) > kGrazingCosine)) continue;
            const bool unblocked = std::isinf(q.ray.t_max)
                                       ? escapes(q.ray.origin, q.ray.direction)
                                       : visibleBothWays(tracer_, q.ray.origin,
                                                         q.ray.origin + q.ray.direction * q.ray.t_max);
            if (unblocked) return true;
        }
        return false;
    }

private:
    const Tracer& tracer_;
    const LightSampler& lights_;
    bool sky_;
};

/// The unnormalised normal of a triangle's front (its winding).
glm::vec3 triangleNormal(const Scene& scene, uint32_t triangle) {
    const glm::uvec3 tri = scene.triangles[triangle];
    return glm::cross(scene.positions[tri.y] - scene.positions[tri.x], scene.positions[tri.z] - scene.positions[tri.x]);
}

/// The side of the surface at `point` that `side` faces. Without `lights`, `lit` stays false.
SideShare measureSide(const Tracer& tracer, const LightTests* light, const SurfacePoint& point, glm::vec3 side,
                      uint32_t stream) {
    const Scene& scene = tracer.scene();
    const Material& m = scene.materials[scene.triangle_materials[point.triangle]];
    SideShare result;
    // The surface as a ray arriving against `side` sees it (back faces flip their normals).
    const RayHit at{point.triangle, 1.0f, point.barycentrics.x, point.barycentrics.y};
    const SurfaceHit hit = makeSurfaceHit(scene, at, -side);
    const ShadingMaterial material = evaluateMaterial(scene, hit);
    // Where light starts is where it lives: an emitting side is lit, whatever else reaches it.
    if (light && maxComponent(emittedRadiance(hit, material)) > 0.0f) result.lit = true;
    if (m.unlit) return result;  // emits its colour, reflects nothing
    const GltfBsdf bsdf(material, hit);
    const double albedo = double(maxComponent(bsdf.albedo(hit.shading_normal)));
    const Frame frame(hit.geometric_normal);
    const glm::vec3 origin = offsetRayOrigin(hit.position, hit.geometric_normal, hit.ray_offset);
    for (uint32_t d = 0; d < kDirectionsPerSide; ++d) {
        // Stratified in the first dimension, jittered per point.
        const glm::vec2 u((float(d) + bitsToUnitFloat(hashCombine(stream, 2 * d))) / float(kDirectionsPerSide),
                          bitsToUnitFloat(hashCombine(stream, 2 * d + 1)));
        const glm::vec3 direction = frame.toWorld(sampleCosineHemisphere(u));
        RayHit landing;
        if (tracer.intersect(Ray{origin, direction}, landing)) {
            const bool back = glm::dot(triangleNormal(scene, landing.triangle), direction) > 0.0f;
            result.landings[result.landed++] = 2 * landing.triangle + (back ? 1u : 0u);
        } else if (light && !result.lit) {
            result.lit = light->escapes(origin, direction);
        }
    }
    result.share = albedo > 0.0 ? albedo * double(result.landed) / double(kDirectionsPerSide) : 0.0;
    if (light && !result.lit) result.lit = light->sampleReaches(hit, bsdf, kLightSamplesPerSide, stream);
    return result;
}

}  // namespace

double SceneReflectance::bounces() const {
    return reflectance < 1.0 ? 1.0 / (1.0 - reflectance) : std::numeric_limits<double>::infinity();
}

std::string SceneReflectance::describe() const {
    char text[200];
    if (unbounded()) {
        std::snprintf(text, sizeof text,
                      "light never leaves this scene (its surfaces send %.4g%% of the light reaching them back "
                      "onto it): its radiance has no finite value",
                      100.0 * reflectance);
    } else {
        std::snprintf(text, sizeof text,
                      "light stays in this scene for about %.0f bounces (its surfaces send %.3g%% of the light "
                      "reaching them back onto it)",
                      bounces(), 100.0 * reflectance);
    }
    return text;
}

SceneReflectance estimateSceneReflectance(const Tracer& tracer, const LightSampler* lights, uint32_t count,
                                          uint32_t seed) {
    SceneReflectance result;
    const std::vector<SurfacePoint> points = sampleSurfacePoints(tracer.scene(), count, seed);
    if (points.empty()) return result;
    prepareBsdfTables();
    const std::optional<LightTests> light = lights && lights->hasLights()
                                                ? std::optional<LightTests>(std::in_place, tracer, *lights)
                                                : std::nullopt;
    // Each point's sides into its own slots, summed in order afterwards: the same sums on any
    // thread count.
    std::vector<SideShare> fronts(points.size()), backs(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        const SurfacePoint& p = points[i];
        const uint32_t stream = hashCombine(seed, uint32_t(i));
        const LightTests* tests = light ? &*light : nullptr;
        fronts[i] = measureSide(tracer, tests, p, p.normal, stream);
        backs[i] = measureSide(tracer, tests, p, -p.normal, hashCombine(stream, 0x5eedu));
    });
    // Light reaching a triangle's side reaches the sides whose reflected rays land there: spread
    // it, round by round, through the sides the points' rays land on (through a window onto the
    // far wall, then onto the wall around the window). The inside of a closed solid under a sky
    // is never reached.
    if (light) {
        // By triangle side: a material's (a fallback tried for triangles no point fell on) let
        // one lit back of an inverted triangle, common in STL meshes, light every inside.
        std::vector<uint8_t> lit_side(2 * tracer.scene().triangles.size(), 0);
        for (size_t i = 0; i < points.size(); ++i) {
            if (fronts[i].lit) lit_side[2 * size_t(points[i].triangle)] = 1;
            if (backs[i].lit) lit_side[2 * size_t(points[i].triangle) + 1] = 1;
        }
        const auto landsOnLight = [&](const SideShare& side) {
            for (uint32_t d = 0; d < side.landed; ++d)
                if (lit_side[side.landings[d]]) return true;
            return false;
        };
        for (int round = 0; round < kSpreadRounds; ++round) {
            bool spread = false;
            for (size_t i = 0; i < points.size(); ++i) {
                for (const bool back : {false, true}) {
                    SideShare& side = back ? backs[i] : fronts[i];
                    if (side.lit || !landsOnLight(side)) continue;
                    side.lit = true;
                    lit_side[2 * size_t(points[i].triangle) + back] = 1;
                    spread = true;
                }
            }
            if (!spread) break;
        }
    }
    // Both sides count: glTF's single-sided materials still reflect on their back (only emission
    // and rasterisers' culling are one-sided), and inside a closed room the walls' inner sides
    // are the ones that matter, whichever way they were modelled. But a side no light reaches,
    // even after a bounce, holds none: the inside of a closed solid under a sky, which would send
    // back everything reaching it, gets nothing, and a point dark on both sides takes no part.
    double sum = 0.0, all_sides = 0.0;
    uint32_t taking_part = 0;
    for (size_t i = 0; i < points.size(); ++i) {
        const SideShare& f = fronts[i];
        const SideShare& b = backs[i];
        all_sides += std::max(f.share, b.share);
        if (!f.lit && !b.lit) continue;
        sum += std::max(f.lit ? f.share : 0.0, b.lit ? b.share : 0.0);
        ++taking_part;
    }
    result.points = uint32_t(points.size());
    // Without lights to tell (or where light reaches no surface), every point takes its larger side.
    result.reflectance = taking_part > 0 ? sum / double(taking_part) : all_sides / double(points.size());
    return result;
}

}  // namespace sharcbake
