// SPDX-License-Identifier: Apache-2.0
/// @file image_internal.h
/// @brief Helpers shared by the image readers and writers (not part of the public interface).
#pragma once

#include "sharcbake/image.h"

#include <cstddef>
#include <cstdint>
#include <string>

namespace sharcbake::detail {

/// Larger images are refused before their pixels are allocated: a damaged header must not ask
/// for gigabytes (a few bytes of run-length HDR, or of EXR, can claim any size). 2^27 pixels is
/// 16384 x 8192, the largest environment maps commonly shared: 1.5 GiB as float RGB.
constexpr uint64_t kMaxImagePixels = uint64_t(1) << 27;
/// What a refusal for kMaxImagePixels says after the image's size.
constexpr const char* kTooManyPixels = "more pixels than sharcbake reads (134,217,728, e.g. 16384x8192)";

/// Writes @p size bytes to @p path with sharcbake::writeFileAtomically (cache_file.h): never a
/// torn file, a symlink stays a link, a device or FIFO is refused. Throws ImageError naming
/// @p path and the reason.
void writeFileAtomically(const std::string& path, const void* data, size_t size);

/// Text from a file as it may be printed in a message: control and non-ASCII bytes (a zero byte
/// would end what() early) as '?'.
std::string printable(const std::string& text);

/// Throws ImageError (naming @p path) unless @p image has positive dimensions and exactly
/// width * height pixels.
void checkImageShape(const std::string& path, const Image& image, const char* what);

}  // namespace sharcbake::detail
