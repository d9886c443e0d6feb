// The GPU model (docs/gpu-model.md): every figure worked out by hand from the
// feed's and the tester's timelines, which test_timing.cpp pins down.
//
// Per tile: B baseline, X extra raster, U feed duration, N no-bank stall, Q
// queue-full stall; G = B + X with base=, overhead + max(raster + X, shading)
// for an estimated tile; W = max(G, U - overlap). Per frame:
// tail = max(0, flushed - feed_end + U'_last - W_last), with = sum W + tail.
#include <catch2/catch.hpp>

#include "testbench/instruments/instruments_util.h"

using namespace rbcd;
using rbcd::tb::frag;

namespace {

// Ten fragments on pixels 0..9 of row 0 (six front faces, four back faces tagged c)
// and other=20; a tile with only other=7; twelve on pixels 32..43 (one front face,
// eleven back faces tagged c).
MemorySource three_tiles() {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    std::vector<Fragment> a, c;
    for (unsigned i = 0; i < 10; ++i)
        a.push_back(i < 6 ? frag(i, 0, 1000 + i, 1, 'F') : frag(i, 0, 1000 + i, 2, 'B', true));
    for (unsigned i = 0; i < 12; ++i)
        c.push_back(i < 1 ? frag(32 + i, 0, 2000 + i, 3, 'F') : frag(32 + i, 0, 2000 + i, 4, 'B', true));
    src.add_tile(tb::tile(0, 0, 0, a, 20));
    src.add_tile(tb::tile(0, 1, 0, {}, 7));
    src.add_tile(tb::tile(0, 2, 0, c));
    return src;
}

std::vector<Fragment> row_of_16(unsigned x0) {
    std::vector<Fragment> fs;
    for (unsigned i = 0; i < 16; ++i) fs.push_back(frag(x0 + i, 0, 500, 1, 'F'));
    return fs;
}

Tile with_base(Tile t, std::uint64_t base) {
    t.has_base = true;
    t.base = base;
    return t;
}

} // namespace

TEST_CASE("instruments: tile cost formula splits the overhead by cause", "[gpu]") {
    // G = 10 + 2 = 12. Feed: 40 cycles, 15 waiting for a bank, 20 for the queue: 5 stall-free.
    GpuTileSample s{100, 40, 10, 2, 12, 15, 20};
    GpuTileCost c = gpu_tile_cost(s, 0);
    CHECK(c.with_unit == 40);
    CHECK(c.overlap == 0);
    CHECK(c.feed_excess == 0);
    // Slack 12 - 5 = 7 hides 7 of the no-bank stall, none of the queue stall.
    CHECK(c.no_bank == 8);
    CHECK(c.queue_full == 20);
    // The previous frame flushed at 110: the first 10 stall cycles are its tail.
    c = gpu_tile_cost(s, 110);
    CHECK(c.overlap == 10);
    CHECK(c.unit_duration == 30);
    CHECK(c.with_unit == 30);
    CHECK(c.no_bank == 0);       // 5 left, all hidden (slack 7), 2 slack left for the queue
    CHECK(c.queue_full == 18);
    // A flush after the whole stall takes all of it; one before the tile none.
    CHECK(gpu_tile_cost(s, 500).overlap == 15);
    CHECK(gpu_tile_cost(s, 90).overlap == 0);
    // The feed slower than the GPU without any stall: feed excess.
    c = gpu_tile_cost(GpuTileSample{0, 9, 4, 1, 5, 0, 0}, 0);
    CHECK(c.with_unit == 9);
    CHECK(c.extra_raster == 1);
    CHECK(c.feed_excess == 4);
    CHECK(c.with_unit - 4 == c.extra_raster + c.feed_excess + c.no_bank + c.queue_full);
    // Part of X hidden behind shading: B = 10, X = 3, G = 11.
    c = gpu_tile_cost(GpuTileSample{0, 4, 10, 3, 11, 0, 0}, 0);
    CHECK(c.with_unit == 11);
    CHECK(c.extra_raster == 1);
}

