// SPDX-License-Identifier: Apache-2.0
// Whole-bake benchmark: the bake's path segments per second against the raw Embree ray limit
// (closest-hit + shadow ray pairs per second) on the same scene, with the same threads, in the
// same run; thread scaling; bake cost as the scene and the capacity grow; peak memory per
// capacity entry and file bytes per live voxel. One JSON object per line on stdout.
// BENCHMARKS.md lists the commands and the figures they produced.
#include "bench_support.h"

#include "sharcbake/scene_loader.h"
#include "support/fnv1a.h"
#include "support/worker_threads.h"
#include "tracing/path_tracer.h"
#include "tracing/render.h"

#include <tbb/global_control.h>
#include <tbb/info.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

using namespace sharcbake;
using namespace sharcbake::bench;

namespace {

struct Options {
    std::string scene_path;         ///< glTF scene; empty = generated room
    uint32_t triangles = 20000;     ///< generated room's size when no scene is given
    std::string resolution = "1280x720";
    uint32_t iterations = 16;
    uint32_t warmup = 2;  ///< untimed iterations before the timed ones
    uint32_t capacity = 1u << 22;
    uint32_t pairs = 1u << 19;
    int repetitions = 3;
    unsigned threads = 0;           ///< 0 = all cores
    std::vector<unsigned> thread_list{1, 2, 4, 8, 16};
    std::vector<uint32_t> triangle_list{1000, 10000, 100000, 1000000};
    std::vector<uint32_t> capacity_list{1u << 16, 1u << 18, 1u << 20, 1u << 22, 1u << 24};
    uint32_t spp = 16;  ///< render: samples per pixel
    std::string trace_kernels = "avx2";  ///< as the baker's --trace-kernels
};

void parseResolution(const std::string& text, int& width, int& height) {
    char x = 0;
    std::istringstream in(text);
    if (!(in >> width >> x >> height) || x != 'x' || width <= 0 || height <= 0) {
        throw CLI::ValidationError("--resolution", "expected WxH, got " + text);
    }
}

std::unique_ptr<BakeScene> loadBakeScene(const Options& o, uint32_t triangles) {
    if (!o.scene_path.empty())
        return std::make_unique<BakeScene>(loadGltf(o.scene_path), traceKernelsNamed(o.trace_kernels));
    return std::make_unique<BakeScene>(makeRoomScene(triangles), traceKernelsNamed(o.trace_kernels));
}

std::string sceneName(const Options& o, const BakeScene& s) {
    return o.scene_path.empty() ? "room" + std::to_string(s.scene.triangles.size()) : o.scene_path;
}

/// The ray limit (every API, best taken), the bake, then the best API again: the limit is the
/// better of the two passes around the bake, so a noisy neighbour cannot flatter the ratio.
void measureLimitAndBake(const Options& o, const BakeScene& s, const char* series, unsigned threads,
                         uint32_t capacity) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    const std::vector<RayPair> pairs = makeRayPairs(s.tracer, s.lights, s.camera_path, o.pairs, 11);
    std::string per_api;
    double best = 0.0;
    RayApi best_api = RayApi::Single;
    for (RayApi api : kAllRayApis) {
        const double rate = measurePairsPerSecond(s.tracer, pairs, api, o.repetitions);
        char text[64];
        std::snprintf(text, sizeof text, "%s\"%s\": %.4g", per_api.empty() ? "" : ", ", toString(api), rate);
        per_api += text;
        if (rate > best) {
            best = rate;
            best_api = api;
        }
    }
    int width = 0, height = 0;
    parseResolution(o.resolution, width, height);
    // Exactly `threads` workers for the bake, as `sharcbake bake --threads` runs it.
    BakeRun bake;
    runOnWorkerThreads(int(threads),
                       [&] { bake = runBake(s, benchBakeSettings(width, height, capacity), o.iterations, o.warmup); });
    const double after = measurePairsPerSecond(s.tracer, pairs, best_api, o.repetitions);
    const double ray_limit = std::max(best, after);
    const double rate = bake.segmentsPerSecond();
    std::printf(
        "{\"series\": \"%s\", \"scene\": \"%s\", \"triangles\": %zu, \"threads\": %u, \"trace_kernels\": \"%s\", "
        "\"capacity\": %u, \"ray_pairs_per_second\": {%s, \"%s_after_bake\": %.4g}, \"ray_limit\": %.4g, "
        "\"ray_limit_api\": \"%s\", "
        "\"bake_segments_per_second\": %.4g, \"ratio\": %.3f, \"iterations\": %u, \"warmup\": %u, \"paths\": %llu, "
        "\"segments\": %llu, \"shadow_rays\": %llu, \"seconds\": {\"update\": %.4f, \"commit\": %.4f, "
        "\"resolve\": %.4f, \"other\": %.4f, \"bake\": %.4f, \"setup\": %.4f, \"kernel\": %.4f}, "
        "\"page_faults\": %llu, \"live_voxels\": %llu, "
        "\"file_bytes\": %llu, \"file_bytes_per_live_voxel\": %.2f, \"file_fnv1a\": \"%016llx\", "
        "\"bytes_per_path_in_flight\": %zu, \"deposits_per_path\": %.2f, %s}\n",
        series, sceneName(o, s).c_str(), s.scene.triangles.size(), threads, traceKernelsName(s.tracer.kernels()),
        capacity, per_api.c_str(), toString(best_api), after, ray_limit, toString(best_api), rate, rate / ray_limit,
        bake.iterations, o.warmup, (unsigned long long)bake.paths, (unsigned long long)bake.segments,
        (unsigned long long)bake.shadow_rays, bake.update_seconds, bake.commit_seconds, bake.resolve_seconds,
        bake.wall_seconds - bake.bakeSeconds(), bake.wall_seconds, bake.setup_seconds, bake.kernel_seconds,
        (unsigned long long)bake.page_faults, (unsigned long long)bake.live_voxels, (unsigned long long)bake.file_bytes,
        bake.live_voxels ? double(bake.file_bytes) / double(bake.live_voxels) : 0.0,
        (unsigned long long)bake.file_digest, UpdateWavefront::bytesPerPathInFlight(),
        bake.paths ? double(bake.deposits) / double(bake.paths) : 0.0, cacheStagesJson(bake.cache_stages).c_str());
    std::fflush(stdout);
}

