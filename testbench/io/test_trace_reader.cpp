// TraceReader / TraceWriter against formats.md: every accepted form, every
// rejected one with its exact line number, gzip input and a writer round trip.
#include <catch2/catch.hpp>

#include "rbcd/testbench/common/temp_dir.h"

#include <stdlib.h>
#include <sys/stat.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/common/fragment.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/io/memory_source.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/trace_writer.h"

using namespace rbcd;
using Catch::Matchers::Contains;
using Catch::Matchers::Equals;
using Catch::Matchers::StartsWith;
using Event = FragmentSource::Event;
namespace fs = std::filesystem;

namespace {

struct TempDir : rbcd::test::TempDir {
    TempDir() : rbcd::test::TempDir("rbcd_io_test") {}
};

using test::slurp;

std::vector<MemorySource::Item> read_path(const std::string& path, const TraceLimits& lim = {}) {
    TraceReader r(path, lim);
    MemorySource m(r.header());
    m.read_all(r);
    Tile t;
    REQUIRE(r.next(t) == Event::End);   // End stays End
    return m.items();
}

// The message of the InputError that reading `content` (as file `name`) raises,
// with the temp dir stripped so that it reads "name:LINE: ...".
std::string error_in_path(const std::string& path, const std::string& shown, const TraceLimits& lim = {}) {
    try {
        TraceReader r(path, lim);
        Tile t;
        while (r.next(t) != Event::End) {
        }
    } catch (const InputError& e) {
        std::string msg = e.what();
        if (msg.compare(0, path.size(), path) == 0) msg = shown + msg.substr(path.size());
        return msg;
    }
    return "<no error>";
}

std::string error_of(const std::string& content, const TraceLimits& lim = {}) {
    TempDir d;
    return error_in_path(d.write("t.rbt", content), "t.rbt", lim);
}

const std::string M = "rbcd-trace 1\n";

#define CHECK_ERR(content, line, what)                                                 \
    do {                                                                               \
        const std::string msg_ = error_of(content);                                    \
        CHECK_THAT(msg_, StartsWith("t.rbt:" #line ": ") && Contains(what));           \
        CHECK(msg_.find('\n') == std::string::npos);                                   \
    } while (0)

#define CHECK_ERR_LIM(content, lim, line, what)                                        \
    do {                                                                               \
        const std::string msg_ = error_of(content, lim);                               \
        CHECK_THAT(msg_, StartsWith("t.rbt:" #line ": ") && Contains(what));           \
    } while (0)

Fragment frag(std::uint32_t x, std::uint32_t y, std::uint32_t d, std::uint32_t id, Facing f, bool c = false) {
    Fragment r;
    r.x = x;
    r.y = y;
    r.depth = d;
    r.id = id;
    r.facing = f;
    r.culled = c;
    return r;
}

// A fragment as text, "x,y,depth,id,F|B[,c];", for comparing whole reads.
std::string frag_text(const Fragment& f) {
    return std::to_string(f.x) + "," + std::to_string(f.y) + "," + std::to_string(f.depth) + "," +
           std::to_string(f.id) + (f.facing == Facing::Back ? ",B" : ",F") + (f.culled ? ",c;" : ";");
}

void check_frag(const Fragment& got, const Fragment& want) {
    CHECK(got.x == want.x);
    CHECK(got.y == want.y);
    CHECK(got.depth == want.depth);
    CHECK(got.id == want.id);
    CHECK(got.facing == want.facing);
    CHECK(got.culled == want.culled);
}

} // namespace

// ---------------------------------------------------------------- valid input

TEST_CASE("io: spec example with default headers", "[io][reader]") {
    TempDir d;
    auto p = d.write("t.rbt", M + "frame 0\ntile 3 7 other=120\nf 53 119 8388607 5 F\nf 53 119 9000000 5 B c\n");
    TraceReader r(p, {});
    CHECK(r.name() == p);
    CHECK(r.header().screen_w == 800);
    CHECK(r.header().screen_h == 480);
    CHECK(r.header().tile_w == 16);
    CHECK(r.header().tile_h == 16);
    CHECK(r.header().depth_bits == 24);
    Tile t;
    t.col = 99;
    REQUIRE(r.next(t) == Event::Frame);
    CHECK(t.frame == 0);
    CHECK(t.col == 99);   // a Frame event leaves the rest alone
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.frame == 0);
    CHECK(t.col == 3);
    CHECK(t.row == 7);
    CHECK(t.other == 120);
    CHECK_FALSE(t.has_base);
    REQUIRE(t.frags.size() == 2);
    check_frag(t.frags[0], frag(53, 119, 8388607, 5, Facing::Front));
    check_frag(t.frags[1], frag(53, 119, 9000000, 5, Facing::Back, true));
    CHECK(r.next(t) == Event::End);
    CHECK(r.next(t) == Event::End);
}

TEST_CASE("io: headers set screen, tile size and depth bits", "[io][reader]") {
    TempDir d;
    TraceLimits lim;
    lim.tile_w = 8;
    lim.tile_h = 4;
    lim.id_bits = 3;
    auto p = d.write("t.rbt", M + "depth_bits 12\nscreen 100 50\ntile_size 8 4\nframe 0\ntile 12 12\nf 99 49 4095 7 B\n");
    TraceReader r(p, lim);
    CHECK(r.header().screen_w == 100);
    CHECK(r.header().screen_h == 50);
    CHECK(r.header().tile_w == 8);
    CHECK(r.header().tile_h == 4);
    CHECK(r.header().depth_bits == 12);
    Tile t;
    REQUIRE(r.next(t) == Event::Frame);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.col == 12);
    CHECK(t.row == 12);
    REQUIRE(t.frags.size() == 1);
    check_frag(t.frags[0], frag(99, 49, 4095, 7, Facing::Back));
    CHECK(r.next(t) == Event::End);
}

TEST_CASE("io: header limits: extremes accepted", "[io][reader]") {
    TempDir d;
    auto items = read_path(d.write("a.rbt", M + "depth_bits 32\nscreen 65535 65535\nframe 0\ntile 4095 4095\n"
                                               "f 65534 65534 4294967295 0 F\n"));
    REQUIRE(items.size() == 2);
    CHECK(items[1].tile.frags.at(0).depth == 4294967295u);
    CHECK(items[1].tile.frags.at(0).x == 65534u);
    auto one = read_path(d.write("b.rbt", M + "depth_bits 1\nscreen 1 1\nframe 0\ntile 0 0\nf 0 0 1 127 B\n"));
    REQUIRE(one.size() == 2);
    CHECK(one[1].tile.frags.at(0).depth == 1u);
    CHECK(one[1].tile.frags.at(0).id == 127u);
    TraceLimits lim16;
    lim16.id_bits = 16;
    auto wide = read_path(d.write("c.rbt", M + "frame 0\ntile 0 0\nf 0 0 0 65535 F\n"), lim16);
    CHECK(wide.at(1).tile.frags.at(0).id == 65535u);
}

TEST_CASE("io: comments, blank lines, tabs, CRLF, leading zeros, no final newline", "[io][reader]") {
    TempDir d;
    const std::string text =
        "# a comment before the magic\n"
        "\n"
        "rbcd-trace 1   # magic\r\n"
        "\t \n"
        "screen\t64  32\r\n"
        "   # indented comment\n"
        "frame 0#glued comment\n"
        "  tile\t1 0\tother=007  base=0 \r\n"
        "f  00017\t0002 000 1 F   \r\n"
        "f 17 2 0000000000000000000000000000000005 1 B\tc # tagged\r\n"
        "\r\n"
        "f 31 15 16777215 127 F c";
    auto items = read_path(d.write("t.rbt", text));
    REQUIRE(items.size() == 2);
    CHECK(items[0].is_frame);
    CHECK(items[0].tile.frame == 0);
    const Tile& t = items[1].tile;
    CHECK(t.col == 1);
    CHECK(t.row == 0);
    CHECK(t.other == 7);
    CHECK(t.has_base);
    CHECK(t.base == 0);
    REQUIRE(t.frags.size() == 3);
    check_frag(t.frags[0], frag(17, 2, 0, 1, Facing::Front));
    check_frag(t.frags[1], frag(17, 2, 5, 1, Facing::Back, true));
    check_frag(t.frags[2], frag(31, 15, 16777215, 127, Facing::Front, true));
    TraceReader r(d.path("t.rbt"), {});
    CHECK(r.header().screen_w == 64);
    CHECK(r.header().screen_h == 32);
}

TEST_CASE("io: a file of only the magic is zero frames", "[io][reader]") {
    TempDir d;
    for (const char* text : {"rbcd-trace 1\n", "rbcd-trace 1", "rbcd-trace 0001\r\n# nothing else\n\n"}) {
        INFO(text);
        TraceReader r(d.write("t.rbt", text), {});
        CHECK(r.header().screen_w == 800);
        Tile t;
        CHECK(r.next(t) == Event::End);
        CHECK(r.next(t) == Event::End);
    }
}

TEST_CASE("io: empty frames and empty tiles are announced", "[io][reader]") {
    TempDir d;
    auto items = read_path(d.write("t.rbt", M + "frame 0\nframe 1\nframe 2\ntile 0 0\nframe 3\n"));
    REQUIRE(items.size() == 5);
    CHECK(items[0].is_frame);
    CHECK(items[0].tile.frame == 0);
    CHECK(items[1].is_frame);
    CHECK(items[1].tile.frame == 1);
    CHECK(items[2].is_frame);
    CHECK(items[2].tile.frame == 2);
    CHECK_FALSE(items[3].is_frame);
    CHECK(items[3].tile.frame == 2);
    CHECK(items[3].tile.frags.empty());
    CHECK(items[4].is_frame);
    CHECK(items[4].tile.frame == 3);
}

TEST_CASE("io: partial edge tiles accept pixels inside the screen", "[io][reader]") {
    TempDir d;
    auto items = read_path(d.write("t.rbt", M + "screen 20 18\nframe 0\ntile 1 1\nf 19 17 0 1 F\nf 16 16 0 1 B\n"));
    REQUIRE(items.size() == 2);
    REQUIRE(items[1].tile.frags.size() == 2);
    CHECK(items[1].tile.frags[0].x == 19);
    CHECK(items[1].tile.frags[0].y == 17);
}

TEST_CASE("io: tile order is kept and a tile may recur in later frames", "[io][reader]") {
    TempDir d;
    auto items = read_path(d.write("t.rbt", M + "frame 0\ntile 5 3\ntile 0 0\ntile 2 1\nf 32 16 1 2 F\n"
                                              "frame 1\ntile 5 3\ntile 0 0\n"));
    REQUIRE(items.size() == 7);
    const unsigned want[][3] = {{0, 5, 3}, {0, 0, 0}, {0, 2, 1}, {1, 5, 3}, {1, 0, 0}};
    const int at[] = {1, 2, 3, 5, 6};
    for (int i = 0; i < 5; ++i) {
        const Tile& t = items[at[i]].tile;
        CHECK_FALSE(items[at[i]].is_frame);
        CHECK(t.frame == want[i][0]);
        CHECK(t.col == want[i][1]);
        CHECK(t.row == want[i][2]);
    }
    CHECK(items[3].tile.frags.size() == 1);
    CHECK(items[1].tile.frags.empty());
}

TEST_CASE("io: tile fields other= and base=, and the tile is fully overwritten", "[io][reader]") {
    TempDir d;
    auto p = d.write("t.rbt", M + "frame 0\ntile 0 0 base=0\ntile 1 0 base=99 other=5\n"
                                  "tile 2 0 other=1099511627776\ntile 3 0\n");
    TraceReader r(p, {});
    Tile t;
    REQUIRE(r.next(t) == Event::Frame);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.has_base);
    CHECK(t.base == 0);
    CHECK(t.other == 0);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.has_base);
    CHECK(t.base == 99);
    CHECK(t.other == 5);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK_FALSE(t.has_base);
    CHECK(t.base == 0);
    CHECK(t.other == 1099511627776ull);   // 2^40, the largest accepted
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.col == 3);
    CHECK(t.other == 0);
    CHECK(r.next(t) == Event::End);
}

