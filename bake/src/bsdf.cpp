// SPDX-License-Identifier: Apache-2.0
#include "bsdf.h"

#include <algorithm>
#include <cmath>

namespace sharcbake {
namespace {

// Below this alpha the lobe is a near-mirror; clamping keeps D finite in float.
constexpr float kMinAlpha = 1e-4f;

glm::vec3 schlick(glm::vec3 f0, glm::vec3 f90, float cos_theta) {
    const float m = glm::clamp(1.0f - cos_theta, 0.0f, 1.0f);
    const float m2 = m * m;
    return f0 + (f90 - f0) * (m2 * m2 * m);
}

}  // namespace

float ggxD(float cos_theta_h, float alpha) {
    if (cos_theta_h <= 0.0f) return 0.0f;
    const float a2 = alpha * alpha;
    const float c2 = cos_theta_h * cos_theta_h;
    const float d = c2 * (a2 - 1.0f) + 1.0f;
    return a2 / (kPi * d * d);
}

float ggxLambda(glm::vec3 w, float alpha) {
    const float c2 = w.z * w.z;
    if (c2 <= 0.0f) return 0.0f;
    const float tan2 = std::max(0.0f, 1.0f - c2) / c2;
    return 0.5f * (std::sqrt(1.0f + alpha * alpha * tan2) - 1.0f);
}

glm::vec3 sampleGgxVisibleNormal(glm::vec3 wo, float alpha, glm::vec2 u) {
    // Stretch the view direction to the hemisphere configuration, sample the projected disk,
    // then unstretch (Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 2018).
    const glm::vec3 vh = glm::normalize(glm::vec3(alpha * wo.x, alpha * wo.y, wo.z));
    const float length2 = vh.x * vh.x + vh.y * vh.y;
    const glm::vec3 t1 = length2 > 0.0f ? glm::vec3(-vh.y, vh.x, 0.0f) / std::sqrt(length2)
                                        : glm::vec3(1.0f, 0.0f, 0.0f);
    const glm::vec3 t2 = glm::cross(vh, t1);
    const float r = std::sqrt(u.x);
    const float phi = 2.0f * kPi * u.y;
    const float p1 = r * std::cos(phi);
    float p2 = r * std::sin(phi);
    const float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * std::sqrt(std::max(0.0f, 1.0f - p1 * p1)) + s * p2;
    const glm::vec3 nh = p1 * t1 + p2 * t2 + std::sqrt(std::max(0.0f, 1.0f - p1 * p1 - p2 * p2)) * vh;
    return glm::normalize(glm::vec3(alpha * nh.x, alpha * nh.y, std::max(1e-6f, nh.z)));
}

GltfBsdf::GltfBsdf(const ShadingMaterial& m, const SurfaceHit& hit, float min_roughness)
    : frame_(hit.shading_normal), geometric_normal_(hit.geometric_normal) {
    const float metallic = glm::clamp(m.metallic, 0.0f, 1.0f);
    roughness_ = glm::clamp(std::max(m.roughness, min_roughness), 0.0f, 1.0f);
    alpha_ = std::max(roughness_ * roughness_, kMinAlpha);
    const float r = (m.ior - 1.0f) / (m.ior + 1.0f);
    dielectric_f0_ = glm::min(glm::vec3(r * r) * m.specular_color, glm::vec3(1.0f)) * m.specular_weight;
    dielectric_f90_ = m.specular_weight;
    diffuse_color_ = (1.0f - metallic) * m.base_color;
    f0_ = glm::mix(dielectric_f0_, m.base_color, metallic);
    f90_ = glm::mix(glm::vec3(dielectric_f90_), glm::vec3(1.0f), metallic);
    has_specular_ = metallic > 0.0f || m.specular_weight > 0.0f;
}

float GltfBsdf::specularProbability(float cos_o) const {
    if (!has_specular_) return 0.0f;
    // Lobe choice follows the two lobes' Fresnel-weighted albedos for this view direction.
    const float spec = luminance(schlick(f0_, f90_, cos_o));
    const float diffuse = luminance(diffuse_color_) *
                          (1.0f - maxComponent(schlick(dielectric_f0_, glm::vec3(dielectric_f90_), cos_o)));
    if (diffuse <= 0.0f) return 1.0f;
    // Keep both lobes reachable so MIS with light sampling never meets a zero pdf.
    return glm::clamp(spec / (spec + diffuse), 0.1f, 0.9f);
}

GltfBsdf::Evaluation GltfBsdf::evaluate(glm::vec3 wo_world, glm::vec3 wi_world) const {
    Evaluation e;
    // Reflection only: both directions on the side of the geometric normal the ray came from.
    if (glm::dot(wi_world, geometric_normal_) <= 0.0f || glm::dot(wo_world, geometric_normal_) <= 0.0f) {
        return e;
    }
    const glm::vec3 wo = frame_.toLocal(wo_world);
    const glm::vec3 wi = frame_.toLocal(wi_world);
    if (wo.z <= 0.0f || wi.z <= 0.0f) return e;
    const glm::vec3 h = glm::normalize(wo + wi);
    const float cos_oh = std::max(0.0f, glm::dot(wo, h));
    const float p_spec = specularProbability(wo.z);

    glm::vec3 f_cos(0.0f);
    float pdf = 0.0f;
    if (p_spec < 1.0f) {
        const glm::vec3 layer = 1.0f - glm::vec3(maxComponent(
                                           schlick(dielectric_f0_, glm::vec3(dielectric_f90_), cos_oh)));
        f_cos += diffuse_color_ * layer * (kInvPi * wi.z);
        pdf += (1.0f - p_spec) * wi.z * kInvPi;
    }
    if (p_spec > 0.0f) {
        const float d = ggxD(h.z, alpha_);
        const float g2 = 1.0f / (1.0f + ggxLambda(wo, alpha_) + ggxLambda(wi, alpha_));
        const float g1 = 1.0f / (1.0f + ggxLambda(wo, alpha_));
        f_cos += schlick(f0_, f90_, cos_oh) * (d * g2 / (4.0f * wo.z));
        // Visible-normal pdf: G1(wo) D(h) max(0, wo.h) / wo.z, times the reflection Jacobian.
        pdf += p_spec * g1 * d / (4.0f * wo.z);
    }
    e.f_cos = f_cos;
    e.pdf = pdf;
    return e;
}

GltfBsdf::Sample GltfBsdf::sample(glm::vec3 wo_world, float u_lobe, glm::vec2 u) const {
    Sample s;
    if (glm::dot(wo_world, geometric_normal_) <= 0.0f) return s;
    const glm::vec3 wo = frame_.toLocal(wo_world);
    if (wo.z <= 0.0f) return s;
    const float p_spec = specularProbability(wo.z);
    glm::vec3 wi;
    s.specular = u_lobe < p_spec;
    if (s.specular) {
        const glm::vec3 h = sampleGgxVisibleNormal(wo, alpha_, u);
        wi = glm::reflect(-wo, h);
    } else {
        wi = sampleCosineHemisphere(u);
    }
    if (wi.z <= 0.0f) return s;
    s.wi = frame_.toWorld(wi);
    const Evaluation e = evaluate(wo_world, s.wi);
    if (!(e.pdf > 0.0f)) return s;
    s.pdf = e.pdf;
    s.weight = e.f_cos / e.pdf;
    s.valid = isFiniteColor(s.weight);
    return s;
}

}  // namespace sharcbake
