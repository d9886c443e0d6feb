// The paced GPU pipeline's frame times and the overhead split
// (docs/gpu-model.md), worked out by hand. The cases use a rasterizer of one
// fragment a cycle and fragment processors fast enough (4 at 1 cycle) that the
// rasterizer sets the pace, so every cycle can be followed.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <tuple>
#include <utility>
#include <vector>

#include "rbcd/hw/even_split.h"
#include "rbcd/hw/fragment_processors.h"
#include "rbcd/testbench/instruments/instruments_util.h"

using namespace rbcd;
using rbcd::tb::frag;

namespace {

SimConfig paced_config() {
    SimConfig cfg = tb::fixed_latency_config();
    cfg.feed.fragments_per_cycle = 1;
    cfg.gpu.cycles_per_fragment = 1;
    return cfg;
}

// Four front faces on pixels 0..3, then the same objects' back faces behind them,
// tagged c: each list is F, B, which matches without a hit.
Tile front_and_culled_backs() {
    std::vector<Fragment> fs;
    for (std::uint32_t i = 0; i < 4; ++i) fs.push_back(frag(i, 0, 100, i + 1, 'F'));
    for (std::uint32_t i = 0; i < 4; ++i) {
        Fragment b = frag(i, 0, 200, i + 1, 'B');
        b.culled = true;
        fs.push_back(b);
    }
    return tb::tile(0, 0, 0, fs);
}

// Rasterizer- and shader-bound fragment pipes, rates from 1 to 64.
struct PipeCase {
    unsigned rate, queue, procs, cycles, ez;
    GpuConfig gpu() const {
        GpuConfig g;
        g.fragment_queue_depth = queue;
        g.fragment_processors = procs;
        g.cycles_per_fragment = cycles;
        g.early_z_cycles = ez;
        return g;
    }
};
// Two pipes and their rasterizer clocks in the same state: clock, last
// finish, and both rings in age order.
bool same_pipe(const FragmentPipe& a, std::uint64_t ta, unsigned ua, const FragmentPipe& b, std::uint64_t tb,
               unsigned ub) {
    std::vector<std::uint64_t> sa, sb;
    a.state(sa);
    b.state(sb);
    return ta == tb && ua == ub && a.done() == b.done() && sa == sb;
}
const PipeCase kPipeCases[] = {{4, 64, 4, 8, 1}, {1, 64, 4, 1, 1}, {3, 7, 5, 2, 0},
                               {64, 3, 2, 9, 4}, {2, 16, 16, 32, 2}, {5, 1, 1, 1, 0}};

} // namespace

TEST_CASE("gpu: c fragments cost rasterizer slots, not shading", "[gpu]") {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(front_and_culled_backs());
    tb::ReportedRun run(paced_config(), src);
    const FrameFigures& f = run.totals();
    // Baseline: 4 fragments emitted at 0..3, shaded from 1..4 (early-Z 1 cycle), done at 5.
    CHECK(f.t.baseline == 5);
    CHECK(f.t.prims_only == 5);
    // With the c fragments the rasterizer also emits at 4..7: free at 8.
    CHECK(f.t.work == 8);
    CHECK(f.t.gpu_done == 8);
    // The unit: issues 1..8, filled 11; 4 lists, 1 row read + 8 elements: tested 11..20;
    // no records, so the frame's records are "in memory" when the tester is done: 20.
    CHECK(f.t.flushed == 20);
    CHECK(f.t.with_unit == 20);
    CHECK(f.extra_prims == 0);
    CHECK(f.extra_fragments == 3);
    CHECK(f.unit_no_bank + f.unit_queue == 0);
    CHECK(f.tail == 12);
    CHECK(f.overhead_pct() == Approx(300.0));
    CHECK(run.sys->total_cycles() == 20);
}

