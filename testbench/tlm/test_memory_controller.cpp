// memory_controller between a driver (an initiator with one socket on each
// port) and the checks below. Every TEST_CASE elaborates its own modules and
// runs sc_start once: ctest runs each case in its own process. No SECTIONs,
// since a section re-runs the case body and would elaborate twice.
//
// Expected numbers are worked out by hand in the comments; the latency
// sequences are from an independent splitmix64 (a few lines of Python):
//   seed 1, [50,100]: 94 84 50 79 53 67 92 56 ...  1000 draws sum to 76176
//   seed 2, [50,100]: 66 70 59 92 87 71 91 61 ...  1000 draws sum to 74968
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>

#include "rbcd/common/errors.h"
#include "rbcd/tlm/memory_controller.h"

using namespace sc_core;
using rbcd::memory_controller;

namespace {

constexpr std::uint64_t kPeriodPs = 2500;   // 400 MHz
constexpr std::uint64_t kBase = 0x80000000ull;
constexpr std::uint64_t kSize = 1ull << 20;

sc_time period() { return sc_time(double(kPeriodPs), SC_PS); }
sc_time cycles(std::uint64_t n) { return sc_time(double(n * kPeriodPs), SC_PS); }

rbcd::MemoryConfig config(unsigned lat_min, unsigned lat_max, std::uint64_t seed = 1) {
    rbcd::MemoryConfig c;
    c.base = kBase;
    c.size_bytes = kSize;
    c.latency_min = lat_min;
    c.latency_max = lat_max;
    c.bytes_per_cycle = 4;
    c.seed = seed;
    return c;
}

struct outcome {
    tlm::tlm_response_status status = tlm::TLM_INCOMPLETE_RESPONSE;
    sc_time delay;                      // as returned by b_transport
    bool dmi_allowed = false;
    sc_time now;                        // sc_time_stamp() after the call
};

// The initiator: runs a test-supplied script in an SC_THREAD so that
// sc_time_stamp() and wait() behave as they do for the real unit and host.
struct driver : sc_module {
    tlm_utils::simple_initiator_socket<driver, rbcd::kBusWidth> unit;
    tlm_utils::simple_initiator_socket<driver, rbcd::kBusWidth> host;
    std::function<void(driver&)> script;

    SC_HAS_PROCESS(driver);
    driver(sc_module_name n, memory_controller& mem, std::function<void(driver&)> s)
        : sc_module(n), unit("unit"), host("host"), script(std::move(s)) {
        unit.bind(mem.unit_port);
        host.bind(mem.host_port);
        SC_THREAD(run);
    }
    void run() { script(*this); }

    // The generic payload is neither copyable nor assignable: fill one in place.
    static void prepare(tlm::tlm_generic_payload& gp, tlm::tlm_command cmd, std::uint64_t addr,
                        unsigned char* data, unsigned len) {
        gp.set_command(cmd);
        gp.set_address(addr);
        gp.set_data_ptr(data);
        gp.set_data_length(len);
        gp.set_streaming_width(len);
        gp.set_byte_enable_ptr(nullptr);
        gp.set_dmi_allowed(false);
        gp.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    }
    static outcome send(tlm_utils::simple_initiator_socket<driver, rbcd::kBusWidth>& s,
                        tlm::tlm_generic_payload& gp, sc_time delay) {
        s->b_transport(gp, delay);
        return {gp.get_response_status(), delay, gp.is_dmi_allowed(), sc_time_stamp()};
    }
    static outcome access(tlm_utils::simple_initiator_socket<driver, rbcd::kBusWidth>& s, tlm::tlm_command cmd,
                          std::uint64_t addr, unsigned char* data, unsigned len, sc_time delay) {
        tlm::tlm_generic_payload gp;
        prepare(gp, cmd, addr, data, len);
        return send(s, gp, delay);
    }
};

std::vector<unsigned char> pattern(unsigned len, unsigned seed) {
    std::vector<unsigned char> v(len);
    for (unsigned i = 0; i < len; ++i) v[i] = static_cast<unsigned char>(i * 7 + seed);
    return v;
}

} // namespace

