// A small virtual platform of its own around the RBCD unit: its own memory
// target behind an address router, its own host that reads the collision
// records back from that memory, and the unit from the installed rbcd package.
//
//   rbcd-embed TRACE [CONFIG.toml]  -> the collision records on stdout
//
// Two units side by side on the same input, each with its own host and output
// regions in the one memory; their records must agree. The memory's latency
// is not a whole number of unit cycles, and each host checks that the records
// it is told of have completed in memory (hw/unit_host_if.h's promise).
//
//   unit[i].mem --> router --[0x120000000, +1 MiB)--> sram (local addresses from 0, 41 ns)
//   host[i].mem --> router
//   unit[i].host --> host[i] (rbcd::unit_host_if: records_ready -> check, read back, print)
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/multi_passthrough_target_socket.h>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

#include "common/config.h"   // the platform's own, not rbcd's
#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/common/records.h"
#include "rbcd/hw/rbcd_unit.h"
#include "rbcd/io/collision_format.h"
#include "rbcd/io/trace_reader.h"

namespace {

constexpr unsigned kBus = rbcd::kBusWidth;
using platform::kSramBase;
using platform::kSramLatencyPs;
using platform::kSramSize;

// The platform's memory: local addresses from 0, answers at once (a fixed
// 41 ns annotated latency), no DMI. Keeps when each write completes.
struct sram : sc_core::sc_module {
    tlm_utils::simple_target_socket<sram, kBus> socket;
    std::vector<unsigned char> bytes = std::vector<unsigned char>(kSramSize);
    std::vector<sc_core::sc_time> done_at = std::vector<sc_core::sc_time>(kSramSize / 16);   // per 16 bytes
    explicit sram(sc_core::sc_module_name n) : sc_module(n), socket("socket") {
        socket.register_b_transport(this, &sram::b_transport);
    }
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& delay) {
        const std::uint64_t a = t.get_address(), n = t.get_data_length();
        if (a > bytes.size() || n > bytes.size() - a || t.get_byte_enable_ptr()) {
            t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
            return;
        }
        if (t.is_write()) std::memcpy(&bytes[a], t.get_data_ptr(), n);
        else if (t.is_read()) std::memcpy(t.get_data_ptr(), &bytes[a], n);
        delay += sc_core::sc_time(kSramLatencyPs, sc_core::SC_PS);
        if (t.is_write())
            for (std::uint64_t b = a / 16; b < (a + n + 15) / 16; ++b) done_at[b] = sc_core::sc_time_stamp() + delay;
        t.set_response_status(tlm::TLM_OK_RESPONSE);
    }
};

// Decodes [kSramBase, +kSramSize) to the sram's local addresses; anything else
// is an address error.
struct router : sc_core::sc_module {
    tlm_utils::multi_passthrough_target_socket<router, kBus> in;
    tlm_utils::simple_initiator_socket<router, kBus> out;
    explicit router(sc_core::sc_module_name n) : sc_module(n), in("in"), out("out") {
        in.register_b_transport(this, &router::b_transport);
    }
    void b_transport(int, tlm::tlm_generic_payload& t, sc_core::sc_time& delay) {
        const std::uint64_t a = t.get_address();
        if (a < kSramBase || a - kSramBase >= kSramSize) {
            t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
            return;
        }
        t.set_address(a - kSramBase);
        out->b_transport(t, delay);
        t.set_address(a);   // the initiator gets its payload back as it sent it
    }
};

// The CPU and its driver: on records ready, reads them over the bus and prints them.
struct host : sc_core::sc_module, rbcd::unit_host_if {
    tlm_utils::simple_initiator_socket<host, kBus> mem;
    const sram& memory;
    sc_core::sc_time period;   // the unit's clock
    std::string out = rbcd::kCollisionsMagic;
    std::vector<unsigned char> buf;
    host(sc_core::sc_module_name n, const sram& m, sc_core::sc_time unit_period)
        : sc_module(n), mem("mem"), memory(m), period(unit_period) {}