TEST_CASE("instruments: baseline estimate and c-tagged extra rasterization by hand", "[gpu]") {
    auto src = three_tiles();
    SimConfig cfg = tb::fixed_latency_config();
    cfg.gpu.raster_fragments_per_cycle = 4;
    cfg.gpu.fragment_processors = 2;
    cfg.gpu.cycles_per_fragment = 3;
    cfg.gpu.tile_overhead_cycles = 5;
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    // Tile 0: shaded 20 + 6 = 26: raster ceil(26/4) = 7, shading ceil(26*3/2) = 39: B = 5 + 39 = 44;
    //         with the 4 culled: ceil(30/4) = 8, X = 1; G = 5 + max(8, 39) = 44: hidden.
    // Tile 1: shaded 7: raster 2, shading ceil(21/2) = 11: B = 16, X = 0, G = 16.
    // Tile 2: shaded 1: raster 1, shading ceil(3/2) = 2: B = 7; with the 11 culled ceil(12/4) = 3,
    //         X = 2; G = 5 + max(3, 2) = 8: one cycle of it shows.
    CHECK(g[0].baseline_cycles == 44 + 16 + 7);
    CHECK(g[0].baseline_cycles == run.sys->feed.frames()[0].baseline_cycles);
    CHECK(g[0].extra_raster_cycles == 3);
    CHECK(g[0].extra_raster_exposed == 1);
    CHECK(g[0].estimate_mismatches == 0);
    // Feed: tile 0 at 0: 10 fragments in 3 cycles, other=20 in 5: U = 8. Tile 1 at 8: U = 2.
    // Tile 2 at 10 (bank 1 free): U = 3; the frame ends at 13. W = max(G, U): 44, 16, 8.
    CHECK(g[0].raster_cycles == 44 + 16 + 8);
    CHECK(g[0].stall_no_bank_cycles == 0);
    CHECK(g[0].stall_queue_full_cycles == 0);
    // Tester: tile 0 filled at 10 + 3 = 13, tested 13 + 1 + 10 = 24; tile 2 issued 11..22,
    // filled 25, tested 25 + 1 + 12 = 38; nothing to write: flushed at 38.
    CHECK(g[0].feed_end == 13);
    CHECK(g[0].flushed == 38);
    // Tail: 38 - 13 + U'(3) - W(8) = 20.
    CHECK(g[0].tail_cycles == 20);
    CHECK(g[0].cycles_with_unit == 68 + 20);
    CHECK(g[0].overhead_pct() == Approx(100.0 * 21 / 67));
    // Without per-tile samples the extra comes on top: W = max(67 + 3, 13) = 70 for the frame;
    // tail 38 - 13 + 13 - 70 < 0.
    const auto coarse = GpuModel::per_frame(*run.sys);
    CHECK(coarse[0].cycles_with_unit == 70);
}

TEST_CASE("instruments: base= replaces the estimate and the extra comes on top", "[gpu]") {
    const SimConfig cfg = tb::fixed_latency_config();
    TraceReader src(tb::instruments_file("gpu_base.rbt"), tb::limits(cfg));
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    // gpu keys as fixed_latency_config pins them. B: 100 (base=), 7 (estimate: max(ceil(7/4), 7*4/4)), 30 (base=). X: 1, 0, 2,
    // on top of a given base= (its split between rasterizer and shaders is unknown).
    CHECK(g[0].tiles == 3);
    CHECK(g[0].tiles_with_base == 2);
    CHECK(g[0].baseline_cycles == 137);
    CHECK(g[0].extra_raster_cycles == 3);
    CHECK(g[0].extra_raster_exposed == 3);
    // The feed timeline of the estimate test (same fragment counts): U = 8, 2, 3. W = max(101, 8), max(7, 2), max(32, 3).
    CHECK(g[0].raster_cycles == 101 + 7 + 32);
    // Flushed at 38, feed end 13: 38 - 13 + 3 - 32 < 0, no tail.
    CHECK(g[0].tail_cycles == 0);
    CHECK(g[0].cycles_with_unit == 140);
    CHECK(g[0].overhead_pct() == Approx(100.0 * 3 / 137));
    const auto j = run.stats();
    CHECK(j["gpu"]["tiles_with_base"] == 2);
    CHECK(j["gpu"]["tiles_estimated"] == 1);
    CHECK(j["frames"][0]["gpu"]["extra_raster_cycles"] == 3);
}

