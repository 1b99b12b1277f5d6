// SPDX-License-Identifier: Apache-2.0
/// @file sample_batch.h
/// @brief PixelSampler::sample2D for many samplers at once, with the same values bit for bit.
///
/// One draw is three Laine-Karras permutations and three hashes: chains of dependent 32-bit
/// multiplies, a sixth of an update path's work. Drawn for a whole batch of paths, eight lanes
/// at a time with AVX2 where the CPU has it (integer arithmetic, so every lane gives exactly the
/// scalar value), they cost a fraction of that. Without AVX2 the scalar draw runs in a loop.
#pragma once

#include "tracing/sampling.h"

#include <cstddef>
#include <cstdint>

namespace sharcbake {

/// out[i] = PixelSampler::sample2D(dimension) of the sampler whose pixelHash() is
/// pixel_hashes[i] and reversedSample() is reversed_samples[i], for i < count.
void sample2DMany(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count, uint32_t dimension,
                  glm::vec2* out);

namespace detail {
/// The two implementations sample2DMany chooses from, for the tests.
void sample2DManyScalar(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count,
                        uint32_t dimension, glm::vec2* out);
/// False (and nothing written) where the CPU or the compiler has no AVX2.
bool sample2DManyAvx2(const uint32_t* pixel_hashes, const uint32_t* reversed_samples, size_t count, uint32_t dimension,
                      glm::vec2* out);
}  // namespace detail

}  // namespace sharcbake
