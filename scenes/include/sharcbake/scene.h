// SPDX-License-Identifier: Apache-2.0
/// @file scene.h
/// @brief The renderer's view of a static scene: world-space triangles, glTF materials,
/// punctual lights, cameras and the sky. Everything is flattened to world space at load time,
/// so the tracer never walks a node hierarchy.
///
/// Units and conventions follow glTF 2.0: metres, right-handed, +Y up, cameras look down -Z.
/// Radiometric quantities are in the renderer's linear units (emission factor x strength is
/// radiance; punctual lights are converted from photometric glTF units with 683 lm/W).
#pragma once

#include <glm/glm.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace sharcbake {

/// The largest |coordinate| (scene units) anything may have in world space: the loader refuses
/// vertices beyond it and skips cameras and lights beyond it, and camera paths may not leave it.
/// Embree asserts on rays that start beyond about 1.8e18; 1e9 m is far beyond any real scene.
inline constexpr double kMaxWorldCoordinate = 1e9;

/// Whether every coordinate of `p` lies within +-kMaxWorldCoordinate (false for NaN).
inline bool withinWorldLimit(const glm::dvec3& p) {
    return p.x >= -kMaxWorldCoordinate && p.x <= kMaxWorldCoordinate && p.y >= -kMaxWorldCoordinate &&
           p.y <= kMaxWorldCoordinate && p.z >= -kMaxWorldCoordinate && p.z <= kMaxWorldCoordinate;
}

/// How texture coordinates outside [0,1] are mapped (glTF sampler wrap modes).
enum class WrapMode : uint8_t { Repeat, ClampToEdge, MirroredRepeat };

/// How a texture's texels are stored, and so how a lookup turns them into linear values.
enum class TexelEncoding : uint8_t {
    Float,   ///< `texels`: linear RGBA floats (16-bit images, EXR skies, converted textures)
    Srgb8,   ///< `texels8`: RGBA8 whose colour channels are sRGB-encoded; alpha is linear
    Linear8  ///< `texels8`: RGBA8 read as linear values (data textures: roughness, normals, ...)
};

/// The linear value of an sRGB-encoded 8-bit code, and of a linear (unorm) one: the 256-entry
/// tables 8-bit texels are decoded through. Both are computed once, with the same arithmetic the
/// loader used when it stored every texel as a float, so a lookup gives the same bits.
const std::array<float, 256>& srgb8ToLinear();
const std::array<float, 256>& unorm8ToFloat();

/// sRGB transfer function to linear (IEC 61966-2-1), for one value in [0, 1].
float srgbToLinear(float c);

/// A decoded texture, row 0 at the top (glTF/image convention, v = 0 is the first row). Lookups
/// return linear-light RGBA: sRGB-encoded images (base colour, emissive, specular colour) are
/// decoded per lookup through a 256-entry table. 8-bit images are kept as 8-bit RGBA (4 bytes a
/// texel instead of 16 as floats), shared between the sRGB and the linear texture when one
/// image is used both as colour and as data; 16-bit images are kept as linear floats.
struct Texture {
    std::string name;
    int width = 0;
    int height = 0;
    TexelEncoding encoding = TexelEncoding::Float;
    std::vector<glm::vec4> texels;  ///< Float: width * height, row-major
    /// Srgb8 and Linear8: width * height RGBA texels, row-major; shared (read-only) by the
    /// textures that read one image in different colour spaces.
    std::shared_ptr<const std::vector<glm::u8vec4>> texels8;
    WrapMode wrap_s = WrapMode::Repeat;
    WrapMode wrap_t = WrapMode::Repeat;
    bool nearest = false;  ///< magnification filter NEAREST; otherwise bilinear

    /// Bilinear (or nearest) lookup with the texture's wrap modes. uv in glTF convention.
    glm::vec4 sample(glm::vec2 uv) const;

    /// The number of texels stored: width * height, or 0 for an empty texture.
    size_t texelCount() const;

