// SPDX-License-Identifier: Apache-2.0
#include "tracing/lights.h"

#include "support/median.h"
#include "tracing/sampling.h"
#include "tracing/surface_points.h"
#include "tracing/tracer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unordered_map>
#include <utility>

namespace sharcbake {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Spatial selection (LightSampler(const Tracer&)).
/// The share of picks made by power alone at a point whose cell has shares. It bounds what a
/// light the shadow rays missed (a lamp seen only from a corner of the cell) can lose: its
/// variance grows at most 1 / kPowerShare times, while lights the cell does not see lose 3/4 of
/// the picks they took.
constexpr float kPowerShare = 0.25f;
/// The grid the shares are learned in: cubic cells, this many along the scene's longest axis.
constexpr uint32_t kCellsAlongLongest = 32;
/// Where the scene's cameras and its local lights (all but the sun and sky), with the surfaces
/// around them, lie within at most this part of the scene's longest extent, once widened by
/// kDetailMargin of their own extent on each side (and at least 1/kDetailSmallestMarginDivisor
/// of the scene), that box gets a detail grid of kCellsAlongLongest cells of its own: a flat of
/// lamp-lit rooms on a 2 km ground otherwise sits in one 62 m cell with the sunlit ground around it.
constexpr float kDetailMostOfScene = 0.5f;
constexpr float kDetailMargin = 0.25f;
constexpr float kDetailFarthestOfMedian = 4.0f;
constexpr uint32_t kDetailSmallestMarginDivisor = 1024;
/// Emissive triangles are grouped by connected piece, so a lamp of many triangles is one group
/// and its shares are measured, not guessed per triangle; a piece wider than two cells of a
/// grid this coarse is split by its cells.
constexpr uint32_t kEmitterCellsAlongLongest = 8;
/// Beyond this many pieces and point or spot lights, lights are grouped by that grid's cells.
constexpr size_t kMostLightGroups = 256;
/// Points spread over the surfaces by area, binned by cell; each cell measures from up to
/// kPointsPerCell of them, kSamplesPerPoint shadow rays each (its two sides in turn). Half as
/// many of each left renders of a flat with four lights up to 1.8 times noisier, and an open
/// scene under sun and sky 1.5 times (noisy shares are worse than power's where power is right).
constexpr uint32_t kLearningPoints = 1u << 18;
constexpr uint32_t kPointsPerCell = 16;
constexpr uint32_t kSamplesPerPoint = 32;
constexpr uint32_t kLearningSeed = 0x11947u;
/// Lights drawn per group in advance, which the measuring samples pick among.
constexpr uint32_t kDrawsPerGroup = 64;
/// A slot keeps its shares only where power's relative variance there (see below) is at least
/// this: in the benchmark's open scene every lit slot falls below it and every shadowed one
/// (1.6) above; rooms lit by a lamp of their own lie far above (10 and more).
constexpr double kPowerCloseEnough = 1.0;

/// Items 0..n-1 grouped by bucket (`bucket_of[i]` < `count`), each bucket in item order (a
/// counting sort): bucket b's items are items[first[b], first[b + 1]).
struct Buckets {
    std::vector<uint32_t> first;
    std::vector<uint32_t> items;
};
Buckets bucketsOf(const std::vector<uint32_t>& bucket_of, uint32_t count) {
    Buckets buckets;
    buckets.first.assign(size_t(count) + 1, 0u);
    for (const uint32_t b : bucket_of) ++buckets.first[b + 1];
    for (uint32_t b = 0; b < count; ++b) buckets.first[b + 1] += buckets.first[b];
    buckets.items.resize(bucket_of.size());
    std::vector<uint32_t> next(buckets.first.begin(), buckets.first.end() - 1);
    for (size_t i = 0; i < bucket_of.size(); ++i) buckets.items[next[bucket_of[i]]++] = uint32_t(i);
    return buckets;
}

glm::vec3 textureMean(const Texture& texture) {
    glm::dvec3 sum(0.0);
    const size_t count = texture.texelCount();
    for (size_t i = 0; i < count; ++i) sum += glm::dvec3(texture.texel(i));
    return count == 0 ? glm::vec3(1.0f) : glm::vec3(sum / double(count));
}

/// KHR_lights_punctual's recommended range cut-off, clamp(1 - (d/range)^4, 0, 1), times the
/// inverse square law: as close to it as a smooth cut-off allows (0.94 at half the range, 0.59 at
/// 0.8 of it). The squared window some engines use (UE4's) would darken a light to 0.64 of the
/// spec's at two thirds of its range; Blender exports EEVEE's "Custom Distance" as `range`.
float rangeWindow(float distance, float range) {
    if (range <= 0.0f) return 1.0f;
    const float ratio = distance / range;
    return glm::clamp(1.0f - ratio * ratio * ratio * ratio, 0.0f, 1.0f);
}

/// 1 - cos(angle), exact for small angles too: in float, the cosine of any angle below about
/// 3e-4 rad rounds to 1, and a narrow spot cone (glTF allows any outer angle above 0) would
/// have no width at all.
float oneMinusCos(float angle) {
    const float s = std::sin(0.5f * angle);
    return 2.0f * s * s;
}

/// KHR_lights_punctual's spot attenuation: squared linear ramp between the cone cosines. Kept in
/// 1 - cos terms (oneMinusCos; for unit vectors 1 - a.b = |a - b|^2 / 2), so a cone of a
/// microradian lights its disc instead of nothing. The extension's sample code floors the
/// ramp's width at 0.001 in cosine, which also darkens any cone narrower than 2.6 degrees;
/// here only a ramp of no width (inner = outer) becomes a hard edge.
float spotAttenuation(const PunctualLight& light, glm::vec3 light_to_point) {
    const float outer = oneMinusCos(light.outer_cone_angle);
    const float inner = oneMinusCos(light.inner_cone_angle);
    const glm::vec3 apart = light.direction - light_to_point;
    const float off_axis = 0.5f * glm::dot(apart, apart);
    if (!(off_axis < outer)) return 0.0f;
    if (!(outer - inner > 0.0f)) return 1.0f;
    const float t = glm::clamp((outer - off_axis) / (outer - inner), 0.0f, 1.0f);
    return t * t;
}

/// A light's selection power: its float32 product, or where that overflows, the same product in
/// double. Scenes whose powers fit float32, all ordinary ones, keep their float32 powers.
double selectionPower(float in_float, double in_double) {
    return std::isfinite(in_float) ? double(in_float) : in_double;
}

/// The powers as Distribution1D's float32 weights, which count infinity as no power: a 1e37
/// emitter of 100 m^2 (power 1.6e39) was never chosen. Selection depends only on the powers'
/// ratios, so where one is beyond float32, all are scaled by one power of two (exact) until the
/// largest fits.
std::vector<float> selectionWeights(std::vector<double> powers) {
    double largest = 0.0;
    for (const double p : powers)
        if (std::isfinite(p)) largest = std::max(largest, p);
    if (largest > double(std::numeric_limits<float>::max())) {
        const int shift = std::ilogb(largest) - 126;  // the largest lands in [2^126, 2^127)
        for (double& p : powers) p = std::ldexp(p, -shift);
    }
    return std::vector<float>(powers.begin(), powers.end());
}

}  // namespace

