// SPDX-License-Identifier: Apache-2.0
/// @file bench_support.h
/// @brief What the benchmarks share: generated scenes of any size, the bake's rays as
/// closest-hit + shadow pairs, the raw Embree ray limit over them (single rays, streams and
/// packets), one measured bake, and a synthetic .sharc cache for the runtime benchmarks.
#pragma once

#include "sharc/baker.h"
#include "sharc/camera_path.h"
#include "tracing/lights.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/scene.h"
#include "tracing/tracer.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake::bench {

/// A closed 8 x 3 x 8 m room lit by an emissive ceiling panel, with a wavy tessellated floor
/// that holds almost all of the `triangles` triangles (at least the room's 14). Grey diffuse
/// walls, one glTF camera inside. The same count gives the same scene.
Scene makeRoomScene(uint32_t triangles);

/// One closest-hit ray and the shadow ray cast from its hit point towards a light sample.
struct RayPair {
    Ray closest;
    Ray shadow;
};

/// The rays a bake traces, as pairs: random-walk paths (cosine bounces, up to 4 vertices) from
/// the camera path's poses, each vertex contributing the ray that reached it and its
/// next-event shadow ray. Deterministic for a seed.
std::vector<RayPair> makeRayPairs(const Tracer& tracer, const LightSampler& lights, const CameraPath& path,
                                  size_t count, uint32_t seed);

/// How the pairs are handed to Embree.
enum class RayApi {
    Single,    ///< rtcIntersect1 + rtcOccluded1, as the baker does today
    Stream,    ///< rtcIntersect1M / rtcOccluded1M over blocks of 64 rays
    Packet8,   ///< rtcIntersect8 / rtcOccluded8
    Packet16,  ///< rtcIntersect16 / rtcOccluded16 (AVX-512 builds; emulated elsewhere)
};
const char* toString(RayApi api);
inline constexpr RayApi kAllRayApis[] = {RayApi::Single, RayApi::Stream, RayApi::Packet8, RayApi::Packet16};

/// Traces `count` pairs on the calling thread; returns how many closest-hit rays hit plus how
/// many shadow rays were blocked (a checksum that keeps the work from being optimised away).
uint64_t tracePairs(const Tracer& tracer, const RayPair* pairs, size_t count, RayApi api);

/// Pairs per second over all pairs, traced in parallel (TBB, the current thread limit):
/// the best of `repetitions` passes.
double measurePairsPerSecond(const Tracer& tracer, const std::vector<RayPair>& pairs, RayApi api,
                             int repetitions);

/// One bake's throughput and where its time went.
struct BakeRun {
    uint32_t iterations = 0;
    double update_seconds = 0.0, commit_seconds = 0.0, resolve_seconds = 0.0;
    double wall_seconds = 0.0;   ///< the timed iterations, end to end
    double setup_seconds = 0.0;  ///< cache allocation (Baker construction)
    double kernel_seconds = 0.0;  ///< the timed iterations' system CPU time, all threads (page faults)
    uint64_t page_faults = 0;     ///< minor page faults in the timed iterations (first touches)
    uint64_t paths = 0, segments = 0, shadow_rays = 0;
    uint64_t deposits = 0;  ///< deposits the update paths made (the commit's input)
    uint64_t live_voxels = 0;
    uint64_t file_bytes = 0;  ///< the .sharc file the bake would write
    uint64_t file_digest = 0;  ///< FNV-1a (64-bit) of that file: equal for every thread count
    CacheStageSeconds cache_stages;  ///< the commit's and the resolve's steps (timed iterations)

    double bakeSeconds() const { return update_seconds + commit_seconds + resolve_seconds; }
    double segmentsPerSecond() const { return double(segments) / wall_seconds; }
};

/// `"cache_stages": {...}`: a run's cache stage seconds as a JSON member.
std::string cacheStagesJson(const CacheStageSeconds& stages);

/// Everything a bake needs besides its settings, built once per scene.
struct BakeScene {
    explicit BakeScene(Scene scene_in, TraceKernels kernels = TraceKernels::kAvx2, uint32_t explore_points = 32,
                       uint32_t seed = 7);
    Scene scene;
    Tracer tracer;
    LightSampler lights;
    CameraPath camera_path;
};

/// The bake's default settings at a reduced virtual-camera resolution.
BakeSettings benchBakeSettings(int width, int height, uint32_t capacity);

/// Runs `iterations` bake iterations (after `warmup` untimed ones) and encodes the result.
BakeRun runBake(const BakeScene& scene, const BakeSettings& settings, uint32_t iterations, uint32_t warmup = 2);

/// Peak resident memory of this process so far (VmHWM), bytes; 0 where /proc is missing.
uint64_t peakResidentBytes();

}  // namespace sharcbake::bench
