// The z-overlap tester alone: the driver fills ZEB banks directly (packed rows
// in sorted order, counts, occupancy bits, overflow notes) and posts the
// tester's jobs; the checker is the real output path: output_buffer ->
// memory_controller (TLM-2.0) -> host_reader -> RecordingSink. No sorter, no
// feed. Expected records follow rbcd-contract.md "Z-overlap test" and
// "Output"; cycle numbers follow the header of hw/zoverlap_tester.h (first row
// read 1 cycle, 1 cycle per element, k cycles for a back face with k > 1 hits).
//
// One TEST_CASE per process (catch_discover_tests): no SECTIONs.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "rbcd/testbench/hw/tb_util.h"
#include "rbcd/tlm/memory_controller.h"

using namespace rbcd;

namespace {

struct E {
    std::uint32_t dq;
    std::uint32_t id;
    char facing;   // 'F' or 'B'
};

SimConfig tester_config() {
    SimConfig cfg;
    cfg.tile.width = 4;   // 8 lists: list li is pixel (x0 + li % 4, y0 + li / 4)
    cfg.tile.height = 2;
    cfg.zeb.list_length = 8;
    cfg.tester.stack_depth = 8;
    cfg.memory.latency_min = cfg.memory.latency_max = 50;
    cfg.host.readback_cycles = 100;
    // One output region: the tester waits for each frame-end readback, which
    // these cases count (the double-buffered case is in test_timing.cpp).
    cfg.output.double_buffer = false;
    return cfg;
}

// Driver + block under test + checker, elaborated once per test case.
struct TesterBench : sc_core::sc_module {
    SC_HAS_PROCESS(TesterBench);

    SimConfig cfg;
    Clocking clk;
    RecordingSink sink;
    std::vector<std::unique_ptr<zeb_bank>> banks;
    memory_controller memory;
    host_reader host;
    output_buffer outbuf;
    zoverlap_tester tester;
    std::vector<std::uint64_t> freed0;   // cycles at which bank 0 announced itself free

    static std::vector<std::unique_ptr<zeb_bank>> make_banks(const SimConfig& c, unsigned n) {
        std::vector<std::unique_ptr<zeb_bank>> v;
        for (unsigned i = 0; i < n; ++i)
            v.push_back(std::make_unique<zeb_bank>(("zeb" + std::to_string(i)).c_str(), c.zeb, c.tile, i));
        return v;
    }

    TesterBench(sc_core::sc_module_name name, const SimConfig& c, unsigned nbanks = 1)
        : sc_module(name),
          cfg(c),
          clk(c.clock.period_ps()),
          banks(make_banks(c, nbanks)),
          memory("memory", c.memory, clk.period()),
          host("host", c, sink),
          outbuf("outbuf", c, clk, host),
          tester("tester", c, clk, outbuf, host) {
        outbuf.mem.bind(memory.unit_port);
        host.mem.bind(memory.host_port);
        SC_THREAD(watch);
    }

    void watch() {
        for (;;) {
            wait(banks[0]->freed);
            freed0.push_back(clk.now());
        }
    }

