// SPDX-License-Identifier: Apache-2.0
#include "tracing/light_grid.h"
#include "support/box.h"

#include <algorithm>
#include <cmath>

namespace sharcbake {

LightSelectionGrid::Lattice::Lattice(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest)
    : origin(bounds_min) {
    const glm::vec3 extent = glm::max(bounds_max - bounds_min, glm::vec3(0.0f));
    const float longest = std::max({extent.x, extent.y, extent.z});
    cell_size = longest > 0.0f && std::isfinite(longest) ? longest / float(std::max(cells_along_longest, 1u)) : 1.0f;
    for (int axis = 0; axis < 3; ++axis) {
        const float cells = std::ceil(extent[axis] / cell_size);
        dimensions[axis] = uint32_t(std::clamp(cells, 1.0f, float(std::max(cells_along_longest, 1u))));
    }
    inverse_cell_size = 1.0f / cell_size;
}

uint32_t LightSelectionGrid::Lattice::cellOf(glm::vec3 p) const {
    glm::uvec3 cell;
    for (int axis = 0; axis < 3; ++axis) {
        const float at = std::floor((p[axis] - origin[axis]) * inverse_cell_size);
        // NaN and points outside take the nearest cell (the comparisons are false for NaN).
        cell[axis] = at >= float(dimensions[axis]) ? dimensions[axis] - 1 : at > 0.0f ? uint32_t(at) : 0u;
    }
    return (cell.z * dimensions.y + cell.y) * dimensions.x + cell.x;
}

LightSelectionGrid::LightSelectionGrid(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest)
    : coarse_(bounds_min, bounds_max, cells_along_longest) {
    first_.assign(size_t(slotCount()) + 1, 0u);
}

LightSelectionGrid::LightSelectionGrid(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest,
                                       glm::vec3 detail_min, glm::vec3 detail_max, uint32_t detail_cells_along_longest)
    : coarse_(bounds_min, bounds_max, cells_along_longest),
      detail_(detail_min, detail_max, detail_cells_along_longest),
      detail_max_(detail_max) {
    first_.assign(size_t(slotCount()) + 1, 0u);
}

uint32_t LightSelectionGrid::directionOf(glm::vec3 normal) {
    const glm::vec3 a = glm::abs(normal);
    int axis = 0;  // NaN compares false: +X
    if (a.y > a[axis]) axis = 1;
    if (a.z > a[axis]) axis = 2;
    return uint32_t(axis) * 2u + (normal[axis] < 0.0f ? 1u : 0u);
}

uint32_t LightSelectionGrid::cellOf(glm::vec3 p) const {
    const bool in_detail = detail_.cellCount() > 0 && insideBox(p, detail_.origin, detail_max_);
    return in_detail ? coarse_.cellCount() + detail_.cellOf(p) : coarse_.cellOf(p);
}

void LightSelectionGrid::setWeights(const std::vector<std::vector<std::pair<uint32_t, double>>>& weights_per_slot) {
    shares_.clear();
    slots_with_shares_ = 0;
    for (uint32_t slot = 0; slot < slotCount(); ++slot) {
        first_[slot] = uint32_t(shares_.size());
        if (slot >= weights_per_slot.size()) continue;
        std::vector<std::pair<uint32_t, double>> weights;
        double total = 0.0;
        for (const auto& [group, weight] : weights_per_slot[slot]) {
            if (!(weight > 0.0) || !std::isfinite(weight)) continue;
            weights.emplace_back(group, weight);
            total += weight;
        }
        if (!(total > 0.0) || !std::isfinite(total)) continue;
        if (weights.size() > kMostShares) {
            // The largest shares; the rest keep what the power share gives them.
            std::nth_element(weights.begin(), weights.begin() + kMostShares, weights.end(),
                             [](const auto& a, const auto& b) {
                                 return a.second != b.second ? a.second > b.second : a.first < b.first;
                             });
            weights.resize(kMostShares);
            total = 0.0;
            for (const auto& [group, weight] : weights) total += weight;
        }
        std::sort(weights.begin(), weights.end());
        double cumulative = 0.0;
        for (const auto& [group, weight] : weights) {
            cumulative += weight;
            shares_.push_back({group, float(weight / total), float(cumulative / total)});
        }
        shares_.back().cumulative = 1.0f;  // u < 1 always finds a share
        ++slots_with_shares_;
    }
    first_[slotCount()] = uint32_t(shares_.size());
}

const LightSelectionGrid::Share& LightSelectionGrid::pick(uint32_t slot, float u, float& remapped) const {
    // Branch-free binary searches: the share a uniform u lands in is unpredictable, and branchy
    // searches over a slot of a hundred groups took an eighth of a render's time.
    const Share* base = shares_.data() + first_[slot];
    for (size_t n = first_[slot + 1] - first_[slot]; n > 1;) {
        const size_t half = n / 2;
        base = base[half - 1].cumulative <= u ? base + half : base;
        n -= half;
    }
    const Share& chosen = *base;
    const float below = base == shares_.data() + first_[slot] ? 0.0f : (base - 1)->cumulative;
    remapped = chosen.probability > 0.0f ? std::clamp((u - below) / chosen.probability, 0.0f, 0x1.fffffep-1f) : 0.0f;
    return chosen;
}

float LightSelectionGrid::probability(uint32_t slot, uint32_t group) const {
    const Share* base = shares_.data() + first_[slot];
    size_t n = first_[slot + 1] - first_[slot];
    if (n == 0) return 0.0f;
    while (n > 1) {
        const size_t half = n / 2;
        base = base[half - 1].group < group ? base + half : base;
        n -= half;
    }
    return base->group == group ? base->probability : 0.0f;
}

}  // namespace sharcbake
