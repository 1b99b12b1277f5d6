// SPDX-License-Identifier: Apache-2.0
#include "sharc/capacity.h"

#include "support/stopwatch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

namespace sharcbake {

std::string CapacityChoice::describe() const {
    char text[256];
    std::snprintf(text, sizeof text,
                  "auto: %u slots to start (%llu voxels reached by %u sampled iterations, x%u, next power of "
                  "two), doubling whenever a quarter is occupied",
                  capacity, (unsigned long long)sampled_voxels, sampled_iterations, kCapacityHeadroom);
    return text;
}

CapacityChoice chooseCapacity(const Tracer& tracer, const LightSampler& lights, const CameraPath& camera_path,
                              BakeSettings settings) {
    const auto start = std::chrono::steady_clock::now();
    // A table of the smallest size: the pre-pass never commits, it only needs an (empty) cache
    // for the paths to look up.
    settings.sharc.grid.capacity = kHashGridBucketSize;
    const Baker sampler(tracer, lights, camera_path, settings, 1.0);

    CapacityChoice choice;
    choice.sampled_iterations = kCapacitySampleIterations;
    // One loop of the camera path, never the bake's --iterations: a resumed bake must choose
    // what the uninterrupted one chose. A shard's iterations k*N+i visit, over one loop, every
    // pose that shard ever visits.
    const uint32_t iterations = std::max(camera_path.period(), kCapacitySampleIterations);
    std::vector<uint64_t> keys;
    std::vector<std::vector<Deposit>> chunks;
    UpdateCounters counters;
    for (uint32_t k = 0; k < choice.sampled_iterations; ++k) {
        // Spread over the loop by the golden-ratio sequence: an even stride would alias with the
        // waypoints (16 samples of 256 iterations on a 64-waypoint loop would visit 4 of
        // them), this visits different parts of the path at every step.
        const double position = std::fmod(0.5 + double(k) * 0.6180339887498949, 1.0);
        const uint32_t iteration = std::min(iterations - 1, uint32_t(position * double(iterations)));
        sampler.traceUpdatePaths(sampler.workIteration(iteration), chunks, counters);
        for (const std::vector<Deposit>& chunk : chunks) {
            for (const Deposit& d : chunk) keys.push_back(d.key);
        }
        std::sort(keys.begin(), keys.end());
        keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    }
    // The coarser voxels every deposited voxel feeds live in the table too (view_region.h).
    const uint32_t coarsest = sampler.depositLevels().coarsestLevel();
    std::vector<uint64_t> level = keys;
    const HashGridKeyDecoder decoder(settings.sharc.grid, settings.sharc.grid_anchor);
    while (!level.empty()) {
        std::vector<uint64_t> coarser;
        for (const uint64_t key : level) {
            if (decodeHashGridKey(key).level < coarsest) coarser.push_back(decoder.coarserKey(key));
        }
        std::sort(coarser.begin(), coarser.end());
        coarser.erase(std::unique(coarser.begin(), coarser.end()), coarser.end());
        keys.insert(keys.end(), coarser.begin(), coarser.end());
        level = std::move(coarser);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    choice.sampled_voxels = keys.size();
    uint64_t capacity = kCapacityMinimum;
    while (capacity < choice.sampled_voxels * kCapacityHeadroom && capacity < kMaxCacheCapacity) capacity *= 2;
    choice.capacity = uint32_t(capacity);
    choice.seconds = secondsSince(start);
    return choice;
}

}  // namespace sharcbake
