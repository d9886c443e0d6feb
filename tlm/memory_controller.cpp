#include "rbcd/tlm/memory_controller.h"

#include <algorithm>
#include <cstring>
#include <limits>
#include <string>

#include "rbcd/common/errors.h"

namespace rbcd {

using sc_core::sc_time;
using tlm::tlm_generic_payload;

namespace {

// splitmix64: tiny, full-period and identical on every platform, unlike the
// std distributions whose output is left to the library implementation.
std::uint64_t splitmix64(std::uint64_t& state) {
    std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

} // namespace

memory_controller::memory_controller(sc_core::sc_module_name name, const MemoryConfig& cfg,
                                     sc_time clock_period)
    : sc_core::sc_module(name),
      unit_port("unit_port"),
      host_port("host_port"),
      base_(cfg.base),
      latency_min_(cfg.latency_min),
      latency_max_(cfg.latency_max),
      bytes_per_cycle_(cfg.bytes_per_cycle),
      period_ticks_(clock_period.value()),
      seed_(cfg.seed),
      prng_state_(cfg.seed) {
    const std::string who = std::string(this->name()) + ": ";
    // Checked here, once, so that b_transport can divide and index freely.
    if (period_ticks_ == 0) throw InputError(who + "clock period must be positive");
    if (cfg.bytes_per_cycle == 0) throw InputError(who + "memory.bytes_per_cycle must be positive");
    if (cfg.latency_min > cfg.latency_max)
        throw InputError(who + "memory.latency_min exceeds memory.latency_max");
    if (cfg.size_bytes == 0) throw InputError(who + "memory.size_bytes must be positive");
    // base + size - 1 is the last address; it must still be a 64-bit address.
    if (cfg.size_bytes - 1 > std::numeric_limits<std::uint64_t>::max() - cfg.base)
        throw InputError(who + "memory mapping extends past the 64-bit address space");
    if (cfg.size_bytes > std::numeric_limits<std::size_t>::max()) throw std::bad_alloc();
    store_.reset(static_cast<unsigned char*>(std::calloc(static_cast<std::size_t>(cfg.size_bytes), 1)));
    if (!store_) throw std::bad_alloc();
    size_ = cfg.size_bytes;

    for (auto* port : {&unit_port, &host_port}) {
        port->register_b_transport(this, &memory_controller::b_transport);
        port->register_transport_dbg(this, &memory_controller::transport_dbg);
        port->register_get_direct_mem_ptr(this, &memory_controller::get_direct_mem_ptr);
    }
}

bool memory_controller::in_map(std::uint64_t address, std::uint64_t length) const {
    // Written as differences so that address + length never has to be formed:
    // a request near 2^64 would otherwise wrap around into the mapping.
    if (address < base_) return false;
    const std::uint64_t offset = address - base_;
    return offset < size_ && length <= size_ - offset;
}

tlm::tlm_response_status memory_controller::check(const tlm_generic_payload& t) const {
    // Nothing else can be judged about a transaction that carries no data.
    if (t.get_data_length() == 0 || t.get_data_ptr() == nullptr) return tlm::TLM_GENERIC_ERROR_RESPONSE;
    if (!t.is_read() && !t.is_write()) return tlm::TLM_COMMAND_ERROR_RESPONSE;
    if (!in_map(t.get_address(), t.get_data_length())) return tlm::TLM_ADDRESS_ERROR_RESPONSE;
    if (t.get_byte_enable_ptr() != nullptr) return tlm::TLM_BYTE_ENABLE_ERROR_RESPONSE;
    // A narrower streaming width would mean a FIFO-style burst to one window.
    if (t.get_streaming_width() < t.get_data_length()) return tlm::TLM_BURST_ERROR_RESPONSE;
    return tlm::TLM_OK_RESPONSE;
}

void memory_controller::reseed_for_frame(std::uint64_t frame) {
    // Frame 0 keeps memory.seed itself; others mix the frame number in.
    std::uint64_t s = seed_ ^ (frame * 0xd1b54a32d192ed03ull);
    prng_state_ = frame == 0 ? seed_ : splitmix64(s);
}

std::uint64_t memory_controller::draw_latency() {
    // Drawn even when min == max so that a seed names the same stream for any
    // latency range; the modulo bias over a span of a few hundred is ~1e-17.
    const std::uint64_t span = latency_max_ - latency_min_ + 1;
    return latency_min_ + splitmix64(prng_state_) % span;
}

void memory_controller::b_transport(tlm_generic_payload& t, sc_time& delay) {
    const tlm::tlm_response_status status = check(t);
    if (status != tlm::TLM_OK_RESPONSE) {
        // Refused before touching anything: no channel time, no latency draw,
        // and the delay stays as annotated since no time was spent here.
        ++stats_.errors;
        t.set_response_status(status);
        return;
    }

    const std::uint64_t offset = t.get_address() - base_;
    const std::uint64_t length = t.get_data_length();
    // LT: data moves at call time; only the timing is deferred to `delay`.
    if (t.is_read()) {
        std::memcpy(t.get_data_ptr(), store_.get() + offset, length);
        ++stats_.reads;
        stats_.bytes_read += length;
    } else {
        std::memcpy(store_.get() + offset, t.get_data_ptr(), length);
        ++stats_.writes;
        stats_.bytes_written += length;
    }

    const sc_time now = sc_core::sc_time_stamp();
    // An initiator running behind another (temporal decoupling) may arrive
    // "before" a request already queued; the channel serves in call order.
    const std::uint64_t arrival = std::max(to_cycles(now + delay), last_arrival_);
    last_arrival_ = arrival;
    const std::uint64_t start = std::max(arrival, channel_free_);
    const std::uint64_t beats = (length + bytes_per_cycle_ - 1) / bytes_per_cycle_;
    const std::uint64_t end = start + beats;
    channel_free_ = end;
    const std::uint64_t latency = draw_latency();
    const std::uint64_t completion = end + latency;
    last_completion_ = completion;

    stats_.busy_cycles += beats;
    stats_.queue_cycles += start - arrival;
    stats_.latency_cycles += latency;
    stats_.max_completion_cycle = std::max(stats_.max_completion_cycle, completion);

    // completion >= floor(arrival) + 1 cycle > now + delay >= now: never negative.
    if (vcd_) {
        vcd_->add_delta(vcd_in_flight_, arrival, +1);
        vcd_->add_delta(vcd_in_flight_, completion, -1);
        vcd_->set(vcd_channel_busy_, start, 1);
        vcd_->set(vcd_channel_busy_, end, 0);
    }

    delay = to_time(completion) - now;
    t.set_dmi_allowed(true);
    t.set_response_status(tlm::TLM_OK_RESPONSE);
}

unsigned int memory_controller::transport_dbg(tlm_generic_payload& t) {
    // Debug transport uses only command, address, data pointer and length; it
    // moves what lies inside the mapping and reports how many bytes that was.
    const std::uint64_t address = t.get_address();
    if ((!t.is_read() && !t.is_write()) || t.get_data_ptr() == nullptr || t.get_data_length() == 0) {
        t.set_response_status(t.get_data_length() == 0 || t.get_data_ptr() == nullptr
                                  ? tlm::TLM_GENERIC_ERROR_RESPONSE
                                  : tlm::TLM_COMMAND_ERROR_RESPONSE);
        return 0;
    }
    if (!in_map(address, 1)) {
        t.set_response_status(tlm::TLM_ADDRESS_ERROR_RESPONSE);
        return 0;
    }
    const std::uint64_t offset = address - base_;
    const std::uint64_t n = std::min<std::uint64_t>(t.get_data_length(), size_ - offset);
    if (t.is_read())
        std::memcpy(t.get_data_ptr(), store_.get() + offset, n);
    else
        std::memcpy(store_.get() + offset, t.get_data_ptr(), n);
    ++stats_.debug_accesses;
    t.set_response_status(tlm::TLM_OK_RESPONSE);
    return static_cast<unsigned int>(n);
}

bool memory_controller::get_direct_mem_ptr(tlm_generic_payload& t, tlm::tlm_dmi& dmi) {
    const std::uint64_t address = t.get_address();
    if (!in_map(address, 1)) {
        // A refusal names the range it covers so the initiator stops asking
        // for any address in the same hole.
        dmi.set_granted_access(tlm::tlm_dmi::DMI_ACCESS_NONE);
        if (address < base_) {
            dmi.set_start_address(0);
            dmi.set_end_address(base_ - 1);
        } else {
            dmi.set_start_address(base_ + size_);
            dmi.set_end_address(std::numeric_limits<std::uint64_t>::max());
        }
        return false;
    }
    dmi.set_dmi_ptr(store_.get());
    dmi.set_start_address(base_);
    dmi.set_end_address(base_ + (size_ - 1));
    dmi.set_granted_access(tlm::tlm_dmi::DMI_ACCESS_READ_WRITE);
    // A DMI access bypasses the channel queue, so the only honest single
    // figure is the worst case of one beat: 1 transfer cycle + latency_max.
    dmi.set_read_latency(to_time(1 + latency_max_));
    dmi.set_write_latency(to_time(1 + latency_max_));
    ++stats_.dmi_grants;
    return true;
}

} // namespace rbcd