TEST_CASE("gpu: deferred culling's primitives cost setup cycles", "[gpu]") {
    Tile t = front_and_culled_backs();
    t.has_prims = t.has_cprims = true;
    t.prims = 2;
    t.cprims = 3;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(t);
    tb::ReportedRun run(paced_config(), src);
    const FrameFigures& f = run.totals();
    // prims=2 over the 4 shaded fragments: setups before fragments 0 and 2 (1 cycle each):
    // S F0 F1 S F2 F3 -> emitted at 1, 2, 4, 5; shaded 2, 3, 5, 6: done 7.
    CHECK(f.t.baseline == 7);
    // cprims=3 over the 4 c fragments: before c0, c1, c2. Without the c fragments' own
    // slots: three more setup cycles after F3: the rasterizer is free at 9.
    CHECK(f.t.prims_only == 9);
    // With them: S c0 S c1 S c2 c3 from 6: c0 at 7, c1 at 9, c2 at 11, c3 at 12: free at 13.
    CHECK(f.t.work == 13);
    CHECK(f.t.gpu_done == 13);
    // The unit: issues 2, 3, 5, 6, 8, 10, 12, 13: filled 16, tested 16..25.
    CHECK(f.t.with_unit == 25);
    CHECK(f.extra_prims == 2);
    CHECK(f.extra_fragments == 4);
    CHECK(f.unit_no_bank + f.unit_queue == 0);
    CHECK(f.tail == 12);
    CHECK(f.t.setup_cycles == 2);
    CHECK(f.t.extra_setup_cycles == 3);
    CHECK(run.sys->raster.stats().primitives == 2);
    CHECK(run.sys->raster.stats().culled_primitives == 3);
}

TEST_CASE("gpu: the overhead split adds up to the overhead in every frame", "[gpu]") {
    // Three frames of mixed tiles with `o` runs, prims and c fragments.
    MemorySource src(StreamHeader{});
    std::uint32_t seed = 7;
    const auto rnd = [&](std::uint32_t n) {
        seed = seed * 1103515245u + 12345u;
        return (seed >> 8) % n;
    };
    for (unsigned fr = 0; fr < 3; ++fr) {
        src.add_frame(fr);
        for (std::uint32_t col = 0; col < 6; ++col) {
            Tile t = tb::tile(fr, col, 0, {});
            t.ordered_other = true;
            t.has_prims = t.has_cprims = true;
            for (unsigned k = 0; k < 60; ++k) {
                if (rnd(3) == 0) {
                    t.other_runs.push_back({static_cast<std::uint32_t>(t.frags.size()), rnd(20) + 1});
                    t.other += t.other_runs.back().count;
                }
                Fragment f = frag(col * 16 + rnd(16), rnd(16), 100 + rnd(1000), rnd(6) + 1, rnd(2) ? 'F' : 'B');
                f.culled = f.facing == Facing::Back && rnd(2);
                t.frags.push_back(f);
            }
            t.prims = rnd(20);
            t.cprims = rnd(10);
            src.add_tile(t);
        }
    }
    SimConfig cfg = tb::fixed_latency_config();
    cfg.zeb.banks = 1;
    cfg.feed.queue_depth = 4;
    cfg.gpu.cycles_per_fragment = 1;   // shading fast enough not to hide the unit
    tb::ReportedRun run(cfg, src);
    REQUIRE(run.frames.size() == 3);
    std::uint64_t base = 0, with = 0;
    for (const auto& j : run.frames) {
        const auto& oc = j["overhead_cycles"];
        const std::uint64_t b = j["baseline_cycles"], w = j["cycles_with_unit"];
        REQUIRE(w >= b);
        CHECK(w - b == oc["extra_primitives"].get<std::uint64_t>() + oc["extra_fragments"].get<std::uint64_t>() +
                           oc["unit_no_bank"].get<std::uint64_t>() + oc["unit_queue"].get<std::uint64_t>() +
                           oc["tail"].get<std::uint64_t>());
        base += b;
        with += w;
    }
    // One bank, a 4-entry queue, fast shaders: the unit costs time here.
    CHECK(run.totals().unit_no_bank > 0);
    CHECK(run.totals().unit_queue > 0);
    CHECK(run.totals().t.baseline == base);
    CHECK(run.totals().t.with_unit == with);
    CHECK(run.sys->total_cycles() == with);
    // Frames follow each other: each starts where the one before it ended.
    CHECK(run.frames[1]["start_cycle"] == run.frames[0]["end_cycle"]);
    CHECK(run.frames[2]["start_cycle"] == run.frames[1]["end_cycle"]);
}

