// SPDX-License-Identifier: Apache-2.0
/// @file capacity.h
/// @brief `--capacity auto`: a hash table sized from the scene and the camera path instead of
/// the SDK's fixed 2^22 slots.
#pragma once

#include "sharc/baker.h"

#include <cstdint>
#include <string>

namespace sharcbake {

struct CapacityChoice {
    uint32_t capacity = 0;            ///< slots: a power of two >= 2^12
    uint32_t sampled_iterations = 0;  ///< iterations the pre-pass traced
    uint64_t sampled_voxels = 0;      ///< distinct keys their paths reached
    double seconds = 0.0;             ///< pre-pass time
    std::string describe() const;     ///< the value and why, for the summary and the metadata
};

/// The table's starting size for --capacity auto. Traces the update paths of
/// kCapacitySampleIterations iterations spread over one loop of the camera path (its period, at
/// least kCapacitySampleIterations iterations; a golden-ratio sequence, so the samples visit
/// every part of it) against an empty cache, counts the distinct voxel keys they deposit into,
/// and takes kCapacityHeadroom times that, rounded up to a power of two: a load of at most 25%
/// if the bake reaches no more voxels than the sample. The choice does not depend on the bake's
/// --iterations, so a bake split by --checkpoint and --resume (32 iterations, then 64) starts
/// from the table, and records the choice, of the bake run in one go; a bake shorter than a
/// loop gets a table for the whole loop, whose untouched pages cost no memory. (Measured: 16-slot buckets start failing inserts near 40% load: 0.03% of
/// inserts on the outdoor scene at 41%, 0.7% on the furnace at 51%; none at 25%.) A closed
/// room is reached almost whole by the sample; an open scene keeps revealing voxels, and the
/// bake doubles its table when needed (SharcSettings::grow_when_loaded), so the estimate only
/// has to avoid needless growth. Deterministic: same scene, settings and seed, same capacity.
CapacityChoice chooseCapacity(const Tracer& tracer, const LightSampler& lights, const CameraPath& camera_path,
                              BakeSettings settings);

inline constexpr uint32_t kCapacitySampleIterations = 16;
inline constexpr uint32_t kCapacityHeadroom = 4;
inline constexpr uint32_t kCapacityMinimum = 1u << 12;

}  // namespace sharcbake
