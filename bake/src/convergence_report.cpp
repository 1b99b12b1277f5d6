// SPDX-License-Identifier: Apache-2.0
#include "convergence_report.h"

#include "sharcbake/cache_file.h"

#include "cache_query.h"
#include "json_text.h"
#include "path_tracer.h"
#include "render.h"
#include "stopwatch.h"

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
    if (!value) return "";
    char text[32];
    std::snprintf(text, sizeof text, "%.6g", *value);
    return text;
}

std::string jsonNumber(std::optional<double> value) {
    return value && std::isfinite(*value) ? csvNumber(value) : "null";
}

/// Writes a finished table with the outputs' atomic, checked write (cache_file.h).
void finishWriting(const std::ostringstream& out, const std::string& path) {
    const std::string text = out.str();
    std::string message;
    if (writeFileAtomically(path, text.data(), text.size(), &message) != CacheFileStatus::kOk) {
        throw std::runtime_error(message);
    }
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
    if (image) return image->mean_relative_error;
    return std::nullopt;
}

ConvergenceEvaluator::ConvergenceEvaluator(const Scene& scene, const Tracer& tracer, const LightSampler& lights,
                                           EvaluationView view, std::optional<Image> reference)
    : tracer_(tracer), lights_(lights), view_(view), known_radiance_(scene.known_radiance) {
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
}

ConvergenceRow ConvergenceEvaluator::evaluate(const SharcCache& cache) const {
    ConvergenceRow row;
    const bool need_data = known_radiance_ || reference_;
    if (!need_data) return row;
    // Exactly what a cache file written now would hold, so the measure is what users get.
    CacheData data = toCacheData(cache);
    row.live_voxels = data.voxels.size();
    if (known_radiance_) row.voxel = measureVoxelError(data, *known_radiance_);
    if (reference_) {
        const auto start = std::chrono::steady_clock::now();
        const BakedCache baked(std::move(data), view_.camera.position);
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
        row.image = compareImages(image, *reference_);
    }
    return row;
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

std::vector<PlainPathTracingRow> ConvergenceEvaluator::plainPathTracing(double until_seconds,
                                                                         uint32_t max_samples_per_pixel) const {
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
        total_samples += batch;
        for (size_t i = 0; i < sum.size(); ++i) {
            sum[i] += glm::dvec3(image.pixels[i]) * double(batch);
            mean.pixels[i] = glm::vec3(sum[i] / double(total_samples));
        }
        seconds += secondsSince(start);
        PlainPathTracingRow row;
        row.samples_per_pixel = total_samples;
        row.seconds = seconds;
        row.rays = counters.closest_hit_rays + counters.shadow_rays;
        row.image = compareImages(mean, *reference_);
        rows.push_back(row);
        if (seconds >= until_seconds) break;
    }
    return rows;
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

void writeConvergenceTables(const std::string& dir, const ConvergenceReport& report) {
    const std::string csv_path = dir + "/convergence.csv";
    std::ostringstream csv;
    csv << "iteration,bake_seconds,render_seconds,total_seconds,rays,live_voxels,"
           "voxel_mean_relative_error,voxel_rms_relative_error,voxel_max_relative_error,voxel_within_1_percent,"
           "image_relative_mse,image_mean_relative_error,image_relative_bias,image_render_noise_relative_mse,"
           "image_cache_relative_mse,image_cache_relative_mse_standard_error\n";
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
            << csvNumber(split(&RelativeMseSplit::rest_standard_error)) << '\n';
    }
    finishWriting(csv, csv_path);

    const std::string plain_path = dir + "/plain_path_tracing.csv";
    std::ostringstream plain;
    plain << "samples_per_pixel,seconds,rays,image_relative_mse,image_mean_relative_error,image_relative_bias\n";
    for (const PlainPathTracingRow& p : report.plain) {
        plain << p.samples_per_pixel << ',' << csvNumber(p.seconds) << ',' << p.rays << ','
              << csvNumber(p.image.relative_mse) << ',' << csvNumber(p.image.mean_relative_error) << ','
              << csvNumber(p.image.relative_bias) << '\n';
    }
    finishWriting(plain, plain_path);

    const std::string json_path = dir + "/convergence.json";
    std::ostringstream json;
    json << "{\n  \"scene\": " << jsonString(report.scene) << ",\n"
         << "  \"reference\": " << jsonString(report.reference) << ",\n"
         << "  \"view\": {\"camera\": " << jsonString(report.view.camera.name) << ", \"width\": " << report.view.width
         << ", \"height\": " << report.view.height << ", \"samples_per_pixel\": " << report.view.samples_per_pixel
         << "},\n"
         << "  \"evaluation_seconds\": " << jsonNumber(report.evaluation_seconds) << ",\n"
         << "  \"target_error\": " << jsonNumber(report.target_error) << ",\n"
         << "  \"checkpoints\": [";
    for (size_t i = 0; i < report.rows.size(); ++i) {
        const ConvergenceRow& r = report.rows[i];
        json << (i ? "," : "") << "\n    {\"iteration\": " << r.iteration
             << ", \"bake_seconds\": " << jsonNumber(r.bake_seconds)
             << ", \"render_seconds\": " << jsonNumber(r.render_seconds)
             << ", \"total_seconds\": " << jsonNumber(r.bake_seconds + r.render_seconds) << ", \"rays\": " << r.rays
             << ", \"live_voxels\": " << r.live_voxels;
        if (r.voxel && r.voxel->voxels > 0) {
            json << ", \"voxel\": {\"voxels\": " << r.voxel->voxels
                 << ", \"mean_relative_error\": " << jsonNumber(r.voxel->mean_relative)
                 << ", \"rms_relative_error\": " << jsonNumber(r.voxel->rms_relative)
                 << ", \"max_relative_error\": " << jsonNumber(r.voxel->max_relative)
                 << ", \"within_1_percent\": " << jsonNumber(r.voxel->within_1_percent) << "}";
        }
        if (r.image) {
            json << ", \"image\": {\"relative_mse\": " << jsonNumber(r.image->relative_mse)
                 << ", \"mean_relative_error\": " << jsonNumber(r.image->mean_relative_error)
                 << ", \"relative_bias\": " << jsonNumber(r.image->relative_bias);
            if (r.image_split) {
                json << ", \"render_noise_relative_mse\": " << jsonNumber(r.image_split->noise)
                     << ", \"cache_relative_mse\": " << jsonNumber(r.image_split->rest)
                     << ", \"cache_relative_mse_standard_error\": " << jsonNumber(r.image_split->rest_standard_error);
            }
            json << "}";
        }
        json << "}";
    }
    json << "\n  ],\n  \"plain_path_tracing\": [";
    for (size_t i = 0; i < report.plain.size(); ++i) {
        const PlainPathTracingRow& p = report.plain[i];
        json << (i ? "," : "") << "\n    {\"samples_per_pixel\": " << p.samples_per_pixel
             << ", \"seconds\": " << jsonNumber(p.seconds) << ", \"rays\": " << p.rays
             << ", \"image\": {\"relative_mse\": " << jsonNumber(p.image.relative_mse)
             << ", \"mean_relative_error\": " << jsonNumber(p.image.mean_relative_error)
             << ", \"relative_bias\": " << jsonNumber(p.image.relative_bias) << "}}";
    }
    json << "\n  ]\n}\n";
    finishWriting(json, json_path);
}

