// SPDX-License-Identifier: Apache-2.0
// Opens a cache through the installed package's C++ API; exit 0 when it validates and has voxels.
#include <sharcbake/runtime.h>

#include <cstdio>

int main(int argc, char** argv) {
    if (argc < 2) return 2;
    sharcbake::CacheView view;
    sharcbake::CacheError error;
    if (sharcbake::CacheView::openFile(argv[1], &view, &error) != sharcbake::CacheFileStatus::kOk) {
        std::fprintf(stderr, "%s\n", error.message.c_str());
        return 1;
    }
    std::printf("%llu voxels\n", (unsigned long long)view.voxelCount());
    return view.voxelCount() > 0 ? 0 : 1;
}
