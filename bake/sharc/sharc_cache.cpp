// SPDX-License-Identifier: Apache-2.0
#include "sharc/sharc_cache.h"

#include "tracing/sampling.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

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

/// Up to kSlots per-slot sums of one chunk's deposits, 96 bits wide per channel, added to the
/// shared accumulation one slot at a time: a path deposits into the same voxels several times,
/// and the bright voxels are shared by every thread, so one atomic add per slot and chunk
/// instead of one per deposit cuts the contention.
/// A hint to start loading the line at `address` for writing; no effect on results. Slots are
/// scattered over a table far larger than the caches, so loops over slots ask a few entries ahead.
inline void prefetchForWrite(const void* address) {
#if defined(__GNUC__) || defined(__clang__)
    __builtin_prefetch(address, 1);
#else
    (void)address;
#endif
}
/// How many entries ahead those loops prefetch (enough to cover a memory latency).
constexpr size_t kPrefetchDistance = 8;

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
    uint64_t negative = 0, clamped = 0, saturated = 0;
    glm::dvec3 clamped_energy{0.0};
    std::vector<uint32_t> touched;
};

double SharcCache::chooseRadianceScale(double max_radiance) {
    // The brightest radiance maps to 2^40: 40 bits of precision below it (and dithered rounding
    // beyond that), 2^22 times above it for one deposit (multi-bounce radiance exceeds emission:
    // L = Le/(1-rho) in a furnace), and 2^32 deposits that bright in a voxel's 72-bit sum.
    const double magnitude = (std::isfinite(max_radiance) && max_radiance > 0.0) ? max_radiance : 1.0;
    const int exponent = std::clamp(40 - int(std::ceil(std::log2(magnitude))), -60, 100);
    return std::ldexp(1.0, exponent);
}

SharcCache::SharcCache(const SharcSettings& settings, double radiance_scale)
    : settings_(settings),
      radiance_scale_(radiance_scale),
      accumulation_(settings.grid.capacity),
      resolved_(settings.grid.capacity) {
    const HashGridStatus status = HashGridTable::create(settings.grid.capacity, &table_);
    if (status != HashGridStatus::kOk) {
        throw std::invalid_argument(std::string("hash grid: ") + toString(status));
    }
}

const ResolvedEntry* SharcCache::findResolved(uint64_t key) const {
    const std::optional<uint32_t> slot = table_.find(key);
    return slot ? &resolved_[*slot] : nullptr;
}

void SharcCache::commit(const std::vector<Deposit>& deposits, uint32_t iteration) {
    commitChunks(std::vector<std::vector<Deposit>>{deposits}, iteration);
}

namespace {
constexpr uint32_t kMissing = kHashGridInvalidIndex;      // key not in the table yet
constexpr uint32_t kDropped = kHashGridInvalidIndex - 1;  // non-finite or failed insert
}  // namespace

void SharcCache::commitChunks(const std::vector<std::vector<Deposit>>& chunks, uint32_t iteration) {
    chunk_slots_.resize(chunks.size());
    chunk_missing_.resize(chunks.size());
    std::vector<uint64_t> chunk_non_finite(chunks.size(), 0);
    std::vector<glm::dvec3> chunk_deposited(chunks.size(), glm::dvec3(0.0));
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t chunk) {
        lookUpSlots(chunks[chunk], chunk, chunk_non_finite[chunk], chunk_deposited[chunk]);
    });
    insertNewKeys(chunks, chunk_non_finite, chunk_deposited);
    std::vector<ChunkNumerics> chunk_numerics(chunks.size());
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t chunk) {
        accumulateChunk(chunks[chunk], chunk, iteration, chunk_numerics[chunk]);
    });
    for (const ChunkNumerics& n : chunk_numerics) {
        numerics_.negative_deposits += n.negative;
        numerics_.clamped_deposits += n.clamped;
        numerics_.clamped_energy += n.clamped_energy;
        numerics_.saturated_sums += n.saturated;
        touched_.insert(touched_.end(), n.touched.begin(), n.touched.end());
    }
}

