// SPDX-License-Identifier: Apache-2.0
// Linear images from other renderers: OpenEXR (readExr), PFM (pbrt, Mitsuba, many research
// renderers) and Radiance HDR (RGBE), told apart by their first bytes; display images (PNG, JPEG,
// ...) are refused with the reason.
#include "image_internal.h"
#include "sharcbake/image.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

[[noreturn]] void fail(const std::string& path, const char* format, const std::string& reason) {
    throw ImageError("cannot read " + std::string(format) + " '" + path + "': " + reason);
}

/// The file's bytes, or its first `limit` bytes.
std::vector<unsigned char> readFileBytes(const std::string& path, size_t limit = SIZE_MAX) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ImageError("cannot open '" + path + "'");
    std::vector<unsigned char> bytes;
    for (std::istreambuf_iterator<char> it(in), end; it != end && bytes.size() < limit; ++it)
        bytes.push_back(static_cast<unsigned char>(*it));
    return bytes;
}

bool startsWith(const std::vector<unsigned char>& bytes, const char* prefix, size_t length) {
    return bytes.size() >= length && std::memcmp(bytes.data(), prefix, length) == 0;
}

/// The name of a display-image format by its signature, or nullptr.
const char* displayFormatName(const std::vector<unsigned char>& bytes) {
    if (startsWith(bytes, "\x89PNG", 4)) return "a PNG";
    if (startsWith(bytes, "\xFF\xD8\xFF", 3)) return "a JPEG";
    if (startsWith(bytes, "GIF8", 4)) return "a GIF";
    if (startsWith(bytes, "BM", 2)) return "a BMP";
    if (startsWith(bytes, "II*\0", 4) || startsWith(bytes, "MM\0*", 4)) return "a TIFF";
    if (startsWith(bytes, "RIFF", 4) && bytes.size() >= 12 && std::memcmp(bytes.data() + 8, "WEBP", 4) == 0)
        return "a WebP";
    return nullptr;
}

/// Cursor over a header of text fields separated by white space.
struct TextCursor {
    const std::vector<unsigned char>& bytes;
    size_t at = 0;

    void skipSpace() {
        while (at < bytes.size() && std::isspace(bytes[at])) ++at;
    }
    std::string token() {
        skipSpace();
        const size_t start = at;
        while (at < bytes.size() && !std::isspace(bytes[at])) ++at;
        return std::string(bytes.begin() + std::ptrdiff_t(start), bytes.begin() + std::ptrdiff_t(at));
    }
    /// One line without its '\n' (and a '\r' before it); false at the end of the bytes.
    bool line(std::string& out) {
        if (at >= bytes.size()) return false;
        const size_t start = at;
        while (at < bytes.size() && bytes[at] != '\n') ++at;
        out.assign(bytes.begin() + std::ptrdiff_t(start), bytes.begin() + std::ptrdiff_t(at));
        if (!out.empty() && out.back() == '\r') out.pop_back();
        if (at < bytes.size()) ++at;  // the '\n'
        return true;
    }
};

/// Whether a number parsed from `text` (strtol, strtod) ended at `end` = the token's end: a zero
/// byte inside the token ends c_str() early, not the token.
bool parsedWholeToken(const std::string& text, const char* end) {
    return !text.empty() && end == text.c_str() + text.size();
}

bool parseDimension(const std::string& text, int& value) {
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (!parsedWholeToken(text, end) || v <= 0 || v > (1L << 20)) return false;
    value = int(v);
    return true;
}

