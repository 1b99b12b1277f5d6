// SPDX-License-Identifier: Apache-2.0
#include "sharc/camera_path.h"
#include "sharcbake/scene.h"
#include "support/box.h"

#include "tracing/light_reach.h"
#include "tracing/render.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"
#include "tracing/surface_points.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>

namespace sharcbake {

const char* toString(CameraPathSource source) {
    switch (source) {
        case CameraPathSource::Explore: return "explore";
        case CameraPathSource::GltfCameras: return "gltf";
        case CameraPathSource::File: return "file";
    }
    return "explore";
}
namespace {

/// Probes in the axis directions plus the eight diagonals: enough to tell a closed solid from open
/// space.
constexpr int kProbeCount = kAxisAndDiagonalDirections;

/// What the probe rays from a point say about it.
struct FreeSpaceProbe {
    bool free = false;
    /// Free, and known to be rather than assumed: a probe left the scene (no closed surface holds
    /// the point) or single-sided faces voted. Where every probe meets double-sided faces, a
    /// point inside a closed object looks just like one inside a closed room.
    bool known = false;
    int escaped = 0;  ///< probe rays that left the scene
};

/// Which faces' winding says where solids are. Blender's exporter writes its default material
/// double-sided, and most models keep their normals pointing out: inside such a model (Suzanne,
/// whose head is open behind the eyes) most probes meet the backs of double-sided faces, and
/// without their vote the inside was free space, reachable through the gaps; a fifth of the hit
/// rate's sample views stood there. But a room modelled from a cube scaled up also shows its
/// camera the backs of double-sided walls: where all faces' winding puts a camera inside a solid,
/// or leaves free fewer than a quarter of the points single-sided faces leave free (none, in such
/// a room without a camera), single-sided faces alone vote, and where those fail too, none.
enum class Winding { kAllFaces, kSingleSided, kIgnored };

/// The directions a point is probed along: the 14 axis and diagonal directions, or for a glTF
/// camera, before its scene's winding is distrusted, 64 spread evenly (a spherical Fibonacci
/// set). Along the 14, one that met the inside of a wall through a gap (a camera on the axis of
/// Suzanne's eye) outvoted the single front face the others met, and the scene lost its
/// double-sided faces' vote. Seen densely, the model's outside outweighs the gap; the outside of a
/// room wound inwards shows a camera nothing but backs either way.
enum class Probes { kAxesAndDiagonals, kCameraSphere };
constexpr uint32_t kCameraSphereProbes = 64;

/// A point is in free space when most probe rays that hit a face that votes (`winding`) hit its
/// front (the side its winding faces): inside a closed solid every ray sees back faces. Points
/// closer to any surface than `clearance` are rejected so the camera does not sit on a wall.
FreeSpaceProbe probeFreeSpace(const Tracer& tracer, glm::vec3 p, float clearance, Winding winding,
                              Probes probes = Probes::kAxesAndDiagonals) {
    int votes = 0, back_votes = 0, single_sided_votes = 0, escaped = 0;
    const Scene& scene = tracer.scene();
    const bool sphere = probes == Probes::kCameraSphere;
    const int count = sphere ? int(kCameraSphereProbes) : kProbeCount;
    for (int i = 0; i < count; ++i) {
        const glm::vec3 d = sphere ? sphericalFibonacciDirection(uint32_t(i), kCameraSphereProbes)
                                   : axisOrDiagonalDirection(i);
        RayHit hit;
        if (!tracer.intersect(Ray{p, d}, hit)) {
            // A ray that slips between two triangles at a shared edge seems to leave a closed
            // mesh (one probe in thousands, in a finely meshed box; the ray back along the same
            // line slips through too): it escapes only if a ray a milliradian beside it misses as
            // well. A leak neither escapes nor votes.
            const glm::vec3 beside = glm::normalize(d + 1e-3f * Frame(d).toWorld(glm::vec3(1.0f, 0.0f, 0.0f)));
            if (!tracer.occluded(Ray{p, beside})) ++escaped;
            continue;
        }
        if (hit.t < clearance) return {};
        const bool double_sided = scene.materials[scene.triangle_materials[hit.triangle]].double_sided;
        if (winding == Winding::kIgnored || (double_sided && winding == Winding::kSingleSided)) continue;
        const glm::uvec3 tri = scene.triangles[hit.triangle];
        const glm::vec3 n = glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                       scene.positions[tri.z] - scene.positions[tri.x]);
        ++votes;
        single_sided_votes += !double_sided;
        if (glm::dot(n, d) > 0.0f) ++back_votes;
    }
    const bool free = votes == 0 || 2 * back_votes < votes;
    // Known as before the double-sided faces voted: a closed room of them, wound either way, says
    // nothing certain about which side is in.
    return {free, free && (escaped > 0 || single_sided_votes > 0), escaped};
}

}  // namespace

CameraPose poseOf(const Camera& camera) {
    return CameraPose{camera.position, camera.forward, camera.up, camera.yfov, camera.znear, camera.zfar};
}

