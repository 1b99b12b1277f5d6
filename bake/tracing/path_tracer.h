// SPDX-License-Identifier: Apache-2.0
/// @file path_tracer.h
/// @brief The reference path tracer: unidirectional, next-event estimation with multiple
/// importance sampling (power heuristic) for area, punctual and sky lights, Russian roulette.
#pragma once

#include "support/sharded_counts.h"
#include "tracing/bsdf.h"
#include "tracing/lights.h"
#include "tracing/sampling.h"
#include "tracing/tracer.h"

#include <glm/glm.hpp>

#include <cstdint>

namespace sharcbake {

struct PathTracerSettings {
    /// Maximum number of surface interactions after the camera (the primary hit is bounce 0).
    /// Russian roulette ends almost every path long before it; the cap only bounds the worst
    /// case (a furnace with albedo 0.99 needs hundreds of bounces to be unbiased to 3%).
    uint32_t max_bounces = 1024;
    /// Russian roulette starts at this bounce.
    uint32_t russian_roulette_start = 3;
};

/// What paths counted: plain numbers, which a path keeps for itself and adds to its render's
/// TraceCounters once, at its end.
struct TraceCounts {
    uint64_t closest_hit_rays = 0;
    uint64_t shadow_rays = 0;
    uint64_t non_finite_samples = 0;  ///< NaN/Inf path samples dropped
    uint64_t cache_hits = 0;          ///< paths ended on a radiance-cache hit
};

/// The counts of one render, added to by all its threads at once (ShardedCounts: no thread waits
/// on another's adds).
class TraceCounters {
public:
    void add(const TraceCounts& counts) {
        shares_.add(0, counts.closest_hit_rays);
        shares_.add(1, counts.shadow_rays);
        shares_.add(2, counts.non_finite_samples);
        shares_.add(3, counts.cache_hits);
    }
    /// The sums so far (exact once the adding threads have finished).
    TraceCounts total() const { return {shares_.total(0), shares_.total(1), shares_.total(2), shares_.total(3)}; }

private:
    ShardedCounts<4> shares_;
};

class GltfBsdf;

/// Next-event estimation at a hit, split around its shadow ray so that many paths can trace
/// theirs together: the segment to test and what arrives if nothing blocks it.
struct ShadowQuery {
    Ray ray;
    glm::vec3 unoccluded{0.0f};  ///< BSDF x cos x Le / pdf, MIS-weighted
    bool needed = false;         ///< false: the light sample contributes nothing (no ray to trace)
};
/// The first half of estimateDirectLight: light and point sampled, BSDF evaluated, no ray traced.
ShadowQuery prepareDirectLight(const LightSampler& lights, const SurfaceHit& hit, const GltfBsdf& bsdf,
                               glm::vec3 wo, float u_select, glm::vec2 u_point);

/// Next-event estimation at a hit: picks one light with u_select, a point on it with u_point,
/// tests occlusion and returns BSDF x cos x Le / pdf, weighted by MIS against BSDF sampling
/// (delta lights have weight 1). Shared by the reference path tracer and the SHaRC update.
glm::vec3 estimateDirectLight(const Tracer& tracer, const LightSampler& lights, const SurfaceHit& hit,
                              const GltfBsdf& bsdf, glm::vec3 wo, float u_select, glm::vec2 u_point,
                              TraceCounts& counts);

/// Russian roulette's survival probability at a vertex: the path's throughput so far (at most 1)
/// times the vertex's directional albedo, largest channel. Decided before the direction is
/// sampled, it never depends on the sample's weight, and above a throughput of 1 paths still
/// thin by the albedo, so the throughput divided by it has the expectation it had: it cannot run
/// away geometrically in a high-albedo scene. (The SHaRC update uses the albedo alone: each of its
/// vertices is an estimate of its own voxel, whatever the camera's throughput; sharc_update.cpp.)
inline float russianRouletteSurvival(glm::vec3 throughput, glm::vec3 albedo) {
    return std::min(1.0f, maxComponent(albedo) * std::min(1.0f, maxComponent(throughput)));
}

/// MIS weight of emission found by a BSDF-sampled ray, against next-event estimation of the
/// same emitter. 1 at the primary hit, where no light was sampled.
float emissionMisWeight(const LightSampler& lights, uint32_t bounce, float previous_bsdf_pdf,
                        glm::vec3 previous_position, glm::vec3 previous_shading_normal, const SurfaceHit& emitter);

/// What a path asks a radiance cache for at a secondary hit. The cache decides whether the
/// hit is eligible (segment long enough, cone footprint wide enough) and what it returns.
struct CacheQuery {
    glm::vec3 position;
    glm::vec3 geometric_normal;  ///< facing the incoming ray
    float segment_length;        ///< length of the segment that reached the hit
    float cone_roughness;        ///< SHaRC's accumulated path roughness (+1 per diffuse bounce)
};

/// A radiance cache the path tracer may end paths on (`render --cache`).
class RadianceCache {
public:
    virtual ~RadianceCache() = default;
    /// The cached outgoing radiance at the hit (emission included), or false to keep tracing.
    virtual bool lookup(const CacheQuery& query, glm::vec3& radiance) const = 0;
};

class PathTracer {
public:
    PathTracer(const Tracer& tracer, const LightSampler& lights, PathTracerSettings settings,
               const RadianceCache* cache = nullptr)
        : tracer_(tracer), lights_(lights), settings_(settings), cache_(cache) {
        prepareBsdfTables();
    }

    /// Radiance arriving along `ray` (towards its origin). `sampler` must be positioned at the
    /// first dimension after the camera's.
    glm::vec3 radiance(const Ray& ray, PixelSampler& sampler, TraceCounters& counters) const;

    /// Dimensions used per bounce; bounce b starts at kFirstBounceDimension + b * this.
    static constexpr uint32_t kDimensionsPerBounce = 4;
    static constexpr uint32_t kFirstBounceDimension = 1;

private:
    const Tracer& tracer_;
    const LightSampler& lights_;
    PathTracerSettings settings_;
    const RadianceCache* cache_;
};

}  // namespace sharcbake
