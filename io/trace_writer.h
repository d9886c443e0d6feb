// Writes a fragment stream as an .rbt text trace that TraceReader reads back
// to the same stream (used by --write-trace and the benchmark generator).
#pragma once
#include <cstdio>
#include <string>

#include "rbcd/common/fragment.h"

namespace rbcd {

class TraceWriter {
public:
    // Throws InputError if the file cannot be created.
    TraceWriter(const std::string& path, const StreamHeader& header);
    ~TraceWriter();
    TraceWriter(const TraceWriter&) = delete;
    TraceWriter& operator=(const TraceWriter&) = delete;
    void frame(std::uint64_t n);
    void tile(const Tile& t);
    // Flushes and closes; throws InputError on a write error.
    void close();

private:
    std::string path_;
    std::FILE* f_ = nullptr;
    std::string buf_;
};

} // namespace rbcd
