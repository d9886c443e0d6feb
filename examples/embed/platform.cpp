// A small virtual platform of its own around the RBCD unit: its own memory
// target behind an address router, its own host that reads the collision
// records back from that memory, and the unit from the installed rbcd package.
//
//   rbcd-embed TRACE [CONFIG.toml]  -> the collision records on stdout
//
//   unit.mem --> router --[0x20000000, +1 MiB)--> sram (local addresses from 0)
//   host.mem --> router
//   unit.host --> host (rbcd::unit_host_if: records_ready -> read back, print)
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
using platform::kSramSize;

// The platform's memory: local addresses from 0, answers at once (a fixed
// 30 ns annotated latency), no DMI.
struct sram : sc_core::sc_module {
    tlm_utils::simple_target_socket<sram, kBus> socket;
    std::vector<unsigned char> bytes = std::vector<unsigned char>(kSramSize);
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
        delay += sc_core::sc_time(30, sc_core::SC_NS);
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
    std::string out = rbcd::kCollisionsMagic;
    std::vector<unsigned char> buf;
    explicit host(sc_core::sc_module_name n) : sc_module(n), mem("mem") {}

    void begin_frame(std::uint64_t n) override { rbcd::append_frame_line(out, n); }
    std::uint64_t records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
                                bool /*because_full*/) override {
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
        rbcd::SimConfig cfg;
        if (argc == 3) rbcd::apply_config_file(cfg, argv[2]);
        // The unit's output region, as this platform maps it: 4 KiB into the sram.
        cfg.memory.base = kSramBase;
        cfg.memory.size_bytes = kSramSize;
        cfg.output.region_offset = 0x1000;
        cfg.validate();

        rbcd::TraceReader trace(argv[1], rbcd::TraceLimits{cfg.tile.width, cfg.tile.height, cfg.zeb.id_bits});
        rbcd::rbcd_unit unit("rbcd", cfg, trace);
        router bus("bus");
        sram memory("sram");
        host cpu("cpu");
        unit.mem.bind(bus.in);
        cpu.mem.bind(bus.in);
        bus.out.bind(memory.socket);
        unit.host.bind(cpu);

        sc_core::sc_start();
        unit.check_finished();
        std::fwrite(cpu.out.data(), 1, cpu.out.size(), stdout);
        std::fprintf(stderr, "rbcd-embed: %llu cycles, %llu readbacks\n",
                     static_cast<unsigned long long>(unit.total_cycles()),
                     static_cast<unsigned long long>(unit.records_ready_count()));
        return 0;
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "rbcd-embed: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rbcd-embed: %s\n", e.what());
        return 1;
    }
}
