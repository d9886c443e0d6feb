// .rbt reader. The hot path is the fragment line: it is parsed in one pass over
// the chunk buffer (no per-line allocation, no iostreams, no per-line memchr);
// anything unusual on a line falls back to a general tokenizer that either
// accepts the line or says precisely what is wrong with it.
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/frame_scan.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <emmintrin.h>   // SSE2, part of x86-64 itself
#include <immintrin.h>   // AVX-512, used only where the CPU has it (whole_lines_avx512)
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string_view>
#include <unordered_set>
#include <sstream>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/io/gzip_stream.h"
#include "rbcd/io/read_ahead.h"

namespace rbcd {

namespace {
constexpr std::uint64_t kTileWorkLimit = std::uint64_t(1) << 40;
}

namespace {

// Above this many tiles in the screen grid a bitmap per frame would be too big
// (1x1-pixel tiles on a 65535x65535 screen): fall back to a hash set.
constexpr std::uint64_t kMaxBitmapTiles = std::uint64_t(1) << 27;

struct CharTable {
    bool tok_end[256] = {};
    constexpr CharTable() {
        tok_end[unsigned(' ')] = tok_end[unsigned('\t')] = true;
        tok_end[unsigned('\n')] = tok_end[unsigned('\r')] = tok_end[unsigned('#')] = true;
    }
};
constexpr CharTable kChars{};

// A byte buffer left uninitialized: a vector would zero a megabyte, touching
// every page of it, before the first read fills what it needs (a short trace,
// and every process of a sweep or of --jobs, paid for all of it).
class RawBuffer {
public:
    char* data() { return p_.get(); }
    std::size_t size() const { return n_; }
    // Keeps the contents.
    void resize(std::size_t n) {
        std::unique_ptr<char[]> q(new char[n]);
        if (n_) std::memcpy(q.get(), p_.get(), std::min(n, n_));
        p_ = std::move(q);
        n_ = n;
    }

private:
    std::unique_ptr<char[]> p_;
    std::size_t n_ = 0;
};

inline bool tok_end(char c) { return kChars.tok_end[static_cast<unsigned char>(c)]; }
inline void skip_ws(const char*& p) {
    // Fields are almost always one space apart: one test, not a loop's two.
    if (p[0] == ' ' && static_cast<unsigned char>(p[1]) > ' ') {
        ++p;
        return;
    }
    while (*p == ' ' || *p == '\t') ++p;
}

// A token quoted for a message: printable, and short enough for one line.
std::string show(std::string_view s) {
    std::string out = "'";
    std::size_t n = 0;
    for (char c : s) {
        if (++n > 40) { out += "..."; break; }
        unsigned char u = static_cast<unsigned char>(c);
        if (u >= 0x20 && u < 0x7f) {
            out += c;
        } else {
            static const char hex[] = "0123456789abcdef";
            out += "\\x";
            out += hex[u >> 4];
            out += hex[u & 15];
        }
    }
    return out + "'";
}

std::string num_str(std::uint64_t v) { return std::to_string(v); }

enum class NumResult { Ok, NotNumber, TooBig };

NumResult parse_u64(std::string_view s, std::uint64_t& v) {
    if (s.empty()) return NumResult::NotNumber;
    std::uint64_t acc = 0;
    for (char c : s) {
        unsigned d = static_cast<unsigned char>(c) - unsigned('0');
        if (d > 9) return NumResult::NotNumber;
        if (__builtin_mul_overflow(acc, 10u, &acc) || __builtin_add_overflow(acc, d, &acc)) {
            // Keep scanning: "99999999999999999999x" is not a number at all.
            for (char r : s)
                if (static_cast<unsigned char>(r) - unsigned('0') > 9) return NumResult::NotNumber;
            return NumResult::TooBig;
        }
    }
    v = acc;
    return NumResult::Ok;
}

// The fields of one record; more than kMax fields is always an error, so the
// rest need not be kept.
struct Fields {
    static constexpr int kMax = 8;
    std::string_view f[kMax];
    int n = 0;
    const char* next = nullptr;   // start of the following line
};

const char* const kFragmentShape = "expected 'f x y depth id F|B [c]'";
const char* const kTileShape = "expected 'tile C R [other=N] [base=N] [prims=N] [cprims=N] [shade=N]'";

} // namespace

struct TraceReader::Impl {
    std::string path;
    TraceLimits lim;
    StreamHeader hdr;
    std::unique_ptr<GzipStream> in;
    std::unique_ptr<ReadAhead> ahead;   // set from the first next() of a compressed trace with lim.read_ahead
    std::uint64_t work = 0;   // declared work so far, cycles (see TraceLimits)

    // Buffer invariants: [cur, data_end) is unread data; [cur, lines_end) holds
    // only whole lines, lines_end being just past a '\n'. One byte is kept spare
    // so a last line without '\n' can be given one.
    RawBuffer buf;
    char* cur = nullptr;
    char* lines_end = nullptr;
    char* data_end = nullptr;
    bool eof = false;
    unsigned long long line = 1;   // number of the line at cur
    // start_at_frame() without a line number: `line` counts from 1 at byte
    // line_from of the file, and a message counts the lines before that byte
    // then (a pass over the data no successful run needs).
    bool line_relative = false;
    std::uint64_t line_from = 0;
    unsigned long long line_in_file(unsigned long long l) const {
        return line_relative ? count_lines_before(path, line_from) - 1 + l : l;
    }
    std::uint64_t pulled = 0;      // bytes of data read from the stream (data_end's position)

    std::uint64_t depth_max = 0, id_max = 0;
    std::uint64_t cols = 0, rows = 0;

    bool seen_frame = false;
    std::uint64_t next_frame = 0;
    std::uint64_t frame = 0;
    bool ended = false;
    std::uint64_t stop_after = UINT64_MAX;   // the last frame read (stop_after_frame)
    std::uint64_t stop_at = UINT64_MAX;      // ... whose next record starts here (expect_stop_at)

    // Current tile's pixel window, clipped to the screen.
    std::uint64_t x0 = 0, xw = 0, y0 = 0, yh = 0;
    std::uint64_t tcol = 0, trow = 0;

