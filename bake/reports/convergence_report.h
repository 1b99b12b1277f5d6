// SPDX-License-Identifier: Apache-2.0
/// @file convergence_report.h
/// @brief Error against run time during a bake (`bake --report`, `--target-error`).
///
/// At checkpoints spaced logarithmically in iterations the bake is paused and measured:
/// - probe error: the cache's voxels against a path-traced reference at surface points, per
///   level and per material, split into the voxels' noise and the bias floor (cache_probes.h);
///   works on any scene;
/// - voxel error: every live voxel against the scene's known radiance (furnace rooms);
/// - image error: a render through the cache as it stands (what `render --cache` would give
///   with a cache file written now) against a reference image of the same camera;
/// and, once the bake is over, plain path tracing of the same view at growing sample counts,
/// so both can be compared at equal time. Evaluation time is kept out of the bake's time.
#pragma once

#include "reports/cache_probes.h"
#include "reports/image_error.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "sharc/sharc_cache.h"
#include "sharcbake/image.h"
#include "sharcbake/scene.h"
#include "tracing/tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace sharcbake {

/// The next checkpoint after `done` iterations: round(2^(k/2)) for k = 0, 1, 2, ... (two per
/// octave: 1, 2, 3, 4, 6, 8, 11, 16, 23, 32, ...), so a long bake costs few evaluations.
uint32_t nextReportCheckpoint(uint32_t done);

/// Error of every live voxel (one with samples) against a known radiance, per voxel the mean
/// over channels of |L - L_known| / L_known.
struct VoxelError {
    uint64_t voxels = 0;
    double mean_relative = 0.0;
    double rms_relative = 0.0;
    double max_relative = 0.0;
    double within_1_percent = 0.0;  ///< share of voxels with relative error <= 0.01
};
VoxelError measureVoxelError(const CacheData& cache, glm::vec3 known_radiance);

/// One evaluation during the bake.
struct ConvergenceRow {
    uint32_t iteration = 0;
    double bake_seconds = 0.0;    ///< bake time so far, evaluation excluded
    double render_seconds = 0.0;  ///< time of the evaluation render through the cache (0 without one)
    uint64_t rays = 0;            ///< bake rays so far (path segments + shadow rays)
    uint64_t live_voxels = 0;
    std::optional<VoxelError> voxel;
    std::optional<ImageComparison> image;
    /// image->relative_mse split into the evaluation render's own noise (it falls with
    /// --report-spp, not with bake time) and the rest: the cache's own error, plus the
    /// reference's noise (none without a --report-spp of at least 2).
    std::optional<RelativeMseSplit> image_split;
    /// The cache against the probe reference. Filled for every row once the bake is over, over
    /// the probes of the final cache (ConvergenceEvaluator::finishProbes); during the bake only
    /// where --target-error needs it, over the probes live at the time.
    std::optional<ProbeMeasure> probes;
    size_t probe_record = SIZE_MAX;  ///< the cache's values at the probes (CacheProbes::record)

    /// The error --target-error compares: the voxel mean relative error where the scene has a
    /// known radiance, else the probes' mean relative error, else the image's.
    std::optional<double> primaryError() const;
};

/// Plain path tracing of the evaluation view with `samples_per_pixel` samples.
struct PlainPathTracingRow {
    uint32_t samples_per_pixel = 0;
    double seconds = 0.0;
    uint64_t rays = 0;
    ImageComparison image;
};

/// The view every evaluation renders.
struct EvaluationView {
    Camera camera;
    int width = 128;
    int height = 128;
    uint32_t samples_per_pixel = 16;  ///< for the render through the cache
    /// As `sharcbake render`: Russian roulette ends paths, the cap only bounds the worst case
    /// (a low cap would bias plain path tracing in a furnace).
    uint32_t max_bounces = PathTracerSettings{}.max_bounces;
};

class ConvergenceEvaluator {
public:
    /// @param reference the image to compare with (same size as the view), or none: then the
    ///        image measure uses the scene's known radiance in every pixel, or is left out.
    /// @param probe_settings probes.probes == 0 leaves the probe measure out.
    /// @param probes_during_bake measure the probes at every checkpoint (for --target-error);
    ///        otherwise only finishProbes() does.
    ConvergenceEvaluator(const Scene& scene, const Tracer& tracer, const LightSampler& lights, EvaluationView view,
                         std::optional<Image> reference, ProbeSettings probe_settings = {},
                         bool probes_during_bake = false);

    bool measuresVoxels() const { return known_radiance_.has_value(); }
    bool measuresImage() const { return reference_.has_value(); }
    bool measuresProbes() const { return probes_.enabled(); }
    bool measuresAnything() const { return measuresVoxels() || measuresImage() || measuresProbes(); }
    const EvaluationView& view() const { return view_; }
    const CacheProbes& probes() const { return probes_; }

    /// Measures the cache as it stands (the row's iteration, time, rays and voxel count are
    /// the caller's to fill).
    ConvergenceRow evaluate(const SharcCache& cache);

    /// Measures every row's probes over the probes of the last row's cache (the one written),
    /// so that every checkpoint is measured on the same points.
    void finishProbes(std::vector<ConvergenceRow>& rows);