TEST_CASE("gpu: without collisionable fragments the unit costs nothing", "[gpu]") {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(tb::tile(0, 0, 0, {}, 100));
    src.add_tile(tb::tile(0, 1, 0, {}, 37));
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    const FrameFigures& f = run.totals();
    CHECK(f.t.baseline > 0);
    CHECK(f.t.with_unit == f.t.baseline);
    CHECK(f.overhead_pct() == 0.0);
    // 137 fragments on 4 processors at 8 cycles: 35 rounds of 8 after the first starts.
    CHECK(run.sys->fragments.stats().fragments == 137);
}

TEST_CASE("gpu: a frame without a baseline reports n/a, not a percentage", "[gpu]") {
    // Frame 0 has only c fragments (the baseline GPU culls them all); frame 1 is empty.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    Fragment b = frag(0, 0, 10, 1, 'B');
    b.culled = true;
    src.add_tile(tb::tile(0, 0, 0, {b}));
    src.add_frame(1);
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    REQUIRE(run.frames.size() == 2);
    CHECK(run.frames[0]["baseline_cycles"] == 0);
    CHECK(run.frames[0]["cycles_with_unit"].get<std::uint64_t>() > 0);
    CHECK(run.frames[0]["overhead_pct"].is_null());
    CHECK(run.frames[1]["overhead_pct"].is_null());
    CHECK(std::isnan(run.totals().overhead_pct()));
    const auto j = run.stats();
    CHECK(j["gpu"]["overhead_pct"].is_null());
    CHECK(j["gpu"]["per_frame_overhead_pct"]["frames_without_baseline"] == 2);
    const std::string s = run.summary();
    INFO(s);
    CHECK(s.find("n/a") != std::string::npos);
    CHECK(s.find("nan") == std::string::npos);
}

TEST_CASE("gpu: base= holds the tile for at least its measured cycles", "[gpu]") {
    Tile t = tb::tile(0, 0, 0, {frag(0, 0, 10, 1, 'F')}, 3);
    t.has_base = true;
    t.base = 100;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(t);
    src.add_tile(tb::tile(0, 1, 0, {}, 1));
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    // The second tile starts at 100; its one fragment enters at 100, shaded 101..109.
    CHECK(run.totals().t.baseline == 109);
    CHECK(run.totals().t.with_unit == 109);
    CHECK(run.totals().t.tiles_with_base == 1);
}

// 8 other fragments at 4 a cycle on 4 processors of C cycles: the first four
// start at 1 (early-Z), the next four when the first finish, at 1 + C; done
// at 1 + 2C, with C = 8 x shade / 100 (at least 1). One simulation a process:
// a test case a value.
static void check_shaded_tile(std::uint32_t shade, std::uint64_t c) {
    Tile t = tb::tile(0, 0, 0, {}, 8);
    t.has_shade = true;
    t.shade = shade;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(t);
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    CHECK(run.totals().t.baseline == 1 + 2 * c);
    CHECK(run.totals().t.with_unit == 1 + 2 * c);
    CHECK(run.sys->fragments.stats().busy_cycles == 8 * c);
}

TEST_CASE("gpu: shade=200 doubles what a tile's fragments cost the processors", "[gpu]") {
    check_shaded_tile(200, 16);
}

TEST_CASE("gpu: shade=1 costs at least one cycle a fragment", "[gpu]") {
    check_shaded_tile(1, 1);
}

TEST_CASE("gpu: fragments in flight keep the cost of their tile", "[gpu]") {
    // A tile at shade=400 (C = 32), then one fragment of a tile without
    // shade= (C = 8), emitted at cycle 2: it waits for the first processor
    // free (33) and is done at 41.
    Tile a = tb::tile(0, 0, 0, {}, 8), b = tb::tile(0, 1, 0, {}, 1);
    a.has_shade = true;
    a.shade = 400;
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(a);
    src.add_tile(b);
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    CHECK(run.totals().t.baseline == 1 + 2 * 32 + 8);
    CHECK(run.sys->fragments.stats().busy_cycles == 8 * 32 + 8);
}

