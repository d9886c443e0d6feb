// The insertion sorter alone: fill_tile() drives fragments straight into a
// zeb_bank (no feed, no tester, no sc_start), and the checker reads the bank's
// packed rows back. Functional results follow rbcd-contract.md "Sorted
// insertion" and "Depth quantization"; cycle numbers follow the pipeline in
// hw/insertion_sorter.h (READ s, SORT s+1, WRITE s+2; issue >= enqueue + 1,
// one per cycle; a queue slot frees in the issue cycle of the fragment
// queue_depth earlier; under "stall" a same-pixel READ waits until s+3).
//
// One TEST_CASE per process (catch_discover_tests): no SECTIONs.
#include <catch2/catch.hpp>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "rbcd/testbench/hw/tb_util.h"

using namespace rbcd;
using rbcd::tb::frag;

namespace {

// A sorter and two banks built from one configuration, nothing bound, nothing run.
// What a tile's fill did, seen from the driver.
struct FillResult {
    std::uint64_t feed_done = 0;       // cycle after the driver's last emission
    std::uint64_t fill_done = 0;       // cycle from which the bank holds the whole tile
    std::uint64_t queue_stall = 0;     // cycles lost against an unhindered driver
    std::uint64_t first_issue = 0, last_issue = 0;
};

// The sorter between a driver that emits feed.fragments_per_cycle fragments a
// cycle into the input queue (the rasterizer's rule, without fragment
// processors) and the banks.
struct SorterBench {
    SimConfig cfg;
    std::unique_ptr<zeb_bank> bank0, bank1;
    std::unique_ptr<input_queue> queue;
    std::unique_ptr<insertion_sorter> sorter;
    explicit SorterBench(const SimConfig& c) : cfg(c) {
        sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
        bank0 = std::make_unique<zeb_bank>("zeb0", cfg.zeb, cfg.tile, 0);
        bank1 = std::make_unique<zeb_bank>("zeb1", cfg.zeb, cfg.tile, 1);
        queue = std::make_unique<input_queue>("queue", cfg.feed);
        sorter = std::make_unique<insertion_sorter>("sorter", cfg);
    }
    // The tile into `bank`, the driver starting at `start`.
    FillResult fill(zeb_bank& bank, const Tile& t, std::uint64_t start = 0, unsigned depth_bits = 24) {
        FillResult r;
        bank.begin_fill(t.frame, t.col, t.row, start);
        sorter->begin_tile(bank, start, t);
        rasterizer::Cursor c;
        c.rate = cfg.feed.fragments_per_cycle;
        c.restart(start);
        bool first = true;
        for (const Fragment& f : t.frags) {
            const std::uint64_t e = queue->room(c.slot());
            c.emit_at(e);
            const std::uint64_t issue = sorter->accept(f, e, depth_bits);
            queue->push(e, issue);
            if (first) r.first_issue = issue;
            first = false;
            r.last_issue = issue;
        }
        const std::uint64_t n = t.frags.size();
        r.fill_done = n ? sorter->end_tile() : start;
        r.feed_done = n ? c.next_free() : start;
        const std::uint64_t rate = cfg.feed.fragments_per_cycle;
        if (n) r.queue_stall = (r.feed_done - start) - (n + rate - 1) / rate;
        return r;
    }
    // List li of `bank` as "dq:idF dq:idB ...", front to back, from the packed words.
    std::string row(const zeb_bank& bank, unsigned li) const {
        const ElementLayout lay = cfg.zeb.layout();
        std::string s;
        for (unsigned i = 0; i < bank.count(li); ++i) {
            const Element e = lay.unpack(bank.list(li)[i]);
            if (!s.empty()) s += ' ';
            s += std::to_string(e.dq) + ":" + std::to_string(e.id) + (e.facing == Facing::Back ? "B" : "F");
        }
        return s;
    }
};

SimConfig small_config(unsigned m) {
    SimConfig cfg;
    cfg.tile.width = 4;
    cfg.tile.height = 4;
    cfg.zeb.list_length = m;
    return cfg;
}

// Fragments for pixel (x, y) of tile (0, 0): one per depth, ids 1, 2, ..., all front faces.
std::vector<Fragment> column(std::uint32_t x, std::vector<std::uint32_t> depths, std::uint32_t y = 0) {
    std::vector<Fragment> v;
    std::uint32_t id = 1;
    for (std::uint32_t d : depths) v.push_back(frag(x, y, d, id++, 'F'));
    return v;
}

void append(std::vector<Fragment>& a, const std::vector<Fragment>& b) { a.insert(a.end(), b.begin(), b.end()); }

// `n` fragments on distinct pixels (row-major) of a 16x16 tile (col, 0), front faces.
Tile distinct_pixels(std::uint32_t col, unsigned n) {
    std::vector<Fragment> v;
    for (unsigned i = 0; i < n; ++i) v.push_back(frag(col * 16 + i % 16, i / 16, 1000 + i, 1, 'F'));
    return tb::tile(0, col, 0, v);
}

// Fragments on tile (0, 0) of a 16x16 tile at the given pixels x (y = 0), front faces.
Tile on_pixels(std::vector<std::uint32_t> xs) {
    std::vector<Fragment> v;
    std::uint32_t d = 100;
    for (std::uint32_t x : xs) v.push_back(frag(x, 0, d += 10, 1, 'F'));
    return tb::tile(0, 0, 0, v);
}

} // namespace