    // Driver: bank b takes tile (col, row) at cycle 0.
    zeb_bank& take(unsigned b, std::uint32_t col, std::uint32_t row) {
        banks[b]->begin_fill(0, col, row, 0);
        return *banks[b];
    }
    // Writes list li front to back as the sorter would leave it.
    void put(zeb_bank& bank, unsigned li, std::vector<E> es) {
        const ElementLayout lay = cfg.zeb.layout();
        for (std::size_t i = 0; i < es.size(); ++i) {
            Element e;
            e.dq = es[i].dq;
            e.id = es[i].id;
            e.facing = es[i].facing == 'B' ? Facing::Back : Facing::Front;
            bank.list(li)[i] = lay.pack(e);
        }
        bank.count(li) = static_cast<std::uint8_t>(es.size());
        bank.mark_occupied(li);
    }
    // One frame of the given (bank, ready cycle) tile jobs, then run to the end.
    void run(std::vector<std::pair<zeb_bank*, std::uint64_t>> jobs) {
        tester.post({zoverlap_tester::Job::FrameStart, 0, nullptr, 0});
        for (auto& j : jobs) {
            // The fragments a rasterizer would have sent for the tile: the
            // elements put and the overflows noted (the per-tile self-check).
            std::uint64_t in = j.first->fragments_dropped();
            for (unsigned li = 0; li < j.first->lists(); ++li) in += j.first->count(li);
            tester.post({zoverlap_tester::Job::TileJob, 0, j.first, j.second, in});
        }
        tester.post({zoverlap_tester::Job::FrameEnd, 0, nullptr, 0});
        tester.post({zoverlap_tester::Job::Finish, 0, nullptr, 0});
        sc_core::sc_start();
    }
    std::string records() const { return tb::to_text(sink); }
};

std::unique_ptr<TesterBench> bench(const SimConfig& cfg, unsigned nbanks = 1) {
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
    return std::make_unique<TesterBench>("bench", cfg, nbanks);
}

// The same two tiles for every output mode. Tile (1, 2): x0 = 4, y0 = 4; tile (2, 2): x0 = 8.
//   list 1 (5,4): 1F 2F 2F 1B@40   -> (1,2)@40 twice (two entries of id 2 above id 1)
//   list 6 (6,5): 2F 1F 5F 2B@8    -> (1,2)@8, (2,5)@8
//   tile 2 list 0 (8,4): 1F 2F 1B@7 -> (1,2)@7
void output_mode_run(TesterBench& b) {
    zeb_bank& t0 = b.take(0, 1, 2);
    b.put(t0, 1, {{10, 1, 'F'}, {20, 2, 'F'}, {30, 2, 'F'}, {40, 1, 'B'}});
    b.put(t0, 6, {{5, 2, 'F'}, {6, 1, 'F'}, {7, 5, 'F'}, {8, 2, 'B'}});
    zeb_bank& t1 = b.take(1, 2, 2);
    b.put(t1, 0, {{5, 1, 'F'}, {6, 2, 'F'}, {7, 1, 'B'}});
    b.run({{&t0, 10}, {&t1, 12}});
}

void check_output_mode_timing(const TesterBench& b) {
    const auto& s = b.tester.stats();
    CHECK(s.tiles == 2);
    CHECK(s.lists == 3);
    CHECK(s.elements == 11);
    CHECK(s.raw_hits == 5);
    // Filtered hits still take their encoder cycle: tile 0 = 1 + (3 + 2) + (3 + 2) = 11,
    // tile 1 = 1 + 2 + 1 = 4.
    CHECK(s.busy_cycles == 15);
    CHECK(s.output_stall_cycles == 0);
    CHECK(b.banks[0]->stats().testing_cycles == 11);
    CHECK(b.banks[1]->stats().testing_cycles == 4);
    // Tile 1 was ready at 12 but the tester was busy with tile 0 until 21.
    CHECK(b.banks[1]->stats().filling_cycles == 21);
    CHECK(b.banks[0]->state() == zeb_bank::State::Free);
    CHECK(b.banks[1]->state() == zeb_bank::State::Free);
}

} // namespace

// ---------------------------------------------------------------------------
// The paper's Figure 5

TEST_CASE("hw tester: figure 5 case 1 - disjoint intervals give no hit", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 1, 2);
    b->put(bank, 5, {{10, 1, 'F'}, {20, 1, 'B'}, {30, 2, 'F'}, {40, 2, 'B'}});
    b->run({{&bank, 10}});
    CHECK(b->records() == "frame 0\n");
    const auto& s = b->tester.stats();
    CHECK(s.tiles == 1);
    CHECK(s.lists == 1);
    CHECK(s.elements == 4);
    CHECK(s.pushes == 2);
    CHECK(s.matches == 2);
    CHECK(s.orphan_back_faces == 0);
    CHECK(s.raw_hits == 0);
    CHECK(s.hits == 0);
    CHECK(s.id_compares == 2 * 8);
    // Ready at 10; row read 10 -> 11; four elements: done at 15. Frame end: nothing to
    // write, readback 100 cycles.
    CHECK(s.idle_cycles == 10);
    CHECK(s.busy_cycles == 5);
    CHECK(s.readback_cycles == 100);
    CHECK(b->tester.finish_cycle() == 115);
    CHECK(bank.stats().filling_cycles == 10);
    CHECK(bank.stats().testing_cycles == 5);
    CHECK(bank.state() == zeb_bank::State::Free);
}

