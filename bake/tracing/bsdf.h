// SPDX-License-Identifier: Apache-2.0
/// @file bsdf.h
/// @brief The glTF 2.0 metallic-roughness BRDF with KHR_materials_specular: a Lambertian base
/// under a GGX (Trowbridge-Reitz) specular layer with height-correlated Smith masking and
/// Schlick Fresnel, mixed with a GGX metal by `metallic`, as the glTF specification's
/// appendix B and KHR_materials_specular define it. Reflection only.
///
/// Energy conservation, as production renderers do it (the glTF formulas lose energy):
/// - single-scattering GGX loses the light that bounces between microfacets more than once (up to
///   about 60% for a rough metal at grazing angles). Each specular lobe gets Kulla and Conty's
///   multiple-scattering lobe, F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), E the
///   directional albedo of a white single-scattering lobe and E_avg its cosine-weighted mean: a
///   white lobe then reflects exactly 1, and the lobe is sampled with the diffuse one (cosine),
///   so no sample weight grows with the missing energy;
/// - the diffuse base receives what the dielectric layer does not reflect: it is scaled by
///   1 - E_spec(mu_o), the layer's own directional albedo (albedo scaling), instead of glTF's
///   1 - F(v.h), so a white base under any layer reflects exactly 1.
/// E and its Schlick split (E_spec = F0 E + (F90 - F0) E5) come from a table over (mu, roughness)
/// computed once from this file's own D and G (ggxAlbedoTable).
///
/// KHR_materials_clearcoat adds a GGX layer on top (F0 0.04, F90 1, its own roughness, the
/// shading normal), weighted by the clearcoat factor. Its single-scattering albedo towards the
/// viewer, c = clearcoat E_spec,coat(mu_o), is what it reflects; everything beneath is scaled by
/// 1 - c, the same albedo scaling as the base's, so a white furnace still reflects exactly 1.
#pragma once

#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <glm/glm.hpp>

#include <limits>

namespace sharcbake {

/// GGX helpers on a local frame with the normal along +Z. alpha = roughness^2.
/// The distribution of normals at half-vector `h` (unit, local frame). Evaluated from h's
/// tangential part, not 1 - cos^2: near a mirror (alpha^2 below float's epsilon) the latter cancels.
float ggxD(glm::vec3 h, float alpha);
float ggxLambda(glm::vec3 w, float alpha);
/// Samples a microfacet normal from the distribution of normals visible from `wo` (Heitz 2018).
glm::vec3 sampleGgxVisibleNormal(glm::vec3 wo, float alpha, glm::vec2 u);

/// The directional albedo of a white single-scattering GGX lobe, E(mu_o, roughness), and of the
/// same lobe weighted by Schlick's (1 - cos(theta_oh))^5, E5: tabulated once (32 cos(theta_o) x 64
/// roughness steps, 1024 stratified visible-normal samples each, deterministic), bilinear between.
struct GgxAlbedo {
    float e = 1.0f;
    float e5 = 0.0f;
};
GgxAlbedo ggxAlbedo(float cos_theta_o, float roughness);
/// E_avg = 2 int E(mu) mu dmu for a roughness, from the same table.
float ggxAverageAlbedo(float roughness);
/// Builds the albedo table now (on every core, about 0.1 s of one), so that a bake or render
/// pays for it in its setup instead of stalling its first shading call. Later calls return at once.
void prepareBsdfTables();

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
        bool specular = false;   ///< chosen from a GGX lobe (for SHaRC's cone-spread test)
        float roughness = 1.0f;  ///< that lobe's roughness (the clearcoat's or the base's); 1 for diffuse
    };
    /// Picks the diffuse or specular lobe with u_lobe, then a direction with u.
    Sample sample(glm::vec3 wo, float u_lobe, glm::vec2 u) const;

    float roughness() const { return roughness_; }
    /// True when the BRDF has no specular part (pure Lambert): its sampling is exact.
    bool isDiffuseOnly() const { return !has_specular_ && !has_coat_; }

    /// The BRDF's directional albedo towards `wo` (what a white furnace would see reflected), per
    /// channel; at most 1. Russian roulette and lobe selection use it.
    glm::vec3 albedo(glm::vec3 wo) const;

private:
    /// What evaluate() and sample() need for one outgoing direction.
    struct Lobes {
        glm::vec3 diffuse{0.0f};              ///< (1 - metallic) base colour x (1 - layer albedo)
        /// F_ms (1 - E(mu_o)) / (1 - E_avg), mixed by metallic: times (1 - E(mu_i)) / pi, the
        /// multiple-scattering lobe.
        glm::vec3 multiple_scattering{0.0f};
        glm::vec3 albedo{0.0f};               ///< the whole BRDF's, towards this direction
        float p_specular = 0.0f;              ///< single-scattering lobe vs cosine, by albedo
        float coat = 0.0f;                    ///< the clearcoat's albedo c towards this direction
        float under_coat = 1.0f;              ///< 1 - c: what reaches the layers beneath
        float p_coat = 0.0f;                  ///< the clearcoat lobe vs the rest, by albedo
    };
    /// The lobes towards cos_o, computed once per outgoing direction: a path vertex asks for
    /// the same wo three times (light sampling, Russian roulette, the next direction).
    const Lobes& lobes(float cos_o) const;
    Lobes computeLobes(float cos_o) const;
    Lobes computeBaseLobes(float cos_o) const;  ///< everything beneath the clearcoat

    Frame frame_;
    glm::vec3 geometric_normal_;
    glm::vec3 diffuse_color_;     ///< (1 - metallic) * base colour
    glm::vec3 metal_f0_;          ///< the metal's reflectance at normal incidence (base colour)
    glm::vec3 dielectric_f0_;     ///< the dielectric layer's, with KHR_materials_specular
    float dielectric_f90_;
    float metallic_;
    float e_avg_;                 ///< ggxAverageAlbedo(roughness)
    float roughness_;
    float alpha_;
    bool has_specular_;           ///< false for pure Lambert (metallic 0, specular weight 0)
    float coat_ = 0.0f;           ///< clearcoat factor (0: no coat)
    float coat_roughness_ = 0.0f;
    float coat_alpha_ = 1.0f;
    bool has_coat_ = false;
    // The last lobes() answer (NaN: none yet). A GltfBsdf belongs to one path vertex, on one
    // thread, so the memo needs no synchronisation.
    mutable float lobes_cos_o_ = std::numeric_limits<float>::quiet_NaN();
    mutable Lobes lobes_;
};

}  // namespace sharcbake
