// Drivers and checkers shared by the hardware tests.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/hw/collision_sink.h"
#include "rbcd/hw/rbcd_system.h"
#include "rbcd/io/collision_format.h"
#include "rbcd/io/memory_source.h"

namespace rbcd::tb {

inline Fragment frag(std::uint32_t x, std::uint32_t y, std::uint32_t depth, std::uint32_t id, char facing,
                     bool culled = false) {
    Fragment f;
    f.x = x;
    f.y = y;
    f.depth = depth;
    f.id = id;
    f.facing = facing == 'B' ? Facing::Back : Facing::Front;
    f.culled = culled;
    return f;
}

inline Tile tile(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::vector<Fragment> frags,
                 std::uint64_t other = 0) {
    Tile t;
    t.frame = frame;
    t.col = col;
    t.row = row;
    t.other = other;
    t.frags = std::move(frags);
    return t;
}

// Elaborates the whole system over `src` and runs it: one per test case (process).
struct SystemRun {
    RecordingSink sink;
    std::unique_ptr<rbcd_system> sys;
    SystemRun(const SimConfig& cfg, FragmentSource& src) {
        sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
        sys = std::make_unique<rbcd_system>("rbcd", cfg, src, sink);
        sys->run();
    }
    std::vector<HitRecord> hits(std::size_t frame_index = 0) const {
        std::vector<HitRecord> v;
        for (const auto& r : sink.frames.at(frame_index).records)
            if (auto* h = std::get_if<HitRecord>(&r)) v.push_back(*h);
        return v;
    }
};

// The records as the --collisions file would list them (without the magic line).
inline std::string to_text(const RecordingSink& s) {
    std::string out;
    for (const auto& f : s.frames) {
        append_frame_line(out, f.frame);
        for (const auto& r : f.records) {
            if (auto* h = std::get_if<HitRecord>(&r)) append_hit_line(out, *h);
            else append_overflow_line(out, std::get<OverflowRecord>(r));
        }
    }
    return out;
}

} // namespace rbcd::tb
