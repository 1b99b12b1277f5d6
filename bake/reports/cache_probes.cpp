// SPDX-License-Identifier: Apache-2.0
#include "reports/cache_probes.h"

#include "tracing/path_tracer.h"
#include "tracing/sampling.h"
#include "support/stopwatch.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

namespace sharcbake {
namespace {

/// z for a two-sided 95% interval of a mean over many probes.
constexpr double kZ95 = 1.96;

/// Mean and 95% half-width of a sample.
struct MeanInterval {
    double mean = 0.0;
    double half_width = 0.0;
};

MeanInterval meanInterval(const std::vector<double>& values) {
    MeanInterval m;
    if (values.empty()) return m;
    double sum = 0.0;
    for (double v : values) sum += v;
    m.mean = sum / double(values.size());
    if (values.size() > 1) {
        double squares = 0.0;
        for (double v : values) squares += (v - m.mean) * (v - m.mean);
        const double variance = squares / double(values.size() - 1);
        m.half_width = kZ95 * std::sqrt(variance / double(values.size()));
    }
    return m;
}

glm::vec3 toVec3(const float (&v)[3]) { return {v[0], v[1], v[2]}; }

/// A probe point must see this share of the scene's diagonal along its normal.
constexpr float kOpenDistance = 0.01f;

/// Relative errors divide by at least this share of the probes' mean grey level.
constexpr double kRelativeFloor = 0.01;

/// Whether a point can be looked up at all. A point in a crevice (a ceiling above a lamp 1 mm
/// under it) or inside a closed object (the floor under a block) shares voxels with the surfaces
/// around it, but no camera ray or path lands on it: the ray along its normal hits something
/// closer than `open_distance`, or the back of a one-sided surface.
bool isOpen(const Scene& scene, const Tracer& tracer, glm::vec3 origin, glm::vec3 normal, float open_distance) {
    Ray ray;
    ray.origin = origin;
    ray.direction = normal;
    RayHit hit;
    if (!tracer.intersect(ray, hit)) return true;
    if (hit.t < open_distance) return false;
    const glm::uvec3 tri = scene.triangles[hit.triangle];
    const glm::vec3 facing = glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                        scene.positions[tri.z] - scene.positions[tri.x]);
    return glm::dot(facing, normal) < 0.0f || scene.materials[scene.triangle_materials[hit.triangle]].double_sided;
}

}  // namespace

double ProbeError::rmsError() const { return std::sqrt(std::max(0.0, relative_mse)); }
double ProbeError::biasFloor() const { return std::sqrt(std::max(0.0, biasSquared())); }

bool ProbeRegionError::standsOut() const {
    return error.probes >= 2 && std::abs(error.relative_bias) >= 0.01 &&
           std::abs(error.relative_bias) > error.relative_bias_ci;
}

CacheProbes::CacheProbes(const Scene& scene, const Tracer& tracer, const LightSampler& lights, ProbeSettings settings)
    : scene_(scene), tracer_(tracer), lights_(lights), settings_(settings) {
    if (settings_.probes == 0 || scene.empty()) return;
    // A reference ray starts this close to its point, so that nothing else lies in between; far
    // above float precision at the scene's size.
    ray_offset_ = std::max(1e-4f * glm::length(scene.bounds_max - scene.bounds_min), 1e-6f);
    const uint64_t wanted = uint64_t(settings_.probes) * std::max(settings_.candidates_per_probe, 1u);
    std::vector<SurfacePoint> points =
        sampleSurfacePoints(scene, uint32_t(std::min<uint64_t>(wanted, 1u << 20)), settings_.seed);
    // The points come in area strata (triangle order); the probes are the first live ones, so
    // shuffle (Fisher-Yates, hashed: deterministic) to make any prefix spread over the scene.
    for (uint32_t i = uint32_t(points.size()); i > 1; --i) {
        const uint32_t j = uint32_t((uint64_t(hashCombine(settings_.seed, i)) * i) >> 32);
        std::swap(points[i - 1], points[j]);
    }
    candidates_.reserve(points.size());
    const float open_distance = kOpenDistance * glm::length(scene.bounds_max - scene.bounds_min);
    for (uint32_t i = 0; i < points.size(); ++i) {
        Candidate c;
        c.point = points[i];
        // Double-sided surfaces: the side that faces the view (a one-sided back is never seen;
        // the outside of a closed double-sided room faces the void, where no lookup comes from).
        const bool back = points[i].double_sided &&
                          glm::dot(points[i].normal, settings_.view_position - points[i].position) < 0.0f;
        c.normal = back ? -points[i].normal : points[i].normal;
        if (!isOpen(scene, tracer, c.point.position + ray_offset_ * c.normal, c.normal, open_distance)) continue;
        c.material = scene.triangle_materials[points[i].triangle];
        candidates_.push_back(c);
    }
    references_.resize(candidates_.size());
}

