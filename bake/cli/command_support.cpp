// SPDX-License-Identifier: Apache-2.0
#include "cli/command_support.h"

#include "sharc/camera_path.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/format.h"
#include "sharcbake/scene_loader.h"
#include "support/fnv1a.h"
#include "support/median.h"
#include "tracing/lights.h"
#include "tracing/sampling.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake {

ExitCode exitCodeFor(CacheFileStatus status) {
    return status == CacheFileStatus::kIoError ? kExitIo : kExitInvalidInput;
}

const char* const kExitCodeHelp =
    "Exit status:\n"
    "  0    success\n"
    "  1    usage error (bad command line)\n"
    "  2    I/O error (a file could not be read or written, a scene's buffer file missing)\n"
    "  3    invalid input (a scene or cache file is malformed)\n"
    "  4    runtime failure\n"
    "  130  interrupted (SIGINT)\n"
    "  143  terminated (SIGTERM)\n";

namespace {
/// warn()'s record: a command is one process, and its warnings are said from its main thread or,
/// rarely, a worker (hence the lock).
struct WarningLog {
    std::mutex mutex;
    std::vector<std::string> given;
};
WarningLog& warningLog() {
    static WarningLog log;
    return log;
}
}  // namespace

void warn(const std::string& text) {
    WarningLog& log = warningLog();
    const std::lock_guard<std::mutex> lock(log.mutex);
    std::fprintf(stderr, "warning: %s\n", text.c_str());
    log.given.push_back(text);
}

std::vector<std::string> warningsGiven() {
    WarningLog& log = warningLog();
    const std::lock_guard<std::mutex> lock(log.mutex);
    return log.given;
}

std::string counted(uint64_t count, std::string_view singular, std::string_view plural) {
    std::string text = std::to_string(count) + " ";
    if (count == 1) return text.append(singular);
    if (!plural.empty()) return text.append(plural);
    return text.append(singular).append("s");
}

const CLI::Validator kFiniteNumber(
    [](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        if (end == text.c_str() || !std::isfinite(value)) return "expected a finite number, got \"" + text + "\"";
        return {};
    },
    "FINITE");

glm::vec3 parseVec3(const std::string& text, const std::string& option_name) {
    std::istringstream in(text);
    glm::vec3 v;
    char comma1 = 0, comma2 = 0;
    if (!(in >> v.x >> comma1 >> v.y >> comma2 >> v.z) || comma1 != ',' || comma2 != ',' ||
        !(in >> std::ws).eof() || !std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) {
        throw CommandError(kExitUsage, option_name + ": expected three finite numbers \"x,y,z\", got \"" +
                                           text + "\"");
    }
    return v;
}

namespace {

/// True when `a` and `b` name one file: the same device and inode when both exist (links
/// followed), else the same path once links and "." / ".." are resolved.
bool sameFile(const std::string& a, const std::string& b) {
    struct stat sa {}, sb {};
    const bool a_exists = ::stat(a.c_str(), &sa) == 0, b_exists = ::stat(b.c_str(), &sb) == 0;
    if (a_exists && b_exists) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    if (a_exists != b_exists) return false;
    std::error_code ea, eb;
    const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ea);
    const std::filesystem::path cb = std::filesystem::weakly_canonical(b, eb);
    return !ea && !eb && ca == cb;
}

}  // namespace

