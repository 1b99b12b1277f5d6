// SPDX-License-Identifier: Apache-2.0
// Writing the .sharc byte layout (SPEC.md §F), and readCacheFile over CacheView (runtime.cpp).
#include "sharcbake/cache_file.h"

#include "container.h"
#include "sharcbake/format.h"
#include "sharcbake/runtime.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string_view>
#include <unordered_set>

#include <cerrno>
#include <climits>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake {
namespace {

static_assert(sizeof(float) == 4 && sizeof(double) == 8, "IEEE 754 floats expected");

}  // namespace


HashGridParameters CacheData::gridParameters() const {
    HashGridParameters p;
    p.logarithm_base = logarithm_base;
    p.scene_scale = scene_scale;
    p.level_bias = level_bias;
    p.bucket_size = bucket_size;
    p.capacity = bake_capacity;
    return p;
}


void sortVoxels(std::vector<CacheVoxel>& voxels) {
    std::sort(voxels.begin(), voxels.end(), [](const CacheVoxel& a, const CacheVoxel& b) { return a.key < b.key; });
}

namespace {

/// What a reader would reject (SPEC §F.10), refused before writing with a writer-side message;
/// on success `levels` holds the voxel count of every level present, ascending.
CacheFileStatus checkCacheData(const CacheData& data, std::vector<CacheLevel>& levels, std::string* message) {
    std::array<uint32_t, kHashGridLevelMax + 1> per_level{};
    for (size_t i = 0; i < data.voxels.size(); ++i) {
        const CacheVoxel& v = data.voxels[i];
        const uint32_t level = uint32_t(v.key >> kHashGridLevelOffset) & kHashGridLevelMask;
        if (v.key == kHashGridInvalidKey || (i > 0 && data.voxels[i - 1].key >= v.key) || level == 0 ||
            (v.key >> kHashGridUserBit) != 0) {
            return fail(CacheFileStatus::kInvalidData, message,
                        "voxels must have non-zero keys with level >= 1 and bit 63 clear, in strictly increasing order "
                        "(voxel " + std::to_string(i) + ")");
        }
        for (float c : v.radiance) {
            if (!std::isfinite(c) || c < 0.0f) {
                return fail(CacheFileStatus::kInvalidData, message,
                            "voxel " + std::to_string(i) + ": radiance must be finite and >= 0");
            }
        }
        if (!std::isfinite(v.sample_weight) || !(v.sample_weight > 0.0f)) {
            return fail(CacheFileStatus::kInvalidData, message,
                        "voxel " + std::to_string(i) + ": sample weight must be finite and > 0 (only live voxels are stored)");
        }
        ++per_level[level];
    }
    if (!std::isfinite(data.gpu_radiance_scale) || !(data.gpu_radiance_scale > 0.0f)) {
        return fail(CacheFileStatus::kInvalidData, message, "the GPU radiance scale must be finite and > 0");
    }
    if (!std::isfinite(data.grid_anchor.x) || !std::isfinite(data.grid_anchor.y) ||
        !std::isfinite(data.grid_anchor.z)) {
        return fail(CacheFileStatus::kInvalidData, message, "the grid anchor must be finite");
    }
    if (!data.voxel_materials.empty() && data.voxel_materials.size() != data.voxels.size()) {
        return fail(CacheFileStatus::kInvalidData, message, "voxel materials: one per voxel, or none");
    }
    for (size_t i = 0; i < data.voxel_materials.size(); ++i) {
        if (!validVoxelMaterial(data.voxel_materials[i])) {
            return fail(CacheFileStatus::kInvalidData, message,
                        "voxel " + std::to_string(i) + ": emission must be finite and >= 0, the demodulation "
                        "factor finite and > 0");
        }
    }
    if (validateHashGridParameters(data.gridParameters()) != HashGridStatus::kOk || data.bake_capacity == 0) {
        return fail(CacheFileStatus::kInvalidData, message,
                    std::string("grid parameters: ") + toString(validateHashGridParameters(data.gridParameters())));
    }
    std::unordered_set<std::string_view> keys;  // linear, not quadratic, in the entry count
    keys.reserve(data.metadata.size());
    for (const auto& [key, value] : data.metadata) {
        if (key.empty() || key.size() > 0xFFFFFFFFu || value.size() > 0xFFFFFFFFu) {
            return fail(CacheFileStatus::kInvalidData, message, "metadata keys must be non-empty");
        }
        if (!keys.insert(key).second) {
            return fail(CacheFileStatus::kInvalidData, message, "duplicate metadata key \"" + key + "\"");
        }
    }
    levels.clear();
    for (uint32_t l = 1; l <= kHashGridLevelMax; ++l) {
        if (per_level[l]) levels.push_back(CacheLevel{l, per_level[l]});
    }
    return CacheFileStatus::kOk;
}

/// GRID (SPEC §F.5): the hash grid's layout and parameters.
void writeGridSection(ByteWriter& w, const CacheData& data, uint32_t level_count) {
    w.put(kHashGridPositionBits);
    w.put(kHashGridLevelBits);
    w.put(kHashGridNormalBits);
    w.put(data.bucket_size);
    w.put(kCacheHashJenkins32Xor);
    w.put(kCacheLodCameraDistance);
    w.put(data.logarithm_base);
    w.put(data.scene_scale);
    w.put(data.level_bias);
    w.put(data.bake_capacity);
    w.put(kHashGridPositionBias);
    w.put(kHashGridNormalBias);
    w.put(uint64_t(data.voxels.size()));
    w.put(level_count);
    w.put(uint32_t(0));
}

/// META (SPEC §F.8): entry count, then each key and value with their lengths.
void writeMetadataSection(ByteWriter& w, const std::vector<std::pair<std::string, std::string>>& metadata) {
    w.put(uint32_t(metadata.size()));
    w.put(uint32_t(0));
    for (const auto& [key, value] : metadata) {
        w.put(uint32_t(key.size()));
        w.put(uint32_t(value.size()));
        w.putBytes(key.data(), key.size());
        w.putBytes(value.data(), value.size());
    }
}

}  // namespace

