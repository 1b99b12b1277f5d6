// SPDX-License-Identifier: Apache-2.0
#include "bench_support.h"

#include "support/fnv1a.h"
#include "support/stopwatch.h"
#include "tracing/render.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <random>
#include <stdexcept>

#include <sys/resource.h>

namespace sharcbake::bench {
namespace {

/// Appends the quad a, b, c, d (two triangles, winding a -> b -> c).
void addQuad(Scene& scene, glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t material) {
    const uint32_t base = uint32_t(scene.positions.size());
    scene.positions.insert(scene.positions.end(), {a, b, c, d});
    scene.triangles.push_back({base, base + 1, base + 2});
    scene.triangles.push_back({base, base + 2, base + 3});
    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
}

CameraPath exploredCameraPath(const Tracer& tracer, const Scene& scene, uint32_t points, uint32_t seed) {
    std::optional<CameraPath> path = exploringCameraPath(tracer, scene, points, seed);
    if (!path) throw std::runtime_error("benchmark scene: no free space for the camera");
    return std::move(*path);
}

template <int N, typename RayHitN, typename RayN, typename Intersect, typename Occluded>
uint64_t tracePackets(RTCScene scene, const RayPair* pairs, size_t count, Intersect intersect, Occluded occluded) {
    uint64_t checksum = 0;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    alignas(64) int valid[N];
    alignas(64) RayHitN rayhit;
    alignas(64) RayN shadow;
    for (size_t start = 0; start < count; start += N) {
        const int n = int(std::min<size_t>(N, count - start));
        for (int i = 0; i < N; ++i) {
            valid[i] = i < n ? -1 : 0;
            const RayPair& pair = pairs[start + size_t(i < n ? i : 0)];
            initEmbreeLane(pair.closest, rayhit.ray, i);
            rayhit.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            rayhit.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
            initEmbreeLane(pair.shadow, shadow, i);
        }
        intersect(valid, scene, &context, &rayhit);
        occluded(valid, scene, &context, &shadow);
        for (int i = 0; i < n; ++i) {
            checksum += rayhit.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
            checksum += shadow.tfar[i] < 0.0f;
        }
    }
    return checksum;
}

}  // namespace

Scene makeRoomScene(uint32_t triangles) {
    Scene scene;
    scene.source_path = "generated room, " + std::to_string(triangles) + " triangles";
    Material wall;
    wall.name = "grey diffuse";
    wall.base_color = glm::vec3(0.6f);
    wall.metallic = 0.0f;
    wall.roughness = 1.0f;
    wall.double_sided = true;
    Material light;
    light.name = "ceiling panel";
    light.base_color = glm::vec3(0.0f);
    light.metallic = 0.0f;
    light.emissive = glm::vec3(1.0f);
    light.emissive_strength = 20.0f;
    scene.materials = {wall, light};

    const float half = 4.0f, height = 3.0f;
    // Walls and ceiling (the floor is the tessellated surface below).
    addQuad(scene, {-half, 0, -half}, {-half, height, -half}, {half, height, -half}, {half, 0, -half}, 0);
    addQuad(scene, {-half, 0, half}, {half, 0, half}, {half, height, half}, {-half, height, half}, 0);
    addQuad(scene, {-half, 0, -half}, {-half, 0, half}, {-half, height, half}, {-half, height, -half}, 0);
    addQuad(scene, {half, 0, -half}, {half, height, -half}, {half, height, half}, {half, 0, half}, 0);
    addQuad(scene, {-half, height, -half}, {-half, height, half}, {half, height, half}, {half, height, -half}, 0);
    // The light faces down, 1 cm below the ceiling.
    const float y = height - 0.01f;
    addQuad(scene, {-0.75f, y, -0.75f}, {0.75f, y, -0.75f}, {0.75f, y, 0.75f}, {-0.75f, y, 0.75f}, 1);

    // Floor: an n x n grid of quads over a gentle wave, facing up.
    const uint32_t remaining = triangles > 12 ? triangles - 12 : 2;
    const uint32_t n = std::max(1u, uint32_t(std::ceil(std::sqrt(double(remaining) / 2.0))));
    const uint32_t base = uint32_t(scene.positions.size());
    for (uint32_t j = 0; j <= n; ++j) {
        for (uint32_t i = 0; i <= n; ++i) {
            const float x = -half + 2.0f * half * float(i) / float(n);
            const float z = -half + 2.0f * half * float(j) / float(n);
            scene.positions.push_back({x, 0.1f + 0.08f * std::sin(3.0f * x) * std::cos(2.0f * z), z});
        }
    }
    for (uint32_t j = 0; j < n; ++j) {
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t v00 = base + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
            scene.triangles.push_back({v00, v01, v10});
            scene.triangles.push_back({v10, v01, v11});
            scene.triangle_materials.insert(scene.triangle_materials.end(), 2, 0u);
        }
    }
    scene.bounds_min = glm::vec3(-half, 0.0f, -half);
    scene.bounds_max = glm::vec3(half, height, half);
    Camera camera;
    camera.name = "camera";
    camera.position = {0.0f, 1.5f, 3.0f};
    scene.cameras.push_back(camera);
    return scene;
}

