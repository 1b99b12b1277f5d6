// SPDX-License-Identifier: Apache-2.0
/// @file surface.h
/// @brief A ray's hit point reconstructed from the scene, and the material evaluated there.
#pragma once

#include "sharcbake/scene.h"
#include "tracing/tracer.h"

#include <glm/glm.hpp>

namespace sharcbake {

/// The geometry at a hit, oriented towards the incoming ray: both normals face the side the
/// ray came from, so reflection happens in the hemisphere around them.
struct SurfaceHit {
    glm::vec3 position{0.0f};
    glm::vec3 geometric_normal{0.0f, 0.0f, 1.0f};  ///< unit, facing the incoming ray
    glm::vec3 shading_normal{0.0f, 0.0f, 1.0f};    ///< unit, same hemisphere as geometric_normal
    glm::vec3 face_normal{0.0f, 0.0f, 1.0f};       ///< unit, from the winding (not flipped)
    float ray_offset = 0.0f;                       ///< rayOffsetFor the triangle: how far rays leaving it start off it
    bool front_face = true;  ///< the ray hit the side the winding's normal points to
    glm::vec2 uv0{0.0f};
    glm::vec2 uv1{0.0f};
    glm::vec4 color{1.0f};  ///< COLOR_0 (white where the scene has none)
    uint32_t triangle = 0;
    uint32_t material = 0;
};

/// Builds the hit from barycentrics. ray_direction is the direction the ray travelled.
SurfaceHit makeSurfaceHit(const Scene& scene, const RayHit& hit, glm::vec3 ray_direction);

/// Starts loading what makeSurfaceHit() reads of `triangle` first: its vertex indices and its
/// material index. Wavefront loops call it for a whole batch of hits, then
/// prefetchSurfaceVertices() for the same batch, so the misses of a large scene overlap.
void prefetchSurfaceTriangle(const Scene& scene, uint32_t triangle);

/// Starts loading the vertex attributes makeSurfaceHit() interpolates (positions, normals and
/// texture coordinates where the scene has them). Reads the triangle's indices.
void prefetchSurfaceVertices(const Scene& scene, uint32_t triangle);

/// Surface point on a triangle from barycentrics (b1, b2) of vertices 1 and 2, oriented along
/// the winding's normal (used for light sampling, where there is no incoming ray).
SurfaceHit makeSurfacePoint(const Scene& scene, uint32_t triangle, float b1, float b2);

/// What light sampling needs of a point on an emissive triangle: where it is, which way the
/// winding faces and what it emits. The same values as makeSurfacePoint() and
/// evaluateMaterial() give, without the shading frame and the BSDF inputs they also build.
struct EmitterPoint {
    glm::vec3 position{0.0f};
    glm::vec3 face_normal{0.0f, 0.0f, 1.0f};  ///< unit, from the winding
    glm::vec3 emission{0.0f};                 ///< ShadingMaterial::emission there
    bool double_sided = false;
};
EmitterPoint makeEmitterPoint(const Scene& scene, uint32_t triangle, float b1, float b2);

/// True where a ray passes through the surface at barycentrics (b1, b2) of `triangle`: its
/// material is MASK with alpha below the cut-off, or BLEND and this point's fixed random number
/// is at least alpha. Alpha is baseColorFactor.a x base colour texture alpha x COLOR_0 alpha.
/// Deterministic: the same point gives the same answer on every ray and thread.
bool isCutOut(const Scene& scene, uint32_t triangle, float b1, float b2);

/// glTF material parameters after texture lookups at one point.
struct ShadingMaterial {
    glm::vec3 base_color{1.0f};
    float metallic = 0.0f;
    float roughness = 1.0f;
    float specular_weight = 1.0f;      ///< KHR_materials_specular: factor x texture alpha
    glm::vec3 specular_color{1.0f};    ///< KHR_materials_specular: factor x texture rgb
    float ior = 1.5f;
    float clearcoat = 0.0f;            ///< KHR_materials_clearcoat: factor x texture red
    float clearcoat_roughness = 0.0f;  ///< KHR_materials_clearcoat: factor x texture green
    glm::vec3 emission{0.0f};          ///< radiance emitted from the front (or both) sides
    bool double_sided = false;
};

/// Evaluates the material of the hit: factors times textures, as the glTF specification says.
ShadingMaterial evaluateMaterial(const Scene& scene, const SurfaceHit& hit);

/// Radiance emitted by the surface towards the incoming ray: the emission on the front side,
/// and on the back side only for double-sided materials.
inline glm::vec3 emittedRadiance(const SurfaceHit& hit, const ShadingMaterial& material) {
    return (hit.front_face || material.double_sided) ? material.emission : glm::vec3(0.0f);
}

}  // namespace sharcbake