TEST_CASE("io: tile key shade= is read, and the tile after it is back to 100", "[io][reader]") {
    TempDir d;
    auto p = d.write("t.rbt", M + "frame 0\ntile 0 0 shade=250 other=3\ntile 1 0\ntile 2 0 shade=1\n");
    TraceReader r(p, {});
    Tile t;
    REQUIRE(r.next(t) == Event::Frame);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.has_shade);
    CHECK(t.shade == 250);
    CHECK(fragment_cycles(8, t) == 20);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK_FALSE(t.has_shade);
    CHECK(t.shade == 100);
    CHECK(fragment_cycles(8, t) == 8);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(fragment_cycles(8, t) == 1);   // 0.08 cycles: at least one
}

TEST_CASE("io: tile keys prims= and cprims= and o records give the rasterization order", "[io][reader]") {
    TempDir d;
    auto p = d.write("t.rbt", M + "frame 0\ntile 0 0 prims=7 cprims=3\no 4\nf 1 1 10 1 F\no 2\no 1\n"
                                  "f 2 1 10 1 B c\no 5\ntile 1 0 other=9\nf 17 1 10 1 F\n");
    TraceReader r(p, {});
    Tile t;
    REQUIRE(r.next(t) == Event::Frame);
    REQUIRE(r.next(t) == Event::Tile);
    CHECK(t.has_prims);
    CHECK(t.has_cprims);
    CHECK(t.prims == 7);
    CHECK(t.cprims == 3);
    CHECK(t.ordered_other);
    CHECK(t.other == 4 + 2 + 1 + 5);
    REQUIRE(t.other_runs.size() == 4);
    CHECK(t.other_runs[0].before == 0);   // before the first fragment
    CHECK(t.other_runs[0].count == 4);
    CHECK(t.other_runs[1].before == 1);
    CHECK(t.other_runs[2].before == 1);
    CHECK(t.other_runs[3].before == 2);   // after the last
    CHECK(t.other_runs[3].count == 5);
    // The next tile starts afresh: no keys, no order.
    REQUIRE(r.next(t) == Event::Tile);
    CHECK_FALSE(t.has_prims);
    CHECK_FALSE(t.has_cprims);
    CHECK(t.prims == 0);
    CHECK_FALSE(t.ordered_other);
    CHECK(t.other_runs.empty());
    CHECK(t.other == 9);
    CHECK(r.next(t) == Event::End);
}

TEST_CASE("io: error: o records and the GPU tile keys", "[io][reader][error]") {
    CHECK_ERR(M + "frame 0\ntile 0 0 other=3\no 2\n", 4, "tile has both other= and 'o' records");
    CHECK_ERR(M + "frame 0\no 2\n", 3, "'o' record outside a tile");
    CHECK_ERR(M + "frame 0\ntile 0 0\no\n", 4, "o has too few fields");
    CHECK_ERR(M + "frame 0\ntile 0 0\no 1 2\n", 4, "o has an extra field");
    CHECK_ERR(M + "frame 0\ntile 0 0\no -1\n", 4, "o count");
    CHECK_ERR(M + "frame 0\ntile 0 0 prims=1 prims=2\n", 3, "tile key 'prims' given twice");
    CHECK_ERR(M + "frame 0\ntile 0 0 cprims=x\n", 3, "tile cprims=");
}

TEST_CASE("io: the fragment vector is reused across tiles", "[io][reader]") {
    TempDir d;
    std::string text = M + "frame 0\ntile 0 0\n";
    for (int i = 0; i < 100; ++i) text += "f " + std::to_string(i % 16) + " " + std::to_string(i / 16) + " 9 1 F\n";
    text += "tile 1 0\nf 16 0 1 2 B\n";
    TraceReader r(d.write("t.rbt", text), {});
    Tile t;
    REQUIRE(r.next(t) == Event::Frame);
    REQUIRE(r.next(t) == Event::Tile);
    REQUIRE(t.frags.size() == 100);
    check_frag(t.frags[99], frag(3, 6, 9, 1, Facing::Front));
    const Fragment* storage = t.frags.data();
    const std::size_t cap = t.frags.capacity();
    REQUIRE(r.next(t) == Event::Tile);
    REQUIRE(t.frags.size() == 1);
    CHECK(t.frags.capacity() == cap);
    CHECK(t.frags.data() == storage);
    check_frag(t.frags[0], frag(16, 0, 1, 2, Facing::Back));
}

