// The timing model's worked example (docs/timing.md) and the stall behaviour
// of banks, queues and output buffer, checked cycle for cycle. Default GPU:
// 4 fragments a cycle, fragment queue 64, early-Z 1 cycle, 4 fragment
// processors at 8 cycles a fragment.
#include <catch2/catch.hpp>

#include "rbcd/testbench/hw/tb_util.h"

using namespace rbcd;
using rbcd::tb::frag;

namespace {

// docs/timing.md, "Worked example": one tile, six fragments on three pixels.
MemorySource worked_example() {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(tb::tile(0, 0, 0,
                          {frag(0, 0, 100, 1, 'F'),    // pixel A
                           frag(0, 0, 200, 2, 'F'),    // pixel A, right behind: same-pixel hazard
                           frag(1, 0, 50, 3, 'F'),     // pixel B
                           frag(1, 0, 60, 3, 'B'),     // pixel B, hazard again
                           frag(2, 0, 10, 4, 'B'),     // pixel C: an orphan back face
                           frag(0, 0, 300, 1, 'B')},   // pixel A: closes id 1 around id 2's front face
                          8));
    return src;
}

SimConfig worked_config() {
    SimConfig cfg;
    cfg.memory.latency_min = cfg.memory.latency_max = 50;
    return cfg;
}

} // namespace

TEST_CASE("hw timing: worked example with forwarding takes 70 cycles", "[timing]") {
    auto src = worked_example();
    tb::SystemRun run(worked_config(), src);
    const auto& s = *run.sys;
    // Rasterizer: other=8 spread over the 7 gaps around the 6 fragments (1 before each,
    // 2 after the last): o f0 o f1 | o f2 o f3 | o f4 o f5 | o o, 4 a cycle: done at 4.
    CHECK(s.raster.stats().busy_cycles == 4);
    CHECK(s.raster.stats().stall_queue_full_cycles == 0);
    CHECK(s.raster.stats().stall_fragment_queue_cycles == 0);
    // Sorter issues at cycles 1..6 (one per cycle, hazards forwarded): fill done at 6 + 3 = 9.
    CHECK(s.sorter.stats().hazard_forwards == 2);
    CHECK(s.sorter.stats().hazard_stall_cycles == 0);
    // Tester: starts at 9, first row read 1 cycle, 6 elements of 1 cycle each (the one hit
    // takes the element's cycle): 16. Flush at 16: 16 bytes take 4 channel cycles, 50 latency: 70.
    CHECK(s.tester.stats().busy_cycles == 7);
    CHECK(s.tester.stats().idle_cycles == 9);
    // Fragment processors: 14 fragments entering at 0 (4), 1 (4), 2 (4), 3 (2) start at
    // 1, 9, 17, 25 (each processor busy 8 cycles): done at 33. The frame ends when its
    // records are in memory, at 70; the host's readback goes on in the other region.
    CHECK(s.fragments.stats().fragments == 14);
    CHECK(s.total_cycles() == 70);
    REQUIRE(run.hits().size() == 1);
    CHECK(run.hits()[0] == HitRecord{0, 0, 1, 2, 300});
    CHECK(s.tester.stats().orphan_back_faces == 1);
    CHECK(s.memory.stats().writes == 1);
}

TEST_CASE("hw timing: worked example stalling on hazards takes 74 cycles", "[timing]") {
    auto src = worked_example();
    SimConfig cfg = worked_config();
    cfg.sorter.hazard = HazardPolicy::Stall;
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;
    // Issues 1, 4 (waits for row A's write), 5, 8 (row B), 9, 10: fill done 13.
    CHECK(s.sorter.stats().hazard_stall_cycles == 4);
    CHECK(s.sorter.stats().hazard_forwards == 0);
    CHECK(s.tester.stats().idle_cycles == 13);
    CHECK(s.total_cycles() == 74);
    REQUIRE(run.hits().size() == 1);
}

TEST_CASE("hw timing: with one output region the frame-end readback waits, outside the frame", "[timing]") {
    auto src = worked_example();
    SimConfig cfg = worked_config();
    cfg.output.double_buffer = false;
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;
    // The frame still ends at 70; the tester waits 500 cycles for the host before it
    // could write again.
    CHECK(s.total_cycles() == 70);
    CHECK(s.tester.stats().readback_cycles == 500);
    CHECK(s.host.stats().readbacks == 1);
}

TEST_CASE("hw timing: a full input queue holds the rasterizer back", "[timing]") {
    // 40 fragments on 40 distinct pixels, queue of 4: the rasterizer emits 4 per cycle,
    // the sorter drains 1 per cycle. Fragment i (i >= 4) enters when fragment i-4 issues.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    std::vector<Fragment> fs;
    for (unsigned i = 0; i < 40; ++i) fs.push_back(frag(i % 16, i / 16, 1000 + i, 1, 'F'));
    src.add_tile(tb::tile(0, 0, 0, fs));
    SimConfig cfg = worked_config();
    cfg.feed.queue_depth = 4;
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;
    // Issues at 1..40. Fragments 0-3 enter at 0, fragment 4 at 1 (its slot), fragment i >= 5
    // at issue(i-4) = i-3, one cycle after its slot: 35 cycles held, the last at cycle 36.
    CHECK(s.sorter.stats().insertions == 40);
    CHECK(s.raster.stats().stall_queue_full_cycles == 35);
    CHECK(s.queue.stats().max_occupancy == 4);
    CHECK(s.raster.stats().busy_cycles == 37 - 35);
}

