#include "sc_main/gpu_model.h"

#include <algorithm>

#include "hw/rbcd_system.h"

namespace rbcd {

GpuTileCost gpu_tile_cost(const GpuTileSample& s, std::uint64_t prev_flushed) {
    GpuTileCost c;
    // The no-bank stall is the first thing in the tile: [start, start + N). What of it
    // lies before the previous frame's flush is that frame's tail.
    c.overlap = prev_flushed > s.start ? std::min(s.stall_no_bank, prev_flushed - s.start) : 0;
    const std::uint64_t no_bank = s.stall_no_bank - c.overlap;
    c.unit_duration = s.duration - c.overlap;
    const std::uint64_t gpu = std::max(s.gpu, s.baseline);
    c.with_unit = std::max(gpu, c.unit_duration);
    c.extra_raster = gpu - s.baseline;

    // The feed's own stall-free time; the GPU's slack over it hides stalls, the
    // no-bank stall first (it comes first), then the queue-full stall.
    const std::uint64_t stall_free = s.duration - s.stall_no_bank - s.stall_queue_full;
    c.feed_excess = stall_free > gpu ? stall_free - gpu : 0;
    std::uint64_t slack = gpu > stall_free ? gpu - stall_free : 0;
    const std::uint64_t hidden_nb = std::min(slack, no_bank);
    slack -= hidden_nb;
    const std::uint64_t hidden_q = std::min(slack, s.stall_queue_full);
    c.no_bank = no_bank - hidden_nb;
    c.queue_full = s.stall_queue_full - hidden_q;
    return c;
}

std::uint64_t gpu_estimated_with_unit(const GpuConfig& g, const Tile& tile, std::uint64_t baseline,
                                      std::uint64_t extra, bool* mismatch) {
    std::uint64_t culled = 0;
    for (const Fragment& f : tile.frags) culled += f.culled;
    const std::uint64_t shaded = tile.other + (tile.frags.size() - culled);
    const std::uint64_t r = g.raster_fragments_per_cycle;
    const std::uint64_t raster = (shaded + r - 1) / r;
    const std::uint64_t raster_all = (shaded + culled + r - 1) / r;
    const std::uint64_t shading = (shaded * g.cycles_per_fragment + g.fragment_processors - 1) / g.fragment_processors;
    const bool same = g.tile_overhead_cycles + std::max(raster, shading) == baseline && raster_all - raster == extra;
    if (mismatch) *mismatch = !same;
    if (!same) return baseline + extra;
    return g.tile_overhead_cycles + std::max(raster_all, shading);
}

void add_tile(GpuFrame& f, const GpuTileSample& s, const GpuTileCost& c) {
    ++f.tiles;
    f.baseline_cycles += s.baseline;
    f.extra_raster_cycles += s.extra_raster;
    f.extra_raster_exposed += c.extra_raster;
    f.raster_cycles += c.with_unit;
    f.stall_no_bank_cycles += s.stall_no_bank;
    f.stall_queue_full_cycles += s.stall_queue_full;
    f.no_bank_exposed += c.no_bank;
    f.queue_full_exposed += c.queue_full;
    f.feed_excess += c.feed_excess;
    f.no_bank_in_previous_tail += c.overlap;
    f.last_unit_duration = c.unit_duration;
    f.last_with_unit = c.with_unit;
}

FrameEnds frame_ends(const rbcd_system& sys, std::size_t i) {
    const auto& ff = sys.feed.frames();
    const auto& tf = sys.tester.frames();
    FrameEnds e;
    e.feed_start = ff[i].start;
    e.feed_end = ff[i].end;
    e.flushed = i < tf.size() ? tf[i].flushed : ff[i].end;
    // The tester takes the frame end after its last tile (or, without one, after the
    // previous frame's readback) and not before the feed posts it.
    e.flush_start = e.feed_end;
    if (i < tf.size()) e.flush_start = std::max(e.flush_start, tf[i].last_tile_done);
    if (i > 0 && i - 1 < tf.size()) {
        e.flush_start = std::max(e.flush_start, tf[i - 1].done);
        e.prev_flushed = tf[i - 1].flushed;
    }
    e.flush_start = std::min(e.flush_start, e.flushed);
    return e;
}

void close_frame(GpuFrame& f, const FrameEnds& e) {
    f.feed_start = e.feed_start;
    f.feed_end = e.feed_end;
    f.flushed = e.flushed;
    f.flush_start = e.flush_start;
    auto pos = [](std::int64_t v) { return v > 0 ? std::uint64_t(v) : std::uint64_t(0); };
    const std::int64_t flushed = std::int64_t(e.flushed);
    // The frame-end flush starts only once the GPU is done with the frame, and takes as long.
    std::uint64_t tail = e.flushed - e.flush_start;
    if (f.tiles) {
        // The unit finishes the last tile (flushed - feed_end) + U' cycles after the tile
        // began on the feed; the GPU spends W on that tile.
        tail = std::max(tail, pos(flushed - std::int64_t(e.feed_end) + std::int64_t(f.last_unit_duration) -
                                  std::int64_t(f.last_with_unit)));
    } else {
        // No tile of its own: the frame begins at the previous frame's flush (or its feed start).
        tail = std::max(tail, pos(flushed - std::int64_t(std::max(e.prev_flushed, e.feed_start))));
    }
    f.tail_cycles = tail;
    f.cycles_with_unit = f.raster_cycles + f.tail_cycles;
    const std::uint64_t plain_tail = e.flushed > e.feed_end ? e.flushed - e.feed_end : 0;
    f.additive_cycles = f.baseline_cycles + f.extra_raster_cycles + f.stall_no_bank_cycles +
                        f.stall_queue_full_cycles + plain_tail;
}

GpuModel::GpuModel(const rbcd_system& sys) : sys_(sys), gpu_cfg_(sys.cfg.gpu) {}

std::uint64_t GpuModel::prev_flushed_now(std::size_t n) const {
    if (n == 0) return 0;
    const auto& tf = sys_.tester.frames();
    // The tester records frame n-1's flush when it ends that frame; until then the
    // flush lies in the future, after every stall seen so far.
    const bool ended = tf.size() > n || (tf.size() == n && (tf[n - 1].flushed || tf[n - 1].done));
    return ended ? tf[n - 1].flushed : sys_.clk.now();
}

void GpuModel::close_tile(std::uint64_t end) {
    if (!tile_open_) return;
    const auto& st = sys_.feed.stats();
    sample_.duration = end - sample_.start;
    sample_.stall_no_bank = st.stall_no_bank_cycles - open_no_bank_;
    sample_.stall_queue_full = st.stall_queue_full_cycles - open_queue_;
    const GpuTileCost c = gpu_tile_cost(sample_, prev_flushed_now(open_frame_));
    GpuFrame& f = frames_.at(open_frame_);
    add_tile(f, sample_, c);
    if (open_has_base_) ++f.tiles_with_base;
    if (open_mismatch_) ++f.estimate_mismatches;
    tile_open_ = false;
}

void GpuModel::on_tile(const Tile& tile) {
    const auto& ff = sys_.feed.frames();
    if (ff.empty()) return;
    const std::size_t n = ff.size() - 1;
    // The open tile ends now, or at its frame's end if a new frame began since.
    if (tile_open_) close_tile(open_frame_ == n ? sys_.clk.now() : ff[open_frame_].end);
    while (frames_.size() < ff.size()) {
        frames_.emplace_back();
        frames_.back().frame = ff[frames_.size() - 1].frame;
    }
    if (seen_frame_ != n) {
        seen_frame_ = n;
        seen_baseline_ = seen_extra_ = seen_with_base_ = 0;
    }
    // The feed has already added this tile to its frame's sums.
    const auto& fs = ff[n];
    tile_open_ = true;
    open_frame_ = n;
    sample_ = GpuTileSample{};
    sample_.start = sys_.clk.now();
    sample_.baseline = fs.baseline_cycles - seen_baseline_;
    sample_.extra_raster = fs.extra_raster_cycles - seen_extra_;
    open_has_base_ = fs.tiles_with_base != seen_with_base_;
    open_mismatch_ = false;
    sample_.gpu = open_has_base_ ? sample_.baseline + sample_.extra_raster
                                 : gpu_estimated_with_unit(gpu_cfg_, tile, sample_.baseline, sample_.extra_raster,
                                                           &open_mismatch_);
    seen_baseline_ = fs.baseline_cycles;
    seen_extra_ = fs.extra_raster_cycles;
    seen_with_base_ = fs.tiles_with_base;
    open_no_bank_ = sys_.feed.stats().stall_no_bank_cycles;
    open_queue_ = sys_.feed.stats().stall_queue_full_cycles;
}

const std::vector<GpuFrame>& GpuModel::finish() {
    if (finished_) return frames_;
    finished_ = true;
    const auto& ff = sys_.feed.frames();
    if (tile_open_) close_tile(ff[open_frame_].end);
    while (frames_.size() < ff.size()) {
        frames_.emplace_back();
        frames_.back().frame = ff[frames_.size() - 1].frame;
    }
    for (std::size_t i = 0; i < frames_.size(); ++i) close_frame(frames_[i], frame_ends(sys_, i));
    return frames_;
}

std::vector<GpuFrame> GpuModel::per_frame(const rbcd_system& sys) {
    std::vector<GpuFrame> out;
    const auto& ff = sys.feed.frames();
    const auto& tf = sys.tester.frames();
    for (std::size_t i = 0; i < ff.size(); ++i) {
        const auto& fs = ff[i];
        GpuFrame f;
        f.frame = fs.frame;
        f.feed_start = fs.start;
        GpuTileSample s;
        s.start = fs.start;
        s.duration = fs.end - fs.start;
        s.baseline = fs.baseline_cycles;
        s.extra_raster = fs.extra_raster_cycles;
        s.stall_no_bank = fs.stall_no_bank;
        s.stall_queue_full = fs.stall_queue_full;
        s.gpu = s.baseline + s.extra_raster;   // no per-tile split: the extra comes on top
        const std::uint64_t prev = i > 0 && i - 1 < tf.size() ? tf[i - 1].flushed : 0;
        if (fs.tiles) {
            add_tile(f, s, gpu_tile_cost(s, prev));
            f.tiles = fs.tiles;
            f.tiles_with_base = fs.tiles_with_base;
        }
        close_frame(f, frame_ends(sys, i));
        out.push_back(f);
    }
    return out;
}

} // namespace rbcd
