// SPDX-License-Identifier: Apache-2.0
/// @file tracer.h
/// @brief Ray casting against a Scene with Embree 3: closest hit and occlusion (shadow) rays.
#pragma once

#include "sharcbake/scene.h"

#include <embree3/rtcore.h>
#include <glm/glm.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace sharcbake {

struct Ray {
    glm::vec3 origin;
    glm::vec3 direction;  ///< unit length
    float t_max = std::numeric_limits<float>::infinity();
    /// Where the ray's segment begins: a camera's near clip plane, which hides what lies nearer
    /// (a camera outside a room sees through its wall). Never before kRayTNear (rayTNear).
    float t_min = 0.0f;
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

/// Where Embree begins tracing `ray`: at its t_min, and no nearer than kRayTNear.
inline float rayTNear(const Ray& ray) { return ray.t_min > kRayTNear ? ray.t_min : kRayTNear; }

/// Whether Embree traces `ray` at all: its origin and direction within +-1.844e18 per component
/// (Embree's FLT_LARGE) and t_min and t_max not NaN. Embree asserts this of every ray, and
/// Debian's build keeps its assertions, so a ray beyond it aborts the process (a NaN from a
/// degenerate normal, an offset by a voxel of 1e20 units). Tracer treats such a ray as meeting
/// nothing.
inline bool embreeTraces(const Ray& ray) {
    constexpr float kLargest = 1.844e18f;
    const glm::vec3 o = glm::abs(ray.origin), d = glm::abs(ray.direction);
    return o.x <= kLargest && o.y <= kLargest && o.z <= kLargest && d.x <= kLargest && d.y <= kLargest &&
           d.z <= kLargest && !std::isnan(ray.t_max) && !std::isnan(ray.t_min);
}

/// Fills an Embree ray from `ray` over (rayTNear(ray), t_max): what Tracer traces, for code that
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
    packet.tnear[lane] = rayTNear(ray);
    packet.tfar[lane] = ray.t_max;
    packet.time[lane] = 0.0f;
    packet.mask[lane] = 0xffffffffu;
    packet.id[lane] = 0;
    packet.flags[lane] = 0;
}

/// Which of Embree's kernels trace the rays. Embree would pick the widest this CPU runs, and its
/// kernels differ in more than speed: SSE4.2's test triangles with separate multiplies and adds,
/// AVX2's and AVX-512's with fused multiply-adds, and their BVHs are walked in other orders, so
/// a ray that passes within a rounding of a triangle's edge, or meets two triangles at the same
/// distance, can hit the other one: the same bake of a CAD model gave different caches with each
/// of the three. Naming the kernels makes caches agree between CPUs that run them (but for the
/// order of overlapping triangles across CPU makers: docs/baking.md).
enum class TraceKernels {
    kAvx2,   ///< AVX2 with FMA: Intel Core and Xeon since Haswell (2013), AMD since Excavator (2015)
    kSse42,  ///< SSE4.2 (SSE2 where a CPU lacks it): every x86-64 CPU; slower
    kNative  ///< Embree's choice for this CPU (AVX-512 where it has it): caches differ between CPUs
};
inline constexpr TraceKernels kAllTraceKernels[] = {TraceKernels::kAvx2, TraceKernels::kSse42, TraceKernels::kNative};

/// "avx2", "sse4.2" or "native", as the command line names them.
const char* traceKernelsName(TraceKernels kernels);
/// Every kernels' name, in kAllTraceKernels' order: what --trace-kernels accepts.
std::vector<std::string> traceKernelsNames();
/// The kernels traceKernelsName names `name`; kAvx2 (the default) for any other name, which the
/// command lines refuse before asking.
TraceKernels traceKernelsNamed(std::string_view name);

/// Whether this CPU runs Embree's AVX2 kernels (AVX2, FMA, BMI1 and BMI2). Where it does not,
/// glibc's maths routines run without FMA too and round some results differently in the last bit
/// (0.07% of random inputs to double sin, exp and pow, 8 in 20 million to float sincos; none of 20
/// million to float sin, exp, log and pow), so a cache baked there can differ from one baked on a
/// newer CPU even with the same kernels.
bool cpuRunsAvx2Kernels();