glm::vec2 directionToEquirect(glm::vec3 d) {
    const float u = 0.5f + std::atan2(d.z, d.x) * (0.5f * kInvPi);
    const float v = std::acos(glm::clamp(d.y, -1.0f, 1.0f)) * kInvPi;
    return {u - std::floor(u), v};
}

glm::vec3 equirectToDirection(glm::vec2 uv) {
    const float phi = (uv.x - 0.5f) * 2.0f * kPi;
    const float theta = uv.y * kPi;
    const float sin_theta = std::sin(theta);
    return {sin_theta * std::cos(phi), std::cos(theta), sin_theta * std::sin(phi)};
}

LightSampler::LightSampler(const Scene& scene) : scene_(scene) {
    std::vector<double> powers;  // one per entry: light selection is proportional to power
    const glm::vec3 extent = scene.bounds_max - scene.bounds_min;
    const float radius = std::max(0.5f * glm::length(extent), 1e-3f);
    // Lights at infinity deliver their power through the scene's bounding disk.
    const float disk_area = kPi * radius * radius;
    addAreaLights(powers);
    addPunctualLights(disk_area, powers);
    addSky(disk_area, powers);
    if (entries_.empty()) return;
    selection_ = Distribution1D(selectionWeights(std::move(powers)));
    for (size_t e = 0; e < entries_.size(); ++e) {
        if (entries_[e].kind == Kind::Triangle) triangle_entry_[entries_[e].index] = uint32_t(e);
        if (entries_[e].kind == Kind::Sky) sky_entry_ = e;
    }
}

