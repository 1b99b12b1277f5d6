// SPDX-License-Identifier: Apache-2.0
/// @file tracer.h
/// @brief Ray casting against a Scene with Embree 3: closest hit and occlusion (shadow) rays.
#pragma once

#include "sharcbake/scene.h"

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include <cstdint>
#include <limits>
#include <vector>

namespace sharcbake {

struct Ray {
    glm::vec3 origin;
    glm::vec3 direction;  ///< unit length
    float t_max = std::numeric_limits<float>::infinity();
};

/// What the closest-hit query returns; the surface itself is reconstructed by the caller from
/// the triangle and barycentrics (see surface.h).
struct RayHit {
    uint32_t triangle = 0;
    float t = 0.0f;
    float u = 0.0f;  ///< barycentric of vertex 1
    float v = 0.0f;  ///< barycentric of vertex 2
};

/// Where every traced ray begins: just after its origin. Embree's robust (watertight) mode
/// reports a triangle through the origin itself at t = 0, so a camera standing on a floor would
/// see the floor behind every upward ray; a distance of zero is never a hit.
inline constexpr float kRayTNear = std::numeric_limits<float>::min();

/// Fills an Embree ray from `ray` over (kRayTNear, t_max): what Tracer traces, for code that
/// calls Embree's packet or stream APIs itself.
void initEmbreeRay(const Ray& ray, RTCRay& embree_ray);

/// initEmbreeRay for lane `lane` of an Embree packet (RTCRay4/8/16: one array per field).
template <typename RayN>
void initEmbreeLane(const Ray& ray, RayN& packet, int lane) {
    packet.org_x[lane] = ray.origin.x;
    packet.org_y[lane] = ray.origin.y;
    packet.org_z[lane] = ray.origin.z;
    packet.dir_x[lane] = ray.direction.x;
    packet.dir_y[lane] = ray.direction.y;
    packet.dir_z[lane] = ray.direction.z;
    packet.tnear[lane] = kRayTNear;
    packet.tfar[lane] = ray.t_max;
    packet.time[lane] = 0.0f;
    packet.mask[lane] = 0xffffffffu;
    packet.id[lane] = 0;
    packet.flags[lane] = 0;
}

/// Owns an Embree device and a committed scene built over Scene's triangles. Thread-safe for
/// queries after construction. Holds a reference to the Scene, which must outlive it.
class Tracer {
public:
    explicit Tracer(const Scene& scene);
    ~Tracer();
    Tracer(const Tracer&) = delete;
    Tracer& operator=(const Tracer&) = delete;

    /// Closest hit along the ray within (0, t_max). Returns false on a miss.
    bool intersect(const Ray& ray, RayHit& hit) const;
    /// True if anything blocks the segment (0, t_max).
    bool occluded(const Ray& ray) const;

    /// Closest hits of `count` rays at once: hits[i] is valid where found[i] is 1. The same hits
    /// as intersect() ray by ray, but Embree traverses them 16 at a time (its packet API, the
    /// fastest of single rays, streams and packets on these rays: BENCHMARKS.md). `rays` and the
    /// outputs hold `count` entries.
    void intersectMany(const Ray* rays, size_t count, RayHit* hits, uint8_t* found) const;
    /// Occlusion of `count` segments at once, 16 at a time: blocked[i] is 1 where something
    /// blocks rays[i].
    void occludedMany(const Ray* rays, size_t count, uint8_t* blocked) const;

    const Scene& scene() const { return scene_; }
    /// The committed Embree scene, for code that calls Embree's packet or stream APIs directly
    /// (the ray-limit benchmark); read-only use only.
    RTCScene embreeScene() const { return rtc_scene_; }

private:
    const Scene& scene_;
    RTCDevice device_ = nullptr;
    RTCScene rtc_scene_ = nullptr;
};

/// Moves a ray origin off a surface so the new ray does not re-hit it, using an offset that
/// scales with the magnitude of the position (integer ULP steps, after Waechter and Binder,
/// "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing Gems 2019).
/// @param normal the geometric normal on the side the ray leaves from.
glm::vec3 offsetRayOrigin(glm::vec3 position, glm::vec3 normal);

/// offsetRayOrigin's two regimes: a coordinate within kRayOffsetOriginRegion of 0 moves a fixed
/// kRayOffsetNearOrigin along the normal (floats are dense there); any other moves 256 float32
/// steps. A scene that lies wholly near the origin therefore gets the fixed offset everywhere.
inline constexpr float kRayOffsetOriginRegion = 1.0f / 32.0f;
inline constexpr float kRayOffsetNearOrigin = 1.0f / 65536.0f;

/// The shadow ray from a surface point, leaving the side `normal` faces, towards a light sample
/// in direction `wi` at `distance` (infinite for the sky and directional lights): it stops just
/// short of the light point. False where the light point is the origin itself.
bool shadowRayTo(glm::vec3 position, glm::vec3 normal, glm::vec3 wi, float distance, Ray& out);

/// True when nothing blocks the segment from `a` to `b` (a ray from `a`; true when they coincide).
bool visibleOneWay(const Tracer& tracer, glm::vec3 a, glm::vec3 b);
/// Unblocked from `a` to `b` and from `b` to `a`. Embree's triangle test is not watertight even in
/// the robust mode the Tracer uses: a ray that meets a shared vertex can slip between its
/// triangles (before robust mode, a shared edge too: among thousands of segments, one joined a
/// closed room's camera to the ground outside). The ray back starts elsewhere and rounds
/// differently, so it does not slip through at the same place.
bool visibleBothWays(const Tracer& tracer, glm::vec3 a, glm::vec3 b);

/// True when a ray from `from` along unit `d` leaves the scene: nothing blocks it, and the ray
/// back from beyond the bounds reaches `from` too (a ray that meets a shared edge can slip
/// between its two triangles, as visibleBothWays says; from inside a closed mesh it would seem to
/// escape).
bool leavesScene(const Tracer& tracer, glm::vec3 from, glm::vec3 d);

/// How far rays from `from` in `directions` directions spread over the sphere (a spherical
/// Fibonacci set) travel before they hit something, for those that do: the room around a point.
std::vector<float> hitDistancesAround(const Tracer& tracer, glm::vec3 from, uint32_t directions);

/// The largest distance offsetRayOrigin moves an origin anywhere in the bounds: at the coordinate
/// farthest from 0 on any axis (`far_coordinate`, as max |bounds|).
float largestRayOffset(float far_coordinate);

}  // namespace sharcbake
