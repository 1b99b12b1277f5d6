// SPDX-License-Identifier: Apache-2.0
// `sharcbake render`: the reference path tracer from a glTF or command-line camera, optionally
// ending paths on a baked SHaRC cache (--cache), or drawing a debug view of that cache.
#include "cli/command_support.h"
#include "cli/commands.h"
#include "sharc/cache_query.h"
#include "sharc/camera_path.h"
#include "sharc/hit_rate.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/image.h"
#include "sharcbake/scene.h"
#include "support/json.h"
#include "support/progress.h"
#include "support/stopwatch.h"
#include "support/worker_threads.h"
#include "tracing/light_reach.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/render.h"
#include "tracing/scene_reflectance.h"
#include "tracing/surface.h"
#include "tracing/tracer.h"

#include <tbb/info.h>

#include <algorithm>
#include <array>
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
    std::string light_selection = "auto";  ///< as bake's --light-selection
    std::string trace_kernels = "avx2";    ///< as bake's --trace-kernels
    std::string scene_path;
    std::string output_path;
    std::string camera;       // name or index
    std::string look_at;      // "ex,ey,ez,tx,ty,tz"
    std::string up = "0,1,0";
    float fov_degrees = kAutomaticCameraFovDegrees;
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
    bool allow_cache_mismatch = false;
    double progress_interval = kDefaultProgressInterval;
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
Camera chooseCamera(const Scene& scene, const RenderOptions& o, const Tracer* tracer) {
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
        if (!withinWorldLimit(glm::dvec3(v[0], v[1], v[2])) || !withinWorldLimit(glm::dvec3(v[3], v[4], v[5]))) {
            throw CommandError(kExitUsage, "--look-at: a coordinate beyond +-1e9, where nothing of a scene may lie");
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
    return sceneCamera(scene, o.camera, "--camera", o.fov_degrees, tracer);
}

void parseResolution(const RenderOptions& o, const Camera& camera, int& width, int& height) {
    parseImageSize(o.resolution.empty() ? "512" : o.resolution, "--resolution", camera.aspect_ratio, width, height,
                   cameraLabel(camera));
}

ToneMap parseToneMap(const std::string& name) {
    if (name == "aces") return ToneMap::Aces;
    if (name == "reinhard") return ToneMap::Reinhard;
    return ToneMap::Clamp;
}

/// One `sharcbake render`, phase by phase: outputs checked, the scene, camera and cache set up,
/// the image (or debug view) rendered, then written and reported.
class RenderRun {
public:
    explicit RenderRun(const RenderOptions& o)
        : o_(o),
          output_is_png_(hasExtension(o.output_path, ".png")),
          // The PNG preview's name derives from the EXR's; it must name no input.
          png_path_(output_is_png_ ? o.output_path
                    : o.no_png     ? std::string()
                                   : std::filesystem::path(o.output_path).replace_extension(".png").string()),
          threads_(o.threads > 0 ? int(o.threads) : tbb::info::default_concurrency()) {}

    void run() {
        // --stats-json -: stdout carries the JSON alone, what is printed for people goes to stderr.
        HumanOutputOnStderr stats_on_stdout(isStandardOutput(o_.stats_json));
        checkOutputs({});
        start_ = std::chrono::steady_clock::now();
        // Set up inside the workers' arena: Embree's scene commit must not be the first to start one.
        runOnWorkerThreads(threads_, [&] {
            setUp();
            render();
        });
        warnAboutNonFiniteSamples();
        warnAboutBlackImage();
        warnAboutHitRate();
        if (o_.debug_view == "bounces") rampBounces();
        writeImages();
        if (!o_.quiet) printSummary();
        stats_on_stdout.release();
        if (!o_.stats_json.empty()) writeStatsJson();
    }

private:
    void checkOutputs(const std::vector<std::string>& more_inputs) const {
        std::vector<std::string> others = {o_.scene_path, o_.cache_path, o_.sky.exr_path};
        others.insert(others.end(), more_inputs.begin(), more_inputs.end());
        if (!output_is_png_ && !hasExtension(o_.output_path, ".exr")) {
            throw CommandError(kExitUsage, o_.output_path + ": the output's name picks its format: .exr (linear "
                                                            "radiance, with a .png preview) or .png (the preview alone)");
        }
        checkOutputPath(o_.output_path, "image", others);
        others.push_back(o_.output_path);
        if (!png_path_.empty() && !output_is_png_) {
            checkOutputPath(png_path_, "PNG preview", others);
            others.push_back(png_path_);
        }
        if (!o_.stats_json.empty()) checkTextOutputPath(o_.stats_json, "stats JSON", others);
    }

    void setUp() {
        scene_ = loadSceneForCommand(o_.scene_path, o_.sky, o_.quiet, o_.limits);
        checkOutputs(scene_.source_files);  // the buffers and textures the scene read
        // The automatic camera looks into a room closed around the scene's centre from inside, and
        // telling a room from a closed model takes the tracer; with any other camera the options
        // are checked before the build.
        const bool automatic = o_.look_at.empty() && o_.camera.empty() && scene_.cameras.empty();
        const auto build_start = std::chrono::steady_clock::now();
        const TraceKernels kernels = traceKernelsNamed(o_.trace_kernels);
        if (automatic) tracer_.emplace(scene_, kernels);
        const Camera chosen = chooseCamera(scene_, o_, tracer_ ? &*tracer_ : nullptr);
        if (!o_.quiet && chosen.index < 0 && chosen.name == "automatic") {
            std::printf("Camera: %s (the scene has no camera; --look-at or --camera choose another)\n",
                        describeCamera(chosen).c_str());
        }
        parseResolution(o_, chosen, width_, height_);
        camera_ = fitCameraToImage(chosen, width_, height_);
        warnAboutCameraFit(chosen, camera_, width_, height_);

        if (!tracer_) tracer_.emplace(scene_, kernels);
        warnWhenKernelsFellBack(kernels, *tracer_, "image");
        if (o_.light_selection == "power") {
            lights_.emplace(scene_);
        } else {
            lights_.emplace(*tracer_);
        }
        light_selection_seconds_ = lights_->spatialSelection().seconds;
        build_seconds_ = secondsSince(build_start);
        warnWhenUnlit(scene_, *lights_, "image");
        warnAboutPunctualLightUnits(*tracer_);
        warnAboutRayOffset();
        warnAboutLongPaths();
        scene_hash_ = sceneContentHash(scene_.source_files);
        if (!o_.cache_path.empty()) {
            CacheView view = openCacheForCommand(o_.cache_path);
            checkCacheBelongsToScene(view);
            cache_ = std::make_unique<BakedCache>(
                std::move(view), camera_.position,
                o_.cache_lookup == "nearest" ? CacheLookup::NearestLevel : CacheLookup::Exact);
        }
        if (o_.debug_view == "bounces") counting_cache_ = std::make_unique<CountingCache>(*cache_);
        if (o_.debug_view == "occupancy") occupancy_ = std::make_unique<BucketOccupancy>(cache_->view());
    }

    /// A cache records the scene and sky it was baked under (metadata scene_hash and sky); one
    /// from another scene, or another version of this one, gives plausible but wrong light.
    void checkCacheBelongsToScene(const CacheView& view) {
        bool has_hash = false, has_sky = false;
        const std::string cache_hash(view.metadata("scene_hash", &has_hash));
        const std::string cache_sky(view.metadata("sky", &has_sky));
        std::string mismatch;
        if (has_hash && cache_hash != scene_hash_) {
            mismatch = "baked from another scene or another version of it (cache " + cache_hash + ", " +
                       o_.scene_path + " " + scene_hash_ + ")";
        }
        const std::string sky = skyDescription(o_.sky);
        if (has_sky && cache_sky != sky) {
            mismatch += std::string(mismatch.empty() ? "" : "; ") + "baked under another sky (cache \"" + cache_sky +
                        "\", this render \"" + sky + "\")";
        }
        if (!mismatch.empty() && !o_.allow_cache_mismatch) {
            throw CommandError(kExitInvalidInput, o_.cache_path + ": " + mismatch +
                                                      "; rebake it, or pass --allow-cache-mismatch to render with it");
        }
        if (!mismatch.empty()) warn(formatted("%s: %s", o_.cache_path.c_str(), mismatch.c_str()));
        cache_mismatch_ = !mismatch.empty();
        if (!has_hash) {
            warn(formatted("%s records no scene_hash: cannot check that it belongs to %s", o_.cache_path.c_str(),
                           o_.scene_path.c_str()));
        }
    }

    bool primaryView() const { return !o_.debug_view.empty() && o_.debug_view != "bounces"; }

    /// A debug view evaluated at the primary hit (0 where the ray leaves the scene).
    glm::vec3 debugViewAt(const Ray& ray) {
        RayHit ray_hit;
        TraceCounts ray_count;
        ray_count.closest_hit_rays = 1;
        counters_.add(ray_count);
        if (!tracer_->intersect(ray, ray_hit)) return glm::vec3(0.0f);
        debug_counts_.add(kDebugHits);
        const SurfaceHit hit = makeSurfaceHit(scene_, ray_hit, ray.direction);
        const uint64_t key = cache_->key(hit.position, hit.geometric_normal);
        if (o_.debug_view == "cache") {
            const std::optional<CacheVoxel> v = cache_->find(key);
            if (!v) {
                debug_counts_.add(kDebugMissing);
                return glm::vec3(0.0f);
            }
            return glm::vec3(v->radiance[0], v->radiance[1], v->radiance[2]);
        }
        if (o_.debug_view == "hash") {
            const Float3 c = hashDebugColor(key);
            return glm::vec3(c.x, c.y, c.z);
        }
        if (o_.debug_view == "levels") return levelColor(decodeHashGridKey(key).level);
        // occupancy: green (empty bucket) to red (full)
        return glm::mix(glm::vec3(0, 1, 0), glm::vec3(1, 0, 0), occupancy_->occupancy(key));
    }

    void render() {
        const RadianceCache* path_cache = counting_cache_ ? static_cast<const RadianceCache*>(counting_cache_.get())
                                                          : static_cast<const RadianceCache*>(cache_.get());
        PathTracerSettings path_settings;
        path_settings.max_bounces = o_.max_bounces;
        const PathTracer path_tracer(*tracer_, *lights_, path_settings, path_cache);
        const bool primary_view = primaryView();
        const auto render_start = std::chrono::steady_clock::now();
        {
            Progress progress(o_.debug_view.empty() ? "Rendering" : "Debug view", "pixels",
                              uint64_t(width_) * uint64_t(height_),
                              ProgressOutput::forCommand(o_.quiet, o_.progress_interval));
            image_ = renderImage(CameraRays(camera_, width_, height_),
                                 ImageRenderSettings{width_, height_, o_.spp, o_.seed},
                                 [&](const Ray& ray, PixelSampler& sampler) {
                                     if (primary_view) return debugViewAt(ray);
                                     if (counting_cache_) {
                                         t_path_lookups = 0;
                                         (void)path_tracer.radiance(ray, sampler, counters_);
                                         return glm::vec3(float(t_path_lookups));
                                     }
                                     return path_tracer.radiance(ray, sampler, counters_);
                                 },
                                 &progress);
        }
        render_seconds_ = secondsSince(render_start);
        counts_ = counters_.total();
        cache_misses_ = cache_ ? cache_->misses() : 0;
        const uint64_t eligible = counts_.cache_hits + cache_misses_;
        hit_rate_ = eligible > 0 ? double(counts_.cache_hits) / double(eligible) : 0.0;
        eligible_ = eligible;
    }

    /// Far from the origin the tracer's self-intersection guard grows with the coordinates (it is
    /// a few float32 roundings of them: rayOffsetFor): a 4 m room 1e8 units out moves ray origins
    /// 165 units. (With the guard of 256 float steps it replaced, a 4 m room 1e6 units out moved
    /// them 16 units and its render came out 67% dark with no word said.)
    void warnAboutRayOffset() const {
        const glm::vec3 far = glm::max(glm::abs(scene_.bounds_min), glm::abs(scene_.bounds_max));
        const float far_coordinate = std::max({far.x, far.y, far.z});
        const glm::vec3 sides = scene_.bounds_max - scene_.bounds_min;
        const float largest_side = std::max({sides.x, sides.y, sides.z});
        if (scene_.triangles.empty() || !(largest_side > 0.0f)) return;  // nothing to leak through
        const float offset = largestRayOffset(far_coordinate);
        if (!(offset > kRayOffsetWarningShare * largest_side)) return;
        warn(
            formatted("the tracer moves ray origins up to %.3g off surfaces (its self-intersection guard: "
                      "%g float32 roundings of coordinates %.3g from the origin), %.3g%% of the scene's largest side "
                      "(%.3g): light leaks through thin walls and corners darken or brighten; move the scene towards "
                      "the origin",
                      double(offset), double(kRayOffsetRoundings), double(far_coordinate),
                      100.0 * double(offset / largest_side), double(largest_side)));
    }

    /// In a scene that keeps its light (a closed room of near-white walls) Russian roulette keeps
    /// paths alive while the albedo is near 1: a reference render ran 1024 bounces per path and
    /// would have taken an hour with no word said.
    void warnAboutLongPaths() const {
        if (!lights_->hasLights() || !(o_.debug_view.empty() || o_.debug_view == "bounces")) return;
        const SceneReflectance reflectance = estimateSceneReflectance(*tracer_, &*lights_);
        if (!(reflectance.reflectance > kStiffReflectance)) return;
        if (reflectance.unbounded()) {
            warn(
                formatted("%s; a path ends only at --max-bounces (%u), and the image shows that cap, not "
                          "the scene's light: give the surfaces an albedo below 1 (base colour) or open the scene",
                          reflectance.describe().c_str(), o_.max_bounces));
        } else {
            warn(
                formatted("%s; paths run long (Russian roulette keeps them while the albedo is near 1, up "
                          "to --max-bounces %u), so the render is slow",
                          reflectance.describe().c_str(), o_.max_bounces));
        }
    }

    /// The path tracer drops a NaN or infinite path sample (it would poison its pixel) and counts
    /// it. Warned even with -q: the image is missing that light, which nothing else shows.
    void warnAboutNonFiniteSamples() const {
        if (primaryView() || counts_.non_finite_samples == 0) return;
        const double samples = double(width_) * double(height_) * double(o_.spp);
        warn(
            formatted("%llu of %.0f path samples (%.3g%%) were NaN or infinite and were dropped%s. Most "
                      "often radiance overflowed float32 (beyond 3.4e38): an emissive strength, a light's "
                      "intensity, the sky or --sky-scale is too large. Scale the scene's light down (the image "
                      "scales with it; --exposure sets the preview's brightness)",
                      (unsigned long long)counts_.non_finite_samples, samples,
                      100.0 * double(counts_.non_finite_samples) / samples,
                      o_.debug_view.empty() ? " (counted as black): the image is too dark where they fell" : ""));
    }

    /// A scene with lights can still render black: from a camera inside a closed object, or in a
    /// part of the scene none of its light reaches. Nothing else says so (warnWhenUnlit is quiet,
    /// the scene has lights), and the user sees a black picture with no word of why.
    void warnAboutBlackImage() const {
        if (!o_.debug_view.empty() || !lights_->hasLights()) return;
        for (const glm::vec3& p : image_.pixels) {
            if (p != glm::vec3(0.0f)) return;
        }
        const std::string camera = camera_.index >= 0 ? cameraLabel(camera_) : "camera '" + camera_.name + "'";
        // What the camera sees, and what stops each light on its way there: a 64 x 64 grid of its rays.
        constexpr int kGrid = 64;
        const CameraRays rays_of(camera_, width_, height_);
        std::vector<Ray> rays;
        for (int y = 0; y < kGrid; ++y) {
            for (int x = 0; x < kGrid; ++x)
                rays.push_back(rays_of.generate(x * width_ / kGrid, y * height_ / kGrid, glm::vec2(0.5f)));
        }
        // The rays see only what lies between the camera's clip planes; a near plane past the
        // scene, or a far one short of it, is the cause to name then.
        std::string clip;
        if (camera_.znear > 0.0f) clip += formatted(" from its near clip plane (znear %g)", double(camera_.znear));
        if (camera_.zfar) clip += formatted(" up to its far clip plane (zfar %g)", double(*camera_.zfar));
        warn(
            formatted("every pixel of the image is black: no light reaches what %s at (%g, %g, %g) "
                      "sees%s: %s. --camera or --look-at choose another view",
                      camera.c_str(), camera_.position.x, camera_.position.y, camera_.position.z, clip.c_str(),
                      whyNoLightArrives(*tracer_, rays).c_str()));
    }

    void warnAboutHitRate() const {
        if (cache_ && !primaryView() && eligible_ == 0 && cache_->refused() > 0) {
            // Nothing was served and the hit-rate warning below has nothing to measure: say why.
            warn(
                formatted("SHaRC's eligibility tests refused all %llu cache lookups from this camera (each "
                          "bounce is shorter than its voxel): the cache's voxels are far larger than what this camera "
                          "sees, so every path was traced in full. Bake with a larger --level-bias (finer voxels)",
                          (unsigned long long)cache_->refused()));
            return;
        }
        if (cache_ && !primaryView() && eligible_ >= kLookupsForARate && hit_rate_ < 0.9 && cache_mismatch_) {
            // Advice about view regions would mislead: the voxels are another scene's or sky's.
            warn(
                formatted("the cache answered only %.1f%% of the lookups from this camera; it was baked for "
                          "another scene or sky (--allow-cache-mismatch, warned above), so its voxels are not this "
                          "render's: bake this scene",
                          100.0 * hit_rate_));
            return;
        }
        if (cache_ && !primaryView() && eligible_ >= kLookupsForARate && hit_rate_ < 0.9) {
            // Warned even with -q: the image is mostly plain path tracing, which the user did not ask for.
            warn(
                formatted("the cache answered only %.1f%% of the lookups from this camera (levels %s of %s); "
                          "the rest were traced. It was baked for other views: bake with --view-region free or a "
                          "region holding this camera, and check the bake's \"predicted hit rate\"%s",
                          100.0 * hit_rate_, describeLevels(cache_->levels()).c_str(), o_.cache_path.c_str(),
                          o_.cache_lookup == "nearest"
                              ? ""
                              : "; --cache-lookup nearest falls back to the nearest level the file holds"));
        }
    }

    void rampBounces() {
        for (const glm::vec3& p : image_.pixels) max_bounces_seen_ = std::max(max_bounces_seen_, p.x);
        for (glm::vec3& p : image_.pixels) p = heatRamp(max_bounces_seen_ > 0.0f ? p.x / max_bounces_seen_ : 0.0f);
    }

    ImageMetadata imageMetadata() const {
        ImageMetadata metadata{
            {"sharcbake:software", "sharcbake " SHARCBAKE_VERSION},
            {"sharcbake:scene", o_.scene_path},
            {"sharcbake:camera", camera_.index >= 0 ? cameraLabel(camera_) : camera_.name},
            {"sharcbake:spp", std::to_string(o_.spp)},
            {"sharcbake:seed", std::to_string(o_.seed)},
            {"sharcbake:max_bounces", std::to_string(o_.max_bounces)},
            {"sharcbake:integrator",
             cache_ ? "path tracer, NEE + MIS, paths end on SHaRC cache hits" : "path tracer, NEE + MIS"},
        };
        if (cache_) {
            metadata["sharcbake:cache"] = o_.cache_path;
            metadata["sharcbake:cache_voxels"] = std::to_string(cache_->view().voxelCount());
            metadata["sharcbake:cache_hits"] = std::to_string(counts_.cache_hits);
            metadata["sharcbake:cache_misses"] = std::to_string(cache_misses_);
            metadata["sharcbake:cache_refused"] = std::to_string(cache_->refused());
            metadata["sharcbake:cache_lookup"] = o_.cache_lookup;
            metadata["sharcbake:cache_nearest_level_hits"] = std::to_string(cache_->nearestLevelHits());
        }
        if (!o_.debug_view.empty()) {
            metadata["sharcbake:debug_view"] = o_.debug_view;
            if (primaryView()) {
                metadata["sharcbake:integrator"] = "debug view at the primary hit, LOD centre = render camera";
            }
        }
        if (primaryView()) {
            metadata["sharcbake:debug_primary_hits"] = std::to_string(debug_counts_.total(kDebugHits));
            if (o_.debug_view == "cache")
                metadata["sharcbake:debug_missing"] = std::to_string(debug_counts_.total(kDebugMissing));
            if (occupancy_) metadata["sharcbake:debug_failed_inserts"] = std::to_string(occupancy_->failedInserts());
        }
        if (o_.debug_view == "bounces") metadata["sharcbake:debug_bounces_max"] = std::to_string(max_bounces_seen_);
        return metadata;
    }

    void writeImages() {
        try {
            if (!output_is_png_) writeExr(o_.output_path, image_, imageMetadata());
            if (!png_path_.empty()) writePng(png_path_, image_, o_.exposure, parseToneMap(o_.tone_map));
        } catch (const ImageError& e) {
            throw CommandError(kExitIo, e.what());
        }
        total_seconds_ = secondsSince(start_);
    }

    uint64_t rays() const { return counts_.closest_hit_rays + counts_.shadow_rays; }

    void printSummary() const {
        // The light selection's measurement is set-up too: named apart where it took any time.
        char light_selection[64] = "";
        if (light_selection_seconds_ >= 0.005)
            std::snprintf(light_selection, sizeof light_selection, ", light selection %.2f s",
                          light_selection_seconds_);
        std::printf("Rendered %dx%d, %u spp, %s in %.2f s (BVH build %.2f s%s, %s)\n", width_, height_, o_.spp,
                    cameraLabel(camera_).c_str(), render_seconds_, build_seconds_ - light_selection_seconds_,
                    light_selection, counted(uint64_t(threads_), "thread").c_str());
        std::printf("  rays: %llu closest-hit + %llu shadow = %.3g rays/s\n",
                    (unsigned long long)counts_.closest_hit_rays, (unsigned long long)counts_.shadow_rays,
                    double(rays()) / render_seconds_);
        if (cache_ && !primaryView()) {
            std::printf(
                "  cache: %llu hits, %llu misses (hit rate %.1f%% of eligible lookups), %llu lookups "
                "refused by the segment/cone tests; %.3f cache hits per path\n",
                (unsigned long long)counts_.cache_hits, (unsigned long long)cache_misses_, 100.0 * hit_rate_,
                (unsigned long long)cache_->refused(),
                double(counts_.cache_hits) / (double(width_) * double(height_) * double(o_.spp)));
            if (cache_->nearestLevelHits() > 0) {
                std::printf("  of the hits, %llu came from another level than the camera's (--cache-lookup nearest)\n",
                            (unsigned long long)cache_->nearestLevelHits());
            }
        }
        if (o_.debug_view == "cache") {
            std::printf("  debug view 'cache': %llu of %llu primary hits have no cached voxel (written as 0)\n",
                        (unsigned long long)debug_counts_.total(kDebugMissing),
                        (unsigned long long)debug_counts_.total(kDebugHits));
        } else if (o_.debug_view == "bounces") {
            std::printf("  debug view 'bounces': ramp blue (0) to red (%.2f bounces, the largest pixel mean)\n",
                        double(max_bounces_seen_));
        }
        if (counts_.non_finite_samples > 0) {
            std::printf("  dropped %llu non-finite path samples\n", (unsigned long long)counts_.non_finite_samples);
        }
        std::printf("Wrote %s%s\n", o_.output_path.c_str(),
                    output_is_png_ || png_path_.empty() ? "" : " and its .png preview");
    }

    void writeStatsJson() const {
        Json json = provenanceJson("render-stats", scene_, scene_hash_);
        json.update({{"output", o_.output_path},
                     {"cache", o_.cache_path.empty() ? Json(nullptr) : Json(o_.cache_path)},
                     {"debug_view", o_.debug_view.empty() ? Json(nullptr) : Json(o_.debug_view)},
                     {"camera", cameraJson(camera_)},
                     {"width", width_},
                     {"height", height_},
                     {"samples_per_pixel", o_.spp},
                     {"threads", threads_},
                     {"seconds",
                      {{"total", total_seconds_},
                       {"bvh_build", build_seconds_},
                       {"light_selection", light_selection_seconds_},
                       {"render", render_seconds_}}},
                     {"light_selection", lightSelectionJson(lights_->spatialSelection())},
                     {"closest_hit_rays", counts_.closest_hit_rays},
                     {"shadow_rays", counts_.shadow_rays},
                     {"rays_per_second", jsonNumber(double(rays()) / render_seconds_)},
                     {"non_finite_samples", counts_.non_finite_samples}});
        if (cache_) {
            json["cache_hits"] = counts_.cache_hits;
            json["cache_misses"] = cache_misses_;
            json["cache_refused"] = cache_->refused();
            json["cache_hit_rate"] = eligible_ > 0 ? jsonNumber(hit_rate_) : Json(nullptr);  // null: no lookups
        }
        if (o_.debug_view == "cache") json["debug_missing"] = debug_counts_.total(kDebugMissing);
        json["warnings"] = warningsGiven();
        writeTextOutput(o_.stats_json, "stats JSON", jsonText(json));
    }

    const RenderOptions& o_;
    const bool output_is_png_;  ///< -o x.png: the tone-mapped preview alone, no EXR
    const std::string png_path_;
    const int threads_;
    std::chrono::steady_clock::time_point start_;
    Scene scene_;
    std::string scene_hash_;
    Camera camera_;
    int width_ = 0, height_ = 0;
    std::optional<Tracer> tracer_;
    std::optional<LightSampler> lights_;
    double build_seconds_ = 0.0;  ///< the tracer and the light sampler, light_selection_seconds_ included
    double light_selection_seconds_ = 0.0;
    std::unique_ptr<BakedCache> cache_;
    std::unique_ptr<CountingCache> counting_cache_;
    std::unique_ptr<BucketOccupancy> occupancy_;
    TraceCounters counters_;     ///< added to while rendering
    TraceCounts counts_;         ///< their totals, after render()
    uint64_t cache_misses_ = 0;  ///< eligible cache lookups that found nothing (the cache counts them)
    enum DebugCount : size_t { kDebugHits, kDebugMissing };
    ShardedCounts<2> debug_counts_;  ///< debug views: primary hits, and of them voxels the cache lacks
    Image image_;
    double render_seconds_ = 0.0, total_seconds_ = 0.0;
    double hit_rate_ = 0.0;
    uint64_t eligible_ = 0;
    bool cache_mismatch_ = false;  ///< the cache is of another scene or sky (--allow-cache-mismatch)
    float max_bounces_seen_ = 0.0f;
};

void runRender(const RenderOptions& o) { RenderRun(o).run(); }

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
    pathOption(cmd->add_option("scene", options->scene_path, "glTF 2.0 scene (.gltf or .glb)"))->required();
    pathOption(
        cmd->add_option("-o,--output", options->output_path,
                        "Output image: .exr (linear radiance, and a tone-mapped .png preview beside it) or .png (the "
                        "preview alone)"))
        ->required();
    cmd->add_option("--camera", options->camera,
                    "glTF camera (default: the first): by its node's name (Blender's object name), else by the glTF "
                    "camera's own name, else by its index, #N or N. A name two cameras share is refused with "
                    "both listed. A scene without cameras gets an automatic one: framing it from outside, or, "
                    "closed around its centre and lit from within (a room), looking across it from inside, or, "
                    "wrapped in a glowing shell (a sky dome modelled as an emissive sphere), framing what the "
                    "shell holds from inside it");
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
    cmd->add_option("--light-selection", options->light_selection,
                    "How each path vertex picks the light it samples: auto (mostly by how much of each light "
                    "reaches its part of the scene, measured with shadow rays first) or power (by power alone, no "
                    "set-up); see bake --help")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "power"}));
    addTraceKernelsOption(cmd, options->trace_kernels);
    cmd->add_option("--threads", options->threads, "Worker threads (0 = all cores)")->capture_default_str();
    addSkyOptions(*cmd, options->sky);
    addSceneLimitOptions(*cmd, options->limits);
    cmd->add_option("--exposure", options->exposure, "PNG preview exposure in stops")->capture_default_str()->check(kFiniteNumber);
    cmd->add_option("--tonemap", options->tone_map, "PNG preview tone map")
        ->capture_default_str()
        ->check(CLI::IsMember({"aces", "reinhard", "clamp"}));
    cmd->add_flag("--no-png", options->no_png, "Do not write the PNG preview");
    pathOption(
        cmd->add_option("--stats-json", options->stats_json,
                        "Write timings and ray counts as JSON to this file; - writes them to stdout, and what the "
                        "render prints for people goes to stderr"));
    CLI::Option* cache_option = pathOption(
        cmd->add_option("--cache", options->cache_path, "Baked cache (.sharc): end paths on cache hits"));
    cmd->add_flag("--allow-cache-mismatch", options->allow_cache_mismatch,
                  "Render with a --cache baked from another scene (its scene_hash differs: another file, or an "
                  "edited version of this one) or under another sky, with a warning instead of exit 3")
        ->needs(cache_option);
    cmd->add_option("--cache-lookup", options->cache_lookup,
                    "exact: SHaRC's lookup, the level the camera's distance picks (what a GPU runtime with the "
                    "SDK gets); nearest: then the nearest level the cache holds (the runtime library's "
                    "lookupNearestLevel)")
        ->capture_default_str()->check(CLI::IsMember({"exact", "nearest"}))->needs(cache_option);
    cmd->add_option("--debug-view", options->debug_view,
                    "Write a debug image of the cache instead: cache, hash, levels, occupancy or bounces")
        ->needs(cache_option)
        ->check(CLI::IsMember({"cache", "hash", "levels", "occupancy", "bounces"}));
    cmd->add_flag("-q,--quiet", options->quiet, "No progress or summary output; warnings and errors still print");
    addProgressIntervalOption(*cmd, options->progress_interval);
    cmd->callback([options] { runRender(*options); });
}

}  // namespace sharcbake
