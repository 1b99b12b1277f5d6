// SPDX-License-Identifier: Apache-2.0
// `sharcbake info` and `sharcbake validate`: what a .sharc file holds, and whether it is valid
// (SPEC.md §F.10 rules). Everything is read through the runtime library (CacheView).
#include "cli/command_support.h"
#include "cli/commands.h"
#include "support/json.h"
#include "sharcbake/runtime.h"

#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace sharcbake {
namespace {

struct InfoOptions {
    std::string path;
    bool json = false;
};

std::string fourcc(uint32_t type) {
    std::string s;
    for (int i = 0; i < 4; ++i) {
        const char c = char((type >> (8 * i)) & 0xFF);
        s += (c >= 0x20 && c < 0x7F && c != '"' && c != '\\') ? c : '?';
    }
    return s;
}

/// Text from the file for the terminal: control characters (ESC, BEL, CR, ..., DEL and the C1
/// controls U+0080-U+009F) become \xNN escapes, so a crafted cache cannot drive the terminal.
std::string printable(std::string_view text) {
    std::string out;
    for (size_t i = 0; i < text.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(text[i]);
        const bool c1 = c == 0xC2 && i + 1 < text.size() && static_cast<unsigned char>(text[i + 1]) >= 0x80 &&
                        static_cast<unsigned char>(text[i + 1]) <= 0x9F;
        if (c < 0x20 || c == 0x7F || c1 || c == '\\') {
            char buf[8];
            if (c == '\\') {
                out += "\\\\";
                continue;
            }
            std::snprintf(buf, sizeof buf, "\\x%02X", c1 ? static_cast<unsigned char>(text[++i]) : c);
            out += c1 ? "\\xC2" + std::string(buf) : std::string(buf);
        } else {
            out += char(c);
        }
    }
    return out;
}


CacheView openOrThrow(const std::string& path) {
    CacheView view;
    CacheError error;
    const CacheFileStatus status = CacheView::openFile(path, &view, &error, CacheView::FileMode::kMap);
    if (status != CacheFileStatus::kOk) {
        throw CommandError(exitCodeFor(status), error.message + " [" + toString(status) + "]");
    }
    return view;
}

void printText(const std::string& path, const CacheView& v) {
    const HashGridParameters p = v.gridParameters();
    const CacheStats s = v.stats();
    std::printf("%s: sharcbake cache, format %u.%u, %" PRIu64 " bytes\n", path.c_str(), v.versionMajor(),
                v.versionMinor(), v.fileSize());
    std::printf("Sections (%zu):\n", v.sections().size());
    for (const CacheSectionInfo& sec : v.sections()) {
        std::printf("  %s  %-8s offset %10" PRIu64 "  length %10" PRIu64 "  crc32 %08X%s\n", fourcc(sec.type).c_str(),
                    sec.required ? "required" : "optional", sec.offset, sec.length, sec.crc32,
                    sec.known ? "" : "  (unknown, skipped)");
    }
    std::printf("Grid: keys 17/9/3 bits (SHaRC 1.7+), Jenkins32 xor hash, bucket %u, LOD by camera distance\n",
                p.bucket_size);
    // %.9g: every binary32 value reads back to the same bits, and engines copy these three into SHaRC
    // parameters bit for bit (a level bias of 2.515625 printed as 2.51562 moved keys).
    std::printf("  log base %.9g, scene scale %.9g, level bias %.9g, bake capacity %u\n", double(p.logarithm_base),
                double(p.scene_scale), double(p.level_bias), v.bakeCapacity());
    const Float3& anchor = v.gridAnchor();
    if (anchor.x != 0.0f || anchor.y != 0.0f || anchor.z != 0.0f) {
        std::printf(
            "  anchor (%.9g, %.9g, %.9g) (ANCR): keys decode to the cells nearest it, for a scene beyond the "
            "17-bit grid range around the origin; lookups do not need it\n",
            double(anchor.x), double(anchor.y), double(anchor.z));
    }
    std::printf("Voxels: %" PRIu64 " live (%.2f%% of the bake capacity; empty slots are not stored), %.1f bytes/voxel\n",
                s.voxels, v.bakeCapacity() ? 100.0 * double(s.voxels) / double(v.bakeCapacity()) : 0.0,
                s.bytes_per_voxel);
    if (s.voxels > 0) {
        std::printf("  radiance min (%g, %g, %g) max (%g, %g, %g) mean (%g, %g, %g)\n", double(s.radiance_min[0]),
                    double(s.radiance_min[1]), double(s.radiance_min[2]), double(s.radiance_max[0]),
                    double(s.radiance_max[1]), double(s.radiance_max[2]), s.radiance_mean[0], s.radiance_mean[1],
                    s.radiance_mean[2]);
        std::printf("  sample weight min %g max %g total %g\n", double(s.weight_min), double(s.weight_max),
                    s.weight_total);
    }
    // What an engine's SHaRC table gets (SPEC §G.6): the scale from RSCL and what fp16 clips.
    const GpuRadianceReport gpu = v.gpuRadianceCheck();
    std::printf("GPU buffers: radiance x %g (%s), fp16 up to 65504: %s\n", double(gpu.radiance_scale),
                v.gpuRadianceScale() == 1.0f ? "no RSCL section" : "RSCL section",
                gpu.warning.empty() ? "nothing clips" : gpu.warning.c_str());
    std::printf("Voxel materials: %s\n", v.hasVoxelMaterials()
                                             ? "kept (VMAT): buffers for SDK builds with separate emissive or "
                                               "material demodulation can be made"
                                             : "not kept (bake --voxel-materials keeps them, for SDK builds with "
                                               "separate emissive or material demodulation)");
    std::printf("Levels: %zu present of 511 (others hold no voxels and are not stored)\n", v.levels().size());
    for (const CacheLevel& l : v.levels()) {
        std::printf("  level %3u  voxel size %-10g  %10u voxels\n", l.level, double(voxelSize(l.level, p)),
                    l.voxel_count);
    }
    // Which runtime cameras the levels were baked for (bake's view_region, levels_covered and
    // predicted_hit_rate metadata).
    bool has_region = false, has_levels = false, has_rate = false;
    const std::string_view region = v.metadata("view_region", &has_region);
    const std::string_view covered = v.metadata("levels_covered", &has_levels);
    const std::string_view rate = v.metadata("predicted_hit_rate", &has_rate);
    if (has_region && has_levels) {
        std::printf("Baked for views: %s; levels %s\n", printable(region).c_str(), printable(covered).c_str());
    }
    if (has_rate) std::printf("Predicted hit rate: %s\n", printable(rate).c_str());
    // What the bake left out because the scene had no use for it (bake's "left_out" metadata),
    // next to what the file leaves out by design (empty slots, absent levels, above).
    for (size_t i = 0; i < v.metadataCount(); ++i) {
        if (v.metadataKey(i) == "left_out") {
            std::printf("Left out by the bake: %s\n", printable(v.metadataValue(i)).c_str());
        } else if (v.metadataKey(i) == "capacity_choice") {
            std::printf("Table capacity %s\n", printable(v.metadataValue(i)).c_str());
        }
    }
    std::printf("Metadata (%zu):\n", v.metadataCount());
    for (size_t i = 0; i < v.metadataCount(); ++i) {
        std::printf("  %s: %s\n", printable(v.metadataKey(i)).c_str(), printable(v.metadataValue(i)).c_str());
    }
}

Json vec3Json(const float v[3]) { return Json::array({jsonNumber(v[0]), jsonNumber(v[1]), jsonNumber(v[2])}); }
Json vec3Json(const double v[3]) { return Json::array({jsonNumber(v[0]), jsonNumber(v[1]), jsonNumber(v[2])}); }

void printJson(const std::string& path, const CacheView& v) {
    const HashGridParameters p = v.gridParameters();
    const CacheStats s = v.stats();
    const GpuRadianceReport gpu = v.gpuRadianceCheck();
    Json sections = Json::array(), levels = Json::array();
    for (const CacheSectionInfo& sec : v.sections()) {
        sections.push_back({{"type", fourcc(sec.type)},
                            {"required", sec.required},
                            {"known", sec.known},
                            {"offset", sec.offset},
                            {"length", sec.length},
                            {"crc32", sec.crc32}});
    }
    for (const CacheLevel& l : v.levels()) {
        levels.push_back({{"level", l.level}, {"voxel_size", jsonNumber(voxelSize(l.level, p))}, {"voxels", l.voxel_count}});
    }
    std::vector<std::pair<std::string, std::string>> pairs;
    for (size_t i = 0; i < v.metadataCount(); ++i) pairs.emplace_back(v.metadataKey(i), v.metadataValue(i));
    const Json json = {
        {"schema", jsonSchemaId("info")},
        {"file", path},
        {"valid", true},
        {"version", {{"major", v.versionMajor()}, {"minor", v.versionMinor()}}},
        {"file_size", v.fileSize()},
        {"sections", sections},
        {"grid",
         {{"position_bits", 17},
          {"level_bits", 9},
          {"normal_bits", 3},
          {"bucket_size", p.bucket_size},
          {"hash", "jenkins32_xor"},
          {"lod_policy", "camera_distance"},
          {"logarithm_base", jsonNumber(p.logarithm_base)},
          {"scene_scale", jsonNumber(p.scene_scale)},
          {"level_bias", jsonNumber(p.level_bias)},
          {"anchor",
           Json::array({jsonNumber(v.gridAnchor().x), jsonNumber(v.gridAnchor().y), jsonNumber(v.gridAnchor().z)})},
          {"bake_capacity", v.bakeCapacity()}}},
        {"gpu",
         {{"radiance_scale", jsonNumber(gpu.radiance_scale)},
          {"brightest", jsonNumber(gpu.brightest)},
          {"fitting_radiance_scale", jsonNumber(gpu.fitting_radiance_scale)},
          {"clipped_voxels", gpu.clipped_voxels},
          {"flushed_voxels", gpu.flushed_voxels},
          {"voxel_materials", v.hasVoxelMaterials()}}},
        {"voxels", s.voxels},
        {"bytes_per_voxel", jsonNumber(s.bytes_per_voxel)},
        {"radiance",
         {{"min", vec3Json(s.radiance_min)}, {"max", vec3Json(s.radiance_max)}, {"mean", vec3Json(s.radiance_mean)}}},
        {"sample_weight",
         {{"min", jsonNumber(s.weight_min)}, {"max", jsonNumber(s.weight_max)}, {"total", jsonNumber(s.weight_total)}}},
        {"levels", levels},
        {"metadata", metadataJson(pairs)},  // numbers as numbers, the rest as strings
    };
    std::fputs(jsonText(json).c_str(), stdout);
}

}  // namespace

