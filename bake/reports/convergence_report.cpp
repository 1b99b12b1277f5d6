// SPDX-License-Identifier: Apache-2.0
#include "reports/convergence_report.h"

#include "sharcbake/cache_file.h"

#include "sharc/cache_query.h"
#include "support/json.h"
#include "tracing/path_tracer.h"
#include "tracing/render.h"
#include "support/stopwatch.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <cerrno>

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace sharcbake {
namespace {

// Evaluation renders use seeds of their own, so that a reference rendered by `sharcbake render`
// with its default seed (0) shares no samples with them: shared samples would correlate the
// errors and understate them.
constexpr uint32_t kCachedRenderSeed = 0x5eba7e01u;
constexpr uint32_t kPlainRenderSeed = 0x9a1e0000u;

/// Empty for a missing value: spreadsheets and gnuplot both read that as "no data".
std::string csvNumber(std::optional<double> value) {
    if (!value || !std::isfinite(*value)) return "";  // empty, as unmeasured (a black reference's bias)
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", *value);
    return text;
}

/// `text` as a gnuplot string literal: single quotes take no escapes except a doubled quote;
/// control characters (possible in a file name) become '?' so the script stays one line each.
std::string gnuplotString(const std::string& text) {
    std::string quoted = "'";
    for (const char c : text) {
        if (c == '\'') {
            quoted += "''";
        } else {
            quoted += static_cast<unsigned char>(c) < 0x20 ? '?' : c;
        }
    }
    return quoted + "'";
}

/// Writes a finished table with the outputs' atomic, checked write (cache_file.h).
void finishWriting(const std::ostringstream& out, const std::string& path) {
    const std::string text = out.str();
    std::string message;
    if (writeFileAtomically(path, text.data(), text.size(), &message) != CacheFileStatus::kOk) {
        throw std::runtime_error(message);
    }
}

Json imageComparisonJson(const ImageComparison& e) {
    return {{"relative_mse", jsonNumber(e.relative_mse)},
            {"mean_relative_error", jsonNumber(e.mean_relative_error)},
            {"relative_bias", jsonNumber(e.relative_bias)},
            {"tile_mean_relative_error", jsonNumber(e.tile_mean_relative_error)},
            // null over an empty mask (every pixel emits), which would otherwise read as no error
            {"masked_mean_relative_error", e.masked_pixels ? jsonNumber(e.masked_mean_relative_error) : Json(nullptr)},
            {"masked_relative_mse", e.masked_pixels ? jsonNumber(e.masked_relative_mse) : Json(nullptr)},
            {"masked_pixels", e.masked_pixels}};
}

Json probeErrorJson(const ProbeError& e) {
    return {{"probes", e.probes},
            {"not_live", e.not_live},
            {"mean_relative_error", jsonNumber(e.mean_relative_error)},
            {"rms_error", jsonNumber(e.rmsError())},
            {"relative_mse", jsonNumber(e.relative_mse)},
            {"relative_mse_ci95", jsonNumber(e.relative_mse_ci)},
            {"voxel_noise", jsonNumber(e.relative_variance)},
            {"bias_squared", jsonNumber(e.biasSquared())},
            {"bias_floor", jsonNumber(e.biasFloor())},
            {"relative_bias", jsonNumber(e.relative_bias)},
            {"relative_bias_ci95", jsonNumber(e.relative_bias_ci)},
            {"reference_noise", jsonNumber(e.reference_noise)},
            {"leaks", e.leaks},
            {"worst_leak", jsonNumber(e.worst_leak)}};
}

Json probeMeasureJson(const ProbeMeasure& m) {
    Json levels = Json::array(), regions = Json::array(), leaks = Json::array();
    for (const ProbeLevelError& level : m.levels) {
        levels.push_back({{"level", level.level}, {"error", probeErrorJson(level.error)}});
    }
    for (const ProbeRegionError& region : m.regions) {
        regions.push_back(
            {{"name", region.name}, {"stands_out", region.standsOut()}, {"error", probeErrorJson(region.error)}});
    }
    for (const ProbeLeak& leak : m.worst_leaks) {
        leaks.push_back({{"position", jsonVec3(leak.position)},
                         {"normal", jsonVec3(leak.normal)},
                         {"level", leak.level},
                         {"material", leak.material},
                         {"cache", jsonVec3(leak.cache)},
                         {"reference", jsonVec3(leak.reference)},
                         {"relative_error", jsonNumber(leak.relative_error)}});
    }
    return {{"view", probeErrorJson(m.view)}, {"levels", levels}, {"regions", regions}, {"worst_leaks", leaks}};
}

}  // namespace

uint32_t nextReportCheckpoint(uint32_t done) {
    for (int k = 0; k < 64; ++k) {
        const double candidate = std::round(std::exp2(0.5 * k));
        if (candidate > double(done)) return candidate >= 4294967295.0 ? UINT32_MAX : uint32_t(candidate);
    }
    return UINT32_MAX;
}

VoxelError measureVoxelError(const CacheData& cache, glm::vec3 known_radiance) {
    VoxelError e;
    double sum = 0.0, sum_squares = 0.0;
    uint64_t within = 0;
    for (const CacheVoxel& v : cache.voxels) {
        if (!(v.sample_weight > 0.0f)) continue;
        double relative = 0.0;
        for (int c = 0; c < 3; ++c) {
            relative += std::abs(double(v.radiance[c]) - double(known_radiance[c])) / double(known_radiance[c]);
        }
        relative /= 3.0;
        if (!std::isfinite(relative)) relative = 1.0;  // cannot happen for a valid cache; never hide it
        ++e.voxels;
        sum += relative;
        sum_squares += relative * relative;
        e.max_relative = std::max(e.max_relative, relative);
        within += relative <= 0.01 ? 1 : 0;
    }
    if (e.voxels > 0) {
        const double n = double(e.voxels);
        e.mean_relative = sum / n;
        e.rms_relative = std::sqrt(sum_squares / n);
        e.within_1_percent = double(within) / n;
    }
    return e;
}

std::optional<double> ConvergenceRow::primaryError() const {
    if (voxel && voxel->voxels > 0) return voxel->mean_relative;
    if (probes && probes->view.probes > 0) return probes->view.mean_relative_error;
    if (image) return image->mean_relative_error;
    return std::nullopt;
}

ConvergenceEvaluator::ConvergenceEvaluator(const Scene& scene, const Tracer& tracer, const LightSampler& lights,
                                           EvaluationView view, std::optional<Image> reference,
                                           ProbeSettings probe_settings, bool probes_during_bake)
    : tracer_(tracer),
      lights_(lights),
      view_(view),
      known_radiance_(scene.known_radiance),
      probes_(scene, tracer, lights, probe_settings),
      probes_during_bake_(probes_during_bake) {
    if (reference) {
        if (reference->width != view_.width || reference->height != view_.height) {
            throw std::invalid_argument("the reference image is " + std::to_string(reference->width) + "x" +
                                        std::to_string(reference->height) + " but the evaluation view is " +
                                        std::to_string(view_.width) + "x" + std::to_string(view_.height));
        }
        reference_ = std::move(reference);
    } else if (known_radiance_) {
        // A furnace room: every pixel sees a surface of the known radiance.
        Image known;
        known.width = view_.width;
        known.height = view_.height;
        known.pixels.assign(size_t(view_.width) * size_t(view_.height), *known_radiance_);
        reference_ = std::move(known);
    }
    if (reference_) {
        const CameraRays rays(view_.camera, view_.width, view_.height);
        cache_mask_.assign(size_t(view_.width) * size_t(view_.height), 0);
        for (int y = 0; y < view_.height; ++y) {
            for (int x = 0; x < view_.width; ++x) {
                RayHit hit;
                if (!tracer.intersect(rays.generate(x, y, glm::vec2(0.5f)), hit)) continue;
                const Material& material = scene.materials[scene.triangle_materials[hit.triangle]];
                cache_mask_[size_t(y) * size_t(view_.width) + size_t(x)] = material.isEmissive() ? 0 : 1;
            }
        }
    }
}

ConvergenceRow ConvergenceEvaluator::evaluate(const SharcCache& cache) {
    ConvergenceRow row;
    if (!measuresAnything()) return row;
    // Exactly what a cache file written now would hold, so the measure is what users get.
    CacheData data = toCacheData(cache);
    row.live_voxels = data.voxels.size();
    if (known_radiance_) row.voxel = measureVoxelError(data, *known_radiance_);
    // Every measure reads the cache through the runtime library, as an engine would.
    const BakedCache baked(data, view_.camera.position);
    if (probes_.enabled()) {
        row.probe_record = probes_.record(baked.view());
        if (probes_during_bake_) row.probes = probes_.measure(row.probe_record, row.probe_record);
    }
    if (reference_) {
        const auto start = std::chrono::steady_clock::now();
        // Two independent halves: their mean is the render, their difference its own noise.
        const uint32_t spp = view_.samples_per_pixel;
        const uint32_t first_half = spp / 2, second_half = spp - spp / 2;
        Image image = renderView(&baked, std::max(first_half, 1u), kCachedRenderSeed);
        if (first_half > 0) {
            const Image second = renderView(&baked, second_half, kCachedRenderSeed + 1);
            row.image_split = splitRelativeMse(image, first_half, second, second_half, *reference_);
            for (size_t i = 0; i < image.pixels.size(); ++i) {
                image.pixels[i] = (image.pixels[i] * float(first_half) + second.pixels[i] * float(second_half)) /
                                  float(spp);
            }
        }
        row.render_seconds = secondsSince(start);
        row.image = compareImages(image, *reference_, &cache_mask_);
    }
    return row;
}

void ConvergenceEvaluator::finishProbes(std::vector<ConvergenceRow>& rows) {
    if (!probes_.enabled() || rows.empty() || rows.back().probe_record == SIZE_MAX) return;
    const size_t population = rows.back().probe_record;
    for (ConvergenceRow& row : rows) {
        if (row.probe_record != SIZE_MAX) row.probes = probes_.measure(row.probe_record, population);
    }
}

Image ConvergenceEvaluator::renderView(const RadianceCache* cache, uint32_t samples_per_pixel, uint32_t seed,
                                       TraceCounters* counters) const {
    PathTracerSettings settings;
    settings.max_bounces = view_.max_bounces;
    const PathTracer path_tracer(tracer_, lights_, settings, cache);
    TraceCounters ignored;
    TraceCounters& count = counters ? *counters : ignored;
    return renderImage(
        CameraRays(view_.camera, view_.width, view_.height),
        ImageRenderSettings{view_.width, view_.height, samples_per_pixel, seed},
        [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, count); }, nullptr);
}

