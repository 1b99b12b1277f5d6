// SPDX-License-Identifier: Apache-2.0
/// @file sharc_update.h
/// @brief SHaRC's update pass on the CPU, as a wavefront: a batch of update paths from the
/// virtual camera advances bounce by bounce, each bounce tracing the batch's rays and then its
/// shadow rays together; every vertex deposits its local radiance into its voxel and propagates
/// it back along its path (docs/sharc_algorithm.md §4).
///
/// The paths of a batch never interact, so the deposits are exactly those of tracing the paths
/// one after another; they come out per path, in path order, whatever the batch size.
#pragma once

#include "tracing/bsdf.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/surface.h"
#include "sharc/sharc_cache.h"
#include "tracing/tracer.h"
#include "sharc/view_region.h"

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

namespace sharcbake {

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

    UpdateCounters& operator+=(const UpdateCounters& other);
};

/// Where an update path starts: its camera ray and its sampler (dimension 0 picked the pixel;
/// bounce b draws PathTracer::kDimensionsPerBounce pairs from kFirstBounceDimension + 4b).
struct UpdatePathStart {
    Ray camera_ray;
    PixelSampler sampler;
};

/// Traces batches of update paths. One object per thread: it owns the batch's scratch memory,
/// which is reused from batch to batch. Reads the cache's resolved entries (the previous
/// iteration's state) but never writes the cache.
class UpdateWavefront {
public:
    UpdateWavefront(const Tracer& tracer, const LightSampler& lights, const SharcCache& cache,
                    UpdatePathSettings settings);
    ~UpdateWavefront();
    UpdateWavefront(const UpdateWavefront&) = delete;
    UpdateWavefront& operator=(const UpdateWavefront&) = delete;

    /// Traces the paths of `starts` and appends their deposits to `out`: path by path, in the
    /// order of `starts`, each path's in vertex order. `levels` picks each vertex's voxel (the
    /// finest level a runtime camera of the view region can ask for there); `camera` is this
    /// iteration's camera position (the level-of-detail centre when the region is the bake
    /// camera itself).
    void trace(const std::vector<UpdatePathStart>& starts, const DepositLevels& levels, const Float3& camera,
               std::vector<Deposit>& out, UpdateCounters& counters);

    /// The memory one path in flight holds (its state between bounces and its share of the
    /// batch's ray arrays), without its deposits, for the benchmarks' report.
    static size_t bytesPerPathInFlight();

private:
    struct Path;
    /// One bounce of the batch: trace the active paths' rays, shade the hits, trace the shadow
    /// rays, deposit, and continue the surviving paths (which stay in `active_`).
    void advance(uint32_t bounce, const DepositLevels& levels, const Float3& camera, UpdateCounters& counters);
    /// The hit's surface, material, key and emission, and the voxel cache resampling would
    /// read there (Path::feedback_key, 0 when this vertex does not resample).
    void shadeSurface(Path& path, const RayHit& ray_hit, uint32_t bounce, uint32_t depth,
                      const DepositLevels& levels, const Float3& camera) const;
    /// Sets `first` and `second` of each path in sample_paths_ to its sampler's pairs of
    /// `dimension` and `dimension + 1`, drawn for all of them at once (sample_batch.h).
    void drawSamples(uint32_t dimension, glm::vec2 Path::*first, glm::vec2 Path::*second);
    /// Looks up the feedback voxels of the shaded paths, a batch at a time.
    void findFeedbackVoxels();
    /// The BSDF and the light sample (the shadow ray to trace with the batch's).
    void prepareLocalLight(Path& path) const;
    /// The vertex's deposits once its shadow ray is answered; then Russian roulette and the
    /// BSDF sample. False when the path ends.
    bool depositAndContinue(Path& path, uint32_t bounce, uint32_t depth, UpdateCounters& counters) const;
    /// SharcUpdateMiss: the sky's radiance, MIS-weighted, to the vertices still waiting.
    void depositSkyMiss(Path& path, uint32_t bounce, UpdateCounters& counters) const;
    /// Cache resampling: ends the path on its feedback voxel's resolved value (less the
    /// emission the previous vertex's light sampling already counted) and returns true; false
    /// when the vertex does not resample or the voxel holds nothing yet.
    bool endOnCache(Path& path, UpdateCounters& counters) const;

    const Tracer& tracer_;
    const LightSampler& lights_;
    const SharcCache& cache_;
    UpdatePathSettings settings_;

    // The batch, reused between calls.
    std::vector<Path> paths_;
    std::vector<uint32_t> active_;          ///< paths still tracing, in batch order
    std::vector<uint32_t> next_active_;
    std::vector<uint32_t> shaded_;          ///< paths whose ray hit a surface this bounce
    std::vector<Ray> rays_;                 ///< this bounce's rays, one per active path
    std::vector<RayHit> hits_;
    std::vector<uint8_t> found_;
    std::vector<uint32_t> shadow_paths_;    ///< the paths of shadow_rays_, one each
    std::vector<Ray> shadow_rays_;
    std::vector<uint8_t> blocked_;          ///< Embree's answer per shadow ray
    std::vector<uint32_t> sample_paths_;    ///< drawSamples' paths, and its lanes:
    std::vector<uint32_t> sample_hashes_;   ///< their samplers' pixelHash()
    std::vector<uint32_t> sample_indices_;  ///< and reversedSample()
    std::vector<glm::vec2> sample_values_;  ///< the first dimension's pairs, then the second's
};

}  // namespace sharcbake