TEST_CASE("io: traces bigger than the read buffer parse and count lines across chunks", "[io][reader]") {
    TempDir d;
    // ~4.5 MB: several 1 MiB chunks, lines split at chunk edges.
    std::string text = M;
    std::uint64_t want_sum = 0, want_frags = 0;
    unsigned frames = 0;
    for (unsigned fr = 0; fr < 6; ++fr, ++frames) {
        text += "frame " + std::to_string(fr) + "\n";
        for (unsigned tc = 0; tc < 40; ++tc) {
            text += "tile " + std::to_string(tc) + " " + std::to_string(fr) + " other=" + std::to_string(tc) + "\n";
            for (unsigned i = 0; i < 800; ++i) {
                unsigned x = tc * 16 + i % 16, y = fr * 16 + (i / 16) % 16, depth = (i * 2654435761u) & 0xffffff;
                text += "f " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(depth) + " " +
                        std::to_string(i % 128) + (i & 1 ? " B\n" : " F c\n");
                want_sum += x + 3ull * y + 5ull * depth + 7ull * (i % 128) + (i & 1) * 11 + (i & 1 ? 0 : 13);
                ++want_frags;
            }
        }
    }
    REQUIRE(text.size() > 4u * 1024 * 1024);
    auto items = read_path(d.write("big.rbt", text));
    std::uint64_t sum = 0, frags = 0, tiles = 0, frame_events = 0;
    for (const auto& it : items) {
        if (it.is_frame) { ++frame_events; continue; }
        ++tiles;
        CHECK(it.tile.other == it.tile.col);
        for (const auto& f : it.tile.frags) {
            sum += f.x + 3ull * f.y + 5ull * f.depth + 7ull * f.id + (f.facing == Facing::Back ? 11 : 0) +
                   (f.culled ? 13 : 0);
            ++frags;
        }
    }
    CHECK(frame_events == frames);
    CHECK(tiles == 240);
    CHECK(frags == want_frags);
    CHECK(sum == want_sum);

    // An error deep inside names its exact line.
    std::size_t lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
    std::string bad = text + "f 0 0 0 0 F\n";   // tile 39 5 does not hold pixel 0 0
    CHECK_THAT(error_in_path(d.write("bad.rbt", bad), "bad.rbt"),
               Equals("bad.rbt:" + std::to_string(lines + 1) + ": fragment x=0 outside tile 39 5 (x 624..639)"));
}

TEST_CASE("io: a line longer than the read buffer is handled", "[io][reader]") {
    TempDir d;
    std::string text = M + "# " + std::string(3u << 20, 'z') + "\nframe 0\ntile 0 0\nf 1 1 1 1 F\n";
    TraceLimits big;
    big.max_line_bytes = 4u << 20;
    auto items = read_path(d.write("t.rbt", text), big);
    REQUIRE(items.size() == 2);
    CHECK(items[1].tile.frags.at(0).x == 1);
    CHECK_THAT(error_of(text + "f 99 0 0 1 F\n", big), Equals("t.rbt:6: fragment x=99 outside tile 0 0 (x 0..15)"));
    // A fragment line padded past the buffer with leading zeros and blanks.
    std::string padded = M + "frame 0\ntile 0 0\nf " + std::string(2u << 20, '0') + "7" + std::string(1u << 20, ' ') +
                         "3 0 1 F\n";
    auto p = read_path(d.write("p.rbt", padded), big);
    CHECK(p.at(1).tile.frags.at(0).x == 7);
    CHECK(p.at(1).tile.frags.at(0).y == 3);
}

// ---------------------------------------------------------------- gzip

namespace {
// One zstd frame of `content` (level 3).
std::string zstd_frame(const std::string& content) {
    std::string out(ZSTD_compressBound(content.size()), '\0');
    const std::size_t n = ZSTD_compress(out.data(), out.size(), content.data(), content.size(), 3);
    REQUIRE_FALSE(ZSTD_isError(n));
    out.resize(n);
    return out;
}
} // namespace

TEST_CASE("io: zstd input is recognised by its bytes; frames are one stream", "[io][reader][zstd]") {
    TempDir d;
    const std::string head = M + "screen 32 32\nframe 0\ntile 1 1 other=3 base=44\nf 16 17 100 9 F\n";
    const std::string rest = "f 16 17 200 9 B c\nframe 1\n";
    const auto plain = read_path(d.write("plain.rbt", head + rest));
    for (const char* name : {"t.rbt.zst", "misleading.rbt.gz", "noext"}) {
        INFO(name);
        // Two frames, the text cut between them anywhere: one stream.
        auto p = d.write(name, zstd_frame(head) + zstd_frame(rest));
        REQUIRE(slurp(p).substr(0, 4) == "\x28\xb5\x2f\xfd");
        auto items = read_path(p);
        REQUIRE(items.size() == plain.size());
        REQUIRE(items[1].tile.frags.size() == 2);
        CHECK(items[1].tile.base == 44);
        check_frag(items[1].tile.frags[1], frag(16, 17, 200, 9, Facing::Back, true));
        CHECK(plain_trace_bytes(p) == 0);   // no byte offsets for --jobs to jump to
    }
}

TEST_CASE("io: error: a zstd trace cut short, or with bytes after its last frame", "[io][reader][zstd][error]") {
    const std::string z = zstd_frame(M + "frame 0\ntile 0 0\nf 1 1 5 1 F\n");
    CHECK_THAT(error_of(z.substr(0, z.size() - 3)), StartsWith("t.rbt:") &&
                                                      Contains(": corrupt or truncated zstd stream: unexpected end of file"));
    CHECK_THAT(error_of(z + "garbage\n"),
               StartsWith("t.rbt:") && Contains(": corrupt or truncated zstd stream: Unknown frame descriptor"));
}

TEST_CASE("io: gzip input is recognised by its bytes, not its name", "[io][reader][gzip]") {
    TempDir d;
    std::string text = M + "screen 32 32\nframe 0\ntile 1 1 other=3 base=44\nf 16 17 100 9 F\nf 16 17 200 9 B c\nframe 1\n";
    auto plain = read_path(d.write("plain.rbt", text));
    for (const char* name : {"t.rbt.gz", "misleading.rbt", "noext"}) {
        INFO(name);
        auto p = d.write_gz(name, text);
        REQUIRE(slurp(p).substr(0, 2) == "\x1f\x8b");
        TraceReader r(p, {});
        CHECK(r.header().screen_w == 32);
        auto items = read_path(p);
        REQUIRE(items.size() == 3);
        CHECK(items[1].tile.base == 44);
        CHECK(items[1].tile.other == 3);
        REQUIRE(items[1].tile.frags.size() == 2);
        check_frag(items[1].tile.frags[1], frag(16, 17, 200, 9, Facing::Back, true));
        CHECK(items[2].tile.frame == 1);
    }
    // A plain file named .gz is still plain.
    auto items = read_path(d.write("plain.gz", text));
    CHECK(items.size() == plain.size());
}

TEST_CASE("io: a big gzip trace reads the same as the plain one", "[io][reader][gzip]") {
    TempDir d;
    std::string text = M + "frame 0\n";
    for (unsigned c = 0; c < 50; ++c) {
        text += "tile " + std::to_string(c) + " 0\n";
        for (unsigned i = 0; i < 2000; ++i)
            text += "f " + std::to_string(c * 16 + i % 16) + " " + std::to_string(i % 16) + " " +
                    std::to_string(i * 7919 % 16777216) + " " + std::to_string(i % 100) + " F\n";
    }
    auto a = read_path(d.write("a.rbt", text));
    auto b = read_path(d.write_gz("b.rbt", text));
    REQUIRE(a.size() == b.size());
    REQUIRE(a.size() == 51);
    for (std::size_t i = 1; i < a.size(); ++i) {
        REQUIRE(a[i].tile.frags.size() == 2000);
        REQUIRE(b[i].tile.frags.size() == 2000);
        CHECK(a[i].tile.frags[1999].depth == b[i].tile.frags[1999].depth);
        CHECK(b[i].tile.frags[1999].depth == 1999u * 7919u % 16777216u);
    }
}