size_t CacheProbes::record(const CacheView& cache) {
    Record r;
    if (!enabled()) {
        records_.push_back(std::move(r));
        return records_.size() - 1;
    }
    for (const CacheLevel& level : cache.levels()) r.levels.push_back(level.level);
    const glm::vec3 view = settings_.view_position;
    const Float3 camera{view.x, view.y, view.z};
    const HashGridKeyer keyer(cache.gridParameters(camera));
    const size_t n = candidates_.size();
    r.values.resize(r.levels.size() * n);
    tbb::parallel_for(size_t(0), n, [&](size_t c) {
        const Float3 p{candidates_[c].point.position.x, candidates_[c].point.position.y,
                       candidates_[c].point.position.z};
        const Float3 normal{candidates_[c].normal.x, candidates_[c].normal.y, candidates_[c].normal.z};
        candidates_[c].view_level = decodeHashGridKey(cache.keyFor(p, normal, camera)).level;
        for (size_t l = 0; l < r.levels.size(); ++l) {
            const uint64_t index = cache.findKey(keyer.keyAtLevel(p, normal, r.levels[l]));
            if (index >= cache.voxelCount()) continue;
            const CacheVoxel v = cache.voxel(index);
            if (!(v.sample_weight > 0.0f)) continue;
            r.values[l * n + c] = Value{toVec3(v.radiance), v.sample_weight};
        }
    });
    records_.push_back(std::move(r));
    return records_.size() - 1;
}

std::vector<CacheProbes::Pair> CacheProbes::population(const Record& record) const {
    std::vector<Pair> pairs;
    const size_t n = candidates_.size();
    uint32_t points = 0;
    for (size_t c = 0; c < n && points < settings_.probes; ++c) {
        bool any = false, view_pair = false;
        for (size_t l = 0; l < record.levels.size(); ++l) {
            if (record.at(l, c, n).sample_weight > 0.0f) {
                const bool at_view_level = record.levels[l] == candidates_[c].view_level;
                pairs.push_back(Pair{uint32_t(c), record.levels[l], at_view_level});
                any = true;
                view_pair = view_pair || at_view_level;
            }
        }
        // A point the view's lookup misses still counts: as not live at the view's level.
        if (any && !view_pair) pairs.push_back(Pair{uint32_t(c), candidates_[c].view_level, true});
        points += any ? 1 : 0;
    }
    return pairs;
}

