// SPDX-License-Identifier: Apache-2.0
/// @file sharc_cache.h
/// @brief The bake's radiance cache: SHaRC's hash grid plus, per slot, a fixed-point
/// accumulation entry and a resolved entry.
///
/// Offline differences from the real-time SDK (see docs/design.md §3.2), each for a reason:
/// - Sums are 72-bit fixed point (64-bit atomics plus a carry count), added in a fixed order, so
///   a bake is bit-identical for any thread count and cannot wrap (the SDK's 32-bit sums can,
///   docs/sharc_algorithm.md §10.1). Rounding to fixed point is dithered, so radiance far below one
///   fixed-point step is kept on average instead of truncated to 0 (10.2).
/// - Resolved means are float32 and weights double: no fp16 dead zone or saturation (10.5).
/// - Voxels are never evicted: a static bake keeps everything it has seen.
/// - The history schedule is a choice (HistorySchedule); the SDK's fixed window is one option.
#pragma once

#include "sharcbake/cache_file.h"
#include "sharcbake/hash_grid.h"
#include "sharcbake/zeroed_array.h"
#include "support/prefetch.h"

#include <glm/glm.hpp>

#include <array>
#include <atomic>
#include <memory>
#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// How a voxel weighs its past iterations against the newest one.
///
/// Cache feedback makes early estimates biased low (the cache they resampled was still dark),
/// so an offline bake must forget them, but forgetting too fast keeps the variance of a short
/// window. Let F be the number of iterations in which the voxel received samples:
/// - Window(A): the SDK's rule; history weight scaled by A/F once F > A. Variance never falls
///   below that of ~A iterations.
/// - Average: every iteration weighs the same; keeps the early bias for ever (decays as 1/F).
/// - Ramp(p): history weight scaled by ((F-1)/F)^p, so iteration k weighs ~k^p: early bias
///   decays as 1/F^(p+1) while the variance is only (p+1)^2/(2p+1) times the average's.
struct HistorySchedule {
    enum class Kind : uint8_t { Window, Average, Ramp };
    Kind kind = Kind::Ramp;
    float value = 8.0f;  ///< A for Window, p for Ramp

    /// Factor applied to the history weight when the voxel's F-th sampled iteration arrives.
    double historyFactor(uint32_t frames) const;
    /// "ramp:1", "window:20", "average"
    std::string describe() const;
    /// Parses the --history syntax; returns false on bad input.
    static bool parse(const std::string& text, HistorySchedule& out);
};

struct SharcSettings {
    /// Log base, scene scale, level bias (the camera is set per iteration), and the table's
    /// capacity in slots: one value for the table and the hash's slot computation.
    HashGridParameters grid = [] {
        HashGridParameters g;
        g.capacity = 1u << 20;
        return g;
    }();
    /// Where the table's keys decode (HashGridKeyDecoder): the scene's centre where it reaches
    /// beyond the 17-bit grid range around the origin (gridAnchorFor), else the origin.
    Float3 grid_anchor{0.0f, 0.0f, 0.0f};
    HistorySchedule history;
    /// Path vertices that receive radiance propagated back from later ones (SDK default with
    /// cache resampling: 2).
    uint32_t propagation_depth = 2;
    bool cache_resampling = true;
    /// Resample the cache only at the end of a path, once `propagation_depth` vertices wait for
    /// radiance (or at the last vertex --max-bounces allows), instead of the SDK's random depth:
    /// every path then carries propagation_depth bounces of exact transport per iteration, so
    /// stiff scenes converge that many times faster per iteration.
    bool resample_at_end = false;
    /// Roughness is raised to at least this in the update pass, so highlights are not cached.
    float update_roughness_clamp = 0.4f;
    /// Window, in sampled iterations, of the short mean that cache resampling reads
    /// (ResolvedEntry::feedback). Every iteration's paths read the previous state, so light
    /// gains about one bounce per feedback step; the history schedule's long memory (ramp:8
    /// weighs the last ~F/9 of F iterations) would make that step grow with F and stiff
    /// transport (furnace rho = 0.99) would never converge. 0 = read the output mean (the SDK).
    uint32_t feedback_window = 1;
    /// Double the table between iterations whenever more than kGrowAtLoad of it is occupied
    /// (--capacity auto), so no insert fails whatever the initial estimate.
    bool grow_when_loaded = false;
    /// Every voxel also feeds its coarser voxels (coarserKey) up to this level: each iteration,
    /// before the resolve, a voxel's accumulation is added to its parent's, so the table holds
    /// every level from the deposits' up, each with its own history, as if every deposit had also
    /// been made at every coarser level (sumIntoCoarserLevels). 0 = only the deposited levels.
    uint32_t coarsest_level = 0;
};