// ---------------------------------------------------------------------------
// Functional: sorted insertion

TEST_CASE("hw sorter: insertion at every position of a list of 3 with M=4", "[sorter]") {
    SorterBench b(small_config(4));
    // Pixel p (p = 0..3) gets 10 20 30 (ids 1-3), then a new element (id 9) at position p.
    const std::uint32_t new_depth[4] = {5, 15, 25, 35};
    std::vector<Fragment> fs;
    for (std::uint32_t p = 0; p < 4; ++p) {
        append(fs, column(p, {10, 20, 30}));
        fs.push_back(frag(p, 0, new_depth[p], 9, 'B'));
    }
    b.fill(*b.bank0, tb::tile(0, 0, 0, fs));
    CHECK(b.row(*b.bank0, 0) == "5:9B 10:1F 20:2F 30:3F");
    CHECK(b.row(*b.bank0, 1) == "10:1F 15:9B 20:2F 30:3F");
    CHECK(b.row(*b.bank0, 2) == "10:1F 20:2F 25:9B 30:3F");
    CHECK(b.row(*b.bank0, 3) == "10:1F 20:2F 30:3F 35:9B");
    const auto& s = b.sorter->stats();
    CHECK(s.insertions == 16);
    CHECK(s.comparator_activations == 16 * 4);
    // Sorted preparation moves nothing; the new elements move 3 + 2 + 1 + 0.
    CHECK(s.mux_shifts == 6);
    CHECK(s.overflows == 0);
    CHECK(s.dropped_new == 0);
    CHECK(s.dropped_last == 0);
    CHECK(b.bank0->stats().row_reads == 16);
    CHECK(b.bank0->stats().row_writes == 16);
    CHECK(b.bank0->lists_overflowed() == 0);
    CHECK(b.bank0->fragments_dropped() == 0);
    for (unsigned p = 0; p < 4; ++p) CHECK(b.bank0->count(p) == 4);
}

TEST_CASE("hw sorter: insertion at every position of a full list of 4 with M=4", "[sorter]") {
    SorterBench b(small_config(4));
    // Pixel p (p = 0..4) holds 10 20 30 40, then the new element (id 9) sorts at position p.
    const std::uint32_t new_depth[5] = {5, 15, 25, 35, 45};
    std::vector<Fragment> fs;
    for (std::uint32_t p = 0; p < 5; ++p) {   // list p is pixel (p % 4, p / 4)
        append(fs, column(p % 4, {10, 20, 30, 40}, p / 4));
        fs.push_back(frag(p % 4, p / 4, new_depth[p], 9, 'F'));
    }
    b.fill(*b.bank0, tb::tile(0, 0, 0, fs));
    CHECK(b.row(*b.bank0, 0) == "5:9F 10:1F 20:2F 30:3F");     // 40 shifted out
    CHECK(b.row(*b.bank0, 1) == "10:1F 15:9F 20:2F 30:3F");
    CHECK(b.row(*b.bank0, 2) == "10:1F 20:2F 25:9F 30:3F");
    CHECK(b.row(*b.bank0, 3) == "10:1F 20:2F 30:3F 35:9F");    // 40 replaced in place
    CHECK(b.row(*b.bank0, 4) == "10:1F 20:2F 30:3F 40:4F");    // position M: new dropped, row unchanged
    const auto& s = b.sorter->stats();
    CHECK(s.insertions == 25);
    CHECK(s.comparator_activations == 25 * 4);
    CHECK(s.overflows == 5);
    CHECK(s.dropped_new == 1);
    CHECK(s.dropped_last == 4);
    // M-1-pos elements move for pos 0..3 (3 + 2 + 1 + 0); none when the new one is dropped.
    CHECK(s.mux_shifts == 6);
    // Every insertion reads its row; the dropped new element writes nothing.
    CHECK(b.bank0->stats().row_reads == 25);
    CHECK(b.bank0->stats().row_writes == 24);
    CHECK(b.bank0->lists_overflowed() == 5);
    CHECK(b.bank0->fragments_dropped() == 5);
    for (unsigned p = 0; p < 5; ++p) CHECK(b.bank0->count(p) == 4);
}

