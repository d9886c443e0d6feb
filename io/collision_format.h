// Text lines of the collision output file (formats.md, "Collision output").
#pragma once
#include <charconv>
#include <cstring>
#include <cstdint>
#include <string>

#include "rbcd/common/records.h"

namespace rbcd {

inline void append_uint(std::string& s, std::uint64_t v) {
    char buf[24];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    s.append(buf, r.ptr);
}
// A record's line is formatted in a local buffer and appended once: the
// string's appends, field by field, cost five times the formatting.
inline char* put_uint(char* p, std::uint64_t v) { return std::to_chars(p, p + 20, v).ptr; }
inline void append_frame_line(std::string& s, std::uint64_t n) {
    char buf[6 + 20 + 1];
    std::memcpy(buf, "frame ", 6);
    char* p = put_uint(buf + 6, n);
    *p++ = '\n';
    s.append(buf, p);
}
inline void append_hit_line(std::string& s, const HitRecord& h) {
    char buf[4 + 5 * 21];
    std::memcpy(buf, "hit ", 4);
    char* p = put_uint(buf + 4, h.x);
    *p++ = ' ';
    p = put_uint(p, h.y);
    *p++ = ' ';
    p = put_uint(p, h.id_a);
    *p++ = ' ';
    p = put_uint(p, h.id_b);
    *p++ = ' ';
    p = put_uint(p, h.dq);
    *p++ = '\n';
    s.append(buf, p);
}
inline void append_overflow_line(std::string& s, const OverflowRecord& o) {
    char buf[9 + 4 * 21];
    std::memcpy(buf, "overflow ", 9);
    char* p = put_uint(buf + 9, o.col);
    *p++ = ' ';
    p = put_uint(p, o.row);
    *p++ = ' ';
    p = put_uint(p, o.lists);
    *p++ = ' ';
    p = put_uint(p, o.dropped);
    *p++ = '\n';
    s.append(buf, p);
}
constexpr const char* kCollisionsMagic = "rbcd-collisions 1\n";

} // namespace rbcd
