// SPDX-License-Identifier: Apache-2.0
/// @file hit_rate.h
/// @brief The share of a runtime's cache lookups a baked cache answers, predicted by replaying
/// SHaRC's query from views: the first secondary hit of a diffuse bounce from every pixel, keyed
/// with the view's camera as the level-of-detail centre, with SHaRC's eligibility tests
/// (cacheQueryEligible), looked up exactly as the SDK looks up (no fallback).
#pragma once

#include "sharc/cache_query.h"
#include "tracing/tracer.h"
#include "sharc/view_region.h"

#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// A camera to predict from; its name says which ("camera 'Main'", "region sample 3").
struct PredictionView {
    Camera camera;
    /// A camera the scene or the user declared, or render's automatic camera of a scene without
    /// one (not a region sample): reported one by one.
    bool declared = false;
};

struct ViewHitRate {
    PredictionView view;
    uint64_t eligible = 0;  ///< lookups that pass SHaRC's eligibility tests
    uint64_t hits = 0;
    /// Lookups the eligibility tests refused (a bounce shorter than its voxel, or a cone wider):
    /// all of them when the voxels are far larger than what the view sees.
    uint64_t refused = 0;
    double rate() const { return eligible ? double(hits) / double(eligible) : 1.0; }
};

/// Fewer eligible lookups than this make no rate worth reporting or warning about (the bake's
/// prediction and render's own count): a lone convex model's first bounces leave it, and the one
/// that met its other side read "0.0% answered".
inline constexpr uint64_t kLookupsForARate = 100;

struct HitRatePrediction {
    std::vector<ViewHitRate> views;
    uint64_t eligible = 0;
    uint64_t hits = 0;
    uint64_t refused = 0;
    double rate() const { return eligible ? double(hits) / double(eligible) : 1.0; }
    /// The lowest rate of a view with at least kLookupsForARate eligible lookups (nullptr when none).
    const ViewHitRate* worst() const;
};

/// The scene's own views: its glTF cameras, or without any, render's automatic camera (unless the
/// region is points or a box, which name where cameras go). Declared.
std::vector<PredictionView> declaredViews(const Tracer& tracer, const ViewRegion& region);

/// Views to predict from: the scene's glTF cameras (declared; without any, render's automatic
/// camera, unless the region is points or a box), and `samples` viewpoints of the region looking
/// in hashed directions: free-space points reachable from the cameras for
/// FreeSpace and Distance, the region's points, random points of its box. Deterministic.
std::vector<PredictionView> predictionViews(const Tracer& tracer, const ViewRegion& region, uint32_t samples,
                                            uint32_t seed);

/// A glTF camera with this share of its lookups refused or more gets (next to) nothing from the
/// cache: the runtime traces its paths in full.
inline constexpr double kUnservedRefusedShare = 0.9;

/// How SHaRC's eligibility tests treat the lookups from the scene's glTF cameras on one grid.
struct RefusedLookups {
    double share = 0.0;  ///< of all their lookups; 0 when they make fewer than kLookupsForARate
    /// Cameras with kLookupsForARate lookups or more, kUnservedRefusedShare of them refused.
    uint32_t unserved = 0;
    std::string first_unserved;  ///< the first such camera's label ("camera 'Hall'", "camera #3")
};

/// The lookups from the scene's glTF cameras (replayed as predictHitRate replays declared views:
/// 64 x 64 pixels, larger for a camera with fewer than kDeclaredViewMinLookups lookups; one
/// diffuse bounce per pixel) that SHaRC's eligibility tests refuse on `grid` whose keys decode
/// near `grid_anchor`: nearly all where the voxels are far larger than what a camera sees (a
/// bounce shorter than its voxel is refused). What the cache holds does not matter.
RefusedLookups refusedLookups(const Tracer& tracer, const HashGridParameters& grid, Float3 grid_anchor);

/// A declared view with fewer lookups than this at the prediction's size (a small model in its
/// frame) is replayed at 4 and then 16 times the size in each direction (kDeclaredViewMaxScale).
inline constexpr uint64_t kDeclaredViewMinLookups = 1000;
inline constexpr int kDeclaredViewMaxScale = 16;
/// Replays stop, view by view in order, once they would take more pixels than this in all (a
/// scene with hundreds of glTF cameras): sixteen views at 1024x1024.
inline constexpr uint64_t kReplayPixelBudget = uint64_t(16) << 20;

/// What a declared view's replay gathers kDeclaredViewMinLookups of: eligible lookups for its hit
/// rate (hits / eligible), or all of them (eligible and refused) for the share refused.
enum class LookupsCounted { kEligible, kAll };

/// Replays the lookups of `width` x `height` pixels (one diffuse bounce each) from every view
/// (a declared one with too few lookups, as `counted` counts them, again at a larger size, see
/// kDeclaredViewMinLookups).
/// For a Distance region, lookups nearer the camera than its minimum are not counted (they are
/// outside what was declared). The counts do not depend on the thread count.
HitRatePrediction predictHitRate(const Tracer& tracer, const CacheData& cache, const ViewRegion& region,
                                 const std::vector<PredictionView>& views, int width = 64, int height = 64,
                                 LookupsCounted counted = LookupsCounted::kEligible);

}  // namespace sharcbake