TEST_CASE("hw tester: figure 5 case 2 - A back inside B gives one hit at A back", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 1, 2);
    // A = 6, B = 2: A F, B F, A B, B B. List 5 is pixel (5, 5).
    b->put(bank, 5, {{10, 6, 'F'}, {20, 2, 'F'}, {30, 6, 'B'}, {40, 2, 'B'}});
    b->run({{&bank, 10}});
    CHECK(b->records() == "frame 0\nhit 5 5 2 6 30\n");
    const auto& s = b->tester.stats();
    CHECK(s.raw_hits == 1);
    CHECK(s.hits == 1);
    CHECK(s.matches == 2);
    CHECK(s.busy_cycles == 5);
    // The hit is written at 15 (flush): 16 bytes = 4 channel cycles + 50 latency = 69; + 100.
    CHECK(b->tester.finish_cycle() == 169);
    CHECK(b->outbuf.stats().records == 1);
    CHECK(b->host.stats().hit_records == 1);
    CHECK(bank.state() == zeb_bank::State::Free);
}

TEST_CASE("hw tester: figure 5 case 3 - B inside A gives one hit at A back", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    // A = 3, B = 1: A F, B F, B B, A B. B's entry is matched but still above A's: one hit.
    b->put(bank, 7, {{10, 3, 'F'}, {20, 1, 'F'}, {30, 1, 'B'}, {40, 3, 'B'}});
    b->run({{&bank, 0}});
    CHECK(b->records() == "frame 0\nhit 3 1 1 3 40\n");
    CHECK(b->tester.stats().matches == 2);
    CHECK(b->tester.stats().raw_hits == 1);
    CHECK(b->tester.stats().busy_cycles == 5);
    CHECK(b->tester.stats().idle_cycles == 0);
}

// ---------------------------------------------------------------------------
// FF-stack corners

TEST_CASE("hw tester: nested intervals of one object never hit themselves", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    b->put(bank, 0, {{10, 1, 'F'}, {20, 1, 'F'}, {30, 1, 'B'}, {40, 1, 'B'}});
    // Nested 1 around 2: 1B@30 matches the bottom 1 (2 above hits, the upper 1 is skipped);
    // 1B@40 matches the upper 1; 2B@50 matches 2 with the matched upper 1 above it.
    b->put(bank, 1, {{10, 1, 'F'}, {15, 2, 'F'}, {20, 1, 'F'}, {30, 1, 'B'}, {40, 1, 'B'}, {50, 2, 'B'}});
    b->run({{&bank, 0}});
    CHECK(b->records() == "frame 0\nhit 1 0 1 2 30\nhit 1 0 1 2 50\n");
    const auto& s = b->tester.stats();
    CHECK(s.matches == 5);
    CHECK(s.orphan_back_faces == 0);
    CHECK(s.raw_hits == 2);
    CHECK(s.pushes == 5);
    // 1 row read + 4 + 6 elements, no back face with more than one hit.
    CHECK(s.busy_cycles == 11);
}