namespace {
// Two tiles, each 16 fragments on distinct pixels, front faces only.
MemorySource two_tiles() {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    for (unsigned t = 0; t < 2; ++t) {
        std::vector<Fragment> fs;
        for (unsigned i = 0; i < 16; ++i) fs.push_back(frag(t * 16 + i, 0, 500, 1, 'F'));
        src.add_tile(tb::tile(0, t, 0, fs));
    }
    return src;
}
} // namespace

// Tile 0: enqueued cycles 0-3, issued 1..16, filled at 19; tested 19..36 (1 row read + 16
// elements), bank free at 36. The rasterizer finishes tile 0 at cycle 4.
TEST_CASE("hw timing: with one bank the second tile waits for the first test", "[timing]") {
    auto src = two_tiles();
    SimConfig cfg = worked_config();
    cfg.zeb.banks = 1;
    tb::SystemRun run(cfg, src);
    // gpu.bank_wait = tile: the whole tile waits at the tile scheduler, 4..36.
    CHECK(run.sys->raster.stats().stall_no_bank_cycles == 32);
    // Tile 1: enqueued 36..39, issued 37..52, filled 55, tested 55..72 (no records: flushed
    // at 72). Fragment processors: tile 0 starts 1, 9, 17, 25; tile 1 37, 45, 53, 61: done 69.
    CHECK(run.sys->total_cycles() == 72);
}

TEST_CASE("hw timing: with one bank and bank_wait = unit only the sorter waits", "[timing]") {
    auto src = two_tiles();
    SimConfig cfg = worked_config();
    cfg.zeb.banks = 1;
    cfg.gpu.bank_wait = BankWait::Unit;
    tb::SystemRun run(cfg, src);
    // Tile 1's 16 fragments go into the input queue (32) at 4..7 while bank 0 is tested;
    // the sorter, which could issue at 17 behind tile 0, waits for the bank (free at 36):
    // issues 36..51, filled 54, tested 54..71.
    CHECK(run.sys->raster.stats().stall_no_bank_cycles == 0);
    CHECK(run.sys->sorter.stats().bank_wait_cycles == 36 - 17);
    // Fragment processors: tile 1 enters at 4..7 and starts at 33, 41, 49, 57: done 65.
    CHECK(run.sys->total_cycles() == 71);
}

TEST_CASE("hw timing: with two banks the second tile fills during the first test", "[timing]") {
    auto src = two_tiles();
    tb::SystemRun run(worked_config(), src);
    CHECK(run.sys->raster.stats().stall_no_bank_cycles == 0);
    // Tile 1: enqueued 4-7, issued 17..32 (behind tile 0), filled 35; the tester is busy with
    // tile 0 until 36, then 36..53. Fragment processors: done 65 (33, 41, 49, 57 + 8).
    CHECK(run.sys->total_cycles() == 65);
}

TEST_CASE("hw timing: a small output buffer stalls the tester", "[timing]") {
    // One pixel, ids 1..5 front, then id 1 back: 4 hits from one back face.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    std::vector<Fragment> fs;
    for (unsigned id = 1; id <= 5; ++id) fs.push_back(frag(0, 0, 100 * id, id, 'F'));
    fs.push_back(frag(0, 0, 1000, 1, 'B'));
    src.add_tile(tb::tile(0, 0, 0, fs));
    SimConfig cfg = worked_config();
    cfg.output.buffer_records = 1;
    cfg.output.burst_records = 1;
    cfg.output.max_outstanding = 1;
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;
    REQUIRE(run.hits().size() == 4);
    // Each record: written alone, 4 channel cycles + 50 latency = 54 cycles until its slot frees.
    // Hits offered at cycles 12, 13.. but each waits for the previous write: 3 stalls.
    CHECK(s.outbuf.stats().bursts == 4);
    CHECK(s.tester.stats().output_stall_cycles > 0);
    // Fill: issues 1..6, done 9. Tester: row read 9->10, 5 fronts 10..15, hits at 15, then
    // 15+54=69, 69+54=123, 123+54=177; last accepted at 177, tile done 178. Flush: last write
    // completes at 177+54 = 231: the frame's end.
    CHECK(s.tester.stats().output_stall_cycles == 3 * 53);
    CHECK(s.total_cycles() == 231);
}

TEST_CASE("hw timing: with one write in flight the buffer's slots stay held until each write completes", "[timing]") {
    // One pixel: 1F 2F 3F 4F then 1B: three hits from one back face. Two buffer slots,
    // bursts of one record, one write in flight, latency 50.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    std::vector<Fragment> fs;
    for (unsigned id = 1; id <= 4; ++id) fs.push_back(frag(0, 0, 10 * id, id, 'F'));
    fs.push_back(frag(0, 0, 50, 1, 'B'));
    src.add_tile(tb::tile(0, 0, 0, fs));
    SimConfig cfg = worked_config();
    cfg.output.buffer_records = 2;
    cfg.output.burst_records = 1;
    cfg.output.max_outstanding = 1;
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;
    REQUIRE(run.hits().size() == 3);
    // Fill: issues 1..5, done 8. Tester: row read 8->9, four pushes to 13.
    // Hit 1 at 13: written 13..17, completes 67 (slot A held to 67).
    // Hit 2 at 14: slot B; its write waits for the one in flight: issued 67, completes 121.
    // Hit 3 at 15: both slots held, the first frees at 67: accepted 67 (52 cycles stalled);
    //   its write waits for 121, completes 175. Tile done 68: the bank was tested 8..68.
    CHECK(s.tester.stats().output_stall_cycles == 52);
    CHECK(s.banks[0]->stats().testing_cycles == 60);
    CHECK(s.outbuf.stats().outstanding_stall_cycles == (67 - 14) + (121 - 67));
    // Frame end: everything complete at 175.
    CHECK(s.total_cycles() == 175);
}
