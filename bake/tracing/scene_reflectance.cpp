// SPDX-License-Identifier: Apache-2.0
#include "tracing/scene_reflectance.h"

#include "tracing/bsdf.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"
#include "tracing/surface_points.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace sharcbake {
namespace {

constexpr uint32_t kDirectionsPerSide = 8;
/// Light samples drawn from each side to measure how much light reaches it directly.
constexpr uint32_t kLightSamplesPerSide = 8;
/// Light samples nearer than this cosine to the side's plane do not count.
constexpr float kGrazingCosine = 1e-3f;
/// A side that light reaches less than this share as well as the other side's is counted as
/// unlit: Embree's triangle test is not watertight, so a ray from inside a closed mesh now and then
/// slips out through an edge.
constexpr double kLeakExposure = 0.25;

/// What one side of a surface point does with the light reaching it.
struct SideShare {
    /// Its albedo (light arriving along its normal) times the share of cosine-distributed rays
    /// leaving it that hit the scene again.
    double share = 0.0;
    /// How much light reaches the side directly: the share of light samples drawn from it that
    /// are unblocked, plus, under a sky, the share of its rays that escape. 0 without lights.
    double exposure = 0.0;
};

/// The side of the surface at `point` that `side` faces.
SideShare measureSide(const Tracer& tracer, const LightSampler* lights, const SurfacePoint& point, glm::vec3 side,
                      uint32_t stream) {
    const Scene& scene = tracer.scene();
    const Material& m = scene.materials[scene.triangle_materials[point.triangle]];
    SideShare result;
    if (m.unlit) return result;  // emits its colour, reflects nothing
    // The surface as a ray arriving against `side` sees it (back faces flip their normals).
    const RayHit at{point.triangle, 1.0f, point.barycentrics.x, point.barycentrics.y};
    const SurfaceHit hit = makeSurfaceHit(scene, at, -side);
    const GltfBsdf bsdf(evaluateMaterial(scene, hit), hit);
    const double albedo = double(maxComponent(bsdf.albedo(hit.shading_normal)));
    if (!(albedo > 0.0)) return result;
    const Frame frame(hit.geometric_normal);
    const glm::vec3 origin = offsetRayOrigin(hit.position, hit.geometric_normal);
    uint32_t hits = 0;
    for (uint32_t d = 0; d < kDirectionsPerSide; ++d) {
        // Stratified in the first dimension, jittered per point.
        const glm::vec2 u((float(d) + bitsToUnitFloat(hashCombine(stream, 2 * d))) / float(kDirectionsPerSide),
                          bitsToUnitFloat(hashCombine(stream, 2 * d + 1)));
        RayHit ignored;
        hits += tracer.intersect(Ray{origin, frame.toWorld(sampleCosineHemisphere(u))}, ignored) ? 1u : 0u;
    }
    result.share = albedo * double(hits) / double(kDirectionsPerSide);
    if (lights == nullptr || !lights->hasLights()) return result;
    if (lights->hasSky()) result.exposure = double(kDirectionsPerSide - hits) / double(kDirectionsPerSide);
    uint32_t unblocked = 0;
    for (uint32_t k = 0; k < kLightSamplesPerSide; ++k) {
        const uint32_t light_stream = hashCombine(stream, 0x11u + k);
        const ShadowQuery q = prepareDirectLight(
            *lights, hit, bsdf, hit.shading_normal, bitsToUnitFloat(hashCombine(light_stream, 0)),
            glm::vec2(bitsToUnitFloat(hashCombine(light_stream, 1)), bitsToUnitFloat(hashCombine(light_stream, 2))));
        // A grazing sample is a point of an emitter in the side's own plane (a wall's other
        // triangles, seen along its outside), which lights nothing.
        const bool facing = glm::dot(q.ray.direction, hit.geometric_normal) > kGrazingCosine;
        if (q.needed && facing && maxComponent(q.unoccluded) > 0.0f && !tracer.occluded(q.ray)) ++unblocked;
    }
    result.exposure += double(unblocked) / double(kLightSamplesPerSide);
    return result;
}

/// The point's two sides weighted by the light reaching each: the share of the light arriving
/// at the point that goes back onto the scene. The outside of a closed solid under a sky counts,
/// not its inside, which would reflect everything back onto itself but gets no light. Where
/// neither side is reached directly (light arrives after bounces), the larger share: glTF's
/// single-sided materials still reflect on their back (only emission and rasterisers' culling
/// are one-sided), and inside a closed room the walls' inner sides are the ones that matter,
/// whichever way they were modelled.
double pointShare(const SideShare& front, const SideShare& back) {
    const double front_exposure = front.exposure < kLeakExposure * back.exposure ? 0.0 : front.exposure;
    const double back_exposure = back.exposure < kLeakExposure * front.exposure ? 0.0 : back.exposure;
    const double exposure = front_exposure + back_exposure;
    if (!(exposure > 0.0)) return std::max(front.share, back.share);
    return (front_exposure * front.share + back_exposure * back.share) / exposure;
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
    // Each point's share into its own slot, summed in order afterwards: the same sum on any
    // thread count.
    std::vector<double> shares(points.size());
    tbb::parallel_for(size_t(0), points.size(), [&](size_t i) {
        const SurfacePoint& p = points[i];
        const uint32_t stream = hashCombine(seed, uint32_t(i));
        shares[i] = pointShare(measureSide(tracer, lights, p, p.normal, stream),
                               measureSide(tracer, lights, p, -p.normal, hashCombine(stream, 0x5eedu)));
    });
    double sum = 0.0;
    for (const double share : shares) sum += share;
    result.points = uint32_t(points.size());
    result.reflectance = sum / double(points.size());
    return result;
}

}  // namespace sharcbake