TEST_CASE("gpu: a long run of fragments is computed in bulk exactly", "[gpu]") {
    // FragmentPipe::shade_run jumps over the periodic part of a long run; it must give
    // the same state as going fragment by fragment, for rasterizer- and shader-bound
    // configurations alike.
    for (const PipeCase c : kPipeCases) {
        const GpuConfig g = c.gpu();
        for (const std::uint64_t m : {257ull, 1000ull, 123457ull}) {
            INFO("rate " << c.rate << " queue " << c.queue << " procs " << c.procs << " cycles " << c.cycles
                         << " run " << m);
            FragmentPipe bulk(g), step(g);
            bulk.restart(0);
            step.restart(0);
            std::uint64_t tb = 5, ts = 5;
            unsigned ub = 1, us = 1;
            const std::uint64_t wb = bulk.shade_run(tb, ub, c.rate, m);
            std::uint64_t ws = 0;
            for (std::uint64_t k = 0; k < m; ++k) ws += step.shade(ts, us, c.rate, 1);
            CHECK(wb == ws);
            CHECK(same_pipe(bulk, tb, ub, step, ts, us));
        }
    }
}

// The same from states a game frame leaves: fragments of other costs still in
// flight (shade=), the rasterizer ahead of or behind the queue, runs just
// above the bulk threshold and long ones.
TEST_CASE("gpu: a run from any state is computed in bulk exactly", "[gpu]") {
    std::mt19937_64 gen(41);
    const auto pick = [&](std::uint64_t lo, std::uint64_t hi) { return lo + gen() % (hi - lo + 1); };
    for (const PipeCase c : kPipeCases) {
        const GpuConfig g = c.gpu();
        for (int trial = 0; trial < 300; ++trial) {
            FragmentPipe bulk(g), step(g);
            bulk.restart(0);
            step.restart(0);
            std::uint64_t t = pick(0, 50);
            unsigned u = static_cast<unsigned>(pick(0, c.rate));
            // A history: runs of fragments at random costs, gaps in the rasterizer.
            for (int h = static_cast<int>(pick(0, 6)); h > 0; --h) {
                const unsigned cost = static_cast<unsigned>(pick(1, 3 * c.cycles + 2));
                bulk.set_cycles_per_fragment(cost);
                const std::uint64_t n = pick(1, 200);
                for (std::uint64_t k = 0; k < n; ++k) bulk.shade(t, u, c.rate, 1);
                if (pick(0, 1)) {
                    t += pick(1, 40);
                    u = 0;
                }
            }
            step = bulk;
            std::uint64_t ts = t;
            unsigned us = u;
            const unsigned cost = static_cast<unsigned>(pick(1, 3 * c.cycles + 2));
            bulk.set_cycles_per_fragment(cost);
            step.set_cycles_per_fragment(cost);
            const std::uint64_t m = pick(0, 1) ? pick(FragmentPipe::kLongRun, 200) : pick(200, 5000);
            INFO("rate " << c.rate << " queue " << c.queue << " procs " << c.procs << " trial " << trial << " cost "
                         << cost << " run " << m);
            const std::uint64_t wb = bulk.shade_run(t, u, c.rate, m);
            std::uint64_t ws = 0;
            for (std::uint64_t k = 0; k < m; ++k) ws += step.shade(ts, us, c.rate, 1);
            REQUIRE(wb == ws);
            REQUIRE(same_pipe(bulk, t, u, step, ts, us));
        }
    }
}

