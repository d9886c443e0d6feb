// The GPU context of the unit: what a frame costs the tile-based GPU without
// the unit (baseline) and with it, per frame, with the overhead split by cause.
// The model and every formula are in docs/gpu-model.md.
//
// The rasterizer feed of the SystemC model runs at the rasterizer's peak rate
// and does not model the fragment processors, so its stall counters are
// measured on a timeline faster than the GPU's. The model therefore works per
// tile: the GPU spends G on a tile with the unit (its baseline plus what the
// extra rasterization of the c-tagged fragments adds), the unit lets the feed
// through the tile in U cycles (its measured duration, stalls included), and
// the tile takes max(G, U). After the frame's last tile comes the tester's
// tail, until the frame's records are in memory.
//
//   GpuModel gpu(sys);                                    // before sys.run()
//   sys.feed.on_tile = [&](const Tile& t) { gpu.on_tile(t); };
//   sys.run();
//   const auto& frames = gpu.finish();                   // per-frame results
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/config.h"
#include "common/fragment.h"

namespace rbcd {

class rbcd_system;

// One tile as the feed went through it, in feed cycles.
struct GpuTileSample {
    std::uint64_t start = 0;              // feed cycle the tile began
    std::uint64_t duration = 0;           // U: feed cycles until the next tile (or the frame's end)
    std::uint64_t baseline = 0;           // B: baseline GPU cycles (base= or the estimate)
    std::uint64_t extra_raster = 0;       // X: rasterization of the c-tagged fragments
    // G: the GPU's own cycles for the tile with the unit. base= tiles: B + X. Estimated
    // tiles: overhead + max(raster + X, shading), the rasterizer's extra work hidden
    // behind the fragment processors where they are the bottleneck.
    std::uint64_t gpu = 0;
    std::uint64_t stall_no_bank = 0;      // N: feed cycles waiting for a free bank
    std::uint64_t stall_queue_full = 0;   // Q: feed cycles held by the full input queue
};

// The tile with the unit, and where its cycles beyond the baseline come from.
// with_unit - baseline == extra_raster + feed_excess + no_bank + queue_full.
struct GpuTileCost {
    std::uint64_t with_unit = 0;          // W = max(G, U - overlap)
    std::uint64_t extra_raster = 0;       // G - B: the extra rasterization the GPU sees
    std::uint64_t unit_duration = 0;      // U - overlap
    std::uint64_t overlap = 0;            // no-bank stall inside the previous frame's tail (charged there)
    std::uint64_t feed_excess = 0;        // the feed's stall-free time beyond G
    std::uint64_t no_bank = 0;            // exposed no-bank stall
    std::uint64_t queue_full = 0;         // exposed queue-full stall
};

// `prev_flushed`: the cycle the previous frame's records were all in memory
// (0 for the first frame); the tile's no-bank stall before it is the
// previous frame's tail, not this tile's cost.
GpuTileCost gpu_tile_cost(const GpuTileSample& s, std::uint64_t prev_flushed);

struct GpuFrame {
    std::uint64_t frame = 0;
    std::uint64_t tiles = 0, tiles_with_base = 0;
    std::uint64_t baseline_cycles = 0;        // sum of B
    std::uint64_t extra_raster_cycles = 0;    // sum of X (work)
    std::uint64_t extra_raster_exposed = 0;   // sum of G - B (time)
    std::uint64_t estimate_mismatches = 0;    // estimated tiles whose B this model could not reproduce
    std::uint64_t raster_cycles = 0;          // sum of W: the frame's tiles with the unit
    std::uint64_t tail_cycles = 0;            // after the last tile until the records are in memory
    std::uint64_t cycles_with_unit = 0;       // raster_cycles + tail_cycles
    // Measured by the feed (its own timeline) and the part the GPU sees.
    std::uint64_t stall_no_bank_cycles = 0, stall_queue_full_cycles = 0;
    std::uint64_t no_bank_exposed = 0, queue_full_exposed = 0, feed_excess = 0;
    std::uint64_t no_bank_in_previous_tail = 0;
    // The plain sum, baseline + X + N + Q + (flushed - feed end): an upper bound.
    std::uint64_t additive_cycles = 0;
    // Feed and tester timeline (feed cycles).
    std::uint64_t feed_start = 0, feed_end = 0, flushed = 0, flush_start = 0;
    // The last tile's U' and W, for the tail.
    std::uint64_t last_unit_duration = 0, last_with_unit = 0;

    std::uint64_t overhead_cycles() const { return cycles_with_unit - baseline_cycles; }
    double overhead_pct() const {
        return baseline_cycles ? 100.0 * double(cycles_with_unit - baseline_cycles) / double(baseline_cycles) : 0.0;
    }
};

// G for a tile without base= (docs/gpu-model.md). `baseline` is the feed's B; when
// this model's estimate does not reproduce it, G falls back to B + X.
std::uint64_t gpu_estimated_with_unit(const GpuConfig& g, const Tile& tile, std::uint64_t baseline,
                                      std::uint64_t extra, bool* mismatch = nullptr);

// Adds the tile's cost to the frame.
void add_tile(GpuFrame& f, const GpuTileSample& s, const GpuTileCost& c);

// The feed's and the tester's cycles a frame's tail is computed from.
struct FrameEnds {
    std::uint64_t feed_start = 0, feed_end = 0;
    std::uint64_t flushed = 0;          // the frame's records all in memory
    std::uint64_t flush_start = 0;      // the tester began the frame-end flush: max(feed end, its last tile, previous done)
    std::uint64_t prev_flushed = 0;     // the previous frame's flushed (0 for the first)
};
FrameEnds frame_ends(const rbcd_system& sys, std::size_t frame_index);

// Sets the frame's tail and totals once its flush is known.
void close_frame(GpuFrame& f, const FrameEnds& e);

class GpuModel {
public:
    explicit GpuModel(const rbcd_system& sys);

    // Call from the feed's on_tile hook (the feed has counted the tile, not yet fed it).
    void on_tile(const Tile& tile);
    // After the run: closes the last tile and every frame's tail. Idempotent.
    const std::vector<GpuFrame>& finish();
    const std::vector<GpuFrame>& frames() const { return frames_; }

    // Without per-tile samples (no hook was wired): each frame as one tile.
    // Coarser: a stall hides behind the whole frame's slack.
    static std::vector<GpuFrame> per_frame(const rbcd_system& sys);

private:
    void close_tile(std::uint64_t end);
    std::uint64_t prev_flushed_now(std::size_t frame_index) const;

    const rbcd_system& sys_;
    GpuConfig gpu_cfg_;
    std::vector<GpuFrame> frames_;
    bool tile_open_ = false;
    std::size_t open_frame_ = 0;          // feed frame index of the open tile
    GpuTileSample sample_;
    bool open_has_base_ = false, open_mismatch_ = false;
    std::uint64_t open_no_bank_ = 0, open_queue_ = 0;   // feed counters when the tile opened
    std::uint64_t seen_baseline_ = 0, seen_extra_ = 0, seen_with_base_ = 0;   // of the current frame's FrameStats
    std::size_t seen_frame_ = ~std::size_t(0);
    bool finished_ = false;
};

} // namespace rbcd
