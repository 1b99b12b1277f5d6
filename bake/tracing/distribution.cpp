// SPDX-License-Identifier: Apache-2.0
#include "tracing/distribution.h"

#include <algorithm>
#include <cmath>

namespace sharcbake {

Distribution1D::Distribution1D(const std::vector<float>& weights) {
    const size_t n = weights.size();
    pmf_.resize(n);
    cdf_.resize(n + 1, 0.0);
    for (size_t i = 0; i < n; ++i) {
        const float w = weights[i];
        const double clamped = (std::isfinite(w) && w > 0.0f) ? double(w) : 0.0;
        cdf_[i + 1] = cdf_[i] + clamped;
    }
    total_ = cdf_[n];
    for (size_t i = 0; i <= n; ++i) {
        cdf_[i] = total_ > 0.0 ? cdf_[i] / total_ : double(i) / double(n);
    }
    for (size_t i = 0; i < n; ++i) pmf_[i] = float(cdf_[i + 1] - cdf_[i]);
}

size_t Distribution1D::sampleDiscrete(float u, float* remapped) const {
    // First bin whose upper cdf exceeds u; bins of zero probability are never chosen.
    const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), double(u));
    size_t i = size_t(std::distance(cdf_.begin() + 1, it));
    i = std::min(i, pmf_.size() - 1);
    while (pmf_[i] <= 0.0f && i > 0) --i;  // u landed exactly on a boundary before empty bins
    if (remapped) {
        const double width = cdf_[i + 1] - cdf_[i];
        const double r = width > 0.0 ? (double(u) - cdf_[i]) / width : 0.0;
        *remapped = float(std::clamp(r, 0.0, double(0x1.fffffep-1f)));
    }
    return i;
}

float Distribution1D::sampleContinuous(float u, float* pdf, size_t* bin) const {
    float within = 0.0f;
    const size_t i = sampleDiscrete(u, &within);
    if (pdf) *pdf = pmf_[i] * float(pmf_.size());
    if (bin) *bin = i;
    return (float(i) + within) / float(pmf_.size());
}

Distribution2D::Distribution2D(const std::vector<float>& weights, int width, int height)
    : width_(width), height_(height) {
    std::vector<float> row_totals(size_t(height), 0.0f);
    rows_.reserve(size_t(height));
    for (int y = 0; y < height; ++y) {
        std::vector<float> row(weights.begin() + ptrdiff_t(y) * width,
                               weights.begin() + ptrdiff_t(y + 1) * width);
        rows_.emplace_back(row);
        row_totals[size_t(y)] = float(rows_.back().total());
    }
    marginal_ = Distribution1D(row_totals);
}

glm::vec2 Distribution2D::sample(glm::vec2 u, float* pdf) const {
    float pdf_v = 0.0f, pdf_u = 0.0f;
    size_t row = 0;
    const float v = marginal_.sampleContinuous(u.y, &pdf_v, &row);
    const float uu = rows_[row].sampleContinuous(u.x, &pdf_u);
    if (pdf) *pdf = pdf_v * pdf_u;
    return {uu, v};
}

float Distribution2D::pdf(glm::vec2 uv) const {
    const int x = std::clamp(int(uv.x * float(width_)), 0, width_ - 1);
    const int y = std::clamp(int(uv.y * float(height_)), 0, height_ - 1);
    return marginal_.pmf(size_t(y)) * float(height_) * rows_[size_t(y)].pmf(size_t(x)) * float(width_);
}

}  // namespace sharcbake