std::string plotConvergence(const std::string& dir, const ConvergenceReport& report) {
    const bool has_image = std::any_of(report.rows.begin(), report.rows.end(), [](const ConvergenceRow& r) { return r.image.has_value(); });
    const bool has_voxel = std::any_of(report.rows.begin(), report.rows.end(),
                                       [](const ConvergenceRow& r) { return r.voxel && r.voxel->voxels > 0; });
    if (!has_image && !has_voxel) return "nothing measured to plot";

    // The script stays beside the tables so that users can restyle and re-run it.
    const std::string script_path = dir + "/convergence.gp";
    {
        std::ofstream gp(script_path);
        const auto plot = [&gp](const std::vector<std::string>& curves) {
            gp << "plot ";
            for (size_t i = 0; i < curves.size(); ++i) gp << (i ? ", \\\n     " : "") << curves[i];
            gp << "\n";
        };
        const std::string spp = std::to_string(report.view.samples_per_pixel);
        gp << "# Written by sharcbake bake --report; re-run with: gnuplot convergence.gp\n"
              "set terminal png size " << (has_image ? "1400,620" : "900,620") << " font ',11'\n"
              "set output 'convergence.png'\n"
              "set datafile separator ','\n"
              "set logscale xy\n"
              "set grid xtics ytics mxtics mytics lc rgb '#dddddd'\n"
              "set key top right box opaque\n"
              "set format y '%g'\n"
              "set xlabel 'seconds (cache: bake + render through it; path tracing: render)'\n"
           << (has_image ? "set multiplot layout 1,2 title " : "set title ")
           << jsonString("Error against time: " + report.scene) << " noenhanced\n"
           << "set ylabel 'mean relative error'\n";
        std::vector<std::string> curves;
        if (has_image) {
            curves.push_back("'convergence.csv' using 'total_seconds':'image_mean_relative_error' with linespoints "
                             "lw 2 pt 7 lc rgb '#9400d3' title 'render through the cache (" + spp + " spp)'");
            if (!report.plain.empty()) {
                curves.push_back("'plain_path_tracing.csv' using 'seconds':'image_mean_relative_error' with linespoints "
                                 "lw 2 pt 5 lc rgb '#009e73' title 'plain path tracing'");
            }
        }
        if (has_voxel) {
            curves.push_back("'convergence.csv' using 'bake_seconds':'voxel_mean_relative_error' with linespoints "
                             "lw 2 pt 9 lc rgb '#e69f00' title 'voxels vs known radiance (bake seconds)'");
        }
        plot(curves);
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
            gp << "set ylabel 'relative MSE'\n";
            plot(curves);
            gp << "unset multiplot\n";
        }
        if (!gp) return script_path + ": cannot write";
    }
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

}  // namespace sharcbake
