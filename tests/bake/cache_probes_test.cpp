// SPDX-License-Identifier: Apache-2.0
// The probe reference of `bake --report`: its references are right where the answer is known,
// its noise is taken out, and a cache biased in one region is caught in that region.
#include "reports/cache_probes.h"
#include "reports/convergence_report.h"
#include "sharc/baker.h"
#include "sharc/cache_query.h"
#include "sharc/camera_path.h"
#include "sharcbake/scene_loader.h"
#include "test_bake_scene.h"
#include "tracing/lights.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace sharcbake {
namespace {

/// A short bake with coarse voxels, as the furnace tests make it.
struct ShortBake {
    Scene scene;
    std::unique_ptr<Tracer> tracer;
    std::unique_ptr<LightSampler> lights;
    std::unique_ptr<CameraPath> path;
    CacheData data;

    ShortBake(const std::string& name, uint32_t iterations, float scene_scale = 5.0f, int resolution = 96) {
        scene = loadGltf(scenePath(name));
        tracer = std::make_unique<Tracer>(scene);
        lights = std::make_unique<LightSampler>(*tracer);
        path = std::make_unique<CameraPath>(exploringCameraPath(*tracer, scene, 16, 3).value());
        BakeSettings settings;
        settings.width = settings.height = resolution;
        settings.sharc.grid.capacity = 1u << 18;
        settings.sharc.grid.scene_scale = scene_scale;
        Baker baker(*tracer, *lights, *path, settings, SharcCache::chooseRadianceScale(estimateMaxRadiance(*tracer)));
        for (uint32_t i = 0; i < iterations; ++i) baker.runIteration();
        data = toCacheData(baker.cache());
    }

