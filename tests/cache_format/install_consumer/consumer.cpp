// SPDX-License-Identifier: Apache-2.0
// The README's C++ lookup example ("Use the cache in an engine") against the installed package:
// the lines between the readme markers are the README's, word for word (the install test
// compares them). Run on the golden cache, it checks the answers; exit 0 when all are right.
#include <sharcbake/runtime.h>

#include <cstdio>

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    const char* path = argv[1];
    // A voxel of the golden file (level 1, seen from the origin), and a camera 7 m from it,
    // whose level (2) the file does not hold at that point.
    const sharcbake::Float3 point{1.0f, 0.0f, 0.0f}, normal{1.0f, 1.0f, 1.0f}, camera{8.0f, 0.0f, 0.0f};
    // readme-begin
    sharcbake::CacheView cache;  // immutable once open: share it between threads
    sharcbake::CacheError error;
    if (sharcbake::CacheView::openFile(path, &cache, &error) != sharcbake::CacheFileStatus::kOk) {
        std::fprintf(stderr, "%s\n", error.message.c_str());  // names the SPEC rule that failed
        return 1;
    }
    cache.buildLookupIndex();  // optional, before sharing: O(1) lookups instead of a binary search
    sharcbake::Float3 radiance{0.0f, 0.0f, 0.0f};
    uint32_t level = 0;
    if (cache.lookup(point, normal, camera, &radiance)) {
        // hit: the voxel SHaRC itself reads for this point from this camera
    } else if (cache.lookupNearestLevel(point, normal, camera, &radiance, &level)) {
        // fallback: the same point at the nearest level the file holds
    }
    // readme-end

    // The golden voxel: radiance (0, 0.5, 1) at level 1. From the origin the exact lookup hits;
    // from `camera` only the fallback does, at level 1.
    sharcbake::Float3 exact{0.0f, 0.0f, 0.0f}, scratch;
    const bool exact_hit = cache.lookup(point, normal, {0.0f, 0.0f, 0.0f}, &exact);
    const bool camera_hit = cache.lookup(point, normal, camera, &scratch);
    std::printf("C++: %llu voxels; exact lookup %s (%g %g %g); from the camera: %s, nearest level %u (%g %g %g)\n",
                (unsigned long long)cache.voxelCount(), exact_hit ? "hit" : "miss", exact.x, exact.y, exact.z,
                camera_hit ? "hit" : "miss", level, radiance.x, radiance.y, radiance.z);
    const bool right = cache.voxelCount() == 40 && exact_hit && exact.x == 0.0f && exact.y == 0.5f && exact.z == 1.0f &&
                       !camera_hit && level == 1 && radiance.x == 0.0f && radiance.y == 0.5f && radiance.z == 1.0f;
    return right ? 0 : 1;
}