    bool use_set = false;
    std::vector<std::uint64_t> tile_bits;
    std::vector<std::uint64_t> tiles_in_frame;
    std::unordered_set<std::uint64_t> tile_set;

    [[noreturn]] void fail(const std::string& what) const { throw input_error_at(path, line_in_file(line), what); }
    // A --jobs worker's data did not end at the next worker's start (expect_stop_at).
    std::string split_elsewhere() const {
        return "frame " + num_str(stop_after + 1) + "'s record is not at byte " + num_str(stop_at) +
               " of the data, where a zstd frame of the file starts with it: the file's zstd frames do not start at "
               "its frame records, so --jobs cannot split it there; run it without --jobs";
    }

    void open();
    bool fill();
    void tokenize(const char* p, Fields& fl) const;
    void advance(const char* next) { cur = const_cast<char*>(next); ++line; }
    std::uint64_t num(std::string_view tok, const std::string& what) const;
    void read_headers();
    void header_record(const Fields& fl, unsigned long long first_line[3]);
    bool fast_fragment(std::vector<Fragment>& out);
    std::size_t whole_lines(std::vector<Fragment>& out, std::size_t room);
    std::size_t whole_lines_avx512(std::vector<Fragment>& out, std::size_t room);
    // The whole-line parse to use: set once, from the CPU and TraceLimits::wide_parse.
    bool avx512 = false;
    std::uint64_t taken_whole = 0;   // lines_taken_whole()
    // The fragment of a whole line, its facing ('F' or 'B') and tag set.
    static Fragment& whole_line_fragment(std::vector<Fragment>& out, char facing, bool culled) {
        Fragment& fr = out.emplace_back();
        fr.facing = facing == 'B' ? Facing::Back : Facing::Front;
        fr.culled = culled;
        return fr;
    }
    // A whole-line run ends at p after n lines: the reader's state follows.
    std::size_t end_whole_lines(const char* p, std::size_t n) {
        cur = const_cast<char*>(p);
        line += n;
        taken_whole += n;
        return n;
    }
    void slow_fragment(const Fields& fl, std::vector<Fragment>& out, bool in_tile);
    void start_tile(const Fields& fl, Tile& t);
    void other_run(const Fields& fl, Tile& t, bool in_tile);
    bool other_given = false;   // the current tile has other=
    std::uint64_t start_frame(const Fields& fl);
    bool mark_tile(std::uint64_t idx);
    Event end_tile(const Tile& t);
};

// The declared work of the tile just read joins the run's; refused past the
// bound, before the simulation could reach a time 64-bit picoseconds cannot hold.
FragmentSource::Event TraceReader::Impl::end_tile(const Tile& t) {
    if (lim.max_work_cycles == 0) return Event::Tile;
    std::uint64_t w = 0, setup = 0;
    const std::uint64_t per_fragment = fragment_cycles(lim.cycles_per_fragment, t);
    const bool over = __builtin_mul_overflow(std::uint64_t(t.frags.size()) + t.other, per_fragment, &w) ||
                      __builtin_mul_overflow(t.prims + t.cprims, lim.cycles_per_primitive, &setup) ||
                      __builtin_add_overflow(w, setup, &w) || __builtin_add_overflow(w, lim.tile_overhead, &w) ||
                      __builtin_add_overflow(w, t.base, &w) || __builtin_add_overflow(work, w, &work) ||
                      work > lim.max_work_cycles;
    if (over) {
        std::ostringstream mhz;
        mhz << lim.clock_mhz;
        // The tile's last line is the one before cur.
        throw input_error_at(path, line_in_file(line > 1 ? line - 1 : line),
                             "the run is too long to simulate: the work declared up to tile " + num_str(tcol) + " " +
                                 num_str(trow) + " of frame " + num_str(frame) +
                                 " ((fragments + other=) x gpu.cycles_per_fragment (x shade= / 100) + (prims= + cprims=) x gpu.setup_cycles_per_primitive + base=) exceeds " +
                                 num_str(lim.max_work_cycles) + " cycles, the limit for clock.mhz = " + mhz.str() +
                                 " (2^60 ps of simulated time; docs/limits.md)");
    }
    return Event::Tile;
}

void TraceReader::Impl::open() {
    // The stream looks at the first two bytes (1f 8b) and reads anything else
    // as plain text, so the file name plays no part.
    in = std::make_unique<GzipStream>(open_input(path, "trace", true), lim.read_chunk);
    buf.resize(std::max<std::size_t>(lim.read_chunk, 16) + 1);
    cur = lines_end = data_end = buf.data();
}

// Makes at least one whole line available at cur; false at the end of input.
bool TraceReader::Impl::fill() {
    for (;;) {
        if (eof) {
            if (cur == data_end) return false;
            *data_end++ = '\n';
            lines_end = data_end;
            return true;
        }
        std::size_t rem = static_cast<std::size_t>(data_end - cur);
        // [cur, data_end) holds no newline: it is the start of one line.
        if (rem > lim.max_line_bytes)
            fail("line longer than " + num_str(lim.max_line_bytes) +
                 " bytes (the limit input.max_line_bytes; docs/limits.md)");
        if (rem && cur != buf.data()) std::memmove(buf.data(), cur, rem);
        // A line longer than half the buffer: grow, so memory follows the
        // longest line, never the trace length.
        if (buf.size() - 1 - rem < buf.size() / 2) buf.resize(buf.size() * 2);
        cur = buf.data();
        data_end = cur + rem;
        lines_end = cur;
        // Reads of at most max_line_bytes + 1 bytes: a line inside one read is
        // within the limit; one that spans reads is measured below.
        const std::size_t room = std::min({buf.size() - 1 - rem, lim.read_chunk,
                                           static_cast<std::size_t>(std::min<std::uint64_t>(lim.max_line_bytes + 1, SIZE_MAX))});
        const long n = ahead ? ahead->read(data_end, room) : in->read(data_end, room);
        if (n < 0) fail(ahead ? ahead->error() : in->error());
        if (n == 0) {
            eof = true;
            continue;
        }
        if (rem) {
            const void* nl = std::memchr(data_end, '\n', static_cast<std::size_t>(n));
            const std::size_t len = rem + (nl ? static_cast<std::size_t>(static_cast<const char*>(nl) - data_end)
                                              : static_cast<std::size_t>(n));
            if (len > lim.max_line_bytes)
                fail("line longer than " + num_str(lim.max_line_bytes) +
                     " bytes (the limit input.max_line_bytes; docs/limits.md)");
        }
        char* fresh = data_end;
        data_end += n;
        pulled += static_cast<std::uint64_t>(n);
        if (const void* nl = memrchr(fresh, '\n', static_cast<std::size_t>(n))) {
            lines_end = static_cast<char*>(const_cast<void*>(nl)) + 1;
            return true;
        }
    }
}

void TraceReader::Impl::tokenize(const char* p, Fields& fl) const {
    fl.n = 0;
    for (;;) {
        skip_ws(p);
        char c = *p;
        if (c == '\n') { fl.next = p + 1; return; }
        if (c == '#') {
            p = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(lines_end - p)));
            fl.next = p + 1;
            return;
        }
        if (c == '\r') {
            if (p[1] == '\n') { fl.next = p + 2; return; }
            fail("stray carriage return (CR is allowed only right before the end of a line)");
        }
        const char* s = p;
        while (!tok_end(*p)) ++p;
        if (fl.n < Fields::kMax) fl.f[fl.n++] = std::string_view(s, static_cast<std::size_t>(p - s));
    }
}

