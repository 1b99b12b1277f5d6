// SPDX-License-Identifier: Apache-2.0
/// @file scene_reflectance.h
/// @brief How long light stays in a scene: the share of the light reaching its surfaces that they
/// reflect back onto the scene, and so about how many bounces a path makes before it leaves or is
/// absorbed. Near 1 (a closed room of white walls) a reference render's paths run to their bounce
/// cap and a bake's cache converges slowly; at 1 the radiance has no finite value.
#pragma once

#include "tracing/tracer.h"

#include <cstdint>
#include <string>

namespace sharcbake {

class LightSampler;

struct SceneReflectance {
    /// Mean over surface points, spread by area, of the surface's albedo (light arriving along its
    /// normal) times the chance that a cosine-distributed reflected ray hits the scene again, of
    /// the side where that product is larger (inside a closed room, the inner one) among the sides
    /// light reaches, directly or after bounces; points no light reaches on either side (the
    /// inside of a closed solid under a sky) take no part.
    double reflectance = 0.0;
    uint32_t points = 0;  ///< points sampled (0: an empty scene)

    /// About how many bounces light makes before it leaves the scene or is absorbed: 1 / (1 - R);
    /// infinite at R >= 1.
    double bounces() const;
    /// True when light makes so many bounces (over 10 000) that the radiance has, for a bake or
    /// a render, no finite value: a closed room of albedo-1 walls.
    bool unbounded() const { return reflectance > 1.0 - 1e-4; }
    /// "light stays in this scene for about 250 bounces (its surfaces send 99.6% of the light
    /// reaching them back onto it)", or the unbounded case's words: what the warnings begin with.
    std::string describe() const;
};

/// Above this reflectance (light makes fifty bounces or more) renders and bakes say so.
inline constexpr double kStiffReflectance = 0.98;

/// Estimates SceneReflectance from `points` area-spread surface points, kDirectionsPerSide rays
/// from each side of each, and a few light samples from `lights` to tell which sides light
/// reaches (without `lights`, every point takes its larger side). Deterministic: the same scene,
/// count and seed give the same value on any thread count. Costs about a millisecond per
/// thousand points.
SceneReflectance estimateSceneReflectance(const Tracer& tracer, const LightSampler* lights, uint32_t points = 2048,
                                          uint32_t seed = 0);

}  // namespace sharcbake