TEST_CASE("hw sorter: a dropped new element leaves the row and the write port untouched", "[sorter]") {
    SorterBench b(small_config(2));
    b.fill(*b.bank0, tb::tile(0, 0, 0, {frag(0, 0, 10, 1, 'F'), frag(0, 0, 20, 2, 'B'), frag(0, 0, 30, 3, 'F')}));
    CHECK(b.row(*b.bank0, 0) == "10:1F 20:2B");
    CHECK(b.bank0->stats().row_reads == 3);
    CHECK(b.bank0->stats().row_writes == 2);
    CHECK(b.sorter->stats().dropped_new == 1);
    CHECK(b.sorter->stats().dropped_last == 0);
    CHECK(b.sorter->stats().mux_shifts == 0);
    CHECK(b.bank0->lists_overflowed() == 1);
    CHECK(b.bank0->fragments_dropped() == 1);
}

TEST_CASE("hw sorter: arrivals out of depth order are sorted with exact mux shifts", "[sorter]") {
    SorterBench b(small_config(8));
    // 30 -> [30]; 10 -> [10 30] (1 shift); 40 -> [10 30 40]; 20 -> [10 20 30 40] (2 shifts);
    // 5 -> 4 shifts; 45 -> none; 25 -> 3 shifts (30 40 45).
    b.fill(*b.bank0, tb::tile(0, 0, 0, column(2, {30, 10, 40, 20, 5, 45, 25})));
    CHECK(b.row(*b.bank0, 2) == "5:5F 10:2F 20:4F 25:7F 30:1F 40:3F 45:6F");
    CHECK(b.sorter->stats().mux_shifts == 1 + 2 + 4 + 3);
    CHECK(b.sorter->stats().comparator_activations == 7 * 8);
    CHECK(b.bank0->count(2) == 7);
}

TEST_CASE("hw sorter: both overflow branches with M=2 and the bank's overflow bookkeeping", "[sorter]") {
    SorterBench b(small_config(2));
    std::vector<Fragment> fs;
    // Pixel 0: 10 20 -> full; 30 dropped (new); 5 shifts 20 out; 7 replaces 10.
    append(fs, column(0, {10, 20, 30, 5, 7}));
    // Pixel 1: 10 20, then 15 replaces 20.
    append(fs, column(1, {10, 20, 15}));
    // Pixel 2: 30 20: no overflow, one shift.
    append(fs, column(2, {30, 20}));
    b.fill(*b.bank0, tb::tile(0, 0, 0, fs));
    CHECK(b.row(*b.bank0, 0) == "5:4F 7:5F");
    CHECK(b.row(*b.bank0, 1) == "10:1F 15:3F");
    CHECK(b.row(*b.bank0, 2) == "20:2F 30:1F");
    const auto& s = b.sorter->stats();
    CHECK(s.overflows == 4);
    CHECK(s.dropped_new == 1);
    CHECK(s.dropped_last == 3);
    CHECK(s.mux_shifts == 2);   // 5 at position 0 of pixel 0, 20 at position 0 of pixel 2
    CHECK(b.bank0->lists_overflowed() == 2);
    CHECK(b.bank0->fragments_dropped() == 4);
    CHECK(b.bank0->stats().row_reads == 10);
    CHECK(b.bank0->stats().row_writes == 9);
}

TEST_CASE("hw sorter: ties under front_first put fronts before backs and equal keys after", "[sorter]") {
    SimConfig cfg = small_config(8);
    cfg.zeb.tie = TiePolicy::FrontFirst;
    SorterBench b(cfg);
    b.fill(*b.bank0, tb::tile(0, 0, 0,
                              {frag(0, 0, 50, 1, 'B'), frag(0, 0, 50, 2, 'F'), frag(0, 0, 50, 3, 'F'),
                               frag(0, 0, 50, 4, 'B'), frag(0, 0, 40, 5, 'B'), frag(0, 0, 60, 6, 'F')}));
    // 1B; 2F before it (1 shift); 3F after 2F (1 shift); 4B after 1B; 40 first (4 shifts); 60 last.
    CHECK(b.row(*b.bank0, 0) == "40:5B 50:2F 50:3F 50:1B 50:4B 60:6F");
    CHECK(b.sorter->stats().mux_shifts == 1 + 1 + 4);
}

