#include "rbcd/hw/output_buffer.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "rbcd/common/errors.h"

namespace rbcd {

output_buffer::output_buffer(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk,
                             unit_host_if& host)
    : sc_module(name),
      mem("mem"),
      clk_(clk),
      host_(host),
      capacity_(cfg.output.buffer_records),
      burst_(cfg.output.burst_records),
      max_outstanding_(cfg.output.max_outstanding),
      region_addr_(cfg.memory.base + cfg.output.region_offset),
      region_bytes_(cfg.output.region_bytes),
      region_free_(cfg.output.regions(), 0),
      data_(std::size_t(cfg.output.burst_records) * kRecordBytes) {
    pending_.reserve(capacity_);
    inflight_.reserve(max_outstanding_);
}

void output_buffer::retire(std::uint64_t cycle) {
    // Latencies are drawn per transaction, so completions can overtake each other.
    auto it = std::remove_if(inflight_.begin(), inflight_.end(), [&](const Inflight& w) {
        if (w.done > cycle) return false;
        inflight_records_ -= w.records;
        return true;
    });
    inflight_.erase(it, inflight_.end());
}

std::uint64_t output_buffer::issue(std::uint64_t cycle, unsigned n) {
    std::uint64_t t = std::max(cycle, engine_cycle_);
    const std::uint64_t bytes = std::uint64_t(n) * kRecordBytes;
    if (write_offset_ + bytes > region_bytes_) {
        // The CPU reads only what has landed: let every write complete first.
        // Not retired here: slots free only as the tester's own time passes them.
        std::uint64_t all_done = t;
        for (const auto& w : inflight_) all_done = std::max(all_done, w.done);
        ++stats_.region_full_events;
        t = switch_region(all_done, true);
    }
    // The engine's time t may run ahead of the tester's: count the writes still
    // in flight at t without retiring them, so that slots stay held for the
    // tester until its own time passes their completion.
    pending_done_.clear();
    for (const auto& w : inflight_)
        if (w.done > t) pending_done_.push_back(w.done);
    if (pending_done_.size() >= max_outstanding_) {
        std::sort(pending_done_.begin(), pending_done_.end());
        const std::uint64_t slot_free = pending_done_[pending_done_.size() - max_outstanding_];
        stats_.outstanding_stall_cycles += slot_free - t;
        t = slot_free;
    }

    for (unsigned i = 0; i < n; ++i) pending_[i].store(&data_[std::size_t(i) * kRecordBytes]);
    gp_.set_command(tlm::TLM_WRITE_COMMAND);
    gp_.set_address(region_addr_ + region_ * region_bytes_ + write_offset_);
    gp_.set_data_ptr(data_.data());
    gp_.set_data_length(static_cast<unsigned>(bytes));
    gp_.set_streaming_width(static_cast<unsigned>(bytes));
    gp_.set_byte_enable_ptr(nullptr);
    gp_.set_byte_enable_length(0);
    gp_.set_dmi_allowed(false);
    gp_.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
    // Loosely timed: the annotated delay carries the local offset from sc_time_stamp().
    sc_core::sc_time delay = clk_.time(t - clk_.now());
    mem->b_transport(gp_, delay);
    // Any status but OK is the run's failure (TLM_INCOMPLETE_RESPONSE too: the
    // target did not answer); docs/embedding.md.
    if (!gp_.is_response_ok()) {
        failure_ = std::string(name()) + ": memory write of " + std::to_string(bytes) + " bytes at " +
                   hex_address(gp_.get_address()) + " failed: " + gp_.get_response_string();
        throw RunError(failure_);
    }
    // Rounded up: a target's latency need not be whole cycles (41 ns at 400 MHz),
    // and records_ready promises the write is complete by its cycle.
    const std::uint64_t done = clk_.cycles_up(sc_core::sc_time_stamp() + delay);

    if (vcd_) {
        vcd_->add_delta(vcd_in_flight_, t, +1);
        vcd_->add_delta(vcd_in_flight_, done, -1);
        vcd_->add_delta(vcd_occupancy_, done, -static_cast<std::int64_t>(n));
        vcd_->set(vcd_offset_, t, write_offset_ + bytes);
    }
    if (observer_) observer_->records_written({gp_.get_address(), bytes, n, t, done});
    inflight_.push_back({done, n});
    inflight_records_ += n;
    pending_.erase(pending_.begin(), pending_.begin() + n);
    write_offset_ += bytes;
    engine_cycle_ = t;
    ++stats_.bursts;
    stats_.bytes += bytes;
    stats_.write_latency_cycles += done - t;
    return t;
}

std::uint64_t output_buffer::push(const MemRecord& r, std::uint64_t cycle) {
    std::uint64_t t = cycle;
    retire(t);
    while (occupancy() >= capacity_) {
        // Full means every slot is pending or in flight; pending never reaches a
        // burst without being issued, so something is in flight here.
        std::uint64_t first_done = ~0ull;
        for (const auto& w : inflight_) first_done = std::min(first_done, w.done);
        if (first_done == ~0ull) first_done = issue(t, static_cast<unsigned>(pending_.size()));
        stats_.full_stall_cycles += std::max(first_done, t) - t;
        t = std::max(first_done, t);
        retire(t);
    }
    pending_.push_back(r);
    ++stats_.records;
    if (vcd_) vcd_->add_delta(vcd_occupancy_, t, +1);
    stats_.max_occupancy = std::max<std::uint64_t>(stats_.max_occupancy, occupancy());
    if (pending_.size() >= burst_) issue(t, burst_);
    return t;
}

std::uint64_t output_buffer::flush(std::uint64_t cycle) {
    std::uint64_t t = cycle;
    while (!pending_.empty()) {
        const unsigned n = static_cast<unsigned>(std::min<std::size_t>(pending_.size(), burst_));
        issue(t, n);
    }
    std::uint64_t all_done = std::max(t, engine_cycle_);
    for (const auto& w : inflight_) all_done = std::max(all_done, w.done);
    retire(all_done);
    return all_done;
}

std::uint64_t output_buffer::switch_region(std::uint64_t all_done, bool because_full) {
    region_free_[region_] = host_.records_ready(region_addr_ + region_ * region_bytes_, write_offset_, all_done, because_full);
    region_ = (region_ + 1) % static_cast<unsigned>(region_free_.size());
    write_offset_ = 0;
    const std::uint64_t ready = std::max(all_done, region_free_[region_]);
    stats_.region_wait_cycles += ready - all_done;
    if (vcd_) {
        vcd_->set(vcd_offset_, ready, 0);
        vcd_->set(vcd_region_, ready, region_);
    }
    return ready;
}

std::uint64_t output_buffer::end_frame(std::uint64_t cycle) {
    return switch_region(flush(cycle), false);
}

} // namespace rbcd