void CacheProbes::computeReferences(const std::vector<Pair>& pairs) {
    std::vector<uint32_t> todo;
    for (const Pair& pair : pairs) {
        if (!references_[pair.candidate].done &&
            (todo.empty() || todo.back() != pair.candidate)) {  // pairs of a candidate are adjacent
            todo.push_back(pair.candidate);
        }
    }
    if (todo.empty()) return;
    const auto start = std::chrono::steady_clock::now();
    PathTracerSettings path_settings;
    path_settings.max_bounces = settings_.max_bounces;
    const PathTracer path_tracer(tracer_, lights_, path_settings, nullptr);
    tbb::parallel_for(size_t(0), todo.size(), [&](size_t i) {
        const uint32_t c = todo[i];
        const Candidate& candidate = candidates_[c];
        const Frame frame(candidate.normal);
        TraceCounters counters;
        // Sums in a fixed order by one task: the reference does not depend on the thread count.
        const uint32_t batches = std::min(kReferenceBatches, std::max(settings_.reference_samples, 1u));
        const uint32_t per_batch = std::max(settings_.reference_samples / batches, 1u);
        glm::dvec3 sum(0.0), sum_squares(0.0), batch_sum(0.0), batch_squares(0.0);
        uint32_t samples = 0, used_batches = 0;
        for (uint32_t batch = 0; batch < batches; ++batch) {
            glm::dvec3 in_batch(0.0);
            uint32_t batch_samples = 0;
            for (uint32_t s = 0; s < per_batch; ++s) {
                // Each batch scrambles the sequence with a hash of its own: independent batches.
                PixelSampler sampler(settings_.seed, c * kReferenceBatches + batch, s);
                const glm::vec3 towards_viewer = frame.toWorld(sampleCosineHemisphere(sampler.next2D()));
                sampler.startDimension(PathTracer::kFirstBounceDimension);
                Ray ray;
                ray.origin = candidate.point.position + ray_offset_ * towards_viewer;
                ray.direction = -towards_viewer;
                ray.t_max = 2.0f * ray_offset_;
                const glm::dvec3 L(path_tracer.radiance(ray, sampler, counters));
                if (!std::isfinite(L.x) || !std::isfinite(L.y) || !std::isfinite(L.z)) continue;
                in_batch += L;
                sum_squares += L * L;
                ++batch_samples;
            }
            if (batch_samples == 0) continue;
            sum += in_batch;
            samples += batch_samples;
            const glm::dvec3 batch_mean = in_batch / double(batch_samples);
            batch_sum += batch_mean;
            batch_squares += batch_mean * batch_mean;
            ++used_batches;
        }
        Reference& reference = references_[c];
        if (samples > 0) {
            reference.mean = sum / double(samples);
            if (samples > 1) {
                reference.sample_variance =
                    glm::max((sum_squares - sum * reference.mean) / double(samples - 1), glm::dvec3(0.0));
            }
            if (used_batches > 1) {
                const glm::dvec3 batch_mean = batch_sum / double(used_batches);
                const glm::dvec3 spread = (batch_squares - batch_sum * batch_mean) / double(used_batches - 1);
                reference.mean_variance = glm::max(spread / double(used_batches), glm::dvec3(0.0));
            }
        }
        reference.done = true;
    });
    reference_seconds_ += secondsSince(start);
}

const CacheProbes::Value* CacheProbes::valueAt(const Record& record, const Pair& pair) const {
    const auto level = std::lower_bound(record.levels.begin(), record.levels.end(), pair.level);
    if (level == record.levels.end() || *level != pair.level) return nullptr;
    const Value& value = record.at(size_t(level - record.levels.begin()), pair.candidate, candidates_.size());
    return value.sample_weight > 0.0f ? &value : nullptr;
}

double CacheProbes::greyOf(const Reference& reference) {
    return (reference.mean.x + reference.mean.y + reference.mean.z) / 3.0;
}

ProbeError CacheProbes::errorOf(const std::vector<Pair>& pairs, const Record& record, double grey_floor,
                                std::vector<ProbeLeak>* leaks) const {
    ProbeError e;
    std::vector<double> absolute, squared, signed_error;
    double variance_sum = 0.0, reference_noise_sum = 0.0;
    for (const Pair& pair : pairs) {
        const Value* value = valueAt(record, pair);
        if (!value) {
            ++e.not_live;
            continue;
        }
        const Reference& reference = references_[pair.candidate];
        const double grey = std::max(greyOf(reference), grey_floor);
        if (!(grey > 0.0)) continue;  // a black scene: no relative error to speak of
        double abs_sum = 0.0, square_sum = 0.0, signed_sum = 0.0, noise = 0.0, variance = 0.0;
        for (int ch = 0; ch < 3; ++ch) {
            const double d = (double(value->radiance[ch]) - reference.mean[ch]) / grey;
            abs_sum += std::abs(d);
            square_sum += d * d;
            signed_sum += d;
            noise += reference.mean_variance[ch] / (grey * grey);
            variance += reference.sample_variance[ch] / (grey * grey) / double(value->sample_weight);
        }
        if (abs_sum / 3.0 > kProbeLeakRatio) {
            ++e.leaks;
            e.worst_leak = std::max(e.worst_leak, abs_sum / 3.0);
            if (leaks) {
                const Candidate& candidate = candidates_[pair.candidate];
                leaks->push_back(ProbeLeak{candidate.point.position, candidate.normal, pair.level,
                                           scene_.materials[candidate.material].name, value->radiance,
                                           glm::vec3(reference.mean), abs_sum / 3.0});
            }
            continue;
        }
        absolute.push_back(abs_sum / 3.0);
        // Unbiased for the cache's own squared error: E[(C - R)^2] = (C - L)^2 + Var(R).
        squared.push_back((square_sum - noise) / 3.0);
        signed_error.push_back(signed_sum / 3.0);
        reference_noise_sum += noise / 3.0;
        variance_sum += variance / 3.0;
    }
    e.probes = absolute.size();
    if (e.probes == 0) return e;
    e.mean_relative_error = meanInterval(absolute).mean;
    const MeanInterval mse = meanInterval(squared);
    e.relative_mse = mse.mean;
    e.relative_mse_ci = mse.half_width;
    const MeanInterval bias = meanInterval(signed_error);
    e.relative_bias = bias.mean;
    e.relative_bias_ci = bias.half_width;
    e.relative_variance = variance_sum / double(e.probes);
    e.reference_noise = reference_noise_sum / double(e.probes);
    return e;
}

