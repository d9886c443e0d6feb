#include "rbcd/hw/fragment_processors.h"

#include "rbcd/common/fragment.h"
#include "rbcd/hw/even_split.h"

namespace rbcd {

// Out of line, in its own translation unit, on purpose: inlined into the
// rasterizer's feed_tile, it changes gcc's inlining of the GPU-only timelines
// on the path scenes take, which costs the default scene 3 to 5%
// (docs/performance.md, "The model").
std::uint64_t FragmentPipe::walk_tile_cut_at_c(const Tile& tile, std::uint64_t& t_io, unsigned& used_io,
                                               unsigned rate, std::uint64_t run) {
    Regs r = load(t_io, used_io);
    // A long run, or any run while the pipe is in a periodic regime, goes
    // through shade_run, which takes the state from the members: stored for
    // it, and loaded back. A short run stepped here leaves the regime's
    // record behind.
    const auto shade_run_here = [&](std::uint64_t m) {
        if (m == 0) return;
        if (m < kLongRun || stepwise) {
            regime_.on = false;
            shade_in(r, rate, m);
            return;
        }
        store(r, t_io, used_io);
        shade_run(t_io, used_io, rate, m);
        r = load(t_io, used_io);
    };
    const auto cut = [&] {
        shade_run_here(run);
        run = 0;
        // The c fragment: the rasterizer's next slot, nothing else.
        if (r.used == rate) {
            ++r.t;
            r.used = 0;
        }
        ++r.used;
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
    store(r, t_io, used_io);
    return run;
}

} // namespace rbcd
