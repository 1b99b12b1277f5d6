// SPDX-License-Identifier: Apache-2.0
// `sharcbake render`: the reference path tracer from a glTF or command-line camera, optionally
// ending paths on a baked SHaRC cache (--cache), or drawing a debug view of that cache.
#include "sharc/cache_query.h"
#include "cli/command_support.h"
#include "cli/commands.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "support/progress.h"
#include "tracing/render.h"
#include "support/stopwatch.h"
#include "tracing/surface.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/image.h"
#include "tracing/tracer.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <sstream>

namespace sharcbake {
namespace {

struct RenderOptions {
    std::string scene_path;
    std::string output_path;
    std::string camera;       // name or index
    std::string look_at;      // "ex,ey,ez,tx,ty,tz"
    std::string up = "0,1,0";
    float fov_degrees = 45.0f;
    std::string resolution;   // "W" or "WxH"
    uint32_t spp = 64;
    uint32_t max_bounces = 1024;
    uint32_t seed = 0;
    unsigned threads = 0;
    SkyOptions sky;
    GltfLoadLimits limits;
    float exposure = 0.0f;
    std::string tone_map = "aces";
    bool no_png = false;
    bool quiet = false;
    std::string stats_json;
    std::string cache_path;  // --cache
    std::string cache_lookup = "exact";  // --cache-lookup
    std::string debug_view;  // --debug-view (requires --cache)
};

/// "1-4, 7" for the levels {1, 2, 3, 4, 7}.
std::string describeLevels(const std::vector<uint32_t>& levels) {
    std::string text;
    for (size_t i = 0; i < levels.size();) {
        size_t j = i;
        while (j + 1 < levels.size() && levels[j + 1] == levels[j] + 1) ++j;
        text += (text.empty() ? "" : ", ") + std::to_string(levels[i]) + (j > i ? "-" + std::to_string(levels[j]) : "");
        i = j + 1;
    }
    return text.empty() ? "none" : text;
}

/// Opens and validates a .sharc file with the runtime library: kExitIo if it cannot be read,
/// kExitInvalidInput if it is not a valid cache.
CacheView openCacheForCommand(const std::string& path) {
    CacheView view;
    CacheError error;
    const CacheFileStatus status = CacheView::openFile(path, &view, &error);
    if (status == CacheFileStatus::kOk) return view;
    const std::string text = error.message.empty() ? path + ": " + toString(status) : error.message;
    throw CommandError(exitCodeFor(status), text);
}

/// Counts the cache lookups of the path being traced on this thread: PathTracer asks the cache
/// at every secondary hit, so the count is the number of bounces the path made before it ended
/// (on a cache hit, by Russian roulette, the bounce cap or escaping the scene).
thread_local uint32_t t_path_lookups = 0;

class CountingCache : public RadianceCache {
public:
    explicit CountingCache(const RadianceCache& inner) : inner_(inner) {}
    bool lookup(const CacheQuery& query, glm::vec3& radiance) const override {
        ++t_path_lookups;
        return inner_.lookup(query, radiance);
    }

private:
    const RadianceCache& inner_;
};

/// Blue -> cyan -> green -> yellow -> red for v in [0, 1].
glm::vec3 heatRamp(float v) {
    static const std::array<glm::vec3, 5> stops = {glm::vec3(0, 0, 1), glm::vec3(0, 1, 1), glm::vec3(0, 1, 0),
                                                   glm::vec3(1, 1, 0), glm::vec3(1, 0, 0)};
    const float x = std::clamp(std::isfinite(v) ? v : 0.0f, 0.0f, 1.0f) * float(stops.size() - 1);
    const size_t i = std::min(size_t(x), stops.size() - 2);
    return glm::mix(stops[i], stops[i + 1], x - float(i));
}

/// A fixed colour per level, cycling every 8 levels.
glm::vec3 levelColor(uint32_t level) {
    static const std::array<glm::vec3, 8> palette = {
        glm::vec3(0.90f, 0.10f, 0.10f), glm::vec3(0.10f, 0.70f, 0.10f), glm::vec3(0.15f, 0.30f, 0.95f),
        glm::vec3(0.95f, 0.85f, 0.10f), glm::vec3(0.80f, 0.20f, 0.80f), glm::vec3(0.10f, 0.80f, 0.85f),
        glm::vec3(0.95f, 0.55f, 0.10f), glm::vec3(0.60f, 0.60f, 0.60f)};
    return palette[level % palette.size()];
}

/// Per-bucket occupancy of the cache's keys re-inserted into a table of the bake's capacity.
/// The capacity and bucket size come from the file, so they are bounded first: each pixel scans
/// one bucket, and a crafted bucket size of 2^32 made an 8x8 image take 35 s.
class BucketOccupancy {
public:
    static constexpr uint32_t kMaxBucketSize = 1024;
    static constexpr uint32_t kMaxCapacity = 1u << 28;  // 2 GiB of keys

