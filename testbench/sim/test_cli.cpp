// rbcd-sim as a user sees it (formats.md, "Command line"): the real executable
// runs as a subprocess. Every bad input, configuration or command line must
// exit 2 with exactly one line on stderr naming file:line or the key, and leave
// no file at the --collisions and --stats paths, not even an older one that
// stood there before the run. Good runs exit 0 with complete outputs.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#ifndef RBCD_SIM
#error "RBCD_SIM must name the rbcd-sim executable"
#endif

#include "rbcd/testbench/sim/cli_util.h"

using namespace rbcd::cli_test;

namespace {

const std::string kHead = "rbcd-trace 1\nframe 0\ntile 0 0\nf 0 0 100 1 F\n";   // lines 1..4

// A trace whose line `line` is bad: exit 2 naming trace:line, nothing left.
void trace_error(const std::string& text, unsigned line, const std::vector<std::string>& needles = {},
                 const std::vector<std::string>& extra = {}, bool gz = false) {
    TempDir td;
    const std::string p = gz ? td.write_gz("bad.rbt", text) : td.write("bad.rbt", text);
    std::vector<std::string> args{"--trace", p};
    args.insert(args.end(), extra.begin(), extra.end());
    const Result r = run_with_outputs(td, args);
    std::vector<std::string> n{p + ":" + std::to_string(line) + ": "};
    n.insert(n.end(), needles.begin(), needles.end());
    INFO("trace:\n" << text);
    expect_input_error(td, r, n);
}

struct Totals {
    std::uint64_t frames, tiles, fragments, overflows, stack_overflows, orphan_back_faces, hits;
};

// Cycles cannot be derived from a vector; a run that did any work took some.
void check_stats(const std::string& path, const Totals& t, bool some_cycles = true) {
    REQUIRE(fs::exists(path));
    const std::string text = slurp(path);
    INFO("stats: " << text);
    nlohmann::json j;
    REQUIRE_NOTHROW(j = nlohmann::json::parse(text));
    REQUIRE(j.is_object());
    REQUIRE(j.contains("totals"));
    const auto& tot = j["totals"];
    REQUIRE(tot.is_object());
    const std::pair<const char*, std::uint64_t> want[] = {
        {"frames", t.frames},
        {"tiles", t.tiles},
        {"fragments", t.fragments},
        {"overflows", t.overflows},
        {"stack_overflows", t.stack_overflows},
        {"orphan_back_faces", t.orphan_back_faces},
        {"hits", t.hits},
    };
    for (const auto& [k, v] : want) {
        INFO(k);
        REQUIRE(tot.contains(k));
        CHECK(tot[k].is_number_integer());
        CHECK(tot[k].is_number_unsigned());
        if (tot[k].is_number_integer()) CHECK(tot[k].get<std::uint64_t>() == v);
    }
    REQUIRE(tot.contains("cycles"));
    CHECK(tot["cycles"].is_number_integer());
    CHECK(tot["cycles"].is_number_unsigned());
    if (tot["cycles"].is_number_integer() && some_cycles) CHECK(tot["cycles"].get<std::uint64_t>() > 0);
}

void expect_success(const TempDir& td, const Result& r) {
    INFO("command: " << r.cmd);
    INFO("stderr: " << r.err);
    CHECK(r.status == 0);
    CHECK(r.err.empty());
    REQUIRE(fs::exists(td.collisions()));
    REQUIRE(fs::exists(td.stats()));
    const auto left = td.out_entries();
    CHECK(left.size() == 2);
}

// A big frame of hits: every pixel of `tiles` tiles has A F, B F, A B, one hit
// per pixel, so the collision output outgrows any buffer long before the end.
std::string long_trace(unsigned tiles) {
    std::string s = "rbcd-trace 1\nframe 0\n";
    s.reserve(std::size_t(tiles) * 256 * 3 * 24);
    for (unsigned t = 0; t < tiles; ++t) {
        const unsigned c = t % 50, r = t / 50;
        s += "tile " + std::to_string(c) + " " + std::to_string(r) + "\n";
        for (unsigned py = 0; py < 16; ++py)
            for (unsigned px = 0; px < 16; ++px) {
                const std::string xy = std::to_string(c * 16 + px) + " " + std::to_string(r * 16 + py);
                s += "f " + xy + " 100 1 F\nf " + xy + " 200 2 F\nf " + xy + " 300 1 B\n";
            }
    }
    return s;
}

} // namespace

