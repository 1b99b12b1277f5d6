// SPDX-License-Identifier: Apache-2.0
// Crash-safe file writing shared by the EXR and PNG writers: the one atomic write of cache_format.
#include "image_internal.h"

#include "sharcbake/cache_file.h"

#include <string>

namespace sharcbake::detail {

std::string printable(const std::string& text) {
    std::string out = text;
    for (char& c : out) {
        if (c < 0x20 || c > 0x7e) c = '?';
    }
    return out;
}

void checkImageShape(const std::string& path, const Image& image, const char* what) {
    if (image.width <= 0 || image.height <= 0) {
        throw ImageError("cannot write " + std::string(what) + " '" + path + "': image is empty (" +
                         std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    }
    if (image.pixels.size() != size_t(image.width) * size_t(image.height)) {
        throw ImageError("cannot write " + std::string(what) + " '" + path + "': image has " +
                         std::to_string(image.pixels.size()) + " pixels, expected " +
                         std::to_string(size_t(image.width) * size_t(image.height)));
    }
}

void writeFileAtomically(const std::string& path, const void* data, size_t size) {
    std::string message;
    if (sharcbake::writeFileAtomically(path, data, size, &message) != CacheFileStatus::kOk) {
        throw ImageError("cannot write '" + path + "': " + message);
    }
}

}  // namespace sharcbake::detail
