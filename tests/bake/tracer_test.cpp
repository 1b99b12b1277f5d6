// SPDX-License-Identifier: Apache-2.0
// The batched ray queries the update wavefront traces with (Embree packets of 16) answer exactly
// as the single-ray queries do, for any count: whole packets, a short last one, and none.
#include "test_bake_scene.h"
#include "tracing/sampling.h"

#include <gtest/gtest.h>

#include <random>

namespace sharcbake {
namespace {

/// Rays from random points of the Cornell box's bounds in random directions, a few of them cut
/// short so that occlusion queries see both answers.
std::vector<Ray> randomRays(const Scene& scene, size_t count, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (size_t i = 0; i < count; ++i) {
        const glm::vec3 u(unit(rng), unit(rng), unit(rng));
        const glm::vec3 origin = scene.bounds_min + u * (scene.bounds_max - scene.bounds_min);
        Ray ray{origin, sampleUniformSphere({unit(rng), unit(rng)})};
        if (i % 3 == 0) ray.t_max = 0.3f * unit(rng);
        rays.push_back(ray);
    }
    return rays;
}

TEST(TracerBatches, PacketsAnswerAsSingleRaysForAnyCount) {
    const TestBakeScene cornell("cornell_box");
    const Tracer& tracer = *cornell.tracer;
    for (size_t count : {size_t(0), size_t(1), size_t(15), size_t(16), size_t(17), size_t(64), size_t(101)}) {
        const std::vector<Ray> rays = randomRays(cornell.scene, count, uint32_t(count) + 1);
        std::vector<RayHit> hits(count);
        std::vector<uint8_t> found(count, 2), blocked(count, 2);
        tracer.intersectMany(rays.data(), count, hits.data(), found.data());
        tracer.occludedMany(rays.data(), count, blocked.data());
        size_t found_count = 0, blocked_count = 0;
        for (size_t i = 0; i < count; ++i) {
            RayHit single;
            const bool hit = tracer.intersect(rays[i], single);
            ASSERT_EQ(found[i], uint8_t(hit)) << "count " << count << ", ray " << i;
            if (hit) {
                EXPECT_EQ(hits[i].triangle, single.triangle) << "count " << count << ", ray " << i;
                EXPECT_EQ(hits[i].t, single.t);
                EXPECT_EQ(hits[i].u, single.u);
                EXPECT_EQ(hits[i].v, single.v);
            }
            EXPECT_EQ(blocked[i], uint8_t(tracer.occluded(rays[i]))) << "count " << count << ", ray " << i;
            found_count += found[i];
            blocked_count += blocked[i];
        }
        if (count >= 64) {  // both answers occur, so the comparison tested something
            EXPECT_GT(found_count, 0u);
            EXPECT_LT(found_count, count);
            EXPECT_GT(blocked_count, 0u);
            EXPECT_LT(blocked_count, count);
        }
    }
}

}  // namespace
}  // namespace sharcbake