/// Plain path tracing (`sharcbake render` without a cache: reference images, the error reports'
/// references) through the scene's first camera, else render's automatic one: closest-hit and
/// shadow rays per second, and a digest of the image, equal for every thread count.
void measureRender(const Options& o, const BakeScene& s, unsigned threads) {
    int width = 0, height = 0;
    parseResolution(o.resolution, width, height);
    const Camera camera = s.scene.cameras.empty() ? automaticCamera(s.scene, glm::radians(kAutomaticCameraFovDegrees))
                                                  : s.scene.cameras.front();
    const PathTracer path_tracer(s.tracer, s.lights, PathTracerSettings{});
    TraceCounters counters;
    Image image;
    const auto start = std::chrono::steady_clock::now();
    runOnWorkerThreads(int(threads), [&] {
        image = renderImage(
            CameraRays(camera, width, height), ImageRenderSettings{width, height, o.spp, 1},
            [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, counters); },
            nullptr);
    });
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const TraceCounts counts = counters.total();
    static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "the pixels are packed floats");
    const uint64_t digest = fnv1a64(image.pixels.data(), image.pixels.size() * sizeof(glm::vec3));
    std::printf(
        "{\"series\": \"render\", \"scene\": \"%s\", \"threads\": %u, \"resolution\": \"%dx%d\", "
        "\"spp\": %u, \"seconds\": %.4f, \"closest_hit_rays\": %llu, \"shadow_rays\": %llu, "
        "\"rays_per_second\": %.4g, \"image_fnv1a\": \"%016llx\"}\n",
        sceneName(o, s).c_str(), threads, width, height, o.spp, seconds, (unsigned long long)counts.closest_hit_rays,
        (unsigned long long)counts.shadow_rays, double(counts.closest_hit_rays + counts.shadow_rays) / seconds,
        (unsigned long long)digest);
    std::fflush(stdout);
}