TEST_CASE("hw tester: orphan back faces are counted and change nothing", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    // 2B on an empty stack; 2B with only id 1 pushed; 1B matches; 1B again finds only a matched entry.
    b->put(bank, 2, {{5, 2, 'B'}, {10, 1, 'F'}, {20, 2, 'B'}, {30, 1, 'B'}, {40, 1, 'B'}});
    b->run({{&bank, 0}});
    CHECK(b->records() == "frame 0\n");
    const auto& s = b->tester.stats();
    CHECK(s.orphan_back_faces == 3);
    CHECK(s.matches == 1);
    CHECK(s.pushes == 1);
    CHECK(s.id_compares == 4 * 8);
    CHECK(s.busy_cycles == 6);
}

TEST_CASE("hw tester: a full stack of T=2 drops the push and counts it", "[tester]") {
    SimConfig cfg = tester_config();
    cfg.tester.stack_depth = 2;
    auto b = bench(cfg);
    zeb_bank& bank = b->take(0, 0, 0);
    // 3F is dropped, so 3B is an orphan and 1B hits 2 only.
    b->put(bank, 0, {{10, 1, 'F'}, {20, 2, 'F'}, {30, 3, 'F'}, {40, 3, 'B'}, {50, 1, 'B'}, {60, 2, 'B'}});
    b->run({{&bank, 0}});
    CHECK(b->records() == "frame 0\nhit 0 0 1 2 50\n");
    const auto& s = b->tester.stats();
    CHECK(s.pushes == 2);
    CHECK(s.stack_overflows == 1);
    CHECK(s.orphan_back_faces == 1);
    CHECK(s.matches == 2);
    CHECK(s.id_compares == 3 * 2);
    CHECK(s.busy_cycles == 7);
}

TEST_CASE("hw tester: matched entries stay on the stack and still hit", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    // 1F 2F 3F; 3B matches 3 (nothing above); 2B matches 2: the matched 3 above still hits;
    // 1B: 2 and 3, both matched, still hit.
    b->put(bank, 0, {{10, 1, 'F'}, {20, 2, 'F'}, {30, 3, 'F'}, {40, 3, 'B'}, {50, 2, 'B'}, {60, 1, 'B'}});
    b->run({{&bank, 0}});
    CHECK(b->records() == "frame 0\nhit 0 0 2 3 50\nhit 0 0 1 2 60\nhit 0 0 1 3 60\n");
    CHECK(b->tester.stats().matches == 3);
    // 1 + 3 fronts + 3B (1) + 2B (1 hit, 1) + 1B (2 hits, 2 cycles) = 8.
    CHECK(b->tester.stats().busy_cycles == 8);
}

TEST_CASE("hw tester: the hit priority encoder emits one hit per cycle", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    b->put(bank, 0,
           {{10, 1, 'F'}, {20, 2, 'F'}, {30, 3, 'F'}, {40, 4, 'F'},   // 4 cycles
            {45, 4, 'B'},                                             // no hit: 1 cycle
            {50, 1, 'B'},                                             // 3 hits: 3 cycles
            {60, 2, 'B'},                                             // 2 hits: 2 cycles
            {70, 9, 'B'}});                                           // orphan: 1 cycle
    b->run({{&bank, 10}});
    CHECK(b->records() ==
          "frame 0\nhit 0 0 1 2 50\nhit 0 0 1 3 50\nhit 0 0 1 4 50\nhit 0 0 2 3 60\nhit 0 0 2 4 60\n");
    const auto& s = b->tester.stats();
    CHECK(s.busy_cycles == 1 + 4 + 1 + 3 + 2 + 1);
    CHECK(s.output_stall_cycles == 0);
    CHECK(s.raw_hits == 5);
    CHECK(s.orphan_back_faces == 1);
    CHECK(bank.stats().testing_cycles == 12);
    // Hits accepted at 16 17 18 19 20; the 4th fills a burst: issued at 19, 64 bytes take the
    // channel 19..35, done 85. The 5th is flushed at 22: channel 35..39, done 89. Readback +100.
    CHECK(b->outbuf.stats().bursts == 2);
    CHECK(b->tester.finish_cycle() == 189);
}

// ---------------------------------------------------------------------------
// Output modes on the same lists