void checkOutputPath(const std::string& path, const std::string& what, const std::vector<std::string>& others) {
    namespace fs = std::filesystem;
    // A file literally named "-" is never what was meant; text reports take "-" for stdout, and
    // this output is not one of them.
    if (isStandardOutput(path)) {
        throw CommandError(kExitUsage, "the " + what + " cannot go to standard output (\"-\"): name a file");
    }
    std::string target, temporary, message;
    if (prepareOutputFile(path, &target, &temporary, &message) != CacheFileStatus::kOk) {
        throw CommandError(kExitIo, message + " (the " + what + ")");
    }
    const fs::path folder = fs::path(target).has_parent_path() ? fs::path(target).parent_path() : fs::path(".");
    std::error_code error;
    if (!fs::is_directory(folder, error)) {
        throw CommandError(kExitIo, path + ": cannot write the " + what + ": folder " + folder.string() +
                                        " does not exist");
    }
    if (::access(folder.c_str(), W_OK) != 0) {
        throw CommandError(kExitIo, path + ": cannot write the " + what + ": folder " + folder.string() +
                                        " is not writable");
    }
    // access() answers from the permission bits, and root passes them everywhere: a folder of
    // /sys or /proc, or one the file system refuses for another reason, passed this check and the
    // bake failed at its very end. Creating (and removing) a file there is the real test.
    const std::string probe = target + ".probe-" + std::to_string(::getpid());
    const int fd = ::open(probe.c_str(), O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (fd < 0) {
        const int why = errno;
        throw CommandError(kExitIo, path + ": cannot write the " + what + ": cannot create a file in folder " +
                                        folder.string() + ": " + std::strerror(why));
    }
    ::close(fd);
    ::unlink(probe.c_str());
    for (const std::string& other : others) {
        if (!other.empty() && sameFile(path, other)) {
            throw CommandError(kExitUsage, path + ": the " + what + " would overwrite " + other +
                                               ", which this command also reads or writes; choose another output");
        }
    }
}

void checkReplacesOnlyItsKind(const std::string& path, const std::string& what, std::string_view identifier,
                              const char* kind) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) return;  // a new file
    std::ifstream in(path, std::ios::binary);
    std::string head(identifier.size(), '\0');
    in.read(head.data(), std::streamsize(head.size()));
    const size_t read = size_t(std::max<std::streamsize>(in.gcount(), 0));
    if (read == 0 || (read == identifier.size() && head == identifier)) return;  // empty, or its kind
    throw CommandError(kExitUsage, path + ": exists and is not " + kind + ": writing the " + what +
                                       " there would destroy it. Remove it first if it is not needed, or choose "
                                       "another output");
}

/// "--seed: cannot read "abc" as UINT: expected a whole number ...": a value the option's type
/// cannot hold, named with the type and what it accepts.
std::string unreadableValueMessage(const std::string& name, const std::string& value, const std::string& full_type) {
    const std::string type = full_type.substr(0, full_type.find(':'));
    const char* accepts = type == "UINT"    ? "a whole number of 0 or more, in digits, that fits the option "
                                              "(most hold up to 4294967295)"
                          : type == "INT"   ? "a whole number, in digits, that fits the option"
                          : type == "FLOAT" ? "a number"
                                            : nullptr;
    return name + ": cannot read \"" + value + "\"" + (type.empty() ? "" : " as " + type) +
           (accepts ? std::string(": expected ") + accepts : std::string());
}

/// From CLI11's range check, "--time-budget: Value abc not in range 0.000000 to 1797693...": its
/// range check runs before the conversion, so a word was called out of range, with the largest
/// double written out in 310 digits. A value that is no number of the option's type is named so;
/// one out of range gets its bounds as a person writes them.
std::string rangeErrorMessage(const std::string& what, const std::string& type) {
    const size_t colon = what.find(": Value ");
    const size_t range = what.find(" not in range ");
    const size_t to = what.find(" to ", range == std::string::npos ? 0 : range);
    if (colon == std::string::npos || range == std::string::npos || to == std::string::npos) return what;
    const std::string name = what.substr(0, colon);
    const std::string value = what.substr(colon + 8, range - colon - 8);
    const bool whole = type.rfind("UINT", 0) == 0 || type.rfind("INT", 0) == 0;
    char* end = nullptr;
    const double number = std::strtod(value.c_str(), &end);
    const bool is_number = !value.empty() && end == value.c_str() + value.size() && std::isfinite(number);
    if (!is_number || (whole && number != std::floor(number))) return unreadableValueMessage(name, value, type);
    const double low = std::strtod(what.c_str() + range + 14, nullptr);
    const double high = std::strtod(what.c_str() + to + 4, nullptr);
    char bounds[96];
    if (type.find("POSITIVE") != std::string::npos) {
        std::snprintf(bounds, sizeof bounds, "greater than 0");
    } else if (high >= 1e300) {
        std::snprintf(bounds, sizeof bounds, "at least %g", low);
    } else {
        std::snprintf(bounds, sizeof bounds, "from %.17g to %.17g", low, high);
    }
    return name + ": " + value + " is out of range: expected " + bounds;
}

