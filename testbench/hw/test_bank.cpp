// One ZEB bank alone: a driver thread moves it through its states at chosen
// cycles, a watcher thread records its freed event, and plain calls check its
// geometry (bits = lists x M x element width, rbcd-contract.md "Terms") and
// the per-tile clear.
//
// One TEST_CASE per process (catch_discover_tests): no SECTIONs.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "rbcd/testbench/hw/tb_util.h"

using namespace rbcd;

namespace {

const char* name_of(zeb_bank::State s) {
    switch (s) {
    case zeb_bank::State::Free: return "Free";
    case zeb_bank::State::Filling: return "Filling";
    case zeb_bank::State::Testing: return "Testing";
    }
    return "?";
}

// Driver: two tiles through one bank at fixed cycles. Watcher: the freed event.
struct BankBench : sc_core::sc_module {
    SC_HAS_PROCESS(BankBench);

    Clocking clk;
    zeb_bank bank;
    std::vector<std::string> trace;          // "cycle:state" after each driver step
    std::vector<std::string> freed_seen;     // "cycle:state" each time freed fired

    BankBench(sc_core::sc_module_name name, const SimConfig& cfg)
        : sc_module(name), clk(cfg.clock.period_ps()), bank("zeb", cfg.zeb, cfg.tile, 3) {
        SC_THREAD(drive);
        SC_THREAD(watch);
    }

    void note(std::vector<std::string>& v) { v.push_back(std::to_string(clk.now()) + ":" + name_of(bank.state())); }

    void drive() {
        note(trace);
        clk.wait_until(2);
        bank.begin_fill(7, 4, 5, 2);
        note(trace);
        clk.wait_until(9);
        bank.begin_test(9);
        note(trace);
        clk.wait_until(21);
        bank.release(21);
        note(trace);
        clk.wait_until(25);
        bank.begin_fill(8, 6, 1, 25);
        note(trace);
        clk.wait_until(30);
        bank.begin_test(30);
        clk.wait_until(40);
        bank.release(40);
        note(trace);
    }
    void watch() {
        for (;;) {
            wait(bank.freed);
            note(freed_seen);
        }
    }
};

} // namespace

TEST_CASE("hw bank: states go Free Filling Testing Free and freed fires on release only", "[bank]") {
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
    SimConfig cfg;
    auto b = std::make_unique<BankBench>("bench", cfg);
    sc_core::sc_start();
    CHECK(b->trace == std::vector<std::string>{"0:Free", "2:Filling", "9:Testing", "21:Free", "25:Filling", "40:Free"});
    CHECK(b->freed_seen == std::vector<std::string>{"21:Free", "40:Free"});
    const auto& s = b->bank.stats();
    CHECK(s.tiles == 2);
    CHECK(s.flash_clears == 2);
    CHECK(s.filling_cycles == (9 - 2) + (30 - 25));
    CHECK(s.testing_cycles == (21 - 9) + (40 - 30));
    CHECK(s.row_reads == 0);
    CHECK(s.row_writes == 0);
    CHECK(b->bank.index() == 3);
    CHECK(b->bank.frame() == 8);
    CHECK(b->bank.tile_col() == 6);
    CHECK(b->bank.tile_row() == 1);
}

TEST_CASE("hw bank: the default bank holds 256 lists of 8 elements of 32 bits - 8 KiB", "[bank]") {
    SimConfig cfg;
    zeb_bank bank("zeb", cfg.zeb, cfg.tile, 0);
    CHECK(bank.lists() == 256);
    CHECK(bank.list_length() == 8);
    CHECK(cfg.zeb.layout().width() == 32);
    CHECK(bank.bits() == 65536);
    CHECK(bank.bits() / 8 == 8 * 1024);   // the paper's Table 1
    CHECK(bank.occupancy().size() == 4);
    CHECK(bank.state() == zeb_bank::State::Free);
}