std::uint64_t TraceReader::Impl::num(std::string_view tok, const std::string& what) const {
    std::uint64_t v = 0;
    switch (parse_u64(tok, v)) {
    case NumResult::Ok: return v;
    case NumResult::NotNumber: fail(what + " " + show(tok) + " is not an unsigned decimal number");
    case NumResult::TooBig: fail(what + " " + show(tok) + " does not fit in 64 bits");
    }
    return v;
}

// Header records before the first frame; stops, without consuming it, at the
// first record that is not a header.
void TraceReader::Impl::read_headers() {
    unsigned long long magic_line = 0;
    Fields fl;
    for (;;) {
        if (cur == lines_end && !fill()) {
            // Point at the last line there is (line 1 of an empty file).
            if (line > 1) --line;
            fail("end of file before the magic record 'rbcd-trace 1': not an .rbt trace");
        }
        tokenize(cur, fl);
        if (fl.n) break;
        advance(fl.next);
    }
    magic_line = line;
    if (fl.f[0] != "rbcd-trace")
        fail("not an .rbt trace: the first record must be 'rbcd-trace 1', found " + show(fl.f[0]));
    if (fl.n < 2) fail("magic record lacks the format version (expected 'rbcd-trace 1')");
    if (fl.n > 2) fail("magic record has an extra field " + show(fl.f[2]) + " (expected 'rbcd-trace 1')");
    std::uint64_t version = num(fl.f[1], "format version");
    if (version != 1) fail("unsupported trace format version " + num_str(version) + " (this reader reads version 1)");
    advance(fl.next);

    unsigned long long first_line[3] = {0, 0, 0};
    for (;;) {
        if (cur == lines_end && !fill()) break;
        tokenize(cur, fl);
        if (fl.n == 0) { advance(fl.next); continue; }
        if (fl.f[0] != "screen" && fl.f[0] != "tile_size" && fl.f[0] != "depth_bits") break;
        header_record(fl, first_line);
        advance(fl.next);
    }

    if (!first_line[1] && (hdr.tile_w != lim.tile_w || hdr.tile_h != lim.tile_h)) {
        throw input_error_at(path, magic_line,
                             "trace has no tile_size header, so its tiles are " + num_str(hdr.tile_w) + " x " +
                                 num_str(hdr.tile_h) + ", but the unit's tile.width x tile.height is " +
                                 num_str(lim.tile_w) + " x " + num_str(lim.tile_h));
    }
    depth_max = (std::uint64_t(1) << hdr.depth_bits) - 1;
    id_max = lim.id_bits >= 32 ? 0xffffffffull : (std::uint64_t(1) << lim.id_bits) - 1;
    cols = (std::uint64_t(hdr.screen_w) + hdr.tile_w - 1) / hdr.tile_w;
    rows = (std::uint64_t(hdr.screen_h) + hdr.tile_h - 1) / hdr.tile_h;
    use_set = cols * rows > kMaxBitmapTiles;
    if (!use_set) tile_bits.assign((cols * rows + 63) / 64, 0);
}

void TraceReader::Impl::header_record(const Fields& fl, unsigned long long first_line[3]) {
    const std::string_view key = fl.f[0];
    const int which = key == "screen" ? 0 : key == "tile_size" ? 1 : 2;
    const std::string name(key);
    if (first_line[which])
        fail("header '" + name + "' repeated (first at line " + std::to_string(first_line[which]) + ")");
    first_line[which] = line;
    const int want = which == 2 ? 2 : 3;
    const std::string shape = which == 0 ? "expected 'screen W H'" : which == 1 ? "expected 'tile_size W H'"
                                                                               : "expected 'depth_bits D'";
    if (fl.n < want) fail("header '" + name + "' has too few fields (" + shape + ")");
    if (fl.n > want) fail("header '" + name + "' has an extra field " + show(fl.f[want]) + " (" + shape + ")");
    if (which == 0) {
        std::uint64_t w = num(fl.f[1], "screen width");
        std::uint64_t h = num(fl.f[2], "screen height");
        if (w < 1 || w > 65535) fail("screen width " + num_str(w) + " out of range 1..65535");
        if (h < 1 || h > 65535) fail("screen height " + num_str(h) + " out of range 1..65535");
        hdr.screen_w = static_cast<std::uint32_t>(w);
        hdr.screen_h = static_cast<std::uint32_t>(h);
    } else if (which == 1) {
        std::uint64_t w = num(fl.f[1], "tile_size width");
        std::uint64_t h = num(fl.f[2], "tile_size height");
        if (w != lim.tile_w || h != lim.tile_h)
            fail("tile_size " + num_str(w) + " " + num_str(h) + " does not match the unit's tile.width x tile.height " +
                 num_str(lim.tile_w) + " x " + num_str(lim.tile_h));
        hdr.tile_w = static_cast<std::uint32_t>(w);
        hdr.tile_h = static_cast<std::uint32_t>(h);
    } else {
        std::uint64_t d = num(fl.f[1], "depth_bits");
        if (d < 1 || d > 32) fail("depth_bits " + num_str(d) + " out of range 1..32");
        hdr.depth_bits = static_cast<unsigned>(d);
    }
}

