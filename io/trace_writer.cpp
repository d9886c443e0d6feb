#include "rbcd/io/trace_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <stdexcept>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>

#include <zlib.h>
#include <zstd.h>

#include "rbcd/common/errors.h"

namespace rbcd {
namespace {

constexpr std::size_t kFlushAt = std::size_t(1) << 20;
// Longest fragment line: "f " + 4 numbers of up to 10 digits + separators + " F c\n".
constexpr std::size_t kMaxFragmentLine = 2 + 4 * 11 + 6;
constexpr std::size_t kMaxTileLine = 128;

inline char* put(char* p, std::uint64_t v) { return std::to_chars(p, p + 20, v).ptr; }
inline char* put(char* p, const char* s) {
    while (*s) *p++ = *s++;
    return p;
}

} // namespace

TraceCompression trace_compression_for(const std::string& name) {
    const auto ends = [&](const char* suffix) {
        const std::size_t n = std::strlen(suffix);
        return name.size() >= n && name.compare(name.size() - n, n, suffix) == 0;
    };
    if (ends(".gz")) return TraceCompression::Gzip;
    if (ends(".zst")) return TraceCompression::Zstd;
    return TraceCompression::None;
}

struct TraceWriter::Deflater {
    z_stream z{};
    std::string out = std::string(std::size_t(1) << 18, '\0');
    ~Deflater() { deflateEnd(&z); }
};

struct TraceWriter::ZstdFrames {
    ZSTD_CCtx* cctx = ZSTD_createCCtx();
    std::string out;
    ~ZstdFrames() { ZSTD_freeCCtx(cctx); }
};

TraceWriter::TraceWriter(const std::string& path, const StreamHeader& header, TraceCompression c,
                         const std::string& shown_as)
    : path_(shown_as.empty() ? path : shown_as) {
    f_ = std::fopen(path.c_str(), "wb");
    if (!f_) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
    start(header, c);
}

TraceWriter::TraceWriter(int fd, const StreamHeader& header, TraceCompression c, const std::string& name)
    : path_(name) {
    const int own = fd >= 0 ? ::fcntl(fd, F_DUPFD_CLOEXEC, 3) : -1;
    f_ = own >= 0 ? ::fdopen(own, "wb") : nullptr;
    if (!f_) {
        const int err = errno;
        if (own >= 0) ::close(own);
        throw InputError(path_ + ": cannot create: " + std::strerror(err));
    }
    start(header, c);
}

void TraceWriter::start(const StreamHeader& header, TraceCompression c) {
    flush_at_ = kFlushAt;
    if (c == TraceCompression::Zstd) {
        zs_ = std::make_unique<ZstdFrames>();
        // Level 1: as fast to decompress as any level, twice as fast to
        // write as level 3 and, on game traces, no larger. The checksum
        // catches a corrupt frame that still decodes.
        if (!zs_->cctx || ZSTD_isError(ZSTD_CCtx_setParameter(zs_->cctx, ZSTD_c_compressionLevel, 1)) ||
            ZSTD_isError(ZSTD_CCtx_setParameter(zs_->cctx, ZSTD_c_checksumFlag, 1)))
            throw std::runtime_error(path_ + ": cannot start zstd compression");
        flush_at_ = kZstdFrameBytes;
    }
    if (c == TraceCompression::Gzip) {
        z_ = std::make_unique<Deflater>();
        // windowBits 15 + 16: a gzip wrapper rather than zlib's. Level 1: a
        // trace is text of small numbers, and level 6 costs three times the
        // CPU of the rest of a game capture's conversion for 20% less size.
        if (deflateInit2(&z_->z, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK)
            throw std::runtime_error(path_ + ": cannot start gzip compression");
    }
    buf_.reserve(flush_at_ + kMaxTileLine);
    buf_ += "rbcd-trace 1\nscreen " + std::to_string(header.screen_w) + " " + std::to_string(header.screen_h) +
            "\ntile_size " + std::to_string(header.tile_w) + " " + std::to_string(header.tile_h) + "\ndepth_bits " +
            std::to_string(header.depth_bits) + "\n";
}

void TraceWriter::write_raw(const char* p, std::size_t n) {
    if (n && std::fwrite(p, 1, n, f_) != n) throw RunError(path_ + ": write failed: " + std::strerror(errno));
}

// Writes n bytes, through the compressor when there is one: for zstd, one
// whole frame; `finish` ends the gzip member. Throws RunError on a write error.
void TraceWriter::emit(const char* p, std::size_t n, bool finish) {
    if (zs_) {
        if (!n) return;
        if (zs_->out.size() < ZSTD_compressBound(n)) zs_->out.resize(ZSTD_compressBound(n));
        const std::size_t got = ZSTD_compress2(zs_->cctx, zs_->out.data(), zs_->out.size(), p, n);
        if (ZSTD_isError(got)) throw std::runtime_error(path_ + ": zstd compression failed");
        write_raw(zs_->out.data(), got);
        return;
    }
    if (!z_) {
        write_raw(p, n);
        return;
    }
    z_stream& z = z_->z;
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(p));
    z.avail_in = static_cast<uInt>(n);
    int rc;
    do {
        z.next_out = reinterpret_cast<Bytef*>(&z_->out[0]);
        z.avail_out = static_cast<uInt>(z_->out.size());
        rc = deflate(&z, finish ? Z_FINISH : Z_NO_FLUSH);
        if (rc == Z_STREAM_ERROR) throw std::runtime_error(path_ + ": gzip compression failed");
        const std::size_t have = z_->out.size() - z.avail_out;
        write_raw(z_->out.data(), have);
    } while (z.avail_out == 0 || (finish && rc != Z_STREAM_END));
}

void TraceWriter::flush() {
    emit(buf_.data(), buf_.size(), false);
    buf_.clear();
}

TraceWriter::~TraceWriter() {
    // close() reports errors; a writer dropped without it (an exception on the
    // way) just releases the file.
    if (f_) std::fclose(f_);
}

void TraceWriter::frame(std::uint64_t n) {
    if (!f_) throw std::logic_error(path_ + ": write after close");
    if (zs_) flush();   // a frame record starts a zstd frame
    buf_ += "frame ";
    buf_ += std::to_string(n);
    buf_ += '\n';
}

void TraceWriter::tile(const Tile& t) {
    if (!f_) throw std::logic_error(path_ + ": write after close");
    std::size_t at = buf_.size();
    // Written in slices so the buffer stays near flush_at_ however big the tile.
    buf_.resize(at + kMaxTileLine);
    char* p = &buf_[at];
    p = put(p, "tile ");
    p = put(p, t.col);
    *p++ = ' ';
    p = put(p, t.row);
    if (!t.ordered_other) {
        p = put(p, " other=");
        p = put(p, t.other);
    }
    if (t.has_base) {
        p = put(p, " base=");
        p = put(p, t.base);
    }
    if (t.has_prims) {
        p = put(p, " prims=");
        p = put(p, t.prims);
    }
    if (t.has_cprims) {
        p = put(p, " cprims=");
        p = put(p, t.cprims);
    }
    if (t.has_shade) {
        p = put(p, " shade=");
        p = put(p, std::uint64_t(t.shade));
    }
    *p++ = '\n';
    buf_.resize(static_cast<std::size_t>(p - buf_.data()));

    std::size_t i = 0;
    const std::size_t n = t.frags.size();
    std::size_t run = 0;
    const auto put_runs_before = [&](std::size_t frag) {
        for (; run < t.other_runs.size() && t.other_runs[run].before <= frag; ++run) {
            const std::size_t at2 = buf_.size();
            buf_.resize(at2 + 24);
            char* q = &buf_[at2];
            q = put(q, "o ");
            q = put(q, t.other_runs[run].count);
            *q++ = '\n';
            buf_.resize(static_cast<std::size_t>(q - buf_.data()));
        }
    };
    while (i < n) {
        if (buf_.size() >= flush_at_) flush();
        // A slice ends at the next `o` run so runs land between the right fragments.
        std::size_t slice = std::min<std::size_t>(n - i, 4096);
        put_runs_before(i);
        if (run < t.other_runs.size()) slice = std::min<std::size_t>(slice, t.other_runs[run].before - i);
        at = buf_.size();
        buf_.resize(at + slice * kMaxFragmentLine);
        p = &buf_[at];
        for (std::size_t e = i + slice; i < e; ++i) {
            const Fragment& f = t.frags[i];
            *p++ = 'f';
            *p++ = ' ';
            p = put(p, f.x);
            *p++ = ' ';
            p = put(p, f.y);
            *p++ = ' ';
            p = put(p, f.depth);
            *p++ = ' ';
            p = put(p, f.id);
            *p++ = ' ';
            *p++ = f.facing == Facing::Front ? 'F' : 'B';
            if (f.culled) {
                *p++ = ' ';
                *p++ = 'c';
            }
            *p++ = '\n';
        }
        buf_.resize(static_cast<std::size_t>(p - buf_.data()));
    }
    put_runs_before(n);
    if (buf_.size() >= flush_at_) flush();
}

void TraceWriter::close() {
    if (!f_) return;
    std::FILE* f = f_;
    bool ok = true;
    int err = 0;
    try {
        emit(buf_.data(), buf_.size(), true);
    } catch (const std::runtime_error&) {
        ok = false;
        err = errno;
    }
    f_ = nullptr;
    buf_.clear();
    if (ok && std::fflush(f) != 0) { ok = false; err = errno; }
    if (std::fclose(f) != 0 && ok) { ok = false; err = errno; }
    if (!ok) throw RunError(path_ + ": write failed: " + std::strerror(err));
}

} // namespace rbcd