std::vector<PlainPathTracingRow> ConvergenceEvaluator::plainPathTracing(
    double until_seconds, uint32_t max_samples_per_pixel, std::optional<RelativeMseSplit>* reference_floor) const {
    std::vector<PlainPathTracingRow> rows;
    if (!reference_) return rows;
    TraceCounters counters;
    std::vector<glm::dvec3> sum(size_t(view_.width) * size_t(view_.height), glm::dvec3(0.0));
    uint32_t total_samples = 0;
    double seconds = 0.0;
    // Levels of 1, 1, 2, 4, ... samples per pixel, each with a seed of its own, give 1, 2, 4,
    // 8, ... samples in all: no sample is rendered twice.
    for (uint32_t level = 0; total_samples < max_samples_per_pixel; ++level) {
        const uint32_t batch = std::min(std::max(total_samples, 1u), max_samples_per_pixel - total_samples);
        const auto start = std::chrono::steady_clock::now();
        const Image image = renderView(nullptr, batch, kPlainRenderSeed + level, &counters);
        Image mean = image;
        // The mean so far and this level are independent renders: the split of their mean.
        if (reference_floor && total_samples > 0) {
            Image previous = image;
            for (size_t i = 0; i < sum.size(); ++i) previous.pixels[i] = glm::vec3(sum[i] / double(total_samples));
            *reference_floor = splitRelativeMse(previous, total_samples, image, batch, *reference_);
        }
        total_samples += batch;
        for (size_t i = 0; i < sum.size(); ++i) {
            sum[i] += glm::dvec3(image.pixels[i]) * double(batch);
            mean.pixels[i] = glm::vec3(sum[i] / double(total_samples));
        }
        seconds += secondsSince(start);
        PlainPathTracingRow row;
        row.samples_per_pixel = total_samples;
        row.seconds = seconds;
        const TraceCounts counts = counters.total();
        row.rays = counts.closest_hit_rays + counts.shadow_rays;
        row.image = compareImages(mean, *reference_, &cache_mask_);
        rows.push_back(row);
        if (seconds >= until_seconds) break;
    }
    return rows;
}

