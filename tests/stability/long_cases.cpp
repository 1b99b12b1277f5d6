// SPDX-License-Identifier: Apache-2.0
// Stability cases too long for ctest (tens of seconds each in Release on 2 cores); run by hand:
//   build/bin/stability_long_cases
// Furnace rho = 0.999: L = 1000, about 3500 bounces to come within 3 %, all through cache feedback.
#include "stability_support.h"

#include <gtest/gtest.h>

namespace sharcbake::stability {
namespace {

TEST(StiffFurnaceLong, Rho0999ReachesLeOverOneMinusRhoThroughCacheFeedback) {
    const FurnaceConvergence run = bakeFurnaceToConvergence(0.999f, 0.03, 32768, 96, 256);
    RecordProperty("iterations_needed", int(run.iterations));
    EXPECT_TRUE(run.converged) << "mean " << run.measured << " after " << run.iterations << " iterations, expected "
                               << run.expected;
    EXPECT_TRUE(run.finite);
    EXPECT_EQ(run.report.clamped_deposits, 0u);
    EXPECT_EQ(run.report.saturated_sums, 0u);
    EXPECT_EQ(run.report.non_finite_dropped, 0u);
}

}  // namespace
}  // namespace sharcbake::stability