// Runs one after another, as a tile's walk gives them: between two runs the
// rasterizer sets up primitives or emits c fragments (its clock moves, the
// pipe does not), or the pipe takes one fragment by push() or another cost.
// A run that continues the periodic regime the run before it verified
// (shade_run()) must give what going fragment by fragment gives, and the
// regime must be continued often enough for that to be what is tested.
TEST_CASE("gpu: runs continuing a periodic regime across setups are exact", "[gpu]") {
    std::mt19937_64 gen(4141);
    const auto pick = [&](std::uint64_t lo, std::uint64_t hi) { return lo + gen() % (hi - lo + 1); };
    for (const PipeCase c : kPipeCases) {
        const GpuConfig g = c.gpu();
        std::uint64_t continued = 0;
        for (int trial = 0; trial < 40; ++trial) {
            FragmentPipe bulk(g), step(g);
            bulk.restart(0);
            step.restart(0);
            std::uint64_t tb = 0, ts = 0;
            unsigned ub = 0, us = 0;
            for (int event = 0; event < 200; ++event) {
                INFO("rate " << c.rate << " queue " << c.queue << " procs " << c.procs << " trial " << trial
                             << " event " << event);
                const bool was_periodic = bulk.periodic();
                const std::uint64_t m = pick(0, 3) ? pick(1, 120) : pick(120, 3000);
                const std::uint64_t wb = bulk.shade_run(tb, ub, c.rate, m);
                std::uint64_t ws = 0;
                for (std::uint64_t k = 0; k < m; ++k) ws += step.shade(ts, us, c.rate, 1);
                REQUIRE(wb == ws);
                REQUIRE(same_pipe(bulk, tb, ub, step, ts, us));
                continued += was_periodic && bulk.periodic();
                switch (pick(0, 9)) {
                case 0: case 1: case 2: case 3: {   // setups: the clock moves on
                    const std::uint64_t cycles = pick(0, 3) ? pick(1, 4) : pick(5, 400);
                    tb = (ub ? tb + 1 : tb) + cycles;   // rasterizer::Cursor::busy
                    ts = (us ? ts + 1 : ts) + cycles;
                    ub = us = 0;
                    break;
                }
                case 4: case 5: {   // c fragments: rasterizer slots only
                    for (std::uint64_t k = pick(1, 6); k > 0; --k) {
                        for (auto [t, u] : {std::pair{&tb, &ub}, std::pair{&ts, &us}}) {
                            if (*u == c.rate) {
                                ++*t;
                                *u = 0;
                            }
                            ++*u;
                        }
                    }
                    break;
                }
                case 6: {   // one fragment pushed outside a run, held back as the unit's queue may hold it
                    const std::uint64_t held = pick(0, 1) ? 0 : pick(0, 1) ? pick(1, 50) : pick(50, 2000);
                    for (auto [p, t, u] : {std::tuple{&bulk, &tb, &ub}, std::tuple{&step, &ts, &us}}) {
                        if (*u == c.rate) {
                            ++*t;
                            *u = 0;
                        }
                        const std::uint64_t e = p->room(*t + held);
                        if (e > *t) *u = 0;
                        *t = e;
                        ++*u;
                        p->push(e);
                    }
                    break;
                }
                case 7: {   // another shading cost, or the same again
                    const unsigned cost = pick(0, 1) ? c.cycles : static_cast<unsigned>(pick(1, 3 * c.cycles + 2));
                    bulk.set_cycles_per_fragment(cost);
                    step.set_cycles_per_fragment(cost);
                    break;
                }
                default: break;   // runs back to back
                }
            }
        }
        INFO("rate " << c.rate << " queue " << c.queue << " procs " << c.procs);
        CHECK(continued > 100);
    }
}

