// SPDX-License-Identifier: Apache-2.0
#include "sharc/voxel_materials.h"

#include "sharc/coverage.h"
#include "sharc/grid_points.h"
#include "sharcbake/sdk_target.h"
#include "tracing/surface_points.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>

namespace sharcbake {
namespace {

constexpr uint32_t kMaxPoints = 1u << 23;
constexpr uint32_t kMinPoints = 1u << 14;
constexpr uint32_t kPointsPerBatch = 1u << 16;
constexpr uint64_t kNoVoxel = ~uint64_t(0);

/// Running sums of one voxel (double: millions of points).
struct VoxelSums {
    glm::dvec3 emission{0.0};
    glm::dvec3 demodulation{0.0};
    uint64_t points = 0;
};

uint64_t voxelIndex(const std::vector<CacheVoxel>& voxels, uint64_t key) {
    const auto it = std::lower_bound(voxels.begin(), voxels.end(), key,
                                     [](const CacheVoxel& v, uint64_t k) { return v.key < k; });
    return it != voxels.end() && it->key == key ? uint64_t(it - voxels.begin()) : kNoVoxel;
}

/// Which sides of the points a pass keys.
enum class Sides : uint8_t {
    /// The front, and the back of double-sided materials: the sides glTF shows.
    Shown,
    /// The back of single-sided materials, into voxels no shown side reached: a room modelled
    /// from a cube, its normals out, is seen from inside on the backs of its walls.
    HiddenIntoEmptyVoxels,
};

/// Adds a batch of points: their keys (the pass's sides x every level) are looked up in parallel,
/// then added in point order, so the sums do not depend on the thread count. A hidden pass adds
/// only to voxels whose sums are still empty (`shown_points`: the shown pass's counts).
void addBatch(const Scene& scene, const CacheData& data, const std::vector<uint32_t>& levels,
              const std::vector<SurfacePoint>& points, size_t begin, size_t end, Sides sides,
              const std::vector<uint64_t>* shown_points, std::vector<VoxelSums>& sums, glm::dvec3& factor_sum) {
    const HashGridParameters grid = data.gridParameters();
    const size_t per_point = 2 * levels.size();
    std::vector<uint64_t> voxel(per_point * (end - begin), kNoVoxel);
    std::vector<std::array<glm::vec3, 2>> values(end - begin);  // emission (either side), demodulation factor
    tbb::parallel_for(tbb::blocked_range<size_t>(begin, end), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i < range.end(); ++i) {
            const SurfacePoint& p = points[i];
            if (sides == Sides::HiddenIntoEmptyVoxels && p.double_sided) continue;
            const SurfaceHit hit = makeSurfacePoint(scene, p.triangle, p.barycentrics.x, p.barycentrics.y);
            const ShadingMaterial material = evaluateMaterial(scene, hit);
            // A single-sided surface emits from its front only.
            const glm::vec3 emission = sides == Sides::Shown ? material.emission : glm::vec3(0.0f);
            values[i - begin] = {emission, demodulationFactor(material)};
            // The back of a single-sided surface is not meant to be seen (glTF culls it): counting
            // it where a shown side reached would mix, at coarse levels, the outside of a room's
            // wall into the voxel of the opposite wall's inside, which faces the same way.
            const size_t first = sides == Sides::Shown ? 0 : 1;
            const size_t last = sides == Sides::Shown ? (p.double_sided ? 2u : 1u) : 2u;
            for (size_t side = first; side < last; ++side) {
                const Float3 normal = toFloat3(side == 0 ? p.normal : -p.normal);
                for (size_t l = 0; l < levels.size(); ++l) {
                    const uint64_t key = hashGridKeyAtLevel(toFloat3(p.position), normal, levels[l], grid);
                    voxel[(i - begin) * per_point + side * levels.size() + l] = voxelIndex(data.voxels, key);
                }
            }
        }
    });
    for (size_t i = begin; i < end; ++i) {
        const std::array<glm::vec3, 2>& v = values[i - begin];
        if (sides == Sides::Shown) factor_sum += glm::dvec3(v[1]);
        for (size_t k = 0; k < per_point; ++k) {
            const uint64_t index = voxel[(i - begin) * per_point + k];
            if (index == kNoVoxel) continue;
            if (shown_points && (*shown_points)[size_t(index)] > 0) continue;
            VoxelSums& s = sums[size_t(index)];
            s.emission += glm::dvec3(v[0]);
            s.demodulation += glm::dvec3(v[1]);
            ++s.points;
        }
    }
}