Camera toCamera(const CameraPose& pose) {
    Camera camera;
    camera.position = pose.position;
    camera.forward = pose.forward;
    camera.up = pose.up;
    camera.yfov = pose.yfov;
    camera.znear = pose.znear;
    camera.zfar = pose.zfar;
    return camera;
}

glm::vec3 viewStart(const Tracer& tracer, const Camera& camera) {
    if (!(camera.znear > 0.0f)) return camera.position;
    const glm::vec3 forward = glm::normalize(camera.forward);
    if (!tracer.occluded(Ray{camera.position, forward, camera.znear})) return camera.position;
    // A near plane past everything on the axis (a scene shrunk around a camera whose znear was
    // not) looks into nothing: the camera's own position is the better start.
    RayHit beyond;
    if (!tracer.intersect(Ray{camera.position, forward, std::numeric_limits<float>::infinity(), camera.znear}, beyond))
        return camera.position;
    return camera.position + camera.znear * forward;
}

bool makeLookAtPose(glm::vec3 eye, glm::vec3 target, float yfov, CameraPose& pose) {
    const glm::vec3 d = target - eye;
    const float length = glm::length(d);
    if (!(length > 0.0f) || !std::isfinite(length)) return false;
    pose.position = eye;
    pose.forward = d / length;
    pose.znear = 0.0f;
    pose.zfar.reset();
    glm::vec3 up(0.0f, 1.0f, 0.0f);
    if (std::abs(glm::dot(up, pose.forward)) > 0.999f) up = glm::vec3(0.0f, 0.0f, -1.0f);
    const glm::vec3 right = glm::normalize(glm::cross(pose.forward, up));
    pose.up = glm::cross(right, pose.forward);
    pose.yfov = yfov;
    return true;
}

std::vector<CameraPose> readCameraPathFile(const std::string& path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        throw CameraPathError(path + ": not a regular file (missing, a FIFO, a device or a folder)");
    }
    std::ifstream in(path);
    if (!in) throw CameraPathError(path + ": cannot open the camera path file");
    std::vector<CameraPose> poses;
    std::string line;
    for (int line_number = 1; std::getline(in, line); ++line_number) {
        const size_t first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#') continue;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream fields(line);
        float v[6];
        for (float& value : v) {
            if (!(fields >> value) || !std::isfinite(value)) {
                throw CameraPathError(path + ":" + std::to_string(line_number) +
                                      ": expected \"px py pz tx ty tz [fov_degrees]\"");
            }
        }
        float fov_degrees = 90.0f;
        if (!(fields >> fov_degrees)) {
            fov_degrees = 90.0f;
            fields.clear();
        } else if (!(fov_degrees > 0.0f && fov_degrees < 180.0f)) {
            throw CameraPathError(path + ":" + std::to_string(line_number) +
                                  ": field of view must be in (0, 180) degrees");
        }
        std::string rest;
        if (fields >> rest) {
            throw CameraPathError(path + ":" + std::to_string(line_number) + ": unexpected \"" + rest + "\"");
        }
        if (!withinWorldLimit(glm::dvec3(v[0], v[1], v[2])) || !withinWorldLimit(glm::dvec3(v[3], v[4], v[5]))) {
            throw CameraPathError(path + ":" + std::to_string(line_number) +
                                  ": a coordinate beyond +-1e9, where nothing of a scene may lie");
        }
        CameraPose pose;
        if (!makeLookAtPose({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, fov_degrees * kPi / 180.0f, pose)) {
            throw CameraPathError(path + ":" + std::to_string(line_number) +
                                  ": the eye and the target are the same point");
        }
        poses.push_back(pose);
    }
    if (poses.empty()) throw CameraPathError(path + ": the camera path file has no waypoint");
    return poses;
}

namespace {

/// Rays from the centre of a closed space, and one bounce on from where each lands: the surfaces
/// a view from inside would see, and where light falling into the space would show.
constexpr uint32_t kEnclosureRays = 64;
/// Whether most of what `center` sees emits: inside a glowing object (a closed emissive model,
/// double-sided), or inside a sky dome modelled as an emissive mesh. 64 rays. "Emits" here is the
/// radiance at the point the ray meets (textures and sides included: a dark texel does not glow),
/// as a view from `center` would show it; hasEmissiveMaterial asks of the material alone.
bool mostlyEmittersAround(const Tracer& tracer, glm::vec3 center) {
    const Scene& scene = tracer.scene();
    uint32_t emitting = 0;
    for (uint32_t i = 0; i < kEnclosureRays; ++i) {
        const glm::vec3 d = sphericalFibonacciDirection(i, kEnclosureRays);
        RayHit hit;
        if (!tracer.intersect(Ray{center, d}, hit)) continue;
        const SurfaceHit surface = makeSurfaceHit(scene, hit, d);
        if (maxComponent(emittedRadiance(surface, evaluateMaterial(scene, surface))) > 0.0f) ++emitting;
    }
    return 2 * emitting > kEnclosureRays;
}

/// Whether light reaches the space closed around a point, asked of many points of one scene:
/// the points on its emitters are drawn once, when first needed (a pass over every triangle).
class LightTest {
public:
    explicit LightTest(const Tracer& tracer) : tracer_(tracer) {}

