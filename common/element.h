// The ZEB element and its sort key: the one definition both the SystemC model
// and the untimed reference model use (rbcd-contract.md, "Terms" and
// "Sorted insertion"). Algorithms live elsewhere, separately in each model.
#pragma once
#include <cstdint>

#include "rbcd/common/fragment.h"

namespace rbcd {

enum class TiePolicy { FrontFirst, Arrival };
enum class OutputMode { Raw, Pixel, Tile };

struct Element {
    std::uint32_t dq = 0;     // quantized depth, z_bits wide
    std::uint32_t id = 0;     // id_bits wide
    Facing facing = Facing::Front;
};

// dq keeps the top z_bits of a depth_bits-wide depth; widened when z_bits > depth_bits.
// 64-bit arithmetic because either shift may reach 31 and z_bits may be 32.
inline std::uint32_t quantize_depth(std::uint32_t depth, unsigned depth_bits, unsigned z_bits) {
    const std::uint64_t d = depth;
    if (z_bits <= depth_bits) return static_cast<std::uint32_t>(d >> (depth_bits - z_bits));
    return static_cast<std::uint32_t>(d << (z_bits - depth_bits));
}

// Comparable key: under front_first (dq, facing) so a front face wins a tie;
// under arrival dq alone, and ties keep arrival order through "insert after equals".
inline std::uint64_t sort_key(const Element& e, TiePolicy tie) {
    return tie == TiePolicy::FrontFirst
               ? (static_cast<std::uint64_t>(e.dq) << 1) | static_cast<std::uint64_t>(e.facing)
               : static_cast<std::uint64_t>(e.dq);
}

// Bit layout of an element in a ZEB word: [dq | id | facing], facing in bit 0.
// z_bits + id_bits + 1 <= 49 bits, so a 64-bit word always holds one.
struct ElementLayout {
    unsigned z_bits = 24, id_bits = 7;
    unsigned width() const { return z_bits + id_bits + 1; }
    std::uint64_t pack(const Element& e) const {
        return (static_cast<std::uint64_t>(e.dq) << (id_bits + 1)) |
               (static_cast<std::uint64_t>(e.id) << 1) | static_cast<std::uint64_t>(e.facing);
    }
    Element unpack(std::uint64_t w) const {
        Element e;
        e.facing = static_cast<Facing>(w & 1u);
        e.id = static_cast<std::uint32_t>((w >> 1) & ((1ull << id_bits) - 1));
        e.dq = static_cast<std::uint32_t>(w >> (id_bits + 1));
        return e;
    }
};

} // namespace rbcd