bool hasExtension(const std::string& path, const char* extension) {
    std::string ext = std::filesystem::path(path).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext == extension;
}

std::string_view cacheFileIdentifier() {
    return {reinterpret_cast<const char*>(kCacheIdentifier), sizeof kCacheIdentifier};
}
std::string_view checkpointFileIdentifier() {
    return {reinterpret_cast<const char*>(kCheckpointIdentifier), sizeof kCheckpointIdentifier};
}
std::string_view vdbFileIdentifier() {
    // OpenVDB's magic number 0x56444220 ("VDB "), written first as a little-endian 64-bit integer.
    static constexpr char kVdbMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};
    return {kVdbMagic, sizeof kVdbMagic};
}

namespace {
constexpr const char* kPathTypeName = "PATH";
}  // namespace

CLI::Option* pathOption(CLI::Option* option) { return option->type_name(kPathTypeName); }

bool isPathOption(const CLI::Option& option) {
    // The type name, with ":" and the descriptions of any checks after it.
    return option.get_type_name().rfind(kPathTypeName, 0) == 0;
}

void checkTextOutputPath(const std::string& path, const std::string& what, const std::vector<std::string>& others) {
    if (!isStandardOutput(path)) checkOutputPath(path, what, others);
}

void writeTextOutput(const std::string& path, const std::string& what, const std::string& text) {
    if (isStandardOutput(path)) {
        if (std::fputs(text.c_str(), stdout) == EOF || std::fflush(stdout) != 0) {
            throw CommandError(kExitIo, "cannot write the " + what + " to standard output: " + std::strerror(errno));
        }
        return;
    }
    std::string message;
    if (writeFileAtomically(path, text.data(), text.size(), &message) != CacheFileStatus::kOk) {
        throw CommandError(kExitIo, "cannot write the " + what + ": " + message);
    }
}

HumanOutputOnStderr::HumanOutputOnStderr(bool active) {
    if (!active) return;
    std::fflush(stdout);
    saved_stdout_ = ::dup(STDOUT_FILENO);
    if (saved_stdout_ < 0) return;  // no stdout to keep clean
    if (::dup2(STDERR_FILENO, STDOUT_FILENO) < 0) {
        ::close(saved_stdout_);
        saved_stdout_ = -1;
        return;
    }
    // stdout stays line-buffered (main sets it), so its lines keep their order among the warnings.
}

void HumanOutputOnStderr::release() {
    if (saved_stdout_ < 0) return;
    std::fflush(stdout);
    ::dup2(saved_stdout_, STDOUT_FILENO);
    ::close(saved_stdout_);
    saved_stdout_ = -1;
}

namespace {

/// The indices of the scene's cameras for which `matches` is true.
template <class Matches>
std::vector<size_t> camerasWhere(const Scene& scene, Matches matches) {
    std::vector<size_t> found;
    for (size_t i = 0; i < scene.cameras.size(); ++i) {
        if (matches(scene.cameras[i])) found.push_back(i);
    }
    return found;
}

/// "#0 node 'Persp', glTF camera 'Camera', #1 ..." for the given cameras.
std::string cameraList(const Scene& scene, const std::vector<size_t>& indices) {
    std::string list;
    for (const size_t i : indices) list += (list.empty() ? "" : ", ") + cameraListEntry(scene.cameras[i]);
    return list;
}

/// "#N" or "N" as an index into the scene's cameras; nothing when `selector` is neither.
std::optional<size_t> cameraIndex(const std::string& selector) {
    const std::string digits = !selector.empty() && selector[0] == '#' ? selector.substr(1) : selector;
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) {
        return std::nullopt;
    }
    return size_t(std::stoul(digits));
}

}  // namespace

