// SPDX-License-Identifier: Apache-2.0
// `sharcbake export-vdb`: a .sharc cache as OpenVDB grids for vdb_view, Houdini and Blender.
// The cache is read through the runtime library; the grids come from sharcbake_vdb.
#include "cli/command_support.h"
#include "cli/commands.h"
#include "sharcbake/runtime.h"
#include "sharcbake/vdb_export.h"

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

struct ExportVdbOptions {
    std::string input;
    std::string output;
    std::vector<uint32_t> levels;
    std::vector<std::string> channels;
    float scale = 1.0f;
    bool split_normals = false;
    std::string up = "y";
    double length_scale = 1.0;
    bool quiet = false;
};

void run(const ExportVdbOptions& o) {
    checkOutputPath(o.output, "VDB", {o.input});
    checkReplacesOnlyItsKind(o.output, "VDB", vdbFileIdentifier(), "an OpenVDB file");
    CacheView view;
    CacheError error;
    const CacheFileStatus status = CacheView::openFile(o.input, &view, &error, CacheView::FileMode::kMap);
    if (status != CacheFileStatus::kOk) {
        throw CommandError(exitCodeFor(status),
                           error.message + " [" + toString(status) + "]");
    }
    VdbExportOptions options;
    options.levels = o.levels;
    if (!o.channels.empty()) {
        options.density = options.color = options.radiance = options.samples = false;
        for (const std::string& c : o.channels) {
            if (c == "density") options.density = true;
            if (c == "color") options.color = true;
            if (c == "radiance") options.radiance = true;
            if (c == "samples") options.samples = true;
        }
    }
    options.scale = o.scale;
    options.split_normals = o.split_normals;
    options.up = o.up == "z" ? VdbUpAxis::kZ : VdbUpAxis::kY;
    options.length_scale = o.length_scale;
    options.source_path = o.input;
    options.writer = "sharcbake " SHARCBAKE_VERSION " export-vdb";

    std::vector<VdbGridInfo> grids;
    std::string message;
    const VdbExportStatus result = exportCacheToVdb(view, o.output, options, &grids, &message);
    if (result == VdbExportStatus::kIoError) throw CommandError(kExitIo, message);
    if (result == VdbExportStatus::kUnrepresentable) throw CommandError(kExitInvalidInput, o.input + ": " + message);
    if (result != VdbExportStatus::kOk) throw CommandError(kExitUsage, message);
    if (o.quiet) return;
    std::printf("%s: %s from %s", o.output.c_str(), counted(grids.size(), "grid").c_str(),
                counted(view.voxelCount(), "cache voxel").c_str());
    if (o.length_scale != 1.0)
        std::printf(", positions and sizes x %.9g (voxel sizes below: the cache's)", o.length_scale);
    std::printf("\n");
    for (const VdbGridInfo& g : grids) {
        std::printf("  %-28s level %3u  voxel size %-10g  %10" PRIu64 " active voxels\n", g.name.c_str(), g.level,
                    double(g.voxel_size), g.active_voxels);
    }
}

}  // namespace

