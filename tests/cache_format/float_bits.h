// SPDX-License-Identifier: Apache-2.0
// binary32 values <-> their bit patterns, for test vectors that must be exact.
#pragma once

#include <cstdint>
#include <cstring>

inline float fromBits(uint32_t u) {
    float f;
    std::memcpy(&f, &u, sizeof f);
    return f;
}

inline uint32_t toBits(float f) {
    uint32_t u;
    std::memcpy(&u, &f, sizeof u);
    return u;
}
