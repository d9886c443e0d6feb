// The GPU's fragment side behind the rasterizer (paper, Figure 3 and Table 2):
// a fragment queue of Q = gpu.fragment_queue_depth entries in front of early-Z,
// and P = gpu.fragment_processors processors that take C =
// gpu.cycles_per_fragment cycles a fragment.
//
// Fragments are dispatched in order to the earliest-free processor; with equal
// service times that is round-robin, so fragment k, entering the queue at e_k,
// starts at
//     s_k = max(e_k + early_z, s_{k-P} + C)
// and frees its queue slot then: fragment k may enter only once s_{k-Q} has
// passed (a pop and a push in the same cycle are allowed). The processors idle
// only when the queue runs dry.
//
// FragmentPipe is that recurrence, in plain C++: the with-unit timeline and the
// baseline timelines of the rasterizer (docs/gpu-model.md) each own one.
//
//   FragmentPipe p(cfg.gpu);
//   std::uint64_t e = p.room(raster_cycle);   // earliest cycle the queue takes one
//   p.push(e);                                 // ... and it enters then
//   p.done();                                  // every fragment so far finished
#pragma once
#include <algorithm>
#include <cstdint>
#include <numeric>
#include <systemc>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/branch_free.h"
#include "rbcd/hw/clocking.h"

namespace rbcd {

struct Tile;   // common/fragment.h

class FragmentPipe {
public:
    explicit FragmentPipe(const GpuConfig& g)
        : q_(g.fragment_queue_depth),
          p_(g.fragment_processors),
          c_(g.cycles_per_fragment),
          ez_(g.early_z_cycles),
          slot_free_(g.fragment_queue_depth, 0),
          proc_free_(g.fragment_processors, 0) {}

    // Frame barrier: an empty queue and idle processors from cycle t on.
    // (Slots and processors free "at 0" constrain nothing: every cycle is >= 0.)
    void restart(std::uint64_t t) {
        regime_.on = false;
        std::fill(slot_free_.begin(), slot_free_.end(), 0);
        std::fill(proc_free_.begin(), proc_free_.end(), 0);
        qi_ = pi_ = 0;
        done_ = t;
    }
    // Earliest cycle >= t at which the queue has a free slot for the next fragment.
    std::uint64_t room(std::uint64_t t) const { return std::max(t, slot_free_[qi_]); }
    // The cycle the next fragment's queue slot frees (room() is its max with t).
    std::uint64_t slot_free_next() const { return slot_free_[qi_]; }
    // The next fragment enters at e (>= room(e)); returns its dispatch cycle.
    [[gnu::always_inline]] std::uint64_t push(std::uint64_t e) {
        regime_.on = false;
        const std::uint64_t s = std::max(e + ez_, proc_free_[pi_]);
        proc_free_[pi_] = s + c_;
        slot_free_[qi_] = s;
        pi_ = branch_free::next(pi_, p_);
        qi_ = branch_free::next(qi_, q_);
        done_ = std::max(done_, s + c_);
        return s;
    }
    // m fragments from a rasterizer emitting `rate` a cycle, whose clock is
    // (t, used): each leaves at the rasterizer's next slot or when the queue
    // has room. Returns the cycles the rasterizer waited. The same as m times
    // room() and push(), with the state in registers.
    [[gnu::always_inline]] std::uint64_t shade(std::uint64_t& t_io, unsigned& used_io, unsigned rate, std::uint64_t m) {
        regime_.on = false;
        return step(t_io, used_io, rate, m);
    }

