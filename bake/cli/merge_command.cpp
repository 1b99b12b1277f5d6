// SPDX-License-Identifier: Apache-2.0
// `sharcbake merge`: shards baked independently (bake --shard i/N, e.g. a scheduler's job
// array) combined into one cache, voxel by voxel, weighted by samples (cache_merge.h).
#include "cli/command_support.h"
#include "cli/commands.h"
#include "sharcbake/cache_merge.h"
#include "support/fnv1a.h"

#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace sharcbake {
namespace {

struct MergeOptions {
    std::vector<std::string> inputs;
    std::string output_path;
    bool quiet = false;
};

/// Metadata that must be equal for two caches to estimate the same radiance: the scene's files,
/// the sky, and the path length (grid parameters and format version are checked by mergeCaches).
/// Caches baked before bakes recorded "sky" lack it: those may still merge with each other.
const std::vector<std::string> kMustAgree = {"scene_hash", "sky", "max_bounces"};

/// Metadata that describes one bake or one merge, not this merge: recomputed or dropped.
bool describesOneBake(const std::string& key) {
    return key == "writer" || key == "iterations" || key == "shard" || key == "stop_reason" || key == "merged_inputs" ||
           key == "merged_shards" || key == "merged_bakes";
}

const std::string* findMetadata(const CacheData& data, const std::string& key) {
    for (const auto& entry : data.metadata) {
        if (entry.first == key) return &entry.second;
    }
    return nullptr;
}

/// "a,b,c" split at the commas (nothing for an empty text).
std::vector<std::string> commaList(const std::string* text) {
    std::vector<std::string> items;
    if (!text || text->empty()) return items;
    size_t start = 0;
    for (size_t comma = text->find(',');; comma = text->find(',', start)) {
        items.push_back(text->substr(start, comma - start));
        if (comma == std::string::npos) break;
        start = comma + 1;
    }
    return items;
}

/// The bakes a cache holds, by a fingerprint of each bake's own metadata: itself for a bake, the
/// list it records for a merge (merged_bakes). A merge of merges is a merge of their bakes, and a
/// bake that two inputs both hold would count its samples twice.
std::vector<std::string> bakesIn(const CacheData& data) {
    if (const std::string* merged = findMetadata(data, "merged_bakes")) return commaList(merged);
    uint64_t hash = kFnv1a64Basis;
    for (const auto& [key, value] : data.metadata) {
        hash = fnv1a64(key.data(), key.size(), hash);
        hash = fnv1a64("=", 1, hash);
        hash = fnv1a64(value.data(), value.size(), hash);
        hash = fnv1a64("\n", 1, hash);
    }
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", (unsigned long long)hash);
    return {text};
}

/// Shard i of N (bake --shard i/N); ordered by N, then i.
struct Shard {
    uint32_t count = 0;
    uint32_t index = 0;
    bool operator<(const Shard& o) const { return count != o.count ? count < o.count : index < o.index; }
    std::string text() const { return std::to_string(index) + "/" + std::to_string(count); }
};

/// The shards a cache holds: its own, or those a merge recorded ("i/N" texts that do not read as
/// shards are left out).
std::vector<Shard> shardsIn(const CacheData& data) {
    std::vector<std::string> texts;
    if (const std::string* merged = findMetadata(data, "merged_shards")) {
        texts = commaList(merged);
    } else if (const std::string* shard = findMetadata(data, "shard")) {
        texts = {*shard};
    }
    std::vector<Shard> shards;
    for (const std::string& text : texts) {
        unsigned index = 0, count = 0;
        if (std::sscanf(text.c_str(), "%u/%u", &index, &count) == 2) shards.push_back(Shard{count, index});
    }
    return shards;
}

uint64_t inputsIn(const CacheData& data) {
    const std::string* merged = findMetadata(data, "merged_inputs");
    return merged ? std::strtoull(merged->c_str(), nullptr, 10) : 1;
}

uint64_t iterationsOf(const CacheData& data) {
    const std::string* text = findMetadata(data, "iterations");
    return text ? std::strtoull(text->c_str(), nullptr, 10) : 0;
}

/// The merged file's metadata: what every input agrees on, the summed iterations, and which
/// inputs went in. Independent of the order of `inputs` (which is canonical here).
std::vector<std::pair<std::string, std::string>> mergedMetadata(const std::vector<CacheData>& inputs) {
    std::vector<std::pair<std::string, std::string>> metadata = {{"writer", "sharcbake " SHARCBAKE_VERSION}};
    for (const auto& [key, value] : inputs[0].metadata) {
        if (describesOneBake(key)) continue;
        const bool shared = std::all_of(inputs.begin(), inputs.end(), [&](const CacheData& d) {
            const std::string* other = findMetadata(d, key);
            return other && *other == value;
        });
        if (shared) metadata.emplace_back(key, value);
    }
    uint64_t iterations = 0, merged_inputs = 0;
    std::set<std::string> bakes;
    std::set<Shard> shard_set;
    for (const CacheData& d : inputs) {
        iterations += iterationsOf(d);
        merged_inputs += inputsIn(d);
        for (const std::string& bake : bakesIn(d)) bakes.insert(bake);
        for (const Shard& shard : shardsIn(d)) shard_set.insert(shard);
    }
    std::string shards, bake_list;
    for (const Shard& shard : shard_set) shards += (shards.empty() ? "" : ",") + shard.text();
    for (const std::string& bake : bakes) bake_list += (bake_list.empty() ? "" : ",") + bake;
    metadata.emplace_back("iterations", std::to_string(iterations));
    metadata.emplace_back("merged_inputs", std::to_string(merged_inputs));
    if (!shards.empty()) metadata.emplace_back("merged_shards", shards);
    metadata.emplace_back("merged_bakes", bake_list);
    return metadata;
}

/// A job array whose task failed leaves a shard out: the merge is still valid (fewer samples),
/// but say so, once per shard count, naming the missing shards.
void warnAboutMissingShards(const std::vector<CacheData>& inputs) {
    std::map<uint32_t, std::set<uint32_t>> present;  // shard count -> indices given
    for (const CacheData& d : inputs) {
        for (const Shard& shard : shardsIn(d)) {
            if (shard.index < shard.count) present[shard.count].insert(shard.index);
        }
    }
    for (const auto& [count, indices] : present) {
        std::string missing;
        uint32_t missing_count = 0;
        for (uint32_t i = 0; i < count; ++i) {
            if (indices.count(i)) continue;
            if (++missing_count <= 8) missing += (missing.empty() ? "" : ", ") + std::to_string(i) + "/" + std::to_string(count);
        }
        if (missing_count > 0) {
            warn(formatted("%u of %u shards missing (%s%s); the merge holds the work of the others", missing_count,
                           count, missing.c_str(), missing_count > 8 ? ", ..." : ""));
        }
    }
}

/// The first iteration (of the unsharded numbering) that both inputs ran, if any: an unsharded
/// bake of K iterations ran 0 to K - 1, shard i/N ran i, N + i, ... (as many as its iterations).
/// Merged inputs, which record several shards, are left to the shard checks.
std::optional<uint64_t> sharedIteration(const CacheData& a, const CacheData& b) {
    const std::vector<Shard> shards_a = shardsIn(a), shards_b = shardsIn(b);
    const uint64_t iterations_a = iterationsOf(a), iterations_b = iterationsOf(b);
    if (iterations_a == 0 || iterations_b == 0 || shards_a.size() > 1 || shards_b.size() > 1) return std::nullopt;
    if (shards_a.empty() && shards_b.empty()) return 0;
    if (!shards_a.empty() && !shards_b.empty()) return std::nullopt;  // same shard twice: refused as such
    const Shard shard = shards_a.empty() ? shards_b[0] : shards_a[0];
    const uint64_t unsharded_iterations = shards_a.empty() ? iterations_a : iterations_b;
    if (shard.index < unsharded_iterations) return uint64_t(shard.index);
    return std::nullopt;
}

/// A bake held by two inputs (a merged cache and one of its own shards) would count its samples
/// twice, and shards of different counts (1/3 beside 0/2) are not one bake split: refused, naming
/// the files.
void refuseOverlaps(const std::vector<CacheData>& inputs, const std::vector<std::string>& paths) {
    std::map<std::string, size_t> holder;  // bake fingerprint -> input
    std::map<Shard, size_t> shard_holder;
    std::set<uint32_t> counts;
    for (size_t i = 0; i < inputs.size(); ++i) {
        for (const std::string& bake : bakesIn(inputs[i])) {
            const auto [at, added] = holder.emplace(bake, i);
            if (!added) {
                throw CommandError(kExitInvalidInput, paths[at->second] + " and " + paths[i] +
                                                          " both hold the same bake (a merged cache and one of "
                                                          "its inputs?): merging them would count its samples "
                                                          "twice");
            }
        }
        for (const Shard& shard : shardsIn(inputs[i])) {
            const auto [at, added] = shard_holder.emplace(shard, i);
            if (!added) {
                throw CommandError(kExitInvalidInput, paths[at->second] + " and " + paths[i] + " both hold shard " +
                                                          shard.text() + ": merging them would count it twice");
            }
            counts.insert(shard.count);
        }
    }
    // One --seed draws the same samples for the same iteration, and shard i/N's iteration k is the
    // unsharded bake's k*N + i: two inputs of one seed that both ran an iteration hold it twice (a
    // 16- and a 32-iteration bake of seed 0 merged into "48 iterations", 16 of them counted twice).
    for (size_t i = 0; i < inputs.size(); ++i) {
        for (size_t j = i + 1; j < inputs.size(); ++j) {
            const std::string* seed = findMetadata(inputs[i], "seed");
            const std::string* other_seed = findMetadata(inputs[j], "seed");
            if (!seed || !other_seed || *seed != *other_seed) continue;
            const std::string* scene = findMetadata(inputs[i], "scene_hash");
            const std::string* other_scene = findMetadata(inputs[j], "scene_hash");
            if (!scene || !other_scene || *scene != *other_scene) continue;  // refused as other scenes
            const std::optional<uint64_t> shared = sharedIteration(inputs[i], inputs[j]);
            if (!shared) continue;
            throw CommandError(kExitInvalidInput,
                               paths[i] + " and " + paths[j] + " were both baked with --seed " + *seed +
                                   " and both ran iteration " + std::to_string(*shared) +
                                   ": an iteration of one seed is the same samples in every bake, and merging them "
                                   "would count it twice. Merge bakes of different --seed values, or the shards of "
                                   "one bake (--shard i/N)");
        }
    }
    if (counts.size() > 1) {
        std::string list;
        for (const uint32_t c : counts) list += (list.empty() ? "" : ", ") + std::to_string(c);
        throw CommandError(kExitInvalidInput, "the inputs are shards of bakes split different ways (shard counts " +
                                                  list + "): shards of one bake share their count N");
    }
}

void runMerge(const MergeOptions& o) {
    checkOutputPath(o.output_path, "merged cache", o.inputs);
    checkReplacesOnlyItsKind(o.output_path, "merged cache", cacheFileIdentifier(), "a sharcbake cache");
    std::vector<CacheData> inputs(o.inputs.size());
    for (size_t i = 0; i < o.inputs.size(); ++i) {
        std::string message;
        const CacheFileStatus status = readCacheFile(o.inputs[i], &inputs[i], &message);
        if (status != CacheFileStatus::kOk) {
            throw CommandError(exitCodeFor(status),
                               message + " [" + toString(status) + "]");
        }
    }
    // Canonical order (by metadata, then size), so the output does not depend on the order of
    // the command line; and two inputs with the same metadata are the same bake listed twice.
    std::vector<size_t> order(inputs.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
        if (inputs[a].metadata != inputs[b].metadata) return inputs[a].metadata < inputs[b].metadata;
        return inputs[a].voxels.size() < inputs[b].voxels.size();
    });
    for (size_t k = 1; k < order.size(); ++k) {
        if (inputs[order[k - 1]].metadata == inputs[order[k]].metadata) {
            throw CommandError(kExitInvalidInput, o.inputs[order[k - 1]] + " and " + o.inputs[order[k]] +
                                                      " are the same bake (same seed, shard and settings); "
                                                      "merging it twice would count its samples twice");
        }
    }
    refuseOverlaps(inputs, o.inputs);
    std::vector<CacheData> sorted;
    std::vector<std::string> sorted_paths;
    for (size_t i : order) {
        sorted.push_back(std::move(inputs[i]));
        sorted_paths.push_back(o.inputs[i]);
    }
    CacheData merged;
    std::string message;
    std::vector<std::string> must_agree = kMustAgree;
    if (std::none_of(sorted.begin(), sorted.end(), [](const CacheData& d) { return findMetadata(d, "sky"); })) {
        must_agree.erase(std::find(must_agree.begin(), must_agree.end(), "sky"));
    }
    if (mergeCaches(sorted, must_agree, &merged, &message) != CacheFileStatus::kOk) {
        // mergeCaches numbers inputs in canonical order: name the files instead.
        for (size_t i = sorted_paths.size(); i-- > 0;) {
            const std::string tag = "input " + std::to_string(i + 1);
            for (size_t at = message.find(tag); at != std::string::npos; at = message.find(tag, at + 1)) {
                message.replace(at, tag.size(), sorted_paths[i]);
            }
        }
        throw CommandError(kExitInvalidInput, "cannot merge: " + message);
    }
    merged.metadata = mergedMetadata(sorted);
    warnAboutMissingShards(sorted);
    const CacheFileStatus status = writeCacheFile(o.output_path, merged, &message);
    if (status != CacheFileStatus::kOk) throw CommandError(kExitIo, message);
    if (!o.quiet) {
        size_t input_voxels = 0;
        for (const CacheData& d : sorted) input_voxels += d.voxels.size();
        std::printf("Merged %s (%s in all, %s) into %s: %s\n", counted(sorted.size(), "cache").c_str(),
                    counted(input_voxels, "voxel").c_str(), counted(iterationsOf(merged), "iteration").c_str(),
                    o.output_path.c_str(), counted(merged.voxels.size(), "voxel").c_str());
    }
}

}  // namespace