/// The load above which a growing table doubles. 16-slot buckets start failing inserts near 40%
/// load (measured); one iteration rarely adds more than a few percent of the table.
inline constexpr double kGrowAtLoad = 0.25;
/// The largest table (--capacity's upper bound, 2^28 slots, about 19 GiB of bake state).
inline constexpr uint32_t kMaxCacheCapacity = 1u << 28;

/// Per-slot accumulation of one iteration: fixed-point radiance sums and the sample count.
/// Integer atomic adds commute, so the sums do not depend on which thread adds first.
/// Each sum is 72 bits wide: a 64-bit word plus a count of its wraps (which also commutes: the
/// number of wraps is floor(total / 2^64) whatever the order), saturating at 255.
struct AccumulationEntry {
    std::array<std::atomic<uint64_t>, 3> sums{};
    std::array<std::atomic<uint8_t>, 3> carries{};
    std::atomic<uint32_t> samples{0};
    std::atomic<uint8_t> touched{0};  ///< already listed for this iteration's resolve
    /// Slot + 1 of the voxel's coarser voxel (SharcSettings::coarsest_level), 0 until looked up.
    /// Kept across iterations (it never changes while the table does not grow), so the hash
    /// lookup happens once per voxel; fits the entry's padding.
    uint32_t coarser_slot = 0;
};

/// Per-slot resolved state: what queries and cache resampling read.
struct ResolvedEntry {
    glm::vec3 mean{0.0f};     ///< mean outgoing radiance (emission included): what the file holds
    /// The same radiance over a short window (SharcSettings::feedback_window): what cache
    /// resampling reads. Noisier than `mean` but only a few iterations behind it, so bounces
    /// accumulate at a fixed rate per iteration; its noise averages out in `mean`.
    glm::vec3 feedback{0.0f};
    uint32_t frames = 0;      ///< iterations in which the voxel received samples
    double weight = 0.0;      ///< effective sample count of the history (0 = no data yet)
    uint32_t last_iteration = 0;  ///< iteration of the newest samples
    uint32_t total_samples = 0;   ///< samples ever received (saturating)
};

/// Whether SHaRC's hash sends `key` to the first bucket whatever the capacity: J(low 32 bits) ^
/// J(high 32 bits) is 0 when the halves are equal. A row of voxels on a surface can make such keys
/// (the key packs x | y << 17 | z << 34 | level << 51: equal halves where y is about 4 x level
/// and x about 4 z), and only a bucket's worth of them fit; a runtime with the SDK's hash loses
/// the rest too.
inline bool keyHalvesAreEqual(uint64_t key) { return uint32_t(key) == uint32_t(key >> 32); }

/// One deposit of an update path into a voxel: radiance x weight, and whether it counts as a
/// sample (the voxel's own direct light) or is propagated from a later vertex (count 0).
struct Deposit {
    uint64_t key = 0;
    glm::vec3 radiance{0.0f};
    uint32_t samples = 0;
};

/// What happened numerically in the accumulation; everything that was changed is counted.
struct NumericsCounters {
    uint64_t deposits = 0;
    glm::dvec3 deposited_energy{0.0};      ///< radiance x weight of every finite deposit, before any change
    uint64_t failed_inserts = 0;           ///< deposits dropped because the bucket was full
    glm::dvec3 failed_insert_energy{0.0};  ///< radiance x samples those deposits carried
    /// Of failed_inserts, those whose key's two 32-bit halves are equal: SHaRC's hash, J(low) ^
    /// J(high), is 0 for every such key, so they all share the first bucket at any capacity.
    uint64_t failed_inserts_equal_halves = 0;
    uint64_t non_finite_deposits = 0;      ///< NaN/Inf deposits dropped
    uint64_t negative_deposits = 0;        ///< negative channel values clamped to 0
    uint64_t clamped_deposits = 0;         ///< single deposits above the fixed-point ceiling
    glm::dvec3 clamped_energy{0.0};        ///< energy removed by that ceiling
    /// Deposits with radiance but less than one fixed-point step in every channel: dithered
    /// rounding keeps them on average, as 0 or 1 step each, so the voxels they feed read as noise.
    uint64_t sub_step_deposits = 0;
    uint64_t saturated_sums = 0;           ///< times a voxel sum reached its 72-bit ceiling
    uint64_t orphan_sums = 0;              ///< radiance without a sample (dropped at resolve)
};

