// rbcd-sim --jobs N (run/jobs.h): the frames run by N workers give the
// bytes one process writes (collisions, --frame-stats, the stats document
// apart from the wall time and the command line that ran), for traces plain,
// gzip and zstd and for scenes, with and without --frames; bad values and what
// cannot be split are refused; an input error is the one a single process
// reports.
#include "rbcd/testbench/sim/cli_util.h"

#include "rbcd/testbench/common/zstd_frames.h"

#include <nlohmann/json.hpp>
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <regex>
#include <thread>

using namespace rbcd::cli_test;

namespace {

struct Outputs {
    std::string stats, collisions, frames, out;
};

// The stats document with what documents the run itself (its wall time, its
// command line) set to what the reference run had; everything else is compared byte for byte.
std::string as_reference(const std::string& stats, const std::string& reference) {
    static const std::regex wall(R"re("(wall_seconds|fragments_per_second)": [^,\n]+)re");
    const std::string a = std::regex_replace(stats, wall, "\"$1\": 0");
    const std::string b = std::regex_replace(reference, wall, "\"$1\": 0");
    nlohmann::json ja = nlohmann::json::parse(a), jb = nlohmann::json::parse(b);
    if (ja.contains("provenance") && jb.contains("provenance"))
        for (const char* key : {"argv", "command_line"}) ja["provenance"][key] = jb["provenance"][key];
    return ja.dump(2) + "\n";
}

Outputs run(const TempDir& td, std::vector<std::string> args, const std::string& jobs) {
    td.plant_old_outputs();
    args.insert(args.end(), {"--collisions", td.collisions(), "--stats", td.stats(), "--frame-stats",
                             td.path("out/frames.jsonl")});
    if (!jobs.empty()) args.insert(args.end(), {"--jobs", jobs});
    const Result r = run_sim(td, args);
    INFO(r.cmd);
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(r.err.empty());
    return {slurp(td.stats()), slurp(td.collisions()), slurp(td.path("out/frames.jsonl")), r.out};
}

void expect_same_as_one_process(const TempDir& td, const std::vector<std::string>& args) {
    const Outputs one = run(td, args, "");
    REQUIRE(one.collisions.size() > 20);
    // The reference's own digests are the files' (the --jobs runs' equal the
    // reference's below, their parent hashing the whole file).
    const nlohmann::json one_stats = nlohmann::json::parse(one.stats);
    for (const auto& in : one_stats["provenance"]["inputs"]) {
        if (in["role"] != "trace") continue;
        const std::string bytes = slurp(in["path"].get<std::string>());
        CHECK(in["size"] == bytes.size());
        CHECK(in["xxh128"] == xxh128_of(bytes));
    }
    for (const char* jobs : {"1", "2", "3"}) {
        INFO("--jobs " << jobs);
        const Outputs n = run(td, args, jobs);
        CHECK(n.collisions == one.collisions);
        CHECK(n.frames == one.frames);
        CHECK(as_reference(n.stats, one.stats) == std::regex_replace(one.stats, std::regex(R"re("(wall_seconds|fragments_per_second)": [^,\n]+)re"), "\"$1\": 0"));
        CHECK(n.out == one.out);
        const auto argv = nlohmann::json::parse(n.stats)["provenance"]["argv"];
        CHECK(argv.back() == jobs);
    }
}

// The default scene at 200 x 120 pixels: its 60 frames and collisions at a
// sixteenth of the fragments (the tests run it many times).
std::string small_scene(const TempDir& td) {
    std::string text = slurp(std::string(RBCD_SOURCE_DIR) + "/scene/default_scene.toml");
    for (const auto& [from, to] : {std::pair<std::string, std::string>{"width = 800", "width = 200"},
                                   {"height = 480", "height = 120"}}) {
        const std::size_t at = text.find(from);
        REQUIRE(at != std::string::npos);
        text.replace(at, from.size(), to);
    }
    return td.write("small.toml", text);
}

// That scene as a trace.
std::string default_trace(const TempDir& td, bool gzip) {
    const std::string t = td.path(gzip ? "scene.rbt.gz" : "scene.rbt");
    const Result w = run_sim(td, {"-q", "--scene", small_scene(td), "--write-trace", td.path("scene.rbt")});
    REQUIRE(w.status == 0);
    if (gzip) td.write_gz("scene.rbt.gz", slurp(td.path("scene.rbt")));
    return t;
}

} // namespace