TEST_CASE("hw tester: raw output writes every hit in order", "[tester]") {
    SimConfig cfg = tester_config();
    cfg.tester.output = OutputMode::Raw;
    auto b = bench(cfg, 2);
    output_mode_run(*b);
    CHECK(b->records() ==
          "frame 0\n"
          "hit 5 4 1 2 40\n"
          "hit 5 4 1 2 40\n"
          "hit 6 5 1 2 8\n"
          "hit 6 5 2 5 8\n"
          "hit 8 4 1 2 7\n");
    CHECK(b->tester.stats().hits == 5);
    CHECK(b->tester.stats().filtered_hits == 0);
    check_output_mode_timing(*b);
}

TEST_CASE("hw tester: pixel output keeps the first hit of each pair per pixel", "[tester]") {
    SimConfig cfg = tester_config();
    cfg.tester.output = OutputMode::Pixel;
    auto b = bench(cfg, 2);
    output_mode_run(*b);
    CHECK(b->records() ==
          "frame 0\n"
          "hit 5 4 1 2 40\n"
          "hit 6 5 1 2 8\n"
          "hit 6 5 2 5 8\n"
          "hit 8 4 1 2 7\n");
    CHECK(b->tester.stats().hits == 4);
    CHECK(b->tester.stats().filtered_hits == 1);
    check_output_mode_timing(*b);
}

TEST_CASE("hw tester: tile output keeps the first hit of each pair per tile", "[tester]") {
    SimConfig cfg = tester_config();
    cfg.tester.output = OutputMode::Tile;
    auto b = bench(cfg, 2);
    output_mode_run(*b);
    CHECK(b->records() ==
          "frame 0\n"
          "hit 5 4 1 2 40\n"
          "hit 6 5 2 5 8\n"
          "hit 8 4 1 2 7\n");
    CHECK(b->tester.stats().hits == 3);
    CHECK(b->tester.stats().filtered_hits == 2);
    check_output_mode_timing(*b);
}

// ---------------------------------------------------------------------------
// Overflow records, empty lists, the bank's release

TEST_CASE("hw tester: an overflow record follows its tile's hits", "[tester]") {
    auto b = bench(tester_config(), 3);
    // Tile (1, 2): list 2 (6,4) hits (1,3); lists 2 and 7 overflowed, 3 fragments dropped.
    zeb_bank& t0 = b->take(0, 1, 2);
    b->put(t0, 2, {{10, 1, 'F'}, {20, 3, 'F'}, {30, 1, 'B'}});
    b->put(t0, 7, {{10, 4, 'F'}});
    t0.note_overflow(2);
    t0.note_overflow(2);
    t0.note_overflow(7);
    // Tile (2, 2): list 4 (8,5) hits (2,4); no overflow.
    zeb_bank& t1 = b->take(1, 2, 2);
    b->put(t1, 4, {{1, 2, 'F'}, {2, 4, 'F'}, {3, 2, 'B'}});
    // Tile (3, 2): no hit, list 0 overflowed once.
    zeb_bank& t2 = b->take(2, 3, 2);
    b->put(t2, 0, {{9, 5, 'F'}});
    t2.note_overflow(0);
    b->run({{&t0, 0}, {&t1, 0}, {&t2, 0}});
    CHECK(b->records() ==
          "frame 0\n"
          "hit 6 4 1 3 30\n"
          "overflow 1 2 2 3\n"
          "hit 8 5 2 4 3\n"
          "overflow 3 2 1 1\n");
    const auto& s = b->tester.stats();
    CHECK(s.overflow_records == 2);
    CHECK(s.hits == 2);
    // Tile 0: 1 + 3 + 1 + overflow record 1 = 6; tile 1: 1 + 3 = 4; tile 2: 1 + 1 + 1 = 3.
    CHECK(s.busy_cycles == 13);
    // The bank is released once its last list is read, before the overflow record's cycle.
    CHECK(b->banks[0]->stats().testing_cycles == 5);
    CHECK(b->banks[1]->stats().testing_cycles == 4);
    CHECK(b->banks[2]->stats().testing_cycles == 2);
    CHECK(b->host.stats().overflow_records == 2);
    CHECK(b->host.stats().hit_records == 2);
}

