// io/frame_scan.h and TraceReader::start_at_frame (rbcd-sim --jobs): the frame
// records a scan finds, plain, gzip and zstd, at any chunk boundary, sampled
// when there are many; the records found near byte offsets; the line count;
// a reader started at a found record giving the frames a whole read gives,
// with the same line numbers in its messages; TraceWriter's zstd frames, and
// the read-ahead thread giving the data and errors a plain read gives.
#include <catch2/catch.hpp>

#include "rbcd/testbench/common/temp_dir.h"

#include <string>
#include <vector>

#include <fcntl.h>
#include <zstd.h>

#include "rbcd/testbench/common/zstd_frames.h"

#include "rbcd/common/errors.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/io/gzip_stream.h"
#include "rbcd/io/read_ahead.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/trace_writer.h"

using namespace rbcd;
using Catch::Matchers::Contains;

namespace {

// Frames 0..n-1, each of one tile with k fragments; odd frames' records
// carry a comment, every fifth starts after blank lines.
std::string trace_text(unsigned n, unsigned k) {
    std::string s = "rbcd-trace 1\nscreen 64 64\n";
    for (unsigned f = 0; f < n; ++f) {
        if (f % 5 == 4) s += "\n\n";
        s += "frame " + std::to_string(f) + (f % 2 ? "  # odd\n" : "\n");
        s += "tile " + std::to_string(f % 4) + " 0 other=3\n";
        for (unsigned i = 0; i < k; ++i)
            s += "f " + std::to_string(f % 4 * 16 + i % 16) + " " + std::to_string(i / 16 % 16) + " " +
                 std::to_string(100 + i) + " 1 F\n";
    }
    return s;
}

std::uint64_t line_of(const std::string& text, std::uint64_t offset) {
    std::uint64_t n = 1;
    for (std::uint64_t i = 0; i < offset; ++i) n += text[i] == '\n';
    return n;
}

std::vector<std::string> frames_read(TraceReader& r) {
    std::vector<std::string> out;
    Tile t;
    for (;;) {
        const auto ev = r.next(t);
        if (ev == FragmentSource::Event::End) return out;
        if (ev == FragmentSource::Event::Frame) out.push_back("F" + std::to_string(t.frame));
        else out.push_back("T" + std::to_string(t.frags.size()));
    }
}

std::string read_all(GzipStream& in) {
    std::string out;
    char buf[4096];
    for (long n; (n = in.read(buf, sizeof buf)) > 0;) out.append(buf, static_cast<std::size_t>(n));
    return out;
}

} // namespace

TEST_CASE("frame scan: every record, its byte and line, plain and gzip", "[frame_scan]") {
    test::TempDir td;
    const std::string text = trace_text(40, 300);
    for (const bool gz : {false, true}) {
        const std::string path = gz ? td.write_gz("t.rbt.gz", text) : td.write("t.rbt", text);
        // Chunks that cut records anywhere, and the default.
        for (const std::size_t chunk : {std::size_t(16), std::size_t(61), std::size_t(4096), std::size_t(1) << 20}) {
            const FrameScan s = scan_frames(path, 4096, chunk);
            INFO((gz ? "gzip" : "plain") << ", chunk " << chunk);
            REQUIRE(s.ok);
            REQUIRE(s.marks.size() == 40);
            for (unsigned f = 0; f < 40; ++f) {
                CHECK(s.marks[f].frame == f);
                CHECK(s.marks[f].line == line_of(text, s.marks[f].offset));
            }
        }
        const FrameScan s = scan_frames(path);
        INFO((gz ? "gzip" : "plain"));
        REQUIRE(s.ok);
        CHECK(s.bytes == text.size());
        CHECK(s.frame_lines == 40);
        REQUIRE(s.marks.size() == 40);
        for (unsigned f = 0; f < 40; ++f) {
            CHECK(s.marks[f].frame == f);
            CHECK(text.compare(s.marks[f].offset, 6, "frame ") == 0);
            CHECK(s.marks[f].line == line_of(text, s.marks[f].offset));
        }
        // Many frames: a sample, every 2^k-th, still exact.
        const FrameScan few = scan_frames(path, 8);
        REQUIRE(few.ok);
        CHECK(few.frame_lines == 40);
        CHECK(few.marks.size() <= 8);
        for (const FrameMark& m : few.marks) {
            CHECK(m.frame % 8 == 0);
            CHECK(m.line == line_of(text, m.offset));
        }
    }
    // The last record without its LF.
    const std::string cut = "rbcd-trace 1\nframe 0\nframe 1";
    const FrameScan c = scan_frames(td.write("cut.rbt", cut));
    REQUIRE(c.marks.size() == 2);
    CHECK(c.marks[1].offset == 21);
    CHECK(c.marks[1].line == 3);
    // Not a trace at all: no record, still ok (the run says what is wrong).
    CHECK(scan_frames(td.write("junk.rbt", std::string(5000, 'x'))).marks.empty());
    CHECK_FALSE(scan_frames(td.path("missing.rbt")).ok);
}

