// SPDX-License-Identifier: Apache-2.0
/// @file sharc_update.h
/// @brief SHaRC's update pass on the CPU: one update path from the virtual camera, depositing
/// each vertex's local radiance into its voxel and propagating it back along the path
/// (docs/sharc_algorithm.md §4).
#pragma once

#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/surface.h"
#include "sharc/sharc_cache.h"
#include "tracing/tracer.h"
#include "sharc/view_region.h"

#include <cstdint>
#include <vector>

namespace sharcbake {

class GltfBsdf;

struct UpdatePathSettings {
    uint32_t max_bounces = 8;        ///< surface interactions per update path
    uint32_t russian_roulette_start = 2;
};

/// Counters of the update pass, per thread and then summed.
struct UpdateCounters {
    uint64_t paths = 0;
    uint64_t segments = 0;           ///< closest-hit rays (path segments)
    uint64_t shadow_rays = 0;
    uint64_t resampled = 0;          ///< paths ended by cache resampling
    uint64_t sky_misses = 0;
    uint64_t non_finite = 0;         ///< NaN/Inf local radiance values replaced by 0
    uint64_t clamped_propagation = 0;  ///< resampled values whose emission share exceeded the voxel mean
};

class UpdatePathTracer {
public:
    UpdatePathTracer(const Tracer& tracer, const LightSampler& lights, const SharcCache& cache,
                     UpdatePathSettings settings);

    /// Traces one update path and appends its deposits, in path order, to `out`. Reads the
    /// cache's resolved entries (the previous iteration's state) but never writes the cache.
    /// `levels` picks each vertex's voxel (the finest level a runtime camera of the view region
    /// can ask for there); `camera` is this iteration's camera position (the level-of-detail
    /// centre when the region is the bake camera itself).
    void trace(const Ray& camera_ray, PixelSampler& sampler, const DepositLevels& levels, const Float3& camera,
               std::vector<Deposit>& out, UpdateCounters& counters) const;

private:
    struct PathState;

    /// SharcUpdateMiss: the sky's radiance, MIS-weighted, to the vertices still waiting.
    void depositSkyMiss(const PathState& path, uint32_t bounce, std::vector<Deposit>& out,
                        UpdateCounters& counters) const;
    /// Cache resampling: at the chosen depth, ends the path on the voxel's resolved value
    /// (less `counted_emission`, already counted by light sampling) and returns true.
    bool endOnCache(PathState& path, const SurfaceHit& hit, glm::vec3 counted_emission, bool last_vertex,
                    uint32_t depth, float u_depth, const DepositLevels& levels, const Float3& camera,
                    std::vector<Deposit>& out, UpdateCounters& counters) const;
    /// Russian roulette, then a BSDF sample for the next segment; false when the path ends.
    bool continuePath(PathState& path, const SurfaceHit& hit, const GltfBsdf& bsdf, glm::vec3 wo, uint32_t bounce,
                      PixelSampler& sampler) const;

    const Tracer& tracer_;
    const LightSampler& lights_;
    const SharcCache& cache_;
    UpdatePathSettings settings_;
};

}  // namespace sharcbake
