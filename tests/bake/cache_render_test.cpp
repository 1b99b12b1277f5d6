// SPDX-License-Identifier: Apache-2.0
// `render --cache`: SHaRC's query eligibility tests, BakedCache lookups, and a cached render of
// the rho = 0.9 furnace, whose every surface has outgoing radiance Le / (1 - rho) = 10.
#include "sharc/baker.h"
#include "sharc/cache_query.h"
#include "sharc/camera_path.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/scene_loader.h"
#include "test_bake_scene.h"
#include "test_rooms.h"
#include "tracing/lights.h"
#include "tracing/path_tracer.h"
#include "tracing/render.h"
#include "tracing/surface.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace sharcbake {
namespace {

// ---- Eligibility (docs/sharc_algorithm.md §6.2, app-side tests) ---------------------------------

TEST(CacheEligibility, SegmentShorterThanTheVoxelDiagonalIsRefused) {
    const float s = 1.0f;
    EXPECT_FALSE(cacheQueryEligible(1.5f, 1.0f, s));             // t < sqrt(3) s, diffuse cone
    EXPECT_FALSE(cacheQueryEligible(std::sqrt(3.0f), 5.0f, s));  // t == sqrt(3) s is not longer
    EXPECT_TRUE(cacheQueryEligible(1.8f, 1.0f, s));              // just past the diagonal
}

TEST(CacheEligibility, MirrorLikeConeAtShortDistanceIsRefused) {
    // r = 0.1: a = 0.01, footprint = t * sqrt(0.5e-4 / (1 - 1e-4)) ~ 0.00707 t, so t = 5 gives
    // 0.035 voxels although the segment test passes.
    EXPECT_FALSE(cacheQueryEligible(5.0f, 0.1f, 1.0f));
    EXPECT_FALSE(cacheQueryEligible(100.0f, 0.1f, 1.0f));
    EXPECT_TRUE(cacheQueryEligible(200.0f, 0.1f, 1.0f));  // 1.41 voxels
    EXPECT_FALSE(cacheQueryEligible(5.0f, 0.0f, 1.0f));   // a perfect mirror never qualifies
}

TEST(CacheEligibility, DiffuseConeAtLongDistanceIsAccepted) {
    // r clamped to 0.99: footprint ~ 3.49 t.
    EXPECT_TRUE(cacheQueryEligible(10.0f, 1.0f, 1.0f));
    EXPECT_TRUE(cacheQueryEligible(10.0f, 3.0f, 1.0f));
    EXPECT_TRUE(cacheQueryEligible(1.8f, 1.0f, 1.0f));
    EXPECT_FALSE(cacheQueryEligible(std::nanf(""), 1.0f, 1.0f));
}

// ---- BakedCache lookups ---------------------------------------------------------------------------

TEST(BakedCache, LookupAppliesTheTestsAndFindsTheVoxel) {
    const glm::vec3 camera(0.0f, 0.0f, 0.0f);
    const glm::vec3 p(3.0f, 0.5f, -2.0f), n(0.0f, 1.0f, 0.0f);
    CacheData data;
    data.scene_scale = 5.0f;
    data.bake_capacity = 1u << 10;
    HashGridParameters params = data.gridParameters();
    const uint64_t key = hashGridKey(Float3{p.x, p.y, p.z}, Float3{n.x, n.y, n.z}, params);
    CacheVoxel v;
    v.key = key;
    v.radiance[0] = 1.0f;
    v.radiance[1] = 2.0f;
    v.radiance[2] = 3.0f;
    v.sample_weight = 4.0f;
    // A voxel without samples is never stored (SPEC: only live voxels), so the other side of the
    // surface has no voxel.
    const uint64_t other_side = hashGridKey(Float3{p.x, p.y, p.z}, Float3{0.0f, -1.0f, 0.0f}, params);
    data.voxels = {v};
    sortVoxels(data.voxels);
    const BakedCache cache(data, camera);
    ASSERT_EQ(cache.key(p, n), key);
    const float s = voxelSize(decodeHashGridKey(key).level, cache.parameters());

    glm::vec3 radiance(-1.0f);
    EXPECT_FALSE(cache.lookup(CacheQuery{p, n, 1.5f * s, 1.0f}, radiance));   // too short
    EXPECT_FALSE(cache.lookup(CacheQuery{p, n, 5.0f * s, 0.1f}, radiance));   // cone too narrow
    EXPECT_EQ(cache.refused(), 2u);
    ASSERT_TRUE(cache.lookup(CacheQuery{p, n, 5.0f * s, 1.0f}, radiance));
    EXPECT_EQ(radiance, glm::vec3(1.0f, 2.0f, 3.0f));
    EXPECT_FALSE(cache.lookup(CacheQuery{p, -n, 5.0f * s, 1.0f}, radiance));  // the other side
    EXPECT_FALSE(cache.lookup(CacheQuery{p, glm::vec3(-1.0f, 0.0f, 0.0f), 5.0f * s, 1.0f}, radiance));  // absent
    EXPECT_EQ(cache.hits(), 1u);
    EXPECT_EQ(cache.misses(), 2u);
    EXPECT_FALSE(cache.find(other_side).has_value());
    EXPECT_FALSE(cache.find(12345u).has_value());
}

// ---- The furnace, baked and rendered through the cache --------------------------------------------

/// A small bake of a furnace room (as furnace_test.cpp's SmallBake), written to a .sharc file and
/// read back, so the render goes through the file format.
class FurnaceCache : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        scene_ = new Scene(loadGltf(scenePath("furnace_rho090")));
        tracer_ = new Tracer(*scene_);
        lights_ = new LightSampler(*tracer_);
        const CameraPath path = exploringCameraPath(*tracer_, *scene_, 16, 3).value();
        BakeSettings settings;
        settings.width = settings.height = 128;
        settings.sharc.grid.capacity = 1u << 18;
        settings.sharc.grid.scene_scale = 5.0f;
        Baker baker(*tracer_, *lights_, path, settings, SharcCache::chooseRadianceScale(estimateMaxRadiance(*tracer_)));
        for (uint32_t i = 0; i < 2048; ++i) baker.runIteration();

