// SPDX-License-Identifier: Apache-2.0
#include "tracing/lights.h"

#include "tracing/sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sharcbake {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

glm::vec3 textureMean(const Texture& texture) {
    glm::dvec3 sum(0.0);
    const size_t count = texture.texelCount();
    for (size_t i = 0; i < count; ++i) sum += glm::dvec3(texture.texel(i));
    return count == 0 ? glm::vec3(1.0f) : glm::vec3(sum / double(count));
}

/// KHR_lights_punctual's recommended range cut-off, clamp(1 - (d/range)^4, 0, 1), times the
/// inverse square law: as close to it as a smooth cut-off allows (0.94 at half the range, 0.59 at
/// 0.8 of it). The squared window some engines use (UE4's) would darken a light to 0.64 of the
/// spec's at two thirds of its range; Blender exports EEVEE's "Custom Distance" as `range`.
float rangeWindow(float distance, float range) {
    if (range <= 0.0f) return 1.0f;
    const float ratio = distance / range;
    return glm::clamp(1.0f - ratio * ratio * ratio * ratio, 0.0f, 1.0f);
}

/// 1 - cos(angle), exact for small angles too: in float, the cosine of any angle below about
/// 3e-4 rad rounds to 1, and a narrow spot cone (glTF allows any outer angle above 0) would
/// have no width at all.
float oneMinusCos(float angle) {
    const float s = std::sin(0.5f * angle);
    return 2.0f * s * s;
}

/// KHR_lights_punctual's spot attenuation: squared linear ramp between the cone cosines. Kept in
/// 1 - cos terms (oneMinusCos; for unit vectors 1 - a.b = |a - b|^2 / 2), so a cone of a
/// microradian lights its disc instead of nothing. The extension's sample code floors the
/// ramp's width at 0.001 in cosine, which also darkens any cone narrower than 2.6 degrees;
/// here only a ramp of no width (inner = outer) becomes a hard edge.
float spotAttenuation(const PunctualLight& light, glm::vec3 light_to_point) {
    const float outer = oneMinusCos(light.outer_cone_angle);
    const float inner = oneMinusCos(light.inner_cone_angle);
    const glm::vec3 apart = light.direction - light_to_point;
    const float off_axis = 0.5f * glm::dot(apart, apart);
    if (!(off_axis < outer)) return 0.0f;
    if (!(outer - inner > 0.0f)) return 1.0f;
    const float t = glm::clamp((outer - off_axis) / (outer - inner), 0.0f, 1.0f);
    return t * t;
}

/// A light's selection power: its float32 product, or where that overflows, the same product in
/// double. Scenes whose powers fit float32, all ordinary ones, keep their float32 powers.
double selectionPower(float in_float, double in_double) {
    return std::isfinite(in_float) ? double(in_float) : in_double;
}

/// The powers as Distribution1D's float32 weights, which count infinity as no power: a 1e37
/// emitter of 100 m^2 (power 1.6e39) was never chosen. Selection depends only on the powers'
/// ratios, so where one is beyond float32, all are scaled by one power of two (exact) until the
/// largest fits.
std::vector<float> selectionWeights(std::vector<double> powers) {
    double largest = 0.0;
    for (const double p : powers)
        if (std::isfinite(p)) largest = std::max(largest, p);
    if (largest > double(std::numeric_limits<float>::max())) {
        const int shift = std::ilogb(largest) - 126;  // the largest lands in [2^126, 2^127)
        for (double& p : powers) p = std::ldexp(p, -shift);
    }
    return std::vector<float>(powers.begin(), powers.end());
}

}  // namespace

glm::vec2 directionToEquirect(glm::vec3 d) {
    const float u = 0.5f + std::atan2(d.z, d.x) * (0.5f * kInvPi);
    const float v = std::acos(glm::clamp(d.y, -1.0f, 1.0f)) * kInvPi;
    return {u - std::floor(u), v};
}

