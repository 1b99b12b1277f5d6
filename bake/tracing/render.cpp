// SPDX-License-Identifier: Apache-2.0
#include "tracing/render.h"

#include "support/progress.h"

#include <tbb/blocked_range2d.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <limits>

namespace sharcbake {
namespace {

/// Half the view's height at unit distance: tan of half the field of view, or an orthographic
/// camera's half height (its rays are parallel: no distance).
float halfViewHeight(const Camera& camera) {
    return camera.orthographic_half_height ? *camera.orthographic_half_height : std::tan(0.5f * camera.yfov);
}

}  // namespace

Camera fitCameraToImage(Camera camera, int width, int height) {
    if (!camera.aspect_ratio || !(*camera.aspect_ratio > 0.0f) || width <= 0 || height <= 0) return camera;
    const float camera_aspect = *camera.aspect_ratio, image_aspect = float(width) / float(height);
    if (std::abs(image_aspect / camera_aspect - 1.0f) < 1e-3f) return camera;
    // The camera's own frame in whole pixels (`--resolution W` rounds W / aspect to the nearest
    // row): nothing to fit, the half-pixel difference is the rounding's.
    if (std::abs(float(width) / camera_aspect - float(height)) <= 0.5f ||
        std::abs(float(height) * camera_aspect - float(width)) <= 0.5f) {
        return camera;
    }
    // Half the view along the camera's larger dimension ("the sensor").
    const float half_y = halfViewHeight(camera);
    const float sensor = camera_aspect >= 1.0f ? half_y * camera_aspect : half_y;
    // Auto fit: the sensor spans the image's larger dimension.
    const float fitted = image_aspect >= 1.0f ? sensor / image_aspect : sensor;
    if (camera.orthographic_half_height) {
        camera.orthographic_half_height = fitted;
    } else {
        camera.yfov = 2.0f * std::atan(fitted);
    }
    camera.aspect_ratio = image_aspect;
    return camera;
}

CameraRays::CameraRays(const Camera& camera, int width, int height)
    : origin_(camera.position), width_(width), height_(height) {
    forward_ = glm::normalize(camera.forward);
    right_ = glm::normalize(glm::cross(forward_, camera.up));
    up_ = glm::cross(right_, forward_);
    orthographic_ = camera.orthographic_half_height.has_value();
    half_y_ = halfViewHeight(camera);
    aspect_ = float(width) / float(height);
    znear_ = camera.znear;
    zfar_ = camera.zfar.value_or(std::numeric_limits<float>::infinity());
}

Ray CameraRays::generate(int x, int y, glm::vec2 jitter) const {
    const float sx = (2.0f * (float(x) + jitter.x) / float(width_) - 1.0f) * half_y_ * aspect_;
    const float sy = (1.0f - 2.0f * (float(y) + jitter.y) / float(height_)) * half_y_;
    if (orthographic_) return Ray{origin_ + sx * right_ + sy * up_, forward_, zfar_, znear_};
    const glm::vec3 direction = glm::normalize(forward_ + sx * right_ + sy * up_);
    // The clip planes stand across the forward axis: along this ray they are 1 / cos farther.
    // Without planes the segment stays (0, inf), whatever the cosine.
    const float cosine = glm::dot(direction, forward_);
    return Ray{origin_, direction, zfar_ / cosine, znear_ / cosine};
}

Image renderImage(const CameraRays& camera, const ImageRenderSettings& settings,
                  const RadianceFunction& radiance, Progress* progress) {
    Image image(settings.width, settings.height);
    constexpr int kTile = 16;
    const tbb::blocked_range2d<int> tiles(0, settings.height, kTile, 0, settings.width, kTile);
    tbb::parallel_for(tiles, [&](const tbb::blocked_range2d<int>& range) {
        for (int y = range.rows().begin(); y < range.rows().end(); ++y) {
            for (int x = range.cols().begin(); x < range.cols().end(); ++x) {
                const uint32_t pixel_id = uint32_t(y) * uint32_t(settings.width) + uint32_t(x);
                glm::dvec3 sum(0.0);
                for (uint32_t s = 0; s < settings.samples_per_pixel; ++s) {
                    PixelSampler sampler(settings.seed, pixel_id, s);
                    const Ray ray = camera.generate(x, y, sampler.next2D());
                    sum += glm::dvec3(radiance(ray, sampler));
                }
                image.at(x, y) = glm::vec3(sum / double(settings.samples_per_pixel));
            }
            if (progress) progress->advance(uint64_t(range.cols().size()));
        }
    });
    return image;
}

}  // namespace sharcbake
