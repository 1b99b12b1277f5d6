// SPDX-License-Identifier: Apache-2.0
/// @file distribution.h
/// @brief Piecewise-constant 1D and 2D distributions for importance sampling (lights by power,
/// environment maps by luminance).
#pragma once

#include <glm/glm.hpp>

#include <cstdint>
#include <vector>

namespace sharcbake {

/// A discrete / piecewise-constant distribution over n bins of [0,1).
class Distribution1D {
public:
    Distribution1D() = default;
    /// Negative and non-finite weights count as 0. If all weights are 0 the distribution is
    /// uniform, so sampling never fails on a valid index.
    explicit Distribution1D(const std::vector<float>& weights);

    size_t size() const { return pmf_.size(); }
    bool empty() const { return pmf_.empty(); }
    /// Probability of bin i.
    float pmf(size_t i) const { return pmf_[i]; }
    /// Total weight (sum of the clamped weights).
    double total() const { return total_; }

    /// Picks a bin with probability pmf; `remapped` receives u rescaled to [0,1) within the bin,
    /// so one random number can be reused.
    size_t sampleDiscrete(float u, float* remapped = nullptr) const;
    /// Samples the continuous piecewise-constant density on [0,1); pdf is the density there.
    float sampleContinuous(float u, float* pdf, size_t* bin = nullptr) const;

private:
    std::vector<float> pmf_;
    std::vector<double> cdf_;  ///< size n + 1, cdf_[0] = 0, cdf_[n] = 1
    double total_ = 0.0;
};

/// Piecewise-constant density over [0,1)^2 (rows = v, columns = u): marginal over rows,
/// conditional per row.
class Distribution2D {
public:
    Distribution2D() = default;
    Distribution2D(const std::vector<float>& weights, int width, int height);
    /// Returns (u, v) and the density with respect to area in [0,1)^2.
    glm::vec2 sample(glm::vec2 u, float* pdf) const;
    float pdf(glm::vec2 uv) const;

private:
    int width_ = 0, height_ = 0;
    std::vector<Distribution1D> rows_;
    Distribution1D marginal_;
};

}  // namespace sharcbake
