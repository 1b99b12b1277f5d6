// SPDX-License-Identifier: Apache-2.0
/// @file light_grid.h
/// @brief A coarse grid over the scene whose cells each say which groups of lights reach the
/// surfaces inside them, and in what shares: the spatial half of light selection (lights.h).
///
/// Selection by power alone spends most shadow rays on lights a point cannot see: in a flat of
/// several rooms each lamp lights its own room, and a sun outside takes nearly every sample of
/// the rooms it never reaches. The grid holds, per slot (a cell and one of six directions the
/// surface faces: a floor and the ceiling above it see different lights, and the underside of
/// the ground none of the sun), a sparse distribution over light groups measured by shadow rays
/// before any path is traced; slots where nothing was measured hold none.
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace sharcbake {

class LightSelectionGrid {
public:
    struct Share {
        uint32_t group = 0;
        float probability = 0.0f;
        float cumulative = 0.0f;  ///< the slot's probabilities up to and including this share
    };

    LightSelectionGrid() = default;
    /// Cubic cells over the bounds, `cells_along_longest` along the longest axis (at least one
    /// along each axis), none holding shares yet.
    LightSelectionGrid(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest);
    /// The same, and a finer grid over the box [detail_min, detail_max] (within the bounds), whose
    /// cells, numbered after the coarse ones, take every point inside it: a house's rooms on a
    /// ground a kilometre wide get cells of their own size, not one cell for the whole house.
    LightSelectionGrid(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest, glm::vec3 detail_min,
                       glm::vec3 detail_max, uint32_t detail_cells_along_longest);

    /// Slots per cell: +X, -X, +Y, -Y, +Z, -Z, by a normal's largest component.
    static constexpr uint32_t kDirections = 6;
    /// A slot keeps its largest shares, this many at most: picking among a few hundred lamps that
    /// all reach a hall costs more than it gains over power.
    static constexpr size_t kMostShares = 64;

    /// The coarse grid's cells along each axis and their width.
    glm::uvec3 dimensions() const { return coarse_.dimensions; }
    float cellSize() const { return coarse_.cell_size; }
    /// The detail grid's (0 cells where there is none), and its box.
    glm::uvec3 detailDimensions() const { return detail_.dimensions; }
    float detailCellSize() const { return detail_.cell_size; }
    glm::vec3 detailMin() const { return detail_.origin; }
    glm::vec3 detailMax() const { return detail_max_; }
    uint32_t cellCount() const { return coarse_.cellCount() + detail_.cellCount(); }
    uint32_t slotCount() const { return cellCount() * kDirections; }
    /// The cell holding `p`: the detail grid's inside its box, else the coarse grid's, where
    /// points outside the bounds take the nearest cell.
    uint32_t cellOf(glm::vec3 p) const;
    /// The slot of a surface at `p` facing `normal` (any length; not finite counts as +X).
    uint32_t slotOf(glm::vec3 p, glm::vec3 normal) const { return cellOf(p) * kDirections + directionOf(normal); }
    static uint32_t directionOf(glm::vec3 normal);

    /// Sets every slot's shares from its weights per group ((group, weight) in any order, a group
    /// at most once), the kMostShares largest. A slot whose weights are all 0 (or not finite)
    /// holds no shares.
    void setWeights(const std::vector<std::vector<std::pair<uint32_t, double>>>& weights_per_slot);

    bool hasShares(uint32_t slot) const { return first_[slot] != first_[slot + 1]; }
    uint32_t slotsWithShares() const { return slots_with_shares_; }
    /// The share `u` in [0, 1) falls in (the slot must have shares); `remapped` gets u rescaled
    /// to [0, 1) within it, so one random number can be reused.
    const Share& pick(uint32_t slot, float u, float& remapped) const;
    /// The probability the slot gives `group`: 0 where it lists none.
    float probability(uint32_t slot, uint32_t group) const;

private:
    /// Cubic cells from `origin`, `dimensions` of them along each axis (0 for no grid).
    struct Lattice {
        glm::vec3 origin{0.0f};
        float cell_size = 0.0f;
        float inverse_cell_size = 0.0f;
        glm::uvec3 dimensions{0u};

        Lattice() = default;
        Lattice(glm::vec3 bounds_min, glm::vec3 bounds_max, uint32_t cells_along_longest);
        uint32_t cellCount() const { return dimensions.x * dimensions.y * dimensions.z; }
        /// The nearest cell to `p` (NaN counts as the first along its axis).
        uint32_t cellOf(glm::vec3 p) const;
    };

    Lattice coarse_{glm::vec3(0.0f), glm::vec3(0.0f), 1u};
    Lattice detail_;
    glm::vec3 detail_max_{0.0f};
    std::vector<uint32_t> first_ =
        std::vector<uint32_t>(kDirections + 1, 0u);  ///< slot s's shares are shares_[first_[s], first_[s + 1])
    std::vector<Share> shares_;                      ///< sorted by group within each slot
    uint32_t slots_with_shares_ = 0;
};

}  // namespace sharcbake