TEST_CASE("rbcd-sim --jobs: a plain trace gives one process's bytes", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    const auto frames = GENERATE(as<std::string>{}, "", "5:40", "7:", "12");
    INFO("--frames " << frames);
    std::vector<std::string> a{"-q", "--trace", t};
    if (!frames.empty()) a.insert(a.end(), {"--frames", frames});
    expect_same_as_one_process(td, a);
}

TEST_CASE("rbcd-sim --jobs: a zstd trace gives one process's bytes", "[jobs]") {
    TempDir td;
    // As rbcd-sim --write-trace NAME.zst (and the converter) write it: a frame record starts each zstd frame.
    const Result w = run_sim(td, {"-q", "--scene", small_scene(td), "--write-trace", td.path("scene.rbt.zst")});
    REQUIRE(w.status == 0);
    const std::string t = td.path("scene.rbt.zst");
    REQUIRE(slurp(t).compare(0, 4, "\x28\xb5\x2f\xfd") == 0);
    const auto frames = GENERATE(as<std::string>{}, "", "3:50", "9:");
    INFO("--frames " << frames);
    std::vector<std::string> a{"-q", "--trace", t};
    if (!frames.empty()) a.insert(a.end(), {"--frames", frames});
    expect_same_as_one_process(td, a);
}

// A zstd file whose frame starts inside a line with text that reads as a
// frame record ("# see frame 1"): split there, the first worker would run
// the rest of frame 0 as its own and the second the same tiles as frame 1.
// The first worker's data must end where the second starts: refused, exit 2.
TEST_CASE("rbcd-sim --jobs: a zstd trace cut inside a line is refused, not split there", "[jobs]") {
    TempDir td;
    const auto tile = [](int col) {
        std::string s = "tile " + std::to_string(col) + " 2\n";
        for (int i = 0; i < 200; ++i)
            s += "f " + std::to_string(col * 16 + i % 16) + " 32 " + std::to_string(100 + i) + " " +
                 std::to_string(1 + i % 3) + (i % 2 ? " F\n" : " B\n");
        return s;
    };
    const std::string head = "rbcd-trace 1\n", frame0 = "frame 0\n" + tile(3) + "# see ", rest = "frame 1\n" + tile(4);
    const std::string t = td.write("cut.rbt.zst", rbcd::test::zstd_frames({head, frame0, rest}));
    const Result one = run_with_outputs(td, {"-q", "--trace", t});
    REQUIRE(one.status == 0);   // one frame: the comment runs to the end of its line
    const Result two = run_with_outputs(td, {"-q", "--trace", t, "--jobs", "2"});
    expect_input_error(td, two, {});
    CHECK(two.err.find("so --jobs cannot split it there; run it without --jobs") != std::string::npos);
}

TEST_CASE("rbcd-sim --jobs: a gzip trace gives one process's bytes", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, true);
    const auto frames = GENERATE(as<std::string>{}, "", "3:50");
    INFO("--frames " << frames);
    std::vector<std::string> a{"-q", "--trace", t, "--set", "zeb.banks=1", "--set", "zeb.list_length=4"};
    if (!frames.empty()) a.insert(a.end(), {"--frames", frames});
    expect_same_as_one_process(td, a);
}

