// floor(j * total / parts) for j = 1, 2, ...: incremental, no division per
// step. How a tile's non-collisionable fragments are spread between its
// collisionable ones when the trace does not order them (docs/timing.md); the
// rasterizer's walks and the fragment pipe's timeline-2 walk share it.
#pragma once
#include <cstdint>

namespace rbcd {

struct EvenSplit {
    std::uint64_t whole, frac, parts, q = 0, r = 0;
    EvenSplit(std::uint64_t total, std::uint64_t p) : whole(total / p), frac(total % p), parts(p) {}
    std::uint64_t next() {
        q += whole;
        r += frac;
        const bool carry = r >= parts;
        q += carry;
        r -= carry ? parts : 0;
        return q;
    }
};

} // namespace rbcd
