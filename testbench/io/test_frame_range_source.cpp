// FrameRangeSource (rbcd-sim --frames): only the chosen frames pass, with their
// own numbers and tiles; reading stops after the last; malformed ranges are
// InputErrors naming --frames.
#include <catch2/catch.hpp>

#include <memory>
#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/io/frame_range_source.h"
#include "rbcd/io/memory_source.h"

using namespace rbcd;
using Catch::Matchers::StartsWith;
using Event = FragmentSource::Event;

namespace {

// Frames 0..4, frame n holding n tiles at column n (rows 0..n-1).
std::unique_ptr<MemorySource> five_frames() {
    auto m = std::make_unique<MemorySource>(StreamHeader{});
    for (std::uint64_t f = 0; f < 5; ++f) {
        m->add_frame(f);
        for (std::uint32_t r = 0; r < f; ++r) {
            Tile t;
            t.frame = f;
            t.col = static_cast<std::uint32_t>(f);
            t.row = r;
            m->add_tile(t);
        }
    }
    return m;
}

// "F<n>" per frame, "T<col>.<row>" per tile.
std::vector<std::string> events(FragmentSource& s) {
    std::vector<std::string> out;
    Tile t;
    for (;;) {
        const Event ev = s.next(t);
        if (ev == Event::End) break;
        out.push_back(ev == Event::Frame ? "F" + std::to_string(t.frame)
                                         : "T" + std::to_string(t.col) + "." + std::to_string(t.row));
    }
    return out;
}

} // namespace

TEST_CASE("frame range passes only its frames with their numbers", "[frames]") {
    using V = std::vector<std::string>;
    FrameRangeSource mid(five_frames(), parse_frame_range("2:3"));
    CHECK(events(mid) == V{"F2", "T2.0", "T2.1", "F3", "T3.0", "T3.1", "T3.2"});
    Tile t;
    CHECK(mid.next(t) == Event::End);   // stays at End

    FrameRangeSource open(five_frames(), parse_frame_range("4:"));
    CHECK(events(open) == V{"F4", "T4.0", "T4.1", "T4.2", "T4.3"});
    FrameRangeSource one(five_frames(), parse_frame_range("0"));
    CHECK(events(one) == V{"F0"});
}

TEST_CASE("a frame range that selects no frame is refused naming the input's frame count", "[frames]") {
    FrameRangeSource past(five_frames(), parse_frame_range("7:9"));
    CHECK_THROWS_WITH(events(past), "--frames: 7:9 selects no frame: the input has 5 frames (0..4)");
    FrameRangeSource open(five_frames(), parse_frame_range("5:"));
    CHECK_THROWS_WITH(events(open), "--frames: 5: selects no frame: the input has 5 frames (0..4)");
    CHECK_THROWS_WITH(parse_frame_range(""), Catch::Matchers::Contains("--frames: empty value"));
}

TEST_CASE("frame range stops reading after its last frame", "[frames]") {
    auto m = five_frames();
    MemorySource* inner = m.get();
    FrameRangeSource s(std::move(m), parse_frame_range("0:1"));
    events(s);
    // Frame 0, frame 1 and its tile, then frame 2's marker that ended the range.
    Tile t;
    CHECK(inner->next(t) == Event::Tile);
    CHECK(t.frame == 2);
}

TEST_CASE("frame range parse", "[frames]") {
    CHECK(parse_frame_range("120:239").first == 120);
    CHECK(parse_frame_range("120:239").last == 239);
    CHECK(parse_frame_range("5:").last == UINT64_MAX);
    CHECK(parse_frame_range("5").last == 5);
    for (const char* bad : {"", ":", ":5", "a:b", "3:2", "-1:4", "1:+4", "1:2:3", " 1:2", "99999999999999999999"})
        CHECK_THROWS_WITH(parse_frame_range(bad), StartsWith("--frames: "));
}
