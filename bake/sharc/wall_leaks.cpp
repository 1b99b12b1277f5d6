// SPDX-License-Identifier: Apache-2.0
#include "sharc/wall_leaks.h"

#include "sharc/grid_points.h"
#include "sharc/light_leaks.h"
#include "support/median.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"
#include "tracing/surface_points.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace sharcbake {
namespace {

/// A side counts as reached when one of this many waypoints nearest to it sees it.
constexpr size_t kWaypointsTried = 6;
/// Directions along the surface a side looks for a wall in, within its voxel.
constexpr uint32_t kAlongDirections = 8;
/// Surfaces a probe along the surface passes (the wall's near face, its far face, ...).
constexpr int kCrossings = 3;
/// Heights, in voxels, at which the wall must block too, up to whatever bounds the space above
/// (a partition reaches the ceiling): a table leg, a kerb or a low divider is seen over.
constexpr float kWallHeights[] = {1.0f, 4.0f, 16.0f};

struct Waypoints {
    std::array<uint32_t, kWaypointsTried> index{};
    uint32_t count = 0;
};

/// The waypoints among the kWaypointsTried nearest `origin` that see it.
Waypoints waypointsSeeing(const Tracer& tracer, glm::vec3 origin, const std::vector<glm::vec3>& waypoints) {
    std::vector<uint32_t> order(waypoints.size());
    std::iota(order.begin(), order.end(), 0u);
    const size_t tried = std::min(kWaypointsTried, order.size());
    std::partial_sort(order.begin(), order.begin() + tried, order.end(), [&](uint32_t a, uint32_t b) {
        const glm::vec3 da = waypoints[a] - origin, db = waypoints[b] - origin;
        return glm::dot(da, da) != glm::dot(db, db) ? glm::dot(da, da) < glm::dot(db, db) : a < b;
    });
    Waypoints seeing;
    for (size_t i = 0; i < tried; ++i)
        if (visibleBothWays(tracer, origin, waypoints[order[i]])) seeing.index[seeing.count++] = order[i];
    return seeing;
}

bool shareOne(const Waypoints& a, const Waypoints& b) {
    for (uint32_t i = 0; i < a.count; ++i)
        for (uint32_t j = 0; j < b.count; ++j)
            if (a.index[i] == b.index[j]) return true;
    return false;
}

/// Whether the side at `origin` (surface point `position`, facing `normal`, keyed `key` from
/// `camera`, in a voxel `voxel` wide) shares its voxel with a surface facing the same way beyond
/// a wall: along the surface, within the voxel, a probe meets something, passes it, and finds
/// just beyond it, below the probe, a surface facing `normal` that SHaRC keys alike and the
/// roaming camera reaches, though no one waypoint sees both and the wall still blocks 1, 4 and 16
/// voxels off the surface and to either side along the wall (or up to what bounds the space).
bool leaksBeyondWall(const Tracer& tracer, const HashGridKeyer& keyer, const std::vector<glm::vec3>& waypoints,
                     glm::vec3 position, glm::vec3 origin, glm::vec3 normal, glm::vec3 camera, uint64_t key,
                     float voxel, const Waypoints& seen_by) {
    const Scene& scene = tracer.scene();
    const Frame frame(normal);
    const float lift = glm::length(origin - position) * 2.0f + 1e-7f;  // just above the surface
    // Far from the origin floats are coarse: where a ray offset along an axis (256 float steps of
    // the point's largest coordinate) is a tenth of the voxel, a wall cannot be told from the
    // offset (the bake warns about the offset itself).
    if (floatSteps(position, 256.0f) > 0.1f * voxel) return false;
    for (uint32_t k = 0; k < kAlongDirections; ++k) {
        const float angle = 2.0f * kPi * (float(k) + 0.5f) / float(kAlongDirections);
        const glm::vec3 along = frame.toWorld(glm::vec3(std::cos(angle), std::sin(angle), 0.0f));
        glm::vec3 from = position + lift * normal;
        float left = voxel;
        for (int crossing = 0; crossing < kCrossings && left > 0.0f; ++crossing) {
            RayHit wall;
            if (!tracer.intersect(Ray{from, along, left}, wall)) break;
            // Just past what the probe met: a few float steps, so a partition 0.1 mm thick (or
            // the bias of SHaRC's keys, 0.1 mm) is not stepped over.
            const glm::vec3 met = from + wall.t * along;
            const glm::vec3 wall_normal = makeSurfaceHit(scene, wall, along).face_normal;
            const float step = floatSteps(met, 8.0f) + 1e-7f;
            from = met + step * along;
            left -= wall.t + step;
            RayHit below;
            if (!tracer.intersect(Ray{from, -normal, 4.0f * lift}, below)) continue;
            const SurfaceHit beyond = makeSurfaceHit(scene, below, -normal);
            if (glm::dot(beyond.geometric_normal, normal) < 0.9f) continue;
            if (scene.materials[beyond.material].isEmissive()) continue;
            if (keyer.key(toFloat3(beyond.position), toFloat3(beyond.geometric_normal), toFloat3(camera)) != key)
                continue;
            const glm::vec3 beyond_origin = offsetRayOrigin(beyond.position, beyond.geometric_normal,
                                                            beyond.ray_offset);
            const Waypoints beyond_seen_by = waypointsSeeing(tracer, beyond_origin, waypoints);
            if (beyond_seen_by.count == 0 || shareOne(seen_by, beyond_seen_by)) continue;
            // Off the surface and both ways along the wall, in the wall's plane: a partition meets
            // the ceiling and the side walls; a low divider, a post or a fin is seen around.
            const glm::vec3 off_surface = normal - glm::dot(normal, wall_normal) * wall_normal;
            if (!(glm::dot(off_surface, off_surface) > 1e-6f)) continue;  // the wall lies along the surface
            const glm::vec3 up_wall = glm::normalize(off_surface);
            const glm::vec3 sideways = glm::normalize(glm::cross(wall_normal, up_wall));
            bool wall_all_round = true;
            for (const glm::vec3 lift_direction : {up_wall, sideways, -sideways}) {
                for (const float height : kWallHeights) {
                    const glm::vec3 up = (height * voxel) * lift_direction;
                    // Past what bounds the space on either side, the wall met it.
                    if (!visibleOneWay(tracer, origin, origin + up) ||
                        !visibleOneWay(tracer, beyond_origin, beyond_origin + up))
                        break;
                    if (visibleBothWays(tracer, origin + up, beyond_origin + up)) {
                        wall_all_round = false;
                        break;
                    }
                }
                if (!wall_all_round) break;
            }
            if (wall_all_round) return true;
        }
    }
    return false;
}

}  // namespace

