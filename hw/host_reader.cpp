#include "hw/host_reader.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace rbcd {

host_reader::host_reader(sc_core::sc_module_name name, const SimConfig& cfg, CollisionSink& sink)
    : sc_module(name),
      mem("mem"),
      sink_(sink),
      readback_cycles_(cfg.host.readback_cycles) {}

std::uint64_t host_reader::read_back(std::uint64_t region_addr, std::uint64_t bytes, std::uint64_t cycle,
                                     bool because_full) {
    ++stats_.readbacks;
    if (because_full) ++stats_.full_readbacks;
    // One CPU: a readback starts when the previous one is over.
    const std::uint64_t start = std::max(cycle, busy_until_);
    stats_.wait_cycles += start - cycle;
    busy_until_ = start + readback_cycles_;
    if (bytes == 0) return busy_until_;
    buf_.resize(bytes);

    // DMI first: the CPU reading through the cache costs the unit nothing but
    // the readback time charged below.
    tlm::tlm_generic_payload gp;
    gp.set_command(tlm::TLM_READ_COMMAND);
    gp.set_address(region_addr);
    gp.set_data_length(static_cast<unsigned>(bytes));
    gp.set_data_ptr(buf_.data());
    gp.set_streaming_width(static_cast<unsigned>(bytes));
    tlm::tlm_dmi dmi;
    bool done = false;
    if (mem->get_direct_mem_ptr(gp, dmi) && dmi.is_read_allowed() && dmi.get_start_address() <= region_addr &&
        dmi.get_end_address() >= region_addr + bytes - 1) {
        std::memcpy(buf_.data(), dmi.get_dmi_ptr() + (region_addr - dmi.get_start_address()), bytes);
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
    return busy_until_;
}

} // namespace rbcd