LightSampler::LightSampler(const Tracer& tracer) : LightSampler(tracer.scene()) {
    const auto start = std::chrono::steady_clock::now();
    groupLights();
    if (spatial_.groups > 1) learnWhereLightArrives(tracer);
    spatial_.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

void LightSampler::groupLights() {
    if (entries_.size() < 2) {
        spatial_.groups = uint32_t(entries_.size());
        return;
    }
    // Emitters are grouped by connected piece (triangles sharing a vertex or its position: a lamp
    // exported with split vertices is still one piece); a piece wider than two cells of a coarse
    // grid (a strip of lights along a corridor, a glowing enclosure) is split by those cells.
    std::vector<uint32_t> emitters;  // entries of emissive triangles
    for (size_t e = 0; e < entries_.size(); ++e)
        if (entries_[e].kind == Kind::Triangle) emitters.push_back(uint32_t(e));
    std::vector<uint32_t> parent(emitters.size());
    for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
    const auto root = [&](uint32_t i) {
        while (parent[i] != i) i = parent[i] = parent[parent[i]];
        return i;
    };
    {
        // Joined through shared vertex indices, then through equal positions (sorted together).
        std::vector<uint32_t> first_with_vertex(scene_.positions.size(), kNoEntry);
        std::vector<std::pair<std::array<float, 3>, uint32_t>> positions;  // one per vertex used
        for (uint32_t i = 0; i < emitters.size(); ++i) {
            const glm::uvec3 tri = scene_.triangles[entries_[emitters[i]].index];
            for (const uint32_t v : {tri.x, tri.y, tri.z}) {
                if (first_with_vertex[v] != kNoEntry) {
                    parent[root(i)] = root(first_with_vertex[v]);
                    continue;
                }
                first_with_vertex[v] = i;
                const glm::vec3 p = scene_.positions[v];
                positions.push_back({{p.x, p.y, p.z}, i});
            }
        }
        std::sort(positions.begin(), positions.end());
        for (size_t k = 1; k < positions.size(); ++k)
            if (positions[k].first == positions[k - 1].first)
                parent[root(positions[k].second)] = root(positions[k - 1].second);
    }
    std::vector<glm::vec3> piece_min(emitters.size(), glm::vec3(kInfinity)),
        piece_max(emitters.size(), glm::vec3(-kInfinity));
    std::vector<glm::vec3> centroids(emitters.size());
    for (uint32_t i = 0; i < emitters.size(); ++i) {
        const glm::uvec3 tri = scene_.triangles[entries_[emitters[i]].index];
        const glm::vec3 a = scene_.positions[tri.x], b = scene_.positions[tri.y], c = scene_.positions[tri.z];
        centroids[i] = (a + b + c) * (1.0f / 3.0f);
        const uint32_t r = root(i);
        piece_min[r] = glm::min(piece_min[r], glm::min(a, glm::min(b, c)));
        piece_max[r] = glm::max(piece_max[r], glm::max(a, glm::max(b, c)));
    }
    const LightSelectionGrid emitter_cells(scene_.bounds_min, scene_.bounds_max, kEmitterCellsAlongLongest);
    const float split_wider_than = 2.0f * emitter_cells.cellSize();
    // A key per entry: its piece (and cell, where split), its punctual light, or the sky. Where
    // there are more than kMostLightGroups pieces and point or spot lights (a facade of lit
    // windows, strings of fairy lights), they are grouped by the coarse grid's cells instead:
    // the shadow rays measure a few hundred groups well, not thousands.
    constexpr uint64_t kLightKey = uint64_t(1) << 62, kCellKey = uint64_t(2) << 62, kSkyKey = uint64_t(3) << 62;
    std::vector<uint64_t> keys(entries_.size()), cell_keys(entries_.size());
    for (size_t e = 0, i = 0; e < entries_.size(); ++e) {
        const Entry& entry = entries_[e];
        if (entry.kind == Kind::Sky) {
            keys[e] = cell_keys[e] = kSkyKey;
        } else if (entry.kind == Kind::Punctual) {
            const PunctualLight& light = scene_.lights[entry.index];
            keys[e] = kLightKey | entry.index;
            cell_keys[e] = light.type == LightType::Directional ? keys[e]
                                                                : kCellKey | emitter_cells.cellOf(light.position);
        } else {
            const uint32_t r = root(uint32_t(i));
            const glm::vec3 extent = piece_max[r] - piece_min[r];
            const bool split = std::max({extent.x, extent.y, extent.z}) > split_wider_than;
            const uint32_t cell = emitter_cells.cellOf(centroids[i]);
            keys[e] = uint64_t(r) << 32 | (split ? cell : kNoEntry);
            cell_keys[e] = kCellKey | cell;
            ++i;
        }
    }
    {
        std::vector<uint64_t> distinct(keys);
        std::sort(distinct.begin(), distinct.end());
        if (size_t(std::unique(distinct.begin(), distinct.end()) - distinct.begin()) > kMostLightGroups) {
            keys = cell_keys;
            spatial_.grouped_by_region = true;
        }
    }
    std::unordered_map<uint64_t, uint32_t> group_of_key;
    uint32_t groups = 0;
    entry_group_.resize(entries_.size());
    for (size_t e = 0; e < entries_.size(); ++e) {
        const auto [it, inserted] = group_of_key.emplace(keys[e], groups);
        if (inserted) ++groups;
        entry_group_[e] = it->second;
    }
    spatial_.groups = groups;
    if (groups < 2) return;
    // Each group's entries, in entry order, chosen among themselves by power.
    Buckets by_group = bucketsOf(entry_group_, groups);
    group_first_ = std::move(by_group.first);
    group_entries_ = std::move(by_group.items);
    group_selection_.resize(groups);
    entry_pmf_in_group_.resize(entries_.size());
    for (uint32_t g = 0; g < groups; ++g) {
        std::vector<float> powers;
        for (uint32_t i = group_first_[g]; i < group_first_[g + 1]; ++i)
            powers.push_back(selection_.pmf(group_entries_[i]));
        group_selection_[g] = Distribution1D(powers);
        for (uint32_t i = group_first_[g]; i < group_first_[g + 1]; ++i)
            entry_pmf_in_group_[group_entries_[i]] = group_selection_[g].pmf(i - group_first_[g]);
    }
}

std::optional<std::pair<glm::vec3, glm::vec3>> LightSampler::detailBox(const Tracer& tracer) const {
    // Where local lights compete and people look: the scene's cameras, its lights other than the
    // sun and sky, and the surfaces around them (the rooms they are in), found by rays in 14
    // directions from each camera and from the middle of each local light group. Hits further
    // than kDetailFarthestOfMedian times a point's median hit are left out: a ray out of a window
    // to the horizon says nothing about the room.
    glm::vec3 lo(kInfinity), hi(-kInfinity);
    const auto include = [&](glm::vec3 p) {
        if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) return;
        lo = glm::min(lo, p);
        hi = glm::max(hi, p);
    };
    std::vector<glm::vec3> origins;
    for (const Camera& camera : scene_.cameras) origins.push_back(camera.position);
    const size_t cameras = origins.size();
    for (uint32_t g = 0; g < spatial_.groups; ++g) {
        glm::dvec3 sum(0.0);
        uint32_t members = 0;
        for (uint32_t i = group_first_[g]; i < group_first_[g + 1]; ++i) {
            const Entry& entry = entries_[group_entries_[i]];
            if (entry.kind == Kind::Punctual && scene_.lights[entry.index].type != LightType::Directional) {
                include(scene_.lights[entry.index].position);
                sum += glm::dvec3(scene_.lights[entry.index].position);
                ++members;
            } else if (entry.kind == Kind::Triangle) {
                const glm::uvec3 tri = scene_.triangles[entry.index];
                for (const uint32_t v : {tri.x, tri.y, tri.z}) include(scene_.positions[v]);
                sum += glm::dvec3(scene_.positions[tri.x] + scene_.positions[tri.y] + scene_.positions[tri.z]) / 3.0;
                ++members;
            }
        }
        if (members > 0) origins.push_back(glm::vec3(sum / double(members)));
    }
    if (origins.size() == cameras) return std::nullopt;  // only the sun and sky
    for (const glm::vec3 origin : origins) {
        include(origin);
        std::array<float, kAxisAndDiagonalDirections> distances;
        std::array<glm::vec3, kAxisAndDiagonalDirections> hits;
        size_t found = 0;
        for (int d = 0; d < kAxisAndDiagonalDirections; ++d) {
            const glm::vec3 direction = axisOrDiagonalDirection(d);
            RayHit hit;
            if (!tracer.intersect(Ray{origin, direction}, hit)) continue;
            distances[found] = hit.t;
            hits[found++] = origin + hit.t * direction;
        }
        if (found == 0) continue;
        const float farthest = kDetailFarthestOfMedian *
                               median(std::vector<float>(distances.begin(), distances.begin() + found));
        for (size_t k = 0; k < found; ++k)
            if (distances[k] <= farthest) include(hits[k]);
    }
    const auto longestOf = [](glm::vec3 extent) { return std::max({extent.x, extent.y, extent.z}); };
    const float scene_longest = longestOf(scene_.bounds_max - scene_.bounds_min);
    const float margin = std::max(kDetailMargin * longestOf(hi - lo),
                                  scene_longest / float(kDetailSmallestMarginDivisor));
    lo = glm::max(lo - margin, scene_.bounds_min);
    hi = glm::min(hi + margin, scene_.bounds_max);
    if (!(longestOf(hi - lo) <= kDetailMostOfScene * scene_longest)) return std::nullopt;
    return std::make_pair(lo, hi);
}