TEST_CASE("hw bank: bits are lists x M x element width for other configurations", "[bank]") {
    SimConfig a;   // 8x8 tile, M = 4, 16 + 7 + 1 = 24-bit elements
    a.tile.width = a.tile.height = 8;
    a.zeb.list_length = 4;
    a.zeb.z_bits = 16;
    zeb_bank ba("zeb_a", a.zeb, a.tile, 0);
    CHECK(ba.lists() == 64);
    CHECK(ba.bits() == 64ull * 4 * 24);
    CHECK(ba.occupancy().size() == 1);

    SimConfig c;   // 32x32 tile, M = 16, 32 + 16 + 1 = 49-bit elements
    c.tile.width = c.tile.height = 32;
    c.zeb.list_length = 16;
    c.zeb.z_bits = 32;
    c.zeb.id_bits = 16;
    zeb_bank bc("zeb_c", c.zeb, c.tile, 1);
    CHECK(bc.bits() == 1024ull * 16 * 49);
    CHECK(bc.occupancy().size() == 16);

    SimConfig d;   // 1x1 tile, M = 1, 1 + 1 + 1 = 3-bit elements
    d.tile.width = d.tile.height = 1;
    d.zeb.list_length = 1;
    d.zeb.z_bits = 1;
    d.zeb.id_bits = 1;
    zeb_bank bd("zeb_d", d.zeb, d.tile, 2);
    CHECK(bd.lists() == 1);
    CHECK(bd.bits() == 3);
    CHECK(bd.occupancy().size() == 1);

    SimConfig e;   // 9x8 tile (72 lists: two bitmap words), M = 64, default 32-bit elements
    e.tile.width = 9;
    e.tile.height = 8;
    e.zeb.list_length = 64;
    zeb_bank be("zeb_e", e.zeb, e.tile, 3);
    CHECK(be.lists() == 72);
    CHECK(be.list_length() == 64);
    CHECK(be.bits() == 72ull * 64 * 32);
    CHECK(be.occupancy().size() == 2);
    // Rows are M words apart and the last row ends at the last word.
    CHECK(be.list(1) - be.list(0) == 64);
    CHECK(be.list(71) - be.list(0) == 71 * 64);
}

TEST_CASE("hw bank: overflow bookkeeping counts each list once and every dropped fragment", "[bank]") {
    SimConfig cfg;
    zeb_bank bank("zeb", cfg.zeb, cfg.tile, 0);
    bank.begin_fill(0, 0, 0, 0);
    bank.note_overflow(0);
    bank.note_overflow(0);
    bank.note_overflow(64);
    bank.note_overflow(255);
    bank.note_overflow(0);
    CHECK(bank.lists_overflowed() == 3);
    CHECK(bank.fragments_dropped() == 5);
}

TEST_CASE("hw bank: begin_fill clears counts occupancy and overflow of the previous tile", "[bank]") {
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
    SimConfig cfg;
    zeb_bank bank("zeb", cfg.zeb, cfg.tile, 0);
    bank.begin_fill(0, 1, 2, 0);
    CHECK(bank.stats().flash_clears == 1);
    const ElementLayout lay = cfg.zeb.layout();
    bank.list(70)[0] = lay.pack(Element{123, 4, Facing::Back});
    bank.count(70) = 1;
    bank.mark_occupied(70);
    bank.count(255) = 8;
    bank.mark_occupied(255);
    bank.note_overflow(255);
    bank.note_overflow(255);
    CHECK(bank.occupancy()[1] == (1ull << 6));
    CHECK(bank.occupancy()[3] == (1ull << 63));
    CHECK(bank.lists_overflowed() == 1);
    CHECK(bank.fragments_dropped() == 2);
    bank.begin_test(10);
    bank.release(20);
    // Free keeps the old tile's bookkeeping until the next fill clears it.
    CHECK(bank.count(70) == 1);
    bank.begin_fill(1, 3, 4, 30);
    CHECK(bank.stats().flash_clears == 2);
    CHECK(bank.stats().tiles == 2);
    CHECK(bank.count(70) == 0);
    CHECK(bank.count(255) == 0);
    for (std::uint64_t w : bank.occupancy()) CHECK(w == 0);
    CHECK(bank.lists_overflowed() == 0);
    CHECK(bank.fragments_dropped() == 0);
    // The per-list overflow flags were cleared too: list 255 counts again in the new tile.
    bank.note_overflow(255);
    CHECK(bank.lists_overflowed() == 1);
    CHECK(bank.fragments_dropped() == 1);
    CHECK(bank.frame() == 1);
    CHECK(bank.tile_col() == 3);
    CHECK(bank.tile_row() == 4);
    // The element rows themselves are not cleared (a count of 0 makes them dead).
    CHECK(lay.unpack(bank.list(70)[0]).dq == 123);
    CHECK(bank.stats().filling_cycles == 10);
    CHECK(bank.stats().testing_cycles == 10);
}
