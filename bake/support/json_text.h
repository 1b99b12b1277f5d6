// SPDX-License-Identifier: Apache-2.0
/// @file json_text.h
/// @brief Text for the JSON the tools write (--stats-json, info --json, reports): one string escaper.
#pragma once

#include <cstdio>
#include <string>
#include <string_view>

namespace sharcbake {

/// `text` as a JSON string literal: quotes and backslashes escaped, \n \r \t by name, other control
/// characters as \uXXXX; UTF-8 passes through (the readers validate it).
inline std::string jsonString(std::string_view text) {
    std::string out = "\"";
    for (const char ch : text) {
        const unsigned char c = static_cast<unsigned char>(ch);
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (c < 0x20) {
                    char escaped[8];
                    std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
                    out += escaped;
                } else {
                    out += ch;
                }
        }
    }
    return out + "\"";
}

}  // namespace sharcbake
