// SPDX-License-Identifier: Apache-2.0
/// @file gltf_loader.cpp
/// @brief glTF 2.0 (.gltf / .glb) to sharcbake::Scene: flattens the node hierarchy into one
/// world-space triangle soup and converts materials, textures, lights, cameras and the sky.
///
/// tinygltf parses JSON, resolves buffers and decodes images; everything it does not check
/// (accessor ranges, index ranges, finite positions, required extensions) is checked here,
/// because a bad scene must fail loudly at load time rather than render wrong hours later.
#include "sharcbake/scene_loader.h"

#include "draco_mesh.h"
#include "gltf_rewrite.h"
#include "message_text.h"

#include <stb_image.h>
#include <tiny_gltf.h>
#include <webp/decode.h>
#include <nlohmann/json.hpp>

#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>

namespace sharcbake {
namespace {

/// Luminous efficacy used by KHR_lights_punctual exporters (Blender's PBR_WATTS_TO_LUMENS)
/// to turn watts into lumens; dividing by it gives back radiometric units.
constexpr double kLumensPerWatt = 683.0;

/// Extensions this loader understands well enough to honour when a file requires them.
/// KHR_mesh_quantization only allows integer attribute types, which the accessor reader
/// converts anyway.
const std::array<const char*, 14> kSupportedRequiredExtensions = {"KHR_lights_punctual",
                                                                  "KHR_materials_emissive_strength",
                                                                  "KHR_materials_specular",
                                                                  "KHR_materials_ior",
                                                                  "KHR_mesh_quantization",
                                                                  "KHR_texture_transform",
                                                                  "KHR_materials_transmission",
                                                                  "EXT_mesh_gpu_instancing",
                                                                  "KHR_materials_pbrSpecularGlossiness",
                                                                  "KHR_draco_mesh_compression",
                                                                  "EXT_meshopt_compression",
                                                                  "EXT_texture_webp",
                                                                  "KHR_materials_clearcoat",
                                                                  "KHR_materials_unlit"};

/// Extensions understood only through the fallback a file must give when it does not require
/// them: KHR_texture_basisu's KTX2 images are not decoded, its textures' PNG or JPEG `source` is
/// read. Required, they are refused (the scene has no image sharcbake can read).
const std::array<const char*, 1> kFallbackOnlyExtensions = {"KHR_texture_basisu"};

/// Extensions that change nothing a path tracer reads, so ignoring them is not worth a warning.
/// FB_ngon_encoding (assimp lists it in every file and puts it on every primitive) only says in
/// which order a polygon's triangles were written, for tools that rebuild the polygon.
const std::array<const char*, 1> kExtensionsThatChangeNothing = {"FB_ngon_encoding"};

/// The scene is traced as world-space triangles, so an instanced mesh is copied per instance.
/// A few kilobytes of instance transforms can ask for billions of triangles: beyond this many
/// from one instanced node the file is refused instead of exhausting memory.
constexpr uint64_t kMaxInstancedTriangles = uint64_t(1) << 26;

/// The longest data: URI a message quotes: enough to show its media type and where the data
/// starts, never the kilobytes of base64 behind it.
constexpr size_t kMaxQuotedUri = 60;

/// `uri` cut to kMaxQuotedUri characters with "..." when longer, made printable.
std::string shortUri(const std::string& uri) {
    return printable(uri.size() > kMaxQuotedUri ? uri.substr(0, kMaxQuotedUri) + "..." : uri);
}

/// Every data: URI in `text` shortened (shortUri): tinygltf quotes them whole.
std::string shortenDataUris(std::string text) {
    for (size_t at = text.find("data:"); at != std::string::npos; at = text.find("data:", at + 1)) {
        const size_t end = std::min(text.find_first_of(" \t\r\n'\"", at), text.size());
        if (end - at > kMaxQuotedUri) text.replace(at, end - at, text.substr(at, kMaxQuotedUri) + "...");
    }
    return text;
}

/// tinygltf's error text without bytes of the files it read: the JSON parser quotes what it
/// read last ("last read: '...'"), which for a file that is not glTF is its raw content, and
/// a buffer it cannot decode by its whole data: URI.
std::string parserMessage(std::string err) {
    for (size_t at = err.find("last read: '"); at != std::string::npos; at = err.find("last read: '", at + 1)) {
        const size_t start = at + 12;
        const size_t end = err.find('\'', start);
        err.replace(start - 1, end == std::string::npos ? std::string::npos : end - start + 2, "(bytes not shown)");
    }
    err = shortenDataUris(std::move(err));
    if (err.size() > 2000) err = err.substr(0, 2000) + "...";
    return printable(err);
}

/// Which other 3D format a file that is not glTF is in ("an OBJ file", ...), from its first bytes,
/// or where they say nothing from its extension; nothing for glTF or JSON (the parser judges
/// those) and for anything else. Converters' inputs reach sharcbake by mistake, and the JSON
/// parser's error would not say what they are (a binary STL's: "JSON nested too deep").
std::optional<std::string> otherModelFormat(const std::string& bytes, const std::string& path) {
    const auto startsWith = [&](std::string_view prefix) { return bytes.compare(0, prefix.size(), prefix) == 0; };
    if (startsWith("glTF")) return std::nullopt;
    const size_t text = startsWith("\xEF\xBB\xBF") ? 3 : 0;  // a UTF-8 byte order mark
    const size_t first = bytes.find_first_not_of(" \t\r\n", text);
    if (first != std::string::npos && bytes[first] == '{') return std::nullopt;
    // Binary formats first: an STL header is free text, and may start with "solid".
    if (startsWith("Kaydara FBX Binary")) return "an FBX file";
    if (bytes.size() >= 84) {
        uint32_t triangles = 0;
        std::memcpy(&triangles, bytes.data() + 80, 4);
        if (triangles > 0 && bytes.size() == 84 + 50 * uint64_t(triangles)) return "an STL file";
    }
    if (startsWith("ply\n") || startsWith("ply\r\n")) return "a PLY file";
    if (startsWith("solid")) return "an STL file";
    if (startsWith("; FBX")) return "an FBX file";
    if (bytes.compare(first == std::string::npos ? 0 : first, 1, "<") == 0 &&
        bytes.substr(0, 4096).find("<COLLADA") != std::string::npos)
        return "a Collada file";
    // OBJ: the first line that is not blank or a comment starts with one of its statements.
    std::istringstream lines(bytes.substr(0, 4096));
    for (std::string line; std::getline(lines, line);) {
        std::istringstream words(line);
        std::string word;
        if (!(words >> word) || word[0] == '#') continue;
        static const std::set<std::string> kObjStatements = {"v", "vt", "vn", "vp", "f",      "l",
                                                             "p", "o",  "g",  "s",  "mtllib", "usemtl"};
        if (kObjStatements.count(word)) return "an OBJ file";
        break;
    }
    std::string extension = std::filesystem::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    static const std::map<std::string, std::string> kByExtension = {{".obj", "an OBJ file"},
                                                                    {".stl", "an STL file"},
                                                                    {".ply", "a PLY file"},
                                                                    {".dae", "a Collada file"},
                                                                    {".fbx", "an FBX file"}};
    if (const auto it = kByExtension.find(extension); it != kByExtension.end()) return it->second;
    return std::nullopt;
}

/// `path` as one word of a shell command: in single quotes unless it holds only characters no
/// shell reads specially.
std::string shellWord(const std::string& path) {
    const bool plain = !path.empty() && std::all_of(path.begin(), path.end(), [](unsigned char c) {
        return std::isalnum(c) || std::string_view("/._+-").find(char(c)) != std::string_view::npos;
    });
    if (plain) return path;
    std::string quoted = "'";
    for (const char c : path) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

/// The glTF version this loader reads (glTF 2.0, "Asset": a 2.x loader reads any 2.y file
/// unless its minVersion asks for more).
constexpr unsigned kGltfMajorVersion = 2;
constexpr unsigned kGltfMinorVersion = 0;

/// A glTF version string, "<major>.<minor>" (the schema's pattern ^[0-9]+\.[0-9]+$); nothing
/// when `text` is not one.
std::optional<std::pair<unsigned, unsigned>> parseGltfVersion(const std::string& text) {
    const size_t dot = text.find('.');
    const auto digits = [](const std::string& part) {
        return !part.empty() && part.size() <= 9 &&
               std::all_of(part.begin(), part.end(), [](char c) { return c >= '0' && c <= '9'; });
    };
    if (dot == std::string::npos || !digits(text.substr(0, dot)) || !digits(text.substr(dot + 1))) return std::nullopt;
    return std::make_pair(unsigned(std::stoul(text.substr(0, dot))), unsigned(std::stoul(text.substr(dot + 1))));
}

/// Why a file with this asset.version (nothing: absent) and asset.minVersion ("" when absent)
/// cannot be read as glTF 2.0, or "" when it can. Refused rather than read: a glTF 1.0 file's
/// meshes and buffers are objects, not arrays, and would load as an empty scene.
std::string gltfVersionProblem(const std::optional<std::string>& version, const std::string& min_version) {
    if (!version) return "asset.version is missing; glTF 2.0 requires it (is this a glTF 2.0 file?)";
    const auto parsed = parseGltfVersion(*version);
    if (!parsed) return "asset.version " + quoted(*version) + " is not a glTF version (<major>.<minor>)";
    if (parsed->first != kGltfMajorVersion) {
        const std::string which = "glTF " + std::to_string(parsed->first) + "." + std::to_string(parsed->second);
        return which + " files are not supported (asset.version " + quoted(*version) +
               "): sharcbake reads glTF 2.0; re-export or convert the scene to glTF 2.0";
    }
    if (min_version.empty()) return {};
    const auto needed = parseGltfVersion(min_version);
    if (!needed) return "asset.minVersion " + quoted(min_version) + " is not a glTF version (<major>.<minor>)";
    if (*needed > std::make_pair(kGltfMajorVersion, kGltfMinorVersion)) {
        return "the file needs glTF " + printable(min_version) + " or later (asset.minVersion); sharcbake reads glTF " +
               std::to_string(kGltfMajorVersion) + "." + std::to_string(kGltfMinorVersion) +
               "; re-export it for glTF 2.0";
    }
    return {};
}

/// The JSON text of a .gltf file or of a GLB's JSON chunk (whatever fits in the file).
std::string_view jsonText(const std::string& bytes, bool glb) {
    if (!glb) return bytes;
    if (bytes.size() < 20) return {};
    uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    return std::string_view(bytes).substr(20, length);
}

/// tinygltf reports a buffer's data: URI it could not decode as "Failed to decode 'uri' : <the
/// URI> in Buffer", without the buffer or the reason. Both are found here from the JSON: the
/// buffer with that URI, and either the size the URI decodes to against its byteLength (an
/// edited or truncated file) or a URI tinygltf does not decode at all. Nothing when the error is
/// another or the JSON does not say more.
std::optional<std::string> dataUriProblem(std::string_view json, const std::string& err) {
    static const std::string kMarker = "Failed to decode 'uri' : ";
    const size_t at = err.find(kMarker);
    if (at == std::string::npos) return std::nullopt;
    const size_t start = at + kMarker.size();
    const std::string uri = err.substr(start, err.find(" in Buffer", start) - start);
    const nlohmann::json doc = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object() || !doc.contains("buffers") || !doc["buffers"].is_array()) {
        return std::nullopt;
    }
    const nlohmann::json& buffers = doc["buffers"];
    for (size_t i = 0; i < buffers.size(); ++i) {
        const nlohmann::json& buffer = buffers[i];
        if (!buffer.is_object() || buffer.value("uri", std::string()) != uri) continue;
        const std::string label = "buffer " + std::to_string(i) + ": data: URI " + shortUri(uri);
        std::vector<unsigned char> data;
        std::string mime_type;
        if (!tinygltf::DecodeDataURI(&data, mime_type, uri, 0, false)) {
            return label +
                   " is not base64 data of a type tinygltf decodes (application/octet-stream or "
                   "application/gltf-buffer), or holds no bytes";
        }
        const nlohmann::json& length = buffer.contains("byteLength") ? buffer["byteLength"] : nlohmann::json();
        return label + " holds " + std::to_string(data.size()) + " bytes, but the buffer's byteLength is " +
               (length.is_null() ? std::string("missing") : printable(length.dump())) +
               " (the two must agree: was the file edited or cut short?)";
    }
    return std::nullopt;
}

/// asset.version and asset.minVersion read from the JSON itself, for a file tinygltf could not
/// parse (its error would hide a version it does not read). Nothing when the JSON does not parse
/// or has no asset object: tinygltf's error says what is wrong then.
std::optional<std::string> versionProblemInJson(std::string_view json) {
    const nlohmann::json doc = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object() || !doc.contains("asset") || !doc["asset"].is_object()) {
        return std::nullopt;
    }
    const nlohmann::json& asset = doc["asset"];
    const auto text = [&](const char* key) -> std::optional<std::string> {
        if (!asset.contains(key)) return std::nullopt;
        return asset[key].is_string() ? asset[key].get<std::string>() : asset[key].dump();
    };
    std::string problem = gltfVersionProblem(text("version"), text("minVersion").value_or(""));
    if (problem.empty()) return std::nullopt;
    return problem;
}

/// tinygltf's "'type' property is missing." names no object. The first object of the glTF's
/// arrays that lacks `property` where glTF 2.0 (or KHR_lights_punctual) requires it, as "light 0
/// 'Sun'", if there is one.
std::optional<std::string> objectMissingProperty(std::string_view json, const std::string& property) {
    const nlohmann::json doc = nlohmann::json::parse(json.begin(), json.end(), nullptr, false);
    if (doc.is_discarded() || !doc.is_object()) return std::nullopt;
    const auto lacking = [&](const nlohmann::json* array, const char* kind) -> std::optional<std::string> {
        if (!array || !array->is_array()) return std::nullopt;
        for (size_t i = 0; i < array->size(); ++i) {
            const nlohmann::json& object = (*array)[i];
            if (!object.is_object() || object.contains(property)) continue;
            std::string label = std::string(kind) + " " + std::to_string(i);
            if (object.contains("name") && object["name"].is_string())
                label += " " + quoted(object["name"].get<std::string>());
            return label;
        }
        return std::nullopt;
    };
    const auto member = [](const nlohmann::json& object, const char* key) -> const nlohmann::json* {
        return object.is_object() && object.contains(key) ? &object[key] : nullptr;
    };
    struct Required {
        const char* array;
        const char* kind;
        std::vector<std::string> properties;
    };
    static const Required kRequired[] = {
        {"accessors", "accessor", {"componentType", "count", "type"}},
        {"bufferViews", "bufferView", {"buffer", "byteLength"}},
        {"buffers", "buffer", {"byteLength"}},
        {"cameras", "camera", {"type"}},
        {"meshes", "mesh", {"primitives"}},
        {"skins", "skin", {"joints"}},
        {"animations", "animation", {"channels", "samplers"}},
    };
    for (const Required& r : kRequired) {
        if (std::find(r.properties.begin(), r.properties.end(), property) == r.properties.end()) continue;
        if (std::optional<std::string> found = lacking(member(doc, r.array), r.kind)) return found;
    }
    if (property == "type") {
        const nlohmann::json* extensions = member(doc, "extensions");
        const nlohmann::json* punctual = extensions ? member(*extensions, "KHR_lights_punctual") : nullptr;
        if (std::optional<std::string> found = lacking(punctual ? member(*punctual, "lights") : nullptr, "light"))
            return *found + " (KHR_lights_punctual)";
    }
    if (property == "attributes" && doc.contains("meshes") && doc["meshes"].is_array()) {
        for (size_t m = 0; m < doc["meshes"].size(); ++m) {
            if (std::optional<std::string> found = lacking(member(doc["meshes"][m], "primitives"),
                                                           ("mesh " + std::to_string(m) + " primitive").c_str()))
                return found;
        }
    }
    return std::nullopt;
}

glm::vec3 vec3Or(const std::vector<double>& v, glm::vec3 fallback) {
    if (v.size() < 3) return fallback;
    return glm::vec3(static_cast<float>(v[0]), static_cast<float>(v[1]), static_cast<float>(v[2]));
}

/// Doubles too, so that a value of the JSON is named as the file gives it: 1e+39, not the inf
/// that float32 makes of it.
std::string numberText(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return text;
}

/// The F0 of a dielectric of ior 1.5, ((1.5 - 1) / (1.5 + 1))^2: what specular-glossiness's
/// specular colour is measured against.
constexpr float kDielectricF0 = 0.04f;

/// The largest float32. glTF's numbers are JSON doubles; the scene is float32, so a value beyond
/// this has no float (it would be infinity).
constexpr double kLargestFloat = std::numeric_limits<float>::max();

bool fitsFloat(double v) { return std::abs(v) <= kLargestFloat; }

template <typename T>
std::string vec3Text(glm::vec<3, T> v) {
    // Appended, not "(" + ...: GCC 12 warns about that form (-Wrestrict, a false positive).
    std::string text = "(";
    text += numberText(v.x);
    text += ", ";
    text += numberText(v.y);
    text += ", ";
    text += numberText(v.z);
    text += ")";
    return text;
}

/// `v` clamped into [lo, hi], or `fallback` where it is not finite: a factor taken into the range
/// glTF gives it.
float clampedFactor(float v, float lo, float hi, float fallback) {
    return std::isfinite(v) ? std::clamp(v, lo, hi) : fallback;
}

glm::vec3 clampedFactor(glm::vec3 v, float lo, float hi, float fallback) {
    return {clampedFactor(v.x, lo, hi, fallback), clampedFactor(v.y, lo, hi, fallback),
            clampedFactor(v.z, lo, hi, fallback)};
}

bool isFinite(const glm::vec3& v) {
    return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool isFinite(const glm::dmat4& m) {
    for (int column = 0; column < 4; ++column)
        for (int row = 0; row < 4; ++row)
            if (!std::isfinite(m[column][row])) return false;
    return true;
}

/// A texture reference as found in core glTF (TextureInfo) or inside extension JSON.
struct TextureSlot {
    int index = -1;
    int texcoord = 0;
    const tinygltf::Value* transform = nullptr;  ///< its KHR_texture_transform object, if any
};

/// What the image loader callback needs, and what it found: why each image it did not decode
/// (glTF image index -> reason) was not.
struct ImageDecoding {
    struct NotDecoded {
        std::string why;
        bool ktx2 = false;     ///< skipped on purpose (KHR_texture_basisu), not broken
        bool missing = false;  ///< no file of its URI beside the scene: `why` says where it was looked for
    };
    uint32_t max_side = 0;  ///< --max-texture-size
    std::map<int, NotDecoded> not_decoded;
    /// Images stored in a bufferView, set aside while tinygltf parses (it passes their bytes on
    /// unchecked) and decoded once their view's range is checked.
    std::vector<int> in_buffer_views;
    bool buffer_views_checked = false;
};

/// Where an accessor's elements live in memory, after range checks.
struct ElementLayout {
    const unsigned char* data = nullptr;
    size_t stride = 0;
    size_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
};

/// One primitive's geometry, already in world space and with degenerate triangles removed.
struct PrimitiveGeometry {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;  ///< empty when the primitive has none
    std::vector<glm::vec2> uv0;      ///< empty when absent
    std::vector<glm::vec2> uv1;      ///< empty when absent
    std::vector<glm::vec4> colors;   ///< COLOR_0 as RGBA; empty when absent
    std::vector<glm::vec4> tangents; ///< TANGENT (xyz, w = bitangent sign); empty when absent
    std::vector<glm::uvec3> triangles;
    /// World positions before their rounding to float (transformToWorld, skinToWorld), for
    /// telling triangles the rounding collapsed from ones modelled flat; emptied after that.
    std::vector<glm::dvec3> exact_positions;
};

/// Reads one component at p and converts it to double; normalized integers map to [0,1] or
/// [-1,1] as the glTF specification defines.
double readComponent(const unsigned char* p, int componentType, bool normalized) {
    auto load = [p](auto value) {
        std::memcpy(&value, p, sizeof(value));  // memcpy: glTF data need not be aligned
        return value;
    };
    switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return load(float{});
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        const double v = load(int8_t{});
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: {
        const double v = load(uint8_t{});
        return normalized ? v / 255.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        const double v = load(int16_t{});
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        const double v = load(uint16_t{});
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        const double v = load(uint32_t{});
        return normalized ? v / 4294967295.0 : v;
    }
    default: return 0.0;  // rejected earlier by ElementLayout validation
    }
}

/// Turns the index list of a primitive into triangles according to its mode
/// (TRIANGLES, TRIANGLE_STRIP or TRIANGLE_FAN), using the glTF specification's orderings.
std::vector<glm::uvec3> assembleTriangles(int mode, const std::vector<uint32_t>& idx) {
    std::vector<glm::uvec3> tris;
    const size_t n = idx.size();
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t i = 0; i + 2 < n; ++i) {
            // Odd triangles swap their first two vertices so all keep the same winding.
            if (i % 2 == 0) tris.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
            else tris.emplace_back(idx[i + 1], idx[i], idx[i + 2]);
        }
    } else if (mode == TINYGLTF_MODE_TRIANGLE_FAN) {
        for (size_t i = 1; i + 1 < n; ++i) tris.emplace_back(idx[i], idx[i + 1], idx[0]);
    } else {
        for (size_t i = 0; i + 2 < n; i += 3) tris.emplace_back(idx[i], idx[i + 1], idx[i + 2]);
    }
    return tris;
}

/// T * R * S, each part optional (identity where absent). `rotation` is glTF's (x, y, z, w),
/// normalised here; a node's TRS and an EXT_mesh_gpu_instancing instance's both compose this way.
glm::dmat4 composeTrs(const std::optional<glm::dvec3>& translation, const std::optional<glm::dvec4>& rotation,
                      const std::optional<glm::dvec3>& scale) {
    glm::dmat4 m(1.0);
    if (translation) m = glm::translate(m, *translation);
    if (rotation) m *= glm::mat4_cast(glm::normalize(glm::dquat(rotation->w, rotation->x, rotation->y, rotation->z)));
    if (scale) m = glm::scale(m, *scale);
    return m;
}

/// A node's local transform: the matrix if given, else T * R * S.
glm::dmat4 localTransform(const tinygltf::Node& node) {
    if (node.matrix.size() == 16) return glm::make_mat4(node.matrix.data());  // column-major, like glm
    const auto vec3 = [](const std::vector<double>& v) {
        return v.size() == 3 ? std::optional<glm::dvec3>(glm::dvec3(v[0], v[1], v[2])) : std::nullopt;
    };
    const std::optional<glm::dvec4> rotation =
        node.rotation.size() == 4 ? std::optional<glm::dvec4>(glm::dvec4(node.rotation[0], node.rotation[1],
                                                                         node.rotation[2], node.rotation[3]))
                                  : std::nullopt;
    return composeTrs(vec3(node.translation), rotation, vec3(node.scale));
}

