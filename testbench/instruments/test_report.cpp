// The --stats document, the stdout summary and the progress line.
#include <catch2/catch.hpp>

#include "rbcd/run/progress.h"
#include "rbcd/testbench/instruments/instruments_util.h"

using namespace rbcd;
using rbcd::tb::frag;

namespace {

// `frames` frames of one tile each; frame f has f + 1 front faces on distinct pixels
// and other=40, so the baseline and the overhead vary from frame to frame.
MemorySource growing_frames(unsigned frames) {
    MemorySource src(StreamHeader{});
    for (unsigned f = 0; f < frames; ++f) {
        src.add_frame(f);
        std::vector<Fragment> fs;
        for (unsigned i = 0; i <= f; ++i) fs.push_back(frag(i % 16, i / 16, 100 + i, 1, 'F'));
        src.add_tile(tb::tile(f, 0, 0, fs, 40));
    }
    return src;
}

} // namespace

TEST_CASE("report: stats JSON has the totals keys, the GPU and energy figures", "[report]") {
    auto src = growing_frames(3);
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    const auto j = run.stats();

    // "totals": exactly the contract's integer keys.
    const auto& t = j["totals"];
    REQUIRE(t.is_object());
    CHECK(t.size() == 8);
    for (const char* k : {"frames", "tiles", "fragments", "overflows", "stack_overflows", "orphan_back_faces", "hits",
                          "cycles"}) {
        INFO(k);
        REQUIRE(t.contains(k));
        CHECK(t[k].is_number_unsigned());
    }
    CHECK(t["frames"] == 3);
    CHECK(t["fragments"] == 1 + 2 + 3);

    const auto& g = j["gpu"];
    for (const char* k : {"baseline_cycles", "cycles_with_unit", "overhead_pct", "stalls", "overhead_cycles",
                          "per_frame_overhead_pct", "bank_wait"}) {
        INFO(k);
        CHECK(g.contains(k));
    }
    for (const char* k : {"extra_primitives", "extra_fragments", "unit_queue", "unit_no_bank", "tail"}) {
        INFO(k);
        CHECK(g["overhead_cycles"].contains(k));
    }
    const auto& e = j["energy"];
    for (const char* k : {"blocks", "dynamic_pj", "leakage_pj", "total_pj", "total_nj", "average_power_mw",
                          "per_event_pj", "per_frame", "gpu", "zeb_device"}) {
        INFO(k);
        CHECK(e.contains(k));
    }
    for (const char* k : {"input_queue", "zeb_bank0", "zeb_bank1", "insertion_sorter", "zoverlap_tester",
                          "output_buffer", "memory"}) {
        INFO(k);
        CHECK(e["blocks"].contains(k));
    }
    for (const char* k : {"baseline_pj", "with_unit_pj", "unit_pj", "overhead_pct"}) {
        INFO(k);
        CHECK(e["gpu"].contains(k));
    }
    // No per-frame data in the document: it streams to --frame-stats.
    CHECK_FALSE(j.contains("frames"));
    CHECK_FALSE(j.contains("series"));

    // The frame lines add up to the totals.
    REQUIRE(run.frames.size() == 3);
    std::uint64_t base = 0, with = 0;
    double unit_pj = 0;
    for (std::size_t i = 0; i < run.frames.size(); ++i) {
        const auto& f = run.frames[i];
        CHECK(f["frame"] == i);
        base += f["baseline_cycles"].get<std::uint64_t>();
        with += f["cycles_with_unit"].get<std::uint64_t>();
        unit_pj += f["energy_pj"]["unit"].get<double>();
    }
    CHECK(g["baseline_cycles"] == base);
    CHECK(g["cycles_with_unit"] == with);
    CHECK(t["cycles"] == with);
    CHECK(g["overhead_pct"].get<double>() == Approx(100.0 * (double(with) - double(base)) / double(base)));
    CHECK(unit_pj == Approx(e["total_pj"].get<double>()));
    // Frame 2: other=40 spread around 3 front faces, 43 fragments into 4 processors at 8
    // cycles, 4 a cycle from the rasterizer: the 43rd (10 rounds) starts at 81: done at 89.
    CHECK(run.frames[2]["baseline_cycles"] == 89);
}

TEST_CASE("report: summary shows the first frames the worst and the mean", "[report]") {
    auto src = growing_frames(12);
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    const auto j = run.stats();
    const std::string s = run.summary();
    INFO(s);
    CHECK(s.find("rbcd-sim: test") == 0);
    CHECK(s.find("frames 12") != std::string::npos);
    for (const char* block : {"rasterizer", "fragment_processors", "input_queue", "zeb_bank0", "zeb_bank1",
                              "insertion_sorter", "zoverlap_tester", "output_buffer", "memory"})
        CHECK(s.find(std::string("\n  ") + block + " ") != std::string::npos);
    CHECK(s.find("GPU time") != std::string::npos);
    CHECK(s.find("GPU energy") != std::string::npos);
    CHECK(s.find("average power") != std::string::npos);
    // Twelve frames: 0, 1, 2, then the worst and the mean; not frame 5 on its own row.
    CHECK(s.find("\n           0 ") != std::string::npos);
    CHECK(s.find("\n           2 ") != std::string::npos);
    CHECK(s.find("\n           5 ") == std::string::npos);
    const std::uint64_t worst = j["gpu"]["per_frame_overhead_pct"]["max_frame"].get<std::uint64_t>();
    CHECK(s.find("worst " + std::to_string(worst)) != std::string::npos);
    CHECK(s.find("\n        mean ") != std::string::npos);
}

TEST_CASE("report: progress waits for the delay then rate-limits and clears", "[report]") {
    double now = 100.0;
    std::string out;
    Progress p(true, [&] { return now; }, [&](const std::string& s) { out += s; }, 3.0, 0.5);
    p.on_frame(1, 1000);
    now = 102.9;
    p.on_frame(2, 2000);
    CHECK(out.empty());   // a short run prints nothing
    now = 104.0;
    p.on_frame(3, 8000);
    CHECK(out == "\rrbcd-sim: 3 frames done, 8000 fragments, 2000 fragments/s");
    out.clear();
    now = 104.2;
    p.on_frame(4, 9000);
    CHECK(out.empty());   // within the interval
    now = 104.6;
    p.on_frame(5, 9200);
    CHECK(out.find("5 frames done") != std::string::npos);
    CHECK(p.shown());
    out.clear();
    p.finish();
    CHECK(out.size() > 2);
    CHECK(out.front() == '\r');
    CHECK(out.back() == '\r');
    CHECK(out.find_first_not_of(" \r") == std::string::npos);
    out.clear();
    p.finish();
    CHECK(out.empty());

    // Disabled (stderr not a terminal): never prints.
    std::string none;
    Progress off(false, [&] { return now; }, [&](const std::string& s) { none += s; }, 0.0, 0.0);
    now += 100;
    off.on_frame(9, 9);
    off.finish();
    CHECK(none.empty());
}
