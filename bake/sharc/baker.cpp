// SPDX-License-Identifier: Apache-2.0
#include "sharc/baker.h"

#include "support/stopwatch.h"
#include "tracing/render.h"
#include "tracing/sample_batch.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

namespace sharcbake {
namespace {

/// Paths per chunk: each chunk is traced by one task and owns its deposit list, so the commit
/// can replay all deposits in path order whatever thread traced them.
constexpr uint32_t kPathsPerChunk = 64;

}  // namespace

DepositLevels levelsFor(const Scene& scene, const BakeSettings& settings) {
    return DepositLevels(settings.sharc.grid, settings.view_region, scene.bounds_min, scene.bounds_max);
}

SharcSettings withCoverage(SharcSettings sharc, const DepositLevels& levels) {
    sharc.coarsest_level = levels.coarsestLevel();
    return sharc;
}

double estimateMaxRadiance(const Tracer& tracer) {
    const Scene& scene = tracer.scene();
    double max_radiance = 0.0;
    // Only materials on the scene's triangles: a material no triangle uses (an unused one in the
    // file, or one whose only triangle the loader dropped as degenerate) emits nothing, and a
    // strength of 1e20 there put every deposit of a scene lit at 1 below one step (a black cache).
    std::vector<bool> used(scene.materials.size(), false);
    for (const uint32_t material : scene.triangle_materials) {
        if (material < used.size()) used[material] = true;
    }
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        const Material& m = scene.materials[i];
        if (used[i] && m.isEmissive())
            max_radiance = std::max(max_radiance, double(maxComponent(m.emissive) * m.emissive_strength));
    }
    max_radiance = std::max(max_radiance, double(maxComponent(scene.sky.uniform)));
    if (scene.sky.map) {
        for (const glm::vec4& t : scene.sky.map->texels) {
            max_radiance = std::max(max_radiance, double(maxComponent(glm::vec3(t)) * scene.sky.scale));
        }
    }
    const double diagonal = double(glm::length(scene.bounds_max - scene.bounds_min));
    for (const PunctualLight& light : scene.lights) {
        const double peak = double(maxComponent(light.intensity));
        if (light.type == LightType::Directional) {
            max_radiance = std::max(max_radiance, peak / kPi);
            continue;
        }
        constexpr uint32_t kDirections = 64;
        const std::vector<float> hits = hitDistancesAround(tracer, light.position, kDirections);
        double nearest = 0.0;
        if (!hits.empty()) {
            nearest = double(*std::min_element(hits.begin(), hits.end())) / 8.0;
        } else {
            // Per axis, how far the light lies outside the bounds (0 within them).
            const glm::vec3 outside = glm::max(glm::max(scene.bounds_min - light.position, glm::vec3(0.0f)),
                                               light.position - scene.bounds_max);
            nearest = double(glm::length(outside));
        }
        nearest = std::max(nearest, 1e-4 * diagonal);
        if (nearest > 0.0) max_radiance = std::max(max_radiance, peak / (nearest * nearest) / kPi);
    }
    return max_radiance;
}

Baker::Baker(const Tracer& tracer, const LightSampler& lights, const CameraPath& camera_path,
             const BakeSettings& settings, double radiance_scale)
    : tracer_(tracer),
      lights_(lights),
      camera_path_(camera_path),
      settings_(settings),
      levels_(levelsFor(tracer.scene(), settings)),
      cache_(withCoverage(settings.sharc, levels_), radiance_scale),
      wavefronts_([this] { return UpdateWavefront(tracer_, lights_, cache_, settings_.path); }) {
    const uint32_t stride = std::max(1u, settings_.update_stride);
    blocks_x_ = (uint32_t(settings_.width) + stride - 1) / stride;
    blocks_y_ = (uint32_t(settings_.height) + stride - 1) / stride;
    prepareBsdfTables();
}

