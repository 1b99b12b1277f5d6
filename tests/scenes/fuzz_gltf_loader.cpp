// SPDX-License-Identifier: Apache-2.0
/// @file fuzz_gltf_loader.cpp
/// @brief libFuzzer harness for the glTF loader (loadGltf on a .gltf or .glb file, everything it
/// reads: accessors, sparse accessors, node hierarchies, materials, textures, lights, cameras,
/// meshopt and Draco streams). Built and run by tests/scenes/fuzzed_loaders_test.sh.
///
/// Each input is written to a file of a private folder and loaded from there: as "scene.glb"
/// when it starts with the GLB magic, else as "scene.gltf". A file that loads must make a scene
/// whose vertices, shading normals and triangles' geometric normals are finite, whose indices
/// and material indices are in range, and whose cameras, lights, materials and sky are what the
/// tracer assumes (checkCamerasAndLights); a file that does not load must fail with
/// SceneLoadError (never another exception, a crash or a sanitizer report).
#include "sharcbake/scene_loader.h"

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

/// The folder inputs are written into, made once per process (libFuzzer's workers are processes)
/// and removed when it exits: a search by hand ran a dozen workers, each leaving one in /tmp.
struct ScratchFolder {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("sharcbake-fuzz-gltf-" + std::to_string(::getpid()));
    ScratchFolder() { std::filesystem::create_directories(path); }
    ~ScratchFolder() {
        std::error_code ignored;
        std::filesystem::remove_all(path, ignored);
    }
};

const std::filesystem::path& inputFolder() {
    static const ScratchFolder folder;
    return folder.path;
}

void check(bool ok, const char* what) {
    if (ok) return;
    std::fprintf(stderr, "fuzz_gltf_loader: a loaded scene breaks its promise: %s\n", what);
    std::abort();
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool unit(const glm::vec3& v) { return finite(v) && std::abs(glm::length(v) - 1.0f) < 1e-3f; }
bool nonNegative(const glm::vec3& v) { return finite(v) && v.x >= 0.0f && v.y >= 0.0f && v.z >= 0.0f; }

/// What the tracer assumes of cameras and lights: rays from them start inside the world's limit
/// (Embree aborts on rays from beyond about 1.8e18), in unit directions, with finite amounts.
void checkCamerasAndLights(const sharcbake::Scene& scene) {
    for (const sharcbake::Camera& c : scene.cameras) {
        check(sharcbake::withinWorldLimit(c.position), "a camera beyond the world's limit");
        check(unit(c.forward) && unit(c.up), "a camera's forward or up is not a unit vector");
        check(c.yfov > 0.0f && c.yfov < 3.1416f, "a camera's yfov is outside (0, pi)");
        check(!c.aspect_ratio || (*c.aspect_ratio > 0.0f && std::isfinite(*c.aspect_ratio)),
              "a camera's aspect ratio is not positive");
        check(!c.orthographic_half_height ||
                  (*c.orthographic_half_height > 0.0f && *c.orthographic_half_height <= sharcbake::kMaxWorldCoordinate),
              "an orthographic view is not positive or wider than the world's limit");
    }
    for (const sharcbake::PunctualLight& l : scene.lights) {
        check(l.type == sharcbake::LightType::Directional || sharcbake::withinWorldLimit(l.position),
              "a point or spot light beyond the world's limit");
        check(unit(l.direction), "a light's direction is not a unit vector");
        check(nonNegative(l.intensity), "a light's intensity is negative or not finite");
        check(std::isfinite(l.range) && l.range >= 0.0f, "a light's range is negative or not finite");
        check(std::isfinite(l.inner_cone_angle) && std::isfinite(l.outer_cone_angle) && l.inner_cone_angle >= 0.0f &&
                  l.inner_cone_angle <= l.outer_cone_angle && l.outer_cone_angle <= 1.5708f,
              "a spot's cone angles are outside 0 <= inner <= outer <= pi/2");
    }
    for (const sharcbake::Material& m : scene.materials) {
        check(nonNegative(m.base_color) && nonNegative(m.emissive) && nonNegative(m.specular_color),
              "a material's colour is negative or not finite");
        check(std::isfinite(m.emissive_strength) && m.emissive_strength >= 0.0f, "an emissive strength");
        check(std::isfinite(m.metallic) && std::isfinite(m.roughness) && std::isfinite(m.ior) &&
                  std::isfinite(m.transmission) && std::isfinite(m.clearcoat) && std::isfinite(m.normal_scale),
              "a material's factor is not finite");
    }
    check(nonNegative(scene.sky.uniform) && std::isfinite(scene.sky.scale) && scene.sky.scale >= 0.0f,
          "the sky is negative or not finite");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const bool glb = size >= 4 && std::memcmp(data, "glTF", 4) == 0;
    const std::filesystem::path path = inputFolder() / (glb ? "scene.glb" : "scene.gltf");
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    try {
        // Small textures keep a mutated image size from spending the run on decoding.
        sharcbake::GltfLoadLimits limits;
        limits.max_texture_size = 256;
        const sharcbake::Scene scene = sharcbake::loadGltf(path.string(), limits);
        check(!scene.materials.empty(), "no materials");
        check(scene.triangle_materials.size() == scene.triangles.size(), "a triangle without a material");
        for (const glm::vec3& p : scene.positions) check(finite(p), "a vertex is not finite");
        for (size_t i = 0; i < scene.triangles.size(); ++i) {
            const glm::uvec3& t = scene.triangles[i];
            const size_t vertices = scene.positions.size();
            check(t.x < vertices && t.y < vertices && t.z < vertices, "an index is out of range");
            // What the tracer does with each triangle it hits: no NaN geometric normal.
            const glm::vec3 normal = glm::normalize(
                glm::cross(scene.positions[t.y] - scene.positions[t.x], scene.positions[t.z] - scene.positions[t.x]));
            check(finite(normal), "a triangle's geometric normal is not finite");
            check(scene.triangle_materials[i] < scene.materials.size(), "a material index is out of range");
        }
        check(scene.normals.empty() || scene.normals.size() == scene.positions.size(), "normals of another count");
        for (const glm::vec3& n : scene.normals) check(finite(n), "a shading normal is not finite");
        check(scene.texcoords0.empty() || scene.texcoords0.size() == scene.positions.size(),
              "texcoords of another count");
        check(scene.tangents.empty() || scene.tangents.size() == scene.positions.size(), "tangents of another count");
        checkCamerasAndLights(scene);
    } catch (const sharcbake::SceneLoadError&) {
        // The expected outcome for most inputs.
    }
    std::filesystem::remove(path);
    return 0;
}
