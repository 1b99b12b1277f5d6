// SPDX-License-Identifier: Apache-2.0
#include "sharc/checkpoint.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake {
namespace {

// Counter names in the checkpoint's CNTR section. Counters only feed the final report; the
// cache itself depends on the table, the resolved entries and the iteration index alone.
struct NamedCount {
    const char* name;
    uint64_t UpdateCounters::*field;
};
constexpr NamedCount kUpdateCounts[] = {
    {"paths", &UpdateCounters::paths},
    {"segments", &UpdateCounters::segments},
    {"shadow_rays", &UpdateCounters::shadow_rays},
    {"resampled", &UpdateCounters::resampled},
    {"sky_misses", &UpdateCounters::sky_misses},
    {"non_finite_radiance", &UpdateCounters::non_finite},
    {"clamped_propagation", &UpdateCounters::clamped_propagation},
};
struct NamedNumericsCount {
    const char* name;
    uint64_t NumericsCounters::*field;
};
constexpr NamedNumericsCount kNumericsCounts[] = {
    {"deposits", &NumericsCounters::deposits},
    {"failed_inserts", &NumericsCounters::failed_inserts},
    {"failed_inserts_equal_halves", &NumericsCounters::failed_inserts_equal_halves},
    {"non_finite_deposits", &NumericsCounters::non_finite_deposits},
    {"negative_deposits", &NumericsCounters::negative_deposits},
    {"clamped_deposits", &NumericsCounters::clamped_deposits},
    {"sub_step_deposits", &NumericsCounters::sub_step_deposits},
    {"saturated_sums", &NumericsCounters::saturated_sums},
    {"orphan_sums", &NumericsCounters::orphan_sums},
};
struct NamedEnergy {
    const char* name;
    glm::dvec3 NumericsCounters::*field;
};
constexpr NamedEnergy kNumericsEnergies[] = {
    {"failed_insert_energy", &NumericsCounters::failed_insert_energy},
    {"clamped_energy", &NumericsCounters::clamped_energy},
    {"deposited_energy", &NumericsCounters::deposited_energy},
};
constexpr const char* kChannels[3] = {".r", ".g", ".b"};

template <typename Value>
const Value* findNamed(const std::vector<std::pair<std::string, Value>>& list, const std::string& name) {
    for (const auto& entry : list) {
        if (entry.first == name) return &entry.second;
    }
    return nullptr;
}

/// "seed: checkpoint \"3\", this bake \"4\"": one setting that differs.
std::string differenceLine(const std::string& key, const std::string& stored, const std::string& current) {
    return key + ": checkpoint \"" + stored + "\", this bake \"" + current + "\"";
}

/// "seed: checkpoint 3, this bake 4" for every setting that differs, or "". Cache-neutral
/// settings are left out (neutralDifferences).
std::string settingDifferences(const BakeSettingsText& stored, const BakeSettingsText& current) {
    std::string differences;
    auto add = [&](const std::string& line) { differences += "\n  " + line; };
    for (const auto& [key, value] : current) {
        if (isCacheNeutralSetting(key)) continue;
        const std::string* old = findNamed(stored, key);
        if (!old) {
            add(key + ": not in the checkpoint, this bake \"" + value + "\"");
        } else if (*old != value) {
            add(differenceLine(key, *old, value));
        }
    }
    for (const auto& [key, value] : stored) {
        if (!isCacheNeutralSetting(key) && !findNamed(current, key)) {
            add(key + ": checkpoint \"" + value + "\", not set by this bake");
        }
    }
    return differences;
}

/// The cache-neutral settings that both record, with other values.
std::vector<std::string> neutralDifferences(const BakeSettingsText& stored, const BakeSettingsText& current) {
    std::vector<std::string> differences;
    for (const auto& [key, value] : current) {
        const std::string* old = isCacheNeutralSetting(key) ? findNamed(stored, key) : nullptr;
        if (old && *old != value) differences.push_back(differenceLine(key, *old, value));
    }
    return differences;
}

}  // namespace

