// SPDX-License-Identifier: Apache-2.0
/// @file light_reach.h
/// @brief Whether light reaches what cameras see, and when it does not, what stops it.
///
/// A scene can have lights and still bake a black cache: a sun inside a sky dome modelled as a
/// plain sphere, a lamp inside a closed bulb or shade, a spot light aimed away from everything,
/// windows of opaque glass. The bake then says nothing is wrong (nothing numerical is), and the
/// artist is left with a cache of zeros. These helpers find such scenes before the bake (a few
/// thousand paths along the roaming camera's rays) and name, light by light, what stops the
/// light on its way to what the camera sees.
#pragma once

#include "sharcbake/scene.h"
#include "tracing/surface.h"
#include "tracing/tracer.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

class LightSampler;

/// True when a punctual light gives any light at all (the light sampler skips the others).
bool givesLight(const PunctualLight& light);

/// A point on an emissive triangle and how far rays leaving it start off it (rayOffsetFor; light
/// sampling's EmitterPoint does not carry it, since its rays end on the emitter).
struct LitPoint {
    EmitterPoint point;
    float ray_offset = 0.0f;
};

/// Points on the scene's emissive triangles where their emission is not black: 64 spread by area
/// and 64 one on each of evenly spaced emissive triangles, so a small bulb beside a large lit
/// panel still gets some. Deterministic.
std::vector<LitPoint> sampleEmitterPoints(const Scene& scene);

/// Whether any of `points` sees the lit side of any of the `emitters` (its front, or either side
/// of a double-sided one), unblocked both ways (visibleBothWays).
bool seesLitEmitter(const Tracer& tracer, const std::vector<glm::vec3>& points, const std::vector<LitPoint>& emitters);

/// What paths of the reference path tracer along `rays` (one path each) found: whether any brings
/// back light, as the bake's update paths along such rays will, and how many of the rays meet a
/// surface. The probe stops at the first path that meets light.
struct LightProbe {
    uint32_t paths = 0;         ///< traced
    uint32_t surface_hits = 0;  ///< of those, whose ray meets a surface
    bool met_light = false;
};
LightProbe probeLight(const Tracer& tracer, const LightSampler& lights, const std::vector<Ray>& rays, uint32_t seed);

/// Rays that must meet a surface before a probe that found no light says the cache will be black:
/// a camera that sees almost nothing (a small model far off in the void) deposits little, and a
/// few thousand of its rays may miss what it does.
inline constexpr uint32_t kProbeHitsForAVerdict = 256;

/// Why no light arrives at what the views whose `rays` these are see (what up to 1024 of them
/// meet, spread over all of them, and one diffuse bounce on from each): for each punctual light, whether those surfaces
/// face away from it, lie outside its cone or range, or every ray towards it is blocked, and by
/// which material first (with the usual cause: a closed sky dome around a sun, a closed bulb
/// around a lamp); emissive surfaces none of them sees; a sky no ray from them reaches; or, where
/// light does reach them, that their materials reflect none of it. One sentence per cause,
/// joined with "; ". Deterministic.
std::string whyNoLightArrives(const Tracer& tracer, const std::vector<Ray>& rays);

}  // namespace sharcbake
