// SPDX-License-Identifier: Apache-2.0
/// @file draco_mesh.h
/// @brief Decoding of KHR_draco_mesh_compression data for the glTF loader. Built as its own
/// shared library, libsharcbake_draco (scenes/CMakeLists.txt says why).
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace sharcbake {

/// What a Draco mesh decodes to: triangle corners as point indices, and the points' attributes.
class DracoMesh {
public:
    /// Decodes a Draco mesh (a bufferView's bytes). Throws std::runtime_error with Draco's
    /// message when the bytes are not a Draco triangle mesh.
    DracoMesh(const unsigned char* data, size_t size);
    ~DracoMesh();
    DracoMesh(const DracoMesh&) = delete;
    DracoMesh& operator=(const DracoMesh&) = delete;

    size_t pointCount() const;
    /// Three point indices per triangle.
    const std::vector<uint32_t>& indices() const { return indices_; }
    /// The attribute glTF's extension names by its unique id, `components` floats per point
    /// (integer data converted; normalized integers, or all integers when `normalize` is set,
    /// mapped to [0, 1] or [-1, 1]; missing components 0). Throws std::runtime_error if there
    /// is no such attribute.
    std::vector<float> attribute(int unique_id, int components, bool normalize) const;
    /// The attribute's own component count (0 if there is no such attribute).
    int componentCount(int unique_id) const;

private:
    struct Impl;
    Impl* impl_;
    std::vector<uint32_t> indices_;
};

}  // namespace sharcbake