// 1. Parallel over chunks: look every key up (the table is read-only here). A path deposits into
//    its own voxel and then into the same voxels again as later vertices propagate back, so the
//    last few keys are remembered; each chunk lists the deposits whose key is new.
void SharcCache::lookUpSlots(const std::vector<Deposit>& deposits, size_t chunk, uint64_t& non_finite,
                             glm::dvec3& deposited) {
    std::vector<uint32_t>& slots = chunk_slots_[chunk];
    std::vector<uint32_t>& missing = chunk_missing_[chunk];
    slots.resize(deposits.size());
    missing.clear();
    constexpr size_t kRecent = 4;
    uint64_t recent_keys[kRecent] = {};  // key 0 never occurs
    uint32_t recent_slots[kRecent] = {};
    size_t next_recent = 0;
    for (size_t i = 0; i < deposits.size(); ++i) {
        const Deposit& d = deposits[i];
        if (!isFiniteColor(d.radiance)) {
            slots[i] = kDropped;
            ++non_finite;
            continue;
        }
        deposited += glm::dvec3(glm::max(d.radiance, glm::vec3(0.0f)));
        size_t r = 0;
        while (r < kRecent && recent_keys[r] != d.key) ++r;
        if (r < kRecent) {
            slots[i] = recent_slots[r];
        } else {
            slots[i] = table_.find(d.key).value_or(kMissing);
            recent_keys[next_recent] = d.key;
            recent_slots[next_recent] = slots[i];
            next_recent = (next_recent + 1) % kRecent;
        }
        if (slots[i] == kMissing) missing.push_back(uint32_t(i));
    }
}

// 2. Serial, in chunk (= path) order: insert the new keys. Slot assignment is therefore the same
//    on every run, whatever thread traced which path. Only the deposits listed as new are
//    visited, so this serial step shrinks to almost nothing once the cache is warm.
void SharcCache::insertNewKeys(const std::vector<std::vector<Deposit>>& chunks,
                               const std::vector<uint64_t>& chunk_non_finite,
                               const std::vector<glm::dvec3>& chunk_deposited) {
    for (size_t chunk = 0; chunk < chunks.size(); ++chunk) {
        const std::vector<Deposit>& deposits = chunks[chunk];
        std::vector<uint32_t>& slots = chunk_slots_[chunk];
        numerics_.deposits += deposits.size();
        numerics_.non_finite_deposits += chunk_non_finite[chunk];
        numerics_.deposited_energy += chunk_deposited[chunk];
        for (const uint32_t i : chunk_missing_[chunk]) {
            const Deposit& d = deposits[i];
            // A key new to this iteration comes back here once per deposit: the first inserts
            // it, the later ones find it.
            const bool fresh = !table_.find(d.key);
            const std::optional<uint32_t> inserted = table_.insert(d.key);
            if (inserted) {
                slots[i] = *inserted;
                occupied_ += fresh;
            } else {
                slots[i] = kDropped;
                ++numerics_.failed_inserts;
                numerics_.failed_insert_energy += glm::dvec3(glm::max(d.radiance, glm::vec3(0.0f)));
            }
        }
    }
}

