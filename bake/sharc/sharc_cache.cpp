// SPDX-License-Identifier: Apache-2.0
#include "sharc/sharc_cache.h"

#include "support/prefetch.h"
#include "support/stopwatch.h"
#include "tracing/sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace sharcbake {

double HistorySchedule::historyFactor(uint32_t frames) const {
    if (frames <= 1) return 0.0;  // no history yet
    switch (kind) {
        case Kind::Average:
            return 1.0;
        case Kind::Window: {
            // The SDK caps the frame counter at A, so once F passes A every new iteration
            // scales the history by A / (A + 1): an exponential window of about A iterations.
            const double a = std::max(1.0, double(value));
            return double(frames) > a ? a / (a + 1.0) : 1.0;
        }
        case Kind::Ramp:
            return std::pow(double(frames - 1) / double(frames), double(value));
    }
    return 1.0;
}

std::string HistorySchedule::describe() const {
    char text[64];
    switch (kind) {
        case Kind::Average: return "average";
        case Kind::Window: std::snprintf(text, sizeof text, "window:%g", double(value)); return text;
        case Kind::Ramp: std::snprintf(text, sizeof text, "ramp:%g", double(value)); return text;
    }
    return "?";
}

bool HistorySchedule::parse(const std::string& text, HistorySchedule& out) {
    if (text == "average") {
        out = {Kind::Average, 0.0f};
        return true;
    }
    const size_t colon = text.find(':');
    if (colon == std::string::npos) return false;
    const std::string name = text.substr(0, colon);
    char* end = nullptr;
    const std::string number = text.substr(colon + 1);
    const float value = std::strtof(number.c_str(), &end);
    if (number.empty() || *end != '\0' || !std::isfinite(value)) return false;
    if (name == "window" && value >= 1.0f) {
        out = {Kind::Window, value};
        return true;
    }
    if (name == "ramp" && value >= 0.0f && value <= 8.0f) {
        out = {Kind::Ramp, value};
        return true;
    }
    return false;
}

namespace {

/// One deposit may add at most 2^62 (22 bits above the brightest emission at 2^40); a voxel's
/// sum saturates at 255 wraps of 2^64, i.e. after at least 2^10 maximal deposits in one iteration.
constexpr uint64_t kMaxFixedDeposit = uint64_t(1) << 62;
constexpr uint8_t kMaxCarries = 255;
/// Deposits below this many fixed-point steps are rounded with a dither, larger ones to nearest.
constexpr double kDitherBelow = 0x1p20;

/// Deterministic dithers in [0, 1) for the three channels of one deposit, 16 bits each: keyed
/// by the iteration, the chunk and the deposit's place in it, all independent of the thread
/// count. Four hashes per deposit; 16 bits leave a rounding bias below 2^-17 of a step.
std::array<double, 3> roundingDither(uint32_t iteration, size_t chunk, size_t index) {
    const uint32_t a = hashCombine(hashCombine(hashUint32(iteration), uint32_t(chunk)), uint32_t(index));
    const uint32_t b = hashUint32(a);
    constexpr double kUnit = 0x1p-16;
    return {double(a & 0xFFFFu) * kUnit, double(a >> 16) * kUnit, double(b & 0xFFFFu) * kUnit};
}

/// Adds `low + carries x 2^64` to a 72-bit sum; false when its carry count saturated (the sum
/// then reads as its ceiling).
bool addToSum(std::atomic<uint64_t>& word, std::atomic<uint8_t>& word_carries, uint64_t low, uint32_t carries) {
    const uint64_t before = word.fetch_add(low, std::memory_order_relaxed);
    carries += before + low < before;  // this add wrapped the word
    if (carries == 0) return true;
    uint8_t count = word_carries.load(std::memory_order_relaxed);
    do {
        if (count == kMaxCarries) return false;
    } while (!word_carries.compare_exchange_weak(
        count, uint8_t(std::min<uint32_t>(kMaxCarries, count + carries)), std::memory_order_relaxed));
    return count + carries <= kMaxCarries;
}

/// How many entries ahead the loops over scattered slots prefetch (enough to cover a memory
/// latency).
constexpr size_t kPrefetchDistance = 8;

/// True for the one caller that marks the entry touched first (it lists the slot). Most calls
/// find it marked already; a plain load spares them the locked exchange, which stalls the
/// thread's later loads until its stores drain.
bool claimTouched(AccumulationEntry& entry) {
    return entry.touched.load(std::memory_order_relaxed) == 0 &&
           entry.touched.exchange(1, std::memory_order_relaxed) == 0;
}

/// Up to kSlots per-slot sums of one chunk's deposits, 96 bits wide per channel, added to the
/// shared accumulation one slot at a time: a path deposits into the same voxels several times,
/// and the bright voxels are shared by every thread, so one atomic add per slot and chunk
/// instead of one per deposit cuts the contention.
class PendingSums {
public:
    struct Sum {
        uint32_t slot = 0;
        uint32_t samples = 0;
        uint64_t sums[3] = {0, 0, 0};
        uint32_t carries[3] = {0, 0, 0};  ///< wraps of sums[c]
    };