TEST_CASE("hw tester: empty lists and stale rows are skipped and the stack restarts per list", "[tester]") {
    auto b = bench(tester_config(), 2);
    zeb_bank& t0 = b->take(0, 0, 0);
    // List 0: one element; the stale words behind the count are never read.
    b->put(t0, 0, {{10, 1, 'F'}, {99, 9, 'F'}, {100, 9, 'B'}});
    t0.count(0) = 1;
    // List 3: stale words that would hit, count 0, not occupied.
    const ElementLayout lay = b->cfg.zeb.layout();
    t0.list(3)[0] = lay.pack(Element{1, 5, Facing::Front});
    t0.list(3)[1] = lay.pack(Element{2, 6, Facing::Front});
    t0.list(3)[2] = lay.pack(Element{3, 5, Facing::Back});
    // List 7: 1B finds no 1 on a fresh stack (list 0's entry is gone): an orphan, no hit.
    b->put(t0, 7, {{20, 2, 'F'}, {30, 1, 'B'}});
    // Tile 1: nothing at all; the tester passes over it without reading a row.
    zeb_bank& t1 = b->take(1, 1, 0);
    b->run({{&t0, 5}, {&t1, 5}});
    CHECK(b->records() == "frame 0\n");
    const auto& s = b->tester.stats();
    CHECK(s.tiles == 2);
    CHECK(s.lists == 2);
    CHECK(s.elements == 3);
    CHECK(s.orphan_back_faces == 1);
    CHECK(s.raw_hits == 0);
    CHECK(s.busy_cycles == 1 + 1 + 2);
    CHECK(t0.stats().row_reads == 2);
    CHECK(t1.stats().row_reads == 0);
    CHECK(t1.stats().testing_cycles == 0);
    CHECK(t0.state() == zeb_bank::State::Free);
    CHECK(t1.state() == zeb_bank::State::Free);
}

TEST_CASE("hw tester: the bank is released when its last list has been read", "[tester]") {
    auto b = bench(tester_config());
    zeb_bank& bank = b->take(0, 0, 0);
    b->put(bank, 0, {{10, 1, 'F'}, {20, 2, 'F'}, {30, 1, 'B'}});
    b->put(bank, 4, {{10, 1, 'F'}});
    CHECK(bank.state() == zeb_bank::State::Filling);
    b->run({{&bank, 20}});
    // Tested 20..25: 1 row read + 3 + 1 elements.
    CHECK(bank.state() == zeb_bank::State::Free);
    REQUIRE(b->freed0.size() == 1);
    CHECK(b->freed0[0] == 25);
    CHECK(bank.stats().tiles == 1);
    CHECK(bank.stats().filling_cycles == 20);
    CHECK(bank.stats().testing_cycles == 5);
    CHECK(bank.stats().row_reads == 2);
    CHECK(bank.stats().row_writes == 0);
    CHECK(b->tester.frames_flushed() == 1);
    // The hit's burst leaves at the frame end, 25: 4 channel cycles + 50 latency.
    CHECK(b->tester.last_flushed() == 79);
}

TEST_CASE("hw tester: two tiles of a frame are tested back to back from cycle 0", "[tester]") {
    auto b = bench(tester_config(), 2);
    zeb_bank& t0 = b->take(0, 0, 0);
    b->put(t0, 0, {{10, 1, 'F'}});
    zeb_bank& t1 = b->take(1, 1, 0);
    b->put(t1, 0, {{10, 1, 'F'}});
    // Tile 0 is tested 0..2, tile 1 2..4: the frame's first tile started at cycle 0.
    b->run({{&t0, 0}, {&t1, 0}});
    CHECK(b->tester.frames_flushed() == 1);
    CHECK(b->tester.last_flushed() == 4);
    CHECK(b->banks[1]->stats().filling_cycles == 2);
}
