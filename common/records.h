// Records the unit writes to memory, and their 16-byte little-endian layout in
// the output region (docs/memory-layout.md).
#pragma once
#include <cstdint>
#include <cstring>

namespace rbcd {

struct HitRecord {
    std::uint32_t x = 0, y = 0;
    std::uint32_t id_a = 0, id_b = 0;   // id_a < id_b
    std::uint32_t dq = 0;               // the back face's quantized depth
    bool operator==(const HitRecord& o) const {
        return x == o.x && y == o.y && id_a == o.id_a && id_b == o.id_b && dq == o.dq;
    }
};

struct OverflowRecord {
    std::uint32_t col = 0, row = 0;
    std::uint32_t lists = 0;            // lists that overflowed in the tile
    std::uint64_t dropped = 0;          // fragments dropped in the tile
    bool operator==(const OverflowRecord& o) const {
        return col == o.col && row == o.row && lists == o.lists && dropped == o.dropped;
    }
};

// One record in memory: 4 little-endian 32-bit words.
//   hit:      w0 = 1<<30 | x, w1 = y,   w2 = id_a<<16 | id_b, w3 = dq
//   overflow: w0 = 2<<30 | col, w1 = row, w2 = lists,          w3 = dropped (saturated at 2^32-1)
// x and col stay below 2^16 (screens are at most 65535 pixels wide), so bits 16..29 are zero.
constexpr unsigned kRecordBytes = 16;
enum class RecordKind : std::uint32_t { Hit = 1, Overflow = 2 };

struct MemRecord {
    std::uint32_t w[4] = {0, 0, 0, 0};

    static MemRecord hit(const HitRecord& h) {
        MemRecord r;
        r.w[0] = (1u << 30) | h.x;
        r.w[1] = h.y;
        r.w[2] = (h.id_a << 16) | h.id_b;
        r.w[3] = h.dq;
        return r;
    }
    static MemRecord overflow(const OverflowRecord& o) {
        MemRecord r;
        r.w[0] = (2u << 30) | o.col;
        r.w[1] = o.row;
        r.w[2] = o.lists;
        r.w[3] = o.dropped > 0xffffffffull ? 0xffffffffu : static_cast<std::uint32_t>(o.dropped);
        return r;
    }
    RecordKind kind() const { return static_cast<RecordKind>(w[0] >> 30); }
    HitRecord as_hit() const { return {w[0] & 0x3fffffffu, w[1], w[2] >> 16, w[2] & 0xffffu, w[3]}; }
    OverflowRecord as_overflow() const { return {w[0] & 0x3fffffffu, w[1], w[2], w[3]}; }

    void store(unsigned char* p) const {
        for (int i = 0; i < 4; ++i)
            for (int b = 0; b < 4; ++b) p[4 * i + b] = static_cast<unsigned char>(w[i] >> (8 * b));
    }
    static MemRecord load(const unsigned char* p) {
        MemRecord r;
        for (int i = 0; i < 4; ++i) {
            std::uint32_t v = 0;
            for (int b = 0; b < 4; ++b) v |= static_cast<std::uint32_t>(p[4 * i + b]) << (8 * b);
            r.w[i] = v;
        }
        return r;
    }
};

} // namespace rbcd