namespace {
// One number of a fragment line on the fast path: false means "let the slow
// path look at this line" (not a number, too long to be safe from overflow,
// glued to another character, missing).
// One to eight digits at w's low end (the first at the lowest byte), `len` of
// them, as a number: the word shifted so the bytes after the field are gone
// (as if padded with leading zeros), then three multiplies combine the digits
// in pairs, fours and eights.
inline std::uint64_t swar_digits(std::uint64_t w, unsigned len) {
    std::uint64_t x = w << (8 * (8 - len));
    x = (x & 0x0F0F0F0F0F0F0F0Full) * 2561 >> 8;
    x = (x & 0x00FF00FF00FF00FFull) * 6553601 >> 16;
    return static_cast<std::uint32_t>((x & 0x0000FFFF0000FFFFull) * 42949672960001ull >> 32);
}
inline std::uint64_t swar_digits(const char* p, unsigned len) {
    std::uint64_t w;
    std::memcpy(&w, p, 8);
    return swar_digits(w, len);
}

inline bool fast_num(const char*& p, std::uint64_t& out, const char* end) {
    skip_ws(p);
    const char* s = p;
    std::uint64_t v = 0;
    unsigned d;
    if (end - p >= 8) {
        // Up to eight digits at once (a 24-bit depth has eight): the run of
        // digits at the low end of the word. A carry or borrow out of a byte
        // only reaches the bytes after the first non-digit, which go unused.
        std::uint64_t w;
        std::memcpy(&w, p, 8);
        const std::uint64_t nd = ((w & 0xF0F0F0F0F0F0F0F0ull) ^ 0x3030303030303030ull) |
                                 (((w + 0x0606060606060606ull) & 0xF0F0F0F0F0F0F0F0ull) ^ 0x3030303030303030ull);
        const unsigned len = nd ? static_cast<unsigned>(__builtin_ctzll(nd)) / 8 : 8;
        if (len == 0) return false;
        v = swar_digits(w, len);
        p += len;
        // Eight digits followed by a ninth is rare; seven against eight (a
        // 24-bit depth) is a coin toss, so that test is not a branch of its own.
        const bool longer = (len == 8) & (static_cast<unsigned char>(*p) - unsigned('0') < 10);
        if (!longer) {
            if (!tok_end(*p)) return false;
            out = v;
            return true;
        }
    }
    while ((d = static_cast<unsigned char>(*p) - unsigned('0')) < 10) {
        v = v * 10 + d;
        ++p;
    }
    // 19 digits never overflow 64 bits; longer ones (leading zeros) go slow.
    if (p == s || p - s > 19 || !tok_end(*p)) return false;
    out = v;
    return true;
}

// A bit per byte of the 32 at p: those equal to c.
inline std::uint32_t bytes_equal(__m128i lo, __m128i hi, char c) {
    const __m128i v = _mm_set1_epi8(c);
    return static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(lo, v))) |
           static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_cmpeq_epi8(hi, v))) << 16;
}

// Whether m has four bits set or more (popcount is a library call without -mpopcnt).
inline bool at_least_four(std::uint32_t m) {
    m &= m - 1;
    m &= m - 1;
    m &= m - 1;
    return m != 0;
}

} // namespace

// libgcc's checks include that the operating system saves the AVX-512
// registers (XCR0), not only the CPUID bits.
bool trace_wide_parse_available() {
    static const bool yes = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512bw") &&
           __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512vbmi") &&
           __builtin_cpu_supports("avx512vbmi2") && __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
    }();
    return yes;
}

namespace {

// The bytes the whole-line parse reads from the line's start: 32 compared,
// and a field's eight-byte load may reach up to 37.
constexpr std::ptrdiff_t kWholeLineBytes = 40;
} // namespace

// The usual line, "f X Y DEPTH ID F|B[ c]" with single spaces and numbers of
// at most eight digits, found with a few compares over its 32 bytes instead of
// byte by byte: the separators and digits are bit masks, the fields' bounds
// their set bits. A run of such lines is taken in one loop that keeps the
// reader's state in registers; the first other line (tabs, CR, comments,
// longer numbers, another record, fewer than 40 bytes of whole lines left)
// ends the run and is left to the byte-by-byte path, which takes or refuses
// it. At most `room` fragments. Returns how many were taken.
std::size_t TraceReader::Impl::whole_lines(std::vector<Fragment>& out, std::size_t room) {
    const char* p = cur;
    const char* const end = lines_end;
    const std::uint64_t x_lo = x0, x_n = xw, y_lo = y0, y_n = yh, d_max = depth_max, i_max = id_max;
    const __m128i below0 = _mm_set1_epi8('0' - 1), above9 = _mm_set1_epi8('9' + 1);
    std::size_t n = 0;
    while (n < room && end - p >= kWholeLineBytes && p[0] == 'f' && p[1] == ' ') {
        const __m128i lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p));
        const __m128i hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 16));
        const std::uint32_t lfs = bytes_equal(lo, hi, '\n');
        if (lfs == 0) break;
        const unsigned e = static_cast<unsigned>(__builtin_ctz(lfs));
        std::uint32_t spaces = bytes_equal(lo, hi, ' ') & ((std::uint32_t(1) << e) - 1) & ~std::uint32_t(3);
        if (!at_least_four(spaces)) break;
        const unsigned s2 = static_cast<unsigned>(__builtin_ctz(spaces));
        spaces &= spaces - 1;
        const unsigned s3 = static_cast<unsigned>(__builtin_ctz(spaces));
        spaces &= spaces - 1;
        const unsigned s4 = static_cast<unsigned>(__builtin_ctz(spaces));
        spaces &= spaces - 1;
        const unsigned s5 = static_cast<unsigned>(__builtin_ctz(spaces));
        // Digits: '0' <= c <= '9' (bytes of 0x80 and up compare as negative).
        const std::uint32_t digits =
            static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_and_si128(_mm_cmpgt_epi8(lo, below0), _mm_cmplt_epi8(lo, above9)))) |
            static_cast<std::uint32_t>(_mm_movemask_epi8(_mm_and_si128(_mm_cmpgt_epi8(hi, below0), _mm_cmplt_epi8(hi, above9))))
                << 16;
        const std::uint32_t numbers = ((std::uint32_t(1) << s5) - 1) & ~std::uint32_t(3) &
                                      ~((std::uint32_t(1) << s2) | (std::uint32_t(1) << s3) | (std::uint32_t(1) << s4));
        const unsigned lx = s2 - 2, ly = s3 - s2 - 1, ld = s4 - s3 - 1, li = s5 - s4 - 1;
        // Every number byte a digit, no field empty (two spaces in a row) or
        // longer than eight digits.
        if ((numbers & ~digits) != 0 || lx - 1 > 7 || ly - 1 > 7 || ld - 1 > 7 || li - 1 > 7) break;
        const char f = p[s5 + 1];
        if (f != 'F' && f != 'B') break;
        const bool culled = e != s5 + 2;
        if (culled && (e != s5 + 4 || p[s5 + 2] != ' ' || p[s5 + 3] != 'c')) break;
        const std::uint64_t x = swar_digits(p + 2, lx), y = swar_digits(p + s2 + 1, ly),
                            d = swar_digits(p + s3 + 1, ld), id = swar_digits(p + s4 + 1, li);
        // Unsigned differences also reject values below the window's start.
        if (x - x_lo >= x_n || y - y_lo >= y_n || d > d_max || id > i_max) break;
        Fragment& fr = whole_line_fragment(out, f, culled);
        fr.x = static_cast<std::uint32_t>(x);
        fr.y = static_cast<std::uint32_t>(y);
        fr.depth = static_cast<std::uint32_t>(d);
        fr.id = static_cast<std::uint32_t>(id);
        p += e + 1;
        ++n;
    }
    return end_whole_lines(p, n);
}

