// SPDX-License-Identifier: Apache-2.0
#include "support/worker_threads.h"

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#define SHARCBAKE_HAS_MXCSR 1
#endif

namespace sharcbake {
namespace {

#if defined(SHARCBAKE_HAS_MXCSR)
constexpr unsigned kFlushToZero = 0x8000;       // MXCSR FTZ: results below the normal range become 0
constexpr unsigned kDenormalsAreZero = 0x0040;  // MXCSR DAZ: subnormal operands are read as 0
#endif

/// Clears flush-to-zero and denormals-are-zero on the calling thread for its lifetime, then puts
/// back what was there.
class GradualUnderflow {
public:
#if defined(SHARCBAKE_HAS_MXCSR)
    GradualUnderflow() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ & ~(kFlushToZero | kDenormalsAreZero)); }
    ~GradualUnderflow() { _mm_setcsr(saved_); }

private:
    unsigned saved_;
#endif
};

}  // namespace

bool flushesSubnormals() {
#if defined(SHARCBAKE_HAS_MXCSR)
    return (_mm_getcsr() & (kFlushToZero | kDenormalsAreZero)) != 0;
#else
    return false;
#endif
}

void runOnWorkerThreads(int threads, const std::function<void()>& work) {
    tbb::global_control thread_limit(tbb::global_control::max_allowed_parallelism, size_t(threads));
    const GradualUnderflow settings;  // what the arena's workers take
    tbb::task_arena arena(threads);
    arena.initialize();
    arena.execute(work);
}

}  // namespace sharcbake