TEST_CASE("tlm memory_controller: one 64-byte write takes 16 transfer + 50 latency cycles", "[tlm][memory]") {
    memory_controller mem("mem", config(50, 50), period());
    auto data = pattern(64, 3);
    outcome w;
    driver drv("drv", mem, [&](driver& d) {
        w = driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 64, SC_ZERO_TIME);
    });
    sc_start();

    CHECK(w.status == tlm::TLM_OK_RESPONSE);
    CHECK(w.dmi_allowed);
    // 64 B / 4 B per cycle = 16 cycles, + 50 = 66 cycles = 165 ns.
    CHECK(w.delay == cycles(66));
    CHECK(w.delay == sc_time(165, SC_NS));
    CHECK(w.now == SC_ZERO_TIME);   // the target annotated, it did not wait
    CHECK(mem.last_completion_cycle() == 66);
    CHECK(mem.channel_free_cycle() == 16);
    CHECK(std::equal(data.begin(), data.end(), mem.data()));
    CHECK(mem.data()[64] == 0);     // nothing beyond the burst
}

TEST_CASE("tlm memory_controller: back-to-back requests queue on the one data channel", "[tlm][memory]") {
    memory_controller mem("mem", config(50, 50), period());
    auto data = pattern(64, 1);
    std::vector<unsigned char> rd(10);
    std::vector<outcome> out;
    driver drv("drv", mem, [&](driver& d) {
        for (int i = 0; i < 3; ++i)
            out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + 64u * i,
                                         data.data(), 64, SC_ZERO_TIME));
        // The host shares the channel: its read waits behind the bursts.
        out.push_back(driver::access(d.host, tlm::TLM_READ_COMMAND, kBase, rd.data(), 10, SC_ZERO_TIME));
    });
    sc_start();

    REQUIRE(out.size() == 4);
    // All arrive at cycle 0. Transfers [0,16) [16,32) [32,48), then 10 B =
    // 3 beats [48,51); each completes 50 cycles after its transfer ends.
    CHECK(out[0].delay == cycles(66));
    CHECK(out[1].delay == cycles(82));
    CHECK(out[2].delay == cycles(98));
    CHECK(out[3].delay == cycles(101));
    for (const auto& o : out) CHECK(o.status == tlm::TLM_OK_RESPONSE);
    CHECK(mem.last_completion_cycle() == 101);
    CHECK(mem.stats().busy_cycles == 51);
    CHECK(mem.stats().queue_cycles == 0 + 16 + 32 + 48);
    CHECK(std::equal(rd.begin(), rd.end(), data.begin()));
}

TEST_CASE("tlm memory_controller: annotated delay sets the arrival cycle", "[tlm][memory]") {
    memory_controller mem("mem", config(50, 50), period());
    auto data = pattern(64, 5);
    std::vector<outcome> out;
    driver drv("drv", mem, [&](driver& d) {
        wait(cycles(10));   // now = cycle 10
        // arrival 10+5 = 15, transfer [15,31), completion 81: 71 cycles from now.
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 64, cycles(5)));
        // arrival 50 after the channel freed at 31: no queueing, [50,52), completion 102.
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 8, cycles(40)));
        // Arrival 55 cycles + 1000 ps floors to cycle 55: [55,56), completion 106.
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 4,
                                     cycles(45) + sc_time(1000, SC_PS)));
        // Out of order: arrival 10 < 55 is taken as 55; channel free at 56:
        // [56,57), completion 107, 1 queue cycle (46 if the arrival were 10).
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 4, SC_ZERO_TIME));
    });
    sc_start();

    REQUIRE(out.size() == 4);
    for (const auto& o : out) {
        CHECK(o.status == tlm::TLM_OK_RESPONSE);
        CHECK(o.now == cycles(10));
    }
    CHECK(out[0].delay == cycles(71));
    CHECK(out[1].delay == cycles(92));
    CHECK(out[2].delay == cycles(96));
    CHECK(out[3].delay == cycles(97));
    CHECK(mem.last_completion_cycle() == 107);
    CHECK(mem.stats().queue_cycles == 1);
    CHECK(mem.stats().busy_cycles == 16 + 2 + 1 + 1);
}

