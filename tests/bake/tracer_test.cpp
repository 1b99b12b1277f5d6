// SPDX-License-Identifier: Apache-2.0
// The batched ray queries the update wavefront traces with (Embree packets of 16) answer exactly
// as the single-ray queries do, for any count: whole packets, a short last one, and none. A closed
// mesh of many triangles lets no ray out through the edges its triangles share.
#include "../cache_format/float_bits.h"
#include "test_bake_scene.h"
#include "test_rooms.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <gtest/gtest.h>
#include <glm/gtc/quaternion.hpp>

#include <cstdio>
#include <limits>
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

/// A closed box of side 2 around the origin whose faces are grids of `cells` x `cells` quads
/// sharing their vertices, turned by `turn` so that no vertex lies on a round coordinate; as
/// tessellated meshes from modelling tools are.
Scene tessellatedBox(int cells, const glm::quat& turn) {
    Scene scene = emptyTestScene();
    scene.materials.emplace_back();
    for (int axis = 0; axis < 3; ++axis) {
        for (float side : {-1.0f, 1.0f}) {
            const uint32_t base = uint32_t(scene.positions.size());
            for (int j = 0; j <= cells; ++j) {
                for (int i = 0; i <= cells; ++i) {
                    glm::vec3 p;
                    p[axis] = side;
                    p[(axis + 1) % 3] = -1.0f + 2.0f * float(i) / float(cells);
                    p[(axis + 2) % 3] = -1.0f + 2.0f * float(j) / float(cells);
                    scene.positions.push_back(turn * p);
                }
            }
            for (int j = 0; j < cells; ++j) {
                for (int i = 0; i < cells; ++i) {
                    const uint32_t a = base + uint32_t(j * (cells + 1) + i), b = a + 1;
                    const uint32_t d = a + uint32_t(cells + 1), c = d + 1;
                    scene.triangles.emplace_back(a, b, c);
                    scene.triangles.emplace_back(a, c, d);
                    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, 0u);
                }
            }
        }
    }
    for (const glm::vec3& p : scene.positions) {
        scene.bounds_min = glm::min(scene.bounds_min, p);
        scene.bounds_max = glm::max(scene.bounds_max, p);
    }
    return scene;
}

// Debian's Embree keeps its assertions: a ray with a NaN or a component beyond 1.844e18 aborted
// the process (`--scene-scale 1e-20` offset the wall-leak probe's rays by voxels 1e20 wide).
// Tracer answers such a ray as meeting nothing, alone and in packets, beside rays it traces.
TEST(TracerGuards, RaysEmbreeWouldAssertOnMeetNothing) {
    const Scene box = tessellatedBox(2, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    const Tracer tracer(box);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const Ray good{glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f), 1e30f};
    std::vector<Ray> rays = {
        {glm::vec3(nan, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f), 1e30f},
        {glm::vec3(0.0f), glm::vec3(0.0f, nan, 0.0f), 1e30f},
        {glm::vec3(0.0f), glm::vec3(1.0f, 0.0f, 0.0f), nan},
        {glm::vec3(0.0f, 0.0f, 1e20f), glm::vec3(0.0f, 0.0f, -1.0f), INFINITY},
        {glm::vec3(0.0f), glm::vec3(-INFINITY, 0.0f, 0.0f), 1e30f},
    };
    for (const Ray& ray : rays) {
        EXPECT_FALSE(embreeTraces(ray));
        RayHit hit;
        EXPECT_FALSE(tracer.intersect(ray, hit));
        EXPECT_FALSE(tracer.occluded(ray));
    }
    ASSERT_TRUE(embreeTraces(good));
    RayHit good_hit;
    ASSERT_TRUE(tracer.intersect(good, good_hit));
    ASSERT_TRUE(tracer.occluded(good));
    rays.insert(rays.begin() + 2, good);  // a traced lane among the refused ones
    std::vector<RayHit> hits(rays.size());
    std::vector<uint8_t> found(rays.size()), blocked(rays.size());
    tracer.intersectMany(rays.data(), rays.size(), hits.data(), found.data());
    tracer.occludedMany(rays.data(), rays.size(), blocked.data());
    for (size_t i = 0; i < rays.size(); ++i) {
        EXPECT_EQ(found[i], i == 2 ? 1 : 0) << i;
        EXPECT_EQ(blocked[i], i == 2 ? 1 : 0) << i;
    }
    EXPECT_EQ(hits[2].triangle, good_hit.triangle);
    EXPECT_EQ(hits[2].t, good_hit.t);
}