TEST_CASE("frame scan: records near byte offsets, and the lines before them", "[frame_scan]") {
    test::TempDir td;
    const std::string text = trace_text(30, 2000);   // frames of ~36 KB: records cross the 64 KiB windows
    const std::string path = td.write("t.rbt", text);
    CHECK(plain_trace_bytes(path) == text.size());
    CHECK(plain_trace_bytes(td.write_gz("t.rbt.gz", text)) == 0);
    std::vector<std::uint64_t> cuts;
    for (std::uint64_t k = 1; k < 12; ++k) cuts.push_back(text.size() * k / 12);
    const FrameScan s = find_frames_near(path, cuts);
    REQUIRE(s.ok);
    REQUIRE(s.marks.size() == cuts.size());
    for (std::size_t i = 0; i < cuts.size(); ++i) {
        const FrameMark& m = s.marks[i];
        // The first record at or after the cut.
        CHECK(m.offset >= cuts[i]);
        CHECK(text.compare(m.offset, 6, "frame ") == 0);
        CHECK(text.find("\nframe ", cuts[i] ? cuts[i] - 1 : 0) + 1 == m.offset);
        CHECK(count_lines_before(path, m.offset) == line_of(text, m.offset));
        CHECK(text.compare(m.offset, 6 + std::to_string(m.frame).size(), "frame " + std::to_string(m.frame)) == 0);
    }
    // A cut past the last record finds nothing; a cut at 0 finds frame 0.
    CHECK(find_frames_near(path, {text.size() - 10}).marks.empty());
    const FrameScan z = find_frames_near(td.write("z.rbt", "frame 0\n"), {0});
    REQUIRE(z.marks.size() == 1);
    CHECK(z.marks[0].offset == 0);
}

TEST_CASE("trace reader started at a frame's record: the frames a whole read gives from there", "[frame_scan]") {
    test::TempDir td;
    const std::string text = trace_text(12, 500);
    for (const bool gz : {false, true}) {
        const std::string path = gz ? td.write_gz("t.rbt.gz", text) : td.write("t.rbt", text);
        const FrameScan s = scan_frames(path);
        REQUIRE(s.marks.size() == 12);
        TraceLimits lim;
        TraceReader whole(path, lim);
        const auto all = frames_read(whole);
        for (const std::size_t read_chunk : {std::size_t(1) << 20, std::size_t(100)}) {
            lim.read_chunk = read_chunk;
            for (unsigned f : {1u, 5u, 11u}) {
                INFO((gz ? "gzip" : "plain") << ", chunk " << read_chunk << ", from frame " << f);
                TraceReader r(path, lim);
                r.start_at_frame(f, s.marks[f].offset, s.marks[f].line);
                const auto got = frames_read(r);
                const auto from = std::find(all.begin(), all.end(), "F" + std::to_string(f));
                CHECK(got == std::vector<std::string>(from, all.end()));
            }
        }
    }
    // An error after the start names the line a whole read names.
    std::string bad = text;
    const std::size_t at = bad.find("\nf ", bad.find("frame 9\n"));
    bad.replace(at + 1, 1, "g");
    const std::string path = td.write("bad.rbt", bad);
    const FrameScan s = scan_frames(path);
    std::string whole_msg, started_msg;
    try {
        TraceReader r(path, TraceLimits{});
        frames_read(r);
    } catch (const InputError& e) {
        whole_msg = e.what();
    }
    try {
        TraceReader r(path, TraceLimits{});
        r.start_at_frame(7, s.marks[7].offset, s.marks[7].line);
        frames_read(r);
    } catch (const InputError& e) {
        started_msg = e.what();
    }
    CHECK_THAT(whole_msg, Contains(":" + std::to_string(line_of(bad, at + 1)) + ":"));
    CHECK(started_msg == whole_msg);
}