ProbeMeasure CacheProbes::measure(size_t index, size_t population_index) {
    ProbeMeasure m;
    if (!enabled() || index >= records_.size() || population_index >= records_.size()) return m;
    const std::vector<Pair> pairs = population(records_[population_index]);
    computeReferences(pairs);
    const Record& record = records_[index];
    // Points in shadow (a block's foot on the floor) would divide by almost nothing: errors are
    // relative to at least a hundredth of the probes' mean grey level, as image errors are to a
    // hundredth of the reference's mean.
    double grey_sum = 0.0;
    for (const Pair& pair : pairs) grey_sum += greyOf(references_[pair.candidate]);
    const double grey_floor = pairs.empty() ? 0.0 : kRelativeFloor * grey_sum / double(pairs.size());
    const auto select = [&pairs](auto&& keep) {
        std::vector<Pair> kept;
        for (const Pair& pair : pairs) {
            if (keep(pair)) kept.push_back(pair);
        }
        return kept;
    };
    m.view = errorOf(select([](const Pair& pair) { return pair.view_level; }), record, grey_floor, &m.worst_leaks);
    std::stable_sort(m.worst_leaks.begin(), m.worst_leaks.end(),
                     [](const ProbeLeak& a, const ProbeLeak& b) { return a.relative_error > b.relative_error; });
    if (m.worst_leaks.size() > ProbeMeasure::kWorstLeaks) m.worst_leaks.resize(ProbeMeasure::kWorstLeaks);
    for (uint32_t level : records_[population_index].levels) {
        // Only pairs live in the population's record: a level the view needs but the cache
        // lacks would be all misses.
        const std::vector<Pair> at_level = select([&](const Pair& pair) {
            return pair.level == level && (!pair.view_level || valueAt(records_[population_index], pair));
        });
        m.levels.push_back(ProbeLevelError{level, errorOf(at_level, record, grey_floor)});
    }
    // A material is named by its name where that is its own; by its index too where the name is
    // empty or shared (CAD exports name ten materials "Material_20"), so regions stay apart.
    std::map<std::string, uint32_t> name_uses;
    for (const Material& material : scene_.materials) ++name_uses[material.name];
    for (uint32_t material = 0; material < scene_.materials.size(); ++material) {
        const std::vector<Pair> in_region = select([&](const Pair& pair) {
            return pair.view_level && candidates_[pair.candidate].material == material;
        });
        if (in_region.empty()) continue;
        const std::string& name = scene_.materials[material].name;
        const std::string label = name.empty()            ? "material " + std::to_string(material)
                                  : name_uses[name] == 1u ? "material '" + name + "'"
                                                          : "material " + std::to_string(material) + " '" + name + "'";
        m.regions.push_back(ProbeRegionError{label, errorOf(in_region, record, grey_floor)});
    }
    const glm::vec3 centre = 0.5f * (scene_.bounds_min + scene_.bounds_max);
    for (uint32_t octant = 0; octant < 8; ++octant) {
        const std::vector<Pair> in_octant = select([&](const Pair& pair) {
            const glm::vec3 p = candidates_[pair.candidate].point.position;
            const uint32_t of = (p.x >= centre.x ? 1u : 0u) | (p.y >= centre.y ? 2u : 0u) | (p.z >= centre.z ? 4u : 0u);
            return pair.view_level && of == octant;
        });
        if (in_octant.empty()) continue;
        const std::string name = std::string("octant x") + (octant & 1u ? "+" : "-") + " y" + (octant & 2u ? "+" : "-") +
                                 " z" + (octant & 4u ? "+" : "-");
        m.regions.push_back(ProbeRegionError{name, errorOf(in_octant, record, grey_floor)});
    }
    return m;
}

uint64_t CacheProbes::referencedPoints() const {
    return uint64_t(std::count_if(references_.begin(), references_.end(), [](const Reference& r) { return r.done; }));
}

}  // namespace sharcbake