std::optional<ProbeFloorFit> fitProbeFloor(std::vector<ConvergenceRow>& rows) {
    // Weighted least squares of y = B + a x over the checkpoints, w = 1 / sigma^2.
    double s = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
    size_t used = 0;
    for (const ConvergenceRow& r : rows) {
        if (!r.probes || r.probes->view.probes < 2) continue;
        const ProbeError& e = r.probes->view;
        const double sigma = std::max(e.relative_mse_ci / 1.96, 1e-12);
        const double w = 1.0 / (sigma * sigma);
        s += w;
        sx += w * e.relative_variance;
        sy += w * e.relative_mse;
        sxx += w * e.relative_variance * e.relative_variance;
        sxy += w * e.relative_variance * e.relative_mse;
        ++used;
    }
    if (used < 3) return std::nullopt;
    ProbeFloorFit fit;
    fit.checkpoints = used;
    const double determinant = s * sxx - sx * sx;
    double a = determinant > 0.0 ? (s * sxy - sx * sy) / determinant : 0.0;
    a = std::clamp(a, 0.0, 1.0);
    double b = (sy - a * sx) / s;
    if (b < 0.0) {  // no floor: all of it is noise
        b = 0.0;
        a = sxx > 0.0 ? std::clamp(sxy / sxx, 0.0, 1.0) : 0.0;
    }
    fit.floor_squared = b;
    fit.noise_scale = a;
    // Variance of the intercept: (X^T W X)^-1 [0][0] = sxx / determinant.
    fit.floor_squared_ci = 1.96 * std::sqrt(determinant > 0.0 ? sxx / determinant : 1.0 / s);
    for (ConvergenceRow& r : rows) {
        if (!r.probes) continue;
        r.probes->view.relative_variance *= a;
        for (ProbeLevelError& level : r.probes->levels) level.error.relative_variance *= a;
        for (ProbeRegionError& region : r.probes->regions) region.error.relative_variance *= a;
    }
    return fit;
}

