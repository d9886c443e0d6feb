#include "hw/rasterizer_feed.h"

#include <algorithm>

namespace rbcd {

rasterizer_feed::rasterizer_feed(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk,
                                 FragmentSource& src, std::vector<zeb_bank*> banks, insertion_sorter& sorter,
                                 zoverlap_tester& tester)
    : sc_module(name),
      clk_(clk),
      src_(src),
      banks_(std::move(banks)),
      sorter_(sorter),
      tester_(tester),
      rate_(cfg.feed.fragments_per_cycle),
      gpu_(cfg.gpu) {
    SC_THREAD(run);
}

void rasterizer_feed::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_frame_ = vcd.add(scope, "frame", 32);
    vcd_col_ = vcd.add(scope, "tile_col", 16);
    vcd_row_ = vcd.add(scope, "tile_row", 16);
    vcd_emit_ = vcd.add(scope, "rasterizing", 1);
    vcd_no_bank_ = vcd.add(scope, "stall_no_bank", 1);
    sorter_.attach_feed_stall(vcd, vcd.add(scope, "stall_queue_full", 1));
}

void rasterizer_feed::feed_tile(const Tile& tile, unsigned depth_bits) {
    FrameStats& fs = frames_.back();
    ++stats_.tiles;
    ++fs.tiles;
    if (tile.has_base) {
        fs.base += tile.base;
        ++fs.tiles_with_base;
    }
    std::uint64_t culled = 0;
    for (const Fragment& f : tile.frags) culled += f.culled;
    stats_.fragments += tile.frags.size();
    stats_.culled_fragments += culled;
    stats_.other_fragments += tile.other;
    fs.fragments += tile.frags.size();
    fs.culled += culled;
    fs.other += tile.other;
    {
        // Baseline: rasterizer and fragment processors overlapped as a pipeline,
        // over what survives culling; the slower of the two sets the tile's time.
        const std::uint64_t shaded = tile.other + (tile.frags.size() - culled);
        const std::uint64_t raster = (shaded + gpu_.raster_fragments_per_cycle - 1) / gpu_.raster_fragments_per_cycle;
        const std::uint64_t shading =
            (shaded * gpu_.cycles_per_fragment + gpu_.fragment_processors - 1) / gpu_.fragment_processors;
        fs.baseline_cycles += tile.has_base ? tile.base : gpu_.tile_overhead_cycles + std::max(raster, shading);
        const std::uint64_t with_culled =
            (shaded + culled + gpu_.raster_fragments_per_cycle - 1) / gpu_.raster_fragments_per_cycle;
        fs.extra_raster_cycles += with_culled - raster;
    }
    if (on_tile) on_tile(tile);

    std::uint64_t t = clk_.now();
    if (vcd_flush_) vcd_flush_->flush_before(t);
    if (vcd_) {
        vcd_->set(vcd_frame_, t, tile.frame);
        vcd_->set(vcd_col_, t, tile.col);
        vcd_->set(vcd_row_, t, tile.row);
    }
    if (!tile.frags.empty()) {
        zeb_bank& bank = *banks_[next_bank_];
        next_bank_ = (next_bank_ + 1) % banks_.size();
        while (bank.state() != zeb_bank::State::Free) wait(bank.freed);
        const std::uint64_t got = clk_.now();
        stats_.stall_no_bank_cycles += got - t;
        fs.stall_no_bank += got - t;
        if (vcd_ && got > t) {
            vcd_->set(vcd_no_bank_, t, 1);
            vcd_->set(vcd_no_bank_, got, 0);
        }
        t = got;

        ++stats_.tiles_with_fragments;
        bank.begin_fill(tile.frame, tile.col, tile.row, t);
        const auto r = sorter_.fill_tile(tile, bank, t, depth_bits);
        tester_.post({zoverlap_tester::Job::TileJob, tile.frame, &bank, r.fill_done});
        stats_.stall_queue_full_cycles += r.queue_stall;
        fs.stall_queue_full += r.queue_stall;
        stats_.busy_cycles += r.feed_done - t - r.queue_stall;
        t = r.feed_done;
    }
    const std::uint64_t other_cycles = (tile.other + rate_ - 1) / rate_;
    stats_.busy_cycles += other_cycles;
    // Rasterizing from the cycle a bank was had (or the tile began) to its last fragment.
    if (vcd_) vcd_->set(vcd_emit_, clk_.now(), 1);
    t += other_cycles;
    if (vcd_) vcd_->set(vcd_emit_, t, 0);
    clk_.wait_until(t);
}

void rasterizer_feed::run() {
    Tile tile;
    const unsigned depth_bits = src_.header().depth_bits;
    bool in_frame = false;
    std::uint64_t frame = 0;
    try {
        for (;;) {
            const auto ev = src_.next(tile);
            if (ev == FragmentSource::Event::Tile) {
                feed_tile(tile, depth_bits);
                continue;
            }
            if (in_frame) {
                frames_.back().end = clk_.now();
                tester_.post({zoverlap_tester::Job::FrameEnd, frame, nullptr, 0});
            }
            if (ev == FragmentSource::Event::End) break;
            frame = tile.frame;
            in_frame = true;
            ++stats_.frames;
            frames_.push_back({});
            frames_.back().frame = frame;
            frames_.back().start = clk_.now();
            if (on_frame) on_frame(frame);
            tester_.post({zoverlap_tester::Job::FrameStart, frame, nullptr, 0});
        }
    } catch (...) {
        error_ = std::current_exception();
        sc_core::sc_stop();
        return;
    }
    tester_.post({zoverlap_tester::Job::Finish, 0, nullptr, 0});
}

} // namespace rbcd
