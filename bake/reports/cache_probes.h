// SPDX-License-Identifier: Apache-2.0
/// @file cache_probes.h
/// @brief The cache measured directly, on any scene: its voxels against a probe reference.
///
/// An image rendered through the cache mixes the cache's error with the render's own noise and
/// the reference image's (noise, pixel filter), and sees only what one camera sees. Probes see
/// the cache itself. Candidate points are spread over the scene's surfaces by area (surface
/// points); at every report checkpoint the cache's value at each candidate is recorded, at every
/// level the cache holds. Once the bake is over, the first `probes` candidates with a live voxel
/// in the final cache are the probes (points in crevices and inside closed objects, where no
/// lookup lands, are left out); each gets a reference: the radiance leaving the point,
/// path traced with the same materials and lights, `reference_samples` times, each sample towards
/// a cosine-distributed direction around the normal (a voxel averages the directions it was
/// looked up from; for Lambert surfaces the direction does not matter). Then every checkpoint's
/// record is compared with the references, per (point, level) pair.
///
/// Errors are relative to the probe's reference grey level (the mean of its channels; at least
/// a hundredth of the probes' mean, so that points in full shadow do not divide by almost
/// nothing), so dark channels of coloured surfaces weigh as much as their contribution. The squared error is split:
///  - the reference's own noise (its sample variance over `reference_samples`) is subtracted;
///  - the rest is the cache's squared error, of which the voxel's noise is estimated as the
///    per-sample variance at the probe over the voxel's effective sample count, and the
///    remainder is the cache's bias (squared). A long bake drives the noise part down; the bias
///    part is the floor it converges to (voxel size, light leaks, feedback not yet converged).
/// Every mean comes with the half-width of its 95% confidence interval over the probes.
#pragma once

#include "tracing/lights.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/runtime.h"
#include "sharcbake/scene.h"
#include "tracing/surface_points.h"
#include "tracing/tracer.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

struct ProbeSettings {
    /// Probe points given a reference; 0 = no probes. Enough that a region holding a sixth of
    /// the points has its bias to about +-2.5% in a cache whose RMS error is 20%.
    uint32_t probes = 2048;
    uint32_t reference_samples = 512;    ///< path samples per probe reference (at least kReferenceBatches)
    uint32_t candidates_per_probe = 4;   ///< surface points tried per probe (some are never live)
    uint32_t max_bounces = 1024;         ///< as `sharcbake render`
    uint32_t seed = 0x9e0be5edu;
    /// The camera whose lookups the headline measure stands for: at each probe point, the level
    /// SHaRC's lookup picks from this position. Double-sided surfaces are probed on the side
    /// that faces it.
    glm::vec3 view_position{0.0f};
};

/// A reference is this many independently scrambled batches of low-discrepancy samples: the
/// spread of their means gives the variance of the reference (the samples within a batch are
/// stratified, so their own spread would overstate it).
constexpr uint32_t kReferenceBatches = 16;

/// A probe's relative error above this is a leak (ProbeError::leaks).
constexpr double kProbeLeakRatio = 3.0;

/// Error of a cache at a set of probes, each measure relative to the probe's reference.
struct ProbeError {
    uint64_t probes = 0;                ///< (point, level) pairs measured
    uint64_t not_live = 0;              ///< pairs of the population whose voxel had no samples yet
    double mean_relative_error = 0.0;   ///< mean |C - R| / R
    double relative_mse = 0.0;          ///< mean (C - R)^2 / R^2, less the reference's noise
    double relative_mse_ci = 0.0;       ///< 95% half-width of relative_mse
    double relative_variance = 0.0;     ///< of relative_mse, the estimated noise of the voxels
    double relative_bias = 0.0;         ///< signed mean (C - R) / R
    double relative_bias_ci = 0.0;      ///< 95% half-width of relative_bias
    double reference_noise = 0.0;       ///< mean variance of the references, relative (subtracted)
    /// Pairs where the cache is off by more than kProbeLeakRatio times the reference: light
    /// leaking through a voxel that straddles a lamp, a wall or a crevice. A different failure
    /// from noise and smooth bias, and rare but large enough to swamp every mean, so counted
    /// here and left out of the measures above.
    uint64_t leaks = 0;
    double worst_leak = 0.0;  ///< the largest relative error among them