TEST_CASE("tlm memory_controller: latency is uniform between min and max and set by the seed", "[tlm][memory]") {
    constexpr int kN = 1000;
    memory_controller mem_a("mem_a", config(50, 100, 1), period());
    memory_controller mem_b("mem_b", config(50, 100, 1), period());
    memory_controller mem_c("mem_c", config(50, 100, 2), period());
    std::vector<std::uint64_t> lat_a, lat_b, lat_c, comp_a;

    // kN 4-byte writes at cycle 0: transfer i is [i, i+1), so its latency is
    // completion - (i + 1).
    auto script = [](std::vector<std::uint64_t>& lat, std::vector<std::uint64_t>* comp) {
        return [&lat, comp](driver& d) {
            unsigned char word[4] = {1, 2, 3, 4};
            for (int i = 0; i < kN; ++i) {
                auto o = driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + 4u * i, word, 4, SC_ZERO_TIME);
                const std::uint64_t c = o.delay.value() / kPeriodPs;
                CHECK(o.delay == cycles(c));   // whole cycles only
                lat.push_back(c - (i + 1));
                if (comp) comp->push_back(c);
            }
        };
    };
    driver da("da", mem_a, script(lat_a, &comp_a));
    driver db("db", mem_b, script(lat_b, nullptr));
    driver dc("dc", mem_c, script(lat_c, nullptr));
    sc_start();

    REQUIRE(lat_a.size() == kN);
    REQUIRE(lat_c.size() == kN);
    CHECK(*std::min_element(lat_a.begin(), lat_a.end()) == 50);
    CHECK(*std::max_element(lat_a.begin(), lat_a.end()) == 100);
    CHECK(*std::min_element(lat_c.begin(), lat_c.end()) == 50);
    CHECK(*std::max_element(lat_c.begin(), lat_c.end()) == 100);
    CHECK(std::count(lat_a.begin(), lat_a.end(), 50u) == 15);
    CHECK(std::count(lat_a.begin(), lat_a.end(), 100u) == 12);

    CHECK(lat_a == lat_b);   // same seed, same stream
    CHECK(lat_a != lat_c);   // another seed, another stream
    CHECK(std::vector<std::uint64_t>(lat_a.begin(), lat_a.begin() + 8) ==
          std::vector<std::uint64_t>{94, 84, 50, 79, 53, 67, 92, 56});
    CHECK(std::vector<std::uint64_t>(lat_c.begin(), lat_c.begin() + 8) ==
          std::vector<std::uint64_t>{66, 70, 59, 92, 87, 71, 91, 61});

    CHECK(mem_a.stats().latency_cycles == 76176);
    CHECK(mem_c.stats().latency_cycles == 74968);
    CHECK(mem_a.stats().mean_latency_cycles() == Approx(76.176));
    // Latest completion is not the last one for seed 1: 1093 vs 1000 + 56.
    CHECK(mem_a.stats().max_completion_cycle == 1093);
    CHECK(mem_a.last_completion_cycle() == 1056);
    CHECK(comp_a.back() == 1056);
    CHECK(mem_a.stats().busy_cycles == kN);
}

