// SPDX-License-Identifier: Apache-2.0
/// @file json.h
/// @brief The one way the tools write JSON (--stats-json, info --json, compare --json, reports):
/// build a Json value, then print it with jsonText().
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include <glm/vec3.hpp>
#include <nlohmann/json.hpp>

namespace sharcbake {

/// A JSON value whose object keys keep the order they were added in, so outputs read in a fixed,
/// meaningful order (counts before rates, totals before parts).
using Json = nlohmann::ordered_json;

/// A number, or null when not finite: JSON has no NaN or infinity.
inline Json jsonNumber(double value) { return std::isfinite(value) ? Json(value) : Json(nullptr); }

/// A number, or null when missing or not finite.
inline Json jsonNumber(std::optional<double> value) { return value ? jsonNumber(*value) : Json(nullptr); }

/// A float as the shortest decimal that reads back as the same float (0.1f prints as 0.1, not
/// as the double 0.10000000149011612); null when not finite.
inline Json jsonNumber(float value) {
    if (!std::isfinite(value)) return nullptr;
    char text[32];
    for (int digits = 6; digits < 9; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, double(value));
        const double shortest = std::strtod(text, nullptr);
        if (float(shortest) == value) return shortest;
    }
    return double(value);
}

inline Json jsonVec3(const glm::vec3& v) { return Json::array({jsonNumber(v.x), jsonNumber(v.y), jsonNumber(v.z)}); }

/// The version of the JSON outputs' layouts, raised when a field changes meaning or goes away
/// (new fields keep it). Every output names its layout in a "schema" field; the JSON Schemas
/// that describe them are in docs/schemas/.
inline constexpr int kJsonOutputVersion = 1;

/// "sharcbake.<output>/<version>", e.g. "sharcbake.bake-stats/1".
inline std::string jsonSchemaId(const char* output) {
    return std::string("sharcbake.") + output + "/" + std::to_string(kJsonOutputVersion);
}

/// The text of `value`: two-space indentation and a final newline. Bytes that are not UTF-8
/// (a scene path on a Latin-1 file system) print as U+FFFD instead of failing the write.
inline std::string jsonText(const Json& value) {
    return value.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

}  // namespace sharcbake