// whole_lines() with AVX-512 (F, BW, VL, VBMI, VBMI2), taking the same lines
// and leaving the same ones to the byte-by-byte path, in about half the
// instructions: the line is one 32-byte register and its masks come out of
// the compares directly; the four numbers are gathered in one byte permute,
// each right-aligned in its own eight bytes with zeros in front, and turned
// into binary together by three multiply-adds; the window and bound checks
// are one compare of four lanes, and the four numbers one store. A field of
// more than eight digits, fewer than four separators or anything else
// unusual fails a check below and ends the run, as there.
// (GCC 12's permute intrinsics pass an undefined vector as the unused source of
// their unmasked form, which -Wmaybe-uninitialized reports at every use.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
__attribute__((target("avx512f,avx512bw,avx512vl,avx512vbmi,avx512vbmi2,bmi,bmi2"))) std::size_t
TraceReader::Impl::whole_lines_avx512(std::vector<Fragment>& out, std::size_t room) {
    static_assert(offsetof(Fragment, x) == 0 && offsetof(Fragment, y) == 4 && offsetof(Fragment, depth) == 8 &&
                      offsetof(Fragment, id) == 12,
                  "the four numbers are stored as one 16-byte vector");
    // The window's bounds as 32-bit lanes: exact while x0 + xw and y0 + yh fit
    // (any real screen); the numbers here have at most eight digits, so a
    // bound of 2^32 or more never rejects one.
    if (x0 + xw > (std::uint64_t(1) << 32) || y0 + yh > (std::uint64_t(1) << 32)) return whole_lines(out, room);
    const auto u32 = [](std::uint64_t v) { return static_cast<int>(static_cast<std::uint32_t>(std::min<std::uint64_t>(v, UINT32_MAX))); };
    const __m128i lo_bound = _mm_setr_epi32(u32(x0), u32(y0), 0, 0);
    const __m128i hi_bound = _mm_setr_epi32(u32(xw - 1), u32(yh - 1), u32(depth_max), u32(id_max));
    // Lane 8k + j of the gather: field k's byte j of 8, right-aligned.
    alignas(32) static constexpr std::int8_t kField[32] = {1, 1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2, 2, 2, 2,
                                                           3, 3, 3, 3, 3, 3, 3, 3, 4, 4, 4, 4, 4, 4, 4, 4};
    alignas(32) static constexpr std::int8_t kBack[32] = {-8, -7, -6, -5, -4, -3, -2, -1, -8, -7, -6, -5, -4, -3, -2, -1,
                                                          -8, -7, -6, -5, -4, -3, -2, -1, -8, -7, -6, -5, -4, -3, -2, -1};
    const __m256i field_end = _mm256_load_si256(reinterpret_cast<const __m256i*>(kField));
    const __m256i field_sep = _mm256_sub_epi8(field_end, _mm256_set1_epi8(1));
    const __m256i back = _mm256_load_si256(reinterpret_cast<const __m256i*>(kBack));
    const __m256i iota = _mm256_setr_epi8(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20,
                                          21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31);
    const __m256i zero_char = _mm256_set1_epi8('0'), nine = _mm256_set1_epi8(9), nl = _mm256_set1_epi8('\n'),
                  space = _mm256_set1_epi8(' ');
    const __m256i tens = _mm256_set1_epi16(0x010A);        // bytes 10, 1: two digits
    const __m256i hundreds = _mm256_set1_epi32(0x00010064); // 100, 1: four digits
    const __m256i myriads = _mm256_set1_epi32(0x00012710);  // 10000, 1: eight digits
    const char* p = cur;
    const char* const end = lines_end;
    std::size_t n = 0;
    while (n < room && end - p >= kWholeLineBytes && p[0] == 'f' && p[1] == ' ') {
        const __m256i v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(p));
        const std::uint32_t lfs = _mm256_cmpeq_epi8_mask(v, nl);
        if (lfs == 0) break;
        const unsigned e = _tzcnt_u32(lfs);
        const std::uint32_t sp = _mm256_mask_cmpeq_epi8_mask(_bzhi_u32(~0u, e), v, space);
        // The separators after "f ": tzcnt of none is 32, which fails the
        // line-end test below, so fewer than four need no test of their own.
        std::uint32_t rest = sp & ~std::uint32_t(3);
        const unsigned s2 = _tzcnt_u32(rest);
        rest = _blsr_u32(rest);
        const unsigned s3 = _tzcnt_u32(rest);
        rest = _blsr_u32(rest);
        const unsigned s4 = _tzcnt_u32(rest);
        rest = _blsr_u32(rest);
        const unsigned s5 = _tzcnt_u32(rest);
        const bool culled = e != s5 + 2;
        if (culled && (e != s5 + 4 || p[s5 + 2] != ' ' || p[s5 + 3] != 'c')) break;
        const char f = p[s5 + 1];
        if (f != 'F' && f != 'B') break;
        // Field lengths minus one, each 0..7 (an empty field wraps around).
        if (((s2 - 3) | (s3 - s2 - 2) | (s4 - s3 - 2) | (s5 - s4 - 2)) > 7) break;
        const __m256i d = _mm256_sub_epi8(v, zero_char);
        const std::uint32_t numbers = _bzhi_u32(~std::uint32_t(3), s5) & ~sp;
        if ((numbers & ~static_cast<std::uint32_t>(_mm256_cmple_epu8_mask(d, nine))) != 0) break;
        // Separator positions in order: 1 (after "f"), s2, s3, s4, s5.
        const __m256i seps = _mm256_maskz_compress_epi8(sp, iota);
        const __m256i idx = _mm256_add_epi8(_mm256_permutexvar_epi8(field_end, seps), back);
        // Bytes after field k's separator only (signed: an index before the
        // line's start is negative).
        const __mmask32 take = _mm256_cmpgt_epi8_mask(idx, _mm256_permutexvar_epi8(field_sep, seps));
        const __m256i digits = _mm256_maskz_permutexvar_epi8(take, idx, d);
        const __m256i pairs = _mm256_maddubs_epi16(digits, tens);
        const __m256i quads = _mm256_madd_epi16(pairs, hundreds);
        const __m256i packed = _mm256_packus_epi32(quads, quads);   // per 128-bit half: fields 0 1 0 1 | 2 3 2 3
        const __m256i eights = _mm256_madd_epi16(packed, myriads);
        const __m128i vals = _mm_unpacklo_epi64(_mm256_castsi256_si128(eights), _mm256_extracti128_si256(eights, 1));
        // x and y less the window's start wrap around below it, so one
        // unsigned compare a lane checks both ends.
        if (_mm_cmple_epu32_mask(_mm_sub_epi32(vals, lo_bound), hi_bound) != 0xF) break;
        _mm_storeu_si128(reinterpret_cast<__m128i*>(&whole_line_fragment(out, f, culled).x), vals);
        p += e + 1;
        ++n;
    }
    return end_whole_lines(p, n);
}
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif

bool TraceReader::Impl::fast_fragment(std::vector<Fragment>& out) {
    const char* p = cur + 2;
    std::uint64_t x, y, d, id;
    if (!fast_num(p, x, lines_end) || !fast_num(p, y, lines_end) || !fast_num(p, d, lines_end) ||
        !fast_num(p, id, lines_end))
        return false;
    skip_ws(p);
    Facing facing;
    if (*p == 'F') facing = Facing::Front;
    else if (*p == 'B') facing = Facing::Back;
    else return false;
    ++p;
    if (!tok_end(*p)) return false;
    skip_ws(p);
    bool culled = false;
    if (*p == 'c' && tok_end(p[1])) {
        culled = true;
        ++p;
        skip_ws(p);
    }
    if (*p == '\n') ++p;
    else if (*p == '\r' && p[1] == '\n') p += 2;
    else if (*p == '#') p = static_cast<const char*>(std::memchr(p, '\n', static_cast<std::size_t>(lines_end - p))) + 1;
    else return false;
    // Unsigned differences also reject values below the window's start.
    if (x - x0 >= xw || y - y0 >= yh || d > depth_max || id > id_max) return false;
    out.push_back(Fragment{static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(d),
                           static_cast<std::uint32_t>(id), facing, culled});
    cur = const_cast<char*>(p);
    ++line;
    return true;
}

void TraceReader::Impl::slow_fragment(const Fields& fl, std::vector<Fragment>& out, bool in_tile) {
    if (!in_tile) {
        if (seen_frame) fail("fragment before any tile of frame " + num_str(frame));
        fail("fragment before any frame and tile");
    }
    static const char* const names[] = {"x", "y", "depth", "object id", "facing"};
    if (fl.n < 6)
        fail(std::string("fragment has too few fields: missing ") + names[fl.n - 1] + " (" + kFragmentShape + ")");
    if (fl.n > 7) fail("fragment has an extra field " + show(fl.f[7]) + " (" + kFragmentShape + ")");
    std::uint64_t x = num(fl.f[1], "fragment x");
    std::uint64_t y = num(fl.f[2], "fragment y");
    std::uint64_t d = num(fl.f[3], "fragment depth");
    std::uint64_t id = num(fl.f[4], "fragment object id");
    Facing facing;
    if (fl.f[5] == "F") facing = Facing::Front;
    else if (fl.f[5] == "B") facing = Facing::Back;
    else fail("fragment facing " + show(fl.f[5]) + " is not F or B");
    if (fl.n == 7 && fl.f[6] != "c")
        fail("fragment field " + show(fl.f[6]) + " after the facing is not the cull tag 'c' (" + kFragmentShape + ")");

    const bool clipped_x = xw < hdr.tile_w, clipped_y = yh < hdr.tile_h;
    const std::string where = "tile " + num_str(tcol) + " " + num_str(trow);
    const std::string scr = "the tile's part inside the " + num_str(hdr.screen_w) + "x" + num_str(hdr.screen_h) + " screen";
    if (x - x0 >= xw)
        fail("fragment x=" + num_str(x) + " outside " + where + " (x " + num_str(x0) + ".." + num_str(x0 + xw - 1) +
             (clipped_x ? ", " + scr : std::string()) + ")");
    if (y - y0 >= yh)
        fail("fragment y=" + num_str(y) + " outside " + where + " (y " + num_str(y0) + ".." + num_str(y0 + yh - 1) +
             (clipped_y ? ", " + scr : std::string()) + ")");
    if (d > depth_max)
        fail("fragment depth=" + num_str(d) + " does not fit depth_bits " + num_str(hdr.depth_bits) + " (max " +
             num_str(depth_max) + ")");
    if (id > id_max)
        fail("fragment object id=" + num_str(id) + " does not fit zeb.id_bits " + num_str(lim.id_bits) + " (max " +
             num_str(id_max) + ")");
    out.push_back(Fragment{static_cast<std::uint32_t>(x), static_cast<std::uint32_t>(y), static_cast<std::uint32_t>(d),
                           static_cast<std::uint32_t>(id), facing, fl.n == 7});
}