void LightSampler::learnWhereLightArrives(const Tracer& tracer) {
    std::vector<SurfacePoint> points = sampleSurfacePoints(scene_, kLearningPoints, kLearningSeed);
    if (const auto detail = detailBox(tracer)) {
        grid_ = LightSelectionGrid(scene_.bounds_min, scene_.bounds_max, kCellsAlongLongest, detail->first,
                                   detail->second, kCellsAlongLongest);
        const std::vector<SurfacePoint> inside = sampleSurfacePointsInBox(scene_, detail->first, detail->second,
                                                                          kLearningPoints, kLearningSeed + 1u);
        points.insert(points.end(), inside.begin(), inside.end());
        spatial_.detail_cells = grid_.detailDimensions();
        spatial_.detail_cell_size = grid_.detailCellSize();
        spatial_.detail_min = grid_.detailMin();
        spatial_.detail_max = grid_.detailMax();
    } else {
        grid_ = LightSelectionGrid(scene_.bounds_min, scene_.bounds_max, kCellsAlongLongest);
    }
    spatial_.cells = grid_.dimensions();
    spatial_.cell_size = grid_.cellSize();
    // The points of each cell, in the order they were drawn.
    std::vector<uint32_t> cell_of_point(points.size());
    for (size_t i = 0; i < points.size(); ++i) cell_of_point[i] = grid_.cellOf(points[i].position);
    const Buckets by_cell = bucketsOf(cell_of_point, grid_.cellCount());
    const std::vector<uint32_t>& first = by_cell.first;
    // Groups are drawn half uniformly and half by power, so a weak lamp beside a sun is measured
    // too; each sample's contribution is divided by the probability it was drawn with.
    const uint32_t groups = spatial_.groups;
    std::vector<float> draw_weights(groups);
    std::vector<double> group_power(groups, 0.0);  // the share power selection gives each group
    for (uint32_t g = 0; g < groups; ++g) {
        for (uint32_t i = group_first_[g]; i < group_first_[g + 1]; ++i)
            group_power[g] += selection_.pmf(group_entries_[i]);
        draw_weights[g] = float(0.5 / double(groups) + 0.5 * group_power[g]);
    }
    const Distribution1D group_draw(draw_weights);
    // Each group's members drawn once by power, kDrawsPerGroup of them (stratified), emitter
    // points placed on the triangles among them: the samples below pick among these instead of
    // searching a group of a million emissive triangles and fetching one at random each time.
    struct Draw {
        uint32_t member = 0;
        EmitterPoint point;  ///< for a triangle
    };
    std::vector<Draw> draws(size_t(groups) * kDrawsPerGroup);
    tbb::parallel_for(uint32_t(0), groups, [&](uint32_t g) {
        for (uint32_t k = 0; k < kDrawsPerGroup; ++k) {
            Draw& draw = draws[size_t(g) * kDrawsPerGroup + k];
            draw.member = uint32_t(group_selection_[g].sampleDiscrete((float(k) + 0.5f) / float(kDrawsPerGroup)));
            const Entry& entry = entries_[group_entries_[group_first_[g] + draw.member]];
            if (entry.kind != Kind::Triangle) continue;
            const uint32_t stream = hashCombine(hashCombine(kLearningSeed ^ 0xd7a3u, g), k);
            const glm::vec2 b = sampleUniformTriangle(
                glm::vec2(bitsToUnitFloat(hashUint32(stream)), bitsToUnitFloat(hashCombine(stream, 1u))));
            draw.point = makeEmitterPoint(scene_, entry.index, b.x, b.y);
        }
    });

    struct Measured {
        uint32_t group;
        double sum;          ///< of the samples' values (0 for the samples that drew another group)
        double sum_squares;  ///< of their squares
    };
    std::vector<std::vector<Measured>> measured(grid_.slotCount());
    std::vector<uint32_t> samples(grid_.slotCount(), 0u);
    std::vector<uint32_t> rays(grid_.cellCount(), 0u);
    // Each point's values are divided by its own mean light, so a slot's shares average what
    // each of its points would pick, not what its brightest points would: in a cell that holds a
    // lamp-lit floor and the sunlit ground outside its wall, raw sums left the lamp 1e-7 of the
    // floor's picks.
    struct Sample {
        uint32_t group;
        double value;
    };
    tbb::parallel_for(uint32_t(0), grid_.cellCount(), [&](uint32_t cell) {
        const uint32_t count = first[cell + 1] - first[cell];
        if (count == 0) return;
        const uint32_t taken = std::min(count, kPointsPerCell);
        std::array<std::vector<Sample>, 2> sides;  // one point's lit samples, by side
        for (uint32_t k = 0; k < taken; ++k) {
            const SurfacePoint& p = points[by_cell.items[first[cell] + uint32_t(uint64_t(k) * count / taken)]];
            std::array<uint32_t, 2> side_slot{}, side_samples{};
            for (std::vector<Sample>& side : sides) side.clear();
            for (uint32_t s = 0; s < kSamplesPerPoint; ++s) {
                const uint32_t stream = hashCombine(hashCombine(kLearningSeed, cell), k * kSamplesPerPoint + s);
                const float u_group = bitsToUnitFloat(hashUint32(stream));
                const glm::vec2 u(bitsToUnitFloat(hashCombine(stream, 1u)), bitsToUnitFloat(hashCombine(stream, 2u)));
                SurfaceHit at;
                at.position = p.position;
                at.face_normal = p.normal;
                at.geometric_normal = at.shading_normal = (s & 1u) ? -p.normal : p.normal;
                const uint32_t slot = cell * LightSelectionGrid::kDirections +
                                      LightSelectionGrid::directionOf(at.geometric_normal);
                ++samples[slot];
                side_slot[s & 1u] = slot;
                ++side_samples[s & 1u];
                float within_group = 0.0f;
                const size_t g = group_draw.sampleDiscrete(u_group, &within_group);
                const Draw& draw = draws[g * kDrawsPerGroup +
                                         std::min(uint32_t(within_group * float(kDrawsPerGroup)), kDrawsPerGroup - 1)];
                const uint32_t member = draw.member;
                const uint32_t e = group_entries_[group_first_[g] + member];
                LightSample light;
                const bool sampled = entries_[e].kind == Kind::Triangle
                                         ? lightFromEmitterPoint(draw.point, triangle_area_[entries_[e].index], 1.0f,
                                                                 at, light)
                                         : sampleEntry(e, 1.0f, at, u, light);
                if (!sampled) continue;
                const float cosine = glm::dot(at.geometric_normal, light.wi);
                const double drawn = double(group_draw.pmf(g)) * double(group_selection_[g].pmf(member));
                const double value = double(luminance(light.radiance)) * double(cosine) / (double(light.pdf) * drawn);
                if (!(cosine > 0.0f) || !(value > 0.0) || !std::isfinite(value)) continue;
                Ray shadow;
                if (!shadowRayTo(at.position, at.geometric_normal, at.ray_offset, light.wi, light.distance, shadow))
                    continue;
                ++rays[cell];
                if (tracer.occluded(shadow)) continue;
                sides[s & 1u].push_back({uint32_t(g), value});
            }
            for (uint32_t side = 0; side < 2; ++side) {
                double sum = 0.0;
                for (const Sample& sample : sides[side]) sum += sample.value;
                if (!(sum > 0.0) || !std::isfinite(sum)) continue;
                const double to_relative = double(side_samples[side]) / sum;  // 1 / the point's mean
                std::vector<Measured>& slot_measured = measured[side_slot[side]];
                for (const Sample& sample : sides[side]) {
                    const double value = sample.value * to_relative;
                    auto found = std::find_if(slot_measured.begin(), slot_measured.end(),
                                              [&](const Measured& m) { return m.group == sample.group; });
                    if (found == slot_measured.end()) {
                        slot_measured.push_back({sample.group, value, value * value});
                    } else {
                        found->sum += value;
                        found->sum_squares += value * value;
                    }
                }
            }
        }
    });
    // Where power picks about as the measured shares would, it stays: one selection for the
    // whole scene keeps a pixel's light samples stratified across the cells its samples land
    // in, which shares changing from cell to cell break (under an open sky, shares everywhere
    // left path tracing twice as noisy as power). The measure: the variance of a one-sample
    // estimate of the slot's light with groups picked by power, relative to its square,
    // sum(c_g^2 / p_g) / C^2 - 1 for the measured contributions c_g, each point's relative to its
    // own light (0 where power is exact; a lit floor under sun and sky 0.04, a shadowed one 1.6,
    // the dim of two rooms 10; summed raw, a lamp-lit floor sharing its slot with the sunlit
    // ground outside looked exact). Each c_g^2 has its sampling variance taken off: among a
    // hundred lamps that reach a hall alike, each measured by a few samples, the squared noise
    // alone made power look far off everywhere.
    std::vector<std::vector<std::pair<uint32_t, double>>> weights(grid_.slotCount());
    std::vector<uint8_t> lit(weights.size(), 0);
    tbb::parallel_for(size_t(0), weights.size(), [&](size_t slot) {
        const double n = double(samples[slot]);
        double total = 0.0, second_moment = 0.0;
        for (const Measured& m : measured[slot]) total += m.sum / n;
        if (!(total > 0.0)) return;
        ++lit[slot];
        for (const Measured& m : measured[slot]) {
            const double mean = m.sum / n;
            const double variance_of_mean = n > 1.0 ? (m.sum_squares / n - mean * mean) / (n - 1.0) : 0.0;
            const double square = std::max(mean * mean - variance_of_mean, 0.0);
            second_moment += group_power[m.group] > 0.0 ? square / (total * total) / group_power[m.group] : kInfinity;
        }
        if (second_moment - 1.0 < kPowerCloseEnough) return;
        for (const Measured& m : measured[slot]) weights[slot].emplace_back(m.group, m.sum);
    });
    grid_.setWeights(weights);
    spatial_.learned_slots = grid_.slotsWithShares();
    for (const uint8_t l : lit) spatial_.lit_slots += l;
    for (const uint32_t r : rays) spatial_.shadow_rays += r;
}