    /// The pending sum of `slot`; when all are taken, the oldest is flushed to make room.
    template <typename Flush>
    Sum& at(uint32_t slot, Flush&& flush) {
        size_t at = 0;
        while (at < count_ && sums_[at].slot != slot) ++at;
        if (at == count_) {
            if (count_ < kSlots) {
                ++count_;
            } else {
                at = next_flush_;
                next_flush_ = (next_flush_ + 1) % kSlots;
                flush(sums_[at]);
            }
            sums_[at] = Sum{slot};
        }
        return sums_[at];
    }
    template <typename Flush>
    void flushAll(Flush&& flush) {
        for (size_t at = 0; at < count_; ++at) flush(sums_[at]);
    }

private:
    static constexpr size_t kSlots = 8;
    Sum sums_[kSlots];
    size_t count_ = 0, next_flush_ = 0;
};

}  // namespace

/// What accumulating one chunk counted, added up in chunk order afterwards.
struct SharcCache::ChunkNumerics {
    uint64_t failed = 0, failed_equal_halves = 0, negative = 0, clamped = 0, saturated = 0, sub_step = 0;
    glm::dvec3 failed_energy{0.0}, clamped_energy{0.0};
    std::vector<uint32_t> touched;
};

double SharcCache::chooseRadianceScale(double max_radiance) {
    // The brightest radiance maps to 2^40: 40 bits of precision below it (and dithered rounding
    // beyond that), 2^22 times above it for one deposit (multi-bounce radiance exceeds emission:
    // L = Le/(1-rho) in a furnace), and 2^32 deposits that bright in a voxel's 72-bit sum.
    // Deposits are float32, so the scale follows the estimate across float32's whole range: from
    // its smallest value (2^-149) to its largest (below 2^128), where one deposit's 2^62 steps
    // still hold 2^22 times the largest float. (A floor at 2^-60 held radiance up to 2^122 = 5.3e36
    // and clamped an emitter of 1e37 47% low.) An estimate beyond float32 (a bright punctual light
    // next to a surface can give one) takes the largest float's scale; none at all (no light, NaN)
    // takes 1's.
    constexpr double kLargestFloat = std::numeric_limits<float>::max();
    constexpr double kSmallestFloat = std::numeric_limits<float>::denorm_min();
    const double magnitude = max_radiance > 0.0 ? std::clamp(max_radiance, kSmallestFloat, kLargestFloat) : 1.0;
    return std::ldexp(1.0, 40 - int(std::ceil(std::log2(magnitude))));
}

SharcCache::SharcCache(const SharcSettings& settings, double radiance_scale)
    : settings_(settings),
      key_decoder_(settings.grid, settings.grid_anchor),
      radiance_scale_(radiance_scale),
      accumulation_(settings.grid.capacity),
      resolved_(settings.grid.capacity) {
    const HashGridStatus status = HashGridTable::create(settings.grid.capacity, &table_);
    if (status != HashGridStatus::kOk) {
        throw std::invalid_argument(std::string("hash grid: ") + toString(status));
    }
}

void SharcCache::adoptRadianceScale(double radiance_scale) {
    if (!touched_.empty() || !(radiance_scale > 0.0) || !std::isfinite(radiance_scale))
        throw std::logic_error("adoptRadianceScale: a positive, finite scale, before anything is accumulated");
    radiance_scale_ = radiance_scale;
}

const ResolvedEntry* SharcCache::findResolved(uint64_t key) const {
    const Probe probe = probeBucket(key, bucketBaseOf(key));
    return probe.found ? &resolved_[probe.slot] : nullptr;
}

uint32_t SharcCache::prefetchKey(uint64_t key) const {
    const uint32_t base = bucketBaseOf(key);
    table_.prefetchBucket(base);
    return base;
}

uint32_t SharcCache::findSlot(uint64_t key, uint32_t base) const {
    const Probe probe = probeBucket(key, base);
    return probe.found ? probe.slot : kNoSlot;
}

void SharcCache::commit(const std::vector<Deposit>& deposits, uint32_t iteration) {
    commitChunks(std::vector<std::vector<Deposit>>{deposits}, iteration);
}