    /// Texel `index` (row-major) as linear RGBA, decoded as `sample` decodes it.
    glm::vec4 texel(size_t index) const {
        if (encoding == TexelEncoding::Float) return texels[index];
        const glm::u8vec4 t = (*texels8)[index];
        const std::array<float, 256>& colour = encoding == TexelEncoding::Srgb8 ? srgb8ToLinear() : unorm8ToFloat();
        const std::array<float, 256>& linear = unorm8ToFloat();
        return {colour[t.x], colour[t.y], colour[t.z], linear[t.w]};
    }
};

/// KHR_texture_transform: an affine map from a mesh's UVs to the texture's,
/// uv' = offset + rotation(angle) * (scale * uv), where the rotation turns UVs counter-clockwise
/// in glTF's v-down texture space: u' = u cos + v sin, v' = v cos - u sin (before the offset).
struct UvTransform {
    glm::vec2 column_u{1.0f, 0.0f};  ///< what one unit of u becomes
    glm::vec2 column_v{0.0f, 1.0f};  ///< what one unit of v becomes
    glm::vec2 offset{0.0f};
    bool identity = true;  ///< no extension: the UVs are used as they are, bit for bit

    static UvTransform fromGltf(glm::vec2 offset, float rotation, glm::vec2 scale);
    glm::vec2 apply(glm::vec2 uv) const { return identity ? uv : column_u * uv.x + column_v * uv.y + offset; }
};

/// A material's reference to a texture: index into Scene::textures, which UV set to use and
/// the UV transform (KHR_texture_transform) applied before the lookup.
struct TextureRef {
    int32_t texture = -1;   ///< -1: no texture
    uint32_t texcoord = 0;  ///< 0 = TEXCOORD_0, 1 = TEXCOORD_1
    UvTransform transform;
    bool isSet() const { return texture >= 0; }
    /// The texture's UV at a point whose two UV sets are uv0 and uv1.
    glm::vec2 uv(glm::vec2 uv0, glm::vec2 uv1) const { return transform.apply(texcoord == 1 ? uv1 : uv0); }
};

/// glTF alphaMode. MASK cuts out where alpha < alpha_cutoff; BLEND is traced as a stochastic
/// cut-out (a surface point is opaque with probability alpha, fixed per point), which transmits
/// light in proportion to 1 - alpha the way Blender's "alpha hashed" mode does.
enum class AlphaMode : uint8_t { Opaque, Mask, Blend };

/// glTF PBR metallic-roughness with KHR_materials_emissive_strength and KHR_materials_specular.
/// Texture values multiply the factors, as the glTF specification says.
struct Material {
    std::string name;
    glm::vec3 base_color{1.0f};
    TextureRef base_color_texture;
    float metallic = 1.0f;
    float roughness = 1.0f;
    TextureRef metallic_roughness_texture;  ///< B = metallic, G = roughness
    glm::vec3 emissive{0.0f};               ///< emissiveFactor (linear)
    float emissive_strength = 1.0f;         ///< KHR_materials_emissive_strength
    TextureRef emissive_texture;
    float specular = 1.0f;                  ///< KHR_materials_specular specularFactor
    glm::vec3 specular_color{1.0f};         ///< KHR_materials_specular specularColorFactor
    TextureRef specular_texture;            ///< A channel
    TextureRef specular_color_texture;      ///< RGB
    float ior = 1.5f;                       ///< KHR_materials_ior (1.5 when absent)
    float clearcoat = 0.0f;                 ///< KHR_materials_clearcoat clearcoatFactor
    TextureRef clearcoat_texture;           ///< R channel (linear)
    float clearcoat_roughness = 0.0f;       ///< clearcoatRoughnessFactor
    TextureRef clearcoat_roughness_texture;  ///< G channel (linear)
    bool double_sided = false;
    TextureRef normal_texture;              ///< tangent-space normal map (linear RGB)
    float normal_scale = 1.0f;              ///< scales the map's X and Y
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float alpha_cutoff = 0.5f;              ///< MASK threshold
    float base_alpha = 1.0f;                ///< baseColorFactor's alpha
    /// KHR_materials_transmission transmissionFactor, traced as thin see-through glass: each
    /// point lets rays through (unbent, untinted) with this probability (times the texture's R).
    float transmission = 0.0f;
    TextureRef transmission_texture;        ///< R channel (linear)
    /// KHR_materials_unlit: the surface shows its base colour whatever the light. The loader
    /// moves that colour into the emission (factor and texture; the base colour turns black, so
    /// nothing is reflected); this flag makes the emission follow the vertex colours too, as the
    /// base colour did.
    bool unlit = false;

