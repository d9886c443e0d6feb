// Collects hit and overflow records from the z-overlap tester and writes them
// to the output region in memory in bursts (TLM-2.0 b_transport, loosely
// timed: each write is annotated with the buffer's local time and the memory
// controller answers with its completion time; no wait() per record).
//
// A record holds its slot from the cycle it is accepted until the burst that
// carries it completes; the tester stalls while every slot is held. At each
// frame end, and whenever the region cannot take the next burst, the buffer
// lets its writes complete, hands the region to the host to read back, and
// goes on in the next region (output.double_buffer: two, used in turn) as
// soon as the host has read that one back; with one region it waits for the
// readback it just started.
#pragma once
#include <cstdint>
#include <string>
#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/records.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/hw/unit_host_if.h"
#include "rbcd/tlm/bus.h"
#include "rbcd/common/vcd_writer.h"

namespace rbcd {

// A burst of records the buffer wrote to memory, for a WriteObserver.
struct RecordWrite {
    std::uint64_t address = 0, bytes = 0, records = 0;
    std::uint64_t issue = 0, done = 0;   // cycles: sent, completed by the memory
};

class WriteObserver {
public:
    virtual ~WriteObserver() = default;
    virtual void records_written(const RecordWrite&) = 0;
};

class output_buffer : public sc_core::sc_module {
public:
    tlm_utils::simple_initiator_socket<output_buffer, kBusWidth> mem;

    struct stats_t {
        std::uint64_t records = 0;            // records accepted from the tester
        std::uint64_t bursts = 0;             // write transactions issued
        std::uint64_t bytes = 0;              // bytes written
        std::uint64_t full_stall_cycles = 0;  // cycles the tester waited for a slot
        std::uint64_t outstanding_stall_cycles = 0;  // cycles a ready burst waited for a free transaction slot
        std::uint64_t region_full_events = 0;
        std::uint64_t region_wait_cycles = 0;  // cycles waiting for the host to read a region back
        std::uint64_t max_occupancy = 0;
        std::uint64_t write_latency_cycles = 0;  // sum over bursts of issue-to-completion cycles
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, records, "records accepted from the tester");
            RBCD_STAT(f, s, bursts, "burst writes issued to memory");
            RBCD_STAT(f, s, bytes, "bytes written to memory");
            RBCD_STAT(f, s, full_stall_cycles, "cycles the tester waited on a full buffer");
            RBCD_STAT(f, s, outstanding_stall_cycles, "cycles bursts waited for a free write slot");
            RBCD_STAT(f, s, region_full_events, "times the output region filled up");
            RBCD_STAT(f, s, region_wait_cycles, "cycles waiting for the host to read the next region back");
            RBCD_STAT(f, s, max_occupancy, "most records held at once");
            RBCD_STAT(f, s, write_latency_cycles, "sum of burst issue-to-completion cycles");
        }
    };

    output_buffer(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk, unit_host_if& host);

    // Offers a record at cycle `cycle`; returns the cycle it was accepted (later when full).
    std::uint64_t push(const MemRecord& r, std::uint64_t cycle);
    // Writes everything held; returns the cycle all writes have completed.
    std::uint64_t flush(std::uint64_t cycle);
    // flush + hand the region to the host; returns when the unit may write again.
    std::uint64_t end_frame(std::uint64_t cycle);

    const stats_t& stats() const { return stats_; }
    // The memory error that stopped the run ("" if none): kept, because the
    // exception leaves through sc_start and the platform may ask afterwards.
    const std::string& failure() const { return failure_; }
    // Told each burst as it is written; none: nothing is gathered.
    void set_write_observer(WriteObserver* o) { observer_ = o; }
    void attach_vcd(VcdWriter& vcd, const std::string& scope) {
        vcd_ = &vcd;
        vcd_occupancy_ = vcd.add(scope, "occupancy", 17);
        vcd_in_flight_ = vcd.add(scope, "writes_in_flight", 9);
        vcd_offset_ = vcd.add(scope, "region_offset", 40);
        vcd_region_ = vcd.add(scope, "region", 1);
    }

private:
    struct Inflight {
        std::uint64_t done;
        unsigned records;
    };
    void retire(std::uint64_t cycle);
    std::uint64_t issue(std::uint64_t cycle, unsigned n);
    std::uint64_t switch_region(std::uint64_t all_done, bool because_full);
    std::uint64_t occupancy() const { return pending_.size() + inflight_records_; }

    const Clocking& clk_;
    unit_host_if& host_;
    unsigned capacity_, burst_, max_outstanding_;
    std::uint64_t region_addr_, region_bytes_;
    std::vector<std::uint64_t> region_free_;   // per region: the host is done reading it back
    unsigned region_ = 0;                      // the region being written
    std::uint64_t write_offset_ = 0;
    std::uint64_t engine_cycle_ = 0;   // the write engine issues in order, never back in time
    std::vector<MemRecord> pending_;
    std::vector<Inflight> inflight_;
    std::vector<std::uint64_t> pending_done_;   // scratch: completions after the engine's time
    std::uint64_t inflight_records_ = 0;
    std::vector<unsigned char> data_;
    tlm::tlm_generic_payload gp_;
    stats_t stats_;
    std::string failure_;
    WriteObserver* observer_ = nullptr;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_occupancy_ = 0, vcd_in_flight_ = 0, vcd_offset_ = 0, vcd_region_ = 0;
};

} // namespace rbcd
