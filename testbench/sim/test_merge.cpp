// rbcd-merge (docs/sweeps.md): runs over consecutive frame ranges merged into
// the outputs of one run over all their frames, byte for byte (wall time
// aside), and refused when they cannot be one run.
#include "rbcd/testbench/sim/cli_util.h"

#include <nlohmann/json.hpp>
#include <functional>
#include <regex>

#ifndef RBCD_MERGE
#error "RBCD_MERGE must name the rbcd-merge executable"
#endif

using namespace rbcd::cli_test;

namespace {

std::string mask_wall_time(const std::string& stats) {
    static const std::regex wall(R"re("(wall_seconds|fragments_per_second)": [^,\n]+)re");
    return std::regex_replace(stats, wall, "\"$1\": 0");
}

enum class Input { Trace, Scene };

struct Split {
    TempDir td;
    std::string trace;   // empty: the default scene itself
    std::vector<std::string> sets;

    explicit Split(std::vector<std::string> config, Input input = Input::Trace) : sets(std::move(config)) {
        if (input == Input::Scene) return;
        // The default scene (60 frames) as a trace, so that parts and whole read one file.
        trace = td.path("input.rbt");
        const Result w = run_sim(td, {"-q", "--write-trace", trace});
        REQUIRE(w.status == 0);
    }
    std::vector<std::string> base() const {
        std::vector<std::string> a{"-q"};
        if (!trace.empty()) a.insert(a.end(), {"--trace", trace});
        for (const auto& s : sets) a.insert(a.end(), {"--set", s});
        return a;
    }
    std::string part(int i, const char* ext) const { return td.path("part" + std::to_string(i) + ext); }
    // Runs the part over frames `range` into part<i>.{json,txt,jsonl}.
    void run_part(int i, const std::string& range) const {
        auto a = base();
        a.insert(a.end(), {"--frames", range, "--stats", part(i, ".json"), "--collisions", part(i, ".txt"),
                           "--frame-stats", part(i, ".jsonl")});
        const Result r = run_sim(td, a);
        INFO(r.err);
        REQUIRE(r.status == 0);
    }
    Result merge(const std::vector<std::string>& parts) const {
        std::vector<std::string> a{"--stats", td.stats(), "--collisions", td.collisions(), "--frame-stats",
                                   td.path("out/frames.jsonl")};
        a.insert(a.end(), parts.begin(), parts.end());
        return run_program(td, RBCD_MERGE, a);
    }
};

} // namespace

TEST_CASE("split runs merge into the whole run's stats, collisions and frame stats, byte for byte", "[merge]") {
    // The default configuration, and one that stalls on banks, overflows and
    // filters output, so that every kind of counter moves; on a trace, and on
    // the scene itself, whose later parts render no frame before their range
    // (a frame is a function of its number).
    const std::vector<std::string> config = GENERATE(
        std::vector<std::string>{},
        std::vector<std::string>{"zeb.banks=1", "zeb.list_length=4", "gpu.bank_wait=unit", "tester.output=tile"});
    const Input input = GENERATE(Input::Trace, Input::Scene);
    INFO((input == Input::Scene ? "the default scene" : "the default scene as a trace"));
    Split s(config, input);
    s.run_part(0, "0:6");
    s.run_part(1, "7:33");
    s.run_part(2, "34:");   // to the input's end: the merged run is the whole input's
    Result m = s.merge({s.part(0, ".json"), s.part(1, ".json"), s.part(2, ".json")});
    INFO(m.err);
    REQUIRE(m.status == 0);
    CHECK(m.err.empty());
    const std::string merged_stats = slurp(s.td.stats()), merged_collisions = slurp(s.td.collisions()),
                      merged_frames = slurp(s.td.path("out/frames.jsonl"));

    // The whole run, with the command line the merge recorded as its equivalent.
    const auto argv = nlohmann::json::parse(merged_stats)["provenance"]["argv"].get<std::vector<std::string>>();
    REQUIRE(argv.size() > 1);
    CHECK(std::find(argv.begin(), argv.end(), "--frames") == argv.end());
    const Result w = run_sim(s.td, std::vector<std::string>(argv.begin() + 1, argv.end()));
    INFO(w.err);
    REQUIRE(w.status == 0);
    const std::string whole_stats = slurp(s.td.stats());
    CHECK(nlohmann::json::parse(whole_stats)["totals"]["frames"] == 60);
    CHECK(mask_wall_time(merged_stats) == mask_wall_time(whole_stats));
    CHECK(merged_collisions == slurp(s.td.collisions()));
    CHECK(merged_frames == slurp(s.td.path("out/frames.jsonl")));
}

