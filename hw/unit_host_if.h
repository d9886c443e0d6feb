// The unit's interface to the host (the CPU and its driver) that consumes the
// collision records: the unit's "records ready" interrupt and the host's
// acknowledge, in one blocking call (docs/embedding.md).
//
// The unit's timing is computed in cycles, not simulated, so the host answers
// at once with the cycle from which the unit may overwrite the region, the way
// an LT target answers b_transport with an annotated delay. Implementations do
// not call wait(): they are called from the unit's thread.
#pragma once
#include <cstdint>
#include <systemc>

namespace rbcd {

class unit_host_if : public virtual sc_core::sc_interface {
public:
    // Records read back from now on belong to frame n (the frames of the
    // collisions format); called before any records_ready of the frame.
    virtual void begin_frame(std::uint64_t n) = 0;
    // Records ready: [address, address + bytes) holds `bytes / 16` records,
    // all written (their b_transport calls returned and their annotated
    // completions are at or before `cycle`). because_full: the region filled
    // up mid-frame; otherwise the frame ended. Returns the cycle, >= `cycle`,
    // from which the unit may write the region again from its start.
    virtual std::uint64_t records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
                                        bool because_full) = 0;
};

} // namespace rbcd