std::string SpatialLightSelection::describe() const {
    char text[512];
    if (!active()) {
        std::snprintf(text, sizeof text, "by power (%s)",
                      groups == 0      ? "no lights"
                      : groups == 1    ? "the lights make one group"
                      : lit_slots == 0 ? "no shadow ray found light reaching a surface"
                                       : "it picks about as the shadow rays measured, everywhere");
    } else {
        char detail[160] = "";
        const glm::vec3 box = detail_max - detail_min;
        if (detail_cells.x > 0)
            std::snprintf(detail, sizeof detail,
                          ", and %ux%ux%u of %.3g over the %.3gx%.3gx%.3g box of the cameras and lamps", detail_cells.x,
                          detail_cells.y, detail_cells.z, double(detail_cell_size), double(box.x), double(box.y),
                          double(box.z));
        const uint32_t slots = (cells.x * cells.y * cells.z + detail_cells.x * detail_cells.y * detail_cells.z) *
                               LightSelectionGrid::kDirections;
        std::snprintf(text, sizeof text,
                      "by where light arrives in %u of %u (cell, direction) slots (a %ux%ux%u grid of %.3g-wide "
                      "cells%s; %u light groups%s; %llu shadow rays, %.2f s), by power elsewhere and in %.0f%% of "
                      "picks everywhere",
                      learned_slots, slots, cells.x, cells.y, cells.z, double(cell_size), detail, groups,
                      grouped_by_region ? ", lights grouped by region: too many to measure one by one" : "",
                      static_cast<unsigned long long>(shadow_rays), seconds, 100.0 * double(kPowerShare));
    }
    return text;
}

