#include "rbcd/io/frame_scan.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <exception>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/io/gzip_stream.h"

#include <zstd.h>

namespace rbcd {

namespace {

// "frame" [ \t]+ digits, ending the token: the number, or false.
bool frame_number(const char* p, const char* end, std::uint64_t& n) {
    if (end - p < 7 || std::memcmp(p, "frame", 5) != 0 || (p[5] != ' ' && p[5] != '\t')) return false;
    p += 5;
    while (p < end && (*p == ' ' || *p == '\t')) ++p;
    if (p == end || *p < '0' || *p > '9') return false;
    std::uint64_t v = 0;
    for (; p < end && *p >= '0' && *p <= '9'; ++p)
        if (__builtin_mul_overflow(v, 10u, &v) || __builtin_add_overflow(v, std::uint64_t(*p - '0'), &v)) return false;
    if (p < end && *p != ' ' && *p != '\t' && *p != '\r' && *p != '\n' && *p != '#') return false;
    n = v;
    return true;
}

// A frame record found: counted, and kept when it falls on the sample
// (every stride-th; at max_marks held, every other kept mark goes and the
// stride doubles), so memory does not grow with the trace.
void keep_mark(FrameScan& out, std::uint64_t& stride, std::size_t max_marks, const FrameMark& m) {
    if (out.frame_lines++ % stride != 0) return;
    if (out.marks.size() == max_marks) {
        std::size_t k = 0;
        for (std::size_t i = 0; i < out.marks.size(); i += 2) out.marks[k++] = out.marks[i];
        out.marks.resize(k);
        stride *= 2;
    }
    if ((out.frame_lines - 1) % stride == 0) out.marks.push_back(m);
}

struct Fd {
    int fd = -1;
    ~Fd() {
        if (fd >= 0) ::close(fd);
    }
};

long read_at(int fd, char* p, std::size_t n, std::uint64_t at) {
    for (;;) {
        const ssize_t got = ::pread(fd, p, n, static_cast<off_t>(at));
        if (got < 0 && errno == EINTR) continue;
        return static_cast<long>(got);
    }
}

// A zstd trace whose frames declare their decompressed sizes (TraceWriter's:
// a frame record starts each): the marks from the frames' headers and the
// first bytes of each, without decompressing the rest. ok = false when a
// frame does not declare its size, or the file ends inside one, and no marks
// when no record starts a frame: the caller then scans the data.
// A record found here starts a frame, not necessarily a line; the worker
// before it checks that it stopped there (TraceReader::expect_stop_at).
FrameScan scan_zstd_headers(int fd, std::uint64_t file_size, std::size_t max_marks) {
    FrameScan out;
    ZSTD_DCtx* dctx = ZSTD_createDCtx();
    if (!dctx) return out;
    struct Free {
        ZSTD_DCtx* d;
        ~Free() { ZSTD_freeDCtx(d); }
    } free_ctx{dctx};
    ZSTD_DCtx_setParameter(dctx, ZSTD_d_windowLogMax, 27);
    std::vector<char> head(18), start(std::size_t(1) << 17);
    std::uint64_t at = 0, data = 0, stride = 1;
    while (at < file_size) {
        const long got = read_at(fd, head.data(), head.size(), at);
        if (got < 8) return out;
        const auto* h = reinterpret_cast<const unsigned char*>(head.data());
        const std::uint32_t magic = h[0] | (std::uint32_t(h[1]) << 8) | (std::uint32_t(h[2]) << 16) | (std::uint32_t(h[3]) << 24);
        if ((magic & 0xfffffff0u) == 0x184d2a50u) {   // a skippable frame: 4-byte size, no data
            at += 8 + (h[4] | (std::uint32_t(h[5]) << 8) | (std::uint32_t(h[6]) << 16) | (std::uint64_t(h[7]) << 24));
            continue;
        }
        const unsigned long long size = ZSTD_getFrameContentSize(head.data(), static_cast<std::size_t>(got));
        if (size == ZSTD_CONTENTSIZE_UNKNOWN || size == ZSTD_CONTENTSIZE_ERROR) return out;
        std::uint64_t end = at + zstd_frame_header_bytes(h[4]);
        for (bool last = false; !last;) {
            unsigned char b[3];
            if (read_at(fd, reinterpret_cast<char*>(b), 3, end) != 3) return out;
            const ZstdBlockHeader bh = zstd_block_header(b);
            if (bh.reserved) return out;
            last = bh.last;
            end += 3 + std::uint64_t(bh.data_bytes);
        }
        if (zstd_frame_has_checksum(h[4])) end += 4;
        if (end > file_size) return out;
        // The frame's first bytes: is it a frame record?
        const std::size_t want = static_cast<std::size_t>(std::min<std::uint64_t>(end - at, start.size()));
        if (read_at(fd, start.data(), want, at) != static_cast<long>(want)) return out;
        char text[32];
        ZSTD_DCtx_reset(dctx, ZSTD_reset_session_only);
        ZSTD_inBuffer in{start.data(), want, 0};
        ZSTD_outBuffer o{text, sizeof text, 0};
        while (o.pos < o.size && in.pos < in.size) {
            const std::size_t rc = ZSTD_decompressStream(dctx, &o, &in);
            if (ZSTD_isError(rc) || rc == 0) break;
        }
        const char* eol = static_cast<const char*>(std::memchr(text, '\n', o.pos));
        std::uint64_t f = 0;
        if (eol && frame_number(text, eol, f)) keep_mark(out, stride, max_marks, {f, data, 0});
        data += size;
        at = end;
    }
    out.bytes = data;
    out.ok = true;
    return out;
}

} // namespace

FrameScan scan_frames(const std::string& path, std::size_t max_marks, std::size_t chunk) {
    FrameScan out;
    max_marks = std::max<std::size_t>(max_marks, 2);
    {
        Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
        struct stat st {};
        unsigned char magic[4] = {0, 0, 0, 0};
        if (f.fd >= 0 && ::fstat(f.fd, &st) == 0 && S_ISREG(st.st_mode) &&
            read_at(f.fd, reinterpret_cast<char*>(magic), 4, 0) == 4 && compression_of(magic, 4) == Compression::Zstd) {
            FrameScan z = scan_zstd_headers(f.fd, static_cast<std::uint64_t>(st.st_size), max_marks);
            // No frame record starts a frame (one frame, as the zstd tool
            // writes a file): the data is scanned.
            if (z.ok && !z.marks.empty()) return z;
        }
    }
    try {
        const std::size_t step = std::max<std::size_t>(chunk, 16);
        GzipStream in(open_input(path, "trace", true), step);
        // buf[0] is always the '\n' before the unscanned lines (a virtual one
        // before the first), so every line start is found as "\nframe". A
        // line longer than a chunk (1 MiB: input.max_line_bytes' default) is
        // not a trace to split.
        std::vector<char> buf(2 * step + 1);
        buf[0] = '\n';
        std::size_t have = 1;
        std::int64_t base = -1;      // data offset of buf[0]
        std::uint64_t line = 0;      // number of the line buf[0] ends
        std::uint64_t stride = 1;    // every stride-th frame line is kept
        bool eof = false;
        while (!eof) {
            if (buf.size() - have < step) return out;   // a line longer than a chunk: not a trace to split
            const long n = in.read(buf.data() + have, step);
            if (n < 0) return out;
            eof = n == 0;
            std::size_t end = have + static_cast<std::size_t>(n);
            if (eof && buf[end - 1] != '\n') buf[end++] = '\n';   // the last line without its LF
            // Scan up to the last LF: the lines after it are not whole yet.
            const char* b = buf.data();
            const char* last = static_cast<const char*>(memrchr(b, '\n', end));
            const std::size_t upto = static_cast<std::size_t>(last - b);
            std::size_t counted = 0;
            for (const char* p = b; p < b + upto;) {
                const char* hit = static_cast<const char*>(memmem(p, static_cast<std::size_t>(b + upto - p), "\nframe", 6));
                if (!hit) break;
                line += static_cast<std::uint64_t>(std::count(b + counted, hit + 1, '\n'));
                counted = static_cast<std::size_t>(hit + 1 - b);
                const char* eol = static_cast<const char*>(std::memchr(hit + 1, '\n', static_cast<std::size_t>(b + end - hit - 1)));
                std::uint64_t f = 0;
                if (frame_number(hit + 1, eol, f))
                    keep_mark(out, stride, max_marks, {f, static_cast<std::uint64_t>(base + (hit + 1 - b)), line});
                p = hit + 1;
            }
            line += static_cast<std::uint64_t>(std::count(b + counted, b + upto, '\n'));
            std::memmove(buf.data(), b + upto, end - upto);
            base += static_cast<std::int64_t>(upto);
            have = end - upto;
        }
        out.bytes = static_cast<std::uint64_t>(base + 1);
        out.ok = true;
    } catch (const std::exception&) {
        out.ok = false;
    }
    return out;
}


std::uint64_t plain_trace_bytes(const std::string& path) {
    Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
    struct stat st {};
    if (f.fd < 0 || ::fstat(f.fd, &st) != 0 || !S_ISREG(st.st_mode)) return 0;
    // A compressed trace has no byte offsets to jump to.
    unsigned char magic[4] = {0, 0, 0, 0};
    const long got = read_at(f.fd, reinterpret_cast<char*>(magic), 4, 0);
    if (compression_of(magic, got > 0 ? static_cast<std::size_t>(got) : 0) != Compression::None) return 0;
    return static_cast<std::uint64_t>(st.st_size);
}

FrameScan find_frames_near(const std::string& path, const std::vector<std::uint64_t>& targets) {
    FrameScan out;
    out.bytes = plain_trace_bytes(path);
    if (out.bytes == 0) return out;
    Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
    if (f.fd < 0) return out;
    constexpr std::size_t kWindow = std::size_t(1) << 16;
    std::vector<char> buf(kWindow + 1);
    for (const std::uint64_t target : targets) {
        // From the byte before the target, so that a record starting at it is seen after its LF.
        std::uint64_t at = target > 0 ? target - 1 : 0;
        bool found = false;
        while (!found && at < out.bytes) {
            const long got = read_at(f.fd, buf.data() + (target == 0 && at == 0 ? 1 : 0), kWindow, at);
            if (got <= 0) break;
            const bool lead = target == 0 && at == 0;   // a virtual LF before the file's first byte
            if (lead) buf[0] = '\n';
            const char* b = buf.data();
            const std::size_t n = static_cast<std::size_t>(got) + (lead ? 1 : 0);
            const std::int64_t base = static_cast<std::int64_t>(at) - (lead ? 1 : 0);
            const char* p = b;
            std::size_t next = 0;   // where the next window starts, relative to b
            for (;;) {
                const char* hit = static_cast<const char*>(memmem(p, static_cast<std::size_t>(b + n - p), "\nframe", 6));
                if (!hit) {
                    next = n > 6 ? n - 6 : n;   // a record cut by the window's end is seen again
                    break;
                }
                const char* eol = static_cast<const char*>(std::memchr(hit + 1, '\n', static_cast<std::size_t>(b + n - hit - 1)));
                if (!eol && base + static_cast<std::int64_t>(n) < static_cast<std::int64_t>(out.bytes)) {
                    next = static_cast<std::size_t>(hit - b);
                    break;
                }
                std::uint64_t num = 0;
                if (frame_number(hit + 1, eol ? eol : b + n, num)) {
                    out.marks.push_back({num, static_cast<std::uint64_t>(base + (hit + 1 - b)), 0});
                    found = true;
                    break;
                }
                p = hit + 1;
            }
            if (next == 0) break;   // no progress: a line longer than the window
            at = static_cast<std::uint64_t>(base + static_cast<std::int64_t>(next));
        }
    }
    // Targets that led to one record give it once; marks stay in file order.
    out.marks.erase(std::unique(out.marks.begin(), out.marks.end(),
                                [](const FrameMark& a, const FrameMark& b) { return a.offset == b.offset; }),
                    out.marks.end());
    out.frame_lines = out.marks.size();
    out.ok = true;
    return out;
}

std::uint64_t count_lines_before(const std::string& path, std::uint64_t offset) {
    // Through the stream, which decompresses a compressed trace: offsets are
    // in its data.
    GzipStream in(open_input(path, "trace"), std::size_t(1) << 20);
    std::vector<char> buf(std::size_t(1) << 20);
    std::uint64_t lines = 1, at = 0;
    while (at < offset) {
        const long got = in.read(buf.data(), static_cast<std::size_t>(std::min<std::uint64_t>(buf.size(), offset - at)));
        if (got < 0) throw InputError(cannot_read_message(path, "trace", in.error()));
        if (got == 0) break;
        lines += static_cast<std::uint64_t>(std::count(buf.data(), buf.data() + got, '\n'));
        at += static_cast<std::uint64_t>(got);
    }
    return lines;
}

} // namespace rbcd