ProbeVerdict probeVerdict(const std::vector<ConvergenceRow>& rows, const ProbeFloorFit& fit) {
    std::vector<const ConvergenceRow*> measured;
    for (const ConvergenceRow& r : rows) {
        if (r.probes && r.probes->view.probes > 0) measured.push_back(&r);
    }
    if (measured.empty()) return {false, "no probe has a voxel yet"};
    const ConvergenceRow& last = *measured.back();
    const ProbeError& end = last.probes->view;
    char text[200];
    const uint64_t population = end.probes + end.not_live;
    if (double(end.not_live) > 0.05 * double(population)) {
        std::snprintf(text, sizeof text,
                      "not converged: %.3g%% of the probes have no voxel yet (more iterations or camera "
                      "positions reach them)",
                      100.0 * double(end.not_live) / double(population));
        return {false, text};
    }
    // The checkpoint nearest half the last one's iterations (at or below it).
    const ConvergenceRow* half = nullptr;
    for (const ConvergenceRow* r : measured) {
        if (2 * uint64_t(r->iteration) <= uint64_t(last.iteration)) half = r;
    }
    if (half && half != &last) {
        const ProbeError& mid = half->probes->view;
        const double margin = std::sqrt(mid.relative_mse_ci * mid.relative_mse_ci +
                                        end.relative_mse_ci * end.relative_mse_ci);
        if (mid.relative_mse - end.relative_mse > margin) {
            std::snprintf(text, sizeof text,
                          "not converged: the RMS error still falls (%.3g%% at %u iterations, %.3g%% at %u), more "
                          "iterations would lower it",
                          100.0 * mid.rmsError(), half->iteration, 100.0 * end.rmsError(), last.iteration);
            return {false, text};
        }
    }
    if (end.rmsError() <= 1.25 * fit.floor()) return {true, "converged, more iterations would not help"};
    return {false, "more iterations would still lower its noise"};
}

std::optional<double> plainErrorAt(const std::vector<PlainPathTracingRow>& plain, double seconds) {
    for (size_t i = 1; i < plain.size(); ++i) {
        const PlainPathTracingRow& a = plain[i - 1];
        const PlainPathTracingRow& b = plain[i];
        if (seconds < a.seconds || seconds > b.seconds) continue;
        const double ea = a.image.mean_relative_error, eb = b.image.mean_relative_error;
        if (!(a.seconds > 0.0) || !(ea > 0.0) || !(eb > 0.0) || b.seconds <= a.seconds) return eb;
        const double t = std::log(seconds / a.seconds) / std::log(b.seconds / a.seconds);
        return std::exp(std::log(ea) + t * (std::log(eb) - std::log(ea)));
    }
    return std::nullopt;
}