void LightSampler::addAreaLights(std::vector<double>& powers) {
    // Power = pi * area * luminance(mean emitted radiance) per emitting side.
    std::vector<glm::vec3> texture_means(scene_.textures.size(), glm::vec3(-1.0f));
    for (uint32_t t = 0; t < scene_.triangles.size(); ++t) {
        const Material& m = scene_.materials[scene_.triangle_materials[t]];
        if (!m.isEmissive()) continue;
        glm::vec3 emission = m.emissive * m.emissive_strength;
        if (m.emissive_texture.isSet()) {
            glm::vec3& mean = texture_means[size_t(m.emissive_texture.texture)];
            if (mean.x < 0.0f) mean = textureMean(scene_.textures[size_t(m.emissive_texture.texture)]);
            emission *= mean;
        }
        const glm::uvec3 tri = scene_.triangles[t];
        const float area = 0.5f * glm::length(glm::cross(scene_.positions[tri.y] - scene_.positions[tri.x],
                                                         scene_.positions[tri.z] - scene_.positions[tri.x]));
        const float sides = m.double_sided ? 2.0f : 1.0f;
        const float power = kPi * area * luminance(emission) * sides;
        if (!(power > 0.0f)) continue;
        if (triangle_area_.empty()) {
            triangle_area_.assign(scene_.triangles.size(), 0.0f);
            triangle_entry_.assign(scene_.triangles.size(), kNoEntry);
        }
        triangle_area_[t] = area;
        entries_.push_back({Kind::Triangle, t});
        powers.push_back(selectionPower(power, double(kPi) * double(area) * luminanceInDouble(emission) * sides));
        ++emissive_triangle_count_;
    }
}

