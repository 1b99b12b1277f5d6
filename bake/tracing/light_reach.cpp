// SPDX-License-Identifier: Apache-2.0
#include "tracing/light_reach.h"

#include "support/median.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/sampling.h"
#include "tracing/tracer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

namespace sharcbake {
namespace {

/// Points on emitters: this many spread by area, as many again one per evenly spaced triangle.
constexpr uint32_t kEmitterPoints = 64;

/// Rays of the views whose hits stand for what the views see.
constexpr uint32_t kRaysTested = 1024;

/// A surface point the views see, just off the side they see.
struct Receiver {
    glm::vec3 at;
    glm::vec3 normal;  ///< of the side the view sees
};

/// What the views' rays meet (up to kRaysTested of them that meet something, taken across all
/// the rays), and one cosine-distributed bounce on from each: the surfaces the views see and
/// those they see lit. `escaped` counts the bounces that leave the scene.
std::vector<Receiver> receiversOf(const Tracer& tracer, const std::vector<Ray>& rays, uint32_t& escaped) {
    const Scene& scene = tracer.scene();
    std::vector<Receiver> receivers;
    escaped = 0;
    // An odd stride visits every ray of a power-of-two count, spread over the views, not the first
    // few views' rays; other counts go in order.
    const size_t stride = rays.size() % 2 == 0 && (rays.size() & (rays.size() - 1)) == 0 ? 2654435761u : 1u;
    uint32_t hits = 0;
    for (size_t k = 0; k < rays.size() && hits < kRaysTested; ++k) {
        const Ray& ray = rays[(k * stride) % rays.size()];
        RayHit hit;
        if (!tracer.intersect(ray, hit)) continue;
        ++hits;
        const SurfaceHit surface = makeSurfaceHit(scene, hit, ray.direction);
        const glm::vec3 normal = surface.geometric_normal;
        const glm::vec3 at = offsetRayOrigin(surface.position, normal, surface.ray_offset);
        receivers.push_back({at, normal});
        const glm::vec3 local = sampleCosineHemisphere({hashToUnitFloat(hits, 2, 0), hashToUnitFloat(hits, 2, 1)});
        const glm::vec3 bounce = Frame(normal).toWorld(local);
        RayHit next;
        if (!tracer.intersect(Ray{at, bounce}, next)) {
            escaped += leavesScene(tracer, at, bounce);
            continue;
        }
        const SurfaceHit lit = makeSurfaceHit(scene, next, bounce);
        receivers.push_back(
            {offsetRayOrigin(lit.position, lit.geometric_normal, lit.ray_offset), lit.geometric_normal});
    }
    return receivers;
}

/// What stands between one punctual light and the receivers.
struct LightPath {
    uint32_t facing = 0;                    ///< receivers whose seen side faces the light, within its cone and range
    uint32_t reached = 0;                   ///< of those, the light reaches unblocked
    uint32_t outside_cone = 0;              ///< facing it, but outside a spot light's cone
    uint32_t out_of_range = 0;              ///< facing it, but beyond its range
    std::map<uint32_t, uint32_t> blockers;  ///< the first blocking surface's material: rays
    std::vector<float> blocker_distances;   ///< from the light, for point and spot lights
    std::vector<float> light_distances;     ///< from the light to the blocked receivers
};

LightPath tracePathsToLight(const Tracer& tracer, const PunctualLight& light, const std::vector<Receiver>& receivers) {
    const Scene& scene = tracer.scene();
    LightPath path;
    for (const Receiver& r : receivers) {
        Ray ray{r.at, -light.direction};
        float distance = INFINITY;
        if (light.type != LightType::Directional) {
            const glm::vec3 to = light.position - r.at;
            distance = glm::length(to);
            if (!(distance > 0.0f)) continue;
            ray.direction = to / distance;
            ray.t_max = distance;
        }
        if (!(glm::dot(r.normal, ray.direction) > 0.0f)) continue;
        if (light.type == LightType::Spot &&
            !(glm::dot(light.direction, -ray.direction) > std::cos(light.outer_cone_angle))) {
            ++path.outside_cone;
            continue;
        }
        if (light.range > 0.0f && !(distance < light.range)) {
            ++path.out_of_range;
            continue;
        }
        ++path.facing;
        RayHit hit;
        if (!tracer.intersect(ray, hit)) {
            ++path.reached;
            continue;
        }
        ++path.blockers[scene.triangle_materials[hit.triangle]];
        if (light.type != LightType::Directional) {
            path.blocker_distances.push_back(distance - hit.t);
            path.light_distances.push_back(distance);
        }
    }
    return path;
}

/// "every ray towards it from them is blocked, 97% first by material 'sky'": the material most
/// rays meet first.
std::string blockedText(const Scene& scene, const LightPath& path) {
    uint32_t material = 0, most = 0;
    for (const auto& [m, rays] : path.blockers) {
        if (rays > most) {
            material = m;
            most = rays;
        }
    }
    char text[200];
    std::snprintf(text, sizeof text,
                  "every ray towards it from the %u of them facing it is blocked, %.0f%% first by %s", path.facing,
                  100.0 * double(most) / double(path.facing), materialLabel(scene, material).c_str());
    return text;
}

std::string punctualLightText(const Tracer& tracer, size_t index, const std::vector<Receiver>& receivers) {
    const Scene& scene = tracer.scene();
    const PunctualLight& light = scene.lights[index];
    const LightPath path = tracePathsToLight(tracer, light, receivers);
    if (path.reached > 0) return {};
    const std::string name = lightLabel(scene, index);
    if (path.facing == 0) {
        if (path.outside_cone > 0)
            return name + ": those facing it all lie outside its cone (it points away from them)";
        if (path.out_of_range > 0) {
            char text[120];
            std::snprintf(text, sizeof text, ": those facing it all lie beyond its range (%g)", double(light.range));
            return name + text;
        }
        if (light.type == LightType::Directional) {
            char text[160];
            std::snprintf(text, sizeof text,
                          ": every one of them faces away from it (it shines towards (%.2g, %.2g, %.2g))",
                          double(light.direction.x), double(light.direction.y), double(light.direction.z));
            return name + text;
        }
        return name +
               ": every one of them faces away from it (it is behind them, as a lamp inside a closed room is "
               "for a camera outside)";
    }
    std::string text = name + ": " + blockedText(scene, path);
    if (light.type == LightType::Directional) {
        return text +
               " (a closed mesh around the scene, such as a sky dome without an emissive or unlit material, "
               "keeps the sun out: make it emissive or unlit, or leave it out of the export and give --sky)";
    }
    // Blocked near the light: it stands inside what blocks it.
    const float blocker = median(std::vector<float>(path.blocker_distances));
    const float receiver = median(std::vector<float>(path.light_distances));
    char at[160];
    std::snprintf(at, sizeof at, ", a median %.3g from the light (the surfaces are a median %.3g from it)",
                  double(blocker), double(receiver));
    text += at;
    if (blocker < 0.1f * receiver) {
        text +=
            " (the light stands inside a closed bulb, shade or fixture: give its glass "
            "KHR_materials_transmission, make it emissive instead, or move the light out of it)";
    }
    return text;
}

}  // namespace

bool givesLight(const PunctualLight& light) {
    return maxComponent(light.intensity) > 0.0f && (light.type != LightType::Spot || light.outer_cone_angle > 0.0f);
}

bool seesLitEmitter(const Tracer& tracer, const std::vector<glm::vec3>& points, const std::vector<LitPoint>& emitters) {
    for (const auto& [e, ray_offset] : emitters) {
        for (const glm::vec3& at : points) {
            const float facing = glm::dot(at - e.position, e.face_normal);
            if (facing == 0.0f || (facing < 0.0f && !e.double_sided)) continue;
            const glm::vec3 lit_side = facing > 0.0f ? e.face_normal : -e.face_normal;
            if (visibleBothWays(tracer, at, offsetRayOrigin(e.position, lit_side, ray_offset))) return true;
        }
    }
    return false;
}

std::vector<LitPoint> sampleEmitterPoints(const Scene& scene) {
    std::vector<uint32_t> emitters;
    std::vector<double> cumulative_area;
    double area = 0.0;
    for (uint32_t t = 0; t < uint32_t(scene.triangles.size()); ++t) {
        if (!scene.materials[scene.triangle_materials[t]].isEmissive()) continue;
        const glm::uvec3 tri = scene.triangles[t];
        area += 0.5 * double(glm::length(glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                                    scene.positions[tri.z] - scene.positions[tri.x])));
        emitters.push_back(t);
        cumulative_area.push_back(area);
    }
    std::vector<LitPoint> points;
    if (emitters.empty()) return points;
    for (uint32_t i = 0; i < 2 * kEmitterPoints; ++i) {
        const double u = (double(i % kEmitterPoints) + 0.5) / double(kEmitterPoints);
        const size_t k = i < kEmitterPoints
                             ? size_t(std::lower_bound(cumulative_area.begin(), cumulative_area.end(), u * area) -
                                      cumulative_area.begin())
                             : size_t(u * double(emitters.size()));
        const glm::vec2 b = sampleUniformTriangle({hashToUnitFloat(i, 0, 1), hashToUnitFloat(i, 0, 2)});
        const uint32_t t = emitters[std::min(k, emitters.size() - 1)];
        const EmitterPoint e = makeEmitterPoint(scene, t, b.x, b.y);
        if (!(maxComponent(e.emission) > 0.0f)) continue;
        const glm::uvec3 tri = scene.triangles[t];
        points.push_back(LitPoint{e, rayOffsetFor(scene.positions[tri.x], scene.positions[tri.y],
                                                  scene.positions[tri.z], e.face_normal)});
    }
    return points;
}

