// SPDX-License-Identifier: Apache-2.0
#include "tracing/scene_reflectance.h"

#include "tracing/bsdf.h"
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

/// The albedo of one side of the surface at `point` (the side `side` faces) times the share of
/// cosine-distributed rays leaving that side that hit the scene again.
double reflectedShare(const Tracer& tracer, const SurfacePoint& point, glm::vec3 side, uint32_t stream) {
    const Scene& scene = tracer.scene();
    const Material& m = scene.materials[scene.triangle_materials[point.triangle]];
    if (m.unlit) return 0.0;  // emits its colour, reflects nothing
    // The surface as a ray arriving against `side` sees it (back faces flip their normals).
    const RayHit at{point.triangle, 1.0f, point.barycentrics.x, point.barycentrics.y};
    const SurfaceHit hit = makeSurfaceHit(scene, at, -side);
    const GltfBsdf bsdf(evaluateMaterial(scene, hit), hit);
    const double albedo = double(maxComponent(bsdf.albedo(hit.shading_normal)));
    if (!(albedo > 0.0)) return 0.0;
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
    return albedo * double(hits) / double(kDirectionsPerSide);
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

SceneReflectance estimateSceneReflectance(const Tracer& tracer, uint32_t count, uint32_t seed) {
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
        // Both sides: glTF's single-sided materials still reflect on their back (only emission and
        // rasterisers' culling are one-sided), and inside a closed room the walls' inner sides are
        // the ones that matter, whichever way they were modelled.
        shares[i] = std::max(reflectedShare(tracer, p, p.normal, stream),
                             reflectedShare(tracer, p, -p.normal, hashCombine(stream, 0x5eedu)));
    });
    double sum = 0.0;
    for (const double share : shares) sum += share;
    result.points = uint32_t(points.size());
    result.reflectance = sum / double(points.size());
    return result;
}

}  // namespace sharcbake
