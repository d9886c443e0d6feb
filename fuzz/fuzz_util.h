// Shared by the fuzz targets: inputs handed to readers that take a path, as an
// in-memory file (memfd: a regular file, as the readers require).
#pragma once
#include <sys/mman.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "rbcd/common/write_all.h"

namespace rbcd::fuzz {

class MemFile {
public:
    MemFile(const void* data, std::size_t size) {
        fd_ = ::memfd_create("rbcd-fuzz", MFD_CLOEXEC);
        if (fd_ < 0) std::abort();
        if (write_all(fd_, data, size) != 0) std::abort();
    }
    ~MemFile() { ::close(fd_); }
    MemFile(const MemFile&) = delete;
    MemFile& operator=(const MemFile&) = delete;
    std::string path() const { return "/proc/self/fd/" + std::to_string(fd_); }

private:
    int fd_ = -1;
};

// A finding: a message in the fuzzer's log and a crash it records.
[[noreturn]] inline void finding(const std::string& what) {
    std::fprintf(stderr, "FINDING: %s\n", what.c_str());
    std::abort();
}


} // namespace rbcd::fuzz