    explicit BucketOccupancy(const CacheView& cache) {
        capacity_ = cache.bakeCapacity() > 0 ? cache.bakeCapacity() : kHashGridDefaultCapacity;
        const uint32_t bucket_size = cache.gridParameters().bucket_size;
        bucket_size_ = bucket_size > 0 ? bucket_size : kHashGridBucketSize;
        if (bucket_size_ > kMaxBucketSize || capacity_ > kMaxCapacity) {
            throw CommandError(kExitInvalidInput,
                               "--debug-view occupancy: the cache's bucket size " + std::to_string(bucket_size_) +
                                   " or table capacity " + std::to_string(capacity_) + " is beyond what the view shows (" +
                                   std::to_string(kMaxBucketSize) + ", " + std::to_string(kMaxCapacity) + ")");
        }
        if (HashGridTable::create(capacity_, &table_, bucket_size_) != HashGridStatus::kOk) {
            throw CommandError(kExitInvalidInput, "the cache's table capacity or bucket size is invalid");
        }
        for (uint64_t i = 0; i < cache.voxelCount(); ++i) (void)table_.insert(cache.key(i));
    }
    /// Occupied slots / slots in the key's bucket, in [0, 1].
    float occupancy(uint64_t key) const {
        const uint32_t base = bucketBase(hashGridHash(key), capacity_, bucket_size_);
        const uint32_t count = bucketProbeCount(capacity_, bucket_size_);
        if (base == kHashGridInvalidIndex || count == 0) return 0.0f;
        uint32_t occupied = 0;
        for (uint32_t i = 0; i < count; ++i) occupied += table_.keyAt(base + i) != kHashGridInvalidKey ? 1u : 0u;
        return float(occupied) / float(count);
    }
    uint64_t failedInserts() const { return table_.failedInserts(); }

private:
    HashGridTable table_;
    uint32_t capacity_ = 0;
    uint32_t bucket_size_ = kHashGridBucketSize;
};

/// The camera the user asked for: --look-at, else --camera, else the scene's first camera,
/// else one that frames the scene's bounds from +Z.
Camera chooseCamera(const Scene& scene, const RenderOptions& o) {
    if (!o.look_at.empty()) {
        std::istringstream in(o.look_at);
        float v[6];
        char comma;
        for (int i = 0; i < 6; ++i) {
            if (!(in >> v[i]) || (i < 5 && !(in >> comma && comma == ','))) {
                throw CommandError(kExitUsage, "--look-at: expected \"ex,ey,ez,tx,ty,tz\", got \"" +
                                                   o.look_at + "\"");
            }
        }
        Camera c;
        c.name = "--look-at";
        c.position = {v[0], v[1], v[2]};
        const glm::vec3 target{v[3], v[4], v[5]};
        if (glm::length(target - c.position) <= 0.0f) {
            throw CommandError(kExitUsage, "--look-at: eye and target are the same point");
        }
        c.forward = glm::normalize(target - c.position);
        const glm::vec3 up = parseVec3(o.up, "--up");
        const glm::vec3 right = glm::cross(c.forward, up);
        if (glm::length(right) < 1e-6f) throw CommandError(kExitUsage, "--up is parallel to the view direction");
        c.up = glm::normalize(glm::cross(glm::normalize(right), c.forward));
        c.yfov = glm::radians(o.fov_degrees);
        return c;
    }
    return sceneCamera(scene, o.camera, "--camera", o.fov_degrees);
}

void parseResolution(const RenderOptions& o, const Camera& camera, int& width, int& height) {
    parseImageSize(o.resolution.empty() ? "512" : o.resolution, "--resolution", camera.aspect_ratio, width, height);
}

ToneMap parseToneMap(const std::string& name) {
    if (name == "aces") return ToneMap::Aces;
    if (name == "reinhard") return ToneMap::Reinhard;
    return ToneMap::Clamp;
}

void runRender(const RenderOptions& o) {
    // The PNG preview's name derives from the output's; it must name neither the EXR nor an input.
    const std::string png_path =
        o.no_png ? std::string() : std::filesystem::path(o.output_path).replace_extension(".png").string();
    const std::vector<std::string> inputs = {o.scene_path, o.cache_path, o.sky.exr_path};
    auto checkOutputs = [&](const std::vector<std::string>& more_inputs) {
        std::vector<std::string> others = inputs;
        others.insert(others.end(), more_inputs.begin(), more_inputs.end());
        checkOutputPath(o.output_path, "image", others);
        others.push_back(o.output_path);
        if (!png_path.empty()) {
            if (png_path == o.output_path) {
                throw CommandError(kExitUsage, o.output_path + ": the EXR output would be overwritten by its own "
                                                               ".png preview; name it .exr or pass --no-png");
            }
            checkOutputPath(png_path, "PNG preview", others);
            others.push_back(png_path);
        }
        if (!o.stats_json.empty()) checkOutputPath(o.stats_json, "stats JSON", others);
    };
    checkOutputs({});
    const auto start = std::chrono::steady_clock::now();
    const int threads = o.threads > 0 ? int(o.threads) : tbb::info::default_concurrency();
    tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, size_t(threads));

