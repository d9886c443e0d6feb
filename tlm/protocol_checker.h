// A TLM-2.0 base-protocol checker for the loosely-timed interfaces the model
// uses (b_transport, transport_dbg, DMI and its invalidation): a pass-through
// module bound between an initiator and a target, which forwards every call
// unchanged and records each rule broken on either side (IEEE 1666-2011,
// clause 11 for the interfaces, 14 for the generic payload):
//
//   initiator, on each b_transport
//     B1 called from a thread process (b_transport may wait)
//     B2 the payload is not already in flight (not passed again before its call returned)
//     B3 command READ, WRITE or IGNORE
//     B4 data pointer set and data length > 0
//     B5 streaming width > 0 and, as this model never streams, equal to the data length
//     B6 byte enable pointer null, or set with a byte enable length > 0
//     B7 response status TLM_INCOMPLETE_RESPONSE
//     B8 DMI allowed reset to false
//     B9 with a memory manager, a reference count > 0
//   target, on return from b_transport
//     T1 response status set (not TLM_INCOMPLETE_RESPONSE)
//     T2 command, address, data pointer, data length, byte enables, streaming width unchanged
//   transport_dbg
//     D1 command READ, WRITE or IGNORE;  D2 data pointer set when length > 0
//     D3 the target returns at most the data length;  D4 command, address, pointer, length unchanged
//   get_direct_mem_ptr
//     M1 command READ or WRITE;  M2 the tlm_dmi passed in is in its initial state
//     M3 a grant covers the requested address, has a pointer and grants some access;
//        a refusal grants none
//     M4 start <= end
//   invalidate_direct_mem_ptr (backward)
//     I1 start <= end
//
// Error responses are counted, not reported: answering an error is legal,
// and what the initiator makes of it is the initiator's test.
#pragma once
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/simple_target_socket.h>

#include "rbcd/tlm/bus.h"

namespace rbcd {

class protocol_checker : public sc_core::sc_module {
public:
    tlm_utils::simple_target_socket<protocol_checker, kBusWidth> target;         // bind the initiator here
    tlm_utils::simple_initiator_socket<protocol_checker, kBusWidth> initiator;   // and this to the target

    struct counts_t {
        std::uint64_t b_transports = 0, error_responses = 0, debug_calls = 0, dmi_requests = 0, dmi_grants = 0,
                      invalidations = 0;
    };

    // fatal: also raise each violation as an SC_ERROR report (message type
    // "rbcd/protocol_checker") when it happens, which by default throws.
    explicit protocol_checker(sc_core::sc_module_name name, bool fatal = false);

    // "B7 b_transport at 0x80000000: response status TLM_OK_RESPONSE on entry", one per violation.
    const std::vector<std::string>& violations() const { return violations_; }
    const counts_t& counts() const { return counts_; }

private:
    void b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& delay);
    unsigned int transport_dbg(tlm::tlm_generic_payload& t);
    bool get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& dmi);
    void invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end);
    void violation(const char* rule, const char* call, std::uint64_t address, const std::string& what);

    bool fatal_;
    std::set<const tlm::tlm_generic_payload*> in_flight_;
    std::vector<std::string> violations_;
    counts_t counts_;
};

} // namespace rbcd
