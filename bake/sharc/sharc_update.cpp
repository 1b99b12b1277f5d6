// SPDX-License-Identifier: Apache-2.0
#include "sharc/sharc_update.h"

#include "tracing/bsdf.h"
#include "tracing/surface.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace sharcbake {
namespace {

/// The last few path vertices that still receive radiance (SharcState): their keys and the
/// product of segment throughputs from each of them to the current vertex.
struct PathHistory {
    static constexpr uint32_t kMaxDepth = 16;
    std::array<uint64_t, kMaxDepth> keys{};
    std::array<glm::vec3, kMaxDepth> weights{};
    uint32_t length = 0;

    /// SharcUpdateMiss / the back-propagation step of SharcUpdateHit.
    void propagate(glm::vec3 radiance, std::vector<Deposit>& out) const {
        for (uint32_t j = 0; j < length; ++j) {
            const glm::vec3 value = radiance * weights[j];
            if (maxComponent(value) > 0.0f) out.push_back(Deposit{keys[j], value, 0});
        }
    }
    /// SharcSetThroughput: the new segment's throughput multiplies every stored weight.
    void applyThroughput(glm::vec3 throughput) {
        for (uint32_t j = 0; j < length; ++j) weights[j] *= throughput;
    }
    /// Shift the history and make `key` the most recent vertex.
    void push(uint64_t key, uint32_t depth) {
        for (uint32_t j = std::min(length, depth - 1); j > 0; --j) {
            keys[j] = keys[j - 1];
            weights[j] = weights[j - 1];
        }
        keys[0] = key;
        weights[0] = glm::vec3(1.0f);
        length = std::min(length + 1, depth);
    }
};

glm::vec3 finiteOrZero(glm::vec3 v, uint64_t& non_finite) {
    if (isFiniteColor(v)) return v;
    ++non_finite;
    return glm::vec3(0.0f);
}

}  // namespace

UpdatePathTracer::UpdatePathTracer(const Tracer& tracer, const LightSampler& lights,
                                   const SharcCache& cache, UpdatePathSettings settings)
    : tracer_(tracer), lights_(lights), cache_(cache), settings_(settings) {}

/// One update path's state between its vertices.
struct UpdatePathTracer::PathState {
    PathHistory history;
    Ray ray;
    float previous_bsdf_pdf = 0.0f;
    glm::vec3 previous_position{0.0f};
    glm::vec3 previous_shading_normal{0.0f};
    glm::vec3 throughput{1.0f};  ///< only for Russian roulette
};

void UpdatePathTracer::trace(const Ray& camera_ray, PixelSampler& sampler, const DepositLevels& levels,
                             const Float3& camera,
                             std::vector<Deposit>& out, UpdateCounters& counters) const {
    const uint32_t depth = std::clamp(cache_.settings().propagation_depth, 1u, PathHistory::kMaxDepth);
    PathState path;
    path.ray = camera_ray;
    path.previous_position = camera_ray.origin;
    TraceCounters trace_counters;  // shadow rays from estimateDirectLight
    ++counters.paths;

    for (uint32_t bounce = 0; bounce < settings_.max_bounces; ++bounce) {
        sampler.startDimension(PathTracer::kFirstBounceDimension + bounce * PathTracer::kDimensionsPerBounce);
        RayHit ray_hit;
        ++counters.segments;
        if (!tracer_.intersect(path.ray, ray_hit)) {
            depositSkyMiss(path, bounce, out, counters);
            break;
        }
        const SurfaceHit hit = makeSurfaceHit(tracer_.scene(), ray_hit, path.ray.direction);
        const ShadingMaterial material = evaluateMaterial(tracer_.scene(), hit);
        const glm::vec3 wo = -path.ray.direction;
        // SHaRC keys use the geometric normal turned towards the incoming ray, so the two sides
        // of a thin wall are different voxels.
        const uint64_t key = levels.key(hit.position, hit.geometric_normal, camera);

        const glm::vec2 u_select_resample = sampler.next2D();
        const glm::vec2 u_light_point = sampler.next2D();

        const glm::vec3 emitted = emittedRadiance(hit, material);
        const float emission_weight =
            maxComponent(emitted) > 0.0f
                ? emissionMisWeight(lights_, bounce, path.previous_bsdf_pdf, path.previous_position, hit)
                : 0.0f;
        const bool last_vertex = bounce + 1 >= settings_.max_bounces;
        if (endOnCache(path, hit, emitted * (1.0f - emission_weight), last_vertex, depth, u_select_resample.y, levels,
                       camera, out, counters)) {
            break;
        }

        // Local radiance at this vertex: its emission and next-event direct light, evaluated
        // with throughput 1 and the update pass's roughness clamp.
        const GltfBsdf bsdf(material, hit, cache_.settings().update_roughness_clamp);
        glm::vec3 direct(0.0f);
        if (lights_.hasLights()) {
            direct = finiteOrZero(estimateDirectLight(tracer_, lights_, hit, bsdf, wo, u_select_resample.x,
                                                      u_light_point, trace_counters),
                                  counters.non_finite);
        }
        // Its own voxel stores the full outgoing radiance (emission included, as the SDK's
        // default does); earlier vertices get the emission's BSDF-sampled share only.
        out.push_back(Deposit{key, emitted + direct, 1});
        path.history.propagate(emitted * emission_weight + direct, out);
        path.history.push(key, depth);

        if (last_vertex || !continuePath(path, hit, bsdf, wo, bounce, sampler)) break;
    }
    counters.shadow_rays += trace_counters.shadow_rays.load(std::memory_order_relaxed);
}