TEST_CASE("tlm memory_controller: data reads back through b_transport and debug transport and DMI", "[tlm][memory]") {
    memory_controller mem("mem", config(50, 50), period());
    const auto burst = pattern(64, 3);
    const auto dbg = pattern(16, 100);
    std::vector<unsigned char> via_bt(64), via_dbg(64), via_dbg_unit(16), tail(16, 0xEE), via_bt2(4);
    outcome w, r, r2;
    unsigned dbg_write_n = 0, dbg_read_n = 0, dbg_unit_n = 0, dbg_tail_n = 0, dbg_out_n = 99;
    bool dmi_ok = false, dmi_below = true, dmi_above = true;
    tlm::tlm_dmi dmi, deny_below, deny_above;

    driver drv("drv", mem, [&](driver& d) {
        auto wb = burst;
        w = driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + 0x100, wb.data(), 64, SC_ZERO_TIME);
        r = driver::access(d.host, tlm::TLM_READ_COMMAND, kBase + 0x100, via_bt.data(), 64, SC_ZERO_TIME);

        auto dw = dbg;
        tlm::tlm_generic_payload gp;
        driver::prepare(gp, tlm::TLM_WRITE_COMMAND, kBase + 0x200, dw.data(), 16);
        dbg_write_n = d.unit->transport_dbg(gp);
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + 0x100, via_dbg.data(), 64);
        dbg_read_n = d.host->transport_dbg(gp);
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + 0x200, via_dbg_unit.data(), 16);
        dbg_unit_n = d.host->transport_dbg(gp);
        // Debug reads stop at the end of the mapping and say how far they got.
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + kSize - 8, tail.data(), 16);
        dbg_tail_n = d.host->transport_dbg(gp);
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + kSize, tail.data(), 16);
        dbg_out_n = d.host->transport_dbg(gp);

        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + 0x100, nullptr, 0);
        dmi_ok = d.host->get_direct_mem_ptr(gp, dmi);
        gp.set_address(kBase - 1);
        dmi_below = d.host->get_direct_mem_ptr(gp, deny_below);
        gp.set_address(kBase + kSize);
        dmi_above = d.host->get_direct_mem_ptr(gp, deny_above);

        // A DMI write is seen by a later b_transport read.
        if (dmi_ok) {
            unsigned char* p = dmi.get_dmi_ptr() + (kBase + 0x300 - dmi.get_start_address());
            p[0] = 0xDE; p[1] = 0xAD; p[2] = 0xBE; p[3] = 0xEF;
        }
        r2 = driver::access(d.host, tlm::TLM_READ_COMMAND, kBase + 0x300, via_bt2.data(), 4, SC_ZERO_TIME);
    });
    sc_start();

    CHECK(w.status == tlm::TLM_OK_RESPONSE);
    CHECK(r.status == tlm::TLM_OK_RESPONSE);
    CHECK(r.dmi_allowed);
    CHECK(via_bt == burst);
    // Write [0,16) -> 66; read [16,32) -> 82; 4-byte read [32,33) -> 83.
    CHECK(w.delay == cycles(66));
    CHECK(r.delay == cycles(82));
    CHECK(r2.delay == cycles(83));

    CHECK(dbg_write_n == 16);
    CHECK(dbg_read_n == 64);
    CHECK(via_dbg == burst);
    CHECK(dbg_unit_n == 16);
    CHECK(via_dbg_unit == dbg);
    CHECK(dbg_tail_n == 8);
    CHECK(std::all_of(tail.begin(), tail.begin() + 8, [](unsigned char c) { return c == 0; }));
    CHECK(std::all_of(tail.begin() + 8, tail.end(), [](unsigned char c) { return c == 0xEE; }));
    CHECK(dbg_out_n == 0);

    REQUIRE(dmi_ok);
    CHECK(dmi.get_start_address() == kBase);
    CHECK(dmi.get_end_address() == kBase + kSize - 1);
    CHECK(dmi.is_read_write_allowed());
    CHECK(dmi.get_dmi_ptr() == mem.data());
    CHECK(std::equal(burst.begin(), burst.end(), dmi.get_dmi_ptr() + 0x100));
    CHECK(std::equal(dbg.begin(), dbg.end(), dmi.get_dmi_ptr() + 0x200));
    // One beat + worst-case latency: 1 + 50 cycles.
    CHECK(dmi.get_read_latency() == cycles(51));
    CHECK(dmi.get_write_latency() == cycles(51));
    CHECK(via_bt2 == std::vector<unsigned char>{0xDE, 0xAD, 0xBE, 0xEF});

    CHECK_FALSE(dmi_below);
    CHECK(deny_below.get_start_address() == 0);
    CHECK(deny_below.get_end_address() == kBase - 1);
    CHECK_FALSE(dmi_above);
    CHECK(deny_above.get_start_address() == kBase + kSize);
    CHECK(deny_above.get_end_address() == std::numeric_limits<std::uint64_t>::max());

    // Debug and DMI traffic took no channel time and counted only as themselves.
    CHECK(mem.stats().busy_cycles == 16 + 16 + 1);
    CHECK(mem.stats().reads == 2);
    CHECK(mem.stats().writes == 1);
    CHECK(mem.stats().debug_accesses == 4);   // the out-of-map one moved nothing
    CHECK(mem.stats().dmi_grants == 1);
}

