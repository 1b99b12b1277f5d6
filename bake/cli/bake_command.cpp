// SPDX-License-Identifier: Apache-2.0
// `sharcbake bake`: the SHaRC bake from a roaming virtual camera into a .sharc cache file.
#include "cli/command_support.h"
#include "cli/commands.h"
#include "cli/config_file.h"
#include "reports/convergence_report.h"
#include "reports/image_error.h"
#include "reports/stability_report.h"
#include "sharc/baker.h"
#include "sharc/camera_path.h"
#include "sharc/capacity.h"
#include "sharc/checkpoint.h"
#include "sharc/coverage.h"
#include "sharc/grid_fit.h"
#include "sharc/hit_rate.h"
#include "sharc/light_leaks.h"
#include "sharc/voxel_materials.h"
#include "sharc/wall_leaks.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/runtime.h"
#include "support/json.h"
#include "support/progress.h"
#include "support/stopwatch.h"
#include "support/worker_threads.h"
#include "tracing/light_reach.h"
#include "tracing/render.h"
#include "tracing/tracer.h"

#include <tbb/info.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cfloat>
#include <chrono>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

#include <unistd.h>

namespace sharcbake {
namespace {

/// Surface points tested for what the roaming camera's positions see (the grid fit): the share
/// is known to about a percent, and a scene the positions see all of costs one ray per point.
constexpr uint32_t kSeenSurfaceSamples = 4096;

struct BakeOptions {
    std::vector<std::string> scene_paths;  ///< as given; one run per scene
    std::string scene_path;                ///< this run's scene
    std::string output_path;
    uint32_t iterations = 512;
    double time_budget = 0.0;
    unsigned threads = 0;
    uint32_t seed = 0;
    std::string scene_scale = "auto";  // a number, or "auto": the SDK sample's 50
    float log_base = kHashGridDefaultLogarithmBase;
    std::string level_bias = "auto";   // a number, or "auto": fitted to the scene (grid_fit.h)
    uint64_t voxel_budget = kDefaultVoxelBudget;
    std::string view_region = "auto";
    uint32_t prediction_views = 32;
    std::string capacity = "4194304";  // the SDK default, or "auto"
    uint32_t update_stride = 5;
    std::string resolution = "1280x720";
    uint32_t max_bounces = 8;
    std::string light_selection = "auto";  ///< "auto" (lights.h: by where light arrives) or "power"
    std::string trace_kernels = "avx2";    ///< "avx2", "sse4.2" or "native" (tracer.h)
    uint32_t propagation_depth = 2;
    std::string resampling = "random";
    std::string history = "ramp:8";
    std::string camera_source_name = "explore";                  ///< as given; parsed into camera_source
    CameraPathSource camera_source = CameraPathSource::Explore;  ///< --camera-path overrides it
    std::string camera_path;
    uint32_t explore_points = 64;
    uint32_t iterations_per_leg = 8;
    uint32_t coverage_points = 20000;
    SkyOptions sky;
    GltfLoadLimits limits;
    std::string stats_json;
    std::string checkpoint_path;
    uint32_t checkpoint_interval = 32;
    std::string resume_path;
    std::string shard = "0/1";
    bool quiet = false;
    double progress_interval = kDefaultProgressInterval;
    bool print_config = false;
    // Error against run time (convergence_report.h).
    std::string report_dir;
    std::string reference_path;
    std::string report_camera;
    std::string report_resolution;
    uint32_t report_spp = 16;
    uint32_t report_probes = ProbeSettings{}.probes;
    uint32_t report_probe_spp = ProbeSettings{}.reference_samples;
    double target_error = 0.0;
    float gpu_radiance_scale = 1.0f;  ///< recorded in the cache for GPU buffers (SPEC §F.8a)
    bool voxel_materials = false;     ///< keep each voxel's emission and demodulation factor (SPEC §F.8b)
};

/// How the roaming camera is made (--camera-source, --camera-path, --explore-points,
/// --iterations-per-leg).
struct CameraRequest {
    CameraPathSource source = CameraPathSource::Explore;
    std::string path_file;  ///< waypoints; when set it overrides `source`
    uint32_t explore_points = 64;
    uint32_t iterations_per_leg = 8;