void registerMergeCommand(CLI::App& app) {
    auto o = std::make_shared<MergeOptions>();
    CLI::App* cmd = app.add_subcommand(
        "merge",
        "Merge caches baked as shards of one bake into a single cache.\n\n"
        "Each voxel gets the sample-weighted mean of the inputs that hold it, and their summed\n"
        "sample weight. The inputs must come from the same scene files (scene_hash) and sky with the\n"
        "same grid parameters and --max-bounces; otherwise merge refuses (exit 3). The output does not\n"
        "depend on the order of the inputs.\n\n"
        "Example (4 shards, e.g. a Slurm job array or GNU parallel, then one merge):\n"
        "  for i in 0 1 2 3; do sharcbake bake scene.gltf --shard $i/4 -o shard$i.sharc; done\n"
        "  sharcbake merge shard0.sharc shard1.sharc shard2.sharc shard3.sharc -o scene.sharc");
    // No CLI11 existence check: a missing or unreadable input is an I/O error (exit 2), as every
    // other command reports it, not a usage error.
    pathOption(cmd->add_option("inputs", o->inputs, "Caches to merge (.sharc)"))->required();
    pathOption(cmd->add_option("-o,--output", o->output_path, "Merged cache (.sharc)"))->required();
    cmd->add_flag("-q,--quiet", o->quiet, "No summary output; warnings and errors still print");
    cmd->callback([o] { runMerge(*o); });
}

}  // namespace sharcbake
