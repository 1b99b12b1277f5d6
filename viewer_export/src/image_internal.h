// SPDX-License-Identifier: Apache-2.0
/// @file image_internal.h
/// @brief Helpers shared by the EXR and PNG writers (not part of the public interface).
#pragma once

#include "sharcbake/image.h"

#include <cstddef>
#include <string>

namespace sharcbake::detail {

/// Writes @p size bytes to @p path with sharcbake::writeFileAtomically (cache_file.h): never a
/// torn file, a symlink stays a link, a device or FIFO is refused. Throws ImageError naming
/// @p path and the reason.
void writeFileAtomically(const std::string& path, const void* data, size_t size);

/// Throws ImageError (naming @p path) unless @p image has positive dimensions and exactly
/// width * height pixels.
void checkImageShape(const std::string& path, const Image& image, const char* what);

}  // namespace sharcbake::detail