namespace {

void writeCheckpointsCsv(const std::string& dir, const ConvergenceReport& report) {
    const std::string csv_path = dir + "/convergence.csv";
    std::ostringstream csv;
    csv << "iteration,bake_seconds,render_seconds,total_seconds,rays,live_voxels,"
           "voxel_mean_relative_error,voxel_rms_relative_error,voxel_max_relative_error,voxel_within_1_percent,"
           "image_relative_mse,image_mean_relative_error,image_relative_bias,image_render_noise_relative_mse,"
           "image_cache_relative_mse,image_cache_relative_mse_standard_error,image_tile_mean_relative_error,"
           "image_masked_mean_relative_error,image_masked_relative_mse,"
           "probe_pairs,probe_not_live,probe_mean_relative_error,probe_rms_error,probe_relative_mse,"
           "probe_relative_mse_ci95,probe_voxel_noise,probe_bias_squared,probe_relative_bias,probe_relative_bias_ci95,"
           "probe_reference_noise,probe_leaks\n";
    for (const ConvergenceRow& r : report.rows) {
        const auto voxel = [&](double VoxelError::*field) -> std::optional<double> {
            if (!r.voxel || r.voxel->voxels == 0) return std::nullopt;
            return (*r.voxel).*field;
        };
        const auto image = [&](double ImageComparison::*field) -> std::optional<double> {
            if (!r.image) return std::nullopt;
            return (*r.image).*field;
        };
        const auto split = [&](double RelativeMseSplit::*field) -> std::optional<double> {
            if (!r.image_split) return std::nullopt;
            return (*r.image_split).*field;
        };
        csv << r.iteration << ',' << csvNumber(r.bake_seconds) << ',' << csvNumber(r.render_seconds) << ','
            << csvNumber(r.bake_seconds + r.render_seconds) << ',' << r.rays << ',' << r.live_voxels << ','
            << csvNumber(voxel(&VoxelError::mean_relative)) << ',' << csvNumber(voxel(&VoxelError::rms_relative))
            << ',' << csvNumber(voxel(&VoxelError::max_relative)) << ','
            << csvNumber(voxel(&VoxelError::within_1_percent)) << ','
            << csvNumber(image(&ImageComparison::relative_mse)) << ','
            << csvNumber(image(&ImageComparison::mean_relative_error)) << ','
            << csvNumber(image(&ImageComparison::relative_bias)) << ',' << csvNumber(split(&RelativeMseSplit::noise))
            << ',' << csvNumber(split(&RelativeMseSplit::rest)) << ','
            << csvNumber(split(&RelativeMseSplit::rest_standard_error)) << ','
            << csvNumber(image(&ImageComparison::tile_mean_relative_error)) << ','
            << csvNumber(image(&ImageComparison::masked_mean_relative_error)) << ','
            << csvNumber(image(&ImageComparison::masked_relative_mse));
        const ProbeError* probe = r.probes && r.probes->view.probes > 0 ? &r.probes->view : nullptr;
        if (probe) {
            csv << ',' << probe->probes << ',' << probe->not_live << ',' << csvNumber(probe->mean_relative_error) << ','
                << csvNumber(probe->rmsError()) << ',' << csvNumber(probe->relative_mse) << ','
                << csvNumber(probe->relative_mse_ci) << ',' << csvNumber(probe->relative_variance) << ','
                << csvNumber(probe->biasSquared()) << ',' << csvNumber(probe->relative_bias) << ','
                << csvNumber(probe->relative_bias_ci) << ',' << csvNumber(probe->reference_noise) << ','
                << probe->leaks;
        } else {
            csv << ",,,,,,,,,,,,";
        }
        csv << '\n';
    }
    finishWriting(csv, csv_path);

}

void writePlainPathTracingCsv(const std::string& dir, const ConvergenceReport& report) {
    const std::string plain_path = dir + "/plain_path_tracing.csv";
    std::ostringstream plain;
    plain << "samples_per_pixel,seconds,rays,image_relative_mse,image_mean_relative_error,image_relative_bias,"
             "image_tile_mean_relative_error,image_masked_mean_relative_error,image_masked_relative_mse\n";
    for (const PlainPathTracingRow& p : report.plain) {
        plain << p.samples_per_pixel << ',' << csvNumber(p.seconds) << ',' << p.rays << ','
              << csvNumber(p.image.relative_mse) << ',' << csvNumber(p.image.mean_relative_error) << ','
              << csvNumber(p.image.relative_bias) << ',' << csvNumber(p.image.tile_mean_relative_error) << ','
              << csvNumber(p.image.masked_mean_relative_error) << ',' << csvNumber(p.image.masked_relative_mse)
              << '\n';
    }
    finishWriting(plain, plain_path);

}

Json convergenceRowJson(const ConvergenceRow& r) {
    Json row = {{"iteration", r.iteration},
                {"bake_seconds", jsonNumber(r.bake_seconds)},
                {"render_seconds", jsonNumber(r.render_seconds)},
                {"total_seconds", jsonNumber(r.bake_seconds + r.render_seconds)},
                {"rays", r.rays},
                {"live_voxels", r.live_voxels}};
    if (r.voxel && r.voxel->voxels > 0) {
        row["voxel"] = {{"voxels", r.voxel->voxels},
                        {"mean_relative_error", jsonNumber(r.voxel->mean_relative)},
                        {"rms_relative_error", jsonNumber(r.voxel->rms_relative)},
                        {"max_relative_error", jsonNumber(r.voxel->max_relative)},
                        {"within_1_percent", jsonNumber(r.voxel->within_1_percent)}};
    }
    if (r.image) {
        Json image = imageComparisonJson(*r.image);
        if (r.image_split) {
            image["render_noise_relative_mse"] = jsonNumber(r.image_split->noise);
            image["cache_relative_mse"] = jsonNumber(r.image_split->rest);
            image["cache_relative_mse_standard_error"] = jsonNumber(r.image_split->rest_standard_error);
        }
        row["image"] = image;
    }
    if (r.probes && r.probes->view.probes > 0) row["probes"] = probeMeasureJson(*r.probes);
    return row;
}

void writeConvergenceJson(const std::string& dir, const ConvergenceReport& report) {
    Json json = {{"schema", jsonSchemaId("convergence")},
                 {"scene", report.scene},
                 {"reference", report.reference},
                 {"view",
                  {{"camera", report.view.camera.name},
                   {"width", report.view.width},
                   {"height", report.view.height},
                   {"samples_per_pixel", report.view.samples_per_pixel}}},
                 {"evaluation_seconds", jsonNumber(report.evaluation_seconds)},
                 {"target_error", jsonNumber(report.target_error)},
                 {"probe_floor", nullptr},
                 {"reference_floor", nullptr},
                 {"checkpoints", Json::array()},
                 {"plain_path_tracing", Json::array()}};
    if (const auto& fit = report.probe_floor) {
        json["probe_floor"] = {{"bias_floor", jsonNumber(fit->floor())},
                               {"floor_squared", jsonNumber(fit->floor_squared)},
                               {"floor_squared_ci95", jsonNumber(fit->floor_squared_ci)},
                               {"noise_scale", jsonNumber(fit->noise_scale)},
                               {"checkpoints", fit->checkpoints}};
        const ProbeVerdict verdict = probeVerdict(report.rows, *fit);
        json["probe_floor"]["converged"] = verdict.converged;
        json["probe_floor"]["verdict"] = verdict.reason;
    }
    if (const auto& floor = report.reference_floor) {
        json["reference_floor"] = {{"relative_mse", jsonNumber(floor->rest)},
                                   {"standard_error", jsonNumber(floor->rest_standard_error)}};
    }
    for (const ConvergenceRow& r : report.rows) json["checkpoints"].push_back(convergenceRowJson(r));
    for (const PlainPathTracingRow& p : report.plain) {
        json["plain_path_tracing"].push_back({{"samples_per_pixel", p.samples_per_pixel},
                                              {"seconds", jsonNumber(p.seconds)},
                                              {"rays", p.rays},
                                              {"image", imageComparisonJson(p.image)}});
    }
    std::ostringstream text;
    text << jsonText(json);
    finishWriting(text, dir + "/convergence.json");
}

}  // namespace