TEST_CASE("tlm memory_controller: malformed requests get the right error and change nothing", "[tlm][memory]") {
    // A real latency range: a refused request must not consume a draw either.
    memory_controller mem("mem", config(50, 100, 1), period());
    std::fill(mem.data(), mem.data() + kSize, 0xA5);

    struct error_case {
        std::string what;
        tlm::tlm_command cmd;
        std::uint64_t addr;
        unsigned len;
        bool null_data = false;
        bool byte_enables = false;
        int streaming_width = -1;   // -1: equal to len
        tlm::tlm_response_status expect;
    };
    const std::vector<error_case> cases = {
        {"below base", tlm::TLM_WRITE_COMMAND, kBase - 1, 4, false, false, -1, tlm::TLM_ADDRESS_ERROR_RESPONSE},
        {"at end", tlm::TLM_WRITE_COMMAND, kBase + kSize, 4, false, false, -1, tlm::TLM_ADDRESS_ERROR_RESPONSE},
        {"straddles end", tlm::TLM_WRITE_COMMAND, kBase + kSize - 4, 8, false, false, -1, tlm::TLM_ADDRESS_ERROR_RESPONSE},
        {"wraps 2^64", tlm::TLM_WRITE_COMMAND, ~std::uint64_t(0) - 3, 64, false, false, -1, tlm::TLM_ADDRESS_ERROR_RESPONSE},
        {"read below base", tlm::TLM_READ_COMMAND, kBase - 64, 64, false, false, -1, tlm::TLM_ADDRESS_ERROR_RESPONSE},
        {"ignore command", tlm::TLM_IGNORE_COMMAND, kBase, 4, false, false, -1, tlm::TLM_COMMAND_ERROR_RESPONSE},
        {"write byte enables", tlm::TLM_WRITE_COMMAND, kBase, 4, false, true, -1, tlm::TLM_BYTE_ENABLE_ERROR_RESPONSE},
        {"read byte enables", tlm::TLM_READ_COMMAND, kBase, 4, false, true, -1, tlm::TLM_BYTE_ENABLE_ERROR_RESPONSE},
        {"streaming width 4", tlm::TLM_WRITE_COMMAND, kBase, 64, false, false, 4, tlm::TLM_BURST_ERROR_RESPONSE},
        {"streaming width 0", tlm::TLM_WRITE_COMMAND, kBase, 64, false, false, 0, tlm::TLM_BURST_ERROR_RESPONSE},
        {"length 0", tlm::TLM_WRITE_COMMAND, kBase, 0, false, false, -1, tlm::TLM_GENERIC_ERROR_RESPONSE},
        {"null data", tlm::TLM_WRITE_COMMAND, kBase, 64, true, false, -1, tlm::TLM_GENERIC_ERROR_RESPONSE},
    };

    struct result {
        outcome o;
        bool buffer_intact;
    };
    std::vector<result> results;
    outcome edge, wide;
    std::vector<unsigned char> wide_buf(64);

    driver drv("drv", mem, [&](driver& d) {
        for (const auto& c : cases) {
            // Writes carry 0x11, reads land in 0x5A: either way no byte may move.
            std::vector<unsigned char> buf(64, c.cmd == tlm::TLM_READ_COMMAND ? 0x5A : 0x11);
            const std::vector<unsigned char> before = buf;
            unsigned char be[4] = {0xFF, 0x00, 0xFF, 0x00};
            tlm::tlm_generic_payload gp;
        driver::prepare(gp, c.cmd, c.addr, c.null_data ? nullptr : buf.data(), c.len);
            if (c.byte_enables) {
                gp.set_byte_enable_ptr(be);
                gp.set_byte_enable_length(4);
            }
            if (c.streaming_width >= 0) gp.set_streaming_width(unsigned(c.streaming_width));
            // 7 cycles annotated: an error must hand the same delay back.
            results.push_back({driver::send(d.unit, gp, cycles(7)), buf == before});
        }
        // After all that the channel is still free at 0 and the PRNG unused:
        // the last 64 bytes of the map go [0,16) + first seed-1 draw 94 = 110.
        auto data = pattern(64, 9);
        edge = driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + kSize - 64, data.data(), 64, SC_ZERO_TIME);
        // A streaming width wider than the data is an ordinary burst:
        // [16,32) + second draw 84 = 116.
        tlm::tlm_generic_payload gp;
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase + kSize - 64, wide_buf.data(), 64);
        gp.set_streaming_width(128);
        wide = driver::send(d.host, gp, SC_ZERO_TIME);
    });
    sc_start();

    REQUIRE(results.size() == cases.size());
    for (std::size_t i = 0; i < cases.size(); ++i) {
        INFO(cases[i].what);
        CHECK(results[i].o.status == cases[i].expect);
        CHECK(results[i].o.delay == cycles(7));
        CHECK_FALSE(results[i].o.dmi_allowed);
        CHECK(results[i].buffer_intact);
    }

    CHECK(edge.status == tlm::TLM_OK_RESPONSE);
    CHECK(edge.delay == cycles(110));
    CHECK(wide.status == tlm::TLM_OK_RESPONSE);
    CHECK(wide.delay == cycles(116));
    CHECK(wide_buf == pattern(64, 9));
    // Only the edge write changed the store.
    CHECK(std::all_of(mem.data(), mem.data() + kSize - 64, [](unsigned char c) { return c == 0xA5; }));

    const auto& s = mem.stats();
    CHECK(s.errors == 12);
    CHECK(s.writes == 1);
    CHECK(s.reads == 1);
    CHECK(s.bytes_written == 64);
    CHECK(s.bytes_read == 64);
    CHECK(s.busy_cycles == 32);
    CHECK(s.queue_cycles == 16);
    CHECK(s.latency_cycles == 94 + 84);
    CHECK(s.max_completion_cycle == 116);
}

