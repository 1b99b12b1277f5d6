// SPDX-License-Identifier: Apache-2.0
#include "tracing/surface.h"

#include "support/prefetch.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace sharcbake {
namespace {

glm::vec4 fetch(const Scene& scene, const TextureRef& ref, const SurfaceHit& hit) {
    if (!ref.isSet() || size_t(ref.texture) >= scene.textures.size()) return glm::vec4(1.0f);
    return scene.textures[size_t(ref.texture)].sample(ref.uv(hit.uv0, hit.uv1));
}

template <typename T>
T barycentric(const std::vector<T>& values, const glm::uvec3& tri, float b0, float b1, float b2) {
    return b0 * values[tri.x] + b1 * values[tri.y] + b2 * values[tri.z];
}

/// The texel of `ref` at barycentric (b0, b1, b2) of triangle `tri` (white where unset), for
/// the queries that need one texture at a point without its whole SurfaceHit.
glm::vec4 texelAt(const Scene& scene, const TextureRef& ref, const glm::uvec3& tri, float b0, float b1, float b2) {
    if (!ref.isSet() || size_t(ref.texture) >= scene.textures.size()) return glm::vec4(1.0f);
    const std::vector<glm::vec2>& uvs = ref.texcoord == 1 ? scene.texcoords1 : scene.texcoords0;
    const glm::vec2 uv = uvs.empty() ? glm::vec2(0.0f) : barycentric(uvs, tri, b0, b1, b2);
    return scene.textures[size_t(ref.texture)].sample(ref.transform.apply(uv));
}

/// Bends the (front-facing) shading normal by the material's tangent-space normal map: X along
/// the tangent, Y along the bitangent, Z along the normal, as glTF defines it. The result is
/// kept just above the surface, where a steep map would otherwise shade from behind it.
void applyNormalMap(const Scene& scene, const Material& m, const glm::uvec3& tri, float b0, float b1, float b2,
                    SurfaceHit& s) {
    const glm::vec4 t0 = scene.tangents[tri.x];
    const glm::vec3 n = s.shading_normal;
    glm::vec3 tangent = barycentric(scene.tangents, tri, b0, b1, b2);
    tangent -= n * glm::dot(n, tangent);
    const float length = glm::length(tangent);
    if (!(length > 1e-6f)) return;  // no tangent here (no UVs): leave the normal as it is
    tangent /= length;
    const glm::vec3 bitangent = glm::cross(n, tangent) * (t0.w < 0.0f ? -1.0f : 1.0f);
    const glm::vec3 texel = glm::vec3(scene.textures[size_t(m.normal_texture.texture)].sample(
                                m.normal_texture.uv(s.uv0, s.uv1))) * 2.0f - 1.0f;
    glm::vec3 mapped = tangent * (texel.x * m.normal_scale) + bitangent * (texel.y * m.normal_scale) + n * texel.z;
    constexpr float kLowestCosine = 0.01f;
    const float cosine = glm::dot(mapped, s.face_normal);
    if (cosine < kLowestCosine) mapped += s.face_normal * (kLowestCosine - cosine) * glm::length(mapped);
    const float mapped_length = glm::length(mapped);
    if (mapped_length > 1e-8f && std::isfinite(mapped_length)) s.shading_normal = mapped / mapped_length;
}

SurfaceHit interpolate(const Scene& scene, uint32_t triangle, float b1, float b2) {
    SurfaceHit s;
    const glm::uvec3 tri = scene.triangles[triangle];
    const float b0 = 1.0f - b1 - b2;
    // References: copies of the 12-byte vectors went through the stack, and reading them back
    // as 8-byte pairs stalled on store forwarding (the hottest instructions of the function).
    const glm::vec3 &p0 = scene.positions[tri.x], &p1 = scene.positions[tri.y], &p2 = scene.positions[tri.z];
    s.position = b0 * p0 + b1 * p1 + b2 * p2;
    s.face_normal = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    s.ray_offset = rayOffsetFor(p0, p1, p2, s.face_normal);
    s.geometric_normal = s.face_normal;
    s.shading_normal = s.face_normal;
    if (!scene.normals.empty()) {
        const glm::vec3 n = b0 * scene.normals[tri.x] + b1 * scene.normals[tri.y] +
                            b2 * scene.normals[tri.z];
        const float length = glm::length(n);
        if (length > 1e-8f && std::isfinite(length)) s.shading_normal = n / length;
    }
    // UVs only feed texture fetches: a scene without textures leaves them out.
    const bool textured = !scene.textures.empty();
    if (textured && !scene.texcoords0.empty()) {
        s.uv0 = b0 * scene.texcoords0[tri.x] + b1 * scene.texcoords0[tri.y] +
                b2 * scene.texcoords0[tri.z];
    }
    if (textured && !scene.texcoords1.empty()) {
        s.uv1 = b0 * scene.texcoords1[tri.x] + b1 * scene.texcoords1[tri.y] +
                b2 * scene.texcoords1[tri.z];
    }
    if (!scene.colors.empty()) s.color = barycentric(scene.colors, tri, b0, b1, b2);
    s.triangle = triangle;
    s.material = scene.triangle_materials[triangle];
    const Material& material = scene.materials[s.material];
    if (material.normal_texture.isSet() && !scene.tangents.empty()) applyNormalMap(scene, material, tri, b0, b1, b2, s);
    return s;
}

}  // namespace

