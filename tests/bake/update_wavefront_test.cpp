// SPDX-License-Identifier: Apache-2.0
// The wavefront is a schedule, not an approximation: a batch of update paths deposits exactly
// what the same paths deposit traced one at a time, in the same order, and counts the same.
#include "sharc/baker.h"
#include "test_bake_scene.h"
#include "sharc/camera_path.h"
#include "sharc/sharc_update.h"
#include "tracing/lights.h"
#include "tracing/render.h"
#include "sharcbake/scene_loader.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

bool sameDeposits(const std::vector<Deposit>& a, const std::vector<Deposit>& b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i) {
        // Bitwise: the batch must not even round differently.
        if (a[i].key != b[i].key || a[i].samples != b[i].samples ||
            std::memcmp(&a[i].radiance, &b[i].radiance, sizeof(glm::vec3)) != 0) {
            return false;
        }
    }
    return true;
}

struct WarmBake : TestBakeScene {
    std::unique_ptr<Baker> baker;

    /// A few iterations, so later paths end on cached voxels (cache resampling) as well.
    WarmBake(const std::string& name, bool resample_at_end) : TestBakeScene(name) {
        BakeSettings settings;
        settings.width = 160;
        settings.height = 90;
        settings.sharc.grid.capacity = 1u << 18;
        settings.sharc.resample_at_end = resample_at_end;
        baker = makeBaker(settings);
        for (int i = 0; i < 6; ++i) baker->runIteration();
    }

    std::vector<UpdatePathStart> starts(uint32_t count, uint32_t iteration) const {
        const CameraPose pose = path->poseAt(iteration);
        const CameraRays camera(toCamera(pose), 160, 90);
        std::vector<UpdatePathStart> result;
        for (uint32_t i = 0; i < count; ++i) {
            PixelSampler sampler(0, i, iteration);
            const glm::vec2 u = sampler.next2D();
            result.push_back(UpdatePathStart{camera.generate(int(u.x * 160), int(u.y * 90), u), sampler});
        }
        return result;
    }
};

void expectBatchEqualsOneByOne(const WarmBake& bake) {
    const uint32_t iteration = 7;
    const std::vector<UpdatePathStart> starts = bake.starts(300, iteration);
    const CameraPose pose = bake.path->poseAt(iteration);
    const Float3 camera{pose.position.x, pose.position.y, pose.position.z};
    const UpdatePathSettings settings = bake.baker->settings().path;
    UpdateWavefront wavefront(*bake.tracer, *bake.lights, bake.baker->cache(), settings);

    std::vector<Deposit> batch, one_by_one, in_sevens;
    UpdateCounters batch_counters, single_counters, seven_counters;
    wavefront.trace(starts, bake.baker->depositLevels(), camera, batch, batch_counters);
    for (const UpdatePathStart& start : starts) {
        wavefront.trace({start}, bake.baker->depositLevels(), camera, one_by_one, single_counters);
    }
    for (size_t first = 0; first < starts.size(); first += 7) {
        const std::vector<UpdatePathStart> group(starts.begin() + std::ptrdiff_t(first),
                                                 starts.begin() + std::ptrdiff_t(std::min(starts.size(), first + 7)));
        wavefront.trace(group, bake.baker->depositLevels(), camera, in_sevens, seven_counters);
    }

    // One deposit per shaded vertex that did not end on the cache: what later vertices send back
    // joins it (PathHistory), so no deposit is a propagated one of its own (samples 0).
    ASSERT_GT(2 * batch.size(), starts.size());
    EXPECT_TRUE(std::all_of(batch.begin(), batch.end(), [](const Deposit& d) { return d.samples == 1; }));
    EXPECT_TRUE(sameDeposits(batch, one_by_one));
    EXPECT_TRUE(sameDeposits(batch, in_sevens));
    for (const UpdateCounters* c : {&single_counters, &seven_counters}) {
        EXPECT_EQ(c->paths, batch_counters.paths);
        EXPECT_EQ(c->segments, batch_counters.segments);
        EXPECT_EQ(c->shadow_rays, batch_counters.shadow_rays);
        EXPECT_EQ(c->resampled, batch_counters.resampled);
        EXPECT_EQ(c->sky_misses, batch_counters.sky_misses);
    }
    // The paths did bounce, trace shadow rays and end on the cache: the cases the batch reorders.
    EXPECT_GT(2 * batch_counters.segments, 3 * batch_counters.paths);  // 1.5 segments a path or more
    EXPECT_GT(batch_counters.shadow_rays, 0u);
    EXPECT_GT(batch_counters.resampled, 0u);
}

TEST(UpdateWavefront, BatchDepositsWhatThePathsDepositOneByOne) {
    expectBatchEqualsOneByOne(WarmBake("cornell_box", false));
    expectBatchEqualsOneByOne(WarmBake("two_rooms", false));
}

TEST(UpdateWavefront, BatchDepositsWhatThePathsDepositOneByOneWhenResamplingAtTheEnd) {
    expectBatchEqualsOneByOne(WarmBake("two_rooms", true));
}

TEST(UpdateWavefront, PathsMissingEverythingDepositTheSkyOnly) {
    // Rays from outside the scene pointing away from it: one segment each, no vertex.
    const WarmBake bake("outdoor", false);
    UpdateWavefront wavefront(*bake.tracer, *bake.lights, bake.baker->cache(), bake.baker->settings().path);
    std::vector<UpdatePathStart> starts;
    for (uint32_t i = 0; i < 10; ++i) {
        const glm::vec3 origin = bake.scene.bounds_max + glm::vec3(1.0f + float(i));
        starts.push_back(UpdatePathStart{Ray{origin, glm::vec3(0.0f, 1.0f, 0.0f)}, PixelSampler(0, i, 0)});
    }
    std::vector<Deposit> deposits;
    UpdateCounters counters;
    wavefront.trace(starts, bake.baker->depositLevels(), Float3{0.0f, 0.0f, 0.0f}, deposits, counters);
    EXPECT_EQ(counters.paths, 10u);
    EXPECT_EQ(counters.segments, 10u);
    EXPECT_EQ(counters.shadow_rays, 0u);
    EXPECT_EQ(counters.sky_misses, 10u);
    EXPECT_TRUE(deposits.empty());  // no vertex waits for the sky's radiance
}

}  // namespace
}  // namespace sharcbake
