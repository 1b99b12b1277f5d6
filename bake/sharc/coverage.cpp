// SPDX-License-Identifier: Apache-2.0
#include "sharc/coverage.h"

#include "tracing/surface_points.h"

#include <algorithm>
#include <set>

namespace sharcbake {

std::vector<uint32_t> levelsPresent(const SharcCache& cache) {
    std::set<uint32_t> levels;
    const HashGridTable& table = cache.table();
    for (uint32_t slot = 0; slot < table.capacity(); ++slot) {
        const uint64_t key = table.keyAt(slot);
        if (key != kHashGridInvalidKey) levels.insert(decodeHashGridKey(key).level);
    }
    return {levels.begin(), levels.end()};
}

std::vector<uint32_t> levelsPresent(const CacheData& data) {
    std::set<uint32_t> levels;
    for (const CacheVoxel& v : data.voxels) levels.insert(decodeHashGridKey(v.key).level);
    return {levels.begin(), levels.end()};
}

CoverageReport measureCoverage(const Scene& scene, const SharcCache& cache, const std::vector<uint32_t>& levels,
                               uint32_t points, const DepositLevels* deposit_levels) {
    CoverageReport report;
    if (scene.empty() || points == 0) return report;
    report.total_area = surfaceArea(scene);
    const HashGridParameters& grid = cache.settings().grid;

    // A voxel with samples, of the key `keyOf(position, normal)` gives, on either side. Paths shade
    // both sides of every surface (a single-sided one only emits from its front) and SHaRC keys
    // the normal turned towards the ray: a room modelled from a cube, its normals out, is
    // reached on the backs of its single-sided walls alone. A point is one point of surface
    // whichever side was reached, double-sided or not (the outside of a closed room faces the
    // void, where no path comes from).
    const auto reached = [&](const SurfacePoint& point, const auto& keyOf) {
        const auto has_voxel = [&](glm::vec3 n) {
            const ResolvedEntry* e = cache.findResolved(keyOf(point.position, n));
            return e && e->weight > 0.0;
        };
        return has_voxel(point.normal) || has_voxel(-point.normal);
    };
    const auto reachedAt = [&](const SurfacePoint& point, uint32_t level) {
        return reached(point, [&](glm::vec3 p, glm::vec3 n) {
            return hashGridKeyAtLevel(Float3{p.x, p.y, p.z}, Float3{n.x, n.y, n.z}, level, grid);
        });
    };
    // At the level the bake deposits into; the bake camera's position only matters for the
    // `bake-camera` region, which callers leave out.
    const auto reachedByDeposits = [&](const SurfacePoint& point) {
        return reached(point, [&](glm::vec3 p, glm::vec3 n) {
            return deposit_levels->key(p, n, Float3{0.0f, 0.0f, 0.0f});
        });
    };
    const uint32_t finest = levels.empty() ? 0 : *std::min_element(levels.begin(), levels.end());
    uint32_t unreached = 0, unreached_finest = 0, unreached_deposit = 0;
    const std::vector<SurfacePoint> surface = sampleSurfacePoints(scene, points);
    for (const SurfacePoint& point : surface) {
        if (deposit_levels && !reachedByDeposits(point)) ++unreached_deposit;
        if (finest != 0 && reachedAt(point, finest)) continue;  // then at some level too
        ++unreached_finest;
        if (std::none_of(levels.begin(), levels.end(), [&](uint32_t level) { return reachedAt(point, level); })) {
            ++unreached;
        }
    }
    report.points = uint32_t(surface.size());
    report.finest_level = finest;
    report.unreached_area = surface.empty() ? 0.0 : double(unreached) / double(surface.size());
    report.unreached_finest_area = surface.empty() ? 0.0 : double(unreached_finest) / double(surface.size());
    report.unreached_deposit_area = surface.empty() ? 0.0 : double(unreached_deposit) / double(surface.size());
    return report;
}

}  // namespace sharcbake