// ---------------------------------------------------------------- success

TEST_CASE("cli: vector with config gives the golden output and stats totals") {
    TempDir td;
    const Result r = run_with_outputs(td, {"--trace", kVectors + "/rule-stack-overflow.rbt", "--config",
                                           kVectors + "/rule-stack-overflow.toml", "--quiet"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == slurp(kVectors + "/rule-stack-overflow.golden"));
    // One frame, one tile, 14 fragments; two C fronts dropped by the 2-entry
    // stack, two C backs orphaned, three hits (see the .rbt comments).
    check_stats(td.stats(), Totals{1, 1, 14, 0, 2, 2, 3});
    CHECK(r.out.empty());
}

TEST_CASE("cli: vector with list overflows gives the golden output and stats totals") {
    TempDir td;
    const Result r = run_with_outputs(td, {"--trace", kVectors + "/rule-overflow-per-tile.rbt", "--config",
                                           kVectors + "/rule-overflow-per-tile.toml"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == slurp(kVectors + "/rule-overflow-per-tile.golden"));
    // Two frames, 4 + 1 tiles, 19 fragments, 2 + 2 dropped, three hits.
    check_stats(td.stats(), Totals{2, 5, 19, 4, 0, 0, 3});
}

TEST_CASE("cli: vector with --set instead of a config file gives the golden output") {
    TempDir td;
    const Result r = run_with_outputs(td, {"--trace", kVectors + "/rule-overflow-per-tile.rbt", "--set",
                                           "zeb.list_length=3", "-q"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == slurp(kVectors + "/rule-overflow-per-tile.golden"));
}

TEST_CASE("cli: gzip trace gives the same output as the plain one") {
    TempDir td;
    const std::string gz = td.write_gz("trace.rbt", slurp(kVectors + "/rule-stack-overflow.rbt"));
    const Result r = run_with_outputs(td, {"--trace", gz, "--config", kVectors + "/rule-stack-overflow.toml", "-q"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == slurp(kVectors + "/rule-stack-overflow.golden"));
    check_stats(td.stats(), Totals{1, 1, 14, 0, 2, 2, 3});
}

TEST_CASE("cli: --threads 1 parses in the simulation thread, with the same outputs") {
    TempDir td;
    const std::string trace = kVectors + "/multi-frame-mixed.rbt", cfg = kVectors + "/multi-frame-mixed.toml";
    Result r = run_with_outputs(td, {"--trace", trace, "--config", cfg, "-q", "--threads", "1"});
    expect_success(td, r);
    const std::string one = slurp(td.collisions());
    CHECK(one == slurp(kVectors + "/multi-frame-mixed.golden"));
    const auto totals = nlohmann::json::parse(slurp(td.stats()))["totals"];
    r = run_with_outputs(td, {"--trace", trace, "--config", cfg, "-q"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == one);
    CHECK(nlohmann::json::parse(slurp(td.stats()))["totals"] == totals);
    for (const char* bad : {"0", "3", "x"}) {
        r = run_with_outputs(td, {"--trace", trace, "-q", "--threads", bad});
        expect_input_error(td, r, {"--threads"});
    }
}

TEST_CASE("cli: trace of only the magic line gives zero frames") {
    TempDir td;
    const std::string p = td.write("empty.rbt", "rbcd-trace 1\n");
    const Result r = run_with_outputs(td, {"--trace", p, "-q"});
    expect_success(td, r);
    CHECK(slurp(td.collisions()) == "rbcd-collisions 1\n");
    check_stats(td.stats(), Totals{0, 0, 0, 0, 0, 0, 0}, false);
}

TEST_CASE("cli: only the requested outputs are written") {
    TempDir td;
    const Result r = run_sim(td, {"--trace", kVectors + "/rule-stack-overflow.rbt", "--config",
                                  kVectors + "/rule-stack-overflow.toml", "--stats", td.stats(), "-q"});
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(td.stats()));
    CHECK_FALSE(fs::exists(td.collisions()));
    CHECK(td.out_entries().size() == 1);
}

TEST_CASE("cli: --help exits 0") {
    TempDir td;
    const Result r = run_sim(td, {"--help"});
    INFO(r.err);
    CHECK(r.status == 0);
    for (const char* opt : {"--config", "--set", "--trace", "--collisions", "--stats", "--dump-config"})
        CHECK_THAT(r.out, Contains(opt));
}

TEST_CASE("cli: --dump-config output read back by --config gives the same dump") {
    TempDir td;
    const Result a = run_sim(td, {"--dump-config"});
    INFO(a.err);
    REQUIRE(a.status == 0);
    CHECK(a.err.empty());
    CHECK_THAT(a.out, Contains("[zeb]"));
    CHECK_THAT(a.out, Contains("list_length = 8"));
    const std::string p = td.write("dump.toml", a.out);
    const Result b = run_sim(td, {"--config", p, "--dump-config"});
    INFO(b.err);
    CHECK(b.status == 0);
    CHECK(b.out == a.out);
}

TEST_CASE("cli: --dump-config of a changed configuration reads back the same") {
    TempDir td;
    const Result a = run_sim(td, {"--config", kVectors + "/rule-tie-arrival.toml", "--set", "zeb.list_length=5",
                                  "--set", "tester.output=tile", "--set", "tile.width=8", "--dump-config"});
    INFO(a.err);
    REQUIRE(a.status == 0);
    CHECK_THAT(a.out, Contains("list_length = 5"));
    CHECK_THAT(a.out, Contains("tie = \"arrival\""));
    CHECK_THAT(a.out, Contains("output = \"tile\""));
    CHECK_THAT(a.out, Contains("width = 8"));
    const std::string p = td.write("dump.toml", a.out);
    const Result b = run_sim(td, {"--config", p, "--dump-config"});
    INFO(b.err);
    CHECK(b.status == 0);
    CHECK(b.out == a.out);
}

TEST_CASE("cli: --set applies after --config and the last --set wins") {
    TempDir td;
    const std::string p = td.write("c.toml", "[zeb]\nlist_length = 4\nbanks = 5\n");
    const Result r = run_sim(td, {"--set", "zeb.list_length=7", "--config", p, "--set", "zeb.list_length=6",
                                  "--set", "zeb.list_length=3", "--dump-config"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("\nlist_length = 3"));
    CHECK_THAT(r.out, Contains("\nbanks = 5"));
}

// ------------------------------------------------------- malformed traces

TEST_CASE("cli: trace bad magic word") { trace_error("rbcd-trac 1\nframe 0\n", 1, {"rbcd-trace"}); }
TEST_CASE("cli: trace first record not the magic") { trace_error("# c\n\nframe 0\n", 3); }
TEST_CASE("cli: trace unsupported version") { trace_error("rbcd-trace 2\n", 1, {"version"}); }
TEST_CASE("cli: trace magic lacks version") { trace_error("rbcd-trace\n", 1); }
TEST_CASE("cli: trace magic extra field") { trace_error("rbcd-trace 1 x\n", 1); }
TEST_CASE("cli: trace empty file") { trace_error("", 1); }
TEST_CASE("cli: trace unknown record") { trace_error(kHead + "fragment 0 0 1 1 F\n", 5, {"fragment"}); }
TEST_CASE("cli: trace unknown record in the header") { trace_error("rbcd-trace 1\nscreens 8 8\n", 2); }
TEST_CASE("cli: trace fragment missing a field") { trace_error(kHead + "f 1 0 100 1\n", 5, {"facing"}); }
TEST_CASE("cli: trace fragment missing all fields") { trace_error(kHead + "f\n", 5); }
TEST_CASE("cli: trace fragment extra field") { trace_error(kHead + "f 1 0 100 1 F c c\n", 5); }
TEST_CASE("cli: trace fragment bad cull tag") { trace_error(kHead + "f 1 0 100 1 F x\n", 5); }
TEST_CASE("cli: trace tile missing row") { trace_error(kHead + "tile 1\n", 5, {"row"}); }
TEST_CASE("cli: trace tile field not key value") { trace_error(kHead + "tile 1 0 7\n", 5); }
TEST_CASE("cli: trace frame missing number") { trace_error(kHead + "frame\n", 5); }
TEST_CASE("cli: trace frame extra field") { trace_error(kHead + "frame 1 2\n", 5); }
TEST_CASE("cli: trace screen missing field") { trace_error("rbcd-trace 1\nscreen 800\n", 2, {"screen"}); }
TEST_CASE("cli: trace screen extra field") { trace_error("rbcd-trace 1\nscreen 800 480 1\n", 2, {"screen"}); }
TEST_CASE("cli: trace tile_size extra field") { trace_error("rbcd-trace 1\ntile_size 16 16 16\n", 2); }
TEST_CASE("cli: trace depth_bits missing value") { trace_error("rbcd-trace 1\ndepth_bits\n", 2); }
TEST_CASE("cli: trace depth_bits out of range") { trace_error("rbcd-trace 1\ndepth_bits 33\n", 2); }
TEST_CASE("cli: trace screen of zero width") { trace_error("rbcd-trace 1\nscreen 0 480\n", 2); }
TEST_CASE("cli: trace negative number") { trace_error(kHead + "f 1 0 -100 1 F\n", 5, {"-100"}); }
TEST_CASE("cli: trace hex number") { trace_error(kHead + "f 0x1 0 100 1 F\n", 5, {"0x1"}); }
TEST_CASE("cli: trace decimal point in number") { trace_error(kHead + "f 1 0 1.5 1 F\n", 5, {"1.5"}); }
TEST_CASE("cli: trace plus sign in frame number") { trace_error(kHead + "frame +1\n", 5, {"+1"}); }
TEST_CASE("cli: trace letter in tile column") { trace_error(kHead + "tile a 0\n", 5); }
TEST_CASE("cli: trace letter in screen size") { trace_error("rbcd-trace 1\nscreen 800 4a0\n", 2); }
TEST_CASE("cli: trace number beyond 64 bits") { trace_error(kHead + "f 1 0 99999999999999999999 1 F\n", 5); }
TEST_CASE("cli: trace first frame not 0") { trace_error("rbcd-trace 1\nframe 1\n", 2, {"sequence"}); }
TEST_CASE("cli: trace frame skipped") { trace_error(kHead + "frame 2\n", 5, {"sequence"}); }
TEST_CASE("cli: trace frame repeated") { trace_error(kHead + "frame 0\n", 5, {"sequence"}); }
TEST_CASE("cli: trace repeated screen header") {
    trace_error("rbcd-trace 1\nscreen 800 480\ndepth_bits 24\nscreen 800 480\n", 4, {"repeated"});
}
TEST_CASE("cli: trace repeated tile_size header") {
    trace_error("rbcd-trace 1\ntile_size 16 16\ntile_size 16 16\n", 3, {"repeated"});
}
TEST_CASE("cli: trace repeated depth_bits header") {
    trace_error("rbcd-trace 1\ndepth_bits 24\ndepth_bits 24\n", 3, {"repeated"});
}
TEST_CASE("cli: trace repeated magic") { trace_error(kHead + "rbcd-trace 1\n", 5); }
TEST_CASE("cli: trace header after frame") { trace_error(kHead + "screen 800 480\n", 5, {"screen"}); }
TEST_CASE("cli: trace depth_bits after frame") { trace_error("rbcd-trace 1\nframe 0\ndepth_bits 16\n", 3); }
TEST_CASE("cli: trace tile column outside the screen") { trace_error(kHead + "tile 50 0\n", 5, {"50"}); }
TEST_CASE("cli: trace tile row outside the screen") { trace_error(kHead + "tile 0 30\n", 5, {"30"}); }
TEST_CASE("cli: trace tile outside a small screen") {
    trace_error("rbcd-trace 1\nscreen 20 20\nframe 0\ntile 1 1\ntile 2 0\n", 5);
}
TEST_CASE("cli: trace repeated tile in a frame") {
    trace_error(kHead + "tile 1 0\ntile 0 0\n", 6, {"twice"});
}
TEST_CASE("cli: trace tile before any frame") { trace_error("rbcd-trace 1\ntile 0 0\n", 2); }
TEST_CASE("cli: trace fragment x outside its tile") { trace_error(kHead + "f 16 0 100 1 F\n", 5, {"x=16"}); }
TEST_CASE("cli: trace fragment y outside its tile") { trace_error(kHead + "f 0 16 100 1 F\n", 5, {"y=16"}); }
TEST_CASE("cli: trace fragment left of its tile") {
    trace_error("rbcd-trace 1\nframe 0\ntile 1 1\nf 15 16 100 1 F\n", 4, {"x=15"});
}
TEST_CASE("cli: trace fragment outside the screen in an edge tile") {
    trace_error("rbcd-trace 1\nscreen 20 20\nframe 0\ntile 1 1\nf 19 19 5 1 F\nf 20 19 5 1 F\n", 6, {"x=20"});
}
TEST_CASE("cli: trace fragment before any tile") { trace_error("rbcd-trace 1\nframe 0\nf 0 0 100 1 F\n", 3); }
TEST_CASE("cli: trace fragment before any frame") { trace_error("rbcd-trace 1\nf 0 0 100 1 F\n", 2); }
TEST_CASE("cli: trace fragment before a tile of the next frame") {
    trace_error(kHead + "frame 1\nf 0 0 100 1 F\n", 6);
}
TEST_CASE("cli: trace object id over the default id_bits") {
    trace_error(kHead + "f 1 0 100 127 F\nf 1 0 100 128 F\n", 6, {"zeb.id_bits"});
}
TEST_CASE("cli: trace object id over a configured id_bits") {
    trace_error(kHead + "f 1 0 100 15 F\nf 1 0 100 16 F\n", 6, {"zeb.id_bits"}, {"--set", "zeb.id_bits=4"});
}
TEST_CASE("cli: trace depth not below 2 to the depth_bits") {
    trace_error(kHead + "f 1 0 16777215 1 F\nf 1 0 16777216 1 F\n", 6, {"depth"});
}
TEST_CASE("cli: trace depth over a declared depth_bits") {
    trace_error("rbcd-trace 1\ndepth_bits 8\nframe 0\ntile 0 0\nf 0 0 255 1 F\nf 0 0 256 1 F\n", 6, {"depth"});
}
TEST_CASE("cli: trace bad facing") { trace_error(kHead + "f 1 0 100 1 X\n", 5, {"facing"}); }
TEST_CASE("cli: trace lower case facing") { trace_error(kHead + "f 1 0 100 1 f\n", 5, {"facing"}); }
TEST_CASE("cli: trace unknown tile key") { trace_error(kHead + "tile 1 0 other=3 bogus=1\n", 5, {"bogus"}); }
TEST_CASE("cli: trace tile key without value") { trace_error(kHead + "tile 1 0 other=\n", 5, {"other"}); }
TEST_CASE("cli: trace tile key repeated") { trace_error(kHead + "tile 1 0 base=3 base=4\n", 5, {"base"}); }
TEST_CASE("cli: trace tile_size mismatching the default config") {
    trace_error("rbcd-trace 1\ntile_size 8 8\nframe 0\n", 2, {"tile_size", "tile.width"});
}
TEST_CASE("cli: trace tile_size mismatching the configured tile") {
    trace_error("rbcd-trace 1\ntile_size 16 16\nframe 0\n", 2, {"tile_size"}, {"--set", "tile.height=8"});
}
TEST_CASE("cli: trace without tile_size under a non-default tile") {
    trace_error("rbcd-trace 1\nframe 0\n", 1, {"tile_size", "tile.width"}, {"--set", "tile.width=8"});
}
TEST_CASE("cli: trace stray carriage return") { trace_error(kHead + "f 1 0 100 1 F\r \n", 5); }
TEST_CASE("cli: trace error in a gzip trace names the line") {
    trace_error(kHead + "f 1 0 100 1 F\nbogus\n", 6, {"bogus"}, {}, true);
}

TEST_CASE("cli: error on the last line of a long trace leaves no output") {
    TempDir td;
    // 320 tiles x 256 pixels = 81920 hits, some 1.6 MB of collision records.
    const std::string good = long_trace(320);
    const std::string gp = td.write("good.rbt", good);
    // First the trace as it is: it runs, so the bad run below had produced
    // output before it reached its last line.
    {
        const Result r = run_with_outputs(td, {"--trace", gp, "-q"});
        expect_success(td, r);
        CHECK(fs::file_size(td.collisions()) > (std::uintmax_t(1) << 20));
        check_stats(td.stats(), Totals{1, 320, 320 * 256 * 3, 0, 0, 0, 320 * 256});
    }
    // The outputs of that run are the older files now.
    std::size_t lines = 0;
    for (char c : good) lines += c == '\n';
    const std::string bp = td.write("bad.rbt", good + "f 0 0 1 1 Q\n");
    const Result r = run_with_outputs(td, {"--trace", bp, "-q"}, false);
    expect_input_error(td, r, {bp + ":" + std::to_string(lines + 1) + ": ", "facing"});
}

TEST_CASE("cli: error in the last frame of a long trace leaves no output") {
    TempDir td;
    const std::string good = long_trace(320);
    std::size_t lines = 0;
    for (char c : good) lines += c == '\n';
    const std::string bp = td.write("bad.rbt", good + "frame 1\ntile 0 0\nf 0 0 100 1 F\nframe 3\n");
    const Result r = run_with_outputs(td, {"--trace", bp});
    expect_input_error(td, r, {bp + ":" + std::to_string(lines + 4) + ": ", "sequence"});
}

TEST_CASE("cli: truncated gzip trace") {
    TempDir td;
    const std::string full = td.write_gz("full.rbt.gz", long_trace(40));
    std::string bytes = slurp(full);
    REQUIRE(bytes.size() > 1000);
    bytes.resize(bytes.size() / 2);
    const std::string p = td.write("cut.rbt.gz", bytes);
    const Result r = run_with_outputs(td, {"--trace", p});
    expect_input_error(td, r, {p + ":"});
}

TEST_CASE("cli: gzip trace with a corrupt body") {
    TempDir td;
    std::string bytes = slurp(td.write_gz("full.rbt.gz", long_trace(8)));
    REQUIRE(bytes.size() > 100);
    for (std::size_t i = bytes.size() / 2; i < bytes.size() / 2 + 16; ++i) bytes[i] = static_cast<char>(~bytes[i]);
    const std::string p = td.write("bad.rbt.gz", bytes);
    const Result r = run_with_outputs(td, {"--trace", p});
    expect_input_error(td, r, {p + ":"});
}

// ------------------------------------------------------- files and config

TEST_CASE("cli: missing trace file") {
    TempDir td;
    const std::string p = td.path("no-such-trace.rbt");
    expect_input_error(td, run_with_outputs(td, {"--trace", p}), {p});
}

TEST_CASE("cli: trace path is a directory") {
    TempDir td;
    const std::string p = td.path("adir");
    fs::create_directory(p);
    expect_input_error(td, run_with_outputs(td, {"--trace", p}), {p});
}

TEST_CASE("cli: missing config file") {
    TempDir td;
    const std::string p = td.path("no-such-config.toml");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--config", p}),
                       {p});
}

TEST_CASE("cli: unknown key in config file names file:line and key") {
    TempDir td;
    const std::string p = td.write("bad.toml", "[zeb]\nlist_length = 4\nbogus = 2\n");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--config", p}),
                       {p + ":3", "zeb.bogus"});
}

TEST_CASE("cli: unknown section in config file names file:line and key") {
    TempDir td;
    const std::string p = td.write("bad.toml", "[bogus]\nx = 2\n");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--config", p}),
                       {p + ":2", "bogus.x"});
}

TEST_CASE("cli: out of range value in config file names file:line and key") {
    TempDir td;
    const std::string p = td.write("bad.toml", "[tester]\nstack_depth = 65\n");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--config", p}),
                       {p + ":2", "tester.stack_depth"});
}

TEST_CASE("cli: TOML syntax error in config file names file:line") {
    TempDir td;
    const std::string p = td.write("bad.toml", "[zeb]\nbanks = 2\nlist_length = = 4\n");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--config", p}),
                       {p + ":3"});
}

