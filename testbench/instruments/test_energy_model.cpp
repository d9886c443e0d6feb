// The energy model (docs/energy.md): per-event energies and a tiny run's
// energy worked out by hand from its counters, with the default [energy] keys.
#include <catch2/catch.hpp>

#include "testbench/instruments/instruments_util.h"

using namespace rbcd;
using rbcd::tb::frag;

TEST_CASE("instruments: per-event energies of the default configuration", "[energy]") {
    const EnergyCosts k = energy_costs(SimConfig{});
    // Element 24 + 7 + 1 = 32 bits; row 8 x 32 = 256; bank 256 lists x 256 = 65536 bits: scale 1.
    CHECK(k.row_bits == 256);
    CHECK(k.bank_bits == 65536);
    CHECK(k.sram_scale == Approx(1.0));
    CHECK(k.row_read_pj == Approx(0.020 * 256));
    CHECK(k.row_write_pj == Approx(0.025 * 256));
    CHECK(k.queue_entry_bits == 8 + 32);
    CHECK(k.queue_write_pj == Approx(0.002 * 40));
    CHECK(k.comparator_pj == Approx(0.0015 * 25));   // 24-bit depth + the facing bit (front-first)
    CHECK(k.mux_element_pj == Approx(0.002 * 32));
    CHECK(k.stack_push_pj == Approx(0.002 * 8));
    CHECK(k.id_compare_pj == Approx(0.001 * 7));
    CHECK(k.buffer_record_pj == Approx(0.002 * 128));
    CHECK(k.bank_leakage_mw == Approx(0.040 * 8));
    CHECK(k.queue_leakage_mw + k.sorter_leakage_mw + k.tester_leakage_mw + k.buffer_leakage_mw == Approx(0.10));
    // Logic leakage split by storage bits: queue 32 x 40, sorter 3 x 256, tester 8 x 8 + 256, buffer 16 x 128.
    CHECK(k.queue_leakage_mw == Approx(0.10 * 1280 / 4416));
    CHECK(k.buffer_leakage_mw == Approx(0.10 * 2048 / 4416));
    CHECK(k.period_ns == Approx(2.5));
}

TEST_CASE("instruments: a longer list costs more per SRAM access", "[energy]") {
    SimConfig cfg;
    const double m8 = energy_costs(cfg).row_read_pj;
    cfg.zeb.list_length = 16;
    const EnergyCosts k16 = energy_costs(cfg);
    // Row 512 bits, bank 131072 bits: sqrt(2) per bit.
    CHECK(k16.row_read_pj == Approx(0.020 * 512 * std::sqrt(2.0)));
    CHECK(k16.row_read_pj > 2 * m8);
    CHECK(k16.row_write_pj == Approx(0.025 * 512 * std::sqrt(2.0)));
    CHECK(k16.bank_leakage_mw == Approx(0.040 * 16));
    cfg.zeb.list_length = 4;
    CHECK(energy_costs(cfg).row_read_pj == Approx(0.020 * 128 * std::sqrt(0.5)));
    // A narrower element: z_bits 16 gives 24-bit elements, a 192-bit row, a 49152-bit bank.
    SimConfig z16;
    z16.zeb.z_bits = 16;
    CHECK(energy_costs(z16).row_read_pj == Approx(0.020 * 192 * std::sqrt(0.75)));
    // The per-bit figure itself scales linearly.
    SimConfig hot;
    hot.energy.sram_read_pj_per_bit = 0.040;
    CHECK(energy_costs(hot).row_read_pj == Approx(2 * m8));
}

