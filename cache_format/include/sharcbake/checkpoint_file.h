// SPDX-License-Identifier: Apache-2.0
/// @file checkpoint_file.h
/// @brief A bake's state between two iterations (what `--checkpoint` writes and `--resume`
/// reads), and the checkpoint file that holds it.
///
/// The byte layout is SPEC.md §C: the .sharc container (header, section table, CRC-32 per
/// section) under its own identifier, so a checkpoint is never mistaken for a cache. Only
/// checkpoint_file.cpp knows the bytes. No exceptions: functions return a CacheFileStatus.
#pragma once

#include "sharcbake/cache_file.h"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace sharcbake {

/// One occupied slot of the bake's hash table and its resolved state. The slot is stored, not
/// only the key, because which slot a later key lands in depends on the slots already taken.
struct CheckpointSlot {
    uint32_t slot = 0;
    uint64_t key = 0;                     ///< non-zero
    float mean[3] = {0.0f, 0.0f, 0.0f};   ///< resolved mean radiance, finite, >= 0
    uint32_t frames = 0;                  ///< iterations in which the voxel received samples
    double weight = 0.0;                  ///< effective sample count of the history, finite, >= 0
    uint32_t last_iteration = 0;
    uint32_t total_samples = 0;
    float feedback[3] = {0.0f, 0.0f, 0.0f};  ///< short-window mean cache resampling reads, finite, >= 0
};

/// Everything a bake needs to continue exactly where it stopped. The per-iteration
/// accumulation is empty between iterations, so it is not part of the state.
struct CheckpointData {
    uint32_t iterations_done = 0;
    uint32_t capacity = 0;     ///< table slots, >= 1
    uint32_t bucket_size = kHashGridBucketSize;
    double radiance_scale = 1.0;  ///< fixed-point scale of the sums, finite, > 0
    /// Occupied slots, strictly increasing slot index, each < capacity.
    std::vector<CheckpointSlot> slots;
    /// What must be equal for a resume to give the uninterrupted bake's result (scene hash,
    /// seed, grid, path and camera settings), as ordered unique key/value UTF-8 text.
    std::vector<std::pair<std::string, std::string>> settings;
    /// Statistics carried across the resume so the final report counts the whole bake.
    std::vector<std::pair<std::string, uint64_t>> counts;
    std::vector<std::pair<std::string, double>> amounts;
};

/// The most iterations a checkpoint may record (rule C8; the bake's --iterations limit), so a
/// crafted counter cannot make a resumed bake loop for ever.
inline constexpr uint32_t kCheckpointMaxIterations = 1u << 30;

/// Serialises `data` (SPEC §C) into `bytes`; refuses data a reader would reject (kInvalidData).
CacheFileStatus encodeCheckpoint(const CheckpointData& data, std::vector<uint8_t>* bytes, std::string* message);

/// Parses and fully validates checkpoint bytes (SPEC §C.4); the message names the rule ("C7: ...").
CacheFileStatus decodeCheckpoint(const uint8_t* bytes, size_t size, CheckpointData* data, std::string* message);

/// Writes atomically (writeFileAtomically): a temporary file beside `path`, flushed to disk, then
/// renamed over `path`. A process killed at any moment leaves the previous checkpoint intact.
CacheFileStatus writeCheckpointFile(const std::string& path, const CheckpointData& data, std::string* message);

/// Reads and validates a checkpoint file; messages start with the path.
CacheFileStatus readCheckpointFile(const std::string& path, CheckpointData* data, std::string* message);

}  // namespace sharcbake