    void begin_frame(std::uint64_t n) override { rbcd::append_frame_line(out, n); }
    std::uint64_t records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
                                bool /*because_full*/) override {
        // The promise: every write of these records has completed by `cycle`.
        for (std::uint64_t off = 0; off < bytes; off += 16) {
            const sc_core::sc_time done = memory.done_at[(address - kSramBase + off) / 16];
            if (done > period * double(cycle))
                throw rbcd::RunError(std::string(name()) + ": records ready at " + (period * double(cycle)).to_string() +
                                     " but the write at " + rbcd::hex_address(address + off) + " completes at " +
                                     done.to_string());
        }
        buf.resize(bytes);
        if (bytes > 0) {
            tlm::tlm_generic_payload gp;
            gp.set_command(tlm::TLM_READ_COMMAND);
            gp.set_address(address);
            gp.set_data_ptr(buf.data());
            gp.set_data_length(static_cast<unsigned>(bytes));
            gp.set_streaming_width(static_cast<unsigned>(bytes));
            gp.set_byte_enable_ptr(nullptr);
            gp.set_dmi_allowed(false);
            gp.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
            sc_core::sc_time delay = sc_core::SC_ZERO_TIME;   // the read's time is the 100 cycles below
            mem->b_transport(gp, delay);
            if (!gp.is_response_ok()) throw rbcd::RunError("host: read failed: " + gp.get_response_string());
        }
        for (std::uint64_t off = 0; off + rbcd::kRecordBytes <= bytes; off += rbcd::kRecordBytes) {
            const rbcd::MemRecord r = rbcd::MemRecord::load(&buf[off]);
            if (r.kind() == rbcd::RecordKind::Hit) rbcd::append_hit_line(out, r.as_hit());
            else if (r.kind() == rbcd::RecordKind::Overflow) rbcd::append_overflow_line(out, r.as_overflow());
            else throw rbcd::RunError("host: corrupt record at " + rbcd::hex_address(address + off));
        }
        return cycle + 100;   // the region is free again 100 unit cycles later
    }
};

} // namespace

int sc_main(int argc, char* argv[]) {
    if (argc < 2 || argc > 3) {
        std::fprintf(stderr, "usage: %s TRACE [CONFIG.toml]\n", argv[0]);
        return 2;
    }
    try {
        rbcd::SimConfig base;
        if (argc == 3) rbcd::apply_config_file(base, argv[2]);
        // Set in code, as a platform does, and checked by the same rules as TOML.
        base.memory.base = kSramBase;
        base.memory.size_bytes = kSramSize;
        rbcd::SimConfig cfg[2] = {base, base};
        for (int i = 0; i < 2; ++i) {
            cfg[i].output.region_offset = platform::kUnitRegionOffset[i];
            cfg[i].validate();
        }
        if (cfg[0].output.region_offset + cfg[0].output.region_bytes * cfg[0].output.regions() >
            cfg[1].output.region_offset)
            throw rbcd::InputError("the two units' output regions overlap: output.region_bytes too large");

        rbcd::TraceReader trace0(argv[1], rbcd::trace_limits(cfg[0]));
        rbcd::TraceReader trace1(argv[1], rbcd::trace_limits(cfg[1]));
        rbcd::rbcd_unit unit0("rbcd0", cfg[0], trace0);
        rbcd::rbcd_unit unit1("rbcd1", cfg[1], trace1);
        router bus("bus");
        sram memory("sram");
        host cpu0("cpu0", memory, unit0.clk.period());
        host cpu1("cpu1", memory, unit1.clk.period());
        unit0.mem.bind(bus.in);
        unit1.mem.bind(bus.in);
        cpu0.mem.bind(bus.in);
        cpu1.mem.bind(bus.in);
        bus.out.bind(memory.socket);
        unit0.host.bind(cpu0);
        unit1.host.bind(cpu1);

        try {
            sc_core::sc_start();
        } catch (const sc_core::sc_report& r) {
            throw rbcd::RunError(r.get_msg());   // a memory error, or a host's check
        }
        unit0.check_finished();
        unit1.check_finished();
        if (cpu0.out != cpu1.out) throw rbcd::RunError("the two units' records differ");
        std::fwrite(cpu0.out.data(), 1, cpu0.out.size(), stdout);
        std::fprintf(stderr, "rbcd-embed: %llu cycles, %llu readbacks\n",
                     static_cast<unsigned long long>(unit0.total_cycles()),
                     static_cast<unsigned long long>(unit0.records_ready_count()));
        return 0;
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "rbcd-embed: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rbcd-embed: %s\n", e.what());
        return 1;
    }
}
