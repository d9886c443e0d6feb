#include "rbcd/hw/fragment_processors.h"

#include "rbcd/common/fragment.h"
#include "rbcd/hw/even_split.h"

namespace rbcd {

// Out of line, in its own translation unit, on purpose: inlined into the
// rasterizer's feed_tile (as the same loop once was), it changed gcc's
// inlining of the GPU-only timelines on the path scenes take, which cost the
// default scene 3 to 5% (docs/performance.md, fourth pass).
std::uint64_t FragmentPipe::walk_tile_cut_at_c(const Tile& tile, std::uint64_t& t_io, unsigned& used_io,
                                               unsigned rate, std::uint64_t run) {
    std::uint64_t t = t_io, done = done_;
    unsigned used = used_io, qi = qi_, pi = pi_;
    std::uint64_t* const slot_free = slot_free_.data();
    std::uint64_t* const proc_free = proc_free_.data();
    // shade() with the state in these locals; a long run stores them for
    // shade_long and loads them back.
    const auto shade_run_here = [&](std::uint64_t m) {
        if (m > kLongRun) {
            t_io = t;
            used_io = used;
            done_ = done;
            qi_ = qi;
            pi_ = pi;
            shade_long(t_io, used_io, rate, m);
            t = t_io;
            used = used_io;
            done = done_;
            qi = qi_;
            pi = pi_;
            return;
        }
        for (std::uint64_t k = 0; k < m; ++k) {
            if (used == rate) {
                ++t;
                used = 0;
            }
            const std::uint64_t room = slot_free[qi];
            if (room > t) {
                t = room;
                used = 0;
            }
            ++used;
            const std::uint64_t s = std::max(t + ez_, proc_free[pi]);
            proc_free[pi] = s + c_;
            slot_free[qi] = s;
            if (++pi == p_) pi = 0;
            if (++qi == q_) qi = 0;
            done = std::max(done, s + c_);
        }
    };
    const auto cut = [&] {
        shade_run_here(run);
        run = 0;
        // The c fragment: the rasterizer's next slot, nothing else.
        if (used == rate) {
            ++t;
            used = 0;
        }
        ++used;
    };
    const std::size_t n = tile.frags.size();
    if (tile.ordered_other) {
        std::size_t k = 0;
        for (std::size_t i = 0; i < n; ++i) {
            for (; k < tile.other_runs.size() && tile.other_runs[k].before <= i; ++k) run += tile.other_runs[k].count;
            if (tile.frags[i].culled) cut();
            else ++run;
        }
        for (; k < tile.other_runs.size(); ++k) run += tile.other_runs[k].count;
    } else {
        EvenSplit split(tile.other, n + 1);
        std::uint64_t before = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t upto = split.next();
            run += upto - before;
            before = upto;
            if (tile.frags[i].culled) cut();
            else ++run;
        }
        run += tile.other - before;
    }
    t_io = t;
    used_io = used;
    done_ = done;
    qi_ = qi;
    pi_ = pi;
    return run;
}

} // namespace rbcd
