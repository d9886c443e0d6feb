#include "rbcd/hw/host_reader.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "rbcd/common/errors.h"

namespace rbcd {

host_reader::host_reader(sc_core::sc_module_name name, const SimConfig& cfg, CollisionSink& sink)
    : sc_module(name), mem("mem"), sink_(sink), readback_cycles_(cfg.host.readback_cycles) {
    mem.register_invalidate_direct_mem_ptr(this, &host_reader::invalidate_direct_mem_ptr);
}

void host_reader::invalidate_direct_mem_ptr(sc_dt::uint64 start, sc_dt::uint64 end) {
    // Any overlap drops the whole grant: a pointer is never used past its range.
    if (dmi_valid_ && start <= dmi_.get_end_address() && end >= dmi_.get_start_address()) dmi_valid_ = false;
}

namespace {

// Every attribute the target may look at is set before each call.
void prepare_read(tlm::tlm_generic_payload& gp, std::uint64_t address, std::uint64_t n, unsigned char* dst) {
    gp.set_command(tlm::TLM_READ_COMMAND);
    gp.set_address(address);
    gp.set_data_ptr(dst);
    gp.set_data_length(static_cast<unsigned>(n));
    gp.set_streaming_width(static_cast<unsigned>(n));
    gp.set_byte_enable_ptr(nullptr);
    gp.set_byte_enable_length(0);
    gp.set_dmi_allowed(false);
    gp.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
}

} // namespace

bool host_reader::read(std::uint64_t address, std::uint64_t n, unsigned char* dst) {
    bool used_dmi = false;
    // A refusal names the range it covers: not asked again inside it in this read.
    std::uint64_t no_dmi_start = 1, no_dmi_end = 0;
    while (n > 0) {
        const bool covered =
            dmi_valid_ && dmi_.get_start_address() <= address && address <= dmi_.get_end_address();
        if (!covered && !(no_dmi_start <= address && address <= no_dmi_end)) {
            prepare_read(gp_, address, n, dst);
            dmi_.init();
            const bool granted = mem->get_direct_mem_ptr(gp_, dmi_);
            dmi_valid_ = granted && dmi_.is_read_allowed() && dmi_.get_dmi_ptr() != nullptr &&
                         dmi_.get_start_address() <= address && address <= dmi_.get_end_address();
            if (!dmi_valid_) {
                const bool names_range = dmi_.get_start_address() <= address && address <= dmi_.get_end_address();
                // (One that names no range around the address: none for the rest of this read.)
                no_dmi_start = names_range ? dmi_.get_start_address() : address;
                no_dmi_end = names_range ? dmi_.get_end_address() : ~std::uint64_t(0);
            }
        }
        if (dmi_valid_ && dmi_.get_start_address() <= address && address <= dmi_.get_end_address()) {
            // Only inside the granted range: the rest of the read goes round again.
            const std::uint64_t k = std::min<std::uint64_t>(n, dmi_.get_end_address() - address + 1);
            std::memcpy(dst, dmi_.get_dmi_ptr() + (address - dmi_.get_start_address()), k);
            used_dmi = true;
            address += k;
            dst += k;
            n -= k;
            continue;
        }
        // No pointer for this address: debug transport, up to where a pointer
        // might be had again; it may move fewer bytes than asked (e.g. at the
        // end of a target's range), the rest going round again.
        std::uint64_t k = n;
        if (no_dmi_start <= address && address <= no_dmi_end) k = std::min<std::uint64_t>(n, no_dmi_end - address + 1);
        prepare_read(gp_, address, k, dst);
        const unsigned got = mem->transport_dbg(gp_);
        if (got == 0 || got > k)
            throw RunError(std::string(name()) + ": debug read of " + std::to_string(k) + " bytes at " +
                           hex_address(address) + " returned " + std::to_string(got) + " bytes");
        address += got;
        dst += got;
        n -= got;
    }
    return used_dmi;
}

std::uint64_t host_reader::records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
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
    if (!keep_dmi_) dmi_valid_ = false;
    if (read(address, bytes, buf_.data())) ++stats_.dmi_reads;
    if (!keep_dmi_) dmi_valid_ = false;

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
            throw RunError(std::string(name()) + ": corrupt record in the output region at " +
                           hex_address(address + off));
        }
    }
    stats_.bytes += bytes;
    return busy_until_;
}

} // namespace rbcd