TEST_CASE("io: gzip: truncated and corrupt streams are errors naming file and line", "[io][reader][gzip]") {
    TempDir d;
    const std::string small = M + "frame 0\nframe 1\n";
    std::string gz = slurp(d.write_gz("s.gz", small));

    // Trailer cut: all text decodes, the stream ends early after line 3.
    d.write("cut.rbt", gz.substr(0, gz.size() - 4));
    CHECK_THAT(error_in_path(d.path("cut.rbt"), "cut.rbt"),
               Equals("cut.rbt:4: corrupt or truncated gzip stream: unexpected end of file"));

    // Bad CRC in the trailer: zlib withholds the chunk that fails the check,
    // so here nothing at all was read.
    std::string crc = gz;
    crc[crc.size() - 8] = static_cast<char>(crc[crc.size() - 8] ^ 0x55);
    d.write("crc.rbt", crc);
    CHECK_THAT(error_in_path(d.path("crc.rbt"), "crc.rbt"),
               Equals("crc.rbt:1: corrupt or truncated gzip stream: incorrect data check"));

    // Unknown compression method in the gzip header: nothing decodes.
    std::string method = gz;
    method[2] = 7;
    d.write("method.rbt", method);
    CHECK_THAT(error_in_path(d.path("method.rbt"), "method.rbt"),
               Equals("method.rbt:1: corrupt or truncated gzip stream: unknown compression method"));

    // Cut in the middle of a big stream: the line is the one being read when
    // the data ran out (counted here from what zlib can decode of the prefix).
    std::string text = M + "frame 0\ntile 0 0\n";
    for (unsigned i = 0; i < 300000; ++i)
        text += "f " + std::to_string(i % 16) + " " + std::to_string(i / 16 % 16) + " " + std::to_string(i) + " 1 F\n";
    std::string big = slurp(d.write_gz("big.gz", text));
    auto half = d.write("half.rbt", big.substr(0, big.size() / 2));
    std::size_t decoded_lines = 0;
    {
        gzFile g = gzopen(half.c_str(), "rb");
        REQUIRE(g != nullptr);
        std::vector<char> b(1 << 16);
        int n;
        while ((n = gzread(g, b.data(), static_cast<unsigned>(b.size()))) > 0)
            decoded_lines += static_cast<std::size_t>(std::count(b.data(), b.data() + n, '\n'));
        gzclose(g);
    }
    REQUIRE(decoded_lines > 1000);
    REQUIRE(decoded_lines < 300000);
    CHECK_THAT(error_in_path(half, "half.rbt"),
               StartsWith("half.rbt:" + std::to_string(decoded_lines + 1) + ": corrupt or truncated gzip stream"));
}

// ---------------------------------------------------------------- round trip

TEST_CASE("io: writer output reads back as the identical stream", "[io][writer]") {
    TempDir d;
    StreamHeader h;
    h.screen_w = 200;   // 12.5 tiles: the last column is partial
    h.screen_h = 100;
    h.depth_bits = 20;
    MemorySource src(h);
    std::uint64_t s = 12345;
    auto rnd = [&s](std::uint64_t n) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return (s >> 33) % n;
    };
    std::size_t total = 0;
    for (std::uint64_t fr = 0; fr < 5; ++fr) {
        src.add_frame(fr);
        if (fr == 2) continue;   // an empty frame
        for (unsigned cell = 0; cell < 13 * 7; ++cell) {
            if (rnd(3) == 0) continue;
            Tile t;
            t.frame = fr;
            t.col = cell % 13;
            t.row = cell / 13;
            t.other = rnd(4) == 0 ? 0 : rnd(4) == 0 ? 1099511627776ull : rnd(100000);
            t.has_base = rnd(2) == 0;
            t.base = t.has_base ? rnd(1000000) : 0;
            const unsigned x0 = t.col * 16, y0 = t.row * 16;
            const unsigned w = std::min(16u, 200 - x0), hh = std::min(16u, 100 - y0);
            const std::size_t n = rnd(60);
            for (std::size_t i = 0; i < n; ++i)
                t.frags.push_back(frag(x0 + static_cast<unsigned>(rnd(w)), y0 + static_cast<unsigned>(rnd(hh)),
                                       i == 0 ? (1u << 20) - 1 : static_cast<std::uint32_t>(rnd(1u << 20)),
                                       static_cast<std::uint32_t>(rnd(128)), rnd(2) ? Facing::Back : Facing::Front,
                                       rnd(5) == 0));
            total += n;
            src.add_tile(std::move(t));
        }
    }
    REQUIRE(total > 1000);
    const std::string p = d.path("rt.rbt");
    {
        TraceWriter w(p, h);
        Tile t;
        src.rewind();
        for (;;) {
            auto ev = src.next(t);
            if (ev == Event::End) break;
            if (ev == Event::Frame) w.frame(t.frame);
            else w.tile(t);
        }
        w.close();
        w.close();   // closing twice is harmless
    }
    TraceReader r(p, {});
    CHECK(r.header().screen_w == 200);
    CHECK(r.header().screen_h == 100);
    CHECK(r.header().tile_w == 16);
    CHECK(r.header().depth_bits == 20);
    MemorySource back(r.header());
    back.read_all(r);
    const auto& a = src.items();
    const auto& b = back.items();
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        INFO("item " << i);
        REQUIRE(a[i].is_frame == b[i].is_frame);
        CHECK(a[i].tile.frame == b[i].tile.frame);
        if (a[i].is_frame) continue;
        CHECK(a[i].tile.col == b[i].tile.col);
        CHECK(a[i].tile.row == b[i].tile.row);
        CHECK(a[i].tile.other == b[i].tile.other);
        CHECK(a[i].tile.has_base == b[i].tile.has_base);
        CHECK(a[i].tile.base == b[i].tile.base);
        REQUIRE(a[i].tile.frags.size() == b[i].tile.frags.size());
        for (std::size_t k = 0; k < a[i].tile.frags.size(); ++k) check_frag(b[i].tile.frags[k], a[i].tile.frags[k]);
    }
}

TEST_CASE("io: writer text has the documented shape", "[io][writer]") {
    TempDir d;
    StreamHeader h;
    const std::string p = d.path("w.rbt");
    TraceWriter w(p, h);
    w.frame(0);
    Tile t;
    t.col = 3;
    t.row = 7;
    t.other = 120;
    t.frags = {frag(53, 119, 8388607, 5, Facing::Front), frag(53, 119, 9000000, 5, Facing::Back, true)};
    w.tile(t);
    t.col = 4;
    t.other = 0;
    t.has_base = true;
    t.base = 77;
    t.frags.clear();
    w.tile(t);
    w.close();
    CHECK(slurp(p) == "rbcd-trace 1\nscreen 800 480\ntile_size 16 16\ndepth_bits 24\nframe 0\n"
                      "tile 3 7 other=120\nf 53 119 8388607 5 F\nf 53 119 9000000 5 B c\n"
                      "tile 4 7 other=0 base=77\n");
}

TEST_CASE("io: writer errors name the file", "[io][writer]") {
    TempDir d;
    const std::string p = d.path("no/such/dir/w.rbt");
    CHECK_THROWS_WITH(TraceWriter(p, StreamHeader{}), StartsWith(p + ": cannot create: ") &&
                                                          Contains("No such file or directory"));
    if (fs::exists("/dev/full")) {
        TraceWriter w("/dev/full", StreamHeader{});
        w.frame(0);
        CHECK_THROWS_WITH(w.close(), StartsWith("/dev/full: write failed: ") && Contains("No space left on device"));
    }
}

// ---------------------------------------------------------------- errors

TEST_CASE("io: error: file cannot be opened", "[io][reader][error]") {
    TempDir d;
    const std::string p = d.path("missing.rbt");
    CHECK_THROWS_WITH(TraceReader(p, {}), Equals(p + ": cannot read trace: No such file or directory"));
    CHECK_THROWS_WITH(TraceReader(d.dir, {}),
                      Equals(d.dir + ": cannot read trace: is a directory, not a regular file (use - for standard input)"));
}

// ---------------------------------------------------------------- hostile input (issue 12)

TEST_CASE("io: hostile: devices and FIFOs are refused, not read", "[io][reader][error][hostile]") {
    // /dev/zero must not be read: the line buffer would grow until std::bad_alloc.
    CHECK_THROWS_WITH(TraceReader("/dev/zero", {}), Equals("/dev/zero: cannot read trace: is a character device, not "
                                                          "a regular file (use - for standard input)"));
    TempDir d;
    const std::string fifo = d.path("f");
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_THROWS_WITH(TraceReader(fifo, {}), Contains("cannot read trace: is a FIFO, not a regular file"));
}