    /// Plain path tracing of the view at 1, 2, 4, ... samples per pixel, each level adding
    /// samples to the last, until it has run `until_seconds` or reached `max_samples_per_pixel`.
    /// `reference_floor`, when given, receives the reference's own floor: the last render's
    /// relative MSE against the reference less that render's noise (from its two independent
    /// halves), i.e. the reference's noise plus whatever differs between the renderers (pixel
    /// filter, materials). No image error below it can be told apart from the reference's.
    std::vector<PlainPathTracingRow> plainPathTracing(double until_seconds, uint32_t max_samples_per_pixel,
                                                      std::optional<RelativeMseSplit>* reference_floor = nullptr) const;

private:
    /// The view path traced at `samples_per_pixel`, through `cache` when given (paths end on
    /// its hits); ray counts are added to `counters` when given.
    Image renderView(const RadianceCache* cache, uint32_t samples_per_pixel, uint32_t seed,
                     TraceCounters* counters = nullptr) const;

    const Tracer& tracer_;
    const LightSampler& lights_;
    EvaluationView view_;
    std::optional<glm::vec3> known_radiance_;
    std::optional<Image> reference_;
    /// Pixels whose centre ray hits a surface that does not emit (ImageComparison's mask).
    std::vector<uint8_t> cache_mask_;
    CacheProbes probes_;
    bool probes_during_bake_ = false;
};

/// The cache's bias floor, fitted over the checkpoints: mean square error at the probes
/// mse_k = floor^2 + noise_scale * v_k, v_k the voxel-noise estimate of checkpoint k (which
/// falls with the voxels' sample counts). The estimate divides the per-sample variance of a
/// reference path by the voxel's sample count; the cache's own samples end on the cache and are
/// less noisy, so the fit scales it (noise_scale, at most 1) rather than trusting it.
/// Weighted by each checkpoint's interval; checkpoints share voxels, so the floor's interval
/// is a lower bound of its uncertainty.
struct ProbeFloorFit {
    double floor_squared = 0.0;     ///< relative MSE that more iterations do not remove
    double floor_squared_ci = 0.0;  ///< 95% half-width
    double noise_scale = 1.0;
    size_t checkpoints = 0;         ///< used by the fit

    double floor() const { return std::sqrt(std::max(0.0, floor_squared)); }
};

/// Fits the floor over the rows with probes; the rows' voxel noise (ProbeError::
/// relative_variance, all levels and materials) is scaled by the fitted noise_scale. Nothing
/// when fewer than 3 rows have probes.
std::optional<ProbeFloorFit> fitProbeFloor(std::vector<ConvergenceRow>& rows);

/// Whether more iterations would still lower the cache's error at the probes, and why. Judged at
/// the last checkpoint with probes:
/// - not converged while more than 5% of the probe points have no voxel yet (more iterations or
///   camera positions reach them; their error is not in the RMS at all);
/// - not converged while the error still falls: the relative MSE of the checkpoint at about half
///   the iterations is above the last's by more than their combined 95% intervals (a floor fitted
///   over a few early checkpoints takes early bias for a floor: 16 iterations of the Cornell box
///   fitted 33%, 128 iterations 17%);
/// - converged where the RMS error is within 1.25x the fitted floor;
/// - else not converged: the voxels' noise still dominates.
struct ProbeVerdict {
    bool converged = false;
    std::string reason;  ///< "converged, more iterations would not help", or what would still fall
};
ProbeVerdict probeVerdict(const std::vector<ConvergenceRow>& rows, const ProbeFloorFit& fit);

/// Everything `--report DIR` writes.
struct ConvergenceReport {
    std::string scene;
    std::string reference;  ///< the reference image's path, "known radiance" or "probe reference"
    EvaluationView view;
    std::vector<ConvergenceRow> rows;
    std::vector<PlainPathTracingRow> plain;
    std::optional<RelativeMseSplit> reference_floor;  ///< see plainPathTracing()
    std::optional<ProbeFloorFit> probe_floor;
    double evaluation_seconds = 0.0;  ///< all evaluation time, kept out of the bake's
    std::optional<double> target_error;
};

/// The plain path tracing error at `seconds`, interpolated log-log between its rows (none
/// outside their range).
std::optional<double> plainErrorAt(const std::vector<PlainPathTracingRow>& plain, double seconds);

/// The files a report writes into its folder (the tables, the plot, its script and gnuplot's log),
/// so a command can check each against its other outputs before it bakes.
inline constexpr const char* kConvergenceReportFiles[] = {"convergence.csv",  "plain_path_tracing.csv",
                                                          "convergence.json", "convergence.gp",
                                                          "convergence.png",  "convergence.gnuplot.log"};

/// Writes DIR/convergence.csv, DIR/plain_path_tracing.csv and DIR/convergence.json. Throws
/// std::runtime_error naming the file that could not be written.
void writeConvergenceTables(const std::string& dir, const ConvergenceReport& report);

/// Writes DIR/convergence.gp and runs gnuplot on it to draw DIR/convergence.png. Returns an
/// empty string, or why there is no plot (gnuplot missing or failing); the tables stand alone.
std::string plotConvergence(const std::string& dir, const ConvergenceReport& report);

}  // namespace sharcbake