bool TraceReader::Impl::mark_tile(std::uint64_t idx) {
    if (use_set) return tile_set.insert(idx).second;
    std::uint64_t& word = tile_bits[idx >> 6];
    const std::uint64_t bit = std::uint64_t(1) << (idx & 63);
    if (word & bit) return false;
    word |= bit;
    tiles_in_frame.push_back(idx);
    return true;
}

void TraceReader::Impl::start_tile(const Fields& fl, Tile& t) {
    if (!seen_frame) fail("tile before any frame");
    if (fl.n < 3) fail(std::string("tile has too few fields: missing ") + (fl.n < 2 ? "column" : "row") + " (" +
                       kTileShape + ")");
    const std::uint64_t c = num(fl.f[1], "tile column");
    const std::uint64_t r = num(fl.f[2], "tile row");
    bool have_other = false, have_base = false, have_prims = false, have_cprims = false, have_shade = false;
    std::uint64_t other = 0, base = 0, prims = 0, cprims = 0, shade = 100;
    for (int i = 3; i < fl.n; ++i) {
        const std::string_view kv = fl.f[i];
        const std::size_t eq = kv.find('=');
        if (eq == std::string_view::npos || eq == 0)
            fail("tile field " + show(kv) + " is not key=value (" + kTileShape + ")");
        const std::string_view key = kv.substr(0, eq), val = kv.substr(eq + 1);
        bool* have;
        std::uint64_t* dst;
        if (key == "other") { have = &have_other; dst = &other; }
        else if (key == "base") { have = &have_base; dst = &base; }
        else if (key == "prims") { have = &have_prims; dst = &prims; }
        else if (key == "cprims") { have = &have_cprims; dst = &cprims; }
        else if (key == "shade") { have = &have_shade; dst = &shade; }
        else fail("tile has unknown key " + show(key) + " (known keys: other, base, prims, cprims, shade)");
        const std::string k(key);
        if (*have) fail("tile key '" + k + "' given twice");
        if (val.empty()) fail("tile field '" + k + "=' has no value");
        *dst = num(val, "tile " + k + "=");
        // Far beyond any tile's work (2^40 fragments or cycles), and kept there so
        // that the timing arithmetic over a whole run cannot overflow 64 bits.
        if (*dst > kTileWorkLimit)
            fail("tile " + k + "=" + num_str(*dst) + " too large (at most " + num_str(kTileWorkLimit) + ")");
        *have = true;
    }
    if (have_shade && (shade < kShadeMin || shade > kShadeMax))
        fail("tile shade=" + num_str(shade) + " outside " + num_str(kShadeMin) + ".." + num_str(kShadeMax) +
             " (percent of gpu.cycles_per_fragment)");
    if (c >= cols)
        fail("tile column " + num_str(c) + " outside the screen (" + num_str(hdr.screen_w) + " px wide = " +
             num_str(cols) + " tile columns, 0.." + num_str(cols - 1) + ")");
    if (r >= rows)
        fail("tile row " + num_str(r) + " outside the screen (" + num_str(hdr.screen_h) + " px high = " +
             num_str(rows) + " tile rows, 0.." + num_str(rows - 1) + ")");
    if (!mark_tile(r * cols + c))
        fail("tile " + num_str(c) + " " + num_str(r) + " appears twice in frame " + num_str(frame));

    tcol = c;
    trow = r;
    x0 = c * hdr.tile_w;
    y0 = r * hdr.tile_h;
    xw = std::min<std::uint64_t>(hdr.tile_w, hdr.screen_w - x0);
    yh = std::min<std::uint64_t>(hdr.tile_h, hdr.screen_h - y0);

    t.frame = frame;
    t.col = static_cast<std::uint32_t>(c);
    t.row = static_cast<std::uint32_t>(r);
    t.other = other;
    t.has_base = have_base;
    t.base = base;
    t.has_prims = have_prims;
    t.prims = prims;
    t.has_cprims = have_cprims;
    t.cprims = cprims;
    t.has_shade = have_shade;
    t.shade = static_cast<std::uint32_t>(shade);
    t.ordered_other = false;
    t.other_runs.clear();
    other_given = have_other;
    t.frags.clear();
}

void TraceReader::Impl::other_run(const Fields& fl, Tile& t, bool in_tile) {
    if (!in_tile) fail("'o' record outside a tile (expected 'o N' between a tile's fragments)");
    if (fl.n < 2) fail("o has too few fields: missing its count (expected 'o N')");
    if (fl.n > 2) fail("o has an extra field " + show(fl.f[2]) + " (expected 'o N')");
    if (other_given) fail("tile has both other= and 'o' records (the o records give its non-collisionable count)");
    const std::uint64_t n = num(fl.f[1], "o count");
    if (n > kTileWorkLimit || t.other + n > kTileWorkLimit)
        fail("tile's o records add up to more than " + num_str(kTileWorkLimit) + " fragments");
    t.ordered_other = true;
    t.other += n;
    t.other_runs.push_back({static_cast<std::uint32_t>(t.frags.size()), n});
}

std::uint64_t TraceReader::Impl::start_frame(const Fields& fl) {
    if (fl.n < 2) fail("frame has too few fields: missing its number (expected 'frame N')");
    if (fl.n > 2) fail("frame has an extra field " + show(fl.f[2]) + " (expected 'frame N')");
    const std::uint64_t n = num(fl.f[1], "frame number");
    if (n != next_frame)
        fail("frame " + num_str(n) + " out of sequence: expected frame " + num_str(next_frame));
    if (use_set) {
        tile_set.clear();
    } else {
        for (std::uint64_t idx : tiles_in_frame) tile_bits[idx >> 6] = 0;
        tiles_in_frame.clear();
    }
    seen_frame = true;
    frame = n;
    ++next_frame;
    return n;
}

