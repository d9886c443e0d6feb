// Self-checks (hw/self_check): silent on a real run with overflows, dropped
// fragments and hits; each end-of-run check fires when its invariant is broken
// in the counters (the test-only hook: the snapshot is a plain struct), the
// per-tile one when the tester's test-only hook loses an element of a tile.
#include <catch2/catch.hpp>

#include <functional>

#include "rbcd/common/errors.h"
#include "rbcd/hw/self_check.h"
#include "rbcd/testbench/hw/tb_util.h"

using namespace rbcd;
using namespace rbcd::tb;

namespace {
// A frame with a hit (objects 1 and 2 overlap at pixel 0,0), an overflowing
// list (M = 4, five fragments at pixel 1,1) and a tile in a second bank.
SimConfig real_config() {
    SimConfig cfg;
    cfg.zeb.list_length = 4;
    return cfg;
}

void add_real_frames(MemorySource& src) {
    src.add_frame(0);
    src.add_tile(tile(0, 0, 0, {frag(0, 0, 100, 1, 'F'), frag(0, 0, 200, 2, 'F'), frag(0, 0, 300, 1, 'B'),
                                frag(0, 0, 400, 2, 'B'), frag(1, 1, 10, 3, 'F'), frag(1, 1, 20, 3, 'B'),
                                frag(1, 1, 30, 4, 'F'), frag(1, 1, 40, 4, 'B'), frag(1, 1, 50, 5, 'F')}));
    src.add_tile(tile(0, 1, 0, {frag(16, 0, 5, 4, 'F'), frag(16, 0, 7, 4, 'B')}, 7));
    src.add_frame(1);
}

SelfCheckCounters real_run() {
    MemorySource src(StreamHeader{});
    add_real_frames(src);
    SystemRun run(real_config(), src);
    return self_check_counters(*run.sys);
}

// The same run with the tester losing one element of its tile-th tile: the
// message it stops with ("" if it does not stop).
std::string run_losing_element(std::uint64_t tile_index) {
    MemorySource src(StreamHeader{});
    add_real_frames(src);
    const SimConfig cfg = real_config();
    RecordingSink sink;
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
    rbcd_system sys("rbcd", cfg, src, sink);
    sys.tester.lose_element_for_test(tile_index);
    try {
        sys.run();
    } catch (const RunError& e) {
        return e.what();
    }
    return "";
}
} // namespace

TEST_CASE("self-check: a real run passes every check", "[self_check]") {
    const SelfCheckCounters c = real_run();
    CHECK(c.feed_fragments == 11);
    CHECK(c.sorter_overflows > 0);
    CHECK(c.tester_hits > 0);
    CHECK(self_check(c).empty());
}

TEST_CASE("self-check: each broken invariant fires its own check", "[self_check]") {
    const SelfCheckCounters good = real_run();
    REQUIRE(self_check(good).empty());
    const std::pair<const char*, std::function<void(SelfCheckCounters&)>> cases[] = {
        {"input_queue_empty", [](SelfCheckCounters& c) { ++c.feed_fragments; }},
        {"fragment_conservation", [](SelfCheckCounters& c) { --c.tester_elements; }},
        {"fragment_conservation", [](SelfCheckCounters& c) { ++c.sorter_overflows; ++c.sorter_dropped_new; }},
        {"overflow_split", [](SelfCheckCounters& c) { ++c.sorter_dropped_last; }},
        {"banks_released", [](SelfCheckCounters& c) { c.banks_not_free = 1; }},
        {"banks_released", [](SelfCheckCounters& c) { ++c.tester_tiles; }},
        {"output_queue_empty", [](SelfCheckCounters& c) { ++c.outbuf_records; }},
        {"output_queue_empty", [](SelfCheckCounters& c) { c.outbuf_bytes += 8; }},
        {"records_reported", [](SelfCheckCounters& c) { ++c.tester_hits; ++c.tester_raw_hits; }},
        {"records_reported", [](SelfCheckCounters& c) { --c.host_overflow_records; ++c.host_hit_records; }},
        {"hits_filtered", [](SelfCheckCounters& c) { ++c.tester_filtered_hits; }},
        {"cycles_consistent", [](SelfCheckCounters& c) { c.tester_busy_cycles = c.total_cycles + 1; }},
        {"cycles_consistent", [](SelfCheckCounters& c) { c.feed_busy_cycles = c.total_cycles + 1; }},
    };
    for (const auto& [name, tamper] : cases) {
        SelfCheckCounters c = good;
        tamper(c);
        const std::string msg = self_check(c);
        INFO(name << ": " << msg);
        CHECK(msg.rfind(std::string("self-check '") + name + "' failed: ", 0) == 0);
        CHECK(msg.find('\n') == std::string::npos);
    }
}

// One process per test case (catch_discover_tests): each elaborates its own system.
TEST_CASE("self-check: a tile that lost a fragment stops the run naming the tile", "[self_check]") {
    // Tile 0: 9 fragments, 8 stored and 1 dropped by the full list at (1,1); one element lost.
    const std::string msg = run_losing_element(0);
    INFO(msg);
    CHECK(msg == "self-check 'tile_conservation' failed: frame 0, tile column 0 row 0: in 9 != stored 7 + "
                 "dropped 1 (a model bug, not bad input)");
}

TEST_CASE("self-check: tile_conservation names the second tile when that one loses a fragment", "[self_check]") {
    const std::string msg = run_losing_element(1);
    INFO(msg);
    CHECK(msg == "self-check 'tile_conservation' failed: frame 0, tile column 1 row 0: in 2 != stored 1 + "
                 "dropped 0 (a model bug, not bad input)");
}
