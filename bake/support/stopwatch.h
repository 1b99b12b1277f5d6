// SPDX-License-Identifier: Apache-2.0
/// @file stopwatch.h
/// @brief Wall-clock seconds for the timings the commands report.
#pragma once

#include <chrono>

namespace sharcbake {

/// Seconds of steady (monotonic) clock since `start`.
inline double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace sharcbake
