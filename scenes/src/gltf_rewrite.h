// SPDX-License-Identifier: Apache-2.0
/// @file gltf_rewrite.h
/// @brief Compressed glTF and image data URIs made parseable by tinygltf 2.7, before it parses
/// (the loader's helper).
///
/// tinygltf 2.7 cannot parse what some glTF pipelines write:
/// - KHR_draco_mesh_compression declares each primitive's indices with an accessor without a
///   bufferView (they are in the Draco data), which tinygltf refuses. Those `indices` are removed,
///   their counts kept; the loader decodes the Draco data itself (draco_mesh.h).
/// - EXT_meshopt_compression (gltfpack) keeps bufferViews compressed in one buffer and declares a
///   "fallback" buffer without data, which tinygltf refuses. Every bufferView is decoded
///   (meshoptimizer) or copied into one new binary buffer, and the file becomes a GLB.
/// - tinygltf refuses the whole file for one image `data:` URI of a type it does not know
///   (image/webp, image/ktx2) or without base64 data, where the loader reads images by their
///   content and drops only the textures of an image it cannot decode. The first gets a neutral
///   type; the second is replaced by one byte no decoder reads, and why is kept for the warning.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>

namespace sharcbake {

/// Compressed data that cannot be decoded, or a view outside its buffer: the message says
/// which bufferView or buffer, and what is wrong.
class GltfRewriteError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// The file as tinygltf can parse it.
struct TinygltfInput {
    std::string bytes;
    bool glb = false;
    /// (mesh, primitive) -> the count of the `indices` accessor removed from a Draco primitive.
    std::map<std::pair<int, int>, uint64_t> draco_index_counts;
    /// glTF image index -> why its `data:` URI was set aside (it holds no base64 data).
    std::map<int, std::string> refused_image_uris;
};

/// Reads an external buffer by its (relative) URI, with the caller's rules for which files a
/// scene may read; throws GltfRewriteError when it may not or cannot.
using ReadBufferFile = std::function<std::string(const std::string& uri)>;

/// True when the file's bytes mention either compression, or hold a `data:` URI tinygltf
/// refuses (a cheap test before parsing JSON).
bool mayNeedRewrite(const std::string& bytes);

/// The file rewritten for tinygltf, or nothing when it needs no rewriting or its JSON does not
/// parse (tinygltf then reads and reports the file as it is). Throws GltfRewriteError.
std::optional<TinygltfInput> rewriteForTinygltf(const std::string& bytes, bool glb, const ReadBufferFile& read_file);

/// %XX escapes of a relative URI decoded into the file name they stand for.
std::string uriDecode(const std::string& uri);

}  // namespace sharcbake