TEST_CASE("cli: --set unknown key") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "zeb.bogus=1"}),
                       {"zeb.bogus"});
}

TEST_CASE("cli: --set unknown section") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "bogus.x=1"}),
                       {"bogus.x"});
}

TEST_CASE("cli: --set bad value for an integer key") {
    TempDir td;
    expect_input_error(
        td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "zeb.list_length=four"}),
        {"zeb.list_length"});
}

TEST_CASE("cli: --set float for an integer key") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "zeb.banks=2.0"}),
                       {"zeb.banks"});
}

TEST_CASE("cli: --set unknown enum value") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "zeb.tie=bogus"}),
                       {"zeb.tie", "bogus"});
}

TEST_CASE("cli: --set without an equals sign") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", "zeb.banks"}),
                       {"zeb.banks"});
}

TEST_CASE("cli: --set out of range value") {
    for (const char* a : {"zeb.list_length=65", "zeb.list_length=0", "tile.width=257", "zeb.banks=17",
                          "zeb.z_bits=33", "zeb.id_bits=17", "tester.stack_depth=0", "tile.height=0"}) {
        TempDir td;
        const std::string key = std::string(a).substr(0, std::string(a).find('='));
        expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set", a}), {key});
    }
}

TEST_CASE("cli: cross-key configuration error") {
    TempDir td;
    expect_input_error(td,
                       run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--set",
                                             "memory.latency_max=10", "--set", "memory.latency_min=20"}),
                       {"memory.latency_min"});
}

