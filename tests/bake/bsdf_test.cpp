// SPDX-License-Identifier: Apache-2.0
// The glTF BRDF: energy (white furnace), sampling against evaluation, pdf consistency.
#include "bsdf.h"
#include "sampling.h"

#include <gtest/gtest.h>

#include <cmath>

namespace sharcbake {
namespace {

SurfaceHit flatHit() {
    SurfaceHit hit;
    hit.geometric_normal = hit.shading_normal = hit.face_normal = {0.0f, 0.0f, 1.0f};
    return hit;
}

ShadingMaterial lambert(float albedo) {
    ShadingMaterial m;
    m.base_color = glm::vec3(albedo);
    m.metallic = 0.0f;
    m.specular_weight = 0.0f;
    return m;
}

ShadingMaterial metal(float roughness) {
    ShadingMaterial m;
    m.base_color = glm::vec3(1.0f);
    m.metallic = 1.0f;
    m.roughness = roughness;
    return m;
}

glm::vec3 directionAt(float cos_theta) {
    return {std::sqrt(std::max(0.0f, 1.0f - cos_theta * cos_theta)), 0.0f, cos_theta};
}

/// Mean of sample weights: the directional albedo estimated by importance sampling.
glm::dvec3 sampledAlbedo(const GltfBsdf& bsdf, glm::vec3 wo, uint32_t count) {
    glm::dvec3 sum(0.0);
    for (uint32_t i = 0; i < count; ++i) {
        PixelSampler sampler(7, 0, i);
        const glm::vec2 u_lobe = sampler.next2D();
        const GltfBsdf::Sample s = bsdf.sample(wo, u_lobe.x, sampler.next2D());
        if (s.valid) sum += glm::dvec3(s.weight);
    }
    return sum / double(count);
}

/// The same albedo by brute-force quadrature of evaluate() over the hemisphere.
glm::dvec3 quadratureAlbedo(const GltfBsdf& bsdf, glm::vec3 wo, int n) {
    glm::dvec3 sum(0.0);
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
            // Uniform hemisphere: pdf 1 / (2 pi).
            const float z = (float(i) + 0.5f) / float(n);
            const float phi = 2.0f * kPi * (float(j) + 0.5f) / float(n);
            const float r = std::sqrt(1.0f - z * z);
            const glm::vec3 wi(r * std::cos(phi), r * std::sin(phi), z);
            sum += glm::dvec3(bsdf.evaluate(wo, wi).f_cos);
        }
    }
    return sum * (2.0 * kPi / double(n * n));
}

TEST(Bsdf, WhiteLambertReflectsEverything) {
    const GltfBsdf bsdf(lambert(1.0f), flatHit());
    EXPECT_TRUE(bsdf.isDiffuseOnly());
    for (float c : {1.0f, 0.5f, 0.1f}) {
        const glm::dvec3 a = sampledAlbedo(bsdf, directionAt(c), 4096);
        EXPECT_NEAR(a.x, 1.0, 1e-3) << "cos(theta_o) = " << c;
        const glm::dvec3 q = quadratureAlbedo(bsdf, directionAt(c), 400);
        EXPECT_NEAR(q.x, 1.0, 5e-3) << "cos(theta_o) = " << c;
    }
}

TEST(Bsdf, GgxSamplingMatchesQuadrature) {
    // Single-scattering GGX loses energy as roughness grows (no multiple scattering): the
    // albedo of a white metal at normal-ish incidence stays above these bounds.
    const struct {
        float roughness, min_albedo;
    } cases[] = {{0.3f, 0.9f}, {0.6f, 0.7f}, {1.0f, 0.3f}};
    for (const auto& [roughness, min_albedo] : cases) {
        const GltfBsdf bsdf(metal(roughness), flatHit());
        for (float c : {0.9f, 0.5f}) {
            const glm::vec3 wo = directionAt(c);
            const glm::dvec3 sampled = sampledAlbedo(bsdf, wo, 1 << 16);
            const glm::dvec3 quadrature = quadratureAlbedo(bsdf, wo, 800);
            EXPECT_NEAR(sampled.x, quadrature.x, 0.02 * quadrature.x)
                << "roughness " << roughness << ", cos(theta_o) " << c;
            EXPECT_LE(quadrature.x, 1.01);
            EXPECT_GT(quadrature.x, min_albedo) << "roughness " << roughness;
        }
    }
}

TEST(Bsdf, SamplePdfMatchesEvaluatePdf) {
    ShadingMaterial m = metal(0.5f);
    m.metallic = 0.3f;
    m.base_color = {0.8f, 0.5f, 0.2f};
    const GltfBsdf bsdf(m, flatHit());
    const glm::vec3 wo = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    for (uint32_t i = 0; i < 256; ++i) {
        PixelSampler sampler(3, 1, i);
        const glm::vec2 u_lobe = sampler.next2D();
        const GltfBsdf::Sample s = bsdf.sample(wo, u_lobe.x, sampler.next2D());
        if (!s.valid) continue;
        const GltfBsdf::Evaluation e = bsdf.evaluate(wo, s.wi);
        EXPECT_NEAR(s.pdf, e.pdf, 1e-4f * e.pdf);
        EXPECT_GT(s.wi.z, 0.0f);
    }
}

TEST(Bsdf, UpdateRoughnessClampRaisesRoughness) {
    const GltfBsdf mirror(metal(0.05f), flatHit(), 0.4f);
    EXPECT_FLOAT_EQ(mirror.roughness(), 0.4f);
    const GltfBsdf rough(metal(0.8f), flatHit(), 0.4f);
    EXPECT_FLOAT_EQ(rough.roughness(), 0.8f);
}

TEST(Sampling, PixelSamplerIsAPureFunction) {
    PixelSampler a(1, 2, 3), b(1, 2, 3), c(1, 2, 4);
    for (int i = 0; i < 8; ++i) {
        const glm::vec2 va = a.next2D(), vb = b.next2D(), vc = c.next2D();
        EXPECT_EQ(va, vb);
        EXPECT_NE(va, vc);
        EXPECT_GE(va.x, 0.0f);
        EXPECT_LT(va.x, 1.0f);
    }
}

TEST(Sampling, SobolPairsAreStratified) {
    // 16 samples of one pixel's first pair fall one per 4x4 stratum ((0,2)-sequence).
    bool seen[16] = {};
    for (uint32_t i = 0; i < 16; ++i) {
        PixelSampler s(11, 5, i);
        const glm::vec2 u = s.next2D();
        seen[int(u.y * 4) * 4 + int(u.x * 4)] = true;
    }
    for (bool b : seen) EXPECT_TRUE(b);
}

}  // namespace
}  // namespace sharcbake