std::vector<RayPair> makeRayPairs(const Tracer& tracer, const LightSampler& lights, const CameraPath& path,
                                  size_t count, uint32_t seed) {
    std::vector<RayPair> pairs;
    pairs.reserve(count);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform(0.0f, kOneMinusEpsilon);
    const int width = 320, height = 180;
    for (uint32_t attempt = 0; pairs.size() < count; ++attempt) {
        if (attempt > 64 * count + 1024) throw std::runtime_error("benchmark rays: the scene yields no shadow rays");
        const CameraPose pose = path.poseAt(attempt % 1024);
        const CameraRays rays(toCamera(pose), width, height);
        Ray ray = rays.generate(int(uniform(rng) * width), int(uniform(rng) * height), {uniform(rng), uniform(rng)});
        for (int vertex = 0; vertex < 4 && pairs.size() < count; ++vertex) {
            RayHit ray_hit;
            if (!tracer.intersect(ray, ray_hit)) break;
            const SurfaceHit hit = makeSurfaceHit(tracer.scene(), ray_hit, ray.direction);
            const glm::vec3 origin = offsetRayOrigin(hit.position, hit.geometric_normal, hit.ray_offset);
            LightSample light;
            if (lights.sample(hit, uniform(rng), {uniform(rng), uniform(rng)}, light) &&
                glm::dot(light.wi, hit.geometric_normal) > 0.0f) {
                Ray shadow{origin, light.wi};
                if (std::isfinite(light.distance)) shadow.t_max = light.distance * (1.0f - 1e-4f);
                pairs.push_back(RayPair{ray, shadow});
            }
            const Frame frame(hit.geometric_normal);
            ray = Ray{origin, glm::normalize(frame.toWorld(sampleCosineHemisphere({uniform(rng), uniform(rng)})))};
        }
    }
    return pairs;
}

const char* toString(RayApi api) {
    switch (api) {
        case RayApi::Single: return "single";
        case RayApi::Stream: return "stream";
        case RayApi::Packet8: return "packet8";
        case RayApi::Packet16: return "packet16";
    }
    return "?";
}

uint64_t tracePairs(const Tracer& tracer, const RayPair* pairs, size_t count, RayApi api) {
    const RTCScene scene = tracer.embreeScene();
    uint64_t checksum = 0;
    switch (api) {
        case RayApi::Single: {
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            for (size_t i = 0; i < count; ++i) {
                RTCRayHit rayhit;
                initEmbreeRay(pairs[i].closest, rayhit.ray);
                rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                rtcIntersect1(scene, &context, &rayhit);
                RTCRay shadow;
                initEmbreeRay(pairs[i].shadow, shadow);
                rtcOccluded1(scene, &context, &shadow);
                checksum += (rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID) + (shadow.tfar < 0.0f);
            }
            return checksum;
        }
        case RayApi::Stream: {
            constexpr size_t kBlock = 64;
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            RTCRayHit rayhits[kBlock];
            RTCRay shadows[kBlock];
            for (size_t start = 0; start < count; start += kBlock) {
                const size_t n = std::min(kBlock, count - start);
                for (size_t i = 0; i < n; ++i) {
                    initEmbreeRay(pairs[start + i].closest, rayhits[i].ray);
                    rayhits[i].hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rayhits[i].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
                    initEmbreeRay(pairs[start + i].shadow, shadows[i]);
                }
                rtcIntersect1M(scene, &context, rayhits, unsigned(n), sizeof(RTCRayHit));
                rtcOccluded1M(scene, &context, shadows, unsigned(n), sizeof(RTCRay));
                for (size_t i = 0; i < n; ++i) {
                    checksum += (rayhits[i].hit.geomID != RTC_INVALID_GEOMETRY_ID) + (shadows[i].tfar < 0.0f);
                }
            }
            return checksum;
        }
        case RayApi::Packet8:
            return tracePackets<8, RTCRayHit8, RTCRay8>(scene, pairs, count, rtcIntersect8, rtcOccluded8);
        case RayApi::Packet16:
            return tracePackets<16, RTCRayHit16, RTCRay16>(scene, pairs, count, rtcIntersect16, rtcOccluded16);
    }
    return checksum;
}