/// The rotation of a node's local transform, what orients a light whose node is scaled to zero
/// (its -Z axis has then no direction): R times the signs of S for T * R * S (a zero scale keeps
/// its axis, a negative one mirrors it, as in the full transform), the orthogonal factor of the
/// polar decomposition of a matrix. Nothing for a singular matrix: it has no orientation.
std::optional<glm::dmat3> localOrientation(const tinygltf::Node& node) {
    if (node.matrix.size() != 16) {
        glm::dmat3 r(1.0);
        if (node.rotation.size() == 4) {
            r = glm::mat3_cast(
                glm::normalize(glm::dquat(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2])));
        }
        if (node.scale.size() == 3) {
            for (int axis = 0; axis < 3; ++axis)
                if (node.scale[size_t(axis)] < 0.0) r[axis] = -r[axis];
        }
        return r;
    }
    glm::dmat3 q(glm::make_mat4(node.matrix.data()));
    const double size = glm::length(q[0]) * glm::length(q[1]) * glm::length(q[2]);
    if (!(std::abs(glm::determinant(q)) > 1e-12 * size)) return std::nullopt;  // NaN too
    // Newton's iteration for the polar decomposition, scaled so that it converges in a few steps
    // whatever the matrix's scale (Higham, "Computing the polar decomposition", 1986).
    const auto norm = [](const glm::dmat3& m) {  // Frobenius
        return std::sqrt(glm::dot(m[0], m[0]) + glm::dot(m[1], m[1]) + glm::dot(m[2], m[2]));
    };
    for (int i = 0; i < 100; ++i) {
        const glm::dmat3 inverse_transpose = glm::transpose(glm::inverse(q));
        const double gamma = std::sqrt(norm(inverse_transpose) / norm(q));
        const glm::dmat3 next = 0.5 * (gamma * q + (1.0 / gamma) * inverse_transpose);
        const glm::dmat3 step = next - q;
        q = next;
        if (norm(step) < 1e-15) break;
    }
    return q;
}

/// Builds the glTF-spec default material used by primitives without one.
Material defaultMaterial() {
    Material m;
    m.name = "(default)";
    // Material's member defaults already are the glTF defaults: white, metallic 1, rough 1.
    return m;
}

class GltfLoader {
public:
    GltfLoader(std::string path, const GltfLoadLimits& limits) : path_(std::move(path)), limits_(limits) {
        scene_.source_path = path_;
    }

    Scene load() {
        parseFile();
        checkRequiredExtensions();
        warnAboutIgnoredExtensions();
        convertMaterials();
        readSky();
        readKnownRadiance();
        removeRepeatedChildren();
        warnAboutAMissingDefaultScene();
        for (int root : uniqueRootNodes()) visitNode(root, glm::dmat4(1.0));
        warnAboutMeshesOutsideTheScene();
        warnAboutSeveralParents();
        warnAboutAnimations();
        warnAboutPrimitivesWithoutMaterial();
        warnAboutFlatEmitters();
        if (scene_.materials.empty()) scene_.materials.push_back(defaultMaterial());
        settleAlphaModes();
        writeMaterialWarnings();
        computeBounds();
        scene_.stats.triangles_loaded = scene_.triangles.size();
        warnAboutCollapsedTriangles();
        warnAboutTinyTriangles();
        warnAboutCoincidentEmitters();
        return std::move(scene_);
    }

private:
    std::string path_;
    GltfLoadLimits limits_;
    tinygltf::Model model_;
    Scene scene_;
    int default_material_ = -1;
    uint64_t mesh_nodes_visited_ = 0;  ///< nodes with a mesh in the loaded scene (instanced or not)
    /// The (mesh, primitive) pairs given the default material, and the label of the first the walk reached.
    std::set<std::pair<int, size_t>> primitives_without_material_;
    /// Per material: triangles read, and those left once degenerate ones were dropped.
    std::map<uint32_t, std::pair<size_t, size_t>> triangles_by_material_;
    std::string first_without_material_;
    ImageDecoding image_decoding_;
    /// (glTF texture index, decode as sRGB) -> Scene::textures index; a texture used both as
    /// colour and as data is two Scene textures over one copy of its 8-bit texels.
    std::map<std::pair<int, bool>, int> texture_cache_;
    /// glTF image index -> its 8-bit texels as RGBA8, shared by every texture that reads it.
    std::map<int, std::shared_ptr<const std::vector<glm::u8vec4>>> rgba8_images_;
    std::map<std::pair<int, int>, uint64_t> draco_index_counts_;      ///< (mesh, primitive) -> indices' count
    std::map<std::pair<int, float>, int> roughness_from_glossiness_;  ///< (texture, glossiness) -> converted
    std::vector<bool> on_path_;  ///< nodes on the current hierarchy path (cycle detection)
    /// Per node, where the walk first reached it: -2 not yet, -1 as a root of the scene, else the
    /// parent node's index; and the other parents of the nodes reached under several.
    std::vector<int> first_parent_;
    std::map<int, std::vector<int>> other_parents_;
    /// Lights skipped for what they are, not where (a type not supported, an intensity beyond
    /// float32), already warned about: named once however many nodes place them.
    std::set<size_t> unusable_lights_;
    std::set<size_t> placed_lights_;       ///< lights placed by a node so far (convertLight)
    std::vector<glm::dmat4> node_worlds_;  ///< every node's world matrix, made for the first skin
    std::set<std::string> warned_;
    /// Warnings many materials can share, by their text: the labels of the materials, in order.
    std::vector<std::pair<std::string, std::vector<std::string>>> material_warnings_;
    std::map<std::string, size_t> material_warning_index_;
    uint64_t collapsed_triangles_ = 0;  ///< triangles flat in float but not in double (dropDegenerateTriangles)
    double collapsed_farthest_ = 0.0;   ///< the largest coordinate among their vertices

    // ---------------------------------------------------------------- errors and warnings

    [[noreturn]] void fail(const std::string& what) const { throw SceneLoadError(path_ + ": " + what); }
    [[noreturn]] void failMissingFile(const std::string& what) const {
        throw SceneLoadError(path_ + ": " + what, SceneLoadError::Kind::kMissingFile);
    }

    /// Animations are not played (a bake is of one static pose), and nothing said so: an animated
    /// object or walkthrough camera was baked where its node's transform puts it, which Blender's
    /// exporter sets to the first frame, not the frame shown when the file was written.
    void warnAboutAnimations() {
        std::set<int> nodes;
        for (const tinygltf::Animation& animation : model_.animations) {
            for (const tinygltf::AnimationChannel& channel : animation.channels) {
                if (channel.target_node >= 0 && size_t(channel.target_node) < model_.nodes.size())
                    nodes.insert(channel.target_node);
            }
        }
        if (nodes.empty()) return;
        // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "text" + std::string.
        std::string cameras;
        for (const int node : nodes) {
            if (model_.nodes[size_t(node)].camera < 0) continue;
            if (!cameras.empty()) cameras += ", ";
            cameras += nodeLabel(node);
        }
        std::string text = std::to_string(model_.animations.size());
        text += model_.animations.size() == 1 ? " animation moves " : " animations move ";
        text += std::to_string(nodes.size());
        text += nodes.size() == 1 ? " node" : " nodes";
        if (!cameras.empty()) {
            text += " (cameras among them: ";
            text += cameras;
            text += ")";
        }
        text +=
            "; animations are not played: the scene is loaded in the pose its nodes' transforms hold, which "
            "exporters write as the rest pose or the first frame (Blender's: frame 1, not the frame shown)";
        warn(text);
    }

    /// Records a warning once: a mesh instanced a thousand times should not repeat its
    /// repaired-normals warning a thousand times.
    void warn(const std::string& what) {
        std::string line = path_ + ": " + what;
        if (warned_.insert(line).second) scene_.stats.warnings.push_back(std::move(line));
    }

    /// A warning about one material that others may share: kept until the materials are settled
    /// (writeMaterialWarnings), then written once per text. A file whose 147 materials each carry
    /// an occlusion texture gets one line naming the first and the count, not 147 lines burying
    /// the warnings that matter.
    void warnForMaterial(const std::string& label, const std::string& text) {
        const auto [it, added] = material_warning_index_.emplace(text, material_warnings_.size());
        if (added) material_warnings_.push_back({text, {}});
        std::vector<std::string>& labels = material_warnings_[it->second].second;
        if (std::find(labels.begin(), labels.end(), label) == labels.end()) labels.push_back(label);
    }

    void writeMaterialWarnings() {
        for (const auto& [text, labels] : material_warnings_) {
            const size_t others = labels.size() - 1;
            warn(labels.front() +
                 (others == 0
                      ? ""
                      : " and " + std::to_string(others) + (others == 1 ? " other material" : " other materials")) +
                 ": " + text);
        }
        material_warnings_.clear();
        material_warning_index_.clear();
    }

    std::string meshLabel(int meshIndex, size_t primIndex) const {
        const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
        std::string label = "mesh " + std::to_string(meshIndex);
        if (!mesh.name.empty()) label += " " + quoted(mesh.name);
        return label + " primitive " + std::to_string(primIndex);
    }

    // ---------------------------------------------------------------- file parsing

    static bool hasGlbMagic(const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        char magic[4] = {};
        in.read(magic, 4);
        return in.gcount() == 4 && std::memcmp(magic, "glTF", 4) == 0;
    }

    /// What readAndRecordFile needs: the list it records into and the scene's folder.
    struct FileAccess {
        std::vector<std::string>* files;
        std::filesystem::path folder;  ///< canonical
        std::string_view json;         ///< the glTF's JSON text, for imageFiles
        /// The files the images' URIs name (canonical; not those a buffer names too), read from
        /// `json` when an empty file first asks for them.
        std::optional<std::set<std::filesystem::path>> image_files;
        /// The folder as tinygltf writes it before a URI (tinygltfBaseDir, or the base_dir it is
        /// given): the paths it tries that do not start with it are in the current directory.
        std::string search_dir;
        /// Paths tinygltf asked for that name no file, each with the '\' of its URI read as '/'
        /// (withForwardSlashes).
        std::map<std::string, std::string> slashed_paths;
    };

    /// The folder tinygltf joins a file's URIs to when it reads the file itself: its path up to
    /// the last '/' or '\', empty for a bare name (tinygltf's GetBaseDir).
    static std::string tinygltfBaseDir(const std::string& path) {
        const size_t separator = path.find_last_of("/\\");
        return separator == std::string::npos ? std::string() : path.substr(0, separator);
    }

    /// tinygltf looks for a URI's file in the scene's folder, then in the current directory:
    /// what loaded (and what the folder check refused) would depend on where sharcbake runs. Only
    /// the paths it builds from the scene's folder exist for it.
    static bool existsBesideScene(const std::string& path, void* user) {
        return uriStart(*static_cast<const FileAccess*>(user), path) && tinygltf::FileExists(path, nullptr);
    }

    /// Where the URI starts in a path tinygltf built from the scene's folder; nothing for the
    /// paths it tries in the current directory.
    static std::optional<size_t> uriStart(const FileAccess& access, const std::string& path) {
        const std::string& dir = access.search_dir;
        if (dir.empty()) return 0;
        const std::string prefix = dir.back() == '/' ? dir : dir + '/';
        if (path.rfind(prefix, 0) != 0) return std::nullopt;
        return prefix.size();
    }

    /// assimp copies an MTL file's Windows paths into the URI unchanged ("textures\wall.png"), and
    /// '\' is a letter of file names on other systems: where the path as written names no file, the
    /// one with the URI's '\' read as '/' is used (readAndRecordFile keeps it to the scene's folder).
    static std::string withForwardSlashes(const std::string& path, void* user) {
        auto& access = *static_cast<FileAccess*>(user);
        const std::optional<size_t> uri = uriStart(access, path);
        std::error_code error;
        if (!uri || path.find('\\', *uri) == std::string::npos || std::filesystem::exists(path, error)) return path;
        std::string slashed = path;
        std::replace(slashed.begin() + std::ptrdiff_t(*uri), slashed.end(), '\\', '/');
        if (!std::filesystem::exists(slashed, error)) return path;
        access.slashed_paths.emplace(path, slashed);
        return slashed;
    }

    /// What readAndRecordFile hands tinygltf for an empty image file, which tinygltf would refuse
    /// before the image loader sees it (this version as a missing image, with its own "File
    /// read error" lines; others fail the parse): not an image of any format, so that
    /// loadImageBounded reports it as an image that cannot be decoded, like any other.
    static constexpr char kEmptyImageFile[] = "\0sharcbake: an empty image file\0";

    static bool isEmptyImageFile(const unsigned char* bytes, int size) {
        return size == int(sizeof kEmptyImageFile) && std::memcmp(bytes, kEmptyImageFile, sizeof kEmptyImageFile) == 0;
    }

    /// A URI decoded as tinygltf decodes it ('+' is a space to it, "%2B" a plus).
    static std::string tinygltfDecodedUri(std::string uri) {
        for (size_t at = uri.find('+'); at != std::string::npos; at = uri.find('+', at)) uri.replace(at, 1, "%20");
        return uriDecode(uri);
    }

    /// The file a relative URI names in the scene's folder, decoded as tinygltf decodes it, and
    /// with '\' read as '/' where that names a file and the URI as written none (withForwardSlashes).
    static std::filesystem::path uriFile(const FileAccess& access, const std::string& uri) {
        std::string decoded = tinygltfDecodedUri(uri);
        std::error_code error;
        if (decoded.find('\\') != std::string::npos && !std::filesystem::exists(access.folder / decoded, error)) {
            std::string slashed = decoded;
            std::replace(slashed.begin(), slashed.end(), '\\', '/');
            if (std::filesystem::exists(access.folder / slashed, error)) decoded = std::move(slashed);
        }
        return std::filesystem::weakly_canonical(access.folder / decoded, error);
    }

    /// True when `path` is the file of one of the scene's images and of none of its buffers.
    static bool isImageFile(FileAccess& access, const std::string& path) {
        if (!access.image_files) {
            access.image_files.emplace();
            const nlohmann::json doc = nlohmann::json::parse(access.json.begin(), access.json.end(), nullptr, false);
            std::set<std::filesystem::path> buffer_files;
            const auto files = [&](const char* array, std::set<std::filesystem::path>& into) {
                if (doc.is_discarded() || !doc.is_object() || !doc.contains(array) || !doc[array].is_array()) return;
                for (const nlohmann::json& item : doc[array]) {
                    if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
                    const std::string uri = item["uri"].get<std::string>();
                    if (uri.rfind("data:", 0) != 0) into.insert(uriFile(access, uri));
                }
            };
            files("images", *access.image_files);
            files("buffers", buffer_files);
            for (const std::filesystem::path& file : buffer_files) access.image_files->erase(file);
        }
        std::error_code error;
        return access.image_files->count(std::filesystem::weakly_canonical(path, error)) > 0;
    }

