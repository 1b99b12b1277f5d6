// SPDX-License-Identifier: Apache-2.0
// Extreme radiance: emitters from 1e-35 to 1e37, and a tiny, very bright emitter beside a dim,
// large one. No integer wrap, no fp saturation, energy conserved, every clamp counted.
#include "stability_support.h"

#include "reports/stability_report.h"
#include "support/worker_threads.h"
#include "tracing/render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

namespace sharcbake::stability {
namespace {

/// Furnace rho = 0.5 (L = 2 Le) at emission levels 72 decades apart: the fixed-point scale
/// follows the brightest emission, so every level must give the same relative answer. 1e37 came
/// out 73% low (the scale stopped at 2^-60, where a deposit holds at most 2^122 = 5.3e36), 1e-35
/// as 0 (the scale stopped at 2^100, where its deposits were 1e-5 of a step, below the dither).
/// The same paths at every level, too: light selection follows the powers' ratios, and at 1e37
/// the walls' powers (pi x 8 m^2 x 1e37 and more) were beyond float32, read as none, and the paths
/// differed (1.9995 Le against 1.9966 Le at every other level).
class EmissionSweep : public ::testing::TestWithParam<float> {};

/// Held by pointer: the bake's tracer refers to its scene.
std::unique_ptr<SmallBake> furnaceBake(float emission) {
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, 0.5f, emission);
    BakeConfig config;
    config.iterations = 128;
    auto bake = std::make_unique<SmallBake>(std::move(scene), config);
    bake->run();
    return bake;
}

/// The furnace's measured answer per unit of emission at Le = 1.
double unitFurnaceAnswer() {
    static const double answer = sampleWeightedMean(furnaceBake(1.0f)->cache());
    return answer;
}

TEST_P(EmissionSweep, FurnaceGivesTwiceTheEmissionAtAnyMagnitude) {
    const float emission = GetParam();
    const std::unique_ptr<SmallBake> furnace = furnaceBake(emission);
    const SmallBake& bake = *furnace;
    const double expected = 2.0 * double(emission);
    const double measured = sampleWeightedMean(bake.cache());
    constexpr double kTolerance = 0.01;
    std::printf("[stability] furnace rho=0.5 Le=%g: expected %g, measured %g (tolerance %g%%), scale %g\n",
                double(emission), expected, measured, 100.0 * kTolerance, bake.cache().radianceScale());
    EXPECT_NEAR(measured, expected, kTolerance * expected);
    // Float32 rounding of the emission and the paths' radiance apart (1e-35 is near its smallest
    // normal values), the answer at Le = 1 scaled.
    EXPECT_NEAR(measured / double(emission), unitFurnaceAnswer(), 1e-4 * unitFurnaceAnswer());
    const StabilityReport report = bake.report();
    EXPECT_EQ(report.clamped_deposits, 0u);
    EXPECT_EQ(report.saturated_sums, 0u);
    EXPECT_EQ(report.non_finite_dropped, 0u);
    EXPECT_EQ(report.sub_step_deposits, 0u);
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
}

INSTANTIATE_TEST_SUITE_P(Extreme, EmissionSweep, ::testing::Values(1e-35f, 1e-6f, 1e-3f, 1.0f, 1e3f, 1e7f, 1e37f),
                         [](const auto& info) {
                             const int decade = int(std::lround(std::log10(double(info.param))));
                             return std::string("Le_1e") + (decade < 0 ? "m" : "") + std::to_string(std::abs(decade));
                         });

/// The reference render of the furnace at emissions near float32's smallest normal value
/// (1.2e-38; 1e-38 is below it), on the workers the commands trace on. The tracer is built first,
/// outside them, as a library user would build it: Embree's scene commit then starts TBB's first
/// arena with flush-to-zero on, and renders in that arena were black at 1e-38 and 10% dark at
/// 1e-37 (the bounces below 1.2e-38 were dropped). The bake was exact: it ran in an arena of its own.
class SubnormalRender : public ::testing::TestWithParam<float> {};

TEST_P(SubnormalRender, FurnaceImageIsTwiceTheEmission) {
    const float emission = GetParam();
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, 0.5f, emission);
    const Tracer tracer(scene);
    const LightSampler lights(tracer);
    const PathTracer path_tracer(tracer, lights, PathTracerSettings{});
    TraceCounters counters;
    constexpr int kSize = 24;
    std::atomic<bool> flushed{false};
    Image image;
    runOnWorkerThreads(2, [&] {
        image = renderImage(
            CameraRays(scene.cameras.at(0), kSize, kSize), ImageRenderSettings{kSize, kSize, 32, 1},
            [&](const Ray& ray, PixelSampler& sampler) {
                if (flushesSubnormals()) flushed = true;
                return path_tracer.radiance(ray, sampler, counters);
            },
            nullptr);
    });
    EXPECT_FALSE(flushed) << "a worker flushes subnormal values to zero";
    double sum = 0.0;
    for (const glm::vec3& p : image.pixels) sum += (double(p.x) + double(p.y) + double(p.z)) / 3.0;
    const double measured = sum / double(image.pixels.size()) / double(emission);
    std::printf("[stability] furnace render rho=0.5 Le=%g: expected 2 Le, measured %.4f Le\n", double(emission),
                measured);
    EXPECT_NEAR(measured, 2.0, 0.02 * 2.0);
}