Camera sceneCamera(const Scene& scene, const std::string& selector, const std::string& option_name, float fov_degrees,
                   const Tracer* tracer) {
    if (selector.empty()) {
        if (!scene.cameras.empty()) return scene.cameras.front();
        return tracer ? automaticCamera(*tracer, glm::radians(fov_degrees))
                      : automaticCamera(scene, glm::radians(fov_degrees));
    }
    // Node names first: they are the names users see (Blender's object names), and several nodes
    // may place one glTF camera, which its own name cannot tell apart.
    const std::vector<size_t> by_node = camerasWhere(scene, [&](const Camera& c) { return c.node_name == selector; });
    const std::vector<size_t> by_name = camerasWhere(scene, [&](const Camera& c) { return c.name == selector; });
    for (const auto& [found, what] : {std::pair(&by_node, "node name"), std::pair(&by_name, "glTF camera name")}) {
        if (found->size() == 1) return scene.cameras[found->front()];
        if (found->size() > 1) {
            throw CommandError(kExitUsage, option_name + " " + selector + ": " + std::to_string(found->size()) +
                                               " cameras have that " + what + " (" + cameraList(scene, *found) +
                                               "); choose one by its index, e.g. " + option_name + " '#" +
                                               std::to_string(found->front()) + "'");
        }
    }
    if (const std::optional<size_t> index = cameraIndex(selector); index && *index < scene.cameras.size()) {
        return scene.cameras[*index];
    }
    std::vector<size_t> all(scene.cameras.size());
    std::iota(all.begin(), all.end(), size_t(0));
    throw CommandError(kExitUsage, option_name + " " + selector + ": no such camera in the scene (" +
                                       (all.empty() ? "it has none" : "it has " + cameraList(scene, all)) +
                                       "; give a node name, a glTF camera name or an index #N)");
}

std::string describeCamera(const Camera& camera) {
    const glm::vec3 target = camera.position + camera.forward;
    char text[256];
    std::snprintf(text, sizeof text, "%s at (%g, %g, %g) looking at (%g, %g, %g), up (%g, %g, %g), ",
                  (camera.index >= 0 ? cameraLabel(camera) : "'" + camera.name + "'").c_str(), camera.position.x,
                  camera.position.y, camera.position.z, target.x, target.y, target.z, camera.up.x, camera.up.y,
                  camera.up.z);
    std::string result = text;
    if (camera.orthographic_half_height) {
        std::snprintf(text, sizeof text, "orthographic, %g high", 2.0 * double(*camera.orthographic_half_height));
    } else {
        std::snprintf(text, sizeof text, "vertical fov %.3g deg", double(glm::degrees(camera.yfov)));
    }
    return result + text;
}

void warnAboutCameraFit(const Camera& camera, const Camera& fitted, int width, int height) {
    if (!camera.aspect_ratio) return;
    // What the fit changed: an orthographic view's height, or the vertical field of view.
    const bool orthographic = camera.orthographic_half_height.has_value();
    const float before = orthographic ? *camera.orthographic_half_height : camera.yfov;
    const float after = orthographic ? *fitted.orthographic_half_height : fitted.yfov;
    if (after == before) return;
    char change[160];
    if (orthographic) {
        std::snprintf(change, sizeof change, "the view's longer side spans the image's longer side; %g high instead of %g",
                      2.0 * double(after), 2.0 * double(before));
    } else {
        std::snprintf(change, sizeof change,
                      "the field of view of the camera's longer side spans the image's longer side; vertical field "
                      "of view %.3g deg instead of %.3g",
                      double(glm::degrees(after)), double(glm::degrees(before)));
    }
    warn(
        formatted("%s%s has aspect ratio %.3g but the image is %dx%d (%.3g): framed as Blender's sensor "
                  "fit Auto frames it (%s). Give only the width (--resolution %d) for the camera's own frame",
                  orthographic ? "orthographic " : "", cameraLabel(camera).c_str(), double(*camera.aspect_ratio), width,
                  height, double(width) / double(height), change, width));
}

namespace {

/// Why a punctual light the light sampler left out gives no light.
std::string whyDark(const PunctualLight& light) {
    if (light.type == LightType::Spot && !(light.outer_cone_angle > 0.0f)) return "a spot cone of angle 0";
    return "intensity 0 or a black colour";
}

}  // namespace