    // The same as shade(), for any m. A run of identical fragments is a
    // max-plus system with constant input, and shift-invariant: from a state
    // S, if one block of fragments leaves S + D (every ring entry, the
    // rasterizer's clock and the last finish later by D cycles, its slot count
    // the same), the next block leaves S + 2D, and so on. So a run steps one
    // block, compares, and jumps over the whole blocks left once the state
    // repeats; a pipe in its periodic regime (a long stretch of a game
    // frame's other fragments) is verified by one block wherever the regime
    // began. Its cost does not grow with the run's length.
    //
    // The regime outlives the run. Until something else changes the pipe
    // (a run too short to jump, which is stepped and clears the record:
    // keeping it through such runs returned under 5% on game frames;
    // push(), restart(), another cost), setups or c fragments between two
    // runs move only the rasterizer's clock. In a shader-bound pipe (game
    // frames keep it so) the processors, not the clock, decide when the next
    // fragments are dispatched: the run's fragments are stepped beside the
    // clock the regime would have had, and once the two clocks meet, every
    // fragment having been dispatched when the regime dispatches it, the
    // pipe is back in the regime and the rest of the run jumps. Nothing is
    // assumed: a fragment dispatched otherwise, or clocks that do not meet
    // within a block, and the run is verified afresh.
    [[gnu::always_inline]] std::uint64_t shade_run(std::uint64_t& t, unsigned& used, unsigned rate, std::uint64_t m) {
        if (stepwise) return shade(t, used, rate, m);
        if (m < kLongRun) {
            regime_.on &= m == 0;
            return step(t, used, rate, m);
        }
        if (regime_.on) return shade_from_regime(t, used, rate, m);
        return shade_long(t, used, rate, m);
    }
    static constexpr std::uint64_t kLongRun = 48;
    // Every run fragment by fragment: the reference the bulk runs are tested
    // against (rbcd-sim's hidden --gpu-stepwise; testbench/sim/test_gpu_properties.cpp).
    static inline bool stepwise = false;

    // A GPU-only timeline's walk of a tile without setups whose c fragments cut
    // its shaded run (rasterizer.cpp, Pure): `run` shaded fragments pending
    // before the tile's first, then the tile's fragments in order, its
    // non-collisionable ones spread as the rasterizer spreads them; each c
    // fragment takes the rasterizer's next slot after the run before it is
    // shaded. Returns the shaded fragments left pending after the last c
    // fragment. The same as shade_run() of each run and a slot between, with
    // the state loaded once a tile.
    std::uint64_t walk_tile_cut_at_c(const Tile& tile, std::uint64_t& t, unsigned& used, unsigned rate,
                                     std::uint64_t run);

    // Whether the last run left the pipe in a verified periodic regime that
    // the next run may continue (shade_run()).
    bool periodic() const { return regime_.on; }

    // The cycle every fragment pushed since restart() has finished.
    std::uint64_t done() const { return done_; }
    unsigned processors() const { return p_; }
    unsigned cycles_per_fragment() const { return c_; }
    // The service time of the fragments pushed from now on (a tile's shade=);
    // those in flight keep theirs.
    void set_cycles_per_fragment(unsigned c) {
        regime_.on &= c == c_;
        c_ = c;
    }