INSTANTIATE_TEST_SUITE_P(Extreme, SubnormalRender, ::testing::Values(1e-38f, 1e-37f, 1.0f), [](const auto& info) {
    const int decade = int(std::lround(std::log10(double(info.param))));
    return std::string("Le_1e") + (decade < 0 ? "m" : "") + std::to_string(std::abs(decade));
});

/// Appends a single-sided square emitter (facing -Y, side `side`, radiance `emission`, albedo
/// `rho`) with its corner at `corner`.
void addCeilingEmitter(Scene& scene, glm::vec3 corner, float side, float emission, float rho) {
    Material m;
    m.name = "tiny_bright";
    m.base_color = glm::vec3(rho);
    m.metallic = 0.0f;
    m.specular = 0.0f;
    m.emissive = glm::vec3(1.0f);
    m.emissive_strength = emission;
    const uint32_t material = uint32_t(scene.materials.size());
    scene.materials.push_back(m);
    const uint32_t base = uint32_t(scene.positions.size());
    for (glm::vec2 d : {glm::vec2(0, 0), glm::vec2(0, 1), glm::vec2(1, 0), glm::vec2(1, 1)}) {
        scene.positions.push_back(corner + glm::vec3(d.x * side, 0.0f, d.y * side));
        if (!scene.normals.empty()) scene.normals.push_back(glm::vec3(0.0f, -1.0f, 0.0f));
        if (!scene.texcoords0.empty()) scene.texcoords0.push_back(glm::vec2(0.0f));
        if (!scene.texcoords1.empty()) scene.texcoords1.push_back(glm::vec2(0.0f));
    }
    // Counter-clockwise seen from below: the front faces -Y.
    scene.triangles.push_back(glm::uvec3(base, base + 2, base + 1));
    scene.triangles.push_back(glm::uvec3(base + 2, base + 3, base + 1));
    scene.triangle_materials.insert(scene.triangle_materials.end(), 2, material);
}

