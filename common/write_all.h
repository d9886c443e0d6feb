// Writing a whole buffer to a descriptor: write(2) may take less than it is
// given (a pipe, a signal, a file size limit reached part-way), so every
// writer that goes past stdio loops the same way.
#pragma once
#include <unistd.h>

#include <cerrno>
#include <cstddef>

namespace rbcd {

// Writes the n bytes at p to fd, retrying after EINTR. Returns 0, or the
// errno of the write that failed (ENOSPC for one that wrote nothing).
inline int write_all(int fd, const void* p, std::size_t n) {
    const char* c = static_cast<const char*>(p);
    while (n) {
        const ssize_t k = ::write(fd, c, n);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) return k < 0 ? errno : ENOSPC;
        c += k;
        n -= static_cast<std::size_t>(k);
    }
    return 0;
}

} // namespace rbcd
