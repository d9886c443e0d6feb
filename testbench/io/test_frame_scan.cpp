// io/frame_scan.h and TraceReader::start_at_frame (rbcd-sim --jobs): the frame
// records a scan finds, plain and gzip, at any chunk boundary, sampled when
// there are many; the records found near byte offsets; the line count; and a
// reader started at a found record giving the frames a whole read gives, with
// the same line numbers in its messages.
#include <catch2/catch.hpp>

#include "rbcd/testbench/common/temp_dir.h"

#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/io/trace_reader.h"

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