/// PFM: "PF" (RGB) or "Pf" (grey), width, height, a scale whose sign gives the byte order
/// (negative: little-endian), one white-space character, then float32 pixels, rows from the
/// bottom up.
Image readPfm(const std::string& path, const std::vector<unsigned char>& bytes) {
    TextCursor cursor{bytes};
    const std::string magic = cursor.token();
    const int channels = magic == "PF" ? 3 : 1;
    int width = 0, height = 0;
    if (!parseDimension(cursor.token(), width) || !parseDimension(cursor.token(), height)) {
        fail(path, "PFM", "the header's width and height are not positive integers");
    }
    const std::string scale_text = cursor.token();
    char* end = nullptr;
    const double scale = std::strtod(scale_text.c_str(), &end);
    if (!parsedWholeToken(scale_text, end) || !std::isfinite(scale) || scale == 0.0) {
        fail(path, "PFM", "the header's scale '" + detail::printable(scale_text) + "' is not a non-zero number");
    }
    if (cursor.at >= bytes.size() || !std::isspace(bytes[cursor.at])) fail(path, "PFM", "the header ends early");
    ++cursor.at;  // exactly one white-space character before the pixels
    if (uint64_t(width) * uint64_t(height) > detail::kMaxImagePixels) {
        fail(path, "PFM", std::to_string(width) + "x" + std::to_string(height) + " is " + detail::kTooManyPixels);
    }
    const uint64_t expected = uint64_t(width) * uint64_t(height) * uint64_t(channels) * 4u;
    const uint64_t present = bytes.size() - cursor.at;
    if (present != expected) {
        fail(path, "PFM",
             "expected " + std::to_string(expected) + " bytes of pixels for " + std::to_string(width) + "x" +
                 std::to_string(height) + (channels == 3 ? " RGB" : " grey") + ", found " + std::to_string(present) +
                 (present < expected ? " (truncated)" : ""));
    }
    const bool little_endian = scale < 0.0;
    const unsigned char* data = bytes.data() + cursor.at;
    const auto value = [&](uint64_t index) {
        unsigned char b[4];
        std::memcpy(b, data + 4 * index, 4);
        const uint32_t bits = little_endian
                                  ? uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24
                                  : uint32_t(b[3]) | uint32_t(b[2]) << 8 | uint32_t(b[1]) << 16 | uint32_t(b[0]) << 24;
        float f;
        std::memcpy(&f, &bits, 4);
        return f;
    };
    Image image(width, height);
    for (int y = 0; y < height; ++y) {
        const uint64_t row = uint64_t(height - 1 - y) * uint64_t(width);  // stored bottom up
        for (int x = 0; x < width; ++x) {
            const uint64_t p = (row + uint64_t(x)) * uint64_t(channels);
            image.at(x, y) = channels == 3 ? glm::vec3(value(p), value(p + 1), value(p + 2)) : glm::vec3(value(p));
        }
    }
    return image;
}

/// One RGBE pixel as radiance (Radiance's colr_color: the mantissas' centres, 2^(e - 136)).
glm::vec3 rgbeToFloat(const unsigned char rgbe[4]) {
    if (rgbe[3] == 0) return glm::vec3(0.0f);
    const float f = std::ldexp(1.0f, int(rgbe[3]) - (128 + 8));
    return {(float(rgbe[0]) + 0.5f) * f, (float(rgbe[1]) + 0.5f) * f, (float(rgbe[2]) + 0.5f) * f};
}

