#include "rbcd/io/frame_range_source.h"

#include <charconv>

#include "rbcd/common/errors.h"

namespace rbcd {

namespace {

bool parse_u64(const std::string& s, std::uint64_t& v) {
    if (s.empty()) return false;
    for (char c : s)
        if (c < '0' || c > '9') return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

} // namespace

FrameRange parse_frame_range(const std::string& text) {
    const auto bad = [&](const std::string& why) {
        return InputError("--frames: " + why + ", got \"" + text + "\" (expected A:B, A: or A)");
    };
    FrameRange r;
    if (text.empty()) throw bad("empty value");
    const auto colon = text.find(':');
    const std::string a = text.substr(0, colon);
    if (!parse_u64(a, r.first)) throw bad("first frame is not an unsigned integer");
    if (colon == std::string::npos) {
        r.last = r.first;
        return r;
    }
    const std::string b = text.substr(colon + 1);
    if (!b.empty() && !parse_u64(b, r.last)) throw bad("last frame is not an unsigned integer");
    if (r.last < r.first) throw bad("last frame before the first");
    return r;
}

InputError no_frame_selected(const FrameRange& range, std::uint64_t input_frames) {
    const std::string last = range.last == UINT64_MAX ? "" : std::to_string(range.last);
    return InputError("--frames: " + std::to_string(range.first) + ":" + last + " selects no frame: the input has " +
                      std::to_string(input_frames) + " frame" + (input_frames == 1 ? "" : "s") +
                      (input_frames ? " (0.." + std::to_string(input_frames - 1) + ")" : std::string()));
}

FrameRangeSource::FrameRangeSource(std::unique_ptr<FragmentSource> inner, FrameRange range)
    : inner_(std::move(inner)), range_(range) {}

FragmentSource::Event FrameRangeSource::next(Tile& tile) {
    if (done_) return Event::End;
    for (;;) {
        const Event ev = inner_->next(tile);
        if (ev == Event::End) {
            done_ = true;
            // A range past the input's end would give an empty run that looks
            // like a result (no frame, exit 0): refused, as a bad --frames is.
            if (!selected_) throw no_frame_selected(range_, input_frames_);
            return ev;
        }
        if (ev == Event::Frame) {
            input_frames_ = tile.frame + 1;
            if (tile.frame > range_.last) {
                // Frames only count up: nothing after this one is wanted.
                done_ = true;
                return Event::End;
            }
            in_range_ = tile.frame >= range_.first;
            selected_ = selected_ || in_range_;
            if (in_range_) return ev;
            continue;
        }
        if (in_range_) return ev;
    }
}

} // namespace rbcd
