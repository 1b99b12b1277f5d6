// SPDX-License-Identifier: Apache-2.0
/// @file camera_path.h
/// @brief The virtual camera that roams the scene during a bake.
///
/// SHaRC picks a voxel's level from its distance to the camera, so the cache only holds the
/// levels some camera position asked for. The bake therefore moves the camera through the
/// places a player (or the runtime's camera) will be: along the glTF cameras, along a path file,
/// or through the scene's free space found automatically.
#pragma once

#include "tracing/tracer.h"

#include <glm/glm.hpp>

#include <algorithm>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace sharcbake {

/// One camera placement: where it is and where it looks.
struct CameraPose {
    glm::vec3 position{0.0f};
    glm::vec3 forward{0.0f, 0.0f, -1.0f};  ///< unit
    glm::vec3 up{0.0f, 1.0f, 0.0f};        ///< unit, orthogonal to forward
    float yfov = 1.5707963f;               ///< vertical field of view, radians
    /// A glTF camera's clip planes (Camera::znear, zfar), kept only while the pose is that
    /// camera's own view (poseOf); every view the roaming camera turns or moves to has none.
    float znear = 0.0f;
    std::optional<float> zfar;
};

/// A glTF camera's pose: its position, orientation, field of view and clip planes.
CameraPose poseOf(const Camera& camera);

/// Where the waypoints come from.
enum class CameraPathSource : uint8_t {
    Explore,      ///< free-space points reachable from the glTF cameras (or the scene centre)
    GltfCameras,  ///< the scene's glTF cameras, in file order, as a loop
    File          ///< a camera path file (format in readCameraPathFile)
};

/// "explore", "gltf", "file": the names the command line and the bake's settings use.
const char* toString(CameraPathSource source);

