// The tile-based GPU's rasterizer (paper, Figure 3), driving the fragment
// processors and the RBCD unit from a fragment stream (trace or scene).
//
// Per tile, in rasterization order: gpu.tile_overhead_cycles, then the tile's
// primitives and fragments. A primitive's setup (gpu.setup_cycles_per_primitive)
// comes before its fragments; a trace gives only the counts (prims=, cprims=),
// so setups are spread evenly over the fragments they belong to: prims over
// the shaded ones (non-collisionable and collisionable without c), cprims over
// the c-tagged ones. Fragments leave at feed.fragments_per_cycle, each only
// when every queue it goes to has room:
//   non-collisionable       -> fragment queue (early-Z, fragment processors)
//   collisionable, no c     -> fragment queue and the unit's input queue
//   collisionable, c        -> the unit's input queue only
// A full queue stalls the rasterizer. A tile with collisionable fragments needs
// a ZEB bank (round-robin): gpu.bank_wait = "tile" holds the whole tile at the
// tile scheduler until its bank is free; "unit" lets the rasterizer go on and
// holds only the sorter, so the unit's queue fills and then stalls it.
//
// Frames are separated by a barrier: a frame ends when the last fragment
// processor is done and the unit's last record of the frame is in memory, and
// the next frame starts from there on an empty pipeline and a drained unit.
//
// The same run computes three GPU-only timelines on the same stream, which
// share the rasterizer's and the fragment processors' model but not the unit:
//   baseline  the GPU without the unit: face culling early, so no c fragments
//             and no cprims;
//   prims     the baseline plus the cprims setups;
//   work      plus the c fragments' rasterization (still no unit).
// Their differences split the overhead by cause (docs/gpu-model.md).
//
// Timing is computed per tile in plain C++ (no clock process): one wait() per
// tile, plus a wait for a busy bank and one at each frame's end.
#pragma once
#include <cstdint>
#include <exception>
#include <string>
#include <systemc>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/fragment.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/hw/fragment_processors.h"
#include "rbcd/hw/input_queue.h"
#include "rbcd/hw/insertion_sorter.h"
#include "rbcd/hw/zeb_bank.h"
#include "rbcd/hw/zoverlap_tester.h"

namespace rbcd {

// One frame as the rasterizer saw it, at its barrier. Cycles are durations
// from the frame's start unless named *_cycle.
struct FrameTimes {
    std::uint64_t frame = 0;
    std::uint64_t start_cycle = 0, end_cycle = 0;   // with the unit, absolute
    std::uint64_t with_unit = 0;        // end - start: GPU and unit done
    std::uint64_t gpu_done = 0;         // ... of which the fragment processors and rasterizer
    std::uint64_t flushed = 0;          // the unit's last record of the frame in memory
    std::uint64_t baseline = 0;         // the GPU without the unit
    std::uint64_t prims_only = 0;       // baseline + the cprims setups
    std::uint64_t work = 0;             // ... + the c fragments' rasterization
    std::uint64_t tiles = 0, tiles_with_fragments = 0, tiles_with_base = 0;
    std::uint64_t fragments = 0, culled = 0, other = 0;
    std::uint64_t shaded = 0;           // fragments to the fragment processors (other + not c)
    std::uint64_t shading_cycles = 0;   // ... times each one's cycles (gpu.cycles_per_fragment, shade=)
    std::uint64_t prims = 0, cprims = 0;
    // Rasterizer cycles lost, with the unit.
    std::uint64_t stall_no_bank = 0, stall_queue_full = 0, stall_fragment_queue = 0;
    std::uint64_t setup_cycles = 0, extra_setup_cycles = 0;
    // The overhead split (docs/gpu-model.md); sums to with_unit - baseline.
    std::uint64_t cost_extra_prims() const { return prims_only - baseline; }
    std::uint64_t cost_extra_fragments() const { return work - prims_only; }
    std::uint64_t cost_unit() const { return gpu_done - work; }   // queue and bank stalls
    std::uint64_t cost_tail() const { return with_unit - gpu_done; }
};

// One tile as the rasterizer fed it, with the unit (absolute cycles).
struct TileTimes {
    std::uint64_t seq = 0;              // the tile's place in the run, from 0
    std::uint64_t frame = 0;
    std::uint32_t col = 0, row = 0;
    int bank = -1;                      // the ZEB bank it took; -1: no collisionable fragment
    std::uint64_t fragments = 0, culled = 0, other = 0, prims = 0, cprims = 0;
    std::uint64_t arrive = 0;           // the rasterizer free for it
    std::uint64_t start = 0, end = 0;   // rasterizing (after a wait for its bank)
    std::uint64_t fill_start = 0;       // its bank free to fill
    std::uint64_t fill_end = 0;         // the bank holds the whole tile
    std::uint64_t stall_no_bank = 0, stall_queue_full = 0, stall_fragment_queue = 0;
};

// Observers of the stream and its frames (trace writer, images, stats, progress).
class RasterObserver {
public:
    virtual ~RasterObserver() = default;
    virtual void frame_begin(std::uint64_t /*frame*/) {}
    // Before the tile is rasterized.
    virtual void tile(const Tile&) {}
    // After it, for observers added with add_tile_observer (the tile database).
    virtual void tile_fed(const TileTimes&) {}
    // At the frame's barrier: every block is done with the frame.
    virtual void frame_end(const FrameTimes&) {}
};

class rasterizer : public sc_core::sc_module {
public:
    SC_HAS_PROCESS(rasterizer);

