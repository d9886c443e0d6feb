// The CPU side of the output region: reads the records the unit wrote, as
// software would (after each frame, and when the region is full), through a
// DMI pointer when the memory grants one, else through debug transport.
#pragma once
#include <cstdint>
#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>

#include "common/config.h"
#include "hw/clocking.h"
#include "hw/collision_sink.h"

namespace rbcd {

class host_reader : public sc_core::sc_module {
public:
    tlm_utils::simple_initiator_socket<host_reader> mem;

    struct stats_t {
        std::uint64_t readbacks = 0;        // times the region was read back
        std::uint64_t full_readbacks = 0;   // ... of which because the region was full
        std::uint64_t records = 0;
        std::uint64_t hit_records = 0;
        std::uint64_t overflow_records = 0;
        std::uint64_t bytes = 0;
        std::uint64_t dmi_reads = 0;        // readbacks served by the DMI pointer
        std::uint64_t wait_cycles = 0;      // cycles a readback waited for the previous one
        template <class F> void for_each(F f) const {
            RBCD_STAT(f, *this, readbacks, "readbacks of the output region");
            RBCD_STAT(f, *this, full_readbacks, "readbacks forced by a full region");
            RBCD_STAT(f, *this, records, "records read back");
            RBCD_STAT(f, *this, hit_records, "hit records read back");
            RBCD_STAT(f, *this, overflow_records, "overflow records read back");
            RBCD_STAT(f, *this, bytes, "bytes read back");
            RBCD_STAT(f, *this, dmi_reads, "readbacks through the DMI pointer");
            RBCD_STAT(f, *this, wait_cycles, "cycles readbacks waited for the host to finish the previous one");
        }
    };

    host_reader(sc_core::sc_module_name name, const SimConfig& cfg, CollisionSink& sink);

    void begin_frame(std::uint64_t n) { sink_.frame(n); }
    // Reads `bytes` bytes of records from the region at `region_addr`, from
    // cycle `cycle` or when the host is done with its previous readback;
    // returns the cycle from which the unit may overwrite that region.
    std::uint64_t read_back(std::uint64_t region_addr, std::uint64_t bytes, std::uint64_t cycle, bool because_full);

    const stats_t& stats() const { return stats_; }

private:
    CollisionSink& sink_;
    std::uint64_t readback_cycles_;
    std::uint64_t busy_until_ = 0;
    std::vector<unsigned char> buf_;
    stats_t stats_;
};

} // namespace rbcd