    const Scene scene = loadSceneForCommand(o.scene_path, o.sky, o.quiet, o.limits);
    checkOutputs(scene.source_files);  // the buffers and textures the scene read
    const Camera chosen = chooseCamera(scene, o);
    if (!o.quiet && chosen.name == "automatic") {
        std::printf("Camera: %s (the scene has no camera; --look-at or --camera choose another)\n",
                    describeCamera(chosen).c_str());
    }
    int width = 0, height = 0;
    parseResolution(o, chosen, width, height);
    const Camera camera = fitCameraToImage(chosen, width, height);
    warnAboutCameraFit(chosen, camera, width, height);

    const auto build_start = std::chrono::steady_clock::now();
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    const double build_seconds = secondsSince(build_start);
    if (!o.quiet && !lights.hasLights()) {
        std::fprintf(stderr, "warning: the scene has no lights, no emissive surfaces and a black sky: "
                             "the image will be black\n");
    }

    std::unique_ptr<BakedCache> cache;
    if (!o.cache_path.empty()) {
        cache = std::make_unique<BakedCache>(openCacheForCommand(o.cache_path), camera.position,
                                             o.cache_lookup == "nearest" ? CacheLookup::NearestLevel : CacheLookup::Exact);
    }
    std::unique_ptr<CountingCache> counting_cache;
    if (o.debug_view == "bounces") counting_cache = std::make_unique<CountingCache>(*cache);
    const RadianceCache* path_cache = counting_cache ? static_cast<const RadianceCache*>(counting_cache.get())
                                                     : static_cast<const RadianceCache*>(cache.get());

    PathTracerSettings path_settings;
    path_settings.max_bounces = o.max_bounces;
    const PathTracer path_tracer(tracer, lights, path_settings, path_cache);
    TraceCounters counters;
    ImageRenderSettings settings{width, height, o.spp, o.seed};
    const bool primary_view = !o.debug_view.empty() && o.debug_view != "bounces";
    std::unique_ptr<BucketOccupancy> occupancy;
    if (o.debug_view == "occupancy") occupancy = std::make_unique<BucketOccupancy>(cache->view());
    std::atomic<uint64_t> debug_hits{0}, debug_missing{0};

    // A debug view evaluated at the primary hit (0 where the ray leaves the scene).
    auto primaryView = [&](const Ray& ray) -> glm::vec3 {
        RayHit ray_hit;
        counters.closest_hit_rays.fetch_add(1, std::memory_order_relaxed);
        if (!tracer.intersect(ray, ray_hit)) return glm::vec3(0.0f);
        debug_hits.fetch_add(1, std::memory_order_relaxed);
        const SurfaceHit hit = makeSurfaceHit(scene, ray_hit, ray.direction);
        const uint64_t key = cache->key(hit.position, hit.geometric_normal);
        if (o.debug_view == "cache") {
            const std::optional<CacheVoxel> v = cache->find(key);
            if (!v) {
                debug_missing.fetch_add(1, std::memory_order_relaxed);
                return glm::vec3(0.0f);
            }
            return glm::vec3(v->radiance[0], v->radiance[1], v->radiance[2]);
        }
        if (o.debug_view == "hash") {
            const Float3 c = hashDebugColor(key);
            return glm::vec3(c.x, c.y, c.z);
        }
        if (o.debug_view == "levels") return levelColor(decodeHashGridKey(key).level);
        // occupancy: green (empty bucket) to red (full)
        return glm::mix(glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), occupancy->occupancy(key));
    };

