#include "rbcd/hw/rasterizer.h"
#include "rbcd/hw/even_split.h"

#include <algorithm>
#include <limits>
#include <type_traits>

namespace rbcd {

namespace {

constexpr std::uint64_t kNever = std::numeric_limits<std::uint64_t>::max();

// P setups spread evenly over L elements: primitive j's setup comes before
// element floor(j * L / P), so before element i the rasterizer has done
// min(P, ceil((i + 1) * P / L)) of them. Tracks the elements that need none,
// so the 128-bit arithmetic runs once per setup, not per element.
struct SetupSpread {
    std::uint64_t p, l;
    std::uint64_t i = 0, done = 0, free = 0;
    SetupSpread(std::uint64_t prims, std::uint64_t elements) : p(prims), l(elements) {
        if (p == 0 || l == 0) free = kNever;
    }
    // Setups due before the next element; the element is then counted.
    std::uint64_t before_next() {
        if (free) {
            if (free != kNever) --free;
            ++i;
            return 0;
        }
        const auto need128 = ((unsigned __int128)(i + 1) * p + l - 1) / l;
        const std::uint64_t need = need128 > p ? p : std::uint64_t(need128);
        const std::uint64_t k = need - done;
        done = need;
        free = done >= p ? kNever : std::uint64_t((unsigned __int128)done * l / p) - (i + 1);
        ++i;
        return k;
    }
    // The next `n` elements need no setup (n <= free).
    void skip(std::uint64_t n) {
        i += n;
        if (free != kNever) free -= n;
    }
};

// Walks a tile's rasterization order: setups, runs of non-collisionable
// fragments with no setup inside, collisionable fragments.
//   v.setup(extra, k)  k primitive setups (extra: cprims)
//   v.others(m)        m non-collisionable fragments
//   v.frag(f)          one collisionable fragment
template <class V>
void walk_tile(const Tile& tile, std::uint64_t culled, V& v) {
    const std::uint64_t n = tile.frags.size();
    SetupSpread shaded(tile.prims, tile.other + (n - culled)), extra(tile.cprims, culled);
    if (shaded.l == 0 && shaded.p) v.setup(false, shaded.p);
    if (extra.l == 0 && extra.p) v.setup(true, extra.p);
    const auto others = [&](std::uint64_t m) {
        if (shaded.free == kNever) {
            // No setup left among the shaded fragments: one run.
            if (m) v.others(m);
            shaded.i += m;
            return;
        }
        while (m) {
            if (const std::uint64_t k = shaded.before_next()) v.setup(false, k);
            const std::uint64_t run = 1 + std::min(m - 1, shaded.free);
            shaded.skip(run - 1);
            v.others(run);
            m -= run;
        }
    };
    const auto frag = [&](const Fragment& f) {
        SetupSpread& s = f.culled ? extra : shaded;
        if (const std::uint64_t k = s.before_next()) v.setup(f.culled, k);
        v.frag(f);
    };
    if (tile.ordered_other) {
        std::size_t run = 0;
        for (std::size_t i = 0; i < n; ++i) {
            for (; run < tile.other_runs.size() && tile.other_runs[run].before <= i; ++run)
                others(tile.other_runs[run].count);
            frag(tile.frags[i]);
        }
        for (; run < tile.other_runs.size(); ++run) others(tile.other_runs[run].count);
    } else {
        // Not given: spread evenly between the collisionable fragments.
        EvenSplit split(tile.other, n + 1);
        std::uint64_t done = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t upto = split.next();
            others(upto - done);
            done = upto;
            frag(tile.frags[i]);
        }
        others(tile.other - done);
    }
}

// walk_tile for a tile without setups (prims = cprims = 0, as most traces'
// tiles): the same calls, without the spreads' bookkeeping per fragment.
template <class V>
void walk_tile_without_setups(const Tile& tile, V& v) {
    const std::size_t n = tile.frags.size();
    if (tile.ordered_other) {
        std::size_t run = 0;
        for (std::size_t i = 0; i < n; ++i) {
            for (; run < tile.other_runs.size() && tile.other_runs[run].before <= i; ++run)
                if (tile.other_runs[run].count) v.others(tile.other_runs[run].count);
            v.frag(tile.frags[i]);
        }
        for (; run < tile.other_runs.size(); ++run)
            if (tile.other_runs[run].count) v.others(tile.other_runs[run].count);
    } else {
        EvenSplit split(tile.other, n + 1);
        std::uint64_t done = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t upto = split.next();
            if (upto > done) v.others(upto - done);
            done = upto;
            v.frag(tile.frags[i]);
        }
        if (tile.other > done) v.others(tile.other - done);
    }
}