TEST_CASE("io: hostile: a line longer than input.max_line_bytes is refused naming the key", "[io][reader][error][hostile]") {
    TraceLimits lim;
    lim.max_line_bytes = 1000;
    lim.read_chunk = 64;
    const std::string ok = M + "# " + std::string(990, 'z') + "\nframe 0\n";
    CHECK(error_of(ok, lim) == "<no error>");
    const std::string msg = error_of(M + "frame 0\n# " + std::string(5000, 'z') + "\n", lim);
    CHECK_THAT(msg, StartsWith("t.rbt:3: line longer than 1000 bytes") && Contains("input.max_line_bytes"));
}

TEST_CASE("io: hostile: a gzip bomb of zeros ends at the line limit in bounded memory", "[io][reader][error][hostile]") {
    // 64 MiB of NUL bytes inflate from a few tens of KiB: one endless line.
    TempDir d;
    const std::string p = d.write_gz("bomb.rbt", M + std::string(64u << 20, '\0'));
    CHECK(fs::file_size(p) < (1u << 20));
    CHECK_THAT(error_in_path(p, "bomb.rbt"), StartsWith("bomb.rbt:2: line longer than 1048576 bytes") &&
                                                 Contains("input.max_line_bytes"));
}

TEST_CASE("io: hostile: a tile with more than input.max_tile_fragments fragments is refused", "[io][reader][error][hostile]") {
    TraceLimits lim;
    lim.max_tile_fragments = 3;
    std::string t = M + "frame 0\ntile 0 0\nf 0 0 1 1 F\nf 0 0 2 1 F\nf 0 0 3 1 F\n";
    CHECK(error_of(t, lim) == "<no error>");
    CHECK_THAT(error_of(t + "f 0 0 4 1 F\n", lim),
               Equals("t.rbt:7: tile 0 0 has more than 3 fragments (the limit input.max_tile_fragments; docs/limits.md)"));
    // The slow path (a comment on the line) is bounded too.
    CHECK_THAT(error_of(t + "f 0 0 4 1 F # x\n", lim), StartsWith("t.rbt:7: tile 0 0 has more than 3 fragments"));
}

TEST_CASE("io: hostile: declared work that would overflow simulated time is refused naming clock.mhz",
          "[io][reader][error][hostile]") {
    // other=2^40 on enough tiles would wrap totals.cycles around 2^64 ps.
    SimConfig cfg;
    const TraceLimits lim = trace_limits(cfg);
    REQUIRE(lim.max_work_cycles == (std::uint64_t(1) << 62) / 2500 / 4);
    std::string t = M + "screen 2048 2048\nframe 0\n";
    for (int i = 0; i < 200; ++i) t += "tile " + std::to_string(i % 128) + " " + std::to_string(i / 128) + " other=1099511627776\n";
    const std::string msg = error_of(t, lim);
    CHECK_THAT(msg, Contains("the run is too long to simulate") && Contains("clock.mhz = 400") &&
                        Contains("docs/limits.md"));
    // The same trace at a few tiles is fine.
    CHECK(error_of(M + "frame 0\ntile 0 0 other=1099511627776 base=1099511627776\n", lim) == "<no error>");
}

TEST_CASE("io: hostile: bytes after the last gzip member are an error", "[io][reader][error][hostile][gzip]") {
    TempDir d;
    const std::string text = M + "frame 0\ntile 0 0\nf 0 0 1 1 F\n";
    const std::string gz = slurp(d.write_gz("a.gz", text));
    // Two members are one stream.
    auto two = read_path(d.write("two.rbt", gz + slurp(d.write_gz("b.gz", "frame 1\n"))));
    CHECK(two.size() == 3);
    for (const std::string& tail : {std::string("x"), std::string("\n"), std::string(100, '\0'), std::string("\x1f")}) {
        const std::string p = d.write("tail.rbt", gz + tail);
        CHECK_THAT(error_in_path(p, "tail.rbt"), Contains("bytes after the last gzip member"));
    }
}

TEST_CASE("io: hostile: every read chunk size gives the same stream (refill boundaries)", "[io][reader][hostile]") {
    TempDir d;
    std::string text = M + "screen 64 64\n# comment\r\nframe 0\ntile 1 1 other=3\nf 16 17 100 9 F\nf 16 17 200 9 B c\n"
                           "tile 0 0\nf 0 0 5 1 F # tail\nframe 1\ntile 2 2\nf 33 34 7 2 B";
    const auto want = read_path(d.write("ref.rbt", text));
    const std::string plain = d.write("p.rbt", text), gz = d.write_gz("g.rbt", text);
    const std::string zst = d.write("z.rbt", zstd_frame(text.substr(0, 40)) + zstd_frame(text.substr(40)));
    for (std::size_t chunk : {1u, 2u, 3u, 7u, 64u}) {
        INFO("chunk " << chunk);
        TraceLimits lim;
        lim.read_chunk = chunk;
        for (const auto& p : {plain, gz, zst}) {
            const auto got = read_path(p, lim);
            REQUIRE(got.size() == want.size());
            for (std::size_t i = 0; i < got.size(); ++i) CHECK(got[i].tile.frags.size() == want[i].tile.frags.size());
        }
    }
}

// The usual fragment line is parsed from its 32 bytes at once when at least 40
// bytes of whole lines follow its start; a line at the end of the buffered
// data goes byte by byte. Both must read every line alike: the fragment, or
// the same error.
TEST_CASE("io: a fragment line reads the same with and without 40 bytes after it (whole-line path)", "[io][reader]") {
    const std::vector<std::string> lines = {
        "f 16 0 0 1 F", "f 31 15 16777215 127 B c", "f 16 0 12345678 1 F", "f 16 0 1234567 1 B",
        "f 16 0 00000001 1 F", "f 0016 00015 000000001 0000127 B c", "f 16 0 99999999 1 F",
        "f 16  0 5 1 F", "f  16 0 5 1 F", "f 16 0 5 1  F", "f 16 0 5 1 F  c", "f 16\t0 5 1 F", "f\t16 0 5 1 F",
        "f 16 0 5 1 F\r", "f 16 0 5 1 F c\r", "f 16 0 5 1 F # note", "f 16 0 5 1 F#note", "f 16 0 5 1 F c#x",
        "f 16 0 5 1 F ", "f 16 0 5 1 F c ", "f 16 0 5 1 F c c", "f 16 0 5 1 Fc", "f 16 0 5 1 X", "f 16 0 5 1 f",
        "f 16 0 5 1 F d", "f 16 0 5 1 F C", "f 16 0 5 1 FB", "f 16 0 5 1 0", "f 40 0 0 1 F", "f 15 0 0 1 F",
        "f 16 16 0 1 F", "f 16 0 16777216 1 F", "f 16 0 123456789 1 F", "f 16 0 0 128 F", "f 16 0 1a 1 F",
        "f 16 0 +5 1 F", "f 16 0 5", "f 16 0 5 1", "f 16 0 5 1 # F", "f 16 0 5 1 F c x", "f 1\x80 0 5 1 F",
        "f 16 0 5\x001 F", "f 16 0 0x10 1 F", "f 16 0 18446744073709551616 1 F", "f 16 0 5 1 F\x0bc"};
    const std::string head = M + "frame 0\ntile 1 0\n", tail = "# " + std::string(60, 'x') + "\n";
    const auto outcome = [](const std::string& text, bool wide = true) -> std::string {
        TempDir d;
        const std::string path = d.write("t.rbt", text);
        try {
            TraceLimits lim;
            lim.wide_parse = wide;
            TraceReader r(path, lim);
            Tile t;
            std::string s;
            while (r.next(t) != Event::End)
                for (const Fragment& f : t.frags) s += frag_text(f);
            return s;
        } catch (const InputError& e) {
            std::string msg = e.what();
            return "error " + msg.substr(msg.find(':'));
        }
    };
    for (const std::string& l : lines) {
        INFO(l);
        const std::string alone = outcome(head + l + "\n"), followed = outcome(head + l + "\n" + tail);
        CHECK(alone == followed);
        // The AVX-512 whole-line parse (where this CPU has it) and the portable one alike.
        CHECK(outcome(head + l + "\n" + tail, false) == followed);
        // And between two usual lines, each read on the whole-line path.
        const std::string ok = "f 17 1 7 2 B\n";
        const std::string between = outcome(head + ok + l + "\n" + ok + tail);
        CHECK(outcome(head + ok + l + "\n" + ok) == between);
        CHECK(outcome(head + ok + l + "\n" + ok + tail, false) == between);
    }
    CHECK(outcome(head + "f 31 15 16777215 127 B c\n" + tail) == "31,15,16777215,127,B,c;");
    CHECK(outcome(head + "f 0016 00015 000000001 0000127 B c\n" + tail) == "16,15,1,127,B,c;");
}

