// SPDX-License-Identifier: Apache-2.0
#include "sharc/hit_rate.h"

#include "sharc/camera_path.h"
#include "tracing/render.h"
#include "tracing/sampling.h"
#include "tracing/surface.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace sharcbake {
namespace {

/// A view looking along a hashed direction from `position`.
PredictionView sampledView(const std::string& name, glm::vec3 position, uint32_t hash) {
    const glm::vec3 direction =
        sampleUniformSphere({bitsToUnitFloat(hashUint32(hash)), bitsToUnitFloat(hashUint32(hash ^ 0x9E3779B9u))});
    CameraPose pose;
    pose.position = position;
    (void)makeLookAtPose(position, position + direction, glm::radians(75.0f), pose);
    PredictionView view{toCamera(pose), false};
    view.camera.name = name;
    return view;
}

/// The scene's glTF cameras as declared views, each named as the bake names it ("camera 'Persp'",
/// or "camera #3" without names).
std::vector<PredictionView> gltfCameraViews(const Scene& scene) {
    std::vector<PredictionView> views;
    for (const Camera& c : scene.cameras) {
        views.push_back(PredictionView{c, true});
        views.back().camera.name = cameraLabel(c);
    }
    return views;
}

}  // namespace

const ViewHitRate* HitRatePrediction::worst() const {
    const ViewHitRate* worst = nullptr;
    for (const ViewHitRate& v : views) {
        if (v.eligible >= kLookupsForARate && (!worst || v.rate() < worst->rate())) worst = &v;
    }
    return worst;
}

std::vector<PredictionView> declaredViews(const Tracer& tracer, const ViewRegion& region) {
    const Scene& scene = tracer.scene();
    std::vector<PredictionView> views = gltfCameraViews(scene);
    // Without a camera of its own, the scene is looked at first from where render's automatic
    // camera puts it (with render's default field of view).
    if (scene.cameras.empty() && region.kind != ViewRegion::Kind::Points && region.kind != ViewRegion::Kind::Box) {
        PredictionView view{automaticCamera(tracer, glm::radians(kAutomaticCameraFovDegrees)), true};
        view.camera.name = "automatic camera (render's view of a scene without cameras)";
        views.push_back(view);
    }
    return views;
}

RefusedLookups refusedLookups(const Tracer& tracer, const HashGridParameters& grid, Float3 grid_anchor) {
    CacheData empty;
    empty.logarithm_base = grid.logarithm_base;
    empty.scene_scale = grid.scene_scale;
    empty.level_bias = grid.level_bias;
    empty.grid_anchor = grid_anchor;
    empty.bake_capacity = grid.capacity;
    // Declared, as the bake's prediction has them: a camera with few lookups at 64 x 64 (small
    // objects in its frame) is replayed larger, so its share rests on enough of them. Replays
    // gather lookups, not eligible ones: a camera whose lookups were nearly all refused was
    // replayed until 1000 were eligible, taking the whole replay budget (VC.glb's 14 cameras:
    // 15 M pixels, 6 of a default bake's 28 s) and a weight in the share 256 times the others'.
    const HitRatePrediction p = predictHitRate(tracer, empty, ViewRegion{}, gltfCameraViews(tracer.scene()), 64, 64,
                                               LookupsCounted::kAll);
    RefusedLookups refused;
    const uint64_t lookups = p.eligible + p.refused;
    refused.share = lookups >= kLookupsForARate ? double(p.refused) / double(lookups) : 0.0;
    for (const ViewHitRate& view : p.views) {
        const uint64_t own = view.eligible + view.refused;
        if (own < kLookupsForARate || double(view.refused) < kUnservedRefusedShare * double(own)) continue;
        if (refused.unserved++ == 0) refused.first_unserved = view.view.camera.name;
    }
    return refused;
}