// Two frames of about equal bytes: one of fragments (simulated), one mostly
// comment lines (read, nothing to simulate), in either order.
std::string light_and_heavy(const TempDir& td, bool heavy_first) {
    std::string heavy = "tile 3 2\n", light = "tile 3 2\nf 48 32 100 1 F\nf 48 32 200 2 B\n";
    std::uint64_t rng = 12345;
    const auto next = [&rng] { return (rng = rng * 6364136223846793005ull + 1442695040888963407ull) >> 33; };
    for (int i = 0; i < 100000; ++i)
        heavy += "f " + std::to_string(48 + next() % 16) + " " + std::to_string(32 + next() % 16) + " " +
                 std::to_string(next() % (1u << 24)) + " " + std::to_string(1 + next() % 30) + (next() % 2 ? " F\n" : " B\n");
    while (light.size() < heavy.size()) light += "# " + std::string(78, 'x') + "\n";
    const std::string head = "rbcd-trace 1\nscreen 800 480\ntile_size 16 16\ndepth_bits 24\n";
    return td.write(heavy_first ? "heavy-first.rbt" : "light-first.rbt",
                    head + "frame 0\n" + (heavy_first ? heavy : light) + "frame 1\n" + (heavy_first ? light : heavy));
}

TEST_CASE("rbcd-sim --jobs: a trace's digest is the file's whichever worker ends first", "[jobs]") {
    // Each worker hashes the blocks of its part as it reads them (the first
    // chained, the second as block sums), and the parent joins them when the
    // last has ended: with a light first part, after the second; with a heavy
    // one, after the first. Either way: the file's digest.
    TempDir td;
    for (const bool heavy_first : {false, true}) {
        INFO("heavy part first: " << heavy_first);
        const std::string t = light_and_heavy(td, heavy_first);
        const Result r = run_sim(td, {"-q", "--trace", t, "--jobs", "2", "--stats", td.stats()});
        INFO(r.err);
        REQUIRE(r.status == 0);
        const auto in = nlohmann::json::parse(slurp(td.stats()))["provenance"]["inputs"][0];
        const std::string bytes = slurp(t);
        CHECK(in["size"] == bytes.size());
        CHECK(in["xxh128"] == xxh128_of(bytes));
    }
}

TEST_CASE("rbcd-sim --jobs: a worker's command line run alone", "[jobs]") {
    // The workers are forks that _exit, which LeakSanitizer does not check;
    // run as programs of their own, their code is (the sanitizer build).
    TempDir td;
    const std::string t = default_trace(td, false);
    const std::string text = slurp(t);
    const std::size_t at = text.find("frame 30\n");
    REQUIRE(at != std::string::npos);
    const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    // Their blocks of the trace's digest (run/part_digest.h): the first's
    // chained, the second's sums in a file of 64 bytes a block.
    const std::uint64_t cut = at / 1024 * 1024, end = (text.size() - 1) / 1024 * 1024;
    const std::vector<std::string> parts[] = {
        {"--trace", t, "--frames", "0:29", "--worker-part", "first", "--worker-digest", "0:" + std::to_string(cut)},
        {"--trace", t, "--frames", "30:", "--worker-part", "trace:" + std::to_string(at) + ":" + std::to_string(line),
         "--worker-digest", std::to_string(cut) + ":" + std::to_string(end), "--worker-digest-sums", td.path("1.xxh")},
        {"--scene", small_scene(td), "--frames", "20:39", "--worker-part", "scene"},
    };
    for (const auto& p : parts) {
        std::vector<std::string> a = p;
        a.insert(a.end(), {"-q", "--threads", "1", "--stats", td.stats(), "--frame-stats", td.path("out/f.jsonl"),
                           "--collisions", td.collisions()});
        const Result r = run_sim(td, a);
        INFO(r.cmd);
        INFO(r.err);
        REQUIRE(r.status == 0);
        CHECK(r.err.empty());
        const auto stats = nlohmann::json::parse(slurp(td.stats()));
        // Only the work a trace's frames declared, for the parent's bound.
        if (p[0] == "--trace") {
            REQUIRE(stats.contains("worker"));
            CHECK(stats["worker"].size() == 2);
            CHECK(stats["worker"].contains("declared_work"));
            const auto& d = stats["worker"]["digest"];
            const bool first = p[5] == "first";
            CHECK(d["from"] == (first ? 0 : cut));
            CHECK(d["blocks"] == (first ? cut : end - cut) / 1024);
            CHECK(d["file"]["size"] == text.size());
            CHECK(d.contains("acc") == first);
            if (!first) CHECK(std::filesystem::file_size(td.path("1.xxh")) == (end - cut) / 1024 * 64);
        } else {
            CHECK_FALSE(stats.contains("worker"));
        }
        CHECK((!stats.contains("provenance") || stats["provenance"].is_null()));   // the parent's to say
    }
}