void Baker::traceUpdatePaths(uint32_t work_iteration, std::vector<std::vector<Deposit>>& chunk_deposits,
                             UpdateCounters& counters) const {
    const CameraPose pose = camera_path_.poseAt(work_iteration);
    const CameraRays camera(toCamera(pose), settings_.width, settings_.height);
    const Float3 camera_position{pose.position.x, pose.position.y, pose.position.z};
    const uint32_t stride = std::max(1u, settings_.update_stride);
    const uint32_t paths = pathsPerIteration();
    chunk_deposits.resize((paths + kPathsPerChunk - 1) / kPathsPerChunk);

    // Every chunk of paths is one wavefront batch, traced by one task into its own deposit list.
    tbb::enumerable_thread_specific<UpdateCounters> thread_counters;
    tbb::enumerable_thread_specific<std::vector<UpdatePathStart>> thread_starts;
    struct PixelDraws {  // the chunk's pixel positions, drawn at once (sample_batch.h)
        std::vector<uint32_t> hashes, indices;
        std::vector<glm::vec2> values;
    };
    tbb::enumerable_thread_specific<PixelDraws> thread_draws;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunk_deposits.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
        UpdateCounters& local = thread_counters.local();
        UpdateWavefront& wavefront = wavefronts_.local();
        std::vector<UpdatePathStart>& starts = thread_starts.local();
        PixelDraws& draws = thread_draws.local();
        for (size_t chunk = r.begin(); chunk != r.end(); ++chunk) {
            std::vector<Deposit>& deposits = chunk_deposits[chunk];
            deposits.clear();
            starts.clear();
            const uint32_t first = uint32_t(chunk) * kPathsPerChunk;
            const uint32_t last = std::min(paths, first + kPathsPerChunk);
            draws.hashes.clear();
            draws.indices.clear();
            for (uint32_t block = first; block < last; ++block) {
                const PixelSampler sampler(settings_.seed, block, work_iteration);
                draws.hashes.push_back(sampler.pixelHash());
                draws.indices.push_back(sampler.reversedSample());
            }
            draws.values.resize(draws.hashes.size());
            sample2DMany(draws.hashes.data(), draws.indices.data(), draws.hashes.size(), 0, draws.values.data());
            for (uint32_t block = first; block < last; ++block) {
                // One random pixel (and sub-pixel position) per block, new every iteration: the
                // sampler's dimension 0.
                const PixelSampler sampler(draws.hashes[block - first], draws.indices[block - first]);
                const glm::vec2 u = draws.values[block - first] * float(stride);
                const int x = std::min(settings_.width - 1, int((block % blocks_x_) * stride + uint32_t(u.x)));
                const int y = std::min(settings_.height - 1, int((block / blocks_x_) * stride + uint32_t(u.y)));
                starts.push_back(UpdatePathStart{camera.generate(x, y, glm::fract(u)), sampler});
            }
            wavefront.trace(starts, levels_, camera_position, deposits, local);
        }
    });
    for (const UpdateCounters& c : thread_counters) counters += c;
}

void Baker::runIteration() {
    const uint32_t iteration = iteration_;
    const uint32_t work_iteration = workIteration(iteration);
    auto start = std::chrono::steady_clock::now();
    traceUpdatePaths(work_iteration, chunk_deposits_, counters_);
    seconds_.update += secondsSince(start);

    // Commit: new keys inserted by fixed slot ranges, each in chunk order (SharcCache::commitChunks),
    // so the same slots and sums on every run and for any thread count.
    start = std::chrono::steady_clock::now();
    cache_.commitChunks(chunk_deposits_, work_iteration);
    seconds_.commit += secondsSince(start);

    start = std::chrono::steady_clock::now();
    cache_.resolve(iteration);
    if (settings_.sharc.grow_when_loaded) {
        uint64_t capacity = cache_.capacity();
        while (double(cache_.occupiedSlots()) > kGrowAtLoad * double(capacity) && capacity < kMaxCacheCapacity) {
            capacity *= 2;
        }
        if (capacity > cache_.capacity()) cache_.grow(uint32_t(std::min<uint64_t>(capacity, kMaxCacheCapacity)));
    }
    seconds_.resolve += secondsSince(start);
    ++iteration_;
}

}  // namespace sharcbake