CheckpointData captureCheckpoint(const Baker& baker, const BakeSettingsText& settings) {
    const SharcCache& cache = baker.cache();
    CheckpointData data;
    data.iterations_done = baker.iterationsDone();
    data.capacity = cache.capacity();
    data.bucket_size = cache.table().bucketSize();
    data.radiance_scale = cache.radianceScale();
    data.settings = settings;
    for (uint32_t slot = 0; slot < cache.capacity(); ++slot) {
        const uint64_t key = cache.table().keyAt(slot);
        if (key == kHashGridInvalidKey) continue;
        const ResolvedEntry& r = cache.resolved()[slot];
        CheckpointSlot s;
        s.slot = slot;
        s.key = key;
        s.mean[0] = r.mean.x;
        s.mean[1] = r.mean.y;
        s.mean[2] = r.mean.z;
        s.feedback[0] = r.feedback.x;
        s.feedback[1] = r.feedback.y;
        s.feedback[2] = r.feedback.z;
        s.frames = r.frames;
        s.weight = r.weight;
        s.last_iteration = r.last_iteration;
        s.total_samples = r.total_samples;
        data.slots.push_back(s);
    }
    const UpdateCounters& update = baker.counters();
    for (const NamedCount& c : kUpdateCounts) data.counts.emplace_back(c.name, update.*c.field);
    const NumericsCounters& numerics = cache.numerics();
    for (const NamedNumericsCount& c : kNumericsCounts) data.counts.emplace_back(c.name, numerics.*c.field);
    for (const NamedEnergy& e : kNumericsEnergies) {
        for (int ch = 0; ch < 3; ++ch) data.amounts.emplace_back(std::string(e.name) + kChannels[ch], (numerics.*e.field)[ch]);
    }
    return data;
}

void saveCheckpoint(const std::string& path, const Baker& baker, const BakeSettingsText& settings) {
    std::string message;
    if (writeCheckpointFile(path, captureCheckpoint(baker, settings), &message) != CacheFileStatus::kOk) {
        throw CheckpointError(CheckpointError::Kind::kIo, message);
    }
}

