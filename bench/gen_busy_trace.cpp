// Deterministic generator of a "busy frames" .rbt trace for throughput runs:
// an 800x480 screen of 16x16 tiles, ~400 occupied tiles a frame, 1-5 closed
// objects a tile, each covering ~70% of the tile with one or two depth
// intervals. Streams tile by tile, so the trace can be far bigger than memory.
//
//   gen_busy_trace OUT [FRAGMENTS=5000000] [FRAMES=8] [SEED=1] [--tiles 400] [--interleaved]
//
// By default each object's fragments come in bursts (its front faces, then its
// back faces). --interleaved emits the same fragments as a rasterizer working
// on many small primitives does: each object's fragments cut into runs of 2 to
// 8 (one small triangle's worth), and the tile's runs taken from its objects
// in random order, so objects, faces and pixels of the tile mix.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/common/fragment.h"
#include "rbcd/io/trace_writer.h"

namespace {

// splitmix64 and our own range mapping: std:: distributions differ between
// standard libraries, and the trace must be the same everywhere for a seed.
struct Rng {
    std::uint64_t s;
    std::uint64_t next() {
        std::uint64_t z = (s += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    // Uniform in [lo, hi]; the modulo bias is far below anything measured here.
    std::uint64_t range(std::uint64_t lo, std::uint64_t hi) { return lo + next() % (hi - lo + 1); }
    double unit() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
};

constexpr unsigned kScreenW = 800, kScreenH = 480, kTile = 16, kDepthBits = 24;
constexpr unsigned kMaxObjects = 5, kMaxId = 100;
constexpr double kCoverage = 0.7;
// Mean objects (3) x mean fragments per covered pixel (F+B or 2x F+B: 3) x pixels.
constexpr double kMeanFragsPerPixelFull = 3.0 * 3.0 * kTile * kTile;

// One object's fragments in tile (x0, y0) of size tw x th: a rectangle of
// about kCoverage x scale of the tile, one or two depth intervals, each its
// front faces then its back faces.
void add_object(Rng& rng, rbcd::Tile& t, std::uint32_t id, unsigned x0, unsigned y0, unsigned tw, unsigned th,
                double scale, std::uint64_t cluster) {
    double cov = kCoverage * scale * (0.85 + 0.3 * rng.unit());
    cov = std::clamp(cov, 1.0 / (tw * th), 1.0);
    const unsigned area = std::max(1u, static_cast<unsigned>(std::lround(cov * tw * th)));
    const unsigned wmin = std::max(1u, (area + th - 1) / th), wmax = std::min(tw, area);
    const unsigned rw = static_cast<unsigned>(rng.range(wmin, std::max(wmin, wmax)));
    const unsigned rh = std::min(th, (area + rw - 1) / rw);
    const unsigned rx = x0 + static_cast<unsigned>(rng.range(0, tw - rw));
    const unsigned ry = y0 + static_cast<unsigned>(rng.range(0, th - rh));
    const unsigned intervals = static_cast<unsigned>(rng.range(1, 2));
    // Depth = plane over the rectangle; slopes stay small enough
    // that every depth fits 24 bits (cluster leaves 2^21 headroom).
    const std::int64_t gx = static_cast<std::int64_t>(rng.range(0, 128)) - 64;
    const std::int64_t gy = static_cast<std::int64_t>(rng.range(0, 128)) - 64;
    std::int64_t near = static_cast<std::int64_t>(cluster + rng.range(0, 1u << 19)) + 2048;
    for (unsigned iv = 0; iv < intervals; ++iv) {
        const std::int64_t thick = static_cast<std::int64_t>(rng.range(1u << 12, 1u << 18));
        // Front faces are rasterized first, the back faces of
        // the same interval later: one burst per object.
        for (int pass = 0; pass < 2; ++pass) {
            for (unsigned y = ry; y < ry + rh; ++y) {
                for (unsigned x = rx; x < rx + rw; ++x) {
                    const std::int64_t d = near + gx * (x - x0) + gy * (y - y0) + (pass ? thick : 0);
                    rbcd::Fragment f;
                    f.x = x;
                    f.y = y;
                    f.depth = static_cast<std::uint32_t>(d);
                    f.id = id;
                    f.facing = pass ? rbcd::Facing::Back : rbcd::Facing::Front;
                    // Back faces of closed objects are what
                    // back-face culling removes: deferred culling.
                    f.culled = pass == 1;
                    t.frags.push_back(f);
                }
            }
        }
        near += thick + static_cast<std::int64_t>(rng.range(1u << 12, 1u << 18));
    }
}

// Runs of 2..8 fragments, in a random order of the tile's runs; a run keeps
// its fragments' order.
void interleave(Rng& mix, rbcd::Tile& t) {
    std::vector<std::pair<std::size_t, std::size_t>> runs;   // [begin, end)
    for (std::size_t b = 0; b < t.frags.size();) {
        const std::size_t e = std::min(t.frags.size(), b + static_cast<std::size_t>(mix.range(2, 8)));
        runs.emplace_back(b, e);
        b = e;
    }
    for (std::size_t i = runs.size(); i > 1; --i) std::swap(runs[i - 1], runs[mix.range(0, i - 1)]);
    std::vector<rbcd::Fragment> mixed;
    mixed.reserve(t.frags.size());
    for (const auto& [b, e] : runs) mixed.insert(mixed.end(), t.frags.begin() + b, t.frags.begin() + e);
    t.frags.swap(mixed);
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"Writes a deterministic busy-frames .rbt trace"};
    std::string out;
    std::uint64_t target = 5000000, frames = 8, seed = 1;
    unsigned tiles_per_frame = 400;
    bool interleaved = false;
    app.add_option("out", out, "output trace path")->required();
    app.add_option("fragments", target, "target number of fragments (about)")->check(CLI::Range(1ull, 1ull << 40));
    app.add_option("frames", frames, "frames")->check(CLI::Range(1ull, 1ull << 20));
    app.add_option("seed", seed, "random seed");
    app.add_option("--tiles", tiles_per_frame, "occupied tiles per frame (at least; raised when the target needs it)")
        ->check(CLI::Range(1u, 1500u));
    app.add_flag("--interleaved", interleaved, "objects' fragments mixed in small runs, not per-object bursts");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }

