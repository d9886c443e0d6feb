// The contract (rbcd-contract.md) transcribed as plainly as possible. This is
// the oracle: every step is written the way the contract words it, with
// ordinary containers, and deliberately not the way the hardware does it
// (no comparator rows, no fixed-size arrays, no bit-packed words), so that a
// shared misreading of the hardware structure cannot hide in both models.
#include "rbcd/ref/reference_model.h"

#include <algorithm>
#include <set>
#include <string>
#include <utility>

#include "rbcd/common/errors.h"

namespace rbcd::ref {

namespace {

std::string tile_name(const Tile& t) {
    return "frame " + std::to_string(t.frame) + " tile " + std::to_string(t.col) + " " + std::to_string(t.row);
}

} // namespace

unsigned insert_element(std::vector<Element>& list, const Element& e, unsigned M, TiePolicy tie) {
    const std::uint64_t key = sort_key(e, tie);
    // "Insertion position = the number of elements whose key <= the new key."
    const auto position = static_cast<std::size_t>(
        std::count_if(list.begin(), list.end(), [&](const Element& o) { return sort_key(o, tie) <= key; }));
    if (list.size() < M) {
        list.insert(list.begin() + static_cast<std::ptrdiff_t>(position), e);
        return 0;
    }
    // Full list: position M drops the newcomer, anything else pushes the last one out.
    if (position == M) return 1;
    list.insert(list.begin() + static_cast<std::ptrdiff_t>(position), e);
    list.pop_back();
    return 1;
}

namespace {

struct StackEntry {
    std::uint32_t id;
    bool matched;
};

struct RawHit {
    HitRecord rec;
    std::size_t pixel;   // list index inside the tile, for the "pixel" filter
};

// Walks one list front to back with an empty FF-stack; appends hits in raw order.
void walk_list(const std::vector<Element>& list, std::size_t pixel, std::uint32_t x, std::uint32_t y, unsigned T,
               std::vector<RawHit>& hits, RefCounts& counts) {
    std::vector<StackEntry> stack;   // index 0 = bottom
    for (const Element& e : list) {
        if (e.facing == Facing::Front) {
            if (stack.size() >= T) {
                ++counts.stack_overflows;
                continue;
            }
            stack.push_back({e.id, false});
            continue;
        }
        const std::uint32_t c = e.id;
        // "the bottommost entry m with matched = 0 and id = c"
        std::size_t m = stack.size();
        for (std::size_t i = 0; i < stack.size(); ++i) {
            if (!stack[i].matched && stack[i].id == c) {
                m = i;
                break;
            }
        }
        if (m == stack.size()) {
            ++counts.orphan_back_faces;
            continue;
        }
        // "every entry i above m (i > m, bottom to top), whatever its matched bit, whose id is not c"
        for (std::size_t i = m + 1; i < stack.size(); ++i) {
            if (stack[i].id == c) continue;
            HitRecord h;
            h.x = x;
            h.y = y;
            h.id_a = std::min(stack[i].id, c);
            h.id_b = std::max(stack[i].id, c);
            h.dq = e.dq;
            hits.push_back({h, pixel});
        }
        stack[m].matched = true;
    }
}

} // namespace

RefConfig ref_config_from(const SimConfig& sim, unsigned depth_bits) {
    RefConfig c;
    c.tile_w = sim.tile.width;
    c.tile_h = sim.tile.height;
    c.list_length = sim.zeb.list_length;
    c.z_bits = sim.zeb.z_bits;
    c.id_bits = sim.zeb.id_bits;
    c.tie = sim.zeb.tie;
    c.stack_depth = sim.tester.stack_depth;
    c.output = sim.tester.output;
    c.depth_bits = depth_bits;
    return c;
}

void reference_tile(const RefConfig& cfg, const Tile& tile, std::vector<RefRecord>& out, RefCounts& counts) {
    const std::uint64_t x0 = std::uint64_t{tile.col} * cfg.tile_w;
    const std::uint64_t y0 = std::uint64_t{tile.row} * cfg.tile_h;

    // Preconditions first, so that a bad tile leaves `out` and `counts` untouched.
    for (const Fragment& f : tile.frags) {
        if (f.x < x0 || f.x >= x0 + cfg.tile_w || f.y < y0 || f.y >= y0 + cfg.tile_h)
            throw InputError(tile_name(tile) + ": fragment (" + std::to_string(f.x) + ", " + std::to_string(f.y) +
                             ") outside the tile");
        if (cfg.id_bits < 32 && (std::uint64_t{f.id} >> cfg.id_bits) != 0)
            throw InputError(tile_name(tile) + ": object id " + std::to_string(f.id) + " does not fit in " +
                             std::to_string(cfg.id_bits) + " bits");
        if (cfg.depth_bits < 32 && (std::uint64_t{f.depth} >> cfg.depth_bits) != 0)
            throw InputError(tile_name(tile) + ": depth " + std::to_string(f.depth) + " does not fit in " +
                             std::to_string(cfg.depth_bits) + " bits");
    }

    ++counts.tiles;
    counts.fragments += tile.frags.size();

    const std::size_t pixels = std::size_t{cfg.tile_w} * cfg.tile_h;
    std::vector<std::vector<Element>> lists(pixels);
    std::vector<std::uint64_t> dropped_per_list(pixels, 0);

    for (const Fragment& f : tile.frags) {
        Element e;
        e.dq = quantize_depth(f.depth, cfg.depth_bits, cfg.z_bits);
        e.id = f.id;
        e.facing = f.facing;
        const std::size_t pixel = static_cast<std::size_t>((f.y - y0) * cfg.tile_w + (f.x - x0));
        dropped_per_list[pixel] += insert_element(lists[pixel], e, cfg.list_length, cfg.tie);
    }

    std::vector<RawHit> raw;
    for (std::size_t p = 0; p < pixels; ++p) {
        if (lists[p].empty()) continue;
        const auto x = static_cast<std::uint32_t>(x0 + p % cfg.tile_w);
        const auto y = static_cast<std::uint32_t>(y0 + p / cfg.tile_w);
        walk_list(lists[p], p, x, y, cfg.stack_depth, raw, counts);
    }

    // Output filter: keep the first hit of each pair within the pixel or tile, unchanged.
    std::set<std::pair<std::size_t, std::pair<std::uint32_t, std::uint32_t>>> seen;
    for (const RawHit& h : raw) {
        bool keep = true;
        if (cfg.output != OutputMode::Raw) {
            const std::size_t scope = cfg.output == OutputMode::Pixel ? h.pixel : 0;
            keep = seen.insert({scope, {h.rec.id_a, h.rec.id_b}}).second;
        }
        if (keep) {
            out.emplace_back(h.rec);
            ++counts.hits;
        }
    }

    OverflowRecord ov;
    ov.col = tile.col;
    ov.row = tile.row;
    for (std::uint64_t d : dropped_per_list) {
        if (d > 0) ++ov.lists;
        ov.dropped += d;
    }
    counts.overflows += ov.dropped;
    if (ov.lists > 0) out.emplace_back(ov);
}

RefResult run_reference(const RefConfig& cfg_in, FragmentSource& src) {
    const StreamHeader& h = src.header();
    if (h.tile_w != cfg_in.tile_w || h.tile_h != cfg_in.tile_h)
        throw InputError(src.name() + ": tile size " + std::to_string(h.tile_w) + "x" + std::to_string(h.tile_h) +
                         " differs from the unit's " + std::to_string(cfg_in.tile_w) + "x" +
                         std::to_string(cfg_in.tile_h));
    RefConfig cfg = cfg_in;
    cfg.depth_bits = h.depth_bits;

    RefResult r;
    Tile t;
    for (;;) {
        const FragmentSource::Event ev = src.next(t);
        if (ev == FragmentSource::Event::End) break;
        if (ev == FragmentSource::Event::Frame) {
            r.frames.push_back(RefFrame{t.frame, {}});
            ++r.counts.frames;
            continue;
        }
        if (r.frames.empty()) throw InputError(src.name() + ": tile before the first frame");
        reference_tile(cfg, t, r.frames.back().records, r.counts);
    }
    return r;
}

} // namespace rbcd::ref