    const auto render_start = std::chrono::steady_clock::now();
    Image image;
    {
        Progress progress(o.debug_view.empty() ? "Rendering" : "Debug view",
                          uint64_t(width) * uint64_t(height), !o.quiet && Progress::isTerminal());
        image = renderImage(CameraRays(camera, width, height), settings,
                            [&](const Ray& ray, PixelSampler& sampler) {
                                if (primary_view) return primaryView(ray);
                                if (counting_cache) {
                                    t_path_lookups = 0;
                                    (void)path_tracer.radiance(ray, sampler, counters);
                                    return glm::vec3(float(t_path_lookups));
                                }
                                return path_tracer.radiance(ray, sampler, counters);
                            },
                            &progress);
    }
    const double render_seconds = secondsSince(render_start);
    const uint64_t rays = counters.closest_hit_rays + counters.shadow_rays;
    if (cache) counters.cache_misses = cache->misses();
    const uint64_t eligible = counters.cache_hits + counters.cache_misses;
    const double hit_rate = eligible > 0 ? double(counters.cache_hits) / double(eligible) : 0.0;
    if (cache && !primary_view && eligible >= 100 && hit_rate < 0.9) {
        // Warned even with -q: the image is mostly plain path tracing, which the user did not ask for.
        std::fprintf(stderr,
                     "warning: the cache answered only %.1f%% of the lookups from this camera (levels %s of %s); the "
                     "rest were traced. It was baked for other views: bake with --view-region free (the default) "
                     "or a region holding this camera, and check the bake's \"predicted hit rate\"%s\n",
                     100.0 * hit_rate, describeLevels(cache->levels()).c_str(), o.cache_path.c_str(),
                     o.cache_lookup == "nearest" ? "" : "; --cache-lookup nearest falls back to the nearest level the file holds");
    }

    float max_bounces_seen = 0.0f;
    if (o.debug_view == "bounces") {
        for (const glm::vec3& p : image.pixels) max_bounces_seen = std::max(max_bounces_seen, p.x);
        for (glm::vec3& p : image.pixels) p = heatRamp(max_bounces_seen > 0.0f ? p.x / max_bounces_seen : 0.0f);
    }

    ImageMetadata metadata{
        {"sharcbake:software", "sharcbake " SHARCBAKE_VERSION},
        {"sharcbake:scene", o.scene_path},
        {"sharcbake:camera", camera.name},
        {"sharcbake:spp", std::to_string(o.spp)},
        {"sharcbake:seed", std::to_string(o.seed)},
        {"sharcbake:max_bounces", std::to_string(o.max_bounces)},
        {"sharcbake:integrator", cache ? "path tracer, NEE + MIS, paths end on SHaRC cache hits"
                                       : "path tracer, NEE + MIS"},
    };
    if (cache) {
        metadata["sharcbake:cache"] = o.cache_path;
        metadata["sharcbake:cache_voxels"] = std::to_string(cache->view().voxelCount());
        metadata["sharcbake:cache_hits"] = std::to_string(counters.cache_hits.load());
        metadata["sharcbake:cache_misses"] = std::to_string(counters.cache_misses.load());
        metadata["sharcbake:cache_refused"] = std::to_string(cache->refused());
        metadata["sharcbake:cache_lookup"] = o.cache_lookup;
        metadata["sharcbake:cache_nearest_level_hits"] = std::to_string(cache->nearestLevelHits());
    }
    if (!o.debug_view.empty()) {
        metadata["sharcbake:debug_view"] = o.debug_view;
        metadata["sharcbake:integrator"] =
            primary_view ? "debug view at the primary hit, LOD centre = render camera" : metadata["sharcbake:integrator"];
    }
    if (primary_view) {
        metadata["sharcbake:debug_primary_hits"] = std::to_string(debug_hits.load());
        if (o.debug_view == "cache") metadata["sharcbake:debug_missing"] = std::to_string(debug_missing.load());
        if (occupancy) metadata["sharcbake:debug_failed_inserts"] = std::to_string(occupancy->failedInserts());
    }
    if (o.debug_view == "bounces") metadata["sharcbake:debug_bounces_max"] = std::to_string(max_bounces_seen);
    try {
        writeExr(o.output_path, image, metadata);
        if (!o.no_png) {
            writePng(png_path, image, o.exposure, parseToneMap(o.tone_map));
        }
    } catch (const ImageError& e) {
        throw CommandError(kExitIo, e.what());
    }
    const double total_seconds = secondsSince(start);

