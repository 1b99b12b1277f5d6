// SPDX-License-Identifier: Apache-2.0
#include "gltf_rewrite.h"

#include "message_text.h"

#include <meshoptimizer.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>

namespace sharcbake {
namespace {

[[noreturn]] void fail(const std::string& what) { throw GltfRewriteError(what); }

/// Removes `indices` from every KHR_draco_mesh_compression primitive (see rewriteForTinygltf).
bool removeDracoIndices(nlohmann::json& doc, std::map<std::pair<int, int>, uint64_t>& counts) {
    if (!doc.contains("meshes") || !doc["meshes"].is_array()) return false;
    const nlohmann::json* accessors = doc.contains("accessors") && doc["accessors"].is_array() ? &doc["accessors"]
                                                                                               : nullptr;
    bool changed = false;
    for (size_t m = 0; m < doc["meshes"].size(); ++m) {
        nlohmann::json& mesh = doc["meshes"][m];
        if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array()) continue;
        for (size_t p = 0; p < mesh["primitives"].size(); ++p) {
            nlohmann::json& prim = mesh["primitives"][p];
            if (!prim.is_object() || !prim.contains("indices") || !prim.contains("extensions") ||
                !prim["extensions"].is_object() || !prim["extensions"].contains("KHR_draco_mesh_compression"))
                continue;
            const nlohmann::json& indices = prim["indices"];
            if (accessors && indices.is_number_unsigned() && indices.get<uint64_t>() < accessors->size()) {
                const nlohmann::json& accessor = (*accessors)[indices.get<size_t>()];
                if (accessor.is_object() && accessor.contains("count") && accessor["count"].is_number_unsigned())
                    counts[{int(m), int(p)}] = accessor["count"].get<uint64_t>();
            }
            prim.erase("indices");
            changed = true;
        }
    }
    return changed;
}

/// The bytes of a base64 data URI's payload.
std::string base64Decode(const std::string& text, const std::string& what) {
    std::string out;
    uint32_t bits = 0;
    int count = 0;
    for (const char c : text) {
        int v;
        if (c >= 'A' && c <= 'Z') v = c - 'A';
        else if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
        else if (c >= '0' && c <= '9') v = c - '0' + 52;
        else if (c == '+') v = 62;
        else if (c == '/') v = 63;
        else if (c == '=') break;
        else fail(what + ": a data URI that is not base64");
        bits = (bits << 6) | uint32_t(v);
        if (++count == 4) {
            out += char(bits >> 16);
            out += char(bits >> 8);
            out += char(bits);
            bits = 0;
            count = 0;
        }
    }
    if (count == 2) out += char(bits >> 4);
    if (count == 3) {
        out += char(bits >> 10);
        out += char(bits >> 2);
    }
    return out;
}

/// The bytes of buffer `index` of the JSON (EXT_meshopt_compression's source buffers): the
/// GLB's binary chunk, a data: URI or a file read by `read_file`. Empty for a buffer without
/// data (a meshopt fallback).
std::string bufferBytes(const nlohmann::json& doc, size_t index, bool glb, const std::string& glb_bin,
                        const ReadBufferFile& read_file) {
    const std::string what = "buffer " + std::to_string(index);
    if (!doc.contains("buffers") || !doc["buffers"].is_array() || index >= doc["buffers"].size())
        fail(what + " does not exist");
    const nlohmann::json& buffer = doc["buffers"][index];
    if (!buffer.is_object() || !buffer.contains("uri") || !buffer["uri"].is_string())
        return glb && index == 0 ? glb_bin : std::string();
    const std::string uri = buffer["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0) {
        const size_t comma = uri.find(',');
        if (comma == std::string::npos || uri.find(";base64", 0) > comma)
            fail(what + ": a data URI that is not base64");
        return base64Decode(uri.substr(comma + 1), what);
    }
    return read_file(uri);
}

/// One EXT_meshopt_compression bufferView decoded: `count` elements of `byteStride` bytes.
std::string decodeMeshoptView(const nlohmann::json& ext, const char* data, size_t size, const std::string& label) {
    const auto integer = [&](const char* name) -> uint64_t {
        if (!ext.contains(name) || !ext[name].is_number_unsigned()) fail(label + ": no " + name);
        return ext[name].get<uint64_t>();
    };
    const uint64_t count = integer("count"), stride = integer("byteStride");
    const std::string mode = ext.contains("mode") && ext["mode"].is_string() ? ext["mode"].get<std::string>() : "";
    const std::string filter = ext.contains("filter") && ext["filter"].is_string() ? ext["filter"].get<std::string>()
                                                                                   : "NONE";
    // The codecs shrink data by at most about 64x (zeros): a larger claim is not data.
    if (stride == 0 || stride > 256 || count > (uint64_t(size) * 128 + 4096) / stride)
        fail(label + ": " + std::to_string(count) + " elements of " + std::to_string(stride) + " bytes from " +
             std::to_string(size) + " compressed bytes is not a valid size");
    std::string out(size_t(count * stride), '\0');
    const auto* src = reinterpret_cast<const unsigned char*>(data);
    int result = -1;
    if (mode == "ATTRIBUTES") {
        if (stride % 4 != 0) fail(label + ": ATTRIBUTES with a byteStride that is not a multiple of 4");
        result = meshopt_decodeVertexBuffer(out.data(), count, stride, src, size);
    } else if (mode == "TRIANGLES" || mode == "INDICES") {
        if (stride != 2 && stride != 4) fail(label + ": " + mode + " with a byteStride other than 2 or 4");
        if (mode == "TRIANGLES" && count % 3 != 0) fail(label + ": TRIANGLES with a count not divisible by 3");
        result = mode == "TRIANGLES" ? meshopt_decodeIndexBuffer(out.data(), count, stride, src, size)
                                     : meshopt_decodeIndexSequence(out.data(), count, stride, src, size);
    } else {
        fail(label + ": unknown mode " + quoted(mode));
    }
    if (result != 0) fail(label + ": meshoptimizer could not decode it (error " + std::to_string(result) + ")");
    if (filter == "NONE") return out;
    if (mode != "ATTRIBUTES") fail(label + ": filter " + quoted(filter) + " on " + mode);
    if (filter == "OCTAHEDRAL" && (stride == 4 || stride == 8)) {
        meshopt_decodeFilterOct(out.data(), count, stride);
    } else if (filter == "QUATERNION" && stride == 8) {
        meshopt_decodeFilterQuat(out.data(), count, stride);
    } else if (filter == "EXPONENTIAL" && stride % 4 == 0) {
        meshopt_decodeFilterExp(out.data(), count, stride);
    } else {
        fail(label + ": filter " + quoted(filter) + " with byteStride " + std::to_string(stride) +
             " is not one EXT_meshopt_compression defines");
    }
    return out;
}

/// Decodes every EXT_meshopt_compression bufferView (copying the others) into one binary
/// buffer that replaces the file's buffers; returns it, or nothing if no view is compressed.
std::optional<std::string> decodeMeshoptBufferViews(nlohmann::json& doc, bool glb, const std::string& glb_bin,
                                                    const ReadBufferFile& read_file) {
    if (!doc.contains("bufferViews") || !doc["bufferViews"].is_array()) return std::nullopt;
    nlohmann::json& views = doc["bufferViews"];
    bool any = false;
    for (const nlohmann::json& view : views)
        any |= view.is_object() && view.contains("extensions") && view["extensions"].is_object() &&
               view["extensions"].contains("EXT_meshopt_compression");
    if (!any) return std::nullopt;
    std::map<size_t, std::string> buffers;  // read once each
    const auto source = [&](const nlohmann::json& object,
                            const std::string& what) -> std::pair<const std::string*, size_t> {
        const auto field = [&](const char* name, uint64_t fallback) {
            if (!object.contains(name)) return fallback;
            if (!object[name].is_number_unsigned()) fail(what + ": " + name + " is not a non-negative integer");
            return object[name].get<uint64_t>();
        };
        const uint64_t buffer = field("buffer", ~uint64_t(0)), offset = field("byteOffset", 0),
                       length = field("byteLength", ~uint64_t(0));
        if (buffer == ~uint64_t(0) || length == ~uint64_t(0)) fail(what + ": no buffer or byteLength");
        auto it = buffers.find(buffer);
        if (it == buffers.end()) it = buffers.emplace(buffer, bufferBytes(doc, buffer, glb, glb_bin, read_file)).first;
        if (offset > it->second.size() || length > it->second.size() - offset)
            fail(what + " spans bytes [" + std::to_string(offset) + ", " + std::to_string(offset + length) +
                 ") but buffer " + std::to_string(buffer) + " holds only " + std::to_string(it->second.size()) +
                 " bytes (missing or short buffer)");
        return {&it->second, size_t(offset)};
    };
    std::string bin;
    for (size_t v = 0; v < views.size(); ++v) {
        nlohmann::json& view = views[v];
        const std::string what = "bufferView " + std::to_string(v);
        if (!view.is_object()) fail(what + " is not an object");
        while (bin.size() % 16 != 0) bin += '\0';
        const size_t offset = bin.size();
        if (view.contains("extensions") && view["extensions"].is_object() &&
            view["extensions"].contains("EXT_meshopt_compression")) {
            const nlohmann::json ext = view["extensions"]["EXT_meshopt_compression"];
            const std::string label = what + " EXT_meshopt_compression";
            if (!ext.is_object()) fail(label + " is not an object");
            const auto [data, start] = source(ext, label);
            const std::string decoded = decodeMeshoptView(ext, data->data() + start, ext["byteLength"].get<size_t>(),
                                                          label);
            bin += decoded;
            view["byteLength"] = decoded.size();  // count x byteStride; the accessors are checked against it
            view["extensions"].erase("EXT_meshopt_compression");
            if (view["extensions"].empty()) view.erase("extensions");
        } else {
            const auto [data, start] = source(view, what);
            bin.append(*data, start, view["byteLength"].get<size_t>());
        }
        view["buffer"] = 0;
        view["byteOffset"] = offset;
    }
    doc["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}}});
    return bin;
}

/// The `data:` URI prefixes tinygltf 2.7 decodes (DecodeDataURI); it refuses any other.
constexpr const char* kTinygltfDataUriHeaders[] = {"data:application/octet-stream;base64,",
                                                   "data:image/jpeg;base64,",
                                                   "data:image/png;base64,",
                                                   "data:image/bmp;base64,",
                                                   "data:image/gif;base64,",
                                                   "data:text/plain;base64,",
                                                   "data:application/gltf-buffer;base64,"};

/// Neutral type for an image's bytes: the loader's image decoders go by the bytes' content.
constexpr const char* kOctetStreamHeader = "data:application/octet-stream;base64,";

bool isBase64Char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '+' || c == '/'; }

/// What tinygltf makes of a `data:` URI: it decodes base64 payloads under the headers above; it
/// refuses any other type (image/webp, image/ktx2, ...) and a payload with fewer than the two
/// base64 characters that make a byte (it stops at the first character that is not base64).
enum class DataUri { Decoded, OtherType, NoData };

/// The URI's header up to and including ";base64,", or nothing when it is not base64.
std::optional<size_t> base64HeaderLength(const char* uri, size_t size) {
    static constexpr char kMarker[] = ";base64,";
    const std::string_view text(uri, std::min<size_t>(size, 256));  // headers are short
    const size_t at = text.find(kMarker);
    if (at == std::string_view::npos) return std::nullopt;
    return at + sizeof kMarker - 1;
}

DataUri classifyDataUri(const char* uri, size_t size) {
    const std::optional<size_t> header = base64HeaderLength(uri, size);
    if (!header || size < *header + 2 || !isBase64Char(uri[*header]) || !isBase64Char(uri[*header + 1]))
        return DataUri::NoData;
    for (const char* known : kTinygltfDataUriHeaders) {
        if (std::strlen(known) == *header && std::memcmp(uri, known, *header) == 0) return DataUri::Decoded;
    }
    return DataUri::OtherType;
}

/// True when some `"data:` string in the file's bytes is one tinygltf would refuse.
bool hasRefusedDataUri(const std::string& bytes) {
    for (size_t at = bytes.find("\"data:"); at != std::string::npos; at = bytes.find("\"data:", at + 1)) {
        const size_t end = bytes.find('"', at + 1);
        const size_t size = (end == std::string::npos ? bytes.size() : end) - (at + 1);
        if (classifyDataUri(bytes.data() + at + 1, size) != DataUri::Decoded) return true;
    }
    return false;
}

/// Image `data:` URIs tinygltf would refuse, made parseable: one of another type (WebP, KTX2)
/// gets the neutral type, so its bytes reach the loader's decoders, which go by content; one
/// without base64 data becomes one byte no decoder reads, and why is recorded (see the header).
bool fixImageDataUris(nlohmann::json& doc, std::map<int, std::string>& refused) {
    if (!doc.contains("images") || !doc["images"].is_array()) return false;
    bool changed = false;
    for (size_t i = 0; i < doc["images"].size(); ++i) {
        nlohmann::json& image = doc["images"][i];
        if (!image.is_object() || !image.contains("uri") || !image["uri"].is_string()) continue;
        const std::string& uri = image["uri"].get_ref<const std::string&>();
        if (uri.rfind("data:", 0) != 0) continue;
        switch (classifyDataUri(uri.data(), uri.size())) {
            case DataUri::Decoded: continue;
            case DataUri::OtherType:
                image["uri"] = kOctetStreamHeader + uri.substr(*base64HeaderLength(uri.data(), uri.size()));
                break;
            case DataUri::NoData:
                refused[int(i)] = "its data: URI holds no base64 data";
                image["uri"] = std::string(kOctetStreamHeader) + "AA==";
                break;
        }
        changed = true;
    }
    return changed;
}

}  // namespace