void addTraceKernelsOption(CLI::App* command, std::string& kernels) {
    command
        ->add_option("--trace-kernels", kernels,
                     "Which of Embree's ray-tracing kernels trace the rays. Kernels of different widths round and "
                     "order their triangle tests differently: a ray that grazes an edge can hit the other triangle, "
                     "and its path, and the result, go another way. avx2: AVX2's kernels, which Intel Core and Xeon "
                     "CPUs since 2013 and AMD's since 2015 all run, so their caches agree (SSE4.2's, with a warning, "
                     "on a CPU without AVX2); sse4.2: kernels every x86-64 CPU runs, slower; native: Embree's choice "
                     "for this CPU (AVX-512 where it has it), so caches agree only between CPUs where it chooses "
                     "alike. docs/baking.md says what was checked")
        ->capture_default_str()
        ->check(CLI::IsMember(traceKernelsNames()));
}

void warnWhenKernelsFellBack(TraceKernels asked, const Tracer& tracer, const char* result) {
    if (tracer.kernels() == asked) return;
    warn(formatted(
        "this CPU has no AVX2 and FMA: tracing with Embree's %s kernels instead of its %s ones, so "
        "the %s can differ from one made on a CPU with them (--trace-kernels %s there runs these kernels too; "
        "glibc's maths, without FMA here, still round some results differently)",
        traceKernelsName(tracer.kernels()), traceKernelsName(asked), result, traceKernelsName(tracer.kernels())));
}

void warnWhenUnlit(const Scene& scene, const LightSampler& lights, const char* result) {
    if (lights.hasLights()) return;
    // "No lights" would be false for a scene whose lights all give none: name them and why.
    std::string what = "no lights";
    if (!scene.lights.empty()) {
        std::string dark;
        for (const uint32_t i : lights.darkLights()) {
            const PunctualLight& light = scene.lights[i];
            dark += std::string(dark.empty() ? "" : ", ") + lightLabel(scene, i) + ": " + whyDark(light);
        }
        what = "no light from its punctual lights (" + dark + ")";
    }
    // Models made for glTF viewers (sample collections, asset stores) carry no lights: viewers light
    // them with an environment, which is what --sky gives.
    warn(
        formatted("the scene has %s, no emissive surfaces and a black sky: the %s will be black. A model made "
                  "for glTF viewers is lit by their environment: give it one with --sky r,g,b (e.g. --sky 1,1,1) or "
                  "--sky-exr FILE",
                  what.c_str(), result));
}

void warnAboutPunctualLightUnits(const Tracer& tracer) {
    const Scene& scene = tracer.scene();
    // Each point or spot light's median distance to the surfaces around it (rays in 64 directions
    // that hit), then the median over the lights.
    constexpr uint32_t kDirections = 64;
    std::vector<float> light_distances;
    for (const PunctualLight& light : scene.lights) {
        if (light.type == LightType::Directional) continue;
        std::vector<float> distances = hitDistancesAround(tracer, light.position, kDirections);
        if (!distances.empty()) light_distances.push_back(median(std::move(distances)));
    }
    if (light_distances.empty()) return;
    const float distance = median(std::move(light_distances));
    if (!(distance > kFarPunctualLightDistance)) return;
    warn(
        formatted("the scene's point and spot lights are a median %.3g units from the surfaces around them. glTF's "
                  "units are metres, and these lights fall off with the squared distance (their intensity is in "
                  "candela), so they light this scene as lamps %.3g m away would: if it was modelled in "
                  "millimetres (CAD, some exporters' unit settings), they are 10^6 times too dim (in "
                  "centimetres 10^4). Scale it to metres (a 0.001 or 0.01 scale on its root node, or the "
                  "exporter's unit setting); emissive surfaces, the "
                  "sky and the grid do not depend on the units, these lights do",
                  double(distance), double(distance)));
}