// 3. Parallel over chunks: fixed-point conversion and integer atomic adds, which commute, so the
//    sums do not depend on the order either. Integer addition with carries is associative, so
//    the 72-bit sums are bit-identical however PendingSums groups them.
void SharcCache::accumulateChunk(const std::vector<Deposit>& deposits, size_t chunk, uint32_t iteration,
                                 ChunkNumerics& numerics) {
    const std::vector<uint32_t>& slots = chunk_slots_[chunk];
    const auto flush = [&](const PendingSums::Sum& p) {
        AccumulationEntry& entry = accumulation_[p.slot];
        if (entry.touched.exchange(1, std::memory_order_relaxed) == 0) numerics.touched.push_back(p.slot);
        for (int c = 0; c < 3; ++c) {
            if ((p.sums[c] || p.carries[c]) && !addToSum(entry.sums[c], entry.carries[c], p.sums[c], p.carries[c])) {
                ++numerics.saturated;
            }
        }
        if (p.samples) entry.samples.fetch_add(p.samples, std::memory_order_relaxed);
    };
    PendingSums pending;
    for (size_t i = 0; i < deposits.size(); ++i) {
        if (i + kPrefetchDistance < deposits.size() && slots[i + kPrefetchDistance] < kDropped) {
            prefetchForWrite(&accumulation_[slots[i + kPrefetchDistance]]);
        }
        if (slots[i] >= kDropped) continue;
        const Deposit& d = deposits[i];
        PendingSums::Sum& sum = pending.at(slots[i], flush);
        bool negative = false, clamped = false;
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
    using SlotLists = tbb::enumerable_thread_specific<std::vector<uint32_t>>;
    const auto gather = [](SlotLists& lists, std::vector<uint32_t>& out) {
        for (std::vector<uint32_t>& list : lists) {
            out.insert(out.end(), list.begin(), list.end());
            list.clear();
        }
    };
    // The touched voxels by level; coarser voxels join the next level's list as they are touched.
    std::vector<std::vector<uint32_t>> by_level(size_t(coarsest) + 1);
    for (const uint32_t slot : touched_) {
        const uint32_t level = decodeHashGridKey(table_.keyAt(slot)).level;
        if (level < coarsest) by_level[level].push_back(slot);
    }
    SlotLists unknown, newly_touched;
    for (uint32_t level = kHashGridLevelMin; level < coarsest; ++level) {
        const std::vector<uint32_t>& slots = by_level[level];
        if (slots.empty()) continue;
        // The coarser voxel of each voxel is looked up once (then remembered in coarser_slot).
        // New coarser keys are inserted serially in slot order, so their slots do not depend on
        // the thread count.
        tbb::parallel_for(size_t(0), slots.size(), [&](size_t i) {
            if (accumulation_[slots[i]].coarser_slot == 0) unknown.local().push_back(slots[i]);
        });
        std::vector<uint32_t> lookups;
        gather(unknown, lookups);
        std::sort(lookups.begin(), lookups.end());
        for (const uint32_t slot : lookups) {
            const uint64_t parent_key = coarserKey(table_.keyAt(slot), settings_.grid);
            const bool fresh = !table_.find(parent_key);
            const std::optional<uint32_t> parent = table_.insert(parent_key);
            if (!parent) {
                ++numerics_.failed_inserts;  // the finer voxel keeps its samples; this level lacks it
                continue;
            }
            occupied_ += fresh;
            accumulation_[slot].coarser_slot = *parent + 1;
        }
        // Integer adds commute, so the coarser sums do not depend on the order either.
        std::atomic<uint64_t> saturated{0};
        tbb::parallel_for(size_t(0), slots.size(), [&](size_t i) {
            AccumulationEntry& child = accumulation_[slots[i]];
            if (child.coarser_slot == 0) return;
            const uint32_t parent_slot = child.coarser_slot - 1;
            AccumulationEntry& parent = accumulation_[parent_slot];
            if (parent.touched.exchange(1, std::memory_order_relaxed) == 0) newly_touched.local().push_back(parent_slot);
            for (int c = 0; c < 3; ++c) {
                const uint64_t low = child.sums[c].load(std::memory_order_relaxed);
                const uint8_t carries = child.carries[c].load(std::memory_order_relaxed);
                if ((low || carries) && !addToSum(parent.sums[c], parent.carries[c], low, carries)) {
                    saturated.fetch_add(1, std::memory_order_relaxed);
                }
            }
            parent.samples.fetch_add(child.samples.load(std::memory_order_relaxed), std::memory_order_relaxed);
        });
        numerics_.saturated_sums += saturated.load();
        const size_t before = touched_.size();
        gather(newly_touched, touched_);
        if (level + 1 < coarsest) {
            by_level[level + 1].insert(by_level[level + 1].end(), touched_.begin() + std::ptrdiff_t(before), touched_.end());
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

void SharcCache::resolve(uint32_t iteration) {
    sumIntoCoarserLevels();
    const double inverse_scale = 1.0 / radiance_scale_;
    std::vector<uint8_t> orphan(touched_.size(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, touched_.size()), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t i = range.begin(); i != range.end(); ++i) {
            if (i + kPrefetchDistance < range.end()) {
                prefetchForWrite(&accumulation_[touched_[i + kPrefetchDistance]]);
                prefetchForWrite(&resolved_[touched_[i + kPrefetchDistance]]);
            }
            orphan[i] = resolveSlot(touched_[i], iteration, inverse_scale);
        }
    });
    for (size_t i = 0; i < touched_.size(); ++i) numerics_.orphan_sums += orphan[i];
    touched_.clear();
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