void writeConvergenceTables(const std::string& dir, const ConvergenceReport& report) {
    writeCheckpointsCsv(dir, report);
    writePlainPathTracingCsv(dir, report);
    writeConvergenceJson(dir, report);
}

namespace {

/// Runs gnuplot on `script_path` in `dir`. Returns an empty string, or why there is no plot.
std::string runGnuplot(const std::string& dir, const std::string& script_path) {
    // fork + exec rather than system(): no shell, so no quoting of the folder name.
    const std::string log_path = dir + "/convergence.gnuplot.log";
    const pid_t child = ::fork();
    if (child < 0) return "could not start gnuplot";
    if (child == 0) {
        const int log = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (log >= 0) ::dup2(log, STDERR_FILENO);
        if (::chdir(dir.c_str()) != 0) ::_exit(126);
        ::execlp("gnuplot", "gnuplot", "convergence.gp", static_cast<char*>(nullptr));
        ::_exit(127);
    }
    int status = 0;
    while (::waitpid(child, &status, 0) < 0) {
        if (errno != EINTR) return "could not wait for gnuplot";
    }
    if (!WIFEXITED(status)) return "gnuplot crashed; see " + log_path;
    if (WEXITSTATUS(status) == 127) {
        return "gnuplot is not installed (Debian: apt-get install gnuplot-nox); the tables and " + script_path +
               " are written";
    }
    if (WEXITSTATUS(status) != 0) return "gnuplot failed; see " + log_path;
    std::remove(log_path.c_str());
    return "";
}

}  // namespace