    /// Whether light reaches the space closed around `center`, as it reaches a room: an emitter
    /// is seen from it, or lights a surface seen from it (a ceiling panel, a lamp behind
    /// furniture), a punctual light is in it, or the sky or the sun comes in through an opening
    /// the probes missed. The inside of a closed object lit from outside (a model under the sky,
    /// lamps around it) is dark: no light reaches it, and a view from there is black. Surfaces one
    /// bounce away count, so a light around a corner of the space is found too. A few thousand
    /// rays; deterministic.
    bool reachesInside(glm::vec3 center);

private:
    const Tracer& tracer_;
    std::optional<std::vector<LitPoint>> emitters_;  ///< sampleEmitterPoints, once drawn
};

bool LightTest::reachesInside(glm::vec3 center) {
    const Tracer& tracer = tracer_;
    const Scene& scene = tracer.scene();
    const bool sky = !scene.sky.isBlack();
    // Where light could land: the centre and points just off the surfaces around it, on the
    // side facing it.
    std::vector<glm::vec3> receivers;
    std::vector<std::pair<glm::vec3, glm::vec3>> landed;  // where the rays met a surface, and that side's normal
    // Whether the ray that left `from` along `d` meets light: the sky, or an emitter's lit side.
    const auto rayFindsLight = [&](glm::vec3 from, glm::vec3 d) {
        RayHit hit;
        if (!tracer.intersect(Ray{from, d}, hit)) return sky && leavesScene(tracer, from, d);
        const SurfaceHit surface = makeSurfaceHit(scene, hit, d);
        if (maxComponent(emittedRadiance(surface, evaluateMaterial(scene, surface))) > 0.0f) return true;
        const glm::vec3 at = offsetRayOrigin(surface.position, surface.geometric_normal, surface.ray_offset);
        receivers.push_back(at);
        landed.emplace_back(at, surface.geometric_normal);
        return false;
    };
    for (uint32_t i = 0; i < kEnclosureRays; ++i) {
        if (rayFindsLight(center, sphericalFibonacciDirection(i, kEnclosureRays))) return true;
    }
    for (uint32_t i = 0, first_hits = uint32_t(landed.size()); i < first_hits; ++i) {
        const auto [at, normal] = landed[i];  // a copy: the bounce adds to `landed`
        const glm::vec3 local = sampleCosineHemisphere({hashToUnitFloat(i, 1, 0), hashToUnitFloat(i, 1, 1)});
        if (rayFindsLight(at, Frame(normal).toWorld(local))) return true;
    }
    receivers.push_back(center);
    for (const PunctualLight& light : scene.lights) {
        if (!givesLight(light)) continue;
        for (const glm::vec3& at : receivers) {
            const bool reached = light.type == LightType::Directional
                                     ? leavesScene(tracer, at, -light.direction)
                                     : (light.range <= 0.0f || glm::distance(at, light.position) < light.range) &&
                                           visibleBothWays(tracer, at, light.position);
            if (reached) return true;
        }
    }
    if (!emitters_) emitters_ = sampleEmitterPoints(scene);
    return seesLitEmitter(tracer, receivers, *emitters_);
}

/// A candidate camera position that passed the free-space test.
struct FreePoint {
    glm::vec3 position;
    bool start;
    bool known;   ///< FreeSpaceProbe::known (a camera always is)
    int escaped;  ///< FreeSpaceProbe::escaped
};

/// Free points tested for light where a scene without cameras says nothing else of which free
/// space is a room, and before closed free space is called dark: a few thousand rays each.
constexpr size_t kLightTests = 16;

/// The candidates' sets connected under mutual visibility, and which of them to keep: the sets
/// that hold a camera. Without cameras, the start is only the centre of the bounds, which may lie
/// inside a closed double-sided object (Blender's default material is double-sided), whose inside
/// looks free: the sets where free space is known are kept instead, else those light reaches (a
/// room is lit from within, the inside of a closed object is not; the inside of a glowing object
/// only where nothing else is lit), else the centre's set, and with none of these the largest
/// set. Returns, per point, whether its set is kept.
std::vector<bool> reachablePoints(const Tracer& tracer, LightTest& light, const std::vector<FreePoint>& points,
                                  bool starts_are_cameras) {
    // Union-find over all pairs: a few thousand rays.
    const size_t n = points.size();
    std::vector<size_t> parent(n);
    std::iota(parent.begin(), parent.end(), size_t(0));
    auto root = [&](size_t a) {
        while (parent[a] != a) a = parent[a] = parent[parent[a]];
        return a;
    };
    for (size_t a = 0; a < n; ++a) {
        for (size_t b = a + 1; b < n; ++b) {
            if (root(a) != root(b) && visibleBothWays(tracer, points[a].position, points[b].position)) {
                parent[root(b)] = root(a);
            }
        }
    }
    std::vector<bool> keep_root(n, false);
    bool any_kept = false;
    for (size_t i = 0; i < n; ++i) {
        if (starts_are_cameras ? points[i].start : points[i].known) keep_root[root(i)] = any_kept = true;
    }
    // Points spread over all candidates, so a lit room beside a larger dark inside is found. The
    // inside of a glowing object (a light fixture modelled as a closed emissive mesh) is lit by
    // its own walls: kept only where no other lit space is (a glowing box around a model).
    const size_t light_tests = any_kept ? 0 : std::min(n, kLightTests);
    std::vector<size_t> glowing_insides;
    for (size_t k = 0; k < light_tests; ++k) {
        const size_t i = k * n / light_tests;
        if (keep_root[root(i)] || !light.reachesInside(points[i].position)) continue;
        if (mostlyEmittersAround(tracer, points[i].position)) {
            glowing_insides.push_back(i);
        } else {
            keep_root[root(i)] = any_kept = true;
        }
    }
    if (!any_kept) {
        for (size_t i : glowing_insides) keep_root[root(i)] = any_kept = true;
    }
    for (size_t i = 0; i < n && !any_kept; ++i) {
        if (points[i].start) keep_root[root(i)] = any_kept = true;
    }
    if (!any_kept && n > 0) {
        std::vector<size_t> size(n, 0);
        for (size_t i = 0; i < n; ++i) ++size[root(i)];
        keep_root[size_t(std::max_element(size.begin(), size.end()) - size.begin())] = true;
    }
    std::vector<bool> kept(n);
    for (size_t i = 0; i < n; ++i) kept[i] = keep_root[root(i)];
    return kept;
}

/// Scales of the candidates around the starts: from half the bounds' largest extent, halving,
/// down to this fraction of the diagonal (a 4 m room beside a 10 km ground plane is reached at
/// 2^-11 of the plane).
constexpr float kSmallestAroundStarts = 1e-5f;
/// Candidates near the surfaces keep this fraction of their scale clear, as the bounds-wide ones
/// keep 1% of the diagonal: a wall's thickness, not a ground plane's extent.
constexpr float kClearanceOfScale = 0.02f;

}  // namespace

