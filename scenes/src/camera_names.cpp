// SPDX-License-Identifier: Apache-2.0
/// @file camera_names.cpp
/// @brief How messages name a camera: by its node's name, its glTF camera's name or its index.
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

}  // namespace sharcbake
