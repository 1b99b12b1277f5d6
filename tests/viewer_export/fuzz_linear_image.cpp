// SPDX-License-Identifier: Apache-2.0
/// @file fuzz_linear_image.cpp
/// @brief libFuzzer harness for readLinearImage, the reader of other renderers' images that
/// `sharcbake compare` and `render --compare` take: PFM and Radiance HDR (parsed here, flat and
/// run-length) and OpenEXR (through OpenEXR). Built and run by tests/scenes/fuzzed_loaders_test.sh.
///
/// Each input is written to a file of a private folder and read from there. An image that reads
/// must hold width x height pixels; a file that does not read must fail with ImageError (never
/// another exception, a crash or a sanitizer report).
#include "sharcbake/image.h"

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

/// The file inputs are written to, named once per process (libFuzzer's workers are processes)
/// and removed when it exits.
struct ScratchFile {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("sharcbake-fuzz-image-" + std::to_string(::getpid()));
    ~ScratchFile() {
        std::error_code ignored;
        std::filesystem::remove(path, ignored);
    }
};

const std::filesystem::path& inputPath() {
    static const ScratchFile file;
    return file.path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    {
        std::ofstream out(inputPath(), std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    }
    try {
        const sharcbake::Image image = sharcbake::readLinearImage(inputPath().string());
        if (image.width <= 0 || image.height <= 0 ||
            image.pixels.size() != size_t(image.width) * size_t(image.height)) {
            std::fprintf(stderr, "fuzz_linear_image: an image read with %d x %d pixels holds %zu\n", image.width,
                         image.height, image.pixels.size());
            std::abort();
        }
    } catch (const sharcbake::ImageError&) {
        // The expected outcome for most inputs.
    }
    std::filesystem::remove(inputPath());
    return 0;
}
