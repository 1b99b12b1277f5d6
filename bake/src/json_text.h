// SPDX-License-Identifier: Apache-2.0
/// @file json_text.h
/// @brief Text for the JSON the tools write (--stats-json, reports): strings quoted and escaped.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace sharcbake {

/// `text` as a JSON string literal: quotes and backslashes escaped, control characters as \uXXXX.
inline std::string jsonString(const std::string& text) {
    std::string out = "\"";
    for (char c : text) {
        if (c == '"' || c == '\\') out += '\\';
        if (uint8_t(c) < 0x20) {
            char escaped[8];
            std::snprintf(escaped, sizeof escaped, "\\u%04x", unsigned(uint8_t(c)));
            out += escaped;
            continue;
        }
        out += c;
    }
    return out + "\"";
}

}  // namespace sharcbake
