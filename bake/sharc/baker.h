// SPDX-License-Identifier: Apache-2.0
/// @file baker.h
/// @brief The bake loop: per iteration, place the virtual camera, trace the sparse update
/// paths in parallel, commit their deposits in a fixed order, resolve.
#pragma once

#include "sharc/camera_path.h"
#include "tracing/lights.h"
#include "sharc/sharc_cache.h"
#include "sharc/sharc_update.h"
#include "tracing/tracer.h"

#include <tbb/enumerable_thread_specific.h>

#include <cstdint>
#include <vector>

namespace sharcbake {

struct BakeSettings {
    int width = 1280;  ///< virtual camera image size; update paths start in 1 of stride^2 pixels
    int height = 720;
    uint32_t update_stride = 5;  ///< one random pixel per stride x stride block, per iteration
    uint32_t seed = 0;
    /// Shard `shard_index` of `shard_count` (--shard i/N): this bake's k-th iteration does the
    /// work of iteration k*N + i of the unsharded bake (its camera pose and its samples), so N
    /// shards of K iterations together trace exactly the paths of one bake of N*K iterations.
    uint32_t shard_index = 0;
    uint32_t shard_count = 1;
    UpdatePathSettings path;
    SharcSettings sharc;
    /// Where the runtime's cameras may be: decides each deposit's level and the levels the
    /// written cache covers (view_region.h).
    ViewRegion view_region;
};

/// Seconds spent per stage, summed over iterations.
struct StageSeconds {
    double update = 0.0;   ///< tracing update paths (parallel)
    double commit = 0.0;   ///< inserting keys and adding deposits (parallel; slots and sums independent of the threads)
    double resolve = 0.0;  ///< folding accumulation into the resolved entries (parallel)
};

class Baker {
public:
    Baker(const Tracer& tracer, const LightSampler& lights, const CameraPath& camera_path,
          const BakeSettings& settings, double radiance_scale);

    /// Runs one update + resolve iteration.
    void runIteration();

    /// Traces the update paths of unsharded iteration `work_iteration` against the current cache
    /// into one deposit list per fixed chunk of paths, without committing them (runIteration's
    /// first stage; also the capacity pre-pass).
    void traceUpdatePaths(uint32_t work_iteration, std::vector<std::vector<Deposit>>& chunk_deposits,
                          UpdateCounters& counters) const;

    /// Continues a bake from a checkpoint: `iterations_done` iterations already ran and their
    /// counters are `counters` (the cache state is restored through mutableCache()).
    void resumeAt(uint32_t iterations_done, const UpdateCounters& counters) {
        iteration_ = iterations_done;
        counters_ = counters;
    }
    SharcCache& mutableCache() { return cache_; }

    /// The unsharded iteration whose camera pose and samples this bake's iteration `iteration`
    /// uses (the identity without --shard).
    uint32_t workIteration(uint32_t iteration) const {
        return iteration * settings_.shard_count + settings_.shard_index;
    }

    uint32_t iterationsDone() const { return iteration_; }
    const SharcCache& cache() const { return cache_; }
    const UpdateCounters& counters() const { return counters_; }
    const StageSeconds& seconds() const { return seconds_; }
    uint32_t pathsPerIteration() const { return blocks_x_ * blocks_y_; }
    const BakeSettings& settings() const { return settings_; }
    const DepositLevels& depositLevels() const { return levels_; }

private:
    const Tracer& tracer_;
    const LightSampler& lights_;
    const CameraPath& camera_path_;
    BakeSettings settings_;
    DepositLevels levels_;  ///< each path vertex's voxel, from the grid and the view region
    SharcCache cache_;
    /// One wavefront (and its batch memory) per thread, kept between iterations.
    mutable tbb::enumerable_thread_specific<UpdateWavefront> wavefronts_;
    uint32_t blocks_x_, blocks_y_;
    uint32_t iteration_ = 0;
    std::vector<std::vector<Deposit>> chunk_deposits_;  ///< one list per fixed chunk of paths
    UpdateCounters counters_;
    StageSeconds seconds_;
};

/// The deposit levels of a bake of `scene` with `settings` (grid and view region).
DepositLevels levelsFor(const Scene& scene, const BakeSettings& settings);
/// `sharc` with the coarsest level its written cache covers (SharcSettings::coarsest_level).
SharcSettings withCoverage(SharcSettings sharc, const DepositLevels& levels);

/// The brightest radiance the scene can put into a voxel, for the fixed-point scale: emission of
/// the materials its triangles use, sky, and for each point or spot light the radiance a white
/// surface facing it would have at an eighth of the distance to the nearest surface 64 rays from it hit (a surface the rays pass
/// between, nearer still, fits the scale's 2^22 headroom). That distance is never taken below
/// 1e-4 of the scene's diagonal (a light touching a surface would otherwise put every other
/// deposit below one step), and where the rays hit nothing it is the distance to the scene's
/// bounds. The light's own scene units decide, so a lamp kilometres from the surfaces of a scene
/// in millimetres does not put the scale where a lamp 1 cm from a wall would.
double estimateMaxRadiance(const Tracer& tracer);

}  // namespace sharcbake
