// SPDX-License-Identifier: Apache-2.0
/// @file image.h
/// @brief Linear float RGB images and their files: OpenEXR (linear, 32-bit float) for data,
/// PNG (tone-mapped, sRGB, 8-bit) for people; PFM and Radiance HDR read from other renderers.
#pragma once

#include <glm/glm.hpp>

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace sharcbake {

/// Row-major RGB image, row 0 at the top.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> pixels;

    Image() = default;
    Image(int w, int h) : width(w), height(h), pixels(size_t(w) * size_t(h), glm::vec3(0.0f)) {}
    glm::vec3& at(int x, int y) { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
    const glm::vec3& at(int x, int y) const { return pixels[size_t(y) * size_t(width) + size_t(x)]; }
};

/// Thrown when an image file cannot be written or read; what() names the file.
class ImageError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// String attributes stored in the EXR header (provenance: tool version, settings, timings).
using ImageMetadata = std::map<std::string, std::string>;

/// Writes a 32-bit float RGB OpenEXR file. Throws ImageError.
void writeExr(const std::string& path, const Image& image, const ImageMetadata& metadata = {});

/// Refuses (ImageError) an OpenEXR file that OpenEXR 3.1 would make allocate what it claims
/// before finding the damage: a header attribute larger than the rest of the file or whose size
/// disagrees with what its type holds, a data window of more than 2^27 pixels (16384 x 8192), or
/// a chunk (a tile, or the rows compressed together) that decodes to more than 256 MiB. Every
/// part of a multi-part file is checked. readExr calls it; call it before reading an EXR with
/// OpenEXR elsewhere.
void checkExrHeaders(const std::string& path);

/// How many rows of an OpenEXR image `width` pixels wide to allocate and read at a time, so that
/// a header claiming more rows than the file holds fails at the first missing one rather than
/// after the whole image was cleared: a power of two of about 2^22 pixels, at most 256 rows (so
/// a strip covers whole chunks of every compression), at least 1.
int exrRowsPerStrip(int width);

/// Reads the R, G, B channels of an OpenEXR file (any pixel type) as float. A missing channel
/// reads as 0; a single Y (luminance) channel is replicated. A layered file without plain R, G, B
/// (Blender's multilayer EXR) is read from its only layer with R, G and B, or its single
/// "Combined" pass; with neither, or no picture channels at all, an error names the layers or
/// channels. Throws ImageError.
Image readExr(const std::string& path, ImageMetadata* metadata = nullptr);

/// Reads a linear RGB image from any renderer, by the file's first bytes: OpenEXR (readExr), PFM
/// ("PF" colour or "Pf" grey, either byte order, rows from the bottom up: pbrt, Mitsuba) or
/// Radiance HDR (RGBE, flat or run-length; EXPOSURE and COLORCORR divided back out). Display
/// images (PNG, JPEG, TIFF, ...) are refused with the reason: their 8-bit values are not
/// radiance. Throws ImageError.
Image readLinearImage(const std::string& path);

/// Tone-mapping for PNG previews: exposure (in stops), then the operator, then the sRGB curve.
enum class ToneMap { Clamp, Reinhard, Aces };

/// Writes an 8-bit sRGB PNG preview of a linear image. Throws ImageError.
void writePng(const std::string& path, const Image& image, float exposure_stops = 0.0f,
              ToneMap tone_map = ToneMap::Aces);

/// The tone-mapped, sRGB-encoded value in [0,1] of one linear pixel (exposed for tests).
glm::vec3 toneMapPixel(glm::vec3 linear, float exposure_stops, ToneMap tone_map);

}  // namespace sharcbake