TEST_CASE("hw sorter: ties under arrival keep arrival order whatever the facing", "[sorter]") {
    SimConfig cfg = small_config(8);
    cfg.zeb.tie = TiePolicy::Arrival;
    SorterBench b(cfg);
    b.fill(*b.bank0, tb::tile(0, 0, 0,
                              {frag(0, 0, 50, 1, 'B'), frag(0, 0, 50, 2, 'F'), frag(0, 0, 50, 3, 'F'),
                               frag(0, 0, 50, 4, 'B'), frag(0, 0, 40, 5, 'B'), frag(0, 0, 60, 6, 'F')}));
    CHECK(b.row(*b.bank0, 0) == "40:5B 50:1B 50:2F 50:3F 50:4B 60:6F");
    CHECK(b.sorter->stats().mux_shifts == 4);
}

TEST_CASE("hw sorter: a tie on a full list under front_first drops the back face not the front", "[sorter]") {
    SimConfig cfg = small_config(2);
    SorterBench b(cfg);
    // Pixel 0: [50:1F 50:2B] full, then 50:3F sorts between them: 2B is shifted out.
    // Pixel 1: [50:1F 50:2F] full, then 50:3F goes after both equals: position M, dropped.
    b.fill(*b.bank0, tb::tile(0, 0, 0,
                              {frag(0, 0, 50, 1, 'F'), frag(0, 0, 50, 2, 'B'), frag(0, 0, 50, 3, 'F'),
                               frag(1, 0, 50, 1, 'F'), frag(1, 0, 50, 2, 'F'), frag(1, 0, 50, 3, 'F')}));
    CHECK(b.row(*b.bank0, 0) == "50:1F 50:3F");
    CHECK(b.row(*b.bank0, 1) == "50:1F 50:2F");
    CHECK(b.sorter->stats().dropped_last == 1);
    CHECK(b.sorter->stats().dropped_new == 1);
}

TEST_CASE("hw sorter: quantization with z_bits below depth_bits collapses depths", "[sorter]") {
    SimConfig cfg = small_config(8);
    cfg.zeb.z_bits = 16;   // depth_bits 24: dq = depth >> 8
    SorterBench b(cfg);
    // 0x1ff and 0x100 both give dq 1 (arrival order kept among the fronts), 0xff gives 0.
    // Pixel 1: 0x100 back then 0x1ff front: equal dq, front first.
    b.fill(*b.bank0, tb::tile(0, 0, 0,
                              {frag(0, 0, 0x1ff, 1, 'F'), frag(0, 0, 0x100, 2, 'F'), frag(0, 0, 0xff, 3, 'B'),
                               frag(1, 0, 0x100, 4, 'B'), frag(1, 0, 0x1ff, 5, 'F'),
                               frag(2, 0, 0xffffff, 6, 'F')}),
           0, 24);
    CHECK(b.row(*b.bank0, 0) == "0:3B 1:1F 1:2F");
    CHECK(b.row(*b.bank0, 1) == "1:5F 1:4B");
    CHECK(b.row(*b.bank0, 2) == "65535:6F");
}

TEST_CASE("hw sorter: quantization with z_bits above depth_bits widens depths", "[sorter]") {
    SimConfig cfg = small_config(8);
    cfg.zeb.z_bits = 24;
    SorterBench b(cfg);
    // depth_bits 16: dq = depth << 8.
    b.fill(*b.bank0, tb::tile(0, 0, 0, {frag(0, 0, 0x1234, 1, 'F'), frag(0, 0, 0xffff, 2, 'B'),
                                        frag(0, 0, 0x0001, 3, 'F')}),
           0, 16);
    CHECK(b.row(*b.bank0, 0) == std::to_string(0x100) + ":3F " + std::to_string(0x123400) + ":1F " +
                                    std::to_string(0xffff00) + ":2B");
}

TEST_CASE("hw sorter: 32-bit depths and 16-bit ids survive packing in a 49-bit element", "[sorter]") {
    SimConfig cfg = small_config(4);
    cfg.zeb.z_bits = 32;
    cfg.zeb.id_bits = 16;
    SorterBench b(cfg);
    b.fill(*b.bank0, tb::tile(0, 0, 0, {frag(0, 0, 0xffffffffu, 65535, 'B'), frag(0, 0, 0xfffffffeu, 1, 'B'),
                                        frag(0, 0, 0xffffffffu, 2, 'F'), frag(0, 0, 0x80000000u, 65534, 'F')}),
           0, 32);
    CHECK(b.row(*b.bank0, 0) == "2147483648:65534F 4294967294:1B 4294967295:2F 4294967295:65535B");
    CHECK(b.bank0->bits() == 16ull * 4 * 49);
}