namespace {

/// A gnuplot `plot` command of `curves`, one per line.
void writePlot(std::ostream& gp, const std::vector<std::string>& curves) {
    gp << "plot ";
    for (size_t i = 0; i < curves.size(); ++i) gp << (i ? ", \\\n     " : "") << curves[i];
    gp << "\n";
}

/// The probe panel: the cache itself, its RMS error at the probes falling with bake time towards
/// the bias floor, the part that more samples do not remove.
void writeProbePanel(std::ostream& gp, const ConvergenceReport& report) {
    std::vector<std::string> curves;
    const double floor = report.probe_floor ? report.probe_floor->floor() : 0.0;
    double first_seconds = 0.0;
    for (const ConvergenceRow& r : report.rows) {
        if (r.probes && r.probes->view.probes > 0) {
            first_seconds = r.bake_seconds;
            break;
        }
    }
    gp << "set xlabel 'bake seconds'\n"
          "set ylabel 'relative error of the cache at the probes'\n"
          "set key bottom left box opaque\n";
    if (first_seconds > 0.0) gp << "set xrange [" << first_seconds / 1.5 << ":*]\n";
    // Error bars from the interval of the mean square (its low end kept above 0 for the
    // log axis).
    curves.push_back("'convergence.csv' using 'bake_seconds':'probe_rms_error':"
                     "(sqrt(column('probe_relative_mse') - column('probe_relative_mse_ci95') > 1e-6 ? "
                     "column('probe_relative_mse') - column('probe_relative_mse_ci95') : 1e-6)):"
                     "(sqrt(column('probe_relative_mse') + column('probe_relative_mse_ci95'))) with "
                     "yerrorlines lw 2 pt 7 lc rgb '#d55e00' title 'RMS error (95% interval)'");
    curves.push_back("'convergence.csv' using 'bake_seconds':(sqrt(column('probe_voxel_noise'))) with "
                     "linespoints lw 1 pt 6 lc rgb '#56b4e9' title 'of which voxel noise'");
    curves.push_back("'convergence.csv' using 'bake_seconds':(column('probe_bias_squared') > 0 ? "
                     "sqrt(column('probe_bias_squared')) : NaN) with linespoints lw 1 pt 4 lc rgb '#009e73' "
                     "title 'of which bias'");
    if (floor > 0.0) {
        char line[160];
        std::snprintf(line, sizeof line, "%.6g with lines dt 2 lw 2 lc rgb '#000000' title 'bias floor %.3g%%'",
                      floor, 100.0 * floor);
        curves.push_back(line);
    }
    writePlot(gp, curves);
    gp << "set key top right box opaque\nset autoscale x\n";
}

}  // namespace

