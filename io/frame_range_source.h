// A FragmentSource that passes through only the frames first..last of another
// source (rbcd-sim --frames A:B), keeping their real frame numbers, so that a
// long input can be run in frame ranges on several workers and the ranges'
// collision files concatenated (docs/sweeps.md, "One long input across workers").
//
//     auto src = std::make_unique<FrameRangeSource>(std::move(inner), parse_frame_range("120:239"));
//
// A range that selects no frame of the input is an InputError at the input's
// end, naming the input's frame count (an empty run would look like a result).
// Frames before `first` that the inner source produces are dropped (a trace's
// reader still checks them, so a range run reports the same input errors a
// whole run would up to `last`; a scene started at `first` renders none:
// scene/scene_source.h); reading stops after `last`, so what follows it is
// never parsed.
#pragma once
#include <cstdint>
#include <memory>
#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/common/fragment.h"

namespace rbcd {

struct FrameRange {
    std::uint64_t first = 0;
    std::uint64_t last = UINT64_MAX;   // inclusive
};

// "A:B" (both inclusive), "A:" (A to the end) or "A" (frame A alone); decimal.
// Throws InputError "--frames: ..." when malformed or B < A.
FrameRange parse_frame_range(const std::string& text);

// The error of a range that selects no frame of an input of `input_frames`
// frames: thrown at the input's end, or at once by a caller that knows the
// count (a scene).
InputError no_frame_selected(const FrameRange& range, std::uint64_t input_frames);

class FrameRangeSource final : public FragmentSource {
public:
    FrameRangeSource(std::unique_ptr<FragmentSource> inner, FrameRange range);
    const StreamHeader& header() const override { return inner_->header(); }
    Event next(Tile& tile) override;
    std::string name() const override { return inner_->name(); }

private:
    std::unique_ptr<FragmentSource> inner_;
    FrameRange range_;
    bool in_range_ = false;
    bool done_ = false;
    bool selected_ = false;              // some frame was in the range
    std::uint64_t input_frames_ = 0;     // frames of the input seen so far
};

} // namespace rbcd