    /// True when rays may pass through some of this material's surface.
    bool cutsOut() const { return alpha_mode != AlphaMode::Opaque || transmission > 0.0f; }

    /// True when some surface with this material emits light.
    bool isEmissive() const {
        return emissive_strength > 0.0f &&
               (emissive.x > 0.0f || emissive.y > 0.0f || emissive.z > 0.0f);
    }
    bool hasTextures() const {
        return base_color_texture.isSet() || metallic_roughness_texture.isSet() || emissive_texture.isSet() ||
               specular_texture.isSet() || specular_color_texture.isSet() || normal_texture.isSet() ||
               clearcoat_texture.isSet() || clearcoat_roughness_texture.isSet();
    }
};

/// KHR_lights_punctual, converted to radiometric units.
enum class LightType : uint8_t { Point, Spot, Directional };

struct PunctualLight {
    std::string name;  ///< the KHR_lights_punctual light's own name (Blender: the light data's)
    /// The name of the glTF node that places the light; empty when it has none. Blender names the
    /// node after the object ("Lamp") and the light after its data ("Point"), and users know a
    /// light by the object's name.
    std::string node_name;
    LightType type = LightType::Point;
    glm::vec3 position{0.0f};            ///< world space (point, spot)
    glm::vec3 direction{0.0f, 0.0f, -1.0f};  ///< world-space direction the light travels (spot, directional)
    /// Point/spot: radiant intensity in W/sr (candela / 683).
    /// Directional: irradiance in W/m^2 on a surface facing the light (lux / 683).
    glm::vec3 intensity{0.0f};
    /// 0 = infinite. Beyond it the light gives nothing; within it the inverse square law is
    /// windowed by KHR_lights_punctual's recommended clamp(1 - (d/range)^4, 0, 1).
    float range = 0.0f;
    float inner_cone_angle = 0.0f;                    ///< spot, radians
    float outer_cone_angle = 0.785398163397448f;      ///< spot, radians (pi/4 default)
};

/// A pinhole camera, from a glTF node with a perspective camera or from the command line.
struct Camera {
    /// The glTF camera's own name (`cameras[i].name`; empty when it has none), or what the tool
    /// calls a camera it makes ("--look-at", "automatic").
    std::string name;
    /// The name of the glTF node that places the camera; empty when it has none. Blender's
    /// exporter names the node after the object ("Persp") and the camera after the object's
    /// camera data ("Camera.001"), so users know a camera by this name.
    std::string node_name;
    /// Its index in Scene::cameras, for a camera of the scene; -1 for one the tool makes.
    int32_t index = -1;
    glm::vec3 position{0.0f};
    glm::vec3 forward{0.0f, 0.0f, -1.0f};  ///< unit, world space
    glm::vec3 up{0.0f, 1.0f, 0.0f};        ///< unit, orthogonal to forward
    float yfov = 0.8f;                     ///< vertical field of view, radians (perspective cameras)
    std::optional<float> aspect_ratio;     ///< width / height if the glTF camera gives one
    /// Orthographic cameras: half the view's height in scene units (glTF `ymag`; `aspect_ratio`
    /// is xmag / ymag). Rays leave the view rectangle in parallel; `yfov` is not used for them.
    std::optional<float> orthographic_half_height;
    /// The clip planes (glTF `znear`, `zfar`; Blender's clip start and end): distances along
    /// `forward` from the camera's position, in world units, between which it sees. Geometry nearer
    /// than `znear` is not seen (a camera outside a room with its near plane past the wall sees the
    /// room's inside); beyond `zfar` the view sees the sky. 0 and no far plane for the cameras the
    /// tool makes.
    float znear = 0.0f;
    std::optional<float> zfar;
};

