// SPDX-License-Identifier: Apache-2.0
// Crash-safe file writing shared by the EXR and PNG writers.
#include "image_internal.h"

#include <cerrno>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sharcbake::detail {
namespace {

std::string errnoText(int err) { return std::strerror(err); }

/// Directory part of @p path for fsync after the rename ("." when there is none).
std::string parentDirectory(const std::string& path) {
    const size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return ".";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

}  // namespace

void checkImageShape(const std::string& path, const Image& image, const char* what) {
    if (image.width <= 0 || image.height <= 0) {
        throw ImageError("cannot write " + std::string(what) + " '" + path + "': image is empty (" +
                         std::to_string(image.width) + "x" + std::to_string(image.height) + ")");
    }
    if (image.pixels.size() != size_t(image.width) * size_t(image.height)) {
        throw ImageError("cannot write " + std::string(what) + " '" + path + "': image has " +
                         std::to_string(image.pixels.size()) + " pixels, expected " +
                         std::to_string(size_t(image.width) * size_t(image.height)));
    }
}

void writeFileAtomically(const std::string& path, const void* data, size_t size) {
    const std::string tmp = path + ".tmp-" + std::to_string(long(::getpid()));
    auto fail = [&](const std::string& step, int err, bool remove_tmp) {
        if (remove_tmp) ::unlink(tmp.c_str());
        throw ImageError("cannot write '" + path + "': " + step + ": " + errnoText(err));
    };

    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0) fail("cannot create temporary file '" + tmp + "'", errno, false);

    const char* bytes = static_cast<const char*>(data);
    size_t left = size;
    while (left > 0) {
        const ssize_t n = ::write(fd, bytes, left);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int err = errno;
            ::close(fd);
            fail("write failed", err, true);
        }
        bytes += n;
        left -= size_t(n);
    }
    if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
        // EINVAL/EROFS: the file system does not support syncing (e.g. a pipe-like target);
        // the data are still written.
        const int err = errno;
        ::close(fd);
        fail("fsync failed", err, true);
    }
    if (::close(fd) != 0) fail("close failed", errno, true);
    if (::rename(tmp.c_str(), path.c_str()) != 0) fail("cannot rename temporary file", errno, true);

    // Make the rename itself durable; best effort (not every file system allows it).
    const int dir_fd = ::open(parentDirectory(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd >= 0) {
        (void)::fsync(dir_fd);
        ::close(dir_fd);
    }
}

}  // namespace sharcbake::detail
