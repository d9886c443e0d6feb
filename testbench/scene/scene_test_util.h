// Helpers of the scene tests: scene text builders, a stream capture that checks
// the stream's structural rules, and a per-pixel depth-interval overlap check
// (independent of the unit's model) to tell which objects collide.
#pragma once
#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>

#include "rbcd/common/errors.h"

#include "rbcd/common/fragment.h"
#include "rbcd/scene/scene_source.h"

namespace scene_test {

using rbcd::Facing;
using rbcd::Fragment;
using rbcd::FragmentSource;
using rbcd::StreamHeader;
using rbcd::Tile;

struct V3 {
    double x = 0, y = 0, z = 0;
};

inline std::string v3(const V3& v) {
    std::ostringstream s;
    s.precision(17);
    s << "[" << v.x << ", " << v.y << ", " << v.z << "]";
    return s.str();
}

struct Cam {
    V3 eye{0, 0, 0}, target{0, 0, -1};
    double fov_y = 60, near = 0.1, far = 100;
};

inline std::string scene_header(unsigned w, unsigned h, unsigned frames, const Cam& c = Cam{}) {
    std::ostringstream s;
    s << "format = \"rbcd-scene 1\"\nframes = " << frames << "\n[screen]\nwidth = " << w << "\nheight = " << h
      << "\n[camera]\neye = " << v3(c.eye) << "\ntarget = " << v3(c.target) << "\nfov_y = " << c.fov_y
      << "\nnear = " << c.near << "\nfar = " << c.far << "\n";
    return s.str();
}

struct Obj {
    std::string name = "obj";
    std::string mesh = "sphere";
    std::optional<int> id;
    V3 pos{0, 0, -5}, rot{0, 0, 0}, scale{1, 1, 1};
    std::string cull = "back";
    int segments = 0;    // 0: not written
    std::string extra;   // appended verbatim (keys, [[object.key]] tables)
};

inline std::string object_text(const Obj& o) {
    std::ostringstream s;
    s << "[[object]]\nname = \"" << o.name << "\"\nmesh = \"" << o.mesh << "\"\n";
    if (o.id) s << "id = " << *o.id << "\n";
    if (o.segments) s << "segments = " << o.segments << "\n";
    s << "cull = \"" << o.cull << "\"\nposition = " << v3(o.pos) << "\nrotation = " << v3(o.rot)
      << "\nscale = " << v3(o.scale) << "\n" << o.extra;
    return s.str();
}

struct Frame {
    std::uint64_t frame = 0;
    std::vector<Tile> tiles;
    std::size_t fragments() const {
        std::size_t n = 0;
        for (const auto& t : tiles) n += t.frags.size();
        return n;
    }
    std::uint64_t other() const {
        std::uint64_t n = 0;
        for (const auto& t : tiles) n += t.other;
        return n;
    }
};

struct Capture {
    StreamHeader h;
    std::vector<Frame> frames;
};

// Drains `src`, checking what formats.md and the scene contract require of the
// stream: frames counting up from 0, tiles in row-major order without repeats,
// fragments inside their tile and the screen, depths within depth_bits, no
// tile without any fragment.
inline Capture capture(FragmentSource& src) {
    Capture c;
    c.h = src.header();
    const StreamHeader& h = c.h;
    const std::uint32_t tiles_x = (h.screen_w + h.tile_w - 1) / h.tile_w;
    const std::uint32_t tiles_y = (h.screen_h + h.tile_h - 1) / h.tile_h;
    Tile t;
    long long last_index = -1;
    for (;;) {
        auto ev = src.next(t);
        if (ev == FragmentSource::Event::End) break;
        if (ev == FragmentSource::Event::Frame) {
            REQUIRE(t.frame == c.frames.size());
            c.frames.push_back(Frame{t.frame, {}});
            last_index = -1;
            continue;
        }
        REQUIRE(!c.frames.empty());
        REQUIRE(t.frame == c.frames.back().frame);
        REQUIRE(t.col < tiles_x);
        REQUIRE(t.row < tiles_y);
        const long long index = (long long)t.row * tiles_x + t.col;
        REQUIRE(index > last_index);
        last_index = index;
        REQUIRE((!t.frags.empty() || t.other > 0));
        // One assertion per tile: millions of per-fragment ones would dominate the run time.
        std::size_t bad = 0;
        for (const auto& f : t.frags) {
            bad += f.x < t.col * h.tile_w || f.x >= (t.col + 1) * h.tile_w || f.y < t.row * h.tile_h ||
                   f.y >= (t.row + 1) * h.tile_h || f.x >= h.screen_w || f.y >= h.screen_h ||
                   f.depth >= (1ull << h.depth_bits);
        }
        INFO("frame " << t.frame << " tile " << t.col << "," << t.row);
        REQUIRE(bad == 0);
        c.frames.back().tiles.push_back(t);
    }
    return c;
}

inline Capture capture_text(const std::string& text, const rbcd::scene::SceneLimits& lim = {}) {
    auto src = rbcd::scene::SceneSource::from_text(text, "", "<test>", lim);
    return capture(*src);
}

// Fragments of one frame per pixel (row-major), in stream order.
inline std::vector<std::vector<Fragment>> per_pixel(const Frame& f, const StreamHeader& h) {
    std::vector<std::vector<Fragment>> px(std::size_t(h.screen_w) * h.screen_h);
    for (const auto& t : f.tiles)
        for (const auto& fr : t.frags) px[std::size_t(fr.y) * h.screen_w + fr.x].push_back(fr);
    return px;
}

struct Interval {
    std::uint32_t lo, hi;
};

// Inside-intervals of each object along one pixel's ray: fronts open, backs
// close (nested surfaces counted), a back without an open front is ignored.
inline std::map<std::uint32_t, std::vector<Interval>> intervals(std::vector<Fragment> frags) {
    std::sort(frags.begin(), frags.end(), [](const Fragment& a, const Fragment& b) {
        if (a.depth != b.depth) return a.depth < b.depth;
        return a.facing == Facing::Front && b.facing == Facing::Back;
    });
    std::map<std::uint32_t, std::vector<Interval>> out;
    std::map<std::uint32_t, std::pair<int, std::uint32_t>> open;   // id -> (depth count, start)
    for (const auto& f : frags) {
        auto& o = open[f.id];
        if (f.facing == Facing::Front) {
            if (o.first++ == 0) o.second = f.depth;
        } else if (o.first > 0 && --o.first == 0) {
            out[f.id].push_back({o.second, f.depth});
        }
    }
    return out;
}

using Pair = std::pair<std::uint32_t, std::uint32_t>;

using PixelFrags = std::vector<std::vector<Fragment>>;

// Pairs (smaller id first) whose inside-intervals overlap at some pixel.
inline std::set<Pair> colliding_pairs(const PixelFrags& px) {
    std::set<Pair> pairs;
    for (std::size_t i = 0; i < px.size(); ++i) {
        if (px[i].size() < 4) continue;
        auto iv = intervals(px[i]);
        for (auto a = iv.begin(); a != iv.end(); ++a)
            for (auto b = std::next(a); b != iv.end(); ++b)
                for (const auto& ia : a->second)
                    for (const auto& ib : b->second)
                        if (ia.lo <= ib.hi && ib.lo <= ia.hi) pairs.insert({a->first, b->first});
    }
    return pairs;
}

inline std::set<Pair> colliding_pairs(const Frame& f, const StreamHeader& h) { return colliding_pairs(per_pixel(f, h)); }

// Pixels where both objects have fragments (their screen footprints overlap).
inline std::size_t shared_pixels(const PixelFrags& px, std::uint32_t a, std::uint32_t b) {
    std::size_t n = 0;
    for (const auto& p : px) {
        bool ha = false, hb = false;
        for (const auto& fr : p) {
            ha |= fr.id == a;
            hb |= fr.id == b;
        }
        n += ha && hb;
    }
    return n;
}

inline std::size_t shared_pixels(const Frame& f, const StreamHeader& h, std::uint32_t a, std::uint32_t b) {
    return shared_pixels(per_pixel(f, h), a, b);
}

// The one-line message a bad scene text gives ("" if it is accepted); drain:
// render every frame too (errors found while rendering).
inline std::string error_of(const std::string& text, const rbcd::scene::SceneLimits& lim = {}, bool drain = false) {
    try {
        auto s = rbcd::scene::SceneSource::from_text(text, "", "bad.toml", lim);
        if (drain) capture(*s);
    } catch (const rbcd::InputError& e) {
        return e.what();
    }
    return "";
}

} // namespace scene_test