ExplorationResult exploreFreeSpace(const Tracer& tracer, const std::vector<glm::vec3>& starts, bool starts_are_cameras,
                                   uint32_t count, uint32_t seed) {
    const Scene& scene = tracer.scene();
    ExplorationResult result;
    if (scene.empty() || count == 0) return result;

    // Bounds, widened on flat axes so a ground plane still leaves room above it.
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float diagonal = glm::length(scene.bounds_max - scene.bounds_min);
    const glm::vec3 half = glm::max(0.5f * (scene.bounds_max - scene.bounds_min), glm::vec3(0.05f * diagonal));
    const float clearance = 0.01f * diagonal;

    std::vector<FreePoint> free_points;
    LightTest light(tracer);
    const auto tryPoint = [&](glm::vec3 p, float point_clearance, Winding winding) {
        ++result.candidates;
        const FreeSpaceProbe probe = probeFreeSpace(tracer, p, point_clearance, winding);
        if (probe.free) free_points.push_back({p, false, probe.known, probe.escaped});
    };
    // Candidates: the starts first, then stratified random points in the bounds (8x more than
    // needed).
    const auto collect = [&](Winding winding) {
        free_points.clear();
        for (const glm::vec3& s : starts) {
            ++result.candidates;
            const FreeSpaceProbe probe = probeFreeSpace(tracer, s, 0.0f, winding);
            if (starts_are_cameras || probe.free)
                free_points.push_back({s, true, starts_are_cameras || probe.known, probe.escaped});
        }
        for (uint32_t i = 0; i < 8 * count; ++i) {
            const glm::vec3 u(hashToUnitFloat(seed, i, 0), hashToUnitFloat(seed, i, 1), hashToUnitFloat(seed, i, 2));
            tryPoint(center + (2.0f * u - 1.0f) * half, clearance, winding);
        }
    };
    // The scene's own cameras look from free space. Where a winding test puts one of them inside
    // a solid, or finds no free space at all, the scene's winding does not tell inside from
    // outside that way (faces facing away from the viewer, as a room modelled from a cube has
    // them): the next, weaker test is used, and last none, where clearance and reachability
    // decide alone. The cameras are probed densely (Probes::kCameraSphere).
    Winding winding = Winding::kAllFaces;
    // The cameras a winding puts inside a solid (indices into `starts`), for the report.
    const auto camerasInSolids = [&](Winding w) {
        std::vector<uint32_t> inside;
        for (uint32_t i = 0; i < uint32_t(starts.size()); ++i)
            if (!probeFreeSpace(tracer, starts[i], 0.0f, w, Probes::kCameraSphere).free) inside.push_back(i);
        return inside;
    };
    const auto weaker = [](Winding w) { return w == Winding::kAllFaces ? Winding::kSingleSided : Winding::kIgnored; };
    if (starts_are_cameras) {
        while (winding != Winding::kIgnored) {
            std::vector<uint32_t> inside = camerasInSolids(winding);
            if (inside.empty()) break;
            if (winding == Winding::kSingleSided) result.cameras_in_solids = std::move(inside);
            winding = weaker(winding);
        }
    }
    collect(winding);
    if (winding == Winding::kAllFaces) {
        // Where double-sided faces put most of what single-sided faces leave free inside solids,
        // they are not telling solids apart (a room of them wound outwards, some furniture wound
        // inwards, without a camera): single-sided faces alone vote. Suzanne's inside is a quarter
        // of the single-sided free points, a closed double-sided sphere's a third.
        std::vector<FreePoint> all_faces = std::move(free_points);
        const uint32_t tried = result.candidates;  // the same candidates, tested again
        collect(Winding::kSingleSided);
        result.candidates = tried;
        if (4 * all_faces.size() >= free_points.size()) {
            free_points = std::move(all_faces);
        } else {
            winding = Winding::kSingleSided;
        }
    }
    while (winding != Winding::kIgnored && free_points.empty()) {
        winding = weaker(winding);
        collect(winding);
    }
    result.winding_ignored = winding == Winding::kIgnored;
    std::vector<bool> kept = reachablePoints(tracer, light, free_points, starts_are_cameras);

    // Where the starts' free space is a small part of the bounds (a room beside a large ground
    // plane or terrain), the bounds-wide candidates almost never fall in it and the camera would
    // stay at the starts: candidates around each start, at scales halving from the bounds' down
    // to a wall's thickness, fill it. Scenes whose bounds-wide candidates reach enough points
    // keep them alone.
    if (size_t(std::count(kept.begin(), kept.end(), true)) < count && !starts.empty()) {
        const float largest_half = std::max({half.x, half.y, half.z});
        uint32_t scales = 0;
        for (float r = 0.5f * largest_half; r >= kSmallestAroundStarts * diagonal && scales < 64; r *= 0.5f) ++scales;
        // As many candidates as the bounds-wide ones (8x the points needed): every scale around
        // one start, then around the next, round-robin. A scene with hundreds of cameras costs no
        // more, and the pairwise reachability test stays a few hundred thousand rays.
        const uint32_t candidates = 8 * count;
        for (uint32_t i = 0; i < candidates && scales > 0; ++i) {
            const glm::vec3& start = starts[(i / scales) % starts.size()];
            const float r = 0.5f * largest_half * std::ldexp(1.0f, -int(i % scales));
            const uint32_t n = candidates + i;
            const glm::vec3 u(hashToUnitFloat(seed, n, 0), hashToUnitFloat(seed, n, 1), hashToUnitFloat(seed, n, 2));
            tryPoint(start + (2.0f * u - 1.0f) * r, std::min(clearance, kClearanceOfScale * r), winding);
        }
        kept = reachablePoints(tracer, light, free_points, starts_are_cameras);
    }
    result.free = uint32_t(free_points.size());
    if (free_points.empty()) return result;

    uint64_t escaped_probes = 0;
    bool any_known = false;
    for (size_t i = 0; i < free_points.size() && result.points.size() < count; ++i) {
        if (!kept[i]) continue;
        result.points.push_back(free_points[i].position);
        escaped_probes += uint64_t(free_points[i].escaped);
        any_known = any_known || free_points[i].known;
    }
    if (!result.points.empty())
        result.escaped_fraction = float(double(escaped_probes) / double(result.points.size() * kProbeCount));
    // Without a camera, free space that is closed (no probe ray leaves it), that no single-sided
    // face calls free, and that no light reaches is the inside of a closed object lit from
    // outside: a cube or a housing under the sky, whose bounds hold nothing but its inside. The
    // automatic camera frames such a scene from outside; so must the bake. Points spread over
    // those found are tested, since a lit room may be a few of them. Space with an opening is left
    // alone (light may come in through it), as is a room whose single-sided walls face it (a sky
    // dome of unlit faces wound inwards).
    if (!starts_are_cameras && !result.points.empty() && escaped_probes == 0 && !any_known) {
        const size_t tested = std::min(result.points.size(), kLightTests);
        bool lit = false;
        for (size_t i = 0; i < tested && !lit; ++i) {
            lit = light.reachesInside(result.points[i * result.points.size() / tested]);
        }
        result.dark_enclosure = !lit;
    }
    return result;
}