LightProbe probeLight(const Tracer& tracer, const LightSampler& lights, const std::vector<Ray>& rays, uint32_t seed) {
    LightProbe probe;
    if (!lights.hasLights()) return probe;
    const PathTracer paths(tracer, lights, PathTracerSettings{});
    TraceCounters counters;
    for (size_t i = 0; i < rays.size(); ++i) {
        ++probe.paths;
        probe.surface_hits += tracer.occluded(rays[i]);
        PixelSampler sampler(seed, uint32_t(i), 0);
        sampler.startDimension(PathTracer::kFirstBounceDimension);
        if (maxComponent(paths.radiance(rays[i], sampler, counters)) > 0.0f) {
            probe.met_light = true;
            break;
        }
    }
    return probe;
}

std::string whyNoLightArrives(const Tracer& tracer, const std::vector<Ray>& rays) {
    const Scene& scene = tracer.scene();
    uint32_t escaped = 0;
    const std::vector<Receiver> receivers = receiversOf(tracer, rays, escaped);
    if (receivers.empty()) return "the camera's rays meet no surface";
    char counted[120];
    std::snprintf(counted, sizeof counted, "of the %zu surface points the views see (and see lit by one bounce), ",
                  receivers.size());
    std::vector<std::string> causes;
    bool reached = false;
    for (size_t i = 0; i < scene.lights.size(); ++i) {
        if (!givesLight(scene.lights[i])) continue;
        std::string text = punctualLightText(tracer, i, receivers);
        if (text.empty()) {
            reached = true;
        } else {
            causes.push_back(std::move(text));
        }
    }
    const std::vector<LitPoint> emitters = sampleEmitterPoints(scene);
    if (!emitters.empty()) {
        std::vector<glm::vec3> points;
        for (const Receiver& r : receivers) points.push_back(r.at);
        if (seesLitEmitter(tracer, points, emitters)) {
            reached = true;
        } else {
            causes.push_back("none of them sees an emissive surface");
        }
    }
    if (!scene.sky.isBlack()) {
        if (escaped > 0) {
            reached = true;
        } else {
            causes.push_back("no ray from them leaves the scene, so the sky lights only its outside");
        }
    }
    std::string text = counted;
    if (reached) {
        return text +
               "some are lit directly, so the paths that found no light were few, or the materials there "
               "reflect none of it (a black base colour)";
    }
    for (size_t i = 0; i < causes.size(); ++i) text += (i == 0 ? "" : "; ") + causes[i];
    return text;
}

}  // namespace sharcbake