/// Sets `hit`'s distance and barycentrics anew from the triangle Embree found (hit.triangle), in
/// double precision with correctly rounded operations only. Embree's own come from a reciprocal
/// estimate (rcpps or rcp14, whose bits differ between CPU models and vendors) refined once, with
/// fused multiply-adds in some kernels: recomputed, they are the same bits wherever the same
/// triangle is hit.
void recomputeHit(const Scene& scene, const Ray& ray, RayHit& hit);

/// Owns an Embree device and a committed scene built over Scene's triangles. Thread-safe for
/// queries after construction. Holds a reference to the Scene, which must outlive it.
class Tracer {
public:
    /// Traces with `kernels`; kAvx2 on a CPU that cannot run them traces with kSse42 (kernels()
    /// says which).
    explicit Tracer(const Scene& scene, TraceKernels kernels = TraceKernels::kAvx2);
    ~Tracer();
    Tracer(const Tracer&) = delete;
    Tracer& operator=(const Tracer&) = delete;

    /// Closest hit along the ray within (t_min, t_max), from just after the origin for t_min 0.
    /// Returns false on a miss, and for a ray Embree does not trace (embreeTraces).
    bool intersect(const Ray& ray, RayHit& hit) const;
    /// True if anything blocks the segment (t_min, t_max); false for a ray Embree does not trace.
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
    /// The kernels tracing: those asked for, or kSse42 where the CPU cannot run kAvx2.
    TraceKernels kernels() const { return kernels_; }
    /// The committed Embree scene, for code that calls Embree's packet or stream APIs directly
    /// (the ray-limit benchmark); read-only use only.
    RTCScene embreeScene() const { return rtc_scene_; }

private:
    const Scene& scene_;
    TraceKernels kernels_;
    RTCDevice device_ = nullptr;
    RTCScene rtc_scene_ = nullptr;
};

/// Float32 roundings (2^-24 of a magnitude) in rayOffsetFor's bound. A point interpolated from a
/// triangle's vertices lies off its plane by a few roundings of their coordinates, and Embree's
/// test of a ray leaving it rounds its origin against the vertices once more: rays from 50,000
/// hit points on boxes of 2 to 16 triangles a side, 0.002 to 2000 units wide, 0 to 10^5 units from
/// the origin, turned and not, met their own surface with a bound of 1 or 2 roundings and never
/// with 4 (measured); 16 leaves a factor of 4.
inline constexpr float kRayOffsetRoundings = 16.0f;

/// How far off its triangle a point interpolated from the vertices p0, p1, p2 (binary32) may lie,
/// along the triangle's unit `normal` (either side): kRayOffsetRoundings roundings of the
/// vertices' largest magnitude on each axis, weighted by the normal's component on it (after
/// pbrt-v4's floating-point error bounds), and at least one rounding of their largest coordinate.
/// It depends on the vertices, not on where the point lies on the triangle: a point near the
/// origin on a triangle 10 km wide is as uncertain as its far corner. Scale-invariant: a scene 1 mm
/// across gets offsets 1000 times smaller than the same scene 1 m across. NaN normals (zero-area
/// triangles) give the least offset.
float rayOffsetFor(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 normal);

/// Moves a ray origin `offset` (rayOffsetFor its triangle) off a surface along the unit `normal`
/// of the side the ray leaves from, and one float step further on each axis the normal leans
/// along, so that rounding never puts it back on the surface.
glm::vec3 offsetRayOrigin(glm::vec3 position, glm::vec3 normal, float offset);

/// The shadow ray from a surface point, leaving the side `normal` faces (`offset` off it, as
/// offsetRayOrigin), towards a light sample in direction `wi` at `distance` (infinite for the sky
/// and directional lights): it stops just short of the light point. False where the light point
/// is the origin itself.
bool shadowRayTo(glm::vec3 position, glm::vec3 normal, float offset, glm::vec3 wi, float distance, Ray& out);

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

/// The largest distance offsetRayOrigin moves an origin off a triangle within the bounds: one
/// whose vertices reach the coordinate farthest from 0 (`far_coordinate`, as max |bounds|) on
/// every axis, facing diagonally.
float largestRayOffset(float far_coordinate);

/// bake and render warn when that offset exceeds this share of the scene's largest side: light
/// leaks through its walls and its corners darken (a 4-unit room 1e7 out: offset 19, 30% dark).
inline constexpr float kRayOffsetWarningShare = 0.01f;

}  // namespace sharcbake