    // The block shade_long() compares states after: a multiple of the
    // processors' and the rasterizer's periods, and at least 16 fragments.
    std::uint64_t period_hint(unsigned rate) const {
        std::uint64_t b = std::lcm<std::uint64_t>(p_, rate);
        while (b < 16) b *= 2;
        return b;
    }
    // Whether this pipe's state is `o`'s later by `shift` cycles: every queue
    // slot and processor in age order and the last finish. Fed the same
    // fragments from a rasterizer clock later by `shift`, it then stays so
    // (the recurrences are shift-invariant), waits included.
    bool follows(const FragmentPipe& o, std::uint64_t shift) const {
        return c_ == o.c_ && shifted_from(o.slot_free_, o.qi_, o.proc_free_, o.pi_, o.done_, shift);
    }
    // Becomes `o` later by `shift` cycles.
    void follow(const FragmentPipe& o, std::uint64_t shift) {
        slot_free_ = o.slot_free_;
        proc_free_ = o.proc_free_;
        qi_ = o.qi_;
        pi_ = o.pi_;
        done_ = o.done_;
        shift_by(shift);
        regime_ = o.regime_;
        regime_.t += shift;
    }
    // The state in age order (oldest first): queue slots, then processors.
    void state(std::vector<std::uint64_t>& out) const {
        out.clear();
        for (unsigned a = 0; a < q_; ++a) out.push_back(slot_free_[(qi_ + a) % q_]);
        for (unsigned a = 0; a < p_; ++a) out.push_back(proc_free_[(pi_ + a) % p_]);
    }

private:
    // The recurrence's running state, held in locals by the loops below: the
    // rasterizer's clock (t, used), the last finish, the rings' positions.
    struct Regs {
        std::uint64_t t, done;
        unsigned used, qi, pi;
    };
    [[gnu::always_inline]] Regs load(std::uint64_t t, unsigned used) const { return Regs{t, done_, used, qi_, pi_}; }
    [[gnu::always_inline]] void store(const Regs& r, std::uint64_t& t, unsigned& used) {
        t = r.t;
        used = r.used;
        done_ = r.done;
        qi_ = r.qi;
        pi_ = r.pi;
    }
    // m fragments, leaving the periodic regime's record as it is: the
    // callers say whether the state stays on it.
    [[gnu::always_inline]] std::uint64_t step(std::uint64_t& t_io, unsigned& used_io, unsigned rate, std::uint64_t m) {
        Regs r = load(t_io, used_io);
        const std::uint64_t wait = shade_in(r, rate, m);
        store(r, t_io, used_io);
        return wait;
    }
    // shade_run() of a run after one that left the regime recorded. Out of
    // line: the walks that inline shade_run() keep their loops small.
    [[gnu::noinline]] std::uint64_t shade_from_regime(std::uint64_t& t, unsigned& used, unsigned rate, std::uint64_t m) {
        std::uint64_t wait = 0;
        m -= rejoin(t, used, rate, m, wait);
        if (regime_.on) return m ? wait + shade_in_regime(t, used, rate, m) : wait;
        if (m < kLongRun) return wait + step(t, used, rate, m);
        return wait + shade_long(t, used, rate, m);
    }
    // Steps the run's fragments from clock (t, used) beside the clock the
    // regime would have had, (regime_.t, regime_.used), while the two differ;
    // the rings stay the regime's as long as each fragment is dispatched when
    // the regime dispatches it. Returns the fragments stepped (their waits
    // added to `wait`). The regime stays recorded, with the clock it has
    // there, when the clocks met or the run ended first; a fragment
    // dispatched otherwise, or a block without meeting, clears it.
    std::uint64_t rejoin(std::uint64_t& t, unsigned& used, unsigned rate, std::uint64_t m, std::uint64_t& wait) {
        std::uint64_t gt = regime_.t;
        unsigned gu = regime_.used;
        std::uint64_t k = 0;
        for (; (t != gt || used != gu) && k < m; ++k) {
            if (k == regime_.block) {
                regime_.on = false;
                return k;
            }
            const std::uint64_t room = slot_free_[qi_];
            enter(gt, gu, rate, room);
            wait += enter(t, used, rate, room);
            const std::uint64_t regime_s = std::max(gt + ez_, proc_free_[pi_]);
            regime_.on = push(t) == regime_s;
            if (!regime_.on) return k + 1;
        }
        regime_.t = gt;
        regime_.used = gu;
        return k;
    }
    // The rest of a run that is in the periodic regime: the whole blocks in
    // one jump, the others stepped.
    std::uint64_t shade_in_regime(std::uint64_t& t, unsigned& used, unsigned rate, std::uint64_t m) {
        std::uint64_t wait = 0;
        const std::uint64_t jumps = m / regime_.block;
        if (jumps) {
            shift_by(jumps * regime_.delta);
            t += jumps * regime_.delta;
            wait += jumps * regime_.wait;
            m -= jumps * regime_.block;
        }
        wait += step(t, used, rate, m);
        regime_.t = t;
        regime_.used = used;
        return wait;
    }
    // The rasterizer's clock (t, used) as the next fragment enters the
    // queue, whose slot frees at `room`: the rasterizer's next slot, or the
    // slot's freeing if later. Returns the cycles it waited.
    [[gnu::always_inline]] static std::uint64_t enter(std::uint64_t& t, unsigned& used, unsigned rate,
                                                      std::uint64_t room) {
        if (used == rate) {
            ++t;
            used = 0;
        }
        if (room <= t) {
            ++used;
            return 0;
        }
        const std::uint64_t wait = room - t;
        t = room;
        used = 1;
        return wait;
    }
    // shade()'s loop on that state; shade() and walk_tile_cut_at_c() load it
    // once and store it once around as many runs as they have.
    [[gnu::always_inline]] std::uint64_t shade_in(Regs& r, unsigned rate, std::uint64_t m) {
        std::uint64_t t = r.t, done = r.done, wait = 0;
        unsigned used = r.used, qi = r.qi, pi = r.pi;
        std::uint64_t* const slot_free = slot_free_.data();
        std::uint64_t* const proc_free = proc_free_.data();
        for (std::uint64_t k = 0; k < m; ++k) {
            wait += enter(t, used, rate, slot_free[qi]);
            const std::uint64_t s = std::max(t + ez_, proc_free[pi]);
            proc_free[pi] = s + c_;
            slot_free[qi] = s;
            if (++pi == p_) pi = 0;
            if (++qi == q_) qi = 0;
            done = std::max(done, s + c_);
        }
        r = Regs{t, done, used, qi, pi};
        return wait;
    }