void prefetchSurfaceTriangle(const Scene& scene, uint32_t triangle) {
    prefetchObjectForRead(&scene.triangles[triangle]);
    prefetchForRead(&scene.triangle_materials[triangle]);
}

void prefetchSurfaceVertices(const Scene& scene, uint32_t triangle) {
    const glm::uvec3 tri = scene.triangles[triangle];
    for (const uint32_t vertex : {tri.x, tri.y, tri.z}) {
        prefetchObjectForRead(&scene.positions[vertex]);
        if (!scene.normals.empty()) prefetchObjectForRead(&scene.normals[vertex]);
        if (!scene.textures.empty() && !scene.texcoords0.empty()) prefetchObjectForRead(&scene.texcoords0[vertex]);
    }
}

SurfaceHit makeSurfaceHit(const Scene& scene, const RayHit& hit, glm::vec3 ray_direction) {
    SurfaceHit s = interpolate(scene, hit.triangle, hit.u, hit.v);
    s.front_face = glm::dot(s.face_normal, ray_direction) < 0.0f;
    if (!s.front_face) s.geometric_normal = -s.face_normal;
    // Interpolated normals may point away from the viewer near silhouettes; keep the shading
    // normal in the geometric hemisphere so reflection stays on the side the ray is on.
    if (glm::dot(s.shading_normal, s.geometric_normal) < 0.0f) s.shading_normal = -s.shading_normal;
    return s;
}

SurfaceHit makeSurfacePoint(const Scene& scene, uint32_t triangle, float b1, float b2) {
    SurfaceHit s = interpolate(scene, triangle, b1, b2);
    if (glm::dot(s.shading_normal, s.geometric_normal) < 0.0f) s.shading_normal = -s.shading_normal;
    return s;
}

EmitterPoint makeEmitterPoint(const Scene& scene, uint32_t triangle, float b1, float b2) {
    // Each value by the same expression as interpolate() and evaluateMaterial(), so a light
    // sample is bit for bit what the full surface point would give.
    EmitterPoint e;
    const glm::uvec3 tri = scene.triangles[triangle];
    const float b0 = 1.0f - b1 - b2;
    const glm::vec3 &p0 = scene.positions[tri.x], &p1 = scene.positions[tri.y], &p2 = scene.positions[tri.z];
    e.position = barycentric(scene.positions, tri, b0, b1, b2);
    e.face_normal = glm::normalize(glm::cross(p1 - p0, p2 - p0));
    const Material& m = scene.materials[scene.triangle_materials[triangle]];
    e.double_sided = m.double_sided;
    if (!m.isEmissive()) return e;
    e.emission = m.emissive * m.emissive_strength * glm::vec3(texelAt(scene, m.emissive_texture, tri, b0, b1, b2));
    if (m.unlit && !scene.colors.empty()) e.emission *= glm::vec3(barycentric(scene.colors, tri, b0, b1, b2));
    return e;
}