// Random fragment lines, most of them the usual shape and some bent by one
// byte (a digit too many, a separator doubled or changed, a value just outside
// its bound), read with the AVX-512 whole-line parse and with the portable
// one: the same fragments, or the same error at the same line.
TEST_CASE("io: the AVX-512 and portable whole-line parses read random lines alike", "[io][reader]") {
    if (!trace_wide_parse_available())
        WARN("this CPU has no AVX-512 (F, BW, VL, VBMI, VBMI2): both reads below use the portable parse, "
             "so the comparison is skipped in effect");
    std::uint64_t seed = 0x9e3779b97f4a7c15ull;
    const auto rnd = [&](std::uint64_t n) {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        return seed % n;
    };
    const auto zeros = [&](std::uint64_t one_in, std::uint64_t most) {
        return std::string(rnd(one_in) == 0 ? rnd(most + 1) : 0, '0');
    };
    const std::string bytes = " \t\r#cFB0123456789x\x80";
    TempDir d;
    for (int file = 0; file < 60; ++file) {
        // Screen 65519 x 60 with 16 x 16 tiles: x has up to five digits, and
        // the last column and row are clipped (15 and 12 pixels).
        // 32-bit depths have nine and ten digits too, which the whole-line
        // parses leave to the byte-by-byte path.
        const unsigned depth_bits = file % 4 == 0 ? 32 : rnd(4) == 0 ? 20 + static_cast<unsigned>(rnd(13)) : 24;
        std::string text = M + "screen 65519 60\ndepth_bits " + std::to_string(depth_bits) + "\nframe 0\n";
        TraceLimits lim;
        // Object ids of 32 bits (eight-digit ids in reach) in a fifth of the files.
        lim.id_bits = file % 5 == 1 ? 32 : rnd(4) == 0 ? 1 + static_cast<unsigned>(rnd(16)) : 7;
        lim.max_tile_fragments = 1u << 20;
        // One line of a third of the files bent by a byte, of another third
        // given a coordinate outside its tile (beyond either edge).
        const int bent = file % 3 == 2 ? -1 : static_cast<int>(rnd(1200));
        for (int tile = 0; tile < 4; ++tile) {
            const bool edge = tile == 0 && file % 2 == 0;
            const std::uint64_t col = edge ? 4094 : rnd(4094), row = edge ? 3 : rnd(4);
            const std::uint64_t w = col == 4094 ? 15 : 16, h = row == 3 ? 12 : 16;
            text += "tile " + std::to_string(col) + " " + std::to_string(row) + "\n";
            for (int i = 0; i < 300; ++i) {
                const bool outside = file % 3 == 1 && tile * 300 + i == bent;
                std::uint64_t x = col * 16 + rnd(w), y = row * 16 + rnd(h);
                if (outside) {
                    std::uint64_t& v = rnd(2) ? x : y;
                    const std::uint64_t lo = &v == &x ? col * 16 : row * 16, n = &v == &x ? w : h;
                    v = rnd(2) && lo > 0 ? lo - 1 - rnd(std::min<std::uint64_t>(lo, 3)) : lo + n + rnd(3);
                }
                const std::uint64_t id = rnd(lim.id_bits == 32 && rnd(3) == 0 ? 100000000 : 128);
                std::string l = "f " + zeros(8, 3) + std::to_string(x) + " " + zeros(8, 6) + std::to_string(y) + " " +
                                zeros(6, 2) +
                                std::to_string(rnd(std::uint64_t(1) << (depth_bits == 32 && rnd(4) == 0 ? 32 : 24))) +
                                " " + zeros(9, 2) + std::to_string(id) + (rnd(2) ? " F" : " B") +
                                (rnd(3) == 0 ? " c" : "");
                if (file % 3 == 0 && tile * 300 + i == bent) l[2 + rnd(l.size() - 2)] = bytes[rnd(bytes.size())];
                text += l + "\n";
            }
        }
        text += "# " + std::string(60, 'x') + "\n";
        INFO("file " << file);
        const std::string path = d.write("r.rbt", text);
        const auto read = [&](bool wide, std::uint64_t& taken) -> std::string {
            TraceLimits l = lim;
            l.wide_parse = wide;
            std::string s;
            std::unique_ptr<TraceReader> r;
            try {
                r = std::make_unique<TraceReader>(path, l);
                Tile t;
                while (r->next(t) != Event::End)
                    for (const Fragment& f : t.frags) s += frag_text(f);
            } catch (const InputError& e) {
                s += std::string("error ") + e.what();
            }
            taken = r ? r->lines_taken_whole() : 0;
            return s;
        };
        std::uint64_t taken_wide = 0, taken_portable = 0;
        const std::string wide = read(true, taken_wide), portable = read(false, taken_portable);
        CHECK(wide == portable);
        // The same lines taken whole: neither parse leaves to the slow path a
        // line the other takes.
        CHECK(taken_wide == taken_portable);
        // The files with no line bent and bounds every line meets read whole,
        // most of their lines on the whole-line path.
        if (file % 3 == 2 && depth_bits >= 24 && lim.id_bits >= 7) {
            CHECK(std::count(wide.begin(), wide.end(), ';') == 1200);
            CHECK(taken_wide > 600);
        }
    }
}

TEST_CASE("io: error: magic record", "[io][reader][error]") {
    CHECK_THAT(error_of(""), Equals("t.rbt:1: end of file before the magic record 'rbcd-trace 1': not an .rbt trace"));
    CHECK_ERR("# only\n# comments\n", 2, "end of file before the magic record");
    CHECK_ERR("\n\n", 2, "end of file before the magic record");
    CHECK_ERR("rbcd-trace 2\n", 1, "unsupported trace format version 2");
    CHECK_ERR("rbcd-trace\n", 1, "lacks the format version");
    CHECK_ERR("rbcd-trace 1 x\n", 1, "extra field 'x'");
    CHECK_ERR("rbcd-trace one\n", 1, "format version 'one' is not an unsigned decimal number");
    CHECK_ERR("rbcd_trace 1\n", 1, "not an .rbt trace: the first record must be 'rbcd-trace 1', found 'rbcd_trace'");
    CHECK_ERR("screen 800 480\nrbcd-trace 1\n", 1, "not an .rbt trace");
    CHECK_ERR("\n# c\nframe 0\n", 3, "not an .rbt trace");
    CHECK_ERR(M + "rbcd-trace 1\n", 2, "magic record 'rbcd-trace' repeated");
    CHECK_ERR(M + "frame 0\nrbcd-trace 1\n", 3, "magic record 'rbcd-trace' repeated");
    CHECK_ERR(std::string("\x1f\x8b", 2), 1, "corrupt or truncated gzip stream");
}