TEST_CASE("tlm memory_controller: activity counters are exact", "[tlm][memory]") {
    memory_controller mem("mem", config(50, 50), period());
    auto data = pattern(64, 2);
    std::vector<unsigned char> rd(16);
    std::vector<outcome> out;
    driver drv("drv", mem, [&](driver& d) {
        // W1 [0,16) -> 66. W2 arrives 0, waits 16: [16,32) -> 82.
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase, data.data(), 64, SC_ZERO_TIME));
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + 64, data.data(), 64, SC_ZERO_TIME));
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + kSize, data.data(), 4, SC_ZERO_TIME));
        // R1 10 B at cycle 100: [100,103) -> 153.
        out.push_back(driver::access(d.host, tlm::TLM_READ_COMMAND, kBase, rd.data(), 10, cycles(100)));
        // W3 5 B, arrival 0 taken as 100, waits 3: 2 beats [103,105) -> 155.
        out.push_back(driver::access(d.unit, tlm::TLM_WRITE_COMMAND, kBase + 128, data.data(), 5, SC_ZERO_TIME));
        tlm::tlm_generic_payload gp;
        driver::prepare(gp, tlm::TLM_READ_COMMAND, kBase, rd.data(), 16);
        d.host->transport_dbg(gp);
        tlm::tlm_dmi dmi;
        d.host->get_direct_mem_ptr(gp, dmi);
    });
    sc_start();

    REQUIRE(out.size() == 5);
    CHECK(out[0].delay == cycles(66));
    CHECK(out[1].delay == cycles(82));
    CHECK(out[2].status == tlm::TLM_ADDRESS_ERROR_RESPONSE);
    CHECK(out[3].delay == cycles(153));
    CHECK(out[4].delay == cycles(155));

    const auto& s = mem.stats();
    CHECK(s.reads == 1);
    CHECK(s.writes == 3);
    CHECK(s.bytes_read == 10);
    CHECK(s.bytes_written == 64 + 64 + 5);
    CHECK(s.errors == 1);
    CHECK(s.busy_cycles == 16 + 16 + 3 + 2);
    CHECK(s.queue_cycles == 0 + 16 + 0 + 3);
    CHECK(s.latency_cycles == 4 * 50);
    CHECK(s.max_completion_cycle == 155);
    CHECK(s.debug_accesses == 1);
    CHECK(s.dmi_grants == 1);
    CHECK(s.transactions() == 4);
    CHECK(s.mean_latency_cycles() == Approx(50.0));
    CHECK(s.channel_utilization() == Approx(37.0 / 155.0));
    CHECK(mem.last_completion_cycle() == 155);

    // for_each enumerates every counter once, with its value and a description.
    std::vector<std::string> names;
    std::vector<std::uint64_t> values;
    bool described = true;
    s.for_each([&](const char* name, std::uint64_t v, const char* help) {
        names.emplace_back(name);
        values.push_back(v);
        described = described && help && *help;
    });
    CHECK(names == std::vector<std::string>{"reads", "writes", "bytes_read", "bytes_written", "errors",
                                            "busy_cycles", "queue_cycles", "latency_cycles",
                                            "max_completion_cycle", "debug_accesses", "dmi_grants"});
    CHECK(values == std::vector<std::uint64_t>{1, 3, 10, 133, 1, 37, 19, 200, 155, 1, 1});
    CHECK(described);
    CHECK(std::set<std::string>(names.begin(), names.end()).size() == names.size());
}