TEST_CASE("trace writer: a zstd trace is a frame for the header and one from every frame record", "[frame_scan][zstd]") {
    test::TempDir td;
    const std::string text = trace_text(9, 700);
    TraceLimits lim;
    lim.tile_w = lim.tile_h = 16;
    TraceReader plain(td.write("t.rbt", text), lim);
    const std::string path = td.path("t.rbt.zst");
    CHECK(trace_compression_for(path) == TraceCompression::Zstd);
    CHECK(trace_compression_for("a.rbt.gz") == TraceCompression::Gzip);
    CHECK(trace_compression_for("a.zst.rbt") == TraceCompression::None);
    {
        TraceWriter w(path, plain.header(), TraceCompression::Zstd);
        Tile t;
        for (auto ev = plain.next(t); ev != FragmentSource::Event::End; ev = plain.next(t))
            ev == FragmentSource::Event::Frame ? w.frame(t.frame) : w.tile(t);
        w.close();
    }
    const std::string z = test::slurp(path);
    // Walk the frames: each states its size, and a frame record starts each but the first.
    std::string data;
    std::size_t at = 0, frames = 0;
    while (at < z.size()) {
        const std::size_t csize = ZSTD_findFrameCompressedSize(z.data() + at, z.size() - at);
        REQUIRE_FALSE(ZSTD_isError(csize));
        const unsigned long long size = ZSTD_getFrameContentSize(z.data() + at, csize);
        REQUIRE(size != ZSTD_CONTENTSIZE_UNKNOWN);
        std::string piece(size, '\0');
        REQUIRE(ZSTD_decompress(piece.data(), piece.size(), z.data() + at, csize) == size);
        if (frames == 0) CHECK(piece.rfind("rbcd-trace 1\n", 0) == 0);
        else CHECK(piece.rfind("frame " + std::to_string(frames - 1) + "\n", 0) == 0);
        data += piece;
        at += csize;
        ++frames;
    }
    CHECK(frames == 10);
    // A skip passes over whole frames by their headers: frame 3's checksum
    // broken is an error to a read, not to a skip past it.
    {
        std::size_t at3 = 0;
        for (int f = 0; f < 4; ++f) at3 += ZSTD_findFrameCompressedSize(z.data() + at3, z.size() - at3);
        std::string bad = z;
        bad[at3 - 1] = static_cast<char>(bad[at3 - 1] ^ 0x5a);   // frame 3's last checksum byte
        const std::string bad_path = td.write("bad.rbt.zst", bad);
        GzipStream whole(::open(bad_path.c_str(), O_RDONLY), 4096);
        read_all(whole);
        CHECK_THAT(whole.error(), Contains("corrupt or truncated zstd stream"));
        GzipStream skipping(::open(bad_path.c_str(), O_RDONLY), 4096);
        char c;
        REQUIRE(skipping.read(&c, 1) == 1);
        const std::uint64_t upto = data.find("frame 4\n");
        REQUIRE(skipping.skip(upto - 1) == static_cast<long long>(upto - 1));
        CHECK(read_all(skipping) == data.substr(upto));
        CHECK(skipping.error().empty());
    }
    // The same stream read back as the writer's text of the plain trace.
    const std::string again = td.path("again.rbt");
    {
        TraceReader r(path, lim);
        TraceWriter w(again, r.header());
        Tile t;
        for (auto ev = r.next(t); ev != FragmentSource::Event::End; ev = r.next(t))
            ev == FragmentSource::Event::Frame ? w.frame(t.frame) : w.tile(t);
        w.close();
    }
    CHECK(test::slurp(again) == data);
}

