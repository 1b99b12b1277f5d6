// SPDX-License-Identifier: Apache-2.0
/// @file worker_threads.h
/// @brief The TBB workers a command traces on: how many, and how they round floats.
#pragma once

#include <functional>

namespace sharcbake {

/// Runs `work` on the calling thread in a TBB arena of exactly `threads` workers, more than the
/// machine has cores if asked (results do not depend on the count; tests check that with more
/// threads than the test machine has cores). Every worker computes with IEEE 754 gradual
/// underflow: values below float32's smallest normal (1.2e-38) are kept, not flushed to zero.
///
/// Why here: TBB gives its workers the floating-point settings of the thread that starts their
/// arena, and left to itself starts its first arena inside Embree's scene commit, which runs with
/// flush-to-zero and denormals-are-zero on. Every later parallel loop inherited them: a render of
/// a furnace emitting 1e-38 came out black and one emitting 1e-37 10% dark, while the bake, in an
/// arena of its own, was exact.
void runOnWorkerThreads(int threads, const std::function<void()>& work);

/// Whether the calling thread flushes subnormal floats to zero (or reads them as zero).
bool flushesSubnormals();

}  // namespace sharcbake
