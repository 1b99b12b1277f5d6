// SPDX-License-Identifier: Apache-2.0
/// @file stability_support.h
/// @brief What the stability cases share: scenes changed in memory (scaled, moved, materials
/// replaced), a small in-process bake from the exploring camera, and the measurements the cases
/// assert on (area-weighted mean of the cache over the scene's surfaces, finiteness).
#pragma once

#include "sharc/baker.h"
#include "sharc/camera_path.h"
#include "sharc/coverage.h"
#include "tracing/distribution.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/sampling.h"
#include "sharcbake/scene_loader.h"
#include "reports/stability_report.h"
#include "tracing/tracer.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace sharcbake::stability {

inline std::string scenePath(const std::string& name) {
    return std::string(SHARCBAKE_SCENES_DIR) + "/" + name + "/" + name + ".gltf";
}

/// Scales the scene about the origin by `scale`, then moves it by `offset`: geometry, cameras,
/// punctual lights and bounds.
inline void transformScene(Scene& scene, float scale, glm::vec3 offset) {
    for (glm::vec3& p : scene.positions) p = p * scale + offset;
    for (Camera& c : scene.cameras) {
        c.position = c.position * scale + offset;
        // Clip distances scale with the scene too, as the generator's --scale writes them: a
        // near plane left at 0.01 clips away a room shrunk to 4 mm.
        c.znear *= scale;
        if (c.zfar) *c.zfar *= scale;
    }
    for (PunctualLight& l : scene.lights) l.position = l.position * scale + offset;
    scene.bounds_min = scene.bounds_min * scale + offset;
    scene.bounds_max = scene.bounds_max * scale + offset;
}

/// Every material becomes a Lambert surface of albedo `rho` emitting `emission` (a furnace).
inline void makeFurnace(Scene& scene, float rho, float emission) {
    for (Material& m : scene.materials) {
        m.base_color = glm::vec3(rho);
        m.emissive = glm::vec3(1.0f);
        m.emissive_strength = emission;
    }
}

struct BakeConfig {
    int resolution = 48;           ///< virtual camera is resolution x resolution
    uint32_t update_stride = 4;
    uint32_t iterations = 64;
    uint32_t capacity = 1u << 16;
    float scene_scale = 5.0f;      ///< coarse voxels: a few hundred in a room, many samples each
    float level_bias = 0.0f;
    uint32_t max_bounces = 8;
    uint32_t explore_points = 16;
    HistorySchedule history;
    uint32_t feedback_window = SharcSettings{}.feedback_window;
    uint32_t propagation_depth = SharcSettings{}.propagation_depth;
    bool resample_at_end = false;
};

/// A bake of `scene` from the exploring camera (starting at the scene's glTF cameras), run
/// iteration by iteration so a case can watch it converge.
class SmallBake {
public:
    SmallBake(Scene scene_in, const BakeConfig& config) : scene(std::move(scene_in)), config_(config) {
        tracer = std::make_unique<Tracer>(scene);
        lights = std::make_unique<LightSampler>(*tracer);
        std::optional<CameraPath> explored = exploringCameraPath(*tracer, scene, config.explore_points, 3);
        if (!explored) {  // degenerate scenes: a camera where the first start would have been
            const glm::vec3 start = scene.cameras.empty() ? 0.5f * (scene.bounds_min + scene.bounds_max)
                                                          : scene.cameras.front().position;
            explored = CameraPath({CameraPose{start}}, true, 1, 0.0f, 3);
        }
        path = std::make_unique<CameraPath>(std::move(*explored));
        makeBaker(*path);
    }

    /// A bake along a given camera path (for cameras placed on purpose, e.g. on a surface).
    SmallBake(Scene scene_in, const BakeConfig& config, std::vector<CameraPose> poses)
        : scene(std::move(scene_in)), config_(config) {
        tracer = std::make_unique<Tracer>(scene);
        lights = std::make_unique<LightSampler>(*tracer);
        path = std::make_unique<CameraPath>(std::move(poses), false, 1, 0.0f, 3);
        makeBaker(*path);
    }

    void run(uint32_t iterations) {
        for (uint32_t i = 0; i < iterations; ++i) baker->runIteration();
    }
    void run() { run(config_.iterations); }

    const SharcCache& cache() const { return baker->cache(); }
    StabilityReport report() const {
        return makeStabilityReport(cache(), baker->counters(), scene.bounds_min, scene.bounds_max,
                                   levelsPresent(cache()));
    }