/// A 0.1 mm emitter of radiance 1e7 just below the ceiling of a closed room whose walls all
/// emit 1e-3: ten decades apart, about equal power. Albedo 0.5 everywhere, so energy
/// conservation gives the area mean of the outgoing radiance over all surfaces but the emitter:
/// sum(Le A) / ((1 - rho) A) - Le_bright A_bright / A. Before dithered rounding and the 2^40
/// fixed-point scale, every deposit in the room (about 0.1 fixed-point step) rounded to 0.
TEST(Fireflies, TinyBrightEmitterBesideADimLargeOneConservesEnergy) {
    constexpr float kRho = 0.5f, kDim = 1e-3f, kBright = 1e7f, kSide = 1e-4f;
    Scene scene = loadGltf(scenePath("furnace_rho050"));
    makeFurnace(scene, kRho, kDim);
    addCeilingEmitter(scene, glm::vec3(-1.0f, 2.99f, 1.0f), kSide, kBright, kRho);
    const auto [area, emission] = areaAndEmission(scene);
    const double bright_emission = double(kBright) * double(kSide) * double(kSide);
    const double expected = emission.x / ((1.0 - double(kRho)) * area) - bright_emission / area;
    BakeConfig config;
    config.iterations = 256;
    config.resolution = 64;
    SmallBake bake(std::move(scene), config);
    bake.run();
    const AreaMean mean = areaMeanRadiance(bake.scene, bake.cache(), 8000);
    constexpr double kTolerance = 0.05;
    const StabilityReport report = bake.report();
    std::printf("[stability] fireflies: expected %g, measured %g (tolerance %g%%); clamped %llu deposits (%.3g%% of "
                "the energy), saturated %llu\n",
                expected, mean.radiance.x, 100.0 * kTolerance, (unsigned long long)report.clamped_deposits,
                100.0 * report.share(report.clamped_energy), (unsigned long long)report.saturated_sums);
    EXPECT_NEAR(mean.radiance.x, expected, kTolerance * expected);
    EXPECT_GT(mean.reached, 0.95);
    EXPECT_EQ(report.clamped_deposits, 0u);
    EXPECT_EQ(report.saturated_sums, 0u);
    EXPECT_TRUE(cacheIsFinite(bake.cache()));
}

// The accumulation itself, one voxel at a time.

SharcSettings oneVoxelSettings() {
    SharcSettings s;
    s.grid.capacity = 64;
    s.history = {HistorySchedule::Kind::Average, 0.0f};
    return s;
}

constexpr uint64_t kKey = 0x0000000000010001ull | (uint64_t(3) << kHashGridLevelOffset);

/// Radiance 1e-13 of the brightest is 0.1 fixed-point step: truncation or round-to-nearest
/// stores 0 for ever; dithered rounding keeps it on average.
TEST(FixedPoint, RadianceFarBelowOneStepIsKeptOnAverage) {
    const double scale = SharcCache::chooseRadianceScale(1e7);
    SharcCache cache(oneVoxelSettings(), scale);
    const float tiny = float(0.1 / scale);
    constexpr int kDeposits = 100000;
    cache.commit(std::vector<Deposit>(kDeposits, Deposit{kKey, glm::vec3(tiny), 1}));
    cache.resolve(0);
    const ResolvedEntry* e = cache.findResolved(kKey);
    ASSERT_NE(e, nullptr);
    // Binomial(1e5, 0.1) / 1e5 has a relative standard deviation of 0.95%: 5% is > 5 sigma.
    EXPECT_NEAR(e->mean.x, tiny, 0.05 * tiny);
    // Every one of them was below one step: counted, and the stability report says what it costs.
    EXPECT_EQ(cache.numerics().sub_step_deposits, uint64_t(kDeposits));
    const StabilityReport report = makeStabilityReport(cache, UpdateCounters{}, glm::vec3(0.0f), glm::vec3(1.0f), {1});
    EXPECT_EQ(report.sub_step_deposits, uint64_t(kDeposits));
    const bool warned = std::any_of(report.warnings.begin(), report.warnings.end(), [](const std::string& w) {
        return w.find("100% of deposits carried less than one fixed-point step") != std::string::npos;
    });
    EXPECT_TRUE(warned) << testing::PrintToString(report.warnings);
    // Whole, remedy included: a 512-byte buffer cut it off mid-sentence.
    const bool whole = std::any_of(report.warnings.begin(), report.warnings.end(), [](const std::string& w) {
        return w.find("or bake the dim part as a scene of its own") != std::string::npos;
    });
    EXPECT_TRUE(whole) << testing::PrintToString(report.warnings);

    // One step and more is not counted, however dim against the brightest emitter.
    SharcCache steps(oneVoxelSettings(), scale);
    steps.commit(std::vector<Deposit>(100, Deposit{kKey, glm::vec3(float(1.5 / scale)), 1}));
    EXPECT_EQ(steps.numerics().sub_step_deposits, 0u);
}