TEST_CASE("rbcd-merge refuses parts that are not one run", "[merge]") {
    // Made once for all sections (each section re-enters the test case); no
    // section changes these files.
    static const Split& s = [] () -> const Split& {
        static Split split({});
        split.run_part(0, "0:9");
        split.run_part(1, "10:19");
        split.run_part(2, "25:29");
        return split;
    }();

    SECTION("out of order") {
        s.td.plant_old_outputs();
        expect_input_error(s.td, s.merge({s.part(1, ".json"), s.part(0, ".json")}),
                           {"rbcd-merge: ", s.part(0, ".json"), "frame_range", "frame 0 does not follow frame 19"});
    }
    SECTION("a gap") {
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.part(1, ".json"), s.part(2, ".json")}),
                           {s.part(2, ".json"), "frame 25 does not follow frame 19"});
    }
    SECTION("another configuration") {
        auto a = s.base();
        a.insert(a.end(), {"--set", "zeb.list_length=4", "--frames", "10:19", "--stats", s.part(3, ".json"),
                           "--collisions", s.part(3, ".txt")});
        REQUIRE(run_sim(s.td, a).status == 0);
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.part(3, ".json")}),
                           {s.part(3, ".json"), "config"});
    }
    SECTION("not a stats file") {
        std::ofstream(s.td.path("bad.json")) << "{\"format\": \"rbcd-stats 2\"}";
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.td.path("bad.json")}),
                           {s.td.path("bad.json"), "stats: input: missing"});
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.part(0, ".txt")}),
                           {s.part(0, ".txt"), "not JSON"});
        expect_input_error(s.td, s.merge({s.td.path("missing.json")}), {s.td.path("missing.json")});
    }
    SECTION("a part's collisions file gone") {
        s.run_part(4, "10:19");
        fs::remove(s.part(4, ".txt"));
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.part(4, ".json")}), {s.part(4, ".txt")});
    }
    SECTION("a tampered counter") {
        auto j = nlohmann::json::parse(slurp(s.part(1, ".json")));
        j["blocks"]["insertion_sorter"]["overflows"] = -1;
        std::ofstream(s.td.path("tampered.json")) << j.dump(2);
        expect_input_error(s.td, s.merge({s.part(0, ".json"), s.td.path("tampered.json")}),
                           {"blocks.insertion_sorter.overflows", "not an unsigned integer"});
    }
}

// ---- Hostile parts (issue 22): each case a way a merge can go wrong unchecked.
namespace {

// Parts 0:29 and 30:59 of the default scene, made once per process.
const Split& halves() {
    static Split split({});
    static const bool made = [] {
        split.run_part(0, "0:29");
        split.run_part(1, "30:59");
        return true;
    }();
    (void)made;
    return split;
}

// A copy of a part's stats with `edit` applied, written beside it.
std::string tampered(const Split& s, int i, const std::string& name, const std::function<void(nlohmann::json&)>& edit) {
    auto j = nlohmann::json::parse(slurp(s.part(i, ".json")));
    edit(j);
    const std::string p = s.td.path(name);
    std::ofstream(p) << j.dump(2);
    return p;
}

// The value after OPTION in a part's recorded argv set to `value`.
void set_arg(nlohmann::json& j, const std::string& option, const std::string& value) {
    auto& argv = j["provenance"]["argv"];
    for (std::size_t k = 0; k + 1 < argv.size(); ++k)
        if (argv[k] == option) argv[k + 1] = value;
}

} // namespace

TEST_CASE("rbcd-merge: an output naming a part's own file is refused and the file kept", "[merge_hostile]") {
    const Split& s = halves();
    const std::string own = slurp(s.part(0, ".txt"));
    Result r = run_program(s.td, RBCD_MERGE,
                           {"--stats", s.td.stats(), "--collisions", s.part(0, ".txt"), s.part(0, ".json"), s.part(1, ".json")});
    expect_input_error(s.td, r, {"--collisions", "is the input file"});
    CHECK(slurp(s.part(0, ".txt")) == own);
    // Two outputs into one file: refused, not exit 0 with one lost.
    r = run_program(s.td, RBCD_MERGE,
                    {"--stats", s.td.stats(), "--collisions", s.td.stats(), s.part(0, ".json"), s.part(1, ".json")});
    expect_input_error(s.td, r, {"--collisions", "is also --stats's output"});
}

TEST_CASE("rbcd-merge: parts that leave out frames are merged as the range they cover", "[merge_hostile]") {
    Split s({});
    s.run_part(0, "10:29");
    s.run_part(1, "30:49");
    Result m = s.merge({s.part(0, ".json"), s.part(1, ".json")});
    INFO(m.err);
    REQUIRE(m.status == 0);
    const auto stats = nlohmann::json::parse(slurp(s.td.stats()));
    const auto argv = stats["provenance"]["argv"].get<std::vector<std::string>>();
    const auto at = std::find(argv.begin(), argv.end(), "--frames");
    REQUIRE(at != argv.end());
    CHECK(*(at + 1) == "10:49");
    CHECK(stats["totals"]["frames"] == 40);
    // The recorded command line reproduces the merged stats.
    const std::string merged = slurp(s.td.stats());
    const Result w = run_sim(s.td, std::vector<std::string>(argv.begin() + 1, argv.end()));
    REQUIRE(w.status == 0);
    CHECK(mask_wall_time(merged) == mask_wall_time(slurp(s.td.stats())));
}

