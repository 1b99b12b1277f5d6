// SPDX-License-Identifier: Apache-2.0
// .sharc -> OpenVDB: see vdb_export.h for the grid layout and the octant merge rule.
#include "sharcbake/vdb_export.h"

#include "sharcbake/cache_file.h"

#include <openvdb/openvdb.h>
#include <openvdb/io/File.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <unordered_map>
#include <utility>

#include <unistd.h>

namespace sharcbake {
namespace {

/// One output cell: the sums needed for the sample-weighted mean.
struct Cell {
    openvdb::Coord ijk;
    double weighted[3] = {0, 0, 0};  ///< Σ wᵢ·rᵢ
    double plain[3] = {0, 0, 0};     ///< Σ rᵢ (fallback when Σ wᵢ = 0)
    double weight = 0;               ///< Σ wᵢ
    uint32_t count = 0;
};

using GroupKey = std::pair<uint32_t, int32_t>;  // (level, octant or -1)
using Groups = std::map<GroupKey, std::unordered_map<uint64_t, Cell>>;

constexpr uint64_t kNormalBitsMask = uint64_t(kHashGridNormalMask) << kHashGridNormalOffset;

/// Groups the cache entries of the selected levels into cells (normal bits merged unless split).
Groups accumulate(const CacheView& cache, const std::vector<uint32_t>& levels, bool split) {
    Groups groups;
    for (uint64_t i = 0; i < cache.voxelCount(); ++i) {
        const CacheVoxel v = cache.voxel(i);
        const HashGridCell c = decodeHashGridKey(v.key);
        if (std::find(levels.begin(), levels.end(), c.level) == levels.end()) continue;
        const int32_t octant = split ? int32_t(c.normal_bits) : -1;
        Cell& cell = groups[{c.level, octant}][v.key & ~kNormalBitsMask];
        cell.ijk = openvdb::Coord(c.grid.x, c.grid.y, c.grid.z);
        const double w = std::max(0.0f, v.sample_weight);
        for (int k = 0; k < 3; ++k) {
            cell.weighted[k] += w * double(v.radiance[k]);
            cell.plain[k] += double(v.radiance[k]);
        }
        cell.weight += w;
        ++cell.count;
    }
    return groups;
}

openvdb::Vec3f meanRadiance(const Cell& cell) {
    openvdb::Vec3f r;
    for (int k = 0; k < 3; ++k) {
        r[k] = float(cell.weight > 0 ? cell.weighted[k] / cell.weight : cell.plain[k] / double(cell.count));
    }
    return r;
}

std::string octantName(int32_t octant) {
    std::string s = "n";
    const char axes[3] = {'x', 'y', 'z'};
    for (int k = 0; k < 3; ++k) {
        s += (octant >> k) & 1 ? '-' : '+';
        s += axes[k];
    }
    return s;
}

void tagGrid(openvdb::GridBase& grid, const std::string& name, uint32_t level, int32_t octant, float voxel_size,
             float scale, const std::string& meaning) {
    grid.setName(name);
    grid.insertMeta("sharcbake_level", openvdb::Int32Metadata(int32_t(level)));
    grid.insertMeta("sharcbake_voxel_size", openvdb::FloatMetadata(voxel_size));
    grid.insertMeta("sharcbake_scale", openvdb::FloatMetadata(scale));
    grid.insertMeta("sharcbake_normal_octant",
                    openvdb::StringMetadata(octant < 0 ? "merged (sample-weighted mean)" : octantName(octant)));
    grid.insertMeta("sharcbake_meaning", openvdb::StringMetadata(meaning));
}

struct GridSet {
    openvdb::FloatGrid::Ptr density, samples;
    openvdb::Vec3SGrid::Ptr color, radiance;
};

GridSet buildGrids(const std::unordered_map<uint64_t, Cell>& cells, const openvdb::math::Transform::Ptr& xform,
                   float scale) {
    GridSet g;
    g.density = openvdb::FloatGrid::create(0.0f);
    g.samples = openvdb::FloatGrid::create(0.0f);
    g.color = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    g.radiance = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    auto d = g.density->getAccessor();
    auto s = g.samples->getAccessor();
    auto c = g.color->getAccessor();
    auto r = g.radiance->getAccessor();
    for (const auto& [key, cell] : cells) {
        (void)key;
        const openvdb::Vec3f rad = meanRadiance(cell);
        const float rgb[3] = {rad[0], rad[1], rad[2]};
        d.setValueOn(cell.ijk, radianceLuminance(rgb) * scale);
        s.setValueOn(cell.ijk, float(cell.weight));
        c.setValueOn(cell.ijk, rad * scale);
        r.setValueOn(cell.ijk, rad);
    }
    for (openvdb::GridBase* grid :
         {static_cast<openvdb::GridBase*>(g.density.get()), static_cast<openvdb::GridBase*>(g.samples.get()),
          static_cast<openvdb::GridBase*>(g.color.get()), static_cast<openvdb::GridBase*>(g.radiance.get())}) {
        grid->setTransform(xform->copy());
    }
    g.density->setGridClass(openvdb::GRID_FOG_VOLUME);
    g.color->setVectorType(openvdb::VEC_INVARIANT);
    g.radiance->setVectorType(openvdb::VEC_INVARIANT);
    return g;
}

}  // namespace

VdbExportStatus exportCacheToVdb(const CacheView& cache, const std::string& out_path, const VdbExportOptions& options,
                                 std::vector<VdbGridInfo>* grids_out, std::string* message) {
    auto fail = [&](VdbExportStatus status, const std::string& text) {
        if (message) *message = text;
        return status;
    };
    if (grids_out) grids_out->clear();
    if (!cache.isOpen()) return fail(VdbExportStatus::kInvalidArgument, "no cache open");
    if (!std::isfinite(options.scale)) return fail(VdbExportStatus::kInvalidArgument, "scale must be finite");

    std::vector<uint32_t> present;
    for (const CacheLevel& l : cache.levels()) present.push_back(l.level);
    std::vector<uint32_t> levels = options.levels.empty() ? present : options.levels;
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    for (const uint32_t l : levels) {
        if (std::find(present.begin(), present.end(), l) == present.end()) {
            std::string list;
            for (const uint32_t p : present) list += (list.empty() ? "" : ",") + std::to_string(p);
            return fail(VdbExportStatus::kInvalidArgument, "level " + std::to_string(l) +
                                                               " is not in the cache (levels present: " +
                                                               (list.empty() ? "none" : list) + ")");
        }
    }
    if (levels.empty()) return fail(VdbExportStatus::kUnrepresentable, "the cache holds no voxels: nothing to export");

    openvdb::initialize();
    const HashGridParameters params = cache.gridParameters();
    std::map<uint32_t, openvdb::math::Transform::Ptr> transforms;
    for (const uint32_t l : levels) {
        const float s = voxelSize(l, params);
        if (!std::isfinite(s) || s <= 0.0f) {
            return fail(VdbExportStatus::kUnrepresentable, "level " + std::to_string(l) + " has no finite voxel size");
        }
        // VDB voxel centres sit at index × s; the cache voxel g spans [g·s, (g+1)·s).
        try {
            auto xform = openvdb::math::Transform::createLinearTransform(double(s));
            xform->postTranslate(openvdb::Vec3d(0.5 * double(s)));
            transforms[l] = xform;
        } catch (const std::exception& e) {
            return fail(VdbExportStatus::kUnrepresentable, "level " + std::to_string(l) + ": voxel size " +
                                                               std::to_string(s) + " is out of OpenVDB's range: " + e.what());
        }
    }

    openvdb::GridPtrVec grids;
    auto add = [&](const openvdb::GridBase::Ptr& grid, uint32_t level, int32_t octant) {
        if (grid->activeVoxelCount() == 0) return;
        grids.push_back(grid);
        if (grids_out) {
            grids_out->push_back({grid->getName(), level, octant, uint64_t(grid->activeVoxelCount()),
                                  float(grid->voxelSize()[0])});
        }
    };

    // `density` and `color` first: the merged finest (smallest voxel) level exported.
    const uint32_t finest = levels.front();
    {
        const Groups merged = accumulate(cache, {finest}, false);
        const GridSet g = buildGrids(merged.begin()->second, transforms[finest], options.scale);
        const float s = voxelSize(finest, params);
        tagGrid(*g.density, "density", finest, -1, s, options.scale,
                "luminance of radiance x scale, finest level (same as level" + std::to_string(finest) + "_density)");
        tagGrid(*g.color, "color", finest, -1, s, options.scale,
                "radiance x scale, finest level (same as level" + std::to_string(finest) + "_color)");
        add(g.density, finest, -1);
        add(g.color, finest, -1);
    }

    const Groups groups = accumulate(cache, levels, options.split_normals);
    for (const auto& [group, cells] : groups) {
        const auto [level, octant] = group;
        const float s = voxelSize(level, params);
        const GridSet g = buildGrids(cells, transforms[level], options.scale);
        const std::string prefix =
            "level" + std::to_string(level) + (octant < 0 ? std::string() : "_" + octantName(octant)) + "_";
        if (options.density) {
            tagGrid(*g.density, prefix + "density", level, octant, s, options.scale, "luminance of radiance x scale");
            add(g.density, level, octant);
        }
        if (options.color) {
            tagGrid(*g.color, prefix + "color", level, octant, s, options.scale, "radiance x scale");
            add(g.color, level, octant);
        }
        if (options.radiance) {
            tagGrid(*g.radiance, prefix + "radiance", level, octant, s, 1.0f, "mean outgoing radiance (unscaled)");
            add(g.radiance, level, octant);
        }
        if (options.samples) {
            tagGrid(*g.samples, prefix + "samples", level, octant, s, 1.0f, "effective sample count (sum of weights)");
            add(g.samples, level, octant);
        }
    }

    openvdb::MetaMap meta;
    meta.insertMeta("sharcbake_source", openvdb::StringMetadata(options.source_path));
    meta.insertMeta("sharcbake_format_version", openvdb::StringMetadata(std::to_string(cache.versionMajor()) + "." +
                                                                        std::to_string(cache.versionMinor())));
    meta.insertMeta("sharcbake_writer", openvdb::StringMetadata(options.writer));
    meta.insertMeta("units", openvdb::StringMetadata("glTF metres, +Y up"));
    meta.insertMeta("sharcbake_octants",
                    openvdb::StringMetadata(options.split_normals ? "split: one grid set per normal octant"
                                                                  : "merged: sample-weighted mean of the octants"));
    meta.insertMeta("sharcbake_grid_logarithm_base", openvdb::FloatMetadata(params.logarithm_base));
    meta.insertMeta("sharcbake_grid_scene_scale", openvdb::FloatMetadata(params.scene_scale));
    meta.insertMeta("sharcbake_grid_level_bias", openvdb::FloatMetadata(params.level_bias));
    meta.insertMeta("sharcbake_display_scale", openvdb::FloatMetadata(options.scale));
    for (size_t i = 0; i < cache.metadataCount(); ++i) {
        meta.insertMeta("sharcbake_bake_" + std::string(cache.metadataKey(i)),
                        openvdb::StringMetadata(std::string(cache.metadataValue(i))));
    }

    // The caches' output rules (cache_file.h): the grids go to a temporary beside the target, which
    // is read back in full (OpenVDB does not report write errors: a full disk leaves a truncated
    // file) and only then renamed over the target. A device or FIFO is never replaced, and on
    // failure the previous file is intact. (io::File, not io::Stream: vdb_render needs the grid
    // offsets that only a file archive stores.)
    std::string target, temporary, problem;
    if (prepareOutputFile(out_path, &target, &temporary, &problem) != CacheFileStatus::kOk) {
        return fail(VdbExportStatus::kIoError, "cannot write " + out_path + ": " + problem);
    }
    try {
        openvdb::io::File file(temporary);
        file.write(grids, meta);
        file.close();
        openvdb::io::File check(temporary);
        check.open(false);
        const openvdb::GridPtrVecPtr read_back = check.getGrids();
        check.close();
        if (!read_back || read_back->size() != grids.size()) throw std::runtime_error("the grids do not read back");
    } catch (const std::exception& e) {
        ::unlink(temporary.c_str());
        return fail(VdbExportStatus::kIoError, "cannot write " + out_path + " (disk full?): " + e.what() +
                                                   "; the previous file is untouched");
    }
    if (commitOutputFile(temporary, target, &problem) != CacheFileStatus::kOk) {
        return fail(VdbExportStatus::kIoError, "cannot write " + out_path + ": " + problem);
    }
    return VdbExportStatus::kOk;
}

}  // namespace sharcbake
