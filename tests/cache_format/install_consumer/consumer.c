/* SPDX-License-Identifier: Apache-2.0 */
/* The README's C lookup example against the installed package, compiled as C (the lines between
 * the readme markers are the README's, word for word). Run on the golden cache, it checks the
 * answers of the exact and the nearest-level lookup; exit 0 when all are right. */
#include <sharcbake/runtime_c.h>

#include <stdio.h>

int main(int argc, char** argv) {
    /* A voxel of the golden file (level 1, seen from the origin), and a camera 7 m from it,
     * whose level (2) the file does not hold at that point. */
    const float point[3] = {1.0f, 0.0f, 0.0f}, normal[3] = {1.0f, 1.0f, 1.0f}, camera[3] = {8.0f, 0.0f, 0.0f};
    const float origin[3] = {0.0f, 0.0f, 0.0f};
    const char* path = argc > 1 ? argv[1] : NULL;
    float exact[3] = {0.0f, 0.0f, 0.0f}, scratch[3];
    float center[3] = {0.0f, 0.0f, 0.0f}, anchor[3] = {1.0f, 1.0f, 1.0f}, size = 0.0f;
    uint32_t voxel_level = 0;
    int exact_hit, camera_hit, located, right;
    if (!path) return 2;
    /* readme-begin */
    sharcbake_cache* cache = NULL;
    char message[256];
    float radiance[3] = {0.0f, 0.0f, 0.0f};
    uint32_t level = 0; /* the level that answered, from the fallback */
    if (sharcbake_cache_open_file(path, 0, &cache, NULL, message, sizeof message) != SHARCBAKE_OK) {
        fprintf(stderr, "%s\n", message);
        return 1;
    }
    sharcbake_cache_build_lookup_index(cache); /* optional, before sharing: O(1) lookups, batches 10x faster */
    if (!sharcbake_cache_lookup(cache, point, normal, camera, radiance)) {
        sharcbake_cache_lookup_nearest_level(cache, point, normal, camera, radiance, &level);
    }
    /* readme-end */

    /* The golden voxel: radiance (0, 0.5, 1) at level 1; from the origin the exact lookup hits,
     * from `camera` only the fallback does, at level 1. */
    exact_hit = sharcbake_cache_lookup(cache, point, normal, origin, exact);
    camera_hit = sharcbake_cache_lookup(cache, point, normal, camera, scratch);
    printf("C: %llu voxels, %u levels; exact lookup %s (%g %g %g); from the camera: %s, nearest level %u (%g %g %g)\n",
           (unsigned long long)sharcbake_cache_voxel_count(cache), sharcbake_cache_level_count(cache),
           exact_hit ? "hit" : "miss", exact[0], exact[1], exact[2], camera_hit ? "hit" : "miss", level, radiance[0],
           radiance[1], radiance[2]);
    /* Voxel 0's place (the golden file has no anchor: the origin) is its key's cell. */
    located = sharcbake_cache_voxel_location(cache, 0, center, &size, &voxel_level, NULL);
    sharcbake_cache_grid_anchor(cache, anchor);
    printf("C: voxel 0 at (%g %g %g), %g wide, level %u\n", center[0], center[1], center[2], size, voxel_level);
    right = located && voxel_level >= 1 && size == (float)(1 << voxel_level) / 50.0f && anchor[0] == 0.0f &&
            sharcbake_cache_voxel_count(cache) == 40 && sharcbake_cache_level_count(cache) == 4 && exact_hit &&
            exact[0] == 0.0f && exact[1] == 0.5f && exact[2] == 1.0f && !camera_hit && level == 1 &&
            radiance[0] == 0.0f && radiance[1] == 0.5f && radiance[2] == 1.0f;
    sharcbake_cache_close(cache);
    return right ? 0 : 1;
}
