// SPDX-License-Identifier: Apache-2.0
#include "sharc/sharc_update.h"

#include "tracing/sample_batch.h"

#include <algorithm>
#include <cmath>

namespace sharcbake {
namespace {

/// The last few path vertices that still receive radiance (SharcState): where their own deposit
/// is in the path's deposit list, and the product of segment throughputs from each of them to the
/// current vertex.
///
/// Radiance propagated back to a vertex is added to that vertex's own deposit (same voxel, same
/// iteration) instead of becoming a deposit of its own, as SharcUpdateHit's atomic adds would: the
/// voxel's sums are the same, with one fixed-point rounding instead of several, and the commit
/// looks up and adds about half as many deposits.
struct PathHistory {
    static constexpr uint32_t kMaxDepth = 16;
    std::array<uint32_t, kMaxDepth> deposits{};  ///< index into the path's deposits
    std::array<glm::vec3, kMaxDepth> weights{};
    uint32_t length = 0;

    /// SharcUpdateMiss / the back-propagation step of SharcUpdateHit.
    void propagate(glm::vec3 radiance, std::vector<Deposit>& out) const {
        for (uint32_t j = 0; j < length; ++j) {
            const glm::vec3 value = radiance * weights[j];
            if (!(maxComponent(value) > 0.0f)) continue;
            if (isFiniteColor(value)) {
                out[deposits[j]].radiance += value;
            } else {
                const uint64_t key = out[deposits[j]].key;
                out.push_back(Deposit{key, value, 0});  // kept apart: the commit counts and drops it
            }
        }
    }
    /// SharcSetThroughput: the new segment's throughput multiplies every stored weight.
    void applyThroughput(glm::vec3 throughput) {
        for (uint32_t j = 0; j < length; ++j) weights[j] *= throughput;
    }
    /// Forget every vertex. Only the first `length` entries are ever read, so the arrays keep
    /// their stale values (zeroing them was a third of trace()'s own time).
    void clear() { length = 0; }
    /// Shift the history and make the vertex whose own deposit is `deposit` the most recent.
    void push(uint32_t deposit, uint32_t depth) {
        for (uint32_t j = std::min(length, depth - 1); j > 0; --j) {
            deposits[j] = deposits[j - 1];
            weights[j] = weights[j - 1];
        }
        deposits[0] = deposit;
        weights[0] = glm::vec3(1.0f);
        length = std::min(length + 1, depth);
    }
};

glm::vec3 finiteOrZero(glm::vec3 v, uint64_t& non_finite) {
    if (isFiniteColor(v)) return v;
    ++non_finite;
    return glm::vec3(0.0f);
}

}  // namespace

UpdateCounters& UpdateCounters::operator+=(const UpdateCounters& other) {
    paths += other.paths;
    segments += other.segments;
    shadow_rays += other.shadow_rays;
    resampled += other.resampled;
    sky_misses += other.sky_misses;
    non_finite += other.non_finite;
    clamped_propagation += other.clamped_propagation;
    return *this;
}

/// One update path's state between its bounces, and the vertex being shaded between the
/// shading step and the deposit step of a bounce (its shadow ray is traced in between).
struct UpdateWavefront::Path {
    PixelSampler sampler{0, 0, 0};
    PathHistory history;
    Ray ray;
    float previous_bsdf_pdf = 0.0f;
    glm::vec3 previous_position{0.0f};
    glm::vec3 previous_shading_normal{0.0f};
    std::vector<Deposit> deposits;