bool mayNeedRewrite(const std::string& bytes) {
    return bytes.find("KHR_draco_mesh_compression") != std::string::npos ||
           bytes.find("EXT_meshopt_compression") != std::string::npos || hasRefusedDataUri(bytes);
}

std::optional<TinygltfInput> rewriteForTinygltf(const std::string& bytes, bool glb, const ReadBufferFile& read_file) {
    const bool draco = bytes.find("KHR_draco_mesh_compression") != std::string::npos;
    const bool meshopt = bytes.find("EXT_meshopt_compression") != std::string::npos;
    const bool data_uris = hasRefusedDataUri(bytes);
    if (!draco && !meshopt && !data_uris) return std::nullopt;
    size_t json_begin = 0, json_size = bytes.size();
    std::string glb_bin;  // the GLB's binary chunk: buffer 0 when that has no uri
    if (glb) {
        if (bytes.size() < 20 || std::memcmp(bytes.data() + 16, "JSON", 4) != 0) return std::nullopt;
        uint32_t total = 0, chunk = 0;
        std::memcpy(&total, bytes.data() + 8, 4);
        std::memcpy(&chunk, bytes.data() + 12, 4);
        if (total > bytes.size() || chunk > total - 20) return std::nullopt;
        json_begin = 20;
        json_size = chunk;
        const size_t bin_header = 20 + size_t(chunk);
        if (bin_header + 8 <= total && std::memcmp(bytes.data() + bin_header + 4, "BIN", 4) == 0) {
            uint32_t bin_size = 0;
            std::memcpy(&bin_size, bytes.data() + bin_header, 4);
            if (bin_size <= total - bin_header - 8) glb_bin = bytes.substr(bin_header + 8, bin_size);
        }
    }
    nlohmann::json doc = nlohmann::json::parse(bytes.begin() + std::ptrdiff_t(json_begin),
                                               bytes.begin() + std::ptrdiff_t(json_begin + json_size), nullptr,
                                               /*allow_exceptions=*/false);
    if (doc.is_discarded() || !doc.is_object()) return std::nullopt;
    TinygltfInput result;
    std::optional<std::string> decoded_bin;
    if (meshopt) decoded_bin = decodeMeshoptBufferViews(doc, glb, glb_bin, read_file);
    const bool draco_changed = draco && removeDracoIndices(doc, result.draco_index_counts);
    const bool images_changed = data_uris && fixImageDataUris(doc, result.refused_image_uris);
    if (!decoded_bin && !draco_changed && !images_changed) return std::nullopt;  // tinygltf reads the file itself

    std::string json = doc.dump();
    if (!glb && !decoded_bin) {
        result.bytes = std::move(json);
        return result;
    }
    const std::string& bin = decoded_bin ? *decoded_bin : glb_bin;
    const bool has_bin = decoded_bin || !glb_bin.empty();
    while (json.size() % 4 != 0) json += ' ';
    std::string padded_bin = bin;
    while (padded_bin.size() % 4 != 0) padded_bin += '\0';
    std::string out;
    const auto put32 = [&out](uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    out += "glTF";
    put32(2);
    put32(uint32_t(12 + 8 + json.size() + (has_bin ? 8 + padded_bin.size() : 0)));
    put32(uint32_t(json.size()));
    out += "JSON";
    out += json;
    if (has_bin) {
        put32(uint32_t(padded_bin.size()));
        out += std::string("BIN\0", 4);
        out += padded_bin;
    }
    result.bytes = std::move(out);
    result.glb = true;
    return result;
}

std::string uriDecode(const std::string& uri) {
    std::string out;
    for (size_t i = 0; i < uri.size(); ++i) {
        if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
            std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
            out += char(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
            i += 2;
        } else {
            out += uri[i];
        }
    }
    return out;
}

}  // namespace sharcbake