TEST_CASE("rbcd-sim --jobs: a scene gives one process's bytes", "[jobs]") {
    TempDir td;
    const auto frames = GENERATE(as<std::string>{}, "", "10:45", "58:");
    INFO("--frames " << frames);
    std::vector<std::string> a{"-q", "--scene", small_scene(td)};
    if (!frames.empty()) a.insert(a.end(), {"--frames", frames});
    expect_same_as_one_process(td, a);
}

TEST_CASE("rbcd-sim --jobs: the summary on standard output is one process's", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    expect_same_as_one_process(td, {"--trace", t});
    // The built-in scene, as it is: a part of it.
    expect_same_as_one_process(td, {"--frames", "20:29"});
}

// The first worker writes its collisions straight into the output; here the
// output is the standard output (a pipe), which the later parts are copied
// to without copy_file_range.
TEST_CASE("rbcd-sim --jobs: collisions on standard output are one process's", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    const Result one = run_sim(td, {"-q", "--trace", t, "--collisions", "-"});
    REQUIRE(one.status == 0);
    REQUIRE(count_lines(one.out) > 20);
    for (const char* jobs : {"2", "3"}) {
        INFO("--jobs " << jobs);
        const Result n = run_sim(td, {"-q", "--trace", t, "--collisions", "-", "--stats", td.stats(), "--jobs", jobs});
        INFO(n.err);
        REQUIRE(n.status == 0);
        CHECK(n.out == one.out);
    }
}

// Started by a shell with standard input closed, or with SIGCHLD ignored: the
// output may then be descriptor 0 (the first worker writes into it), and the
// workers' statuses must still be known.
TEST_CASE("rbcd-sim --jobs: started without standard input, or with SIGCHLD ignored", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    const Outputs one = run(td, {"-q", "--trace", t}, "");
    fs::remove(td.path("out/frames.jsonl"));
    for (const char* how : {"exec \"$0\" \"$@\" <&-", "trap '' CHLD; exec \"$0\" \"$@\""}) {
        INFO(how);
        td.plant_old_outputs();
        const Result r = run_program(td, "/bin/sh", {"-c", how, RBCD_SIM, "-q", "--trace", t, "--jobs", "2",
                                                     "--collisions", td.collisions(), "--stats", td.stats()});
        INFO(r.err);
        REQUIRE(r.status == 0);
        CHECK(slurp(td.collisions()) == one.collisions);
        // A worker's failure is still seen.
        std::string bad = slurp(t);
        const std::size_t at = bad.find("\nf ", bad.find("\nframe 50\n"));
        REQUIRE(at != std::string::npos);
        bad.replace(at + 1, 1, "g");
        const std::string bad_path = td.write("bad.rbt", bad);
        td.plant_old_outputs();
        const Result b = run_program(td, "/bin/sh", {"-c", how, RBCD_SIM, "-q", "--trace", bad_path, "--jobs", "2",
                                                     "--collisions", td.collisions(), "--stats", td.stats()});
        expect_input_error(td, b, {"bad.rbt:"});
    }
}

TEST_CASE("rbcd-sim --jobs: more workers than frames", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    const Outputs one = run(td, {"-q", "--trace", t, "--frames", "30:31"}, "");
    const Outputs n = run(td, {"-q", "--trace", t, "--frames", "30:31"}, "8");
    CHECK(n.collisions == one.collisions);
    CHECK(n.frames == one.frames);
}

