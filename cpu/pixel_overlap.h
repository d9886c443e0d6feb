// Per pixel, with unbounded lists and exact (rasterizer) depths: which pairs of
// objects' depth intervals overlap, and which only come within a tolerance of
// each other. The accuracy analysis uses it to tell a miss caused by the depth
// resolution from one whose contact region falls between pixel centres
// (docs/accuracy.md).
#pragma once
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "rbcd/common/fragment.h"

namespace rbcd::cpucd {

struct PixelCounts {
    std::uint64_t overlap = 0;   // pixels where an interval of a and one of b overlap (touching included)
    std::uint64_t near = 0;      // pixels without overlap where they come within `tolerance` depth units
};
using PairKey = std::pair<std::uint32_t, std::uint32_t>;   // (smaller id, larger id)
using FramePixels = std::map<PairKey, PixelCounts>;
// Depth complexity: pixels by the number of collisionable fragments on them
// (index n, n >= 1; the last bin counts kDepthBins - 1 and more).
constexpr std::size_t kDepthBins = 65;
using DepthHistogram = std::vector<std::uint64_t>;

// One tile's fragments (any order): adds to `out`. An object's intervals along a
// pixel's ray run from a front face to the back face that closes it (nested
// fronts of the same object merge); front before back at equal depth.
void pixel_overlap_tile(const std::vector<Fragment>& frags, std::uint32_t tolerance, FramePixels& out,
                        DepthHistogram* depth = nullptr);

// The whole stream, one map per frame.
std::vector<FramePixels> pixel_overlap(FragmentSource& src, std::uint32_t tolerance, DepthHistogram* depth = nullptr);

} // namespace rbcd::cpucd
