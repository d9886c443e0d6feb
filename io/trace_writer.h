// Writes a fragment stream as an .rbt text trace that TraceReader reads back
// to the same stream (used by --write-trace and the benchmark generator).
#pragma once
#include <cstdio>
#include <memory>
#include <string>

#include "rbcd/common/fragment.h"

namespace rbcd {

class TraceWriter {
public:
    // Throws InputError if the file cannot be created. With `gzip` the file is
    // one gzip member (TraceReader recognises it by its first two bytes).
    // Messages name `shown_as` when given: the user's path, where `path` is
    // the descriptor of its temporary (OutputFile::open_file_path).
    TraceWriter(const std::string& path, const StreamHeader& header, bool gzip = false, const std::string& shown_as = {});
    // The same into descriptor `fd` (duplicated: the caller keeps its own),
    // named `name` in messages. The trace shares the descriptor's offset: on
    // a standard output redirected to a file it is not written from the
    // file's start again, under what else goes there.
    TraceWriter(int fd, const StreamHeader& header, bool gzip, const std::string& name);
    ~TraceWriter();
    TraceWriter(const TraceWriter&) = delete;
    TraceWriter& operator=(const TraceWriter&) = delete;
    void frame(std::uint64_t n);
    void tile(const Tile& t);
    // Flushes and closes. A write error, here or before, throws RunError
    // "NAME: write failed: why".
    void close();

private:
    struct Deflater;
    void start(const StreamHeader& header, bool gzip);
    void flush();
    void emit(const char* p, std::size_t n, bool finish);

    std::string path_;
    std::FILE* f_ = nullptr;
    std::string buf_;
    std::unique_ptr<Deflater> z_;   // set when compressing
};

} // namespace rbcd
