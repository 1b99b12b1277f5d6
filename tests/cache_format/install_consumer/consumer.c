/* SPDX-License-Identifier: Apache-2.0 */
/* Opens a cache through the installed package's C API (compiled as C). */
#include <sharcbake/runtime_c.h>

#include <stdio.h>

int main(int argc, char** argv) {
    sharcbake_cache* cache = NULL;
    char message[256];
    uint32_t rule = 0;
    if (argc < 2) return 2;
    if (sharcbake_cache_open_file(argv[1], 1, &cache, &rule, message, sizeof message) != SHARCBAKE_OK) {
        fprintf(stderr, "%s\n", message);
        return 1;
    }
    printf("%llu voxels, %u levels\n", (unsigned long long)sharcbake_cache_voxel_count(cache),
           sharcbake_cache_level_count(cache));
    sharcbake_cache_close(cache);
    return 0;
}
