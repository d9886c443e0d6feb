// Cycle <-> sc_time conversion. Blocks compute their timelines in integer
// cycles and touch sc_time only to synchronise, so the conversion is exact.
#pragma once
#include <cstdint>
#include <systemc>

#include "rbcd/common/stat_counters.h"

namespace rbcd {

class Clocking {
public:
    explicit Clocking(std::uint64_t period_ps)
        : period_ps_(period_ps), period_(static_cast<double>(period_ps), sc_core::SC_PS), ticks_(period_.value()) {}
    std::uint64_t period_ps() const { return period_ps_; }
    const sc_core::sc_time& period() const { return period_; }
    sc_core::sc_time time(std::uint64_t cycles) const { return sc_core::sc_time::from_value(cycles * ticks_); }
    std::uint64_t cycles(const sc_core::sc_time& t) const { return t.value() / ticks_; }
    // The first cycle boundary at or after t: when something that ends at t
    // (a target's annotated completion, not always a whole number of periods)
    // is over.
    std::uint64_t cycles_up(const sc_core::sc_time& t) const { return (t.value() + ticks_ - 1) / ticks_; }
    std::uint64_t now() const { return cycles(sc_core::sc_time_stamp()); }
    // Suspends the calling thread until cycle `c` (no-op if already there).
    void wait_until(std::uint64_t c) const {
        const std::uint64_t n = now();
        if (c > n) sc_core::wait(time(c - n));
    }

private:
    std::uint64_t period_ps_;
    sc_core::sc_time period_;
    std::uint64_t ticks_;   // period in kernel time resolution units
};

} // namespace rbcd
