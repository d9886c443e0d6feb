#include "rbcd/cpu/pixel_overlap.h"

#include <algorithm>
#include <numeric>

namespace rbcd::cpucd {

namespace {

struct Interval {
    std::uint32_t id;
    std::uint32_t lo, hi;
};

} // namespace

void pixel_overlap_tile(const std::vector<Fragment>& frags, std::uint32_t tolerance, FramePixels& out,
                        DepthHistogram* depth) {
    std::vector<std::uint32_t> idx(frags.size());
    std::iota(idx.begin(), idx.end(), 0u);
    std::sort(idx.begin(), idx.end(), [&](std::uint32_t i, std::uint32_t j) {
        const Fragment& a = frags[i];
        const Fragment& b = frags[j];
        if (a.y != b.y) return a.y < b.y;
        if (a.x != b.x) return a.x < b.x;
        if (a.depth != b.depth) return a.depth < b.depth;
        if (a.facing != b.facing) return a.facing == Facing::Front;
        return i < j;
    });
    std::vector<Interval> iv;
    struct Open {
        std::uint32_t id, count, start;
    };
    std::vector<Open> open;
    std::map<PairKey, int> seen;   // per pixel: 2 overlap, 1 near
    for (std::size_t s = 0; s < idx.size();) {
        std::size_t e = s;
        const Fragment& f0 = frags[idx[s]];
        while (e < idx.size() && frags[idx[e]].x == f0.x && frags[idx[e]].y == f0.y) ++e;
        if (depth) {
            depth->resize(kDepthBins, 0);
            ++(*depth)[std::min(e - s, kDepthBins - 1)];
        }
        iv.clear();
        open.clear();
        for (std::size_t k = s; k < e; ++k) {
            const Fragment& f = frags[idx[k]];
            auto it = std::find_if(open.begin(), open.end(), [&](const Open& o) { return o.id == f.id; });
            if (f.facing == Facing::Front) {
                if (it == open.end()) open.push_back({f.id, 1, f.depth});
                else if (it->count++ == 0) it->start = f.depth;
            } else if (it != open.end() && it->count > 0) {
                if (--it->count == 0) iv.push_back({f.id, it->start, f.depth});
            }
        }
        seen.clear();
        for (std::size_t i = 0; i < iv.size(); ++i) {
            for (std::size_t j = i + 1; j < iv.size(); ++j) {
                if (iv[i].id == iv[j].id) continue;
                const std::uint32_t lo = std::max(iv[i].lo, iv[j].lo), hi = std::min(iv[i].hi, iv[j].hi);
                const int v = lo <= hi ? 2 : (lo - hi <= tolerance ? 1 : 0);
                if (!v) continue;
                const PairKey key{std::min(iv[i].id, iv[j].id), std::max(iv[i].id, iv[j].id)};
                int& cur = seen[key];
                cur = std::max(cur, v);
            }
        }
        for (const auto& [key, v] : seen) {
            PixelCounts& c = out[key];
            if (v == 2) ++c.overlap;
            else ++c.near;
        }
        s = e;
    }
}

std::vector<FramePixels> pixel_overlap(FragmentSource& src, std::uint32_t tolerance, DepthHistogram* depth) {
    std::vector<FramePixels> frames;
    Tile t;
    for (;;) {
        const auto ev = src.next(t);
        if (ev == FragmentSource::Event::End) break;
        if (ev == FragmentSource::Event::Frame) frames.emplace_back();
        else if (!frames.empty()) pixel_overlap_tile(t.frags, tolerance, frames.back(), depth);
    }
    return frames;
}

} // namespace rbcd::cpucd
