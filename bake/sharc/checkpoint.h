// SPDX-License-Identifier: Apache-2.0
/// @file checkpoint.h
/// @brief Saving a bake's state between iterations and continuing from it (--checkpoint,
/// --resume). The bytes are cache_format's (checkpoint_file.h); this maps a Baker onto them.
#pragma once

#include "sharc/baker.h"
#include "sharcbake/checkpoint_file.h"

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {

using BakeSettingsText = std::vector<std::pair<std::string, std::string>>;

/// A setting whose key is an option's name ("--voxel-materials") records an option that does not
/// change the bake's state (the table, the voxels, the iterations), only what is made from it
/// afterwards: a resume that gives it another value warns instead of refusing.
inline bool isCacheNeutralSetting(const std::string& key) { return key.rfind("--", 0) == 0; }

/// Why a checkpoint could not be saved, resumed from or locked. The message names the file;
/// the command line adds which option it came from and the exit code.
class CheckpointError : public std::runtime_error {
public:
    enum class Kind {
        kIo,       ///< the file could not be read or written
        kInvalid,  ///< not a valid checkpoint, or one of another bake (other settings or table)
        kInUse,    ///< another bake holds the checkpoint's lock
    };
    CheckpointError(Kind kind, const std::string& message) : std::runtime_error(message), kind_(kind) {}
    Kind kind() const { return kind_; }

private:
    Kind kind_;
};

/// The baker's state after its last iteration, with the settings a resume must match.
CheckpointData captureCheckpoint(const Baker& baker, const BakeSettingsText& settings);

/// Writes captureCheckpoint(baker, settings) to `path` atomically; throws CheckpointError (kIo).
void saveCheckpoint(const std::string& path, const Baker& baker, const BakeSettingsText& settings);

/// Reads `path` and puts its state into `baker`, which must be fresh (no iteration run).
/// Throws CheckpointError: kIo if the file cannot be read, kInvalid if it is not a valid
/// checkpoint or was written with other settings (the message lists each difference). Returns
/// one line for each cache-neutral setting (isCacheNeutralSetting) that the checkpoint records
/// with another value, e.g. "--voxel-materials: checkpoint \"false\", this bake \"true\"";
/// one the checkpoint does not record (an older one) is not compared.
std::vector<std::string> resumeFromCheckpoint(const std::string& path, const BakeSettingsText& settings, Baker& baker);

/// Exclusive use of a checkpoint path for one bake, taken before any work: two bakes sharing one
/// checkpoint would overwrite each other's state, so the second is refused at start
/// (CheckpointError kInUse, naming the other process; kIo when the lock cannot be made). The lock is flock() on `path` + ".lock",
/// removed when the lock is released; a process killed with the lock held releases it with its
/// file descriptors, and the next bake takes over the stale file.
class CheckpointLock {
public:
    explicit CheckpointLock(const std::string& path);
    ~CheckpointLock();
    CheckpointLock(const CheckpointLock&) = delete;
    CheckpointLock& operator=(const CheckpointLock&) = delete;

    /// The lock file (`path` + ".lock").
    const std::string& lockPath() const { return lock_path_; }

private:
    std::string lock_path_;
    int fd_ = -1;
};

}  // namespace sharcbake
