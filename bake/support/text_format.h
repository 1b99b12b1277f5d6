// SPDX-License-Identifier: Apache-2.0
/// @file text_format.h
/// @brief printf-style formatting into a std::string, for messages built from numbers.
#pragma once

#include <string>

namespace sharcbake {

/// `pattern` and its arguments as std::snprintf writes them, at any length.
std::string formatted(const char* pattern, ...) __attribute__((format(printf, 1, 2)));

}  // namespace sharcbake
