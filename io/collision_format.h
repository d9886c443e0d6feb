// Text lines of the collision output file (formats.md, "Collision output").
#pragma once
#include <charconv>
#include <cstdint>
#include <string>

#include "rbcd/common/records.h"

namespace rbcd {

inline void append_uint(std::string& s, std::uint64_t v) {
    char buf[24];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    s.append(buf, r.ptr);
}
inline void append_frame_line(std::string& s, std::uint64_t n) {
    s += "frame ";
    append_uint(s, n);
    s += '\n';
}
inline void append_hit_line(std::string& s, const HitRecord& h) {
    s += "hit ";
    append_uint(s, h.x); s += ' ';
    append_uint(s, h.y); s += ' ';
    append_uint(s, h.id_a); s += ' ';
    append_uint(s, h.id_b); s += ' ';
    append_uint(s, h.dq); s += '\n';
}
inline void append_overflow_line(std::string& s, const OverflowRecord& o) {
    s += "overflow ";
    append_uint(s, o.col); s += ' ';
    append_uint(s, o.row); s += ' ';
    append_uint(s, o.lists); s += ' ';
    append_uint(s, o.dropped); s += '\n';
}
constexpr const char* kCollisionsMagic = "rbcd-collisions 1\n";

} // namespace rbcd