class CameraPathError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Reads a camera path file: one waypoint per line, "px py pz tx ty tz [fov_degrees]" (eye
/// position and the point it looks at, world units; the field of view defaults to 90), the
/// values separated by spaces or commas (as --look-at writes them, or a spreadsheet's CSV).
/// Blank lines and lines starting with '#' are ignored. Throws CameraPathError naming the file
/// and line on malformed input or when the file has no waypoint.
std::vector<CameraPose> readCameraPathFile(const std::string& path);

/// The pinhole camera of a pose (no name, no aspect ratio of its own), with the pose's clip planes.
Camera toCamera(const CameraPose& pose);

/// Builds a pose looking from `eye` towards `target` with +Y up (a different up when the view
/// is vertical), without clip planes: a view no glTF camera gives. Returns false if eye ==
/// target.
bool makeLookAtPose(glm::vec3 eye, glm::vec3 target, float yfov, CameraPose& pose);

/// What free-space exploration found, for the bake's report.
struct ExplorationResult {
    std::vector<glm::vec3> points;  ///< reachable free-space positions, the order they are visited
    uint32_t candidates = 0;        ///< points tried
    uint32_t free = 0;              ///< not inside geometry
    bool winding_ignored = false;   ///< faces' winding did not tell solids from free space: not used
    /// The glTF cameras (indices into the scene's cameras) that single-sided faces' winding put
    /// inside a solid, which made it ignored: a camera inside a closed object by mistake, or every
    /// camera of a room modelled from a cube with its normals out.
    std::vector<uint32_t> cameras_in_solids;
    /// The share of the probe rays from `points` that leave the scene without a hit: near 0 in a
    /// closed room, most of them around an object under the sky.
    float escaped_fraction = 0.0f;
    uint32_t views_around = 0;  ///< views from around the scene added to the path (exploringCameraPath)
    /// The scene has cameras, and every one stands outside its bounds (looking at it from outside,
    /// as Blender's default camera looks at its cube): a reason for the views from around.
    bool cameras_outside = false;
    /// The scene has no camera, and the free space found is closed and dark: no probe ray leaves
    /// it, no single-sided face's winding calls it free, and no light reaches it (tested at up to
    /// 16 of `points`). It is the inside of a closed object lit from outside (a cube or a housing
    /// under the sky), so the scene is looked at from around it instead (exploringCameraPath, the
    /// hit-rate prediction).
    bool dark_enclosure = false;
};

/// Above this share of escaping probe rays the space the exploration found is open, as around a
/// lone object, and a scene without cameras is seen from outside (exploringCameraPath).
inline constexpr float kOpenSceneEscapedFraction = 0.5f;

/// Where a glTF camera's view begins: its position, or, where geometry stands between it and its
/// near clip plane along its forward axis (a cutaway: a camera outside a room looking in through
/// the wall its znear clips away), the centre of that plane, if the axis meets anything past it.
/// The free space the camera looks into is there, and exploring from the camera's own position
/// would stay outside the room.
glm::vec3 viewStart(const Tracer& tracer, const Camera& camera);

/// The radius of the sphere around the scene's bounds (at least 1e-3).
float boundingRadius(const Scene& scene);

/// The distance from the centre of the scene's bounds at which a camera of vertical field of view
/// `yfov` sees the whole bounding sphere with a 10% margin (where `render` puts its automatic
/// camera).
float framingDistance(const Scene& scene, float yfov);

/// The camera `render` uses for a scene without one: it frames the bounding sphere with vertical
/// field of view `yfov` (radians) from the front, to the right and above (26.5 degrees of
/// elevation, 24 of azimuth), so no axis-aligned plane of a glTF scene (+Y up) is seen edge-on.
/// Named "automatic".
Camera automaticCamera(const Scene& scene, float yfov);

/// The same, unless the scene is a room closed around the centre of its bounds (the centre is free
/// space, no probe ray from it leaves the scene, and the camera outside cannot see it) and that
/// closed space is a place to look from: single-sided faces around it face it, or light reaches
/// into it (an emitter or a punctual light inside, seen from it or from what it sees; walls wound
/// away from it then count as free space around it, as a cube scaled into a room has them). From
/// outside such a scene the camera sees only the outer sides of its walls, which nothing lights
/// and the bake never reaches; it then stands near the wall behind the centre, looking level along
/// the horizontal axis with the most room. The inside of a closed double-sided model lit from
/// outside (Blender's default material, under the sky) looks just as closed, but is dark: it is
/// framed from outside. A scene wrapped in a glowing shell (a sky dome modelled as an emissive or
/// unlit sphere, a glowing box around a model), whose content rays from outside meet only after
/// the shell, is framed as from outside but from inside the shell: what does not emit, from the
/// same direction, no farther than 90% of the way to the shell. Named "automatic" either way.
Camera automaticCamera(const Tracer& tracer, float yfov);

/// The automatic camera's vertical field of view unless the user gives one (render's --fov), in
/// degrees: also what the bake's report and hit-rate prediction look through.
inline constexpr float kAutomaticCameraFovDegrees = 45.0f;

/// `count` views of the scene from around it, spread evenly over the sphere of 1.5 bounding radii
/// around the centre of its bounds (a spherical Fibonacci set), each looking with a 45-degree
/// field of view at a point of the surface drawn by area (deterministic for a seed).
std::vector<CameraPose> viewsAroundScene(const Scene& scene, uint32_t count, uint32_t seed);

/// Finds up to `count` positions inside the scene's bounds that are not inside geometry and are
/// reachable, by unoccluded straight segments, from `starts`. Inside geometry means behind the
/// single-sided faces most probe rays hit; double-sided faces have no inside. With
/// `starts_are_cameras` (the scene's glTF cameras) the starts are free space by definition, and
/// the connected sets holding them are kept. Otherwise the start (the centre of the bounds) may
/// lie inside a closed double-sided object, whose inside looks free, so the sets kept are those
/// where free space is known (a probe ray left the scene, or single-sided faces said so); where
/// none is, those light reaches, else the start's set, else the largest set. If a camera is behind
/// single-sided faces, or no point is free at all, the winding cannot be trusted and is ignored
/// for the whole scene (`winding_ignored`): then only the clearance from surfaces and
/// reachability decide. Without cameras, closed free space that no light reaches is flagged
/// `dark_enclosure`.
/// Deterministic for a given seed.
ExplorationResult exploreFreeSpace(const Tracer& tracer, const std::vector<glm::vec3>& starts, bool starts_are_cameras,
                                   uint32_t count, uint32_t seed);

/// The camera of each bake iteration.
class CameraPath {
public:
    /// Waypoints visited as a loop. With `random_directions` the camera visits one waypoint per
    /// iteration and looks in a new random direction each time (exploration), except at the
    /// waypoints `aimed` marks (empty: none), which keep their own direction; otherwise it looks
    /// where the waypoints look, moving between consecutive waypoints over `iterations_per_leg`
    /// iterations.
    CameraPath(std::vector<CameraPose> waypoints, bool random_directions, uint32_t iterations_per_leg,
               float position_jitter, uint32_t seed, std::vector<bool> aimed = {});

    /// The pose of bake iteration `iteration`, including its jitter (a pure function of the
    /// iteration and the seed).
    CameraPose poseAt(uint32_t iteration) const;

    const std::vector<CameraPose>& waypoints() const { return waypoints_; }

    /// Iterations of one loop of the path: after it the poses repeat (up to their random
    /// directions and jitter). One per waypoint when exploring, else iterations_per_leg each.
    uint32_t period() const {
        const uint64_t loop = uint64_t(waypoints_.size()) * (random_directions_ ? 1u : iterations_per_leg_);
        return uint32_t(std::min<uint64_t>(std::max<uint64_t>(loop, 1), UINT32_MAX));
    }

private:
    std::vector<CameraPose> waypoints_;
    std::vector<bool> aimed_;
    bool random_directions_;
    uint32_t iterations_per_leg_;
    float position_jitter_;
    uint32_t seed_;
};

/// Rays of the roaming camera: `poses` poses spread evenly over one loop of the path (its
/// period), `rays_per_pose` rays from each through pixels of a `width` x `height` image drawn at
/// random, as the bake's update paths leave it. What a probe before the bake traces to learn what
/// the bake's paths will meet. Deterministic for a seed.
std::vector<Ray> sampleCameraPathRays(const CameraPath& path, int width, int height, uint32_t poses,
                                      uint32_t rays_per_pose, uint32_t seed);

/// The roaming camera for runtime cameras that stay at the glTF cameras (`--view-region auto`
/// keeping the grid to them): at each glTF camera's position in turn, looking alternately its own
/// way and in a new random direction each iteration, as a camera standing there and turning looks
/// (the hit-rate prediction's views of such a region are the same). A camera exploring free space
/// would spend most of its paths where those cameras never look: a room with a window on a lawn
/// 200 m wide rendered through the cache +3.6% too bright from its camera when the exploring
/// camera baked it, +0.1% from here (tests/bench/window_room.sh, BENCHMARKS.md). No gliding
/// between the cameras, which would cross the walls between rooms. The scene must have a camera.
CameraPath atGltfCameraPositions(const Scene& scene, uint32_t seed);

/// The exploring camera of a bake: up to `points` free-space positions reachable from the scene's
/// glTF cameras (from its centre when it has none), visited in turn, each iteration looking in a
/// new random direction. A scene whose free space is open (escaped_fraction at least
/// kOpenSceneEscapedFraction) and that has no camera, or whose cameras all stand outside its
/// bounds, is also looked at from outside: as many views from around it (viewsAroundScene), which
/// keep their direction, alternate with the free-space positions. A scene without a camera whose
/// free space is a dark enclosure (the inside of a closed object lit from outside) gets the views
/// from around alone.
/// std::nullopt when no free space was found; `explored` (if given) receives the search's counts
/// either way.
std::optional<CameraPath> exploringCameraPath(const Tracer& tracer, const Scene& scene, uint32_t points,
                                              uint32_t seed, ExplorationResult* explored = nullptr);

}  // namespace sharcbake