void registerInfoCommand(CLI::App& app) {
    auto o = std::make_shared<InfoOptions>();
    CLI::App* info = app.add_subcommand(
        "info",
        "Show what a .sharc cache holds: format version, sections, grid parameters, levels present,\n"
        "voxel counts and sizes, radiance statistics and bake metadata. The file is fully validated\n"
        "first (exit 3 if invalid, 2 if unreadable).\n\n"
        "Example:\n"
        "  sharcbake info out/cornell_box.sharc --json");
    pathOption(info->add_option("file", o->path, "Cache file (.sharc)"))->required();
    info->add_flag("--json", o->json, "Machine-readable JSON on stdout");
    info->callback([o] {
        const CacheView view = openOrThrow(o->path);
        if (o->json) {
            printJson(o->path, view);
        } else {
            printText(o->path, view);
        }
    });

    auto v = std::make_shared<InfoOptions>();
    CLI::App* validate =
        app.add_subcommand("validate",
                           "Check a .sharc cache against every validation rule of cache_format/SPEC.md (V1..V21).\n"
                           "On failure prints the rule that failed. Exit codes: 0 valid, 3 invalid, 2 cannot read.\n\n"
                           "Example:\n"
                           "  sharcbake validate out/cornell_box.sharc");
    pathOption(validate->add_option("file", v->path, "Cache file (.sharc)"))->required();
    validate->add_flag("--json", v->json, "Print the result as JSON");
    validate->callback([v] {
        CacheView view;
        CacheError error;
        const CacheFileStatus status = CacheView::openFile(v->path, &view, &error);
        if (v->json) {
            const Json json = {{"schema", jsonSchemaId("validate")},
                               {"file", v->path},
                               {"valid", status == CacheFileStatus::kOk},
                               {"status", toString(status)},
                               {"rule", error.rule ? Json("V" + std::to_string(error.rule)) : Json(nullptr)},
                               {"message", error.message}};
            std::fputs(jsonText(json).c_str(), stdout);
            if (status != CacheFileStatus::kOk) throw CommandError(exitCodeFor(status), error.message);
            return;
        }
        if (status != CacheFileStatus::kOk) {
            throw CommandError(exitCodeFor(status), std::string(status == CacheFileStatus::kIoError ? "" : "invalid: ") +
                                                        error.message + " [" + toString(status) + "]");
        }
        std::printf("%s: valid (format %u.%u, %s, %s, %s)\n", v->path.c_str(), view.versionMajor(), view.versionMinor(),
                    counted(view.voxelCount(), "voxel").c_str(), counted(view.levels().size(), "level").c_str(),
                    counted(view.sections().size(), "section").c_str());
    });
}

}  // namespace sharcbake
