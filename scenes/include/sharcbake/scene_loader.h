// SPDX-License-Identifier: Apache-2.0
/// @file scene_loader.h
/// @brief Loading glTF 2.0 scenes (.gltf and .glb) and equirectangular EXR skies.
#pragma once

#include "sharcbake/scene.h"

#include <cstdint>
#include <stdexcept>
#include <string>

namespace sharcbake {

/// Thrown for any file that cannot be loaded. what() names the file and the problem, e.g.
/// "scene.gltf: accessor 3 (indices of mesh 'Floor'): index 812 out of range (412 vertices)".
/// kind() tells a wrong file from one the scene needs that is not there (an external buffer).
class SceneLoadError : public std::runtime_error {
public:
    enum class Kind {
        kInvalid,     ///< the content is wrong
        kMissingFile  ///< a file the scene names (a buffer) is not there
    };
    explicit SceneLoadError(const std::string& what, Kind kind = Kind::kInvalid)
        : std::runtime_error(what), kind_(kind) {}
    Kind kind() const { return kind_; }

private:
    Kind kind_;
};

/// Loads a glTF 2.0 file (.gltf with external or embedded buffers, or .glb) and flattens the
/// default scene (or scene 0) into world space. Degenerate triangles are dropped and counted
/// in Scene::stats; anything that would make the scene wrong (missing buffer, index out of
/// range, NaN/Inf vertex, unsupported required extension) throws SceneLoadError.
/// Bounds for untrusted scenes. Buffers and images are read only from the scene's folder or below;
/// an accessor without a bufferView holds at most max(65,536, bytes of the scene's buffers)
/// elements; JSON nesting deeper than 256 and world coordinates beyond +-1e9 m are refused.
struct GltfLoadLimits {
    /// Images wider or taller than this are refused before they are decoded (a 249 KB PNG of
    /// 16000x16000 texels decodes to 1 GB of 8-bit texels).
    uint32_t max_texture_size = 8192;
};
Scene loadGltf(const std::string& path, const GltfLoadLimits& limits = {});

/// Reads an equirectangular (lat-long) environment map from an OpenEXR file into a linear
/// texture. Throws SceneLoadError with the file name on failure.
/// Mapping (the same as Blender's, converted to glTF's +Y-up axes): for a unit direction d,
///   u = 0.5 + atan2(d.z, d.x) / (2 pi),  v = acos(d.y) / pi   (v = 0 is the top row, +Y).
Texture loadEquirectExr(const std::string& path);

}  // namespace sharcbake
