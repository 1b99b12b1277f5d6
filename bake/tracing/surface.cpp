// SPDX-License-Identifier: Apache-2.0
#include "tracing/surface.h"

#include <cmath>

namespace sharcbake {
namespace {

glm::vec4 fetch(const Scene& scene, const TextureRef& ref, const SurfaceHit& hit) {
    if (!ref.isSet() || size_t(ref.texture) >= scene.textures.size()) return glm::vec4(1.0f);
    return scene.textures[size_t(ref.texture)].sample(ref.texcoord == 1 ? hit.uv1 : hit.uv0);
}

SurfaceHit interpolate(const Scene& scene, uint32_t triangle, float b1, float b2) {
    SurfaceHit s;
    const glm::uvec3 tri = scene.triangles[triangle];
    const float b0 = 1.0f - b1 - b2;
    const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y],
                    p2 = scene.positions[tri.z];
    s.position = b0 * p0 + b1 * p1 + b2 * p2;
    s.face_normal = glm::normalize(glm::cross(p1 - p0, p2 - p0));
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
    s.triangle = triangle;
    s.material = scene.triangle_materials[triangle];
    return s;
}

}  // namespace

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

ShadingMaterial evaluateMaterial(const Scene& scene, const SurfaceHit& hit) {
    const Material& m = scene.materials[hit.material];
    ShadingMaterial out;
    out.base_color = m.base_color * glm::vec3(fetch(scene, m.base_color_texture, hit));
    const glm::vec4 mr = fetch(scene, m.metallic_roughness_texture, hit);
    out.metallic = glm::clamp(m.metallic * mr.b, 0.0f, 1.0f);
    out.roughness = glm::clamp(m.roughness * mr.g, 0.0f, 1.0f);
    out.specular_weight = glm::clamp(m.specular * fetch(scene, m.specular_texture, hit).a, 0.0f, 1.0f);
    out.specular_color = m.specular_color * glm::vec3(fetch(scene, m.specular_color_texture, hit));
    out.ior = m.ior;
    if (m.isEmissive()) {
        out.emission = m.emissive * m.emissive_strength * glm::vec3(fetch(scene, m.emissive_texture, hit));
    }
    out.double_sided = m.double_sided;
    return out;
}

}  // namespace sharcbake