bool isCutOut(const Scene& scene, uint32_t triangle, float b1, float b2) {
    const Material& m = scene.materials[scene.triangle_materials[triangle]];
    if (!m.cutsOut()) return false;
    const glm::uvec3 tri = scene.triangles[triangle];
    const float b0 = 1.0f - b1 - b2;
    const auto texel = [&](const TextureRef& ref) { return texelAt(scene, ref, tri, b0, b1, b2); };
    // The share of this point that stops rays: alpha for BLEND, and what transmission leaves.
    float opacity = 1.0f;
    if (m.alpha_mode != AlphaMode::Opaque) {
        float alpha = m.base_alpha;
        if (!scene.colors.empty()) alpha *= barycentric(scene.colors, tri, b0, b1, b2).a;
        if (m.base_color_texture.isSet()) alpha *= texel(m.base_color_texture).a;
        if (m.alpha_mode == AlphaMode::Mask) {
            if (alpha < m.alpha_cutoff) return true;
        } else {
            opacity = alpha;
        }
    }
    if (m.transmission > 0.0f) {
        float transmission = m.transmission;
        if (m.transmission_texture.isSet()) transmission *= texel(m.transmission_texture).r;
        opacity *= 1.0f - std::clamp(transmission, 0.0f, 1.0f);
    }
    if (opacity >= 1.0f) return false;
    // A fixed random number per point (triangle and barycentric bits), so the pattern is the
    // same for every ray and thread count, and opaque in a share `opacity` of the surface.
    uint32_t b1_bits, b2_bits;
    std::memcpy(&b1_bits, &b1, sizeof b1_bits);
    std::memcpy(&b2_bits, &b2, sizeof b2_bits);
    uint64_t h = (uint64_t(triangle) << 32 | b1_bits) * 0x9E3779B97F4A7C15ull ^ (uint64_t(b2_bits) * 0xC2B2AE3D27D4EB4Full);
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 29;
    return float(h >> 40) * 0x1.0p-24f >= opacity;
}

ShadingMaterial evaluateMaterial(const Scene& scene, const SurfaceHit& hit) {
    const Material& m = scene.materials[hit.material];
    ShadingMaterial out;
    out.base_color = m.base_color * glm::vec3(fetch(scene, m.base_color_texture, hit)) * glm::vec3(hit.color);
    const glm::vec4 mr = fetch(scene, m.metallic_roughness_texture, hit);
    out.metallic = glm::clamp(m.metallic * mr.b, 0.0f, 1.0f);
    out.roughness = glm::clamp(m.roughness * mr.g, 0.0f, 1.0f);
    out.specular_weight = glm::clamp(m.specular * fetch(scene, m.specular_texture, hit).a, 0.0f, 1.0f);
    out.specular_color = m.specular_color * glm::vec3(fetch(scene, m.specular_color_texture, hit));
    out.ior = m.ior;
    if (m.clearcoat > 0.0f) {
        out.clearcoat = glm::clamp(m.clearcoat * fetch(scene, m.clearcoat_texture, hit).r, 0.0f, 1.0f);
        out.clearcoat_roughness = glm::clamp(m.clearcoat_roughness * fetch(scene, m.clearcoat_roughness_texture, hit).g,
                                             0.0f, 1.0f);
    }
    if (m.isEmissive()) {
        out.emission = m.emissive * m.emissive_strength * glm::vec3(fetch(scene, m.emissive_texture, hit));
        if (m.unlit) out.emission *= glm::vec3(hit.color);  // the base colour's vertex colours
    }
    out.double_sided = m.double_sided;
    return out;
}

}  // namespace sharcbake
