#include "hw/host_reader.h"

#include <cstring>
#include <stdexcept>

namespace rbcd {

host_reader::host_reader(sc_core::sc_module_name name, const SimConfig& cfg, CollisionSink& sink)
    : sc_module(name),
      mem("mem"),
      sink_(sink),
      region_addr_(cfg.memory.base + cfg.output.region_offset),
      readback_cycles_(cfg.host.readback_cycles) {}

std::uint64_t host_reader::read_back(std::uint64_t bytes, std::uint64_t cycle, bool because_full) {
    ++stats_.readbacks;
    if (because_full) ++stats_.full_readbacks;
    if (bytes == 0) return cycle + readback_cycles_;
    buf_.resize(bytes);

    // DMI first: the CPU reading through the cache costs the unit nothing but
    // the readback time charged below.
    tlm::tlm_generic_payload gp;
    gp.set_command(tlm::TLM_READ_COMMAND);
    gp.set_address(region_addr_);
    gp.set_data_length(static_cast<unsigned>(bytes));
    gp.set_data_ptr(buf_.data());
    gp.set_streaming_width(static_cast<unsigned>(bytes));
    tlm::tlm_dmi dmi;
    bool done = false;
    if (mem->get_direct_mem_ptr(gp, dmi) && dmi.is_read_allowed() && dmi.get_start_address() <= region_addr_ &&
        dmi.get_end_address() >= region_addr_ + bytes - 1) {
        std::memcpy(buf_.data(), dmi.get_dmi_ptr() + (region_addr_ - dmi.get_start_address()), bytes);
        ++stats_.dmi_reads;
        done = true;
    }
    if (!done) {
        gp.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
        if (mem->transport_dbg(gp) != bytes)
            throw std::runtime_error("host_reader: debug read of the output region failed");
    }

    for (std::uint64_t off = 0; off + kRecordBytes <= bytes; off += kRecordBytes) {
        const MemRecord r = MemRecord::load(&buf_[off]);
        ++stats_.records;
        switch (r.kind()) {
        case RecordKind::Hit:
            ++stats_.hit_records;
            sink_.hit(r.as_hit());
            break;
        case RecordKind::Overflow:
            ++stats_.overflow_records;
            sink_.overflow(r.as_overflow());
            break;
        default:
            throw std::runtime_error("host_reader: corrupt record in the output region at offset " +
                                     std::to_string(off));
        }
    }
    stats_.bytes += bytes;
    return cycle + readback_cycles_;
}

} // namespace rbcd