namespace {

/// The radius of the sphere around the box [lo, hi] (at least 1e-3).
float boxRadius(glm::vec3 lo, glm::vec3 hi) { return std::max(0.5f * glm::length(hi - lo), 1e-3f); }

/// How far a camera of vertical field of view `yfov` stands to see a sphere of `radius` whole,
/// with a 10% margin.
float framingDistanceOf(float radius, float yfov) { return 1.1f * radius / std::sin(0.5f * yfov); }

}  // namespace

float boundingRadius(const Scene& scene) { return boxRadius(scene.bounds_min, scene.bounds_max); }

float framingDistance(const Scene& scene, float yfov) { return framingDistanceOf(boundingRadius(scene), yfov); }

Camera automaticCamera(const Scene& scene, float yfov) {
    Camera c;
    c.name = "automatic";
    c.yfov = yfov;
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const glm::vec3 toward_camera = glm::normalize(glm::vec3(0.45f, 0.55f, 1.0f));
    c.position = center + toward_camera * framingDistance(scene, c.yfov);
    c.forward = -toward_camera;
    c.up = glm::normalize(glm::cross(glm::cross(c.forward, glm::vec3(0.0f, 1.0f, 0.0f)), c.forward));
    return c;
}

namespace {

/// Rays from outside the scene towards its content that must all meet a glowing shell first.
constexpr uint32_t kShellRays = 16;

/// Whether the triangle's material emits at all, whatever its texture says at any one point: a
/// dome whose texture has dark texels is still a shell (unlike mostlyEmittersAround, which asks
/// what a view shows).
bool hasEmissiveMaterial(const Scene& scene, uint32_t triangle) {
    return scene.materials[scene.triangle_materials[triangle]].isEmissive();
}

/// The camera inside a closed room around the centre of the scene's bounds (automaticCamera's
/// second half), or nothing where the scene is to be framed from outside.
std::optional<Camera> cameraInsideRoom(const Tracer& tracer, const Camera& outside) {
    const Scene& scene = tracer.scene();
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float clearance = 0.01f * glm::length(scene.bounds_max - scene.bounds_min);
    const FreeSpaceProbe by_winding = probeFreeSpace(tracer, center, clearance, Winding::kSingleSided);
    // Single-sided walls wound away from the centre (a cube scaled up into a room) put it inside a
    // solid: the clearance alone then says whether it is free, as exploreFreeSpace ignores a
    // winding that finds no free space, and light below whether it is a room.
    const FreeSpaceProbe probe = by_winding.free ? by_winding
                                                 : probeFreeSpace(tracer, center, clearance, Winding::kIgnored);
    if (!probe.free || probe.escaped > 0 || visibleOneWay(tracer, outside.position, center)) return std::nullopt;
    // Closed around the centre: a room, or the inside of a closed object. Single-sided walls
    // facing the centre say a room (the winding voted it free); other walls (double-sided, as
    // Blender writes them by default, or wound outwards) look the same from inside a room and
    // inside a solid model, and only light tells them apart: a room is lit from within, a model
    // under the sky from outside.
    // The inside of a glowing object (a closed emissive model, double-sided) is lit by its own
    // walls: no room, whose lamps are a part of what surrounds the centre. Where most of what the
    // centre sees emits, the view from there is a white wall and the object is framed from outside.
    if (!by_winding.known && (mostlyEmittersAround(tracer, center) || !LightTest(tracer).reachesInside(center)))
        return std::nullopt;
    // Level (+Y up), along the horizontal axis with the most room, from near the wall behind: the
    // view across the whole room (from the centre it filled the frame with the far wall alone).
    const auto distanceTo = [&](glm::vec3 d) {
        RayHit hit;
        return tracer.intersect(Ray{center, d}, hit) ? hit.t : std::numeric_limits<float>::infinity();
    };
    const glm::vec3 axes[2] = {{0, 0, 1}, {1, 0, 0}};
    float longest = -1.0f;
    Camera inside = outside;
    for (const glm::vec3& axis : axes) {
        const float ahead = distanceTo(-axis), behind = distanceTo(axis);
        if (!(ahead + behind > longest) || !std::isfinite(ahead + behind)) continue;
        longest = ahead + behind;
        inside.forward = -axis;  // glTF's cameras look down -Z: the first axis ties to that
        inside.position = center + axis * (0.8f * behind);
    }
    if (longest < 0.0f) return std::nullopt;
    inside.up = glm::vec3(0.0f, 1.0f, 0.0f);
    return inside;
}

/// A scene wrapped in a glowing shell: a sky dome modelled as an emissive or unlit sphere (or
/// hemisphere) around it, or a glowing box around a model. From outside, the camera sees nothing
/// but the shell, whose outer side the bake never reaches (it explores the lit space inside).
/// The shell is recognised from above and around: rays from outside the scene towards the
/// centre of what does not emit (the content), from kShellRays directions above it, meet
/// emitting surfaces first (all but one: a ray may slip through a shared vertex). Returns the
/// camera framing the content from `outside`'s direction, moved inside the shell where the
/// framing distance reaches it; nothing where no such shell hides the content.
std::optional<Camera> cameraInsideGlowingShell(const Tracer& tracer, const Camera& outside) {
    const Scene& scene = tracer.scene();
    glm::vec3 lo(std::numeric_limits<float>::max()), hi(-std::numeric_limits<float>::max());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        if (hasEmissiveMaterial(scene, uint32_t(t))) continue;
        for (int k = 0; k < 3; ++k) {
            lo = glm::min(lo, scene.positions[scene.triangles[t][k]]);
            hi = glm::max(hi, scene.positions[scene.triangles[t][k]]);
        }
    }
    if (!(lo.x <= hi.x)) return std::nullopt;  // everything emits: a glowing object, no content
    const glm::vec3 content = 0.5f * (lo + hi);
    const glm::vec3 scene_center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float far = 2.0f * boundingRadius(scene) + glm::distance(content, scene_center);
    // How far from the content's centre, along `d`, a ray from outside first meets an emitter;
    // negative where its first hit does not emit or it meets nothing.
    const auto shellDistance = [&](glm::vec3 d) {
        RayHit hit;
        if (!tracer.intersect(Ray{content + far * d, -d}, hit) || !hasEmissiveMaterial(scene, hit.triangle))
            return -1.0f;
        return far - hit.t;
    };
    uint32_t shell_hits = 0;
    for (uint32_t i = 0; i < kShellRays; ++i) {  // the upper half of a Fibonacci sphere
        if (shellDistance(sphericalFibonacciDirection(i, 2 * kShellRays)) > 0.0f) ++shell_hits;
    }
    const glm::vec3 toward_camera = glm::normalize(outside.position - scene_center);
    const float shell = shellDistance(toward_camera);
    if (shell_hits + 1 < kShellRays || shell <= 0.0f) return std::nullopt;
    Camera inside = outside;
    inside.position = content +
                      toward_camera * std::min(framingDistanceOf(boxRadius(lo, hi), outside.yfov), 0.9f * shell);
    return inside;
}

}  // namespace