namespace {
constexpr uint32_t kMissing = kHashGridInvalidIndex;           // key not in the table yet
constexpr uint32_t kDropped = kHashGridInvalidIndex - 1;       // non-finite deposit
constexpr uint32_t kFailedInsert = kHashGridInvalidIndex - 2;  // the key's bucket was full

/// The fixed slot ranges of the parallel insert (SharcCache::insertByRange). A key belongs to the
/// range holding its bucket's first slot. They depend on the capacity only, never on the thread
/// count, so neither do the slots the keys get.
struct InsertRanges {
    uint32_t shift = 0;  ///< range of a bucket base = base >> shift
    size_t count = 1;
    size_t of(uint32_t base) const { return base >> shift; }
};

/// At least 4096 slots a range, so a task has work worth its scheduling and a range is far
/// longer than the bucket_size - 1 slots a window reaches past its end; at most about 1024
/// ranges, so grouping keys by range stays cheap (measured, BENCHMARKS.md).
constexpr uint32_t kMinRangeShift = 12;
constexpr uint32_t kMaxRanges = 1024;

InsertRanges insertRanges(uint32_t capacity, uint32_t probes) {
    uint32_t shift = kMinRangeShift;
    while ((uint64_t(1) << shift) < probes || (capacity >> shift) > kMaxRanges) ++shift;
    const uint32_t last_base = capacity - probes;  // bucketBase never returns more
    return {shift, size_t(last_base >> shift) + 1};
}

/// Blocks of input lists that groupByRange counts and scatters in parallel: at most 64, and one
/// per 4096 keys. The result does not depend on them (the sort is stable).
constexpr size_t kGroupBlocks = 64;
constexpr size_t kKeysPerGroupBlock = 4096;
/// Below this many keys they are inserted on the calling thread, in the ranges' order.
constexpr size_t kParallelInsertFrom = 4096;
/// Finer voxels per task when their coarser keys are looked up.
constexpr size_t kLinkBlock = 1024;
/// Below this many items a loop runs on the calling thread: waking the workers costs more.
constexpr size_t kParallelLoopFrom = 2048;

/// Calls body(first, last) over [0, count): in parallel blocks, or once on this thread when
/// count is small. Bodies must not depend on how the range is split.
template <typename Body>
void forEachIndex(size_t count, Body&& body) {
    if (count < kParallelLoopFrom) {
        if (count > 0) body(size_t(0), count);
        return;
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, kParallelLoopFrom / 4),
                      [&](const tbb::blocked_range<size_t>& range) { body(range.begin(), range.end()); });
}
}  // namespace

/// Keys to insert, grouped by insert range; each range's keys keep the order of the input lists.
struct SharcCache::KeysByRange {
    std::unique_ptr<NewKey[]> keys;   ///< left uninitialised until scattered: no serial zero fill
    std::vector<size_t> range_begin;  ///< range r holds keys[range_begin[r], range_begin[r + 1])
};

void SharcCache::commitChunks(const std::vector<std::vector<Deposit>>& chunks, uint32_t iteration) {
    chunk_slots_.resize(chunks.size());
    chunk_missing_.resize(chunks.size());
    std::vector<uint64_t> chunk_non_finite(chunks.size(), 0);
    std::vector<glm::dvec3> chunk_deposited(chunks.size(), glm::dvec3(0.0));
    auto start = std::chrono::steady_clock::now();
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t chunk) {
        lookUpSlots(chunks[chunk], chunk, chunk_non_finite[chunk], chunk_deposited[chunk]);
    });
    for (size_t chunk = 0; chunk < chunks.size(); ++chunk) {
        numerics_.deposits += chunks[chunk].size();
        numerics_.non_finite_deposits += chunk_non_finite[chunk];
        numerics_.deposited_energy += chunk_deposited[chunk];
    }
    stage_seconds_.look_up += secondsSince(start);
    start = std::chrono::steady_clock::now();
    insertNewKeys();
    stage_seconds_.insert += secondsSince(start);
    start = std::chrono::steady_clock::now();
    std::vector<ChunkNumerics> chunk_numerics(chunks.size());
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t chunk) {
        accumulateChunk(chunks[chunk], chunk, iteration, chunk_numerics[chunk]);
    });
    for (const ChunkNumerics& n : chunk_numerics) {
        numerics_.failed_inserts += n.failed;
        numerics_.failed_inserts_equal_halves += n.failed_equal_halves;
        numerics_.failed_insert_energy += n.failed_energy;
        numerics_.negative_deposits += n.negative;
        numerics_.clamped_deposits += n.clamped;
        numerics_.sub_step_deposits += n.sub_step;
        numerics_.clamped_energy += n.clamped_energy;
        numerics_.saturated_sums += n.saturated;
        touched_.insert(touched_.end(), n.touched.begin(), n.touched.end());
    }
    stage_seconds_.accumulate += secondsSince(start);
}

// 1. Parallel over chunks: look every key up (the table is read-only here). A path deposits into
//    its own voxel and then into the same voxels again as later vertices propagate back, so the
//    last few keys are remembered; each chunk lists the deposits whose key is new.
void SharcCache::lookUpSlots(const std::vector<Deposit>& deposits, size_t chunk, uint64_t& non_finite,
                             glm::dvec3& deposited) {
    std::vector<uint32_t>& slots = chunk_slots_[chunk];
    std::vector<NewKey>& missing = chunk_missing_[chunk];
    slots.resize(deposits.size());
    missing.clear();
    constexpr size_t kRecent = 4;
    uint64_t recent_keys[kRecent] = {};  // key 0 never occurs
    uint32_t recent_slots[kRecent] = {};
    uint32_t recent_bases[kRecent] = {};  // a recent key may be missing too: its base is listed again
    size_t next_recent = 0;
    // The buckets of the next few deposits are prefetched, so their table misses overlap.
    uint32_t ahead_bases[kPrefetchDistance];
    for (size_t j = 0; j < std::min(kPrefetchDistance, deposits.size()); ++j) {
        ahead_bases[j] = bucketBaseOf(deposits[j].key);
        table_.prefetchBucket(ahead_bases[j]);
    }
    for (size_t i = 0; i < deposits.size(); ++i) {
        const Deposit& d = deposits[i];
        const uint32_t base = ahead_bases[i % kPrefetchDistance];
        if (i + kPrefetchDistance < deposits.size()) {
            const uint32_t ahead = bucketBaseOf(deposits[i + kPrefetchDistance].key);
            ahead_bases[i % kPrefetchDistance] = ahead;
            table_.prefetchBucket(ahead);
        }
        if (!isFiniteColor(d.radiance)) {
            slots[i] = kDropped;
            ++non_finite;
            continue;
        }
        deposited += glm::dvec3(glm::max(d.radiance, glm::vec3(0.0f)));
        size_t r = 0;
        while (r < kRecent && recent_keys[r] != d.key) ++r;
        if (r == kRecent) {
            r = next_recent;
            next_recent = (next_recent + 1) % kRecent;
            recent_keys[r] = d.key;
            recent_bases[r] = base;
            const Probe probe = probeBucket(d.key, recent_bases[r]);
            recent_slots[r] = probe.found ? probe.slot : kMissing;
        }
        slots[i] = recent_slots[r];
        if (slots[i] == kMissing) missing.push_back(NewKey{d.key, recent_bases[r], uint32_t(chunk), uint32_t(i)});
    }
}

