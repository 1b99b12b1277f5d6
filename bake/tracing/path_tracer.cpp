// SPDX-License-Identifier: Apache-2.0
#include "tracing/path_tracer.h"

#include "tracing/bsdf.h"
#include "tracing/surface.h"

#include <cmath>

namespace sharcbake {

ShadowQuery prepareDirectLight(const LightSampler& lights, const SurfaceHit& hit, const GltfBsdf& bsdf,
                               glm::vec3 wo, float u_select, glm::vec2 u_point) {
    ShadowQuery query;
    LightSample light;
    if (!lights.sample(hit, u_select, u_point, light)) return query;
    const GltfBsdf::Evaluation e = bsdf.evaluate(wo, light.wi);
    if (maxComponent(e.f_cos) <= 0.0f) return query;

    Ray shadow;
    if (!shadowRayTo(hit.position, hit.geometric_normal, hit.ray_offset, light.wi, light.distance, shadow))
        return query;
    const float weight = light.is_delta ? 1.0f : powerHeuristic(light.pdf, e.pdf);
    query.ray = shadow;
    query.unoccluded = e.f_cos * light.radiance * (weight / light.pdf);
    query.needed = true;
    return query;
}

glm::vec3 estimateDirectLight(const Tracer& tracer, const LightSampler& lights, const SurfaceHit& hit,
                              const GltfBsdf& bsdf, glm::vec3 wo, float u_select, glm::vec2 u_point,
                              TraceCounts& counts) {
    const ShadowQuery query = prepareDirectLight(lights, hit, bsdf, wo, u_select, u_point);
    if (!query.needed) return glm::vec3(0.0f);
    ++counts.shadow_rays;
    return tracer.occluded(query.ray) ? glm::vec3(0.0f) : query.unoccluded;
}

float emissionMisWeight(const LightSampler& lights, uint32_t bounce, float previous_bsdf_pdf,
                        glm::vec3 previous_position, glm::vec3 previous_shading_normal, const SurfaceHit& emitter) {
    if (bounce == 0) return 1.0f;
    return powerHeuristic(previous_bsdf_pdf, lights.pdfEmitter(previous_position, previous_shading_normal, emitter));
}

glm::vec3 PathTracer::radiance(const Ray& camera_ray, PixelSampler& sampler,
                               TraceCounters& counters) const {
    glm::vec3 result(0.0f);
    glm::vec3 throughput(1.0f);
    Ray ray = camera_ray;
    // State of the previous vertex, for MIS when the BSDF-sampled ray finds a light.
    float previous_bsdf_pdf = 0.0f;
    glm::vec3 previous_position = ray.origin;
    glm::vec3 previous_shading_normal(0.0f);
    float cone_roughness = 0.0f;  // SHaRC's path spread: +1 per diffuse bounce, +roughness per glossy
    TraceCounts counts;           // this path's, added to `counters` once at its end

    for (uint32_t bounce = 0;; ++bounce) {
        sampler.startDimension(kFirstBounceDimension + bounce * kDimensionsPerBounce);
        RayHit ray_hit;
        ++counts.closest_hit_rays;
        if (!tracer_.intersect(ray, ray_hit)) {
            if (lights_.hasSky()) {
                const glm::vec3 sky = lights_.skyRadiance(ray.direction);
                const float weight = bounce == 0
                                         ? 1.0f
                                         : powerHeuristic(previous_bsdf_pdf,
                                                          lights_.pdfSky(previous_position, previous_shading_normal,
                                                                         ray.direction));
                result += throughput * sky * weight;
            }
            break;
        }
        const SurfaceHit hit = makeSurfaceHit(tracer_.scene(), ray_hit, ray.direction);
        const ShadingMaterial material = evaluateMaterial(tracer_.scene(), hit);
        const glm::vec3 wo = -ray.direction;

        const glm::vec3 emitted = emittedRadiance(hit, material);
        const bool emits = maxComponent(emitted) > 0.0f;
        const float emission_weight = emits ? emissionMisWeight(lights_, bounce, previous_bsdf_pdf, previous_position,
                                                                previous_shading_normal, hit)
                                            : 0.0f;
        if (emits) result += throughput * emitted * emission_weight;

        // A cached value is the full outgoing radiance, emission included. The emission's
        // BSDF-sampled share was added above; the share next-event estimation covered at the
        // previous vertex must not be added twice, so only the reflected part is taken here.
        if (cache_ && bounce > 0) {
            glm::vec3 cached;
            if (cache_->lookup(CacheQuery{hit.position, hit.geometric_normal, ray_hit.t, cone_roughness},
                               cached)) {
                ++counts.cache_hits;
                result += throughput * glm::max(cached - emitted, glm::vec3(0.0f));
                break;
            }
        }
        if (bounce >= settings_.max_bounces) break;

        const GltfBsdf bsdf(material, hit);
        const glm::vec2 u_light_select = sampler.next2D();
        const glm::vec2 u_light_point = sampler.next2D();
        if (lights_.hasLights()) {
            result += throughput *
                      estimateDirectLight(tracer_, lights_, hit, bsdf, wo, u_light_select.x, u_light_point, counts);
        }

        const glm::vec2 u_lobe_rr = sampler.next2D();
        // Russian roulette before sampling, from the vertex's albedo (not the sampled weight): a
        // path survives with its expected throughput, at most the albedo even when the throughput
        // exceeds 1, so the throughput cannot grow in expectation however long the path.
        float survive = 1.0f;
        if (bounce >= settings_.russian_roulette_start) {
            survive = russianRouletteSurvival(throughput, bsdf.albedo(wo));
            if (!(survive > 0.0f) || u_lobe_rr.y >= survive) break;
        }
        const GltfBsdf::Sample s = bsdf.sample(wo, u_lobe_rr.x, sampler.next2D());
        if (!s.valid) break;
        throughput *= s.weight / survive;
        cone_roughness += s.specular ? s.roughness : 1.0f;
        previous_bsdf_pdf = s.pdf;
        previous_position = hit.position;
        previous_shading_normal = hit.shading_normal;
        ray = Ray{offsetRayOrigin(hit.position, hit.geometric_normal, hit.ray_offset), s.wi};
    }
    const bool finite = isFiniteColor(result);
    counts.non_finite_samples += !finite;
    counters.add(counts);
    return finite ? result : glm::vec3(0.0f);
}

}  // namespace sharcbake