void parseImageSize(const std::string& text, const std::string& option_name, std::optional<float> aspect, int& width,
                    int& height, const std::string& aspect_source) {
    width = 0;
    height = 0;
    char x = 0;
    std::istringstream in(text);
    if (!(in >> width) || width <= 0 || (in >> x && (x != 'x' || !(in >> height) || height <= 0)) ||
        !(in >> std::ws).eof()) {
        throw CommandError(kExitUsage, option_name + ": expected W or WxH with positive integers, got \"" + text + "\"");
    }
    constexpr int64_t kMaxPixels = int64_t(1) << 28;
    const bool height_from_aspect = height == 0;
    if (height_from_aspect) {
        // In double: a tiny aspect ratio would overflow an int.
        const double tall = std::max(1.0, std::round(double(width) / double(aspect.value_or(1.0f))));
        if (aspect && double(width) * tall > double(kMaxPixels)) {
            char message[512];
            std::snprintf(message, sizeof message,
                          "%s %s: %s has aspect ratio %g, which would make the image %d x %.0f pixels, too large; "
                          "give both sides (%s %dx%d)",
                          option_name.c_str(), text.c_str(), aspect_source.c_str(), double(*aspect), width, tall,
                          option_name.c_str(), width, width);
            throw CommandError(kExitUsage, message);
        }
        height = int(tall);
    }
    if (int64_t(width) * int64_t(height) > kMaxPixels) {
        throw CommandError(kExitUsage, option_name + " " + text + ": image too large (at most 2^28 pixels)");
    }
}

void addSkyOptions(CLI::App& command, SkyOptions& options) {
    command.add_option("--sky", options.uniform,
                       "Uniform sky radiance \"r,g,b\" (linear), replacing the scene's sky "
                       "(scenes may set one in scene extras: sharcbake.sky_radiance)");
    pathOption(command.add_option("--sky-exr", options.exr_path,
                                  "Equirectangular EXR environment map for the sky (+Y up, Blender's "
                                  "orientation)"));  // a missing file is an I/O error when it is read (exit 2)
    command
        .add_option("--sky-scale", options.scale,
                    "Multiplier for the sky map (refused where it takes a texel or the sky's total beyond "
                    "float32)")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber)
        ->check(kFiniteNumber);
}

void addSceneLimitOptions(CLI::App& command, GltfLoadLimits& limits) {
    command.add_option("--max-texture-size", limits.max_texture_size,
                       "Refuse scene images wider or taller than this many texels (checked before decoding)")
        ->capture_default_str()
        ->check(CLI::Range(1u, 1u << 16));
}

/// FNV-1a (64-bit) of the bytes of the scene's files one after the other (the glTF or GLB, then
/// its external buffers and images: Scene::source_files), so a cache records which scene it was
/// baked from, geometry included.
std::string sceneContentHash(const std::vector<std::string>& files) {
    uint64_t hash = kFnv1a64Basis;
    std::vector<char> buffer(1 << 16);
    for (const std::string& file : files) {
        std::ifstream in(file, std::ios::binary);
        if (!in) throw CommandError(kExitIo, file + ": cannot read (a file of the scene)");
        while (in.read(buffer.data(), std::streamsize(buffer.size())) || in.gcount() > 0) {
            hash = fnv1a64(buffer.data(), size_t(in.gcount()), hash);
        }
    }
    char text[32];
    std::snprintf(text, sizeof text, "fnv1a64:%016llx", (unsigned long long)hash);
    return text;
}

/// The sky the bake used where it is not the scene file's own (that one is in scene_hash): a
/// uniform radiance as parsed, or a map by the hash of its bytes and its scale. Shards baked
/// under different skies must not merge.
std::string skyDescription(const SkyOptions& sky) {
    if (!sky.uniform.empty()) {
        const glm::vec3 radiance = parseVec3(sky.uniform, "--sky");
        char text[96];
        std::snprintf(text, sizeof text, "uniform %.9g,%.9g,%.9g", radiance.x, radiance.y, radiance.z);
        return text;
    }
    if (!sky.exr_path.empty()) {
        char scale[32];
        std::snprintf(scale, sizeof scale, "%.9g", sky.scale);
        return "map " + sceneContentHash({sky.exr_path}) + " x " + scale;
    }
    return "scene";
}

void addProgressIntervalOption(CLI::App& command, double& seconds) {
    command
        .add_option("--progress-interval", seconds,
                    "Seconds between progress lines (done, elapsed, ETA) printed when stdout is not a "
                    "terminal, as in a pipe, a log file or CI; 0: none. A terminal shows a bar instead")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 86400.0));
}