TEST_CASE("cli: configuration error with --dump-config") {
    TempDir td;
    const Result r = run_sim(td, {"--set", "zeb.banks=0", "--dump-config"});
    INFO(r.out);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, Contains("zeb.banks"));
    CHECK(r.out.empty());
}

// ------------------------------------------------------------ command line

TEST_CASE("cli: unknown command-line option") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--bogus-option"}),
                       {"--bogus-option"});
}

TEST_CASE("cli: stray positional argument") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "stray-word"}),
                       {"stray-word"});
}

TEST_CASE("cli: missing option argument") {
    TempDir td;
    // --trace last, without its file.
    td.plant_old_outputs();
    const Result r = run_sim(td, {"--collisions", td.collisions(), "--stats", td.stats(), "--trace"});
    expect_input_error(td, r, {"--trace"});
}

TEST_CASE("cli: missing config option argument") {
    TempDir td;
    td.plant_old_outputs();
    const Result r = run_sim(td, {"--collisions", td.collisions(), "--stats", td.stats(), "--config"});
    expect_input_error(td, r, {"--config"});
}

TEST_CASE("cli: collisions path in a nonexistent directory") {
    TempDir td;
    td.plant_old_outputs();
    fs::remove(td.collisions());   // only --stats names a path in out/
    const std::string bad = td.path("no-such-dir/collisions.txt");
    const Result r = run_sim(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--stats", td.stats(),
                                  "--collisions", bad});
    expect_error(td, r, 2, {bad});
    CHECK_FALSE(fs::exists(bad));
}

TEST_CASE("cli: stats path in a nonexistent directory") {
    TempDir td;
    td.plant_old_outputs();
    const std::string bad = td.path("no-such-dir/stats.json");
    const Result r = run_sim(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--collisions", td.collisions(),
                                  "--stats", bad});
    INFO("stderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, Contains(bad));
    CHECK_FALSE(fs::exists(td.collisions()));
    CHECK_FALSE(fs::exists(bad));
    CHECK(td.out_entries().size() == 1);   // only the untouched older stats.json
}

TEST_CASE("cli: output path that is a directory") {
    TempDir td;
    const std::string dir = td.path("adir");
    fs::create_directory(dir);
    td.plant_old_outputs();
    const Result r = run_sim(td, {"--trace", kVectors + "/rule-fig5-case1.rbt", "--collisions", dir, "--stats",
                                  td.stats()});
    INFO("stderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, Contains(dir));
    CHECK_FALSE(fs::exists(td.stats()));
    CHECK(fs::is_directory(dir));
}
