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
//
// The same settled changes can go to another encoding instead of VCD text: a
// WaveEncoder (outputs/fst_writer.h writes FST) sees the same scopes, signals,
// times and values, so the two formats cannot drift apart.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace rbcd {

// Receives the writer's output in order: the definitions once (scopes nested,
// each signal once), then times (ps, increasing) each followed by the values
// that changed; dumpvars() brackets the window's opening values.
class WaveEncoder {
public:
    virtual ~WaveEncoder() = default;
    virtual void begin(const std::string& date, const std::string& version, std::uint64_t period_ps) = 0;
    virtual void scope(const std::string& name) = 0;
    virtual void upscope() = 0;
    virtual void var(unsigned sig, const std::string& name, unsigned width) = 0;
    virtual void end_definitions() = 0;
    virtual void time(std::uint64_t ps) = 0;
    virtual void dumpvars(bool /*begin*/) {}
    virtual void value(unsigned sig, unsigned width, std::uint64_t v) = 0;
    virtual void finish() = 0;
};

class VcdWriter {
public:
    using Sig = unsigned;
    using Output = std::function<void(const std::string&)>;

    VcdWriter(Output out, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle,
              std::string version = "rbcd-tlm");
    // The same recording, written through `enc` instead of as VCD text.
    VcdWriter(WaveEncoder& enc, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle,
              std::string version = "rbcd-tlm");

    Sig add(const std::string& scope, const std::string& name, unsigned width, std::uint64_t initial = 0);
    void set(Sig s, std::uint64_t cycle, std::uint64_t value) { events_.push_back({cycle, seq_++, s, false, value}); }
    void add_delta(Sig s, std::uint64_t cycle, std::int64_t delta) {
        events_.push_back({cycle, seq_++, s, true, static_cast<std::uint64_t>(delta)});
    }
    void flush_before(std::uint64_t cycle);
    void finish(std::uint64_t end_cycle);
    std::size_t signals() const { return sigs_.size(); }
    // Signal `s`'s scope, name and width, as added (the layout of a GTKWave save file).
    const std::string& scope_of(Sig s) const { return sigs_[s].scope; }
    const std::string& name_of(Sig s) const { return sigs_[s].name; }
    unsigned width_of(Sig s) const { return sigs_[s].width; }

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
    WaveEncoder* enc_ = nullptr;
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