// Writes the sections in the order of SPEC §F.4: GRID, KEYS, VOXL, LEVL, META (and RSCL, VMAT, ANCR).
CacheFileStatus encodeCacheFile(const CacheData& data, std::vector<uint8_t>* out, std::string* message) {
    if (!out) return fail(CacheFileStatus::kInvalidArgument, message, "encodeCacheFile: null output");
    if (!hostIsLittleEndian()) return fail(CacheFileStatus::kUnsupportedFeature, message, "big-endian hosts are not supported");
    std::vector<CacheLevel> levels;
    if (const CacheFileStatus status = checkCacheData(data, levels, message); status != CacheFileStatus::kOk) {
        return status;
    }
    const bool scaled = data.gpu_radiance_scale != 1.0f;  // SPEC §F.8a: RSCL only when not 1
    const bool materials = !data.voxel_materials.empty();  // SPEC §F.8b: VMAT only when kept
    const Float3& anchor = data.grid_anchor;
    const bool anchored = anchor.x != 0.0f || anchor.y != 0.0f || anchor.z != 0.0f;  // SPEC §F.8c
    const uint32_t kSections = 5 + (scaled ? 1 : 0) + (materials ? 1 : 0) + (anchored ? 1 : 0);
    std::vector<uint8_t>& bytes = *out;
    bytes.clear();
    bytes.reserve(kCacheHeaderSize + kSections * kCacheSectionEntrySize + 64 + data.voxels.size() * 24 +
                  levels.size() * 8 + 4096);
    ContainerWriter container(bytes, kCacheIdentifier, kCacheVersionMajor, kCacheVersionMinor, kSections);
    ByteWriter& w = container.out();
    container.beginSection(kSectionGrid, kCacheSectionRequired);
    writeGridSection(w, data, uint32_t(levels.size()));
    container.endSection();
    container.beginSection(kSectionKeys, kCacheSectionRequired);  // SPEC §F.6
    for (const CacheVoxel& v : data.voxels) w.put(v.key);
    container.endSection();
    container.beginSection(kSectionVoxels, kCacheSectionRequired);  // SPEC §F.6
    for (const CacheVoxel& v : data.voxels) {
        w.put(v.radiance[0]);
        w.put(v.radiance[1]);
        w.put(v.radiance[2]);
        w.put(v.sample_weight);
    }
    container.endSection();
    container.beginSection(kSectionLevels, kCacheSectionRequired);  // SPEC §F.7
    for (const CacheLevel& l : levels) {
        w.put(l.level);
        w.put(l.voxel_count);
    }
    container.endSection();
    container.beginSection(kSectionMetadata, 0);  // optional
    writeMetadataSection(w, data.metadata);
    container.endSection();
    if (scaled) {
        container.beginSection(kSectionRadianceScale, kCacheSectionRequired);  // SPEC §F.8a
        w.put(data.gpu_radiance_scale);
        w.put(uint32_t(0));
        container.endSection();
    }
    if (materials) {
        container.beginSection(kSectionVoxelMaterials, 0);  // SPEC §F.8b, optional
        for (const CacheVoxelMaterial& m : data.voxel_materials) {
            for (float c : m.emission) w.put(c);
            for (float c : m.demodulation) w.put(c);
        }
        container.endSection();
    }
    if (anchored) {
        container.beginSection(kSectionGridAnchor, 0);  // SPEC §F.8c, optional
        w.put(anchor.x);
        w.put(anchor.y);
        w.put(anchor.z);
        w.put(uint32_t(0));
        container.endSection();
    }
    container.finish();  // table entries, file size, checksums
    // Metadata text is validated as UTF-8 by the reader: check here, on the encoded bytes.
    CacheView view;
    CacheError error;
    if (CacheView::openMemory(bytes.data(), bytes.size(), &view, &error) != CacheFileStatus::kOk) {
        return fail(CacheFileStatus::kInvalidData, message, "the data cannot be stored: " + error.message);
    }
    return CacheFileStatus::kOk;
}