// gpu_banks.rbt: tiles 0 and 1 of 16 fragments, base=20 each; tile 2 empty, base=100.
// Feed and tester timelines as test_timing.cpp's one-bank / two-bank cases.
TEST_CASE("instruments: one bank stalls the rasterizer", "[gpu]") {
    SimConfig cfg = tb::fixed_latency_config();
    cfg.zeb.banks = 1;
    TraceReader src(tb::instruments_file("gpu_banks.rbt"), tb::limits(cfg));
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    CHECK(g[0].baseline_cycles == 140);
    // Tile 0: U = 4, W = 20. Tile 1 begins at 4, waits for the bank until 36 (N = 32), emits
    // until 40: U = 36, W = max(20, 36) = 36; the GPU's slack 20 - 4 hides 16 of the 32.
    // Tile 2 begins at 40: U = 0, W = 100.
    CHECK(g[0].stall_no_bank_cycles == 32);
    CHECK(g[0].no_bank_exposed == 16);
    CHECK(g[0].raster_cycles == 20 + 36 + 100);
    // Tile 1 tested 55..72: flushed 72, feed end 40: 72 - 40 + 0 - 100 < 0.
    CHECK(g[0].tail_cycles == 0);
    CHECK(g[0].cycles_with_unit == 156);
    CHECK(g[0].overhead_pct() == Approx(100.0 * 16 / 140));
    // Frame granularity (no probe) hides the stall behind the whole frame's slack:
    // U = 40 for the frame against B = 140.
    const auto coarse = GpuModel::per_frame(*run.sys);
    REQUIRE(coarse.size() == 1);
    CHECK(coarse[0].cycles_with_unit == 140);
    const auto j = make_stats(*run.sys, RunInfo{"test", 0.0});
    CHECK(j["gpu"]["granularity"] == "frame");
    CHECK(j["gpu"]["cycles_with_unit"] == 140);
    CHECK(run.stats()["gpu"]["granularity"] == "tile");
}

TEST_CASE("instruments: two banks do not stall the rasterizer", "[gpu]") {
    const SimConfig cfg = tb::fixed_latency_config();
    TraceReader src(tb::instruments_file("gpu_banks.rbt"), tb::limits(cfg));
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    // Tile 1 begins at 4 on bank 1: U = 4. Tile 2 at 8. Tile 1 tested 36..53.
    CHECK(g[0].stall_no_bank_cycles == 0);
    CHECK(g[0].raster_cycles == 140);
    CHECK(g[0].flushed == 53);
    CHECK(g[0].tail_cycles == 0);
    CHECK(g[0].cycles_with_unit == 140);
    CHECK(g[0].overhead_pct() == 0.0);
}

TEST_CASE("instruments: the tester's tail after the last tile", "[gpu]") {
    // gpu_banks.rbt without its last tile, two banks, built in memory.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(with_base(tb::tile(0, 0, 0, row_of_16(0)), 20));
    src.add_tile(with_base(tb::tile(0, 1, 0, row_of_16(16)), 20));
    tb::ProbedRun run(tb::fixed_latency_config(), src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    // Feed ends at 8; tile 1 tested 36..53: flushed 53. Last tile U' = 4, W = 20:
    // the unit is done 53 - 8 + 4 = 49 cycles after the tile began, the GPU 20: tail 29.
    CHECK(g[0].feed_end == 8);
    CHECK(g[0].flushed == 53);
    CHECK(g[0].tail_cycles == 29);
    CHECK(g[0].cycles_with_unit == 40 + 29);
    // The plain sum: 40 + 0 + 0 + 0 + (53 - 8).
    CHECK(g[0].additive_cycles == 85);
    const auto j = run.stats();
    CHECK(j["gpu"]["overhead_cycles"]["tail"] == 29);
    CHECK(j["gpu"]["additive_upper_bound"]["cycles"] == 85);
}

TEST_CASE("instruments: a stall inside the previous frame's tail is not counted twice", "[gpu]") {
    // Two frames of one 16-fragment tile each, base=20, one bank, no readback time.
    MemorySource src(StreamHeader{});
    for (unsigned f = 0; f < 2; ++f) {
        src.add_frame(f);
        src.add_tile(with_base(tb::tile(f, 0, 0, row_of_16(0)), 20));
    }
    SimConfig cfg = tb::fixed_latency_config();
    cfg.zeb.banks = 1;
    cfg.host.readback_cycles = 0;
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 2);
    // Frame 0: tile at 0, U = 4, W = 20; tested 19..36, flushed 36; tail 36 - 4 + 4 - 20 = 16.
    CHECK(g[0].flushed == 36);
    CHECK(g[0].tail_cycles == 16);
    CHECK(g[0].cycles_with_unit == 36);
    // Frame 1: its tile begins at 4 and waits for the bank until 36: all 32 stall cycles lie
    // in frame 0's tail. U' = 36 - 32 = 4, W = 20. Tested 55..72; feed end 40:
    // tail 72 - 40 + 4 - 20 = 16.
    CHECK(g[1].stall_no_bank_cycles == 32);
    CHECK(g[1].no_bank_in_previous_tail == 32);
    CHECK(g[1].no_bank_exposed == 0);
    CHECK(g[1].raster_cycles == 20);
    CHECK(g[1].flushed == 72);
    CHECK(g[1].tail_cycles == 16);
    CHECK(g[1].cycles_with_unit == 36);
    // With the GPU paced, frame 1 starts at 36 when the bank is free: 36 + 36 = 72, the
    // cycle the unit is done. Counting the stall twice would give 36 + 52.
    CHECK(g[0].cycles_with_unit + g[1].cycles_with_unit == 72);
}

