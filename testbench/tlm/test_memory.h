// A memory target for the protocol tests, unlike the bundled controller in
// every way a platform's memory may be: it answers a chosen write with an
// error, grants DMI only for a window of its range, moves at most a few bytes
// per debug read, and invalidates its DMI grants after every k-th write.
//
// The DMI window is kept in a buffer of its own, exactly the window's size
// with guard bytes around it, written through by b_transport while it is
// granted and poisoned (0xEE) when invalidated: an initiator that reads past
// its grant or through a dropped pointer reads guard bytes, not records.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_target_socket.h>

#include "rbcd/tlm/bus.h"

namespace rbcd::tb {

struct test_memory : sc_core::sc_module {
    tlm_utils::simple_target_socket<test_memory, kBusWidth> unit_port;
    tlm_utils::simple_target_socket<test_memory, kBusWidth> host_port;

    struct options {
        std::uint64_t base = 0, size = 1 << 20;
        std::uint64_t latency_cycles = 20;   // annotated per b_transport
        std::uint64_t latency_extra_ps = 0;  // added to it: a latency that is not whole cycles
        std::uint64_t error_on_write = 0;    // 1-based write answered with error_status; 0 never
        tlm::tlm_response_status error_status = tlm::TLM_ADDRESS_ERROR_RESPONSE;
        bool dmi = true;
        std::uint64_t dmi_start = 0, dmi_bytes = ~std::uint64_t(0);   // window offsets into the memory
        unsigned debug_max = 0;              // bytes per transport_dbg call; 0 unlimited
        std::uint64_t invalidate_every = 0;  // invalidate all grants after every k-th write; 0 never
    };
    static constexpr unsigned kGuard = 64;
    static constexpr unsigned char kPoison = 0xEE;

    options opt;
    sc_core::sc_time period;
    std::vector<unsigned char> store;
    std::unique_ptr<std::vector<unsigned char>> window;   // live DMI window (with guards), or null
    std::uint64_t win_lo = 0, win_hi = 0;                 // window offsets [lo, hi)
    std::vector<std::unique_ptr<std::vector<unsigned char>>> dropped;   // poisoned, kept allocated
    std::uint64_t writes = 0, errors = 0, grants = 0, refusals = 0, invalidations = 0, debug_reads = 0;
    std::uint64_t error_address = 0;
    sc_core::sc_time last_write_done = sc_core::SC_ZERO_TIME;   // latest completion of a write so far

    test_memory(sc_core::sc_module_name n, const options& o, sc_core::sc_time clock_period)
        : sc_module(n), unit_port("unit_port"), host_port("host_port"), opt(o), period(clock_period),
          store(o.size, 0) {
        for (auto* p : {&unit_port, &host_port}) {
            p->register_b_transport(this, &test_memory::b_transport);
            p->register_transport_dbg(this, &test_memory::transport_dbg);
            p->register_get_direct_mem_ptr(this, &test_memory::get_direct_mem_ptr);
        }
    }

    bool inside(std::uint64_t a, std::uint64_t n) const {
        return a >= opt.base && a - opt.base <= opt.size && n <= opt.size - (a - opt.base);
    }

    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& delay) {
        const std::uint64_t a = t.get_address(), n = t.get_data_length();
        if (t.is_write() && ++writes == opt.error_on_write) {
            ++errors;
            error_address = a;
            t.set_response_status(opt.error_status);
            return;
        }
        if (!inside(a, n) || t.get_byte_enable_ptr() || t.get_streaming_width() < n) {
            t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
            return;
        }
        const std::uint64_t off = a - opt.base;
        if (t.is_read()) {
            std::memcpy(t.get_data_ptr(), &store[off], n);
        } else if (t.is_write()) {
            std::memcpy(&store[off], t.get_data_ptr(), n);
            write_through(off, n);
        }
        delay += period * double(opt.latency_cycles) + sc_core::sc_time(double(opt.latency_extra_ps), sc_core::SC_PS);
        if (t.is_write()) last_write_done = std::max(last_write_done, sc_core::sc_time_stamp() + delay);
        t.set_response_status(tlm::TLM_OK_RESPONSE);
        if (t.is_write() && opt.invalidate_every && writes % opt.invalidate_every == 0) invalidate_all();
    }

    void write_through(std::uint64_t off, std::uint64_t n) {
        if (!window) return;
        const std::uint64_t lo = std::max(off, win_lo), hi = std::min(off + n, win_hi);
        if (lo < hi) std::memcpy(window->data() + kGuard + (lo - win_lo), &store[lo], hi - lo);
    }

    void invalidate_all() {
        if (!window) return;
        ++invalidations;
        std::fill(window->begin(), window->end(), kPoison);
        dropped.push_back(std::move(window));
        unit_port->invalidate_direct_mem_ptr(0, ~sc_dt::uint64(0));
        host_port->invalidate_direct_mem_ptr(0, ~sc_dt::uint64(0));
    }

    unsigned int transport_dbg(tlm::tlm_generic_payload& t) {
        const std::uint64_t a = t.get_address();
        if (!inside(a, 1)) return 0;
        std::uint64_t n = std::min<std::uint64_t>(t.get_data_length(), opt.size - (a - opt.base));
        if (opt.debug_max) n = std::min<std::uint64_t>(n, opt.debug_max);
        if (t.is_read()) std::memcpy(t.get_data_ptr(), &store[a - opt.base], n);
        ++debug_reads;
        t.set_response_status(tlm::TLM_OK_RESPONSE);
        return static_cast<unsigned>(n);
    }

    bool get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& dmi) {
        const std::uint64_t a = t.get_address();
        const std::uint64_t lo = opt.dmi_start, hi = std::min(opt.size, opt.dmi_start + std::min(opt.dmi_bytes, opt.size));
        const bool in_window = opt.dmi && inside(a, 1) && a - opt.base >= lo && a - opt.base < hi;
        if (!in_window) {
            // A refusal names the hole around the address.
            ++refusals;
            dmi.set_granted_access(tlm::tlm_dmi::DMI_ACCESS_NONE);
            if (!opt.dmi || !inside(a, 1)) return false;
            if (a - opt.base < lo) {
                dmi.set_start_address(opt.base);
                dmi.set_end_address(opt.base + lo - 1);
            } else {
                dmi.set_start_address(opt.base + hi);
                dmi.set_end_address(opt.base + opt.size - 1);
            }
            return false;
        }
        if (!window) {
            window = std::make_unique<std::vector<unsigned char>>(hi - lo + 2 * kGuard, kPoison);
            std::memcpy(window->data() + kGuard, &store[lo], hi - lo);
            win_lo = lo;
            win_hi = hi;
        }
        ++grants;
        dmi.set_dmi_ptr(window->data() + kGuard);
        dmi.set_start_address(opt.base + lo);
        dmi.set_end_address(opt.base + hi - 1);
        // Read only: writes must go through b_transport, which keeps store and window equal.
        dmi.set_granted_access(tlm::tlm_dmi::DMI_ACCESS_READ);
        dmi.set_read_latency(sc_core::SC_ZERO_TIME);
        dmi.set_write_latency(sc_core::SC_ZERO_TIME);
        return true;
    }
};

} // namespace rbcd::tb
