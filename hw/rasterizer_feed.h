// The rasterizer feed: replays a fragment stream tile by tile at the
// rasterizer's rate into the unit. A tile's collisionable fragments cannot
// start until a ZEB bank is free (banks are taken in round-robin order, which
// keeps tiles tested in rasterization order); the input queue in front of the
// sorter holds the rasterizer back when full. The tile's non-collisionable
// fragments (`other=`) follow its collisionable ones through the rasterizer,
// which is when the unit catches up.
#pragma once
#include <cstdint>
#include <exception>
#include <systemc>
#include <vector>

#include "common/config.h"
#include "common/fragment.h"
#include "hw/clocking.h"
#include "hw/insertion_sorter.h"
#include "hw/zeb_bank.h"
#include "common/vcd_writer.h"
#include "hw/zoverlap_tester.h"

namespace rbcd {

class rasterizer_feed : public sc_core::sc_module {
public:
    SC_HAS_PROCESS(rasterizer_feed);

    struct stats_t {
        std::uint64_t frames = 0;
        std::uint64_t tiles = 0;                 // tile records of the input
        std::uint64_t tiles_with_fragments = 0;  // tiles that took a bank
        std::uint64_t fragments = 0;             // collisionable fragments sent to the unit
        std::uint64_t culled_fragments = 0;      // ... of which tagged c
        std::uint64_t other_fragments = 0;       // non-collisionable fragments rasterized
        std::uint64_t busy_cycles = 0;           // cycles emitting fragments
        std::uint64_t stall_no_bank_cycles = 0;  // cycles waiting for a free ZEB bank
        std::uint64_t stall_queue_full_cycles = 0;  // cycles held by the unit's full input queue
        template <class F> void for_each(F f) const {
            RBCD_STAT(f, *this, frames, "frames replayed");
            RBCD_STAT(f, *this, tiles, "tile records of the input");
            RBCD_STAT(f, *this, tiles_with_fragments, "tiles with collisionable fragments (took a bank)");
            RBCD_STAT(f, *this, fragments, "collisionable fragments sent to the unit");
            RBCD_STAT(f, *this, culled_fragments, "fragments tagged c (deferred face culling)");
            RBCD_STAT(f, *this, other_fragments, "non-collisionable fragments rasterized");
            RBCD_STAT(f, *this, busy_cycles, "cycles emitting fragments");
            RBCD_STAT(f, *this, stall_no_bank_cycles, "cycles stalled: no free ZEB bank");
            RBCD_STAT(f, *this, stall_queue_full_cycles, "cycles stalled: input queue full");
        }
    };

    // Per-frame figures for the stats' per-frame series.
    struct FrameStats {
        std::uint64_t frame = 0;
        std::uint64_t start = 0, end = 0;   // feed cycles
        std::uint64_t tiles = 0, fragments = 0, other = 0, culled = 0;
        std::uint64_t stall_no_bank = 0, stall_queue_full = 0;
        std::uint64_t base = 0;             // sum of base= of the frame's tiles
        std::uint64_t tiles_with_base = 0;
        // Baseline GPU cycles of the frame's tiles without the unit: base= where
        // given, else the estimate of docs/gpu-model.md.
        std::uint64_t baseline_cycles = 0;
        // Extra rasterizer cycles for the c-tagged fragments, which the baseline
        // culled before rasterization.
        std::uint64_t extra_raster_cycles = 0;
    };

    rasterizer_feed(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk, FragmentSource& src,
                    std::vector<zeb_bank*> banks, insertion_sorter& sorter, zoverlap_tester& tester);

    // Set when the source threw: the simulation was stopped and this holds why.
    std::exception_ptr error() const { return error_; }
    const stats_t& stats() const { return stats_; }
    const std::vector<FrameStats>& frames() const { return frames_; }

    // Observes every tile as it is fed (e.g. the scene imager, --write-trace); may be null.
    std::function<void(const Tile&)> on_tile;
    std::function<void(std::uint64_t)> on_frame;

    // Waveforms; the feed also retires the writer's settled events at each tile.
    void attach_vcd(VcdWriter& vcd, const std::string& scope);
    void set_vcd_flush(VcdWriter* vcd) { vcd_flush_ = vcd; }

private:
    void run();
    void feed_tile(const Tile& tile, unsigned depth_bits);

    const Clocking& clk_;
    FragmentSource& src_;
    std::vector<zeb_bank*> banks_;
    insertion_sorter& sorter_;
    zoverlap_tester& tester_;
    unsigned rate_;
    GpuConfig gpu_;
    unsigned next_bank_ = 0;
    std::exception_ptr error_;
    std::vector<FrameStats> frames_;
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter* vcd_flush_ = nullptr;
    VcdWriter::Sig vcd_frame_ = 0, vcd_col_ = 0, vcd_row_ = 0, vcd_emit_ = 0, vcd_no_bank_ = 0;
};

} // namespace rbcd