TEST_CASE("tlm memory_controller: impossible configurations are refused at construction", "[tlm][memory]") {
    auto bad = config(50, 50);
    bad.latency_min = 101;
    bad.latency_max = 100;
    CHECK_THROWS_AS(memory_controller("m1", bad, period()), rbcd::InputError);
    bad = config(50, 50);
    bad.bytes_per_cycle = 0;
    CHECK_THROWS_AS(memory_controller("m2", bad, period()), rbcd::InputError);
    bad = config(50, 50);
    bad.size_bytes = 0;
    CHECK_THROWS_AS(memory_controller("m3", bad, period()), rbcd::InputError);
    bad = config(50, 50);
    bad.base = ~std::uint64_t(0) - 15;   // 16 bytes fit below 2^64, 1 MiB does not
    CHECK_THROWS_AS(memory_controller("m4", bad, period()), rbcd::InputError);
    CHECK_THROWS_AS(memory_controller("m5", config(50, 50), SC_ZERO_TIME), rbcd::InputError);

    // The edge itself is fine: a map ending exactly at 2^64 - 1.
    auto edge = config(50, 50);
    edge.base = ~std::uint64_t(0) - 15;
    edge.size_bytes = 16;
    memory_controller ok("ok", edge, period());
    CHECK(ok.size() == 16);
}