TEST_CASE("hw sorter: occupancy bits are set exactly for the non-empty lists", "[sorter]") {
    SorterBench b(SimConfig{});   // 16x16 tile: 256 lists, 4 bitmap words
    // Tile (2, 1): x0 = 32, y0 = 16. Lists 0, 63, 64, 200, 255.
    b.fill(*b.bank0, tb::tile(0, 2, 1,
                              {frag(32, 16, 5, 1, 'F'), frag(47, 19, 5, 1, 'F'), frag(32, 20, 5, 1, 'F'),
                               frag(40, 28, 5, 1, 'F'), frag(47, 31, 5, 1, 'F'), frag(47, 31, 6, 1, 'B')}));
    const auto& occ = b.bank0->occupancy();
    REQUIRE(occ.size() == 4);
    CHECK(occ[0] == ((1ull << 0) | (1ull << 63)));
    CHECK(occ[1] == (1ull << 0));
    CHECK(occ[2] == 0);
    CHECK(occ[3] == ((1ull << 8) | (1ull << 63)));
    CHECK(b.bank0->count(0) == 1);
    CHECK(b.bank0->count(63) == 1);
    CHECK(b.bank0->count(64) == 1);
    CHECK(b.bank0->count(200) == 1);
    CHECK(b.bank0->count(255) == 2);
    CHECK(b.bank0->count(1) == 0);
    CHECK(b.row(*b.bank0, 255) == "5:1F 6:1B");
}

TEST_CASE("hw sorter: a list that only drops new elements stays occupied and counted once", "[sorter]") {
    SorterBench b(small_config(1));
    // M=1: 10 kept; 20 30 dropped (new); 5 replaces 10 (last shifted out).
    b.fill(*b.bank0, tb::tile(0, 0, 0, column(3, {10, 20, 30, 5})));
    CHECK(b.row(*b.bank0, 3) == "5:4F");
    CHECK(b.bank0->occupancy()[0] == (1ull << 3));
    CHECK(b.bank0->lists_overflowed() == 1);
    CHECK(b.bank0->fragments_dropped() == 3);
    CHECK(b.sorter->stats().dropped_new == 2);
    CHECK(b.sorter->stats().dropped_last == 1);
    CHECK(b.sorter->stats().mux_shifts == 0);
    CHECK(b.bank0->stats().row_writes == 2);
}

// ---------------------------------------------------------------------------
// Timing of fill_tile

TEST_CASE("hw sorter: timing at rate 4 with a deep queue", "[sorter][timing]") {
    SimConfig cfg;
    cfg.feed.fragments_per_cycle = 4;
    cfg.feed.queue_depth = 32;
    SorterBench b(cfg);
    // Enqueued 0-3 at 100, 4-7 at 101, 8-9 at 102; issued 101..110.
    const auto r = b.fill(*b.bank0, distinct_pixels(0, 10), 100);
    CHECK(r.feed_done == 103);
    CHECK(r.first_issue == 101);
    CHECK(r.last_issue == 110);
    CHECK(r.fill_done == 113);
    CHECK(r.queue_stall == 0);
    const auto& s = b.sorter->stats();
    CHECK(s.busy_cycles == 10);
    CHECK(s.hazard_forwards == 0);
    CHECK(s.hazard_stall_cycles == 0);
    // Fragment 9 enqueues at 102, when fragments 0 and 1 have issued: 8 held.
    CHECK(b.queue->stats().max_occupancy == 8);
}

TEST_CASE("hw sorter: timing at rate 1 with a deep queue", "[sorter][timing]") {
    SimConfig cfg;
    cfg.feed.fragments_per_cycle = 1;
    cfg.feed.queue_depth = 32;
    SorterBench b(cfg);
    // Enqueued 100..109, each issued the cycle after: the feed is the bottleneck.
    const auto r = b.fill(*b.bank0, distinct_pixels(0, 10), 100);
    CHECK(r.feed_done == 110);
    CHECK(r.first_issue == 101);
    CHECK(r.last_issue == 110);
    CHECK(r.fill_done == 113);
    CHECK(r.queue_stall == 0);
    CHECK(b.queue->stats().max_occupancy == 1);
}

TEST_CASE("hw sorter: timing with a queue of depth 1", "[sorter][timing]") {
    SimConfig cfg;
    cfg.feed.fragments_per_cycle = 4;
    cfg.feed.queue_depth = 1;
    SorterBench b(cfg);
    // Fragment i enqueues when fragment i-1 issues (cycle i), issues at i+1.
    const auto r = b.fill(*b.bank0, distinct_pixels(0, 6), 0);
    CHECK(r.first_issue == 1);
    CHECK(r.last_issue == 6);
    CHECK(r.fill_done == 9);
    CHECK(r.feed_done == 6);
    CHECK(r.queue_stall == 6 - 2);   // an unhindered feed needs ceil(6/4) = 2 cycles
    CHECK(b.queue->stats().max_occupancy == 1);
}

