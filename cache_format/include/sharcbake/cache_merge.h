// SPDX-License-Identifier: Apache-2.0
/// @file cache_merge.h
/// @brief Combining caches baked independently (shards) of the same scene into one.
#pragma once

#include "sharcbake/cache_file.h"

#include <string>
#include <vector>

namespace sharcbake {

/// Merges `inputs` voxel by voxel: a key present in several inputs gets the sample-weighted
/// mean of their radiance, sum(w_i * L_i) / sum(w_i), and the summed weight; a key present in
/// one input is copied. Contributions are summed in double in a canonical order (sorted by
/// weight, then radiance), so the result does not depend on the order of `inputs`.
///
/// Refuses (kInvalidData, with a message naming the first differing input and field) inputs
/// whose grid parameters (logarithm base, scene scale, level bias, bucket size), GPU radiance
/// scales or format versions differ, or whose metadata differ in one of `keys_that_must_agree` (for example
/// "scene_hash"; a key missing from an input counts as a difference).
/// `out` gets the merged voxels and the grid parameters, bake_capacity the largest input's;
/// its metadata is left empty for the caller to describe the merge.
CacheFileStatus mergeCaches(const std::vector<CacheData>& inputs, const std::vector<std::string>& keys_that_must_agree,
                            CacheData* out, std::string* message);

}  // namespace sharcbake