        const SharcCache& cache = baker.cache();
        CacheData data = toCacheData(cache);
        const std::string file =
            (std::filesystem::temp_directory_path() / "sharcbake_cache_render_test.sharc").string();
        std::string message;
        ASSERT_EQ(writeCacheFile(file, data, &message), CacheFileStatus::kOk) << message;
        data_ = new CacheData;
        ASSERT_EQ(readCacheFile(file, data_, &message), CacheFileStatus::kOk) << message;
        std::filesystem::remove(file);
    }
    static void TearDownTestSuite() {
        delete data_;
        delete lights_;
        delete tracer_;
        delete scene_;
    }

    static Scene* scene_;
    static Tracer* tracer_;
    static LightSampler* lights_;
    static CacheData* data_;
};
Scene* FurnaceCache::scene_ = nullptr;
Tracer* FurnaceCache::tracer_ = nullptr;
LightSampler* FurnaceCache::lights_ = nullptr;
CacheData* FurnaceCache::data_ = nullptr;

TEST_F(FurnaceCache, CachedRenderMeanIsLeOverOneMinusRho) {
    ASSERT_GT(data_->voxels.size(), 50u);
    const Camera& camera = scene_->cameras.at(0);
    const BakedCache cache(*data_, camera.position);
    const PathTracer path_tracer(*tracer_, *lights_, PathTracerSettings{}, &cache);
    TraceCounters counters;
    const int res = 32;
    const Image image = renderImage(
        CameraRays(camera, res, res), ImageRenderSettings{res, res, 64, 1},
        [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, counters); }, nullptr);
    glm::dvec3 mean(0.0);
    for (const glm::vec3& p : image.pixels) mean += glm::dvec3(p);
    mean /= double(image.pixels.size());
    // Issue bar: the cached render within 2% of the analytic radiance Le / (1 - rho) = 10.
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(mean[ch], 10.0, 0.2) << "channel " << ch;
    std::printf("cached furnace: mean %.4f, %zu voxels, %llu hits, %llu misses, %llu refused\n", mean.x,
                data_->voxels.size(), (unsigned long long)cache.hits(), (unsigned long long)cache.misses(),
                (unsigned long long)cache.refused());
    // Most paths end on the cache after one bounce.
    const TraceCounts counts = counters.total();
    EXPECT_GT(counts.cache_hits, uint64_t(res * res * 64) / 2);
    EXPECT_EQ(counts.cache_hits, cache.hits());
    EXPECT_EQ(counts.non_finite_samples, 0u);
}

TEST_F(FurnaceCache, CacheSeenFromTheCameraIsTenWhereVoxelsExist) {
    const Camera& camera = scene_->cameras.at(0);
    const BakedCache cache(*data_, camera.position);
    const int res = 32;
    const CameraRays rays(camera, res, res);
    uint32_t hits = 0, found = 0;
    double sum = 0.0, worst = 0.0;
    for (int y = 0; y < res; ++y) {
        for (int x = 0; x < res; ++x) {
            const Ray ray = rays.generate(x, y, glm::vec2(0.5f));
            RayHit ray_hit;
            if (!tracer_->intersect(ray, ray_hit)) continue;
            ++hits;
            const SurfaceHit hit = makeSurfaceHit(*scene_, ray_hit, ray.direction);
            const std::optional<CacheVoxel> v = cache.find(cache.key(hit.position, hit.geometric_normal));
            if (!v) continue;
            ++found;
            sum += v->radiance[0];
            worst = std::max(worst, std::abs(double(v->radiance[0]) - 10.0) / 10.0);
        }
    }
    ASSERT_EQ(hits, uint32_t(res * res));  // the camera is inside the closed room
    EXPECT_GT(found, hits * 9 / 10) << "the bake's voxels should cover what the camera sees";
    ASSERT_GT(found, 0u);
    EXPECT_NEAR(sum / found, 10.0, 0.3);
    EXPECT_LT(worst, 0.15);
}

}  // namespace
// ---- Framing a glTF camera whose aspect ratio differs from the image's (Blender's sensor fit Auto)