    const unsigned cols = (kScreenW + kTile - 1) / kTile, rows = (kScreenH + kTile - 1) / kTile;
    const unsigned grid = cols * rows;
    // Coverage saturates at 100%; beyond that, more tiles are the only way up.
    const double max_mean_per_tile = kMeanFragsPerPixelFull * 0.95;
    const double need_tiles = std::ceil(static_cast<double>(target) / (static_cast<double>(frames) * max_mean_per_tile));
    tiles_per_frame = static_cast<unsigned>(std::min<double>(grid, std::max<double>(tiles_per_frame, need_tiles)));

    Rng rng{seed};
    // The interleaving draws from a stream of its own: both orders hold the same fragments.
    Rng mix{seed ^ 0x5bd1e9955bd1e995ull};
    rbcd::StreamHeader h;
    h.screen_w = kScreenW;
    h.screen_h = kScreenH;
    h.tile_w = h.tile_h = kTile;
    h.depth_bits = kDepthBits;

    std::uint64_t written = 0, tiles_written = 0;
    try {
        rbcd::TraceWriter w(out, h);
        std::vector<unsigned> cells(grid);
        rbcd::Tile t;
        const std::uint64_t total_tiles = frames * tiles_per_frame;
        for (std::uint64_t fr = 0; fr < frames; ++fr) {
            w.frame(fr);
            for (unsigned i = 0; i < grid; ++i) cells[i] = i;
            for (unsigned i = 0; i < tiles_per_frame; ++i) std::swap(cells[i], cells[rng.range(i, grid - 1)]);
            // A tiling GPU walks its bins in screen order.
            std::sort(cells.begin(), cells.begin() + tiles_per_frame);
            for (unsigned ti = 0; ti < tiles_per_frame; ++ti) {
                const unsigned col = cells[ti] % cols, row = cells[ti] / cols;
                t.frame = fr;
                t.col = col;
                t.row = row;
                t.other = rng.range(0, 3000);
                t.has_base = false;
                t.frags.clear();

                // Steer each tile towards the remaining average so the total
                // lands near the target whatever the random draws did so far.
                const double left = static_cast<double>(target > written ? target - written : 0);
                const double budget = left / static_cast<double>(total_tiles - tiles_written);
                const double scale = budget / (kMeanFragsPerPixelFull * kCoverage);

                const unsigned x0 = col * kTile, y0 = row * kTile;
                const unsigned tw = std::min(kTile, kScreenW - x0), th = std::min(kTile, kScreenH - y0);
                const unsigned objects = static_cast<unsigned>(rng.range(1, kMaxObjects));
                // Objects of one tile sit in one depth neighbourhood so that they
                // interpenetrate often, as in a busy scene.
                const std::uint64_t cluster = rng.range(1u << 12, (1u << kDepthBits) - (1u << 21));
                std::uint32_t ids[kMaxObjects];
                for (unsigned o = 0; o < objects; ++o) {
                    bool dup;
                    do {
                        ids[o] = static_cast<std::uint32_t>(rng.range(1, kMaxId));
                        dup = std::find(ids, ids + o, ids[o]) != ids + o;
                    } while (dup);
                }
                for (unsigned o = 0; o < objects; ++o) add_object(rng, t, ids[o], x0, y0, tw, th, scale, cluster);
                if (interleaved) interleave(mix, t);
                w.tile(t);
                written += t.frags.size();
                ++tiles_written;
            }
        }
        w.close();
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "gen_busy_trace: %s\n", e.what());
        std::remove(out.c_str());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "gen_busy_trace: %s\n", e.what());
        std::remove(out.c_str());
        return 1;
    }
    std::printf("%llu fragments, %llu tiles, %llu frames written to %s\n", static_cast<unsigned long long>(written),
                static_cast<unsigned long long>(tiles_written), static_cast<unsigned long long>(frames), out.c_str());
    return 0;
}