// Rays from inside a closed mesh aimed at the midpoints of its shared edges must all hit it.
// Embree's fast triangle test is not watertight: without its robust mode 9,950 of these 147,456
// rays left a box of 64 x 64 quads a side (random rays: 3 in a million at 400 x 400), and a
// white box under a sky baked black voxels. (Robust mode still lets some rays aimed exactly at a
// vertex through: Embree's limit, and a set of directions of measure zero.)
TEST(TracerWatertight, NoRayLeavesAClosedMeshThroughASharedEdge) {
    const Scene box = tessellatedBox(64, glm::normalize(glm::quat(0.9f, 0.2f, -0.3f, 0.15f)));
    const Tracer tracer(box);
    const glm::vec3 origins[] = {{0.0f, 0.0f, 0.0f}, {0.31f, -0.47f, 0.12f}, {-0.66f, 0.58f, -0.73f}};
    std::vector<Ray> rays;
    for (const glm::vec3& origin : origins) {
        for (size_t t = 0; t < box.triangles.size(); t += 3) {
            const glm::uvec3 tri = box.triangles[t];
            const glm::vec3 a = box.positions[tri.x], b = box.positions[tri.y], c = box.positions[tri.z];
            for (const glm::vec3& target : {0.5f * (a + b), 0.5f * (a + c), 0.5f * (b + c)}) {
                rays.push_back(Ray{origin, glm::normalize(target - origin)});
            }
        }
    }
    std::vector<RayHit> hits(rays.size());
    std::vector<uint8_t> found(rays.size());
    tracer.intersectMany(rays.data(), rays.size(), hits.data(), found.data());
    size_t escaped = 0, escaped_single = 0, unoccluded = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
        escaped += found[i] == 0;
        RayHit hit;
        escaped_single += !tracer.intersect(rays[i], hit);
        unoccluded += !tracer.occluded(rays[i]);
    }
    EXPECT_EQ(escaped, 0u) << "of " << rays.size() << " rays (packets)";
    EXPECT_EQ(escaped_single, 0u) << "of " << rays.size() << " rays (single)";
    EXPECT_EQ(unoccluded, 0u) << "of " << rays.size() << " rays (occlusion)";
}

// Embree's kernels of different widths (SSE4.2, AVX2, AVX-512) compute a hit's distance and
// barycentrics with their own roundings (a reciprocal estimate, fused multiply-adds): the same ray
// on the same triangle gave other bits with each, and a bake other caches on other CPUs. The
// tracer recomputes them from the triangle, so they are the same bits whichever kernels found it.
// (Which triangle a ray meets at a shared edge can still differ between kernels; that is why a
// bake names its kernels, --trace-kernels.)
TEST(TracerKernels, AHitOnTheSameTriangleIsTheSameBitsWithEveryKernel) {
    const Scene box = tessellatedBox(48, glm::normalize(glm::quat(0.9f, 0.2f, -0.3f, 0.15f)));
    const Tracer sse(box, TraceKernels::kSse42), avx2(box, TraceKernels::kAvx2), native(box, TraceKernels::kNative);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Ray> rays;
    for (int i = 0; i < 60000; ++i) {
        const glm::vec3 origin = 0.55f * (2.0f * glm::vec3(unit(rng), unit(rng), unit(rng)) - 1.0f);
        rays.push_back(Ray{origin, sampleUniformSphere({unit(rng), unit(rng)})});
    }
    size_t compared = 0, other_triangle = 0;
    for (const Tracer* other : {&avx2, &native}) {
        std::vector<RayHit> hits(rays.size()), other_hits(rays.size());
        std::vector<uint8_t> found(rays.size()), other_found(rays.size());
        sse.intersectMany(rays.data(), rays.size(), hits.data(), found.data());
        other->intersectMany(rays.data(), rays.size(), other_hits.data(), other_found.data());
        for (size_t i = 0; i < rays.size(); ++i) {
            ASSERT_TRUE(found[i] && other_found[i]) << "ray " << i << " left the closed box";
            RayHit single;
            ASSERT_TRUE(other->intersect(rays[i], single));
            EXPECT_EQ(single.triangle, other_hits[i].triangle);
            EXPECT_EQ(toBits(single.t), toBits(other_hits[i].t)) << "ray " << i;
            if (hits[i].triangle != other_hits[i].triangle) {
                ++other_triangle;
                continue;
            }
            ++compared;
            EXPECT_EQ(toBits(hits[i].t), toBits(other_hits[i].t)) << "ray " << i;
            EXPECT_EQ(toBits(hits[i].u), toBits(other_hits[i].u)) << "ray " << i;
            EXPECT_EQ(toBits(hits[i].v), toBits(other_hits[i].v)) << "ray " << i;
        }
    }
    std::printf("kernels %s and %s: %zu hits compared, %zu rays met another triangle\n",
                traceKernelsName(avx2.kernels()), traceKernelsName(native.kernels()), compared, other_triangle);
    EXPECT_GT(compared, 119000u);
}

