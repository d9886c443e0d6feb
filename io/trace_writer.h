// Writes a fragment stream as an .rbt text trace that TraceReader reads back
// to the same stream (used by --write-trace and the benchmark generator).
#pragma once
#include <cstdio>
#include <memory>
#include <string>

#include "rbcd/common/fragment.h"

namespace rbcd {

// How a trace is stored (docs/formats.md): text, one gzip member, or zstd
// frames. TraceReader recognises the compressed forms by their magic bytes.
//   Zstd: the header lines are one frame and every frame record starts a
//   new one (cut again every kZstdFrameBytes of text), each with its
//   decompressed size and a checksum in its header, so that rbcd-sim --jobs
//   finds the frame records and passes over the frames before a worker's
//   without decompressing them.
enum class TraceCompression { None, Gzip, Zstd };
// What a file name asks for: "*.gz" gzip, "*.zst" zstd, anything else text.
TraceCompression trace_compression_for(const std::string& name);

class TraceWriter {
public:
    static constexpr std::size_t kZstdFrameBytes = std::size_t(8) << 20;

    // Throws InputError if the file cannot be created. Messages name
    // `shown_as` when given: the user's path, where `path` is the descriptor
    // of its temporary (OutputFile::open_file_path).
    TraceWriter(const std::string& path, const StreamHeader& header, TraceCompression c = TraceCompression::None,
                const std::string& shown_as = {});
    // The same into descriptor `fd` (duplicated: the caller keeps its own),
    // named `name` in messages. The trace shares the descriptor's offset: on
    // a standard output redirected to a file it is not written from the
    // file's start again, under what else goes there.
    TraceWriter(int fd, const StreamHeader& header, TraceCompression c, const std::string& name);
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
    struct ZstdFrames;
    void start(const StreamHeader& header, TraceCompression c);
    void flush();
    void emit(const char* p, std::size_t n, bool finish);
    void write_raw(const char* p, std::size_t n);

    std::string path_;
    std::FILE* f_ = nullptr;
    std::string buf_;
    std::size_t flush_at_ = 0;         // buf_ is written out (one zstd frame) from this size on
    std::unique_ptr<Deflater> z_;      // set when writing gzip
    std::unique_ptr<ZstdFrames> zs_;   // set when writing zstd
};

} // namespace rbcd