    struct stats_t {
        std::uint64_t frames = 0;
        std::uint64_t tiles = 0;                 // tile records of the input
        std::uint64_t tiles_with_fragments = 0;  // tiles that took a bank
        std::uint64_t fragments = 0;             // collisionable fragments sent to the unit
        std::uint64_t culled_fragments = 0;      // ... of which tagged c
        std::uint64_t other_fragments = 0;       // non-collisionable fragments rasterized
        std::uint64_t primitives = 0;            // prims= set up
        std::uint64_t culled_primitives = 0;     // cprims= set up
        std::uint64_t busy_cycles = 0;           // cycles emitting fragments or setting up
        std::uint64_t stall_no_bank_cycles = 0;  // cycles waiting for a free ZEB bank
        std::uint64_t stall_queue_full_cycles = 0;     // ... for room in the unit's input queue
        std::uint64_t stall_fragment_queue_cycles = 0; // ... for room in the fragment queue
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, frames, "frames replayed");
            RBCD_STAT(f, s, tiles, "tile records of the input");
            RBCD_STAT(f, s, tiles_with_fragments, "tiles with collisionable fragments (took a bank)");
            RBCD_STAT(f, s, fragments, "collisionable fragments sent to the unit");
            RBCD_STAT(f, s, culled_fragments, "fragments tagged c (deferred face culling)");
            RBCD_STAT(f, s, other_fragments, "non-collisionable fragments rasterized");
            RBCD_STAT(f, s, primitives, "primitives set up (prims=)");
            RBCD_STAT(f, s, culled_primitives, "primitives set up only for deferred culling (cprims=)");
            RBCD_STAT(f, s, busy_cycles, "cycles emitting fragments or setting up primitives");
            RBCD_STAT(f, s, stall_no_bank_cycles, "cycles stalled: no free ZEB bank");
            RBCD_STAT(f, s, stall_queue_full_cycles, "cycles stalled: the unit's input queue full");
            RBCD_STAT(f, s, stall_fragment_queue_cycles, "cycles stalled: the fragment queue full");
        }
    };

    rasterizer(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk, FragmentSource& src,
               std::vector<zeb_bank*> banks, fragment_processors& fp, input_queue& iq, insertion_sorter& sorter,
               zoverlap_tester& tester);

    // Set when the source threw: the simulation was stopped and this holds why.
    std::exception_ptr error() const { return error_; }
    const stats_t& stats() const { return stats_; }
    // The end of the last frame (0 before any): the run's length in cycles.
    std::uint64_t end_cycle() const { return last_end_; }
    void add_observer(RasterObserver* o) { observers_.push_back(o); }
    // Also told tile_fed(); without any, no tile's times are gathered.
    void add_tile_observer(RasterObserver* o) {
        observers_.push_back(o);
        tile_observers_.push_back(o);
    }

    // Waveforms; the rasterizer also retires the writer's settled events at each tile.
    void attach_vcd(VcdWriter& vcd, const std::string& scope);
    void set_vcd_flush(VcdWriter* vcd) { vcd_flush_ = vcd; }

    // The rasterizer's emission clock in one timeline: R fragments a cycle;
    // setup occupies whole cycles.
    struct Cursor {
        std::uint64_t t = 0;
        unsigned used = 0, rate = 1;
        // Masks, not branches: whether a cycle is full or a fragment waited
        // follows the input (hw/branch_free.h).
        std::uint64_t slot() {
            const unsigned full = used == rate;
            t += full;
            used &= full - 1u;
            return t;
        }
        void emit_at(std::uint64_t e) {
            const unsigned later = e > t;
            t = std::max(t, e);
            used = (used & (later - 1u)) + 1;
        }
        void busy(std::uint64_t cycles) {
            if (!cycles) return;
            t = next_free() + cycles;
            used = 0;
        }
        std::uint64_t next_free() const { return used ? t + 1 : t; }
        void restart(std::uint64_t at) {
            t = at;
            used = 0;
        }
    };

private:
    struct Pure;   // the GPU-only timelines
    template <insertion_sorter::Path P>
    struct Unit;   // the with-unit timeline's per-element steps, for the sorter's path P

    void run();
    void begin_frame(std::uint64_t frame);
    void end_frame();
    void feed_tile(const Tile& tile);
    std::uint64_t count_tile(const Tile& tile);
    std::uint64_t walk_gpu_only(const Tile& tile, std::uint64_t culled, bool no_setups, bool same_walk);

    const SimConfig& cfg_;
    const Clocking& clk_;
    FragmentSource& src_;
    std::vector<zeb_bank*> banks_;
    fragment_processors& fp_;
    input_queue& iq_;
    insertion_sorter& sorter_;
    zoverlap_tester& tester_;
    unsigned depth_bits_ = 24;
    unsigned next_bank_ = 0;
    Cursor unit_;                          // the with-unit timeline's rasterizer
    std::vector<FragmentPipe> pure_fp_;    // baseline, prims, work
    std::vector<Cursor> pure_r_;
    bool pure_live_[3] = {true, false, false};
    Tile tile_;                            // the tile being rasterized
    FrameTimes cur_;
    bool in_frame_ = false;
    std::uint64_t last_end_ = 0;
    std::exception_ptr error_;
    stats_t stats_;
    std::vector<RasterObserver*> observers_;
    std::vector<RasterObserver*> tile_observers_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter* vcd_flush_ = nullptr;
    VcdWriter::Sig vcd_frame_ = 0, vcd_col_ = 0, vcd_row_ = 0, vcd_emit_ = 0, vcd_no_bank_ = 0, vcd_queue_full_ = 0;
};

} // namespace rbcd