CacheVoxelMaterial meansOf(const VoxelSums& s) {
    CacheVoxelMaterial m;
    for (int c = 0; c < 3; ++c) {
        m.emission[c] = float(s.emission[c] / double(s.points));
        m.demodulation[c] = float(s.demodulation[c] / double(s.points));
    }
    return m;
}

}  // namespace

glm::vec3 demodulationFactor(const ShadingMaterial& material) {
    const glm::vec3 diffuse = (1.0f - material.metallic) * material.base_color;
    // The dielectric layer's F0 as the BSDF has it (KHR_materials_ior and _specular), mixed with
    // the metal's (the base colour) by metallic.
    const float r = (material.ior - 1.0f) / (material.ior + 1.0f);
    const glm::vec3 dielectric_f0 =
        glm::min(glm::vec3(r * r) * material.specular_color, glm::vec3(1.0f)) * material.specular_weight;
    const glm::vec3 f0 = glm::mix(dielectric_f0, material.base_color, material.metallic);
    const Float3 m = sharcDemodulationFactor(toFloat3(diffuse), toFloat3(f0));
    return {m.x, m.y, m.z};
}

std::vector<CacheVoxelMaterial> computeVoxelMaterials(const Scene& scene, const CacheData& data,
                                                      VoxelMaterialStats* stats, uint32_t points_per_voxel) {
    std::vector<CacheVoxelMaterial> result(data.voxels.size());
    if (data.voxels.empty()) return result;
    const uint64_t wanted = uint64_t(points_per_voxel) * data.voxels.size();
    const uint32_t count = uint32_t(std::clamp<uint64_t>(wanted, kMinPoints, kMaxPoints));
    const std::vector<SurfacePoint> points = sampleSurfacePoints(scene, count, /*seed=*/0x564d4154u);
    const std::vector<uint32_t> levels = levelsPresent(data);
    std::vector<VoxelSums> sums(data.voxels.size());
    glm::dvec3 factor_sum{0.0};
    for (size_t begin = 0; begin < points.size(); begin += kPointsPerBatch) {
        addBatch(scene, data, levels, points, begin, std::min(points.size(), begin + kPointsPerBatch), Sides::Shown,
                 nullptr, sums, factor_sum);
    }
    // Voxels the shown sides left empty may be the insides of rooms wound outwards.
    std::vector<uint64_t> shown_points(sums.size());
    for (size_t i = 0; i < sums.size(); ++i) shown_points[i] = sums[i].points;
    for (size_t begin = 0; begin < points.size(); begin += kPointsPerBatch) {
        addBatch(scene, data, levels, points, begin, std::min(points.size(), begin + kPointsPerBatch),
                 Sides::HiddenIntoEmptyVoxels, &shown_points, sums, factor_sum);
    }
    VoxelMaterialStats local;
    local.points = points.size();
    CacheVoxelMaterial scene_mean;
    for (int c = 0; c < 3; ++c) {
        scene_mean.demodulation[c] = points.empty() ? 1.0f : float(factor_sum[c] / double(points.size()));
    }
    const HashGridKeyDecoder decoder(data.gridParameters(), data.grid_anchor);
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        if (sums[i].points > 0) {
            result[i] = meansOf(sums[i]);
            continue;
        }
        // A sliver of surface no point landed in: the nearest coarser voxel that has points.
        uint64_t key = decoder.coarserKey(data.voxels[i].key);
        uint64_t index = kNoVoxel;
        while (key != 0 && (index = voxelIndex(data.voxels, key), index == kNoVoxel || sums[size_t(index)].points == 0)) {
            key = decoder.coarserKey(key);
        }
        if (key != 0 && index != kNoVoxel) {
            result[i] = meansOf(sums[size_t(index)]);
            ++local.voxels_from_coarser;
        } else {
            result[i] = scene_mean;
            ++local.voxels_from_scene_mean;
        }
    }
    if (stats) *stats = local;
    return result;
}

}  // namespace sharcbake