/// The scale follows the brightest radiance across float32's normal range, so a voxel holds it
/// exactly at any magnitude. With the scale held to [2^-60, 2^100], 1e37 was stored 47% low
/// (clamped at 2^62 steps of 2^60: 5.3e36) and 1e-37 as 0 (1e-7 of a step). Denormals are left
/// out: where Embree has set the thread to flush them to zero (it does for its own threads, and
/// a process that made a device before runs the rest of its work that way), they are 0 anyway.
TEST(FixedPoint, RadianceAcrossFloat32sRangeIsStoredExactly) {
    for (const float radiance : {std::numeric_limits<float>::min(), 1e-37f, 1e-30f, 1e30f, 1e37f,
                                 std::numeric_limits<float>::max()}) {
        SCOPED_TRACE(radiance);
        SharcCache cache(oneVoxelSettings(), SharcCache::chooseRadianceScale(radiance));
        cache.commit(std::vector<Deposit>(10, Deposit{kKey, glm::vec3(radiance), 1}));
        cache.resolve(0);
        const ResolvedEntry* e = cache.findResolved(kKey);
        ASSERT_NE(e, nullptr);
        EXPECT_EQ(e->mean.x, radiance);
        EXPECT_EQ(cache.numerics().clamped_deposits, 0u);
        EXPECT_EQ(cache.numerics().sub_step_deposits, 0u);
    }
    // An estimate beyond float32 (a bright punctual light next to a surface can give one) takes the largest float's
    // scale; it took 1's, where every deposit above 2^22 was clamped.
    EXPECT_EQ(SharcCache::chooseRadianceScale(std::numeric_limits<double>::infinity()),
              SharcCache::chooseRadianceScale(std::numeric_limits<float>::max()));
    EXPECT_EQ(SharcCache::chooseRadianceScale(1e300), SharcCache::chooseRadianceScale(1e39));
}

