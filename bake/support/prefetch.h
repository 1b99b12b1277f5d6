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

/// Both ends of an object: table entries of 40 or 48 bytes straddle two cache lines at half or
/// more of their slots, and a hint for the first line alone leaves the second to miss.
template <typename T>
void prefetchObjectForRead(const T* object) {
    prefetchForRead(object);
    prefetchForRead(reinterpret_cast<const char*>(object) + sizeof(T) - 1);
}

template <typename T>
void prefetchObjectForWrite(const T* object) {
    prefetchForWrite(object);
    prefetchForWrite(reinterpret_cast<const char*>(object) + sizeof(T) - 1);
}

}  // namespace sharcbake