    std::uint64_t shade_long(std::uint64_t& t, unsigned& used, unsigned rate, std::uint64_t m) {
        // A setup just before the run leaves the rasterizer's clock off the
        // regime's cycle; the run's first fragment, waiting for the queue,
        // puts it back, so the first block compared is usually periodic.
        std::uint64_t wait = step(t, used, rate, 1);
        --m;
        const std::uint64_t block = period_hint(rate);
        // One block to compare and at least one to jump over.
        while (m >= 2 * block) {
            ref_slot_ = slot_free_;
            ref_proc_ = proc_free_;
            const unsigned ref_qi = qi_, ref_pi = pi_, ref_used = used;
            const std::uint64_t ref_t = t, ref_done = done_;
            const std::uint64_t block_wait = step(t, used, rate, block);
            m -= block;
            wait += block_wait;
            const std::uint64_t delta = t - ref_t;
            if (used == ref_used && delta > 0 && shifted_from(ref_slot_, ref_qi, ref_proc_, ref_pi, ref_done, delta)) {
                const std::uint64_t jumps = m / block;
                shift_by(jumps * delta);
                t += jumps * delta;
                wait += jumps * block_wait;
                m -= jumps * block;
                regime_.on = true;
                regime_.block = block;
                regime_.delta = delta;
                regime_.wait = block_wait;
                break;
            }
        }
        wait += step(t, used, rate, m);
        regime_.t = t;
        regime_.used = used;
        return wait;
    }
    // The rings and last finish are those given (positions qi, pi) later by
    // `shift`: every queue slot and processor in age order.
    bool shifted_from(const std::vector<std::uint64_t>& slot, unsigned qi, const std::vector<std::uint64_t>& proc,
                      unsigned pi, std::uint64_t done, std::uint64_t shift) const {
        return done_ == done + shift && same_shifted(slot_free_, qi_, slot, qi, shift) &&
               same_shifted(proc_free_, pi_, proc, pi, shift);
    }
    // The same state in age order, later by `shift`: the ring positions stay.
    void shift_by(std::uint64_t shift) {
        for (auto& v : slot_free_) v += shift;
        for (auto& v : proc_free_) v += shift;
        done_ += shift;
    }
    // Ring `now` read from position `at` equals ring `ref` read from `ref_at`,
    // entry by entry in age order, plus delta.
    static bool same_shifted(const std::vector<std::uint64_t>& now, unsigned at, const std::vector<std::uint64_t>& ref,
                             unsigned ref_at, std::uint64_t delta) {
        const std::size_t n = now.size();
        for (std::size_t a = 0, i = at, j = ref_at; a < n; ++a) {
            if (now[i] != ref[j] + delta) return false;
            if (++i == n) i = 0;
            if (++j == n) j = 0;
        }
        return true;
    }

