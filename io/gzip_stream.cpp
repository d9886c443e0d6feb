#include "rbcd/io/gzip_stream.h"

#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>

namespace rbcd {

Compression compression_of(const unsigned char* m, std::size_t n) {
    if (n >= 2 && m[0] == 0x1f && m[1] == 0x8b) return Compression::Gzip;
    if (n >= 4 && m[0] == 0x28 && m[1] == 0xb5 && m[2] == 0x2f && m[3] == 0xfd) return Compression::Zstd;
    return Compression::None;
}

std::size_t zstd_frame_header_bytes(unsigned char d) {
    // Magic, descriptor, window byte unless single-segment, dictionary id
    // and content size fields by the descriptor's flags.
    static const unsigned kDictBytes[4] = {0, 1, 2, 4};
    static const unsigned kSizeBytes[4] = {0, 2, 4, 8};
    const bool single = d & 0x20;
    const unsigned fcs = (d >> 6) == 0 ? (single ? 1 : 0) : kSizeBytes[d >> 6];
    return 4 + 1 + (single ? 0 : 1) + kDictBytes[d & 3] + fcs;
}

ZstdBlockHeader zstd_block_header(const unsigned char* b) {
    const std::uint32_t h = b[0] | (std::uint32_t(b[1]) << 8) | (std::uint32_t(b[2]) << 16);
    const unsigned type = (h >> 1) & 3;   // raw, RLE (one byte of data), compressed, reserved
    ZstdBlockHeader z;
    z.last = h & 1;
    z.reserved = type == 3;
    z.data_bytes = type == 1 ? 1 : (h >> 3);
    return z;
}

// The magic is read with a small buffer (at least the 4 bytes of zstd's): a
// plain file is then read straight into the caller's buffer, and only a
// compressed one needs a raw buffer of its own.
GzipStream::GzipStream(int fd, std::size_t chunk_bytes)
    : fd_(fd), chunk_(std::max<std::size_t>(chunk_bytes, 2)),
      in_(std::max<std::size_t>(std::min<std::size_t>(chunk_, 4096), 4)) {}

GzipStream::~GzipStream() {
    if (z_init_) inflateEnd(&zs_);
    if (zd_) ZSTD_freeDStream(zd_);
    if (fd_ > 0) ::close(fd_);
}

long GzipStream::fail(const std::string& what) {
    error_ = what;
    return -1;
}

bool GzipStream::refill() {
    if (raw_eof_) return false;
    if (in_pos_ < in_end_ && in_pos_ > 0) {
        std::memmove(in_.data(), in_.data() + in_pos_, in_end_ - in_pos_);
        in_end_ -= in_pos_;
        in_pos_ = 0;
    } else if (in_pos_ == in_end_) {
        in_pos_ = in_end_ = 0;
    }
    if (in_end_ == in_.size()) return true;
    const long n = read_raw(in_.data() + in_end_, in_.size() - in_end_);
    if (n <= 0) return false;
    in_end_ += static_cast<std::size_t>(n);
    return true;
}

long GzipStream::read_raw(void* dst, std::size_t n) {
    for (;;) {
        const ssize_t got = ::read(fd_, dst, n);
        if (got < 0 && errno == EINTR) continue;
        if (got < 0) return fail(std::string("read error: ") + std::strerror(errno));
        if (observer_) {
            if (got == 0) observer_->end();
            else observer_->raw(dst, static_cast<std::size_t>(got));
        }
        if (got == 0) raw_eof_ = true;
        return static_cast<long>(got);
    }
}

long long GzipStream::skip(unsigned long long n) {
    unsigned long long done = 0;
    if (!started_ && !start()) return -1;
    // Reads and drops data while more() holds, up to n in all; false on an error.
    std::vector<char> scratch;
    const auto read_and_drop = [&](auto more) {
        scratch.resize(std::size_t(1) << 16);
        while (done < n && more()) {
            const long got = read(scratch.data(), static_cast<std::size_t>(std::min<unsigned long long>(n - done, scratch.size())));
            if (got < 0) return false;
            if (got == 0) break;
            done += static_cast<unsigned long long>(got);
        }
        return true;
    };
    if (zstd_) {
        // The frame the reader is in (its first chunk read past the header's
        // frame) is decompressed to its end; the whole frames after it are
        // passed over by their headers.
        if (!read_and_drop([&] { return zstd_frame_open_; })) return -1;
        const long long k = skip_zstd_frames(n - done);
        if (k < 0) return -1;
        done += static_cast<unsigned long long>(k);
    }
    if (started_ && !gz_ && !zstd_) {
        const std::size_t k = static_cast<std::size_t>(std::min<unsigned long long>(n, in_end_ - in_pos_));
        in_pos_ += k;
        done += k;
        if (done < n && !raw_eof_ && n - done <= static_cast<unsigned long long>(LLONG_MAX)) {
            // lseek moves past the end of a file without complaint: where the
            // file ends is seen by the next read.
            const off_t here = ::lseek(fd_, 0, SEEK_CUR);
            struct stat st {};
            if (here >= 0 && ::fstat(fd_, &st) == 0 && S_ISREG(st.st_mode)) {
                const unsigned long long left = st.st_size > here ? static_cast<unsigned long long>(st.st_size - here) : 0;
                const unsigned long long k2 = std::min(n - done, left);
                if (const off_t to = ::lseek(fd_, static_cast<off_t>(k2), SEEK_CUR); to >= 0) {
                    if (observer_ && k2) observer_->gap(static_cast<std::uint64_t>(to));
                    done += k2;
                    if (done < n) raw_eof_ = true;
                    return static_cast<long long>(done);
                }
            }
        }
    }
    if (!read_and_drop([] { return true; })) return -1;
    return static_cast<long long>(done);
}

// Reads the magic and sets up the decompressor it asks for; false on an error.
bool GzipStream::start() {
    // The magics need two (gzip) and four (zstd) bytes; a chunk of one byte
    // reads four times.
    while (in_end_ - in_pos_ < 4 && refill()) {}
    if (!error_.empty()) return false;
    started_ = true;
    const Compression c = compression_of(in_.data() + in_pos_, in_end_ - in_pos_);
    gz_ = c == Compression::Gzip;
    zstd_ = c == Compression::Zstd;
    if (gz_) {
        in_.resize(chunk_);
        if (inflateInit2(&zs_, 15 + 16) != Z_OK) {
            fail("cannot start zlib: out of memory");
            return false;
        }
        z_init_ = true;
    } else if (zstd_) {
        in_.resize(std::max(chunk_, ZSTD_DStreamInSize()));
        zd_ = ZSTD_createDStream();
        if (!zd_ || ZSTD_isError(ZSTD_initDStream(zd_))) {
            fail("cannot start zstd: out of memory");
            return false;
        }
        // A frame may ask for a window of up to 2^27 bytes (zstd's default
        // limit): memory stays bounded whatever the file says.
        ZSTD_DCtx_setParameter(zd_, ZSTD_d_windowLogMax, 27);
    }
    return true;
}

long GzipStream::read(char* dst, std::size_t n) {
    if (!error_.empty()) return -1;
    if (n > INT_MAX) n = INT_MAX;
    if (!started_ && !start()) return -1;
    if (gz_) return read_gzip(dst, n);
    if (zstd_) return read_zstd(dst, n);
    if (in_pos_ == in_end_) {
        // Straight into the caller's buffer: the bytes would only be copied
        // out of ours (a trace's every byte, once more).
        return raw_eof_ ? 0 : read_raw(dst, std::min(n, chunk_));
    }
    const std::size_t k = std::min(n, in_end_ - in_pos_);
    std::memcpy(dst, in_.data() + in_pos_, k);
    in_pos_ += k;
    return static_cast<long>(k);
}

// Whole zstd frames that declare their decompressed size, from a frame
// boundary, while they fit in n: their blocks are passed over by their
// headers (RFC 8878, 3.1.1), not decompressed. What they hold is not
// checked: the worker whose frames they are decompresses them. Returns the
// data bytes passed over; -1 when the file ends inside a frame or a block
// header is impossible.
long long GzipStream::skip_zstd_frames(unsigned long long n) {
    unsigned long long done = 0;
    // Makes k raw bytes available at in_pos_; false at the end of the file.
    const auto have = [&](std::size_t k) {
        while (in_end_ - in_pos_ < k && refill()) {}
        return in_end_ - in_pos_ >= k;
    };
    const auto drop = [&](unsigned long long k) {
        while (k) {
            if (in_pos_ == in_end_ && !refill()) return false;
            const std::size_t d = static_cast<std::size_t>(std::min<unsigned long long>(k, in_end_ - in_pos_));
            in_pos_ += d;
            k -= d;
        }
        return true;
    };
    const auto truncated = [&] {
        if (error_.empty()) fail("corrupt or truncated zstd stream: unexpected end of file");
        return -1LL;
    };
    while (!zstd_frame_open_ && done < n) {
        if (!have(4)) break;   // the end of the data, or an error read() reports
        const unsigned char* p = in_.data() + in_pos_;
        if (compression_of(p, 4) != Compression::Zstd) break;   // a skippable frame or garbage: read() decides
        // A header is 6 to 18 bytes; the last frame may be shorter than 18.
        if (!have(18) && in_end_ - in_pos_ < 6) break;
        p = in_.data() + in_pos_;
        const unsigned long long size = ZSTD_getFrameContentSize(p, in_end_ - in_pos_);
        if (size == ZSTD_CONTENTSIZE_UNKNOWN || size == ZSTD_CONTENTSIZE_ERROR || size > n - done) break;
        const unsigned char d = p[4];
        if (!drop(zstd_frame_header_bytes(d))) return truncated();
        for (bool last = false; !last;) {
            if (!have(3)) return truncated();
            const ZstdBlockHeader b = zstd_block_header(in_.data() + in_pos_);
            if (b.reserved) return fail("corrupt or truncated zstd stream: reserved block type");
            last = b.last;
            if (!drop(3 + std::uint64_t(b.data_bytes))) return truncated();
        }
        if (zstd_frame_has_checksum(d) && !drop(4)) return truncated();
        done += size;
    }
    return static_cast<long long>(done);
}

long GzipStream::read_zstd(char* dst, std::size_t n) {
    for (;;) {
        if (in_pos_ == in_end_ && !refill()) {
            if (!error_.empty()) return -1;
            if (zstd_frame_open_) return fail("corrupt or truncated zstd stream: unexpected end of file");
            return 0;   // the end of the file, between frames
        }
        ZSTD_inBuffer in{in_.data() + in_pos_, in_end_ - in_pos_, 0};
        ZSTD_outBuffer out{dst, n, 0};
        // Past a frame's end the next bytes must start another frame: the
        // decoder refuses anything else ("unknown frame descriptor").
        const std::size_t rc = ZSTD_decompressStream(zd_, &out, &in);
        in_pos_ += in.pos;
        if (ZSTD_isError(rc))
            return fail(std::string("corrupt or truncated zstd stream: ") + ZSTD_getErrorName(rc));
        zstd_frame_open_ = rc != 0;
        if (out.pos) return static_cast<long>(out.pos);
        if (in.pos == 0 && in_pos_ < in_end_ && in_end_ < in_.size())
            return fail("corrupt or truncated zstd stream: no progress");
    }
}

long GzipStream::read_gzip(char* dst, std::size_t n) {
    for (;;) {
        if (member_done_) {
            // Another member, or the end of the file; anything else is an error.
            while (in_end_ - in_pos_ < 2 && refill()) {}
            if (!error_.empty()) return -1;
            if (in_pos_ == in_end_) return 0;
            if (in_end_ - in_pos_ < 2 || in_[in_pos_] != 0x1f || in_[in_pos_ + 1] != 0x8b)
                return fail("corrupt gzip file: bytes after the last gzip member that are not another member");
            if (inflateReset(&zs_) != Z_OK) return fail("corrupt or truncated gzip stream: inflateReset failed");
            member_done_ = false;
        }
        if (in_pos_ == in_end_ && !refill()) {
            if (!error_.empty()) return -1;
            return fail("corrupt or truncated gzip stream: unexpected end of file");
        }
        zs_.next_in = in_.data() + in_pos_;
        zs_.avail_in = static_cast<uInt>(std::min<std::size_t>(in_end_ - in_pos_, UINT_MAX));
        zs_.next_out = reinterpret_cast<Bytef*>(dst);
        zs_.avail_out = static_cast<uInt>(n);
        const int rc = inflate(&zs_, Z_NO_FLUSH);
        in_pos_ = static_cast<std::size_t>(zs_.next_in - in_.data());
        const std::size_t produced = n - zs_.avail_out;
        if (rc == Z_STREAM_END) member_done_ = true;
        else if (rc == Z_BUF_ERROR && produced == 0 && in_pos_ < in_end_)
            return fail("corrupt or truncated gzip stream: no progress");
        else if (rc != Z_OK && rc != Z_BUF_ERROR)
            return fail(std::string("corrupt or truncated gzip stream: ") + (zs_.msg ? zs_.msg : "inflate error"));
        if (produced) return static_cast<long>(produced);
    }
}

} // namespace rbcd