Camera automaticCamera(const Tracer& tracer, float yfov) {
    const Camera outside = automaticCamera(tracer.scene(), yfov);
    if (tracer.scene().empty()) return outside;
    if (std::optional<Camera> room = cameraInsideRoom(tracer, outside)) return *room;
    if (std::optional<Camera> shell = cameraInsideGlowingShell(tracer, outside)) return *shell;
    return outside;
}

namespace {
/// Views from around an open scene look from this many radii of its bounding sphere, just outside
/// it (so never inside geometry), with a 45-degree field of view, at points of the surface: the
/// surface fills most of each image, so most update paths meet it, and the views' many
/// directions see all of it. Measured on lone models under a sky (BENCHMARKS.md, "A lone model
/// without a camera") against views that frame the whole bounding sphere as render's automatic
/// camera does, and against views aimed at the centre.
constexpr float kViewsAroundDistance = 1.5f;
}  // namespace

std::vector<CameraPose> viewsAroundScene(const Scene& scene, uint32_t count, uint32_t seed) {
    std::vector<CameraPose> poses;
    // Each view looks at a point of the surface, drawn by area: a thin or sparse model leaves
    // most of a view aimed at the centre empty.
    const std::vector<SurfacePoint> targets = sampleSurfacePoints(scene, count, seed);
    if (targets.empty()) return poses;
    const glm::vec3 center = 0.5f * (scene.bounds_min + scene.bounds_max);
    const float distance = kViewsAroundDistance * boundingRadius(scene);
    constexpr float kYfov = 0.25f * kPi;
    for (uint32_t i = 0; i < count; ++i) {
        const glm::vec3 direction = sphericalFibonacciDirection(i, count);
        // The points come in the order of the scene's triangles: a hashed pick keeps where a view
        // stands from deciding which part of the scene it looks at.
        const glm::vec3 target = targets[hashCombine(hashUint32(seed), i) % targets.size()].position;
        CameraPose pose;
        if (makeLookAtPose(center + distance * direction, target, kYfov, pose)) poses.push_back(pose);
    }
    return poses;
}