    /// relative_mse less the voxels' noise: the cache's bias, squared (may come out negative
    /// when both are near zero).
    double biasSquared() const { return relative_mse - relative_variance; }
    /// sqrt(max(0, relative_mse)): the cache's relative RMS error.
    double rmsError() const;
    /// sqrt(max(0, biasSquared())): the bias floor a longer bake converges to.
    double biasFloor() const;
};

struct ProbeLevelError {
    uint32_t level = 0;
    ProbeError error;
};

/// Probes of one region: a material (what an artist recognises in a scene), or an octant of
/// the scene's bounds (where in the scene).
struct ProbeRegionError {
    std::string name;  ///< "material 'red'", "octant x- y+ z-" (x- = below the bounds' centre)
    ProbeError error;
    /// The region's signed bias is outside its confidence interval and at least 1%: it is
    /// brighter or darker than the rest of the cache's error explains.
    bool standsOut() const;
};

/// One checkpoint's probe measure.
/// A leak at the view's level, for the report to point at.
struct ProbeLeak {
    glm::vec3 position;
    glm::vec3 normal;
    uint32_t level = 0;
    std::string material;
    glm::vec3 cache{0.0f};
    glm::vec3 reference{0.0f};
    double relative_error = 0.0;
};

struct ProbeMeasure {
    /// At each point, the level the view's lookups use (ProbeSettings::view_position); points
    /// whose voxel at that level never got samples are counted in not_live.
    ProbeError view;
    std::vector<ProbeLevelError> levels;    ///< every level the cache holds at the points, ascending
    /// At the view's level: by material in the scene's order, then by octant; empty regions left out.
    std::vector<ProbeRegionError> regions;
    std::vector<ProbeLeak> worst_leaks;     ///< the view's level, worst first, at most kWorstLeaks
    static constexpr size_t kWorstLeaks = 5;
};

class CacheProbes {
public:
    CacheProbes(const Scene& scene, const Tracer& tracer, const LightSampler& lights, ProbeSettings settings);

    bool enabled() const { return settings_.probes > 0 && !candidates_.empty(); }
    const ProbeSettings& settings() const { return settings_; }

    /// Records the cache's value at every candidate, at every level it holds, read through the
    /// runtime library. Returns the record's index.
    size_t record(const CacheView& cache);
    size_t records() const { return records_.size(); }

    /// The error of record `index` over the probes chosen from record `population` (usually the
    /// last: the cache that is written). Computes the references it needs (kept for later calls).
    ProbeMeasure measure(size_t index, size_t population);

    /// Probe points (not pairs) with a reference so far, and the time spent on references.
    uint64_t referencedPoints() const;
    double referenceSeconds() const { return reference_seconds_; }

private:
    struct Candidate {
        SurfacePoint point;
        glm::vec3 normal;  ///< the side measured (points of double-sided materials pick one)
        uint32_t material = 0;
        uint32_t view_level = 0;  ///< set by record() (the grid is the cache's)
    };
    struct Reference {
        bool done = false;
        glm::dvec3 mean{0.0};
        glm::dvec3 sample_variance{0.0};  ///< per path sample, as if they were independent
        glm::dvec3 mean_variance{0.0};    ///< of `mean`, from the spread of independent batches
    };
    struct Value {
        glm::vec3 radiance{0.0f};
        float sample_weight = 0.0f;  ///< 0: no live voxel
    };
    /// The cache at every candidate: values[level_index * candidates + candidate].
    struct Record {
        std::vector<uint32_t> levels;
        std::vector<Value> values;
        const Value& at(size_t level_index, size_t candidate, size_t candidates) const {
            return values[level_index * candidates + candidate];
        }
    };
    struct Pair {
        uint32_t candidate;
        uint32_t level;
        bool view_level;  ///< the level the view's lookup picks at this point
    };

    std::vector<Pair> population(const Record& record) const;
    void computeReferences(const std::vector<Pair>& pairs);
    /// The record's value at a pair, or nullptr when its voxel had no samples.
    const Value* valueAt(const Record& record, const Pair& pair) const;
    static double greyOf(const Reference& reference);
    ProbeError errorOf(const std::vector<Pair>& pairs, const Record& record, double grey_floor,
                       std::vector<ProbeLeak>* leaks = nullptr) const;

    const Scene& scene_;
    const Tracer& tracer_;
    const LightSampler& lights_;
    ProbeSettings settings_;
    float ray_offset_ = 1e-4f;  ///< distance from which a reference ray looks at its point
    std::vector<Candidate> candidates_;
    std::vector<Reference> references_;
    std::vector<Record> records_;
    double reference_seconds_ = 0.0;
};

}  // namespace sharcbake