    /// "explore||64|8": what a resumed bake must ask for again.
    std::string describe() const {
        return std::string(toString(source)) + "|" + path_file + "|" + std::to_string(explore_points) + "|" +
               std::to_string(iterations_per_leg);
    }
};

/// The bake the command line asks for, parsed and checked once (bakeJobFromOptions). The cache's
/// metadata, the checkpoint's settings and the stats are derived from this, never from the
/// option strings, so each value has one owner.
struct BakeJob {
    std::string scene_path;
    SkyOptions sky;
    /// What the Baker runs. The level bias (when auto) and the capacity (when auto) are final
    /// once the scene is loaded (decideGrid, chooseAutoCapacity).
    BakeSettings settings;
    CameraRequest camera;
    bool level_bias_auto = true;
    bool scene_scale_auto = true;
    bool capacity_auto = false;
    uint64_t voxel_budget = kDefaultVoxelBudget;  ///< what an auto level bias fits to
    bool voxel_budget_given = false;              ///< --voxel-budget is not the default (auto region keeps it)
    bool light_selection_by_power = false;        ///< --light-selection power
    /// --trace-kernels; once the tracer exists, the kernels it runs (SSE4.2 where AVX2 was asked
    /// for on a CPU without it), which the cache's metadata records.
    TraceKernels trace_kernels = TraceKernels::kAvx2;
};

/// Above this share of the deposited energy dropped for want of a slot, the cache's gaps are the
/// table's doing: the warnings that blame where the roaming camera went are left out (the
/// stability warning about full buckets names --capacity).
constexpr double kTableFullShare = 0.1;

/// The signal that asked the bake to stop (SIGINT, or SIGTERM as batch schedulers send before a
/// time limit or a preemption), or 0. The bake finishes its iteration and writes its outputs; a
/// second signal aborts promptly.
std::atomic<int> g_stop_signal{0};
/// When the first signal came (CLOCK_MONOTONIC, nanoseconds): the same signal again within
/// kSameStopRequest is one request delivered twice, not a second Ctrl-C. GNU `timeout`, a common
/// limit in CI, signals the bake and then its whole process group, the bake included, and that
/// second copy aborted the bake with nothing written.
std::atomic<int64_t> g_stop_signal_time{0};
constexpr int64_t kSameStopRequest = 250'000'000;  // 0.25 s: faster than a person presses twice
/// The checkpoint lock file a second signal removes before the process ends, so an aborted bake
/// leaves no lock behind (the lock itself dies with the process; its file would stay), and the
/// checkpoint the abort message names when one is on disk. Written before
/// g_abort_lock_path_set is raised and read in the handler only after it, as plain arrays:
/// unlink() and access() are safe in a signal handler, a std::string is not.
char g_abort_lock_path[PATH_MAX] = {};
char g_abort_checkpoint_path[PATH_MAX] = {};
std::atomic<bool> g_abort_lock_path_set{false};

int64_t monotonicNanoseconds() {  // clock_gettime is async-signal-safe
    timespec now{};
    ::clock_gettime(CLOCK_MONOTONIC, &now);
    return int64_t(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

/// write() of a NUL-terminated string; safe in a signal handler.
void writeToStderr(const char* text) {
    [[maybe_unused]] const ssize_t written = ::write(STDERR_FILENO, text, std::strlen(text));
}

/// A second signal while the first is being honoured ends the process at once (the default action).
extern "C" void onStopSignal(int signal) {
    const int64_t now = monotonicNanoseconds();
    const int first = g_stop_signal.exchange(signal);
    if (first == 0) {
        g_stop_signal_time.store(now);
        return;
    }
    if (first == signal && now - g_stop_signal_time.load() < kSameStopRequest) {
        g_stop_signal.store(first);
        return;  // the first request delivered again
    }
    // Said, since the abort writes nothing; the checkpoint only if one is on disk to resume.
    const bool locked = g_abort_lock_path_set.load(std::memory_order_acquire);
    writeToStderr("\nsharcbake: a second signal: aborted at once, no cache written");
    if (locked && ::access(g_abort_checkpoint_path, F_OK) == 0) {
        writeToStderr("; the last checkpoint, ");
        writeToStderr(g_abort_checkpoint_path);
        writeToStderr(", is kept: --resume it");
    }
    writeToStderr("\n");
    if (locked) ::unlink(g_abort_lock_path);  // still held
    std::signal(signal, SIG_DFL);
    std::raise(signal);
}

/// A CheckpointLock whose file a second stop signal removes (g_abort_lock_path) while it is held.
class AbortSafeCheckpointLock {
public:
    explicit AbortSafeCheckpointLock(const std::string& checkpoint_path) : lock_(checkpoint_path) {
        const std::string& path = lock_.lockPath();
        // A longer path keeps its file on an abort (and is not named).
        if (path.size() < sizeof g_abort_lock_path && checkpoint_path.size() < sizeof g_abort_checkpoint_path) {
            std::memcpy(g_abort_lock_path, path.c_str(), path.size() + 1);
            std::memcpy(g_abort_checkpoint_path, checkpoint_path.c_str(), checkpoint_path.size() + 1);
            g_abort_lock_path_set.store(true, std::memory_order_release);
        }
    }
    /// Runs before the lock's own destructor removes the file: a signal after it finds nothing to
    /// remove (another bake may already have made a new lock file at the path).
    ~AbortSafeCheckpointLock() { g_abort_lock_path_set.store(false, std::memory_order_release); }
    AbortSafeCheckpointLock(const AbortSafeCheckpointLock&) = delete;
    AbortSafeCheckpointLock& operator=(const AbortSafeCheckpointLock&) = delete;

private:
    CheckpointLock lock_;
};

/// SIGINT and SIGTERM set g_stop_signal while one lives; the handlers before it come back after.
class StopSignalHandlers {
public:
    StopSignalHandlers()
        : interrupt_(std::signal(SIGINT, onStopSignal)), terminate_(std::signal(SIGTERM, onStopSignal)) {
        g_stop_signal = 0;
        g_stop_signal_time = 0;
    }
    ~StopSignalHandlers() {
        std::signal(SIGINT, interrupt_);
        std::signal(SIGTERM, terminate_);
    }
    StopSignalHandlers(const StopSignalHandlers&) = delete;
    StopSignalHandlers& operator=(const StopSignalHandlers&) = delete;

private:
    void (*interrupt_)(int);
    void (*terminate_)(int);
};

void parseSize(const std::string& text, const char* option, int& width, int& height) {
    char x = 0;
    std::istringstream in(text);
    if (!(in >> width >> x >> height) || x != 'x' || width <= 0 || height <= 0 || !(in >> std::ws).eof() ||
        int64_t(width) * height > (int64_t(1) << 26)) {
        throw CommandError(kExitUsage, std::string(option) + ": expected WxH with positive integers, got \"" + text + "\"");
    }
}

/// Parses a --capacity number (16 .. 2^28).
uint32_t parseCapacity(const std::string& text) {
    std::istringstream in(text);
    long long value = 0;
    if (!(in >> value) || !(in >> std::ws).eof() || value < 16 || value > (1ll << 28)) {
        throw CommandError(kExitUsage, "--capacity: expected \"auto\" or a slot count in [16, 268435456], got \"" +
                                           text + "\"");
    }
    return uint32_t(value);
}

/// What the tracer skips because the scene has no use for it, "; "-separated (cache metadata
/// "left_out", printed by `info`).
std::string workLeftOut(const Scene& scene, const LightSampler& lights) {
    std::string list;
    auto add = [&](const char* item) { list += (list.empty() ? "" : "; ") + std::string(item); };
    if (!lights.hasLights()) {
        add("light sampling and shadow rays (no lights, no emissive surfaces, black sky)");
    } else if (!lights.hasSky()) {
        add("sky lookups and sky sampling (black sky)");
    }
    if (scene.textures.empty()) add("texture fetches and UV interpolation (no textures)");
    return list.empty() ? "nothing" : list;
}

/// Parses --shard "i/N" (0 <= i < N).
void parseShard(const std::string& text, uint32_t& index, uint32_t& count) {
    char slash = 0;
    long long i = -1, n = -1;
    std::istringstream in(text);
    if (!(in >> i >> slash >> n) || slash != '/' || !(in >> std::ws).eof() || n < 1 || n > (1 << 16) || i < 0 || i >= n) {
        throw CommandError(kExitUsage, "--shard: expected \"i/N\" with 0 <= i < N <= 65536, got \"" + text + "\"");
    }
    index = uint32_t(i);
    count = uint32_t(n);
}

/// The roaming camera the options ask for.
/// The bake's camera path; `description` says how it was made, and `cameras_in_solids` names the
/// glTF cameras exploration found inside a solid by the faces' winding (cameraLabel).
CameraPath makeCameraPath(const BakeJob& job, const Scene& scene, const Tracer& tracer, std::string& description,
                          std::vector<std::string>& cameras_in_solids) {
    const float diagonal = glm::length(scene.bounds_max - scene.bounds_min);
    if (!job.camera.path_file.empty()) {
        std::error_code error;
        if (!std::filesystem::is_regular_file(job.camera.path_file, error)) {  // I/O, not a malformed file
            throw CommandError(kExitIo, job.camera.path_file +
                                            ": cannot read the camera path: not a regular file (missing, a FIFO, a "
                                            "device or a folder)");
        }
        std::vector<CameraPose> poses;
        try {
            poses = readCameraPathFile(job.camera.path_file);
        } catch (const CameraPathError& e) {
            throw CommandError(kExitInvalidInput, e.what());
        }
        description = "path file " + pathAsGiven(job.camera.path_file) + " (" + std::to_string(poses.size()) +
                      " waypoints)";
        return CameraPath(std::move(poses), false, job.camera.iterations_per_leg, 0.002f * diagonal, job.settings.seed);
    }
    if (job.camera.source == CameraPathSource::GltfCameras) {
        if (scene.cameras.empty()) {
            throw CommandError(kExitInvalidInput, job.scene_path + ": --camera-source gltf, but the scene has no camera");
        }
        std::vector<CameraPose> poses;
        for (const Camera& c : scene.cameras) poses.push_back(poseOf(c));  // its own view, clip planes included
        description = "glTF cameras (" + std::to_string(poses.size()) + " waypoints)";
        return CameraPath(std::move(poses), false, job.camera.iterations_per_leg, 0.002f * diagonal, job.settings.seed);
    }
    ExplorationResult explored;
    std::optional<CameraPath> path = exploringCameraPath(tracer, scene, job.camera.explore_points, job.settings.seed, &explored);
    if (!path) {
        throw CommandError(kExitInvalidInput, job.scene_path + ": found no free space to place the camera in (tried " +
                                                  std::to_string(explored.candidates) +
                                                  " points); give a --camera-path" +
                                                  (scene.cameras.empty() ? "" : " or --camera-source gltf"));
    }
    // "1 view", "64 views".
    const std::string views_around = std::to_string(explored.views_around) +
                                     (explored.views_around == 1 ? " view" : " views") + " from around the scene";
    if (explored.dark_enclosure && explored.views_around > 0) {
        description = views_around +
                      " (it has no camera, and the free space inside its bounds is closed and no light reaches it: "
                      "the inside of a closed object lit from outside, which no runtime camera sees)";
        return std::move(*path);
    }
    // Which cameras the winding put inside a solid: all of a room modelled from a cube with its
    // normals out, or one that stands inside a closed object by mistake.
    std::string in_solids;
    const std::vector<uint32_t>& inside = explored.cameras_in_solids;
    for (const uint32_t i : inside) cameras_in_solids.push_back(cameraLabel(scene.cameras[i]));
    for (size_t i = 0; i < inside.size() && i < 3; ++i) in_solids += (i == 0 ? "" : ", ") + cameras_in_solids[i];
    if (inside.size() > 3) in_solids += " and " + std::to_string(inside.size() - 3) + " more";
    description = "exploration (" + std::to_string(explored.points.size()) + " reachable free-space points of " +
                  std::to_string(explored.candidates) + " tried" +
                  (!explored.winding_ignored ? ""
                   : inside.empty()
                       ? "; faces' winding ignored: it puts every point inside a solid"
                       : "; faces' winding ignored: it puts " + in_solids +
                             " inside a solid (faces wound away from the camera, or a camera inside a closed object)") +
                  ")";
    if (explored.views_around > 0) {
        description += ", and " + views_around + " (" +
                       (explored.cameras_outside ? "its cameras all stand outside its bounds" : "it has no camera") +
                       ", and " + std::to_string(int(std::lround(100.0f * explored.escaped_fraction))) +
                       "% of the probe rays from those points leave it)";
    }
    return std::move(*path);
}

/// Runs a checkpoint step (lock, save, resume) and reports its failure as the command line
/// does: `prefix` names the option or output, I/O failures exit 2, invalid checkpoints 3.
template <typename Step>
void checkpointStep(const std::string& prefix, Step&& step) {
    try {
        step();
    } catch (const CheckpointError& e) {
        switch (e.kind()) {
            case CheckpointError::Kind::kInvalid: throw CommandError(kExitInvalidInput, prefix + e.what());
            case CheckpointError::Kind::kInUse:
                throw CommandError(kExitIo, prefix + e.what() + "; give this one another --checkpoint");
            case CheckpointError::Kind::kIo: break;
        }
        throw CommandError(kExitIo, prefix + e.what());
    }
}

/// The evaluator --report and --target-error need, or none when neither is asked for.
std::unique_ptr<ConvergenceEvaluator> makeEvaluator(const BakeOptions& o, const Scene& scene, const Tracer& tracer,
                                                    const LightSampler& lights, std::string& reference_description) {
    if (o.report_dir.empty() && o.target_error <= 0.0) return nullptr;
    if (o.reference_path.empty() && !scene.known_radiance && o.report_probes == 0) {
        throw CommandError(kExitUsage, std::string(o.report_dir.empty() ? "--target-error" : "--report") +
                                           ": nothing to measure the error against with --report-probes 0: give "
                                           "--reference EXR (a converged render of the evaluation camera), leave the "
                                           "probes on, or bake a scene with a known radiance "
                                           "(extras.sharcbake.expected_radiance, like the furnace rooms)");
    }
    EvaluationView view;
    view.camera = sceneCamera(scene, o.report_camera, "--report-camera", kAutomaticCameraFovDegrees, &tracer);
    view.samples_per_pixel = o.report_spp;
    std::optional<Image> reference;
    if (!o.reference_path.empty()) {
        try {
            reference = readLinearImage(o.reference_path);
        } catch (const ImageError& e) {
            throw CommandError(kExitIo, std::string("--reference: ") + e.what());
        }
        view.width = reference->width;
        view.height = reference->height;
        bool no_scale = false;
        errorScale(*reference, &no_scale);
        if (no_scale) {
            // As compare says: the image rows' numbers would then be in the scene's units.
            warn(
                formatted("--reference %s has no positive finite mean (black, or no finite pixel): the "
                          "report's image measures fall back to absolute epsilons of 0.01 and depend on the "
                          "scene's units (its probe measures do not)",
                          o.reference_path.c_str()));
        }
        if (!o.report_resolution.empty()) {
            int width = 0, height = 0;
            parseImageSize(o.report_resolution, "--report-resolution", view.camera.aspect_ratio, width, height,
                           cameraLabel(view.camera));
            if (width != view.width || height != view.height) {
                throw CommandError(kExitUsage, "--report-resolution " + o.report_resolution + " differs from the " +
                                                   std::to_string(view.width) + "x" + std::to_string(view.height) +
                                                   " reference " + o.reference_path);
            }
        }
        reference_description = o.reference_path;
    } else {
        parseImageSize(o.report_resolution.empty() ? "128" : o.report_resolution, "--report-resolution",
                       view.camera.aspect_ratio, view.width, view.height, cameraLabel(view.camera));
        reference_description = scene.known_radiance ? "known radiance" : "probe reference";
    }
    const Camera unfitted = view.camera;
    view.camera = fitCameraToImage(view.camera, view.width, view.height);
    warnAboutCameraFit(unfitted, view.camera, view.width, view.height);
    ProbeSettings probes;
    probes.probes = o.report_probes;
    probes.reference_samples = o.report_probe_spp;
    probes.view_position = view.camera.position;
    // --target-error reads the probes at each checkpoint only where nothing better is known.
    const bool probes_during_bake = o.target_error > 0.0 && !scene.known_radiance;
    return std::make_unique<ConvergenceEvaluator>(scene, tracer, lights, view, std::move(reference), probes,
                                                  probes_during_bake);
}

std::string percent(std::optional<double> value) {
    if (!value) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.3g%%", 100.0 * *value);
    return text;
}

/// The cache's part of an evaluation's relative MSE with its standard error, e.g. "1.5e-05 +- 2e-05".
std::string cacheRelativeMse(const ConvergenceRow& row) {
    if (!row.image_split) return "-";
    char text[48];
    std::snprintf(text, sizeof text, "%.2g +- %.1g", row.image_split->rest, row.image_split->rest_standard_error);
    return text;
}

std::string general(std::optional<double> value) {
    if (!value) return "-";
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", *value);
    return text;
}

/// "3.1% +- 0.4%" for a probe measure's relative RMS error and its 95% interval (the interval
/// of the RMS from that of the mean square: d(sqrt x) = dx / (2 sqrt x)).
std::string probeRms(const ProbeError& e) {
    if (e.probes == 0) return "-";
    const double rms = e.rmsError();
    const double half_width = rms > 0.0 ? e.relative_mse_ci / (2.0 * rms) : std::sqrt(e.relative_mse_ci);
    char text[48];
    std::snprintf(text, sizeof text, "%.3g%% +- %.2g%%", 100.0 * rms, 100.0 * half_width);
    return text;
}

/// The probe measure's headline: where the cache started, where it ended, its bias floor, and
/// the regions and levels that stand out.
void printProbeSummary(const ConvergenceReport& report, const CacheProbes& probes) {
    const std::optional<ProbeFloorFit>& fit = report.probe_floor;
    const ConvergenceRow* first = nullptr;
    for (const ConvergenceRow& r : report.rows) {
        if (r.probes && r.probes->view.probes > 0) {
            first = &r;
            break;
        }
    }
    const ConvergenceRow& last = report.rows.back();
    if (!first || !last.probes) return;
    const ProbeError& end = last.probes->view;
    std::printf("  probes: %llu surface points, references of %u path samples (%.2f s); %llu of the points have "
                "no voxel at the level the evaluation camera looks them up at\n",
                (unsigned long long)probes.referencedPoints(), probes.settings().reference_samples,
                probes.referenceSeconds(), (unsigned long long)end.not_live);
    // The noise estimate scaled as the fit found it (the cache's own samples are less noisy than a
    // reference path): unscaled, the furnace's "voxel noise 10.1%" exceeded its whole RMS of 1.55%.
    // The split is of the mean square, so the two parts never exceed the whole.
    const double mean_square = end.rmsError() * end.rmsError();
    const double noise_square = std::clamp((fit ? fit->noise_scale : 1.0) * end.relative_variance, 0.0, mean_square);
    std::printf(
        "  the cache's RMS error at the camera's levels: %s after %u iteration%s, %s after %u; of the last, "
        "voxel noise %.3g%%, bias %.3g%% (signed %+.2f%% +- %.2f%%)\n",
        probeRms(first->probes->view).c_str(), first->iteration, first->iteration == 1 ? "" : "s",
        probeRms(end).c_str(), last.iteration, 100.0 * std::sqrt(noise_square),
        100.0 * std::sqrt(mean_square - noise_square), 100.0 * end.relative_bias, 100.0 * end.relative_bias_ci);
    if (fit) {
        const double low = std::sqrt(std::max(0.0, fit->floor_squared - fit->floor_squared_ci));
        const double high = std::sqrt(fit->floor_squared + fit->floor_squared_ci);
        // A floor that fits 0 has no ratio ("the cache is at 0x its floor" said the opposite).
        const std::string where = fit->floor() > 0.0
                                      ? formatted("the cache is at %.2gx its floor", end.rmsError() / fit->floor())
                                      : std::string("the floor fits 0, so the error left is noise");
        std::printf("  bias floor (fitted over %zu checkpoints): %.3g%% (95%%: %.3g%% to %.3g%%); %s: %s\n",
                    fit->checkpoints, 100.0 * fit->floor(), 100.0 * low, 100.0 * high, where.c_str(),
                    probeVerdict(report.rows, *fit).reason.c_str());
    }
    // Every level at the same points: what cameras at other distances would get.
    std::string by_level;
    for (const ProbeLevelError& level : last.probes->levels) {
        if (level.error.probes == 0) continue;
        char text[96];
        std::snprintf(text, sizeof text, "%s%u: %.3g%% (bias %.3g%%)", by_level.empty() ? "" : ", ", level.level,
                      100.0 * level.error.rmsError(), 100.0 * level.error.biasFloor());
        by_level += text;
    }
    if (!by_level.empty()) std::printf("    RMS error by level at all points: %s\n", by_level.c_str());
    if (end.leaks > 0) {
        std::printf("    %llu of the probes (%.2g%%) are leaks, the cache more than %gx off (worst %.3gx), left out of "
                    "the measures above:\n",
                    (unsigned long long)end.leaks, 100.0 * double(end.leaks) / double(end.leaks + end.probes),
                    kProbeLeakRatio, end.worst_leak);
        for (const ProbeLeak& leak : last.probes->worst_leaks) {
            std::printf("      at (%.4g, %.4g, %.4g) facing (%.2g, %.2g, %.2g), %s, level %u: cache %.3g, reference "
                        "%.3g (grey)\n",
                        leak.position.x, leak.position.y, leak.position.z, leak.normal.x, leak.normal.y,
                        leak.normal.z, leak.material.empty() ? "(unnamed material)" : leak.material.c_str(),
                        leak.level, (leak.cache.x + leak.cache.y + leak.cache.z) / 3.0,
                        (leak.reference.x + leak.reference.y + leak.reference.z) / 3.0);
        }
    }
    for (const ProbeRegionError& region : last.probes->regions) {
        if (!region.standsOut()) continue;
        std::printf("    %s stands out: signed bias %+.2f%% +- %.2f%% over %llu probes\n",
                    region.name.c_str(),
                    100.0 * region.error.relative_bias, 100.0 * region.error.relative_bias_ci,
                    (unsigned long long)region.error.probes);
    }
}

/// The convergence table of --report / --target-error, and the comparison at equal time.
void printConvergence(const ConvergenceReport& report, const CacheProbes& probes) {
    std::printf("Convergence (%s; evaluation %.2f s, not counted in the bake):\n", report.reference.c_str(),
                report.evaluation_seconds);
    // relMSE less the render's noise is the cache's own error: the column a longer bake lowers.
    std::printf("  %10s %10s %12s %18s %12s %12s %12s %20s\n", "iteration", "bake s", "live voxels", "probe RMS",
                "voxel error", "image error", "image relMSE", "less render noise");
    for (const ConvergenceRow& r : report.rows) {
        std::printf("  %10u %10.3f %12llu %18s %12s %12s %12s %20s\n", r.iteration, r.bake_seconds,
                    (unsigned long long)r.live_voxels, r.probes ? probeRms(r.probes->view).c_str() : "-",
                    percent(r.voxel ? std::optional<double>(r.voxel->mean_relative) : std::nullopt).c_str(),
                    percent(r.image ? std::optional<double>(r.image->mean_relative_error) : std::nullopt).c_str(),
                    general(r.image ? std::optional<double>(r.image->relative_mse) : std::nullopt).c_str(),
                    cacheRelativeMse(r).c_str());
    }
    printProbeSummary(report, probes);
    const ConvergenceRow& end = report.rows.back();
    if (end.image) {
        // "over the 0 pixels seen through the cache 0%" was printed for a view that sees none.
        const std::string seen = end.image->masked_pixels == 0
                                     ? std::string("; no pixel sees the cache directly")
                                     : formatted("; over the %llu pixels seen through the cache %s",
                                                 (unsigned long long)end.image->masked_pixels,
                                                 percent(end.image->masked_mean_relative_error).c_str());
        std::printf(
            "  image at the end: mean relative error %s; over %dx%d-pixel tiles %s (most render noise "
            "averaged out)%s\n",
            percent(end.image->mean_relative_error).c_str(), kComparisonTile, kComparisonTile,
            percent(end.image->tile_mean_relative_error).c_str(), seen.c_str());
    }
    if (report.reference_floor) {
        std::printf("  the reference's own floor: relative MSE %.2g +- %.1g (its noise and what differs between the "
                    "renderers): image errors below it cannot be told from the reference's\n",
                    report.reference_floor->rest, report.reference_floor->rest_standard_error);
    }
    if (!report.plain.empty()) {
        const ConvergenceRow& last = report.rows.back();
        const double total = last.bake_seconds + last.render_seconds;
        const std::optional<double> plain = plainErrorAt(report.plain, total);
        std::printf("  at %.2f s (bake + render through the cache): cache %s, plain path tracing %s "
                    "(%u spp took %.2f s)\n",
                    total, percent(last.image->mean_relative_error).c_str(), percent(plain).c_str(),
                    report.plain.back().samples_per_pixel, report.plain.back().seconds);
    }
}

/// A finite float option ("--scene-scale 25"); usage error otherwise.
float parseFiniteFloat(const std::string& text, const char* option) {
    char* end = nullptr;
    const float value = std::strtof(text.c_str(), &end);
    if (text.empty() || !end || *end != '\0' || !std::isfinite(value)) {
        throw CommandError(kExitUsage, std::string(option) + ": expected \"auto\" or a number, got \"" + text + "\"");
    }
    return value;
}

/// The usage error for grid parameters validateHashGridParameters refuses (`status`), naming the
/// options that set them where their values are each fine and only their voxel size is not.
CommandError gridParametersError(const HashGridParameters& grid, HashGridStatus status) {
    if (status != HashGridStatus::kUnrepresentableVoxelSize)
        return CommandError(kExitUsage, std::string("hash grid parameters: ") + toString(status));
    // A subnormal scale is wrong whatever the bias; otherwise the bias is what the fit would set.
    const char* remedy = grid.scene_scale < FLT_MIN
                             ? "Use --scene-scale auto (50): SHaRC's scene scale is the same in any units"
                             : "Use --level-bias auto, which fits the finest voxels to the scene's units";
    char text[400];
    std::snprintf(text, sizeof text,
                  "--scene-scale %g, --log-base %g and --level-bias %g give voxels float32 cannot represent: the "
                  "finest is %g wide (%g / (%g x %g^%g)), and every level's voxel would be 0 or infinitely wide. %s",
                  double(grid.scene_scale), double(grid.logarithm_base), double(grid.level_bias),
                  double(voxelSize(kHashGridLevelMin, grid)), double(grid.logarithm_base), double(grid.scene_scale),
                  double(grid.logarithm_base), double(grid.level_bias), remedy);
    return CommandError(kExitUsage, text);
}

/// The bake's settings from its options (usage errors for malformed ones).
BakeSettings settingsFromOptions(const BakeOptions& o) {
    BakeSettings settings;
    parseSize(o.resolution, "--resolution", settings.width, settings.height);
    settings.update_stride = o.update_stride;
    settings.seed = o.seed;
    parseShard(o.shard, settings.shard_index, settings.shard_count);
    settings.path.max_bounces = o.max_bounces;
    settings.sharc.propagation_depth = o.propagation_depth;
    settings.sharc.resample_at_end = o.resampling == "end";
    // --capacity auto starts from the SDK's default; the bake replaces it after a pre-pass.
    settings.sharc.grid.capacity = o.capacity == "auto" ? 1u << 22 : parseCapacity(o.capacity);
    settings.sharc.grid.scene_scale =
        o.scene_scale == "auto" ? kHashGridDefaultSceneScale : parseFiniteFloat(o.scene_scale, "--scene-scale");
    settings.sharc.grid.logarithm_base = o.log_base;
    // --level-bias auto is fitted once the scene is loaded (fitGrid); 0 until then.
    settings.sharc.grid.level_bias = o.level_bias == "auto" ? 0.0f : parseFiniteFloat(o.level_bias, "--level-bias");
    try {
        settings.view_region = parseViewRegion(o.view_region);
    } catch (const std::invalid_argument& e) {
        throw CommandError(kExitUsage, std::string("--view-region: ") + e.what());
    }
    if (!HistorySchedule::parse(o.history, settings.sharc.history)) {
        throw CommandError(kExitUsage, "--history: expected \"ramp:P\" (0..8), \"window:A\" (A >= 1) or \"average\", got \"" +
                                           o.history + "\"");
    }
    const HashGridStatus grid_status = validateHashGridParameters(settings.sharc.grid);
    if (grid_status != HashGridStatus::kOk) throw gridParametersError(settings.sharc.grid, grid_status);
    return settings;
}

/// Everything the bake command does, from its options.
BakeJob bakeJobFromOptions(const BakeOptions& o) {
    BakeJob job;
    job.scene_path = o.scene_path;
    job.sky = o.sky;
    job.settings = settingsFromOptions(o);
    job.light_selection_by_power = o.light_selection == "power";
    job.trace_kernels = traceKernelsNamed(o.trace_kernels);
    job.camera.source = o.camera_source;
    job.camera.path_file = o.camera_path;
    job.camera.explore_points = o.explore_points;
    job.camera.iterations_per_leg = o.iterations_per_leg;
    job.level_bias_auto = o.level_bias == "auto";
    job.scene_scale_auto = o.scene_scale == "auto";
    job.capacity_auto = o.capacity == "auto";
    job.voxel_budget = o.voxel_budget;
    // A budget other than the default is the user's: --view-region auto keeps it. (Not whether the
    // option was given: --print-config writes the default into the file it makes.)
    job.voxel_budget_given = o.voxel_budget != kDefaultVoxelBudget;
    return job;
}

/// "1,2,5"
std::string joined(const std::vector<uint32_t>& values) {
    std::string text;
    for (const uint32_t v : values) text += (text.empty() ? "" : ",") + std::to_string(v);
    return text;
}

/// "98.7% of 131072 lookups from 33 views (lowest: camera 'Main' 97.1%)"
std::string describeHitRate(const HitRatePrediction& p) {
    char text[256];
    if (p.eligible == 0 && p.refused > 0) {  // voxels far larger than what the views see
        std::snprintf(text, sizeof text,
                      "no lookups from %s pass SHaRC's tests (all %llu refused: each bounce is shorter than "
                      "its voxel)",
                      counted(p.views.size(), "view").c_str(), (unsigned long long)p.refused);
        return text;
    }
    if (p.eligible == 0) {  // every first bounce leaves the scene (a lone object): a rate of nothing
        std::snprintf(text, sizeof text, "no lookups from %s (no first bounce from them hits a surface)",
                      counted(p.views.size(), "view").c_str());
        return text;
    }
    if (p.eligible < kLookupsForARate) {  // nearly every first bounce leaves the scene: no rate to speak of
        std::snprintf(text, sizeof text,
                      "%.1f%% of only %s from %s (nearly every first bounce from them leaves the "
                      "scene: little for a cache to answer)",
                      100.0 * p.rate(), counted(p.eligible, "lookup").c_str(), counted(p.views.size(), "view").c_str());
        return text;
    }
    std::snprintf(text, sizeof text, "%.1f%% of %llu lookups from %s", 100.0 * p.rate(), (unsigned long long)p.eligible,
                  counted(p.views.size(), "view").c_str());
    std::string result = text;
    if (const ViewHitRate* worst = p.worst()) {
        std::snprintf(text, sizeof text, " (lowest: %s, %.1f%%)", worst->view.camera.name.c_str(), 100.0 * worst->rate());
        result += text;
    }
    return result;
}

Json hitRateJson(const HitRatePrediction& p) {
    Json views = Json::array();
    for (const ViewHitRate& v : p.views) {
        views.push_back({{"name", v.view.camera.name},
                         {"declared", v.view.declared},
                         {"position", jsonVec3(v.view.camera.position)},
                         {"rate", v.eligible ? jsonNumber(v.rate()) : Json(nullptr)},
                         {"lookups", v.eligible},
                         {"refused", v.refused}});
    }
    return {{"rate", p.eligible ? jsonNumber(p.rate()) : Json(nullptr)},  // null: nothing to rate
            {"lookups", p.eligible},
            {"hits", p.hits},
            {"refused", p.refused},
            {"views", views}};
}

Json lightLeaksJson(const LightLeakReport& r) {
    Json leaks = Json::array();
    for (const EmitterLeak& leak : r.leaks) {
        leaks.push_back({{"material", leak.material_label},
                         {"area_share", jsonNumber(leak.area_share)},
                         {"median_gap", jsonNumber(leak.median_gap)},
                         {"voxel_size", jsonNumber(leak.voxel_size)}});
    }
    return {{"emissive_materials", r.emissive_materials}, {"points", r.points}, {"leaks", leaks}};
}

/// Below 95% of SHaRC's lookups answered, the cache does not serve its views: say which and why.
/// `unreached_area`: the share of the surface no update path reached (see warnAboutTheCache).
void warnAboutHitRate(const HitRatePrediction& p, double unreached_area,
                      const std::vector<std::string>& cameras_in_solids, bool has_gltf_cameras) {
    if (p.eligible == 0 && p.refused > 0) {
        warn(
            formatted("SHaRC's eligibility tests refuse every one of the %llu lookups from the views (each "
                      "bounce is shorter than its voxel): the voxels are far larger than what the cameras see, so "
                      "a runtime traces every path in full. Give a larger --level-bias (each +1 halves the voxels)",
                      (unsigned long long)p.refused));
        return;
    }
    if (p.eligible < kLookupsForARate) return;  // a rate of a handful says nothing (describeHitRate says why)
    constexpr double kWanted = 0.95;
    const ViewHitRate* worst = p.worst();
    if (p.rate() >= kWanted && (!worst || worst->rate() >= kWanted)) return;
    // The declared cameras' own share, apart: sampled free-space viewpoints (in corners, inside
    // open models) can pull the whole down while the scene's cameras are served.
    uint64_t declared_eligible = 0, declared_hits = 0;
    const ViewHitRate* one_declared = nullptr;
    size_t declared_views = 0;
    for (const ViewHitRate& v : p.views) {
        if (!v.view.declared) continue;
        declared_eligible += v.eligible;
        declared_hits += v.hits;
        one_declared = &v;
        ++declared_views;
    }
    char declared[160] = "";
    // Not when the lowest view is the one camera itself: it would be named twice.
    if (declared_eligible > 0 && !(declared_views == 1 && worst == one_declared)) {
        const std::string which = declared_views == 1 ? one_declared->view.camera.name
                                                      : std::to_string(declared_views) + " cameras";
        std::snprintf(declared, sizeof declared, "; from %s %.1f%%", which.c_str(),
                      100.0 * double(declared_hits) / double(declared_eligible));
    }
    char lowest[320] = "";
    if (worst) {
        std::snprintf(lowest, sizeof lowest, " (lowest: %s, %.1f%%%s)", worst->view.camera.name.c_str(),
                      100.0 * worst->rate(), declared);
    }
    const char* remedy = unreached_area <= 0.05
                             ? "Give more --iterations (the finest level is not filled yet) or a --view-region that "
                               "holds the views (free holds every camera position)."
                         : has_gltf_cameras ? "The roaming camera never reached part of the surface: give more "
                                              "--iterations, a --camera-path through the places the views see, or "
                                              "--camera-source gltf."
                                            : "The roaming camera never reached part of the surface: give more "
                                              "--iterations, more --explore-points, or a --camera-path through the "
                                              "places the views see.";
    // A lowest camera that stands inside a solid by the winding may be inside a closed object by
    // mistake, where no bake reaches what it sees: more iterations would not help it.
    std::string inside;
    if (worst && worst->view.declared &&
        std::find(cameras_in_solids.begin(), cameras_in_solids.end(), worst->view.camera.name) !=
            cameras_in_solids.end()) {
        inside = " The faces' winding puts " + worst->view.camera.name +
                 " inside a solid (the Camera line names it): if it stands inside a closed object by mistake, "
                 "move it.";
    }
    warn(
        formatted("the cache answers %.1f%% of SHaRC's lookups from its views%s; a runtime traces the rest. "
                  "%s%s Engines can also fall back to the nearest level the file holds (lookupNearestLevel; render "
                  "--cache-lookup nearest shows it)",
                  100.0 * p.rate(), lowest, remedy, inside.c_str()));
}

/// The bake's summary lists each glTF camera's predicted rate up to this many cameras; beyond, the
/// lowest kListedCameras - 1 and one line for the rest (a scene with 204 cameras printed 204 lines).
/// The stats JSON lists every one.
constexpr size_t kListedCameras = 16;

/// Which of `p`'s views the summary lists: every declared one, or where there are more than
/// kListedCameras, those SHaRC refuses outright and then the lowest rates (in the cameras' order).
std::vector<bool> camerasToList(const HitRatePrediction& p) {
    std::vector<bool> listed(p.views.size(), false);
    std::vector<size_t> declared;
    for (size_t i = 0; i < p.views.size(); ++i)
        if (p.views[i].view.declared) declared.push_back(i);
    if (declared.size() <= kListedCameras) {
        for (size_t i : declared) listed[i] = true;
        return listed;
    }
    // Refused outright first, then rated views from the lowest rate, then those too few to rate.
    const auto rank = [&p](size_t i) {
        const ViewHitRate& v = p.views[i];
        if (v.eligible == 0 && v.refused > 0) return -1.0;
        return v.eligible < kLookupsForARate ? 2.0 : v.rate();
    };
    std::stable_sort(declared.begin(), declared.end(), [&](size_t a, size_t b) { return rank(a) < rank(b); });
    for (size_t k = 0; k + 1 < kListedCameras; ++k) listed[declared[k]] = true;
    return listed;
}

/// One line for the declared views camerasToList left out: how many, and the lowest rate among them.
void printUnlistedCameras(const HitRatePrediction& p, const std::vector<bool>& listed) {
    size_t rated = 0, unrated = 0;
    double lowest = 1.0;
    for (size_t i = 0; i < p.views.size(); ++i) {
        const ViewHitRate& v = p.views[i];
        if (!v.view.declared || listed[i]) continue;
        if (v.eligible >= kLookupsForARate) {
            ++rated;
            lowest = std::min(lowest, v.rate());
        } else {
            ++unrated;
        }
    }
    if (rated + unrated == 0) return;
    std::string text = "    and " + std::to_string(rated + unrated) + " more cameras";
    char rate[64];
    std::snprintf(rate, sizeof rate, ", each %.1f%% or above", 100.0 * lowest);
    if (rated > 0) text += rate;
    if (unrated > 0) text += " (" + std::to_string(unrated) + " with too few lookups for a rate)";
    std::printf("%s; the stats JSON (--stats-json) lists every one\n", text.c_str());
}

/// What the grid step decided, for the output, the metadata and the stats.
struct GridDecision {
    std::string choice;                 ///< "auto: level bias 3.5: ..." or "given: ..."
    std::vector<std::string> warnings;  ///< units that do not fit the scene, each with the fix
    uint32_t finest_level = 1;
    uint32_t coarsest_level = 0;
    std::string misses;  ///< which camera distances find no voxel, or empty
    bool auto_kept_to_gltf_cameras = false;  ///< `--view-region auto` chose the glTF cameras
    std::string levelsCovered() const {
        if (coarsest_level == 0) return "the bake camera's";
        return std::to_string(finest_level) + "-" + std::to_string(coarsest_level);
    }
};

/// SHaRC refusing this share of the glTF cameras' lookups on free space's grid or more makes
/// `--view-region auto` consider keeping the grid to the glTF cameras; it keeps it there only where
/// their grid refuses less than kServedRefusedShare.
constexpr double kFreeFailsRefusedShare = 0.9;
constexpr double kServedRefusedShare = 0.5;
/// The budgets `--view-region auto` tries for the glTF cameras, in times the default voxel budget,
/// smallest first: the least that makes their voxels fine enough, since every voxel more takes
/// samples from the others (a room with a window, 1.37 times the budget would do: in 4 times it, its
/// finer voxels rendered 5% too dark after the default 512 iterations and 0.5% after 2048). At most
/// 16 times (2^21 voxels, a file of about 50 MB).
constexpr std::array<std::pair<uint64_t, uint64_t>, 9> kAutoBudgetGrowth = {
    {{1, 1}, {3, 2}, {2, 1}, {3, 1}, {4, 1}, {6, 1}, {8, 1}, {12, 1}, {16, 1}}};

/// `--view-region auto` (the default) is free space, unless the scene's glTF cameras would get
/// nothing, or something wrong, from it. Nothing: small objects on a ground plane 2000 times their
/// size get level-1 voxels 30 units wide in the voxel budget, every bounce from the camera is
/// shorter than its voxel, and SHaRC's eligibility tests refuse all of its lookups (the runtime
/// traces every path: right, but no cache). Wrong: a room with a window on a ground 200 m wide
/// gets level-1 voxels 0.56 m wide, wider than the room's 0.2 m walls, and the sunlit ground's
/// light leaks in through them (rendered from the room's cameras through the cache: +317% and
/// +414% too bright). So where free space's grid has 90% or more of the glTF cameras' lookups
/// refused, or 90% of one camera's that the finest grid tried would serve (VC.glb from
/// glTF-Sample-Models: 4 of its 14 cameras got nothing, the others 95%), or gives the typical glTF
/// camera voxels wider than the voxel warning allows (voxelsAroundCameras), the region becomes the
/// glTF cameras (`region`, its `source` saying why) if their grid serves them: fewer than half
/// refused, every camera served that the finest grid serves, and voxels no wider than that warning
/// allows, in the budget or, where it is the default, in up to 16 times it (`job.voxel_budget`
/// grows). A camera no grid tried serves (inside a box a few millimetres wide) counts against
/// none. Otherwise free space it stays: passing lookups into voxels about a room wide would be
/// worse than refusing them (the flat of 4 m rooms on a 2 km ground, kept to its cameras in the
/// default budget, rendered through the cache 110% too bright), and the voxel warning says what
/// would make them finer. `free_fit` is free space's fit; returns the cameras' fit where the region
/// became theirs.
std::optional<GridFit> keepToGltfCamerasWhereFreeFails(BakeJob& job, const Tracer& tracer, const SeenSurface* seen,
                                                       const HashGridParameters& grid, const GridFit& free_fit,
                                                       ViewRegion& region) {
    const Scene& scene = tracer.scene();
    if (scene.cameras.empty()) return std::nullopt;
    HashGridParameters free_grid = grid;
    free_grid.level_bias = free_fit.level_bias;
    const float free_voxel = free_fit.finest_voxel_size;
    const RefusedLookups free_refused = refusedLookups(tracer, free_grid, gridAnchorFor(scene, free_voxel));
    // The typical camera is found once (rays around every glTF camera); each grid only sizes its voxel.
    const VoxelsAroundCameras free_around = voxelsAroundCameras(tracer, free_grid);
    const ViewRegion at_cameras = atGltfCameras(scene);
    const size_t budgets_tried = job.voxel_budget_given ? 1 : kAutoBudgetGrowth.size();  // a budget given is kept
    const auto cameraGrid = [&](size_t b, GridFit* fit) {
        const auto [times, per] = kAutoBudgetGrowth[b];
        *fit = fitLevelBias(scene, grid, job.voxel_budget * times / per, seen, &at_cameras);
        HashGridParameters camera_grid = grid;
        camera_grid.level_bias = fit->level_bias;
        return camera_grid;
    };
    const auto refusedOn = [&](const HashGridParameters& camera_grid) {
        return refusedLookups(tracer, camera_grid, gridAnchorFor(scene, voxelSize(kHashGridLevelMin, camera_grid)));
    };
    // Cameras that even the finest grid tried leaves unserved: no grid here can help them.
    uint32_t unservable = 0;
    if (free_refused.unserved > 0) {
        GridFit finest;
        unservable = refusedOn(cameraGrid(budgets_tried - 1, &finest)).unserved;
    }
    if (free_refused.share < kFreeFailsRefusedShare && free_refused.unserved <= unservable && !free_around.tooWide())
        return std::nullopt;
    for (size_t b = 0; b < budgets_tried; ++b) {
        const auto [times, per] = kAutoBudgetGrowth[b];
        const uint64_t budget = job.voxel_budget * times / per;
        GridFit fit;
        const HashGridParameters camera_grid = cameraGrid(b, &fit);
        const VoxelsAroundCameras around = free_around.on(camera_grid);
        if (around.tooWide()) continue;
        const RefusedLookups camera_refused = refusedOn(camera_grid);
        if (!(camera_refused.share < kServedRefusedShare) || camera_refused.unserved > unservable) continue;
        char grown[96] = "";
        if (budget != job.voxel_budget) {
            std::snprintf(grown, sizeof grown, " in --voxel-budget %llu (%g times the default)",
                          (unsigned long long)budget, double(times) / double(per));
        }
        char why[640];
        if (free_refused.share >= kFreeFailsRefusedShare) {
            std::snprintf(why, sizeof why,
                          "the glTF cameras, chosen by --view-region auto: in free space, level-1 voxels %.3g wide "
                          "would have SHaRC refuse %.0f%% of their lookups (each bounce shorter than its voxel), "
                          "here %.0f%%%s; --view-region free keeps runtime cameras anywhere",
                          double(free_voxel), 100.0 * free_refused.share, 100.0 * camera_refused.share, grown);
        } else if (free_refused.unserved > unservable) {
            const uint32_t others = free_refused.unserved - 1;
            const std::string whose =
                free_refused.first_unserved +
                (others == 0 ? "" : " and " + std::to_string(others) + (others == 1 ? " other" : " others"));
            std::snprintf(why, sizeof why,
                          "the glTF cameras, chosen by --view-region auto: in free space, level-1 voxels %.3g wide "
                          "would have SHaRC refuse %.0f%% or more of the lookups of %s (each bounce shorter than its "
                          "voxel), here %.0f%% of all%s; --view-region free keeps runtime cameras anywhere",
                          double(free_voxel), 100.0 * kUnservedRefusedShare, whose.c_str(),
                          100.0 * camera_refused.share, grown);
        } else {
            std::snprintf(why, sizeof why,
                          "the glTF cameras, chosen by --view-region auto: in free space, %s would get voxels %.3g "
                          "wide, wider than 1/%g of the distance to what it sees (a median %.3g), which blur its view "
                          "and leak light through walls thinner than one; here %.3g%s; --view-region free keeps "
                          "runtime cameras anywhere",
                          cameraLabel(*free_around.camera).c_str(), double(free_around.voxel),
                          double(kDistancePerVoxelAroundCameras), double(free_around.distance), double(around.voxel),
                          grown);
        }
        region = at_cameras;
        region.source = why;
        job.voxel_budget = budget;
        return fit;
    }
    return std::nullopt;
}

/// Resolves the view region's cameras (gltf, path) and fits the level bias (--level-bias auto),
/// or checks the given one against the scene.
GridDecision decideGrid(BakeJob& job, const Tracer& tracer, const SeenSurface* seen) {
    const Scene& scene = tracer.scene();
    BakeSettings& settings = job.settings;
    ViewRegion& region = settings.view_region;
    if (region.kind == ViewRegion::Kind::Points && region.source == "gltf") {
        if (scene.cameras.empty()) {
            throw CommandError(kExitInvalidInput, job.scene_path + ": --view-region gltf, but the scene has no camera");
        }
        region = atGltfCameras(scene);
    } else if (region.kind == ViewRegion::Kind::Points && region.source == "path") {
        if (job.camera.path_file.empty()) throw CommandError(kExitUsage, "--view-region path needs --camera-path FILE");
        try {
            for (const CameraPose& pose : readCameraPathFile(job.camera.path_file)) region.points.push_back(pose.position);
        } catch (const CameraPathError& e) {
            throw CommandError(kExitInvalidInput, e.what());
        }
        region.source = "waypoints of " + pathAsGiven(job.camera.path_file);
    }
    GridDecision decision;
    HashGridParameters& grid = settings.sharc.grid;
    const bool auto_region = region.kind == ViewRegion::Kind::FreeSpace && region.source == "auto";
    if (auto_region) region.source.clear();  // free space, unless the glTF cameras get it below
    if (job.level_bias_auto) {
        GridFit fit = fitLevelBias(scene, grid, job.voxel_budget, seen, &region);
        // Kept to the glTF cameras, the fit already passed the voxel warning's check.
        const std::optional<GridFit> kept = auto_region
                                                ? keepToGltfCamerasWhereFreeFails(job, tracer, seen, grid, fit, region)
                                                : std::nullopt;
        if (kept) fit = *kept;
        decision.auto_kept_to_gltf_cameras = kept.has_value();
        grid.level_bias = fit.level_bias;
        decision.choice = "auto, " + fit.reason;
        const std::string warning = kept ? std::string()
                                         : checkVoxelsAroundCameras(tracer, grid, region, &fit, job.voxel_budget, seen);
        if (!warning.empty()) decision.warnings.push_back(warning);
    } else {
        char text[96];
        std::snprintf(text, sizeof text, "given: level bias %.9g, finest voxels %.4g wide", double(grid.level_bias),
                      double(voxelSize(kHashGridLevelMin, grid)));
        decision.choice = text;
    }
    const HashGridStatus status = validateHashGridParameters(grid);
    if (status != HashGridStatus::kOk) throw gridParametersError(grid, status);
    settings.sharc.grid_anchor = gridAnchorFor(scene, voxelSize(kHashGridLevelMin, grid));
    const DepositLevels levels = levelsFor(scene, settings);
    decision.finest_level = levels.finestLevel();
    decision.coarsest_level = levels.coarsestLevel();
    if (region.kind == ViewRegion::Kind::Distance && decision.finest_level > kHashGridLevelMin) {
        // Level L starts at camera distance b^(L - bias).
        char text[160];
        std::snprintf(text, sizeof text, "; cameras nearer than %g to a surface ask for finer levels and miss there "
                      "(the runtime's nearest-level lookup falls back)",
                      std::pow(double(grid.logarithm_base), double(decision.finest_level) - double(grid.level_bias)));
        decision.misses = text;
    }
    if (!job.level_bias_auto) {
        decision.warnings = checkGridForScene(scene, grid, decision.finest_level, job.voxel_budget);
        // A bias far off for the whole scene is warned about once, above.
        const std::string warning = decision.warnings.empty() ? checkVoxelsAroundCameras(tracer, grid, region, nullptr,
                                                                                         job.voxel_budget, seen)
                                                              : std::string();
        if (!warning.empty()) decision.warnings.push_back(warning);
    }
    if (!job.scene_scale_auto) {
        const std::string warning = checkSceneScale(grid.scene_scale);
        if (!warning.empty()) decision.warnings.push_back(warning);
    }
    return decision;
}

/// The cache's metadata: everything that reproduces the bake, and nothing that varies between
/// runs (timings go to --stats-json), so the same scene, settings and seed give the same file
/// byte for byte. "iterations" is filled in after the bake.
/// The fixed-point radiance scale (a power of two) as the metadata records it: std::to_string's
/// fixed notation, exact for the scales of 1 and more ordinary scenes get (caches baked before
/// keep their bytes), and all its digits below 1, where six decimals read 0 for any scene brighter
/// than about 1e18 and a resume could not tell two such scales apart.
std::string radianceScaleText(double radiance_scale) {
    if (radiance_scale >= 1.0) return std::to_string(radiance_scale);
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", radiance_scale);
    return text;
}

/// What a finished bake adds to its settings: the iterations done and the table's final size.
struct BakeOutcome {
    uint32_t iterations = 0;
    uint32_t capacity = 0;  ///< grown from the starting one with --capacity auto
};

/// The cache file's metadata: the bake's settings, and with `outcome` what it did. Without one
/// (at the start, for the checkpoint's settings) the iterations are empty and the capacity is
/// the starting one.
std::vector<std::pair<std::string, std::string>> bakeMetadata(const BakeJob& job, const Scene& scene,
                                                              const std::string& scene_hash,
                                                              const LightSampler& lights, double radiance_scale,
                                                              const std::string& camera_description,
                                                              const std::string& capacity_choice,
                                                              const std::string& grid_choice,
                                                              const std::string& levels_covered,
                                                              std::optional<BakeOutcome> outcome = std::nullopt) {
    const BakeSettings& settings = job.settings;
    std::vector<std::pair<std::string, std::string>> metadata = {
        {"writer", "sharcbake " SHARCBAKE_VERSION},
        {"scene", pathAsGiven(job.scene_path)},
        {"scene_hash", scene_hash},
        {"sky", skyDescription(job.sky)},
        {"iterations", outcome ? std::to_string(outcome->iterations) : ""},
        {"seed", std::to_string(settings.seed)},
        {"history", settings.sharc.history.describe()},
        {"resolution", std::to_string(settings.width) + "x" + std::to_string(settings.height)},
        {"update_stride", std::to_string(settings.update_stride)},
        {"max_bounces", std::to_string(settings.path.max_bounces)},
        {"light_selection", job.light_selection_by_power ? "power" : "auto"},
        {"trace_kernels", traceKernelsName(job.trace_kernels)},
        {"camera", camera_description},
        {"radiance_scale", radianceScaleText(radiance_scale)},
        {"scene_scale", std::to_string(settings.sharc.grid.scene_scale)},
        {"log_base", std::to_string(settings.sharc.grid.logarithm_base)},
        {"level_bias", std::to_string(settings.sharc.grid.level_bias)},
        {"grid_choice", grid_choice},
        {"view_region", settings.view_region.describe()},
        {"levels_covered", levels_covered},
        {"capacity", std::to_string(outcome ? outcome->capacity : settings.sharc.grid.capacity)},
        {"left_out", workLeftOut(scene, lights)},
    };
    if (!capacity_choice.empty()) metadata.emplace_back("capacity_choice", capacity_choice);
    if (settings.shard_count > 1) {
        metadata.emplace_back("shard", std::to_string(settings.shard_index) + "/" + std::to_string(settings.shard_count));
    }
    return metadata;
}

/// With --capacity auto and --resume: the starting capacity and its description that the first
/// run chose (its checkpoint's settings), so the resumed bake continues on that table without a
/// pre-pass. The pre-pass does not depend on --iterations, so this is what a fresh one would
/// choose; a checkpoint of an older sharcbake, whose pre-pass did, keeps its own. Nothing when
/// the checkpoint cannot be read or was not an auto bake; resumeFromCheckpoint then reports
/// what is wrong.
std::optional<std::pair<uint32_t, std::string>> autoCapacityOfCheckpoint(const std::string& path) {
    CheckpointData data;
    std::string message;
    if (path.empty() || readCheckpointFile(path, &data, &message) != CacheFileStatus::kOk) return std::nullopt;
    std::string capacity, choice;
    for (const auto& [key, value] : data.settings) {
        if (key == "capacity") capacity = value;
        if (key == "capacity_choice") choice = value;
    }
    char* end = nullptr;
    const unsigned long slots = std::strtoul(capacity.c_str(), &end, 10);
    if (choice.empty() || capacity.empty() || *end != '\0' || slots < 16 || slots > (1ul << 28)) return std::nullopt;
    return std::make_pair(uint32_t(slots), choice);
}

/// What a resume must match: the metadata without the scene's path (the hash names the scene)
/// and the iteration count, plus the options that change the work but are not recorded in the
/// cache.
BakeSettingsText resumeSettings(const std::vector<std::pair<std::string, std::string>>& metadata,
                                const BakeJob& job) {
    BakeSettingsText settings;
    for (const auto& entry : metadata) {
        // The shard is added below for every bake; the metadata names it only for shards.
        if (entry.first != "scene" && entry.first != "iterations" && entry.first != "shard") settings.push_back(entry);
    }
    settings.emplace_back("shard", std::to_string(job.settings.shard_index) + "/" +
                                       std::to_string(job.settings.shard_count));
    settings.emplace_back("camera_options", job.camera.describe());
    return settings;
}

/// Options that do not change the bake's state (its table and voxels), only what is made from it
/// after the iterations: the cache's voxel materials, GPU radiance scale and predicted hit rate,
/// and the coverage report. The checkpoint records them under their option names; a resume with
/// other values warns and goes on (isCacheNeutralSetting).
BakeSettingsText cacheNeutralSettings(const BakeOptions& o) {
    char scale[32];
    std::snprintf(scale, sizeof scale, "%.9g", double(o.gpu_radiance_scale));
    return {{"--voxel-materials", o.voxel_materials ? "true" : "false"},
            {"--gpu-radiance-scale", scale},
            {"--prediction-views", std::to_string(o.prediction_views)},
            {"--coverage-points", std::to_string(o.coverage_points)}};
}

/// One `sharcbake bake`, phase by phase: the outputs checked and the checkpoint locked before
/// any work, the scene loaded and the bake set up, the iterations, the cache written, then what
/// is reported about it. Each phase is a function; the state they share is the members.
class BakeRun {
public:
    explicit BakeRun(const BakeOptions& o)
        : o_(o),
          threads_(o.threads > 0 ? int(o.threads) : tbb::info::default_concurrency()),
          checkpoint_path_(!o.checkpoint_path.empty() ? o.checkpoint_path : o.resume_path),
          job_(bakeJobFromOptions(o)) {}

    void run() {
        try {
            runOnWorkerThreads(threads_, [&] { runPhases(); });
        } catch (...) {
            // A refusal after the folder was made (an unknown --report-camera, a missing
            // --reference) left it behind, empty; remove() leaves a folder that holds anything.
            std::error_code error;
            if (made_report_folder_) std::filesystem::remove(o_.report_dir, error);
            throw;
        }
    }

private:
    void runPhases() {
        // --stats-json -: stdout carries the JSON alone, what is printed for people goes to stderr.
        HumanOutputOnStderr stats_on_stdout(isStandardOutput(o_.stats_json));
        // From before the checkpoint is locked: a signal while the scene loads and the bake is
        // set up (seconds for a large scene) stops it at the first iteration, with the lock
        // released and a checkpoint to resume, not with a lock left behind.
        stop_signals_.emplace();
        prepareOutputs();
        setUp();
        if (!o_.quiet) printPlan();
        iterate();
        writeCache();
        if (!o_.quiet) printSummary();
        if (evaluator_) writeReport();
        stats_on_stdout.release();
        warnAboutTheCache();
        if (!o_.stats_json.empty()) writeStatsJson();  // after the warnings, which it lists
        stopIfSignalled();
    }

    /// No output may be an input or another output; --resume F keeps checkpointing into F.
    void checkOutputs(const std::vector<std::string>& more_inputs) const {
        std::vector<std::string> others = {job_.scene_path, o_.resume_path, job_.sky.exr_path};
        others.insert(others.end(), more_inputs.begin(), more_inputs.end());
        checkOutputPath(o_.output_path, "cache", others);
        checkReplacesOnlyItsKind(o_.output_path, "cache", cacheFileIdentifier(), "a sharcbake cache");
        others.push_back(o_.output_path);
        if (!checkpoint_path_.empty()) {
            std::vector<std::string> checkpoint_others = others;
            std::erase(checkpoint_others, o_.resume_path);  // the one input it may replace
            checkOutputPath(checkpoint_path_, "checkpoint", checkpoint_others);
            // --resume's own file is read first, and refused there with what it is (exit 3).
            if (checkpoint_path_ != o_.resume_path) {
                checkReplacesOnlyItsKind(checkpoint_path_, "checkpoint", checkpointFileIdentifier(),
                                         "a sharcbake checkpoint");
            }
        }
        others.push_back(checkpoint_path_);
        if (!o_.stats_json.empty()) checkTextOutputPath(o_.stats_json, "stats JSON", others);
        others.push_back(o_.stats_json);
        if (!o_.report_dir.empty()) {
            for (const char* name : kConvergenceReportFiles) {
                const std::string file = (std::filesystem::path(o_.report_dir) / name).string();
                checkOutputPath(file, "report", others);
                others.push_back(file);
            }
        }
    }

    /// --report names a folder, made if missing. Checked before it is made: a folder made at the
    /// cache's path (--report equal to -o) was left behind by the refusal, and an existing file
    /// was called a folder that "does not exist".
    /// Returns whether it made the folder.
    bool prepareReportFolder() const {
        namespace fs = std::filesystem;
        std::error_code error;
        const fs::path folder = fs::weakly_canonical(fs::absolute(o_.report_dir, error), error);
        for (const auto& [other, what] : {std::pair{o_.output_path, "cache"}, std::pair{checkpoint_path_, "checkpoint"},
                                          std::pair{o_.stats_json, "stats JSON"}}) {
            if (other.empty() || isStandardOutput(other)) continue;
            if (fs::weakly_canonical(fs::absolute(other, error), error) == folder) {
                throw CommandError(kExitUsage, o_.report_dir + ": the report folder would take the " +
                                                   std::string(what) + "'s path; choose another --report folder");
            }
        }
        if (fs::exists(o_.report_dir, error) && !fs::is_directory(o_.report_dir, error)) {
            throw CommandError(kExitIo, o_.report_dir +
                                            ": --report names a file, not a folder: name a folder "
                                            "(made if missing) for the report's tables and plot");
        }
        const bool made = fs::create_directories(o_.report_dir, error);
        if (error) {
            throw CommandError(kExitIo, o_.report_dir + ": cannot make the report folder: " + error.message());
        }
        return made;
    }

    /// A fresh bake (no --resume) whose --checkpoint names an existing file would replace it at its
    /// first checkpoint: a rerun of a preempted job's command threw away 794 iterations so. Refused
    /// before any work; --resume continues it (a finished bake's checkpoint too), deleting it
    /// starts over.
    void refuseToOverwriteCheckpoint() const {
        if (!o_.resume_path.empty()) return;
        std::error_code error;
        const auto size = std::filesystem::file_size(checkpoint_path_, error);
        if (error || size == 0) return;
        throw CommandError(kExitUsage, checkpoint_path_ + ": --checkpoint names an existing file (" +
                                           std::to_string(size) +
                                           " bytes), which this fresh bake would replace: add "
                                           "--resume " +
                                           checkpoint_path_ +
                                           " to continue the bake it holds, or "
                                           "delete it to start over");
    }

    void prepareOutputs() {
        if (!o_.reference_path.empty()) requireRegularInputFile(o_.reference_path);  // before the scene loads
        made_report_folder_ = !o_.report_dir.empty() && prepareReportFolder();
        checkOutputs({});
        // Two bakes sharing one checkpoint: refuse the second now.
        if (!checkpoint_path_.empty()) {
            checkpointStep("", [&] { checkpoint_lock_.emplace(checkpoint_path_); });
            refuseToOverwriteCheckpoint();
        }
    }

    void setUp() {
        scene_ = loadSceneForCommand(job_.scene_path, job_.sky, o_.quiet, o_.limits);
        checkOutputs(scene_.source_files);  // the buffers and images the scene read
        scene_hash_ = sceneContentHash(scene_.source_files);
        if (scene_.empty()) {
            // What the loader left out, so a file of lines (CAD edges) or of degenerate triangles
            // says why nothing is left.
            const LoadStats& stats = scene_.stats;
            std::string why;
            const auto add = [&why](uint64_t count, const char* one, const char* many, const char* reason) {
                if (count > 0) {
                    why += (why.empty() ? " (" : "; ") + std::to_string(count) + (count == 1 ? one : many) + reason;
                }
            };
            add(stats.primitives_skipped, " primitive of points or lines skipped",
                " primitives of points or lines skipped", ": they have no surface");
            const uint64_t flat = stats.degenerate_triangles_dropped - stats.triangles_collapsed_by_rounding -
                                  stats.triangles_too_small_for_float;
            add(flat, " degenerate triangle dropped", " degenerate triangles dropped", ": they have no area");
            add(stats.triangles_too_small_for_float, " triangle too small for float32",
                " triangles too small for float32", " (edges of about 1e-9 units or less): scale the model up");
            add(stats.triangles_collapsed_by_rounding, " triangle collapsed", " triangles collapsed",
                " when rounded to float32 far from the origin: move the model towards the origin");
            throw CommandError(kExitInvalidInput, job_.scene_path + ": the scene has no triangles to bake" + why +
                                                      (why.empty() ? "" : ")"));
        }
        const auto setup_start = std::chrono::steady_clock::now();
        tracer_.emplace(scene_, job_.trace_kernels);
        warnWhenKernelsFellBack(job_.trace_kernels, *tracer_, "cache");
        job_.trace_kernels = tracer_->kernels();
        if (job_.light_selection_by_power) {
            lights_.emplace(scene_);
        } else {
            lights_.emplace(*tracer_);
        }
        warnWhenUnlit(scene_, *lights_, "cache");
        warnAboutPunctualLightUnits(*tracer_);
        camera_path_.emplace(makeCameraPath(job_, scene_, *tracer_, camera_description_, cameras_in_solids_));
        // The automatic grid fits what the roaming camera's positions (and the scene's cameras) see.
        if (job_.level_bias_auto) {
            seen_ = surfaceSeenFrom(*tracer_, bakeViewpoints(), kSeenSurfaceSamples, job_.settings.seed);
        }
        grid_decision_ = decideGrid(job_, *tracer_, seen_ ? &*seen_ : nullptr);
        if (roamingAtGltfCameras()) {
            // The runtime's cameras stay at the glTF cameras: bake what they look up from there.
            camera_path_.emplace(atGltfCameraPositions(scene_, job_.settings.seed));
            camera_description_ =
                "at the glTF cameras' positions, looking their own way and around (--view-region "
                "auto keeps the grid to them; --view-region free, or gltf with --camera-source "
                "explore, roams free space)";
        }
        // Along the rays of the camera the bake will use, the exploring one's having served the grid.
        warnWhenNoLightArrives();
        for (const std::string& warning : grid_decision_.warnings) warn(warning);
        warnAboutLeaks();
        if (autoCapacity()) chooseAutoCapacity();
        baker_ = std::make_unique<Baker>(*tracer_, *lights_, *camera_path_, job_.settings,
                                         SharcCache::chooseRadianceScale(estimateMaxRadiance(*tracer_)));
        resume_settings_ = resumeSettings(metadata(std::nullopt), job_);
        for (auto& setting : cacheNeutralSettings(o_)) resume_settings_.push_back(std::move(setting));
        if (!o_.resume_path.empty()) {
            std::vector<std::string> neutral_differences;
            checkpointStep("--resume: ", [&] {
                neutral_differences = resumeFromCheckpoint(o_.resume_path, resume_settings_, *baker_);
            });
            for (const std::string& difference : neutral_differences) {
                warn(formatted("--resume %s: %s (it does not change the baked voxels; the bake goes on)",
                               o_.resume_path.c_str(), difference.c_str()));
            }
        }
        first_iteration_ = baker_->iterationsDone();
        counters_at_start_ = baker_->counters();  // a checkpoint's: the rates count this run's rays
        if (first_iteration_ > o_.iterations) {
            // A checkpoint is never cut back: the cache holds every iteration it had.
            warn(
                formatted("%s holds %u iterations, more than --iterations %u: no more are baked, and the "
                          "cache holds all %u",
                          o_.resume_path.c_str(), first_iteration_, o_.iterations, first_iteration_));
        }
        report_.scene = job_.scene_path;
        if (o_.target_error > 0.0) report_.target_error = o_.target_error;
        evaluator_ = makeEvaluator(o_, scene_, *tracer_, *lights_, report_.reference);
        if (evaluator_) report_.view = evaluator_->view();
        setup_seconds_ = secondsSince(setup_start);
    }

    bool autoCapacity() const { return job_.capacity_auto; }

    std::vector<std::pair<std::string, std::string>> metadata(std::optional<BakeOutcome> outcome) const {
        return bakeMetadata(job_, scene_, scene_hash_, *lights_, baker_->cache().radianceScale(), camera_description_,
                            capacity_choice_text_, grid_decision_.choice, grid_decision_.levelsCovered(), outcome);
    }

    void chooseAutoCapacity() {
        if (const auto resumed = autoCapacityOfCheckpoint(o_.resume_path)) {
            // Resuming: the table the first run chose (chooseCapacity would choose it again).
            capacity_choice_.capacity = resumed->first;
            capacity_choice_text_ = resumed->second;
        } else {
            capacity_choice_ = chooseCapacity(*tracer_, *lights_, *camera_path_, job_.settings);
            capacity_choice_text_ = capacity_choice_.describe();
        }
        job_.settings.sharc.grid.capacity = capacity_choice_.capacity;
        job_.settings.sharc.grow_when_loaded = true;
    }

    void printPlan() const {
        if (job_.settings.shard_count > 1) {
            std::printf("Shard %u of %u: iterations k*%u + %u of the unsharded bake\n", job_.settings.shard_index,
                        job_.settings.shard_count, job_.settings.shard_count, job_.settings.shard_index);
        }
        if (!o_.resume_path.empty()) {
            std::printf("Resumed from %s after %s\n", o_.resume_path.c_str(),
                        counted(first_iteration_, "iteration").c_str());
        }
        std::printf("Camera: %s\n", camera_description_.c_str());
        std::printf("Grid: scene scale %.9g, log base %.9g, %s\n", double(job_.settings.sharc.grid.scene_scale),
                    double(job_.settings.sharc.grid.logarithm_base), grid_decision_.choice.c_str());
        std::printf("Views: %s; levels %s%s\n", job_.settings.view_region.describe().c_str(),
                    grid_decision_.levelsCovered().c_str(), grid_decision_.misses.c_str());
        if (autoCapacity()) {
            std::printf("Capacity %s, pre-pass %.2f s\n", capacity_choice_text_.c_str(), capacity_choice_.seconds);
        }
        std::printf("Light selection: %s\n", job_.light_selection_by_power
                                                 ? "by power (--light-selection power)"
                                                 : lights_->spatialSelection().describe().c_str());
        std::printf("Left out: %s\n", workLeftOut(scene_, *lights_).c_str());
        std::printf(
            "Baking: %u paths per iteration (%dx%d, stride %u), capacity %u, history %s, %s, "
            "Embree's %s kernels\n",
            baker_->pathsPerIteration(), job_.settings.width, job_.settings.height, job_.settings.update_stride,
            job_.settings.sharc.grid.capacity, job_.settings.sharc.history.describe().c_str(),
            counted(uint64_t(threads_), "thread").c_str(), traceKernelsName(tracer_->kernels()));
        std::fflush(stdout);
    }

    /// Bake time so far: evaluation pauses the bake, and its time is kept out of the bake's time
    /// and of --time-budget.
    double bakeSeconds() const { return secondsSince(bake_start_) - evaluation_seconds_; }

    /// Measures the cache as it stands (convergence_report.h) and returns the row.
    const ConvergenceRow& evaluate() {
        const double bake_time = bakeSeconds();
        const auto evaluation_start = std::chrono::steady_clock::now();
        ConvergenceRow row = evaluator_->evaluate(baker_->cache());
        row.iteration = baker_->iterationsDone();
        row.bake_seconds = bake_time;
        row.rays = baker_->counters().segments + baker_->counters().shadow_rays;
        evaluation_seconds_ += secondsSince(evaluation_start);
        report_.rows.push_back(row);
        return report_.rows.back();
    }

    void saveCheckpointNow() {
        checkpointStep("checkpoint: ", [&] { saveCheckpoint(checkpoint_path_, *baker_, resume_settings_); });
    }

    /// The iterations, until --iterations, a signal, --time-budget or --target-error stops them;
    /// then the report's last measures and the checkpoint of the end.
    void iterate() {
        bake_start_ = std::chrono::steady_clock::now();
        {
            Progress progress("Baking", "iterations", o_.iterations - std::min(o_.iterations, first_iteration_),
                              ProgressOutput::forCommand(o_.quiet, o_.progress_interval));
            uint32_t next_checkpoint = nextReportCheckpoint(0);
            while (next_checkpoint <= first_iteration_ && next_checkpoint != UINT32_MAX) {
                next_checkpoint = nextReportCheckpoint(next_checkpoint);
            }
            while (baker_->iterationsDone() < o_.iterations) {
                if (g_stop_signal != 0) {
                    stop_reason_ = g_stop_signal == SIGTERM ? "terminated" : "interrupted";
                    break;
                }
                if (o_.time_budget > 0.0 && bakeSeconds() >= o_.time_budget) {
                    stop_reason_ = "time budget";
                    break;
                }
                baker_->runIteration();
                progress.advance();
                progress.setDetail(std::to_string(baker_->cache().liveEntries()) + " voxels");
                if (!checkpoint_path_.empty() && baker_->iterationsDone() % o_.checkpoint_interval == 0) {
                    saveCheckpointNow();
                }
                if (evaluator_ && baker_->iterationsDone() == next_checkpoint) {
                    next_checkpoint = nextReportCheckpoint(next_checkpoint);
                    const std::optional<double> error = evaluate().primaryError();
                    if (o_.target_error > 0.0 && error && *error <= o_.target_error) {
                        stop_reason_ = "target error";
                        break;
                    }
                }
            }
            progress.finish();
        }
        if (evaluator_) finishEvaluation();
        // Whatever stopped the bake, the checkpoint holds its end: an interrupted bake continues
        // from here, a finished one can be extended with a larger --iterations.
        if (!checkpoint_path_.empty()) saveCheckpointNow();
        stop_signals_.reset();  // a signal from here on ends the process at once
        bake_seconds_ = bakeSeconds();
    }

    void finishEvaluation() {
        // The end point of every curve is the cache that is written.
        if (report_.rows.empty() || report_.rows.back().iteration != baker_->iterationsDone()) evaluate();
        const auto probes_start = std::chrono::steady_clock::now();
        evaluator_->finishProbes(report_.rows);
        report_.probe_floor = fitProbeFloor(report_.rows);
        evaluation_seconds_ += secondsSince(probes_start);
    }

    /// Coverage and the predicted hit rate (measured on the cache as written, and recorded in
    /// its metadata), then the file.
    void writeCache() {
        const auto finish_start = std::chrono::steady_clock::now();
        const SharcCache& cache = baker_->cache();
        levels_ = levelsPresent(cache);
        const bool bake_camera_levels = job_.settings.view_region.kind == ViewRegion::Kind::BakeCamera;
        coverage_ = measureCoverage(scene_, cache, levels_, o_.coverage_points,
                                    bake_camera_levels ? nullptr : &baker_->depositLevels());
        CacheData data = toCacheData(cache);
        // What the cache will answer: SHaRC's exact lookups from the scene's cameras and the region.
        prediction_ = predictHitRate(*tracer_, data, job_.settings.view_region,
                                     predictionViews(*tracer_, job_.settings.view_region, o_.prediction_views, job_.settings.seed));
        data.metadata = metadata(BakeOutcome{baker_->iterationsDone(), cache.capacity()});
        data.metadata.emplace_back("predicted_hit_rate", describeHitRate(prediction_));
        data.metadata.emplace_back("stop_reason", stop_reason_);
        data.gpu_radiance_scale = o_.gpu_radiance_scale;
        if (o_.voxel_materials) data.voxel_materials = computeVoxelMaterials(scene_, data, &voxel_material_stats_);
        std::string message;
        const CacheFileStatus status = writeCacheFile(o_.output_path, data, &message);
        if (status != CacheFileStatus::kOk) throw CommandError(kExitIo, message);
        // What a GPU SHaRC table would clip (fp16), from the file as written.
        CacheView written;
        if (CacheView::openFile(o_.output_path, &written, nullptr, CacheView::FileMode::kMap) == CacheFileStatus::kOk) {
            gpu_warning_ = written.gpuRadianceCheck().warning;
        }
        live_voxels_ = data.voxels.size();
        written_levels_ = levelsPresent(data);
        finish_seconds_ = secondsSince(finish_start);
        stability_ = makeStabilityReport(cache, baker_->counters(), scene_.bounds_min, scene_.bounds_max, levels_);
        if (lights_->hasLights())
            addSceneReflectance(stability_, estimateSceneReflectance(*tracer_, &*lights_, 2048, job_.settings.seed));
    }

    /// Whether the roaming camera stands at the glTF cameras' positions (atGltfCameraPositions):
    /// where `--view-region auto` kept the grid to them, and neither a --camera-path nor
    /// --camera-source gltf says where else it goes.
    bool roamingAtGltfCameras() const {
        return grid_decision_.auto_kept_to_gltf_cameras && job_.camera.source == CameraPathSource::Explore &&
               job_.camera.path_file.empty();
    }

    /// The roaming camera's waypoints and the scene's glTF cameras: where the bake looks from.
    std::vector<glm::vec3> bakeViewpoints() const {
        std::vector<glm::vec3> viewpoints;
        for (const CameraPose& pose : camera_path_->waypoints()) viewpoints.push_back(pose.position);
        for (const Camera& camera : scene_.cameras) viewpoints.push_back(camera.position);
        return viewpoints;
    }

    /// The roaming camera's rays: 64 poses spread over its path, `rays_per_pose` rays each.
    std::vector<Ray> probeRays(uint32_t rays_per_pose) const {
        return sampleCameraPathRays(*camera_path_, job_.settings.width, job_.settings.height, 64, rays_per_pose,
                                    job_.settings.seed);
    }

    /// A scene with lights whose light never reaches what the bake's camera sees (a sun inside a
    /// sky dome modelled as a plain sphere, a lamp inside a closed bulb) bakes a cache of zeros,
    /// which nothing numerical flags: said before baking, with what stops each light, when paths
    /// along 4096 of the roaming camera's rays meet surfaces but no light.
    void warnWhenNoLightArrives() {
        if (!lights_->hasLights()) return;  // warnWhenUnlit said so
        const std::vector<Ray> rays = probeRays(64);
        const LightProbe probe = probeLight(*tracer_, *lights_, rays, job_.settings.seed);
        if (probe.met_light || probe.surface_hits < kProbeHitsForAVerdict) return;
        warned_no_light_ = true;
        warn(
            formatted("none of %u paths from the roaming camera met light (%u of them met a surface), so "
                      "the cache will be black: %s",
                      probe.paths, probe.surface_hits, whyNoLightArrives(*tracer_, rays).c_str()));
    }

    /// Light leaks the voxels will cause, seen from the scene's own cameras (render's automatic
    /// camera without any; the roaming camera's waypoints for a box or points region of a scene
    /// without cameras): emitters nearer another surface than a voxel is wide, and walls thinner
    /// than a voxel between places the waypoints reach. Said before baking, so the artist can
    /// move or thicken them.
    void warnAboutLeaks() {
        std::vector<glm::vec3> waypoints;
        for (const CameraPose& pose : camera_path_->waypoints()) waypoints.push_back(pose.position);
        std::vector<glm::vec3> cameras;
        for (const PredictionView& view : declaredViews(*tracer_, job_.settings.view_region))
            cameras.push_back(view.camera.position);
        if (cameras.empty()) cameras = waypoints;
        light_leaks_ = findLightLeaks(*tracer_, job_.settings.sharc.grid, cameras, 256, job_.settings.seed);
        wall_leaks_ = findWallLeaks(*tracer_, job_.settings.sharc.grid, cameras, waypoints, 16384, job_.settings.seed);
        if (const std::string wall = wall_leaks_.describe(); !wall.empty()) warn(wall);
        constexpr size_t kLeaksNamed = 5;  // a city of lit windows would fill the log
        for (size_t i = 0; i < light_leaks_.leaks.size() && i < kLeaksNamed; ++i)
            warn(LightLeakReport::describe(light_leaks_.leaks[i]));
        if (light_leaks_.leaks.size() > kLeaksNamed) {
            warn(
                formatted("%zu more emissive materials leak light the same way (--stats-json lists "
                          "them under light_leaks)",
                          light_leaks_.leaks.size() - kLeaksNamed));
        }
    }

    /// Rays traced by this run, per second of its update stage: the counters a resumed bake
    /// restores from its checkpoint are not this run's (a resume of 64 + 64 iterations reported
    /// twice its rate, and one that baked none 1.7e16 rays/s).
    double raysPerSecond() const {
        const UpdateCounters& c = baker_->counters();
        return perUpdateSecond((c.segments + c.shadow_rays) - (counters_at_start_.segments + counters_at_start_.shadow_rays));
    }
    double segmentsPerSecond() const { return perUpdateSecond(baker_->counters().segments - counters_at_start_.segments); }
    /// `count` of this run's events per second of its update stage; 0 when it had none.
    double perUpdateSecond(uint64_t count) const {
        return count == 0 ? 0.0 : double(count) / std::max(baker_->seconds().update, 1e-9);
    }
    double occupancy() const {
        return double(baker_->cache().liveEntries()) / double(baker_->cache().capacity());
    }

    /// The summary's words for stop_reason_ (the stats JSON keeps the bare reason).
    static const char* howTheBakeStopped(const std::string& reason) {
        if (reason == "iterations") return "all --iterations done";
        if (reason == "time budget") return "stopped by --time-budget";
        if (reason == "target error") return "stopped at --target-error";
        if (reason == "interrupted") return "interrupted by SIGINT";
        if (reason == "terminated") return "terminated by SIGTERM";
        return "stopped";
    }

    void printSummary() const {
        const UpdateCounters& c = baker_->counters();
        const StageSeconds& stage = baker_->seconds();
        const uint32_t this_run = baker_->iterationsDone() - std::min(baker_->iterationsDone(), first_iteration_);
        std::printf("Baked %s%s in %.2f s (%s)\n", counted(baker_->iterationsDone(), "iteration").c_str(),
                    first_iteration_ > 0 ? formatted(", %u of them in this run,", this_run).c_str() : "", bake_seconds_,
                    howTheBakeStopped(stop_reason_));
        std::printf("  time: update %.2f s, commit %.2f s, resolve %.2f s; setup %.2f s, coverage+write %.2f s\n",
                    stage.update, stage.commit, stage.resolve, setup_seconds_, finish_seconds_);
        std::printf("  paths %llu, segments %llu, shadow rays %llu%s: %.3g rays/s, %.3g segments/s%s\n",
                    (unsigned long long)c.paths, (unsigned long long)c.segments, (unsigned long long)c.shadow_rays,
                    first_iteration_ > 0 ? " (all iterations)" : "", raysPerSecond(), segmentsPerSecond(),
                    first_iteration_ > 0 ? " (this run)" : "");
        std::printf("  cache: %llu live voxels, occupancy %.2f%% of %u, levels {%s}\n",
                    (unsigned long long)live_voxels_, 100.0 * occupancy(), baker_->cache().capacity(),
                    joined(written_levels_).c_str());
        // Where deposits go to other levels than the finest (gltf, path and box regions), the area
        // no path reached is its own figure.
        const ViewRegion::Kind region = job_.settings.view_region.kind;
        char deposit_levels[96] = "";
        if (region == ViewRegion::Kind::Points || region == ViewRegion::Kind::Box) {
            std::snprintf(deposit_levels, sizeof deposit_levels, ", %.2f%% none at the level its deposits go to",
                          100.0 * coverage_.unreached_deposit_area);
        }
        if (written_levels_.empty()) {
            std::printf("  coverage: %.2f%% of the surface area has no voxel (the cache is empty; %s tested)\n",
                        100.0 * coverage_.unreached_area, counted(coverage_.points, "point").c_str());
        } else {
            std::printf(
                "  coverage: %.2f%% of the surface area has no voxel at any level, %.2f%% none at the finest "
                "(level %u)%s (%s tested)\n",
                100.0 * coverage_.unreached_area, 100.0 * coverage_.unreached_finest_area, coverage_.finest_level,
                deposit_levels, counted(coverage_.points, "point").c_str());
        }
        std::printf("  predicted hit rate: %s\n", describeHitRate(prediction_).c_str());
        const std::vector<bool> listed = camerasToList(prediction_);
        for (size_t i = 0; i < prediction_.views.size(); ++i) {
            const ViewHitRate& v = prediction_.views[i];
            if (!listed[i]) continue;  // only declared views are listed
            if (v.eligible == 0 && v.refused > 0) {
                std::printf(
                    "    %s: no lookups pass SHaRC's tests (all %llu refused: each bounce is shorter than "
                    "its voxel)\n",
                    v.view.camera.name.c_str(), (unsigned long long)v.refused);
            } else if (v.eligible == 0) {
                std::printf("    %s: no lookups (no first bounce from it hits a surface)\n",
                            v.view.camera.name.c_str());
            } else {
                std::printf("    %s: %.1f%% of %llu lookups%s\n", v.view.camera.name.c_str(), 100.0 * v.rate(),
                            (unsigned long long)v.eligible,
                            v.eligible < kLookupsForARate ? " (too few for a rate: its first bounces leave the scene)"
                                                          : "");
            }
        }
        printUnlistedCameras(prediction_, listed);
        printStabilitySection(stdout, stability_);
        std::printf("Wrote %s (%llu voxels)\n", o_.output_path.c_str(), (unsigned long long)live_voxels_);
        if (o_.voxel_materials) {
            const VoxelMaterialStats& m = voxel_material_stats_;
            std::printf("  voxel materials (emission, demodulation factor) from %llu surface points; %llu voxels took "
                        "a coarser voxel's, %llu the scene's mean\n",
                        (unsigned long long)m.points, (unsigned long long)m.voxels_from_coarser,
                        (unsigned long long)m.voxels_from_scene_mean);
        }
    }

    /// Plain path tracing at equal time, the convergence table, and --report's files.
    void writeReport() {
        if (!o_.report_dir.empty() && evaluator_->measuresImage()) {
            // Plain path tracing of the same view for as long as the bake plus its last render took.
            const ConvergenceRow& last = report_.rows.back();
            const auto plain_start = std::chrono::steady_clock::now();
            report_.plain = evaluator_->plainPathTracing(last.bake_seconds + last.render_seconds, 1u << 16,
                                                        &report_.reference_floor);
            evaluation_seconds_ += secondsSince(plain_start);
        }
        report_.evaluation_seconds = evaluation_seconds_;
        if (!o_.quiet) printConvergence(report_, evaluator_->probes());
        if (o_.report_dir.empty()) return;
        try {
            writeConvergenceTables(o_.report_dir, report_);
        } catch (const std::runtime_error& e) {
            throw CommandError(kExitIo, e.what());
        }
        const std::string plot_problem = plotConvergence(o_.report_dir, report_);
        if (!plot_problem.empty()) warn(formatted("no convergence plot: %s", plot_problem.c_str()));
        if (!o_.quiet) {
            std::printf("Wrote %s/convergence.csv, plain_path_tracing.csv, convergence.json%s\n", o_.report_dir.c_str(),
                        plot_problem.empty() ? ", convergence.png" : "");
        }
    }

    void writeStatsJson() const {
        const UpdateCounters& c = baker_->counters();
        const StageSeconds& stage = baker_->seconds();
        Json json = provenanceJson("bake-stats", scene_, scene_hash_);
        json.update({
            {"output", o_.output_path},
            {"checkpoint", checkpoint_path_.empty() ? Json(nullptr) : Json(checkpoint_path_)},
            {"camera",
             {{"mode", roamingAtGltfCameras()          ? "gltf_positions"
                       : job_.camera.path_file.empty() ? toString(job_.camera.source)
                                                       : "file"},
              {"description", camera_description_}}},
            {"settings", metadataJson(metadata(BakeOutcome{baker_->iterationsDone(), baker_->cache().capacity()}))},
            {"iterations", baker_->iterationsDone()},
            {"stop_reason", stop_reason_},
            {"threads", threads_},
            {"seconds",
             {{"total", secondsSince(start_)},
              {"setup", setup_seconds_},
              {"bake", bake_seconds_},
              {"update", stage.update},
              {"commit", stage.commit},
              {"resolve", stage.resolve},
              {"finish", finish_seconds_},
              {"evaluation", evaluation_seconds_}}},
            {"paths", c.paths},
            {"segments", c.segments},
            {"shadow_rays", c.shadow_rays},
            {"rays_per_second", jsonNumber(raysPerSecond())},
            {"resampled_paths", c.resampled},
            {"live_voxels", live_voxels_},
            {"capacity", baker_->cache().capacity()},
            {"occupancy", jsonNumber(occupancy())},
            {"levels", written_levels_},
            {"coverage",
             {{"points", coverage_.points},
              {"unreached_area_fraction", coverage_.unreached_area},
              {"unreached_finest_level_area_fraction", coverage_.unreached_finest_area},
              {"unreached_deposit_level_area_fraction", coverage_.unreached_deposit_area},
              {"finest_level", coverage_.finest_level}}},
            {"grid",
             {{"scene_scale", jsonNumber(job_.settings.sharc.grid.scene_scale)},
              {"log_base", jsonNumber(job_.settings.sharc.grid.logarithm_base)},
              {"level_bias", jsonNumber(job_.settings.sharc.grid.level_bias)},
              {"level_bias_auto", job_.level_bias_auto},
              {"finest_voxel_size", jsonNumber(voxelSize(kHashGridLevelMin, job_.settings.sharc.grid))}}},
            {"view_region", job_.settings.view_region.describe()},
            {"levels_covered", grid_decision_.levelsCovered()},
            {"predicted_hit_rate", hitRateJson(prediction_)},
            {"stability", stabilityJson(stability_)},
            {"light_leaks", lightLeaksJson(light_leaks_)},
            {"wall_leaks",
             {{"points", wall_leaks_.points},
              {"seen_sides", wall_leaks_.seen_sides},
              {"leaking_sides", wall_leaks_.leaking_sides},
              {"share", jsonNumber(wall_leaks_.share)},
              {"voxel_size", jsonNumber(wall_leaks_.voxel_size)},
              {"warned", !wall_leaks_.describe().empty()}}},
            {"light_selection", lightSelectionJson(lights_->spatialSelection())},
            {"warnings", warningsGiven()},
        });
        writeTextOutput(o_.stats_json, "stats JSON", jsonText(json));
    }

    /// Warnings about what the cache lacks.
    void warnAboutTheCache() const {
        const SharcCache& cache = baker_->cache();
        // Every deposit goes to the level DepositLevels gives its point (the finest for the default
        // region, the level of the distance to the region's cameras for gltf, path and box), so a
        // point without a voxel there was never reached, whatever coarser voxels cover it.
        // A roaming camera kept to the glTF cameras' positions never reaches what they never see
        // (a lawn beyond the room's window): there the hit rate from those positions says what
        // the cache lacks, and the surface's coverage says nothing.
        const double unreached = roamingAtGltfCameras() ? 0.0
                                 : job_.settings.view_region.kind != ViewRegion::Kind::BakeCamera
                                     ? coverage_.unreached_deposit_area
                                     : coverage_.unreached_area;
        // A table too small for the scene drops most deposits: what the cache lacks is then not
        // the roaming camera's doing, and the warnings below that blame it would mislead (the
        // stability warning names --capacity).
        const bool table_full = stability_.share(stability_.failed_insert_energy) > kTableFullShare;
        if (baker_->iterationsDone() == 0) {
            warn(
                formatted("the cache is empty: no iteration ran (%s before the first), so every lookup will "
                          "miss",
                          howTheBakeStopped(stop_reason_)));
        } else if (!table_full) {
            warnAboutHitRate(prediction_, unreached, cameras_in_solids_, !scene_.cameras.empty());
        }
        if (baker_->iterationsDone() == 0 || table_full) {
            // Said above, or by the stability warning that names --capacity.
        } else if (live_voxels_ == 0) {
            // The file is valid, and every lookup from it will miss: say so once, plainly.
            const char* remedies = !job_.camera.path_file.empty() ? "a --camera-path whose cameras look at the scene"
                                   : job_.camera.source == CameraPathSource::GltfCameras
                                       ? "--camera-source explore (the free space around the glTF cameras)"
                                       : "more --explore-points, or a --camera-path that looks at the scene";
            warn(
                formatted("the cache is empty: no path from the roaming camera hit a surface, so every "
                          "lookup will miss. Check that the camera looks at the scene, or give %s",
                          remedies));
        } else if (unreached > 0.3) {
            // Not a stability problem, so not in that section, but the cache is missing much of the scene.
            char sight[200] = "";
            if (seen_ && seen_->fraction < kFitToSeenBelow) {
                std::snprintf(sight, sizeof sight,
                              "; the roaming camera's viewpoints see only %.2g%% of it (the grid is fitted to that "
                              "part), so the rest is out of their sight",
                              100.0 * seen_->fraction);
            }
            // The remedies that change where the camera goes, less the one already in use.
            const char* remedies = !job_.camera.path_file.empty()
                                       ? "a --camera-path through the places it misses, or --camera-source explore "
                                         "without a path"
                                   : job_.camera.source == CameraPathSource::GltfCameras
                                       ? "--camera-source explore (the free space around the glTF cameras), or a "
                                         "--camera-path through the scene"
                                   : scene_.cameras.empty()
                                       ? "--explore-points, or a --camera-path through the scene"
                                       : "--explore-points, a --camera-path through the scene, or --camera-source gltf";
            warn(
                formatted("%.0f%% of the surface area was never reached by the roaming camera (%u points "
                          "tested; hidden sides count too)%s: cameras that see it will miss. Give more --iterations, "
                          "%s",
                          100.0 * unreached, coverage_.points, sight, remedies));
        }
        if (live_voxels_ > 0 && stability_.deposits > 0 && !(stability_.deposited_energy > 0.0) &&
            lights_->hasLights() && !warned_no_light_) {
            // The probe before the bake found light the bake's own paths never did, or too few of
            // its rays met a surface to tell; more of the camera's rays find what it sees.
            warn(formatted("the cache is black: none of its %llu deposits carried light: %s",
                           (unsigned long long)stability_.deposits,
                           whyNoLightArrives(*tracer_, probeRays(1024)).c_str()));
        }
        if (!gpu_warning_.empty()) warn(formatted("GPU buffers: %s", gpu_warning_.c_str()));
        // Without the summary (-q) its Stability section's warnings would go unsaid.
        if (o_.quiet) {
            // Not through warn(): the stats JSON lists them under stability.warnings either way.
            for (const std::string& w : stability_.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
        }
        if (autoCapacity() && cache.numerics().failed_inserts > cache.numerics().failed_inserts_equal_halves) {
            // The table doubles between iterations; one iteration filled it faster than that.
            warn(formatted(
                "--capacity auto started at %u slots and grew to %u, but %llu deposits found no "
                "slot within an iteration; bake with a fixed --capacity %llu",
                job_.settings.sharc.grid.capacity, cache.capacity(),
                (unsigned long long)(cache.numerics().failed_inserts - cache.numerics().failed_inserts_equal_halves),
                2ull * cache.capacity()));
        }
    }

    /// The exit code of a bake a signal stopped (its outputs are written).
    static void stopIfSignalled() {
        if (g_stop_signal == SIGTERM) {
            throw CommandError(kExitTerminated,
                               "terminated (SIGTERM); the cache and checkpoint written hold the iterations done");
        }
        if (g_stop_signal != 0) throw CommandError(kExitInterrupted, "interrupted; the cache written holds the iterations done");
    }

    const BakeOptions& o_;
    const std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
    const int threads_;
    const std::string checkpoint_path_;
    std::optional<StopSignalHandlers> stop_signals_;
    std::optional<AbortSafeCheckpointLock> checkpoint_lock_;

    BakeJob job_;
    Scene scene_;
    std::string scene_hash_;
    std::optional<Tracer> tracer_;
    std::optional<LightSampler> lights_;
    GridDecision grid_decision_;
    std::optional<SeenSurface> seen_;  ///< what the roaming camera's positions see (--level-bias auto)
    std::string camera_description_;
    std::vector<std::string> cameras_in_solids_;  ///< makeCameraPath's, for the hit-rate warning
    bool warned_no_light_ = false;                ///< warnWhenNoLightArrives warned that the cache will be black
    std::optional<CameraPath> camera_path_;
    CapacityChoice capacity_choice_;
    std::string capacity_choice_text_;  ///< empty for a fixed --capacity
    std::unique_ptr<Baker> baker_;
    BakeSettingsText resume_settings_;
    bool made_report_folder_ = false;  ///< this bake made --report's folder (removed, if empty, on failure)
    uint32_t first_iteration_ = 0;
    UpdateCounters counters_at_start_;  ///< restored from --resume's checkpoint, else zero
    double setup_seconds_ = 0.0;

    ConvergenceReport report_;
    std::unique_ptr<ConvergenceEvaluator> evaluator_;
    std::chrono::steady_clock::time_point bake_start_;
    double evaluation_seconds_ = 0.0;
    double bake_seconds_ = 0.0;
    const char* stop_reason_ = "iterations";

    std::vector<uint32_t> levels_;
    CoverageReport coverage_;
    HitRatePrediction prediction_;
    uint64_t live_voxels_ = 0;
    VoxelMaterialStats voxel_material_stats_;  ///< --voxel-materials: how the means were found
    std::string gpu_warning_;               ///< fp16 clipping of the written cache at its GPU radiance scale
    std::vector<uint32_t> written_levels_;  ///< the levels of the cache file's voxels
    StabilityReport stability_;
    LightLeakReport light_leaks_;  ///< emitters sharing voxels with a surface behind them
    WallLeakReport wall_leaks_;    ///< surfaces sharing voxels across walls thinner than a voxel
    double finish_seconds_ = 0.0;
};

/// The file name `scene_path` gives its outputs in a batch: "level" for "maps/level.glb".
std::string sceneStem(const std::string& scene_path) { return std::filesystem::path(scene_path).stem().string(); }

/// One scene's options in a batch: the folders given for -o, --stats-json, --checkpoint and
/// --report hold that scene's files, named after it.
BakeOptions batchEntryOptions(const BakeOptions& batch, const std::string& scene_path) {
    const std::filesystem::path stem = sceneStem(scene_path);
    BakeOptions o = batch;
    o.scene_path = scene_path;
    o.output_path = (std::filesystem::path(batch.output_path) / stem).string() + ".sharc";
    if (!batch.stats_json.empty()) o.stats_json = (std::filesystem::path(batch.stats_json) / stem).string() + ".json";
    if (!batch.checkpoint_path.empty()) {
        o.checkpoint_path = (std::filesystem::path(batch.checkpoint_path) / stem).string() + ".ckpt";
    }
    if (!batch.report_dir.empty()) o.report_dir = (std::filesystem::path(batch.report_dir) / stem).string();
    return o;
}

/// What a batch cannot do, and the folders it writes into (created when missing).
void checkBatch(const BakeOptions& o) {
    const auto refuse = [](const std::string& why) { throw CommandError(kExitUsage, "several scenes: " + why); };
    if (!o.resume_path.empty()) refuse("--resume continues one bake; resume each scene on its own");
    if (!o.reference_path.empty()) refuse("--reference is an image of one scene");
    if (!o.camera_path.empty()) refuse("--camera-path is a path through one scene");
    if (isStandardOutput(o.stats_json)) {
        refuse("--stats-json - would write one JSON document per scene on stdout; give a folder for NAME.json");
    }
    std::set<std::string> stems;
    for (const std::string& scene : o.scene_paths) {
        if (!stems.insert(sceneStem(scene)).second) {
            refuse("two scenes named \"" + sceneStem(scene) + "\" would write the same outputs; bake them apart");
        }
    }
    // A folder named like one output file is a mistake (a folder called out/all.sharc was made).
    for (const auto& [folder, option, extension] :
         {std::tuple{o.output_path, "-o", ".sharc"}, std::tuple{o.stats_json, "--stats-json", ".json"},
          std::tuple{o.checkpoint_path, "--checkpoint", ".ckpt"}}) {
        std::error_code error;
        if (hasExtension(folder, extension) && !std::filesystem::is_directory(folder, error)) {
            refuse(std::string(option) + " " + folder +
                   " names a folder with several scenes (each scene's file goes "
                   "into it as NAME" +
                   extension + "), and this name looks like one file's: give a folder");
        }
    }
    for (const std::string& folder : {o.output_path, o.stats_json, o.checkpoint_path, o.report_dir}) {
        if (folder.empty()) continue;
        std::error_code error;
        std::filesystem::create_directories(folder, error);
        if (!std::filesystem::is_directory(folder, error)) {
            throw CommandError(kExitIo, folder + ": with several scenes -o, --stats-json, --checkpoint and --report "
                                                 "name folders, and this one cannot be made");
        }
    }
}

/// Several scenes, one after the other, each with its own outputs and outcome. A failing scene
/// does not stop the others; a signal stops the batch. The exit code is the first failure's.
void runBatch(const BakeOptions& batch) {
    checkBatch(batch);
    struct Outcome {
        std::string scene;
        std::string output;
        ExitCode code = kExitOk;
        std::string message;
    };
    std::vector<Outcome> outcomes;
    for (size_t i = 0; i < batch.scene_paths.size(); ++i) {
        const BakeOptions o = batchEntryOptions(batch, batch.scene_paths[i]);
        if (!o.quiet) std::printf("\n== Scene %zu of %zu: %s\n", i + 1, batch.scene_paths.size(), o.scene_path.c_str());
        Outcome outcome{o.scene_path, o.output_path};
        try {
            BakeRun(o).run();
        } catch (const CommandError& e) {
            std::fflush(stdout);  // the error after the scene's own lines, in a log that holds both
            std::fprintf(stderr, "sharcbake: error: %s\n", e.what());
            outcome.code = e.code();
            outcome.message = e.what();
        }
        outcomes.push_back(outcome);
        if (outcome.code == kExitInterrupted || outcome.code == kExitTerminated) break;
    }
    const auto failed = std::count_if(outcomes.begin(), outcomes.end(), [](const Outcome& x) { return x.code != 0; });
    // -q prints nothing but warnings and errors, a batch's summary included: each failure has
    // printed its error, and the exit code and the last error name the first one.
    if (!batch.quiet)
        std::printf("\nBatch: %zu of %s baked\n", outcomes.size() - size_t(failed),
                    counted(batch.scene_paths.size(), "scene").c_str());
    for (size_t i = 0; i < batch.scene_paths.size() && !batch.quiet; ++i) {
        if (i >= outcomes.size()) {
            std::printf("  not run   %s (the batch was stopped)\n", batch.scene_paths[i].c_str());
        } else if (outcomes[i].code == kExitOk) {
            std::printf("  ok        %s -> %s\n", outcomes[i].scene.c_str(), outcomes[i].output.c_str());
        } else {
            std::printf("  exit %-4d %s: %s\n", outcomes[i].code, outcomes[i].scene.c_str(), outcomes[i].message.c_str());
        }
    }
    std::fflush(stdout);
    for (const Outcome& x : outcomes) {
        if (x.code != kExitOk) throw CommandError(x.code, std::to_string(failed) + " of " +
                                                              std::to_string(batch.scene_paths.size()) +
                                                              " scenes failed (first: " + x.scene + ")");
    }
    if (outcomes.size() < batch.scene_paths.size()) throw CommandError(kExitInterrupted, "the batch was stopped");
}

/// The command's options as a TOML section that --config reads back: every option that has a
/// value (defaults included, so the file pins them) under its help text. Options left unset
/// (an empty path) are left out: read back, an empty value would be checked as a path. Paths are
/// written absolute: --config reads relative ones from the file's folder, and where the printed
/// file will be kept is not known here.
/// The options that shape the error report do nothing without one: `--reference out/ref.exr` alone
/// baked without a word of measurement. Refused, naming what they need. Compared with the
/// defaults, not counted as given: --print-config writes every option, defaults included.
void requireReportForReportOptions(const BakeOptions& o) {
    if (!o.report_dir.empty() || o.target_error > 0.0) return;
    const BakeOptions defaults;
    std::vector<std::string> given;
    if (o.reference_path != defaults.reference_path) given.push_back("--reference");
    if (o.report_camera != defaults.report_camera) given.push_back("--report-camera");
    if (o.report_resolution != defaults.report_resolution) given.push_back("--report-resolution");
    if (o.report_spp != defaults.report_spp) given.push_back("--report-spp");
    if (o.report_probes != defaults.report_probes) given.push_back("--report-probes");
    if (o.report_probe_spp != defaults.report_probe_spp) given.push_back("--report-probe-spp");
    if (given.empty()) return;
    std::string names;
    for (const std::string& name : given) names += (names.empty() ? "" : ", ") + name;
    throw CommandError(kExitUsage, names + (given.size() == 1 ? " shapes" : " shape") +
                                       " the error report, which only --report DIR (or --target-error E) makes: "
                                       "give one of them too, or leave " +
                                       (given.size() == 1 ? "it" : "them") + " out");
}

void printConfig(CLI::App& command) {
    makePathOptionsAbsolute(command);
    std::istringstream lines(command.config_to_str(true, true));
    std::string text = "# sharcbake " SHARCBAKE_VERSION " bake settings: sharcbake --config FILE bake [SCENE...]\n"
                       "# Paths are written absolute; relative ones, if you edit them in, are read from this "
                       "file's folder.\n[" +
                       command.get_name() + "]\n";
    std::string comment;
    for (std::string line; std::getline(lines, line);) {
        if (line.empty()) continue;
        if (line[0] == '#') {
            comment = line;
            continue;
        }
        const bool unset = line.size() >= 3 && line.compare(line.size() - 3, 3, "=\"\"") == 0;
        if (!unset && line.rfind("print-config", 0) != 0 && line.rfind("help", 0) != 0) {
            text += "\n" + comment + "\n" + line + "\n";
        }
        comment.clear();
    }
    std::fputs(text.c_str(), stdout);
}

void runBake(BakeOptions o) {
    if (o.scene_paths.size() > 1) return runBatch(o);
    o.scene_path = o.scene_paths.front();
    BakeRun(o).run();
}

}  // namespace

void registerBakeCommand(CLI::App& app) {
    auto o = std::make_shared<BakeOptions>();
    CLI::App* cmd = app.add_subcommand(
        "bake",
        "Bake a SHaRC radiance cache.\n\n"
        "A virtual camera roams the scene; every iteration traces sparse update paths from it\n"
        "(one random pixel per --update-stride block), deposits each path vertex's radiance into\n"
        "its hash-grid voxel, and resolves the voxels. The result is written as a .sharc file.\n"
        "Same scene, options and --seed give a byte-identical cache for any --threads.\n\n"
        "SHaRC picks a lookup's level from the runtime camera's distance, so each vertex is cached\n"
        "at every level a camera of --view-region can ask for there (default: anywhere, unless that\n"
        "fails the glTF cameras: nothing to look up, or voxels wider than their walls), on a grid\n"
        "whose finest level is fitted to the scene's units (--level-bias auto). After the bake the\n"
        "share of SHaRC's exact lookups the cache answers from the scene's cameras and sampled\n"
        "viewpoints is printed as the predicted hit rate (a warning below 95%).\n\n"
        "Examples:\n"
        "  sharcbake bake scenes/cornell_box/cornell_box.gltf -o out/cornell_box.sharc --iterations 512\n"
        "  sharcbake bake level.gltf -o level.sharc --view-region distance:0.5 --voxel-budget 1000000");
    pathOption(cmd->add_option("scene", o->scene_paths,
                               "glTF 2.0 scene (.gltf or .glb); several scenes bake one after the other, each with its "
                               "own outputs (then -o, --stats-json, --checkpoint and --report name folders holding "
                               "NAME.sharc, NAME.json, NAME.ckpt and NAME/ for each scene NAME)"))
        ->required();
    pathOption(
        cmd->add_option("-o,--output", o->output_path, "Output cache (.sharc), or its folder for several scenes"))
        ->required();
    cmd->add_option("--iterations", o->iterations, "Update + resolve iterations")->capture_default_str()->check(CLI::Range(1u, 1u << 30));
    cmd->add_option("--time-budget", o->time_budget, "Stop after this many seconds of baking (0 = no limit)")
        ->capture_default_str()->check(CLI::NonNegativeNumber)->check(kFiniteNumber);
    cmd->add_option("--threads", o->threads, "Worker threads: exactly this many, even beyond the core count (0 = one per core). The cache does not depend on it")->capture_default_str();
    cmd->add_option("--seed", o->seed, "Random seed")->capture_default_str();
    cmd->add_option("--scene-scale", o->scene_scale,
                    "SHaRC scene scale S: a voxel at camera distance d is about d/S wide, in any units (larger = "
                    "finer). auto = 50, the SDK sample's value. Copy it into the engine's SHaRC parameters "
                    "(sharcbake info shows it)")->capture_default_str();
    cmd->add_option("--gpu-radiance-scale", o->gpu_radiance_scale,
                    "Factor recorded in the cache for GPU buffers: an engine's SHaRC table gets radiance x this, "
                    "in fp16 (at most 65504). Use the engine's radiance units per scene unit (its exposure or "
                    "pre-exposure); a warning names the largest factor that clips nothing (docs/engine_guide.md)")
        ->capture_default_str()->check(CLI::PositiveNumber)->check(kFiniteNumber);
    cmd->add_flag("--voxel-materials", o->voxel_materials,
                  "Also store each voxel's mean emission and SHaRC demodulation factor (about 24 bytes per voxel), "
                  "so that GPU buffers can be made for engines whose SHaRC build keeps emission apart "
                  "(SHARC_SEPARATE_EMISSIVE) or demodulates materials (SHARC_MATERIAL_DEMODULATION); "
                  "docs/engine_guide.md");
    cmd->add_option("--log-base", o->log_base,
                    "SHaRC level logarithm base b (> 1); a power of two (2, the SDK's, or 4) makes the levels "
                    "nest exactly")->capture_default_str()->check(kFiniteNumber);
    cmd->add_option("--level-bias", o->level_bias,
                    "SHaRC level bias: sets the finest voxels, b^(1-bias)/S wide, which every camera closer than "
                    "b^(2-bias) uses. auto fits it to the scene's units: the finest level holds the visible surface "
                    "in about --voxel-budget voxels. A number is checked against the scene (warning when it spans "
                    "too few or too many voxels)")
        ->capture_default_str();
    cmd->add_option("--voxel-budget", o->voxel_budget,
                    "Voxels for the whole visible surface at the finest level (--level-bias auto), or for the "
                    "part the cameras' free space sees when that is under a quarter of it (a room beside a large "
                    "ground plane); each coarser level adds about a quarter of the one below. With --view-region "
                    "gltf, path, box or distance, the surface is counted at the level those cameras ask for at each "
                    "place instead (finer voxels where they stand, coarse far away)")
        ->capture_default_str()
        ->check(CLI::Range(uint64_t(64), uint64_t(1) << 28));
    cmd->add_option("--view-region", o->view_region,
                    "Where the runtime's cameras may be; each surface point the bake reaches is cached at every "
                    "level such a camera can ask for there. auto: free, unless free space fails the glTF cameras "
                    "(SHaRC would refuse 90% or more of their lookups, or their voxels would be wider than 1/8 of the "
                    "distance to what they see, leaking light through walls: a house on a vast ground) and gltf, in "
                    "the --voxel-budget or, where that is the default, the least of 1.5 to 16 times it that does, "
                    "serves them with voxels fine enough, then gltf; free: anywhere (every level from the finest up); "
                    "gltf: "
                    "at the scene's glTF cameras; path: at the --camera-path waypoints; box:x0,y0,z0,x1,y1,z1; "
                    "distance:MIN[:MAX]: never nearer than MIN to what it looks up; bake-camera: only the "
                    "roaming camera's own levels (the SDK's rule, no coverage)")
        ->capture_default_str();
    cmd->add_option("--prediction-views", o->prediction_views,
                    "Viewpoints of the region, besides the glTF cameras, from which the bake predicts its hit rate")
        ->capture_default_str()->check(CLI::Range(0u, 4096u));
    cmd->add_option("--capacity", o->capacity,
                    "Hash table slots (>= 16; a power of two is SDK-friendly), or \"auto\": sized from the scene "
                    "to start by a short pre-pass (4x the voxels that 16 iterations sampled over one loop of the "
                    "camera path reach, next power of two; the same for any --iterations, so a resumed bake "
                    "records what an uninterrupted one does), doubled between iterations whenever a quarter is "
                    "occupied")
        ->capture_default_str();
    cmd->add_option("--update-stride", o->update_stride, "One update path per NxN pixel block")
        ->capture_default_str()->check(CLI::Range(1u, 64u));
    cmd->add_option("--resolution", o->resolution, "Virtual camera image size WxH")->capture_default_str();
    cmd->add_option("--max-bounces", o->max_bounces, "Surface interactions per update path")
        ->capture_default_str()->check(CLI::Range(1u, 1024u));
    cmd->add_option("--light-selection", o->light_selection,
                    "How each path vertex picks the light it samples. auto: mostly by how much of each light "
                    "reaches its part of the scene, measured with shadow rays before the first path (by power "
                    "where that gains nothing; nothing is measured when the lights make one group); power: by "
                    "power alone, with no set-up (what earlier versions did; lamps a point cannot see take their share "
                    "of its samples)")
        ->capture_default_str()
        ->check(CLI::IsMember({"auto", "power"}));
    addTraceKernelsOption(cmd, o->trace_kernels);
    cmd->add_option("--propagation-depth", o->propagation_depth,
                    "Path vertices that receive the radiance found after them (SHARC_PROPAGATION_DEPTH); cache "
                    "resampling ends a path at a random depth up to this, so deeper paths carry more bounces per "
                    "iteration")
        ->capture_default_str()->check(CLI::Range(1u, 16u));
    cmd->add_option("--resampling", o->resampling,
                    "Where update paths end on the cache: random (the SDK's: a random depth up to "
                    "--propagation-depth) or end (only once --propagation-depth vertices wait, or at the last "
                    "vertex --max-bounces allows: that many bounces per iteration)")
        ->capture_default_str()->check(CLI::IsMember({"random", "end"}));
    cmd->add_option("--history", o->history,
                    "How voxels forget early (biased) iterations: ramp:P (iteration k weighs k^P), "
                    "window:A (SHaRC's exponential window of A iterations) or average")
        ->capture_default_str();
    cmd->add_option("--camera-source", o->camera_source_name,
                    "Where the roaming camera goes: explore (free space reachable from the glTF cameras; a "
                    "scene that is open around, such as a lone model, and has no camera or only cameras "
                    "outside its bounds, is also looked at from around it; a closed model without a camera "
                    "whose inside no light reaches, from around alone; where --view-region auto keeps the grid "
                    "to the glTF cameras, at their positions instead, looking their own way and around) or gltf "
                    "(gliding along the glTF cameras)")
        ->capture_default_str()
        ->check(CLI::IsMember({"explore", "gltf"}))
        ->each([o](const std::string& name) {
            o->camera_source = name == "gltf" ? CameraPathSource::GltfCameras : CameraPathSource::Explore;
        });
    pathOption(cmd->add_option("--camera-path", o->camera_path,
                               "Camera path file (overrides --camera-source): one waypoint per line, "
                               "\"px py pz tx ty tz [fov_degrees]\" (eye, the point it looks at, the vertical field "
                               "of view, 90 if not given; spaces or commas between), '#' comments"));
    cmd->add_option("--explore-points", o->explore_points,
                    "Free-space points the exploring camera visits, and as many views from around a scene looked "
                    "at from outside (see --camera-source)")
        ->capture_default_str()
        ->check(CLI::Range(1u, 4096u));
    cmd->add_option("--iterations-per-leg", o->iterations_per_leg,
                    "Iterations between consecutive waypoints (gltf / path file)")->capture_default_str()->check(CLI::Range(1u, 1u << 20));
    cmd->add_option("--coverage-points", o->coverage_points,
                    "Surface points tested for the coverage report (the share of the surface with no voxel at any "
                    "level, and with none at the finest level: the surface no update path reached)")
        ->capture_default_str();
    addSkyOptions(*cmd, o->sky);
    addSceneLimitOptions(*cmd, o->limits);
    pathOption(
        cmd->add_option("--stats-json", o->stats_json,
                        "Write the bake statistics as JSON to this file; - writes them to stdout, and what the bake "
                        "prints for people goes to stderr (one scene only)"));
    pathOption(cmd->add_option("--checkpoint", o->checkpoint_path,
                               "Save the bake state to this file every --checkpoint-interval iterations and at the end "
                               "(atomic: temporary file, then rename), so a killed bake can --resume"));
    cmd->add_option("--checkpoint-interval", o->checkpoint_interval,
                    "Iterations between checkpoints (counted in iterations, not seconds, so the files are "
                    "reproducible)")
        ->capture_default_str()->check(CLI::Range(1u, 1u << 30));
    pathOption(
        cmd->add_option("--resume", o->resume_path,
                        "Continue the bake saved in this checkpoint. Give the same scene and options as the "
                        "first run (--iterations may grow): the cache is byte-identical to an uninterrupted bake. "
                        "Other values of --voxel-materials, --gpu-radiance-scale, --prediction-views and "
                        "--coverage-points (they do not change the baked voxels) are warned about; any other "
                        "difference is refused. Checkpoints keep going to this file unless --checkpoint names "
                        "another"));
    cmd->add_option("--shard", o->shard,
                    "Bake share i of N (0 <= i < N) of the work of one bake of N x --iterations: iteration k "
                    "does iteration k*N+i of that bake (its camera pose and samples). Combine the N caches "
                    "with 'sharcbake merge'")
        ->capture_default_str();
    pathOption(
        cmd->add_option("--report", o->report_dir,
                        "Measure error against run time: at checkpoints 1, 2, 3, 4, 6, 8, 11, 16, ... iterations (two "
                        "per octave), measure the cache, then plain path tracing of the same view; write "
                        "DIR/convergence.csv, plain_path_tracing.csv, convergence.json and convergence.png "
                        "(gnuplot). Evaluation time is not counted in the bake's time. Works on any scene: the "
                        "cache is measured against a path-traced probe reference (--report-probes); --reference adds "
                        "an image comparison, a scene with a known radiance an exact voxel error"));
    pathOption(cmd->add_option(
        "--reference", o->reference_path,
        "Linear image (OpenEXR, PFM or Radiance HDR) of the evaluation camera (any converged render, e.g. "
        "sharcbake render --spp 4096): the image error is a render through the cache against it; its size is the "
        "evaluation size"));
    cmd->add_option("--report-camera", o->report_camera,
                    "Evaluation camera (default: the first): a glTF camera by its node's name, its own name or its "
                    "index #N, as render --camera");
    cmd->add_option("--report-resolution", o->report_resolution,
                    "Evaluation image size \"W\" or \"WxH\" when there is no --reference (default 128 wide)");
    cmd->add_option("--report-spp", o->report_spp, "Samples per pixel of the evaluation render through the cache, rendered as two independent "
                    "halves whose difference splits the image error into the render's own noise and the cache's "
                    "error (the \"less render noise\" column)")
        ->capture_default_str()->check(CLI::Range(1u, 1u << 16));
    cmd->add_option("--report-probes", o->report_probes,
                    "Surface points (spread by area over surfaces the cache reached) at which the report compares "
                    "the cache's voxels, at every level, with a path-traced reference; 0 = no probe measure")
        ->capture_default_str()->check(CLI::Range(0u, 1u << 16));
    cmd->add_option("--report-probe-spp", o->report_probe_spp,
                    "Path samples of each probe's reference; its noise is estimated and taken out of the error")
        ->capture_default_str()->check(CLI::Range(2u, 1u << 20));
    cmd->add_option(
           "--target-error", o->target_error,
           "Stop at the first checkpoint where the error is at most E (a fraction: 0.02 = 2%): the voxels' "
           "mean relative error against the known radiance where the scene has one, else the probes' mean "
           "relative error (over the probes live at the time), else the image's against --reference (sharcbake "
           "compare's, the same in any radiance units)")
        ->check(CLI::PositiveNumber)
        ->check(kFiniteNumber);
    cmd->add_flag("-q,--quiet", o->quiet, "No progress or summary output; warnings and errors still print");
    addProgressIntervalOption(*cmd, o->progress_interval);
    cmd->add_flag("--print-config", o->print_config,
                  "Print these options as a [bake] section for 'sharcbake --config FILE bake' and exit "
                  "without baking (paths made absolute: in a config file, relative ones are relative to its "
                  "folder)");
    cmd->callback([o, cmd] {
        if (o->print_config) return printConfig(*cmd);
        requireReportForReportOptions(*o);
        runBake(*o);
    });
}

}  // namespace sharcbake