TEST_CASE("hw sorter: timing with a queue of depth 2", "[sorter][timing]") {
    SimConfig cfg;
    cfg.feed.fragments_per_cycle = 4;
    cfg.feed.queue_depth = 2;
    SorterBench b(cfg);
    // Enqueue 0 0 1 2 3 4, issue 1 2 3 4 5 6.
    const auto r = b.fill(*b.bank0, distinct_pixels(0, 6), 0);
    CHECK(r.first_issue == 1);
    CHECK(r.last_issue == 6);
    CHECK(r.fill_done == 9);
    CHECK(r.feed_done == 5);
    CHECK(r.queue_stall == 3);
    CHECK(b.queue->stats().max_occupancy == 2);
}

TEST_CASE("hw sorter: same-pixel hazards are forwarded without losing a cycle", "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Forward;
    SorterBench b(cfg);
    // Pixels A A B A C C (x = 0 0 1 0 2 2): issues 1..6; hazards at fragments 1, 3 and 5.
    const auto r = b.fill(*b.bank0, on_pixels({0, 0, 1, 0, 2, 2}), 0);
    CHECK(r.first_issue == 1);
    CHECK(r.last_issue == 6);
    CHECK(r.fill_done == 9);
    CHECK(r.feed_done == 2);
    CHECK(b.sorter->stats().hazard_forwards == 3);
    CHECK(b.sorter->stats().hazard_stall_cycles == 0);
    CHECK(b.row(*b.bank0, 0) == "110:1F 120:1F 140:1F");
    CHECK(b.row(*b.bank0, 2) == "150:1F 160:1F");
}

TEST_CASE("hw sorter: same-pixel hazards stall the read until the older write is done", "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Stall;
    SorterBench b(cfg);
    // A 1; A waits for 1+3 = 4 (2 lost); B 5; A: unhindered 6, 2-back A at 4 -> 7 (1 lost);
    // C 8; C: unhindered 9, waits for 8+3 = 11 (2 lost).
    const auto r = b.fill(*b.bank0, on_pixels({0, 0, 1, 0, 2, 2}), 0);
    CHECK(r.first_issue == 1);
    CHECK(r.last_issue == 11);
    CHECK(r.fill_done == 14);
    CHECK(r.feed_done == 2);
    CHECK(r.queue_stall == 0);
    CHECK(b.sorter->stats().hazard_forwards == 0);
    CHECK(b.sorter->stats().hazard_stall_cycles == 5);
    CHECK(b.sorter->stats().busy_cycles == 6);
    CHECK(b.row(*b.bank0, 0) == "110:1F 120:1F 140:1F");
}

TEST_CASE("hw sorter: under stall a re-read exactly three cycles after the read is allowed", "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Stall;
    SorterBench b(cfg);
    // B A B A: B 1, A 2, B waits for 4, A unhindered 5 = 2 + 3: no further stall.
    const auto r = b.fill(*b.bank0, on_pixels({1, 0, 1, 0}), 0);
    CHECK(r.last_issue == 5);
    CHECK(r.fill_done == 8);
    CHECK(b.sorter->stats().hazard_stall_cycles == 1);
}

TEST_CASE("hw sorter: B A B A forwarded counts two hazards", "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Forward;
    SorterBench b(cfg);
    const auto r = b.fill(*b.bank0, on_pixels({1, 0, 1, 0}), 0);
    CHECK(r.last_issue == 4);
    CHECK(r.fill_done == 7);
    CHECK(b.sorter->stats().hazard_forwards == 2);
}

TEST_CASE("hw sorter: stall and queue interact - a stalled issue holds the feed of a full queue",
          "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Stall;
    cfg.feed.fragments_per_cycle = 4;
    cfg.feed.queue_depth = 1;
    SorterBench b(cfg);
    // A A B: A enq 0 issue 1; A enq 1 (slot frees at 1) issue 4 (stall); B enq 4 issue 5.
    const auto r = b.fill(*b.bank0, on_pixels({0, 0, 1}), 0);
    CHECK(r.first_issue == 1);
    CHECK(r.last_issue == 5);
    CHECK(r.fill_done == 8);
    CHECK(r.feed_done == 5);
    CHECK(r.queue_stall == 5 - 1);
    CHECK(b.sorter->stats().hazard_stall_cycles == 2);
}