void LightSampler::addPunctualLights(float disk_area, std::vector<double>& powers) {
    for (uint32_t i = 0; i < scene_.lights.size(); ++i) {
        const PunctualLight& light = scene_.lights[i];
        const float lum = luminance(light.intensity);
        // The power per unit of luminance: the solid angle it shines into, or the area it lights.
        float spread = 0.0f;
        switch (light.type) {
            case LightType::Point: spread = 4.0f * kPi; break;
            case LightType::Spot: {
                // The solid angle of a cone halfway between the two (1 - cos stays exact for
                // narrow cones, whose power would otherwise round to zero and drop the light).
                const float one_minus_cos_mid = 0.5f * (oneMinusCos(light.inner_cone_angle) +
                                                        oneMinusCos(light.outer_cone_angle));
                spread = 2.0f * kPi * one_minus_cos_mid;
                break;
            }
            case LightType::Directional: spread = disk_area; break;
        }
        const float power = spread * lum;
        if (!(power > 0.0f)) {
            dark_lights_.push_back(i);
            continue;
        }
        entries_.push_back({Kind::Punctual, i});
        powers.push_back(selectionPower(power, double(spread) * luminanceInDouble(light.intensity)));
    }
}

void LightSampler::addSky(float disk_area, std::vector<double>& powers) {
    if (scene_.sky.isBlack()) return;
    float mean_luminance = luminance(scene_.sky.uniform);
    if (scene_.sky.map) {
        const Texture& map = *scene_.sky.map;
        const size_t width = size_t(map.width), height = size_t(map.height);
        std::vector<float> lum(width * height);
        for (size_t i = 0; i < lum.size(); ++i) lum[i] = std::max(0.0f, luminance(glm::vec3(map.texels[i])));
        // Each cell's weight is the mean of the bilinear lookup over it (skyRadiance filters the
        // map): a texel's light spreads half a texel into its eight neighbours, 1/8, 3/4, 1/8 along
        // each axis (u wraps, v clamps, as the lookup does). With the texel alone the neighbours
        // had no light-sampling pdf, and a one-texel sun lit them only through BSDF samples:
        // fireflies, three times the noise of the same sun spread over 3x3 texels.
        const auto at = [&](int64_t x, int64_t y) {
            const int64_t w = int64_t(width), h = int64_t(height);
            return lum[size_t(std::clamp<int64_t>(y, 0, h - 1)) * width + size_t(((x % w) + w) % w)];
        };
        constexpr float kTent[3] = {0.125f, 0.75f, 0.125f};
        std::vector<float> weights(width * height);
        double sum = 0.0;
        for (size_t y = 0; y < height; ++y) {
            // Rows near the poles cover less solid angle.
            const float sin_theta = std::sin(kPi * (float(y) + 0.5f) / float(map.height));
            for (size_t x = 0; x < width; ++x) {
                float cell = 0.0f;
                for (int dy = -1; dy <= 1; ++dy) {
                    for (int dx = -1; dx <= 1; ++dx)
                        cell += kTent[dy + 1] * kTent[dx + 1] * at(int64_t(x) + dx, int64_t(y) + dy);
                }
                weights[y * width + x] = cell * sin_theta;
                sum += double(cell * sin_theta);
            }
        }
        sky_map_distribution_ = Distribution2D(weights, map.width, map.height);
        mean_luminance =
            float(sum / std::max(1.0, double(map.width) * double(map.height)) * (kPi / 2.0)) * scene_.sky.scale;
    }
    if (mean_luminance > 0.0f) {
        has_sky_ = true;
        entries_.push_back({Kind::Sky, 0});
        powers.push_back(
            selectionPower(kPi * mean_luminance * disk_area, double(kPi) * double(mean_luminance) * double(disk_area)));
    }
}

bool LightSampler::sample(const SurfaceHit& at, float u_select, glm::vec2 u, LightSample& out) const {
    if (selection_.empty()) return false;
    const uint32_t slot = spatial_.active() ? grid_.slotOf(at.position, at.shading_normal) : 0u;
    if (!spatial_.active() || !grid_.hasShares(slot)) {
        const size_t e = selection_.sampleDiscrete(u_select);
        return sampleEntry(e, selection_.pmf(e), at, u, out);
    }
    size_t e;
    float group_share;  // what the slot gives e's group (slotSelectionPmf's lookup, without the search)
    if (u_select < kPowerShare) {
        e = selection_.sampleDiscrete(std::min(u_select / kPowerShare, kOneMinusEpsilon));
        group_share = grid_.probability(slot, entry_group_[e]);
    } else {
        float within_share = 0.0f;
        const LightSelectionGrid::Share& share =
            grid_.pick(slot, std::min((u_select - kPowerShare) / (1.0f - kPowerShare), kOneMinusEpsilon), within_share);
        e = group_entries_[group_first_[share.group] + group_selection_[share.group].sampleDiscrete(within_share)];
        group_share = share.probability;
    }
    return sampleEntry(e, mixedPmf(e, group_share), at, u, out);
}

float LightSampler::selectionPmf(size_t entry, glm::vec3 at, glm::vec3 normal) const {
    return spatial_.active() ? slotSelectionPmf(entry, grid_.slotOf(at, normal)) : selection_.pmf(entry);
}

float LightSampler::slotSelectionPmf(size_t entry, uint32_t slot) const {
    if (!spatial_.active() || !grid_.hasShares(slot)) return selection_.pmf(entry);
    return mixedPmf(entry, grid_.probability(slot, entry_group_[entry]));
}

float LightSampler::mixedPmf(size_t entry, float group_share) const {
    return kPowerShare * selection_.pmf(entry) + (1.0f - kPowerShare) * (group_share * entry_pmf_in_group_[entry]);
}

