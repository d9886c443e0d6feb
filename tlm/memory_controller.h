// The system memory controller the RBCD unit writes collision records through,
// as a loosely-timed TLM-2.0 target.
//
// Timing is computed, not simulated: nothing ticks and b_transport never
// calls wait(). Every successful b_transport is placed on one shared data
// channel, in cycles of the clock period given to the constructor:
//
//   arrival    = cycles(sc_time_stamp() + annotated delay)      (floored)
//                (never earlier than the previous arrival: FCFS channel)
//   start      = max(arrival, end of the previous transfer)
//   end        = start + ceil(length / bytes_per_cycle)
//   completion = end + latency, latency uniform in [latency_min, latency_max]
//                from a splitmix64 stream seeded with MemoryConfig::seed
//
// and the annotated delay is set to completion - sc_time_stamp().
//
// Both sockets reach the same store and the same channel: the host's
// b_transport reads queue behind the unit's writes. Debug transport and DMI
// take no channel time and draw no latency; DMI is how the host reads records
// back at zero simulated cost.
//
// Checks, first failing one wins, each leaving memory, channel, PRNG and the
// annotated delay untouched (the response is the only effect, plus `errors`):
//   length 0 or null data pointer              TLM_GENERIC_ERROR_RESPONSE
//   command neither read nor write (IGNORE)    TLM_COMMAND_ERROR_RESPONSE
//   [address, address+length) not inside map   TLM_ADDRESS_ERROR_RESPONSE
//   byte enable pointer set                    TLM_BYTE_ENABLE_ERROR_RESPONSE
//   streaming width < length                   TLM_BURST_ERROR_RESPONSE
// Byte enables are refused rather than honoured: the unit writes whole
// records, so a masked write would be an initiator bug worth reporting.
//
// Usage:
//   rbcd::memory_controller mem("mem", cfg.memory, sc_time(2500, SC_PS));
//   unit.mem.bind(mem.unit_port);          // rbcd_unit, see hw/rbcd_unit.h
//   host.mem.bind(mem.host_port);          // host_reader
//   ... sc_start(); mem.stats().for_each([](auto name, auto v, auto help) {...});
#pragma once
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_target_socket.h>

#include "rbcd/common/config.h"
#include "rbcd/common/stat_counters.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/tlm/bus.h"

namespace rbcd {

// One counter per activity, gem5 style; derived figures are formulas below.
struct memory_stats {
    std::uint64_t reads = 0;                 // successful b_transport reads
    std::uint64_t writes = 0;                // successful b_transport writes
    std::uint64_t bytes_read = 0;
    std::uint64_t bytes_written = 0;
    std::uint64_t errors = 0;                // b_transport answered with an error
    std::uint64_t busy_cycles = 0;           // data channel occupied
    std::uint64_t queue_cycles = 0;          // waited for the channel after arrival
    std::uint64_t latency_cycles = 0;        // drawn latencies, summed
    std::uint64_t max_completion_cycle = 0;  // latest completion seen
    std::uint64_t debug_accesses = 0;        // transport_dbg calls that moved bytes
    std::uint64_t dmi_grants = 0;            // get_direct_mem_ptr calls granted

    std::uint64_t transactions() const { return reads + writes; }
    double mean_latency_cycles() const {
        return transactions() ? double(latency_cycles) / double(transactions()) : 0.0;
    }
    // Fraction of the run (up to the last completion) the channel carried data.
    double channel_utilization() const {
        return max_completion_cycle ? double(busy_cycles) / double(max_completion_cycle) : 0.0;
    }

