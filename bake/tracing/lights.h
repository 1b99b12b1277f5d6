// SPDX-License-Identifier: Apache-2.0
/// @file lights.h
/// @brief Next-event estimation: choosing a light (by its power, and where learned, by how much
/// of it reaches the shading point's region) and a point or direction on it, plus the pdfs that
/// multiple importance sampling needs when a BSDF-sampled ray finds the same light.
///
/// Lights are emissive triangles (area lights), KHR_lights_punctual lights (point, spot,
/// directional) and the sky (uniform, or an equirectangular map sampled by luminance).
#pragma once

#include "sharcbake/scene.h"
#include "tracing/distribution.h"
#include "tracing/light_grid.h"
#include "tracing/surface.h"

#include <glm/glm.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {

struct LightSample {
    glm::vec3 wi{0.0f};          ///< unit direction from the shading point towards the light
    float distance = 0.0f;       ///< to the light point; infinity for the sky and directional lights
    glm::vec3 radiance{0.0f};    ///< arriving radiance (delta lights: irradiance-like, see pdf)
    float pdf = 0.0f;            ///< selection probability x solid-angle pdf; delta: selection only
    bool is_delta = false;       ///< punctual: no MIS, the BSDF can never hit it
};

class Tracer;

/// How LightSampler(const Tracer&) learned where light arrives (all 0 where it did not).
struct SpatialLightSelection {
    uint32_t groups = 0;             ///< lights grouped: each punctual light, the sky, emitters by piece
    bool grouped_by_region = false;  ///< too many pieces and lights: grouped by coarse cells instead
    glm::uvec3 cells{0u};        ///< the grid's cells along each axis
    float cell_size = 0.0f;      ///< world units
    /// The finer grid over where the cameras and local lights are (0 cells where there is none).
    glm::uvec3 detail_cells{0u};
    float detail_cell_size = 0.0f;
    glm::vec3 detail_min{0.0f}, detail_max{0.0f};
    uint32_t lit_slots = 0;      ///< (cell, direction) slots whose surfaces some light reached
    uint32_t learned_slots = 0;  ///< of those, the slots that select by their measured shares
    uint64_t shadow_rays = 0;
    double seconds = 0.0;
    bool active() const { return learned_slots > 0; }
    /// One line for the bake's plan: what was learned, or why nothing was.
    std::string describe() const;
};

class LightSampler {
public:
    /// Selection by power alone.
    explicit LightSampler(const Scene& scene);
    /// Selection by power and by where light arrives: before any path is traced, shadow rays
    /// from points spread over the surfaces measure how much each group of lights gives each
    /// cell of a coarse grid (and each direction a surface there faces). Where power would pick
    /// about as well, it stays; elsewhere a shading point picks by its slot's shares most of the
    /// time (a quarter of the time by power, so no light that reaches a point is ever left out).
    /// A scene whose lights make one group selects as by power. The same scene gives the same
    /// selection on any thread count.
    explicit LightSampler(const Tracer& tracer);

    bool hasLights() const { return !selection_.empty(); }
    bool hasEmissiveTriangles() const { return emissive_triangle_count_ > 0; }
    bool hasSky() const { return has_sky_; }
    /// Scene::lights indices of punctual lights that give no light (a zero intensity, a black
    /// colour or a spot cone of zero angle) and are never sampled: a "no lights" warning names them.
    const std::vector<uint32_t>& darkLights() const { return dark_lights_; }

    /// Samples one light for the shading point. Returns false if there is nothing to sample or
    /// the chosen sample carries no energy. Occlusion is not tested here.
    bool sample(const SurfaceHit& at, float u_select, glm::vec2 u, LightSample& out) const;

    /// The pdf that sample() returns for the emitter point `emitter` (a surface hit found by a
    /// ray from `from`, a point whose shading normal is `from_normal`), for MIS. 0 for
    /// non-emissive triangles.
    float pdfEmitter(glm::vec3 from, glm::vec3 from_normal, const SurfaceHit& emitter) const;