// 2. Parallel by slot range, in chunk (= path) order within each range: insert the new keys.
//    Slot assignment therefore depends only on the paths, never on the threads (insertByRange).
//    Only the deposits listed as new are visited.
void SharcCache::insertNewKeys() {
    occupied_ += insertByRange(chunk_missing_, [this](const NewKey& k, uint32_t slot) {
        chunk_slots_[k.owner][k.index] = slot == kNoSlot ? kFailedInsert : slot;
    });
}

uint32_t SharcCache::bucketBaseOf(uint64_t key) const {
    return bucketBase(hashGridHash(key), table_.capacity(), table_.bucketSize());
}

// HashGridTable::find scans the whole window because the runtime's tables may have holes
// (eviction). A bake's table never has: no key is ever removed (grow builds a new table;
// restoreSlot's clearSlot only undoes the insert it just made), and insert claims the first slot
// that is empty or holds the key, so every slot between a key's bucket base and the key stays
// occupied. The first empty slot therefore ends the search, which for a key not in the table
// saves most of the window's loads.
SharcCache::Probe SharcCache::probeBucket(uint64_t key, uint32_t base) const {
    if (key == kHashGridInvalidKey) return {kNoSlot, false};  // never stored (an empty slot is 0)
    const uint32_t end = base + bucketProbeCount(table_.capacity(), table_.bucketSize());
    for (uint32_t slot = base; slot < end; ++slot) {
        const uint64_t stored = table_.keyAt(slot);
        if (stored == key) return {slot, true};
        if (stored == kHashGridInvalidKey) return {slot, false};
    }
    return {kNoSlot, false};
}

// A stable counting sort by range: blocks of consecutive lists count their keys per range in
// parallel, the counts become offsets (range by range, block by block), and the blocks scatter
// their keys in parallel. Each range thus holds its keys in list order, then order within a list.
SharcCache::KeysByRange SharcCache::groupByRange(const std::vector<std::vector<NewKey>>& lists) const {
    const InsertRanges ranges = insertRanges(table_.capacity(),
                                             bucketProbeCount(table_.capacity(), table_.bucketSize()));
    size_t total = 0;
    for (const std::vector<NewKey>& list : lists) total += list.size();
    // Few keys (a warm cache) need few blocks: each block's counters cost O(ranges).
    const size_t blocks = std::min({lists.size(), kGroupBlocks, total / kKeysPerGroupBlock + 1});
    const auto blockLists = [&](size_t block) {
        return std::pair(lists.size() * block / blocks, lists.size() * (block + 1) / blocks);
    };
    std::vector<size_t> offsets(blocks * ranges.count, 0);  // [block][range]: counts, then offsets
    tbb::parallel_for(size_t(0), blocks, [&](size_t block) {
        size_t* counts = &offsets[block * ranges.count];
        const auto [first, last] = blockLists(block);
        for (size_t list = first; list < last; ++list) {
            for (const NewKey& k : lists[list]) ++counts[ranges.of(k.base)];
        }
    });
    KeysByRange grouped;
    grouped.range_begin.assign(ranges.count + 1, 0);
    for (size_t block = 0; block < blocks; ++block) {  // each range's size (memory order, no strides)
        const size_t* counts = &offsets[block * ranges.count];
        for (size_t range = 0; range < ranges.count; ++range) grouped.range_begin[range + 1] += counts[range];
    }
    for (size_t range = 0; range < ranges.count; ++range) grouped.range_begin[range + 1] += grouped.range_begin[range];
    std::vector<size_t> next(grouped.range_begin.begin(), grouped.range_begin.end() - 1);
    for (size_t block = 0; block < blocks; ++block) {  // a block's keys follow the earlier blocks' in each range
        for (size_t range = 0; range < ranges.count; ++range) {
            const size_t count = offsets[block * ranges.count + range];
            offsets[block * ranges.count + range] = next[range];
            next[range] += count;
        }
    }
    grouped.keys.reset(new NewKey[total]);
    tbb::parallel_for(size_t(0), blocks, [&](size_t block) {
        size_t* next_key = &offsets[block * ranges.count];
        const auto [first, last] = blockLists(block);
        for (size_t list = first; list < last; ++list) {
            for (const NewKey& k : lists[list]) grouped.keys[next_key[ranges.of(k.base)]++] = k;
        }
    });
    return grouped;
}