CameraPath::CameraPath(std::vector<CameraPose> waypoints, bool random_directions, uint32_t iterations_per_leg,
                       float position_jitter, uint32_t seed, std::vector<bool> aimed)
    : waypoints_(std::move(waypoints)),
      aimed_(std::move(aimed)),
      random_directions_(random_directions),
      iterations_per_leg_(std::max(1u, iterations_per_leg)),
      position_jitter_(position_jitter),
      seed_(seed) {
    if (waypoints_.empty()) throw CameraPathError("the camera path has no waypoint");
    aimed_.resize(waypoints_.size(), false);
}

CameraPose CameraPath::poseAt(uint32_t iteration) const {
    const size_t n = waypoints_.size();
    CameraPose pose;
    if (random_directions_) {
        // Exploration: every waypoint in turn, looking in a fresh uniformly random direction
        // unless it is aimed (a view from around the scene).
        pose = waypoints_[iteration % n];
        if (!aimed_[iteration % n]) {
            const glm::vec3 d = sampleUniformSphere(
                {hashToUnitFloat(seed_, iteration, 10), hashToUnitFloat(seed_, iteration, 11)});
            makeLookAtPose(pose.position, pose.position + d, pose.yfov, pose);
        }
    } else {
        // Glide from waypoint k to k+1 over iterations_per_leg iterations, looping.
        const uint32_t leg = iteration / iterations_per_leg_;
        const float t = float(iteration % iterations_per_leg_) / float(iterations_per_leg_);
        const CameraPose& a = waypoints_[leg % n];
        const CameraPose& b = waypoints_[(leg + 1) % n];
        glm::vec3 forward = (1.0f - t) * a.forward + t * b.forward;
        if (glm::length(forward) < 1e-4f) forward = a.forward;
        const glm::vec3 position = (1.0f - t) * a.position + t * b.position;
        makeLookAtPose(position, position + glm::normalize(forward), (1.0f - t) * a.yfov + t * b.yfov, pose);
        // At the waypoint itself the view is the waypoint's: a glTF camera's keeps its clip
        // planes (a cutaway camera outside a room sees in). Between waypoints it is no camera's,
        // and a near plane carried along a glide would cut through whatever it passes.
        if (t == 0.0f) {
            pose.znear = a.znear;
            pose.zfar = a.zfar;
        }
    }
    // The position jitter (a fraction of a percent of the scene) shakes a view without making it
    // another: the clip planes stay.
    if (position_jitter_ > 0.0f) {
        const glm::vec3 u(hashToUnitFloat(seed_, iteration, 20), hashToUnitFloat(seed_, iteration, 21),
                          hashToUnitFloat(seed_, iteration, 22));
        pose.position += (2.0f * u - 1.0f) * position_jitter_;
    }
    return pose;
}

