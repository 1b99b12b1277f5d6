// SPDX-License-Identifier: Apache-2.0
// Voxel materials (the cache's VMAT section) on a baked Cornell box, read the way an engine built
// with SHARC_MATERIAL_DEMODULATION and SHARC_SEPARATE_EMISSIVE reads them: at a hit, the stored
// value times the hit's demodulation factor, plus the hit's emission. Where one material fills
// the voxel that is the plain baked radiance (fp16 rounding apart); over the scene's surface the
// demodulated reads average to the plain radiance within 1%, and with the emission apart within
// the few percent that coarse voxels mixing the lamp and the ceiling add.
#include "sharc/voxel_materials.h"
#include "sharc/baker.h"
#include "sharc/camera_path.h"
#include "sharcbake/cache_file.h"
#include "sharcbake/runtime.h"
#include "sharcbake/scene_loader.h"
#include "test_bake_scene.h"
#include "tracing/lights.h"
#include "tracing/surface.h"
#include "tracing/surface_points.h"
#include "tracing/tracer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

namespace sharcbake {
namespace {

Float3 toFloat3(glm::vec3 v) { return Float3{v.x, v.y, v.z}; }

TEST(VoxelMaterials, ADemodulatingEngineReadsThePlainRadianceOfABakedCornellBox) {
    const TestBakeScene bake("cornell_box");
    const Scene& scene = bake.scene;
    BakeSettings settings;
    settings.width = settings.height = 96;
    settings.sharc.grid.capacity = 1u << 18;
    const std::unique_ptr<Baker> baker = bake.makeBaker(settings);
    for (uint32_t i = 0; i < 32; ++i) baker->runIteration();
    CacheData data = toCacheData(baker->cache());
    ASSERT_GT(data.voxels.size(), 1000u);
    VoxelMaterialStats stats;
    data.voxel_materials = computeVoxelMaterials(scene, data, &stats);
    EXPECT_EQ(stats.voxels_from_scene_mean, 0u);
    EXPECT_LT(stats.voxels_from_coarser, data.voxels.size() / 10) << "most voxels have their own surface points";

    std::vector<uint8_t> bytes;
    std::string message;
    ASSERT_EQ(encodeCacheFile(data, &bytes, &message), CacheFileStatus::kOk) << message;
    CacheView view;
    ASSERT_EQ(CacheView::openMemory(bytes.data(), bytes.size(), &view, nullptr), CacheFileStatus::kOk);
    GpuBufferOptions options;
    GpuInsertList plain, engine, demodulated;
    ASSERT_EQ(view.gpuInsertList(options, &plain, nullptr), CacheFileStatus::kOk);
    options.build.material_demodulation = true;
    ASSERT_EQ(view.gpuInsertList(options, &demodulated, nullptr), CacheFileStatus::kOk);
    options.build.separate_emissive = true;
    ASSERT_EQ(view.gpuInsertList(options, &engine, nullptr), CacheFileStatus::kOk);

    // Hits spread by area (other points than the bake's means used), at every level present.
    const std::vector<SurfacePoint> hits = sampleSurfacePoints(scene, 20000, 11);
    const HashGridParameters grid = data.gridParameters();
    glm::dvec3 read_sum{0.0}, demodulated_sum{0.0}, plain_sum{0.0};
    uint64_t found = 0, single_material = 0, single_material_exact = 0, lamp_hits = 0;
    for (const SurfacePoint& p : hits) {
        const ShadingMaterial material =
            evaluateMaterial(scene, makeSurfacePoint(scene, p.triangle, p.barycentrics.x, p.barycentrics.y));
        const glm::vec3 factor = demodulationFactor(material);
        lamp_hits += glm::length(material.emission) > 0.0f ? 1 : 0;
        for (const CacheLevel& level : view.levels()) {
            const uint64_t index =
                view.findKey(hashGridKeyAtLevel(toFloat3(p.position), toFloat3(p.normal), level.level, grid));
            if (index == view.voxelCount()) continue;
            ++found;
            const CacheVoxelMaterial voxel = view.voxelMaterial(index);
            bool one_material = true, exact = true;
            for (int c = 0; c < 3; ++c) {
                const double stored = halfToFloat(engine.values[index].radiance[c]);
                const double read = stored * factor[c] + material.emission[c];
                const double expected = halfToFloat(plain.values[index].radiance[c]);
                read_sum[c] += read;
                demodulated_sum[c] += halfToFloat(demodulated.values[index].radiance[c]) * factor[c];
                plain_sum[c] += expected;
                one_material = one_material && std::abs(voxel.demodulation[c] - factor[c]) < 1e-4f * factor[c] &&
                               std::abs(voxel.emission[c] - material.emission[c]) < 1e-4f;
                exact = exact && std::abs(read - expected) <= 2e-3 * expected + 1e-6;
            }
            single_material += one_material ? 1 : 0;
            single_material_exact += one_material && exact ? 1 : 0;
        }
    }
    ASSERT_GT(lamp_hits, 10u) << "the lamp is sampled";
    EXPECT_GT(found, hits.size() * 4) << "hits find voxels at several levels";
    EXPECT_GT(single_material, found / 2) << "most voxels hold one material";
    EXPECT_EQ(single_material_exact, single_material) << "one material: the read is the plain radiance";
    for (int c = 0; c < 3; ++c) {
        // Demodulation alone: the reads average to the radiance (the factor's voxel mean is by
        // area, as the hits are).
        EXPECT_NEAR(demodulated_sum[c] / plain_sum[c], 1.0, 0.01) << "channel " << c;
        // With the emission kept apart, coarse voxels that hold the lamp and the ceiling around it
        // read a few percent bright: the emission's mean is by area, the baked radiance by the
        // bake's hits, which see the lamp less than its area (measured +3.5% to +4.6%; the
        // engine guide states it).
        EXPECT_GT(read_sum[c] / plain_sum[c], 0.99) << "channel " << c;
        EXPECT_LT(read_sum[c] / plain_sum[c], 1.06) << "channel " << c;
    }
}

}  // namespace
}  // namespace sharcbake