std::string WallLeakReport::describe() const {
    if (share < kWallLeakShare || leaking_sides < kWallLeakSides) return "";
    char text[640];
    std::snprintf(text, sizeof text,
                  "%.2g%% of the surface the roaming camera reaches shares voxels (%.3g units wide, as the "
                  "nearest view keys them) with surface facing the same way on the other side of a wall thinner "
                  "than that: where paths reach both sides, renders through the cache show each side's light on "
                  "the other, and the cache's own lookups carry it through the room (two rooms 0.1 mm apart: the "
                  "dim one 60 times too bright). Give partitions a thickness of at least %.3g, or bake the rooms "
                  "apart",
                  100.0 * share, double(voxel_size), double(voxel_size));
    return text;
}

WallLeakReport findWallLeaks(const Tracer& tracer, const HashGridParameters& grid,
                             const std::vector<glm::vec3>& cameras, const std::vector<glm::vec3>& waypoints,
                             uint32_t points, uint32_t seed) {
    WallLeakReport report;
    if (cameras.empty() || waypoints.empty()) return report;
    const Scene& scene = tracer.scene();
    const std::vector<SurfacePoint> surface = sampleSurfacePoints(scene, points, hashCombine(seed, 0x3a11u));
    report.points = uint32_t(surface.size());
    const HashGridKeyer keyer(grid);
    // Both sides of every point: single-sided surfaces reflect on their backs too. Emitters are
    // the light-leak check's (light_leaks.h): a lamp under a ceiling is not a wall.
    std::vector<uint8_t> seen(2 * surface.size(), 0), leaking(2 * surface.size(), 0);
    std::vector<float> voxel_of(2 * surface.size(), 0.0f);
    tbb::parallel_for(size_t(0), seen.size(), [&](size_t i) {
        const SurfacePoint& p = surface[i / 2];
        if (scene.materials[scene.triangle_materials[p.triangle]].isEmissive()) return;
        const glm::vec3 normal = (i & 1) ? -p.normal : p.normal;
        const glm::vec3 origin = offsetRayOrigin(p.position, normal, p.ray_offset);
        const Waypoints seen_by = waypointsSeeing(tracer, origin, waypoints);
        if (seen_by.count == 0) return;
        seen[i] = 1;
        const glm::vec3 camera = nearestCamera(p.position, cameras);
        const glm::vec3 to_camera = p.position - camera;
        const float voxel = keyer.voxelSizeAt(keyer.levelOf(glm::dot(to_camera, to_camera)));
        const uint64_t key = keyer.key(toFloat3(p.position), toFloat3(normal), toFloat3(camera));
        if (leaksBeyondWall(tracer, keyer, waypoints, p.position, origin, normal, camera, key, voxel, seen_by)) {
            leaking[i] = 1;
            voxel_of[i] = voxel;
        }
    });
    std::vector<float> voxels;
    for (size_t i = 0; i < seen.size(); ++i) {
        report.seen_sides += seen[i];
        if (leaking[i]) voxels.push_back(voxel_of[i]);
    }
    report.leaking_sides = uint32_t(voxels.size());
    report.share = report.seen_sides == 0 ? 0.0 : double(voxels.size()) / double(report.seen_sides);
    if (!voxels.empty()) report.voxel_size = median(voxels);
    return report;
}

}  // namespace sharcbake
