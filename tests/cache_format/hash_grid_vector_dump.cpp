// SPDX-License-Identifier: Apache-2.0
// Test helper for the C++/Python cross-check (hash_grid_vectors.py --check --dump-exe).
// stdin, one case per line: 12 binary32 bit patterns in hex (position xyz, normal xyz, camera xyz,
// logarithm base, scene scale, level bias) and a decimal capacity.
// stdout, one line per case: level gx gy gz key(hex16) hash(hex8) base_slot voxel_size(bits)
// debug_color(3 x bits) voxel_center(3 x bits).
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "float_bits.h"
#include "sharcbake/hash_grid.h"

int main() {
    using namespace sharcbake;
    uint32_t w[12];
    uint32_t capacity;
    while (std::scanf("%" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32
                      " %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32 " %" SCNx32
                      " %" SCNu32,
                      &w[0], &w[1], &w[2], &w[3], &w[4], &w[5], &w[6], &w[7], &w[8], &w[9],
                      &w[10], &w[11], &capacity) == 13) {
        const Float3 p{fromBits(w[0]), fromBits(w[1]), fromBits(w[2])};
        const Float3 n{fromBits(w[3]), fromBits(w[4]), fromBits(w[5])};
        HashGridParameters params;
        params.camera_position = Float3{fromBits(w[6]), fromBits(w[7]), fromBits(w[8])};
        params.logarithm_base = fromBits(w[9]);
        params.scene_scale = fromBits(w[10]);
        params.level_bias = fromBits(w[11]);
        params.capacity = capacity;

        const HashGridCell cell = gridCell(p, params);
        const uint64_t key = hashGridKey(p, n, params);
        const uint32_t hash = hashGridHash(key);
        const Float3 color = hashDebugColor(key);
        const Float3 center = voxelCenter(key, params);
        std::printf("%u %d %d %d %016" PRIx64 " %08x %u %08x %08x %08x %08x %08x %08x %08x\n",
                    cell.level, cell.grid.x, cell.grid.y, cell.grid.z, key, hash,
                    bucketBase(hash, capacity), toBits(voxelSize(cell.level, params)),
                    toBits(color.x), toBits(color.y), toBits(color.z), toBits(center.x),
                    toBits(center.y), toBits(center.z));
    }
    return 0;
}