// Whether timeline (rb, pb) is timeline (ra, pa) later by some cycles, set in
// `shift`: the rasterizer's clock and slot count, the queue, the processors.
bool follows(const rasterizer::Cursor& rb, const FragmentPipe& pb, const rasterizer::Cursor& ra, const FragmentPipe& pa,
             std::uint64_t& shift) {
    if (rb.used != ra.used || rb.t < ra.t) return false;
    shift = rb.t - ra.t;
    return pb.follows(pa, shift);
}
// Timeline (rb, pb) becomes (ra, pa) later by `shift`.
void take_shifted(rasterizer::Cursor& rb, FragmentPipe& pb, const rasterizer::Cursor& ra, const FragmentPipe& pa,
                  std::uint64_t shift) {
    rb.t = ra.t + shift;
    rb.used = ra.used;
    pb.follow(pa, shift);
}
[[gnu::always_inline]] inline std::uint64_t shade_run(rasterizer::Cursor& r, FragmentPipe& fp, std::uint64_t m) {
    return fp.shade_run(r.t, r.used, r.rate, m);
}

} // namespace

// The three GPU-only timelines: 0 baseline, 1 + cprims setups, 2 + c
// fragments. Until a frame has cprims (c fragments) timeline 1 (2) is the
// same as the one before it and is not computed: `live` says which are.
struct rasterizer::Pure {
    std::vector<Cursor>& r;
    std::vector<FragmentPipe>& fp;
    std::uint64_t setup_cycles;
    const bool* live;
    // Shaded fragments not yet pushed, per timeline: between two events that
    // differ for a timeline its fragments form one run, which shade_run can
    // take in bulk. Timeline 0 sees only regular setups, 1 also the extra
    // ones, 2 also the c fragments.
    std::uint64_t pending[3] = {0, 0, 0};
    std::uint64_t wait[3] = {0, 0, 0};   // the rasterizer's cycles waiting for the queue, this walk
    void flush(std::size_t i) {
        if (pending[i]) wait[i] += shade_run(r[i], fp[i], pending[i]);
        pending[i] = 0;
    }
    void setup(bool extra, std::uint64_t k) {
        for (std::size_t i = extra ? 1 : 0; i < 3; ++i) {
            if (!live[i]) continue;
            flush(i);
            r[i].busy(k * setup_cycles);
        }
    }
    void others(std::uint64_t m) {
        for (std::size_t i = 0; i < 3; ++i) pending[i] += m;
    }
    void frag(const Fragment& f) {
        if (!f.culled) {
            for (std::size_t i = 0; i < 3; ++i) ++pending[i];
        } else {
            flush(2);
            r[2].emit_at(r[2].slot());
        }
    }
    void finish() {
        for (std::size_t i = 0; i < 3; ++i)
            if (live[i]) flush(i);
    }
    // A tile without setups gives timelines 0 and 1 one run of its shaded
    // fragments and timeline 2 that run cut at its c fragments: the events
    // walk_tile_without_setups gives, counted instead of visited one by one.
    void walk_without_setups(const Tile& tile, std::uint64_t culled) {
        const std::size_t n = tile.frags.size();
        const std::uint64_t shaded = tile.other + (n - culled);
        pending[0] += shaded;
        pending[1] += shaded;
        if (!culled) {
            pending[2] += shaded;
            return;
        }
        // Timeline 2 cut at the c fragments, walked by the pipe in one call
        // (its own translation unit: fragment_processors.cpp says why).
        pending[2] = fp[2].walk_tile_cut_at_c(tile, r[2].t, r[2].used, r[2].rate, pending[2]);
    }
};