    Scene scene;
    std::unique_ptr<Tracer> tracer;
    std::unique_ptr<LightSampler> lights;
    std::unique_ptr<CameraPath> path;
    std::unique_ptr<Baker> baker;

private:
    void makeBaker(const CameraPath& camera_path) {
        BakeSettings settings;
        settings.width = settings.height = config_.resolution;
        settings.update_stride = config_.update_stride;
        settings.path.max_bounces = config_.max_bounces;
        settings.sharc.grid.capacity = config_.capacity;
        settings.sharc.grid.scene_scale = config_.scene_scale;
        settings.sharc.grid.level_bias = config_.level_bias;
        settings.sharc.history = config_.history;
        settings.sharc.feedback_window = config_.feedback_window;
        settings.sharc.propagation_depth = config_.propagation_depth;
        settings.sharc.resample_at_end = config_.resample_at_end;
        baker = std::make_unique<Baker>(*tracer, *lights, camera_path, settings,
                                        SharcCache::chooseRadianceScale(estimateMaxRadiance(*tracer)));
    }
    BakeConfig config_;
};

/// Mean resolved radiance (first channel) over voxels with at least `min_samples` samples,
/// weighted by their samples.
inline double sampleWeightedMean(const SharcCache& cache, uint32_t min_samples = 16) {
    double sum = 0.0, weight = 0.0;
    for (uint32_t slot = 0; slot < cache.capacity(); ++slot) {
        const ResolvedEntry& r = cache.resolved()[slot];
        if (cache.table().keyAt(slot) == kHashGridInvalidKey || r.total_samples < min_samples) continue;
        sum += double(r.mean.x) * r.total_samples;
        weight += r.total_samples;
    }
    return weight > 0.0 ? sum / weight : 0.0;
}

/// True when no resolved entry of the cache holds a NaN or Inf (mean or weight).
inline bool cacheIsFinite(const SharcCache& cache) {
    for (const ResolvedEntry& r : cache.resolved()) {
        if (!isFiniteColor(r.mean) || !std::isfinite(r.weight)) return false;
    }
    return true;
}

/// A point on a surface's front side, drawn by area.
struct SurfacePoint {
    glm::vec3 position;
    glm::vec3 normal;  ///< geometric, on the front side
};

/// `points` stratified surface points distributed by area (deterministic), keeping those for
/// which `keep(position)` holds.
template <class Keep>
std::vector<SurfacePoint> areaSamples(const Scene& scene, uint32_t points, Keep keep) {
    std::vector<float> areas(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3 tri = scene.triangles[t];
        areas[t] = 0.5f * glm::length(glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                                 scene.positions[tri.z] - scene.positions[tri.x]));
    }
    const Distribution1D by_area(areas);
    std::vector<SurfacePoint> samples;
    for (uint32_t i = 0; i < points; ++i) {
        const float u = (float(i) + bitsToUnitFloat(hashUint32(i * 3 + 1))) / float(points);
        const uint32_t t = uint32_t(by_area.sampleDiscrete(std::min(u, kOneMinusEpsilon)));
        const glm::vec2 b =
            sampleUniformTriangle({bitsToUnitFloat(hashUint32(i * 3 + 2)), bitsToUnitFloat(hashUint32(i * 3 + 3))});
        const glm::uvec3 tri = scene.triangles[t];
        const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
        const glm::vec3 p = (1.0f - b.x - b.y) * p0 + b.x * p1 + b.y * p2;
        if (keep(p)) samples.push_back(SurfacePoint{p, glm::normalize(glm::cross(p1 - p0, p2 - p0))});
    }
    return samples;
}

inline std::vector<SurfacePoint> areaSamples(const Scene& scene, uint32_t points) {
    return areaSamples(scene, points, [](glm::vec3) { return true; });
}

struct AreaMean {
    glm::dvec3 radiance{0.0};  ///< mean over the reached points
    double reached = 0.0;      ///< share of the points with a voxel at some level present
};

/// The cache's mean outgoing radiance over surface points: each point reads its voxel at the
/// finest level present that holds one (the deposits' level; the coarser levels every voxel feeds
/// average over more of the scene, as a far camera sees it).
inline AreaMean cacheMean(const SharcCache& cache, const std::vector<SurfacePoint>& samples) {
    const std::vector<uint32_t> levels = levelsPresent(cache);
    const HashGridParameters& grid = cache.settings().grid;
    AreaMean result;
    uint32_t reached = 0;
    for (const SurfacePoint& s : samples) {
        glm::dvec3 sum(0.0);
        double weight = 0.0;
        for (uint32_t level : levels) {
            const ResolvedEntry* e = cache.findResolved(hashGridKeyAtLevel(
                Float3{s.position.x, s.position.y, s.position.z}, Float3{s.normal.x, s.normal.y, s.normal.z}, level, grid));
            if (e && e->weight > 0.0) {
                sum += glm::dvec3(e->mean) * e->weight;
                weight += e->weight;
                break;
            }
        }
        if (weight > 0.0) {
            result.radiance += sum / weight;
            ++reached;
        }
    }
    if (reached > 0) result.radiance /= double(reached);
    result.reached = samples.empty() ? 0.0 : double(reached) / double(samples.size());
    return result;
}