std::vector<PredictionView> predictionViews(const Tracer& tracer, const ViewRegion& region, uint32_t samples,
                                            uint32_t seed) {
    const Scene& scene = tracer.scene();
    std::vector<PredictionView> views = declaredViews(tracer, region);
    std::vector<glm::vec3> starts;
    // As the bake explores (exploringCameraPath): from where each camera's view begins.
    for (const Camera& c : scene.cameras) starts.push_back(viewStart(tracer, c));
    std::vector<glm::vec3> points;
    switch (region.kind) {
    case ViewRegion::Kind::FreeSpace:
    case ViewRegion::Kind::Distance:
    case ViewRegion::Kind::BakeCamera: {
        const uint32_t explore_seed = seed ^ 0x5EED0001u;
        const ExplorationResult explored = exploreFreeSpace(tracer, starts, !starts.empty(), samples, explore_seed);
        if (!explored.dark_enclosure) {
            points = explored.points;
            break;
        }
        // The dark inside of a closed object: runtime cameras look at it from outside, as the bake
        // does (exploringCameraPath).
        const std::vector<CameraPose> around = viewsAroundScene(scene, samples, explore_seed);
        for (size_t i = 0; i < around.size(); ++i) {
            PredictionView view{toCamera(around[i]), false};
            view.camera.name = "view from around " + std::to_string(i);
            views.push_back(view);
        }
        break;
    }
    case ViewRegion::Kind::Points:
        for (uint32_t i = 0; i < samples && !region.points.empty(); ++i) {
            points.push_back(region.points[size_t(i) * region.points.size() / samples]);
        }
        break;
    case ViewRegion::Kind::Box:
        for (uint32_t i = 0; i < samples; ++i) {
            const glm::vec3 u(bitsToUnitFloat(hashUint32(seed + 3 * i)), bitsToUnitFloat(hashUint32(seed + 3 * i + 1)),
                              bitsToUnitFloat(hashUint32(seed + 3 * i + 2)));
            points.push_back(region.box_min + u * (region.box_max - region.box_min));
        }
        break;
    }
    for (size_t i = 0; i < points.size(); ++i) {
        views.push_back(sampledView("region sample " + std::to_string(i), points[i],
                                    hashCombine(hashUint32(seed), uint32_t(i))));
    }
    return views;
}

HitRatePrediction predictHitRate(const Tracer& tracer, const CacheData& cache, const ViewRegion& region,
                                 const std::vector<PredictionView>& views, int width, int height,
                                 LookupsCounted counted) {
    HitRatePrediction prediction;
    BakedCache baked(cache, glm::vec3(0.0f));
    const float min_distance2 =
        region.kind == ViewRegion::Kind::Distance ? region.min_distance * region.min_distance : 0.0f;
    // One view's lookups at w x h pixels; `pass` keys the samples, so a replay draws new ones.
    const auto replay = [&](size_t v, int w, int h, uint32_t pass) {
        const Camera& camera = views[v].camera;
        baked.setCamera(camera.position);
        const CameraRays rays(camera, w, h);
        tbb::parallel_for(tbb::blocked_range<int>(0, w * h, 256), [&](const tbb::blocked_range<int>& r) {
            for (int pixel = r.begin(); pixel != r.end(); ++pixel) {
                PixelSampler sampler(uint32_t(v) * 0x9E3779B1u, uint32_t(pixel), pass);
                const Ray primary = rays.generate(pixel % w, pixel / w, sampler.next2D());
                RayHit first;
                if (!tracer.intersect(primary, first)) continue;
                const SurfaceHit a = makeSurfaceHit(tracer.scene(), first, primary.direction);
                // A diffuse bounce, as most runtime paths take; SHaRC queries the hit it reaches.
                const glm::vec3 direction = Frame(a.geometric_normal).toWorld(sampleCosineHemisphere(sampler.next2D()));
                const Ray bounce{offsetRayOrigin(a.position, a.geometric_normal, a.ray_offset), direction};
                RayHit second;
                if (!tracer.intersect(bounce, second)) continue;
                const SurfaceHit b = makeSurfaceHit(tracer.scene(), second, bounce.direction);
                const glm::vec3 to_camera = b.position - camera.position;
                if (glm::dot(to_camera, to_camera) < min_distance2) continue;  // nearer than declared
                glm::vec3 radiance;
                (void)baked.lookup(CacheQuery{b.position, b.geometric_normal, second.t, 1.0f}, radiance);
            }
        });
        ViewHitRate rate;
        rate.view = views[v];
        rate.hits = baked.hits();
        rate.eligible = baked.hits() + baked.misses();
        rate.refused = baked.refused();
        return rate;
    };
    uint64_t replayed_pixels = 0;
    for (size_t v = 0; v < views.size(); ++v) {
        ViewHitRate rate = replay(v, width, height, 0);
        // A declared camera whose frame is mostly sky (a small model in it) gets few lookups at
        // this size: its own rate, which the bake reports, is replayed at 4 times the size each
        // way until it has enough lookups, up to kDeclaredViewMaxScale.
        const auto lookups = [counted](const ViewHitRate& r) {
            return counted == LookupsCounted::kAll ? r.eligible + r.refused : r.eligible;
        };
        uint32_t pass = 0;
        for (int scale = 4;
             views[v].declared && lookups(rate) < kDeclaredViewMinLookups && scale <= kDeclaredViewMaxScale;
             scale *= 4) {
            const uint64_t pixels = uint64_t(width * scale) * uint64_t(height * scale);
            if (replayed_pixels + pixels > kReplayPixelBudget) break;
            replayed_pixels += pixels;
            rate = replay(v, width * scale, height * scale, ++pass);
        }
        prediction.hits += rate.hits;
        prediction.eligible += rate.eligible;
        prediction.refused += rate.refused;
        prediction.views.push_back(rate);
    }
    return prediction;
}

}  // namespace sharcbake
