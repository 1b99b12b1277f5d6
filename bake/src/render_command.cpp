// SPDX-License-Identifier: Apache-2.0
// `sharcbake render`: the reference path tracer from a glTF or command-line camera.
#include "command_support.h"
#include "commands.h"
#include "lights.h"
#include "path_tracer.h"
#include "progress.h"
#include "render.h"
#include "sharcbake/image.h"
#include "tracer.h"

#include <tbb/global_control.h>
#include <tbb/info.h>

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
    float exposure = 0.0f;
    std::string tone_map = "aces";
    bool no_png = false;
    bool quiet = false;
    std::string stats_json;
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
    if (!o.camera.empty()) {
        for (const Camera& c : scene.cameras) {
            if (c.name == o.camera) return c;
        }
        char* end = nullptr;
        const unsigned long index = std::strtoul(o.camera.c_str(), &end, 10);
        if (end && *end == '\0' && index < scene.cameras.size()) return scene.cameras[index];
        std::string names;
        for (size_t i = 0; i < scene.cameras.size(); ++i) {
            names += (i ? ", " : "") + std::to_string(i) + " '" + scene.cameras[i].name + "'";
        }
        throw CommandError(kExitUsage, "--camera " + o.camera + ": no such camera in the scene (" +
                                           (names.empty() ? "it has none" : "it has " + names) + ")");
    }
    if (!scene.cameras.empty()) return scene.cameras.front();
    // Frame the bounding sphere with the default field of view, looking down -Z.
    Camera c;
    c.name = "automatic";
    c.yfov = glm::radians(o.fov_degrees);
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float radius = std::max(0.5f * glm::length(scene.bounds_max - scene.bounds_min), 1e-3f);
    c.position = center + glm::vec3(0.0f, 0.0f, 1.1f * radius / std::sin(0.5f * c.yfov));
    return c;
}

void parseResolution(const RenderOptions& o, const Camera& camera, int& width, int& height) {
    width = 512;
    height = 0;
    if (!o.resolution.empty()) {
        char x = 0;
        std::istringstream in(o.resolution);
        if (!(in >> width) || width <= 0 || (in >> x && (x != 'x' || !(in >> height) || height <= 0)) ||
            !(in >> std::ws).eof()) {
            throw CommandError(kExitUsage, "--resolution: expected W or WxH with positive integers, got \"" +
                                               o.resolution + "\"");
        }
    }
    if (height == 0) {
        const float aspect = camera.aspect_ratio.value_or(1.0f);
        height = std::max(1, int(std::lround(float(width) / aspect)));
    }
    if (int64_t(width) * int64_t(height) > (int64_t(1) << 28)) {
        throw CommandError(kExitUsage, "--resolution: image too large");
    }
}

ToneMap parseToneMap(const std::string& name) {
    if (name == "aces") return ToneMap::Aces;
    if (name == "reinhard") return ToneMap::Reinhard;
    return ToneMap::Clamp;
}