/// One bake in this process, for the capacity series: its peak memory is this process's.
void measureOneBake(const Options& o) {
    const uint64_t before = peakResidentBytes();
    const std::unique_ptr<BakeScene> s = loadBakeScene(o, o.triangles);
    const uint64_t scene_peak = peakResidentBytes();
    int width = 0, height = 0;
    parseResolution(o.resolution, width, height);
    BakeRun bake;
    runOnWorkerThreads(o.threads ? int(o.threads) : tbb::info::default_concurrency(), [&] {
        bake = runBake(*s, benchBakeSettings(width, height, o.capacity), o.iterations, o.warmup);
    });
    const uint64_t peak = peakResidentBytes();
    std::printf("{\"series\": \"capacity\", \"scene\": \"%s\", \"capacity\": %u, \"iterations\": %u, "
                "\"bake_segments_per_second\": %.4g, \"seconds\": {\"update\": %.4f, \"commit\": %.4f, "
                "\"resolve\": %.4f, \"bake\": %.4f, \"setup\": %.4f}, \"seconds_per_iteration\": %.4f, "
                "\"peak_rss_bytes\": %llu, \"peak_rss_before_bake_bytes\": %llu, \"peak_rss_at_start_bytes\": %llu, "
                "\"live_voxels\": %llu, \"file_bytes_per_live_voxel\": %.2f, %s}\n",
                sceneName(o, *s).c_str(), o.capacity, bake.iterations, bake.segmentsPerSecond(),
                bake.update_seconds, bake.commit_seconds, bake.resolve_seconds, bake.wall_seconds, bake.setup_seconds,
                bake.wall_seconds / bake.iterations, (unsigned long long)peak, (unsigned long long)scene_peak,
                (unsigned long long)before, (unsigned long long)bake.live_voxels,
                bake.live_voxels ? double(bake.file_bytes) / double(bake.live_voxels) : 0.0,
                cacheStagesJson(bake.cache_stages).c_str());
    std::fflush(stdout);
}

