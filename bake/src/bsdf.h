// SPDX-License-Identifier: Apache-2.0
/// @file bsdf.h
/// @brief The glTF 2.0 metallic-roughness BRDF with KHR_materials_specular: a Lambertian base
/// under a GGX (Trowbridge-Reitz) specular layer with height-correlated Smith masking and
/// Schlick Fresnel, mixed with a GGX metal by `metallic`, as the glTF specification's
/// appendix B and KHR_materials_specular define it. Reflection only.
#pragma once

#include "sampling.h"
#include "surface.h"

#include <glm/glm.hpp>

namespace sharcbake {

/// GGX helpers on a local frame with the normal along +Z. alpha = roughness^2.
float ggxD(float cos_theta_h, float alpha);
float ggxLambda(glm::vec3 w, float alpha);
/// Samples a microfacet normal from the distribution of normals visible from `wo` (Heitz 2018).
glm::vec3 sampleGgxVisibleNormal(glm::vec3 wo, float alpha, glm::vec2 u);

class GltfBsdf {
public:
    /// @param min_roughness roughness is raised to at least this value (SHaRC's update pass
    ///        clamps it to 0.4 so that sharp highlights are not cached); 0 for reference renders.
    GltfBsdf(const ShadingMaterial& material, const SurfaceHit& hit, float min_roughness = 0.0f);

    struct Evaluation {
        glm::vec3 f_cos{0.0f};  ///< BRDF times |cos(theta_i)|
        float pdf = 0.0f;        ///< solid-angle pdf with which sample() returns wi
    };
    /// Both directions point away from the surface. wi below the geometric surface gives 0.
    Evaluation evaluate(glm::vec3 wo, glm::vec3 wi) const;

    struct Sample {
        glm::vec3 wi{0.0f};
        glm::vec3 weight{0.0f};  ///< f * |cos| / pdf
        float pdf = 0.0f;
        bool valid = false;
        bool specular = false;  ///< chosen from the GGX lobe (for SHaRC's cone-spread test)
    };
    /// Picks the diffuse or specular lobe with u_lobe, then a direction with u.
    Sample sample(glm::vec3 wo, float u_lobe, glm::vec2 u) const;

    float roughness() const { return roughness_; }
    /// True when the BRDF has no specular part (pure Lambert): its sampling is exact.
    bool isDiffuseOnly() const { return !has_specular_; }

private:
    float specularProbability(float cos_o) const;

    Frame frame_;
    glm::vec3 geometric_normal_;
    glm::vec3 diffuse_color_;     ///< (1 - metallic) * base colour
    glm::vec3 f0_;                ///< mixed dielectric/metal reflectance at normal incidence
    glm::vec3 f90_;
    glm::vec3 dielectric_f0_;     ///< for the diffuse layer's energy split
    float dielectric_f90_;
    float roughness_;
    float alpha_;
    bool has_specular_;           ///< false for pure Lambert (metallic 0, specular weight 0)
};

}  // namespace sharcbake