template <typename Store>
bool SharcCache::insertKey(const NewKey& k, Store& store) {
    // A key listed several times (one per deposit, or per finer voxel) is inserted by its first
    // occurrence; the later ones find it.
    const Probe probe = probeBucket(k.key, k.base);
    if (probe.found || probe.slot == kNoSlot) {
        store(k, probe.slot);
        return false;
    }
    // No other range writes this window now, so the insert takes probe.slot.
    const std::optional<uint32_t> slot = table_.insert(k.key);
    store(k, slot.value_or(kNoSlot));
    return slot.has_value();
}

// Ranges run in two phases, the even ones in parallel and then the odd ones, each inserting its
// keys serially in their order. A key whose bucket starts in range r probes only up to
// bucket_size - 1 slots past r's end, i.e. into range r + 1, never further (ranges are longer
// than that): two ranges of one phase therefore never read or write the same slot, and every
// range sees the table exactly as the previous phase left it. Slots depend on the keys' order
// and the ranges (the capacity) only.
//
// Few keys (a warm cache's new ones, a level's new coarser voxels) take the same order on this
// thread without being grouped: every key of an even range in list order, then every key of an
// odd range. Keys of different ranges of one phase never meet, so interleaving them changes
// nothing, and grouping would cost O(ranges) (up to 1024) per call, nine levels per iteration.
template <typename Store>
uint64_t SharcCache::insertByRange(const std::vector<std::vector<NewKey>>& lists, Store&& store) {
    size_t total = 0;
    for (const std::vector<NewKey>& list : lists) total += list.size();
    if (total == 0) return 0;
    if (total < kParallelInsertFrom) {
        const InsertRanges ranges = insertRanges(table_.capacity(),
                                                 bucketProbeCount(table_.capacity(), table_.bucketSize()));
        uint64_t fresh = 0;
        for (size_t parity = 0; parity < 2; ++parity) {
            for (const std::vector<NewKey>& list : lists) {
                for (const NewKey& k : list) {
                    if ((ranges.of(k.base) & 1u) == parity) fresh += insertKey(k, store);
                }
            }
        }
        return fresh;
    }
    const KeysByRange grouped = groupByRange(lists);
    const size_t range_count = grouped.range_begin.size() - 1;
    const auto insertRange = [&](size_t range) {
        uint64_t range_fresh = 0;
        for (size_t i = grouped.range_begin[range]; i < grouped.range_begin[range + 1]; ++i) {
            range_fresh += insertKey(grouped.keys[i], store);
        }
        return range_fresh;
    };
    std::atomic<uint64_t> fresh{0};
    for (size_t parity = 0; parity < 2; ++parity) {
        tbb::parallel_for(size_t(0), (range_count + 1 - parity) / 2, [&](size_t half) {
            fresh.fetch_add(insertRange(2 * half + parity), std::memory_order_relaxed);
        });
    }
    return fresh.load();
}

// 3. Parallel over chunks: fixed-point conversion and integer atomic adds, which commute, so the
//    sums do not depend on the order either. Integer addition with carries is associative, so
//    the 72-bit sums are bit-identical however PendingSums groups them.
void SharcCache::accumulateChunk(const std::vector<Deposit>& deposits, size_t chunk, uint32_t iteration,
                                 ChunkNumerics& numerics) {
    const std::vector<uint32_t>& slots = chunk_slots_[chunk];
    const auto flush = [&](const PendingSums::Sum& p) {
        AccumulationEntry& entry = accumulation_[p.slot];
        if (claimTouched(entry)) numerics.touched.push_back(p.slot);
        for (int c = 0; c < 3; ++c) {
            if ((p.sums[c] || p.carries[c]) && !addToSum(entry.sums[c], entry.carries[c], p.sums[c], p.carries[c])) {
                ++numerics.saturated;
            }
        }
        if (p.samples) entry.samples.fetch_add(p.samples, std::memory_order_relaxed);
    };
    PendingSums pending;
    for (size_t i = 0; i < deposits.size(); ++i) {
        if (i + kPrefetchDistance < deposits.size() && slots[i + kPrefetchDistance] < kFailedInsert) {
            prefetchObjectForWrite(&accumulation_[slots[i + kPrefetchDistance]]);
        }
        const Deposit& d = deposits[i];
        if (slots[i] == kFailedInsert) {
            ++numerics.failed;
            numerics.failed_equal_halves += keyHalvesAreEqual(d.key) ? 1 : 0;
            numerics.failed_energy += glm::dvec3(glm::max(d.radiance, glm::vec3(0.0f)));
            continue;
        }
        if (slots[i] == kDropped) continue;
        PendingSums::Sum& sum = pending.at(slots[i], flush);
        bool negative = false, clamped = false;
        double largest_scaled = 0.0;
        std::array<double, 3> dither{};
        bool dither_ready = false;
        for (int c = 0; c < 3; ++c) {
            double value = double(d.radiance[c]);
            if (value < 0.0) {
                negative = true;
                value = 0.0;
            }
            // Dithered rounding where it matters: the expected fixed-point value is exactly value
            // x scale, so light below one step is kept on average; truncation would drop it for
            // good (docs/sharc_algorithm.md §10.2). Above 2^20 steps, rounding to nearest is off
            // by at most 2^-21 and the hash is not worth its time.
            const double scaled = value * radiance_scale_;
            largest_scaled = std::max(largest_scaled, scaled);
            double fixed;
            if (scaled >= kDitherBelow) {
                fixed = std::nearbyint(scaled);
            } else {
                if (!dither_ready) {
                    dither = roundingDither(iteration, chunk, i);
                    dither_ready = true;
                }
                fixed = std::floor(scaled + dither[c]);
            }
            if (fixed > double(kMaxFixedDeposit)) {
                clamped = true;
                numerics.clamped_energy[c] += (fixed - double(kMaxFixedDeposit)) / radiance_scale_;
                fixed = double(kMaxFixedDeposit);
            }
            if (fixed > 0.0) {
                const uint64_t before = sum.sums[c];
                sum.sums[c] += uint64_t(fixed);
                sum.carries[c] += sum.sums[c] < before;  // at most 2^62 per add: wraps once at most
            }
        }
        numerics.negative += negative;
        numerics.clamped += clamped;
        numerics.sub_step += largest_scaled > 0.0 && largest_scaled < 1.0;
        sum.samples += d.samples;
    }
    pending.flushAll(flush);
}