    // The current vertex.
    SurfaceHit hit;
    ShadingMaterial material;
    // This bounce's four sample pairs (PathTracer::kDimensionsPerBounce), drawn for the whole
    // batch before they are used: the sampler is a chain of dependent multiplies, and a loop over
    // many paths' draws keeps the CPU busy where one path's draw would wait on each multiply.
    glm::vec2 u_select_resample{0.0f};
    glm::vec2 u_light_point{0.0f};
    glm::vec2 u_lobe_rr{0.0f};
    glm::vec2 u_direction{0.0f};
    uint64_t feedback_key = 0;            ///< the voxel cache resampling reads; 0 = not this vertex
    uint32_t feedback_base = 0;           ///< its bucket's first slot (from the prefetch pass)
    uint32_t feedback_slot = SharcCache::kNoSlot;
    std::optional<GltfBsdf> bsdf;
    glm::vec3 wo{0.0f};
    uint64_t key = 0;
    glm::vec3 emitted{0.0f};
    float emission_weight = 0.0f;
    ShadowQuery shadow;
    bool shadow_blocked = false;  ///< the batch's answer for `shadow`
};

UpdateWavefront::UpdateWavefront(const Tracer& tracer, const LightSampler& lights, const SharcCache& cache,
                                 UpdatePathSettings settings)
    : tracer_(tracer), lights_(lights), cache_(cache), settings_(settings) {}

UpdateWavefront::~UpdateWavefront() = default;

size_t UpdateWavefront::bytesPerPathInFlight() {
    // The path's state, its entries in the batch's index lists, its ray and hit, its shadow ray,
    // and its lanes in the batch's sample draws (index, two sampler words, two pairs). Embree's
    // packets (16 rays on the stack) are the thread's, not the path's. Its deposits come on top
    // (sizeof(Deposit) each).
    return sizeof(Path) + sizeof(uint32_t) * 4 + sizeof(Ray) * 2 + sizeof(RayHit) + sizeof(uint8_t) * 2 +
           sizeof(uint32_t) * 3 + sizeof(glm::vec2) * 2;
}

void UpdateWavefront::trace(const std::vector<UpdatePathStart>& starts, const DepositLevels& levels,
                            const Float3& camera, std::vector<Deposit>& out, UpdateCounters& counters) {
    if (paths_.size() < starts.size()) paths_.resize(starts.size());
    active_.clear();
    for (size_t i = 0; i < starts.size(); ++i) {
        Path& path = paths_[i];
        path.sampler = starts[i].sampler;
        path.history.clear();
        path.ray = starts[i].camera_ray;
        path.previous_bsdf_pdf = 0.0f;
        path.previous_position = path.ray.origin;
        path.previous_shading_normal = glm::vec3(0.0f);
        path.deposits.clear();
        active_.push_back(uint32_t(i));
    }
    counters.paths += starts.size();
    for (uint32_t bounce = 0; bounce < settings_.max_bounces && !active_.empty(); ++bounce) {
        advance(bounce, levels, camera, counters);
    }
    for (size_t i = 0; i < starts.size(); ++i) out.insert(out.end(), paths_[i].deposits.begin(), paths_[i].deposits.end());
}

void UpdateWavefront::advance(uint32_t bounce, const DepositLevels& levels, const Float3& camera,
                              UpdateCounters& counters) {
    const uint32_t depth = std::clamp(cache_.settings().propagation_depth, 1u, PathHistory::kMaxDepth);
    const size_t count = active_.size();
    rays_.resize(count);
    hits_.resize(count);
    found_.resize(count);
    for (size_t i = 0; i < count; ++i) rays_[i] = paths_[active_[i]].ray;
    tracer_.intersectMany(rays_.data(), count, hits_.data(), found_.data());
    counters.segments += count;

    // The samples of the vertices found: the dimensions sampler.next2D would give, drawn for the
    // batch at once (sample_batch.h). Two pairs for the shading, two for the next direction.
    static_assert(PathTracer::kDimensionsPerBounce == 4, "dimension .. dimension + 3 are this bounce's");
    const uint32_t dimension = PathTracer::kFirstBounceDimension + bounce * PathTracer::kDimensionsPerBounce;
    // The hits' triangles, then their vertices, start loading while the samples are drawn:
    // in a large scene each is a cache miss, and these overlap where the shading's would not.
    const Scene& scene = tracer_.scene();
    sample_paths_.clear();
    for (size_t i = 0; i < count; ++i) {
        if (!found_[i]) continue;
        sample_paths_.push_back(active_[i]);
        prefetchSurfaceTriangle(scene, hits_[i].triangle);
    }
    for (size_t i = 0; i < count; ++i) {
        if (found_[i]) prefetchSurfaceVertices(scene, hits_[i].triangle);
    }
    drawSamples(dimension, &Path::u_select_resample, &Path::u_light_point);

    // Shade every hit; paths that end here (sky, cache) drop out of the batch.
    shaded_.clear();
    for (size_t i = 0; i < count; ++i) {
        Path& path = paths_[active_[i]];
        if (!found_[i]) {
            depositSkyMiss(path, bounce, counters);
            continue;
        }
        shadeSurface(path, hits_[i], bounce, depth, levels, camera);
        shaded_.push_back(active_[i]);
    }
    findFeedbackVoxels();
    shadow_paths_.clear();
    shadow_rays_.clear();
    next_active_.clear();
    for (const uint32_t index : shaded_) {
        Path& path = paths_[index];
        if (endOnCache(path, counters)) continue;
        prepareLocalLight(path);
        if (path.shadow.needed) {
            shadow_paths_.push_back(index);
            shadow_rays_.push_back(path.shadow.ray);
        }
        next_active_.push_back(index);
    }
    blocked_.resize(shadow_rays_.size());
    tracer_.occludedMany(shadow_rays_.data(), shadow_rays_.size(), blocked_.data());
    counters.shadow_rays += shadow_rays_.size();
    for (size_t s = 0; s < shadow_paths_.size(); ++s) paths_[shadow_paths_[s]].shadow_blocked = blocked_[s] != 0;

    // Deposit, then continue the survivors; the batch keeps its order.
    if (bounce + 1 < settings_.max_bounces) {
        sample_paths_.assign(next_active_.begin(), next_active_.end());
        drawSamples(dimension + 2, &Path::u_lobe_rr, &Path::u_direction);
    }
    active_.clear();
    for (const uint32_t index : next_active_) {
        if (depositAndContinue(paths_[index], bounce, depth, counters)) active_.push_back(index);
    }
}

void UpdateWavefront::drawSamples(uint32_t dimension, glm::vec2 Path::*first, glm::vec2 Path::*second) {
    const size_t count = sample_paths_.size();
    sample_hashes_.resize(count);
    sample_indices_.resize(count);
    sample_values_.resize(2 * count);
    for (size_t i = 0; i < count; ++i) {
        const PixelSampler& sampler = paths_[sample_paths_[i]].sampler;
        sample_hashes_[i] = sampler.pixelHash();
        sample_indices_[i] = sampler.reversedSample();
    }
    sample2DMany(sample_hashes_.data(), sample_indices_.data(), count, dimension, sample_values_.data());
    sample2DMany(sample_hashes_.data(), sample_indices_.data(), count, dimension + 1, sample_values_.data() + count);
    for (size_t i = 0; i < count; ++i) {
        Path& path = paths_[sample_paths_[i]];
        path.*first = sample_values_[i];
        path.*second = sample_values_[count + i];
    }
}

void UpdateWavefront::shadeSurface(Path& path, const RayHit& ray_hit, uint32_t bounce, uint32_t depth,
                                   const DepositLevels& levels, const Float3& camera) const {
    path.hit = makeSurfaceHit(tracer_.scene(), ray_hit, path.ray.direction);
    const SurfaceHit& hit = path.hit;
    path.material = evaluateMaterial(tracer_.scene(), hit);
    path.wo = -path.ray.direction;
    // SHaRC keys use the geometric normal turned towards the incoming ray, so the two sides
    // of a thin wall are different voxels.
    path.key = levels.key(hit.position, hit.geometric_normal, camera);

    path.emitted = emittedRadiance(hit, path.material);
    path.emission_weight = maxComponent(path.emitted) > 0.0f
                               ? emissionMisWeight(lights_, bounce, path.previous_bsdf_pdf, path.previous_position,
                                                   path.previous_shading_normal, hit)
                               : 0.0f;

    // Cache resampling: with a random depth in [1, depth] (or, resampling at the end, once
    // `depth` vertices wait), the path may end on this voxel's resolved value.
    path.feedback_key = 0;
    path.feedback_slot = SharcCache::kNoSlot;
    const SharcSettings& sharc = cache_.settings();
    if (!sharc.cache_resampling || path.history.length == 0) return;
    const bool last_vertex = bounce + 1 >= settings_.max_bounces;
    const uint32_t resample_depth =
        sharc.resample_at_end ? (last_vertex ? 1u : depth)
                              : uint32_t(std::lround(1.0f + float(depth - 1) * path.u_select_resample.y));
    if (resample_depth > path.history.length) return;
    path.feedback_key = levels.feedbackKey(hit.position, hit.geometric_normal, camera);
}

void UpdateWavefront::findFeedbackVoxels() {
    // Two passes, each prefetching what the next one reads: the table's buckets, then the
    // resolved entries. Their cache misses (the table is far larger than any cache) overlap.
    for (const uint32_t index : shaded_) {
        Path& path = paths_[index];
        if (path.feedback_key) path.feedback_base = cache_.prefetchKey(path.feedback_key);
    }
    for (const uint32_t index : shaded_) {
        Path& path = paths_[index];
        if (!path.feedback_key) continue;
        path.feedback_slot = cache_.findSlot(path.feedback_key, path.feedback_base);
        if (path.feedback_slot != SharcCache::kNoSlot) cache_.prefetchResolved(path.feedback_slot);
    }
}

void UpdateWavefront::prepareLocalLight(Path& path) const {
    // Local radiance at this vertex: its emission and next-event direct light, evaluated with
    // throughput 1 and the update pass's roughness clamp. The shadow ray waits for the batch.
    path.bsdf.emplace(path.material, path.hit, cache_.settings().update_roughness_clamp);
    path.shadow = lights_.hasLights() ? prepareDirectLight(lights_, path.hit, *path.bsdf, path.wo,
                                                           path.u_select_resample.x, path.u_light_point)
                                      : ShadowQuery{};
}

bool UpdateWavefront::depositAndContinue(Path& path, uint32_t bounce, uint32_t depth, UpdateCounters& counters) const {
    glm::vec3 direct(0.0f);
    if (lights_.hasLights()) {
        direct = finiteOrZero(path.shadow.needed && !path.shadow_blocked ? path.shadow.unoccluded : glm::vec3(0.0f),
                              counters.non_finite);
    }
    // Its own voxel stores the full outgoing radiance (emission included, as the SDK's default
    // does); earlier vertices get the emission's BSDF-sampled share only.
    path.deposits.push_back(Deposit{path.key, path.emitted + direct, 1});
    const uint32_t own = uint32_t(path.deposits.size() - 1);
    path.history.propagate(path.emitted * path.emission_weight + direct, path.deposits);
    path.history.push(own, depth);
    if (bounce + 1 >= settings_.max_bounces) return false;

    // Russian roulette from the vertex's own albedo, then the next direction. Unlike in PathTracer,
    // the throughput from the camera has no say: every vertex's deposit estimates its own voxel,
    // whose indirect light only this continuation brings back. (With it, a path that had crossed
    // a surface reflecting nothing, such as an unlit sky dome, died at the next vertex and left
    // that voxel its direct light alone: a floor under such a dome came out 20% dark.)
    const GltfBsdf& bsdf = *path.bsdf;
    const glm::vec2 u_lobe_rr = path.u_lobe_rr;
    float survive = 1.0f;
    if (bounce >= settings_.russian_roulette_start) {
        survive = std::min(1.0f, maxComponent(bsdf.albedo(path.wo)));
        if (!(survive > 0.0f) || u_lobe_rr.y >= survive) return false;
    }
    const GltfBsdf::Sample s = bsdf.sample(path.wo, u_lobe_rr.x, path.u_direction);
    if (!s.valid) return false;
    const glm::vec3 segment = s.weight / survive;
    path.history.applyThroughput(segment);
    path.previous_bsdf_pdf = s.pdf;
    path.previous_position = path.hit.position;
    path.previous_shading_normal = path.hit.shading_normal;
    path.ray = Ray{offsetRayOrigin(path.hit.position, path.hit.geometric_normal, path.hit.ray_offset), s.wi};
    return true;
}

void UpdateWavefront::depositSkyMiss(Path& path, uint32_t bounce, UpdateCounters& counters) const {
    if (!lights_.hasSky()) return;
    // SharcUpdateMiss, with the BSDF-sampling MIS weight: the previous vertex's own next-event
    // estimate already holds the light-sampling share of the sky.
    const float weight = bounce == 0 ? 1.0f
                                     : powerHeuristic(path.previous_bsdf_pdf,
                                                      lights_.pdfSky(path.previous_position,
                                                                     path.previous_shading_normal, path.ray.direction));
    path.history.propagate(finiteOrZero(lights_.skyRadiance(path.ray.direction) * weight, counters.non_finite),
                           path.deposits);
    ++counters.sky_misses;
}

bool UpdateWavefront::endOnCache(Path& path, UpdateCounters& counters) const {
    if (path.feedback_slot == SharcCache::kNoSlot) return false;
    const ResolvedEntry& entry = cache_.resolvedAt(path.feedback_slot);
    if (!(entry.weight > 0.0)) return false;
    // The cached mean holds this voxel's full emission, but the previous vertex's light
    // sampling already counted the emission's light-sampled share.
    const glm::vec3 counted_emission = path.emitted * (1.0f - path.emission_weight);
    glm::vec3 value = entry.feedback - counted_emission;
    if (value.x < 0.0f || value.y < 0.0f || value.z < 0.0f) {
        ++counters.clamped_propagation;
        value = glm::max(value, glm::vec3(0.0f));
    }
    path.history.propagate(value, path.deposits);
    ++counters.resampled;
    return true;
}

}  // namespace sharcbake
