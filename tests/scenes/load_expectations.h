// SPDX-License-Identifier: Apache-2.0
/// @file load_expectations.h
/// @brief Expectations on loadGltf's refusals shared by the loader's tests.
#pragma once

#include "sharcbake/scene_loader.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace sharcbake::test {

/// loadGltf(`path`) refuses the scene as a missing file (kMissingFile: the command exits 2, not 3)
/// naming buffer `uri` and the scene's folder, in the words a missing image's warning uses.
inline void expectMissingBuffer(const std::string& path, const std::string& uri) {
    const std::string folder = std::filesystem::canonical(std::filesystem::path(path).parent_path()).string();
    try {
        loadGltf(path);
        ADD_FAILURE() << "expected SceneLoadError";
    } catch (const SceneLoadError& e) {
        EXPECT_EQ(e.kind(), SceneLoadError::Kind::kMissingFile);
        EXPECT_EQ(std::string(e.what()),
                  path + ": buffer '" + uri + "' not found beside the scene (looked in " + folder + ")");
    }
}

}  // namespace sharcbake::test
