// Energy of the unit and of the GPU around it (docs/energy.md gives every
// formula, default and source).
//
// The unit: per-event dynamic energy from the blocks' counters, and per-block
// leakage over the time it is charged for (each frame's GPU time with the
// unit). The GPU: per shaded fragment, per rasterized fragment, per primitive
// set up and its tile-cache bytes, the colour buffer flushed per tile, and
// static power over the frame's time; computed for the baseline GPU and for
// the GPU with the unit, so that the normalized energy (paper, Figure 9b) is
// reported beside the normalized time.
//
//   const EnergyCosts k = energy_costs(cfg);         // per event, from the configuration
//   const Activity a = activity_of(sys);             // the unit's event counts so far
//   const EnergyReport e = energy_of(k, a, cycles);  // pJ per block
//   const double g = gpu_energy_pj(k, GpuWork{...}, cycles);
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/report/unit_counters.h"

namespace rbcd {

class rbcd_system;

// The ZEB macro's figures at its reference size (8 KiB, 32-byte rows).
struct ZebSramFigures {
    double read_pj, write_pj, leakage_mw;
};
ZebSramFigures zeb_sram_figures(ZebDevice d);

// Energy of one event of each kind (pJ), and the leakage (mW) of each block.
struct EnergyCosts {
    std::uint64_t bank_bits = 0;          // one ZEB bank: lists x M x element width
    unsigned row_bits = 0;                // one list row: M x element width
    double sram_scale = 1.0;              // (row_bits / 256) x sqrt(bank_bits / 65536), for accesses
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
    // The GPU.
    double gpu_fragment_pj = 0, gpu_raster_fragment_pj = 0, gpu_primitive_pj = 0;   // primitive incl. its tile-cache read
    double gpu_tile_flush_pj = 0, gpu_static_mw = 0;
};

EnergyCosts energy_costs(const SimConfig& cfg);

// The unit's event counts (cumulative, or a frame's difference).
struct Activity {
    std::uint64_t queue_writes = 0;       // fragments entering the input queue
    std::uint64_t comparator_activations = 0;
    std::uint64_t mux_moves = 0;          // elements shifted + new elements placed
    std::uint64_t sorter_row_reads = 0, row_writes = 0;
    std::uint64_t tester_row_reads = 0;
    std::uint64_t stack_pushes = 0, stack_matches = 0, id_compares = 0;
    std::uint64_t buffer_records = 0;
    std::uint64_t memory_bytes = 0;       // through b_transport (the unit's writes)
    std::vector<std::uint64_t> bank_reads, bank_writes;   // per bank; empty in a difference
    Activity operator-(const Activity& o) const;   // per-bank vectors dropped
};

Activity activity_of(const UnitCounters& c);
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

// What the GPU did in a frame, in one of its two versions.
struct GpuWork {
    std::uint64_t shaded = 0;       // fragments through the fragment processors
    std::uint64_t rasterized = 0;   // fragments the rasterizer produced
    std::uint64_t primitives = 0;   // primitives set up
    std::uint64_t tiles = 0;        // tiles rendered (colour buffer flushed)
};
// The GPU's own energy (pJ) for that work over `cycles` of frame time.
double gpu_energy_pj(const EnergyCosts& k, const GpuWork& w, std::uint64_t cycles);

} // namespace rbcd
