// Decompression beside the parse: a thread of its own reads a compressed
// trace's stream a few chunks ahead, so that inflating gzip (about 200 MB/s
// of text) or zstd overlaps the parse and the simulation on other cores. The
// data, its errors and their place in it are exactly the stream's: an error
// is returned where the stream raised it, after every byte before it. Memory
// is bounded by `depth` chunks.
//
//   GzipStream in(fd, chunk);
//   ReadAhead ahead(in, chunk);         // the thread starts; `in` is its own from now on
//   long n = ahead.read(dst, size);     // as in.read(); ahead.error() as in.error()
//
// The stream's RawObserver, if any, is called on the thread; the thread has
// ended (and told it end()) before read() returns 0.
#pragma once
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rbcd/io/gzip_stream.h"

namespace rbcd {

class ReadAhead {
public:
    ReadAhead(GzipStream& in, std::size_t chunk, std::size_t depth = 4);
    ~ReadAhead();   // stops the thread (after its current read) and joins it
    ReadAhead(const ReadAhead&) = delete;
    ReadAhead& operator=(const ReadAhead&) = delete;

    long read(char* dst, std::size_t n);
    const std::string& error() const { return error_; }

private:
    struct Chunk {
        std::vector<char> bytes;
        long got = 0;   // bytes held; 0: the end of the data; -1: the stream's error
    };
    void produce();

    GzipStream& in_;
    std::vector<Chunk> ring_;
    std::size_t head_ = 0, count_ = 0, pos_ = 0;   // pos_: bytes of ring_[head_] already read
    bool stop_ = false;
    std::string error_;
    std::mutex m_;
    std::condition_variable not_empty_, not_full_;
    std::thread thread_;
};

} // namespace rbcd