TEST_CASE("io: error: headers", "[io][reader][error]") {
    CHECK_ERR(M + "screen 800 480\nscreen 800 480\n", 3, "header 'screen' repeated (first at line 2)");
    CHECK_ERR(M + "tile_size 16 16\n#\ntile_size 16 16\n", 4, "header 'tile_size' repeated (first at line 2)");
    CHECK_ERR(M + "depth_bits 24\ndepth_bits 20\n", 3, "header 'depth_bits' repeated");
    CHECK_ERR(M + "frame 0\nscreen 10 10\n", 3, "header 'screen' after the first frame");
    CHECK_ERR(M + "frame 0\ntile 0 0\nf 1 1 1 1 F\ndepth_bits 8\n", 5, "header 'depth_bits' after the first frame");
    CHECK_ERR(M + "frame 0\nframe 1\ntile_size 16 16\n", 4, "header 'tile_size' after the first frame");
    CHECK_ERR(M + "depth_bits 0\n", 2, "depth_bits 0 out of range 1..32");
    CHECK_ERR(M + "depth_bits 33\n", 2, "depth_bits 33 out of range 1..32");
    CHECK_ERR(M + "depth_bits\n", 2, "header 'depth_bits' has too few fields");
    CHECK_ERR(M + "depth_bits 8 8\n", 2, "header 'depth_bits' has an extra field '8'");
    CHECK_ERR(M + "depth_bits 99999999999999999999\n", 2, "depth_bits '99999999999999999999' does not fit in 64 bits");
    CHECK_ERR(M + "screen 0 480\n", 2, "screen width 0 out of range 1..65535");
    CHECK_ERR(M + "screen 65536 480\n", 2, "screen width 65536 out of range 1..65535");
    CHECK_ERR(M + "screen 800 0\n", 2, "screen height 0 out of range 1..65535");
    CHECK_ERR(M + "screen 800 65536\n", 2, "screen height 65536 out of range 1..65535");
    CHECK_ERR(M + "screen 4294967297 480\n", 2, "screen width 4294967297 out of range");
    CHECK_ERR(M + "screen 800\n", 2, "header 'screen' has too few fields");
    CHECK_ERR(M + "screen 800 480 1\n", 2, "header 'screen' has an extra field '1'");
    CHECK_ERR(M + "screen 800 -480\n", 2, "screen height '-480' is not an unsigned decimal number");
    CHECK_ERR(M + "tile_size 8 8\n", 2, "tile_size 8 8 does not match the unit's tile.width x tile.height 16 x 16");
    CHECK_ERR(M + "tile_size 16 8\n", 2, "tile_size 16 8 does not match");
    CHECK_ERR(M + "tile_size 16\n", 2, "header 'tile_size' has too few fields");
    TraceLimits lim8;
    lim8.tile_w = lim8.tile_h = 8;
    CHECK_ERR_LIM(M + "tile_size 16 16\n", lim8, 2, "tile_size 16 16 does not match the unit's tile.width x tile.height 8 x 8");
    CHECK_ERR_LIM(M + "frame 0\n", lim8, 1, "no tile_size header, so its tiles are 16 x 16");
    CHECK_ERR_LIM("# c\n" + M + "screen 64 64\nframe 0\n", lim8, 2, "no tile_size header");
    CHECK_THAT(error_of(M + "tile_size 8 8\nframe 0\ntile 7 7\n", lim8), Equals("<no error>"));
}

TEST_CASE("io: error: frames", "[io][reader][error]") {
    CHECK_THAT(error_of(M + "frame 1\n"), Equals("t.rbt:2: frame 1 out of sequence: expected frame 0"));
    CHECK_ERR(M + "frame 0\nframe 2\n", 3, "frame 2 out of sequence: expected frame 1");
    CHECK_ERR(M + "frame 0\ntile 0 0\nframe 0\n", 4, "frame 0 out of sequence: expected frame 1");
    CHECK_ERR(M + "frame\n", 2, "frame has too few fields");
    CHECK_ERR(M + "frame 0 1\n", 2, "frame has an extra field '1'");
    CHECK_ERR(M + "frame zero\n", 2, "frame number 'zero' is not an unsigned decimal number");
    CHECK_ERR(M + "frame 18446744073709551616\n", 2, "frame number '18446744073709551616' does not fit in 64 bits");
}

TEST_CASE("io: error: tile and fragment placement", "[io][reader][error]") {
    CHECK_THAT(error_of(M + "tile 0 0\n"), Equals("t.rbt:2: tile before any frame"));
    CHECK_ERR(M + "screen 16 16\ntile 0 0\n", 3, "tile before any frame");
    CHECK_THAT(error_of(M + "frame 0\nf 1 1 1 1 F\n"), Equals("t.rbt:3: fragment before any tile of frame 0"));
    CHECK_ERR(M + "f 1 1 1 1 F\n", 2, "fragment before any frame and tile");
    CHECK_ERR(M + "frame 0\ntile 0 0\nframe 1\nf 1 1 1 1 F\n", 5, "fragment before any tile of frame 1");
    CHECK_ERR(M + "frame 0\n\nf 1 1 1 1 F junk\n", 4, "fragment before any tile");
}

TEST_CASE("io: error: tile records", "[io][reader][error]") {
    const std::string F0 = M + "frame 0\n";
    CHECK_ERR(F0 + "tile\n", 3, "tile has too few fields: missing column");
    CHECK_ERR(F0 + "tile 0\n", 3, "tile has too few fields: missing row");
    CHECK_ERR(F0 + "tile 0 0 foo=1\n", 3, "tile has unknown key 'foo' (known keys: other, base, prims, cprims, shade)");
    CHECK_ERR(F0 + "tile 0 0 shade=0\n", 3, "tile shade=0 outside 1..10000 (percent of gpu.cycles_per_fragment)");
    CHECK_ERR(F0 + "tile 0 0 shade=10001\n", 3, "tile shade=10001 outside 1..10000");
    CHECK_ERR(F0 + "tile 0 0 shade=50 shade=60\n", 3, "tile key 'shade' given twice");
    CHECK_ERR(F0 + "tile 0 0 Other=1\n", 3, "tile has unknown key 'Other'");
    CHECK_ERR(F0 + "tile 0 0 other=1 other=2\n", 3, "tile key 'other' given twice");
    CHECK_ERR(F0 + "tile 0 0 base=1 other=2 base=3\n", 3, "tile key 'base' given twice");
    CHECK_ERR(F0 + "tile 0 0 other\n", 3, "tile field 'other' is not key=value");
    // Past 2^40 the run's cycle arithmetic could overflow: rejected, not wrapped.
    CHECK_ERR(F0 + "tile 0 0 other=1099511627777\n", 3, "tile other=1099511627777 too large (at most 1099511627776)");
    CHECK_ERR(F0 + "tile 0 0 base=18446744073709551615\n", 3, "tile base=18446744073709551615 too large");
    CHECK_ERR(F0 + "tile 0 0 =5\n", 3, "tile field '=5' is not key=value");
    CHECK_ERR(F0 + "tile 0 0 5\n", 3, "tile field '5' is not key=value");
    CHECK_ERR(F0 + "tile 0 0 other=\n", 3, "tile field 'other=' has no value");
    CHECK_ERR(F0 + "tile 0 0 other = 5\n", 3, "tile field 'other' is not key=value");
    CHECK_ERR(F0 + "tile 0 0 other=x\n", 3, "tile other= 'x' is not an unsigned decimal number");
    CHECK_ERR(F0 + "tile 0 0 base=-1\n", 3, "tile base= '-1' is not an unsigned decimal number");
    CHECK_ERR(F0 + "tile 0 0 other=1=2\n", 3, "tile other= '1=2' is not an unsigned decimal number");
    CHECK_ERR(F0 + "tile 0 0 other=18446744073709551616\n", 3, "tile other= '18446744073709551616' does not fit in 64 bits");
    CHECK_ERR(F0 + "tile x 0\n", 3, "tile column 'x' is not an unsigned decimal number");
    CHECK_ERR(F0 + "tile 0 +1\n", 3, "tile row '+1' is not an unsigned decimal number");
    CHECK_THAT(error_of(F0 + "tile 50 0\n"),
               Equals("t.rbt:3: tile column 50 outside the screen (800 px wide = 50 tile columns, 0..49)"));
    CHECK_ERR(F0 + "tile 0 30\n", 3, "tile row 30 outside the screen (480 px high = 30 tile rows, 0..29)");
    CHECK_ERR(F0 + "tile 4294967296 0\n", 3, "tile column 4294967296 outside the screen");
    CHECK_ERR(M + "screen 20 17\nframe 0\ntile 1 1\ntile 2 0\n", 5, "tile column 2 outside the screen (20 px wide = 2 tile columns, 0..1)");
    CHECK_THAT(error_of(F0 + "tile 49 29\n"), Equals("<no error>"));
    CHECK_THAT(error_of(F0 + "tile 1 2\nf 16 32 0 1 F\ntile 3 3\ntile 1 2\n"),
               Equals("t.rbt:6: tile 1 2 appears twice in frame 0"));
    // The per-frame tile set also works when the grid is too big for a bitmap.
    TraceLimits tiny;
    tiny.tile_w = tiny.tile_h = 1;
    CHECK_ERR_LIM(M + "tile_size 1 1\nscreen 65535 65535\nframe 0\ntile 65534 65534\nframe 1\ntile 65534 65534\n"
                      "tile 0 1\ntile 65534 65534\n",
                  tiny, 9, "tile 65534 65534 appears twice in frame 1");
}