TEST_CASE("rbcd-sim --jobs: bad values are refused", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    for (const char* v : {"0", "-1", "two", "", "1025", "2.5"}) {
        INFO("--jobs '" << v << "'");
        expect_input_error(td, run_with_outputs(td, {"-q", "--trace", t, "--jobs", v}), {"--jobs"});
    }
    // A worker's own option, outside a worker.
    expect_input_error(td, run_with_outputs(td, {"-q", "--trace", t, "--worker-collisions-name", "x.txt"}),
                       {"--worker-collisions-name", "--worker-part"});
    expect_input_error(td, run_with_outputs(td, {"-q", "--trace", t, "--worker-digest", "0:1024"}),
                       {"--worker-digest", "--worker-part"});
    expect_input_error(td, run_with_outputs(td, {"-q", "--trace", t, "--worker-digest-sums", "x.xxh"}),
                       {"--worker-digest-sums", "--worker-digest"});
    // A worker's digest blocks that are not whole blocks, in order, with
    // somewhere to put a later part's sums.
    const std::vector<std::string> worker{"-q", "--trace", t, "--frames", "0:3", "--worker-part", "first"};
    for (const char* v : {"0", "0:1000", "2048:1024", "a:1024", "0:-1024", ":", "1024:2048"}) {
        INFO("--worker-digest '" << v << "'");
        std::vector<std::string> a = worker;
        a.insert(a.end(), {"--worker-digest", v});
        expect_input_error(td, run_with_outputs(td, a), {"--worker-digest"});
    }
}

TEST_CASE("rbcd-sim --jobs: what one process must write is refused with more than one", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    expect_input_error(td, run_with_outputs(td, {"-q", "--trace", t, "--jobs", "2", "--vcd", td.path("out/w.vcd")}),
                       {"--jobs", "--vcd"});
    expect_input_error(td, run_with_outputs(td, {"-q", "--jobs", "2", "--images", td.path("out/img")}),
                       {"--jobs", "--images"});
    expect_input_error(td, run_with_outputs(td, {"-q", "--jobs", "2", "--write-trace", td.path("out/t.rbt")}),
                       {"--jobs", "--write-trace"});
    expect_input_error(td, run_with_outputs(td, {"-q", "--trace", "-", "--jobs", "2"}), {"--jobs", "standard input"});
    // --jobs 1 is one process, whatever else is asked.
    td.plant_old_outputs();
    CHECK(run_sim(td, {"-q", "--frames", "0:1", "--jobs", "1", "--write-trace", td.path("t2.rbt")}).status == 2);
    CHECK(run_sim(td, {"-q", "--jobs", "1", "--frames", "0:1", "--vcd", td.path("w.vcd")}).status == 0);
}

TEST_CASE("rbcd-sim --jobs: an input error is the one a single process reports", "[jobs]") {
    TempDir td;
    const std::string t = default_trace(td, false);
    std::string text = slurp(t);
    // A fragment line broken in frame 50, then one in frame 10: each is the first error in its turn.
    const auto break_in = [&](std::string s, unsigned frame) {
        const std::size_t at = s.find("\nf ", s.find("\nframe " + std::to_string(frame) + "\n"));
        REQUIRE(at != std::string::npos);
        s.replace(at + 1, 1, "g");
        return s;
    };
    for (const std::string& bad : {break_in(text, 50), break_in(break_in(text, 50), 10)}) {
        for (const int kind : {0, 1, 2}) {
            const std::string path = kind == 1   ? td.write_gz("bad.rbt.gz", bad)
                                     : kind == 2 ? td.write("bad.rbt.zst", rbcd::test::zstd_frames(rbcd::test::by_frame(bad)))
                                                 : td.write("bad.rbt", bad);
            td.plant_old_outputs();
            const Result one = run_with_outputs(td, {"-q", "--trace", path});
            REQUIRE(one.status == 2);
            for (const char* jobs : {"2", "3"}) {
                INFO("--jobs " << jobs << (kind == 1 ? " gzip" : kind == 2 ? " zstd" : ""));
                const Result n = run_with_outputs(td, {"-q", "--trace", path, "--jobs", jobs});
                expect_input_error(td, n, {});
                CHECK(n.err == one.err);
            }
        }
    }
}