TEST_CASE("hw sorter: pipeline and queue state carry over between tiles", "[sorter][timing]") {
    SimConfig cfg;
    cfg.feed.fragments_per_cycle = 4;
    cfg.feed.queue_depth = 4;
    SorterBench b(cfg);
    // Tile 0: fragments 0-3 enqueue at 0, fragment i >= 4 when fragment i-4 issues (i-3); issues 1..16.
    const auto r0 = b.fill(*b.bank0, distinct_pixels(0, 16), 0);
    CHECK(r0.first_issue == 1);
    CHECK(r0.last_issue == 16);
    CHECK(r0.fill_done == 19);
    CHECK(r0.feed_done == 13);
    CHECK(r0.queue_stall == 13 - 4);
    // Tile 1 starts at 13 into a queue still holding fragments 13-15 of tile 0: fragment 16
    // takes the slot fragment 12 freed at 13, fragment i (16..31) enqueues at i-3, issues at
    // i+1 behind tile 0's last issue.
    const auto r1 = b.fill(*b.bank1, distinct_pixels(1, 16), r0.feed_done);
    CHECK(r1.first_issue == 17);
    CHECK(r1.last_issue == 32);
    CHECK(r1.fill_done == 35);
    CHECK(r1.feed_done == 29);
    CHECK(r1.queue_stall == (29 - 13) - 4);
    const auto& s = b.sorter->stats();
    CHECK(s.insertions == 32);
    CHECK(s.busy_cycles == 32);
    CHECK(r0.queue_stall + r1.queue_stall == 9 + 12);
    CHECK(b.queue->stats().max_occupancy == 4);
}

TEST_CASE("hw sorter: a later tile issues behind the previous one or after its own enqueue", "[sorter][timing]") {
    SimConfig cfg;   // rate 4, queue 32
    SorterBench b(cfg);
    // Tile 0: enqueue 0-3, issue 1..16, feed done 4.
    const auto r0 = b.fill(*b.bank0, distinct_pixels(0, 16), 0);
    CHECK(r0.feed_done == 4);
    CHECK(r0.last_issue == 16);
    // Tile 1 from 4: enqueue 4-7, the sorter is still busy with tile 0: issues 17..32.
    const auto r1 = b.fill(*b.bank1, distinct_pixels(1, 16), 4);
    CHECK(r1.first_issue == 17);
    CHECK(r1.last_issue == 32);
    CHECK(r1.fill_done == 35);
    CHECK(r1.feed_done == 8);
    CHECK(r1.queue_stall == 0);
    // Tile 2 much later, into bank 0 again after its test: the pipeline is empty, issue = enqueue + 1.
    b.bank0->begin_test(19);
    b.bank0->release(40);
    const auto r2 = b.fill(*b.bank0, distinct_pixels(2, 3), 200);
    CHECK(r2.first_issue == 201);
    CHECK(r2.last_issue == 203);
    CHECK(r2.fill_done == 206);
    CHECK(r2.feed_done == 201);
    CHECK(b.row(*b.bank0, 0) == "1000:1F");
    CHECK(b.row(*b.bank0, 3) == "");   // cleared by begin_fill: tile 0's list 3 is gone
    // Starvation is counted within a tile only: none here.
}

TEST_CASE("hw sorter: hazards do not reach across tiles", "[sorter][timing]") {
    SimConfig cfg;
    cfg.sorter.hazard = HazardPolicy::Stall;
    SorterBench b(cfg);
    // Tile 0 ends on pixel 0 issued at 2; tile 1 starts on pixel 0 (another bank) at 3.
    const auto r0 = b.fill(*b.bank0, tb::tile(0, 0, 0, {frag(1, 0, 10, 1, 'F'), frag(0, 0, 10, 1, 'F')}), 0);
    CHECK(r0.last_issue == 2);
    const auto r1 = b.fill(*b.bank1, tb::tile(0, 1, 0, {frag(16, 0, 10, 1, 'F')}), r0.feed_done);
    CHECK(r1.first_issue == 3);
    CHECK(b.sorter->stats().hazard_stall_cycles == 0);
}