/// Wall-clock seconds of the cache's own stages, summed over iterations: where the commit and the
/// resolve spend their time, and which of their steps keep a bake from scaling with threads.
struct CacheStageSeconds {
    double look_up = 0.0;         ///< commit: finding each deposit's slot (parallel)
    double insert = 0.0;          ///< commit: inserting new keys by slot range (parallel by range)
    double accumulate = 0.0;      ///< commit: fixed-point adds (parallel), and gathering the touched slots
    double coarser_levels = 0.0;  ///< resolve: summing voxels into their coarser voxels
    double resolve = 0.0;         ///< resolve: folding the accumulation into the resolved entries
};

class SharcCache {
public:
    /// @param radiance_scale fixed-point scale of the sums (a power of two, see chooseRadianceScale)
    SharcCache(const SharcSettings& settings, double radiance_scale);

    const SharcSettings& settings() const { return settings_; }
    uint32_t capacity() const { return table_.capacity(); }
    double radianceScale() const { return radiance_scale_; }
    /// Takes a restored bake's scale (a checkpoint's), which a later sharcbake may choose
    /// differently for the same scene; only while nothing is accumulated, so no sum mixes scales.
    void adoptRadianceScale(double radiance_scale);

    /// The resolved entry of a key, or nullptr when the key is absent. Safe to call from many
    /// threads while no commit or resolve runs.
    const ResolvedEntry* findResolved(uint64_t key) const;
    /// findResolved in steps, for a batch of lookups whose memory latency should overlap:
    /// prefetchKey for every key (it returns the key's bucket base), then findSlot (and
    /// prefetchResolved) for every key, then resolvedAt. findSlot returns kNoSlot when the key
    /// is absent.
    static constexpr uint32_t kNoSlot = kHashGridInvalidIndex;  ///< also insertByRange's full bucket
    uint32_t prefetchKey(uint64_t key) const;
    uint32_t findSlot(uint64_t key, uint32_t base) const;
    void prefetchResolved(uint32_t slot) const { prefetchObjectForRead(&resolved_[slot]); }
    const ResolvedEntry& resolvedAt(uint32_t slot) const { return resolved_[slot]; }

    /// Adds the deposits of consecutive chunks of update paths: looks keys up in parallel,
    /// inserts the new ones in parallel by slot range, each range in chunk order (so slot
    /// assignment is the same on every run and for any thread count, insertByRange), then adds
    /// the fixed-point radiance in parallel with integer atomics.
    /// `iteration` keys the rounding dither (with the chunk and the deposit's place in it), so
    /// the sums do not depend on the thread count, a resumed bake or a shard.
    void commitChunks(const std::vector<std::vector<Deposit>>& chunks, uint32_t iteration);
    /// One chunk (tests).
    void commit(const std::vector<Deposit>& deposits, uint32_t iteration = 0);

    /// Folds this iteration's accumulation into the resolved entries with the history schedule
    /// and clears it (after sumIntoCoarserLevels). Each slot reads and writes only itself, so the
    /// result does not depend on the thread count.
    void resolve(uint32_t iteration);

    const NumericsCounters& numerics() const { return numerics_; }
    const CacheStageSeconds& stageSeconds() const { return stage_seconds_; }
    /// Slots holding a key (O(capacity)).
    uint64_t liveEntries() const { return table_.occupiedSlots(); }
    /// Slots holding a key, counted as keys are inserted (O(1)).
    uint64_t occupiedSlots() const { return occupied_; }

    /// Moves every key and its resolved state into a new table of `capacity` slots (larger than
    /// the current one), re-inserted in increasing old-slot order so the result is the same on
    /// every run. Between iterations only: the accumulation must be empty.
    void grow(uint32_t capacity);

    const HashGridTable& table() const { return table_; }
    const ZeroedArray<ResolvedEntry>& resolved() const { return resolved_; }

    /// Puts `key` back into `slot` with its resolved state, on a cache fresh from the
    /// constructor, for a resumed bake. Call in increasing slot order: a key then lands where it
    /// landed first (no key is ever removed, so the slots it skipped are taken again). Returns
    /// false, changing nothing, if the key would land in another slot (the state is not one this
    /// table produced).
    bool restoreSlot(uint32_t slot, uint64_t key, const ResolvedEntry& resolved);
    /// Replaces the numerics counters (a resumed bake carries them over).
    void restoreNumerics(const NumericsCounters& numerics) { numerics_ = numerics; }

