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
                               uint32_t points) {
    CoverageReport report;
    if (scene.empty() || points == 0) return report;
    report.total_area = surfaceArea(scene);
    const HashGridParameters& grid = cache.settings().grid;

    auto reached = [&](glm::vec3 p, glm::vec3 n) {
        for (uint32_t level : levels) {
            const ResolvedEntry* e =
                cache.findResolved(hashGridKeyAtLevel(Float3{p.x, p.y, p.z}, Float3{n.x, n.y, n.z}, level, grid));
            if (e && e->weight > 0.0) return true;
        }
        return false;
    };
    uint32_t unreached = 0;
    const std::vector<SurfacePoint> surface = sampleSurfacePoints(scene, points);
    for (const SurfacePoint& point : surface) {
        if (!reached(point.position, point.normal) && !(point.double_sided && reached(point.position, -point.normal))) {
            ++unreached;
        }
    }
    report.points = uint32_t(surface.size());
    report.unreached_area = surface.empty() ? 0.0 : double(unreached) / double(surface.size());
    return report;
}

}  // namespace sharcbake