// The with-unit timeline.
template <insertion_sorter::Path P>
struct rasterizer::Unit {
    rasterizer& R;
    std::uint64_t setup_cycles;
    std::uint64_t bank_ready;
    bool bank_wait_unit;
    void setup(bool extra, std::uint64_t k) {
        R.unit_.busy(k * setup_cycles);
        (extra ? R.cur_.extra_setup_cycles : R.cur_.setup_cycles) += k * setup_cycles;
    }
    // Inlined into the walks: a call per fragment costs a tenth of their time.
    [[gnu::always_inline]] void others(std::uint64_t m) {
        std::uint64_t wait = 0;
        if (R.vcd_) {
            // Per fragment, so the processors' waveforms see each one.
            for (std::uint64_t k = 0; k < m; ++k) {
                const std::uint64_t slot = R.unit_.slot();
                const std::uint64_t e = R.fp_.room(slot);
                R.unit_.emit_at(e);
                R.fp_.push(e);
                wait += e - slot;
            }
        } else if (m == 1) {
            // The common run between two collisionable fragments: shade()'s
            // one step without loading and storing the pipe's state around it.
            const std::uint64_t slot = R.unit_.slot();
            const std::uint64_t e = R.fp_.room(slot);
            R.unit_.emit_at(e);
            R.fp_.pipe().push(e);
            R.fp_.count(1);
            wait = e - slot;
        } else {
            wait = shade_run(R.unit_, R.fp_.pipe(), m);
            R.fp_.count(m);
        }
        R.cur_.stall_fragment_queue += wait;
    }
    [[gnu::always_inline]] void frag(const Fragment& f) {
        const std::uint64_t slot = R.unit_.slot();
        const std::uint64_t uq = R.iq_.room(slot);
        // c fragments skip the fragment queue; a mask, not a branch on the input.
        const std::uint64_t fq = std::max(slot, R.fp_.pipe().slot_free_next() & (std::uint64_t(f.culled) - 1));
        const std::uint64_t e = std::max(uq, fq);
        if (e > slot) {
            if (uq >= fq) {
                // Waiting on the unit; while its bank is not ready, for the bank.
                const std::uint64_t nb = bank_wait_unit && slot < bank_ready ? std::min(e, bank_ready) - slot : 0;
                R.cur_.stall_no_bank += nb;
                R.cur_.stall_queue_full += e - slot - nb;
                if (R.vcd_) {
                    R.vcd_->set(R.vcd_queue_full_, slot, 1);
                    R.vcd_->set(R.vcd_queue_full_, e, 0);
                }
            } else {
                R.cur_.stall_fragment_queue += e - slot;
            }
        }
        R.unit_.emit_at(e);
        if (!f.culled) R.fp_.push(e);
        R.iq_.push(e, R.sorter_.template accept<P>(f, e, R.depth_bits_));
    }
};

rasterizer::rasterizer(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk, FragmentSource& src,
                       std::vector<zeb_bank*> banks, fragment_processors& fp, input_queue& iq,
                       insertion_sorter& sorter, zoverlap_tester& tester)
    : sc_module(name),
      cfg_(cfg),
      clk_(clk),
      src_(src),
      banks_(std::move(banks)),
      fp_(fp),
      iq_(iq),
      sorter_(sorter),
      tester_(tester),
      pure_fp_(3, FragmentPipe(cfg.gpu)),
      pure_r_(3) {
    unit_.rate = cfg.feed.fragments_per_cycle;
    for (auto& r : pure_r_) r.rate = cfg.feed.fragments_per_cycle;
    SC_THREAD(run);
}

void rasterizer::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_frame_ = vcd.add(scope, "frame", 32);
    vcd_col_ = vcd.add(scope, "tile_col", 16);
    vcd_row_ = vcd.add(scope, "tile_row", 16);
    vcd_emit_ = vcd.add(scope, "rasterizing", 1);
    vcd_no_bank_ = vcd.add(scope, "stall_no_bank", 1);
    vcd_queue_full_ = vcd.add(scope, "stall_queue_full", 1);
}

void rasterizer::begin_frame(std::uint64_t frame) {
    const std::uint64_t t = clk_.now();
    cur_ = FrameTimes{};
    cur_.frame = frame;
    cur_.start_cycle = t;
    in_frame_ = true;
    ++stats_.frames;
    // The barrier: every queue empty, the unit drained; banks restart at 0 so
    // that a frame's timing does not depend on the frames before it.
    unit_.restart(t);
    fp_.restart(t);
    iq_.restart();
    sorter_.restart(t);
    next_bank_ = 0;
    for (std::size_t i = 0; i < 3; ++i) {
        pure_r_[i].restart(0);
        pure_fp_[i].restart(0);
        pure_live_[i] = i == 0;
    }
    if (vcd_) vcd_->set(vcd_frame_, t, frame);
    for (auto* o : observers_) o->frame_begin(frame);
    tester_.post({zoverlap_tester::Job::FrameStart, frame, nullptr, 0});
}