glm::vec3 equirectToDirection(glm::vec2 uv) {
    const float phi = (uv.x - 0.5f) * 2.0f * kPi;
    const float theta = uv.y * kPi;
    const float sin_theta = std::sin(theta);
    return {sin_theta * std::cos(phi), std::cos(theta), sin_theta * std::sin(phi)};
}

LightSampler::LightSampler(const Scene& scene) : scene_(scene) {
    std::vector<double> powers;  // one per entry: light selection is proportional to power
    const glm::vec3 extent = scene.bounds_max - scene.bounds_min;
    const float radius = std::max(0.5f * glm::length(extent), 1e-3f);
    // Lights at infinity deliver their power through the scene's bounding disk.
    const float disk_area = kPi * radius * radius;
    addAreaLights(powers);
    addPunctualLights(disk_area, powers);
    addSky(disk_area, powers);
    if (entries_.empty()) return;
    selection_ = Distribution1D(selectionWeights(std::move(powers)));
    for (size_t e = 0; e < entries_.size(); ++e) {
        if (entries_[e].kind == Kind::Triangle) triangle_pmf_[entries_[e].index] = selection_.pmf(e);
        if (entries_[e].kind == Kind::Sky) sky_pmf_ = selection_.pmf(e);
    }
}

void LightSampler::addAreaLights(std::vector<double>& powers) {
    // Power = pi * area * luminance(mean emitted radiance) per emitting side.
    std::vector<glm::vec3> texture_means(scene_.textures.size(), glm::vec3(-1.0f));
    for (uint32_t t = 0; t < scene_.triangles.size(); ++t) {
        const Material& m = scene_.materials[scene_.triangle_materials[t]];
        if (!m.isEmissive()) continue;
        glm::vec3 emission = m.emissive * m.emissive_strength;
        if (m.emissive_texture.isSet()) {
            glm::vec3& mean = texture_means[size_t(m.emissive_texture.texture)];
            if (mean.x < 0.0f) mean = textureMean(scene_.textures[size_t(m.emissive_texture.texture)]);
            emission *= mean;
        }
        const glm::uvec3 tri = scene_.triangles[t];
        const float area = 0.5f * glm::length(glm::cross(scene_.positions[tri.y] - scene_.positions[tri.x],
                                                         scene_.positions[tri.z] - scene_.positions[tri.x]));
        const float sides = m.double_sided ? 2.0f : 1.0f;
        const float power = kPi * area * luminance(emission) * sides;
        if (!(power > 0.0f)) continue;
        if (triangle_area_.empty()) {
            triangle_area_.assign(scene_.triangles.size(), 0.0f);
            triangle_pmf_.assign(scene_.triangles.size(), 0.0f);
        }
        triangle_area_[t] = area;
        entries_.push_back({Kind::Triangle, t});
        powers.push_back(selectionPower(power, double(kPi) * double(area) * luminanceInDouble(emission) * sides));
        ++emissive_triangle_count_;
    }
}

void LightSampler::addPunctualLights(float disk_area, std::vector<double>& powers) {
    for (uint32_t i = 0; i < scene_.lights.size(); ++i) {
        const PunctualLight& light = scene_.lights[i];
        const float lum = luminance(light.intensity);
        // The power per unit of luminance: the solid angle it shines into, or the area it lights.
        float spread = 0.0f;
        switch (light.type) {
            case LightType::Point: spread = 4.0f * kPi; break;
            case LightType::Spot: {
                // The solid angle of a cone halfway between the two (1 - cos stays exact for
                // narrow cones, whose power would otherwise round to zero and drop the light).
                const float one_minus_cos_mid = 0.5f * (oneMinusCos(light.inner_cone_angle) +
                                                        oneMinusCos(light.outer_cone_angle));
                spread = 2.0f * kPi * one_minus_cos_mid;
                break;
            }
            case LightType::Directional: spread = disk_area; break;
        }
        const float power = spread * lum;
        if (!(power > 0.0f)) {
            dark_lights_.push_back(i);
            continue;
        }
        entries_.push_back({Kind::Punctual, i});
        powers.push_back(selectionPower(power, double(spread) * luminanceInDouble(light.intensity)));
    }
}