// FragmentPipe::walk_tile_cut_at_c walks GPU-only timeline 2 through a tile
// without setups (the shaded fragments pushed, each c fragment one rasterizer
// slot) by runs between c fragments, with the state held in locals. It must
// leave the state stepping fragment by fragment leaves, with the fragments
// after the last c fragment left pending. Random tiles: c fragments alone, in
// runs and at the ends; others spread evenly (thin and thick) or ordered by o
// records; pending runs before the tile short and long; rasterizer- and
// shader-bound configurations, rates below and above a run of c fragments.
TEST_CASE("gpu: timeline 2's tile walk equals stepping fragment by fragment", "[gpu]") {
    std::mt19937_64 gen(2026);
    const auto pick = [&](std::uint64_t lo, std::uint64_t hi) { return lo + gen() % (hi - lo + 1); };
    for (const PipeCase c : kPipeCases) {
        const GpuConfig g = c.gpu();
        for (int trial = 0; trial < 200; ++trial) {
            Tile tile;
            const std::size_t n = pick(1, 300);
            const unsigned c_pct = static_cast<unsigned>(pick(0, 4)) * 25;   // 0, 25, 50, 75, 100 % c
            for (std::size_t i = 0; i < n; ++i) {
                Fragment f = frag(0, 0, 1, 1, 'F');
                f.culled = pick(1, 100) <= c_pct;
                tile.frags.push_back(f);
            }
            tile.frags[pick(0, n - 1)].culled = true;   // the walk's tiles have one
            const int others = static_cast<int>(pick(0, 3));
            if (others == 3) {
                tile.ordered_other = true;
                for (std::size_t i = 0; i <= n; i += pick(1, 40)) {
                    tile.other_runs.push_back({static_cast<std::uint32_t>(i), pick(0, 5)});
                    tile.other += tile.other_runs.back().count;
                }
            } else {
                tile.other = others == 0 ? 0 : others == 1 ? pick(0, 2 * n) : pick(2 * n + 1, 5 * n + 3);
            }
            const std::uint64_t pending = pick(0, 1) ? pick(0, 8) : pick(257, 2000);
            INFO("rate " << c.rate << " queue " << c.queue << " procs " << c.procs << " trial " << trial << " n " << n
                         << " other " << tile.other << (tile.ordered_other ? " ordered" : "") << " pending " << pending);
            FragmentPipe walk(g), step(g);
            walk.restart(3);
            step.restart(3);
            std::uint64_t tw = 7, ts = 7;
            unsigned uw = 2 % c.rate + 1, us = uw;
            // Stepping: the pending run, then the tile's order (others before
            // fragment i as the rasterizer spreads or orders them).
            std::uint64_t after_last_c = 0;
            const auto shade_one = [&] {
                step.shade(ts, us, c.rate, 1);
                ++after_last_c;
            };
            for (std::uint64_t k = 0; k < pending; ++k) shade_one();
            EvenSplit split(tile.other, n + 1);
            std::uint64_t done_others = 0;
            std::size_t run = 0;
            for (std::size_t i = 0; i <= n; ++i) {
                std::uint64_t upto = 0;
                if (tile.ordered_other) {
                    upto = done_others;
                    for (; run < tile.other_runs.size() && tile.other_runs[run].before <= i; ++run)
                        upto += tile.other_runs[run].count;
                    if (i == n)
                        for (; run < tile.other_runs.size(); ++run) upto += tile.other_runs[run].count;
                } else {
                    upto = i < n ? split.next() : tile.other;
                }
                for (; done_others < upto; ++done_others) shade_one();
                if (i == n) break;
                if (tile.frags[i].culled) {
                    if (us == c.rate) {
                        ++ts;
                        us = 0;
                    }
                    ++us;
                    after_last_c = 0;
                } else {
                    shade_one();
                }
            }
            const std::uint64_t left = walk.walk_tile_cut_at_c(tile, tw, uw, c.rate, pending);
            REQUIRE(left == after_last_c);
            // The pending fragments shaded on both sides, then the whole state compared.
            walk.shade_run(tw, uw, c.rate, left);
            REQUIRE(same_pipe(walk, tw, uw, step, ts, us));
        }
    }
}

TEST_CASE("gpu: a tile with other=2^40 finishes at once", "[gpu]") {
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(tb::tile(0, 0, 0, {frag(0, 0, 10, 1, 'F')}, std::uint64_t(1) << 40));
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    // 2^40 + 1 fragments on 4 processors at 8 cycles: 2 cycles a fragment once saturated.
    const std::uint64_t b = run.totals().t.baseline;
    CHECK(b >= (std::uint64_t(1) << 41));
    CHECK(b <= (std::uint64_t(1) << 41) + 64);
    CHECK(run.totals().t.with_unit == b);
}