std::vector<Ray> sampleCameraPathRays(const CameraPath& path, int width, int height, uint32_t poses,
                                      uint32_t rays_per_pose, uint32_t seed) {
    std::vector<Ray> rays;
    rays.reserve(size_t(poses) * rays_per_pose);
    const uint64_t period = path.period();
    for (uint32_t k = 0; k < poses; ++k) {
        const CameraRays camera(toCamera(path.poseAt(uint32_t(uint64_t(k) * period / poses))), width, height);
        for (uint32_t i = 0; i < rays_per_pose; ++i) {
            const uint32_t id = k * rays_per_pose + i;
            const int x = std::min(int(hashToUnitFloat(seed, id, 5) * float(width)), width - 1);
            const int y = std::min(int(hashToUnitFloat(seed, id, 6) * float(height)), height - 1);
            rays.push_back(camera.generate(x, y, {hashToUnitFloat(seed, id, 7), hashToUnitFloat(seed, id, 8)}));
        }
    }
    return rays;
}

CameraPath atGltfCameraPositions(const Scene& scene, uint32_t seed) {
    std::vector<CameraPose> poses;
    std::vector<bool> aimed;
    for (const Camera& camera : scene.cameras) {
        const CameraPose own = poseOf(camera);  // its own view, clip planes and all
        poses.push_back(own);
        aimed.push_back(true);
        poses.push_back(own);  // its direction is drawn afresh each iteration, without clip planes
        aimed.push_back(false);
    }
    return CameraPath(std::move(poses), true, 1, 0.0f, seed, std::move(aimed));
}

std::optional<CameraPath> exploringCameraPath(const Tracer& tracer, const Scene& scene, uint32_t points,
                                              uint32_t seed, ExplorationResult* explored) {
    std::vector<glm::vec3> starts;
    // From where each camera's view begins: a cutaway camera outside a room looks into the room.
    for (const Camera& c : scene.cameras) starts.push_back(viewStart(tracer, c));
    const bool starts_are_cameras = !starts.empty();
    if (starts.empty()) starts.push_back(0.5f * (scene.bounds_min + scene.bounds_max));
    ExplorationResult result = exploreFreeSpace(tracer, starts, starts_are_cameras, points, seed);
    if (result.points.empty()) {
        if (explored) *explored = result;
        return std::nullopt;
    }
    // Open space around the free points (most probe rays leave the scene, as around a lone
    // model) says the scene is looked at from outside, as render's automatic camera does, when it
    // has no camera or its cameras all stand outside its bounds (Blender's default camera and
    // cube): exploring inside the bounds and the corner of them the cameras face leaves the rest
    // without a voxel at the finest level (75% of Blender's default cube). A camera inside the
    // bounds (a street, a room with an open side, a house's interior beside its exterior view)
    // keeps the bake's paths near it.
    result.cameras_outside = starts_are_cameras;
    for (const glm::vec3& start : starts) {
        if (insideBox(start, scene.bounds_min, scene.bounds_max)) result.cameras_outside = false;
    }
    std::vector<CameraPose> around;
    if ((!starts_are_cameras || result.cameras_outside) &&
        (result.escaped_fraction >= kOpenSceneEscapedFraction || result.dark_enclosure)) {
        around = viewsAroundScene(scene, uint32_t(result.points.size()), seed);
    }
    result.views_around = uint32_t(around.size());
    if (explored) *explored = result;
    // The inside of a closed object lit from outside is black and no runtime camera stands
    // there: the views from around alone.
    if (result.dark_enclosure && !around.empty()) {
        return CameraPath(std::move(around), true, 1, 0.0f, seed, std::vector<bool>(result.views_around, true));
    }
    // Free-space points and views from around alternate, so a short bake gets both.
    std::vector<CameraPose> poses;
    std::vector<bool> aimed;
    for (size_t i = 0; i < result.points.size(); ++i) {
        poses.push_back(CameraPose{result.points[i]});
        aimed.push_back(false);
        if (i < around.size()) {
            poses.push_back(around[i]);
            aimed.push_back(true);
        }
    }
    return CameraPath(std::move(poses), true, 1, 0.0f, seed, std::move(aimed));
}

}  // namespace sharcbake
