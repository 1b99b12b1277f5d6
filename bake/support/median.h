// SPDX-License-Identifier: Apache-2.0
/// @file median.h
/// @brief The median of a set of values, for the checks that report a typical distance or size.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace sharcbake {

/// The upper median of `values` (the middle one of an odd count, the higher of the two middle
/// ones of an even count); 0 for none.
inline float median(std::vector<float> values) {
    if (values.empty()) return 0.0f;
    const size_t middle = values.size() / 2;
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(middle), values.end());
    return values[middle];
}

}  // namespace sharcbake
