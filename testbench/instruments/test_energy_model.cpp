// The energy model (docs/energy.md): per-event energies, and a tiny run's
// unit and GPU energy worked out by hand from its counters and frame time.
#include <catch2/catch.hpp>

#include <cmath>

#include "rbcd/testbench/instruments/instruments_util.h"

using namespace rbcd;
using rbcd::tb::frag;

TEST_CASE("energy: per-event energies of the default configuration", "[energy]") {
    const EnergyCosts k = energy_costs(SimConfig{});
    // Element 24 + 7 + 1 = 32 bits; row 8 x 32 = 256 bits = 32 bytes; bank 256 lists x 256
    // bits = 8 KiB: exactly the CACTI reference macro (LOP, 1R1W).
    CHECK(k.row_bits == 256);
    CHECK(k.bank_bits == 65536);
    CHECK(k.sram_scale == Approx(1.0));
    CHECK(k.row_read_pj == Approx(3.46));
    CHECK(k.row_write_pj == Approx(6.70));
    CHECK(k.bank_leakage_mw == Approx(1.20));
    CHECK(k.queue_entry_bits == 8 + 32);
    CHECK(k.queue_write_pj == Approx(0.002 * 40));
    CHECK(k.comparator_pj == Approx(0.0015 * 25));   // 24-bit depth + the facing bit (front-first)
    CHECK(k.mux_element_pj == Approx(0.002 * 32));
    CHECK(k.stack_push_pj == Approx(0.002 * 8));
    CHECK(k.id_compare_pj == Approx(0.001 * 7));
    CHECK(k.buffer_record_pj == Approx(0.002 * 128));
    CHECK(k.queue_leakage_mw + k.sorter_leakage_mw + k.tester_leakage_mw + k.buffer_leakage_mw == Approx(0.10));
    CHECK(k.period_ns == Approx(2.5));
    // The GPU: a primitive costs its setup and its 64 bytes of tile cache; a tile flushes
    // 1 KiB of colour buffer to memory.
    CHECK(k.gpu_fragment_pj == Approx(300.0));
    CHECK(k.gpu_primitive_pj == Approx(60.0 + 64 * 0.5));
    CHECK(k.gpu_tile_flush_pj == Approx(1024 * 40.0));
}

TEST_CASE("energy: the ZEB device types and sizes", "[energy]") {
    SimConfig cfg;
    cfg.energy.zeb_device = ZebDevice::Lstp;
    CHECK(energy_costs(cfg).row_read_pj == Approx(8.43));
    CHECK(energy_costs(cfg).row_write_pj == Approx(18.83));
    CHECK(energy_costs(cfg).bank_leakage_mw == Approx(0.0024));
    cfg.energy.zeb_device = ZebDevice::Hp;
    CHECK(energy_costs(cfg).row_read_pj == Approx(6.46));
    CHECK(energy_costs(cfg).row_write_pj == Approx(14.70));
    CHECK(energy_costs(cfg).bank_leakage_mw == Approx(3.38));
    // M = 16: a 512-bit row in a 16 KiB bank: twice the row, sqrt(2) for the array.
    SimConfig m16;
    m16.zeb.list_length = 16;
    const EnergyCosts k = energy_costs(m16);
    CHECK(k.row_read_pj == Approx(3.46 * 2 * std::sqrt(2.0)));
    CHECK(k.row_write_pj == Approx(6.70 * 2 * std::sqrt(2.0)));
    CHECK(k.bank_leakage_mw == Approx(1.20 * 2));
    // Leakage scales with the bits, accesses more slowly than linearly.
    m16.zeb.list_length = 4;
    CHECK(energy_costs(m16).row_read_pj == Approx(3.46 * 0.5 * std::sqrt(0.5)));
}