bool LightSampler::sampleEntry(size_t e, float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const {
    switch (entries_[e].kind) {
        case Kind::Triangle: return sampleTriangle(entries_[e].index, pmf, at, u, out);
        case Kind::Punctual: return samplePunctual(scene_.lights[entries_[e].index], pmf, at, out);
        case Kind::Sky: return sampleSky(pmf, at, u, out);
    }
    return false;
}

bool LightSampler::sampleTriangle(uint32_t triangle, float pmf, const SurfaceHit& at, glm::vec2 u,
                                  LightSample& out) const {
    const glm::vec2 b = sampleUniformTriangle(u);
    return lightFromEmitterPoint(makeEmitterPoint(scene_, triangle, b.x, b.y), triangle_area_[triangle], pmf, at, out);
}

bool LightSampler::lightFromEmitterPoint(const EmitterPoint& point, float area, float pmf, const SurfaceHit& at,
                                         LightSample& out) {
    const glm::vec3 to_light = point.position - at.position;
    const float distance2 = glm::dot(to_light, to_light);
    if (!(distance2 > 0.0f)) return false;
    const float distance = std::sqrt(distance2);
    const glm::vec3 wi = to_light / distance;
    const float cos_light = -glm::dot(point.face_normal, wi);
    if (cos_light == 0.0f || (cos_light < 0.0f && !point.double_sided)) return false;
    out.wi = wi;
    out.distance = distance;
    out.radiance = point.emission;
    out.pdf = pmf * distance2 / (area * std::abs(cos_light));
    out.is_delta = false;
    return out.pdf > 0.0f && std::isfinite(out.pdf);
}

bool LightSampler::samplePunctual(const PunctualLight& light, float pmf, const SurfaceHit& at,
                                  LightSample& out) const {
    out.is_delta = true;
    out.pdf = pmf;
    if (light.type == LightType::Directional) {
        out.wi = -light.direction;
        out.distance = kInfinity;
        out.radiance = light.intensity;
        return true;
    }
    const glm::vec3 to_light = light.position - at.position;
    const float distance2 = glm::dot(to_light, to_light);
    if (!(distance2 > 0.0f)) return false;
    const float distance = std::sqrt(distance2);
    out.wi = to_light / distance;
    out.distance = distance;
    float scale = rangeWindow(distance, light.range) / distance2;
    if (light.type == LightType::Spot) scale *= spotAttenuation(light, -out.wi);
    out.radiance = light.intensity * scale;
    return scale > 0.0f;
}

bool LightSampler::sampleSky(float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const {
    if (scene_.sky.map) {
        float uv_pdf = 0.0f;
        const glm::vec2 uv = sky_map_distribution_.sample(u, &uv_pdf);
        const float sin_theta = std::sin(uv.y * kPi);
        if (!(uv_pdf > 0.0f) || sin_theta <= 0.0f) return false;
        out.wi = equirectToDirection(uv);
        out.pdf = pmf * uv_pdf / (2.0f * kPi * kPi * sin_theta);
    } else {
        // A uniform sky is best sampled by the cosine lobe of the receiving surface.
        out.wi = Frame(at.shading_normal).toWorld(sampleCosineHemisphere(u));
        out.pdf = pmf * std::max(0.0f, glm::dot(out.wi, at.shading_normal)) * kInvPi;
    }
    out.distance = kInfinity;
    out.radiance = skyRadiance(out.wi);
    out.is_delta = false;
    return out.pdf > 0.0f;
}

float LightSampler::pdfEmitter(glm::vec3 from, glm::vec3 from_normal, const SurfaceHit& emitter) const {
    if (triangle_entry_.empty() || triangle_entry_[emitter.triangle] == kNoEntry) return 0.0f;
    const float pmf = selectionPmf(triangle_entry_[emitter.triangle], from, from_normal);
    if (pmf <= 0.0f) return 0.0f;
    const glm::vec3 to_light = emitter.position - from;
    const float distance2 = glm::dot(to_light, to_light);
    const float cos_light = std::abs(glm::dot(emitter.face_normal, to_light)) / std::sqrt(distance2);
    if (!(cos_light > 0.0f)) return 0.0f;
    return pmf * distance2 / (triangle_area_[emitter.triangle] * cos_light);
}

float LightSampler::skyDirectionPdf(glm::vec3 shading_normal, glm::vec3 direction) const {
    if (scene_.sky.map) {
        const glm::vec2 uv = directionToEquirect(direction);
        const float sin_theta = std::sin(uv.y * kPi);
        if (sin_theta <= 0.0f) return 0.0f;
        return sky_map_distribution_.pdf(uv) / (2.0f * kPi * kPi * sin_theta);
    }
    return std::max(0.0f, glm::dot(direction, shading_normal)) * kInvPi;
}

float LightSampler::pdfSky(glm::vec3 from, glm::vec3 shading_normal, glm::vec3 direction) const {
    return has_sky_ ? selectionPmf(sky_entry_, from, shading_normal) * skyDirectionPdf(shading_normal, direction)
                    : 0.0f;
}

glm::vec3 LightSampler::skyRadiance(glm::vec3 direction) const {
    const Sky& sky = scene_.sky;
    if (sky.map) return glm::vec3(sky.map->sample(directionToEquirect(direction))) * sky.scale;
    return sky.uniform;
}

}  // namespace sharcbake