glm::dvec3 SharcCache::feedbackMean(const ResolvedEntry& r, const glm::dvec3& newest, const glm::dvec3& mean) const {
    const uint32_t window = settings_.feedback_window;
    if (window == 0) return mean;
    // An exponential window of `window` sampled iterations (a plain average before that): the
    // newest estimate weighs at least 1/window.
    const double newest_weight = 1.0 / double(std::min(r.frames, window));
    return glm::dvec3(r.feedback) + (newest - glm::dvec3(r.feedback)) * newest_weight;
}

void SharcCache::sumIntoCoarserLevels() {
    const uint32_t coarsest = settings_.coarsest_level;
    if (coarsest == 0 || touched_.empty()) return;
    // Per level up to the coarsest: the touched voxels, and those of them whose coarser voxel is
    // not linked yet. Listed per thread, then joined: the order within a list does not matter
    // (integer adds commute, and the unlinked ones are sorted before they are looked up).
    using LevelLists = std::vector<std::vector<uint32_t>>;
    const auto emptyLists = [coarsest] { return LevelLists(size_t(coarsest) + 1); };
    tbb::enumerable_thread_specific<LevelLists> local_touched(emptyLists), local_unlinked(emptyLists);
    LevelLists by_level = emptyLists(), unlinked = emptyLists();
    const auto join = [](tbb::enumerable_thread_specific<LevelLists>& local, uint32_t level,
                         std::vector<uint32_t>& out) {
        for (LevelLists& lists : local) {
            out.insert(out.end(), lists[level].begin(), lists[level].end());
            lists[level].clear();
        }
    };
    // Each key read is a cache miss in a large table: read them in parallel.
    forEachIndex(touched_.size(), [&](size_t first, size_t last) {
        LevelLists& touched = local_touched.local();
        LevelLists& new_links = local_unlinked.local();
        for (size_t i = first; i < last; ++i) {
            if (i + kPrefetchDistance < last) {
                table_.prefetchBucket(touched_[i + kPrefetchDistance]);
                prefetchForRead(&accumulation_[touched_[i + kPrefetchDistance]].coarser_slot);  // all the split reads
            }
            const uint32_t slot = touched_[i];
            const uint32_t level = decodeHashGridKey(table_.keyAt(slot)).level;
            if (level >= coarsest) continue;
            touched[level].push_back(slot);
            if (accumulation_[slot].coarser_slot == 0) new_links[level].push_back(slot);
        }
    });
    for (uint32_t level = kHashGridLevelMin; level < coarsest; ++level) {
        join(local_touched, level, by_level[level]);
        join(local_unlinked, level, unlinked[level]);
    }
    for (uint32_t level = kHashGridLevelMin; level < coarsest; ++level) {
        const std::vector<uint32_t>& slots = by_level[level];
        if (slots.empty()) continue;
        // The coarser voxel of each voxel is looked up once (then remembered in coarser_slot),
        // in slot order, so the new coarser keys' slots do not depend on the threads.
        std::vector<uint32_t>& lookups = unlinked[level];
        if (!lookups.empty()) {
            tbb::parallel_sort(lookups.begin(), lookups.end());
            linkCoarserVoxels(lookups);
        }
        const bool has_coarser = level + 1 < coarsest;
        std::atomic<uint64_t> saturated{0};
        forEachIndex(slots.size(), [&](size_t first, size_t last) {
            uint64_t range_saturated = 0;
            for (size_t i = first; i < last; ++i) {
                // Children and parents are scattered over the table: fetch the child two
                // distances ahead, and its parent (whose slot the child holds) one ahead.
                if (i + 2 * kPrefetchDistance < last)
                    prefetchObjectForRead(&accumulation_[slots[i + 2 * kPrefetchDistance]]);
                if (i + kPrefetchDistance < last) {
                    const uint32_t ahead = accumulation_[slots[i + kPrefetchDistance]].coarser_slot;
                    if (ahead != 0) prefetchObjectForWrite(&accumulation_[ahead - 1]);
                }
                AccumulationEntry& child = accumulation_[slots[i]];
                if (child.coarser_slot == 0) continue;
                const uint32_t parent_slot = child.coarser_slot - 1;
                AccumulationEntry& parent = accumulation_[parent_slot];
                if (claimTouched(parent)) {  // touched here for the first time: the next level lists it
                    local_touched.local()[level + 1].push_back(parent_slot);
                    if (has_coarser && parent.coarser_slot == 0)
                        local_unlinked.local()[level + 1].push_back(parent_slot);
                }
                for (int c = 0; c < 3; ++c) {
                    const uint64_t low = child.sums[c].load(std::memory_order_relaxed);
                    const uint8_t carries = child.carries[c].load(std::memory_order_relaxed);
                    if ((low || carries) && !addToSum(parent.sums[c], parent.carries[c], low, carries))
                        ++range_saturated;
                }
                parent.samples.fetch_add(child.samples.load(std::memory_order_relaxed), std::memory_order_relaxed);
            }
            if (range_saturated) saturated.fetch_add(range_saturated, std::memory_order_relaxed);
        });
        numerics_.saturated_sums += saturated.load();
        // The newly touched voxels go to the resolve's list, and below the coarsest level to the
        // next level's.
        const size_t before = touched_.size();
        join(local_touched, level + 1, touched_);
        if (has_coarser) {
            by_level[level + 1].insert(by_level[level + 1].end(), touched_.begin() + std::ptrdiff_t(before), touched_.end());
            join(local_unlinked, level + 1, unlinked[level + 1]);
        }
    }
}