    /// The pdf that sample() returns for sky direction `direction` from the point `from` whose
    /// shading normal was `shading_normal`, for MIS.
    float pdfSky(glm::vec3 from, glm::vec3 shading_normal, glm::vec3 direction) const;

    /// The probability sample() picks light `entry` at `at` for a surface whose shading normal is
    /// `normal` (tests, and the pdfs above).
    float selectionPmf(size_t entry, glm::vec3 at, glm::vec3 normal) const;
    size_t entryCount() const { return entries_.size(); }
    const SpatialLightSelection& spatialSelection() const { return spatial_; }

    /// Sky radiance arriving from `direction` (pointing away from the scene).
    glm::vec3 skyRadiance(glm::vec3 direction) const;

private:
    enum class Kind : uint8_t { Triangle, Punctual, Sky };
    static constexpr uint32_t kNoEntry = ~0u;
    struct Entry {
        Kind kind;
        uint32_t index;  ///< triangle index or light index
    };

    /// The constructor's parts: each adds its lights to entries_ and their powers to `powers`
    /// (float32 products, in double only where those overflow: selectionPower).
    void addAreaLights(std::vector<double>& powers);
    void addPunctualLights(float disk_area, std::vector<double>& powers);
    void addSky(float disk_area, std::vector<double>& powers);

    float slotSelectionPmf(size_t entry, uint32_t slot) const;
    /// The probability of `entry` where the slot gives its group `group_share`.
    float mixedPmf(size_t entry, float group_share) const;
    /// Samples entry `e` as if it had been picked with probability `pmf`.
    bool sampleEntry(size_t e, float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const;
    bool sampleTriangle(uint32_t triangle, float pmf, const SurfaceHit& at, glm::vec2 u,
                        LightSample& out) const;
    /// The light from a point on an emissive triangle of `area` picked with probability `pmf`.
    static bool lightFromEmitterPoint(const EmitterPoint& point, float area, float pmf, const SurfaceHit& at,
                                      LightSample& out);
    bool samplePunctual(const PunctualLight& light, float pmf, const SurfaceHit& at,
                        LightSample& out) const;
    bool sampleSky(float pmf, const SurfaceHit& at, glm::vec2 u, LightSample& out) const;
    float skyDirectionPdf(glm::vec3 shading_normal, glm::vec3 direction) const;

    /// LightSampler(const Tracer&)'s parts: the groups, then the slots' shares.
    void groupLights();
    void learnWhereLightArrives(const Tracer& tracer);
    /// The box the detail grid covers, or none where it would cover most of the scene anyway.
    std::optional<std::pair<glm::vec3, glm::vec3>> detailBox(const Tracer& tracer) const;

    const Scene& scene_;
    std::vector<Entry> entries_;
    Distribution1D selection_;              ///< by power
    std::vector<uint32_t> triangle_entry_;  ///< per scene triangle: its entry (kNoEntry = not a light)
    std::vector<float> triangle_area_;  ///< per scene triangle, only filled for emitters
    uint32_t emissive_triangle_count_ = 0;
    std::vector<uint32_t> dark_lights_;
    bool has_sky_ = false;
    size_t sky_entry_ = 0;
    Distribution2D sky_map_distribution_;

    // Spatial selection (empty unless learned): entry -> group, each group's entries by power,
    // and the grid of shares per group.
    std::vector<uint32_t> entry_group_;
    std::vector<float> entry_pmf_in_group_;
    std::vector<uint32_t> group_first_;  ///< group g's entries are group_entries_[first[g], first[g + 1])
    std::vector<uint32_t> group_entries_;
    std::vector<Distribution1D> group_selection_;
    LightSelectionGrid grid_;
    SpatialLightSelection spatial_;
};

/// Equirectangular mapping shared with the loader (see scene_loader.h): direction <-> (u, v).
glm::vec2 directionToEquirect(glm::vec3 direction);
glm::vec3 equirectToDirection(glm::vec2 uv);

}  // namespace sharcbake