TraceLimits trace_limits(const SimConfig& cfg) {
    TraceLimits l;
    l.tile_w = cfg.tile.width;
    l.tile_h = cfg.tile.height;
    l.id_bits = cfg.zeb.id_bits;
    l.max_line_bytes = cfg.input.max_line_bytes;
    l.max_tile_fragments = cfg.input.max_tile_fragments;
    // A quarter of the run's cycle budget: the rest covers what the trace does
    // not declare (sorting, testing, memory, per-tile and per-frame costs).
    l.max_work_cycles = cfg.max_run_cycles() / 4;
    l.cycles_per_fragment = std::max<std::uint64_t>(cfg.gpu.cycles_per_fragment, 1);
    l.cycles_per_primitive = cfg.gpu.setup_cycles_per_primitive;
    l.tile_overhead = cfg.gpu.tile_overhead_cycles;
    l.clock_mhz = cfg.clock.mhz;
    return l;
}

TraceReader::TraceReader(const std::string& path, const TraceLimits& limits, RawObserver* observer)
    : impl_(std::make_unique<Impl>()) {
    if (limits.tile_w < 1 || limits.tile_h < 1 || limits.id_bits < 1 || limits.read_chunk < 1)
        throw std::invalid_argument("TraceReader: tile size and id_bits must be at least 1");
    impl_->path = path;
    impl_->lim = limits;
    impl_->avx512 = limits.wide_parse && trace_wide_parse_available();
    impl_->open();
    impl_->in->observe(observer);
    impl_->read_headers();
}

TraceReader::~TraceReader() = default;

void TraceReader::start_at_frame(std::uint64_t frame, std::uint64_t offset, std::uint64_t line) {
    Impl& m = *impl_;
    const std::uint64_t at = m.pulled - static_cast<std::uint64_t>(m.data_end - m.cur);
    if (m.seen_frame || offset < at) throw std::logic_error("TraceReader::start_at_frame: not ahead of the reader");
    if (offset - at <= static_cast<std::uint64_t>(m.data_end - m.cur)) {
        m.cur += offset - at;
        if (m.cur > m.lines_end) m.lines_end = m.cur;   // fill() reads the rest of the line
    } else {
        const long long got = m.in->skip(offset - m.pulled);
        if (got < 0) m.fail(m.in->error());
        m.pulled += static_cast<std::uint64_t>(got);
        m.cur = m.lines_end = m.data_end = m.buf.data();
    }
    m.line = line ? line : 1;
    m.line_relative = line == 0;
    m.line_from = offset;
    m.next_frame = frame;
}

std::uint64_t TraceReader::declared_work() const { return impl_->work; }

void TraceReader::count_work_from(std::uint64_t work_before) { impl_->work = work_before; }

void TraceReader::stop_after_frame(std::uint64_t last) { impl_->stop_after = last; }

void TraceReader::expect_stop_at(std::uint64_t offset) { impl_->stop_at = offset; }

std::uint64_t TraceReader::lines_taken_whole() const { return impl_->taken_whole; }

bool TraceReader::parses_wide() const { return impl_->avx512; }

const StreamHeader& TraceReader::header() const { return impl_->hdr; }

std::string TraceReader::name() const { return impl_->path; }

FragmentSource::Event TraceReader::next(Tile& t) {
    Impl& m = *impl_;
    if (m.ended) return Event::End;
    // Not before: a --jobs worker's start_at_frame() passes over data first.
    if (m.lim.read_ahead && !m.ahead && m.in->compressed())
        m.ahead = std::make_unique<ReadAhead>(*m.in, std::max<std::size_t>(m.lim.read_chunk, 16));
    bool in_tile = false;
    Fields fl;
    for (;;) {
        if (m.cur == m.lines_end && !m.fill()) {
            if (in_tile) return m.end_tile(t);
            if (m.stop_at != UINT64_MAX) m.fail(m.split_elsewhere());
            m.ended = true;
            return Event::End;
        }
        if (in_tile && t.frags.size() >= m.lim.max_tile_fragments && m.cur[0] == 'f')
            m.fail("tile " + num_str(m.tcol) + " " + num_str(m.trow) + " has more than " +
                   num_str(m.lim.max_tile_fragments) +
                   " fragments (the limit input.max_tile_fragments; docs/limits.md)");
        if (in_tile && m.cur[0] == 'f') {
            const std::size_t room = m.lim.max_tile_fragments - t.frags.size();
            if (m.avx512 ? m.whole_lines_avx512(t.frags, room) : m.whole_lines(t.frags, room)) continue;
        }
        if (in_tile && m.cur[0] == 'f' && (m.cur[1] == ' ' || m.cur[1] == '\t') && m.fast_fragment(t.frags)) continue;

        m.tokenize(m.cur, fl);
        if (fl.n == 0) {
            m.advance(fl.next);
            continue;
        }
        const std::string_view key = fl.f[0];
        if (key == "f") {
            m.slow_fragment(fl, t.frags, in_tile);
            m.advance(fl.next);
            continue;
        }
        if (key == "o") {
            m.other_run(fl, t, in_tile);
            m.advance(fl.next);
            continue;
        }
        // The record that ends a tile stays unread until the next call.
        if (key == "tile") {
            if (in_tile) return m.end_tile(t);
            m.start_tile(fl, t);
            m.advance(fl.next);
            in_tile = true;
            continue;
        }
        if (key == "frame") {
            if (in_tile) return m.end_tile(t);
            t.frame = m.start_frame(fl);
            if (t.frame > m.stop_after) {
                const std::uint64_t here = m.pulled - static_cast<std::uint64_t>(m.data_end - m.cur);
                if (m.stop_at != UINT64_MAX && here != m.stop_at) m.fail(m.split_elsewhere());
                m.ended = true;
                return Event::End;
            }
            m.advance(fl.next);
            return Event::Frame;
        }
        if (key == "screen" || key == "tile_size" || key == "depth_bits")
            m.fail("header '" + std::string(key) + "' after the first frame (headers must come before it)");
        if (key == "rbcd-trace") m.fail("magic record 'rbcd-trace' repeated (it must be only the first record)");
        m.fail("unknown record " + show(key));
    }
}

} // namespace rbcd
