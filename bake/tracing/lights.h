// SPDX-License-Identifier: Apache-2.0
/// @file lights.h
/// @brief Next-event estimation: choosing a light in proportion to its estimated power and a
/// point or direction on it, plus the pdfs that multiple importance sampling needs when a
/// BSDF-sampled ray finds the same light.
///
/// Lights are emissive triangles (area lights), KHR_lights_punctual lights (point, spot,
/// directional) and the sky (uniform, or an equirectangular map sampled by luminance).
#pragma once

#include "tracing/distribution.h"
#include "sharcbake/scene.h"
#include "tracing/surface.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace sharcbake {

struct LightSample {
    glm::vec3 wi{0.0f};          ///< unit direction from the shading point towards the light
    float distance = 0.0f;       ///< to the light point; infinity for the sky and directional lights
    glm::vec3 radiance{0.0f};    ///< arriving radiance (delta lights: irradiance-like, see pdf)
    float pdf = 0.0f;            ///< selection probability x solid-angle pdf; delta: selection only
    bool is_delta = false;       ///< punctual: no MIS, the BSDF can never hit it
};

class LightSampler {
public:
    explicit LightSampler(const Scene& scene);

    bool hasLights() const { return !selection_.empty(); }
    bool hasEmissiveTriangles() const { return emissive_triangle_count_ > 0; }
    bool hasSky() const { return has_sky_; }
    /// Scene::lights indices of punctual lights that give no light (a zero intensity, a black
    /// colour or a spot cone of zero angle) and are never sampled: a "no lights" warning names them.
    const std::vector<uint32_t>& darkLights() const { return dark_lights_; }

    /// Samples one light for the shading point. Returns false if there is nothing to sample or
    /// the chosen sample carries no energy. Occlusion is not tested here.
    bool sample(const SurfaceHit& at, float u_select, glm::vec2 u, LightSample& out) const;

    /// The pdf that sample() returns for the emitter point `emitter` (a surface hit found by a
    /// ray from `from`), for MIS. 0 for non-emissive triangles.
    float pdfEmitter(glm::vec3 from, const SurfaceHit& emitter) const;

    /// The pdf that sample() returns for sky direction `direction` from a point whose shading
    /// normal was `shading_normal`, for MIS.
    float pdfSky(glm::vec3 shading_normal, glm::vec3 direction) const;

    /// Sky radiance arriving from `direction` (pointing away from the scene).
    glm::vec3 skyRadiance(glm::vec3 direction) const;

private:
    enum class Kind : uint8_t { Triangle, Punctual, Sky };
    struct Entry {
        Kind kind;
        uint32_t index;  ///< triangle index or light index
    };

    /// The constructor's parts: each adds its lights to entries_ and their powers to `powers`
    /// (float32 products, in double only where those overflow: selectionPower).
    void addAreaLights(std::vector<double>& powers);
    void addPunctualLights(float disk_area, std::vector<double>& powers);
    void addSky(float disk_area, std::vector<double>& powers);

    bool sampleTriangle(uint32_t triangle, float pmf, const SurfaceHit& at, glm::vec2 u,
                        LightSample& out) const;
    bool samplePunctual(const PunctualLight& light, float pmf, const SurfaceHit& at,
                        LightSample& out) const;
    bool sampleSky(float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const;
    float skyDirectionPdf(glm::vec3 shading_normal, glm::vec3 direction) const;

    const Scene& scene_;
    std::vector<Entry> entries_;
    Distribution1D selection_;
    std::vector<float> triangle_pmf_;   ///< per scene triangle: its selection probability (0 = not a light)
    std::vector<float> triangle_area_;  ///< per scene triangle, only filled for emitters
    uint32_t emissive_triangle_count_ = 0;
    std::vector<uint32_t> dark_lights_;
    bool has_sky_ = false;
    float sky_pmf_ = 0.0f;
    Distribution2D sky_map_distribution_;
};

/// Equirectangular mapping shared with the loader (see scene_loader.h): direction <-> (u, v).
glm::vec2 directionToEquirect(glm::vec3 direction);
glm::vec3 equirectToDirection(glm::vec2 uv);

}  // namespace sharcbake
