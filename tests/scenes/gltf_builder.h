// SPDX-License-Identifier: Apache-2.0
/// @file gltf_builder.h
/// @brief Test helper: builds small glTF documents in memory and writes them as .gltf with
/// an embedded data-URI buffer, .gltf with an external .bin, or .glb.
#pragma once

#include <nlohmann/json.hpp>

#include <atomic>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace sharcbake::test {

constexpr int kByte = 5120;
constexpr int kUnsignedByte = 5121;
constexpr int kShort = 5122;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;

/// A fresh folder under the system temp directory, removed with everything in it.
class TempDir {
public:
    TempDir() {
        static std::atomic<int> counter{0};
        path_ = std::filesystem::temp_directory_path() /
                ("sharcbake_scene_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
        std::filesystem::remove_all(path_);
        std::filesystem::create_directories(path_);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path_, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    std::string file(const std::string& name) const { return (path_ / name).string(); }

private:
    std::filesystem::path path_;
};

inline std::string base64(const std::vector<uint8_t>& data) {
    static const char* digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    size_t i = 0;
    for (; i + 2 < data.size(); i += 3) {
        const uint32_t v = (data[i] << 16) | (data[i + 1] << 8) | data[i + 2];
        for (int s = 18; s >= 0; s -= 6) out += digits[(v >> s) & 63];
    }
    if (const size_t rest = data.size() - i; rest > 0) {
        const uint32_t v = (data[i] << 16) | (rest == 2 ? data[i + 1] << 8 : 0);
        out += digits[(v >> 18) & 63];
        out += digits[(v >> 12) & 63];
        out += rest == 2 ? digits[(v >> 6) & 63] : '=';
        out += '=';
    }
    return out;
}

inline void writeFile(const std::string& path, const void* data, size_t size) {
    std::ofstream out(path, std::ios::binary);
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
}

inline void writeFile(const std::string& path, const std::string& text) { writeFile(path, text.data(), text.size()); }

inline int componentSize(int componentType) {
    switch (componentType) {
    case kByte:
    case kUnsignedByte: return 1;
    case kShort:
    case kUnsignedShort: return 2;
    default: return 4;
    }
}

inline int componentCount(const std::string& type) {
    if (type == "SCALAR") return 1;
    if (type == "VEC2") return 2;
    if (type == "VEC3") return 3;
    if (type == "VEC4") return 4;
    return 16;  // MAT4
}

class GltfBuilder {
public:
    nlohmann::json doc;
    std::vector<uint8_t> bin;

    GltfBuilder() {
        doc["asset"]["version"] = "2.0";
        doc["asset"]["generator"] = "sharcbake scene_tests";
    }

    /// Appends raw bytes (4-byte aligned) as a new bufferView; returns its index.
    int addView(const void* data, size_t bytes, size_t stride = 0) {
        while (bin.size() % 4 != 0) bin.push_back(0);
        const size_t offset = bin.size();
        bin.resize(offset + bytes);
        std::memcpy(bin.data() + offset, data, bytes);
        nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", bytes}};
        if (stride != 0) view["byteStride"] = stride;
        doc["bufferViews"].push_back(view);
        return static_cast<int>(doc["bufferViews"].size()) - 1;
    }

    int addAccessor(int view, int componentType, size_t count, const std::string& type, size_t byteOffset = 0,
                    bool normalized = false) {
        nlohmann::json acc = {{"bufferView", view}, {"componentType", componentType}, {"count", count}, {"type", type}};
        if (byteOffset != 0) acc["byteOffset"] = byteOffset;
        if (normalized) acc["normalized"] = true;
        doc["accessors"].push_back(acc);
        return static_cast<int>(doc["accessors"].size()) - 1;
    }

    /// A tightly packed accessor over `values` (count derived from the element size).
    template <class T>
    int addData(const std::vector<T>& values, int componentType, const std::string& type, bool normalized = false) {
        const size_t bytes = values.size() * sizeof(T);
        const int view = addView(values.data(), bytes);
        const size_t elementSize = static_cast<size_t>(componentSize(componentType)) * componentCount(type);
        return addAccessor(view, componentType, bytes / elementSize, type, 0, normalized);
    }

    int addPositions(const std::vector<float>& xyz) { return addData(xyz, kFloat, "VEC3"); }

    int addMesh(const nlohmann::json& primitives, const std::string& name = "") {
        nlohmann::json mesh = {{"primitives", primitives}};
        if (!name.empty()) mesh["name"] = name;
        doc["meshes"].push_back(mesh);
        return static_cast<int>(doc["meshes"].size()) - 1;
    }

    int addNode(const nlohmann::json& node) {
        doc["nodes"].push_back(node);
        return static_cast<int>(doc["nodes"].size()) - 1;
    }

    int addMaterial(const nlohmann::json& material) {
        doc["materials"].push_back(material);
        return static_cast<int>(doc["materials"].size()) - 1;
    }

    /// One scene holding the given root nodes, made the default.
    void setScene(const std::vector<int>& roots) {
        doc["scenes"] = nlohmann::json::array({{{"nodes", roots}}});
        doc["scene"] = 0;
    }

    /// Mesh + node + scene in one call: a single triangle-list primitive.
    int addMeshNode(const nlohmann::json& primitive, const nlohmann::json& node = nlohmann::json::object()) {
        const int mesh = addMesh(nlohmann::json::array({primitive}));
        nlohmann::json n = node;
        n["mesh"] = mesh;
        return addNode(n);
    }

    std::string writeEmbedded(const TempDir& dir, const std::string& name) const {
        nlohmann::json d = doc;
        if (!bin.empty())
            d["buffers"] = nlohmann::json::array(
                {{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64(bin)}}});
        const std::string path = dir.file(name);
        writeFile(path, d.dump(2));
        return path;
    }

    /// .gltf + external .bin; `writeBin = false` leaves the .bin missing on purpose.
    std::string writeExternal(const TempDir& dir, const std::string& name, const std::string& binName,
                              bool writeBin = true) const {
        nlohmann::json d = doc;
        d["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}, {"uri", binName}}});
        if (writeBin) writeFile(dir.file(binName), bin.data(), bin.size());
        const std::string path = dir.file(name);
        writeFile(path, d.dump(2));
        return path;
    }

    std::string writeGlb(const TempDir& dir, const std::string& name) const {
        nlohmann::json d = doc;
        if (!bin.empty()) d["buffers"] = nlohmann::json::array({{{"byteLength", bin.size()}}});
        std::string json = d.dump();
        while (json.size() % 4 != 0) json += ' ';  // JSON chunk is padded with spaces
        std::vector<uint8_t> payload = bin;
        while (payload.size() % 4 != 0) payload.push_back(0);

        std::vector<uint8_t> glb;
        auto put32 = [&](uint32_t v) {
            for (int i = 0; i < 4; ++i) glb.push_back(static_cast<uint8_t>(v >> (8 * i)));
        };
        const uint32_t total = 12 + 8 + static_cast<uint32_t>(json.size()) +
                               (payload.empty() ? 0 : 8 + static_cast<uint32_t>(payload.size()));
        put32(0x46546C67);  // "glTF"
        put32(2);
        put32(total);
        put32(static_cast<uint32_t>(json.size()));
        put32(0x4E4F534A);  // "JSON"
        glb.insert(glb.end(), json.begin(), json.end());
        if (!payload.empty()) {
            put32(static_cast<uint32_t>(payload.size()));
            put32(0x004E4942);  // "BIN\0"
            glb.insert(glb.end(), payload.begin(), payload.end());
        }
        const std::string path = dir.file(name);
        writeFile(path, glb.data(), glb.size());
        return path;
    }
};

}  // namespace sharcbake::test
