// SPDX-License-Identifier: Apache-2.0
#include "sharc/view_region.h"
#include "sharcbake/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace sharcbake {
namespace {

std::string formatVec3(glm::vec3 v) {
    char text[96];
    std::snprintf(text, sizeof text, "(%g,%g,%g)", v.x, v.y, v.z);
    return text;
}

/// Comma-separated finite floats, exactly `count` of them.
bool parseFloats(const std::string& text, size_t count, std::vector<float>& out) {
    out.clear();
    std::istringstream in(text);
    std::string field;
    while (std::getline(in, field, ',')) {
        char* end = nullptr;
        const float value = std::strtof(field.c_str(), &end);
        if (field.empty() || !end || *end != '\0' || !std::isfinite(value)) return false;
        out.push_back(value);
    }
    return out.size() == count;
}

/// The farthest distance between any point of box A and any point of box B.
float farthestDistance(glm::vec3 a_min, glm::vec3 a_max, glm::vec3 b_min, glm::vec3 b_max) {
    const glm::vec3 d = glm::max(glm::abs(a_max - b_min), glm::abs(b_max - a_min));
    return glm::length(d);
}

float distance2(const Float3& a, glm::vec3 b) {
    const float x = a.x - b.x, y = a.y - b.y, z = a.z - b.z;
    return x * x + y * y + z * z;
}

}  // namespace

std::string ViewRegion::describe() const {
    char text[160];
    switch (kind) {
    case Kind::FreeSpace:
        return "free space (any camera position)";
    case Kind::Points:
        return std::to_string(points.size()) + (points.size() == 1 ? " camera position (" : " camera positions (") +
               source + ")";
    case Kind::Box:
        return "box " + formatVec3(box_min) + "-" + formatVec3(box_max);
    case Kind::Distance:
        if (max_distance > 0.0f) {
            std::snprintf(text, sizeof text, "cameras %g to %g from the surfaces", min_distance, max_distance);
        } else {
            std::snprintf(text, sizeof text, "cameras at least %g from the surfaces", min_distance);
        }
        return text;
    case Kind::BakeCamera:
        return "bake camera only (the SDK's rule: no level coverage)";
    }
    return "unknown";
}

ViewRegion parseViewRegion(const std::string& text) {
    ViewRegion region;
    const std::string forms =
        "expected auto, free, gltf, path, box:x0,y0,z0,x1,y1,z1, distance:MIN, distance:MIN:MAX or bake-camera";
    if (text == "free") return region;
    if (text == "auto") {
        region.source = "auto";
        return region;
    }
    if (text == "bake-camera") {
        region.kind = ViewRegion::Kind::BakeCamera;
        return region;
    }
    if (text == "gltf" || text == "path") {
        region.kind = ViewRegion::Kind::Points;
        region.source = text;
        return region;
    }
    std::vector<float> values;
    if (text.rfind("box:", 0) == 0) {
        if (!parseFloats(text.substr(4), 6, values)) throw std::invalid_argument("box: needs six numbers; " + forms);
        // Views are traced from inside the box; beyond the world's limit Embree refuses the rays.
        if (!withinWorldLimit(glm::dvec3(values[0], values[1], values[2])) ||
            !withinWorldLimit(glm::dvec3(values[3], values[4], values[5]))) {
            throw std::invalid_argument(
                "box: a coordinate beyond +-1e9, where nothing of a scene may lie (for "
                "cameras anywhere, give free)");
        }
        region.kind = ViewRegion::Kind::Box;
        region.box_min = glm::min(glm::vec3(values[0], values[1], values[2]), glm::vec3(values[3], values[4], values[5]));
        region.box_max = glm::max(glm::vec3(values[0], values[1], values[2]), glm::vec3(values[3], values[4], values[5]));
        return region;
    }
    if (text.rfind("distance:", 0) == 0) {
        std::string rest = text.substr(9);
        std::replace(rest.begin(), rest.end(), ':', ',');
        if (!(parseFloats(rest, 1, values) || parseFloats(rest, 2, values)) || !(values[0] > 0.0f) ||
            (values.size() == 2 && !(values[1] > values[0]))) {
            throw std::invalid_argument("distance: needs MIN > 0 and optionally MAX > MIN; " + forms);
        }
        region.kind = ViewRegion::Kind::Distance;
        region.min_distance = values[0];
        if (values.size() == 2) region.max_distance = values[1];
        return region;
    }
    throw std::invalid_argument("\"" + text + "\": " + forms);
}