std::string plotConvergence(const std::string& dir, const ConvergenceReport& report) {
    const auto any = [&report](auto&& has) { return std::any_of(report.rows.begin(), report.rows.end(), has); };
    const bool has_image = any([](const ConvergenceRow& r) { return r.image.has_value(); });
    const bool has_voxel = any([](const ConvergenceRow& r) { return r.voxel && r.voxel->voxels > 0; });
    const bool has_probes = any([](const ConvergenceRow& r) { return r.probes && r.probes->view.probes > 0; });
    if (!has_image && !has_voxel && !has_probes) return "nothing measured to plot";
    const int panels = (has_probes ? 1 : 0) + (has_image || has_voxel ? 1 : 0) + (has_image ? 1 : 0);

    // The script stays beside the tables so that users can restyle and re-run it.
    const std::string script_path = dir + "/convergence.gp";
    {
        std::ofstream gp(script_path);
        const auto plot = [&gp](const std::vector<std::string>& curves) { writePlot(gp, curves); };
        const std::string spp = std::to_string(report.view.samples_per_pixel);
        gp << "# Written by sharcbake bake --report; re-run with: gnuplot convergence.gp\n"
              "set terminal png size " << 100 + 600 * panels << ",620 font ',11'\n"
              "set output 'convergence.png'\n"
              "set datafile separator ','\n"
              "set logscale xy\n"
              "set grid xtics ytics mxtics mytics lc rgb '#dddddd'\n"
              "set key top right box opaque\n"
              "set format y '%g'\n"
           << "set multiplot layout 1," << panels << " title "
           << gnuplotString("Error against time: " + report.scene) << " noenhanced\n";
        std::vector<std::string> curves;
        if (has_probes) writeProbePanel(gp, report);
        if (has_image || has_voxel) {
            gp << "set xlabel 'seconds (cache: bake + render through it; path tracing: render)'\n"
                  "set ylabel 'mean relative error'\n";
        }
        if (has_image) {
            curves.push_back("'convergence.csv' using 'total_seconds':'image_mean_relative_error' with linespoints "
                             "lw 2 pt 7 lc rgb '#9400d3' title 'render through the cache (" + spp + " spp)'");
            curves.push_back("'convergence.csv' using 'total_seconds':'image_tile_mean_relative_error' with "
                             "linespoints lw 1 pt 6 lc rgb '#9400d3' title 'the same over " +
                             std::to_string(kComparisonTile) + "x" + std::to_string(kComparisonTile) + " tiles'");
            if (!report.plain.empty()) {
                curves.push_back("'plain_path_tracing.csv' using 'seconds':'image_mean_relative_error' with linespoints "
                                 "lw 2 pt 5 lc rgb '#009e73' title 'plain path tracing'");
            }
        }
        if (has_voxel) {
            curves.push_back("'convergence.csv' using 'bake_seconds':'voxel_mean_relative_error' with linespoints "
                             "lw 2 pt 9 lc rgb '#e69f00' title 'voxels vs known radiance (bake seconds)'");
        }
        if (!curves.empty()) plot(curves);
        if (has_image) {
            // Relative MSE splits into the render's own noise and the rest (the cache's error):
            // the panel shows which of the two a longer bake would reduce.
            curves.clear();
            curves.push_back("'convergence.csv' using 'total_seconds':'image_relative_mse' with linespoints "
                             "lw 2 pt 7 lc rgb '#9400d3' title 'render through the cache (" + spp + " spp)'");
            // Only where the rest stands out from its own standard error: elsewhere it is noise.
            curves.push_back("'convergence.csv' using 'total_seconds':(column('image_cache_relative_mse') > "
                             "2 * column('image_cache_relative_mse_standard_error') ? column('image_cache_relative_mse') "
                             ": NaN) with linespoints lw 2 pt 6 lc rgb '#56b4e9' title 'less its render noise: the cache "
                             "(> 2 s.e.)'");
            if (!report.plain.empty()) {
                curves.push_back("'plain_path_tracing.csv' using 'seconds':'image_relative_mse' with linespoints "
                                 "lw 2 pt 5 lc rgb '#009e73' title 'plain path tracing'");
            }
            if (report.reference_floor && report.reference_floor->rest > 0.0) {
                char line[160];
                std::snprintf(line, sizeof line, "%.6g with lines dt 3 lw 2 lc rgb '#777777' title \"the reference's "
                              "own floor\"", report.reference_floor->rest);
                curves.push_back(line);
            }
            gp << "set ylabel 'relative MSE'\n";
            plot(curves);
        }
        gp << "unset multiplot\n";
        if (!gp) return script_path + ": cannot write";
    }
    return runGnuplot(dir, script_path);
}

}  // namespace sharcbake