double measurePairsPerSecond(const Tracer& tracer, const std::vector<RayPair>& pairs, RayApi api, int repetitions) {
    constexpr size_t kGrain = 1024;
    double best = 0.0;
    for (int rep = 0; rep < std::max(1, repetitions); ++rep) {
        std::atomic<uint64_t> checksum{0};
        const auto start = std::chrono::steady_clock::now();
        tbb::parallel_for(size_t(0), (pairs.size() + kGrain - 1) / kGrain, [&](size_t block) {
            const size_t first = block * kGrain;
            const size_t n = std::min(kGrain, pairs.size() - first);
            checksum.fetch_add(tracePairs(tracer, pairs.data() + first, n, api), std::memory_order_relaxed);
        });
        const double seconds = secondsSince(start);
        if (checksum.load() == 0) throw std::runtime_error("benchmark rays: nothing was hit");
        best = std::max(best, double(pairs.size()) / seconds);
    }
    return best;
}

BakeScene::BakeScene(Scene scene_in, TraceKernels kernels, uint32_t explore_points, uint32_t seed)
    : scene(std::move(scene_in)),
      tracer(scene, kernels),
      lights(tracer),
      camera_path(exploredCameraPath(tracer, scene, explore_points, seed)) {}

BakeSettings benchBakeSettings(int width, int height, uint32_t capacity) {
    BakeSettings settings;
    settings.width = width;
    settings.height = height;
    settings.sharc.grid.capacity = capacity;
    settings.sharc.grid.capacity = capacity;
    return settings;
}

BakeRun runBake(const BakeScene& s, const BakeSettings& settings, uint32_t iterations, uint32_t warmup) {
    BakeRun run;
    const auto setup_start = std::chrono::steady_clock::now();
    Baker baker(s.tracer, s.lights, s.camera_path, settings,
                SharcCache::chooseRadianceScale(estimateMaxRadiance(s.tracer)));
    run.setup_seconds = secondsSince(setup_start);
    for (uint32_t i = 0; i < warmup; ++i) baker.runIteration();
    const UpdateCounters before = baker.counters();
    const uint64_t deposits_before = baker.cache().numerics().deposits;
    const StageSeconds seconds_before = baker.seconds();
    const CacheStageSeconds stages_before = baker.cache().stageSeconds();
    rusage usage_before{};
    getrusage(RUSAGE_SELF, &usage_before);
    const auto start = std::chrono::steady_clock::now();
    for (uint32_t i = 0; i < iterations; ++i) baker.runIteration();
    run.wall_seconds = secondsSince(start);
    rusage usage_after{};
    getrusage(RUSAGE_SELF, &usage_after);
    run.kernel_seconds = double(usage_after.ru_stime.tv_sec - usage_before.ru_stime.tv_sec) +
                         1e-6 * double(usage_after.ru_stime.tv_usec - usage_before.ru_stime.tv_usec);
    run.page_faults = uint64_t(usage_after.ru_minflt - usage_before.ru_minflt);
    run.iterations = iterations;
    run.update_seconds = baker.seconds().update - seconds_before.update;
    run.commit_seconds = baker.seconds().commit - seconds_before.commit;
    run.resolve_seconds = baker.seconds().resolve - seconds_before.resolve;
    const CacheStageSeconds& stages = baker.cache().stageSeconds();
    run.cache_stages.look_up = stages.look_up - stages_before.look_up;
    run.cache_stages.insert = stages.insert - stages_before.insert;
    run.cache_stages.accumulate = stages.accumulate - stages_before.accumulate;
    run.cache_stages.coarser_levels = stages.coarser_levels - stages_before.coarser_levels;
    run.cache_stages.resolve = stages.resolve - stages_before.resolve;
    run.paths = baker.counters().paths - before.paths;
    run.segments = baker.counters().segments - before.segments;
    run.shadow_rays = baker.counters().shadow_rays - before.shadow_rays;
    run.deposits = baker.cache().numerics().deposits - deposits_before;
    const CacheData data = toCacheData(baker.cache());
    std::vector<uint8_t> bytes;
    std::string message;
    if (encodeCacheFile(data, &bytes, &message) != CacheFileStatus::kOk) throw std::runtime_error(message);
    run.live_voxels = data.voxels.size();
    run.file_bytes = bytes.size();
    run.file_digest = fnv1a64(bytes.data(), bytes.size());
    return run;
}

uint64_t peakResidentBytes() {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind("VmHWM:", 0) == 0) return uint64_t(std::stoull(line.substr(6))) * 1024u;
    }
    return 0;
}

std::string cacheStagesJson(const CacheStageSeconds& stages) {
    char text[256];
    std::snprintf(text, sizeof text,
                  "\"cache_stages\": {\"look_up\": %.4f, \"insert\": %.4f, \"accumulate\": %.4f, "
                  "\"coarser_levels\": %.4f, \"resolve\": %.4f}",
                  stages.look_up, stages.insert, stages.accumulate, stages.coarser_levels, stages.resolve);
    return text;
}

}  // namespace sharcbake::bench
