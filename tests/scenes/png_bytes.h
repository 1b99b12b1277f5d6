// SPDX-License-Identifier: Apache-2.0
/// @file png_bytes.h
/// @brief Test helper: encodes RGBA pixels as PNG bytes in memory (Debian's libstb; link stb).
#pragma once

#include <stb_image_write.h>

#include <cstdint>
#include <vector>

namespace sharcbake::test {

/// An 8-bit PNG of `width` x `height` RGBA pixels.
inline std::vector<uint8_t> png(int width, int height, const std::vector<uint8_t>& rgba) {
    std::vector<uint8_t> bytes;
    stbi_write_png_to_func(
        [](void* context, void* data, int size) {
            auto* out = static_cast<std::vector<uint8_t>*>(context);
            out->insert(out->end(), static_cast<uint8_t*>(data), static_cast<uint8_t*>(data) + size);
        },
        &bytes, width, height, 4, rgba.data(), width * 4);
    return bytes;
}

}  // namespace sharcbake::test