void registerExportVdbCommand(CLI::App& app) {
    auto o = std::make_shared<ExportVdbOptions>();
    CLI::App* cmd = app.add_subcommand(
        "export-vdb",
        "Write a .sharc cache as OpenVDB grids to look at it in vdb_view, Houdini or Blender.\n\n"
        "Each SHaRC level present becomes its own grid set with its own voxel size: a VDB voxel is\n"
        "one cache voxel, placed where the cache has it (glTF units, metres, +Y up; --up z turns\n"
        "it +Z up for Blender and other Z-up viewers; --length-scale 1000 writes it in millimetres,\n"
        "for a small model whose finest voxels are too small for OpenVDB).\n"
        "Grids, in file order:\n"
        "  density, color          the finest level exported again under the names viewers look\n"
        "                          for; 'density' is first, so vdb_render renders it\n"
        "  levelL_density          float: luminance of the radiance x --scale (a fog volume)\n"
        "  levelL_color            vec3: radiance x --scale\n"
        "  levelL_radiance         vec3: mean outgoing radiance, unscaled (W/(m^2 sr) per channel)\n"
        "  levelL_samples          float: effective sample count behind the mean\n"
        "SHaRC keeps up to 8 entries per voxel, one per octant of the surface normal. They are\n"
        "merged into one VDB voxel by their sample-weighted mean (samples = sum of weights);\n"
        "--split-normals writes one grid set per octant instead (levelL_xpos_yneg_zpos_density:\n"
        "the signs of the normal's components).\n"
        "File metadata records the source cache, its format version, the bake metadata (scene,\n"
        "settings) and the units; each grid records its level, voxel size and scale.\n\n"
        "Viewing the result:\n"
        "  vdb_print -l out.vdb                    list grids, transforms and metadata\n"
        "  vdb_view out.vdb                        interactive viewer (OpenVDB tools)\n"
        "  vdb_render out.vdb out.exr -res 640x480 -translate 0,1,4 -absorb 0.5,0.5,0.5\n"
        "  Houdini: a File SOP reading out.vdb (then a Volume Visualization SOP on 'density')\n"
        "  Blender: blender --python viewer_export/blender/import_sharc_vdb.py -- out.vdb (upright,\n"
        "  with an emission material reading 'color'; export one level with --levels for it)\n"
        "  Raise --scale when a dim cache looks empty; lower it when it looks solid.\n\n"
        "Examples:\n"
        "  sharcbake export-vdb out/cornell_box.sharc -o out/cornell_box.vdb\n"
        "  sharcbake export-vdb cache.sharc -o fine.vdb --levels 3,4 --channels density,color --scale 4\n"
        "  sharcbake export-vdb ring.sharc -o ring_mm.vdb --length-scale 1000\n\n"
        "Exit codes: 1 bad option (or a --levels level the cache lacks), or an output that is the\n"
        "input; 2 cannot read/write (an existing output that is not a regular file included);\n"
        "3 invalid cache, or one OpenVDB cannot hold (no voxels, a voxel size out of its range).");
    pathOption(cmd->add_option("cache", o->input, "Cache file (.sharc)"))->required();
    pathOption(cmd->add_option("-o,--output", o->output, "Output OpenVDB file (.vdb)"))->required();
    cmd->add_option("--levels", o->levels, "Comma-separated SHaRC levels to export (default: all present)")
        ->delimiter(',');
    cmd->add_option("--channels", o->channels,
                    "Comma-separated per-level grids: density,color,radiance,samples (default: all)")
        ->delimiter(',')
        ->check(CLI::IsMember({"density", "color", "radiance", "samples"}));
    cmd->add_option("--scale", o->scale, "Display scale for the density and color grids")
        ->capture_default_str()
        ->check(CLI::PositiveNumber)->check(kFiniteNumber);
    cmd->add_flag("--split-normals", o->split_normals, "One grid set per normal octant instead of merging them");
    cmd->add_option("--up", o->up,
                    "Up axis of the written world: y (glTF's, unchanged) or z (turned +90 degrees about X, "
                    "glTF (x, y, z) at (x, -z, y), for Blender and other Z-up viewers)")
        ->capture_default_str()
        ->check(CLI::IsMember({"y", "z"}));
    cmd->add_option("--length-scale", o->length_scale,
                    "Multiply every position and voxel size by this: 1000 writes metres as millimetres, for "
                    "voxels too small for OpenVDB (under about 1e-5) or a viewer that expects other units")
        ->capture_default_str()
        ->check(CLI::PositiveNumber)
        ->check(kFiniteNumber);
    cmd->add_flag("-q,--quiet", o->quiet, "Print nothing on success but warnings");
    cmd->callback([o] { run(*o); });
}

}  // namespace sharcbake