void rasterizer::end_frame() {
    tester_.post({zoverlap_tester::Job::FrameEnd, cur_.frame, nullptr, 0});
    const std::uint64_t want = tester_.frames_flushed() + 1;
    while (tester_.frames_flushed() < want) wait(tester_.frame_flushed);
    const std::uint64_t start = cur_.start_cycle;
    const std::uint64_t gpu_end = std::max(fp_.done(), unit_.next_free());
    const std::uint64_t flushed = std::max(tester_.last_flushed(), start);
    const std::uint64_t end = std::max(gpu_end, flushed);
    cur_.end_cycle = end;
    last_end_ = end;
    cur_.with_unit = end - start;
    cur_.gpu_done = gpu_end - start;
    cur_.flushed = flushed - start;
    const auto pure_end = [&](std::size_t i) {
        while (!pure_live_[i]) --i;   // the same as the timeline before it
        return std::max(pure_fp_[i].done(), pure_r_[i].next_free());
    };
    cur_.baseline = pure_end(0);
    cur_.prims_only = pure_end(1);
    cur_.work = pure_end(2);
    fp_.close_frame(cur_.with_unit, cur_.shading_cycles);
    stats_.stall_no_bank_cycles += cur_.stall_no_bank;
    stats_.stall_queue_full_cycles += cur_.stall_queue_full;
    stats_.stall_fragment_queue_cycles += cur_.stall_fragment_queue;
    clk_.wait_until(end);
    in_frame_ = false;
    for (auto* o : observers_) o->frame_end(cur_);
}

// The tile's counts, run and frame, its shading cost set on every pipe, and
// the tile observers' look at it; returns its culled fragments. This and walk_gpu_only are inlined into
// feed_tile: the per-tile code keeps the layout GCC gives it in one piece
// (the same instructions executed; left to GCC, the split cost 0.9% more on
// the default scene).
[[gnu::always_inline]] inline std::uint64_t rasterizer::count_tile(const Tile& tile) {
    ++stats_.tiles;
    ++cur_.tiles;
    std::uint64_t culled = 0;
    for (const Fragment& f : tile.frags) culled += f.culled;
    const std::uint64_t n = tile.frags.size();
    stats_.fragments += n;
    stats_.culled_fragments += culled;
    stats_.other_fragments += tile.other;
    stats_.primitives += tile.prims;
    stats_.culled_primitives += tile.cprims;
    cur_.fragments += n;
    cur_.culled += culled;
    cur_.other += tile.other;
    cur_.shaded += tile.other + (n - culled);
    // The tile's shading cost (shade=): every pipe takes it for the tile's
    // fragments; a GPU-only timeline's pending runs end with each tile.
    const auto per_fragment = static_cast<unsigned>(fragment_cycles(cfg_.gpu.cycles_per_fragment, tile));
    cur_.shading_cycles += (tile.other + (n - culled)) * per_fragment;
    if (per_fragment != fp_.pipe().cycles_per_fragment()) {
        fp_.pipe().set_cycles_per_fragment(per_fragment);
        for (auto& p : pure_fp_) p.set_cycles_per_fragment(per_fragment);
    }
    cur_.prims += tile.prims;
    cur_.cprims += tile.cprims;
    cur_.tiles_with_base += tile.has_base;
    for (auto* o : observers_) o->tile(tile);
    return culled;
}

