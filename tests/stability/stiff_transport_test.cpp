// SPDX-License-Identifier: Apache-2.0
// Stiff transport: light that needs hundreds to thousands of bounces (furnace rho = 0.99 and
// 0.999, L = Le / (1 - rho) = 100 and 1000) and a room lit only through a doorway. Cache
// feedback has to carry the bounces across iterations; each case reports the iterations it needed.
#include "stability_support.h"

#include <gtest/gtest.h>

namespace sharcbake::stability {
namespace {

/// rho = 0.99: about 350 bounces to come within 3 %, carried one feedback step per iteration.
/// rho = 0.999 needs ten times as many and runs in stability_long_cases (not in ctest).
TEST(StiffFurnace, Rho099ReachesLeOverOneMinusRhoThroughCacheFeedback) {
    const FurnaceConvergence run = bakeFurnaceToConvergence(0.99f, 0.03, 4096, 96);
    RecordProperty("iterations_needed", int(run.iterations));
    EXPECT_TRUE(run.converged) << "mean " << run.measured << " after " << run.iterations << " iterations, expected "
                               << run.expected;
    EXPECT_TRUE(run.finite);
    EXPECT_EQ(run.report.clamped_deposits, 0u);
    EXPECT_EQ(run.report.saturated_sums, 0u);
    EXPECT_EQ(run.report.non_finite_dropped, 0u);
    EXPECT_TRUE(run.report.warnings.empty()) << run.report.warnings.front();
}

/// Resampling only at the end of 16-vertex paths (bake --resampling end --propagation-depth 16
/// --max-bounces 17): every path carries up to 16 bounces of exact transport per iteration, so
/// the same furnace converges in a fraction of the iterations.
TEST(StiffFurnace, ResamplingAtTheEndOfLongPathsConvergesInFewIterations) {
    BakeConfig config;
    config.propagation_depth = 16;
    config.resample_at_end = true;
    config.max_bounces = 17;
    const FurnaceConvergence run = bakeFurnaceToConvergence(0.99f, 0.01, 512, 96, 32, config);
    RecordProperty("iterations_needed", int(run.iterations));
    EXPECT_TRUE(run.converged) << "mean " << run.measured << " after " << run.iterations << " iterations";
    EXPECT_LE(run.iterations, 128u);
    EXPECT_TRUE(run.finite);
    // rho = 0.999 (L = 1000): within 1% in at most 1024 iterations.
    const FurnaceConvergence stiffer = bakeFurnaceToConvergence(0.999f, 0.01, 1024, 96, 64, config);
    EXPECT_TRUE(stiffer.converged) << "mean " << stiffer.measured << " after " << stiffer.iterations << " iterations";
}

/// With the SDK's feedback (cache resampling reads the long history mean), ramp:8 remembers the
/// last ~F/9 of F iterations, so bounces accumulate only logarithmically with F: rho = 0.99 is
/// still 3/4 dark after 512 iterations, where the short feedback window is past half way.
TEST(StiffFurnace, ShortFeedbackWindowIsWhatMakesStiffTransportConverge) {
    auto meanAfter = [](uint32_t feedback_window) {
        Scene scene = loadGltf(scenePath("furnace_rho099"));
        makeFurnace(scene, 0.99f, 1.0f);
        BakeConfig config;
        config.feedback_window = feedback_window;
        SmallBake bake(std::move(scene), config);
        bake.run(512);
        return sampleWeightedMean(bake.cache());
    };
    const double sdk = meanAfter(0), fast = meanAfter(SharcSettings{}.feedback_window);
    std::printf("[stability] furnace rho=0.99 after 512 iterations at 48x48: %g with the SDK feedback, %g with window %u\n",
                sdk, fast, SharcSettings{}.feedback_window);
    EXPECT_LT(sdk, 35.0);
    EXPECT_GT(fast, 50.0);
}

/// two_rooms: room B has no light and sees none directly except at grazing angles through the
/// doorway; its surfaces are lit by light that bounced in room A. Reference: the path tracer's
/// outgoing radiance at the same surface points. Voxels must be fine enough (S = 20: 0.1 m near
/// the camera) not to straddle the doorway: at S = 5 the cache averages room A's lit floor into
/// room B's and room B comes out ~28 % too bright, for any feedback window (spatial averaging,
/// a bias by design, docs/sharc_algorithm.md §10.13).
TEST(StiffTwoRooms, RoomLitThroughTheDoorwayMatchesThePathTracer) {
    Scene scene = loadGltf(scenePath("two_rooms"));
    BakeConfig config;
    config.scene_scale = 20.0f;
    config.resolution = 64;
    config.capacity = 1u << 17;
    SmallBake bake(std::move(scene), config);
    const std::vector<SurfacePoint> room_b = areaSamples(bake.scene, 8000, [](glm::vec3 p) { return p.x > 0.1f; });
    const double reference = referenceMean(*bake.tracer, *bake.lights, room_b, 32).x;
    constexpr uint32_t kStep = 256, kMaxIterations = 3072;
    constexpr double kTolerance = 0.05;
    AreaMean mean;
    uint32_t converged_at = 0;
    while (bake.baker->iterationsDone() < kMaxIterations) {
        bake.run(kStep);
        mean = cacheMean(bake.cache(), room_b);
        if (std::abs(mean.radiance.x - reference) <= kTolerance * reference) {
            converged_at = bake.baker->iterationsDone();
            break;
        }
    }
    std::printf("[stability] two_rooms room B: reference %g, measured %g after %u iterations (tolerance %g%%), %.1f%% "
                "of %zu points reached\n",
                reference, mean.radiance.x, bake.baker->iterationsDone(), 100.0 * kTolerance, 100.0 * mean.reached,
                room_b.size());
    RecordProperty("iterations_needed", int(bake.baker->iterationsDone()));
    EXPECT_GT(converged_at, 0u) << "room B mean " << mean.radiance.x << ", reference " << reference;
    EXPECT_GT(mean.reached, 0.95);
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
    EXPECT_TRUE(bake.report().warnings.empty());
}

}  // namespace
}  // namespace sharcbake::stability