TEST(CameraFit, KeepsTheFieldOfViewOfTheCamerasLongerSideOnTheImagesLongerSide) {
    Camera wide;
    wide.yfov = 0.6f;
    wide.aspect_ratio = 16.0f / 9.0f;
    const float tan_x = std::tan(0.3f) * 16.0f / 9.0f;  // the camera's horizontal half-angle tangent
    // Its own aspect: unchanged, also where the height is W / aspect rounded to whole pixels
    // (--resolution 100 on a 16:9 camera is 100x56).
    EXPECT_EQ(fitCameraToImage(wide, 1600, 900).yfov, 0.6f);
    EXPECT_EQ(fitCameraToImage(wide, 100, 56).yfov, 0.6f);
    EXPECT_EQ(fitCameraToImage(wide, 64, 36).yfov, 0.6f);
    // Square image: the horizontal field of view stays, so the vertical one grows to it.
    EXPECT_NEAR(std::tan(0.5f * fitCameraToImage(wide, 256, 256).yfov), tan_x, 1e-5f);
    // Portrait 9:16: the camera's long side spans the image's long side (its height).
    EXPECT_NEAR(std::tan(0.5f * fitCameraToImage(wide, 90, 160).yfov), tan_x, 1e-5f);
    // A portrait camera (1:2) on a 2:1 image: its vertical field of view spans the image's width.
    Camera tall;
    tall.yfov = 1.0f;
    tall.aspect_ratio = 0.5f;
    EXPECT_NEAR(std::tan(0.5f * fitCameraToImage(tall, 200, 100).yfov), std::tan(0.5f) / 2.0f, 1e-5f);
    // No aspect ratio in the glTF: nothing to fit.
    Camera free;
    free.yfov = 0.7f;
    EXPECT_EQ(fitCameraToImage(free, 100, 300).yfov, 0.7f);
}

TEST(CameraFit, OrthographicKeepsTheExtentOfTheViewsLongerSide) {
    Camera iso;
    iso.orthographic_half_height = 2.0f;
    iso.aspect_ratio = 2.0f;  // 8 x 4 units
    EXPECT_EQ(*fitCameraToImage(iso, 200, 100).orthographic_half_height, 2.0f);
    EXPECT_EQ(*fitCameraToImage(iso, 63, 32).orthographic_half_height, 2.0f);          // 63 / 2 rounded
    EXPECT_FLOAT_EQ(*fitCameraToImage(iso, 100, 100).orthographic_half_height, 4.0f);  // 8 wide: 8 high
    EXPECT_FLOAT_EQ(*fitCameraToImage(iso, 100, 200).orthographic_half_height, 4.0f);  // 8 spans the height
    EXPECT_EQ(fitCameraToImage(iso, 100, 100).yfov, iso.yfov);
}

TEST(CameraRays, OrthographicRaysAreParallelFromTheViewRectangle) {
    Camera iso;
    iso.position = {1.0f, 5.0f, 0.0f};
    iso.forward = {0.0f, -1.0f, 0.0f};
    iso.up = {0.0f, 0.0f, -1.0f};
    iso.orthographic_half_height = 2.0f;
    const CameraRays rays(iso, 200, 100);  // 8 x 4 units: right is forward x up = +X
    const Ray corner = rays.generate(0, 0, glm::vec2(0.0f));
    EXPECT_EQ(corner.direction, iso.forward);
    EXPECT_NEAR(corner.origin.x, 1.0f - 4.0f, 1e-5f);
    EXPECT_NEAR(corner.origin.y, 5.0f, 1e-5f);
    EXPECT_NEAR(corner.origin.z, -2.0f, 1e-5f);  // the top row is along up
    const Ray centre = rays.generate(100, 50, glm::vec2(0.0f));
    EXPECT_NEAR(glm::length(centre.origin - iso.position), 0.0f, 1e-5f);
    EXPECT_EQ(centre.direction, iso.forward);
}

// ---- Clip planes (glTF znear and zfar, Blender's clip start and end) --------------------------