// The GPU-only timelines: no bank, no unit. A timeline starts to differ from
// the one before it at its first cprims (c fragment).
//
// A tile that gives every timeline the same walk (same_walk: feed_tile), a
// timeline whose state is timeline 0's later by some cycles (as they all
// become once each settles into the same periodic regime) is not walked: it
// takes timeline 0's state after the tile, later by as much (the
// recurrences are shift-invariant). Returns timeline 0's cycles waiting for
// the fragment queue in the tile.
[[gnu::always_inline]] inline std::uint64_t rasterizer::walk_gpu_only(const Tile& tile, std::uint64_t culled,
                                                                      bool no_setups, bool same_walk) {
    const auto go_live = [&](std::size_t i) {
        if (pure_live_[i]) return;
        const std::size_t from = pure_live_[i - 1] ? i - 1 : i - 2;
        pure_r_[i] = pure_r_[from];
        pure_fp_[i] = pure_fp_[from];
        pure_live_[i] = true;
    };
    if (tile.cprims) go_live(1);
    if (tile.cprims || culled) go_live(2);
    bool walk[3] = {true, pure_live_[1], pure_live_[2]};
    std::uint64_t shift[3] = {0, 0, 0};
    for (std::size_t i = 1; i < 3 && same_walk; ++i)
        walk[i] = walk[i] && !follows(pure_r_[i], pure_fp_[i], pure_r_[0], pure_fp_[0], shift[i]);
    std::uint64_t pure_start[3];
    for (std::size_t i = 0; i < 3; ++i) {
        if (!walk[i]) continue;
        pure_start[i] = pure_r_[i].next_free();
        pure_r_[i].busy(cfg_.gpu.tile_overhead_cycles);
    }
    Pure pure{pure_r_, pure_fp_, cfg_.gpu.setup_cycles_per_primitive, walk};
    if (no_setups) pure.walk_without_setups(tile, culled);
    else walk_tile(tile, culled, pure);
    pure.finish();
    if (tile.has_base)
        for (std::size_t i = 0; i < 3; ++i)
            if (pure_live_[i]) pure_r_[i].restart(std::max(pure_r_[i].next_free(), pure_start[i] + tile.base));
    for (std::size_t i = 1; i < 3; ++i)
        if (pure_live_[i] && !walk[i]) take_shifted(pure_r_[i], pure_fp_[i], pure_r_[0], pure_fp_[0], shift[i]);
    return pure.wait[0];
}

