// The CPU side of the output region: reads the records the unit wrote, as
// software would (after each frame, and when the region is full), through a
// DMI pointer where the memory grants one, else through debug transport.
//
// TLM-2.0 base protocol (docs/embedding.md): a DMI pointer is used only inside
// the range it was granted for, only for the access it grants, and dropped on
// invalidate_direct_mem_ptr for any overlapping range. A partial grant is used
// for its part and the rest read by debug transport, which may itself move
// fewer bytes than asked (it is repeated from where it stopped). By default
// the grant is asked for again at each readback (a driver mapping the buffer
// for one read); keep_dmi(true) keeps it across readbacks until invalidated.
#pragma once
#include <cstdint>
#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/hw/collision_sink.h"
#include "rbcd/hw/unit_host_if.h"
#include "rbcd/tlm/bus.h"

namespace rbcd {

class host_reader : public sc_core::sc_module, public unit_host_if {
public:
    tlm_utils::simple_initiator_socket<host_reader, kBusWidth> mem;

    struct stats_t {
        std::uint64_t readbacks = 0;        // times the region was read back
        std::uint64_t full_readbacks = 0;   // ... of which because the region was full
        std::uint64_t records = 0;
        std::uint64_t hit_records = 0;
        std::uint64_t overflow_records = 0;
        std::uint64_t bytes = 0;
        std::uint64_t dmi_reads = 0;        // readbacks served by the DMI pointer
        std::uint64_t wait_cycles = 0;      // cycles a readback waited for the previous one
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, readbacks, "readbacks of the output region");
            RBCD_STAT(f, s, full_readbacks, "readbacks forced by a full region");
            RBCD_STAT(f, s, records, "records read back");
            RBCD_STAT(f, s, hit_records, "hit records read back");
            RBCD_STAT(f, s, overflow_records, "overflow records read back");
            RBCD_STAT(f, s, bytes, "bytes read back");
            RBCD_STAT(f, s, dmi_reads, "readbacks through the DMI pointer");
            RBCD_STAT(f, s, wait_cycles, "cycles readbacks waited for the host to finish the previous one");
        }
    };

    host_reader(sc_core::sc_module_name name, const SimConfig& cfg, CollisionSink& sink);

    // unit_host_if
    void begin_frame(std::uint64_t n) override { sink_.frame(n); }
    // Reads the records back and hands them to the sink, from `cycle` or when
    // the host is done with its previous readback; returns the cycle from
    // which the unit may overwrite that region (that start + host.readback_cycles).
    std::uint64_t records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
                                bool because_full) override;

    // Keep a DMI grant across readbacks (until invalidated) instead of asking at each.
    void keep_dmi(bool on) { keep_dmi_ = on; }
    const stats_t& stats() const { return stats_; }

private:
    void invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end);
    // Copies [address, address + n) into dst; returns whether any of it came through DMI.
    bool read(std::uint64_t address, std::uint64_t n, unsigned char* dst);

    CollisionSink& sink_;
    std::uint64_t readback_cycles_;
    std::uint64_t busy_until_ = 0;
    std::vector<unsigned char> buf_;
    bool keep_dmi_ = false;
    bool dmi_valid_ = false;    // dmi_ holds a read grant
    tlm::tlm_dmi dmi_;
    tlm::tlm_generic_payload gp_;
    stats_t stats_;
};

} // namespace rbcd
