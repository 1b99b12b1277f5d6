// SPDX-License-Identifier: Apache-2.0
/// @file render.h
/// @brief Rendering an image from a camera: camera rays, parallel tiles, deterministic sums.
#pragma once

#include "tracing/path_tracer.h"
#include "sharcbake/image.h"
#include "sharcbake/scene.h"

#include <functional>

namespace sharcbake {

class Progress;

/// The camera for an image of width x height when its glTF aspect ratio differs: fitted as
/// Blender's sensor fit "Auto" does (Blender's exporter writes yfov for the camera's own aspect):
/// the field of view of the camera's larger dimension is kept on the image's larger dimension.
/// The camera itself when it has no aspect ratio or the image has the same one, to the pixel
/// (a height of W / aspect rounded, as `--resolution W` makes it).
Camera fitCameraToImage(Camera camera, int width, int height);

/// Primary rays of a pinhole camera, or of an orthographic one (parallel rays from the view
/// rectangle around the camera's position), for an image of width x height (row 0 at the top).
/// Each ray's segment lies between the camera's clip planes (Camera::znear, zfar): planes across
/// its forward axis, so a ray at an angle to it begins farther out than znear.
class CameraRays {
public:
    CameraRays(const Camera& camera, int width, int height);
    /// Ray through the image point (x + jitter.x, y + jitter.y), jitter in [0,1)^2.
    Ray generate(int x, int y, glm::vec2 jitter) const;

private:
    glm::vec3 origin_, forward_, right_, up_;
    bool orthographic_;
    float half_y_;  ///< tan(yfov / 2), or the orthographic half height
    float aspect_;
    float znear_, zfar_;  ///< along forward_; zfar_ infinite without a far plane
    int width_, height_;
};

/// Estimates the radiance for one primary ray; the sampler is positioned after the camera's
/// dimensions.
using RadianceFunction = std::function<glm::vec3(const Ray&, PixelSampler&)>;

struct ImageRenderSettings {
    int width = 512;
    int height = 512;
    uint32_t samples_per_pixel = 64;
    uint32_t seed = 0;
};

/// Renders every pixel with `samples_per_pixel` samples. Each pixel's samples are summed in a
/// fixed order by one task, so the image is bit-identical for any thread count.
Image renderImage(const CameraRays& camera, const ImageRenderSettings& settings,
                  const RadianceFunction& radiance, Progress* progress);

}  // namespace sharcbake