namespace {

std::string folderOf(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return ".";
    return slash == 0 ? "/" : path.substr(0, slash);
}

/// Removes "<name>.tmp-PID" files beside `target` whose process no longer runs.
void removeStaleTemporaries(const std::string& target) {
    const std::string folder = folderOf(target);
    const size_t slash = target.find_last_of('/');
    const std::string prefix = (slash == std::string::npos ? target : target.substr(slash + 1)) + ".tmp-";
    DIR* dir = ::opendir(folder.c_str());
    if (!dir) return;
    while (const dirent* entry = ::readdir(dir)) {
        const std::string name = entry->d_name;
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
        const std::string digits = name.substr(prefix.size());
        if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
        const long pid = std::strtol(digits.c_str(), nullptr, 10);
        if (pid <= 0 || pid == long(::getpid())) continue;
        if (::kill(pid_t(pid), 0) != 0 && errno == ESRCH) ::unlink((folder + "/" + name).c_str());
    }
    ::closedir(dir);
}

}  // namespace

CacheFileStatus prepareOutputFile(const std::string& path, std::string* target, std::string* temporary,
                                  std::string* message) {
    if (!target || !temporary) return fail(CacheFileStatus::kInvalidArgument, message, "prepareOutputFile: null output");
    // Follow symbolic links one hop at a time (the last target may not exist yet).
    std::string resolved = path;
    for (int hops = 0;; ++hops) {
        struct stat link_info {};
        if (::lstat(resolved.c_str(), &link_info) != 0 || !S_ISLNK(link_info.st_mode)) break;
        if (hops == 40) return fail(CacheFileStatus::kIoError, message, path + ": too many levels of symbolic links");
        std::string link(size_t(PATH_MAX), '\0');
        const ssize_t n = ::readlink(resolved.c_str(), link.data(), link.size());
        if (n <= 0 || size_t(n) >= link.size()) {
            return fail(CacheFileStatus::kIoError, message, path + ": cannot read the symbolic link");
        }
        link.resize(size_t(n));
        resolved = link[0] == '/' ? link : folderOf(resolved) + "/" + link;
    }
    struct stat info {};
    if (::stat(resolved.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
        const char* kind = S_ISDIR(info.st_mode) ? "a folder"
                           : S_ISCHR(info.st_mode) || S_ISBLK(info.st_mode) ? "a device"
                           : S_ISFIFO(info.st_mode)                          ? "a FIFO"
                                                                             : "not a regular file";
        return fail(CacheFileStatus::kIoError, message,
                    path + ": is " + std::string(kind) + "; outputs are written only to regular files");
    }
    removeStaleTemporaries(resolved);
    *target = resolved;
    *temporary = resolved + ".tmp-" + std::to_string(long(::getpid()));
    return CacheFileStatus::kOk;
}

CacheFileStatus commitOutputFile(const std::string& temporary, const std::string& target, std::string* message) {
    const int fd = ::open(temporary.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
        ::unlink(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message, temporary + ": cannot reopen: " + std::strerror(errno));
    }
    struct stat old_info {};
    const bool keep_mode = ::stat(target.c_str(), &old_info) == 0;
    const bool moded = !keep_mode || ::fchmod(fd, old_info.st_mode & 07777) == 0;
    const bool synced = ::fsync(fd) == 0;
    const bool closed = ::close(fd) == 0;
    if (!synced || !closed || !moded) {
        ::unlink(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message,
                    temporary + ": " + (moded ? "fsync or close failed (disk full?)" : "cannot keep the mode of " + target));
    }
    if (std::rename(temporary.c_str(), target.c_str()) != 0) {
        const int err = errno;
        ::unlink(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message,
                    target + ": cannot rename the temporary file into place: " + std::strerror(err));
    }
    // Make the rename itself durable; best effort (not every file system allows it).
    const int dir_fd = ::open(folderOf(target).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd >= 0) {
        (void)::fsync(dir_fd);
        ::close(dir_fd);
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus writeFileAtomically(const std::string& path, const void* data, size_t size, std::string* message) {
    std::string target, temporary;
    const CacheFileStatus prepared = prepareOutputFile(path, &target, &temporary, message);
    if (prepared != CacheFileStatus::kOk) return prepared;
    const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) return fail(CacheFileStatus::kIoError, message, temporary + ": cannot create: " + std::strerror(errno));
    const uint8_t* bytes = static_cast<const uint8_t*>(data);
    size_t done = 0;
    while (done < size) {
        const ssize_t n = ::write(fd, bytes + done, size - done);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            const int err = n < 0 ? errno : ENOSPC;
            ::close(fd);
            ::unlink(temporary.c_str());
            return fail(CacheFileStatus::kIoError, message,
                        path + ": write failed after " + std::to_string(done) + " of " + std::to_string(size) +
                            " bytes: " + std::strerror(err) + "; the previous file is untouched");
        }
        done += size_t(n);
    }
    if (::close(fd) != 0) {
        ::unlink(temporary.c_str());
        return fail(CacheFileStatus::kIoError, message, temporary + ": close failed: " + std::strerror(errno));
    }
    return commitOutputFile(temporary, target, message);
}

CacheFileStatus writeCacheFile(const std::string& path, const CacheData& data, std::string* message) {
    std::vector<uint8_t> bytes;
    const CacheFileStatus encoded = encodeCacheFile(data, &bytes, message);
    if (encoded != CacheFileStatus::kOk) {
        if (message) *message = path + ": " + *message;
        return encoded;
    }
    const CacheFileStatus written = writeFileAtomically(path, bytes.data(), bytes.size(), message);
    if (written != CacheFileStatus::kOk) return written;
    // Re-open what landed on disk and validate it (KTX habit); keep the file for the bug report.
    CacheView view;
    CacheError error;
    const CacheFileStatus reread = CacheView::openFile(path, &view, &error);
    if (reread != CacheFileStatus::kOk) {
        return fail(reread == CacheFileStatus::kIoError ? CacheFileStatus::kIoError : CacheFileStatus::kCorrupt,
                    message, "the file written does not validate (kept for inspection): " + error.message);
    }
    if (view.fileSize() != bytes.size() || view.voxelCount() != data.voxels.size()) {
        return fail(CacheFileStatus::kIoError, message, path + ": the file read back differs from what was written");
    }
    return CacheFileStatus::kOk;
}

CacheFileStatus readCacheFile(const std::string& path, CacheData* data, std::string* message) {
    CacheView view;
    CacheError error;
    const CacheFileStatus status = CacheView::openFile(path, &view, &error);
    if (status != CacheFileStatus::kOk) return fail(status, message, error.message);
    if (!data) return CacheFileStatus::kOk;
    CacheData result;
    const HashGridParameters p = view.gridParameters();
    result.logarithm_base = p.logarithm_base;
    result.scene_scale = p.scene_scale;
    result.level_bias = p.level_bias;
    result.bucket_size = p.bucket_size;
    result.bake_capacity = view.bakeCapacity();
    result.gpu_radiance_scale = view.gpuRadianceScale();
    result.grid_anchor = view.gridAnchor();
    if (view.hasVoxelMaterials()) {
        result.voxel_materials.resize(size_t(view.voxelCount()));
        for (uint64_t i = 0; i < view.voxelCount(); ++i) result.voxel_materials[size_t(i)] = view.voxelMaterial(i);
    }
    result.version_major = view.versionMajor();
    result.version_minor = view.versionMinor();
    result.voxels.resize(size_t(view.voxelCount()));
    for (uint64_t i = 0; i < view.voxelCount(); ++i) result.voxels[size_t(i)] = view.voxel(i);
    result.levels = view.levels();
    result.metadata.reserve(view.metadataCount());
    for (size_t i = 0; i < view.metadataCount(); ++i) {
        result.metadata.emplace_back(std::string(view.metadataKey(i)), std::string(view.metadataValue(i)));
    }
    *data = std::move(result);
    return CacheFileStatus::kOk;
}

}  // namespace sharcbake
