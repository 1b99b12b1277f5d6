// SPDX-License-Identifier: Apache-2.0
#include "sharc_cache.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace sharcbake {

double HistorySchedule::historyFactor(uint32_t frames) const {
    if (frames <= 1) return 0.0;  // no history yet
    switch (kind) {
        case Kind::Average:
            return 1.0;
        case Kind::Window: {
            // The SDK caps the frame counter at A, so once F passes A every new iteration
            // scales the history by A / (A + 1): an exponential window of about A iterations.
            const double a = std::max(1.0, double(value));
            return double(frames) > a ? a / (a + 1.0) : 1.0;
        }
        case Kind::Ramp:
            return std::pow(double(frames - 1) / double(frames), double(value));
    }
    return 1.0;
}

std::string HistorySchedule::describe() const {
    char text[64];
    switch (kind) {
        case Kind::Average: return "average";
        case Kind::Window: std::snprintf(text, sizeof text, "window:%g", double(value)); return text;
        case Kind::Ramp: std::snprintf(text, sizeof text, "ramp:%g", double(value)); return text;
    }
    return "?";
}

bool HistorySchedule::parse(const std::string& text, HistorySchedule& out) {
    if (text == "average") {
        out = {Kind::Average, 0.0f};
        return true;
    }
    const size_t colon = text.find(':');
    if (colon == std::string::npos) return false;
    const std::string name = text.substr(0, colon);
    char* end = nullptr;
    const std::string number = text.substr(colon + 1);
    const float value = std::strtof(number.c_str(), &end);
    if (number.empty() || *end != '\0' || !std::isfinite(value)) return false;
    if (name == "window" && value >= 1.0f) {
        out = {Kind::Window, value};
        return true;
    }
    if (name == "ramp" && value >= 0.0f && value <= 8.0f) {
        out = {Kind::Ramp, value};
        return true;
    }
    return false;
}

double SharcCache::chooseRadianceScale(double max_radiance) {
    // The brightest radiance maps to 2^30: 30 bits of precision below it, 2^26 times above it
    // for one deposit (multi-bounce radiance exceeds emission: L = Le/(1-rho) in a furnace) and
    // 2^33 times for a voxel's sum in one iteration before the 63-bit ceiling.
    const double magnitude = (std::isfinite(max_radiance) && max_radiance > 0.0) ? max_radiance : 1.0;
    const int exponent = std::clamp(30 - int(std::ceil(std::log2(magnitude))), -60, 90);
    return std::ldexp(1.0, exponent);
}

SharcCache::SharcCache(const SharcSettings& settings, double radiance_scale)
    : settings_(settings),
      radiance_scale_(radiance_scale),
      // One deposit may use at most 1/128 of a sum's range (see chooseRadianceScale).
      max_fixed_deposit_(uint64_t(1) << 56),
      accumulation_(settings.capacity),
      resolved_(settings.capacity),
      touched_flags_(settings.capacity, 0) {
    const HashGridStatus status = HashGridTable::create(settings.capacity, &table_);
    if (status != HashGridStatus::kOk) {
        throw std::invalid_argument(std::string("hash grid: ") + toString(status));
    }
}

const ResolvedEntry* SharcCache::findResolved(uint64_t key) const {
    const std::optional<uint32_t> slot = table_.find(key);
    return slot ? &resolved_[*slot] : nullptr;
}

void SharcCache::commit(const std::vector<Deposit>& deposits) {
    for (const Deposit& d : deposits) {
        ++numerics_.deposits;
        if (!std::isfinite(d.radiance.x) || !std::isfinite(d.radiance.y) || !std::isfinite(d.radiance.z)) {
            ++numerics_.non_finite_deposits;
            continue;
        }
        const std::optional<uint32_t> inserted = table_.insert(d.key);
        if (!inserted) {
            ++numerics_.failed_inserts;
            numerics_.failed_insert_energy += glm::dvec3(glm::max(d.radiance, glm::vec3(0.0f)));
            continue;
        }
        const uint32_t slot = *inserted;
        AccumulationEntry& entry = accumulation_[slot];
        if (!touched_flags_[slot]) {
            touched_flags_[slot] = 1;
            touched_.push_back(slot);
        }
        bool negative = false, clamped = false;
        for (int c = 0; c < 3; ++c) {
            double value = double(d.radiance[c]);
            if (value < 0.0) {
                negative = true;
                value = 0.0;
            }
            // Round to nearest: truncation would bias dim light low (sharc_algorithm.md 10.2).
            double fixed = std::nearbyint(value * radiance_scale_);
            if (fixed > double(max_fixed_deposit_)) {
                clamped = true;
                numerics_.clamped_energy[c] += (fixed - double(max_fixed_deposit_)) / radiance_scale_;
                fixed = double(max_fixed_deposit_);
            }
            const uint64_t add = uint64_t(fixed);
            if (entry.sums[c] > std::numeric_limits<uint64_t>::max() / 2 - add) {
                ++numerics_.saturated_sums;  // 2^63 ceiling: keep the sum, drop the excess
                continue;
            }
            entry.sums[c] += add;
        }
        numerics_.negative_deposits += negative;
        numerics_.clamped_deposits += clamped;
        entry.samples += d.samples;
    }
}

void SharcCache::resolve(uint32_t iteration) {
    const double inverse_scale = 1.0 / radiance_scale_;
    std::vector<uint8_t> orphan(touched_.size(), 0);
    tbb::parallel_for(size_t(0), touched_.size(), [&](size_t i) {
        const uint32_t slot = touched_[i];
        AccumulationEntry& acc = accumulation_[slot];
        ResolvedEntry& r = resolved_[slot];
        if (acc.samples == 0) {
            // Radiance arrived without a sample of its own (cannot happen with the update pass
            // as written; counted so a regression shows up in the stats).
            orphan[i] = 1;
        } else {
            const double n = double(acc.samples);
            const glm::dvec3 mean_new = glm::dvec3(double(acc.sums[0]), double(acc.sums[1]), double(acc.sums[2])) *
                                        (inverse_scale / n);
            r.frames += 1;
            const double history = r.weight * settings_.history.historyFactor(r.frames);
            const double total = history + n;
            const glm::dvec3 mean = (glm::dvec3(r.mean) * history + mean_new * n) / total;
            r.mean = glm::vec3(mean);
            r.weight = total;
            r.last_iteration = iteration;
            r.total_samples = acc.samples > ~r.total_samples ? ~0u : r.total_samples + acc.samples;
        }
        acc = AccumulationEntry{};
        touched_flags_[slot] = 0;
    });
    for (uint8_t o : orphan) numerics_.orphan_sums += o;
    touched_.clear();
}

}  // namespace sharcbake