/// A room 6 x 6 x 6 scene units, its walls facing in, with a point light of intensity `intensity`
/// at (0, height, 0).
Scene roomWithPointLight(float height, float intensity) {
    Scene scene;
    scene.materials.emplace_back();
    const glm::vec3 lo(-3.0f, 0.0f, -3.0f), hi(3.0f, 6.0f, 3.0f);
    for (int i = 0; i < 8; ++i)
        scene.positions.push_back(glm::vec3(i & 1 ? hi.x : lo.x, i & 2 ? hi.y : lo.y, i & 4 ? hi.z : lo.z));
    const int faces[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
    for (const auto& f : faces) {
        scene.triangles.push_back(glm::uvec3(f[0], f[1], f[2]));
        scene.triangles.push_back(glm::uvec3(f[0], f[2], f[3]));
        scene.triangle_materials.insert(scene.triangle_materials.end(), 2, 0u);
    }
    scene.bounds_min = lo;
    scene.bounds_max = hi;
    PunctualLight light;
    light.position = glm::vec3(0.0f, height, 0.0f);
    light.intensity = glm::vec3(intensity);
    scene.lights.push_back(light);
    return scene;
}

/// A point light's share of the fixed-point scale follows its distance to the surfaces around it
/// in the scene's own units: a radiance of I / (d/8)^2 / pi, d the nearest of 64 probe rays' hits.
/// It was I / (1 cm)^2 / pi in any units, so the same room modelled in millimetres, its lamp 10^6
/// brighter so that the walls receive the same light, had a scale 2^20 coarser and its walls'
/// light 2^20 fewer steps deep (a few steps, for a lamp 3 m from the walls: noise, and a warning
/// that blamed the lamp).
TEST(FixedPoint, APointLightCountsAtItsDistanceToTheSurfacesInTheScenesOwnUnits) {
    const float intensity = 100.0f;
    Scene metres = roomWithPointLight(5.0f, intensity);  // 1 m below the ceiling
    const Tracer metres_tracer(metres);
    const double estimate = estimateMaxRadiance(metres_tracer);
    const double at_an_eighth = intensity * 64.0 / kPi;
    EXPECT_LE(estimate, at_an_eighth * (1.0 + 1e-5));
    EXPECT_GE(estimate, 0.8 * at_an_eighth);  // the probe ray nearest the ceiling's normal

    Scene millimetres = roomWithPointLight(5.0f, intensity * 1e6f);
    transformScene(millimetres, 1000.0f, glm::vec3(0.0f));
    const Tracer millimetres_tracer(millimetres);
    EXPECT_NEAR(estimateMaxRadiance(millimetres_tracer) / estimate, 1.0, 1e-5);
    EXPECT_EQ(SharcCache::chooseRadianceScale(estimateMaxRadiance(millimetres_tracer)),
              SharcCache::chooseRadianceScale(estimate));

    // A light on the floor: 1e-4 of the room's diagonal, not the distance to the floor, so that
    // the rest of the room keeps its steps.
    Scene touching = roomWithPointLight(1e-7f, intensity);
    const Tracer touching_tracer(touching);
    const double diagonal = double(glm::length(touching.bounds_max - touching.bounds_min));
    EXPECT_NEAR(estimateMaxRadiance(touching_tracer), intensity / (1e-8 * diagonal * diagonal) / kPi,
                1e-4 * intensity / (1e-8 * diagonal * diagonal));

    // Far outside a small scene, where no probe ray hits: the distance to its bounds.
    Scene far;
    far.materials.emplace_back();
    far.positions = {{-0.5f, 0.0f, -0.5f}, {0.5f, 0.0f, -0.5f}, {0.5f, 0.0f, 0.5f}, {-0.5f, 0.0f, 0.5f}};
    far.triangles = {{0, 2, 1}, {0, 3, 2}};
    far.triangle_materials = {0, 0};
    far.bounds_min = glm::vec3(-0.5f, 0.0f, -0.5f);
    far.bounds_max = glm::vec3(0.5f, 0.0f, 0.5f);
    PunctualLight lamp;
    lamp.position = glm::vec3(0.0f, 1000.0f, 0.0f);
    lamp.intensity = glm::vec3(intensity);
    far.lights.push_back(lamp);
    const Tracer far_tracer(far);
    ASSERT_TRUE(hitDistancesAround(far_tracer, lamp.position, 64).empty());
    EXPECT_NEAR(estimateMaxRadiance(far_tracer), intensity / 1e6 / kPi, 1e-5 * intensity / 1e6 / kPi);
}

/// Only the emission of materials the scene's triangles use sets the scale. A material of strength
/// 1e20 that no triangle uses (unused in the file, or its only triangle dropped as degenerate) put
/// a furnace lit at 1 below one step: a cache of zeros, rendered at 2.
TEST(FixedPoint, AnEmissiveMaterialNoTriangleUsesDoesNotSetTheScale) {
    Scene room = roomWithPointLight(3.0f, 0.0f);
    room.lights.clear();
    room.materials[0].emissive = glm::vec3(1.0f);
    const double lit_at_one = estimateMaxRadiance(Tracer(room));
    EXPECT_EQ(lit_at_one, 1.0);
    Material unused;
    unused.emissive = glm::vec3(1.0f);
    unused.emissive_strength = 1e20f;
    room.materials.push_back(unused);
    EXPECT_EQ(estimateMaxRadiance(Tracer(room)), lit_at_one);
    room.triangle_materials.back() = 1;  // used by one triangle: it counts
    EXPECT_EQ(estimateMaxRadiance(Tracer(room)), double(1e20f));
}

/// A clamp happens only where radiance is 2^22 times the brightest the scale was chosen for;
/// the warning says so with the figures, instead of blaming "extreme emission" (which the scale
/// follows).
TEST(FixedPoint, ClampedDepositsAreExplainedWithTheCeilingAndTheScale) {
    const double scale = SharcCache::chooseRadianceScale(1.0);  // 1 at 2^40 steps: one deposit holds 2^22
    SharcCache cache(oneVoxelSettings(), scale);
    cache.commit(std::vector<Deposit>(3, Deposit{kKey, glm::vec3(float(std::ldexp(1.0, 23))), 1}));
    EXPECT_EQ(cache.numerics().clamped_deposits, 3u);
    const StabilityReport report = makeStabilityReport(cache, UpdateCounters{}, glm::vec3(0.0f), glm::vec3(1.0f), {1});
    const std::string expected =
        "3 deposits carried radiance above 4.19e+06, the most one deposit holds (2^62 fixed-point steps at scale "
        "1.09951e+12, which puts 1, at least the brightest radiance the scene's emission, sky and punctual lights "
        "give, at 2^40 steps), and were clamped, removing 50% of the deposited energy";
    const bool warned = std::any_of(report.warnings.begin(), report.warnings.end(), [&](const std::string& w) {
        return w.find(expected) != std::string::npos && w.find("extreme emission") == std::string::npos;
    });
    EXPECT_TRUE(warned) << testing::PrintToString(report.warnings);
}

/// Emission near float32's largest value overflows where a path adds light to it or carries it:
/// the warning said "a material, light or sky produced them", and now names the brightness.
TEST(FixedPoint, NonFiniteRadianceNearFloat32sLargestIsBlamedOnTheBrightness) {
    UpdateCounters update;
    update.non_finite = 2;
    const auto warning = [&](double brightest) {
        const SharcCache cache(oneVoxelSettings(), SharcCache::chooseRadianceScale(brightest));
        const StabilityReport report = makeStabilityReport(cache, update, glm::vec3(0.0f), glm::vec3(1.0f), {1});
        for (const std::string& w : report.warnings)
            if (w.find("NaN/Inf") != std::string::npos) return w;
        return std::string("(none)");
    };
    EXPECT_EQ(warning(3e38),
              "2 NaN/Inf radiance values were dropped (the cache holds none): the scene's brightest radiance, up to "
              "3.4e+38, is within 2^20 of float32's largest (3.4e+38), and radiance that adds to it or carries it "
              "overflows; scale the scene's emission down");
    EXPECT_EQ(warning(1.0),
              "2 NaN/Inf radiance values were dropped (a material, light or sky produced them); the "
              "cache holds none");
}

/// 1024 deposits of 2^52 fixed-point units (2^12 times the brightest emission) sum to 2^62;
/// 2^12 deposits of 2^62 sum to 2^74, past the 64-bit word: the carry keeps it exact up to 2^72.
TEST(FixedPoint, SumsPastSixtyFourBitsCarryInsteadOfWrapping) {
    const double scale = SharcCache::chooseRadianceScale(1.0);
    SharcCache cache(oneVoxelSettings(), scale);
    const float bright = float(std::ldexp(1.0, 61) / scale);  // 2^61 units, below the 2^62 ceiling
    constexpr int kDeposits = 100;                             // 100 x 2^61 = 2^67.6
    cache.commit(std::vector<Deposit>(kDeposits, Deposit{kKey, glm::vec3(bright), 1}));
    cache.resolve(0);
    const ResolvedEntry* e = cache.findResolved(kKey);
    ASSERT_NE(e, nullptr);
    EXPECT_FLOAT_EQ(e->mean.x, bright);
    EXPECT_EQ(cache.numerics().saturated_sums, 0u);
    EXPECT_EQ(cache.numerics().clamped_deposits, 0u);
}

/// Past 2^72 the sum saturates (counted) instead of wrapping to a small value.
TEST(FixedPoint, SumBeyondItsCeilingSaturatesAndIsCounted) {
    const double scale = SharcCache::chooseRadianceScale(1.0);
    SharcCache cache(oneVoxelSettings(), scale);
    const float ceiling_deposit = float(std::ldexp(1.0, 62) / scale);
    constexpr int kDeposits = 2000;  // 2000 x 2^62 > 2^72
    cache.commit(std::vector<Deposit>(kDeposits, Deposit{kKey, glm::vec3(ceiling_deposit), 1}));
    cache.resolve(0);
    const ResolvedEntry* e = cache.findResolved(kKey);
    ASSERT_NE(e, nullptr);
    EXPECT_GT(cache.numerics().saturated_sums, 0u);
    EXPECT_TRUE(std::isfinite(e->mean.x));
    // The ceiling (2^72 units over 2000 samples), never a wrapped, small value.
    EXPECT_NEAR(e->mean.x, std::ldexp(1.0, 72) / scale / kDeposits, 1e-6 * e->mean.x);
}

}  // namespace
}  // namespace sharcbake::stability