// The trace reader's bound on the run's declared work (docs/limits.md) counts
// the whole run: each worker sees only its frames, so the parent adds the
// parts' work and reads again the part where one process crosses the bound.
TEST_CASE("rbcd-sim --jobs: the bound on declared work counts the whole run, as one process does", "[jobs]") {
    TempDir td;
    // At 400 MHz the bound is 2^62 ps of cycles / 4 = 461,168,601,842,738
    // cycles; a tile may declare base=2^40. Four frames of 120 such tiles
    // declare 1.3e14 each: every frame is far below the bound, the run
    // crosses it in frame 3.
    std::string text = "rbcd-trace 1\n";
    for (unsigned f = 0; f < 4; ++f) {
        text += "frame " + std::to_string(f) + "\n";
        for (unsigned i = 0; i < 120; ++i)
            text += "tile " + std::to_string(i % 40) + " " + std::to_string(i / 40) + " base=1099511627776\nf " +
                    std::to_string(16 * (i % 40)) + " " + std::to_string(16 * (i / 40)) + " 5 1 F\n";
    }
    const std::string t = td.write("work.rbt", text);
    for (const bool gz : {false, true}) {
        const std::string path = gz ? td.write_gz("work.rbt.gz", text) : t;
        td.plant_old_outputs();
        const Result one = run_with_outputs(td, {"-q", "--trace", path});
        REQUIRE(one.status == 2);
        CHECK_THAT(one.err, Contains("the run is too long to simulate: the work declared up to tile ") && Contains(" of frame 3 "));
        for (const char* jobs : {"2", "4"}) {
            INFO("--jobs " << jobs << (gz ? " gzip" : ""));
            const Result n = run_with_outputs(td, {"-q", "--trace", path, "--jobs", jobs});
            expect_input_error(td, n, {});
            CHECK(n.err == one.err);
        }
    }
    // Within the bound, --frames alone: the frames before the range count too,
    // as one process reads and checks them.
    const std::string three = td.write("three.rbt", text.substr(0, text.find("frame 3\n")));
    const Result ok = run_sim(td, {"-q", "--trace", three, "--jobs", "3"});
    CHECK(ok.status == 0);
}

TEST_CASE("rbcd-sim --jobs: a scene with nothing in view says so as one process does", "[jobs]") {
    TempDir td;
    const std::string scene =
        td.write("empty.toml", "format = \"rbcd-scene 1\"\nframes = 40\n[screen]\nwidth = 64\nheight = 48\n"
                               "[camera]\neye = [0.0, 0.0, 0.0]\ntarget = [0.0, 0.0, -1.0]\nfov_y = 60.0\n"
                               "near = 0.1\nfar = 100.0\n");
    const Result one = run_with_outputs(td, {"-q", "--scene", scene});
    const Result n = run_with_outputs(td, {"-q", "--scene", scene, "--jobs", "2"});
    expect_input_error(td, n, {"nothing in view"});
    CHECK(n.err == one.err);
}

TEST_CASE("rbcd-sim --jobs: collisions into a pipe whose reader goes away leave nothing behind", "[jobs]") {
    // SIGPIPE ends the run as an interrupt does: the stats' temporary and the
    // workers' directory (in TMPDIR for collisions on standard output) go.
    // The reader closes its end at once, so that the first write fails.
    TempDir td;
    const std::string trace = default_trace(td, false);
    for (const bool scene : {true, false}) {
        INFO((scene ? "a scene" : "a trace"));
        std::ofstream(td.stats()) << "an older result\n";   // gone too: the run failed
        std::vector<std::string> args{"-c", "set -o pipefail; TMPDIR=\"$1\" \"$0\" \"${@:2}\" | { exec 0<&-; sleep 0.5; }",
                                      RBCD_SIM, td.path("out"), "-q", "--jobs", "3", "--collisions", "-", "--stats",
                                      td.stats()};
        if (!scene) args.insert(args.end(), {"--trace", trace});
        else args.insert(args.end(), {"--scene", small_scene(td)});
        const Result r = run_program(td, "/bin/bash", args);
        INFO(r.err);
        CHECK(r.status != 0);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        std::string names;
        for (const auto& e : td.out_entries()) names += e + " ";
        INFO("left behind: " << names);
        CHECK(td.out_entries().empty());
    }
}

