// SPDX-License-Identifier: Apache-2.0
#include "coverage.h"

#include "distribution.h"
#include "sampling.h"

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

CoverageReport measureCoverage(const Scene& scene, const SharcCache& cache, const std::vector<uint32_t>& levels,
                               uint32_t points) {
    CoverageReport report;
    if (scene.empty() || points == 0) return report;
    std::vector<float> areas(scene.triangles.size());
    for (size_t t = 0; t < scene.triangles.size(); ++t) {
        const glm::uvec3 tri = scene.triangles[t];
        areas[t] = 0.5f * glm::length(glm::cross(scene.positions[tri.y] - scene.positions[tri.x],
                                                 scene.positions[tri.z] - scene.positions[tri.x]));
        report.total_area += double(areas[t]);
    }
    const Distribution1D by_area(areas);
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
    for (uint32_t i = 0; i < points; ++i) {
        // Stratified in the area CDF, then uniform in the triangle.
        const float u = (float(i) + bitsToUnitFloat(hashUint32(i * 3 + 1))) / float(points);
        const uint32_t t = uint32_t(by_area.sampleDiscrete(std::min(u, kOneMinusEpsilon)));
        const glm::vec2 b = sampleUniformTriangle({bitsToUnitFloat(hashUint32(i * 3 + 2)),
                                                   bitsToUnitFloat(hashUint32(i * 3 + 3))});
        const glm::uvec3 tri = scene.triangles[t];
        const glm::vec3 p0 = scene.positions[tri.x], p1 = scene.positions[tri.y], p2 = scene.positions[tri.z];
        const glm::vec3 p = (1.0f - b.x - b.y) * p0 + b.x * p1 + b.y * p2;
        const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
        const bool double_sided = scene.materials[scene.triangle_materials[t]].double_sided;
        if (!reached(p, n) && !(double_sided && reached(p, -n))) ++unreached;
    }
    report.points = points;
    report.unreached_area = double(unreached) / double(points);
    return report;
}

}  // namespace sharcbake