    ProbeSettings probeSettings(uint32_t probes, uint32_t samples) const {
        ProbeSettings settings;
        settings.probes = probes;
        settings.reference_samples = samples;
        settings.view_position = scene.cameras.at(0).position;
        return settings;
    }
};

const ProbeRegionError* region(const ProbeMeasure& m, const std::string& name) {
    for (const ProbeRegionError& r : m.regions) {
        if (r.name == name) return &r;
    }
    return nullptr;
}

// In the rho = 0.9 furnace every surface leaves radiance 10. A cache that holds exactly 10 in
// every voxel is right everywhere, so what the probes measure is their references' own error:
// no bias beyond its interval, and a mean square that is only the references' noise, which
// the measure takes out. Then the half of the room below x = 0 is made 5% too bright: its
// octants show +5% and stand out, the others do not move.
TEST(CacheProbes, FurnaceReferencesAreExactAndABiasedRegionStandsOut) {
    ShortBake bake("furnace_rho090", 8);
    CacheData exact = bake.data;
    for (CacheVoxel& v : exact.voxels) v.radiance[0] = v.radiance[1] = v.radiance[2] = 10.0f;
    CacheData biased = exact;
    const HashGridParameters grid = biased.gridParameters();
    const float centre_x = 0.5f * (bake.scene.bounds_min.x + bake.scene.bounds_max.x);
    for (CacheVoxel& v : biased.voxels) {
        if (voxelCenter(v.key, grid).x < centre_x) v.radiance[0] = v.radiance[1] = v.radiance[2] = 10.5f;
    }
    CacheProbes probes(bake.scene, *bake.tracer, *bake.lights, bake.probeSettings(256, 256));
    ASSERT_TRUE(probes.enabled());
    const size_t exact_record = probes.record(BakedCache(exact, glm::vec3(0.0f)).view());
    const size_t biased_record = probes.record(BakedCache(biased, glm::vec3(0.0f)).view());
    const ProbeMeasure m = probes.measure(exact_record, exact_record);
    ASSERT_GE(m.view.probes, 128u);
    EXPECT_EQ(m.view.leaks, 0u);
    EXPECT_GT(m.view.reference_noise, 0.0);
    EXPECT_LT(std::abs(m.view.relative_bias), std::max(m.view.relative_bias_ci, 0.005)) << m.view.relative_bias;
    // (C - R)^2 less Var(R) has expectation 0 here: within its interval, and far below the noise.
    EXPECT_LT(std::abs(m.view.relative_mse), m.view.relative_mse_ci + 1e-6) << m.view.relative_mse;
    EXPECT_LT(std::abs(m.view.relative_mse), 0.5 * m.view.reference_noise);
    for (const ProbeRegionError& r : m.regions) EXPECT_FALSE(r.standsOut()) << r.name;

    const ProbeMeasure b = probes.measure(biased_record, exact_record);
    int standing_out = 0;
    for (const ProbeRegionError& r : b.regions) {
        if (r.name.rfind("octant x-", 0) == 0) {
            EXPECT_NEAR(r.error.relative_bias, 0.05, std::max(0.01, r.error.relative_bias_ci)) << r.name;
            EXPECT_TRUE(r.standsOut()) << r.name;
            ++standing_out;
        } else if (r.name.rfind("octant x+", 0) == 0) {
            EXPECT_LT(std::abs(r.error.relative_bias), r.error.relative_bias_ci + 0.005) << r.name;
            EXPECT_FALSE(r.standsOut()) << r.name;
        }
    }
    EXPECT_GE(standing_out, 2);
    // The references are computed once and kept.
    const uint64_t referenced = probes.referencedPoints();
    EXPECT_EQ(probes.measure(exact_record, exact_record).view.relative_mse, m.view.relative_mse);
    EXPECT_EQ(probes.referencedPoints(), referenced);
}

// A baked Cornell box whose red wall (x = -0.5) is made 5% too bright: the red region's signed
// bias rises by 5% of the cache's value (C / R near 1 + the region's own bias), measured tightly
// enough to tell 5% from nothing, and the green wall opposite does not move.
TEST(CacheProbes, ACornellBoxBiasedByFivePercentOnOneWallShowsIt) {
    ShortBake bake("cornell_box", 256, 50.0f, 256);
    CacheData biased = bake.data;
    const HashGridParameters grid = biased.gridParameters();
    for (CacheVoxel& v : biased.voxels) {
        if (voxelCenter(v.key, grid).x < -0.4f) {
            for (float& c : v.radiance) c *= 1.05f;
        }
    }
    CacheProbes probes(bake.scene, *bake.tracer, *bake.lights, bake.probeSettings(2048, 256));
    const size_t unbiased_record = probes.record(BakedCache(bake.data, glm::vec3(0.0f)).view());
    const size_t biased_record = probes.record(BakedCache(biased, glm::vec3(0.0f)).view());
    const ProbeMeasure before = probes.measure(unbiased_record, unbiased_record);
    const ProbeMeasure after = probes.measure(biased_record, unbiased_record);

    const ProbeRegionError* red_before = region(before, "material 'red'");
    const ProbeRegionError* red_after = region(after, "material 'red'");
    const ProbeRegionError* green_before = region(before, "material 'green'");
    const ProbeRegionError* green_after = region(after, "material 'green'");
    ASSERT_TRUE(red_before && red_after && green_before && green_after);
    for (const ProbeRegionError& r : before.regions) {
        std::printf("%s: %llu probes, bias %+.4f +- %.4f, RMS %.3f\n", r.name.c_str(),
                    (unsigned long long)r.error.probes, r.error.relative_bias, r.error.relative_bias_ci,
                    r.error.rmsError());
    }
    EXPECT_GE(red_after->error.probes, 200u);
    const double shift = red_after->error.relative_bias - red_before->error.relative_bias;
    EXPECT_NEAR(shift, 0.05 * (1.0 + red_before->error.relative_bias), 0.01) << shift;
    EXPECT_LT(red_after->error.relative_bias_ci, 0.025) << "too few probes to tell a 5% bias from none";
    EXPECT_TRUE(red_after->standsOut()) << red_after->error.relative_bias;
    EXPECT_EQ(green_after->error.relative_bias, green_before->error.relative_bias);
}

// Regions are named by material name where it is the material's own, and by index too where
// the name is shared or empty: a CAD export with ten materials called "Material_20" printed
// "material 'Material_20' stands out" three times, with different numbers.
TEST(CacheProbes, MaterialsSharingANameGetRegionsNamedApart) {
    ShortBake bake("cornell_box", 8);
    uint32_t red = 0, green = 0;
    for (uint32_t i = 0; i < bake.scene.materials.size(); ++i) {
        if (bake.scene.materials[i].name == "red") red = i;
        if (bake.scene.materials[i].name == "green") green = i;
    }
    ASSERT_NE(red, green);
    bake.scene.materials[red].name = bake.scene.materials[green].name = "Material_20";
    CacheProbes probes(bake.scene, *bake.tracer, *bake.lights, bake.probeSettings(256, 16));
    const size_t record = probes.record(BakedCache(bake.data, glm::vec3(0.0f)).view());
    const ProbeMeasure m = probes.measure(record, record);
    EXPECT_TRUE(region(m, "material " + std::to_string(red) + " 'Material_20'")) << red;
    EXPECT_TRUE(region(m, "material " + std::to_string(green) + " 'Material_20'")) << green;
    EXPECT_FALSE(region(m, "material 'Material_20'"));
    EXPECT_TRUE(region(m, "material 'white'"));  // a name of its own alone
}

TEST(CacheProbes, NoProbesMeansNoWork) {
    ShortBake bake("furnace_rho050", 2);
    ProbeSettings settings = bake.probeSettings(0, 16);
    CacheProbes probes(bake.scene, *bake.tracer, *bake.lights, settings);
    EXPECT_FALSE(probes.enabled());
    const size_t record = probes.record(BakedCache(bake.data, glm::vec3(0.0f)).view());
    EXPECT_EQ(probes.measure(record, record).view.probes, 0u);
    EXPECT_EQ(probes.referencedPoints(), 0u);
}

// The summary called 16 iterations of the Cornell box "converged, more iterations would not help"
// (RMS 37% at 1.1x a floor of 33% fitted over early checkpoints) while 128 iterations reached 25%,
// and a model whose probes were 60% without a voxel converged too. The verdict now also asks
// whether the error still falls since half the iterations, and how many probes have no voxel.
TEST(ProbeVerdict, ConvergedOnlyWhenTheErrorStoppedFallingAndTheProbesHaveVoxels) {
    const auto row = [](uint32_t iteration, double mse, double ci, uint64_t probes, uint64_t not_live) {
        ConvergenceRow r;
        r.iteration = iteration;
        r.probes.emplace();
        r.probes->view.probes = probes;
        r.probes->view.not_live = not_live;
        r.probes->view.relative_mse = mse;
        r.probes->view.relative_mse_ci = ci;
        return r;
    };
    ProbeFloorFit fit;
    fit.floor_squared = 0.33 * 0.33;
    // The Cornell box's 16 iterations: 0.267 +- 0.107 at 8, 0.137 +- 0.059 at 16.
    std::vector<ConvergenceRow> falling = {row(2, 0.236, 0.059, 254, 2), row(4, 0.417, 0.104, 256, 0),
                                           row(8, 0.267, 0.107, 255, 0), row(11, 0.247, 0.104, 253, 0),
                                           row(16, 0.137, 0.059, 255, 0)};
    ProbeVerdict verdict = probeVerdict(falling, fit);
    EXPECT_FALSE(verdict.converged);
    EXPECT_NE(verdict.reason.find("still falls"), std::string::npos) << verdict.reason;
    EXPECT_NE(verdict.reason.find("at 8 iterations"), std::string::npos) << verdict.reason;

    // Flat since half the iterations, within the floor: converged.
    std::vector<ConvergenceRow> flat = {row(8, 0.125, 0.05, 255, 0), row(16, 0.115, 0.05, 255, 0)};
    verdict = probeVerdict(flat, fit);
    EXPECT_TRUE(verdict.converged) << verdict.reason;
    EXPECT_EQ(verdict.reason, "converged, more iterations would not help");

    // As flat, but 155 of 256 probes without a voxel.
    std::vector<ConvergenceRow> uncovered = {row(8, 0.125, 0.05, 101, 155), row(16, 0.115, 0.05, 101, 155)};
    verdict = probeVerdict(uncovered, fit);
    EXPECT_FALSE(verdict.converged);
    EXPECT_NE(verdict.reason.find("60.5% of the probes have no voxel yet"), std::string::npos) << verdict.reason;

    // Flat but well above the floor: the voxels' noise.
    fit.floor_squared = 0.1 * 0.1;
    verdict = probeVerdict(flat, fit);
    EXPECT_FALSE(verdict.converged);
    EXPECT_EQ(verdict.reason, "more iterations would still lower its noise");
}

}  // namespace
}  // namespace sharcbake