ViewRegion atGltfCameras(const Scene& scene) {
    ViewRegion region;
    region.kind = ViewRegion::Kind::Points;
    for (const Camera& camera : scene.cameras) region.points.push_back(camera.position);
    region.source = "the glTF cameras";
    return region;
}

DepositLevels::DepositLevels(const HashGridParameters& grid, const ViewRegion& region, glm::vec3 bounds_min,
                             glm::vec3 bounds_max)
    : region_(region), keyer_(grid) {
    const float diagonal = glm::length(bounds_max - bounds_min);
    // The farthest a region camera looks. Without a bound (free space, a distance without MAX)
    // a camera may stand outside the scene, far away: cover up to the level whose voxels are
    // twice the scene's size, where the whole scene is a handful of voxels (coarse levels cost
    // almost nothing).
    float farthest = 0.0f;
    switch (region_.kind) {
    case ViewRegion::Kind::FreeSpace:
        fixed_level_ = kHashGridLevelMin;
        break;
    case ViewRegion::Kind::Distance:
        fixed_level_ = keyer_.levelOf(region_.min_distance * region_.min_distance);
        farthest = region_.max_distance;
        break;
    case ViewRegion::Kind::Points:
        farthest = 0.0f;
        for (glm::vec3 p : region_.points) {
            farthest = std::max(farthest, farthestDistance(p, p, bounds_min, bounds_max));
        }
        break;
    case ViewRegion::Kind::Box:
        farthest = farthestDistance(region_.box_min, region_.box_max, bounds_min, bounds_max);
        break;
    case ViewRegion::Kind::BakeCamera:
        return;  // coarsest_level_ 0: the cache holds what the bake camera deposited, nothing more
    }
    finest_level_ = fixed_level_ ? fixed_level_ : kHashGridLevelMin;
    if (farthest > 0.0f) {
        // A little beyond the farthest distance: the SDK measures from the biased position.
        const float reach = 1.01f * farthest + 2.0f * kHashGridPositionBias;
        coarsest_level_ = std::max(finest_level_, keyer_.levelOf(reach * reach));
    } else {
        coarsest_level_ = finest_level_;
        while (coarsest_level_ < kHashGridLevelMax && !(keyer_.voxelSizeAt(coarsest_level_) >= 2.0f * diagonal)) {
            ++coarsest_level_;
        }
    }
}

uint32_t DepositLevels::levelOfPoint(const Float3& biased) const {
    if (fixed_level_) return fixed_level_;
    float nearest2 = INFINITY;
    if (region_.kind == ViewRegion::Kind::Points) {
        for (glm::vec3 p : region_.points) nearest2 = std::min(nearest2, distance2(biased, p));
    } else {  // Box: the distance to its nearest point (0 inside)
        const glm::vec3 q(biased.x, biased.y, biased.z);
        const glm::vec3 outside = glm::max(glm::max(region_.box_min - q, q - region_.box_max), glm::vec3(0.0f));
        nearest2 = glm::dot(outside, outside);
    }
    return keyer_.levelOf(nearest2);
}

uint64_t DepositLevels::key(glm::vec3 position, glm::vec3 facing_normal, const Float3& bake_camera) const {
    const Float3 p{position.x, position.y, position.z};
    const Float3 n{facing_normal.x, facing_normal.y, facing_normal.z};
    if (region_.kind == ViewRegion::Kind::BakeCamera) return keyer_.key(p, n, bake_camera);
    const Float3 biased{p.x + kHashGridPositionBias, p.y + kHashGridPositionBias, p.z + kHashGridPositionBias};
    return keyer_.keyAtLevel(p, n, levelOfPoint(biased));
}

uint64_t DepositLevels::feedbackKey(glm::vec3 position, glm::vec3 facing_normal, const Float3& bake_camera) const {
    const Float3 p{position.x, position.y, position.z};
    const Float3 n{facing_normal.x, facing_normal.y, facing_normal.z};
    if (region_.kind == ViewRegion::Kind::BakeCamera) return keyer_.key(p, n, bake_camera);
    const Float3 biased{p.x + kHashGridPositionBias, p.y + kHashGridPositionBias, p.z + kHashGridPositionBias};
    const float dx = bake_camera.x - biased.x, dy = bake_camera.y - biased.y, dz = bake_camera.z - biased.z;
    const uint32_t camera_level = keyer_.levelOf(dx * dx + dy * dy + dz * dz);
    return keyer_.keyAtLevel(p, n, std::clamp(camera_level, levelOfPoint(biased), coarsest_level_));
}

}  // namespace sharcbake