    if (!o.quiet) {
        std::printf("Rendered %dx%d, %u spp, camera '%s' in %.2f s (BVH build %.2f s, %d threads)\n",
                    width, height, o.spp, camera.name.c_str(), render_seconds, build_seconds, threads);
        std::printf("  rays: %llu closest-hit + %llu shadow = %.3g rays/s\n",
                    (unsigned long long)counters.closest_hit_rays.load(),
                    (unsigned long long)counters.shadow_rays.load(), double(rays) / render_seconds);
        if (cache && !primary_view) {
            std::printf("  cache: %llu hits, %llu misses (hit rate %.1f%% of eligible lookups), %llu lookups "
                        "refused by the segment/cone tests; %.3f cache hits per path\n",
                        (unsigned long long)counters.cache_hits.load(), (unsigned long long)counters.cache_misses.load(),
                        100.0 * hit_rate, (unsigned long long)cache->refused(),
                        double(counters.cache_hits) / (double(width) * double(height) * double(o.spp)));
            if (cache->nearestLevelHits() > 0) {
                std::printf("  of the hits, %llu came from another level than the camera's (--cache-lookup nearest)\n",
                            (unsigned long long)cache->nearestLevelHits());
            }
        }
        if (o.debug_view == "cache") {
            std::printf("  debug view 'cache': %llu of %llu primary hits have no cached voxel (written as 0)\n",
                        (unsigned long long)debug_missing.load(), (unsigned long long)debug_hits.load());
        } else if (o.debug_view == "bounces") {
            std::printf("  debug view 'bounces': ramp blue (0) to red (%.2f bounces, the largest pixel mean)\n",
                        double(max_bounces_seen));
        }
        if (counters.non_finite_samples > 0) {
            std::printf("  dropped %llu non-finite path samples\n",
                        (unsigned long long)counters.non_finite_samples.load());
        }
        std::printf("Wrote %s%s\n", o.output_path.c_str(), o.no_png ? "" : " and its .png preview");
    }
    if (!o.stats_json.empty()) {
        std::ostringstream json;
        json << "{\n  \"width\": " << width << ",\n  \"height\": " << height
             << ",\n  \"samples_per_pixel\": " << o.spp << ",\n  \"threads\": " << threads
             << ",\n  \"seconds\": {\"total\": " << total_seconds << ", \"bvh_build\": " << build_seconds
             << ", \"render\": " << render_seconds << "},\n  \"closest_hit_rays\": "
             << counters.closest_hit_rays << ",\n  \"shadow_rays\": " << counters.shadow_rays
             << ",\n  \"rays_per_second\": " << double(rays) / render_seconds
             << ",\n  \"non_finite_samples\": " << counters.non_finite_samples;
        if (cache) {
            json << ",\n  \"cache_hits\": " << counters.cache_hits << ",\n  \"cache_misses\": " << counters.cache_misses
                 << ",\n  \"cache_refused\": " << cache->refused() << ",\n  \"cache_hit_rate\": " << hit_rate;
        }
        if (o.debug_view == "cache") json << ",\n  \"debug_missing\": " << debug_missing.load();
        json << "\n}\n";
        writeTextOutput(o.stats_json, "stats JSON", json.str());
    }
}

}  // namespace

