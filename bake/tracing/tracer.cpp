// SPDX-License-Identifier: Apache-2.0
#include "tracing/tracer.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace sharcbake {
namespace {

void throwOnEmbreeError(RTCDevice device, const char* what) {
    const RTCError error = rtcGetDeviceError(device);
    if (error != RTC_ERROR_NONE) {
        throw std::runtime_error(std::string("Embree error (code ") + std::to_string(int(error)) +
                                 ") while " + what);
    }
}

void initRayHit(const Ray& ray, RTCRayHit& rayhit) {
    initEmbreeRay(ray, rayhit.ray);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

float intAsFloat(int32_t i) {
    float f;
    std::memcpy(&f, &i, sizeof f);
    return f;
}
int32_t floatAsInt(float f) {
    int32_t i;
    std::memcpy(&i, &f, sizeof i);
    return i;
}

/// Embree's filter for both closest-hit and occlusion queries: a candidate hit on a cut-out
/// point of an alpha-masked or blended material is rejected, and the ray goes on. The point is
/// the recomputed one (recomputeHit), so a texel's edge cuts the same rays with every kernel.
void rejectCutOutHits(const RTCFilterFunctionNArguments* args) {
    const Scene& scene = *static_cast<const Scene*>(args->geometryUserPtr);
    const unsigned n = args->N;
    for (unsigned i = 0; i < n; ++i) {
        if (args->valid[i] == 0) continue;
        const Ray ray{{RTCRayN_org_x(args->ray, n, i), RTCRayN_org_y(args->ray, n, i), RTCRayN_org_z(args->ray, n, i)},
                      {RTCRayN_dir_x(args->ray, n, i), RTCRayN_dir_y(args->ray, n, i), RTCRayN_dir_z(args->ray, n, i)}};
        RayHit hit{RTCHitN_primID(args->hit, n, i), RTCRayN_tfar(args->ray, n, i), RTCHitN_u(args->hit, n, i),
                   RTCHitN_v(args->hit, n, i)};
        recomputeHit(scene, ray, hit);
        if (isCutOut(scene, hit.triangle, hit.u, hit.v)) args->valid[i] = 0;
    }
}

/// Embree's configuration for `kernels`: the kernels named, whatever else this CPU could run.
/// SSE4.2's may fall to SSE2's on a CPU without SSE4.2 (the same arithmetic on 4 lanes).
const char* embreeConfig(TraceKernels kernels) {
    switch (kernels) {
        case TraceKernels::kAvx2: return "isa=avx2";
        case TraceKernels::kSse42: return "max_isa=sse4.2";
        case TraceKernels::kNative: return nullptr;
    }
    return nullptr;
}

}  // namespace

const char* traceKernelsName(TraceKernels kernels) {
    switch (kernels) {
        case TraceKernels::kAvx2: return "avx2";
        case TraceKernels::kSse42: return "sse4.2";
        case TraceKernels::kNative: return "native";
    }
    return "?";
}

std::vector<std::string> traceKernelsNames() {
    std::vector<std::string> names;
    for (const TraceKernels kernels : kAllTraceKernels) names.emplace_back(traceKernelsName(kernels));
    return names;
}

TraceKernels traceKernelsNamed(std::string_view name) {
    for (const TraceKernels kernels : kAllTraceKernels) {
        if (name == traceKernelsName(kernels)) return kernels;
    }
    return TraceKernels::kAvx2;
}

bool cpuRunsAvx2Kernels() {
    // What Embree's AVX2 kernels need, and what makes glibc's maths pick its FMA routines.
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") && __builtin_cpu_supports("bmi") &&
           __builtin_cpu_supports("bmi2");
}

void recomputeHit(const Scene& scene, const Ray& ray, RayHit& hit) {
    const glm::uvec3 corners = scene.triangles[hit.triangle];
    const glm::dvec3 p0(scene.positions[corners.x]);
    const glm::dvec3 e1 = glm::dvec3(scene.positions[corners.y]) - p0;
    const glm::dvec3 e2 = glm::dvec3(scene.positions[corners.z]) - p0;
    const glm::dvec3 d(ray.direction);
    const glm::dvec3 p = glm::cross(d, e2);
    const double determinant = glm::dot(e1, p);
    // Embree found a hit, so the ray crosses the triangle's plane; a determinant that is zero
    // in double precision all the same keeps Embree's values.
    if (!(determinant != 0.0)) return;
    const double inverse = 1.0 / determinant;
    const glm::dvec3 s = glm::dvec3(ray.origin) - p0;
    const glm::dvec3 q = glm::cross(s, e1);
    // Embree's watertight test put the hit on the triangle: rounding that puts it a hair outside
    // is clamped back onto it.
    double u = std::clamp(glm::dot(s, p) * inverse, 0.0, 1.0);
    double v = std::clamp(glm::dot(d, q) * inverse, 0.0, 1.0);
    if (u + v > 1.0) {
        const double sum = u + v;
        u /= sum;
        v /= sum;
    }
    hit.u = float(u);
    hit.v = float(v);
    hit.t = std::clamp(float(glm::dot(e2, q) * inverse), rayTNear(ray), ray.t_max);
}

Tracer::Tracer(const Scene& scene, TraceKernels kernels)
    : scene_(scene),
      kernels_(kernels == TraceKernels::kAvx2 && !cpuRunsAvx2Kernels() ? TraceKernels::kSse42 : kernels) {
    device_ = rtcNewDevice(embreeConfig(kernels_));
    if (!device_) {
        throw std::runtime_error(std::string("Embree: cannot create a device with its ") + traceKernelsName(kernels_) +
                                 " kernels");
    }
    rtc_scene_ = rtcNewScene(device_);
    // An offline bake traces billions of rays against one build: spend time on BVH quality.
    rtcSetSceneBuildQuality(rtc_scene_, RTC_BUILD_QUALITY_HIGH);
    // Robust mode makes the triangle test (nearly) watertight. Without it rays slip between
    // triangles that share an edge, a few per million in a tessellated mesh: a path escapes a
    // closed room to the sky or into a wall's inside and deposits a firefly or a black voxel.
    // It costs about 6% of the bake's throughput (BENCHMARKS.md, "Watertight tracing").
    rtcSetSceneFlags(rtc_scene_, RTC_SCENE_FLAG_ROBUST);

    if (!scene.triangles.empty()) {
        RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree may read 16 bytes at the last vertex, so its own allocation (padded) is used.
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
            scene.positions.size()));
        for (size_t i = 0; i < scene.positions.size(); ++i) {
            vertices[3 * i + 0] = scene.positions[i].x;
            vertices[3 * i + 1] = scene.positions[i].y;
            vertices[3 * i + 2] = scene.positions[i].z;
        }
        auto* indices = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(uint32_t),
            scene.triangles.size()));
        std::memcpy(indices, scene.triangles.data(), scene.triangles.size() * sizeof(glm::uvec3));
        // Only a scene with cut-outs pays for a filter call per candidate hit.
        if (std::any_of(scene.materials.begin(), scene.materials.end(), [](const Material& m) { return m.cutsOut(); })) {
            rtcSetGeometryUserData(geometry, const_cast<Scene*>(&scene));
            rtcSetGeometryIntersectFilterFunction(geometry, rejectCutOutHits);
            rtcSetGeometryOccludedFilterFunction(geometry, rejectCutOutHits);
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(rtc_scene_, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(rtc_scene_);
    throwOnEmbreeError(device_, "building the scene");
}

void initEmbreeRay(const Ray& ray, RTCRay& r) {
    r.org_x = ray.origin.x;
    r.org_y = ray.origin.y;
    r.org_z = ray.origin.z;
    r.dir_x = ray.direction.x;
    r.dir_y = ray.direction.y;
    r.dir_z = ray.direction.z;
    r.tnear = rayTNear(ray);
    r.tfar = ray.t_max;
    r.time = 0.0f;
    r.mask = 0xffffffffu;
    r.id = 0;
    r.flags = 0;
}

Tracer::~Tracer() {
    if (rtc_scene_) rtcReleaseScene(rtc_scene_);
    if (device_) rtcReleaseDevice(device_);
}

bool Tracer::intersect(const Ray& ray, RayHit& hit) const {
    if (!embreeTraces(ray)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayhit;
    initRayHit(ray, rayhit);
    rtcIntersect1(rtc_scene_, &context, &rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit = RayHit{rayhit.hit.primID, rayhit.ray.tfar, rayhit.hit.u, rayhit.hit.v};
    recomputeHit(scene_, ray, hit);
    return true;
}

bool Tracer::occluded(const Ray& ray) const {
    if (!embreeTraces(ray)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayhit;
    initRayHit(ray, rayhit);
    rtcOccluded1(rtc_scene_, &context, &rayhit.ray);
    // Embree marks an occluded ray by setting tfar to -inf.
    return rayhit.ray.tfar < 0.0f;
}

namespace {
/// Embree's packets: 16 lanes (fillPacket parks those beyond the rays' count).
constexpr int kPacketWidth = 16;

/// Sets the valid mask and the rays of one packet from rays[start, start + 16). A lane past
/// `count` (the last packet), or holding a ray Embree does not trace (embreeTraces), is parked:
/// masked off, and given an empty segment (tnear > tfar) too, since on a CPU without 16-wide
/// kernels Embree traces a 16-ray packet as a stream, which ignores the mask and skips only the
/// lanes whose segment is empty. Returns the lanes filled from `rays`.
template <typename RayN>
int fillPacket(const Ray* rays, size_t start, size_t count, int (&valid)[kPacketWidth], RayN& packet) {
    const int n = int(std::min<size_t>(kPacketWidth, count - start));
    static const Ray kParked{glm::vec3(0.0f), glm::vec3(0.0f, 0.0f, 1.0f), 0.0f};
    for (int i = 0; i < kPacketWidth; ++i) {
        const bool traced = i < n && embreeTraces(rays[start + size_t(i)]);
        valid[i] = traced ? -1 : 0;
        initEmbreeLane(traced ? rays[start + size_t(i)] : kParked, packet, i);
        if (!traced) packet.tnear[i] = 1.0f;  // beyond tfar 0: an empty segment
    }
    return n;
}

}  // namespace

void Tracer::intersectMany(const Ray* rays, size_t count, RayHit* hits, uint8_t* found) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    alignas(64) int valid[kPacketWidth];
    alignas(64) RTCRayHit16 packet;
    for (size_t start = 0; start < count; start += kPacketWidth) {
        const int n = fillPacket(rays, start, count, valid, packet.ray);
        for (int i = 0; i < kPacketWidth; ++i) {
            packet.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
            packet.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
        }
        rtcIntersect16(valid, rtc_scene_, &context, &packet);
        for (int i = 0; i < n; ++i) {
            found[start + i] = packet.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID;
            hits[start + i] = RayHit{packet.hit.primID[i], packet.ray.tfar[i], packet.hit.u[i], packet.hit.v[i]};
            if (found[start + i]) recomputeHit(scene_, rays[start + i], hits[start + i]);
        }
    }
}

void Tracer::occludedMany(const Ray* rays, size_t count, uint8_t* blocked) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    alignas(64) int valid[kPacketWidth];
    alignas(64) RTCRay16 packet;
    for (size_t start = 0; start < count; start += kPacketWidth) {
        const int n = fillPacket(rays, start, count, valid, packet);
        rtcOccluded16(valid, rtc_scene_, &context, &packet);
        for (int i = 0; i < n; ++i) blocked[start + i] = valid[i] != 0 && packet.tfar[i] < 0.0f;  // Embree's mark
    }
}

float rayOffsetFor(glm::vec3 p0, glm::vec3 p1, glm::vec3 p2, glm::vec3 normal) {
    constexpr float kRounding = 0x1p-24f;
    const glm::vec3 largest = glm::max(glm::max(glm::abs(p0), glm::abs(p1)), glm::abs(p2));
    const float bound = kRayOffsetRoundings * kRounding * glm::dot(glm::abs(normal), largest);
    // Written so that a NaN bound (a NaN normal) gives the least offset.
    return std::max(kRounding * std::max({largest.x, largest.y, largest.z}), bound);
}

namespace {

/// The next float from `x` towards +infinity (`up`) or -infinity; infinities and NaN stay.
float nextFloat(float x, bool up) {
    if (!std::isfinite(x)) return x;
    if (x == 0.0f) return up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
    return intAsFloat(floatAsInt(x) + ((x > 0.0f) == up ? 1 : -1));
}

}  // namespace

glm::vec3 offsetRayOrigin(glm::vec3 position, glm::vec3 normal, float offset) {
    glm::vec3 result = position + offset * normal;
    for (int axis = 0; axis < 3; ++axis) {
        if (normal[axis] != 0.0f) result[axis] = nextFloat(result[axis], normal[axis] > 0.0f);
    }
    return result;
}

bool shadowRayTo(glm::vec3 position, glm::vec3 normal, float offset, glm::vec3 wi, float distance, Ray& out) {
    out = Ray{offsetRayOrigin(position, normal, offset), wi, distance};
    if (!std::isfinite(distance)) return true;
    // Aim from the offset origin at the light point itself. Going `distance` along wi from the
    // offset origin would end up to one offset beyond the light and hit the emitter, wherever the
    // offset is not small against the distance: near the light, and far from the origin.
    const glm::vec3 to_light = position + wi * distance - out.origin;
    const float length = glm::length(to_light);
    if (!(length > 0.0f)) return false;
    out.direction = to_light / length;
    out.t_max = length * (1.0f - 1e-4f);
    return true;
}

bool visibleOneWay(const Tracer& tracer, glm::vec3 a, glm::vec3 b) {
    const glm::vec3 d = b - a;
    const float length = glm::length(d);
    if (length <= 0.0f) return true;
    return !tracer.occluded(Ray{a, d / length, length});
}

bool leavesScene(const Tracer& tracer, glm::vec3 from, glm::vec3 d) {
    const Scene& scene = tracer.scene();
    const float beyond_bounds = 2.0f * glm::length(scene.bounds_max - scene.bounds_min) + 1.0f;
    return !tracer.occluded(Ray{from, d}) && visibleOneWay(tracer, from + beyond_bounds * d, from);
}

bool visibleBothWays(const Tracer& tracer, glm::vec3 a, glm::vec3 b) {
    return visibleOneWay(tracer, a, b) && visibleOneWay(tracer, b, a);
}

std::vector<float> hitDistancesAround(const Tracer& tracer, glm::vec3 from, uint32_t directions) {
    std::vector<float> distances;
    for (uint32_t i = 0; i < directions; ++i) {
        RayHit hit;
        if (tracer.intersect(Ray{from, sphericalFibonacciDirection(i, directions)}, hit)) distances.push_back(hit.t);
    }
    return distances;
}

float largestRayOffset(float far_coordinate) {
    const glm::vec3 corner(far_coordinate);
    const glm::vec3 diagonal = glm::normalize(glm::vec3(1.0f));
    return glm::length(offsetRayOrigin(corner, diagonal, rayOffsetFor(corner, corner, corner, diagonal)) - corner);
}

}  // namespace sharcbake