TEST_CASE("io: error: fragment records", "[io][reader][error]") {
    const std::string T = M + "frame 0\ntile 1 0\n";   // pixels x 16..31, y 0..15
    CHECK_THAT(error_of(T + "f 40 0 0 1 F\n"), Equals("t.rbt:4: fragment x=40 outside tile 1 0 (x 16..31)"));
    CHECK_ERR(T + "f 16 0 0 1 F\nf 15 0 0 1 F\n", 5, "fragment x=15 outside tile 1 0 (x 16..31)");
    CHECK_ERR(T + "f 32 0 0 1 F\n", 4, "fragment x=32 outside tile 1 0");
    CHECK_ERR(T + "f 16 16 0 1 F\n", 4, "fragment y=16 outside tile 1 0 (y 0..15)");
    // No wraparound: 2^32 + 16 is not 16.
    CHECK_ERR(T + "f 4294967312 0 0 1 F\n", 4, "fragment x=4294967312 outside tile 1 0");
    CHECK_ERR(T + "f 16 4294967296 0 1 F\n", 4, "fragment y=4294967296 outside tile 1 0");
    CHECK_THAT(error_of(M + "screen 20 18\nframe 0\ntile 1 1\nf 19 17 0 1 F\nf 20 17 0 1 F\n"),
               Equals("t.rbt:6: fragment x=20 outside tile 1 1 (x 16..19, the tile's part inside the 20x18 screen)"));
    CHECK_ERR(M + "screen 20 18\nframe 0\ntile 1 1\nf 16 18 0 1 F\n", 5,
              "fragment y=18 outside tile 1 1 (y 16..17, the tile's part inside the 20x18 screen)");
    CHECK_THAT(error_of(T + "f 16 0 16777216 1 F\n"),
               Equals("t.rbt:4: fragment depth=16777216 does not fit depth_bits 24 (max 16777215)"));
    CHECK_ERR(M + "depth_bits 32\nframe 0\ntile 0 0\nf 0 0 4294967296 1 F\n", 5, "fragment depth=4294967296 does not fit depth_bits 32");
    CHECK_ERR(M + "depth_bits 1\nframe 0\ntile 0 0\nf 0 0 2 1 F\n", 5, "fragment depth=2 does not fit depth_bits 1 (max 1)");
    CHECK_THAT(error_of(T + "f 16 0 0 128 F\n"),
               Equals("t.rbt:4: fragment object id=128 does not fit zeb.id_bits 7 (max 127)"));
    TraceLimits lim16;
    lim16.id_bits = 16;
    CHECK_ERR_LIM(T + "f 16 0 0 65536 F\n", lim16, 4, "fragment object id=65536 does not fit zeb.id_bits 16 (max 65535)");
    CHECK_ERR_LIM(T + "f 16 0 0 4294967297 F\n", lim16, 4, "fragment object id=4294967297 does not fit");
    CHECK_ERR(T + "f 16 0 0 1 X\n", 4, "fragment facing 'X' is not F or B");
    CHECK_ERR(T + "f 16 0 0 1 f\n", 4, "fragment facing 'f' is not F or B");
    CHECK_ERR(T + "f 16 0 0 1 FB\n", 4, "fragment facing 'FB' is not F or B");
    CHECK_ERR(T + "f 16 0 0 1 Fc\n", 4, "fragment facing 'Fc' is not F or B");
    CHECK_ERR(T + "f 16 0 0 1 0\n", 4, "fragment facing '0' is not F or B");
    CHECK_ERR(T + "f\n", 4, "fragment has too few fields: missing x");
    CHECK_ERR(T + "f 16\n", 4, "fragment has too few fields: missing y");
    CHECK_ERR(T + "f 16 0\n", 4, "fragment has too few fields: missing depth");
    CHECK_ERR(T + "f 16 0 0\n", 4, "fragment has too few fields: missing object id");
    CHECK_ERR(T + "f 16 0 0 1 # F\n", 4, "fragment has too few fields: missing facing");
    CHECK_ERR(T + "f 16 0 0 1 F c x\n", 4, "fragment has an extra field 'x'");
    CHECK_ERR(T + "f 16 0 0 1 F c c\n", 4, "fragment has an extra field 'c'");
    CHECK_ERR(T + "f 16 0 0 1 F d\n", 4, "fragment field 'd' after the facing is not the cull tag 'c'");
    CHECK_ERR(T + "f 16 0 0 1 F C\n", 4, "fragment field 'C' after the facing is not the cull tag 'c'");
    CHECK_ERR(T + "f 16 0 0 1 F cc\n", 4, "fragment field 'cc' after the facing is not the cull tag 'c'");
    CHECK_ERR(T + "f +16 0 0 1 F\n", 4, "fragment x '+16' is not an unsigned decimal number");
    CHECK_ERR(T + "f 16 -0 0 1 F\n", 4, "fragment y '-0' is not an unsigned decimal number");
    CHECK_ERR(T + "f 16 0 0x10 1 F\n", 4, "fragment depth '0x10' is not an unsigned decimal number");
    CHECK_ERR(T + "f 16 0 1.5 1 F\n", 4, "fragment depth '1.5' is not an unsigned decimal number");
    CHECK_ERR(T + "f 16 0 0 1a F\n", 4, "fragment object id '1a' is not an unsigned decimal number");
    CHECK_ERR(T + "f 18446744073709551616 0 0 1 F\n", 4, "fragment x '18446744073709551616' does not fit in 64 bits");
    // 2^64 + 16 and 2^64 + 5 would wrap to values that fit.
    CHECK_ERR(T + "f 18446744073709551632 0 0 1 F\n", 4, "fragment x '18446744073709551632' does not fit in 64 bits");
    CHECK_ERR(T + "f 16 0 18446744073709551621 1 F\n", 4, "fragment depth '18446744073709551621' does not fit in 64 bits");
    CHECK_ERR(T + "f 16 0 0 36893488147419103233 F\n", 4, "fragment object id '36893488147419103233' does not fit in 64 bits");
    CHECK_ERR(T + "f 16 0 99999999999999999999999 1 F\n", 4, "fragment depth '99999999999999999999999' does not fit in 64 bits");
    CHECK_ERR(T + "f 16 0 0 99999999999999999999x F\n", 4, "fragment object id '99999999999999999999x' is not an unsigned decimal number");
    // 2^64 - 1 parses; it is the range check that rejects it.
    CHECK_ERR(T + "f 18446744073709551615 0 0 1 F\n", 4, "fragment x=18446744073709551615 outside tile 1 0");
    CHECK_ERR(T + "f 000000000000000000000000000040 0 0 1 F\n", 4, "fragment x=40 outside tile 1 0");
}

TEST_CASE("io: error: unknown records and bad characters", "[io][reader][error]") {
    const std::string T = M + "frame 0\ntile 0 0\n";
    CHECK_THAT(error_of(T + "g 1 2\n"), Equals("t.rbt:4: unknown record 'g'"));
    CHECK_ERR(T + "F 1 1 1 1 F\n", 4, "unknown record 'F'");
    CHECK_ERR(T + "f1 1 1 1 F\n", 4, "unknown record 'f1'");
    CHECK_ERR(M + "frames 0\n", 2, "unknown record 'frames'");
    CHECK_ERR(M + "frame 0\ntiles 0 0\n", 3, "unknown record 'tiles'");
    CHECK_ERR(M + "frame 0\n" + std::string("\0 0 0\n", 6), 3, "unknown record '\\x00'");
    CHECK_ERR(T + "f 1 1 1 1 F\rx\n", 4, "stray carriage return");
    CHECK_ERR(T + "f 1 1 1 1 F\r\r\n", 4, "stray carriage return");
    CHECK_ERR(M + "frame 0\r\r\n", 2, "stray carriage return");
    CHECK_ERR(T + "f 1 1 1 1\vF\n", 4, "fragment has too few fields: missing facing");
    // The last line needs no newline, and its errors still carry its number.
    CHECK_ERR(T + "f 1 1 1 1 Q", 4, "fragment facing 'Q' is not F or B");
}
