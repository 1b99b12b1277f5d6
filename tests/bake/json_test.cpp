// SPDX-License-Identifier: Apache-2.0
// The tools' JSON output (support/json.h): numbers JSON can hold, floats in their shortest form,
// keys in the order written, and text that stays valid whatever bytes a path holds.
#include "support/json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace sharcbake {
namespace {

TEST(JsonOutput, NonFiniteAndMissingNumbersAreNull) {
    EXPECT_TRUE(jsonNumber(std::numeric_limits<double>::quiet_NaN()).is_null());
    EXPECT_TRUE(jsonNumber(std::numeric_limits<double>::infinity()).is_null());
    EXPECT_TRUE(jsonNumber(-std::numeric_limits<float>::infinity()).is_null());
    EXPECT_TRUE(jsonNumber(std::optional<double>()).is_null());
    EXPECT_EQ(jsonNumber(std::optional<double>(2.5)).get<double>(), 2.5);
    EXPECT_EQ(jsonText(jsonNumber(std::nan(""))), "null\n");
}

TEST(JsonOutput, FloatsPrintShortestAndReadBackExactly) {
    EXPECT_EQ(jsonNumber(0.1f).dump(), "0.1");
    EXPECT_EQ(jsonNumber(1e-7f).dump(), "1e-07");
    for (const float f : {0.1f, 1.0f / 3.0f, 3.4028235e38f, 1.17549435e-38f, 65504.0f, -7.25e-5f}) {
        EXPECT_EQ(float(Json::parse(jsonNumber(f).dump()).get<double>()), f) << f;
        EXPECT_LE(jsonNumber(f).dump().size(), 15u) << f;
    }
    // Doubles keep every digit they have.
    EXPECT_EQ(Json::parse(jsonNumber(0.1 + 0.2).dump()).get<double>(), 0.1 + 0.2);
}

TEST(JsonOutput, KeysKeepTheirOrderAndTextIsIndented) {
    const Json json = {{"zeta", 1}, {"alpha", {{"b", true}, {"a", nullptr}}}, {"list", {1, 2}}};
    EXPECT_EQ(jsonText(json),
              "{\n  \"zeta\": 1,\n  \"alpha\": {\n    \"b\": true,\n    \"a\": null\n  },\n"
              "  \"list\": [\n    1,\n    2\n  ]\n}\n");
}

TEST(JsonOutput, StringsAreEscapedAndInvalidUtf8IsReplaced) {
    const Json json = {{"path", std::string("a\"b\\c\n\x01 \xC3\xA9 \xFF")}};
    const std::string text = jsonText(json);
    EXPECT_NE(text.find(R"(a\"b\\c\n\u0001 é )"), std::string::npos) << text;
    EXPECT_NE(text.find("\xEF\xBF\xBD"), std::string::npos) << "0xFF becomes U+FFFD: " << text;
    EXPECT_TRUE(Json::accept(text)) << text;
}

TEST(JsonOutput, Vec3IsAnArrayWithNullsForNonFinite) {
    const Json v = jsonVec3(glm::vec3(1.5f, std::numeric_limits<float>::infinity(), 0.1f));
    EXPECT_EQ(v.dump(), "[1.5,null,0.1]");
}

}  // namespace
}  // namespace sharcbake