    /// The power-of-two fixed-point scale that maps `max_radiance` (the brightest emission or
    /// sky in the scene) to 2^40, for any radiance float32 holds: from 2^-149 * 2^189 to
    /// (almost) 2^128 * 2^-88.
    static double chooseRadianceScale(double max_radiance);

private:
    struct ChunkNumerics;
    /// A key missing from the table, waiting for insertByRange: the first slot of its bucket, and
    /// where its slot goes (a commit: chunk and deposit index; coarser levels: the finer voxel's
    /// slot, index unused). Trivial, so a grouped array of them is not zero-filled first.
    struct NewKey {
        uint64_t key;
        uint32_t base;
        uint32_t owner;
        uint32_t index;
    };
    struct KeysByRange;
    /// commitChunks' stages: look the keys up (parallel), insert the new ones (parallel by slot
    /// range, see insertByRange), add the deposits' fixed-point values (parallel).
    void lookUpSlots(const std::vector<Deposit>& deposits, size_t chunk, uint64_t& non_finite, glm::dvec3& deposited);
    void insertNewKeys();
    void accumulateChunk(const std::vector<Deposit>& deposits, size_t chunk, uint32_t iteration,
                         ChunkNumerics& numerics);

    /// Adds this iteration's accumulation of every touched voxel below SharcSettings::coarsest_level
    /// to its coarser voxel, level by level from the finest, inserting coarser keys that are new by
    /// range in increasing slot order of their finer voxels (so slots are the same on every run);
    /// integer sums commute, so the sums are too.
    void sumIntoCoarserLevels();
    /// Folds one touched slot's accumulation into its resolved entry and clears it; true when
    /// the slot had radiance but no sample (an orphan sum, dropped).
    bool resolveSlot(uint32_t slot, uint32_t iteration, double inverse_scale);
    /// Sets coarser_slot of the given finer voxels (sorted by slot), inserting the coarser keys
    /// that are new; a failed insert is counted and leaves coarser_slot at 0.
    void linkCoarserVoxels(const std::vector<uint32_t>& sorted_slots);

    /// The first slot of `key`'s bucket.
    uint32_t bucketBaseOf(uint64_t key) const;
    /// Where `key` is (found) or would be inserted: the slot holding it, else the first empty slot
    /// of its bucket (`base` = bucketBaseOf(key)), else kHashGridInvalidIndex (a full bucket, or
    /// key 0). Stops at the first empty slot, which is exact only because a bake never removes a
    /// key (HashGridTable::find cannot assume that). Thread-safe while no insert touches the
    /// bucket.
    struct Probe {
        uint32_t slot;
        bool found;
    };
    Probe probeBucket(uint64_t key, uint32_t base) const;
    /// Groups the keys of `lists` (taken in order) by insert range, in parallel, keeping their
    /// order within each range.
    KeysByRange groupByRange(const std::vector<std::vector<NewKey>>& lists) const;
    /// The deterministic parallel insert. The table is cut into fixed ranges of at least 4096
    /// slots (a function of the capacity only); a key belongs to the range of its bucket's first
    /// slot. All even ranges insert their keys in parallel, then all odd ranges, each range
    /// serially in its keys' order: ranges running together never share a slot, so a key's slot
    /// depends on the keys and their order only, never on the thread count or the scheduling.
    /// The keys of `lists` are taken in order (grouped by range when there are many). Calls
    /// store(key, slot) per key (kHashGridInvalidIndex when its bucket is full) and returns how
    /// many keys were new to the table.
    template <typename Store>
    uint64_t insertByRange(const std::vector<std::vector<NewKey>>& lists, Store&& store);
    /// One key of insertByRange: found, inserted, or its bucket full; true when it was new.
    template <typename Store>
    bool insertKey(const NewKey& k, Store& store);
    /// The voxel's new short-window feedback value (r.frames already counts this iteration).
    glm::dvec3 feedbackMean(const ResolvedEntry& r, const glm::dvec3& newest, const glm::dvec3& mean) const;

    SharcSettings settings_;
    HashGridKeyDecoder key_decoder_;  ///< settings_'s grid and anchor: coarser keys of wrapped cells
    HashGridTable table_;
    double radiance_scale_;
    // Zero-filled lazily (ZeroedArray): a table far larger than the scene needs costs memory only
    // for the pages its voxels land in.
    ZeroedArray<AccumulationEntry> accumulation_;
    ZeroedArray<ResolvedEntry> resolved_;
    std::vector<uint32_t> touched_;  ///< slots with accumulation this iteration (any order)
    std::vector<std::vector<uint32_t>> chunk_slots_;  ///< commit scratch: each deposit's slot
    std::vector<std::vector<NewKey>> chunk_missing_;  ///< commit scratch: deposits with a new key
    NumericsCounters numerics_;
    CacheStageSeconds stage_seconds_;
    uint64_t occupied_ = 0;
};

/// The cache as file data: live voxels with samples (every level the table holds), in canonical
/// (key) order, and the grid parameters. What `bake` writes.
CacheData toCacheData(const SharcCache& cache);

}  // namespace sharcbake