namespace {

std::string shortNumber(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", value);
    return text;
}

/// --sky-scale multiplies the map's texels where paths read them (Sky::scale), in float32. A
/// product beyond float32's range is as infinite as a texel stored so, which loadEquirectExr
/// refuses: every path that escapes towards it would be dropped as non-finite. So is a sky whose
/// total, its radiance integrated over all directions, overflows float32 (the light sampler
/// weighs the sky by such a sum).
void checkScaledSky(const std::string& path, const Texture& map, float scale) {
    uint64_t overflowing = 0;
    float largest = 0.0f;
    double total = 0.0;  // sum of texel radiance x solid angle, channels averaged, then scaled
    const double pi = std::acos(-1.0);
    for (int y = 0; y < map.height; ++y) {
        const double sin_theta = std::sin(pi * (double(y) + 0.5) / double(map.height));
        const double solid_angle = (2.0 * pi / double(map.width)) * (pi / double(map.height)) * sin_theta;
        for (int x = 0; x < map.width; ++x) {
            const glm::vec4& texel = map.texels[size_t(y) * size_t(map.width) + size_t(x)];
            for (int c = 0; c < 3; ++c) {
                overflowing += std::isfinite(texel[c] * scale) ? 0 : 1;
                largest = std::max(largest, texel[c]);
            }
            total += (double(texel.x) + double(texel.y) + double(texel.z)) / 3.0 * solid_angle;
        }
    }
    total *= double(scale);
    const std::string advice = "; lower --sky-scale (the radiance of the scene scales with it)";
    if (overflowing > 0) {
        throw CommandError(kExitInvalidInput, path + ": " + std::to_string(overflowing) +
                                                  " colour values are infinite at --sky-scale " + shortNumber(scale) +
                                                  " (the brightest texel, " + shortNumber(largest) +
                                                  ", times the scale is beyond float32's 3.4e38)" + advice);
    }
    if (!(total <= double(std::numeric_limits<float>::max()))) {
        throw CommandError(kExitInvalidInput, path +
                                                  ": the sky's total radiance (over all directions) is infinite "
                                                  "at --sky-scale " +
                                                  shortNumber(scale) + ", beyond float32's 3.4e38" + advice);
    }
}

}  // namespace

void requireRegularInputFile(const std::string& path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        throw CommandError(kExitIo, path + (std::filesystem::exists(path, error)
                                                ? ": not a regular file (a FIFO, device or folder)"
                                                : ": no such file"));
    }
}

Scene loadSceneForCommand(const std::string& path, const SkyOptions& sky, bool quiet, const GltfLoadLimits& limits) {
    requireRegularInputFile(path);
    std::error_code error;
    if (!sky.exr_path.empty() && !std::filesystem::is_regular_file(sky.exr_path, error)) {
        throw CommandError(kExitIo, sky.exr_path + ": --sky-exr is not a regular file");
    }
    Scene scene;
    try {
        scene = loadGltf(path, limits);
        if (!sky.exr_path.empty()) {
            scene.sky.map = loadEquirectExr(sky.exr_path);
            scene.sky.scale = sky.scale;
        }
    } catch (const SceneLoadError& e) {
        throw CommandError(e.kind() == SceneLoadError::Kind::kMissingFile ? kExitIo : kExitInvalidInput, e.what());
    }
    if (scene.sky.map && sky.uniform.empty()) checkScaledSky(sky.exr_path, *scene.sky.map, scene.sky.scale);
    if (!sky.uniform.empty()) {
        scene.sky.uniform = parseVec3(sky.uniform, "--sky");
        if (scene.sky.uniform.x < 0.0f || scene.sky.uniform.y < 0.0f || scene.sky.uniform.z < 0.0f) {
            throw CommandError(kExitUsage, "--sky: radiance must be >= 0, got \"" + sky.uniform + "\"");
        }
        scene.sky.map.reset();
    }
    if (!quiet) describeScene(scene);
    // Warnings are not progress: --quiet never hides them.
    for (const std::string& warning : scene.stats.warnings) warn(warning);
    return scene;
}