std::vector<std::string> resumeFromCheckpoint(const std::string& path, const BakeSettingsText& settings, Baker& baker) {
    CheckpointData data;
    std::string message;
    const CacheFileStatus status = readCheckpointFile(path, &data, &message);
    if (status == CacheFileStatus::kIoError) throw CheckpointError(CheckpointError::Kind::kIo, message);
    if (status != CacheFileStatus::kOk) {
        // The status' words are a cache file's ("not a sharcbake cache file"); C1's message says it.
        const bool said = status == CacheFileStatus::kBadMagic;
        throw CheckpointError(CheckpointError::Kind::kInvalid,
                              said ? message : message + " (" + toString(status) + ")");
    }
    const std::string differences = settingDifferences(data.settings, settings);
    if (!differences.empty()) {
        throw CheckpointError(CheckpointError::Kind::kInvalid, path +
                                                                     " was written by a bake with other settings; resume with the "
                                                  "same scene and options (--iterations and --time-budget may "
                                                  "change):" + differences);
    }
    SharcCache& cache = baker.mutableCache();
    // A growing table (--capacity auto) may have grown before the checkpoint.
    if (cache.settings().grow_when_loaded && data.capacity > cache.capacity() && baker.iterationsDone() == 0) {
        cache.grow(data.capacity);
    }
    if (baker.iterationsDone() != 0) {
        throw CheckpointError(CheckpointError::Kind::kInvalid,
                              path + ": a checkpoint resumes a bake that has not run yet (this one ran " +
                                  std::to_string(baker.iterationsDone()) + " iterations)");
    }
    if (data.capacity != cache.capacity() || data.bucket_size != cache.table().bucketSize()) {
        const auto table = [](uint64_t capacity, uint32_t bucket_size) {
            return "capacity " + std::to_string(capacity) + ", buckets of " + std::to_string(bucket_size);
        };
        throw CheckpointError(CheckpointError::Kind::kInvalid, path + ": the checkpoint's table (" +
                                                                   table(data.capacity, data.bucket_size) +
                                                                   ") does not match this bake's (" +
                                                                   table(cache.capacity(), cache.table().bucketSize()) +
                                                                   "): resume with the --capacity it was baked with");
    }
    // The fixed-point scale is the checkpoint's: the same settings give the same one, unless the
    // sharcbake that wrote it chose scales by another rule (point lights counted at 1 cm before).
    cache.adoptRadianceScale(data.radiance_scale);
    for (const CheckpointSlot& s : data.slots) {
        ResolvedEntry r;
        r.mean = glm::vec3(s.mean[0], s.mean[1], s.mean[2]);
        r.feedback = glm::vec3(s.feedback[0], s.feedback[1], s.feedback[2]);
        r.frames = s.frames;
        r.weight = s.weight;
        r.last_iteration = s.last_iteration;
        r.total_samples = s.total_samples;
        if (!cache.restoreSlot(s.slot, s.key, r)) {
            throw CheckpointError(CheckpointError::Kind::kInvalid, path + ": slot " + std::to_string(s.slot) +
                                                      " holds a key this table would not put there");
        }
    }
    UpdateCounters update;
    for (const NamedCount& c : kUpdateCounts) {
        if (const uint64_t* v = findNamed(data.counts, c.name)) update.*c.field = *v;
    }
    NumericsCounters numerics;
    for (const NamedNumericsCount& c : kNumericsCounts) {
        if (const uint64_t* v = findNamed(data.counts, c.name)) numerics.*c.field = *v;
    }
    for (const NamedEnergy& e : kNumericsEnergies) {
        for (int ch = 0; ch < 3; ++ch) {
            if (const double* v = findNamed(data.amounts, std::string(e.name) + kChannels[ch])) (numerics.*e.field)[ch] = *v;
        }
    }
    cache.restoreNumerics(numerics);
    baker.resumeAt(data.iterations_done, update);
    return neutralDifferences(data.settings, settings);
}

CheckpointLock::CheckpointLock(const std::string& path) : lock_path_(path + ".lock") {
    for (int attempt = 0; attempt < 8; ++attempt) {
        const int fd = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0) {
            throw CheckpointError(CheckpointError::Kind::kIo,
                                  lock_path_ + ": cannot create the checkpoint lock: " + std::strerror(errno));
        }
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            char owner[32] = {};
            const ssize_t n = ::pread(fd, owner, sizeof owner - 1, 0);
            ::close(fd);
            std::string pid = n > 0 ? std::string(owner, size_t(n)) : std::string();
            pid.resize(std::min(pid.size(), pid.find_first_not_of("0123456789")));
            throw CheckpointError(CheckpointError::Kind::kInUse, path + ": the checkpoint is in use by another bake (process " +
                                                                     (pid.empty() ? std::string("?") : pid) + ")");
        }
        // The holder before us may have removed the file between our open and our lock: only a
        // lock on the file that is still at the path counts.
        struct stat held {}, current {};
        if (::fstat(fd, &held) == 0 && ::stat(lock_path_.c_str(), &current) == 0 && held.st_dev == current.st_dev &&
            held.st_ino == current.st_ino) {
            const std::string pid = std::to_string(long(::getpid()));
            if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) != ssize_t(pid.size())) {
                // The pid is only for the other bake's message; the lock holds without it.
            }
            fd_ = fd;
            return;
        }
        ::close(fd);
    }
    throw CheckpointError(CheckpointError::Kind::kIo,
                          lock_path_ + ": cannot take the checkpoint lock (the file keeps changing)");
}

CheckpointLock::~CheckpointLock() {
    if (fd_ < 0) return;
    ::unlink(lock_path_.c_str());  // while still locked, so no other bake holds a lock on a removed file
    ::close(fd_);
}

}  // namespace sharcbake