TEST_CASE("rbcd-merge: a part whose frames are not what its --frames selects is refused", "[merge_hostile]") {
    const Split& s = halves();
    // Claims 25:59 but holds 30..59: frames 25..29 would be missing.
    const std::string claims = tampered(s, 1, "claims.json", [](nlohmann::json& j) { set_arg(j, "--frames", "25:59"); });
    expect_input_error(s.td, s.merge({s.part(0, ".json"), claims}), {"claims.json", "frame_range: 30..59", "25:59"});
    // totals.frames against its own frame_range.
    const std::string short_count = tampered(s, 1, "count.json", [](nlohmann::json& j) { j["totals"]["frames"] = 5; });
    expect_input_error(s.td, s.merge({s.part(0, ".json"), short_count}),
                       {"count.json", "totals.frames: 5 does not match frame_range 30..59"});
}

TEST_CASE("rbcd-merge: sums past 2^64 are refused", "[merge_hostile]") {
    const Split& s = halves();
    const std::string huge = tampered(s, 1, "huge.json", [](nlohmann::json& j) {
        j["totals"]["cycles"] = UINT64_MAX;
        j["gpu"]["cycles_with_unit"] = UINT64_MAX;
    });
    expect_input_error(s.td, s.merge({s.part(0, ".json"), huge}), {"huge.json", "beyond 2^64 - 1"});
    const std::string counter = tampered(s, 1, "counter.json", [](nlohmann::json& j) {
        j["blocks"]["insertion_sorter"]["overflows"] = UINT64_MAX;
    });
    const std::string counter0 = tampered(s, 0, "counter0.json", [](nlohmann::json& j) {
        j["blocks"]["insertion_sorter"]["overflows"] = 2;
    });
    expect_input_error(s.td, s.merge({counter0, counter}), {"blocks.insertion_sorter.overflows", "beyond 2^64 - 1"});
}

TEST_CASE("rbcd-merge: collision files are read and checked against their part's frames", "[merge_hostile]") {
    const Split& s = halves();
    // Another part's file.
    const std::string other = tampered(s, 1, "other.json", [&](nlohmann::json& j) { set_arg(j, "--collisions", s.part(0, ".txt")); });
    expect_input_error(s.td, s.merge({s.part(0, ".json"), other}), {s.part(0, ".txt") + ":2", "frame 0 where frame 30"});
    // Binary garbage.
    const std::string junk = s.td.write("junk.txt", std::string("\x00\x01\xff\x1b garbage\n", 13));
    const std::string garbage = tampered(s, 1, "garbage.json", [&](nlohmann::json& j) { set_arg(j, "--collisions", junk); });
    const Result g = s.merge({s.part(0, ".json"), garbage});
    expect_input_error(s.td, g, {"junk.txt:1", "not a collisions file"});
    CHECK(g.err.find('\x1b') == std::string::npos);
    // Cut short: no final LF (a plain join would write "frame 29frame 30").
    std::string text = slurp(s.part(0, ".txt"));
    text.pop_back();
    const std::string cut = s.td.write("cut.txt", text);
    const std::string cut_json = tampered(s, 0, "cut.json", [&](nlohmann::json& j) { set_arg(j, "--collisions", cut); });
    expect_input_error(s.td, s.merge({cut_json, s.part(1, ".json")}), {"cut.txt", "does not end with LF"});
    // A FIFO named by the provenance: refused, not waited on.
    const std::string fifo = s.td.path("fifo.txt");
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    const std::string fifo_json = tampered(s, 1, "fifo.json", [&](nlohmann::json& j) { set_arg(j, "--collisions", fifo); });
    expect_input_error(s.td, s.merge({s.part(0, ".json"), fifo_json}), {"fifo.txt: cannot read collisions file: is a FIFO"});
}

TEST_CASE("rbcd-sim --frames: an empty value or a range without frames is refused", "[frames_cli]") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--frames", ""}), {"--frames: empty value"});
    expect_input_error(td, run_with_outputs(td, {"--frames", "60:70"}),
                       {"--frames: 60:70 selects no frame: the input has 60 frames (0..59)"});
}

TEST_CASE("rbcd-merge: messages are one line, escaped, long tokens cut", "[merge_hostile]") {
    TempDir td;
    // A 1 MB token the JSON parser quotes back, with an ESC in it.
    const std::string bad = td.write("bad.json", "{\"format\": \"" + std::string(1 << 20, 'x') + "\x1b");
    const Result r = run_program(td, RBCD_MERGE, {"--stats", td.stats(), bad});
    expect_input_error(td, r, {"bad.json", "not JSON", "bytes)"});
    CHECK(r.err.size() < 4096);
    CHECK(r.err.find('\x1b') == std::string::npos);
}