    /// Reads one file for tinygltf. Untrusted scenes: only regular files (a FIFO or a device
    /// would block or never end), and a buffer or image only from the scene's folder or below
    /// (a URI with "../" or an absolute path is refused, so a scene cannot read /etc/passwd).
    static bool readAndRecordFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                                  void* user) {
        auto& access = *static_cast<FileAccess*>(user);
        std::error_code error;
        if (!std::filesystem::is_regular_file(path, error)) {
            if (err) *err += "File is not a regular file: " + path + "\n";
            return false;
        }
        if (!access.files->empty()) {
            const std::filesystem::path resolved = std::filesystem::weakly_canonical(path, error);
            const auto [end, unused] = std::mismatch(access.folder.begin(), access.folder.end(), resolved.begin(),
                                                     resolved.end());
            (void)unused;
            if (error || end != access.folder.end()) {
                if (err) {
                    *err += "File " + path + " is outside the scene's folder " + access.folder.string() +
                            "; untrusted scenes may not read it\n";
                }
                return false;
            }
        }
        const auto size = std::filesystem::file_size(path, error);
        if (!error && size == 0 && isImageFile(access, path)) {
            out->assign(std::begin(kEmptyImageFile), std::end(kEmptyImageFile));
        } else if (!tinygltf::ReadWholeFile(out, err, path, nullptr)) {
            return false;
        }
        auto& list = *access.files;
        const std::string file = std::filesystem::path(path).lexically_normal().string();
        if (std::find(list.begin(), list.end(), file) == list.end()) list.push_back(file);
        return true;
    }

    /// The deepest JSON nesting the loader accepts; real glTF files nest about 10 deep. The JSON
    /// parser recurses per level, so 20,000 nested arrays would overflow its stack.
    static constexpr int kMaxJsonNesting = 256;

    /// Refuses absurd nesting in the glTF's JSON (the file, or a GLB's JSON chunk) before parsing.
    void checkJsonNesting(const std::string& bytes) {
        size_t begin = 0, end = bytes.size();
        if (bytes.size() >= 20 && std::memcmp(bytes.data(), "glTF", 4) == 0) {
            uint32_t length = 0;
            std::memcpy(&length, bytes.data() + 12, 4);
            begin = 20;
            end = std::min<size_t>(bytes.size(), begin + length);
        }
        int depth = 0;
        bool in_string = false;
        for (size_t i = begin; i < end; ++i) {
            const char c = bytes[i];
            if (in_string) {
                if (c == '\\') ++i;
                else if (c == '"') in_string = false;
            } else if (c == '"') {
                in_string = true;
            } else if (c == '[' || c == '{') {
                if (++depth > kMaxJsonNesting) {
                    fail("JSON nested more than " + std::to_string(kMaxJsonNesting) + " levels deep (at byte " +
                         std::to_string(i) + "); refused before parsing");
                }
            } else if (c == ']' || c == '}') {
                --depth;
            }
        }
    }

    /// An image's size from its header against --max-texture-size; false (with the reason in
    /// `err`) when a side is over it.
    static bool withinTextureLimit(int index, int width, int height, uint32_t max_side, std::string* err) {
        if (uint64_t(width) <= max_side && uint64_t(height) <= max_side) return true;
        if (err) {
            *err += "image " + std::to_string(index) + " is " + std::to_string(width) + "x" + std::to_string(height) +
                    " texels, above the limit of " + std::to_string(max_side) +
                    " per side (raise it with --max-texture-size)\n";
        }
        return false;
    }

    static bool isWebp(const unsigned char* bytes, int size) {
        return size >= 12 && std::memcmp(bytes, "RIFF", 4) == 0 && std::memcmp(bytes + 8, "WEBP", 4) == 0;
    }

    /// KTX2's 12-byte identifier, which KHR_texture_basisu's images start with.
    static bool isKtx2(const unsigned char* bytes, int size) {
        static constexpr unsigned char kIdentifier[12] = {0xAB, 'K',  'T',  'X',  ' ',  '2',
                                                          '0',  0xBB, '\r', '\n', 0x1A, '\n'};
        return size >= 12 && std::memcmp(bytes, kIdentifier, 12) == 0;
    }

    /// EXT_texture_webp's images, which tinygltf's stb decoder cannot read, with libwebp: 8-bit
    /// RGBA, behind the same size check as the other images. Bytes libwebp cannot decode are
    /// recorded in `decoding` (the scene still loads); only an image over the size limit fails.
    static bool loadWebp(tinygltf::Image* image, int index, std::string* err, const unsigned char* bytes, int size,
                         ImageDecoding& decoding) {
        int width = 0, height = 0;
        if (!WebPGetInfo(bytes, size_t(size), &width, &height)) {
            decoding.not_decoded.emplace(index, ImageDecoding::NotDecoded{"not a WebP image libwebp can read", false});
            return true;
        }
        if (!withinTextureLimit(index, width, height, decoding.max_side, err)) return false;
        uint8_t* rgba = WebPDecodeRGBA(bytes, size_t(size), &width, &height);
        if (!rgba) {
            decoding.not_decoded.emplace(index, ImageDecoding::NotDecoded{"libwebp could not decode it", false});
            return true;
        }
        image->width = width;
        image->height = height;
        image->component = 4;
        image->bits = 8;
        image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
        image->image.assign(rgba, rgba + size_t(width) * size_t(height) * 4);
        WebPFree(rgba);
        return true;
    }

    /// Why tinygltf's decoder gave up on an image, from its error text and stb_image's reason.
    static std::string decodeFailure(std::string tinygltf_err) {
        if (tinygltf_err.find("STB cannot decode") != std::string::npos) {
            const char* reason = stbi_failure_reason();
            return std::string("stb_image cannot decode it (") + (reason ? reason : "unknown image format") + ")";
        }
        while (!tinygltf_err.empty() && (tinygltf_err.back() == '\n' || tinygltf_err.back() == '\r'))
            tinygltf_err.pop_back();
        return printable(tinygltf_err.empty() ? std::string("unknown error") : tinygltf_err);
    }

    /// tinygltf's image decoder behind a size check on the image header, so a small file that
    /// declares a huge image is refused before its texels are allocated. An image that cannot be
    /// decoded (corrupt, or a format stb does not read) does not fail the parse: tinygltf would
    /// refuse the whole scene for it, where a missing image only drops its textures. It is
    /// recorded in the ImageDecoding `user` and left without texels; so is an empty file, which
    /// arrives as kEmptyImageFile. KTX2 images are not decoded at all: KHR_texture_basisu's
    /// textures read their PNG or JPEG fallback.
    static bool loadImageBounded(tinygltf::Image* image, const int index, std::string* err, std::string* warn,
                                 int req_width, int req_height, const unsigned char* bytes, int size, void* user) {
        ImageDecoding& decoding = *static_cast<ImageDecoding*>(user);
        if (image->bufferView >= 0 && !decoding.buffer_views_checked) {
            // tinygltf hands over a bufferView's bytes without checking that the view lies inside
            // its buffer: decodeImagesInBufferViews checks, then comes back here.
            decoding.in_buffer_views.push_back(index);
            return true;
        }
        if (isEmptyImageFile(bytes, size)) {
            decoding.not_decoded.emplace(index, ImageDecoding::NotDecoded{"the file is empty (0 bytes)", false});
            return true;
        }
        if (isKtx2(bytes, size)) {
            decoding.not_decoded.emplace(
                index,
                ImageDecoding::NotDecoded{"a KTX2 (Basis Universal) image, which sharcbake does not decode", true});
            return true;
        }
        if (isWebp(bytes, size)) return loadWebp(image, index, err, bytes, size, decoding);
        int width = 0, height = 0, channels = 0;
        if (stbi_info_from_memory(bytes, size, &width, &height, &channels) &&
            !withinTextureLimit(index, width, height, decoding.max_side, err))
            return false;
        std::string decode_err;
        if (tinygltf::LoadImageData(image, index, &decode_err, warn, req_width, req_height, bytes, size, nullptr))
            return true;
        // emplace: a data: URI set aside before parsing (gltf_rewrite.h) keeps its own reason.
        decoding.not_decoded.emplace(index, ImageDecoding::NotDecoded{decodeFailure(decode_err), false});
        return true;
    }

    /// "buffer 'rooms.bin' not found beside the scene (looked in /scenes)": the words a missing
    /// image's warning uses, for a buffer, which the scene cannot load without.
    std::string missingBufferMessage(const std::string& uri, const FileAccess& access) const {
        return "buffer " + quoted(uri) + " not found beside the scene (looked in " + access.folder.string() + ")";
    }

    /// The file tinygltf reported with "File not found : URI" (a required file: a buffer; a
    /// missing image is only a warning), if it did.
    static std::optional<std::string> fileTinygltfDidNotFind(const std::string& err) {
        return tinygltfFileAfter(err, "File not found : ");
    }

    /// NAME of tinygltf's "'NAME' property is missing", if that is its error.
    static std::optional<std::string> tinygltfMissingProperty(const std::string& err) {
        const size_t end = err.find("' property is missing");
        if (end == std::string::npos) return std::nullopt;
        const size_t begin = err.rfind('\'', end == 0 ? 0 : end - 1);
        if (begin == std::string::npos || begin >= end) return std::nullopt;
        return err.substr(begin + 1, end - begin - 1);
    }

    /// The file named after `prefix` in tinygltf's error text ("File is empty : PATH"), if there.
    static std::optional<std::string> tinygltfFileAfter(const std::string& err, const std::string& prefix) {
        const size_t at = err.find(prefix);
        if (at == std::string::npos) return std::nullopt;
        const size_t begin = at + prefix.size();
        const size_t end = err.find('\n', begin);
        return err.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
    }

    void parseFile() {
        if (!std::filesystem::exists(path_)) fail("file not found");
        std::error_code error;
        if (!std::filesystem::is_regular_file(path_, error)) fail("not a regular file");
        FileAccess access{&scene_.source_files,
                          std::filesystem::weakly_canonical(path_, error).parent_path()};
        tinygltf::TinyGLTF parser;
        // tinygltf's own file access, recording each file it reads (the glTF or GLB, external
        // buffers, images): Scene::source_files is then exactly what the scene was loaded from,
        // with tinygltf's URI decoding and its handling of missing images.
        image_decoding_.max_side = limits_.max_texture_size;
        parser.SetImageLoader(&loadImageBounded, &image_decoding_);
        access.search_dir = tinygltfBaseDir(path_);
        parser.SetFsCallbacks(tinygltf::FsCallbacks{&existsBesideScene, &withForwardSlashes, &readAndRecordFile,
                                                    &tinygltf::WriteWholeFile, &access});
        std::ifstream in(path_, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        if (const std::optional<std::string> format = otherModelFormat(bytes, path_)) {
            const std::string glb = std::filesystem::path(path_).replace_extension(".glb").string();
            fail(*format + ", not glTF 2.0: convert it, e.g. `assimp export " + shellWord(path_) + " " +
                 shellWord(glb) + " -f glb2` or Blender's glTF exporter");
        }
        checkJsonNesting(bytes);
        std::string err;
        std::string warnings;
        // Decide by content, not extension: a .gltf that is really binary still loads.
        const bool glb = hasGlbMagic(path_);
        if (glb) checkGlbContainer(bytes);
        access.json = jsonText(bytes, glb);
        std::optional<TinygltfInput> rewritten;
        if (mayNeedRewrite(bytes)) {
            // Recorded first, as tinygltf's reader would (the buffers and images read later must
            // sit beside it), since the rewritten file is parsed from memory.
            scene_.source_files.push_back(std::filesystem::path(path_).lexically_normal().string());
            try {
                rewritten = rewriteForTinygltf(bytes, glb,
                                               [&](const std::string& uri) { return readBufferFile(uri, access); });
            } catch (const GltfRewriteError& e) {
                fail(e.what());
            }
        }
        bool ok = false;
        if (rewritten) {
            draco_index_counts_ = rewritten->draco_index_counts;
            for (const auto& [index, why] : rewritten->refused_image_uris)
                image_decoding_.not_decoded.emplace(index, ImageDecoding::NotDecoded{why, false});
            const std::string base_dir = std::filesystem::path(path_).parent_path().string();
            access.search_dir = base_dir;
            if (rewritten->bytes.size() > std::numeric_limits<unsigned int>::max())
                fail("more than 4 GiB once decompressed; tinygltf cannot parse it");
            const unsigned int size = static_cast<unsigned int>(rewritten->bytes.size());
            ok = rewritten->glb
                     ? parser.LoadBinaryFromMemory(&model_, &err, &warnings,
                                                   reinterpret_cast<const unsigned char*>(rewritten->bytes.data()),
                                                   size, base_dir)
                     : parser.LoadASCIIFromString(&model_, &err, &warnings, rewritten->bytes.data(), size, base_dir);
        } else {
            ok = glb ? parser.LoadBinaryFromFile(&model_, &err, &warnings, path_)
                     : parser.LoadASCIIFromFile(&model_, &err, &warnings, path_);
        }
        if (ok) {
            recordMissingImages(access);
            warnAboutWindowsPaths(access);
            decodeImagesInBufferViews(warnings);
        }
        const std::set<std::string> superseded = tinygltfLinesAboutMissingImages();
        std::istringstream lines(warnings);
        for (std::string line; std::getline(lines, line);)
            if (!line.empty() && !superseded.count(line)) warn("tinygltf: " + line);
        if (ok) {
            // A parse that succeeds can still report errors it recovered from (a baseColorFactor of
            // 2 numbers: the default is kept); they were dropped unsaid.
            std::istringstream errors(err);
            for (std::string line; std::getline(errors, line);)
                if (!line.empty()) warn("tinygltf: " + printable(line) + " (the default is used)");
        }
        if (!ok) {
            if (const std::optional<std::string> problem = versionProblemInJson(jsonText(bytes, glb))) fail(*problem);
            if (const std::optional<std::string> problem = dataUriProblem(jsonText(bytes, glb), err)) fail(*problem);
            if (const std::optional<std::string> uri = fileTinygltfDidNotFind(err); uri && uri->rfind("data:", 0) != 0)
                failMissingFile(missingBufferMessage(*uri, access));
            // tinygltf: "File read error : PATH : File is empty : PATH" for a 0-byte buffer file.
            if (const std::optional<std::string> empty = tinygltfFileAfter(err, "File is empty : ")) {
                fail("buffer file " + quoted(std::filesystem::path(*empty).filename().string()) +
                     " is empty (0 bytes): the scene's geometry is not in it (an interrupted copy or download?)");
            }
            if (const std::optional<std::string> property = tinygltfMissingProperty(err)) {
                if (const std::optional<std::string> object = objectMissingProperty(jsonText(bytes, glb), *property))
                    fail(*object + " lacks \"" + printable(*property) + "\", which glTF requires of it");
            }
            while (!err.empty() && (err.back() == '\n' || err.back() == '\r')) err.pop_back();
            fail("glTF parse failed: " + (err.empty() ? std::string("unknown error") : parserMessage(err)));
        }
        const std::string problem = gltfVersionProblem(model_.asset.version, model_.asset.minVersion);
        if (!problem.empty()) fail(problem);
        warnAboutUndecodedImages();
    }

    /// The images stored in bufferViews, which loadImageBounded set aside, decoded now that the
    /// views can be checked against their buffers (tinygltf found both indices valid). An image
    /// whose view reaches past its buffer is left without texels, as a missing file is. The
    /// decoder's warnings join tinygltf's `warnings`, reported with them.
    void decodeImagesInBufferViews(std::string& warnings) {
        image_decoding_.buffer_views_checked = true;
        for (const int index : image_decoding_.in_buffer_views) {
            tinygltf::Image& image = model_.images[size_t(index)];
            const tinygltf::BufferView& view = model_.bufferViews[size_t(image.bufferView)];
            std::optional<std::string> problem = viewOutsideBuffer(image.bufferView);
            if (!problem && view.byteLength > size_t(std::numeric_limits<int>::max()))
                problem = "bufferView " + std::to_string(image.bufferView) + " holds more than 2 GiB";
            if (problem) {
                image_decoding_.not_decoded.emplace(index, ImageDecoding::NotDecoded{*problem, false});
                continue;
            }
            const tinygltf::Buffer& buffer = model_.buffers[size_t(view.buffer)];
            std::string err;
            if (!loadImageBounded(&image, index, &err, &warnings, 0, 0, buffer.data.data() + view.byteOffset,
                                  int(view.byteLength), &image_decoding_)) {
                while (!err.empty() && err.back() == '\n') err.pop_back();
                fail(err);  // over --max-texture-size
            }
        }
    }

    /// Images whose file is not beside the scene: tinygltf leaves them without texels, and says
    /// only "File not found".
    void recordMissingImages(const FileAccess& access) {
        for (size_t index = 0; index < model_.images.size(); ++index) {
            const tinygltf::Image& image = model_.images[index];
            if (image.uri.empty() || image.uri.rfind("data:", 0) == 0 || !image.image.empty()) continue;
            std::error_code error;
            if (std::filesystem::exists(uriFile(access, image.uri), error)) continue;  // tinygltf says why not read
            const std::string where = "not found beside the scene (looked in " + access.folder.string() + ")";
            image_decoding_.not_decoded.emplace(int(index), ImageDecoding::NotDecoded{where, false, true});
        }
    }

    /// One warning per file read with its URI's '\' taken as '/' (withForwardSlashes).
    void warnAboutWindowsPaths(const FileAccess& access) {
        for (const auto& [written, read] : access.slashed_paths) {
            const std::string file = std::filesystem::path(read).lexically_normal().string();
            if (std::find(scene_.source_files.begin(), scene_.source_files.end(), file) == scene_.source_files.end())
                continue;  // refused (outside the scene's folder): tinygltf's warning says so
            const size_t uri = uriStart(access, written).value_or(0);
            warn("file " + quoted(written.substr(uri)) + " not found; read " + quoted(read.substr(uri)) +
                 ", taking '\\' as a folder separator (a Windows path; glTF URIs use '/')");
        }
    }

    /// tinygltf's warnings about the images recordMissingImages found, which its warning replaces.
    std::set<std::string> tinygltfLinesAboutMissingImages() const {
        std::set<std::string> lines;
        for (const auto& [index, undecoded] : image_decoding_.not_decoded) {
            if (!undecoded.missing) continue;
            const tinygltf::Image& image = model_.images[size_t(index)];
            lines.insert("File not found : " + tinygltfDecodedUri(image.uri));
            lines.insert("Failed to load external 'uri' for image[" + std::to_string(index) + "] name = [" +
                         image.name + "]");
        }
        return lines;
    }

    /// One warning per image that was not found or could not be decoded, used by a texture or
    /// not, saying why. KTX2 images are skipped on purpose (KHR_texture_basisu): their textures
    /// say so.
    void warnAboutUndecodedImages() {
        for (const auto& [index, undecoded] : image_decoding_.not_decoded) {
            if (undecoded.ktx2) continue;
            const std::string problem = undecoded.missing ? " " : " cannot be decoded: ";
            warn(imageLabel(index) + problem + undecoded.why + "; textures using it are ignored");
        }
    }

    /// The GLB container before tinygltf reads it: a header of version 1 is glTF 1.0's
    /// KHR_binary_glTF, and a file cut short fails there with only "Invalid glTF binary".
    void checkGlbContainer(const std::string& bytes) const {
        if (bytes.size() < 8) return;
        uint32_t version = 0;
        std::memcpy(&version, bytes.data() + 4, 4);
        if (version == 1) {
            fail(
                "binary glTF version 1 (glTF 1.0's KHR_binary_glTF) is not supported: sharcbake reads glTF 2.0; "
                "re-export or convert the scene to glTF 2.0");
        }
        if (version != 2) fail("binary glTF version " + std::to_string(version) + " is not supported (GLB 2 expected)");
        // tinygltf says only "Invalid glTF binary." for a file cut short (an interrupted download
        // or copy): the header's and the JSON chunk's lengths against the bytes there are.
        const std::string size = std::to_string(bytes.size());
        if (bytes.size() < 20)
            fail("a GLB file of " + size + " bytes, shorter than its headers (20 bytes): the file is cut short");
        uint32_t length = 0, json_length = 0, json_type = 0;
        std::memcpy(&length, bytes.data() + 8, 4);
        std::memcpy(&json_length, bytes.data() + 12, 4);
        std::memcpy(&json_type, bytes.data() + 16, 4);
        if (length > bytes.size()) {
            fail("the GLB header says the file is " + std::to_string(length) + " bytes, but it has " + size +
                 ": the file is cut short (an interrupted download or copy?) or its header is wrong");
        }
        if (json_type != 0x4E4F534Au) fail("the GLB's first chunk is not its JSON chunk (type 'JSON')");
        if (uint64_t(json_length) + 20 > length) {
            fail("the GLB's JSON chunk says it is " + std::to_string(json_length) + " bytes, but only " +
                 std::to_string(length < 20 ? 0 : length - 20) + " follow it in the file's " + std::to_string(length) +
                 " bytes: the file is cut short or was written wrongly");
        }
    }

    /// An external buffer of a compressed file, read before tinygltf parses it (gltf_rewrite.h),
    /// with the confinement and recording of tinygltf's own reads here.
    std::string readBufferFile(const std::string& uri, const FileAccess& access) const {
        std::vector<unsigned char> data;
        std::string err;
        FileAccess confined = access;
        const std::string file = (std::filesystem::path(path_).parent_path() / uriDecode(uri)).string();
        std::error_code error;
        if (!std::filesystem::exists(file, error)) failMissingFile(missingBufferMessage(uri, access));
        if (!readAndRecordFile(&data, &err, file, &confined)) {
            while (!err.empty() && err.back() == '\n') err.pop_back();
            throw GltfRewriteError("buffer " + quoted(uri) + ": " +
                                   (err.empty() ? std::string("cannot be read") : printable(err)));
        }
        return std::string(data.begin(), data.end());
    }

    void checkRequiredExtensions() const {
        for (const std::string& ext : model_.extensionsRequired) {
            if (ext == "KHR_texture_basisu")
                fail(
                    "required extension \"KHR_texture_basisu\": KTX2 / Basis Universal textures are not supported by "
                    "sharcbake; export PNG or JPEG textures (or give each texture a PNG or JPEG `source` and list "
                    "the extension only in extensionsUsed)");
            const bool known = std::any_of(kSupportedRequiredExtensions.begin(), kSupportedRequiredExtensions.end(),
                                           [&](const char* s) { return ext == s; });
            if (!known) fail("required extension " + quoted(ext) + " is not supported by sharcbake");
        }
    }

    /// Extensions that are only "used" may be ignored by a loader, but some change what the
    /// scene looks like (instancing, transmission), so say so: of those an object of the file
    /// carries. Converters list some that nothing carries (assimp keeps the list of the file it
    /// converted), and those ignore nothing.
    void warnAboutIgnoredExtensions() {
        std::optional<std::map<std::string, Carriers>> carried;
        for (const std::string& ext : model_.extensionsUsed) {
            const auto is = [&](const char* s) { return ext == s; };
            const bool known =
                std::any_of(kSupportedRequiredExtensions.begin(), kSupportedRequiredExtensions.end(), is) ||
                std::any_of(kFallbackOnlyExtensions.begin(), kFallbackOnlyExtensions.end(), is) ||
                std::any_of(kExtensionsThatChangeNothing.begin(), kExtensionsThatChangeNothing.end(), is);
            if (known) continue;
            if (!carried) carried = carriedExtensions();
            const auto found = carried->find(ext);
            if (found == carried->end()) continue;
            const Carriers& on = found->second;
            warn("extension " + quoted(ext) + " (on " + on.first +
                 (on.count > 1
                      ? " and " + std::to_string(on.count - 1) + (on.count == 2 ? " other object" : " other objects")
                      : std::string()) +
                 ") is not supported and is ignored");
        }
    }

    /// The objects that carry one extension: the first, named, and how many in all.
    struct Carriers {
        std::string first;
        size_t count = 0;
    };

    /// The extensions the file's objects carry in their `extensions`, also inside another
    /// extension's object (a texture reference of KHR_materials_specular's has its own), each with
    /// the objects carrying it (a texture reference counts as its material).
    std::map<std::string, Carriers> carriedExtensions() const {
        std::map<std::string, Carriers> carriers;
        std::string owner;               // the object being searched
        std::set<std::string> on_owner;  // its extensions, so a material counts once for each
        const auto note = [&](const std::string& name) {
            if (!on_owner.insert(name).second) return;
            Carriers& c = carriers[name];
            if (c.count++ == 0) c.first = owner;
        };
        std::function<void(const tinygltf::Value&)> inside = [&](const tinygltf::Value& value) {
            if (value.IsArray()) {
                for (size_t i = 0; i < value.ArrayLen(); ++i) inside(value.Get(int(i)));
            } else if (value.IsObject()) {
                for (const std::string& key : value.Keys()) {
                    const tinygltf::Value& member = value.Get(key);
                    if (key == "extensions" && member.IsObject())
                        for (const std::string& name : member.Keys()) note(name);
                    inside(member);
                }
            }
        };
        const auto add = [&](const tinygltf::ExtensionMap& extensions) {
            for (const auto& [name, value] : extensions) {
                note(name);
                inside(value);
            }
        };
        const auto object = [&](std::string label) {
            owner = std::move(label);
            on_owner.clear();
        };
        const auto named = [](std::string label, const std::string& name) {
            return name.empty() ? label : label + " " + quoted(name);
        };
        // Objects with nothing but their own `extensions` to search, labelled "KIND i 'name'".
        const auto each = [&](const auto& objects, const char* kind) {
            for (size_t i = 0; i < objects.size(); ++i) {
                object(named(kind + (" " + std::to_string(i)), objects[i].name));
                add(objects[i].extensions);
            }
        };
        object("the file");
        add(model_.extensions);
        add(model_.asset.extensions);
        for (size_t i = 0; i < model_.scenes.size(); ++i) {
            object(sceneLabel(i));
            add(model_.scenes[i].extensions);
        }
        for (size_t i = 0; i < model_.nodes.size(); ++i) {
            object(nodeLabel(int(i)));
            add(model_.nodes[i].extensions);
        }
        for (size_t i = 0; i < model_.meshes.size(); ++i) {
            const tinygltf::Mesh& mesh = model_.meshes[i];
            object(named("mesh " + std::to_string(i), mesh.name));
            add(mesh.extensions);
            for (size_t p = 0; p < mesh.primitives.size(); ++p) {
                object(meshLabel(int(i), p));
                add(mesh.primitives[p].extensions);
            }
        }
        for (size_t i = 0; i < model_.materials.size(); ++i) {
            const tinygltf::Material& material = model_.materials[i];
            object(named("material " + std::to_string(i), material.name));
            add(material.extensions);
            add(material.pbrMetallicRoughness.extensions);
            add(material.pbrMetallicRoughness.baseColorTexture.extensions);
            add(material.pbrMetallicRoughness.metallicRoughnessTexture.extensions);
            add(material.normalTexture.extensions);
            add(material.occlusionTexture.extensions);
            add(material.emissiveTexture.extensions);
        }
        each(model_.textures, "texture");
        for (size_t i = 0; i < model_.images.size(); ++i) {
            object(imageLabel(int(i)));
            add(model_.images[i].extensions);
        }
        each(model_.samplers, "sampler");
        for (size_t i = 0; i < model_.cameras.size(); ++i) {
            const tinygltf::Camera& camera = model_.cameras[i];
            object(named("camera " + std::to_string(i), camera.name));
            add(camera.extensions);
            add(camera.perspective.extensions);
            add(camera.orthographic.extensions);
        }
        for (size_t i = 0; i < model_.lights.size(); ++i) {
            object(named("light " + std::to_string(i), model_.lights[i].name));
            add(model_.lights[i].extensions);
            add(model_.lights[i].spot.extensions);
        }
        each(model_.accessors, "accessor");
        each(model_.bufferViews, "bufferView");
        each(model_.buffers, "buffer");
        each(model_.skins, "skin");
        for (size_t i = 0; i < model_.animations.size(); ++i) {
            const tinygltf::Animation& animation = model_.animations[i];
            object(named("animation " + std::to_string(i), animation.name));
            add(animation.extensions);
            for (const tinygltf::AnimationChannel& channel : animation.channels) {
                add(channel.extensions);
                add(channel.target_extensions);
            }
            for (const tinygltf::AnimationSampler& sampler : animation.samplers) add(sampler.extensions);
        }
        return carriers;
    }

    // ---------------------------------------------------------------- accessors

    const tinygltf::Accessor& accessorAt(int index, const std::string& what) const {
        if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
            fail(what + ": accessor " + std::to_string(index) + " does not exist");
        return model_.accessors[index];
    }

    /// What is wrong when bufferView `viewIndex` (whose buffer exists) reaches past its buffer's
    /// bytes; nothing when it fits.
    std::optional<std::string> viewOutsideBuffer(int viewIndex) const {
        const tinygltf::BufferView& view = model_.bufferViews[size_t(viewIndex)];
        const tinygltf::Buffer& buffer = model_.buffers[size_t(view.buffer)];
        if (view.byteOffset <= buffer.data.size() && view.byteLength <= buffer.data.size() - view.byteOffset)
            return std::nullopt;
        return "bufferView " + std::to_string(viewIndex) + " spans bytes [" + std::to_string(view.byteOffset) + ", " +
               std::to_string(view.byteOffset + view.byteLength) + ") but buffer " + std::to_string(view.buffer) +
               (buffer.uri.empty() || buffer.uri.rfind("data:", 0) == 0 ? "" : " (" + quoted(buffer.uri) + ")") +
               " holds only " + std::to_string(buffer.data.size()) + " bytes (missing or short buffer)";
    }

    /// Validates that `count` elements of `components` x `componentType`, starting at
    /// `byteOffset` within buffer view `viewIndex`, lie inside the view and the view inside
    /// its buffer, and returns where they are.
    ElementLayout layoutInView(int viewIndex, size_t byteOffset, size_t count, int componentType,
                               int components, bool allowStride, const std::string& what) const {
        if (viewIndex < 0 || static_cast<size_t>(viewIndex) >= model_.bufferViews.size())
            fail(what + ": bufferView " + std::to_string(viewIndex) + " does not exist");
        const tinygltf::BufferView& view = model_.bufferViews[viewIndex];
        if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model_.buffers.size())
            fail(what + ": bufferView " + std::to_string(viewIndex) + " names missing buffer " +
                 std::to_string(view.buffer));
        const tinygltf::Buffer& buffer = model_.buffers[view.buffer];
        if (const std::optional<std::string> problem = viewOutsideBuffer(viewIndex)) fail(what + ": " + *problem);

        const int componentSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(componentType));
        if (componentSize <= 0 || componentType == TINYGLTF_COMPONENT_TYPE_DOUBLE)
            fail(what + ": unsupported component type " + std::to_string(componentType));
        const size_t elementSize = static_cast<size_t>(componentSize) * components;
        const size_t stride = allowStride && view.byteStride != 0 ? view.byteStride : elementSize;
        if (stride < elementSize)
            fail(what + ": byteStride " + std::to_string(stride) + " is smaller than the element size " +
                 std::to_string(elementSize));

        ElementLayout layout{buffer.data.data() + view.byteOffset + byteOffset, stride, count, componentType,
                             components, false};
        if (count == 0) return layout;
        // Every element takes at least one byte, so a count beyond the view length is out of
        // range; checking it first keeps the multiplication below from overflowing.
        const bool fits = byteOffset <= view.byteLength && count <= view.byteLength &&
                          stride * (count - 1) + elementSize <= view.byteLength - byteOffset;
        if (!fits)
            fail(what + ": " + std::to_string(count) + " elements of " + std::to_string(elementSize) +
                 " bytes (stride " + std::to_string(stride) + ") from byte " + std::to_string(byteOffset) +
                 " run past the end of bufferView " + std::to_string(viewIndex) + " (" +
                 std::to_string(view.byteLength) + " bytes): accessor out of buffer range");
        return layout;
    }

    static void readElements(const ElementLayout& layout, std::vector<double>& out, size_t firstOut = 0) {
        const int componentSize = tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(layout.component_type));
        for (size_t i = 0; i < layout.count; ++i) {
            const unsigned char* element = layout.data + i * layout.stride;
            for (int c = 0; c < layout.components; ++c)
                out[(firstOut + i) * layout.components + c] =
                    readComponent(element + c * componentSize, layout.component_type, layout.normalized);
        }
    }

    /// Overwrites the elements a sparse accessor substitutes (glTF 2.0 sparse storage).
    void applySparse(const tinygltf::Accessor& acc, int components, std::vector<double>& out,
                     const std::string& what) const {
        const auto& sparse = acc.sparse;
        if (sparse.count <= 0 || static_cast<size_t>(sparse.count) > acc.count)
            fail(what + ": sparse count " + std::to_string(sparse.count) + " is invalid for " +
                 std::to_string(acc.count) + " elements");
        const int indexType = sparse.indices.componentType;
        if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(what + ": sparse indices have unsupported component type " + std::to_string(indexType));
        const auto count = static_cast<size_t>(sparse.count);
        ElementLayout indices = layoutInView(sparse.indices.bufferView, static_cast<size_t>(sparse.indices.byteOffset),
                                             count, indexType, 1, false, what + " (sparse indices)");
        ElementLayout values = layoutInView(sparse.values.bufferView, static_cast<size_t>(sparse.values.byteOffset),
                                            count, acc.componentType, components, false, what + " (sparse values)");
        values.normalized = acc.normalized;
        std::vector<double> target(count);
        readElements(indices, target);
        std::vector<double> substitutes(count * components);
        readElements(values, substitutes);
        for (size_t i = 0; i < count; ++i) {
            const double t = target[i];
            if (t >= static_cast<double>(acc.count))
                fail(what + ": sparse index " + std::to_string(static_cast<uint64_t>(t)) + " out of range (" +
                     std::to_string(acc.count) + " elements)");
            const auto dst = static_cast<size_t>(t);
            for (int c = 0; c < components; ++c) out[dst * components + c] = substitutes[i * components + c];
        }
    }

    /// Reads any accessor as doubles (exact for every glTF component type), count x components.
    /// glTF's word for an accessor type ("VEC3"), for messages; tinygltf keeps a number.
    static std::string accessorTypeName(int type) {
        switch (type) {
            case TINYGLTF_TYPE_SCALAR: return "SCALAR";
            case TINYGLTF_TYPE_VEC2: return "VEC2";
            case TINYGLTF_TYPE_VEC3: return "VEC3";
            case TINYGLTF_TYPE_VEC4: return "VEC4";
            case TINYGLTF_TYPE_MAT2: return "MAT2";
            case TINYGLTF_TYPE_MAT3: return "MAT3";
            case TINYGLTF_TYPE_MAT4: return "MAT4";
        }
        return "unknown (" + std::to_string(type) + ")";
    }

    std::vector<double> readAccessor(int index, int expectedType, const std::string& what) const {
        const std::string label = what + " (accessor " + std::to_string(index) + ")";
        const tinygltf::Accessor& acc = accessorAt(index, what);
        if (acc.type != expectedType)
            fail(label + ": has type " + accessorTypeName(acc.type) + ", expected " + accessorTypeName(expectedType));
        const int components = tinygltf::GetNumComponentsInType(static_cast<uint32_t>(acc.type));
        // Bound the allocation before making it: an 8 KB file must not cost gigabytes. Elements in
        // a bufferView take at least a byte each; a zero-filled accessor gets the same allowance.
        uint64_t buffer_bytes = 0;
        for (const tinygltf::Buffer& b : model_.buffers) buffer_bytes += b.data.size();
        const uint64_t max_elements = std::max<uint64_t>(uint64_t(1) << 16, buffer_bytes);
        if (components <= 0 || acc.count > max_elements) {
            fail(label + ": count " + std::to_string(acc.count) + " is more than the scene's buffers can hold (" +
                 std::to_string(max_elements) + " elements at most)");
        }
        std::vector<double> out(acc.count * size_t(components), 0.0);
        // Without a bufferView the accessor is all zeros (plus any sparse substitutions).
        if (acc.bufferView >= 0) {
            ElementLayout layout =
                layoutInView(acc.bufferView, acc.byteOffset, acc.count, acc.componentType, components, true, label);
            layout.normalized = acc.normalized;
            readElements(layout, out);
        } else if (tinygltf::GetComponentSizeInBytes(static_cast<uint32_t>(acc.componentType)) <= 0) {
            fail(label + ": unsupported component type " + std::to_string(acc.componentType));
        }
        if (acc.sparse.isSparse) applySparse(acc, components, out, label);
        return out;
    }

    std::vector<glm::vec3> readVec3(int index, const std::string& what) const {
        const std::vector<double> raw = readAccessor(index, TINYGLTF_TYPE_VEC3, what);
        std::vector<glm::vec3> out(raw.size() / 3);
        for (size_t i = 0; i < out.size(); ++i)
            out[i] = glm::vec3(glm::dvec3(raw[3 * i], raw[3 * i + 1], raw[3 * i + 2]));
        return out;
    }

    std::vector<glm::vec4> readVec4(int index, const std::string& what) const {
        const std::vector<double> raw = readAccessor(index, TINYGLTF_TYPE_VEC4, what);
        std::vector<glm::vec4> out(raw.size() / 4);
        for (size_t i = 0; i < out.size(); ++i)
            out[i] = glm::vec4(glm::dvec4(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2], raw[4 * i + 3]));
        return out;
    }

    /// COLOR_0: VEC3 or VEC4 of floats or normalized unsigned bytes/shorts, linear (glTF says
    /// vertex colours are linear); alpha 1 where absent. Non-finite or negative values are
    /// clamped to [0, 1] with a warning rather than poisoning every path that hits them.
    std::vector<glm::vec4> readColors(int index, const std::string& what) {
        const tinygltf::Accessor& acc = accessorAt(index, what);
        const bool rgba = acc.type == TINYGLTF_TYPE_VEC4;
        const std::vector<double> raw = readAccessor(index, rgba ? TINYGLTF_TYPE_VEC4 : TINYGLTF_TYPE_VEC3, what);
        return colorsFromValues(raw, rgba ? 4 : 3, what);
    }

    /// RGB or RGBA colours, `components` values each, into RGBA (alpha 1 where absent); values
    /// outside [0, 1] or not finite are clamped (non-finite to 1) with a warning.
    template <typename T>
    std::vector<glm::vec4> colorsFromValues(const std::vector<T>& raw, size_t components, const std::string& what) {
        std::vector<glm::vec4> out(raw.size() / components, glm::vec4(1.0f));
        size_t clamped = 0;
        for (size_t i = 0; i < out.size(); ++i) {
            for (size_t c = 0; c < components; ++c) {
                const T v = raw[components * i + c];
                const T safe = std::isfinite(v) ? std::clamp(v, T(0), T(1)) : T(1);
                clamped += safe != v;
                out[i][int(c)] = float(safe);
            }
        }
        if (clamped > 0) warn(what + ": " + std::to_string(clamped) + " values outside [0, 1] clamped");
        return out;
    }

    std::vector<glm::vec2> readVec2(int index, const std::string& what) const {
        const std::vector<double> raw = readAccessor(index, TINYGLTF_TYPE_VEC2, what);
        std::vector<glm::vec2> out(raw.size() / 2);
        for (size_t i = 0; i < out.size(); ++i) out[i] = glm::vec2(glm::dvec2(raw[2 * i], raw[2 * i + 1]));
        return out;
    }

    std::vector<uint32_t> readIndices(int index, size_t vertexCount, const std::string& what) const {
        const tinygltf::Accessor& acc = accessorAt(index, what + " indices");
        const int type = acc.componentType;
        if (type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            fail(what + " indices (accessor " + std::to_string(index) + "): component type " + std::to_string(type) +
                 " is not an unsigned integer type");
        if (acc.normalized) fail(what + " indices (accessor " + std::to_string(index) + "): normalized indices");
        const std::vector<double> raw = readAccessor(index, TINYGLTF_TYPE_SCALAR, what + " indices");
        std::vector<uint32_t> out(raw.size());
        for (size_t i = 0; i < raw.size(); ++i) {
            if (raw[i] >= static_cast<double>(vertexCount))
                fail(what + " indices (accessor " + std::to_string(index) + "): index " +
                     std::to_string(static_cast<uint64_t>(raw[i])) + " at position " + std::to_string(i) +
                     " out of range (" + std::to_string(vertexCount) + " vertices)");
            out[i] = static_cast<uint32_t>(raw[i]);
        }
        return out;
    }

    // ---------------------------------------------------------------- scene graph

    /// The scene loaded: the default one, else scene 0. The file must have scenes.
    const tinygltf::Scene& loadedScene() const {
        int s = model_.defaultScene;
        if (s < 0 || static_cast<size_t>(s) >= model_.scenes.size()) s = 0;
        return model_.scenes[static_cast<size_t>(s)];
    }

    std::string sceneLabel(size_t index) const {
        const std::string& name = model_.scenes[index].name;
        return "scene " + std::to_string(index) + (name.empty() ? "" : " " + quoted(name));
    }

    /// A "scene" index the file does not have falls back to scene 0, as viewers do; said, since
    /// the file meant another.
    void warnAboutAMissingDefaultScene() {
        const int s = model_.defaultScene;
        if (model_.scenes.empty() || s < 0 || size_t(s) < model_.scenes.size()) return;
        warn("the file's \"scene\" is " + std::to_string(s) + ", but it has " + std::to_string(model_.scenes.size()) +
             (model_.scenes.size() == 1 ? " scene" : " scenes") + ": " + sceneLabel(0) + " is loaded");
    }

    /// Whether any node under `root` has a mesh (cycles were refused while visiting the scene;
    /// `seen` keeps a bad file from looping here too).
    bool placesAMesh(int root, std::vector<bool>& seen) const {
        if (root < 0 || size_t(root) >= model_.nodes.size() || seen[size_t(root)]) return false;
        seen[size_t(root)] = true;
        const tinygltf::Node& node = model_.nodes[size_t(root)];
        if (node.mesh >= 0) return true;
        for (const int child : node.children)
            if (placesAMesh(child, seen)) return true;
        return false;
    }

    static std::string rootsListed(size_t count) {
        if (count == 0) return "it lists no root nodes";
        return "it lists " + std::to_string(count) + (count == 1 ? " root node" : " root nodes") + ", none with a mesh";
    }

    /// A loaded scene that places none of the file's meshes (its node list empty, or its nodes
    /// without meshes) loads as nothing: "0 triangles", with the meshes sitting in another scene
    /// or on nodes no scene lists. Said, with the scenes that do place them.
    void warnAboutMeshesOutsideTheScene() {
        if (mesh_nodes_visited_ > 0 || model_.meshes.empty() || model_.scenes.empty()) return;
        const size_t loaded = size_t(&loadedScene() - model_.scenes.data());
        std::string others;
        for (size_t s = 0; s < model_.scenes.size(); ++s) {
            if (s == loaded) continue;
            std::vector<bool> seen(model_.nodes.size(), false);
            bool places = false;
            for (const int root : model_.scenes[s].nodes) places = places || placesAMesh(root, seen);
            if (places) others += (others.empty() ? "" : ", ") + sceneLabel(s);
        }
        const size_t meshes = model_.meshes.size();
        warn(sceneLabel(loaded) + ", the one loaded, places none of the file's " + std::to_string(meshes) +
             (meshes == 1 ? " mesh" : " meshes") + " (" + rootsListed(loadedScene().nodes.size()) + "); " +
             (others.empty() ? std::string("they are on nodes no scene lists")
                             : others + " place" + (others.find(',') == std::string::npos ? "s" : "") +
                                   " them: make it the file's \"scene\" (the one loaded)"));
    }

    /// The loaded scene's roots, else every node that is nobody's child.
    std::vector<int> rootNodes() const {
        if (!model_.scenes.empty()) return loadedScene().nodes;
        std::vector<bool> isChild(model_.nodes.size(), false);
        for (const tinygltf::Node& n : model_.nodes)
            for (int c : n.children)
                if (c >= 0 && static_cast<size_t>(c) < isChild.size()) isChild[c] = true;
        std::vector<int> roots;
        for (size_t i = 0; i < isChild.size(); ++i)
            if (!isChild[i]) roots.push_back(static_cast<int>(i));
        return roots;
    }

    /// Leaves out the repeats of an index in `list` (the first of each stays); returns each
    /// repeated index with how many times it was listed, in the order of the list.
    static std::vector<std::pair<int, int>> removeRepeats(std::vector<int>& list) {
        std::vector<std::pair<int, int>> repeated;
        if (list.size() < 2) return repeated;
        std::map<int, int> count;
        for (int index : list) ++count[index];
        if (count.size() == list.size()) return repeated;
        std::vector<int> unique;
        for (int index : list) {
            int& n = count[index];
            if (n == 0) continue;  // listed before
            if (n > 1) repeated.emplace_back(index, n);
            unique.push_back(index);
            n = 0;
        }
        list = std::move(unique);
        return repeated;
    }

    /// "node 3 'Lamp'", or "node 3" for a node without a name (or no node at all).
    std::string nodeLabel(int index) const {
        std::string label = "node " + std::to_string(index);
        if (index >= 0 && static_cast<size_t>(index) < model_.nodes.size() &&
            !model_.nodes[size_t(index)].name.empty()) {
            label += ' ';
            label += quoted(model_.nodes[size_t(index)].name);
        }
        return label;
    }

    /// glTF wants a node's children listed once each; a node listed twice was loaded twice at
    /// one place (two copies of its meshes on each other, its light twice as bright).
    void removeRepeatedChildren() {
        for (size_t i = 0; i < model_.nodes.size(); ++i) {
            for (const auto& [child, times] : removeRepeats(model_.nodes[i].children)) {
                warn(nodeLabel(int(i)) + " lists " + nodeLabel(child) + " " + std::to_string(times) +
                     " times among its children; glTF wants each once: it is loaded once");
            }
        }
    }

    /// rootNodes() with each listed once, as glTF wants (a root listed twice was loaded twice at
    /// one place), and a warning for each repeat.
    std::vector<int> uniqueRootNodes() {
        std::vector<int> roots = rootNodes();
        for (const auto& [root, times] : removeRepeats(roots)) {
            warn("the scene lists " + nodeLabel(root) + " " + std::to_string(times) +
                 " times among its root nodes; glTF wants each once: it is loaded once");
        }
        return roots;
    }

    /// glTF allows a node one parent, and a root none. A node under two (two nodes list it as a
    /// child, or the scene lists as a root a node that another lists) sits at two places: it is
    /// loaded at each, a copy under each parent, as the loader always did (viewers differ: three.js
    /// keeps one); said here, since the copies double what it holds.
    void warnAboutSeveralParents() {
        for (const auto& [node, others] : other_parents_) {
            std::vector<int> parents{first_parent_[size_t(node)]};
            parents.insert(parents.end(), others.begin(), others.end());
            std::string where;
            for (size_t i = 0; i < parents.size(); ++i) {
                where += i == 0 ? "" : i + 1 == parents.size() ? " and " : ", ";
                where += parents[i] < 0 ? "a root of the scene" : "the child of " + nodeLabel(parents[i]);
            }
            warn(nodeLabel(node) + " is " + where + "; glTF allows a node one parent: a copy of it (and of its " +
                 "children) is loaded at each place, " + std::to_string(parents.size()) + " in all");
        }
    }

    /// glTF's rotations are unit quaternions; exporters write them so to a few digits. Another
    /// length is normalised (a zero one is no rotation) and said, as is an array of another size.
    void warnAboutRotation(int index, const tinygltf::Node& node) {
        if (node.matrix.size() == 16 || node.rotation.empty()) return;
        const std::string label = nodeLabel(index);
        if (node.rotation.size() != 4) {
            warn(label + ": rotation has " + std::to_string(node.rotation.size()) + " numbers, glTF wants 4; ignored");
            return;
        }
        const double length = std::sqrt(node.rotation[0] * node.rotation[0] + node.rotation[1] * node.rotation[1] +
                                        node.rotation[2] * node.rotation[2] + node.rotation[3] * node.rotation[3]);
        if (length == 0.0) {
            warn(label + ": rotation (0, 0, 0, 0) is no unit quaternion; no rotation used");
        } else if (std::isfinite(length) && std::abs(length - 1.0) > 1e-3) {  // NaN: the transform's check refuses it
            warn(label + ": rotation of length " + numberText(float(length)) + " is no unit quaternion; normalised");
        }
    }

    /// The rotation of a node's world transform: localOrientation along its path from the root,
    /// what orients a light where a zero scale leaves its -Z axis no direction; or the nearest node
    /// of the path whose matrix is singular, where there is no orientation.
    struct WorldOrientation {
        glm::dmat3 rotation{1.0};
        int singular_node = -1;
    };
    WorldOrientation pathOrientation(const std::vector<int>& path) const {
        WorldOrientation o;
        for (int index : path) {
            if (const std::optional<glm::dmat3> local = localOrientation(model_.nodes[size_t(index)]))
                o.rotation *= *local;
            else o.singular_node = index;
        }
        return o;
    }

    /// Depth-first over the hierarchy under `root` with an explicit stack, not recursion, so a
    /// crafted chain of 20,000 nested nodes cannot overflow the call stack.
    void visitNode(int root, const glm::dmat4& parent) {
        struct Frame {
            int index;
            glm::dmat4 world;
            size_t next_child;
        };
        std::vector<Frame> stack;
        const auto enter = [&](int index, const glm::dmat4& parent_world, int parent_index) {
            if (index < 0 || static_cast<size_t>(index) >= model_.nodes.size())
                fail("node " + std::to_string(index) + " does not exist");
            if (on_path_.empty()) on_path_.assign(model_.nodes.size(), false);
            if (on_path_[index])
                fail("node " + std::to_string(index) + " is its own ancestor (cycle in the node hierarchy)");
            on_path_[index] = true;
            if (first_parent_.empty()) first_parent_.assign(model_.nodes.size(), -2);
            if (first_parent_[index] == -2) {
                first_parent_[index] = parent_index;
            } else if (first_parent_[index] != parent_index) {
                std::vector<int>& others = other_parents_[index];
                if (std::find(others.begin(), others.end(), parent_index) == others.end())
                    others.push_back(parent_index);
            }
            const tinygltf::Node& node = model_.nodes[index];
            warnAboutRotation(index, node);
            const glm::dmat4 world = parent_world * localTransform(node);
            if (node.mesh >= 0) {
                ++mesh_nodes_visited_;
                const auto instancing = node.extensions.find("EXT_mesh_gpu_instancing");
                if (instancing == node.extensions.end()) {
                    addMesh(node.mesh, world, index);
                } else {
                    // The node's mesh is drawn once per instance, each relative to the node.
                    for (const glm::dmat4& instance : instanceTransforms(index, instancing->second))
                        addMesh(node.mesh, world * instance, index);
                }
            }
            if (node.camera >= 0) addCamera(node, world);
            // The path's orientation is made only for a light that needs it (a rare zero scale).
            addNodeLight(index, world, [&] {
                std::vector<int> path;
                for (const Frame& f : stack) path.push_back(f.index);
                path.push_back(index);
                return pathOrientation(path);
            });
            stack.push_back(Frame{index, world, 0});
        };
        enter(root, parent, -1);
        while (!stack.empty()) {
            Frame& top = stack.back();
            const std::vector<int>& children = model_.nodes[top.index].children;
            if (top.next_child < children.size()) {
                const int child = children[top.next_child++];
                const glm::dmat4 world = top.world;  // `top` moves when the stack grows
                enter(child, world, top.index);
            } else {
                on_path_[top.index] = false;
                stack.pop_back();
            }
        }
    }

    /// EXT_mesh_gpu_instancing: one T * R * S per instance from the TRANSLATION, ROTATION and
    /// SCALE accessors (each optional, at least one given, all of one count); other attributes
    /// (the extension allows application-specific ones starting with "_") are ignored.
    std::vector<glm::dmat4> instanceTransforms(int nodeIndex, const tinygltf::Value& extension) {
        const std::string label = "node " + std::to_string(nodeIndex) + " EXT_mesh_gpu_instancing";
        const tinygltf::Value& attributes = extension.Get("attributes");
        const auto accessorOf = [&](const char* name) {
            if (!attributes.IsObject() || !attributes.Has(name)) return -1;
            const tinygltf::Value& v = attributes.Get(name);
            if (!v.IsInt() || v.GetNumberAsInt() < 0) fail(label + ": " + name + " is not an accessor index");
            return v.GetNumberAsInt();
        };
        const int t = accessorOf("TRANSLATION"), r = accessorOf("ROTATION"), sc = accessorOf("SCALE");
        if (t < 0 && r < 0 && sc < 0) fail(label + ": \"attributes\" has none of TRANSLATION, ROTATION and SCALE");
        const std::vector<glm::vec3> translations = t >= 0 ? readVec3(t, label + " TRANSLATION")
                                                           : std::vector<glm::vec3>();
        const std::vector<glm::vec4> rotations = r >= 0 ? readVec4(r, label + " ROTATION") : std::vector<glm::vec4>();
        const std::vector<glm::vec3> scales = sc >= 0 ? readVec3(sc, label + " SCALE") : std::vector<glm::vec3>();
        const size_t count = t >= 0 ? translations.size() : r >= 0 ? rotations.size() : scales.size();
        const auto checkCount = [&](int accessor, size_t n, const char* name) {
            if (accessor >= 0 && n != count)
                fail(label + ": " + name + " has " + std::to_string(n) + " elements, the other attributes " +
                     std::to_string(count));
        };
        checkCount(t, translations.size(), "TRANSLATION");
        checkCount(r, rotations.size(), "ROTATION");
        checkCount(sc, scales.size(), "SCALE");
        const uint64_t triangles = meshTriangleBound(model_.nodes[nodeIndex].mesh);
        if (triangles > 0 && uint64_t(count) > kMaxInstancedTriangles / triangles)
            fail(label + ": " + std::to_string(count) + " instances of a mesh of up to " + std::to_string(triangles) +
                 " triangles would make more than " + std::to_string(kMaxInstancedTriangles) +
                 " triangles; sharcbake copies every instance into the traced scene");

        std::vector<glm::dmat4> transforms(count);
        for (size_t i = 0; i < count; ++i) {
            const std::string which = label + ": instance " + std::to_string(i);
            if (t >= 0 && !isFinite(translations[i])) fail(which + " has a NaN or infinite TRANSLATION");
            if (r >= 0) {
                const double length = glm::length(glm::dvec4(rotations[i]));
                if (!std::isfinite(length) || length < 1e-6) fail(which + " has a zero, NaN or infinite ROTATION");
            }
            if (sc >= 0 && !isFinite(scales[i])) fail(which + " has a NaN or infinite SCALE");
            transforms[i] = composeTrs(t >= 0 ? std::optional<glm::dvec3>(translations[i]) : std::nullopt,
                                       r >= 0 ? std::optional<glm::dvec4>(rotations[i]) : std::nullopt,
                                       sc >= 0 ? std::optional<glm::dvec3>(scales[i]) : std::nullopt);
        }
        return transforms;
    }

    /// At most how many triangles one copy of a mesh adds, from its accessors' counts (before
    /// degenerate triangles are dropped).
    uint64_t meshTriangleBound(int meshIndex) const {
        if (meshIndex < 0 || static_cast<size_t>(meshIndex) >= model_.meshes.size()) return 0;
        uint64_t triangles = 0;
        for (size_t p = 0; p < model_.meshes[meshIndex].primitives.size(); ++p) {
            const tinygltf::Primitive& prim = model_.meshes[meshIndex].primitives[p];
            if (!isTriangleMode(prim.mode)) continue;
            if (const auto draco = draco_index_counts_.find({meshIndex, int(p)}); draco != draco_index_counts_.end()) {
                triangles += draco->second / 3;  // Draco decodes to a triangle list
                continue;
            }
            int counted = prim.indices;
            if (counted < 0) {
                const auto position = prim.attributes.find("POSITION");
                counted = position == prim.attributes.end() ? -1 : position->second;
            }
            if (counted < 0 || static_cast<size_t>(counted) >= model_.accessors.size()) continue;
            const uint64_t n = model_.accessors[counted].count;
            const bool list = prim.mode != TINYGLTF_MODE_TRIANGLE_STRIP && prim.mode != TINYGLTF_MODE_TRIANGLE_FAN;
            triangles += list ? n / 3 : (n > 2 ? n - 2 : 0);
        }
        return triangles;
    }

    // ---------------------------------------------------------------- geometry

    void addMesh(int meshIndex, const glm::dmat4& world, int nodeIndex) {
        if (static_cast<size_t>(meshIndex) >= model_.meshes.size())
            fail("node " + std::to_string(nodeIndex) + " names missing mesh " + std::to_string(meshIndex));
        const tinygltf::Node& node = model_.nodes[nodeIndex];
        // A skinned mesh is posed by its joints as the file's node transforms place them, as
        // viewers show it; its own node's transform is not used (glTF 2.0, "Skins").
        std::vector<glm::dmat4> joints;
        if (node.skin >= 0) {
            if (node.extensions.count("EXT_mesh_gpu_instancing"))
                warn("node " + std::to_string(nodeIndex) +
                     ": skinning of an instanced mesh ignored, mesh used in its bind pose");
            else joints = jointMatrices(node.skin, "node " + std::to_string(nodeIndex));
        }
        const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
        // A static scene shows the morph targets at their default weights: the node's, else the
        // mesh's (glTF 2.0, "Morph Targets"), as viewers and Blender's own shape keys do.
        const std::vector<double>& weights = !model_.nodes[nodeIndex].weights.empty() ? model_.nodes[nodeIndex].weights
                                                                                      : mesh.weights;
        for (size_t p = 0; p < mesh.primitives.size(); ++p) addPrimitive(meshIndex, p, world, weights, joints);
    }

    /// The world matrix of every node of the file (a joint need not be in the displayed scene),
    /// from the roots down; made once.
    const std::vector<glm::dmat4>& nodeWorlds() {
        if (!node_worlds_.empty() || model_.nodes.empty()) return node_worlds_;
        const size_t n = model_.nodes.size();
        std::vector<int> parent(n, -1);
        for (size_t i = 0; i < n; ++i)
            for (int c : model_.nodes[i].children)
                if (c >= 0 && static_cast<size_t>(c) < n) parent[size_t(c)] = int(i);
        node_worlds_.assign(n, glm::dmat4(1.0));
        std::vector<uint8_t> state(n, 0);  // 0: not yet, 1: on the chain being made, 2: made
        std::vector<int> chain;
        for (size_t i = 0; i < n; ++i) {
            chain.clear();
            int k = int(i);
            while (k >= 0 && state[size_t(k)] != 2) {
                if (state[size_t(k)] == 1)
                    fail("node " + std::to_string(k) + " is its own ancestor (cycle in the node hierarchy)");
                state[size_t(k)] = 1;
                chain.push_back(k);
                k = parent[size_t(k)];
            }
            glm::dmat4 world = k >= 0 ? node_worlds_[size_t(k)] : glm::dmat4(1.0);
            for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
                world = world * localTransform(model_.nodes[size_t(*it)]);
                node_worlds_[size_t(*it)] = world;
                state[size_t(*it)] = 2;
            }
        }
        return node_worlds_;
    }

    /// Each joint's skinning matrix: its node's world matrix times its inverse bind matrix
    /// (identity where the skin gives none).
    std::vector<glm::dmat4> jointMatrices(int skinIndex, const std::string& owner) {
        if (skinIndex < 0 || static_cast<size_t>(skinIndex) >= model_.skins.size())
            fail(owner + " names missing skin " + std::to_string(skinIndex));
        const tinygltf::Skin& skin = model_.skins[size_t(skinIndex)];
        const std::string label = owner + " skin " + std::to_string(skinIndex);
        if (skin.joints.empty()) fail(label + ": no joints");
        std::vector<double> inverse_bind;
        if (skin.inverseBindMatrices >= 0) {
            inverse_bind = readAccessor(skin.inverseBindMatrices, TINYGLTF_TYPE_MAT4, label + " inverseBindMatrices");
            if (inverse_bind.size() < 16 * skin.joints.size())
                fail(label + ": " + std::to_string(inverse_bind.size() / 16) + " inverse bind matrices for " +
                     std::to_string(skin.joints.size()) + " joints");
        }
        const std::vector<glm::dmat4>& worlds = nodeWorlds();
        std::vector<glm::dmat4> joints;
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            const int node = skin.joints[j];
            if (node < 0 || static_cast<size_t>(node) >= worlds.size())
                fail(label + ": joint " + std::to_string(j) + " names missing node " + std::to_string(node));
            const glm::dmat4 inverse = inverse_bind.empty() ? glm::dmat4(1.0) : glm::make_mat4(&inverse_bind[16 * j]);
            joints.push_back(worlds[size_t(node)] * inverse);
        }
        return joints;
    }

    static bool isTriangleMode(int mode) {
        return mode == -1 || mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP ||
               mode == TINYGLTF_MODE_TRIANGLE_FAN;
    }

    void addPrimitive(int meshIndex, size_t primIndex, const glm::dmat4& world, const std::vector<double>& weights,
                      const std::vector<glm::dmat4>& joints) {
        const tinygltf::Primitive& prim = model_.meshes[meshIndex].primitives[primIndex];
        const std::string label = meshLabel(meshIndex, primIndex);
        if (!isTriangleMode(prim.mode)) {
            ++scene_.stats.primitives_skipped;  // points and lines have no surface to hit
            return;
        }
        PrimitiveGeometry geo;
        std::vector<uint32_t> indices;
        int mode = prim.mode;
        if (const tinygltf::Value* draco = extension(prim.extensions, "KHR_draco_mesh_compression")) {
            readDracoPrimitive(prim, *draco, label, geo, indices);
            mode = TINYGLTF_MODE_TRIANGLES;  // Draco decodes to a triangle list whatever the mode
        } else {
            geo = readPrimitive(prim, label);
            indices = primitiveIndices(prim, geo.positions.size(), label);
        }
        if (mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN && indices.size() % 3 != 0)
            warn(label + ": " + std::to_string(indices.size()) + " indices is not a multiple of 3; the last " +
                 std::to_string(indices.size() % 3) + " ignored");
        geo.triangles = assembleTriangles(mode, indices);

        applyMorphTargets(prim, weights, label, geo);
        const bool skinned = !joints.empty() && prim.attributes.count("JOINTS_0") && prim.attributes.count("WEIGHTS_0");
        if (skinned && extension(prim.extensions, "KHR_draco_mesh_compression")) {
            warn(label + ": skinning of a Draco-compressed primitive ignored, mesh used in its bind pose");
            transformToWorld(geo, world, label);
        } else if (skinned) {
            skinToWorld(prim, joints, world, label, geo);
        } else {
            if (!joints.empty())
                warn(label + ": skinned node without JOINTS_0 and WEIGHTS_0; mesh used in its bind pose");
            transformToWorld(geo, world, label);
        }
        const size_t triangles_read = geo.triangles.size();
        dropDegenerateTriangles(geo);
        if (geo.normals.empty()) makeFlatShaded(geo);
        else repairNormals(geo, label);
        const uint32_t material = materialForPrimitive(prim, meshIndex, primIndex, label);
        if (triangles_read > 0) {
            std::pair<size_t, size_t>& counts = triangles_by_material_[material];
            counts.first += triangles_read;
            counts.second += geo.triangles.size();
        }
        if (const TextureRef& map = scene_.materials[material].normal_texture; map.isSet()) {
            if (geo.tangents.empty()) {
                computeTangents(geo, transformedUvs(map.texcoord == 1 ? geo.uv1 : geo.uv0, map.transform), label);
            } else if (!map.transform.identity) {
                turnTangents(geo, map.transform);
            }
        }
        appendGeometry(geo, material);
    }

    /// KHR_draco_mesh_compression: the attributes the extension names, and the indices, come
    /// from the Draco data in its bufferView; attributes it does not name are read from their
    /// accessors as usual. The rules of readPrimitive apply to what comes out.
    void readDracoPrimitive(const tinygltf::Primitive& prim, const tinygltf::Value& ext, const std::string& label,
                            PrimitiveGeometry& geo, std::vector<uint32_t>& indices) {
        const std::string what = label + " KHR_draco_mesh_compression";
        const std::optional<double> view = number(ext, "bufferView");
        if (!view || *view < 0 || *view != std::floor(*view)) fail(what + ": no bufferView");
        const int viewIndex = static_cast<int>(*view);
        if (static_cast<size_t>(viewIndex) >= model_.bufferViews.size())
            fail(what + ": bufferView " + std::to_string(viewIndex) + " does not exist");
        const size_t bytes = model_.bufferViews[static_cast<size_t>(viewIndex)].byteLength;
        const ElementLayout data = layoutInView(viewIndex, 0, bytes, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, 1, false,
                                                what);
        std::optional<DracoMesh> mesh;
        try {
            mesh.emplace(data.data, bytes);
        } catch (const std::runtime_error& e) {
            fail(what + " (bufferView " + std::to_string(viewIndex) + "): " + e.what());
        }
        const tinygltf::Value* ids = ext.Has("attributes") && ext.Get("attributes").IsObject() ? &ext.Get("attributes")
                                                                                               : nullptr;
        const auto dracoId = [&](const char* name) {
            if (!ids || !ids->Has(name) || !ids->Get(name).IsInt()) return -1;
            return ids->Get(name).GetNumberAsInt();
        };
        const size_t points = mesh->pointCount();
        // One glTF attribute, from the Draco data if the extension names it, else its accessor.
        const auto read = [&](const char* name, int components, std::vector<float>& out) {
            const auto accessor = prim.attributes.find(name);
            const int id = dracoId(name);
            if (id < 0) {
                if (accessor == prim.attributes.end()) return false;
                const std::vector<double> raw = readAccessor(accessor->second,
                                                             components == 2   ? TINYGLTF_TYPE_VEC2
                                                             : components == 3 ? TINYGLTF_TYPE_VEC3
                                                                               : TINYGLTF_TYPE_VEC4,
                                                             label + " " + name);
                out.assign(raw.begin(), raw.end());
            } else {
                if (mesh->componentCount(id) == 0)
                    fail(what + ": attribute " + name + " names Draco attribute " + std::to_string(id) +
                         ", which it lacks");
                const bool normalized = accessor != prim.attributes.end() && accessor->second >= 0 &&
                                        static_cast<size_t>(accessor->second) < model_.accessors.size() &&
                                        model_.accessors[static_cast<size_t>(accessor->second)].normalized;
                out = mesh->attribute(id, components, normalized);
            }
            if (out.size() != points * size_t(components))
                fail(label + ": " + name + " has " + std::to_string(out.size() / size_t(components)) +
                     " elements but the Draco data has " + std::to_string(points) + " points");
            return true;
        };
        std::vector<float> values;
        if (dracoId("POSITION") < 0) fail(what + ": the extension names no POSITION attribute");
        read("POSITION", 3, values);
        geo.positions.resize(points);
        for (size_t i = 0; i < points; ++i) {
            geo.positions[i] = glm::vec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
            if (!isFinite(geo.positions[i]))
                fail(what + ": POSITION of point " + std::to_string(i) + " is NaN or infinite");
        }
        if (read("NORMAL", 3, values)) {
            geo.normals.resize(points);
            for (size_t i = 0; i < points; ++i)
                geo.normals[i] = glm::vec3(values[3 * i], values[3 * i + 1], values[3 * i + 2]);
        }
        for (auto [name, uv] : {std::pair{"TEXCOORD_0", &geo.uv0}, std::pair{"TEXCOORD_1", &geo.uv1}}) {
            if (!read(name, 2, values)) continue;
            uv->resize(points);
            for (size_t i = 0; i < points; ++i) (*uv)[i] = glm::vec2(values[2 * i], values[2 * i + 1]);
        }
        if (read("TANGENT", 4, values)) {
            geo.tangents.resize(points);
            for (size_t i = 0; i < points; ++i)
                geo.tangents[i] = glm::vec4(values[4 * i], values[4 * i + 1], values[4 * i + 2], values[4 * i + 3]);
        }
        if (const int id = dracoId("COLOR_0"); id >= 0 || prim.attributes.count("COLOR_0")) {
            if (id < 0) {
                geo.colors = readColors(prim.attributes.at("COLOR_0"), label + " COLOR_0");
            } else {
                const int components = mesh->componentCount(id) == 4 ? 4 : 3;
                read("COLOR_0", components, values);
                geo.colors = colorsFromValues(values, size_t(components), label + " COLOR_0");
            }
            if (geo.colors.size() != points) fail(label + ": COLOR_0 does not have one colour per Draco point");
        }
        indices = mesh->indices();
        for (size_t i = 0; i < indices.size(); ++i) {
            if (indices[i] >= points)
                fail(what + ": index " + std::to_string(indices[i]) + " at position " + std::to_string(i) +
                     " out of range (" + std::to_string(points) + " points)");
        }
    }

    PrimitiveGeometry readPrimitive(const tinygltf::Primitive& prim, const std::string& label) {
        PrimitiveGeometry geo;
        auto attribute = [&](const char* name) {
            const auto it = prim.attributes.find(name);
            return it == prim.attributes.end() ? -1 : it->second;
        };
        const int position = attribute("POSITION");
        if (position < 0) fail(label + ": no POSITION attribute");
        geo.positions = readVec3(position, label + " POSITION");
        for (size_t i = 0; i < geo.positions.size(); ++i)
            if (!isFinite(geo.positions[i]))
                fail(label + " POSITION (accessor " + std::to_string(position) + "): vertex " + std::to_string(i) +
                     " is NaN or infinite");

        const size_t n = geo.positions.size();
        auto checkCount = [&](size_t count, const char* name) {
            if (count != n)
                fail(label + ": " + name + " has " + std::to_string(count) + " elements but POSITION has " +
                     std::to_string(n));
        };
        if (const int a = attribute("NORMAL"); a >= 0) {
            geo.normals = readVec3(a, label + " NORMAL");
            checkCount(geo.normals.size(), "NORMAL");
        }
        if (const int a = attribute("TEXCOORD_0"); a >= 0) {
            geo.uv0 = readVec2(a, label + " TEXCOORD_0");
            checkCount(geo.uv0.size(), "TEXCOORD_0");
        }
        if (const int a = attribute("TEXCOORD_1"); a >= 0) {
            geo.uv1 = readVec2(a, label + " TEXCOORD_1");
            checkCount(geo.uv1.size(), "TEXCOORD_1");
        }
        if (const int a = attribute("COLOR_0"); a >= 0) {
            geo.colors = readColors(a, label + " COLOR_0");
            checkCount(geo.colors.size(), "COLOR_0");
        }
        if (const int a = attribute("TANGENT"); a >= 0) {
            geo.tangents = readVec4(a, label + " TANGENT");
            checkCount(geo.tangents.size(), "TANGENT");
        }
        return geo;
    }

    /// Adds each morph target's POSITION, NORMAL and TANGENT displacements, times its weight, to
    /// the primitive's attributes (normals are renormalised with the node transform). Targets
    /// without a weight count as 0; a weight without a target is ignored with a warning.
    void applyMorphTargets(const tinygltf::Primitive& prim, const std::vector<double>& weights,
                           const std::string& label, PrimitiveGeometry& geo) {
        if (prim.targets.empty() || weights.empty()) return;
        if (weights.size() > prim.targets.size())
            warn(label + ": " + std::to_string(weights.size()) + " morph weights for " +
                 std::to_string(prim.targets.size()) + " targets; the extra weights are ignored");
        const size_t n = geo.positions.size();
        for (size_t t = 0; t < prim.targets.size() && t < weights.size(); ++t) {
            const double w = weights[t];
            if (w == 0.0) continue;
            if (!std::isfinite(w)) fail(label + ": morph weight " + std::to_string(t) + " is not finite");
            const std::string what = label + " morph target " + std::to_string(t);
            for (const auto& [name, accessor] : prim.targets[t]) {
                std::vector<glm::vec3>* values = name == "POSITION" ? &geo.positions
                                                 : name == "NORMAL" ? &geo.normals
                                                                    : nullptr;
                const bool tangent = name == "TANGENT" && !geo.tangents.empty();
                if (!values && !tangent) continue;  // other attributes, or displacements of absent ones
                if (values && values->empty()) continue;
                const std::vector<glm::vec3> delta = readVec3(accessor, what + " " + name);
                if (delta.size() != n)
                    fail(what + " " + name + " has " + std::to_string(delta.size()) + " elements but POSITION has " +
                         std::to_string(n));
                for (size_t i = 0; i < n; ++i) {
                    const glm::vec3 d = glm::vec3(w * glm::dvec3(delta[i]));
                    if (values) (*values)[i] += d;
                    else geo.tangents[i] += glm::vec4(d, 0.0f);
                }
            }
        }
        for (size_t i = 0; i < n; ++i)
            if (!isFinite(geo.positions[i]))
                fail(label + ": vertex " + std::to_string(i) + " is NaN or infinite after its morph targets");
    }

    std::vector<uint32_t> primitiveIndices(const tinygltf::Primitive& prim, size_t vertexCount,
                                           const std::string& label) const {
        if (prim.indices >= 0) return readIndices(prim.indices, vertexCount, label);
        if (vertexCount > std::numeric_limits<uint32_t>::max()) fail(label + ": more than 2^32 vertices");
        std::vector<uint32_t> indices(vertexCount);
        std::iota(indices.begin(), indices.end(), 0u);  // non-indexed: vertices in order
        return indices;
    }

    /// Positions by the world matrix, normals by its inverse transpose (so they stay
    /// perpendicular under non-uniform scale). A mirroring transform (negative determinant)
    /// turns counter-clockwise triangles clockwise, so their winding is flipped back.
    void transformToWorld(PrimitiveGeometry& geo, const glm::dmat4& world, const std::string& label) {
        for (size_t i = 0; i < geo.positions.size(); ++i) {
            const glm::dvec3 p = glm::dvec3(world * glm::dvec4(glm::dvec3(geo.positions[i]), 1.0));
            if (!withinWorldLimit(p)) {
                char at[96];
                std::snprintf(at, sizeof at, "(%.6g, %.6g, %.6g)", p.x, p.y, p.z);
                fail(label + ": vertex " + std::to_string(i) + " lies at " + at +
                     " after the node transforms, beyond +-1e9 m");
            }
            geo.positions[i] = glm::vec3(p);
            geo.exact_positions.push_back(p);
        }
        const glm::dmat3 linear(world);
        const double det = glm::determinant(linear);
        if (det == 0.0 || !std::isfinite(det))
            warn(label + ": node transform is singular; the primitive is flattened");
        const glm::dmat3 normalMatrix = det != 0.0 ? glm::inverseTranspose(linear) : linear;
        for (glm::vec3& n : geo.normals) n = glm::vec3(glm::normalize(normalMatrix * glm::dvec3(n)));
        // Tangents lie in the surface: they transform like positions. A mirror flips the
        // bitangent's handedness, as it flips the winding.
        for (glm::vec4& t : geo.tangents) {
            const glm::dvec3 xyz = linear * glm::dvec3(t);
            const double length = glm::length(xyz);
            t = glm::vec4(length > 0.0 ? glm::vec3(xyz / length) : glm::vec3(0.0f), det < 0.0 ? -t.w : t.w);
        }
        if (det < 0.0)
            for (glm::uvec3& t : geo.triangles) std::swap(t.y, t.z);
    }

    /// Linear blend skinning: each vertex by the weighted sum of its joints' matrices (JOINTS_n
    /// and WEIGHTS_n, every set the primitive has; weights that do not sum to 1 are normalised),
    /// its normal by that sum's inverse transpose, its tangent by its linear part; a triangle
    /// whose first vertex's sum mirrors is wound back, as transformToWorld does.
    void skinToWorld(const tinygltf::Primitive& prim, const std::vector<glm::dmat4>& joints, const glm::dmat4& world,
                     const std::string& label, PrimitiveGeometry& geo) {
        const size_t n = geo.positions.size();
        std::vector<glm::dmat4> blend(n, glm::dmat4(0.0));
        std::vector<double> total(n, 0.0);
        for (int set = 0;; ++set) {
            const auto j = prim.attributes.find("JOINTS_" + std::to_string(set));
            const auto w = prim.attributes.find("WEIGHTS_" + std::to_string(set));
            if (j == prim.attributes.end() || w == prim.attributes.end()) break;
            const std::string what = label + " JOINTS_" + std::to_string(set) + "/WEIGHTS_" + std::to_string(set);
            const std::vector<glm::vec4> indices = readVec4(j->second, what);
            const std::vector<glm::vec4> influence = readVec4(w->second, what);
            if (indices.size() != n || influence.size() != n)
                fail(what + ": " + std::to_string(indices.size()) + " and " + std::to_string(influence.size()) +
                     " elements but POSITION has " + std::to_string(n));
            for (size_t i = 0; i < n; ++i) {
                for (int c = 0; c < 4; ++c) {
                    const double weight = influence[i][c];
                    if (weight == 0.0) continue;
                    const double joint = indices[i][c];
                    if (!(weight > 0.0) || !std::isfinite(weight) || !(joint >= 0.0) ||
                        joint >= double(joints.size()) || joint != std::floor(joint))
                        fail(what + ": vertex " + std::to_string(i) + " has joint " + std::to_string(joint) +
                             " with weight " + std::to_string(weight) + " (the skin has " +
                             std::to_string(joints.size()) + " joints)");
                    blend[i] += weight * joints[size_t(joint)];
                    total[i] += weight;
                }
            }
        }
        size_t unweighted = 0;
        std::vector<double> determinant(n);  // of each vertex's blended matrix, for the winding
        for (size_t i = 0; i < n; ++i) {
            // A vertex no joint moves stays where its node puts it (viewers differ; none is right).
            unweighted += !(total[i] > 0.0);
            const glm::dmat4 m = total[i] > 0.0 ? blend[i] / total[i] : world;
            const glm::dvec3 p = glm::dvec3(m * glm::dvec4(glm::dvec3(geo.positions[i]), 1.0));
            if (!withinWorldLimit(p))
                fail(label + ": vertex " + std::to_string(i) + " lies beyond +-1e9 m after skinning");
            geo.positions[i] = glm::vec3(p);
            geo.exact_positions.push_back(p);
            const glm::dmat3 linear(m);
            const double det = glm::determinant(linear);
            if (!geo.normals.empty()) {
                const glm::dvec3 normal = (det != 0.0 ? glm::inverseTranspose(linear) : linear) *
                                          glm::dvec3(geo.normals[i]);
                const double length = glm::length(normal);
                geo.normals[i] = length > 0.0 ? glm::vec3(normal / length) : geo.normals[i];
            }
            if (!geo.tangents.empty()) {
                const glm::dvec3 t = linear * glm::dvec3(geo.tangents[i]);
                const double length = glm::length(t);
                geo.tangents[i] = glm::vec4(length > 0.0 ? glm::vec3(t / length) : glm::vec3(0.0f),
                                            det < 0.0 ? -geo.tangents[i].w : geo.tangents[i].w);
            }
            determinant[i] = det;
        }
        for (glm::uvec3& t : geo.triangles)
            if (determinant[t.x] < 0.0) std::swap(t.y, t.z);
        if (unweighted > 0)
            warn(label + ": " + std::to_string(unweighted) +
                 " skinned vertices have no joint weight; they stay where "
                 "the node puts them");
    }

    static glm::dvec3 triangleCross(const PrimitiveGeometry& geo, const glm::uvec3& t) {
        const glm::dvec3 a(geo.positions[t.x]);
        return glm::cross(glm::dvec3(geo.positions[t.y]) - a, glm::dvec3(geo.positions[t.z]) - a);
    }

    /// An emissive material all of whose triangles had no area gives no light: a lamp modelled as
    /// a line or a point (a collapsed plane) would otherwise leave only "no emissive surfaces".
    void warnAboutFlatEmitters() {
        for (const auto& [material, counts] : triangles_by_material_) {
            const Material& m = scene_.materials[material];
            if (!m.isEmissive() || counts.second > 0) continue;
            warn("material " + std::to_string(material) + (m.name.empty() ? "" : " " + quoted(m.name)) +
                 " emits light, but all " + std::to_string(counts.first) +
                 " of its triangles were dropped as degenerate (no area, or too small for float32): it gives no light");
        }
    }

    /// Drops triangles with a repeated index or (numerically) zero area: they cannot be hit
    /// and would give NaN geometric normals. Zero area is judged relative to the edge lengths
    /// so that tiny but well-shaped triangles survive, down to where float can no longer hold
    /// their normal: a cross product of the float edges below 2^-60 (edges of about 1e-9 units)
    /// underflows in the squared lengths that normalise it, and a fuzzed file's instances scaled
    /// by 1e-43 gave NaN normals, rays and a failed Embree assertion.
    void dropDegenerateTriangles(PrimitiveGeometry& geo) {
        const auto flat = [](const glm::dvec3& a, const glm::dvec3& b, const glm::dvec3& c) {
            const glm::dvec3 e1 = b - a, e2 = c - a;
            const double crossLength = glm::length(glm::cross(e1, e2));  // NaN-safe: !(x > y)
            return !(crossLength > 1e-7 * glm::length(e1) * glm::length(e2));
        };
        const auto tooSmallForFloat = [](const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
            const glm::vec3 n = glm::cross(b - a, c - a);
            return !(glm::dot(n, n) >= 0x1p-120f);  // float's smallest normal number is 2^-126
        };
        const std::vector<glm::dvec3>& exact = geo.exact_positions;
        auto degenerate = [&](const glm::uvec3& t) {
            if (t.x == t.y || t.y == t.z || t.x == t.z) return true;
            const glm::vec3 &a = geo.positions[t.x], &b = geo.positions[t.y], &c = geo.positions[t.z];
            if (!flat(glm::dvec3(a), glm::dvec3(b), glm::dvec3(c))) {
                if (!tooSmallForFloat(a, b, c)) return false;
                ++scene_.stats.triangles_too_small_for_float;
                return true;
            }
            // Flat in float but not in double: rounding the world positions to float collapsed it
            // (a model far from the origin, where float steps are as large as its detail).
            if (exact.size() == geo.positions.size() && !flat(exact[t.x], exact[t.y], exact[t.z])) {
                ++collapsed_triangles_;
                for (const uint32_t v : {t.x, t.y, t.z}) {
                    const glm::dvec3 p = glm::abs(exact[v]);
                    collapsed_farthest_ = std::max({collapsed_farthest_, p.x, p.y, p.z});
                }
            }
            return true;
        };
        const size_t before = geo.triangles.size();
        std::erase_if(geo.triangles, degenerate);
        scene_.stats.degenerate_triangles_dropped += before - geo.triangles.size();
        geo.exact_positions = {};
    }

    /// Emissive triangles with the same three corners as another (a face duplicated by an
    /// export, an emissive mesh instanced twice at one place): each is a light, so N copies light
    /// the scene N times as brightly while a camera sees one surface of the emitter's radiance.
    /// Every renderer that samples lights per triangle does the same; the file is what to fix.
    void warnAboutCoincidentEmitters() {
        using Corners = std::array<std::array<float, 3>, 3>;
        std::vector<Corners> emitters;
        for (size_t t = 0; t < scene_.triangles.size(); ++t) {
            if (!scene_.materials[scene_.triangle_materials[t]].isEmissive()) continue;
            Corners c;
            const glm::uvec3 tri = scene_.triangles[t];
            for (int k = 0; k < 3; ++k) {
                const glm::vec3 p = scene_.positions[tri[k]];
                c[size_t(k)] = {p.x, p.y, p.z};
            }
            std::sort(c.begin(), c.end());  // either winding, any first corner
            emitters.push_back(c);
        }
        std::sort(emitters.begin(), emitters.end());
        uint64_t copies = 0;
        for (size_t i = 1; i < emitters.size(); ++i) copies += emitters[i] == emitters[i - 1];
        if (copies == 0) return;
        warn(std::to_string(copies) +
             " emissive triangles lie exactly on another emissive triangle (the same three corners: a duplicated "
             "face, or an emissive mesh placed twice): each is a light, so two copies light the scene twice as "
             "brightly while a camera sees one surface; remove the duplicates");
    }

    /// One warning for every triangle too small for float32's normals: a model of size 1e-10
    /// (a room scaled down twice by a unit setting) was refused as "24 degenerate triangles have no
    /// area", which they do.
    void warnAboutTinyTriangles() {
        const uint64_t tiny = scene_.stats.triangles_too_small_for_float;
        if (tiny == 0) return;
        warn(std::to_string(tiny) + (tiny == 1 ? " triangle is" : " triangles are") +
             " too small for float32 (edges of about 1e-9 units or less, whose normal underflows) and " +
             (tiny == 1 ? "was" : "were") +
             " dropped: the model is far too small in its units; scale it up (a scale on its root node, or the "
             "exporter's unit setting)" +
             (scene_.triangles.empty() ? "; no triangle is left" : ""));
    }

    /// One warning for every triangle that rounding to float collapsed: the scene lies too far
    /// from the origin for its detail, which no float32 renderer (SHaRC's GPU code included) can
    /// hold either, so the fix is the scene's, not the bake's.
    void warnAboutCollapsedTriangles() {
        if (collapsed_triangles_ == 0) return;
        const double step = double(std::nextafter(float(collapsed_farthest_), INFINITY)) -
                            double(float(collapsed_farthest_));
        char text[512];
        std::snprintf(text, sizeof text,
                      "%llu triangles collapsed to zero area when their world positions were rounded to float32, "
                      "%.3g from the origin, where float32 steps are %.3g apart: the model lies too far from the "
                      "origin for its detail (any float32 renderer loses it there too); move it towards the origin "
                      "(a translation on its root node, or the exporter's origin setting)%s",
                      (unsigned long long)collapsed_triangles_, collapsed_farthest_, step,
                      scene_.triangles.empty() ? "; no triangle is left" : "");
        warn(text);
        scene_.stats.triangles_collapsed_by_rounding = collapsed_triangles_;
    }

    /// glTF says a primitive without normals is flat shaded; that needs one vertex per
    /// triangle corner so each can carry its face normal.
    static void makeFlatShaded(PrimitiveGeometry& geo) {
        PrimitiveGeometry flat;
        const size_t corners = geo.triangles.size() * 3;
        flat.positions.reserve(corners);
        flat.normals.reserve(corners);
        for (const glm::uvec3& t : geo.triangles) {
            const glm::vec3 n(glm::normalize(triangleCross(geo, t)));
            const auto base = static_cast<uint32_t>(flat.positions.size());
            for (uint32_t v : {t.x, t.y, t.z}) {
                flat.positions.push_back(geo.positions[v]);
                flat.normals.push_back(n);
                if (!geo.uv0.empty()) flat.uv0.push_back(geo.uv0[v]);
                if (!geo.uv1.empty()) flat.uv1.push_back(geo.uv1[v]);
                if (!geo.colors.empty()) flat.colors.push_back(geo.colors[v]);
                if (!geo.tangents.empty()) flat.tangents.push_back(geo.tangents[v]);
            }
            flat.triangles.emplace_back(base, base + 1, base + 2);
        }
        geo = std::move(flat);
    }

    /// Per-vertex tangents for a normal-mapped primitive without TANGENT, from the directions in
    /// which its texture coordinates grow (each triangle's dP/du, weighted by its area and summed
    /// at its vertices, then made orthogonal to the vertex normal); w is the sign that makes
    /// (normal x tangent) * w the direction of falling v. glTF asks for MikkTSpace tangents,
    /// which agree with these where UV charts are smooth and differ slightly at seams.
    void computeTangents(PrimitiveGeometry& geo, const std::vector<glm::vec2>& uv, const std::string& label) {
        if (uv.empty()) {
            warn(label + ": a normal map but no texture coordinates for it; the map is ignored");
            return;
        }
        std::vector<glm::dvec3> along_u(geo.positions.size(), glm::dvec3(0.0));
        std::vector<glm::dvec3> along_v(geo.positions.size(), glm::dvec3(0.0));
        for (const glm::uvec3& t : geo.triangles) {
            const glm::dvec3 e1 = glm::dvec3(geo.positions[t.y]) - glm::dvec3(geo.positions[t.x]);
            const glm::dvec3 e2 = glm::dvec3(geo.positions[t.z]) - glm::dvec3(geo.positions[t.x]);
            const glm::dvec2 d1 = glm::dvec2(uv[t.y]) - glm::dvec2(uv[t.x]);
            const glm::dvec2 d2 = glm::dvec2(uv[t.z]) - glm::dvec2(uv[t.x]);
            const double det = d1.x * d2.y - d2.x * d1.y;
            if (!(std::abs(det) > 1e-20)) continue;  // no UV area: no direction to take
            // Dividing by |det| instead of det weights each triangle by its area.
            const double area = glm::length(glm::cross(e1, e2));
            const glm::dvec3 du = (e1 * d2.y - e2 * d1.y) / det, dv = (e2 * d1.x - e1 * d2.x) / det;
            const double weight = area / std::max(glm::length(du), 1e-30);
            for (uint32_t v : {t.x, t.y, t.z}) {
                along_u[v] += du * weight;
                along_v[v] += dv * weight;
            }
        }
        geo.tangents.assign(geo.positions.size(), glm::vec4(0.0f));
        for (size_t i = 0; i < geo.positions.size(); ++i) {
            const glm::dvec3 n(geo.normals[i]);
            const glm::dvec3 t = along_u[i] - n * glm::dot(n, along_u[i]);
            const double length = glm::length(t);
            if (!(length > 1e-12)) continue;  // stays zero: the map is not applied at this vertex
            // glTF's normal maps put +Y towards the top of the image, where v decreases: the
            // bitangent (normal x tangent) x w must point against growing v.
            const double handedness = glm::dot(glm::cross(n, t), along_v[i]) < 0.0 ? 1.0 : -1.0;
            geo.tangents[i] = glm::vec4(glm::vec3(t / length), float(handedness));
        }
    }

    static std::vector<glm::vec2> transformedUvs(const std::vector<glm::vec2>& uv, const UvTransform& transform) {
        if (transform.identity) return uv;
        std::vector<glm::vec2> out(uv.size());
        for (size_t i = 0; i < uv.size(); ++i) out[i] = transform.apply(uv[i]);
        return out;
    }

    /// A normal map read through a UV transform (KHR_texture_transform) needs the tangent frame
    /// of the transformed UVs: its tangent is dP/du', not the file's dP/du. With the file's frame
    /// (T along growing u, w (N x T) along falling v, equally long as UV charts are locally
    /// conformal), dP/d(u', v') = [dP/du dP/dv] M^-1 for the transform's linear part M.
    static void turnTangents(PrimitiveGeometry& geo, const UvTransform& transform) {
        const glm::dmat2 m(glm::dvec2(transform.column_u), glm::dvec2(transform.column_v));
        if (!(std::abs(glm::determinant(m)) > 1e-20)) return;  // a degenerate transform: the map is flat anyway
        const glm::dmat2 inverse = glm::inverse(m);
        for (size_t i = 0; i < geo.tangents.size(); ++i) {
            const glm::vec4 t = geo.tangents[i];
            const glm::dvec3 n(geo.normals[i]);
            const glm::dvec3 along_u{glm::vec3(t)};
            const glm::dvec3 along_v = -glm::cross(n, along_u) * (t.w < 0.0f ? -1.0 : 1.0);
            const glm::dvec3 new_u = along_u * inverse[0][0] + along_v * inverse[0][1];
            const glm::dvec3 new_v = along_u * inverse[1][0] + along_v * inverse[1][1];
            const double length = glm::length(new_u);
            if (!(length > 1e-12)) continue;
            const double handedness = glm::dot(glm::cross(n, new_u), new_v) < 0.0 ? 1.0 : -1.0;
            geo.tangents[i] = glm::vec4(glm::vec3(new_u / length), float(handedness));
        }
    }

    /// Replaces NaN, infinite or zero normals with the area-weighted geometric normal of the
    /// triangles around the vertex, and says how many were fixed.
    void repairNormals(PrimitiveGeometry& geo, const std::string& label) {
        std::vector<bool> bad(geo.normals.size());
        size_t badCount = 0;
        for (size_t i = 0; i < geo.normals.size(); ++i) {
            bad[i] = !isFinite(geo.normals[i]) || glm::dot(geo.normals[i], geo.normals[i]) < 0.5f;
            badCount += bad[i];
        }
        if (badCount == 0) return;
        std::vector<glm::dvec3> accumulated(geo.normals.size(), glm::dvec3(0.0));
        for (const glm::uvec3& t : geo.triangles) {
            const glm::dvec3 c = triangleCross(geo, t);  // length = 2 x area: area weighting
            for (uint32_t v : {t.x, t.y, t.z})
                if (bad[v]) accumulated[v] += c;
        }
        for (size_t i = 0; i < geo.normals.size(); ++i) {
            if (!bad[i]) continue;
            const double len = glm::length(accumulated[i]);
            // A vertex no triangle uses cannot be shaded; any unit vector keeps the data valid.
            geo.normals[i] = len > 0.0 ? glm::vec3(accumulated[i] / len) : glm::vec3(0.0f, 1.0f, 0.0f);
        }
        warn(label + ": " + std::to_string(badCount) +
             " NaN, infinite or zero normals replaced by the geometric normal");
    }

    /// Appends a primitive to the scene's single vertex/triangle soup. Attributes one
    /// primitive lacks but another has are filled with zeros so every array stays one per
    /// vertex.
    void appendGeometry(const PrimitiveGeometry& geo, uint32_t material) {
        const size_t base = scene_.positions.size();
        if (base + geo.positions.size() > std::numeric_limits<uint32_t>::max())
            fail("scene has more than 2^32 vertices");
        auto append = [&](auto& dst, const auto& src, auto missing) {
            if (src.empty() && dst.empty()) return;  // nobody has this attribute (yet)
            dst.resize(base, missing);               // back-fill earlier primitives without it
            if (src.empty()) dst.resize(base + geo.positions.size(), missing);
            else dst.insert(dst.end(), src.begin(), src.end());
        };
        append(scene_.texcoords0, geo.uv0, glm::vec2(0.0f));
        append(scene_.texcoords1, geo.uv1, glm::vec2(0.0f));
        append(scene_.colors, geo.colors, glm::vec4(1.0f));      // no colour: white, opaque
        append(scene_.tangents, geo.tangents, glm::vec4(0.0f));  // no tangent: the map is not applied
        scene_.positions.insert(scene_.positions.end(), geo.positions.begin(), geo.positions.end());
        scene_.normals.insert(scene_.normals.end(), geo.normals.begin(), geo.normals.end());
        const auto offset = static_cast<uint32_t>(base);
        for (const glm::uvec3& t : geo.triangles) {
            scene_.triangles.push_back(t + glm::uvec3(offset));
            scene_.triangle_materials.push_back(material);
        }
    }

    void computeBounds() {
        if (scene_.triangles.empty()) return;
        glm::vec3 lo(std::numeric_limits<float>::max());
        glm::vec3 hi(std::numeric_limits<float>::lowest());
        for (const glm::uvec3& t : scene_.triangles)
            for (uint32_t v : {t.x, t.y, t.z}) {
                lo = glm::min(lo, scene_.positions[v]);
                hi = glm::max(hi, scene_.positions[v]);
            }
        scene_.bounds_min = lo;
        scene_.bounds_max = hi;
    }

    // ---------------------------------------------------------------- materials

    uint32_t materialForPrimitive(const tinygltf::Primitive& prim, int meshIndex, size_t primIndex,
                                  const std::string& label) {
        if (prim.material >= 0) {
            if (static_cast<size_t>(prim.material) >= model_.materials.size())
                fail(label + ": material " + std::to_string(prim.material) + " does not exist");
            return static_cast<uint32_t>(prim.material);  // scene materials mirror glTF's order
        }
        if (default_material_ < 0) {
            default_material_ = static_cast<int>(scene_.materials.size());
            scene_.materials.push_back(defaultMaterial());
            first_without_material_ = label;
        }
        primitives_without_material_.emplace(meshIndex, primIndex);
        return static_cast<uint32_t>(default_material_);
    }

    /// One warning for every primitive without a material: an export without materials
    /// (Blender's Materials: None) leaves the whole scene white metal, not one mesh.
    void warnAboutPrimitivesWithoutMaterial() {
        if (primitives_without_material_.empty()) return;
        std::string which = first_without_material_ + " has no material";
        if (primitives_without_material_.size() > 1) {
            std::set<int> meshes;
            for (const auto& [mesh, primitive] : primitives_without_material_) meshes.insert(mesh);
            which = std::to_string(primitives_without_material_.size()) + " primitives in " +
                    std::to_string(meshes.size()) + (meshes.size() == 1 ? " mesh" : " meshes") +
                    " have no material (first: " + first_without_material_ + ")";
        }
        warn(which +
             ": glTF's default applies, a white metal (metallicFactor 1, roughnessFactor 1), which reflects "
             "differently from the grey diffuse Blender shows for a mesh without a material; assign a material to "
             "say what it is");
    }

    void convertMaterials() {
        scene_.materials.reserve(model_.materials.size() + 1);
        for (size_t i = 0; i < model_.materials.size(); ++i) scene_.materials.push_back(convertMaterial(i));
    }

    Material convertMaterial(size_t index) {
        const tinygltf::Material& src = model_.materials[index];
        const std::string label = "material " + std::to_string(index) + (src.name.empty() ? "" : " " + quoted(src.name));
        const tinygltf::PbrMetallicRoughness& pbr = src.pbrMetallicRoughness;
        Material m;
        m.name = src.name;
        m.base_color = vec3Or(pbr.baseColorFactor, glm::vec3(1.0f));
        m.metallic = static_cast<float>(pbr.metallicFactor);
        m.roughness = static_cast<float>(pbr.roughnessFactor);
        m.emissive = vec3Or(src.emissiveFactor, glm::vec3(0.0f));
        m.double_sided = src.doubleSided;
        m.base_color_texture = textureRef(textureSlot(pbr.baseColorTexture), true, label);
        m.metallic_roughness_texture = textureRef(textureSlot(pbr.metallicRoughnessTexture), false, label);
        m.emissive_texture = textureRef(textureSlot(src.emissiveTexture), true, label);
        m.normal_texture = textureRef(textureSlot(src.normalTexture), false, label);
        m.normal_scale = static_cast<float>(src.normalTexture.scale);
        if (src.occlusionTexture.index >= 0) {
            // Not lost light: ambient occlusion is an approximation of what the path tracer
            // computes from the geometry itself.
            warnForMaterial(label, "occlusionTexture ignored (the path tracer computes occlusion from the geometry)");
        }
        readAlpha(src, m, label);
        readMaterialExtensions(src, m, label);
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_pbrSpecularGlossiness")) {
            const Material fallback = m;
            readSpecularGlossiness(*ext, m, label);
            // A material without pbrMetallicRoughness has no fallback to disagree with: glTF's
            // defaults (white metal) stand in, which no one wrote.
            if (!(src.pbrMetallicRoughness == tinygltf::PbrMetallicRoughness()))
                warnWhenFallbackDiffers(fallback, m, label);
        }
        leaveOutEmissionBeyondFloat(src, m, label);
        clampToGltfRanges(m, label);
        if (extension(src.extensions, "KHR_materials_unlit")) makeUnlit(m);
        return m;
    }

    /// Emission is traced in float32, as emissiveFactor x emissiveStrength x texture (at most 1).
    /// A factor or strength beyond float32's range, or a product of the two beyond it (each
    /// finite: a factor of 2 times a strength of 3e38), has no float value: read, it was infinity
    /// or a fallback (a strength of 1e39 was loaded as 1), wrong by orders of magnitude either way.
    /// Clamped to the largest float, the light would still overflow at its first bounce and the
    /// bake would drop it as NaN/Inf. So the material's emission is left out, with a warning
    /// naming the field and the value as the file gives it.
    void leaveOutEmissionBeyondFloat(const tinygltf::Material& src, Material& m, const std::string& label) {
        const glm::dvec3 factor = src.emissiveFactor.size() == 3
                                      ? glm::dvec3(src.emissiveFactor[0], src.emissiveFactor[1], src.emissiveFactor[2])
                                      : glm::dvec3(0.0);
        const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_emissive_strength");
        const double strength = ext ? number(*ext, "emissiveStrength").value_or(1.0) : 1.0;
        const std::string factor_text = "emissiveFactor " + vec3Text(factor);
        const std::string strength_text = "emissiveStrength " + numberText(strength);
        std::string beyond;
        if (!fitsFloat(factor.x) || !fitsFloat(factor.y) || !fitsFloat(factor.z)) {
            beyond = factor_text;
        } else if (!fitsFloat(strength)) {
            beyond = strength_text;
        } else {
            const double brightest = std::max({factor.x, factor.y, factor.z}) * strength;
            if (!fitsFloat(brightest)) beyond = factor_text + " x " + strength_text + " = " + numberText(brightest);
        }
        if (beyond.empty()) return;
        warn(label + ": " + beyond + " is beyond float32's range (at most " + numberText(kLargestFloat) +
             "), so the material's emission is left out; scale the scene's emission down");
        m.emissive = glm::vec3(0.0f);
        m.emissive_strength = 1.0f;
    }

    /// Factors outside the ranges glTF gives them are clamped into them, with one warning per
    /// material naming each. A base colour above 1 reflects more light than reaches the surface,
    /// so light would grow with every bounce; negative ones would subtract light. Emission above
    /// 1 is kept (exporters from before KHR_materials_emissive_strength write bright lights so);
    /// below 0 it is not.
    void clampToGltfRanges(Material& m, const std::string& label) {
        std::string fixed;
        const auto note = [&fixed](const std::string& what) { fixed += (fixed.empty() ? "" : ", ") + what; };
        const auto clampVec3 = [&](glm::vec3& v, float lo, float hi, float fallback, const char* name) {
            const glm::vec3 before = v;
            v = clampedFactor(v, lo, hi, fallback);
            if (v != before) note(std::string(name) + " " + vec3Text(before) + " -> " + vec3Text(v));
        };
        const auto clampFloat = [&](float& v, float lo, float hi, float fallback, const char* name) {
            const float before = v;
            v = clampedFactor(v, lo, hi, fallback);
            if (v != before) note(std::string(name) + " " + numberText(before) + " -> " + numberText(v));
        };
        const float kNoLimit = std::numeric_limits<float>::max();
        clampVec3(m.base_color, 0.0f, 1.0f, 1.0f, "base colour");
        clampFloat(m.metallic, 0.0f, 1.0f, 1.0f, "metallic");
        clampFloat(m.roughness, 0.0f, 1.0f, 1.0f, "roughness");
        clampVec3(m.emissive, 0.0f, kNoLimit, 0.0f, "emissive");
        clampFloat(m.emissive_strength, 0.0f, kNoLimit, 1.0f, "emissive strength");
        clampFloat(m.specular, 0.0f, 1.0f, 1.0f, "specular");
        clampVec3(m.specular_color, 0.0f, kNoLimit, 1.0f, "specular colour");
        clampFloat(m.ior, 0.0f, kNoLimit, 1.5f, "ior");
        if (!fixed.empty()) warn(label + ": factors outside glTF's ranges clamped into them (" + fixed + ")");
    }

    /// KHR_materials_unlit (scanned and pre-lit models, sky domes, stylised assets): viewers show
    /// the base colour (factor x texture x vertex colour) as it is. Traced as a surface that emits
    /// exactly that radiance and reflects nothing, so the cache holds what viewers show there, and
    /// the light it gives the rest of the scene is the light it shows (a sky dome lights the scene
    /// as a sky). The base colour texture stays for the alpha (MASK, BLEND); its colour is black.
    static void makeUnlit(Material& m) {
        m.unlit = true;
        m.emissive = m.base_color;
        m.emissive_strength = 1.0f;
        m.emissive_texture = m.base_color_texture;
        m.base_color = glm::vec3(0.0f);
        m.metallic = 0.0f;
        m.specular = 0.0f;
        m.specular_texture = TextureRef{};
        m.specular_color_texture = TextureRef{};
        m.metallic_roughness_texture = TextureRef{};
        m.clearcoat = 0.0f;
        m.clearcoat_texture = TextureRef{};
        m.clearcoat_roughness_texture = TextureRef{};
        m.normal_texture = TextureRef{};
    }

    /// KHR_materials_pbrSpecularGlossiness (older exporters and sample models; it takes the
    /// place of pbrMetallicRoughness, which is then only a fallback) as the metallic-roughness
    /// material with the same BRDF: a dielectric (metallic 0) whose base colour is the diffuse
    /// colour and whose F0 is the specular colour (KHR_materials_specular's colour, divided by
    /// the 0.04 of ior 1.5), roughness 1 - glossiness.
    void readSpecularGlossiness(const tinygltf::Value& ext, Material& m, const std::string& label) {
        const std::optional<glm::vec4> diffuse = vecValue<4>(ext, "diffuseFactor");
        m.base_color = diffuse ? glm::vec3(*diffuse) : glm::vec3(1.0f);
        m.base_alpha = diffuse ? std::clamp(diffuse->w, 0.0f, 1.0f) : 1.0f;
        m.base_color_texture = textureRef(textureSlot(ext, "diffuseTexture"), true, label);
        m.metallic = 0.0f;
        m.ior = 1.5f;
        m.specular = 1.0f;
        m.specular_texture = TextureRef();
        m.specular_color = vecValue<3>(ext, "specularFactor").value_or(glm::vec3(1.0f)) / kDielectricF0;
        const float glossiness = std::clamp(static_cast<float>(number(ext, "glossinessFactor").value_or(1.0)), 0.0f,
                                            1.0f);
        const TextureSlot slot = textureSlot(ext, "specularGlossinessTexture");
        m.specular_color_texture = textureRef(slot, true, label);  // RGB: the specular colour, sRGB
        m.roughness = 1.0f - glossiness;
        m.metallic_roughness_texture = TextureRef();
        if (slot.index >= 0) {
            // A: glossiness (linear). Roughness is 1 - factor x A, which no factor on a texture
            // can express: the texture is converted once into metallic-roughness form.
            m.metallic_roughness_texture = textureRef(slot, false, label);
            if (m.metallic_roughness_texture.isSet()) {
                m.metallic_roughness_texture.texture = roughnessFromGlossiness(m.metallic_roughness_texture.texture,
                                                                               glossiness);
                m.roughness = 1.0f;
            }
        }
    }

    /// A specular-glossiness material is read as the extension says, but viewers without the
    /// extension show its pbrMetallicRoughness fallback. Where the two disagree (assimp writes
    /// OBJ's `Ks 0.5` as specular 0.5, ten times a dielectric's F0, and its fallback as a plain
    /// dielectric; `Tr 1` as an opaque diffuse and a transparent fallback) the render differs from
    /// what the user saw: one warning, with both values. Only values both sides give by factors
    /// are compared.
    void warnWhenFallbackDiffers(const Material& fallback, const Material& used, const std::string& label) {
        const auto maxOf = [](glm::vec3 v) { return std::max({v.x, v.y, v.z}); };
        const float fallback_f0 = maxOf(glm::mix(glm::vec3(kDielectricF0), fallback.base_color, fallback.metallic));
        const float used_f0 = maxOf(used.specular_color) * kDielectricF0;
        const float fallback_diffuse = maxOf(fallback.base_color) * (1.0f - fallback.metallic);
        const float used_diffuse = maxOf(used.base_color);
        // A value that comes through a texture on either side is not known from the factors (a
        // fallback's metallic 1 times an ORM texture is the texture's metallic: Corset's
        // spec-gloss variant in glTF-Sample-Models read "diffuse 1 against 0"), so not compared.
        const bool fallback_metal_mapped = fallback.metallic_roughness_texture.isSet();
        const bool fallback_colour_mapped = fallback.base_color_texture.isSet();
        const bool f0_known = !fallback_metal_mapped && !(fallback_colour_mapped && fallback.metallic > 0.0f) &&
                              !used.specular_color_texture.isSet();
        const bool diffuse_known = !fallback_metal_mapped && !fallback_colour_mapped &&
                                   !used.base_color_texture.isSet();
        const bool alpha_known = !fallback_colour_mapped && !used.base_color_texture.isSet();
        std::string differences;
        char text[96];
        if (f0_known && std::abs(fallback_f0 - used_f0) > 0.15f) {
            std::snprintf(text, sizeof text, "specular reflectance (F0) %.3g against %.3g", double(used_f0),
                          double(fallback_f0));
            differences += text;
        }
        if (diffuse_known && std::abs(fallback_diffuse - used_diffuse) > 0.25f) {
            std::snprintf(text, sizeof text, "%sdiffuse %.3g against %.3g", differences.empty() ? "" : ", ",
                          double(used_diffuse), double(fallback_diffuse));
            differences += text;
        }
        if (alpha_known && std::abs(fallback.base_alpha - used.base_alpha) > 0.5f) {
            std::snprintf(text, sizeof text, "%salpha %.3g against %.3g", differences.empty() ? "" : ", ",
                          double(used.base_alpha), double(fallback.base_alpha));
            differences += text;
        }
        if (differences.empty()) return;
        warnForMaterial(
            label,
            "KHR_materials_pbrSpecularGlossiness and its pbrMetallicRoughness fallback (what viewers "
            "without the extension show) describe different materials: " +
                differences +
                " (extension against fallback); the extension is used, as glTF asks. Check the material in the tool "
                "that wrote it");
    }

    /// A texture whose G is 1 - glossiness x A of `texture` (metallic-roughness form: G
    /// roughness, B metallic 0), made once per (texture, glossiness).
    int roughnessFromGlossiness(int texture, float glossiness) {
        const auto key = std::make_pair(texture, glossiness);
        if (const auto it = roughness_from_glossiness_.find(key); it != roughness_from_glossiness_.end())
            return it->second;
        const Texture& source = scene_.textures[static_cast<size_t>(texture)];
        Texture converted;
        converted.name = source.name + " (roughness from glossiness)";
        converted.width = source.width;
        converted.height = source.height;
        converted.wrap_s = source.wrap_s;
        converted.wrap_t = source.wrap_t;
        converted.nearest = source.nearest;
        // Floats: 1 - glossiness x A is no longer on the 8-bit grid.
        converted.texels.resize(source.texelCount());
        for (size_t i = 0; i < converted.texels.size(); ++i)
            converted.texels[i] = glm::vec4(0.0f, 1.0f - glossiness * source.texel(i).a, 0.0f, 1.0f);
        scene_.textures.push_back(std::move(converted));
        const int index = static_cast<int>(scene_.textures.size()) - 1;
        roughness_from_glossiness_.emplace(key, index);
        return index;
    }

    /// alphaMode, alphaCutoff and the base colour's alpha. MASK and BLEND materials let rays
    /// through where they are transparent (Material::cutsOut).
    void readAlpha(const tinygltf::Material& src, Material& m, const std::string& label) {
        m.base_alpha = src.pbrMetallicRoughness.baseColorFactor.size() == 4
                           ? std::clamp(static_cast<float>(src.pbrMetallicRoughness.baseColorFactor[3]), 0.0f, 1.0f)
                           : 1.0f;
        m.alpha_cutoff = static_cast<float>(src.alphaCutoff);
        if (!(m.alpha_cutoff >= 0.0f)) {  // glTF's minimum is 0; below it MASK would hide nothing
            warn(label + ": alphaCutoff " + numberText(m.alpha_cutoff) + " is below glTF's minimum 0; 0 used");
            m.alpha_cutoff = 0.0f;
        }
        if (src.alphaMode == "MASK") {
            m.alpha_mode = AlphaMode::Mask;
        } else if (src.alphaMode == "BLEND") {
            m.alpha_mode = AlphaMode::Blend;
        } else if (src.alphaMode != "OPAQUE" && !src.alphaMode.empty()) {
            warnForMaterial(label, "unknown alphaMode " + quoted(src.alphaMode) + " treated as OPAQUE");
        }
    }

    /// A MASK or BLEND material whose alpha is 1 everywhere (factor, texture and the vertex
    /// colours of its triangles) is opaque: tracing it as such skips the per-hit alpha test.
    void settleAlphaModes() {
        std::vector<bool> vertex_alpha(scene_.materials.size(), false);  // some vertex colour alpha < 1
        if (!scene_.colors.empty()) {
            for (size_t t = 0; t < scene_.triangles.size(); ++t) {
                for (uint32_t v : {scene_.triangles[t].x, scene_.triangles[t].y, scene_.triangles[t].z})
                    if (scene_.colors[v].a < 1.0f) vertex_alpha[scene_.triangle_materials[t]] = true;
            }
        }
        for (size_t i = 0; i < scene_.materials.size(); ++i) {
            Material& m = scene_.materials[i];
            if (m.alpha_mode == AlphaMode::Opaque) continue;
            const bool texture_alpha = m.base_color_texture.isSet() &&
                                       hasAlphaBelowOne(scene_.textures[size_t(m.base_color_texture.texture)]);
            const bool partial = m.base_alpha < 1.0f || texture_alpha || vertex_alpha[i];
            const float lowest_alpha = partial ? 0.0f : 1.0f;
            if (m.alpha_mode == AlphaMode::Mask ? !(lowest_alpha < m.alpha_cutoff) : !partial) {
                m.alpha_mode = AlphaMode::Opaque;
            } else if (m.alpha_mode == AlphaMode::Blend) {
                const std::string& name = m.name;
                warnForMaterial(
                    "material " + std::to_string(i) + (name.empty() ? "" : " " + quoted(name)),
                    "alphaMode BLEND is traced as a stochastic cut-out (opaque with probability alpha at each "
                    "point, like Blender's alpha hashed); refraction and tinted transmission are not modelled");
            }
        }
    }

    static bool hasAlphaBelowOne(const Texture& texture) {
        for (size_t i = 0; i < texture.texelCount(); ++i)
            if (texture.texel(i).a < 1.0f) return true;
        return false;
    }

    static const tinygltf::Value* extension(const tinygltf::ExtensionMap& extensions, const char* name) {
        const auto it = extensions.find(name);
        return it == extensions.end() || !it->second.IsObject() ? nullptr : &it->second;
    }

    /// An extension's number: `fallback` when absent, and also when present as something else
    /// (a string, an array), with a warning naming it: {"emissiveStrength": "bright"} was 1 silently.
    double numberOr(const tinygltf::Value& object, const char* key, double fallback, const std::string& label) {
        if (!object.Has(key)) return fallback;
        if (const std::optional<double> value = number(object, key)) return *value;
        warn(label + ": " + key + " is not a number; " + numberText(float(fallback)) + " used");
        return fallback;
    }

    static std::optional<double> number(const tinygltf::Value& object, const char* key) {
        if (!object.Has(key) || !object.Get(key).IsNumber()) return std::nullopt;
        return object.Get(key).GetNumberAsDouble();
    }

    /// A JSON array of N numbers, or nothing when absent or malformed.
    template <int N>
    static std::optional<glm::vec<N, float>> vecValue(const tinygltf::Value& object, const char* key) {
        if (!object.Has(key)) return std::nullopt;
        const tinygltf::Value& a = object.Get(key);
        if (!a.IsArray() || a.ArrayLen() != size_t(N)) return std::nullopt;
        glm::vec<N, float> v;
        for (int i = 0; i < N; ++i) {
            if (!a.Get(i).IsNumber()) return std::nullopt;
            v[i] = static_cast<float>(a.Get(i).GetNumberAsDouble());
        }
        return v;
    }

    static std::optional<glm::vec2> vec2Value(const tinygltf::Value& object, const char* key) {
        if (!object.Has(key)) return std::nullopt;
        const tinygltf::Value& a = object.Get(key);
        if (!a.IsArray() || a.ArrayLen() != 2 || !a.Get(0).IsNumber() || !a.Get(1).IsNumber()) return std::nullopt;
        return glm::vec2(static_cast<float>(a.Get(0).GetNumberAsDouble()), static_cast<float>(a.Get(1).GetNumberAsDouble()));
    }

    /// A core textureInfo (base colour, metallic-roughness, emissive, normal).
    template <typename Info>
    static TextureSlot textureSlot(const Info& info) {
        return TextureSlot{info.index, info.texCoord, extension(info.extensions, "KHR_texture_transform")};
    }

    /// A textureInfo inside an extension's JSON (KHR_materials_specular's textures).
    static TextureSlot textureSlot(const tinygltf::Value& object, const char* key) {
        TextureSlot slot;
        if (!object.Has(key) || !object.Get(key).IsObject()) return slot;
        const tinygltf::Value& info = object.Get(key);
        if (auto i = number(info, "index")) slot.index = static_cast<int>(*i);
        if (auto t = number(info, "texCoord")) slot.texcoord = static_cast<int>(*t);
        if (info.Has("extensions") && info.Get("extensions").IsObject()) {
            const tinygltf::Value& extensions = info.Get("extensions");
            if (extensions.Has("KHR_texture_transform") && extensions.Get("KHR_texture_transform").IsObject())
                slot.transform = &extensions.Get("KHR_texture_transform");
        }
        return slot;
    }

    /// KHR_texture_transform's offset, rotation and scale, and its texCoord, which overrides the
    /// textureInfo's. A malformed transform is ignored with a warning (the texture is still read
    /// through the untransformed UVs) rather than failing the scene.
    UvTransform readTextureTransform(const tinygltf::Value& t, int& texcoord, const std::string& what) {
        const bool has_offset = t.Has("offset"), has_scale = t.Has("scale"), has_rotation = t.Has("rotation");
        const std::optional<glm::vec2> offset = vec2Value(t, "offset"), scale = vec2Value(t, "scale");
        const std::optional<double> rotation = number(t, "rotation");
        const bool valid = (!has_offset || (offset && std::isfinite(offset->x) && std::isfinite(offset->y))) &&
                           (!has_scale || (scale && std::isfinite(scale->x) && std::isfinite(scale->y))) &&
                           (!has_rotation || (rotation && std::isfinite(*rotation)));
        if (!valid) {
            warn(what + ": KHR_texture_transform needs offset and scale as two finite numbers and a finite rotation; "
                        "transform ignored");
            return UvTransform{};
        }
        if (auto override_texcoord = number(t, "texCoord")) texcoord = static_cast<int>(*override_texcoord);
        return UvTransform::fromGltf(offset.value_or(glm::vec2(0.0f)), static_cast<float>(rotation.value_or(0.0)),
                                     scale.value_or(glm::vec2(1.0f)));
    }

    void readMaterialExtensions(const tinygltf::Material& src, Material& m, const std::string& label) {
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_emissive_strength"))
            m.emissive_strength = static_cast<float>(numberOr(*ext, "emissiveStrength", 1.0, label));
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_ior"))
            m.ior = static_cast<float>(numberOr(*ext, "ior", 1.5, label));
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_transmission")) {
            m.transmission = std::clamp(static_cast<float>(numberOr(*ext, "transmissionFactor", 0.0, label)), 0.0f,
                                        1.0f);
            m.transmission_texture = textureRef(textureSlot(*ext, "transmissionTexture"), false, label);
            if (m.transmission > 0.0f) {
                // Blender's glass (Principled Transmission) exports as this. Opaque, it would
                // keep daylight out of every room behind a window.
                warnForMaterial(label, std::string(
                                           "KHR_materials_transmission is traced as thin see-through glass: a share ") +
                                           "transmissionFactor of each surface lets rays through unbent and untinted; "
                                           "the glass's colour " +
                                           "and the reflection of the transmitted share are not modelled");
            }
        }
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_clearcoat")) {
            m.clearcoat = std::clamp(static_cast<float>(number(*ext, "clearcoatFactor").value_or(0.0)), 0.0f, 1.0f);
            m.clearcoat_roughness =
                std::clamp(static_cast<float>(number(*ext, "clearcoatRoughnessFactor").value_or(0.0)), 0.0f, 1.0f);
            m.clearcoat_texture = textureRef(textureSlot(*ext, "clearcoatTexture"), false, label);
            m.clearcoat_roughness_texture = textureRef(textureSlot(*ext, "clearcoatRoughnessTexture"), false, label);
            if (m.clearcoat > 0.0f && textureSlot(*ext, "clearcoatNormalTexture").index >= 0) {
                warnForMaterial(label,
                                "KHR_materials_clearcoat clearcoatNormalTexture ignored: the coat uses the "
                                "material's shading normal");
            }
        }
        if (const tinygltf::Value* ext = extension(src.extensions, "KHR_materials_specular")) {
            m.specular = static_cast<float>(number(*ext, "specularFactor").value_or(1.0));
            m.specular_color = vecValue<3>(*ext, "specularColorFactor").value_or(glm::vec3(1.0f));
            m.specular_texture = textureRef(textureSlot(*ext, "specularTexture"), false, label);
            m.specular_color_texture = textureRef(textureSlot(*ext, "specularColorTexture"), true, label);
            if (m.specular_color == glm::vec3(0.0f) && !m.specular_color_texture.isSet()) {
                // Blender's exporter writes colour [0, 0, 0] (and no factor) for Principled
                // "Specular" 0: no specular reflection at all. Read to the letter, glTF keeps
                // F90 = specularFactor, a reflection at grazing angles only that the artist never
                // saw; read it as Blender meant.
                m.specular = 0.0f;
                warn("KHR_materials_specular specularColorFactor [0, 0, 0] (how Blender exports Specular 0) is "
                     "read as no specular reflection; glTF's formula would keep a grazing-angle reflection");
            }
        }
    }

    // ---------------------------------------------------------------- textures

    TextureRef textureRef(TextureSlot slot, bool srgb, const std::string& label) {
        TextureRef ref;
        if (slot.index < 0) return ref;
        if (static_cast<size_t>(slot.index) >= model_.textures.size())
            fail(label + ": texture " + std::to_string(slot.index) + " does not exist");
        if (slot.transform) {
            ref.transform = readTextureTransform(*slot.transform, slot.texcoord,
                                                 label + ": texture " + std::to_string(slot.index));
        }
        if (slot.texcoord < 0 || slot.texcoord > 1) {
            warn(label + ": texture " + std::to_string(slot.index) + " uses TEXCOORD_" + std::to_string(slot.texcoord) +
                 "; only TEXCOORD_0 and TEXCOORD_1 are loaded, texture ignored");
            return ref;
        }
        const auto key = std::make_pair(slot.index, srgb);
        auto it = texture_cache_.find(key);
        if (it == texture_cache_.end()) it = texture_cache_.emplace(key, decodeTexture(slot.index, srgb, label)).first;
        ref.texture = it->second;
        ref.texcoord = static_cast<uint32_t>(slot.texcoord);
        return ref;
    }

    static WrapMode wrapMode(int glWrap) {
        switch (glWrap) {
        case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return WrapMode::ClampToEdge;
        case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return WrapMode::MirroredRepeat;
        default: return WrapMode::Repeat;
        }
    }

    /// The image a texture reads, or -1 (with a warning) when it has none sharcbake can read.
    /// EXT_texture_webp names the WebP image, and `source` (if any) a fallback for viewers
    /// without WebP: the WebP one is read. KHR_texture_basisu names a KTX2 image, which is not
    /// decoded: `source`, its PNG or JPEG fallback, is read.
    int textureImage(int textureIndex, const std::string& what) {
        const tinygltf::Texture& src = model_.textures[size_t(textureIndex)];
        if (const tinygltf::Value* webp = extension(src.extensions, "EXT_texture_webp")) {
            if (const std::optional<double> webp_source = number(*webp, "source"))
                return static_cast<int>(*webp_source);
        }
        if (const tinygltf::Value* basisu = extension(src.extensions, "KHR_texture_basisu")) {
            const std::optional<double> ktx2 = number(*basisu, "source");
            const std::string ktx2_label = "KHR_texture_basisu image" +
                                           (ktx2 ? " " + std::to_string(static_cast<long long>(*ktx2)) : std::string());
            if (src.source < 0) {
                warn(what + " has only a " + ktx2_label +
                     " (KTX2 / Basis Universal, which sharcbake does not decode) and no PNG or JPEG fallback; "
                     "texture ignored");
                return -1;
            }
            // Without the material's label: one note per texture, however many materials use it.
            warn("texture " + std::to_string(textureIndex) + ": " + ktx2_label +
                 " (KTX2 / Basis Universal) is not decoded; its fallback " + imageLabel(src.source) + " is read");
        }
        return src.source;
    }

    /// Decodes a glTF texture's image and returns its Scene index, or -1 (with a warning) when
    /// the image is missing or undecodable, so the material falls back to its factors instead of
    /// failing the whole scene.
    int decodeTexture(int textureIndex, bool srgb, const std::string& label) {
        const tinygltf::Texture& src = model_.textures[textureIndex];
        const std::string what = label + ": texture " + std::to_string(textureIndex);
        const int source = textureImage(textureIndex, what);
        if (source < 0) return -1;
        if (static_cast<size_t>(source) >= model_.images.size()) {
            warn(what + " has no image sharcbake can decode; texture ignored");
            return -1;
        }
        if (const auto it = image_decoding_.not_decoded.find(source); it != image_decoding_.not_decoded.end()) {
            const std::string problem = it->second.ktx2      ? " is " + it->second.why
                                        : it->second.missing ? std::string(" not found")
                                                             : std::string(" could not be decoded");
            warn(what + ": " + imageLabel(source) + problem + "; texture ignored");
            return -1;
        }
        Texture tex;
        tex.name = imageName(model_.images[static_cast<size_t>(source)], source);
        if (!setTexels(source, srgb, tex)) {  // a file tinygltf did not read (outside the folder): it said why
            warn(what + ": image " + std::to_string(source) + " could not be decoded; texture ignored");
            return -1;
        }
        if (src.sampler >= 0 && static_cast<size_t>(src.sampler) < model_.samplers.size()) {
            const tinygltf::Sampler& sampler = model_.samplers[src.sampler];
            tex.wrap_s = wrapMode(sampler.wrapS);
            tex.wrap_t = wrapMode(sampler.wrapT);
            tex.nearest = sampler.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
        }
        scene_.textures.push_back(std::move(tex));
        return static_cast<int>(scene_.textures.size()) - 1;
    }

    static std::string imageName(const tinygltf::Image& image, int index) {
        if (!image.name.empty()) return image.name;
        if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) return image.uri;
        return "image " + std::to_string(index);  // embedded: the URI is the pixels themselves
    }

    /// "image N" and its name or file, for warnings.
    std::string imageLabel(int index) const {
        std::string label = "image " + std::to_string(index);
        if (index < 0 || static_cast<size_t>(index) >= model_.images.size()) return label;
        const tinygltf::Image& image = model_.images[static_cast<size_t>(index)];
        if (!image.name.empty()) return label + " " + quoted(image.name);
        if (!image.uri.empty() && image.uri.rfind("data:", 0) != 0) return label + " " + quoted(image.uri);
        return label;
    }

    /// True when tinygltf decoded the image into `bits`-bit samples, 1-4 channels, all present.
    static bool hasPixels(const tinygltf::Image& image, int bits) {
        const int channels = image.component;
        if (image.width <= 0 || image.height <= 0 || channels < 1 || channels > 4 || image.bits != bits) return false;
        const size_t pixels = static_cast<size_t>(image.width) * image.height;
        return image.image.size() >= pixels * channels * (bits / 8);
    }

    /// The image's texels into `tex`: an 8-bit image as RGBA8 shared by every texture that reads
    /// it, in either colour space (decoded per lookup); a 16-bit image as linear floats, decoded
    /// here for `srgb` (8 bits would lose its precision). False when the image has no pixels.
    bool setTexels(int source, bool srgb, Texture& tex) {
        const tinygltf::Image& image = model_.images[static_cast<size_t>(source)];
        if (std::shared_ptr<const std::vector<glm::u8vec4>> rgba8 = rgba8Texels(source)) {
            tex.width = image.width;
            tex.height = image.height;
            tex.encoding = srgb ? TexelEncoding::Srgb8 : TexelEncoding::Linear8;
            tex.texels8 = std::move(rgba8);
            return true;
        }
        return convertPixels16(image, srgb, tex);
    }

    /// An 8-bit image's texels as RGBA8 (grey becomes g, g, g; a missing alpha 255), made once per
    /// image. tinygltf's own copy of the pixels is freed: the image is then held once while the
    /// rest of the scene loads. Null for an image that is not 8-bit or has no pixels.
    std::shared_ptr<const std::vector<glm::u8vec4>> rgba8Texels(int source) {
        if (const auto it = rgba8_images_.find(source); it != rgba8_images_.end()) return it->second;
        tinygltf::Image& image = model_.images[static_cast<size_t>(source)];
        if (!hasPixels(image, 8)) return nullptr;
        const int channels = image.component;
        const size_t pixels = static_cast<size_t>(image.width) * image.height;
        auto texels = std::make_shared<std::vector<glm::u8vec4>>(pixels);
        const unsigned char* in = image.image.data();
        for (size_t p = 0; p < pixels; ++p, in += channels) {
            const uint8_t alpha = channels == 2 || channels == 4 ? in[channels - 1] : 255;
            (*texels)[p] = channels <= 2 ? glm::u8vec4(in[0], in[0], in[0], alpha)  // grey or grey + alpha
                                         : glm::u8vec4(in[0], in[1], in[2], alpha);
        }
        std::vector<unsigned char>().swap(image.image);
        rgba8_images_.emplace(source, texels);
        return texels;
    }

    /// A 16-bit image (1-4 channels, as tinygltf decoded it) to linear RGBA floats. Colour
    /// channels of sRGB images are decoded; alpha is always linear.
    static bool convertPixels16(const tinygltf::Image& image, bool srgb, Texture& tex) {
        if (!hasPixels(image, 16)) return false;
        const int channels = image.component;
        const size_t pixels = static_cast<size_t>(image.width) * image.height;
        auto linear = [&](size_t pixel, int c) -> float {
            uint16_t v;
            std::memcpy(&v, &image.image[(pixel * channels + c) * 2], 2);  // stb returns 16-bit samples in host order
            return v / 65535.0f;
        };
        auto colour = [&](size_t pixel, int c) -> float {
            const float v = linear(pixel, c);
            return srgb ? srgbToLinear(v) : v;
        };

        tex.width = image.width;
        tex.height = image.height;
        tex.encoding = TexelEncoding::Float;
        tex.texels.resize(pixels);
        const bool hasAlpha = channels == 2 || channels == 4;
        for (size_t p = 0; p < pixels; ++p) {
            const float alpha = hasAlpha ? linear(p, channels - 1) : 1.0f;
            if (channels <= 2) {  // grey or grey + alpha
                const float g = colour(p, 0);
                tex.texels[p] = glm::vec4(g, g, g, alpha);
            } else {
                tex.texels[p] = glm::vec4(colour(p, 0), colour(p, 1), colour(p, 2), alpha);
            }
        }
        return true;
    }

    // ---------------------------------------------------------------- lights

    template <typename OrientationOfPath>
    void addNodeLight(int nodeIndex, const glm::dmat4& world, const OrientationOfPath& orientation) {
        const tinygltf::Node& node = model_.nodes[size_t(nodeIndex)];
        const tinygltf::Value* ext = extension(node.extensions, "KHR_lights_punctual");
        if (!ext) return;
        const std::optional<double> index = number(*ext, "light");
        if (!index || *index < 0 || *index >= static_cast<double>(model_.lights.size()))
            fail("node " + quoted(node.name) + ": KHR_lights_punctual light " +
                 (index ? std::to_string(static_cast<long long>(*index)) : std::string("(missing)")) +
                 " does not exist");
        const size_t light = static_cast<size_t>(*index);
        if (std::optional<PunctualLight> converted = convertLight(model_.lights[light], light, nodeIndex, world,
                                                                  orientation)) {
            scene_.lights.push_back(std::move(*converted));
        }
    }

    /// Photometric glTF units to the renderer's radiometric ones: candela (lm/sr) / 683 =
    /// W/sr for point and spot, lux (lm/m^2) / 683 = W/m^2 for directional. The colour is a
    /// per-channel multiplier on the intensity (KHR_lights_punctual). Nothing, with a warning,
    /// for a light of another type, one whose intensity or place has no float32 value, and a
    /// directional or spot light without a direction.
    template <typename OrientationOfPath>
    std::optional<PunctualLight> convertLight(const tinygltf::Light& src, size_t lightIndex, int nodeIndex,
                                              const glm::dmat4& world, const OrientationOfPath& orientationOfPath) {
        PunctualLight light;
        light.name = src.name;
        light.node_name = model_.nodes[size_t(nodeIndex)].name;
        const std::string label = "light " + std::to_string(lightIndex) +
                                  (src.name.empty() ? "" : " " + quoted(src.name)) + " on " + nodeLabel(nodeIndex);
        // What is wrong with the light itself (its colour, intensity, cone) is said at its first
        // node, not again at each node that places it too.
        const bool first_placement = placed_lights_.insert(lightIndex).second;
        if (src.type == "directional") light.type = LightType::Directional;
        else if (src.type == "spot") light.type = LightType::Spot;
        else if (src.type == "point") light.type = LightType::Point;
        else {
            // The extension's schema takes any string, so that later types do not break older
            // loaders: such a light is left out, named once however many nodes place it.
            if (unusable_lights_.insert(lightIndex).second) {
                warn(label + ": type " + quoted(src.type) +
                     " is none of KHR_lights_punctual's (directional, point, spot); skipped");
            }
            return std::nullopt;
        }

        // A negative colour or intensity would take light away; out of the extension's ranges, they
        // are clamped into them (colour [0, 1], intensity at least 0) with a warning. Read as the
        // file's doubles, so that the warning names a colour of 1e39 as that, not as float32's inf.
        const glm::dvec3 given_colour = src.color.size() < 3 ? glm::dvec3(1.0)
                                                             : glm::dvec3(src.color[0], src.color[1], src.color[2]);
        const auto clampedColour = [](double c) { return std::isnan(c) ? 1.0 : std::clamp(c, 0.0, 1.0); };
        const glm::dvec3 colour(clampedColour(given_colour.x), clampedColour(given_colour.y),
                                clampedColour(given_colour.z));
        const double intensity = std::isnan(src.intensity) ? 1.0 : std::max(src.intensity, 0.0);
        // An intensity whose radiometric value has no float32 would be an infinite light: its
        // power, and the brightest radiance the bake's fixed point is scaled to, infinite too.
        const double radiometric = intensity / kLumensPerWatt;
        if (!fitsFloat(radiometric)) {
            if (unusable_lights_.insert(lightIndex).second) {
                warn(label + ": intensity " + numberText(src.intensity) + " (" + numberText(radiometric) +
                     " after dividing by 683 lm/W) is beyond float32's range (at most " + numberText(kLargestFloat) +
                     "); skipped");
            }
            return std::nullopt;
        }
        if (first_placement && (colour != given_colour || intensity != src.intensity)) {
            warn(label + ": colour " + vec3Text(given_colour) + " and intensity " + numberText(src.intensity) +
                 " clamped into KHR_lights_punctual's ranges (colour [0, 1], intensity at least 0): " +
                 vec3Text(colour) + ", " + numberText(intensity));
        }

        // Where the light is must have a float32 value: a translation beyond float32's range
        // (1e39), or scales along the path whose product overflows a double (1e200 under 1e200,
        // which leaves the matrix infinity and NaN), would put the light at infinity or NaN, where
        // it lights nothing and says nothing.
        if (!isFinite(world)) {
            warn(label +
                 ": the node's world transform is not finite (the scales and translations along its path "
                 "overflow a double); skipped");
            return std::nullopt;
        }
        const glm::dvec3 position(world * glm::dvec4(0.0, 0.0, 0.0, 1.0));
        const bool within_world = withinWorldLimit(position);
        if (light.type != LightType::Directional && !within_world) {
            warn(label + ": the node's transform puts the light at " + vec3Text(position) +
                 ", beyond +-1e9 m, where nothing of a scene may lie (a sun is a directional light); skipped");
            return std::nullopt;
        }
        // A directional light's position means nothing (and may be anywhere).
        light.position = within_world ? glm::vec3(position) : glm::vec3(0.0f);
        // The node's -Z in world space, through the whole world matrix (a mirror turns it). Where a
        // scale of zero collapses that axis (how some tools hide an object), the rotations along
        // the node's path orient the light, as glTF says; a singular matrix has none.
        const glm::dvec3 dir = glm::dmat3(world) * glm::dvec3(0.0, 0.0, -1.0);
        const double length = glm::length(dir);
        if (std::isfinite(length) && length > 0.0) {
            light.direction = glm::vec3(dir / length);
        } else if (light.type != LightType::Point) {
            const WorldOrientation orientation = orientationOfPath();
            const glm::dvec3 oriented = orientation.rotation * glm::dvec3(0.0, 0.0, -1.0);
            if (orientation.singular_node >= 0) {
                warn(label + ": the node's -Z axis has no direction in world space (a scale of zero), and the " +
                     "matrix of " + nodeLabel(orientation.singular_node) +
                     " is singular, so nothing orients the light; skipped (give that node rotation, translation "
                     "and scale instead of its matrix)");
                return std::nullopt;
            }
            if (!isFinite(glm::vec3(oriented))) {
                warn(label + ": the node's transform is not finite, so the light has no direction; skipped");
                return std::nullopt;
            }
            light.direction = glm::vec3(glm::normalize(oriented));
        }
        light.intensity = glm::vec3(colour) * static_cast<float>(radiometric);
        light.range = src.range > 0.0 ? static_cast<float>(src.range) : 0.0f;
        if (light.type == LightType::Spot) setSpotCone(src, first_placement ? label : std::string(), light);
        return light;
    }

    /// The extension requires 0 <= inner < outer <= pi/2; clamp anything else so the
    /// renderer's smooth-step between the cones stays well defined. Warns naming `label`, unless
    /// it is empty (the light was warned about at another node).
    void setSpotCone(const tinygltf::Light& src, const std::string& label, PunctualLight& light) {
        constexpr double halfPi = 1.5707963267948966;
        const double outer = std::clamp(src.spot.outerConeAngle, 0.0, halfPi);
        const double inner = std::clamp(src.spot.innerConeAngle, 0.0, outer);
        if (!label.empty() && (outer != src.spot.outerConeAngle || inner != src.spot.innerConeAngle || inner == outer))
            warn(label + ": spot cone angles (inner " + std::to_string(src.spot.innerConeAngle) + ", outer " +
                 std::to_string(src.spot.outerConeAngle) + ") outside 0 <= inner < outer <= pi/2; clamped");
        light.inner_cone_angle = static_cast<float>(inner);
        light.outer_cone_angle = static_cast<float>(outer);
    }

    // ---------------------------------------------------------------- cameras

    void addCamera(const tinygltf::Node& node, const glm::dmat4& world) {
        if (static_cast<size_t>(node.camera) >= model_.cameras.size())
            fail("node " + quoted(node.name) + ": camera " + std::to_string(node.camera) + " does not exist");
        const tinygltf::Camera& src = model_.cameras[node.camera];
        Camera cam;
        cam.name = src.name;
        cam.node_name = node.name;
        // Skipped cameras get no index: a nameless one is named by its node.
        const std::string label = cam.name.empty() && cam.node_name.empty()
                                      ? "camera of node " + std::to_string(&node - model_.nodes.data())
                                      : cameraLabel(cam);
        const bool orthographic = src.type == "orthographic";
        if (!orthographic && src.type != "perspective") {
            warn(label + ": " + printable(src.type) + " cameras are not supported; skipped");
            return;
        }
        const glm::dvec3 position(world * glm::dvec4(0.0, 0.0, 0.0, 1.0));
        if (!withinWorldLimit(position)) {
            warn(label + ": the node's transform puts the camera at " + vec3Text(position) +
                 ", beyond +-1e9 m, where nothing of a scene may lie; skipped");
            return;
        }
        cam.position = glm::vec3(position);
        const glm::dmat3 linear(world);
        const glm::dvec3 view_axis = linear * glm::dvec3(0.0, 0.0, -1.0);
        const glm::dvec3 forward = glm::normalize(view_axis);
        // Scale or shear in the node matrix can tilt +Y off perpendicular; project it back.
        glm::dvec3 up = linear * glm::dvec3(0.0, 1.0, 0.0);
        up = glm::normalize(up - glm::dot(up, forward) * forward);
        if (!isFinite(glm::vec3(forward)) || !isFinite(glm::vec3(up))) {
            warn(label + ": degenerate node transform; skipped");
            return;
        }
        cam.forward = glm::vec3(forward);
        cam.up = glm::vec3(up);
        if (orthographic) {
            // glTF: xmag and ymag are half the view's width and height; zero is invalid, and a
            // negative value (a mirrored view) is read by its size.
            const double xmag = std::abs(src.orthographic.xmag), ymag = std::abs(src.orthographic.ymag);
            // Rays start across the view rectangle: one wider than the world's limit starts them
            // where Embree refuses rays.
            if (!(xmag > 0.0 && ymag > 0.0 && xmag <= kMaxWorldCoordinate && ymag <= kMaxWorldCoordinate &&
                  float(xmag) > 0.0f && float(ymag) > 0.0f)) {
                warn(label + ": orthographic xmag " + numberText(src.orthographic.xmag) + " and ymag " +
                     numberText(src.orthographic.ymag) + " must be non-zero and at most 1e9; skipped");
                return;
            }
            cam.orthographic_half_height = float(ymag);
            cam.aspect_ratio = sensibleAspectRatio(xmag / ymag, "xmag / ymag", label);
            readClipPlanes(src.orthographic.znear, src.orthographic.zfar, true, glm::length(view_axis), label, cam);
            addSceneCamera(std::move(cam));
            return;
        }
        if (src.perspective.yfov > 0.0 && src.perspective.yfov < 3.14159)
            cam.yfov = static_cast<float>(src.perspective.yfov);
        else
            warn(label + ": invalid yfov " + std::to_string(src.perspective.yfov) + "; using " +
                 std::to_string(cam.yfov));
        if (src.perspective.aspectRatio > 0.0)
            cam.aspect_ratio = sensibleAspectRatio(src.perspective.aspectRatio, "aspectRatio", label);
        readClipPlanes(src.perspective.znear, src.perspective.zfar, false, glm::length(view_axis), label, cam);
        addSceneCamera(std::move(cam));
    }

    /// The camera's clip planes (Blender writes its clip start and end there), given in the camera
    /// node's space: `scale` is the length its world matrix gives the view axis. glTF derives the
    /// view "with the scaling ignored", and `yfov` and `ymag` are read so; the clip distances are
    /// scaled all the same, as viewers that clip in the camera's space (three.js) do, so that a
    /// root node changing units (x0.001 from millimetres) keeps the clip where the file's author
    /// put it against the scene: unscaled, the Cornell box under a kilometre root lost its whole
    /// view behind a near plane 10 m away in the box's units. A camera node of scale 1 (Blender's)
    /// reads them as written. Bad values are warned about and dropped, as for `yfov`, leaving the
    /// camera to see from its position (znear 0) or without end (no zfar); a perspective `znear`
    /// of 0 (below glTF's minimum, but meaning the same) and its absent `zfar` (tinygltf's 0: an
    /// infinite projection) are no error.
    void readClipPlanes(double znear, double zfar, bool orthographic, double scale, const std::string& label,
                        Camera& cam) {
        const double near = znear * scale, far = zfar * scale;
        if (near >= 0.0 && near <= kMaxWorldCoordinate) {
            cam.znear = float(near);
        } else {
            warn(label + ": invalid znear " + numberText(znear) +
                 " (a distance from 0 to 1e9 in the scene); the camera sees from its position");
        }
        const bool absent = !orthographic && zfar == 0.0;
        if (absent) return;
        // Compared as the floats the rays use: a zfar a rounding past znear is no gap to see in.
        if (!(far > double(cam.znear)) || (far <= kMaxWorldCoordinate && !(float(far) > cam.znear))) {
            warn(label + ": invalid zfar " + numberText(zfar) + " (must be greater than znear " +
                 numberText(cam.znear > 0.0f ? znear : 0.0) + "); no far clip plane");
            return;
        }
        // Beyond the world's limit there is nothing to clip.
        if (far <= kMaxWorldCoordinate) cam.zfar = float(far);
    }

    /// Aspect ratios of real frames, from tall phone screens to wide panoramas, are well inside
    /// these bounds; beyond them a renders's height from its width (`--resolution W`) would be a
    /// single row, or too many pixels to allocate.
    static constexpr double kMinAspectRatio = 0.01;
    static constexpr double kMaxAspectRatio = 100.0;

    /// `aspect` (width / height), or nothing with a warning when it is no real frame's: the
    /// image's own size then gives the aspect.
    std::optional<float> sensibleAspectRatio(double aspect, const char* what, const std::string& label) {
        if (aspect >= kMinAspectRatio && aspect <= kMaxAspectRatio) return float(aspect);
        char text[64];
        std::snprintf(text, sizeof text, "%g", aspect);
        warn(label + ": " + what + " " + text +
             " is outside [0.01, 100], no real frame's; ignored (an image's "
             "width and height give its aspect ratio, a width alone a square)");
        return std::nullopt;
    }

    void addSceneCamera(Camera cam) {
        cam.index = int32_t(scene_.cameras.size());
        scene_.cameras.push_back(std::move(cam));
    }

    // ---------------------------------------------------------------- sky

    /// sharcbake's keys in the extras: the root's, else the loaded scene's, where Blender writes
    /// the custom properties of its scene. Null where neither has any.
    const tinygltf::Value* sharcbakeExtras() const {
        if (model_.extras.IsObject() && model_.extras.Has("sharcbake")) return &model_.extras.Get("sharcbake");
        if (model_.scenes.empty()) return nullptr;
        const tinygltf::Value& extras = loadedScene().extras;
        return extras.IsObject() && extras.Has("sharcbake") ? &extras.Get("sharcbake") : nullptr;
    }

    /// sharcbake's own convention: extras {"sharcbake": {"sky_radiance": [r, g, b]}} (the root's
    /// or the scene's) gives a uniform sky radiance (linear, W/(m^2 sr)); glTF has no standard way
    /// to say this.
    void readSky() {
        const tinygltf::Value* extras = sharcbakeExtras();
        if (!extras) return;
        const tinygltf::Value& ours = *extras;
        if (!ours.IsObject() || !ours.Has("sky_radiance")) return;
        const std::optional<glm::vec3> sky = vecValue<3>(ours, "sky_radiance");
        if (!sky || !isFinite(*sky) || sky->x < 0.0f || sky->y < 0.0f || sky->z < 0.0f)
            fail("extras.sharcbake.sky_radiance must be an array of 3 finite, non-negative numbers");
        scene_.sky.uniform = *sky;
    }

    /// Root extras {"sharcbake": {"expected_radiance": L or [r, g, b]}}: the radiance every
    /// surface has (scenes/README.md, furnace rooms), so error can be measured exactly.
    void readKnownRadiance() {
        const tinygltf::Value* extras = sharcbakeExtras();
        if (!extras) return;
        const tinygltf::Value& ours = *extras;
        if (!ours.IsObject() || !ours.Has("expected_radiance")) return;
        std::optional<glm::vec3> known = vecValue<3>(ours, "expected_radiance");
        if (!known) {
            if (const std::optional<double> scalar = number(ours, "expected_radiance")) known = glm::vec3(float(*scalar));
        }
        if (!known || !isFinite(*known) || known->x <= 0.0f || known->y <= 0.0f || known->z <= 0.0f)
            fail("extras.sharcbake.expected_radiance must be a positive finite number or an array of 3");
        scene_.known_radiance = *known;
    }
};

}  // namespace

Scene loadGltf(const std::string& path, const GltfLoadLimits& limits) { return GltfLoader(path, limits).load(); }

}  // namespace sharcbake
