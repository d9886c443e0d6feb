#include "rbcd/hw/fragment_processors.h"

#include <vector>

#include "rbcd/common/fragment.h"
#include "rbcd/hw/even_split.h"

namespace rbcd {

// Out of line, in its own translation unit, on purpose: inlined into the
// rasterizer's feed_tile (as the same loop once was), it changed gcc's
// inlining of the GPU-only timelines on the path scenes take, which cost the
// default scene 3 to 5% (docs/performance.md, fourth pass).
std::uint64_t FragmentPipe::walk_tile_cut_at_c(const Tile& tile, std::uint64_t& t_io, unsigned& used_io,
                                               unsigned rate, std::uint64_t run) {
    const std::size_t n = tile.frags.size();
    // The usual tile of a rasterizer's order: its non-collisionable fragments
    // spread evenly, at most two before a collisionable one.
    if (!tile.ordered_other && tile.other <= 2 * std::uint64_t(n)) return walk_spread_cut_at_c(tile, t_io, used_io, rate, run);
    Regs r = load(t_io, used_io);
    // A long run goes through shade_long, which takes the state from the
    // members: stored for it, and loaded back.
    const auto shade_run_here = [&](std::uint64_t m) {
        if (m <= kLongRun) {
            shade_in(r, rate, m);
            return;
        }
        store(r, t_io, used_io);
        shade_long(t_io, used_io, rate, m);
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

// walk_tile_cut_at_c for a tile whose non-collisionable fragments are spread
// evenly, at most two between collisionable ones, in two passes. Whether a
// fragment is c follows the input, so a loop that branches on it mispredicts
// about every other fragment of a tile whose objects are interleaved (the
// rasterizer's order over many small primitives): that cost a worker of
// rbcd-bench's interleaved trace 10 ms of its 129. The first pass lists the
// tile's shaded fragments, each with the number of c fragments (rasterizer
// slots, nothing else) just before it, without a branch on c; the second
// takes the slots and shades the fragments, as the walk above does one by one.
std::uint64_t FragmentPipe::walk_spread_cut_at_c(const Tile& tile, std::uint64_t& t_io, unsigned& used_io,
                                                 unsigned rate, std::uint64_t run) {
    const std::size_t n = tile.frags.size();
    // What follows the tile's last c fragment stays pending, returned.
    std::size_t last = n;
    while (last > 0 && !tile.frags[last - 1].culled) --last;
    if (last == 0) return run + tile.other + n;   // no c fragment (the caller's tiles have one)
    // Fragments [0, last) are walked: the shaded ones among them, and the
    // others spread before them, with two entries of room past the last.
    thread_local std::vector<std::uint32_t> slots_before;
    if (slots_before.size() < last + 2 * last + 2) slots_before.resize(3 * last + 2);
    std::uint32_t* const e = slots_before.data();
    EvenSplit split(tile.other, n + 1);
    std::uint64_t before = 0;
    std::size_t m = 0;
    std::uint32_t pc = 0;   // c fragments since the last shaded one
    for (std::size_t i = 0; i < last; ++i) {
        const std::uint64_t upto = split.next();
        const std::size_t k = static_cast<std::size_t>(upto - before);   // 0, 1 or 2 others before fragment i
        before = upto;
        // The first of them takes the slots before it; the second none.
        e[m] = pc;
        e[m + 1] = 0;
        pc &= 0u - std::uint32_t(k == 0);
        m += k;
        // Then fragment i: shaded, it takes them (if no other did); c, one more slot.
        const bool c = tile.frags[i].culled;
        e[m] = pc;
        m += !c;
        pc = (pc + 1) & (0u - std::uint32_t(c));
    }
    Regs r = load(t_io, used_io);
    // The run pending before the tile comes first (it may be long).
    if (run <= kLongRun) {
        shade_in(r, rate, run);
    } else {
        store(r, t_io, used_io);
        shade_long(t_io, used_io, rate, run);
        r = load(t_io, used_io);
    }
    // Each shaded fragment: the c fragments' slots and its own taken at once
    // (at most one cycle boundary crossed, when they are no more than the
    // rate: no branch on where the cycle ends), then shade()'s step.
    std::uint64_t t = r.t, done = r.done;
    unsigned used = r.used, qi = r.qi, pi = r.pi;
    std::uint64_t* const slot_free = slot_free_.data();
    std::uint64_t* const proc_free = proc_free_.data();
    const auto take_slots = [&](std::uint64_t k) {
        const std::uint64_t u = used + k;
        if (k <= rate) {
            const unsigned over = u > rate;
            t += over;
            used = static_cast<unsigned>(u - (over ? rate : 0));
        } else {
            t += (u - 1) / rate;
            used = static_cast<unsigned>((u - 1) % rate + 1);
        }
    };
    for (std::size_t j = 0; j < m; ++j) {
        take_slots(std::uint64_t(e[j]) + 1);
        const std::uint64_t room = slot_free[qi];
        if (room > t) {
            t = room;
            used = 1;
        }
        enter(t, done, qi, pi, slot_free, proc_free);
    }
    take_slots(pc);
    r = Regs{t, done, used, qi, pi};
    store(r, t_io, used_io);
    return (tile.other - before) + (n - last);
}

} // namespace rbcd