void rasterizer::feed_tile(const Tile& tile) {
    const std::uint64_t culled = count_tile(tile);
    const std::uint64_t n = tile.frags.size();
    const std::uint64_t overhead = cfg_.gpu.tile_overhead_cycles;
    const std::uint64_t setup = cfg_.gpu.setup_cycles_per_primitive;
    const bool no_setups = tile.prims == 0 && tile.cprims == 0;
    // A tile without collisionable fragments, cprims or base= gives every
    // timeline, the with-unit one too (no bank, no unit), the walk timeline 0
    // takes: one whose state is timeline 0's later by some cycles takes
    // timeline 0's after the tile (walk_gpu_only). Waveforms want each
    // fragment's cycles: walked then.
    const bool same_walk = n == 0 && tile.cprims == 0 && !tile.has_base && !FragmentPipe::stepwise;
    std::uint64_t unit_shift = 0;
    const bool unit_follows = same_walk && !vcd_ && follows(unit_, fp_.pipe(), pure_r_[0], pure_fp_[0], unit_shift);
    const std::uint64_t wait0 = walk_gpu_only(tile, culled, no_setups, same_walk);

    // With the unit.
    const std::uint64_t t0 = unit_.next_free();
    if (vcd_flush_) vcd_flush_->flush_before(std::min(t0, clk_.now()));
    if (vcd_) {
        vcd_->set(vcd_col_, t0, tile.col);
        vcd_->set(vcd_row_, t0, tile.row);
    }
    // Per-tile stall figures for tile observers.
    const std::uint64_t no_bank_before = cur_.stall_no_bank, queue_full_before = cur_.stall_queue_full,
                        fragment_queue_before = cur_.stall_fragment_queue;
    std::uint64_t start = t0, bank_ready = t0;
    const bool bank_wait_unit = cfg_.gpu.bank_wait == BankWait::Unit;
    zeb_bank* bank = nullptr;
    if (n) {
        bank = banks_[next_bank_];
        next_bank_ = (next_bank_ + 1) % banks_.size();
        while (bank->state() != zeb_bank::State::Free) wait(bank->freed);
        bank_ready = std::max(t0, bank->state_since());
        if (!bank_wait_unit) {
            // The tile scheduler holds the whole tile until its bank is free.
            cur_.stall_no_bank += bank_ready - t0;
            if (vcd_ && bank_ready > t0) {
                vcd_->set(vcd_no_bank_, t0, 1);
                vcd_->set(vcd_no_bank_, bank_ready, 0);
            }
            start = bank_ready;
            unit_.restart(start);
        }
        ++stats_.tiles_with_fragments;
        ++cur_.tiles_with_fragments;
        bank->begin_fill(tile.frame, tile.col, tile.row, bank_ready);
        sorter_.begin_tile(*bank, bank_ready, tile);
    }
    if (vcd_) vcd_->set(vcd_emit_, start, 1);
    const std::uint64_t stalls_before = cur_.stall_no_bank + cur_.stall_queue_full + cur_.stall_fragment_queue;
    unit_.busy(overhead);
    const auto walk_with_unit = [&](auto path) {
        Unit<decltype(path)::value> unit{*this, setup, bank_ready, bank_wait_unit};
        if (no_setups) walk_tile_without_setups(tile, unit);
        else walk_tile(tile, culled, unit);
    };
    // One walk per sorter path, each its own straight code (insertion_sorter::path()).
    using Path = insertion_sorter::Path;
    if (unit_follows) {
        take_shifted(unit_, fp_.pipe(), pure_r_[0], pure_fp_[0], unit_shift);
        fp_.count(tile.other);
        cur_.stall_fragment_queue += wait0;
        cur_.setup_cycles += tile.prims * setup;
    } else {
        switch (sorter_.path()) {
        case Path::Loops: walk_with_unit(std::integral_constant<Path, Path::Loops>{}); break;
        case Path::LoopsCounted: walk_with_unit(std::integral_constant<Path, Path::LoopsCounted>{}); break;
        case Path::AllSlots: walk_with_unit(std::integral_constant<Path, Path::AllSlots>{}); break;
        }
    }
    if (tile.has_base) unit_.restart(std::max(unit_.next_free(), start + tile.base));
    const std::uint64_t end = unit_.next_free();
    const std::uint64_t stalls = cur_.stall_no_bank + cur_.stall_queue_full + cur_.stall_fragment_queue - stalls_before;
    const std::uint64_t span = end - start;
    stats_.busy_cycles += span > stalls ? span - stalls : 0;
    if (vcd_) vcd_->set(vcd_emit_, end, 0);
    const std::uint64_t filled = bank ? sorter_.end_tile() : end;
    if (!tile_observers_.empty()) {
        TileTimes tt;
        tt.seq = stats_.tiles - 1;
        tt.frame = tile.frame;
        tt.col = tile.col;
        tt.row = tile.row;
        tt.bank = bank ? static_cast<int>(bank->index()) : -1;
        tt.fragments = n;
        tt.culled = culled;
        tt.other = tile.other;
        tt.prims = tile.prims;
        tt.cprims = tile.cprims;
        tt.arrive = t0;
        tt.start = start;
        tt.end = end;
        tt.fill_start = bank ? bank_ready : end;
        tt.fill_end = filled;
        tt.stall_no_bank = cur_.stall_no_bank - no_bank_before;
        tt.stall_queue_full = cur_.stall_queue_full - queue_full_before;
        tt.stall_fragment_queue = cur_.stall_fragment_queue - fragment_queue_before;
        for (auto* o : tile_observers_) o->tile_fed(tt);
    }
    if (bank) tester_.post({zoverlap_tester::Job::TileJob, tile.frame, bank, filled, n});
    clk_.wait_until(end);
}

void rasterizer::run() {
    // The tile is a member, not a local: a thread stopped by an error elsewhere
    // is never unwound, and its stack's objects would never be destroyed.
    Tile& tile = tile_;
    depth_bits_ = src_.header().depth_bits;
    try {
        for (;;) {
            const auto ev = src_.next(tile);
            if (ev == FragmentSource::Event::Tile) {
                feed_tile(tile);
                continue;
            }
            if (in_frame_) end_frame();
            if (ev == FragmentSource::Event::End) break;
            begin_frame(tile.frame);
        }
    } catch (...) {
        error_ = std::current_exception();
        sc_core::sc_stop();
        return;
    }
    tester_.post({zoverlap_tester::Job::Finish, 0, nullptr, 0});
}

} // namespace rbcd