TEST(CameraRays, SegmentsLieBetweenTheClipPlanesAcrossTheForwardAxis) {
    Camera camera;
    camera.yfov = 1.2f;
    camera.znear = 0.5f;
    camera.zfar = 4.0f;
    const CameraRays rays(camera, 64, 64);
    for (const glm::ivec2 pixel : {glm::ivec2(32, 32), glm::ivec2(0, 0), glm::ivec2(63, 10)}) {
        const Ray ray = rays.generate(pixel.x, pixel.y, glm::vec2(0.5f));
        const float cosine = glm::dot(ray.direction, camera.forward);
        // Where the ray meets each plane, it is znear or zfar along forward.
        EXPECT_NEAR(ray.t_min * cosine, 0.5f, 1e-5f);
        EXPECT_NEAR(ray.t_max * cosine, 4.0f, 1e-5f);
    }
    // Orthographic rays run along forward: the distances themselves.
    camera.orthographic_half_height = 1.0f;
    const Ray parallel = CameraRays(camera, 8, 8).generate(0, 7, glm::vec2(0.5f));
    EXPECT_EQ(parallel.t_min, 0.5f);
    EXPECT_EQ(parallel.t_max, 4.0f);
    // No planes: the whole ray, as before.
    const Ray whole = CameraRays(Camera{}, 8, 8).generate(3, 3, glm::vec2(0.5f));
    EXPECT_EQ(whole.t_min, 0.0f);
    EXPECT_TRUE(std::isinf(whole.t_max));
}

/// `scene` through `camera` at 24 x 24 pixels, 4 samples each, path traced.
Image renderThrough(const Scene& scene, const Camera& camera, PathTracerSettings settings = {}) {
    const Tracer tracer(scene);
    const LightSampler lights(scene);  // without learning where light arrives: quicker, as unbiased
    const PathTracer path_tracer(tracer, lights, settings);
    TraceCounters counters;
    return renderImage(
        CameraRays(camera, 24, 24), ImageRenderSettings{24, 24, 4, 1},
        [&](const Ray& ray, PixelSampler& sampler) { return path_tracer.radiance(ray, sampler, counters); }, nullptr);
}

double meanOf(const Image& image) {
    double sum = 0.0;
    for (const glm::vec3& p : image.pixels) sum += double(p.x + p.y + p.z) / 3.0;
    return sum / double(image.pixels.size());
}

TEST(CameraClipPlanes, ACameraOutsideAClosedRoomSeesInPastItsNearPlane) {
    const Scene scene = cutawayRoom();
    Camera cutaway = scene.cameras.at(0);
    const double inside = meanOf(renderThrough(scene, cutaway));
    EXPECT_GT(inside, 0.01) << "the lit room behind the clipped wall";
    // Without the clip the camera sees the front wall's unlit outer side: black.
    cutaway.znear = 0.0f;
    EXPECT_EQ(meanOf(renderThrough(scene, cutaway)), 0.0);
    // An orthographic camera outside with its near plane inside sees what the same camera inside
    // sees: parallel rays from its view rectangle meet the same points.
    Camera outside = scene.cameras.at(0);
    outside.orthographic_half_height = 0.9f;
    Camera within = outside;
    within.position.z = outside.position.z - outside.znear;
    within.znear = 0.0f;
    const Image seen_from_outside = renderThrough(scene, outside), seen_within = renderThrough(scene, within);
    EXPECT_GT(meanOf(seen_within), 0.01);
    EXPECT_NEAR(meanOf(seen_from_outside), meanOf(seen_within), 1e-3 * meanOf(seen_within));
}

TEST(CameraClipPlanes, NothingBeyondTheFarPlaneIsSeenButTheSky) {
    Scene scene = cutawayRoom();
    scene.sky.uniform = glm::vec3(0.25f);  // outside the closed room, seen only past a far plane
    Camera centre = scene.cameras.at(0);
    centre.position = glm::vec3(0.0f, 1.0f, 0.0f);  // 1 m from every wall it sees
    centre.znear = 0.0f;
    centre.zfar = 0.5f;
    PathTracerSettings short_paths;  // in a closed room under a sky the paths run long; what the
    short_paths.max_bounces = 2;     // camera sees is the question here
    const Image clipped = renderThrough(scene, centre, short_paths);
    for (const glm::vec3& p : clipped.pixels) ASSERT_EQ(p, glm::vec3(0.25f));
    centre.zfar = 5.0f;  // beyond the room: its walls
    const Image whole = renderThrough(scene, centre, short_paths);
    size_t sky = 0;
    for (const glm::vec3& p : whole.pixels) sky += p == glm::vec3(0.25f);
    EXPECT_EQ(sky, 0u);
    EXPECT_GT(meanOf(whole), 0.01);
}

}  // namespace sharcbake
