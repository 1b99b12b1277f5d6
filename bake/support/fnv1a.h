// SPDX-License-Identifier: Apache-2.0
/// @file fnv1a.h
/// @brief FNV-1a (64-bit): the digest of bytes that must come out the same on every run.
#pragma once

#include <cstddef>
#include <cstdint>

namespace sharcbake {

inline constexpr uint64_t kFnv1a64Basis = 0xcbf29ce484222325ull;

/// FNV-1a (64-bit) of `size` bytes, continuing from `hash` (kFnv1a64Basis to start), so bytes
/// read in pieces hash as if read at once: a scene's files, a cache file, an image.
inline uint64_t fnv1a64(const void* data, size_t size, uint64_t hash = kFnv1a64Basis) {
    const auto* bytes = static_cast<const uint8_t*>(data);
    for (size_t i = 0; i < size; ++i) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    return hash;
}

}  // namespace sharcbake
