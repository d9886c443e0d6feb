#include "rbcd/io/collision_check.h"

#include <charconv>
#include <vector>

#include "rbcd/common/errors.h"

namespace rbcd {

namespace {

// Fields separated by one space, decimal without sign or leading zeros
// (formats.md); false on anything else.
bool split_numbers(std::string_view s, std::vector<std::uint64_t>& out, std::size_t n) {
    out.clear();
    std::size_t i = 0;
    while (out.size() < n) {
        const std::size_t b = i;
        while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
        if (i == b || (i - b > 1 && s[b] == '0')) return false;
        std::uint64_t v = 0;
        const auto r = std::from_chars(s.data() + b, s.data() + i, v);
        if (r.ec != std::errc() || r.ptr != s.data() + i) return false;
        out.push_back(v);
        if (out.size() < n) {
            if (i >= s.size() || s[i] != ' ') return false;
            ++i;
        }
    }
    return i == s.size();
}

} // namespace

CollisionFileCheck::CollisionFileCheck(std::string name, std::uint64_t first, std::uint64_t frames)
    : name_(std::move(name)), first_(first), frames_(frames) {}

void CollisionFileCheck::fail(const std::string& what) const { throw input_error_at(name_, line_no_, what); }

void CollisionFileCheck::line(std::string_view s) {
    ++line_no_;
    if (s.size() > kMaxLineBytes) fail("not a collisions file: a line longer than " + std::to_string(kMaxLineBytes) + " bytes");
    if (line_no_ == 1) {
        if (s != "rbcd-collisions 1") fail("not a collisions file (expected 'rbcd-collisions 1')");
        return;
    }
    static thread_local std::vector<std::uint64_t> v;
    if (s.substr(0, 6) == "frame ") {
        if (!split_numbers(s.substr(6), v, 1)) fail("malformed frame line (expected 'frame N')");
        const std::uint64_t expected = first_ + seen_frames_;
        if (seen_frames_ >= frames_)
            fail("frame " + std::to_string(v[0]) + " beyond the part's frames " + std::to_string(first_) + ".." +
                 std::to_string(first_ + frames_ - 1));
        if (v[0] != expected) fail("frame " + std::to_string(v[0]) + " where frame " + std::to_string(expected) + " was expected");
        ++seen_frames_;
        return;
    }
    const bool hit = s.substr(0, 4) == "hit ", overflow = s.substr(0, 9) == "overflow ";
    if (!hit && !overflow) fail("not a frame, hit or overflow line");
    if (seen_frames_ == 0) fail("a record before the first frame line");
    if (hit) {
        if (!split_numbers(s.substr(4), v, 5)) fail("malformed hit line (expected 'hit X Y ID_A ID_B DQ')");
        for (std::size_t k = 0; k < 5; ++k)
            if (v[k] > UINT32_MAX) fail("hit: a field beyond 32 bits");
        if (v[2] >= v[3]) fail("hit: id_a must be below id_b");
    } else {
        if (!split_numbers(s.substr(9), v, 4)) fail("malformed overflow line (expected 'overflow COL ROW LISTS DROPPED')");
        for (std::size_t k = 0; k < 3; ++k)
            if (v[k] > UINT32_MAX) fail("overflow: a field beyond 32 bits");
    }
}

void CollisionFileCheck::finish(bool ended_with_lf) {
    if (line_no_ == 0) throw input_error_at(name_, 1, "not a collisions file (empty)");
    if (!ended_with_lf) fail("the last line does not end with LF (the file is cut short)");
    if (seen_frames_ != frames_)
        throw InputError(name_ + ": " + std::to_string(seen_frames_) + " frame lines where the part has " +
                         std::to_string(frames_) + " frames (" + std::to_string(first_) + ".." +
                         std::to_string(first_ + frames_ - 1) + ")");
}

} // namespace rbcd