/// How messages name a camera, so that the user can pick it with `render --camera`: by its node's
/// name, with the glTF camera's when that differs ("camera 'Persp' (glTF camera 'Camera.001')"),
/// else by the glTF camera's name, else by its index ("camera #3"). Names are made printable.
std::string cameraLabel(const Camera& camera);

/// One camera in a list of the scene's cameras, every name given: "#0 node 'Persp', glTF camera
/// 'Camera'", "#3 (no names)".
std::string cameraListEntry(const Camera& camera);

/// The environment seen by rays that leave the scene. Either a uniform radiance or an
/// equirectangular (lat-long) map; the map is multiplied by `scale`.
struct Sky {
    glm::vec3 uniform{0.0f};
    std::optional<Texture> map;  ///< equirectangular, +Y up, u = 0 at -X? see sky.h for the mapping
    float scale = 1.0f;
    bool isBlack() const {
        return !map && uniform.x <= 0.0f && uniform.y <= 0.0f && uniform.z <= 0.0f;
    }
};

/// Counters the loader fills so the CLI can say what it dropped or assumed.
struct LoadStats {
    uint64_t triangles_loaded = 0;
    uint64_t degenerate_triangles_dropped = 0;  ///< zero area or repeated indices
    /// Of those, triangles with area in double precision that rounding their world positions to
    /// float32 collapsed (a model far from the origin).
    uint64_t triangles_collapsed_by_rounding = 0;
    /// Of those, triangles with area whose float32 normal underflows (edges of about 1e-9 units or
    /// less: a model far too small in its units).
    uint64_t triangles_too_small_for_float = 0;
    uint64_t primitives_skipped = 0;            ///< non-triangle modes (points, lines)
    std::vector<std::string> warnings;          ///< human-readable, one per issue
};

/// The whole scene, flattened to world space.
struct Scene {
    std::string source_path;
    /// Every file the scene was read from, each once, in the order the glTF parser read them:
    /// the glTF or GLB file, then its external buffers and images (a missing image, ignored
    /// with a warning, is not among them). A content hash of the scene must cover them all: a
    /// .gltf's geometry lives in its .bin.
    std::vector<std::string> source_files;

    // Geometry: one indexed triangle soup in world space. Vertex attributes are per vertex;
    // triangles index them; each triangle has a material index.
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;     ///< empty, or one per vertex (unit, world space)
    std::vector<glm::vec2> texcoords0;  ///< empty, or one per vertex
    std::vector<glm::vec2> texcoords1;  ///< empty, or one per vertex
    std::vector<glm::vec4> colors;      ///< COLOR_0 (linear RGBA); empty, or one per vertex
    /// Unit tangent (xyz) and the bitangent's sign (w), for normal maps; empty, or one per vertex
    /// (TANGENT, or computed from TEXCOORDs where a normal-mapped primitive has none).
    std::vector<glm::vec4> tangents;
    std::vector<glm::uvec3> triangles;
    std::vector<uint32_t> triangle_materials;

    std::vector<Material> materials;  ///< never empty after loading (a default is appended if needed)
    std::vector<Texture> textures;
    std::vector<PunctualLight> lights;
    std::vector<Camera> cameras;
    Sky sky;
    LoadStats stats;

    /// The outgoing radiance of every surface when the scene says it is known (a furnace room:
    /// root extras {"sharcbake": {"expected_radiance": L or [r, g, b]}}). Convergence reports
    /// measure the cache against it.
    std::optional<glm::vec3> known_radiance;

    /// Axis-aligned bounds of all triangles (min, max). Both zero for an empty scene.
    glm::vec3 bounds_min{0.0f};
    glm::vec3 bounds_max{0.0f};

    bool empty() const { return triangles.empty(); }
};

/// "material 'Wood'", or "material #3" for one without a name. Names are made printable.
std::string materialLabel(const Scene& scene, uint32_t material);

/// "point light 'Lamp' (glTF light 'Point')", "directional light 'Sun'", "spot light #2": the
/// light's kind and its node's name, with the glTF light's where that differs, else the glTF
/// light's name, else its index. Names are made printable.
std::string lightLabel(const Scene& scene, size_t light);

}  // namespace sharcbake
