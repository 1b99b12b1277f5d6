// SPDX-License-Identifier: Apache-2.0
// .sharc -> OpenVDB: see vdb_export.h for the grid layout and the octant merge rule.
#include "sharcbake/vdb_export.h"

#include "sharcbake/cache_file.h"

#include <openvdb/io/Archive.h>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <utility>

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
/// Cells are decoded near the file's grid anchor (SPEC §H.6a): a scene far from the origin keeps
/// its place.
Groups accumulate(const CacheView& cache, const std::vector<uint32_t>& levels, bool split) {
    Groups groups;
    const HashGridKeyDecoder decoder(cache.gridParameters(), cache.gridAnchor());
    for (uint64_t i = 0; i < cache.voxelCount(); ++i) {
        const CacheVoxel v = cache.voxel(i);
        const HashGridCell c = decoder.decode(v.key);
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

/// "xpos_yneg_zpos": the signs of the normal's components in a sharc octant (a bit set is a
/// negative component). Plain letters, so the names work in attribute expressions.
std::string octantName(int32_t octant) {
    std::string s;
    const char axes[3] = {'x', 'y', 'z'};
    for (int k = 0; k < 3; ++k) {
        s += (k ? "_" : "") + std::string(1, axes[k]) + ((octant >> k) & 1 ? "neg" : "pos");
    }
    return s;
}

/// Names and describes a grid. Its voxel size is recorded in VDB units (the grid transform's,
/// scene units x `length_scale`: what a viewer measures, and what an emission of radiance per
/// voxel width divides by) and in the scene's own units.
void tagGrid(openvdb::GridBase& grid, const std::string& name, uint32_t level, int32_t octant, float voxel_size,
             double length_scale, float scale, const std::string& meaning) {
    grid.setName(name);
    grid.insertMeta("sharcbake_level", openvdb::Int32Metadata(int32_t(level)));
    grid.insertMeta("sharcbake_voxel_size", openvdb::FloatMetadata(float(double(voxel_size) * length_scale)));
    grid.insertMeta("sharcbake_scene_voxel_size", openvdb::FloatMetadata(voxel_size));
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

/// The levels to export, sorted, each one the cache holds; an error message otherwise.
std::string selectLevels(const CacheView& cache, const VdbExportOptions& options, std::vector<uint32_t>& levels) {
    std::vector<uint32_t> present;
    for (const CacheLevel& l : cache.levels()) present.push_back(l.level);
    levels = options.levels.empty() ? present : options.levels;
    std::sort(levels.begin(), levels.end());
    levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
    for (const uint32_t l : levels) {
        if (std::find(present.begin(), present.end(), l) == present.end()) {
            std::string list;
            for (const uint32_t p : present) list += (list.empty() ? "" : ",") + std::to_string(p);
            return "level " + std::to_string(l) + " is not in the cache (levels present: " +
                   (list.empty() ? "none" : list) + ")";
        }
    }
    return {};
}

/// Index-to-world transform of one level: VDB voxel centres sit at index x s, and the cache voxel
/// g holds the points p whose biased position p + 1e-4 (SHaRC's position bias, per component)
/// lies in [g s, (g+1) s), so the index space is shifted by half a voxel less the bias; s and the
/// shift are then multiplied by the length scale. (A surface of a model 0.1 mm across baked in
/// micrometre voxels would otherwise sit 1e-4 units, a hundred voxels, from its voxels.) For a
/// Z-up viewer the world is then turned +90 degrees about X: glTF's (x, y, z) becomes (x, -z, y).
openvdb::math::Transform::Ptr levelTransform(float voxel_size, double length_scale, VdbUpAxis up) {
    const double s = double(voxel_size) * length_scale;
    auto xform = openvdb::math::Transform::createLinearTransform(s);
    xform->postTranslate(openvdb::Vec3d((0.5 * double(voxel_size) - double(kHashGridPositionBias)) * length_scale));
    if (up == VdbUpAxis::kZ) xform->postRotate(0.5 * openvdb::math::pi<double>(), openvdb::math::X_AXIS);
    return xform;
}

/// The grids written, in file order, and what is said about them.
class GridList {
public:
    explicit GridList(std::vector<VdbGridInfo>* info) : info_(info) {}
    void add(const openvdb::GridBase::Ptr& grid, uint32_t level, int32_t octant, float voxel_size) {
        if (grid->activeVoxelCount() == 0) return;  // empty grids are left out
        grids_.push_back(grid);
        if (info_) info_->push_back({grid->getName(), level, octant, uint64_t(grid->activeVoxelCount()), voxel_size});
    }
    const openvdb::GridPtrVec& grids() const { return grids_; }

private:
    openvdb::GridPtrVec grids_;
    std::vector<VdbGridInfo>* info_;
};

/// `density` and `color`, first in the file: the merged finest level exported, under the names
/// viewers look for.
void addFinestGrids(const CacheView& cache, uint32_t finest, const openvdb::math::Transform::Ptr& xform,
                    const VdbExportOptions& options, GridList& list) {
    const Groups merged = accumulate(cache, {finest}, false);
    const GridSet g = buildGrids(merged.begin()->second, xform, options.scale);
    const float s = voxelSize(finest, cache.gridParameters());
    tagGrid(*g.density, "density", finest, -1, s, options.length_scale, options.scale,
            "luminance of radiance x scale, finest level (same as level" + std::to_string(finest) + "_density)");
    tagGrid(*g.color, "color", finest, -1, s, options.length_scale, options.scale,
            "radiance x scale, finest level (same as level" + std::to_string(finest) + "_color)");
    list.add(g.density, finest, -1, s);
    list.add(g.color, finest, -1, s);
}

/// levelL[_octant]_density, _color, _radiance and _samples, as the options choose.
void addLevelGrids(const CacheView& cache, const std::vector<uint32_t>& levels,
                   const std::map<uint32_t, openvdb::math::Transform::Ptr>& transforms,
                   const VdbExportOptions& options, GridList& list) {
    for (const auto& [group, cells] : accumulate(cache, levels, options.split_normals)) {
        const auto [level, octant] = group;
        const float s = voxelSize(level, cache.gridParameters());
        const GridSet g = buildGrids(cells, transforms.at(level), options.scale);
        const std::string prefix =
            "level" + std::to_string(level) + (octant < 0 ? std::string() : "_" + octantName(octant)) + "_";
        if (options.density) {
            tagGrid(*g.density, prefix + "density", level, octant, s, options.length_scale, options.scale,
                    "luminance of radiance x scale");
            list.add(g.density, level, octant, s);
        }
        if (options.color) {
            tagGrid(*g.color, prefix + "color", level, octant, s, options.length_scale, options.scale,
                    "radiance x scale");
            list.add(g.color, level, octant, s);
        }
        if (options.radiance) {
            tagGrid(*g.radiance, prefix + "radiance", level, octant, s, options.length_scale, 1.0f,
                    "mean outgoing radiance (unscaled)");
            list.add(g.radiance, level, octant, s);
        }
        if (options.samples) {
            tagGrid(*g.samples, prefix + "samples", level, octant, s, options.length_scale, 1.0f,
                    "effective sample count (sum of weights)");
            list.add(g.samples, level, octant, s);
        }
    }
}

/// The file's metadata: where the grids come from, their units and axes, the grid parameters an
/// engine needs, and the cache's own metadata (bake_*).
openvdb::MetaMap fileMetadata(const CacheView& cache, const VdbExportOptions& options) {
    const HashGridParameters params = cache.gridParameters();
    openvdb::MetaMap meta;
    meta.insertMeta("sharcbake_source", openvdb::StringMetadata(options.source_path));
    meta.insertMeta("sharcbake_format_version", openvdb::StringMetadata(std::to_string(cache.versionMajor()) + "." +
                                                                        std::to_string(cache.versionMinor())));
    meta.insertMeta("sharcbake_writer", openvdb::StringMetadata(options.writer));
    char scaled[96] = "";
    if (options.length_scale != 1.0)
        std::snprintf(scaled, sizeof scaled, " x %.9g (one VDB unit is 1/%.9g glTF unit)", options.length_scale,
                      options.length_scale);
    meta.insertMeta("units",
                    openvdb::StringMetadata(
                        std::string("glTF metres") + scaled +
                        (options.up == VdbUpAxis::kZ ? ", turned +Z up (glTF (x, y, z) is (x, -z, y))" : ", +Y up")));
    meta.insertMeta("sharcbake_length_scale", openvdb::DoubleMetadata(options.length_scale));
    meta.insertMeta("sharcbake_up_axis", openvdb::StringMetadata(options.up == VdbUpAxis::kZ ? "z" : "y"));
    meta.insertMeta("sharcbake_octants",
                    openvdb::StringMetadata(options.split_normals ? "split: one grid set per normal octant"
                                                                  : "merged: sample-weighted mean of the octants"));
    meta.insertMeta("sharcbake_grid_logarithm_base", openvdb::FloatMetadata(params.logarithm_base));
    meta.insertMeta("sharcbake_grid_scene_scale", openvdb::FloatMetadata(params.scene_scale));
    meta.insertMeta("sharcbake_grid_level_bias", openvdb::FloatMetadata(params.level_bias));
    const Float3& anchor = cache.gridAnchor();
    meta.insertMeta("sharcbake_grid_anchor", openvdb::Vec3SMetadata(openvdb::Vec3s(anchor.x, anchor.y, anchor.z)));
    meta.insertMeta("sharcbake_display_scale", openvdb::FloatMetadata(options.scale));
    for (size_t i = 0; i < cache.metadataCount(); ++i) {
        meta.insertMeta("sharcbake_bake_" + std::string(cache.metadataKey(i)),
                        openvdb::StringMetadata(std::string(cache.metadataValue(i))));
    }
    return meta;
}

/// An OpenVDB archive serialised into memory as io::File lays it out, with the grid offsets that
/// vdb_render needs (io::Stream writes none). io::File itself ignores write errors: on a full
/// disk it left a truncated file, and reading that back to find out cost OpenVDB tens of seconds
/// of allocations sized by garbage. Bytes in memory are written by writeFileAtomically instead,
/// which checks every write.
class MemoryArchive : public openvdb::io::Archive {
public:
    std::string serialise(const openvdb::GridPtrVec& grids, const openvdb::MetaMap& meta) const {
        std::ostringstream out(std::ios_base::out | std::ios_base::binary);
        Archive::write(out, grids, /*seekable=*/true, meta);
        if (!out) throw std::runtime_error("OpenVDB could not serialise the grids");
        return std::move(out).str();
    }
};

/// The caches' output rules (cache_file.h): a temporary beside the target, every byte checked,
/// renamed over the target only when complete. A device or FIFO is never replaced, and on failure
/// the previous file is intact. Returns an error message, empty on success.
std::string writeGridsAtomically(const std::string& out_path, const openvdb::GridPtrVec& grids,
                                 const openvdb::MetaMap& meta) {
    std::string bytes;
    try {
        bytes = MemoryArchive().serialise(grids, meta);
    } catch (const std::exception& e) {
        return "cannot write " + out_path + ": " + e.what();
    }
    std::string problem;
    const CacheFileStatus status = writeFileAtomically(out_path, bytes.data(), bytes.size(), &problem);
    // The message names the file, and on a failed write says that the previous one is untouched.
    return status == CacheFileStatus::kOk ? std::string() : problem;
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
    if (!(std::isfinite(options.length_scale) && options.length_scale > 0.0))
        return fail(VdbExportStatus::kInvalidArgument, "length scale must be finite and positive");
    std::vector<uint32_t> levels;
    if (const std::string problem = selectLevels(cache, options, levels); !problem.empty()) {
        return fail(VdbExportStatus::kInvalidArgument, problem);
    }
    if (levels.empty()) return fail(VdbExportStatus::kUnrepresentable, "the cache holds no voxels: nothing to export");
    // density and color are radiance x scale in float32: a scale that takes the brightest voxel
    // beyond float32's range wrote infinities into the grids (exit 0). A cell's mean and its
    // luminance are at most its voxels' largest component.
    double brightest = 0.0;
    for (uint64_t i = 0; i < cache.voxelCount(); ++i) {
        const CacheVoxel v = cache.voxel(i);
        brightest = std::max({brightest, double(v.radiance[0]), double(v.radiance[1]), double(v.radiance[2])});
    }
    constexpr double kLargestFloat = double(std::numeric_limits<float>::max());
    if (brightest * std::abs(double(options.scale)) > kLargestFloat) {
        char text[240];
        std::snprintf(text, sizeof text,
                      "scale %g takes the brightest voxel's radiance (%g) beyond float32's range (%g): the grids "
                      "would hold infinities. Use a scale of at most %.3g",
                      double(options.scale), brightest, kLargestFloat, kLargestFloat / brightest);
        return fail(VdbExportStatus::kInvalidArgument, text);
    }

    openvdb::initialize();
    // A level's transform at a length scale, or null where OpenVDB refuses its voxel size
    // (micrometre voxels in metres: OpenVDB takes a scale near zero for a singular map).
    const auto transformAt = [&](uint32_t level, double length_scale) -> openvdb::math::Transform::Ptr {
        try {
            return levelTransform(voxelSize(level, cache.gridParameters()), length_scale, options.up);
        } catch (const std::exception&) {
            return nullptr;
        }
    };
    std::map<uint32_t, openvdb::math::Transform::Ptr> transforms;
    for (const uint32_t l : levels) {
        const float s = voxelSize(l, cache.gridParameters());
        if (!std::isfinite(s) || s <= 0.0f) {
            return fail(VdbExportStatus::kUnrepresentable, "level " + std::to_string(l) + " has no finite voxel size");
        }
        if ((transforms[l] = transformAt(l, options.length_scale))) continue;
        // Name the levels that do fit (a model of a millimetre has micrometre voxels at its
        // finest levels, and coarser ones OpenVDB holds), and a power-of-ten length scale at which
        // every level asked for fits.
        std::string fitting;
        for (const CacheLevel& present : cache.levels()) {
            if (transformAt(present.level, options.length_scale))
                fitting += (fitting.empty() ? "" : ",") + std::to_string(present.level);
        }
        double all_fit = 0.0;
        double candidate = options.length_scale;
        for (int step = 0; step < 15 && all_fit == 0.0; ++step) {
            candidate *= 10.0;
            if (!std::isfinite(candidate)) break;
            bool fits = true;
            for (const uint32_t level : levels) fits = fits && transformAt(level, candidate) != nullptr;
            if (fits) all_fit = candidate;
        }
        char size[32], scaled[200] = "";
        std::snprintf(size, sizeof size, "%.3g", double(s) * options.length_scale);
        if (all_fit > 0.0)
            std::snprintf(scaled, sizeof scaled, "write them %.9g times larger with --length-scale %.9g", all_fit,
                          all_fit);
        std::string fix;
        if (!fitting.empty()) fix = "export the levels that fit with --levels " + fitting;
        if (all_fit > 0.0) fix += (fix.empty() ? "" : ", or ") + std::string(scaled);
        if (fix.empty())
            fix = "no level of this cache fits at this length scale; a larger --length-scale makes them fit";
        return fail(VdbExportStatus::kUnrepresentable,
                    "level " + std::to_string(l) + ": voxel size " + size + " is out of OpenVDB's range; " + fix);
    }
    GridList list(grids_out);
    addFinestGrids(cache, levels.front(), transforms[levels.front()], options, list);
    addLevelGrids(cache, levels, transforms, options, list);
    if (const std::string problem = writeGridsAtomically(out_path, list.grids(), fileMetadata(cache, options));
        !problem.empty()) {
        return fail(VdbExportStatus::kIoError, problem);
    }
    return VdbExportStatus::kOk;
}

}  // namespace sharcbake