/// The cache's area-weighted mean outgoing radiance over all of the scene's front sides.
/// In a closed scene with one Lambert albedo rho, energy conservation fixes the true value:
/// sum(L A) / A = sum(Le A) / ((1 - rho) A).
inline AreaMean areaMeanRadiance(const Scene& scene, const SharcCache& cache, uint32_t points) {
    return cacheMean(cache, areaSamples(scene, points));
}

/// Reference for cacheMean: the path tracer's outgoing radiance at each point (Lambert
/// surfaces: the same in every direction), seen along the normal from 1 mm in front of it (a
/// unit-scale scene), `spp` paths per point.
inline glm::dvec3 referenceMean(const Tracer& tracer, const LightSampler& lights,
                                const std::vector<SurfacePoint>& samples, uint32_t spp) {
    const PathTracer path_tracer(tracer, lights, PathTracerSettings{});
    std::vector<glm::dvec3> per_point(samples.size());
    TraceCounters counters;
    tbb::parallel_for(size_t(0), samples.size(), [&](size_t i) {
        const SurfacePoint& s = samples[i];
        const Ray ray{s.position + s.normal * 1e-3f, -s.normal};
        glm::dvec3 sum(0.0);
        for (uint32_t k = 0; k < spp; ++k) {
            PixelSampler sampler(7, uint32_t(i), k);
            sampler.startDimension(PathTracer::kFirstBounceDimension);
            sum += glm::dvec3(path_tracer.radiance(ray, sampler, counters));
        }
        per_point[i] = sum / double(spp);
    });
    glm::dvec3 mean(0.0);
    for (const glm::dvec3& v : per_point) mean += v;
    return samples.empty() ? mean : mean / double(samples.size());
}

/// Total area of the scene's triangles and its emitted radiance x area (sum of Le A).
inline std::pair<double, glm::dvec3> areaAndEmission(const Scene& scene) {
    double area = 0.0;
    glm::dvec3 emission(0.0);
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3 tri = scene.triangles[t];
        const double a = 0.5 * glm::length(glm::cross(glm::dvec3(scene.positions[tri.y] - scene.positions[tri.x]),
                                                      glm::dvec3(scene.positions[tri.z] - scene.positions[tri.x])));
        const Material& m = scene.materials[scene.triangle_materials[t]];
        area += a;
        if (m.isEmissive()) emission += glm::dvec3(m.emissive) * double(m.emissive_strength) * a;
    }
    return {area, emission};
}

/// A furnace (every surface albedo rho, emission 1) baked until the sample-weighted voxel mean
/// is within `tolerance` of Le / (1 - rho), checked every `step` iterations.
struct FurnaceConvergence {
    double expected = 0.0;
    double measured = 0.0;
    uint32_t iterations = 0;  ///< iterations run: the first checkpoint within tolerance if converged
    bool converged = false;
    StabilityReport report;
    bool finite = false;
};

inline FurnaceConvergence bakeFurnaceToConvergence(float rho, double tolerance, uint32_t max_iterations,
                                                   int resolution, uint32_t step = 64, BakeConfig config = {}) {
    Scene scene = loadGltf(scenePath("furnace_rho099"));
    makeFurnace(scene, rho, 1.0f);
    config.resolution = resolution;
    SmallBake bake(std::move(scene), config);
    FurnaceConvergence result;
    result.expected = 1.0 / (1.0 - double(rho));
    while (bake.baker->iterationsDone() < max_iterations) {
        bake.run(step);
        result.measured = sampleWeightedMean(bake.cache());
        if (std::abs(result.measured - result.expected) <= tolerance * result.expected) {
            result.converged = true;
            break;
        }
    }
    result.iterations = bake.baker->iterationsDone();
    result.report = bake.report();
    result.finite = cacheIsFinite(bake.cache());
    std::printf("[stability] furnace rho=%g: expected %g, measured %g after %u iterations at %dx%d (tolerance %g%%)%s\n",
                double(rho), result.expected, result.measured, result.iterations, resolution, resolution,
                100.0 * tolerance, result.converged ? "" : ": NOT converged");
    return result;
}

}  // namespace sharcbake::stability