/// Runs `one-bake` in a fresh process per capacity, so each peak-memory figure is its own.
int runCapacitySeries(const Options& o, const std::string& self) {
    for (uint32_t capacity : o.capacity_list) {
        std::string command = "'" + self + "' one-bake --capacity " + std::to_string(capacity) + " --iterations " +
                              std::to_string(o.iterations) + " --warmup " + std::to_string(o.warmup) +
                              " --resolution " + o.resolution + " --threads " + std::to_string(o.threads) +
                              " --trace-kernels " + o.trace_kernels;
        command += o.scene_path.empty() ? " --triangles " + std::to_string(o.triangles) : " --scene '" + o.scene_path + "'";
        std::fflush(stdout);
        if (std::system(command.c_str()) != 0) {
            std::fprintf(stderr, "bake_bench: %s failed\n", command.c_str());
            return 1;
        }
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Whole-bake benchmark: bake throughput against the raw Embree ray limit, thread scaling, scene size\n"
        "and capacity series. Prints one JSON object per measurement.\n\n"
        "Examples:\n"
        "  bake_bench limit --scene scenes/cornell_box/cornell_box.gltf\n"
        "  bake_bench scaling --threads-list 1,2,4,8,16\n"
        "  bake_bench scene-size --triangles-list 1000,10000,100000,1000000\n"
        "  bake_bench capacity --capacity-list 65536,1048576,16777216\n"
        "  bake_bench render --scene scenes/cornell_box/cornell_box.gltf --threads-list 1,16 --resolution 160x160"};
    app.require_subcommand(1);
    Options o;
    auto common = [&o](CLI::App* cmd) {
        cmd->add_option("--scene", o.scene_path, "glTF scene (default: a generated room)");
        cmd->add_option("--triangles", o.triangles, "Triangles of the generated room")->capture_default_str();
        cmd->add_option("--resolution", o.resolution, "Virtual camera size WxH (one path per 5x5 block)")
            ->capture_default_str();
        cmd->add_option("--iterations", o.iterations, "Timed bake iterations (after --warmup untimed ones)")
            ->capture_default_str();
        cmd->add_option("--warmup", o.warmup,
                        "Untimed iterations first. New voxels keep arriving early in a bake, and their pages' "
                        "first touches (page faults) fall into the timed ones; a long warm-up measures the steady "
                        "state of a long bake instead")
            ->capture_default_str();
        cmd->add_option("--capacity", o.capacity, "Cache capacity (slots)")->capture_default_str();
        cmd->add_option("--pairs", o.pairs, "Ray pairs in the ray-limit pool")->capture_default_str();
        cmd->add_option("--repetitions", o.repetitions, "Ray-limit passes; the best counts")->capture_default_str();
        cmd->add_option("--threads", o.threads, "Worker threads (0 = all cores)")->capture_default_str();
        cmd->add_option("--trace-kernels", o.trace_kernels, "Embree's kernels, as the baker's --trace-kernels")
            ->capture_default_str()
            ->check(CLI::IsMember(traceKernelsNames()));
    };
    CLI::App* limit = app.add_subcommand("limit", "Ray limit and bake throughput at one thread count");
    common(limit);
    CLI::App* scaling = app.add_subcommand("scaling", "Ray limit and bake throughput per thread count");
    common(scaling);
    scaling->add_option("--threads-list", o.thread_list, "Thread counts")->delimiter(',');
    CLI::App* scene_size = app.add_subcommand("scene-size", "Ray limit and bake throughput as the room grows");
    common(scene_size);
    scene_size->add_option("--triangles-list", o.triangle_list, "Room sizes (triangles)")->delimiter(',');
    CLI::App* capacity = app.add_subcommand("capacity", "Bake cost and peak memory per capacity (one process each)");
    common(capacity);
    capacity->add_option("--capacity-list", o.capacity_list, "Capacities (slots)")->delimiter(',');
    CLI::App* one_bake = app.add_subcommand("one-bake", "One bake with its peak memory (used by `capacity`)");
    common(one_bake);
    CLI::App* render = app.add_subcommand("render", "Plain path tracing (a reference render) per thread count");
    common(render);
    render->add_option("--threads-list", o.thread_list, "Thread counts")->delimiter(',');
    render->add_option("--spp", o.spp, "Samples per pixel")->capture_default_str();
    CLI11_PARSE(app, argc, argv);

    try {
        const unsigned all = unsigned(tbb::info::default_concurrency());
        const unsigned threads = o.threads ? o.threads : all;
        if (limit->parsed()) {
            const std::unique_ptr<BakeScene> s = loadBakeScene(o, o.triangles);
            measureLimitAndBake(o, *s, "limit", threads, o.capacity);
        } else if (scaling->parsed()) {
            const std::unique_ptr<BakeScene> s = loadBakeScene(o, o.triangles);
            for (unsigned t : o.thread_list) {
                if (t > all) {
                    std::printf("{\"series\": \"scaling\", \"threads\": %u, \"skipped\": \"only %u hardware threads\"}\n", t, all);
                    continue;
                }
                measureLimitAndBake(o, *s, "scaling", t, o.capacity);
            }
        } else if (scene_size->parsed()) {
            for (uint32_t triangles : o.triangle_list) {
                const BakeScene s(makeRoomScene(triangles), traceKernelsNamed(o.trace_kernels));
                measureLimitAndBake(o, s, "scene-size", threads, o.capacity);
            }
        } else if (capacity->parsed()) {
            return runCapacitySeries(o, std::filesystem::read_symlink("/proc/self/exe").string());
        } else if (one_bake->parsed()) {
            measureOneBake(o);
        } else if (render->parsed()) {
            const std::unique_ptr<BakeScene> s = loadBakeScene(o, o.triangles);
            for (unsigned t : o.thread_list) {
                if (t <= all) measureRender(o, *s, t);
            }
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bake_bench: %s\n", e.what());
        return 2;
    }
    return 0;
}
