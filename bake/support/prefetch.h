// SPDX-License-Identifier: Apache-2.0
/// @file prefetch.h
/// @brief Hints to start loading a cache line before it is needed. They change no result; code
/// that walks slots scattered over a table far larger than the caches asks a few entries ahead,
/// so that the misses overlap instead of following one another.
#pragma once

namespace sharcbake {

inline void prefetchForRead(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(address, 0);
#else
    (void)address;
#endif
}

inline void prefetchForWrite(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(address, 1);
#else
    (void)address;
#endif
}

}  // namespace sharcbake
