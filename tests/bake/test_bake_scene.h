// SPDX-License-Identifier: Apache-2.0
/// @file test_bake_scene.h
/// @brief What the bake tests set up: a shipped scene by name, and a scene with its tracer,
/// lights and exploring camera path (as `sharcbake bake` sets them up) that makes bakers.
#pragma once

#include "sharc/baker.h"
#include "sharc/camera_path.h"
#include "sharcbake/scene_loader.h"
#include "tracing/lights.h"
#include "tracing/tracer.h"

#include <memory>
#include <string>
#include <utility>

namespace sharcbake {

/// The glTF file of the shipped scene `name` (scenes/NAME/NAME.gltf).
inline std::string scenePath(const std::string& name) {
    return std::string(SHARCBAKE_SCENES_DIR) + "/" + name + "/" + name + ".gltf";
}

/// A loaded scene and what a bake traces it with. Neither copied nor moved: the tracer and the
/// lights refer to the scene.
struct TestBakeScene {
    Scene scene;
    std::unique_ptr<Tracer> tracer;
    std::unique_ptr<LightSampler> lights;
    std::unique_ptr<CameraPath> path;

    explicit TestBakeScene(const std::string& name) : TestBakeScene(loadGltf(scenePath(name))) {}
    explicit TestBakeScene(Scene loaded) : scene(std::move(loaded)) {
        tracer = std::make_unique<Tracer>(scene);
        lights = std::make_unique<LightSampler>(*tracer);
        path = std::make_unique<CameraPath>(exploringCameraPath(*tracer, scene, 16, 3).value());
    }
    TestBakeScene(const TestBakeScene&) = delete;
    TestBakeScene& operator=(const TestBakeScene&) = delete;

    /// A fresh bake of this scene, with the fixed-point scale `sharcbake bake` would choose.
    std::unique_ptr<Baker> makeBaker(const BakeSettings& settings) const {
        return std::make_unique<Baker>(*tracer, *lights, *path, settings,
                                       SharcCache::chooseRadianceScale(estimateMaxRadiance(*tracer)));
    }
};

}  // namespace sharcbake
