#include "rbcd/tlm/protocol_checker.h"

#include "rbcd/common/errors.h"

namespace rbcd {

namespace {

bool valid_command(tlm::tlm_command c) {
    return c == tlm::TLM_READ_COMMAND || c == tlm::TLM_WRITE_COMMAND || c == tlm::TLM_IGNORE_COMMAND;
}

// The attributes a target must leave as it found them.
struct Snapshot {
    tlm::tlm_command command;
    std::uint64_t address;
    unsigned char* data;
    unsigned length, streaming_width, be_length;
    unsigned char* be;
    explicit Snapshot(const tlm::tlm_generic_payload& t)
        : command(t.get_command()),
          address(t.get_address()),
          data(t.get_data_ptr()),
          length(t.get_data_length()),
          streaming_width(t.get_streaming_width()),
          be_length(t.get_byte_enable_length()),
          be(t.get_byte_enable_ptr()) {}
    // The first attribute that differs, or nullptr.
    const char* changed(const tlm::tlm_generic_payload& t, bool debug) const {
        if (t.get_command() != command) return "command";
        if (t.get_address() != address) return "address";
        if (t.get_data_ptr() != data) return "data pointer";
        if (t.get_data_length() != length) return "data length";
        if (debug) return nullptr;
        if (t.get_streaming_width() != streaming_width) return "streaming width";
        if (t.get_byte_enable_ptr() != be) return "byte enable pointer";
        if (t.get_byte_enable_length() != be_length) return "byte enable length";
        return nullptr;
    }
};

} // namespace

protocol_checker::protocol_checker(sc_core::sc_module_name name, bool fatal)
    : sc_module(name), target("target"), initiator("initiator"), fatal_(fatal) {
    target.register_b_transport(this, &protocol_checker::b_transport);
    target.register_transport_dbg(this, &protocol_checker::transport_dbg);
    target.register_get_direct_mem_ptr(this, &protocol_checker::get_direct_mem_ptr);
    initiator.register_invalidate_direct_mem_ptr(this, &protocol_checker::invalidate_direct_mem_ptr);
}

void protocol_checker::violation(const char* rule, const char* call, std::uint64_t address, const std::string& what) {
    violations_.push_back(std::string(rule) + " " + call + " at " + hex_address(address) + ": " + what);
    if (fatal_) SC_REPORT_ERROR("rbcd/protocol_checker", (std::string(name()) + ": " + violations_.back()).c_str());
}

void protocol_checker::b_transport(tlm::tlm_generic_payload& t, sc_core::sc_time& delay) {
    ++counts_.b_transports;
    const std::uint64_t a = t.get_address();
    const char* call = "b_transport";
    const sc_core::sc_process_handle proc = sc_core::sc_get_current_process_handle();
    if (!proc.valid() || proc.proc_kind() != sc_core::SC_THREAD_PROC_)
        violation("B1", call, a, "not called from an SC_THREAD");
    const bool reused = !in_flight_.insert(&t).second;
    if (reused) violation("B2", call, a, "payload already in flight (its earlier b_transport has not returned)");
    if (!valid_command(t.get_command())) violation("B3", call, a, "command is not READ, WRITE or IGNORE");
    if (t.get_data_ptr() == nullptr || t.get_data_length() == 0)
        violation("B4", call, a, "data pointer null or data length 0");
    if (t.get_streaming_width() == 0 || t.get_streaming_width() != t.get_data_length())
        violation("B5", call, a,
                  "streaming width " + std::to_string(t.get_streaming_width()) + " for data length " +
                      std::to_string(t.get_data_length()));
    if (t.get_byte_enable_ptr() != nullptr && t.get_byte_enable_length() == 0)
        violation("B6", call, a, "byte enable pointer set with byte enable length 0");
    if (t.get_response_status() != tlm::TLM_INCOMPLETE_RESPONSE)
        violation("B7", call, a, "response status " + t.get_response_string() + " on entry");
    if (t.is_dmi_allowed()) violation("B8", call, a, "DMI allowed not reset to false");
    if (t.has_mm() && t.get_ref_count() == 0) violation("B9", call, a, "memory-managed payload with reference count 0");

    const Snapshot before(t);
    initiator->b_transport(t, delay);

    if (t.get_response_status() == tlm::TLM_INCOMPLETE_RESPONSE)
        violation("T1", call, a, "target returned TLM_INCOMPLETE_RESPONSE");
    else if (t.is_response_error())
        ++counts_.error_responses;
    if (const char* what = before.changed(t, false)) violation("T2", call, a, std::string("target changed the ") + what);
    if (!reused) in_flight_.erase(&t);
}

unsigned int protocol_checker::transport_dbg(tlm::tlm_generic_payload& t) {
    ++counts_.debug_calls;
    const std::uint64_t a = t.get_address();
    const char* call = "transport_dbg";
    if (!valid_command(t.get_command())) violation("D1", call, a, "command is not READ, WRITE or IGNORE");
    if (t.get_data_length() > 0 && t.get_data_ptr() == nullptr) violation("D2", call, a, "data pointer null");
    const Snapshot before(t);
    const unsigned n = initiator->transport_dbg(t);
    if (n > before.length)
        violation("D3", call, a, "target returned " + std::to_string(n) + " for length " + std::to_string(before.length));
    if (const char* what = before.changed(t, true)) violation("D4", call, a, std::string("target changed the ") + what);
    return n;
}

bool protocol_checker::get_direct_mem_ptr(tlm::tlm_generic_payload& t, tlm::tlm_dmi& dmi) {
    ++counts_.dmi_requests;
    const std::uint64_t a = t.get_address();
    const char* call = "get_direct_mem_ptr";
    if (t.get_command() != tlm::TLM_READ_COMMAND && t.get_command() != tlm::TLM_WRITE_COMMAND)
        violation("M1", call, a, "command is not READ or WRITE");
    if (dmi.get_dmi_ptr() != nullptr || dmi.get_start_address() != 0 ||
        dmi.get_end_address() != ~sc_dt::uint64(0) || dmi.get_granted_access() != tlm::tlm_dmi::DMI_ACCESS_NONE)
        violation("M2", call, a, "tlm_dmi not in its initial state (call init() before each request)");
    const bool granted = initiator->get_direct_mem_ptr(t, dmi);
    if (dmi.get_start_address() > dmi.get_end_address()) violation("M4", call, a, "range start after its end");
    if (granted) {
        ++counts_.dmi_grants;
        if (a < dmi.get_start_address() || a > dmi.get_end_address())
            violation("M3", call, a, "granted range does not contain the address");
        if (dmi.get_dmi_ptr() == nullptr) violation("M3", call, a, "granted with a null pointer");
        if (dmi.get_granted_access() == tlm::tlm_dmi::DMI_ACCESS_NONE)
            violation("M3", call, a, "granted with no access");
    } else if (dmi.get_granted_access() != tlm::tlm_dmi::DMI_ACCESS_NONE) {
        violation("M3", call, a, "refused but grants access");
    }
    return granted;
}

void protocol_checker::invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end) {
    ++counts_.invalidations;
    if (start > end) violation("I1", "invalidate_direct_mem_ptr", start, "range start after its end");
    target->invalidate_direct_mem_ptr(start, end);
}

} // namespace rbcd