void runRender(const RenderOptions& o) {
    const auto start = std::chrono::steady_clock::now();
    const int threads = o.threads > 0 ? int(o.threads) : tbb::info::default_concurrency();
    tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, size_t(threads));

    const Scene scene = loadSceneForCommand(o.scene_path, o.sky, o.quiet);
    const Camera camera = chooseCamera(scene, o);
    int width = 0, height = 0;
    parseResolution(o, camera, width, height);

    const auto build_start = std::chrono::steady_clock::now();
    const Tracer tracer(scene);
    const LightSampler lights(scene);
    const double build_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - build_start).count();
    if (!o.quiet && !lights.hasLights()) {
        std::fprintf(stderr, "warning: the scene has no lights, no emissive surfaces and a black sky: "
                             "the image will be black\n");
    }

    PathTracerSettings path_settings;
    path_settings.max_bounces = o.max_bounces;
    const PathTracer path_tracer(tracer, lights, path_settings);
    TraceCounters counters;
    ImageRenderSettings settings{width, height, o.spp, o.seed};

    const auto render_start = std::chrono::steady_clock::now();
    Image image;
    {
        Progress progress("Rendering", uint64_t(width) * uint64_t(height), !o.quiet && Progress::isTerminal());
        image = renderImage(CameraRays(camera, width, height), settings,
                            [&](const Ray& ray, PixelSampler& sampler) {
                                return path_tracer.radiance(ray, sampler, counters);
                            },
                            &progress);
    }
    const double render_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - render_start).count();
    const uint64_t rays = counters.closest_hit_rays + counters.shadow_rays;

    ImageMetadata metadata{
        {"sharcbake:software", "sharcbake " SHARCBAKE_VERSION},
        {"sharcbake:scene", o.scene_path},
        {"sharcbake:camera", camera.name},
        {"sharcbake:spp", std::to_string(o.spp)},
        {"sharcbake:seed", std::to_string(o.seed)},
        {"sharcbake:max_bounces", std::to_string(o.max_bounces)},
        {"sharcbake:integrator", "path tracer, NEE + MIS"},
    };
    try {
        writeExr(o.output_path, image, metadata);
        if (!o.no_png) {
            writePng(std::filesystem::path(o.output_path).replace_extension(".png").string(), image,
                     o.exposure, parseToneMap(o.tone_map));
        }
    } catch (const ImageError& e) {
        throw CommandError(kExitIo, e.what());
    }
    const double total_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

    if (!o.quiet) {
        std::printf("Rendered %dx%d, %u spp, camera '%s' in %.2f s (BVH build %.2f s, %d threads)\n",
                    width, height, o.spp, camera.name.c_str(), render_seconds, build_seconds, threads);
        std::printf("  rays: %llu closest-hit + %llu shadow = %.3g rays/s\n",
                    (unsigned long long)counters.closest_hit_rays.load(),
                    (unsigned long long)counters.shadow_rays.load(), double(rays) / render_seconds);
        if (counters.non_finite_samples > 0) {
            std::printf("  dropped %llu non-finite path samples\n",
                        (unsigned long long)counters.non_finite_samples.load());
        }
        std::printf("Wrote %s%s\n", o.output_path.c_str(), o.no_png ? "" : " and its .png preview");
    }
    if (!o.stats_json.empty()) {
        std::ofstream json(o.stats_json);
        json << "{\n  \"width\": " << width << ",\n  \"height\": " << height
             << ",\n  \"samples_per_pixel\": " << o.spp << ",\n  \"threads\": " << threads
             << ",\n  \"seconds\": {\"total\": " << total_seconds << ", \"bvh_build\": " << build_seconds
             << ", \"render\": " << render_seconds << "},\n  \"closest_hit_rays\": "
             << counters.closest_hit_rays << ",\n  \"shadow_rays\": " << counters.shadow_rays
             << ",\n  \"rays_per_second\": " << double(rays) / render_seconds
             << ",\n  \"non_finite_samples\": " << counters.non_finite_samples << "\n}\n";
        if (!json) throw CommandError(kExitIo, o.stats_json + ": cannot write");
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
        "Example:\n"
        "  sharcbake render scenes/cornell_box/cornell_box.gltf -o out/cornell.exr --spp 256");
    cmd->add_option("scene", options->scene_path, "glTF 2.0 scene (.gltf or .glb)")->required();
    cmd->add_option("-o,--output", options->output_path, "Output image (.exr)")->required();
    cmd->add_option("--camera", options->camera, "glTF camera by name or index (default: the first)");
    cmd->add_option("--look-at", options->look_at,
                    "Camera from eye and target: \"ex,ey,ez,tx,ty,tz\" (overrides --camera)");
    cmd->add_option("--up", options->up, "Up vector for --look-at")->capture_default_str();
    cmd->add_option("--fov", options->fov_degrees, "Vertical field of view in degrees for --look-at")
        ->capture_default_str()
        ->check(CLI::Range(0.1f, 179.0f));
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
    cmd->add_option("--exposure", options->exposure, "PNG preview exposure in stops")->capture_default_str();
    cmd->add_option("--tonemap", options->tone_map, "PNG preview tone map")
        ->capture_default_str()
        ->check(CLI::IsMember({"aces", "reinhard", "clamp"}));
    cmd->add_flag("--no-png", options->no_png, "Do not write the PNG preview");
    cmd->add_option("--stats-json", options->stats_json, "Write timings and ray counts as JSON");
    cmd->add_flag("-q,--quiet", options->quiet, "No progress or summary output");
    cmd->callback([options] { runRender(*options); });
}

}  // namespace sharcbake