bool SharcCache::resolveSlot(uint32_t slot, uint32_t iteration, double inverse_scale) {
    AccumulationEntry& acc = accumulation_[slot];
    ResolvedEntry& r = resolved_[slot];
    const uint32_t samples = acc.samples.load(std::memory_order_relaxed);
    if (samples > 0) {
        double sums[3];
        for (int c = 0; c < 3; ++c) {
            // A saturated sum's low word may have wrapped once more: read it as the ceiling.
            const uint8_t carries = acc.carries[c].load(std::memory_order_relaxed);
            sums[c] = carries == kMaxCarries ? 0x1p72
                                             : double(acc.sums[c].load(std::memory_order_relaxed)) +
                                                   std::ldexp(double(carries), 64);
        }
        const double n = double(samples);
        const glm::dvec3 mean_new = glm::dvec3(sums[0], sums[1], sums[2]) * (inverse_scale / n);
        r.frames += 1;
        const double history = r.weight * settings_.history.historyFactor(r.frames);
        const double total = history + n;
        const glm::dvec3 mean = (glm::dvec3(r.mean) * history + mean_new * n) / total;
        r.mean = glm::vec3(mean);
        r.feedback = glm::vec3(feedbackMean(r, mean_new, mean));
        r.weight = total;
        r.last_iteration = iteration;
        r.total_samples = samples > ~r.total_samples ? ~0u : r.total_samples + samples;
    }
    for (auto& sum : acc.sums) sum.store(0, std::memory_order_relaxed);
    for (auto& carry : acc.carries) carry.store(0, std::memory_order_relaxed);
    acc.samples.store(0, std::memory_order_relaxed);
    acc.touched.store(0, std::memory_order_relaxed);
    // Radiance that arrived without a sample of its own cannot happen with the update pass as
    // written; the caller counts it so a regression shows up in the stats.
    return samples == 0;
}

// Parallel over fixed blocks of the finer voxels: each computes its coarser key and links the
// coarser voxels already in the table; the new ones are inserted by range in increasing slot
// order of their finer voxels (insertByRange), so their slots do not depend on the thread count.
void SharcCache::linkCoarserVoxels(const std::vector<uint32_t>& sorted_slots) {
    std::vector<std::vector<NewKey>> missing((sorted_slots.size() + kLinkBlock - 1) / kLinkBlock);
    tbb::parallel_for(size_t(0), missing.size(), [&](size_t block) {
        const size_t first = block * kLinkBlock, last = std::min(sorted_slots.size(), (block + 1) * kLinkBlock);
        // Coarser keys are made a distance ahead, so their buckets are prefetched; the ring holds
        // the next ones (as the commit's look-up does). The finer keys two distances ahead.
        struct Parent {
            uint64_t key;
            uint32_t base;
        };
        Parent ahead[kPrefetchDistance];
        const auto makeParent = [&](size_t i) {
            const uint64_t key = key_decoder_.coarserKey(table_.keyAt(sorted_slots[i]));
            const Parent p{key, bucketBaseOf(key)};
            table_.prefetchBucket(p.base);
            return p;
        };
        for (size_t i = first; i < std::min(first + kPrefetchDistance, last); ++i)
            ahead[(i - first) % kPrefetchDistance] = makeParent(i);
        for (size_t i = first; i < last; ++i) {
            if (i + 2 * kPrefetchDistance < last) table_.prefetchBucket(sorted_slots[i + 2 * kPrefetchDistance]);
            const Parent next = ahead[(i - first) % kPrefetchDistance];
            if (i + kPrefetchDistance < last)
                ahead[(i - first) % kPrefetchDistance] = makeParent(i + kPrefetchDistance);
            const uint32_t slot = sorted_slots[i];
            const uint64_t parent_key = next.key;
            const uint32_t base = next.base;
            const Probe parent = probeBucket(parent_key, base);
            if (parent.found) {
                accumulation_[slot].coarser_slot = parent.slot + 1;
            } else {
                missing[block].push_back(NewKey{parent_key, base, slot, 0});
            }
        }
    });
    std::atomic<uint64_t> failed{0}, failed_equal_halves{0};
    occupied_ += insertByRange(missing, [&](const NewKey& k, uint32_t parent) {
        if (parent == kNoSlot) {
            failed.fetch_add(1, std::memory_order_relaxed);  // the finer voxel keeps its samples; this level lacks it
            if (keyHalvesAreEqual(k.key)) failed_equal_halves.fetch_add(1, std::memory_order_relaxed);
        } else {
            accumulation_[k.owner].coarser_slot = parent + 1;
        }
    });
    numerics_.failed_inserts += failed.load();
    numerics_.failed_inserts_equal_halves += failed_equal_halves.load();
}