// A full disk is the output's failure, named as the user named it: the first
// worker writes into the run's output as its standard output ("-"), and its
// error is relayed; not an "internal error". The other outputs are left as a
// failed run leaves them (none).
TEST_CASE("rbcd-sim --jobs: a full disk names the output, as one process does", "[jobs]") {
    if (!std::filesystem::exists("/dev/full")) {
        WARN("skipped: no /dev/full here");
        return;
    }
    TempDir td;
    const std::string trace = default_trace(td, false);
    for (const char* jobs : {"1", "2", "3"}) {
        for (const char* flag : {"--collisions", "--stats"}) {
            INFO("--jobs " << jobs << " " << flag << " /dev/full");
            // The run's other output: an older result there goes too.
            const bool stats_full = std::string(flag) == "--stats";
            const std::string other = stats_full ? td.collisions() : td.stats();
            std::ofstream(other) << "an older result\n";
            std::vector<std::string> args{"-q", "--trace", trace, "--jobs", jobs, flag, "/dev/full"};
            args.insert(args.end(), {stats_full ? "--collisions" : "--stats", other});
            const Result r = run_sim(td, args);
            INFO(r.err);
            CHECK(r.status == 1);
            CHECK(r.err == "rbcd-sim: /dev/full: write failed: No space left on device\n");
            CHECK_FALSE(std::filesystem::exists(other));
            CHECK(td.out_entries().empty());
        }
    }
}

// The join's own write failing: a file size limit stands for the full disk
// (writes past it fail with EFBIG once SIGXFSZ is ignored, as ENOSPC would),
// set just below the whole collisions file: each part's own file is well
// under it (two parts of about 20 KiB each here), so the workers write theirs
// and the parent's append of the second part is what fails.
TEST_CASE("rbcd-sim --jobs: the join's append failing names the output and leaves nothing", "[jobs]") {
    TempDir td;
    const std::string trace = default_trace(td, false);
    const Result one = run_sim(td, {"-q", "--trace", trace, "--collisions", td.collisions()});
    REQUIRE(one.status == 0);
    const std::uint64_t whole = std::filesystem::file_size(td.collisions());
    std::filesystem::remove(td.collisions());
    // sh's ulimit -f counts 512-byte blocks (POSIX).
    const std::uint64_t blocks = (whole - 1) / 512;
    INFO("collisions " << whole << " bytes, limit " << blocks * 512);
    REQUIRE(whole > 16 * 1024);
    std::ofstream(td.stats()) << "an older result\n";
    const std::string cmd = "ulimit -f " + std::to_string(blocks) + "; trap '' XFSZ; exec \"$0\" \"$@\"";
    const Result r = run_program(td, "/bin/sh", {"-c", cmd, RBCD_SIM, "-q", "--trace", trace, "--jobs", "2",
                                                 "--collisions", td.collisions(), "--stats", td.stats()});
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(r.err == "rbcd-sim: " + td.collisions() + ": write failed: File too large\n");
    CHECK(td.out_entries().empty());
}

TEST_CASE("rbcd-sim --jobs: a run stopped by SIGTERM leaves no output, no workers' directory, no workers", "[jobs]") {
    TempDir td;
    td.plant_old_outputs();
    const pid_t pid =
        spawn_program({RBCD_SIM, "-q", "--jobs", "2", "--collisions", td.collisions(), "--stats", td.stats()});
    // The workers' directory appears beside the collisions just before they start.
    bool started = false;
    for (int i = 0; i < 5000 && !started; ++i) {
        for (const auto& e : td.out_entries()) started = started || e.rfind(".rbcd-sim-jobs.", 0) == 0;
        if (!started) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    CHECK(started);
    REQUIRE(kill(pid, SIGTERM) == 0);
    int st = 0;
    REQUIRE(waitpid(pid, &st, 0) == pid);
    CHECK(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 128 + SIGTERM);
    // Workers still running would write into the directory after this.
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    std::string names;
    for (const auto& e : td.out_entries()) names += e + " ";
    INFO("left behind: " << names);
    CHECK(td.out_entries().empty());
}
