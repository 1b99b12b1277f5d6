// SPDX-License-Identifier: Apache-2.0
#include "tracing/bsdf.h"

#include <algorithm>
#include <cmath>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace sharcbake {
namespace {

// Below this alpha the lobe is a near-mirror; clamping keeps D finite in float.
constexpr float kMinAlpha = 1e-4f;

/// Schlick's (1 - cos)^5, the weight of F90 against F0.
float schlickWeight(float cos_theta) {
    const float m = glm::clamp(1.0f - cos_theta, 0.0f, 1.0f);
    const float m2 = m * m;
    return m2 * m2 * m;
}

glm::vec3 schlick(glm::vec3 f0, glm::vec3 f90, float cos_theta) { return f0 + (f90 - f0) * schlickWeight(cos_theta); }

}  // namespace

float ggxD(glm::vec3 h, float alpha) {
    if (h.z <= 0.0f) return 0.0f;
    const float a2 = alpha * alpha;
    // cos^2 (a^2 - 1) + 1 = cos^2 a^2 + sin^2, with sin^2 from the tangential components.
    const float d = h.z * h.z * a2 + (h.x * h.x + h.y * h.y);
    return a2 / (kPi * d * d);
}

float ggxLambda(glm::vec3 w, float alpha) {
    const float c2 = w.z * w.z;
    if (c2 <= 0.0f) return 0.0f;
    const float tan2 = (w.x * w.x + w.y * w.y) / c2;
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

namespace {

// Roughness needs the finer steps: E varies fastest with it (through alpha = roughness^2).
constexpr int kAlbedoTableSize = 32;       // cos(theta_o) steps
constexpr int kAlbedoRoughnessSteps = 64;  // roughness steps
constexpr int kAlbedoRadialSteps = 64;   // samples per entry: radial (warped) x angular strata
constexpr int kAlbedoAngularSteps = 16;

/// One table entry by stratified visible-normal sampling: with F = 1 the weight of a VNDF sample
/// is G2 / G1, its expectation the directional albedo. The sampled disk's radius (sqrt(u.x))
/// near 1 gives the grazing half-vectors where G2 / G1 falls to 0, a thin tail that holds a
/// percent of the integral at moderate roughness: u.x = 1 - (1 - t)^3 puts strata there (weight
/// du/dt = 3 (1 - t)^2).
GgxAlbedo integrateGgxAlbedo(float cos_o, float roughness) {
    const float alpha = std::max(roughness * roughness, kMinAlpha);
    const glm::vec3 wo(std::sqrt(std::max(0.0f, 1.0f - cos_o * cos_o)), 0.0f, cos_o);
    double e = 0.0, e5 = 0.0;
    for (int i = 0; i < kAlbedoRadialSteps; ++i) {
        const double t = (double(i) + 0.5) / kAlbedoRadialSteps;
        const double jacobian = 3.0 * (1.0 - t) * (1.0 - t);
        const float ux = float(1.0 - (1.0 - t) * (1.0 - t) * (1.0 - t));
        for (int j = 0; j < kAlbedoAngularSteps; ++j) {
            const glm::vec2 u(ux, (float(j) + 0.5f) / kAlbedoAngularSteps);
            const glm::vec3 h = sampleGgxVisibleNormal(wo, alpha, u);
            const glm::vec3 wi = glm::reflect(-wo, h);
            if (wi.z <= 0.0f) continue;
            const double weight =
                jacobian * (1.0 + ggxLambda(wo, alpha)) / (1.0 + ggxLambda(wo, alpha) + ggxLambda(wi, alpha));
            const double m = glm::clamp(1.0 - double(glm::dot(wo, h)), 0.0, 1.0);
            e += weight;
            e5 += weight * (m * m * m * m * m);
        }
    }
    const double n = double(kAlbedoRadialSteps * kAlbedoAngularSteps);
    return GgxAlbedo{float(e / n), float(e5 / n)};
}

struct GgxAlbedoTable {
    GgxAlbedo entries[kAlbedoRoughnessSteps][kAlbedoTableSize];  ///< [roughness][cos_o], both 0..1
    float average[kAlbedoRoughnessSteps];                         ///< [roughness]: 2 int E(mu) mu dmu
    GgxAlbedoTable() {
        // Two million samples (about 0.1 s on one core): the rows are independent, so they are
        // filled in parallel, each the same on any thread. Isolated, so a thread waiting for its
        // rows cannot pick up an outer task that would ask for the table being built.
        tbb::this_task_arena::isolate([&] {
            tbb::parallel_for(0, kAlbedoRoughnessSteps, [&](int r) { fillRow(r); });
        });
    }

    void fillRow(int r) {
        for (int c = 0; c < kAlbedoTableSize; ++c) {
            const float cos_o = std::max(float(c) / (kAlbedoTableSize - 1), 1e-3f);
            entries[r][c] = integrateGgxAlbedo(cos_o, float(r) / (kAlbedoRoughnessSteps - 1));
        }
        // Trapezoid rule on the row (the integrand 2 mu E(mu) is smooth).
        double sum = 0.0;
        for (int c = 0; c + 1 < kAlbedoTableSize; ++c) {
            const double m0 = double(c) / (kAlbedoTableSize - 1), m1 = double(c + 1) / (kAlbedoTableSize - 1);
            sum += (m1 - m0) * (m0 * entries[r][c].e + m1 * entries[r][c + 1].e);
        }
        average[r] = float(sum);
    }
};

const GgxAlbedoTable& albedoTable() {
    static const GgxAlbedoTable table;  // built once, thread-safe (C++11 statics)
    return table;
}

}  // namespace

void prepareBsdfTables() { albedoTable(); }

float ggxAverageAlbedo(float roughness) {
    const GgxAlbedoTable& table = albedoTable();
    const float y = glm::clamp(roughness, 0.0f, 1.0f) * (kAlbedoRoughnessSteps - 1);
    const int y0 = std::min(int(y), kAlbedoRoughnessSteps - 2);
    return glm::mix(table.average[y0], table.average[y0 + 1], y - float(y0));
}

GgxAlbedo ggxAlbedo(float cos_theta_o, float roughness) {
    const GgxAlbedoTable& table = albedoTable();
    const float x = glm::clamp(cos_theta_o, 0.0f, 1.0f) * (kAlbedoTableSize - 1);
    const float y = glm::clamp(roughness, 0.0f, 1.0f) * (kAlbedoRoughnessSteps - 1);
    const int x0 = std::min(int(x), kAlbedoTableSize - 2), y0 = std::min(int(y), kAlbedoRoughnessSteps - 2);
    const float fx = x - float(x0), fy = y - float(y0);
    const auto lerp = [&](float GgxAlbedo::*field) {
        const float top = glm::mix(table.entries[y0][x0].*field, table.entries[y0][x0 + 1].*field, fx);
        const float bottom = glm::mix(table.entries[y0 + 1][x0].*field, table.entries[y0 + 1][x0 + 1].*field, fx);
        return glm::mix(top, bottom, fy);
    };
    return GgxAlbedo{lerp(&GgxAlbedo::e), lerp(&GgxAlbedo::e5)};
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
    metal_f0_ = m.base_color;
    metallic_ = metallic;
    has_specular_ = metallic > 0.0f || m.specular_weight > 0.0f;
    e_avg_ = has_specular_ ? ggxAverageAlbedo(roughness_) : 1.0f;
    coat_ = glm::clamp(m.clearcoat, 0.0f, 1.0f);
    has_coat_ = coat_ > 0.0f;
    if (has_coat_) {
        coat_roughness_ = glm::clamp(std::max(m.clearcoat_roughness, min_roughness), 0.0f, 1.0f);
        coat_alpha_ = std::max(coat_roughness_ * coat_roughness_, kMinAlpha);
    }
}

namespace {

/// KHR_materials_clearcoat's layer: a dielectric of ior 1.5, ((1.5 - 1) / (1.5 + 1))^2.
constexpr float kClearcoatF0 = 0.04f;

/// Kulla and Conty's colour of the multiple-scattering lobe for a Schlick Fresnel: the average
/// Fresnel F_avg = F0 + (F90 - F0) / 21 (cosine-weighted), then F_avg^2 E_avg / (1 - F_avg (1 - E_avg)),
/// the light that leaves after any number of bounces; 1 for a white lobe.
glm::vec3 multipleScatteringFresnel(glm::vec3 f0, glm::vec3 f90, float e_avg) {
    const glm::vec3 f_avg = f0 + (f90 - f0) * (1.0f / 21.0f);
    return f_avg * f_avg * e_avg / (1.0f - f_avg * (1.0f - e_avg));
}

}  // namespace

const GltfBsdf::Lobes& GltfBsdf::lobes(float cos_o) const {
    if (!(cos_o == lobes_cos_o_)) {
        lobes_ = computeLobes(cos_o);
        lobes_cos_o_ = cos_o;
    }
    return lobes_;
}

GltfBsdf::Lobes GltfBsdf::computeLobes(float cos_o) const {
    Lobes l = computeBaseLobes(cos_o);
    if (!has_coat_) return l;
    // The clearcoat reflects c = clearcoat (F0 E + (1 - F0) E5) at its roughness (single
    // scattering: with F0 0.04 its multiple scattering is a fraction of a percent); the layers
    // beneath get 1 - c.
    const GgxAlbedo a = ggxAlbedo(cos_o, coat_roughness_);
    l.coat = coat_ * (kClearcoatF0 * a.e + (1.0f - kClearcoatF0) * a.e5);
    l.under_coat = 1.0f - l.coat;
    const float base = luminance(l.albedo) * l.under_coat;
    l.diffuse *= l.under_coat;
    l.multiple_scattering *= l.under_coat;
    l.albedo = glm::vec3(l.coat) + l.albedo * l.under_coat;
    l.p_coat = l.coat + base > 0.0f ? l.coat / (l.coat + base) : 1.0f;
    return l;
}

GltfBsdf::Lobes GltfBsdf::computeBaseLobes(float cos_o) const {
    Lobes l;
    if (!has_specular_) {
        l.diffuse = l.albedo = diffuse_color_;
        return l;
    }
    const GgxAlbedo a = ggxAlbedo(cos_o, roughness_);
    // Each specular lobe: single scattering (Schlick: F0 E + (F90 - F0) E5) plus Kulla-Conty's
    // multiple-scattering lobe, F_ms (1 - E(mu_o)) (1 - E(mu_i)) / (pi (1 - E_avg)), whose albedo
    // F_ms (1 - E(mu_o)) makes a white lobe reflect exactly 1.
    const glm::vec3 dielectric_f90(dielectric_f90_);
    const glm::vec3 dielectric_ss = dielectric_f0_ * a.e + (dielectric_f90 - dielectric_f0_) * a.e5;
    const glm::vec3 metal_ss = metal_f0_ * a.e + (1.0f - metal_f0_) * a.e5;
    glm::vec3 dielectric_ms(0.0f), metal_ms(0.0f);
    if (e_avg_ < 1.0f - 1e-4f) {  // a near-mirror scatters once: no multiple-scattering lobe
        dielectric_ms = multipleScatteringFresnel(dielectric_f0_, dielectric_f90, e_avg_);
        metal_ms = multipleScatteringFresnel(metal_f0_, glm::vec3(1.0f), e_avg_);
        l.multiple_scattering = ((1.0f - metallic_) * dielectric_ms + metallic_ * metal_ms) *
                                (std::max(0.0f, 1.0f - a.e) / (1.0f - e_avg_));
    }
    const glm::vec3 dielectric_albedo =
        glm::min(dielectric_ss + dielectric_ms * std::max(0.0f, 1.0f - a.e), glm::vec3(1.0f));
    l.diffuse = diffuse_color_ * (1.0f - dielectric_albedo);
    const glm::vec3 single_scattering = (1.0f - metallic_) * dielectric_ss + metallic_ * metal_ss;
    // The cosine-sampled part: the diffuse base and the multiple-scattering lobe (whose mean of
    // 1 - E(mu_i) over the cosine-weighted hemisphere is 1 - E_avg).
    const glm::vec3 cosine_albedo = l.diffuse + l.multiple_scattering * (1.0f - e_avg_);
    l.albedo = single_scattering + cosine_albedo;
    const float spec = luminance(single_scattering), cosine = luminance(cosine_albedo);
    l.p_specular = spec + cosine > 0.0f ? spec / (spec + cosine) : 0.5f;
    return l;
}

glm::vec3 GltfBsdf::albedo(glm::vec3 wo_world) const {
    const float cos_o = glm::dot(frame_.toLocal(wo_world), glm::vec3(0.0f, 0.0f, 1.0f));
    if (cos_o <= 0.0f || glm::dot(wo_world, geometric_normal_) <= 0.0f) return glm::vec3(0.0f);
    return lobes(cos_o).albedo;
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
    const Lobes& l = lobes(wo.z);
    const float p_spec = l.p_specular;

    // Diffuse base, scaled by what the dielectric layer leaves (albedo scaling), the
    // multiple-scattering lobe, and the single-scattering lobes; the pdf is the mixture's
    // (one-sample MIS over the two sampling strategies).
    glm::vec3 f_cos = l.diffuse * (kInvPi * wi.z);
    if (maxComponent(l.multiple_scattering) > 0.0f) {
        f_cos += l.multiple_scattering * (std::max(0.0f, 1.0f - ggxAlbedo(wi.z, roughness_).e) * kInvPi * wi.z);
    }
    float pdf = (1.0f - p_spec) * wi.z * kInvPi;
    if (has_specular_) {
        const float d = ggxD(h, alpha_);
        const float g2 = 1.0f / (1.0f + ggxLambda(wo, alpha_) + ggxLambda(wi, alpha_));
        const float g1 = 1.0f / (1.0f + ggxLambda(wo, alpha_));
        const glm::vec3 fresnel = (1.0f - metallic_) * schlick(dielectric_f0_, glm::vec3(dielectric_f90_), cos_oh) +
                                  metallic_ * schlick(metal_f0_, glm::vec3(1.0f), cos_oh);
        // l.diffuse and l.multiple_scattering already carry the coat's 1 - c.
        f_cos += fresnel * (d * g2 / (4.0f * wo.z) * l.under_coat);
        // Visible-normal pdf: G1(wo) D(h) max(0, wo.h) / wo.z, times the reflection Jacobian.
        pdf += p_spec * g1 * d / (4.0f * wo.z);
    }
    if (has_coat_) {
        const float d = ggxD(h, coat_alpha_);
        const float g2 = 1.0f / (1.0f + ggxLambda(wo, coat_alpha_) + ggxLambda(wi, coat_alpha_));
        const float g1 = 1.0f / (1.0f + ggxLambda(wo, coat_alpha_));
        const float fresnel = kClearcoatF0 + (1.0f - kClearcoatF0) * schlickWeight(cos_oh);
        f_cos += glm::vec3(coat_ * fresnel * d * g2 / (4.0f * wo.z));
        pdf = (1.0f - l.p_coat) * pdf + l.p_coat * g1 * d / (4.0f * wo.z);
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
    const Lobes& l = lobes(wo.z);
    glm::vec3 wi;
    if (has_coat_ && u_lobe < l.p_coat) {
        s.specular = true;
        s.roughness = coat_roughness_;
        wi = glm::reflect(-wo, sampleGgxVisibleNormal(wo, coat_alpha_, u));
    } else {
        // The rest of [0, 1) picks among the layers beneath, as without a coat.
        if (has_coat_) u_lobe = std::min((u_lobe - l.p_coat) / (1.0f - l.p_coat), kOneMinusEpsilon);
        s.specular = u_lobe < l.p_specular;
        if (s.specular) {
            s.roughness = roughness_;
            const glm::vec3 h = sampleGgxVisibleNormal(wo, alpha_, u);
            wi = glm::reflect(-wo, h);
        } else {
            wi = sampleCosineHemisphere(u);
        }
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
