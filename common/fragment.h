// What the rasterizer hands to the unit, and the stream interface every input
// (trace file, 3D scene, test generator) implements.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace rbcd {

enum class Facing : std::uint8_t { Front = 0, Back = 1 };

struct Fragment {
    std::uint32_t x = 0, y = 0;   // screen coordinates, inside the fragment's tile
    std::uint32_t depth = 0;      // unsigned, depth_bits wide; smaller = nearer
    std::uint32_t id = 0;         // object id, fits zeb.id_bits (checked by the source)
    Facing facing = Facing::Front;
    bool culled = false;          // 'c': face culling would have removed it
};

// `o N` inside a tile: N non-collisionable fragments rasterized just before
// frags[before] (before == frags.size(): after the last one).
struct OtherRun {
    std::uint32_t before = 0;
    std::uint64_t count = 0;
};

struct Tile {
    std::uint64_t frame = 0;
    std::uint32_t col = 0, row = 0;
    std::uint64_t other = 0;       // non-collisionable fragments of the tile (timing only)
    bool has_base = false;
    std::uint64_t base = 0;        // baseline GPU cycles of the tile, when a simulator measured it
    // Primitives the rasterizer sets up for the tile: in the baseline GPU
    // (prims=), and only because face culling is deferred (cprims=).
    bool has_prims = false, has_cprims = false;
    std::uint64_t prims = 0, cprims = 0;
    // What shading one of the tile's fragments costs the fragment processors,
    // in percent of gpu.cycles_per_fragment (shade=; docs/gpu-model.md):
    // 100 when the trace does not say.
    bool has_shade = false;
    std::uint32_t shade = 100;
    // Rasterization order of the non-collisionable fragments, from `o N`
    // records. Empty: the trace did not say (docs/timing.md: spread evenly).
    bool ordered_other = false;
    std::vector<OtherRun> other_runs;
    std::vector<Fragment> frags;   // in rasterization order
};

// shade= (percent of gpu.cycles_per_fragment): from 1% to 100 times a
// reference fragment, wherever a cost is read or written.
constexpr std::uint32_t kShadeMin = 1, kShadeMax = 10000;

// The fragment processors' cycles for one of tile t's shaded fragments, given
// gpu.cycles_per_fragment c: c x shade= / 100, rounded to the nearest cycle,
// at least 1 (docs/gpu-model.md).
inline std::uint64_t fragment_cycles(std::uint64_t c, const Tile& t) {
    if (!t.has_shade) return c;
    const std::uint64_t scaled = (c * t.shade + 50) / 100;
    return scaled ? scaled : 1;
}

struct StreamHeader {
    std::uint32_t screen_w = 800, screen_h = 480;
    std::uint32_t tile_w = 16, tile_h = 16;
    unsigned depth_bits = 24;
};

// A stream of frames and tiles in rasterization order. Frames count up from 0;
// every frame of the input is announced, also one without tiles.
class FragmentSource {
public:
    enum class Event { Frame, Tile, End };
    virtual ~FragmentSource() = default;
    // Valid once the constructor returned (headers precede the first frame).
    virtual const StreamHeader& header() const = 0;
    // Frame: `tile.frame` holds the new frame number, other fields untouched.
    // Tile: `tile` is overwritten with the next tile (its vector's capacity is reused).
    // Throws InputError naming file:line on malformed input.
    virtual Event next(Tile& tile) = 0;
    // Name used in messages (file path, "<scene>", ...).
    virtual std::string name() const = 0;
};

} // namespace rbcd
