// SPDX-License-Identifier: Apache-2.0
/// @file fuzz_gltf_loader.cpp
/// @brief libFuzzer harness for the glTF loader (loadGltf on a .gltf or .glb file, everything it
/// reads: accessors, sparse accessors, node hierarchies, materials, textures, lights, cameras,
/// meshopt and Draco streams). Built and run by tests/scenes/fuzzed_loaders_test.sh.
///
/// Each input is written to a file of a private folder and loaded from there: as "scene.glb"
/// when it starts with the GLB magic, else as "scene.gltf". A file that loads must make a scene
/// whose vertices, shading normals and triangles' geometric normals are finite and whose
/// indices and material indices are in range; a file that does not load must fail with
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

/// The folder inputs are written into, made once per process (libFuzzer's workers are processes).
const std::filesystem::path& inputFolder() {
    static const std::filesystem::path folder = [] {
        std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("sharcbake-fuzz-gltf-" + std::to_string(::getpid()));
        std::filesystem::create_directories(dir);
        return dir;
    }();
    return folder;
}

void check(bool ok, const char* what) {
    if (ok) return;
    std::fprintf(stderr, "fuzz_gltf_loader: a loaded scene breaks its promise: %s\n", what);
    std::abort();
}

bool finite(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

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
    } catch (const sharcbake::SceneLoadError&) {
        // The expected outcome for most inputs.
    }
    std::filesystem::remove(path);
    return 0;
}