// The recomputed hit is the one Embree found: its distance and barycentrics agree with Embree's
// own to a few float roundings, and lie on the triangle.
TEST(TracerKernels, TheRecomputedHitIsEmbreesWithinRounding) {
    const Scene box = tessellatedBox(16, glm::normalize(glm::quat(0.7f, -0.4f, 0.3f, 0.2f)));
    const Tracer tracer(box);
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int i = 0; i < 20000; ++i) {
        const Ray ray{0.55f * (2.0f * glm::vec3(unit(rng), unit(rng), unit(rng)) - 1.0f),
                      sampleUniformSphere({unit(rng), unit(rng)})};
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit embree;
        initEmbreeRay(ray, embree.ray);
        embree.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(tracer.embreeScene(), &context, &embree);
        ASSERT_NE(embree.hit.geomID, RTC_INVALID_GEOMETRY_ID);
        RayHit hit{embree.hit.primID, embree.ray.tfar, embree.hit.u, embree.hit.v};
        recomputeHit(box, ray, hit);
        EXPECT_NEAR(hit.t, embree.ray.tfar, 4e-6f * embree.ray.tfar) << "ray " << i;
        EXPECT_NEAR(hit.u, embree.hit.u, 4e-6f) << "ray " << i;
        EXPECT_NEAR(hit.v, embree.hit.v, 4e-6f) << "ray " << i;
        EXPECT_GE(hit.u, 0.0f);
        EXPECT_GE(hit.v, 0.0f);
        EXPECT_LE(hit.u + hit.v, 1.0f + 1e-7f);
    }
}

// A ray that starts on a surface and leaves it does not hit that surface at distance 0 (robust
// mode reports such hits unless the ray begins past its origin): a camera standing on a floor sees
// the room, and the far wall is the first hit.
TEST(TracerWatertight, ARayLeavingASurfaceFromAPointOnItDoesNotHitIt) {
    const Scene box = tessellatedBox(4, glm::quat(1.0f, 0.0f, 0.0f, 0.0f));
    const Tracer tracer(box);
    for (const glm::vec3& on_floor : {glm::vec3(0.25f, -1.0f, 0.5f), glm::vec3(0.5f, -1.0f, 0.5f)}) {
        for (const glm::vec3& direction : {glm::vec3(0, 1, 0), glm::vec3(0.3f, 1, -0.2f), glm::vec3(0.9f, 0.05f, 0)}) {
            const Ray ray{on_floor, glm::normalize(direction)};
            RayHit hit;
            ASSERT_TRUE(tracer.intersect(ray, hit));
            EXPECT_GT(hit.t, 0.5f) << "from (" << on_floor.x << ", " << on_floor.z << ") towards (" << direction.x
                                   << ", " << direction.y << ", " << direction.z << ")";
            Ray blocked = ray;
            blocked.t_max = 0.25f;
            EXPECT_FALSE(tracer.occluded(blocked));
        }
    }
}

/// `scene` scaled by `half` (a box of side 2 becomes one of side 2 half) and moved to `at`.
Scene placed(Scene scene, float half, glm::vec3 at) {
    scene.bounds_min = glm::vec3(std::numeric_limits<float>::max());
    scene.bounds_max = glm::vec3(-std::numeric_limits<float>::max());
    for (glm::vec3& p : scene.positions) {
        p = half * p + at;
        scene.bounds_min = glm::min(scene.bounds_min, p);
        scene.bounds_max = glm::max(scene.bounds_max, p);
    }
    return scene;
}