TEST_CASE("instruments: energy of a tiny run by hand", "[energy]") {
    // One pixel: id 2 back at 300, id 1 front at 100, id 2 front at 200, id 1 back at 400.
    // Sorted insertion: 300 -> slot 0; 100 -> slot 0, shifts 1; 200 -> slot 1, shifts 1; 400 -> slot 3.
    // Tester: push 1, push 2, 2B matches (no hit), 1B matches with 2 above it: one hit.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(tb::tile(0, 0, 0,
                          {frag(0, 0, 300, 2, 'B'), frag(0, 0, 100, 1, 'F'), frag(0, 0, 200, 2, 'F'),
                           frag(0, 0, 400, 1, 'B')}));
    tb::ProbedRun run(tb::fixed_latency_config(), src);
    const auto& s = *run.sys;
    REQUIRE(s.sorter.stats().insertions == 4);
    REQUIRE(s.sorter.stats().mux_shifts == 2);
    REQUIRE(s.tester.stats().pushes == 2);
    REQUIRE(s.tester.stats().matches == 2);
    REQUIRE(s.tester.stats().hits == 1);
    // Fill: issues 1..4, filled 7; test 7 + 1 + 4 = 12 with the hit at 11; the flush writes
    // 16 bytes at 12: 4 channel cycles + 50 latency = 66; readback 500: 566 cycles.
    REQUIRE(s.total_cycles() == 566);
    // The bank's reads are the sorter's (one per insertion) plus the tester's (one per list).
    CHECK(s.banks[0]->stats().row_reads == 4 + 1);
    CHECK(s.banks[0]->stats().row_writes == 4);

    const auto j = run.stats();
    const auto& b = j["energy"]["blocks"];
    CHECK(b["input_queue"]["dynamic_pj"].get<double>() == Approx(4 * 0.08));
    CHECK(b["zeb_bank0"]["dynamic_pj"].get<double>() == Approx(5 * 5.12 + 4 * 6.4));
    CHECK(b["zeb_bank1"]["dynamic_pj"].get<double>() == 0.0);
    // 32 comparators of 25 bits; 2 shifted + 4 placed elements of 32 bits.
    CHECK(b["insertion_sorter"]["dynamic_pj"].get<double>() == Approx(32 * 0.0375 + 6 * 0.064));
    // 2 pushes of 8 bits, 2 matched bits, 2 back faces x 8 comparators of 7 bits.
    CHECK(b["zoverlap_tester"]["dynamic_pj"].get<double>() == Approx(2 * 0.016 + 2 * 0.002 + 16 * 0.007));
    CHECK(b["output_buffer"]["dynamic_pj"].get<double>() == Approx(0.256));
    CHECK(b["memory"]["dynamic_pj"].get<double>() == Approx(16 * 40.0));
    const double dynamic = 0.32 + 51.2 + 1.584 + 0.148 + 0.256 + 640.0;
    CHECK(j["energy"]["dynamic_pj"].get<double>() == Approx(dynamic));
    // Leakage: 566 cycles x 2.5 ns = 1415 ns; two banks of 0.32 mW and 0.10 mW of logic.
    CHECK(b["zeb_bank1"]["leakage_pj"].get<double>() == Approx(0.32 * 1415));
    CHECK(j["energy"]["leakage_pj"].get<double>() == Approx(0.74 * 1415));
    CHECK(j["energy"]["total_pj"].get<double>() == Approx(dynamic + 0.74 * 1415));
    CHECK(j["energy"]["total_nj"].get<double>() == Approx((dynamic + 0.74 * 1415) / 1000));
    CHECK(j["energy"]["average_power_mw"].get<double>() == Approx((dynamic + 0.74 * 1415) / 1415));
    // One frame: it carries everything.
    CHECK(j["frames"][0]["energy_nj"].get<double>() == Approx((dynamic + 0.74 * 1415) / 1000));
}

TEST_CASE("instruments: per-frame energy from counter snapshots at the frame boundaries", "[energy]") {
    // Two frames of one 16-fragment tile; one bank, so frame 1's tile is filled while the
    // tester still works on frame 0's: the tester's work must stay with frame 0.
    MemorySource src(StreamHeader{});
    for (unsigned f = 0; f < 2; ++f) {
        src.add_frame(f);
        std::vector<Fragment> fs;
        for (unsigned i = 0; i < 16; ++i) fs.push_back(frag(i, f, 500, 1, 'F'));
        src.add_tile(tb::tile(f, 0, 0, fs));
    }
    SimConfig cfg = tb::fixed_latency_config();
    cfg.zeb.banks = 1;
    tb::ProbedRun run(cfg, src);
    REQUIRE(run.probe->energy.unit_boundaries_seen());
    const auto acts = run.probe->energy.frames();
    REQUIRE(acts.size() == 2);
    for (const auto& a : acts) {
        CHECK(a.queue_writes == 16);
        CHECK(a.sorter_row_reads == 16);
        CHECK(a.row_writes == 16);
        CHECK(a.tester_row_reads == 16);
        CHECK(a.stack_pushes == 16);
        CHECK(a.memory_bytes == 0);
    }
    const auto j = run.stats();
    const auto& fr = j["frames"];
    // Frame 0's share of the timeline ends when the unit has read it back, frame 1's at the end.
    const double ns0 = fr[0]["done_cycle"].get<double>() * 2.5;
    const double ns1 = j["totals"]["cycles"].get<double>() * 2.5 - ns0;
    const double leak_mw = 0.32 + 0.10;
    const double dyn = 16 * 0.08 + 32 * 5.12 + 16 * 6.4 + 16 * 8 * 0.0375 + 16 * 0.064 + 16 * 0.016;
    CHECK(fr[0]["energy_pj"]["total"].get<double>() == Approx(dyn + leak_mw * ns0));
    CHECK(fr[1]["energy_pj"]["total"].get<double>() == Approx(dyn + leak_mw * ns1));
    CHECK(fr[0]["energy_pj"]["zeb"].get<double>() == Approx(32 * 5.12 + 16 * 6.4 + 0.32 * ns0));
    CHECK(fr[0]["energy_nj"].get<double>() + fr[1]["energy_nj"].get<double>() ==
          Approx(j["energy"]["total_nj"].get<double>()));
    CHECK(j["energy"]["per_frame"]["basis"].get<std::string>().find("unit's") != std::string::npos);
}