void LightSampler::addSky(float disk_area, std::vector<double>& powers) {
    if (scene_.sky.isBlack()) return;
    float mean_luminance = luminance(scene_.sky.uniform);
    if (scene_.sky.map) {
        const Texture& map = *scene_.sky.map;
        const size_t width = size_t(map.width), height = size_t(map.height);
        std::vector<float> lum(width * height);
        for (size_t i = 0; i < lum.size(); ++i) lum[i] = std::max(0.0f, luminance(glm::vec3(map.texels[i])));
        // Each cell's weight is the mean of the bilinear lookup over it (skyRadiance filters the
        // map): a texel's light spreads half a texel into its eight neighbours, 1/8, 3/4, 1/8 along
        // each axis (u wraps, v clamps, as the lookup does). With the texel alone the neighbours
        // had no light-sampling pdf, and a one-texel sun lit them only through BSDF samples:
        // fireflies, three times the noise of the same sun spread over 3x3 texels.
        const auto at = [&](int64_t x, int64_t y) {
            const int64_t w = int64_t(width), h = int64_t(height);
            return lum[size_t(std::clamp<int64_t>(y, 0, h - 1)) * width + size_t(((x % w) + w) % w)];
        };
        constexpr float kTent[3] = {0.125f, 0.75f, 0.125f};
        std::vector<float> weights(width * height);
        double sum = 0.0;
        for (size_t y = 0; y < height; ++y) {
            // Rows near the poles cover less solid angle.
            const float sin_theta = std::sin(kPi * (float(y) + 0.5f) / float(map.height));
            for (size_t x = 0; x < width; ++x) {
                float cell = 0.0f;
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx)
                        cell += kTent[dy + 1] * kTent[dx + 1] * at(int64_t(x) + dx, int64_t(y) + dy);
                }
                weights[y * width + x] = cell * sin_theta;
                sum += double(cell * sin_theta);
            }
        }
        sky_map_distribution_ = Distribution2D(weights, map.width, map.height);
        mean_luminance =
            float(sum / std::max(1.0, double(map.width) * double(map.height)) * (kPi / 2.0)) * scene_.sky.scale;
    }
    if (mean_luminance > 0.0f) {
        has_sky_ = true;
        entries_.push_back({Kind::Sky, 0});
        powers.push_back(
            selectionPower(kPi * mean_luminance * disk_area, double(kPi) * double(mean_luminance) * double(disk_area)));
    }
}

bool LightSampler::sample(const SurfaceHit& at, float u_select, glm::vec2 u, LightSample& out) const {
    if (selection_.empty()) return false;
    const size_t e = selection_.sampleDiscrete(u_select);
    const float pmf = selection_.pmf(e);
    switch (entries_[e].kind) {
        case Kind::Triangle: return sampleTriangle(entries_[e].index, pmf, at, u, out);
        case Kind::Punctual: return samplePunctual(scene_.lights[entries_[e].index], pmf, at, out);
        case Kind::Sky: return sampleSky(pmf, at, u, out);
    }
    return false;
}

bool LightSampler::sampleTriangle(uint32_t triangle, float pmf, const SurfaceHit& at, glm::vec2 u,
                                  LightSample& out) const {
    const glm::vec2 b = sampleUniformTriangle(u);
    const EmitterPoint point = makeEmitterPoint(scene_, triangle, b.x, b.y);
    const glm::vec3 to_light = point.position - at.position;
    const float distance2 = glm::dot(to_light, to_light);
    if (!(distance2 > 0.0f)) return false;
    const float distance = std::sqrt(distance2);
    const glm::vec3 wi = to_light / distance;
    const float cos_light = -glm::dot(point.face_normal, wi);
    if (cos_light == 0.0f || (cos_light < 0.0f && !point.double_sided)) return false;
    out.wi = wi;
    out.distance = distance;
    out.radiance = point.emission;
    out.pdf = pmf * distance2 / (triangle_area_[triangle] * std::abs(cos_light));
    out.is_delta = false;
    return out.pdf > 0.0f && std::isfinite(out.pdf);
}

