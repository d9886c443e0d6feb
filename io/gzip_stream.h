// The bytes of a trace: a file descriptor read as it is, inflated when it
// starts with the gzip magic (1f 8b), or decompressed when it starts with the
// zstd magic (28 b5 2f fd), whatever the file's name. Unlike zlib's gzread, it
// reads every member (gzip) or frame (zstd) of a file that holds several and
// calls anything after the last one that is not another an error, instead of
// silently ignoring it (formats.md: the file is compressed or it is text).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <zlib.h>

struct ZSTD_DCtx_s;   // zstd.h's decompression context: only gzip_stream.cpp includes zstd.h

namespace rbcd {

// Sees the file's bytes as they are read (before any inflating), in order from
// the file's start: what hashes an input without reading it a second time
// (rbcd-sim's provenance). file() comes first, with the descriptor read; end()
// when a read finds the end of the file. A stream that skips ahead tells it
// gap(), with the file offset its reads go on from: the bytes it saw no
// longer run unbroken from the start.
class RawObserver {
public:
    virtual ~RawObserver() = default;
    virtual void file(int fd) = 0;
    virtual void raw(const void* bytes, std::size_t n) = 0;
    virtual void end() = 0;
    virtual void gap(std::uint64_t resume_at) = 0;
};

// How a trace's first bytes say it is stored: gzip (1f 8b), zstd (28 b5 2f
// fd) or plain text; n is how many of them the file has (up to 4 are read).
enum class Compression { None, Gzip, Zstd };
Compression compression_of(const unsigned char* magic, std::size_t n);

// The zstd format's layout (RFC 8878, 3.1.1), to pass over frames without
// decompressing them: a frame header's length from its descriptor (the byte
// after the magic), whether a checksum (4 bytes) ends the frame, and a block
// header's (3 bytes) last flag and the bytes of data that follow it
// (reserved: a block type the format does not define, a corrupt file).
std::size_t zstd_frame_header_bytes(unsigned char descriptor);
inline bool zstd_frame_has_checksum(unsigned char descriptor) { return descriptor & 0x04; }
struct ZstdBlockHeader {
    bool last = false, reserved = false;
    std::uint32_t data_bytes = 0;
};
ZstdBlockHeader zstd_block_header(const unsigned char* h);

class GzipStream {
public:
    // Takes ownership of fd (closed by the destructor unless it is 0).
    // chunk_bytes: size of each read(2) of the raw file.
    GzipStream(int fd, std::size_t chunk_bytes);
    ~GzipStream();
    GzipStream(const GzipStream&) = delete;
    GzipStream& operator=(const GzipStream&) = delete;

    // Up to n bytes into dst; 0 at the end of the data; -1 on an error, which
    // error() then describes ("corrupt or truncated gzip stream: ...",
    // "corrupt or truncated zstd stream: ...", "read error: ...").
    long read(char* dst, std::size_t n);
    // Drops the next n bytes of the data: inflated and thrown away from a gzip
    // file, passed over with lseek(2) in a plain one, and in a zstd one whole
    // frames that declare their size passed over by their block headers, the
    // rest decompressed (so that a worker of rbcd-sim --jobs starts at its
    // frames without decompressing those before).
    // Returns the bytes dropped, fewer at the end of the data; -1 on an error.
    long long skip(unsigned long long n);
    const std::string& error() const { return error_; }
    bool compressed() const { return gz_ || zstd_; }
    // Every byte read from the file from now on is shown to `o` (null: none).
    void observe(RawObserver* o) {
        observer_ = o;
        if (o) o->file(fd_);
    }

private:
    bool start();    // reads the magic, sets up the decompressor; false on an error
    bool refill();   // more raw input; false at end of file or on error
    // One read(2) of the file; -1 with error() set on a failure, 0 at its end.
    long read_raw(void* dst, std::size_t n);
    long fail(const std::string& what);
    long read_gzip(char* dst, std::size_t n);
    long read_zstd(char* dst, std::size_t n);
    long long skip_zstd_frames(unsigned long long n);

    int fd_;
    std::size_t chunk_;               // the raw reads' size, once the stream is known to be gzip
    std::vector<unsigned char> in_;   // raw input: the first bytes, then (gzip) what inflate has not taken
    std::size_t in_pos_ = 0, in_end_ = 0;
    bool raw_eof_ = false;
    bool started_ = false, gz_ = false, zstd_ = false;
    bool member_done_ = false;    // between members: the next bytes must start another or end the file
    bool z_init_ = false;
    z_stream zs_{};
    ZSTD_DCtx_s* zd_ = nullptr;
    bool zstd_frame_open_ = false;   // inside a zstd frame: the file may not end here
    std::string error_;
    RawObserver* observer_ = nullptr;
};

} // namespace rbcd
