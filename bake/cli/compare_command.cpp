// SPDX-License-Identifier: Apache-2.0
// `sharcbake compare`: error of an image against a reference image (any renderer's OpenEXR, PFM
// or Radiance HDR; same camera and resolution).
#include "cli/command_support.h"
#include "cli/commands.h"
#include "support/json.h"
#include "reports/image_error.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include <unistd.h>

namespace sharcbake {
namespace {

struct CompareOptions {
    std::string image_path;
    std::string reference_path;
    bool json = false;
};

/// An image that cannot be read is exit 2; one that reads but is no radiance image (a PNG, a
/// cache file, a damaged EXR) is invalid input, exit 3.
Image readImageToCompare(const std::string& path) {
    requireRegularInputFile(path);
    if (::access(path.c_str(), R_OK) != 0) {
        throw CommandError(kExitIo, path + ": cannot read: " + std::strerror(errno));
    }
    try {
        return readLinearImage(path);
    } catch (const sharcbake::ImageError& e) {
        throw CommandError(kExitInvalidInput, e.what());
    }
}

void runCompare(const CompareOptions& o) {
    const Image image = readImageToCompare(o.image_path);
    const Image reference = readImageToCompare(o.reference_path);
    ImageComparison error;
    try {
        error = compareImages(image, reference);
    } catch (const std::invalid_argument& e) {
        throw CommandError(kExitInvalidInput, o.image_path + ": " + e.what());
    }
    if (error.scale_is_fallback) {
        warn(
            formatted("%s has no positive finite mean (black, or no finite pixel): the measures' epsilons "
                      "fall back to an absolute 0.01, so they depend on the images' units",
                      o.reference_path.c_str()));
    }
    if (error.reference_non_finite_pixels > 0) {
        warn(
            formatted("%s has %s with NaN or infinity: nothing to measure against there, so %s out of "
                      "every measure",
                      o.reference_path.c_str(), counted(error.reference_non_finite_pixels, "pixel").c_str(),
                      error.reference_non_finite_pixels == 1 ? "it is left" : "they are left"));
    }
    if (o.json) {
        const Json json = {{"schema", jsonSchemaId("compare")},
                           {"relative_mse", jsonNumber(error.relative_mse)},
                           {"mean_relative_error", jsonNumber(error.mean_relative_error)},
                           {"relative_bias", jsonNumber(error.relative_bias)},
                           {"non_finite_pixels", error.non_finite_pixels},
                           {"reference_non_finite_pixels", error.reference_non_finite_pixels},
                           {"error_scale", jsonNumber(error.scale)},
                           {"error_scale_is_fallback", error.scale_is_fallback}};
        std::fputs(jsonText(json).c_str(), stdout);
    } else {
        char bias[48] = "bias - (the reference is black)";
        if (std::isfinite(error.relative_bias))
            std::snprintf(bias, sizeof bias, "bias %+.4f%%", 100.0 * error.relative_bias);
        std::printf("relative MSE %.6g, mean relative error %.4f%%, %s, non-finite pixels %llu\n", error.relative_mse,
                    100.0 * error.mean_relative_error, bias, (unsigned long long)error.non_finite_pixels);
    }
}

}  // namespace

void registerCompareCommand(CLI::App& app) {
    auto o = std::make_shared<CompareOptions>();
    CLI::App* cmd =
        app.add_subcommand("compare",
                           "Error of an image against a reference image.\n\n"
                           "Both are linear images of the same camera and resolution, from any renderer: OpenEXR,\n"
                           "PFM (pbrt, Mitsuba) or Radiance HDR, told apart by their first bytes. A multilayer EXR\n"
                           "(Blender's) is read from its only RGB layer or its Combined pass. PNG and JPEG are\n"
                           "refused: their 8-bit display values are not radiance.\n\n"
                           "Prints relative MSE ((x-r)^2/(r^2+(0.1m)^2)), mean relative error (|x-r|/(|r|+0.01m))\n"
                           "and the relative bias of the image mean, averaged over pixels and channels. m is the\n"
                           "reference's mean over pixels and channels, so the measures do not depend on the images'\n"
                           "radiance units (m = 1 for a black reference).\n\n"
                           "Example:\n"
                           "  sharcbake compare out/cached.exr out/reference.exr");
    pathOption(cmd->add_option("image", o->image_path, "Image to measure (.exr, .pfm or .hdr)"))->required();
    pathOption(cmd->add_option("reference", o->reference_path, "Reference image (.exr, .pfm or .hdr)"))->required();
    cmd->add_flag("--json", o->json, "Print the measures as one JSON object");
    cmd->callback([o] { runCompare(*o); });
}

}  // namespace sharcbake
