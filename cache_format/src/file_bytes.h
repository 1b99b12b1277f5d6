// SPDX-License-Identifier: Apache-2.0
// A file's bytes for CacheView::openFile: read into a buffer, or memory-mapped where the platform
// offers it (POSIX). The only platform-specific code of the runtime library; elsewhere a
// mapping request reads the file instead. Internal to cache_format/.
#pragma once

#include "sharcbake/cache_types.h"

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace sharcbake {

/// Where loadFileBytes put the file: `owned` (read) or a mapping to release with
/// releaseFileMapping.
struct FileBytes {
    std::vector<uint8_t> owned;
    void* mapping = nullptr;
    size_t mapping_size = 0;
    const uint8_t* data = nullptr;  ///< owned.data() or the mapping; nullptr for an empty file
    size_t size = 0;
};

/// Opens `path` (refusing anything but a regular file, without blocking on a FIFO) and reads or
/// maps it. kIoError with a message naming the path on failure; kOk otherwise.
CacheFileStatus loadFileBytes(const std::string& path, bool map, FileBytes* out, std::string* message);

/// Releases a mapping made by loadFileBytes (nothing for nullptr).
void releaseFileMapping(void* mapping, size_t size);

}  // namespace sharcbake