bool isJsonNumber(std::string_view text) {
    size_t i = 0;
    const auto digits = [&] {
        const size_t start = i;
        while (i < text.size() && text[i] >= '0' && text[i] <= '9') ++i;
        return i > start;
    };
    if (i < text.size() && text[i] == '-') ++i;
    if (i < text.size() && text[i] == '0') {
        ++i;
    } else if (!digits()) {
        return false;
    }
    if (i < text.size() && text[i] == '.' && (++i, !digits())) return false;
    if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
        ++i;
        if (i < text.size() && (text[i] == '+' || text[i] == '-')) ++i;
        if (!digits()) return false;
    }
    return i == text.size();
}

Json metadataJson(const std::vector<std::pair<std::string, std::string>>& metadata) {
    Json json = Json::object();
    for (const auto& [key, value] : metadata) {
        if (isJsonNumber(value)) {
            const double number = std::strtod(value.c_str(), nullptr);
            // Integers stay exact (seeds, capacities); others are doubles.
            const bool integer = value.find_first_of(".eE") == std::string::npos && value.size() < 16;
            json[key] = integer ? Json(std::strtoll(value.c_str(), nullptr, 10)) : jsonNumber(number);
        } else {
            json[key] = value;
        }
    }
    return json;
}

Json cameraJson(const Camera& camera) {
    Json json = {{"name", camera.name},
                 {"node_name", camera.node_name},
                 {"position", jsonVec3(camera.position)},
                 {"forward", jsonVec3(camera.forward)},
                 {"up", jsonVec3(camera.up)},
                 {"yfov", camera.orthographic_half_height ? Json(nullptr) : jsonNumber(camera.yfov)}};
    if (camera.orthographic_half_height)
        json["orthographic_half_height"] = jsonNumber(*camera.orthographic_half_height);
    return json;
}

Json provenanceJson(const char* output_kind, const Scene& scene, const std::string& scene_hash) {
    return {{"schema", jsonSchemaId(output_kind)},
            {"tool", {{"name", "sharcbake"}, {"version", SHARCBAKE_VERSION}}},
            {"scene", {{"path", scene.source_path}, {"content_hash", scene_hash}, {"warnings", scene.stats.warnings}}}};
}

void describeScene(const Scene& scene) {
    std::printf("Scene %s: %s, %s, %s, %s, %s, sky %s\n", scene.source_path.c_str(),
                counted(scene.triangles.size(), "triangle").c_str(),
                counted(scene.materials.size(), "material").c_str(), counted(scene.textures.size(), "texture").c_str(),
                counted(scene.lights.size(), "punctual light").c_str(), counted(scene.cameras.size(), "camera").c_str(),
                scene.sky.map ? "map" : (scene.sky.isBlack() ? "black" : "uniform"));
    if (scene.stats.degenerate_triangles_dropped > 0 || scene.stats.primitives_skipped > 0) {
        std::printf("  dropped %llu degenerate triangles, skipped %llu non-triangle primitives\n",
                    (unsigned long long)scene.stats.degenerate_triangles_dropped,
                    (unsigned long long)scene.stats.primitives_skipped);
    }
}

/// How lights are chosen (lights.h): by power, or by shares measured per grid cell.
Json lightSelectionJson(const SpatialLightSelection& s) {
    return {{"by_where_light_arrives", s.active()},
            {"groups", s.groups},
            {"grouped_by_region", s.grouped_by_region},
            {"cells", {s.cells.x, s.cells.y, s.cells.z}},
            {"cell_size", jsonNumber(s.cell_size)},
            {"detail",
             s.detail_cells.x == 0
                 ? Json(nullptr)
                 : Json{{"min", {jsonNumber(s.detail_min.x), jsonNumber(s.detail_min.y), jsonNumber(s.detail_min.z)}},
                        {"max", {jsonNumber(s.detail_max.x), jsonNumber(s.detail_max.y), jsonNumber(s.detail_max.z)}},
                        {"cells", {s.detail_cells.x, s.detail_cells.y, s.detail_cells.z}},
                        {"cell_size", jsonNumber(s.detail_cell_size)}}},
            {"learned_slots", s.learned_slots},
            {"shadow_rays", s.shadow_rays},
            {"seconds", jsonNumber(s.seconds)}};
}

}  // namespace sharcbake