bool LightSampler::samplePunctual(const PunctualLight& light, float pmf, const SurfaceHit& at,
                                  LightSample& out) const {
    out.is_delta = true;
    out.pdf = pmf;
    if (light.type == LightType::Directional) {
        out.wi = -light.direction;
        out.distance = kInfinity;
        out.radiance = light.intensity;
        return true;
    }
    const glm::vec3 to_light = light.position - at.position;
    const float distance2 = glm::dot(to_light, to_light);
    if (!(distance2 > 0.0f)) return false;
    const float distance = std::sqrt(distance2);
    out.wi = to_light / distance;
    out.distance = distance;
    float scale = rangeWindow(distance, light.range) / distance2;
    if (light.type == LightType::Spot) scale *= spotAttenuation(light, -out.wi);
    out.radiance = light.intensity * scale;
    return scale > 0.0f;
}

bool LightSampler::sampleSky(float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const {
    if (scene_.sky.map) {
        float uv_pdf = 0.0f;
        const glm::vec2 uv = sky_map_distribution_.sample(u, &uv_pdf);
        const float sin_theta = std::sin(uv.y * kPi);
        if (!(uv_pdf > 0.0f) || sin_theta <= 0.0f) return false;
        out.wi = equirectToDirection(uv);
        out.pdf = pmf * uv_pdf / (2.0f * kPi * kPi * sin_theta);
    } else {
        // A uniform sky is best sampled by the cosine lobe of the receiving surface.
        out.wi = Frame(at.shading_normal).toWorld(sampleCosineHemisphere(u));
        out.pdf = pmf * std::max(0.0f, glm::dot(out.wi, at.shading_normal)) * kInvPi;
    }
    out.distance = kInfinity;
    out.radiance = skyRadiance(out.wi);
    out.is_delta = false;
    return out.pdf > 0.0f;
}

float LightSampler::pdfEmitter(glm::vec3 from, const SurfaceHit& emitter) const {
    if (triangle_pmf_.empty()) return 0.0f;
    const float pmf = triangle_pmf_[emitter.triangle];
    if (pmf <= 0.0f) return 0.0f;
    const glm::vec3 to_light = emitter.position - from;
    const float distance2 = glm::dot(to_light, to_light);
    const float cos_light = std::abs(glm::dot(emitter.face_normal, to_light)) / std::sqrt(distance2);
    if (!(cos_light > 0.0f)) return 0.0f;
    return pmf * distance2 / (triangle_area_[emitter.triangle] * cos_light);
}

float LightSampler::skyDirectionPdf(glm::vec3 shading_normal, glm::vec3 direction) const {
    if (scene_.sky.map) {
        const glm::vec2 uv = directionToEquirect(direction);
        const float sin_theta = std::sin(uv.y * kPi);
        if (sin_theta <= 0.0f) return 0.0f;
        return sky_map_distribution_.pdf(uv) / (2.0f * kPi * kPi * sin_theta);
    }
    return std::max(0.0f, glm::dot(direction, shading_normal)) * kInvPi;
}

float LightSampler::pdfSky(glm::vec3 shading_normal, glm::vec3 direction) const {
    return has_sky_ ? sky_pmf_ * skyDirectionPdf(shading_normal, direction) : 0.0f;
}

glm::vec3 LightSampler::skyRadiance(glm::vec3 direction) const {
    const Sky& sky = scene_.sky;
    if (sky.map) return glm::vec3(sky.map->sample(directionToEquirect(direction))) * sky.scale;
    return sky.uniform;
}

}  // namespace sharcbake
