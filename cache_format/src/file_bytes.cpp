// SPDX-License-Identifier: Apache-2.0
#include "file_bytes.h"

#include <cerrno>
#include <cstring>
#include <new>

#if defined(__unix__) || defined(__APPLE__)
#define SHARCBAKE_POSIX_FILES 1
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#else
#include <filesystem>
#include <fstream>
#endif

namespace sharcbake {
namespace {

CacheFileStatus ioError(std::string* message, const std::string& text) {
    if (message) *message = text;
    return CacheFileStatus::kIoError;
}

}  // namespace

#ifdef SHARCBAKE_POSIX_FILES

CacheFileStatus loadFileBytes(const std::string& path, bool map, FileBytes* out, std::string* message) {
    *out = FileBytes{};
    // O_NONBLOCK: opening a FIFO does not wait for a writer (it is then refused as not regular).
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return ioError(message, path + ": cannot open: " + std::strerror(errno));
    struct stat st;
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        ::close(fd);
        return ioError(message, path + ": not a regular file (a FIFO, device or folder)");
    }
    const size_t size = size_t(st.st_size);
    try {
        if (map && size > 0) {
            void* p = ::mmap(nullptr, size, PROT_READ, MAP_PRIVATE, fd, 0);
            if (p == MAP_FAILED) {
                ::close(fd);
                return ioError(message, path + ": mmap failed: " + std::strerror(errno));
            }
            out->mapping = p;
            out->mapping_size = size;
            out->data = static_cast<const uint8_t*>(p);
        } else {
            out->owned.resize(size);
            size_t done = 0;
            while (done < size) {
                const ssize_t n = ::read(fd, out->owned.data() + done, size - done);
                if (n < 0 && errno == EINTR) continue;
                if (n <= 0) {
                    ::close(fd);
                    *out = FileBytes{};
                    return ioError(message, path + ": read failed");
                }
                done += size_t(n);
            }
            out->data = size > 0 ? out->owned.data() : nullptr;
        }
    } catch (const std::bad_alloc&) {
        ::close(fd);
        *out = FileBytes{};
        return ioError(message, path + ": out of memory reading the file");
    }
    ::close(fd);
    out->size = size;
    return CacheFileStatus::kOk;
}

void releaseFileMapping(void* mapping, size_t size) {
    if (mapping) ::munmap(mapping, size);
}

#else  // no POSIX: read the whole file; a mapping request reads too

CacheFileStatus loadFileBytes(const std::string& path, bool /*map*/, FileBytes* out, std::string* message) {
    *out = FileBytes{};
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        return ioError(message, path + ": cannot open, or not a regular file (a device or folder)");
    }
    std::ifstream in(path, std::ios::binary);
    if (!in) return ioError(message, path + ": cannot open");
    try {
        in.seekg(0, std::ios::end);
        const std::streamoff end = in.tellg();
        if (end < 0) return ioError(message, path + ": read failed");
        in.seekg(0, std::ios::beg);
        out->owned.resize(size_t(end));
        if (end > 0 && !in.read(reinterpret_cast<char*>(out->owned.data()), end)) {
            *out = FileBytes{};
            return ioError(message, path + ": read failed");
        }
    } catch (const std::bad_alloc&) {
        *out = FileBytes{};
        return ioError(message, path + ": out of memory reading the file");
    }
    out->data = out->owned.empty() ? nullptr : out->owned.data();
    out->size = out->owned.size();
    return CacheFileStatus::kOk;
}

void releaseFileMapping(void*, size_t) {}

#endif

}  // namespace sharcbake