TEST_CASE("energy: a tiny run by hand for the unit and the GPU", "[energy]") {
    // One pixel: id 2 back at 300, id 1 front at 100, id 2 front at 200, id 1 back at 400.
    // Sorted insertion: 300 -> slot 0; 100 -> slot 0, shifts 1; 200 -> slot 1, shifts 1; 400 -> slot 3.
    // Tester: push 1, push 2, 2B matches (no hit), 1B matches with 2 above it: one hit.
    MemorySource src(StreamHeader{});
    src.add_frame(0);
    src.add_tile(tb::tile(0, 0, 0,
                          {frag(0, 0, 300, 2, 'B'), frag(0, 0, 100, 1, 'F'), frag(0, 0, 200, 2, 'F'),
                           frag(0, 0, 400, 1, 'B')}));
    tb::ReportedRun run(tb::fixed_latency_config(), src);
    const auto& s = *run.sys;
    REQUIRE(s.sorter.stats().insertions == 4);
    REQUIRE(s.sorter.stats().mux_shifts == 2);
    REQUIRE(s.tester.stats().hits == 1);
    // Fill: issues 1..4, filled 7; test 7 + 1 + 4 = 12; the flush writes 16 bytes at 12:
    // 4 channel cycles + 50 latency = 66. The fragment processors are done at 9.
    REQUIRE(s.total_cycles() == 66);
    REQUIRE(run.totals().t.baseline == 9);

    const auto j = run.stats();
    const auto& b = j["energy"]["blocks"];
    CHECK(b["input_queue"]["dynamic_pj"].get<double>() == Approx(4 * 0.08));
    CHECK(b["zeb_bank0"]["dynamic_pj"].get<double>() == Approx(5 * 3.46 + 4 * 6.70));
    CHECK(b["zeb_bank1"]["dynamic_pj"].get<double>() == 0.0);
    CHECK(b["insertion_sorter"]["dynamic_pj"].get<double>() == Approx(32 * 0.0375 + 6 * 0.064));
    CHECK(b["zoverlap_tester"]["dynamic_pj"].get<double>() == Approx(2 * 0.016 + 2 * 0.002 + 16 * 0.007));
    CHECK(b["output_buffer"]["dynamic_pj"].get<double>() == Approx(0.256));
    CHECK(b["memory"]["dynamic_pj"].get<double>() == Approx(16 * 40.0));
    const double dynamic = 0.32 + 5 * 3.46 + 4 * 6.70 + 1.584 + 0.148 + 0.256 + 640.0;
    CHECK(j["energy"]["dynamic_pj"].get<double>() == Approx(dynamic));
    // Leakage over the frame's time with the unit: 66 cycles = 165 ns; 2 x 1.20 + 0.10 mW.
    const double leak = 2.5 * 165;
    CHECK(j["energy"]["leakage_pj"].get<double>() == Approx(leak));
    CHECK(j["energy"]["total_pj"].get<double>() == Approx(dynamic + leak));
    // The GPU: 4 fragments shaded and rasterized, one tile flushed; static power over 9
    // cycles without the unit, 66 with it.
    const double work = 4 * 300.0 + 4 * 8.0 + 1024 * 40.0;
    const double base = work + 60.0 * 9 * 2.5;
    const double with = work + 60.0 * 66 * 2.5 + dynamic + leak;
    CHECK(j["energy"]["gpu"]["baseline_pj"].get<double>() == Approx(base));
    CHECK(j["energy"]["gpu"]["with_unit_pj"].get<double>() == Approx(with));
    CHECK(j["energy"]["gpu"]["overhead_pct"].get<double>() == Approx(100.0 * (with - base) / base));
    CHECK(run.frames[0]["energy_pj"]["unit"].get<double>() == Approx(dynamic + leak));
}

TEST_CASE("energy: per frame from the counters at each frame barrier", "[energy]") {
    // Two frames of one 16-fragment tile: each frame's unit energy is its own work plus
    // leakage over its own time, and the frames add up to the run.
    MemorySource src(StreamHeader{});
    for (unsigned f = 0; f < 2; ++f) {
        src.add_frame(f);
        std::vector<Fragment> fs;
        for (unsigned i = 0; i < 16; ++i) fs.push_back(frag(i, f, 500, 1, 'F'));
        src.add_tile(tb::tile(f, 0, 0, fs));
    }
    SimConfig cfg = tb::fixed_latency_config();
    cfg.zeb.banks = 1;
    tb::ReportedRun run(cfg, src);
    REQUIRE(run.frames.size() == 2);
    const double leak_mw = 1.20 + 0.10;
    const double dyn = 16 * 0.08 + 32 * 3.46 + 16 * 6.70 + 16 * 8 * 0.0375 + 16 * 0.064 + 16 * 0.016;
    double sum = 0;
    for (const auto& f : run.frames) {
        const double ns = f["cycles_with_unit"].get<double>() * 2.5;
        CHECK(f["energy_pj"]["unit"].get<double>() == Approx(dyn + leak_mw * ns));
        sum += f["energy_pj"]["unit"].get<double>();
    }
    CHECK(sum == Approx(run.stats()["energy"]["total_pj"].get<double>()));
}
