// Energy of the unit: per-event dynamic energy from the blocks' counters and
// per-block leakage over the simulated time, with the [energy] section's
// figures (docs/energy.md gives every formula and default).
//
//   const EnergyCosts k = energy_costs(cfg);        // pJ per event, from the configuration
//   const Activity a = activity_of(sys);            // event counts after the run
//   const EnergyReport e = energy_of(k, a, cycles); // pJ per block
//
// Per frame: FrameEnergyProbe snapshots the counters at each frame boundary:
// the feed-side blocks (input queue, sorter, the sorter's bank accesses) when
// the feed ends the frame, the unit-side blocks (tester, its bank reads, output
// buffer, memory) when the unit has the frame's records in memory and read back.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "common/config.h"
#include "hw/collision_sink.h"

namespace rbcd {

class rbcd_system;

// Energy of one event of each kind (pJ), and the leakage (mW) of each block.
struct EnergyCosts {
    std::uint64_t bank_bits = 0;          // one ZEB bank: lists x M x element width
    unsigned row_bits = 0;                // one list row: M x element width
    double sram_scale = 1.0;              // sqrt(bank_bits / 65536)
    double row_read_pj = 0, row_write_pj = 0;
    unsigned queue_entry_bits = 0;        // pixel index + element
    double queue_write_pj = 0;
    unsigned key_bits = 0;                // sorter comparator width
    double comparator_pj = 0;             // one key comparator firing
    double mux_element_pj = 0;            // one element moved (shifted or placed) by the muxes
    double stack_push_pj = 0;             // one FF-stack entry written (id + matched bit)
    double stack_match_pj = 0;            // the matched bit set
    double id_compare_pj = 0;             // one id equality comparator firing
    double buffer_record_pj = 0;          // one 16-byte record written into the output buffer
    double memory_byte_pj = 0;
    // Leakage, mW.
    double bank_leakage_mw = 0;           // each bank
    double queue_leakage_mw = 0, sorter_leakage_mw = 0, tester_leakage_mw = 0, buffer_leakage_mw = 0;
    std::uint64_t queue_bits = 0, sorter_bits = 0, tester_bits = 0, buffer_bits = 0;   // storage, for the split
    unsigned banks = 0;
    double period_ns = 0;
};

EnergyCosts energy_costs(const SimConfig& cfg);

// Event counts. Bank reads and writes per bank for the totals; per frame only
// their sums (all banks cost the same per access).
struct Activity {
    std::uint64_t queue_writes = 0;       // fragments entering the input queue
    std::uint64_t comparator_activations = 0;
    std::uint64_t mux_moves = 0;          // elements shifted + new elements placed
    std::uint64_t sorter_row_reads = 0, row_writes = 0;
    std::uint64_t tester_row_reads = 0;
    std::uint64_t stack_pushes = 0, stack_matches = 0, id_compares = 0;
    std::uint64_t buffer_records = 0;
    std::uint64_t memory_bytes = 0;       // through b_transport (the unit's writes)
    std::vector<std::uint64_t> bank_reads, bank_writes;   // totals only; empty per frame
    Activity operator-(const Activity& o) const;   // per-bank vectors dropped
};

Activity activity_of(const rbcd_system& sys);

struct BlockEnergy {
    std::string name;
    double dynamic_pj = 0, leakage_pj = 0;
    double total_pj() const { return dynamic_pj + leakage_pj; }
};

struct EnergyReport {
    std::vector<BlockEnergy> blocks;      // input_queue, zeb_bank<i> (or zeb), insertion_sorter, ...
    double dynamic_pj = 0, leakage_pj = 0;
    double total_pj() const { return dynamic_pj + leakage_pj; }
    const BlockEnergy* find(const std::string& name) const;
};

// `cycles`: the time the leakage runs over. Per-bank blocks when the activity
// has per-bank counts, else one "zeb" block for all banks.
EnergyReport energy_of(const EnergyCosts& k, const Activity& a, std::uint64_t cycles);

// Snapshots the counters at frame boundaries, for per-frame energy.
class FrameEnergyProbe {
public:
    explicit FrameEnergyProbe(const rbcd_system& sys);
    // From the feed's on_frame hook: frame `n` begins, so the feed is done with n-1.
    void on_feed_frame(std::uint64_t n);
    // The unit starts frame n: everything of n-1 is in memory and read back.
    // Add unit_frames() to the system's collision sink (a TeeSink) to have it called.
    void on_unit_frame(std::uint64_t n);
    CollisionSink& unit_frames() { return sink_; }

    // After the run: activity of each feed frame (sums to the totals).
    std::vector<Activity> frames() const;
    bool unit_boundaries_seen() const { return unit_seen_; }

private:
    struct Sink final : CollisionSink {
        FrameEnergyProbe* probe = nullptr;
        void frame(std::uint64_t n) override { probe->on_unit_frame(n); }
        void hit(const HitRecord&) override {}
        void overflow(const OverflowRecord&) override {}
    };
    const rbcd_system& sys_;
    Sink sink_;
    std::vector<Activity> feed_snaps_, unit_snaps_;   // cumulative at the end of frame i
    std::uint64_t feed_calls_ = 0, unit_calls_ = 0;
    bool unit_seen_ = false;
};

} // namespace rbcd