TEST_CASE("frame scan: a zstd trace's records from its frames' headers, and a reader started at one", "[frame_scan][zstd]") {
    test::TempDir td;
    const std::string text = trace_text(40, 300);
    const std::string path = td.write("t.rbt.zst", test::zstd_frames(test::by_frame(text)));
    const FrameScan s = scan_frames(path);
    REQUIRE(s.ok);
    CHECK(s.bytes == text.size());
    REQUIRE(s.marks.size() == 40);
    for (unsigned f = 0; f < 40; ++f) {
        CHECK(s.marks[f].frame == f);
        CHECK(text.compare(s.marks[f].offset, 6, "frame ") == 0);
        CHECK(s.marks[f].line == 0);   // not counted: the reader counts it if a message needs it
        if (f % 13 == 0) CHECK(count_lines_before(path, s.marks[f].offset) == line_of(text, s.marks[f].offset));
    }
    CHECK(scan_frames(path, 8).marks.size() <= 8);
    // Frames that do not state their size: the data is scanned, as gzip's.
    const std::string streamed = td.write("s.rbt.zst", test::zstd_frames(test::by_frame(text), false));
    const FrameScan ss = scan_frames(streamed);
    REQUIRE(ss.marks.size() == 40);
    CHECK(ss.marks[7].line == line_of(text, ss.marks[7].offset));
    // One frame for the whole text: the scan of the data finds every record.
    REQUIRE(scan_frames(td.write("one.rbt.zst", test::zstd_frames({text}))).marks.size() == 40);
    // A reader started at a mark passes over the frames before it and reads what a whole read gives.
    TraceLimits lim;
    TraceReader whole(path, lim);
    const auto all = frames_read(whole);
    for (const std::size_t chunk : {std::size_t(1) << 20, std::size_t(100)}) {
        lim.read_chunk = chunk;
        for (const bool ahead : {false, true}) {
            lim.read_ahead = ahead;
            for (unsigned f : {1u, 17u, 39u}) {
                INFO("chunk " << chunk << " read-ahead " << ahead << " from frame " << f);
                TraceReader r(path, lim);
                r.start_at_frame(f, s.marks[f].offset, 0);
                const auto from = std::find(all.begin(), all.end(), "F" + std::to_string(f));
                CHECK(frames_read(r) == std::vector<std::string>(from, all.end()));
            }
        }
    }
}

TEST_CASE("gzip stream: skipping a zstd trace passes over whole frames and decompresses the rest", "[frame_scan][zstd]") {
    test::TempDir td;
    const std::string text = trace_text(20, 400);
    const auto pieces = test::by_frame(text);
    const std::string z = test::zstd_frames(pieces);
    const std::string path = td.write("t.rbt.zst", z);
    for (const std::uint64_t n : {std::uint64_t(0), std::uint64_t(pieces[0].size()), std::uint64_t(pieces[0].size() + 5),
                                  std::uint64_t(text.size() / 2), std::uint64_t(text.size()), std::uint64_t(text.size() + 9)}) {
        INFO("skip " << n);
        GzipStream in(::open(path.c_str(), O_RDONLY), 1000);
        char c;
        REQUIRE(in.read(&c, 1) == 1);   // started, as a reader that has read the header
        const long long got = in.skip(n);
        CHECK(got == static_cast<long long>(std::min<std::uint64_t>(n, text.size() - 1)));
        CHECK(read_all(in) == text.substr(std::min<std::uint64_t>(1 + n, text.size())));
    }
    // Cut inside a frame that is passed over: the end of the file is named.
    const std::string cut = td.write("cut.rbt.zst", z.substr(0, z.size() * 2 / 3));
    GzipStream in(::open(cut.c_str(), O_RDONLY), 1000);
    char c;
    REQUIRE(in.read(&c, 1) == 1);
    if (in.skip(text.size()) >= 0) read_all(in);
    CHECK_THAT(in.error(), Contains("corrupt or truncated zstd stream"));
}

TEST_CASE("read-ahead: the data, then the stream's error where it was raised", "[frame_scan][zstd]") {
    test::TempDir td;
    const std::string text = trace_text(30, 500);
    const std::string z = test::zstd_frames(test::by_frame(text));
    for (const bool bad : {false, true}) {
        const std::string path = td.write("t.rbt.zst", bad ? z.substr(0, z.size() - 7) : z);
        GzipStream direct(::open(path.c_str(), O_RDONLY), 4096), threaded(::open(path.c_str(), O_RDONLY), 4096);
        const std::string want = read_all(direct);
        std::string got;
        long n = 0;
        {
            ReadAhead ahead(threaded, 4096, 3);
            char buf[1000];
            while ((n = ahead.read(buf, sizeof buf)) > 0) got.append(buf, static_cast<std::size_t>(n));
            CHECK(ahead.read(buf, sizeof buf) == n);   // the end, or the error, stays
            if (bad) CHECK(ahead.error() == direct.error());
        }
        CHECK(got == want);
        CHECK(n == (bad ? -1 : 0));
        if (!bad) CHECK(got == text);
    }
}