    // f(const char* name, std::uint64_t value, const char* description) for
    // every counter, in declaration order, so that reports need no field list.
    RBCD_STATS_VISITOR {
        f("reads", s.reads, "read transactions completed");
        f("writes", s.writes, "write transactions completed");
        f("bytes_read", s.bytes_read, "bytes read by completed transactions");
        f("bytes_written", s.bytes_written, "bytes written by completed transactions");
        f("errors", s.errors, "transactions answered with an error response");
        f("busy_cycles", s.busy_cycles, "cycles the data channel transferred data");
        f("queue_cycles", s.queue_cycles, "cycles requests waited for the data channel");
        f("latency_cycles", s.latency_cycles, "access latency cycles, summed over transactions");
        f("max_completion_cycle", s.max_completion_cycle, "latest response completion, cycles");
        f("debug_accesses", s.debug_accesses, "debug transport accesses (no time, no channel)");
        f("dmi_grants", s.dmi_grants, "direct memory pointers granted");
    }
};

class memory_controller : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<memory_controller, kBusWidth> unit_port;   // unit's output bursts
    tlm_utils::simple_target_socket<memory_controller, kBusWidth> host_port;   // CPU reading records back

    // Throws InputError if the configuration cannot describe a memory (zero
    // size, zero bandwidth, latency_min > latency_max, mapping past 2^64) or
    // the period is zero: these are configuration mistakes, not transactions.
    memory_controller(sc_core::sc_module_name name, const MemoryConfig& cfg,
                      sc_core::sc_time clock_period);

    const char* kind() const override { return "rbcd::memory_controller"; }

    const memory_stats& stats() const { return stats_; }

    // Waveforms: requests in flight and channel activity, at their computed cycles.
    void attach_vcd(VcdWriter& vcd, const std::string& scope) {
        vcd_ = &vcd;
        vcd_in_flight_ = vcd.add(scope, "requests_in_flight", 9);   // up to 256 writes
        vcd_channel_busy_ = vcd.add(scope, "channel_busy", 1);
    }
    // The backing store; data()[0] is the byte at base().
    unsigned char* data() { return store_.get(); }
    const unsigned char* data() const { return store_.get(); }
    std::uint64_t base() const { return base_; }
    std::uint64_t size() const { return size_; }

    // Completion cycle of the most recent successful b_transport (0 before any).
    std::uint64_t last_completion_cycle() const { return last_completion_; }
    // Cycle from which the data channel is free.
    std::uint64_t channel_free_cycle() const { return channel_free_; }
    // Frame barrier (docs/timing.md): the latency stream restarts from a seed
    // derived from memory.seed and the frame number, so a frame's timing does
    // not depend on how many transactions the frames before it made.
    void reseed_for_frame(std::uint64_t frame);

    // The one place sc_time and cycles meet. to_cycles floors.
    std::uint64_t to_cycles(const sc_core::sc_time& t) const { return t.value() / period_ticks_; }
    sc_core::sc_time to_time(std::uint64_t cycles) const {
        return sc_core::sc_time::from_value(cycles * period_ticks_);
    }

private:
    void b_transport(tlm::tlm_generic_payload& trans, sc_core::sc_time& delay);
    unsigned int transport_dbg(tlm::tlm_generic_payload& trans);
    bool get_direct_mem_ptr(tlm::tlm_generic_payload& trans, tlm::tlm_dmi& dmi);

    tlm::tlm_response_status check(const tlm::tlm_generic_payload& trans) const;
    bool in_map(std::uint64_t address, std::uint64_t length) const;
    std::uint64_t draw_latency();

    struct Free {
        void operator()(unsigned char* p) const { std::free(p); }
    };
    // calloc: a large store is mapped zero pages, touched only where written
    // (a run writes its records into a small part of it), not zeroed at
    // start-up by every process of a sweep or of --jobs.
    std::unique_ptr<unsigned char[], Free> store_;
    std::uint64_t size_ = 0;
    std::uint64_t base_;
    std::uint64_t latency_min_, latency_max_;
    std::uint64_t bytes_per_cycle_;
    std::uint64_t period_ticks_;          // clock period in sc_time resolution units
    std::uint64_t seed_;
    std::uint64_t prng_state_;            // splitmix64

    std::uint64_t last_arrival_ = 0;
    std::uint64_t channel_free_ = 0;
    std::uint64_t last_completion_ = 0;
    memory_stats stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_in_flight_ = 0, vcd_channel_busy_ = 0;
};

} // namespace rbcd