    unsigned q_, p_, c_, ez_;
    std::vector<std::uint64_t> slot_free_;   // s_k of the last Q fragments (ring)
    std::vector<std::uint64_t> proc_free_;   // s_k + C of the last P fragments (ring)
    std::vector<std::uint64_t> ref_slot_, ref_proc_;   // shade_long's state a block before
    unsigned qi_ = 0, pi_ = 0;
    std::uint64_t done_ = 0;
    // The periodic regime shade_long() last verified: from the state after
    // the last run, with the rasterizer's clock then at (t, used), every
    // `block` fragments move the whole state `delta` cycles later and wait
    // `wait` cycles (the waits repeat with the states). Valid while `on`;
    // whatever changes the state but a run's own fragments clears it.
    struct Regime {
        bool on = false;
        std::uint64_t block = 0, delta = 0, wait = 0, t = 0;
        unsigned used = 0;
    } regime_;
};

// The block: the with-unit timeline's fragment queue and processors, with
// their counters and waveforms. The rasterizer drives it.
class fragment_processors : public sc_core::sc_module {
public:
    struct stats_t {
        std::uint64_t fragments = 0;            // fragments shaded
        std::uint64_t busy_cycles = 0;          // processor-cycles shading (each fragment x its C)
        std::uint64_t idle_cycles = 0;          // processor-cycles idle inside frames
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, fragments, "fragments shaded");
            RBCD_STAT(f, s, busy_cycles, "processor-cycles shading (fragments x cycles_per_fragment x shade= / 100)");
            RBCD_STAT(f, s, idle_cycles, "processor-cycles idle between a frame's start and end");
        }
    };

    fragment_processors(sc_core::sc_module_name name, const GpuConfig& g) : sc_module(name), pipe_(g) {}

    std::uint64_t room(std::uint64_t t) const { return pipe_.room(t); }
    [[gnu::always_inline]] std::uint64_t push(std::uint64_t e) {
        const std::uint64_t s = pipe_.push(e);
        ++stats_.fragments;
        if (vcd_) {
            vcd_->add_delta(vcd_queue_, e, +1);
            vcd_->add_delta(vcd_queue_, s, -1);
            vcd_->add_delta(vcd_busy_, s, +1);
            vcd_->add_delta(vcd_busy_, s + pipe_.cycles_per_fragment(), -1);
        }
        return s;
    }
    std::uint64_t done() const { return pipe_.done(); }
    void restart(std::uint64_t t) { pipe_.restart(t); }
    // For runs computed on the pipe directly (no waveforms): count them.
    FragmentPipe& pipe() { return pipe_; }
    void count(std::uint64_t fragments) { stats_.fragments += fragments; }
    // Frame accounting: a frame of `cycles` in which shading took `busy`
    // processor-cycles.
    void close_frame(std::uint64_t cycles, std::uint64_t busy) {
        const std::uint64_t all = cycles * pipe_.processors();
        stats_.busy_cycles += busy;
        stats_.idle_cycles += all > busy ? all - busy : 0;
    }

    const stats_t& stats() const { return stats_; }
    void attach_vcd(VcdWriter& vcd, const std::string& scope) {
        vcd_ = &vcd;
        vcd_queue_ = vcd.add(scope, "queue_occupancy", 17);
        vcd_busy_ = vcd.add(scope, "processors_busy", 9);
    }

private:
    FragmentPipe pipe_;
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_queue_ = 0, vcd_busy_ = 0;
};

} // namespace rbcd