TEST_CASE("instruments: queue-full stalls and feed excess by hand", "[gpu]") {
    // test_timing.cpp's full-queue case: 40 fragments, queue of 4: the feed needs 37 cycles
    // instead of 10. base=5, then an empty tile with base=200 for the unit to finish in.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    std::vector<Fragment> fs;
    for (unsigned i = 0; i < 40; ++i) fs.push_back(frag(i % 16, i / 16, 1000 + i, 1, 'F'));
    src.add_tile(with_base(tb::tile(0, 0, 0, fs), 5));
    src.add_tile(with_base(tb::tile(0, 1, 0, {}), 200));
    SimConfig cfg = tb::fixed_latency_config();
    cfg.feed.queue_depth = 4;
    tb::ProbedRun run(cfg, src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 1);
    // Tile 0: U = 37, Q = 27, stall-free 10 against G = 5: feed excess 5, the queue stall all seen.
    CHECK(g[0].stall_queue_full_cycles == 27);
    CHECK(g[0].queue_full_exposed == 27);
    CHECK(g[0].feed_excess == 5);
    CHECK(g[0].raster_cycles == 37 + 200);
    // Filled 43, tested 43 + 1 + 40 = 84; feed end 37: 84 - 37 + 0 - 200 < 0.
    CHECK(g[0].tail_cycles == 0);
    CHECK(g[0].cycles_with_unit == 237);
    CHECK(g[0].overhead_cycles() == g[0].extra_raster_cycles + g[0].feed_excess + g[0].no_bank_exposed +
                                        g[0].queue_full_exposed + g[0].tail_cycles);
}

TEST_CASE("instruments: the frame-end flush and an empty frame's tail", "[gpu]") {
    // Frame 0: one pixel, id 2 back, id 1 front, id 2 front, id 1 back (one hit), base=1000.
    // Frame 1: no tiles. Readback 500 cycles (default).
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(with_base(tb::tile(0, 0, 0,
                                    {frag(0, 0, 300, 2, 'B'), frag(0, 0, 100, 1, 'F'), frag(0, 0, 200, 2, 'F'),
                                     frag(0, 0, 400, 1, 'B')}),
                           1000));
    src.add_frame(1);
    tb::ProbedRun run(tb::fixed_latency_config(), src);
    const auto& g = run.gpu();
    REQUIRE(g.size() == 2);
    // Feed: 4 fragments in cycle 0, frame 0 ends at 1. Tester: filled 7, tested 7..12 (the hit
    // at 11). The frame end takes the hit's burst at 12: 4 channel cycles + 50: flushed 66,
    // read back until 566. The GPU spends W = 1000 on the tile, so the last tile leaves no
    // tail (66 - 1 + 1 - 1000 < 0), but the flush can only begin after the GPU's frame end
    // and takes 66 - max(1, 12) = 54 cycles.
    CHECK(g[0].flush_start == 12);
    CHECK(g[0].flushed == 66);
    CHECK(g[0].tail_cycles == 54);
    CHECK(g[0].cycles_with_unit == 1054);
    // Frame 1 begins at frame 0's flush (66); the tester takes its frame end after frame 0's
    // readback, at 566, with nothing to write: flushed 566, tail 566 - 66 = 500.
    CHECK(g[1].tiles == 0);
    CHECK(g[1].flushed == 566);
    CHECK(g[1].tail_cycles == 500);
    CHECK(g[1].cycles_with_unit == 500);
    CHECK(g[1].overhead_pct() == 0.0);   // no baseline to compare with
}
