// SPDX-License-Identifier: Apache-2.0
/// @file labels.cpp
/// @brief How messages name a camera, a material and a light: by name where they have one, else by
/// index.
#include "message_text.h"
#include "sharcbake/scene.h"

namespace sharcbake {

std::string cameraLabel(const Camera& camera) {
    if (!camera.node_name.empty()) {
        std::string label = "camera " + quoted(camera.node_name);
        if (!camera.name.empty() && camera.name != camera.node_name)
            label += " (glTF camera " + quoted(camera.name) + ")";
        return label;
    }
    if (!camera.name.empty()) return "camera " + quoted(camera.name);
    // Appended, not "camera #" + to_string(): GCC 12 warns falsely (-Wrestrict) about that form.
    if (camera.index >= 0) return std::string("camera #").append(std::to_string(camera.index));
    return "camera (no name)";
}

std::string cameraListEntry(const Camera& camera) {
    std::string entry = std::string("#").append(std::to_string(camera.index));
    if (!camera.node_name.empty()) entry += " node " + quoted(camera.node_name);
    if (!camera.name.empty())
        entry += std::string(camera.node_name.empty() ? "" : ",") + " glTF camera " + quoted(camera.name);
    if (camera.node_name.empty() && camera.name.empty()) entry += " (no names)";
    return entry;
}

std::string materialLabel(const Scene& scene, uint32_t material) {
    const std::string& name = scene.materials[material].name;
    if (!name.empty()) return "material " + quoted(name);
    return std::string("material #").append(std::to_string(material));
}

std::string lightLabel(const Scene& scene, size_t light) {
    const PunctualLight& l = scene.lights[light];
    const std::string kind = l.type == LightType::Directional ? "directional light "
                             : l.type == LightType::Spot      ? "spot light "
                                                              : "point light ";
    if (!l.node_name.empty()) {
        std::string label = kind + quoted(l.node_name);
        if (!l.name.empty() && l.name != l.node_name) label += " (glTF light " + quoted(l.name) + ")";
        return label;
    }
    if (!l.name.empty()) return kind + quoted(l.name);
    return kind + std::string("#").append(std::to_string(light));
}

}  // namespace sharcbake
