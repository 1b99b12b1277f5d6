// SPDX-License-Identifier: Apache-2.0
/// @file message_text.h
/// @brief Text from a scene file, made safe to print in a message (the loader's helpers).
#pragma once

#include <cstdio>
#include <string>

namespace sharcbake {

/// Text from the scene file for a message: control characters and bytes >= 0x7F are shown as
/// \xNN, so a crafted name cannot drive the terminal.
inline std::string printable(const std::string& s) {
    std::string out;
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (c < 0x20 || c >= 0x7F) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02X", c);
            out += buf;
        } else {
            out += ch;
        }
    }
    return out;
}

/// printable(s) in single quotes.
inline std::string quoted(const std::string& s) {
    std::string out(1, '\'');
    out += printable(s);
    out += '\'';
    return out;
}

}  // namespace sharcbake