void UpdatePathTracer::depositSkyMiss(const PathState& path, uint32_t bounce, std::vector<Deposit>& out,
                                      UpdateCounters& counters) const {
    if (!lights_.hasSky()) return;
    // SharcUpdateMiss, with the BSDF-sampling MIS weight: the previous vertex's own next-event
    // estimate already holds the light-sampling share of the sky.
    const float weight =
        bounce == 0 ? 1.0f
                    : powerHeuristic(path.previous_bsdf_pdf, lights_.pdfSky(path.previous_shading_normal, path.ray.direction));
    path.history.propagate(finiteOrZero(lights_.skyRadiance(path.ray.direction) * weight, counters.non_finite), out);
    ++counters.sky_misses;
}

bool UpdatePathTracer::endOnCache(PathState& path, const SurfaceHit& hit, glm::vec3 counted_emission,
                                  bool last_vertex, uint32_t depth, float u_depth, const DepositLevels& levels,
                                  const Float3& camera, std::vector<Deposit>& out, UpdateCounters& counters) const {
    const SharcSettings& sharc = cache_.settings();
    if (!sharc.cache_resampling || path.history.length == 0) return false;
    // With a random depth in [1, depth] (or, resampling at the end, once `depth` vertices wait),
    // end the path on the voxel's resolved value (the previous iteration's).
    const uint32_t resample_depth = sharc.resample_at_end ? (last_vertex ? 1u : depth)
                                                          : uint32_t(std::lround(1.0f + float(depth - 1) * u_depth));
    if (resample_depth > path.history.length) return false;
    const ResolvedEntry* entry = cache_.findResolved(levels.feedbackKey(hit.position, hit.geometric_normal, camera));
    if (!entry || !(entry->weight > 0.0)) return false;
    // The cached mean holds this voxel's full emission, but the previous vertex's light
    // sampling already counted the emission's light-sampled share (`counted_emission`).
    glm::vec3 value = entry->feedback - counted_emission;
    if (value.x < 0.0f || value.y < 0.0f || value.z < 0.0f) {
        ++counters.clamped_propagation;
        value = glm::max(value, glm::vec3(0.0f));
    }
    path.history.propagate(value, out);
    ++counters.resampled;
    return true;
}

bool UpdatePathTracer::continuePath(PathState& path, const SurfaceHit& hit, const GltfBsdf& bsdf, glm::vec3 wo,
                                    uint32_t bounce, PixelSampler& sampler) const {
    const glm::vec2 u_lobe_rr = sampler.next2D();
    float survive = 1.0f;  // Russian roulette from the vertex's albedo, as PathTracer does
    if (bounce >= settings_.russian_roulette_start) {
        survive = russianRouletteSurvival(path.throughput, bsdf.albedo(wo));
        if (!(survive > 0.0f) || u_lobe_rr.y >= survive) return false;
    }
    const GltfBsdf::Sample s = bsdf.sample(wo, u_lobe_rr.x, sampler.next2D());
    if (!s.valid) return false;
    const glm::vec3 segment = s.weight / survive;
    path.throughput *= segment;
    path.history.applyThroughput(segment);
    path.previous_bsdf_pdf = s.pdf;
    path.previous_position = hit.position;
    path.previous_shading_normal = hit.shading_normal;
    path.ray = Ray{offsetRayOrigin(hit.position, hit.geometric_normal), s.wi};
    return true;
}

}  // namespace sharcbake
