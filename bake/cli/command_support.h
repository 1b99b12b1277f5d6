// SPDX-License-Identifier: Apache-2.0
/// @file command_support.h
/// @brief What every sharcbake subcommand shares: documented exit codes, the error type that
/// carries one, parsing of vector arguments, and scene loading with the sky options.
#pragma once

#include "sharcbake/cache_types.h"
#include "sharcbake/scene.h"
#include "sharcbake/scene_loader.h"
#include "support/json.h"
#include "support/text_format.h"
#include "tracing/tracer.h"

#include <CLI/CLI.hpp>
#include <glm/glm.hpp>

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace sharcbake {

class LightSampler;
struct SpatialLightSelection;

/// Exit codes, documented in `sharcbake --help` and the README.
enum ExitCode : int {
    kExitOk = 0,
    kExitUsage = 1,         ///< bad command line
    kExitIo = 2,            ///< a file could not be read or written
    kExitInvalidInput = 3,  ///< a scene or cache file is malformed
    kExitRuntime = 4,       ///< the work itself failed
    kExitInterrupted = 130,  ///< stopped by SIGINT (128 + 2, as shells report it)
    kExitTerminated = 143    ///< stopped by SIGTERM (128 + 15), e.g. a scheduler's time limit
};

/// The exit code of a cache or checkpoint file that could not be used: kExitIo when it could not
/// be read or written, kExitInvalidInput when its content is wrong.
ExitCode exitCodeFor(CacheFileStatus status);

/// The text appended to the top-level --help.
extern const char* const kExitCodeHelp;

/// An error that ends the command with a given exit code; main() prints what() once.
class CommandError : public std::runtime_error {
public:
    CommandError(ExitCode code, const std::string& message)
        : std::runtime_error(message), code_(code) {}
    ExitCode code() const { return code_; }

private:
    ExitCode code_;
};

/// Refuses (kExitIo) an input that is not a regular file: "PATH: no such file", or "PATH: not a
/// regular file (a FIFO, device or folder)", before anything reads it (a FIFO would block).
void requireRegularInputFile(const std::string& path);

/// Prints "warning: TEXT" on stderr and keeps TEXT for the command's stats JSON (warningsGiven).
/// Every warning a command gives goes through here, so that a pipeline reading the JSON sees what a
/// person reading the log saw.
void warn(const std::string& text);

/// Every warning given so far (warn), in order.
std::vector<std::string> warningsGiven();

/// "1 camera", "3 cameras": a count with its noun, plural unless the count is one (nouns whose
/// plural is not the singular with an "s" pass it as `plural`).
std::string counted(uint64_t count, std::string_view singular, std::string_view plural = {});

/// CLI11 check for floating-point options: the value is a finite number. Range checks alone let
/// "nan" through (every comparison with NaN is false); chain this one after them.
extern const CLI::Validator kFiniteNumber;

/// Parses "x,y,z" into a vector; throws CommandError(kExitUsage) naming the option.
glm::vec3 parseVec3(const std::string& text, const std::string& option_name);

/// Fails early when `path` cannot take the `what` output, before long work so that nothing is
/// lost at the end. kExitIo: its folder is missing or not writable, or it exists and is not a
/// regular file (a folder, a device such as /dev/null, a FIFO, a socket; a symbolic link is
/// followed, and the output is later written through it). kExitUsage: it is the same file as one
/// of `others` (the command's inputs and its other outputs), compared by device and inode after
/// resolving links, or by resolved path when it does not exist yet.
void checkOutputPath(const std::string& path, const std::string& what, const std::vector<std::string>& others = {});

/// Refuses (kExitUsage) an output `path` that exists, is not empty and does not start with
/// `identifier`: a file of another kind (a scene, an image, notes) that the `what` would replace.
/// Swapping two arguments (`bake -o scene.gltf ...`) destroyed the scene without a word; a command
/// replaces only a file of its own kind (`kind`, as in "a sharcbake cache"). Call after
/// checkOutputPath, which refuses what is not a regular file.
void checkReplacesOnlyItsKind(const std::string& path, const std::string& what, std::string_view identifier,
                              const char* kind);
/// The first bytes of the files the commands write: caches, checkpoints, OpenVDB files.
std::string_view cacheFileIdentifier();
std::string_view checkpointFileIdentifier();
std::string_view vdbFileIdentifier();

/// "--seed: cannot read "abc" as UINT: expected a whole number ...": a value the option's type
/// (`full_type`, CLI11's type name such as "UINT" or "FLOAT:POSITIVE") cannot hold.
std::string unreadableValueMessage(const std::string& name, const std::string& value, const std::string& full_type);
/// CLI11's range check's message ("--time-budget: Value abc not in range 0.000000 to 1797693...",
/// the check runs before the conversion) in a person's words: a value that is no number of the
/// option's type (`type`) named so, one out of range with its bounds as a person writes them.
/// Other messages come back unchanged.
std::string rangeErrorMessage(const std::string& what, const std::string& type);

/// True if `path` ends in `extension` (".exr"), in any letter case.
bool hasExtension(const std::string& path, const char* extension);

/// Marks `option` as naming files or folders (its help shows PATH): a relative value read from a
/// --config file is taken relative to that file's folder (config_file.h). Returns `option`.
CLI::Option* pathOption(CLI::Option* option);
bool isPathOption(const CLI::Option& option);

/// "-": an output path that means standard output (the Unix convention), for the outputs that
/// write a text report (--stats-json); never for caches, images or checkpoints.
inline constexpr const char* kStandardOutputPath = "-";
inline bool isStandardOutput(const std::string& path) { return path == kStandardOutputPath; }

/// checkOutputPath for a text report's path; nothing to check for standard output ("-").
void checkTextOutputPath(const std::string& path, const std::string& what, const std::vector<std::string>& others = {});

/// Writes `text` to `path` atomically with the caches' checked write (writeFileAtomically):
/// a failed write throws CommandError(kExitIo) naming the file and leaves the old one intact.
/// "-" writes it to standard output.
void writeTextOutput(const std::string& path, const std::string& what, const std::string& text);

/// While a command's report goes to standard output (`--stats-json -`), what it prints for people
/// (the scene, the plan, progress lines, the summary) goes to stderr instead, so that stdout
/// carries the report alone and a pipe can parse it. Active from construction (when `active`)
/// until release(), which the command calls before it writes the report; the destructor releases.
class HumanOutputOnStderr {
public:
    explicit HumanOutputOnStderr(bool active);
    ~HumanOutputOnStderr() { release(); }
    HumanOutputOnStderr(const HumanOutputOnStderr&) = delete;
    HumanOutputOnStderr& operator=(const HumanOutputOnStderr&) = delete;
    void release();

private:
    int saved_stdout_ = -1;  ///< the real stdout while redirected
};

/// A glTF camera of the scene by name or index, or the first when `selector` is empty; when the
/// scene has none, the automatic camera with `fov_degrees` (automaticCamera: from outside, or from
/// inside a room closed around the scene's centre when `tracer` is given). Throws
/// CommandError(kExitUsage) naming `option_name` and the cameras there are.
Camera sceneCamera(const Scene& scene, const std::string& selector, const std::string& option_name, float fov_degrees,
                   const Tracer* tracer = nullptr);

/// "'name' at (x, y, z) looking at (x, y, z), up (...), vertical fov N deg": a camera's pose, so
/// an automatic one can be reproduced with --look-at.
std::string describeCamera(const Camera& camera);

/// Warns (stderr, also under -q) when fitCameraToImage changed the camera's framing: its glTF
/// aspect ratio differs from the image's.
void warnAboutCameraFit(const Camera& camera, const Camera& fitted, int width, int height);

/// Parses an image size "W" or "WxH"; "W" takes the height from `aspect` (width / height, 1 if
/// unknown), which `aspect_source` names ("camera 'Main'"). Throws CommandError(kExitUsage) naming
/// the option, and the aspect ratio when it is what makes the image too large.
void parseImageSize(const std::string& text, const std::string& option_name, std::optional<float> aspect, int& width,
                    int& height, const std::string& aspect_source = "the camera");

/// Adds --trace-kernels (avx2, sse4.2 or native; tracer.h's TraceKernels) to `command`, whose
/// result ("cache", "image") it describes.
void addTraceKernelsOption(CLI::App* command, std::string& kernels);
/// Warns (stderr, also under -q) when `tracer` runs other kernels than `asked` (SSE4.2 on a CPU
/// without AVX2), so the `result` ("cache", "image") can differ from one made on a newer CPU.
void warnWhenKernelsFellBack(TraceKernels asked, const Tracer& tracer, const char* result);

/// Warns (stderr, also under -q) when nothing in the scene gives light, so the `result` ("image",
/// "cache") will be black; punctual lights that give none are named with the reason.
void warnWhenUnlit(const Scene& scene, const LightSampler& lights, const char* result);

/// Point and spot lights further than this (the median over lights of each one's median distance
/// to the surfaces around it, scene units) suggest a scene in millimetres: a lamp in metres hangs
/// within a few metres of a surface (a lighthouse's beacon 60 m over the sea reads 124; a 3 m
/// room's lamp in millimetres about 1500).
inline constexpr float kFarPunctualLightDistance = 300.0f;

/// Warns (stderr) of point and spot lights as far from the surfaces around them as in a scene
/// modelled in millimetres, where their inverse-square falloff, unlike everything else, depends
/// on the units and makes them 10^6 times too dim.
void warnAboutPunctualLightUnits(const Tracer& tracer);

/// Options that choose the sky, shared by render and bake.
struct SkyOptions {
    std::string uniform;  ///< "r,g,b" or empty
    std::string exr_path;
    float scale = 1.0f;
};
void addSkyOptions(CLI::App& command, SkyOptions& options);

/// Loads the scene (kExitIo if the file is missing, kExitInvalidInput if it is malformed) and
/// applies the sky options over what the scene file says.
Scene loadSceneForCommand(const std::string& path, const SkyOptions& sky, bool quiet,
                          const GltfLoadLimits& limits = {});

/// Seconds between progress lines when stdout is a log rather than a terminal.
inline constexpr double kDefaultProgressInterval = 10.0;
/// --progress-interval, shared by render and bake.
void addProgressIntervalOption(CLI::App& command, double& seconds);

/// --max-texture-size, shared by render and bake.
void addSceneLimitOptions(CLI::App& command, GltfLoadLimits& limits);

/// FNV-1a (64-bit) of the bytes of the scene's files one after the other (the glTF or GLB, then
/// its external buffers and images: Scene::source_files), as "fnv1a64:<16 hex digits>": a cache
/// records which scene it was baked from, geometry included.
std::string sceneContentHash(const std::vector<std::string>& files);

/// The sky a command used where it is not the scene file's own (that one is in the scene's
/// hash): "uniform r,g,b", "map <hash> x <scale>", or "scene".
std::string skyDescription(const SkyOptions& sky);

/// What every --stats-json starts with: "schema" (jsonSchemaId(output_kind)), the tool
/// and its version, and the scene (path, content hash, the loader's warnings).
Json provenanceJson(const char* output_kind, const Scene& scene, const std::string& scene_hash);

/// A camera's pose and field of view.
Json cameraJson(const Camera& camera);

/// How lights are chosen (lights.h), as the stats JSONs of bake and render give it.
Json lightSelectionJson(const SpatialLightSelection& selection);

/// True if `text` is a number in JSON's grammar ("12", "-0.5", "1e-3"; not "+1", " 1" or "0x1").
bool isJsonNumber(std::string_view text);

/// Cache metadata as one JSON object: values that are numbers become numbers, the rest strings.
Json metadataJson(const std::vector<std::pair<std::string, std::string>>& metadata);

/// One line about the loaded scene (triangles, materials, lights, what was dropped) on stdout.
/// The loader's warnings go to stderr from loadSceneForCommand, --quiet or not.
void describeScene(const Scene& scene);

}  // namespace sharcbake