void SharcCache::resolve(uint32_t iteration) {
    auto start = std::chrono::steady_clock::now();
    sumIntoCoarserLevels();
    stage_seconds_.coarser_levels += secondsSince(start);
    start = std::chrono::steady_clock::now();
    const double inverse_scale = 1.0 / radiance_scale_;
    std::vector<uint8_t> orphan(touched_.size(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, touched_.size()), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
            if (i + kPrefetchDistance < range.end()) {
                prefetchObjectForWrite(&accumulation_[touched_[i + kPrefetchDistance]]);
                prefetchObjectForWrite(&resolved_[touched_[i + kPrefetchDistance]]);
            }
            orphan[i] = resolveSlot(touched_[i], iteration, inverse_scale);
        }
    });
    for (size_t i = 0; i < touched_.size(); ++i) numerics_.orphan_sums += orphan[i];
    touched_.clear();
    stage_seconds_.resolve += secondsSince(start);
}

bool SharcCache::restoreSlot(uint32_t slot, uint64_t key, const ResolvedEntry& resolved) {
    if (slot >= table_.capacity() || table_.keyAt(slot) != kHashGridInvalidKey || table_.find(key)) return false;
    const std::optional<uint32_t> inserted = table_.insert(key);
    if (!inserted || *inserted != slot) {
        if (inserted) table_.clearSlot(*inserted);
        return false;
    }
    resolved_[slot] = resolved;
    ++occupied_;
    return true;
}

void SharcCache::grow(uint32_t capacity) {
    if (capacity <= table_.capacity()) return;
    HashGridTable table;
    const HashGridStatus status = HashGridTable::create(capacity, &table);
    if (status != HashGridStatus::kOk) throw std::invalid_argument(std::string("hash grid: ") + toString(status));
    ZeroedArray<ResolvedEntry> resolved(capacity);
    uint64_t occupied = 0;
    for (uint32_t slot = 0; slot < table_.capacity(); ++slot) {
        const uint64_t key = table_.keyAt(slot);
        if (key == kHashGridInvalidKey) continue;
        const std::optional<uint32_t> moved = table.insert(key);
        if (!moved) {  // a full bucket in a table at most an eighth full: counted, never silent
            ++numerics_.failed_inserts;
            numerics_.failed_inserts_equal_halves += keyHalvesAreEqual(key) ? 1 : 0;
            continue;
        }
        resolved[*moved] = resolved_[slot];
        ++occupied;
    }
    table_ = std::move(table);
    resolved_ = std::move(resolved);
    accumulation_ = ZeroedArray<AccumulationEntry>(capacity);
    occupied_ = occupied;
    settings_.grid.capacity = capacity;
}

CacheData toCacheData(const SharcCache& cache) {
    CacheData data;
    const SharcSettings& s = cache.settings();
    data.logarithm_base = s.grid.logarithm_base;
    data.scene_scale = s.grid.scene_scale;
    data.level_bias = s.grid.level_bias;
    data.bucket_size = s.grid.bucket_size;
    data.grid_anchor = s.grid_anchor;
    data.bake_capacity = cache.capacity();
    const HashGridTable& table = cache.table();
    for (uint32_t slot = 0; slot < table.capacity(); ++slot) {
        const uint64_t key = table.keyAt(slot);
        if (key == kHashGridInvalidKey) continue;  // before reading the entry: its page may be untouched
        const ResolvedEntry& r = cache.resolved()[slot];
        if (!(r.weight > 0.0)) continue;
        CacheVoxel v;
        v.key = key;
        v.radiance[0] = r.mean.x;
        v.radiance[1] = r.mean.y;
        v.radiance[2] = r.mean.z;
        v.sample_weight = float(r.weight);
        data.voxels.push_back(v);
    }
    sortVoxels(data.voxels);
    return data;
}

}  // namespace sharcbake