// insert() sorts a tile by loops over the list count or by fixed work over
// all M slots, chosen per tile from how often the count changed in the tiles
// before (insertion_sorter::path()). Both must leave every list as the
// contract's sorted insertion does: the M smallest (depth, then front before
// back under front_first), equal keys in arrival order; and count alike:
// every arrival past M drops one element (the new one when it sorts last),
// the muxes shift the elements below the new one, a row is written unless
// the new element is dropped, and the bank counts each tile's dropped
// fragments and overflowed lists. Tiles of long per-pixel bursts (full
// lists, the count repeats: the loops), then tiles of random pixels (the
// count changes: all slots), then bursts again; for each M the all-slots
// path has (4, 8, 16, with enough fragments a pixel to fill 16) and both tie
// policies. The expected lists and counts are replayed here.
TEST_CASE("sorter: loops and all-slots paths sort alike", "[sorter]") {
    for (const unsigned m : {4u, 8u, 16u}) {
        for (const TiePolicy tie : {TiePolicy::FrontFirst, TiePolicy::Arrival}) {
            SimConfig cfg;   // 16x16 tiles
            cfg.zeb.list_length = m;
            cfg.zeb.tie = tie;
            SorterBench b(cfg);
            std::mt19937_64 gen(2027 + m);
            const auto range = [&](unsigned lo, unsigned hi) { return lo + static_cast<unsigned>(gen() % (hi - lo + 1)); };
            const unsigned random_pixels = m == 16 ? 48 : 256;   // 25 or 4.7 fragments a pixel
            unsigned loops_tiles = 0, all_slots_tiles = 0;
            std::uint64_t want_overflows = 0, want_dropped_new = 0, want_shifts = 0;
            for (unsigned t = 0; t < 48; ++t) {
                const bool bursts = t < 16 || t >= 40;
                std::vector<Fragment> frags;
                for (unsigned k = 0; k < 1200; ++k) {
                    const unsigned px = bursts ? (k / 300) * 37 % 256 : range(0, random_pixels - 1) * 5 % 256;
                    frags.push_back(frag(px % 16, px / 16, range(0, 63) * 4096, range(1, 9), range(0, 1) ? 'F' : 'B'));
                }
                const Tile tile = tb::tile(0, 0, 0, frags);
                zeb_bank bank(("zeb_paths" + std::to_string(m) + "_" + std::to_string(int(tie)) + "_" + std::to_string(t)).c_str(),
                              cfg.zeb, cfg.tile, 0);
                b.fill(bank, tile);
                ++(b.sorter->path() == insertion_sorter::AllSlots ? all_slots_tiles : loops_tiles);
                const auto dq = [&](const Fragment& f) { return quantize_depth(f.depth, 24, cfg.zeb.z_bits); };
                const auto before = [&](const Fragment& a, const Fragment& c) {
                    if (dq(a) != dq(c)) return dq(a) < dq(c);
                    return tie == TiePolicy::FrontFirst && a.facing == Facing::Front && c.facing == Facing::Back;
                };
                std::vector<std::vector<Fragment>> held(256);
                std::vector<bool> overflowed(256, false);
                std::uint64_t tile_dropped = 0, tile_writes = 0;
                for (const Fragment& f : frags) {
                    auto& v = held[f.y * 16 + f.x];
                    const std::size_t n = v.size();
                    const auto at = std::upper_bound(v.begin(), v.end(), f, before);
                    const std::size_t pos = static_cast<std::size_t>(at - v.begin());
                    if (n == m) {
                        ++want_overflows;
                        ++tile_dropped;
                        overflowed[f.y * 16 + f.x] = true;
                        if (pos == m) {
                            ++want_dropped_new;
                            continue;
                        }
                        want_shifts += m - 1 - pos;
                        v.pop_back();
                    } else {
                        want_shifts += n - pos;
                    }
                    v.insert(v.begin() + static_cast<std::ptrdiff_t>(pos), f);
                    ++tile_writes;
                }
                for (unsigned li = 0; li < 256; ++li) {
                    std::string want;
                    for (const Fragment& f : held[li]) {
                        if (!want.empty()) want += ' ';
                        want += std::to_string(dq(f)) + ":" + std::to_string(f.id) + (f.facing == Facing::Back ? "B" : "F");
                    }
                    INFO("M " << m << " tie " << int(tie) << " tile " << t << " list " << li << " path " << b.sorter->path());
                    REQUIRE(b.row(bank, li) == want);
                }
                INFO("M " << m << " tie " << int(tie) << " tile " << t << " path " << b.sorter->path());
                REQUIRE(b.sorter->stats().overflows == want_overflows);
                REQUIRE(b.sorter->stats().dropped_new == want_dropped_new);
                REQUIRE(b.sorter->stats().dropped_last == want_overflows - want_dropped_new);
                REQUIRE(b.sorter->stats().mux_shifts == want_shifts);
                REQUIRE(bank.stats().row_writes == tile_writes);
                REQUIRE(bank.fragments_dropped() == tile_dropped);
                REQUIRE(bank.lists_overflowed() == std::count(overflowed.begin(), overflowed.end(), true));
            }
            INFO("M " << m << " tie " << int(tie) << ": " << loops_tiles << " tiles by the loops, " << all_slots_tiles
                      << " by all slots");
            CHECK(loops_tiles >= 8);
            CHECK(all_slots_tiles >= 8);
            CHECK(want_dropped_new > 0);
            CHECK(want_overflows > want_dropped_new);
        }
    }
}