/// Rays leaving hit points on the inside of a box, `offset_share` of rayOffsetFor off them, in
/// random directions of the hemisphere and grazing it: how many meet the face they left.
size_t selfHits(const Scene& box, float offset_share, uint32_t seed) {
    const Tracer tracer(box);
    const glm::vec3 centre = 0.5f * (box.bounds_min + box.bounds_max);
    const float half = 0.5f * (box.bounds_max.x - box.bounds_min.x);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    size_t self = 0;
    for (int i = 0; i < 4000; ++i) {
        const glm::vec3 jitter(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
        const Ray ray{centre + 0.3f * half * jitter, sampleUniformSphere({unit(rng), unit(rng)})};
        RayHit hit;
        if (!tracer.intersect(ray, hit)) continue;
        const SurfaceHit at = makeSurfaceHit(box, hit, ray.direction);
        const glm::vec3 origin = offsetRayOrigin(at.position, at.geometric_normal, offset_share * at.ray_offset);
        for (const bool grazing : {false, true}) {
            glm::vec3 d = sampleUniformSphere({unit(rng), unit(rng)});
            if (glm::dot(d, at.geometric_normal) < 0.0f) d = -d;
            if (grazing) d = glm::normalize(d - at.geometric_normal * (glm::dot(d, at.geometric_normal) - 1e-3f));
            RayHit next;
            if (!tracer.intersect(Ray{origin, d}, next)) continue;
            const glm::vec3 n = makeSurfaceHit(box, next, d).face_normal;
            self += std::abs(glm::dot(n, at.geometric_normal)) > 0.999f && next.t < 1e-2f * half;
        }
    }
    return self;
}

// The tracer's self-intersection guard is a few float32 roundings of the triangle's coordinates
// (rayOffsetFor). Boxes 2 mm to 2 km wide, of 2 or 32 triangles a side, turned, at the origin and
// up to 10^5 units from it: no ray leaving a hit point meets the face it left, and a sixteenth
// of the guard (one rounding) lets some do, so the guard is tight to within its factor.
TEST(RayOffset, NoRayMeetsTheSurfaceItLeavesAndAFractionOfTheGuardIsNotEnough) {
    const glm::quat turn = glm::normalize(glm::quat(0.9f, 0.2f, -0.3f, 0.15f));
    size_t too_little = 0;
    uint32_t seed = 1;
    for (const int cells : {1, 4}) {
        for (const float half : {1e-3f, 1.0f, 1e3f}) {
            for (const float distance : {0.0f, 1.0f, 1e3f, 1e5f}) {
                if (half < 1.0f && distance > 1e4f) continue;  // smaller than float32 resolves there
                const Scene box = placed(tessellatedBox(cells, turn), half, distance * glm::vec3(1.0f, -0.37f, 0.61f));
                EXPECT_EQ(selfHits(box, 1.0f, seed), 0u) << cells << " cells, half " << half << ", at " << distance;
                too_little += selfHits(box, 1.0f / kRayOffsetRoundings, seed);
                ++seed;
            }
        }
    }
    EXPECT_GT(too_little, 0u);
}

// The guard follows the triangle, not the point and not the origin: a 1 m room 10 km out gets
// centimetres (the 256 float steps it replaced: 0.25), a point near the origin on a triangle 2 km
// wide gets what the triangle's far vertices need, and a 1 mm scene gets a thousandth of the
// same scene's guard in metres.
TEST(RayOffset, TheGuardFollowsTheTrianglesCoordinates) {
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    const float far = rayOffsetFor(glm::vec3(1e4f, 0.0f, 0.0f), glm::vec3(1e4f + 1.0f, 0.0f, 0.0f),
                                   glm::vec3(1e4f, 0.0f, 1.0f), up);
    // Flat at y = 0, nothing rounds off the plane: the least guard, one rounding of 10^4.
    EXPECT_EQ(far, (1e4f + 1.0f) * 0x1p-24f);
    const glm::vec3 tilted = glm::normalize(glm::vec3(1.0f, 1.0f, 0.0f));
    const float room = rayOffsetFor(glm::vec3(1e4f, 1.0f, 0.0f), glm::vec3(1e4f + 1.0f, 0.0f, 0.0f),
                                    glm::vec3(1e4f, 1.0f, 1.0f), tilted);
    EXPECT_GT(room, 1e-3f);
    EXPECT_LT(room, 0.02f);
    const float wide = rayOffsetFor(glm::vec3(-1e3f, -1e3f, 0.0f), glm::vec3(1e3f, 1e3f, 0.0f),
                                    glm::vec3(1e3f, 1e3f, 1e3f), tilted);
    EXPECT_GT(wide, 1e-3f);
    const float metre = rayOffsetFor(glm::vec3(1.0f, 1.0f, 0.0f), glm::vec3(2.0f, 0.0f, 0.0f),
                                     glm::vec3(1.0f, 1.0f, 1.0f), tilted);
    const float millimetre = rayOffsetFor(glm::vec3(1e-3f, 1e-3f, 0.0f), glm::vec3(2e-3f, 0.0f, 0.0f),
                                          glm::vec3(1e-3f, 1e-3f, 1e-3f), tilted);
    EXPECT_NEAR(millimetre / metre, 1e-3f, 1e-5f);
    // A zero-area triangle's NaN normal gives the least guard, not NaN.
    const glm::vec3 nan_normal(std::numeric_limits<float>::quiet_NaN());
    EXPECT_EQ(rayOffsetFor(glm::vec3(2.0f), glm::vec3(2.0f), glm::vec3(2.0f), nan_normal), 2.0f * 0x1p-24f);
    // The origin moves along the normal and at least one float step on each axis it leans along.
    const glm::vec3 p(1e4f, 0.5f, -3.0f);
    const glm::vec3 moved = offsetRayOrigin(p, up, 0.0f);
    EXPECT_EQ(moved.x, p.x);
    EXPECT_GT(moved.y, p.y);
    EXPECT_EQ(moved.z, p.z);
    EXPECT_LT(offsetRayOrigin(p, -tilted, 0.01f).x, p.x);
}

}  // namespace
}  // namespace sharcbake