/// Radiance HDR: "#?RADIANCE" (or another "#?" program name), header lines to a blank line
/// (FORMAT must be 32-bit_rle_rgbe; EXPOSURE and COLORCORR divide back out), the resolution line
/// "-Y height +X width" (or "+Y", rows from the bottom up), then scanlines flat, in the old
/// run-length scheme or the adaptive one (per channel), as Radiance writes them.
Image readRadianceHdr(const std::string& path, const std::vector<unsigned char>& bytes) {
    TextCursor cursor{bytes};
    std::string line;
    cursor.line(line);  // "#?RADIANCE"
    glm::vec3 divide_by(1.0f);
    bool header_ended = false;
    while (cursor.line(line)) {
        if (line.empty()) {
            header_ended = true;
            break;
        }
        if (line.rfind("FORMAT=", 0) == 0 && line != "FORMAT=32-bit_rle_rgbe") {
            fail(path, "Radiance HDR",
                 detail::printable(line.substr(7)) +
                     " pixels are not read (only 32-bit_rle_rgbe; convert XYZE to RGB first)");
        }
        if (line.rfind("EXPOSURE=", 0) == 0) {
            const float exposure = std::strtof(line.c_str() + 9, nullptr);
            if (!(exposure > 0.0f) || !std::isfinite(exposure))
                fail(path, "Radiance HDR", "bad " + detail::printable(line));
            divide_by *= exposure;
        }
        if (line.rfind("COLORCORR=", 0) == 0) {
            std::istringstream fields(line.substr(10));
            glm::vec3 c(0.0f);
            if (!(fields >> c.x >> c.y >> c.z) || !(c.x > 0.0f && c.y > 0.0f && c.z > 0.0f)) {
                fail(path, "Radiance HDR", "bad " + detail::printable(line));
            }
            divide_by *= c;
        }
    }
    if (!header_ended) fail(path, "Radiance HDR", "the header has no end (a blank line)");
    if (!cursor.line(line)) fail(path, "Radiance HDR", "no resolution line");
    std::istringstream resolution(line);
    std::string y_axis, x_axis, height_text, width_text;
    resolution >> y_axis >> height_text >> x_axis >> width_text;
    int width = 0, height = 0;
    if ((y_axis != "-Y" && y_axis != "+Y") || x_axis != "+X" || !parseDimension(height_text, height) ||
        !parseDimension(width_text, width)) {
        fail(path, "Radiance HDR",
             "the resolution line '" + detail::printable(line) + "' is not \"-Y height +X width\"");
    }
    if (uint64_t(width) * uint64_t(height) > detail::kMaxImagePixels) {
        fail(path, "Radiance HDR",
             std::to_string(width) + "x" + std::to_string(height) + " is " + detail::kTooManyPixels);
    }
    const bool bottom_up = y_axis == "+Y";
    size_t at = cursor.at;
    const auto need = [&](size_t count) {
        if (bytes.size() - at < count) fail(path, "Radiance HDR", "the pixels end early (truncated)");
    };
    // Every scanline takes at least 4 bytes (a run-length header or a first pixel): a header that
    // claims more rows than the rest of the file could hold is refused before anything is
    // allocated, and rows are allocated as they decode (in the file's order, flipped at the end
    // for "+Y"): a fuzzed 122-byte file claiming 900,000 rows of 100 pixels cleared 1.1 GB
    // (3.6 s) before finding no pixels.
    if (uint64_t(height) > (bytes.size() - at) / 4) {
        fail(path, "Radiance HDR",
             "the resolution line claims " + std::to_string(height) + " rows where the " +
                 std::to_string(bytes.size() - at) + " bytes after it hold at most " +
                 std::to_string((bytes.size() - at) / 4) + " (truncated)");
    }
    Image image;
    image.width = width;
    image.height = height;
    image.pixels.reserve(size_t(width) * size_t(height));
    std::vector<unsigned char> scanline(size_t(width) * 4);
    for (int row = 0; row < height; ++row) {
        need(4);
        const unsigned char* head = bytes.data() + at;
        if (width >= 8 && width < 32768 && head[0] == 2 && head[1] == 2 && (int(head[2]) << 8 | head[3]) == width) {
            // Adaptive run-length: each channel's bytes in turn, runs (count > 128) or literals.
            at += 4;
            for (int channel = 0; channel < 4; ++channel) {
                for (int x = 0; x < width;) {
                    need(1);
                    int count = bytes[at++];
                    const bool run = count > 128;
                    if (run) count -= 128;
                    if (count == 0 || x + count > width) fail(path, "Radiance HDR", "a bad run in a scanline");
                    need(run ? 1 : size_t(count));
                    for (int k = 0; k < count; ++k)
                        scanline[size_t(x + k) * 4 + size_t(channel)] = bytes[at + (run ? 0 : size_t(k))];
                    at += run ? 1 : size_t(count);
                    x += count;
                }
            }
        } else {
            // Flat pixels, where (1, 1, 1, n) repeats the previous pixel n times (shifted by 8
            // bits for each repeat marker in a row): the old run-length scheme.
            int shift = 0;
            for (int x = 0; x < width;) {
                need(4);
                const unsigned char* p = bytes.data() + at;
                at += 4;
                if (p[0] == 1 && p[1] == 1 && p[2] == 1) {
                    if (x == 0) fail(path, "Radiance HDR", "a repeat before the first pixel of a scanline");
                    if (shift > 24) fail(path, "Radiance HDR", "more than four repeat markers in a row");
                    const uint64_t count = uint64_t(p[3]) << shift;
                    if (count > uint64_t(width - x)) fail(path, "Radiance HDR", "a repeat past the scanline's end");
                    for (uint64_t k = 0; k < count; ++k, ++x)
                        std::memcpy(&scanline[size_t(x) * 4], &scanline[size_t(x - 1) * 4], 4);
                    shift += 8;
                } else {
                    std::memcpy(&scanline[size_t(x) * 4], p, 4);
                    ++x;
                    shift = 0;
                }
            }
        }
        for (int x = 0; x < width; ++x) image.pixels.push_back(rgbeToFloat(&scanline[size_t(x) * 4]) / divide_by);
    }
    if (bottom_up) {
        for (int y = 0; y < height / 2; ++y) {
            const auto top = image.pixels.begin() + std::ptrdiff_t(y) * width;
            std::swap_ranges(top, top + width, image.pixels.begin() + std::ptrdiff_t(height - 1 - y) * width);
        }
    }
    return image;
}

}  // namespace

Image readLinearImage(const std::string& path) {
    // The signature first: an EXR (the usual case, and the largest files) is read by OpenEXR.
    const std::vector<unsigned char> head = readFileBytes(path, 16);
    if (startsWith(head, "\x76\x2f\x31\x01", 4)) return readExr(path);
    if ((startsWith(head, "PF", 2) || startsWith(head, "Pf", 2)) && head.size() > 2 && std::isspace(head[2])) {
        return readPfm(path, readFileBytes(path));
    }
    if (startsWith(head, "#?", 2)) return readRadianceHdr(path, readFileBytes(path));
    const std::vector<unsigned char>& bytes = head;
    if (const char* format = displayFormatName(bytes)) {
        throw ImageError("cannot read '" + path + "': it is " + format +
                         " image, whose 8-bit display values (usually tone-mapped) are not radiance; give the "
                         "image as OpenEXR (sharcbake render writes one beside its PNG preview; Blender: File Format "
                         "OpenEXR), PFM or Radiance HDR");
    }
    throw ImageError("cannot read '" + path + "': not an OpenEXR, PFM or Radiance HDR image" +
                     (bytes.empty() ? std::string(" (the file is empty)") : std::string()));
}

}  // namespace sharcbake