void registerRenderCommand(CLI::App& app) {
    auto options = std::make_shared<RenderOptions>();
    CLI::App* cmd = app.add_subcommand(
        "render",
        "Render an image with the reference path tracer.\n\n"
        "Traces paths from a camera with next-event estimation and multiple importance sampling\n"
        "for area, punctual and sky lights, and writes a linear 32-bit float EXR plus a\n"
        "tone-mapped PNG preview beside it (same name, .png). The camera is --look-at if given,\n"
        "else --camera, else the scene's first glTF camera, else one framing the whole scene.\n"
        "Same scene, options and --seed give identical images for any --threads.\n\n"
        "With --cache FILE.sharc (from 'sharcbake bake') paths end at the first secondary hit whose\n"
        "voxel is in the cache, as SHaRC's query does: keys use the render camera's position as the\n"
        "level-of-detail centre, and a hit is eligible only if the segment reaching it is longer\n"
        "than the voxel diagonal (t > s*sqrt(3)) and the path's cone footprint is wider than a voxel\n"
        "(glossy paths trace on). The summary reports the cache hit rate and rays/s.\n\n"
        "--debug-view NAME (requires --cache) writes a debug image instead of the path-traced one,\n"
        "evaluated at each pixel's primary hit (--spp jittered samples averaged):\n"
        "  cache      the cached radiance seen from the camera (0 where no voxel; count reported)\n"
        "  hash       the voxel's pseudo-colour (SHaRC HashGridDebugColoredHash)\n"
        "  levels     the voxel's level of detail, a fixed colour per level (cycling every 8)\n"
        "  occupancy  how full the voxel's 16-slot bucket is in a table of the bake's capacity,\n"
        "             green (empty) to red (full)\n"
        "  bounces    bounces before each cached path ended (cache hit or termination), as a\n"
        "             blue-to-red ramp from 0 to the image's largest value\n\n"
        "Examples:\n"
        "  sharcbake render scenes/cornell_box/cornell_box.gltf -o out/cornell.exr --spp 256\n"
        "  sharcbake render scenes/cornell_box/cornell_box.gltf -o out/cached.exr --cache out/cornell.sharc\n"
        "  sharcbake render scenes/cornell_box/cornell_box.gltf -o out/hash.exr --cache out/cornell.sharc \\\n"
        "      --debug-view hash --spp 1");
    cmd->add_option("scene", options->scene_path, "glTF 2.0 scene (.gltf or .glb)")->required();
    cmd->add_option("-o,--output", options->output_path, "Output image (.exr)")->required();
    cmd->add_option("--camera", options->camera, "glTF camera by name or index (default: the first)");
    cmd->add_option("--look-at", options->look_at,
                    "Camera from eye and target: \"ex,ey,ez,tx,ty,tz\" (overrides --camera)");
    cmd->add_option("--up", options->up, "Up vector for --look-at")->capture_default_str();
    cmd->add_option("--fov", options->fov_degrees, "Vertical field of view in degrees for --look-at")
        ->capture_default_str()
        ->check(CLI::Range(0.1f, 179.0f))->check(kFiniteNumber);
    cmd->add_option("--resolution", options->resolution,
                    "Image size \"WxH\", or \"W\" with the height from the camera's aspect ratio "
                    "(default 512)");
    cmd->add_option("--spp", options->spp, "Samples per pixel")->capture_default_str()->check(CLI::Range(1u, 1u << 24));
    cmd->add_option("--max-bounces", options->max_bounces,
                    "Cap on surface interactions per path (Russian roulette ends most paths "
                    "much earlier)")
        ->capture_default_str();
    cmd->add_option("--seed", options->seed, "Random seed")->capture_default_str();
    cmd->add_option("--threads", options->threads, "Worker threads (0 = all cores)")->capture_default_str();
    addSkyOptions(*cmd, options->sky);
    addSceneLimitOptions(*cmd, options->limits);
    cmd->add_option("--exposure", options->exposure, "PNG preview exposure in stops")->capture_default_str()->check(kFiniteNumber);
    cmd->add_option("--tonemap", options->tone_map, "PNG preview tone map")
        ->capture_default_str()
        ->check(CLI::IsMember({"aces", "reinhard", "clamp"}));
    cmd->add_flag("--no-png", options->no_png, "Do not write the PNG preview");
    cmd->add_option("--stats-json", options->stats_json, "Write timings and ray counts as JSON");
    CLI::Option* cache_option =
        cmd->add_option("--cache", options->cache_path, "Baked cache (.sharc): end paths on cache hits");
    cmd->add_option("--cache-lookup", options->cache_lookup,
                    "exact: SHaRC's lookup, the level the camera's distance picks (what a GPU runtime with the "
                    "SDK gets); nearest: then the nearest level the cache holds (the runtime library's "
                    "lookupNearestLevel)")
        ->capture_default_str()->check(CLI::IsMember({"exact", "nearest"}))->needs(cache_option);
    cmd->add_option("--debug-view", options->debug_view,
                    "Write a debug image of the cache instead: cache, hash, levels, occupancy or bounces")
        ->needs(cache_option)
        ->check(CLI::IsMember({"cache", "hash", "levels", "occupancy", "bounces"}));
    cmd->add_flag("-q,--quiet", options->quiet, "No progress or summary output");
    cmd->callback([options] { runRender(*options); });
}

}  // namespace sharcbake
