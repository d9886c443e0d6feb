// rbcd-merge (docs/sweeps.md): runs over consecutive frame ranges merged into
// the outputs of one run over all their frames, byte for byte (wall time
// aside), and refused when they cannot be one run.
#include "rbcd/testbench/sim/cli_util.h"

#include <nlohmann/json.hpp>
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

struct Split {
    TempDir td;
    std::string trace = td.path("input.rbt");
    std::vector<std::string> sets;

    explicit Split(std::vector<std::string> config) : sets(std::move(config)) {
        // The default scene (60 frames) as a trace, so that parts and whole read one file.
        const Result w = run_sim(td, {"-q", "--write-trace", trace});
        REQUIRE(w.status == 0);
    }
    std::vector<std::string> base() const {
        std::vector<std::string> a{"-q", "--trace", trace};
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
    // filters output, so that every kind of counter moves.
    const std::vector<std::string> config = GENERATE(
        std::vector<std::string>{},
        std::vector<std::string>{"zeb.banks=1", "zeb.list_length=4", "gpu.bank_wait=unit", "tester.output=tile"});
    Split s(config);
    s.run_part(0, "0:6");
    s.run_part(1, "7:33");
    s.run_part(2, "34:59");
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
