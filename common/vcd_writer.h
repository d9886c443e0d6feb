// A VCD writer for computed timing. Blocks compute their timelines ahead of
// sc_time_stamp() and report value changes at future cycles, out of order
// across blocks; SystemC's own tracer samples only at kernel time steps and
// cannot open a window, so the model writes its waveforms itself.
//
//   VcdWriter vcd(out, period_ps, start, end);
//   auto busy = vcd.add("rbcd.zoverlap_tester", "busy", 1);   // before the first flush
//   vcd.set(busy, 120, 1);  vcd.set(busy, 180, 0);
//   auto occ = vcd.add("rbcd.output_buffer", "occupancy", 16);
//   vcd.add_delta(occ, 130, +1); ...                             // counters as +/- events
//   vcd.flush_before(now);   // events before `now` are final: written, then dropped
//   vcd.finish(end_cycle);
//
// Within one cycle the last change of a signal wins and only the final value is
// written. Changes outside [start, end] are applied but not written; the window
// opens with a $dumpvars of every signal's value.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace rbcd {

class VcdWriter {
public:
    using Sig = unsigned;
    using Output = std::function<void(const std::string&)>;

    VcdWriter(Output out, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle,
              std::string version = "rbcd-tlm");

    Sig add(const std::string& scope, const std::string& name, unsigned width, std::uint64_t initial = 0);
    void set(Sig s, std::uint64_t cycle, std::uint64_t value) { events_.push_back({cycle, seq_++, s, false, value}); }
    void add_delta(Sig s, std::uint64_t cycle, std::int64_t delta) {
        events_.push_back({cycle, seq_++, s, true, static_cast<std::uint64_t>(delta)});
    }
    void flush_before(std::uint64_t cycle);
    void finish(std::uint64_t end_cycle);
    std::size_t signals() const { return sigs_.size(); }

private:
    struct Signal {
        std::string scope, name, code;
        unsigned width;
        std::uint64_t value, written;
        bool dirty;
    };
    struct Event {
        std::uint64_t cycle, seq;
        Sig sig;
        bool delta;
        std::uint64_t value;
    };
    void header();
    void open_window(std::uint64_t cycle);
    void write_value(const Signal& s);
    void emit(std::uint64_t cycle);
    void stamp(std::uint64_t cycle);

    Output out_;
    std::uint64_t period_ps_, start_, end_;
    std::string version_;
    std::vector<Signal> sigs_;
    std::vector<Event> events_;
    std::vector<Sig> touched_;
    std::uint64_t seq_ = 0;
    bool header_done_ = false, window_open_ = false, finished_ = false, stamped_any_ = false;
    std::uint64_t last_stamp_ = 0;
    std::string buf_;
};

} // namespace rbcd
