// The SystemC model against the untimed reference model on random tiles.
// One test case per configuration: SystemC elaborates once per process.
// Across the cases: 24 configurations x 450 tiles = 10,800 tiles.
#include <catch2/catch.hpp>
#include <random>

#include "rbcd/ref/reference_model.h"
#include "rbcd/testbench/hw/tb_util.h"

using namespace rbcd;

namespace {

struct Shape {
    unsigned screen_w = 800, screen_h = 480, depth_bits = 24;
};

// Random tiles that hit the contract's corners: dense pixels (overflow), many
// objects (stack overflow), equal depths (ties), lone back faces (orphans),
// nested intervals of one object, c tags, and partial edge tiles.
class TileGen {
public:
    TileGen(std::uint64_t seed, const SimConfig& cfg, const Shape& sh) : rng_(seed), cfg_(cfg), sh_(sh) {}

    std::uint64_t below(std::uint64_t n) { return n ? rng_() % n : 0; }

    Tile make(std::uint64_t frame, std::uint32_t col, std::uint32_t row) {
        Tile t;
        t.frame = frame;
        t.col = col;
        t.row = row;
        t.other = below(300);
        const unsigned tw = cfg_.tile.width, th = cfg_.tile.height;
        const unsigned x0 = col * tw, y0 = row * th;
        const unsigned w = std::min(tw, sh_.screen_w - x0), h = std::min(th, sh_.screen_h - y0);
        const std::uint32_t max_id = (1u << cfg_.zeb.id_bits) - 1;
        const std::uint64_t max_depth = (sh_.depth_bits == 32) ? 0xffffffffull : ((1ull << sh_.depth_bits) - 1);
        // Coarse depth grid sometimes, so that equal (quantized) depths are common.
        const bool coarse = below(3) == 0;
        auto depth = [&] {
            if (coarse) return static_cast<std::uint32_t>(below(8) * (max_depth / 8));
            return static_cast<std::uint32_t>(below(max_depth + 1));
        };
        const unsigned objects = 1 + static_cast<unsigned>(below(7));
        for (unsigned o = 0; o < objects; ++o) {
            const std::uint32_t id = static_cast<std::uint32_t>(below(std::min<std::uint32_t>(max_id, 12) + 1));
            const unsigned coverage = static_cast<unsigned>(below(101));   // percent of pixels
            const unsigned intervals = 1 + static_cast<unsigned>(below(3));
            for (unsigned p = 0; p < w * h; ++p) {
                if (below(100) >= coverage) continue;
                const std::uint32_t x = x0 + p % w, y = y0 + p / w;
                for (unsigned k = 0; k < intervals; ++k) {
                    std::uint32_t a = depth(), b = depth();
                    if (a > b) std::swap(a, b);
                    const std::uint64_t r = below(20);
                    if (r != 0) t.frags.push_back(frag(x, y, a, id, 'F'));   // r == 0: orphan back face
                    if (r != 1) t.frags.push_back(frag(x, y, b, id, 'B'));   // r == 1: unclosed front face
                }
            }
        }
        // Rasterization order is arbitrary: shuffle in bursts so same-pixel hazards occur too.
        if (below(2) == 0) std::shuffle(t.frags.begin(), t.frags.end(), rng_);
        for (auto& f : t.frags) f.culled = below(10) == 0;
        return t;
    }

private:
    static Fragment frag(std::uint32_t x, std::uint32_t y, std::uint32_t d, std::uint32_t id, char fb) {
        return tb::frag(x, y, d, id, fb);
    }
    std::mt19937_64 rng_;
    const SimConfig& cfg_;
    Shape sh_;
};

std::string ref_text(const ref::RefResult& r) {
    RecordingSink s;
    for (const auto& f : r.frames) {
        s.frame(f.frame);
        for (const auto& rec : f.records) {
            if (auto* h = std::get_if<HitRecord>(&rec)) s.hit(*h);
            else s.overflow(std::get<OverflowRecord>(rec));
        }
    }
    return tb::to_text(s);
}

void differential(std::uint64_t seed, const SimConfig& cfg, const Shape& sh, unsigned tiles = 450) {
    StreamHeader hdr;
    hdr.screen_w = sh.screen_w;
    hdr.screen_h = sh.screen_h;
    hdr.tile_w = cfg.tile.width;
    hdr.tile_h = cfg.tile.height;
    hdr.depth_bits = sh.depth_bits;
    MemorySource src(hdr);
    TileGen gen(seed, cfg, sh);
    const unsigned cols = (sh.screen_w + cfg.tile.width - 1) / cfg.tile.width;
    const unsigned rows = (sh.screen_h + cfg.tile.height - 1) / cfg.tile.height;
    // Frames 0, 1 and 3 carry tiles; frame 2 is empty but must still be announced.
    const unsigned filled_frames[] = {0, 1, 3};
    unsigned made = 0;
    for (unsigned k = 0; k < 3; ++k) {
        const unsigned f = filled_frames[k];
        if (f == 3) src.add_frame(2);
        src.add_frame(f);
        // Distinct tiles per frame in a random (rasterization) order, edge tiles included.
        std::vector<std::uint32_t> order(cols * rows);
        for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
        std::shuffle(order.begin(), order.end(), std::mt19937_64(seed + f));
        const unsigned n = std::min<unsigned>(static_cast<unsigned>(order.size()), (tiles - made) / (3 - k));
        for (unsigned i = 0; i < n; ++i, ++made) src.add_tile(gen.make(f, order[i] % cols, order[i] / cols));
    }
    INFO("tiles generated: " << made);
    REQUIRE(made == tiles);

    src.rewind();
    const ref::RefResult expect = ref::run_reference(ref::ref_config_from(cfg, sh.depth_bits), src);
    src.rewind();
    tb::SystemRun run(cfg, src);
    const auto& s = *run.sys;

    const std::string want = ref_text(expect), got = tb::to_text(run.sink);
    if (want != got) {
        // Point at the first differing line rather than dumping megabytes.
        std::size_t i = 0;
        while (i < want.size() && i < got.size() && want[i] == got[i]) ++i;
        const std::size_t line_start = want.rfind('\n', i == 0 ? 0 : i - 1);
        const std::size_t from = line_start == std::string::npos ? 0 : line_start + 1;
        FAIL("first difference at byte " << i << "\nreference: " << want.substr(from, 120)
                                         << "\nsystemc:   " << got.substr(from, 120));
    }
    CHECK(s.raster.stats().frames == expect.counts.frames);
    CHECK(s.raster.stats().tiles == expect.counts.tiles);
    CHECK(s.raster.stats().fragments == expect.counts.fragments);
    CHECK(s.sorter.stats().overflows == expect.counts.overflows);
    CHECK(s.tester.stats().stack_overflows == expect.counts.stack_overflows);
    CHECK(s.tester.stats().orphan_back_faces == expect.counts.orphan_back_faces);
    CHECK(s.tester.stats().hits == expect.counts.hits);
    CHECK(s.host.stats().hit_records == expect.counts.hits);
    // The generator must actually reach the corners it is meant to: a hit needs
    // three elements in a list and two stack entries.
    if (cfg.zeb.list_length >= 3 && cfg.tester.stack_depth >= 2) CHECK(expect.counts.hits > 0);
    if (cfg.zeb.list_length <= 8) CHECK(expect.counts.overflows > 0);
    CHECK(expect.counts.orphan_back_faces > 0);
}

SimConfig base() {
    SimConfig c;
    return c;
}

} // namespace

#define DIFF_CASE(name, seed, ...)                                      \
    TEST_CASE("hw differential: " name, "[differential]") {            \
        SimConfig cfg = base();                                         \
        Shape sh;                                                       \
        __VA_ARGS__;                                                    \
        differential(seed, cfg, sh);                                    \
    }

DIFF_CASE("default configuration", 1, (void)0)
DIFF_CASE("M 1 and T 1", 2, cfg.zeb.list_length = 1; cfg.tester.stack_depth = 1)
DIFF_CASE("M 2 with one bank", 3, cfg.zeb.list_length = 2; cfg.zeb.banks = 1)
DIFF_CASE("M 4 T 2 arrival ties", 4, cfg.zeb.list_length = 4; cfg.tester.stack_depth = 2;
          cfg.zeb.tie = TiePolicy::Arrival)
DIFF_CASE("M 16 T 16 pixel output", 5, cfg.zeb.list_length = 16; cfg.tester.stack_depth = 16;
          cfg.tester.output = OutputMode::Pixel)
DIFF_CASE("M 64 T 64 tile output", 6, cfg.zeb.list_length = 64; cfg.tester.stack_depth = 64;
          cfg.tester.output = OutputMode::Tile)
DIFF_CASE("z_bits 8 quantization collapses depths", 7, cfg.zeb.z_bits = 8)
DIFF_CASE("z_bits 32 widens 24-bit depths", 8, cfg.zeb.z_bits = 32)
DIFF_CASE("z_bits 1 arrival ties", 9, cfg.zeb.z_bits = 1; cfg.zeb.tie = TiePolicy::Arrival)
DIFF_CASE("depth_bits 32 z_bits 32", 10, sh.depth_bits = 32; cfg.zeb.z_bits = 32)
DIFF_CASE("depth_bits 8 z_bits 24", 11, sh.depth_bits = 8)
DIFF_CASE("id_bits 1", 12, cfg.zeb.id_bits = 1)
DIFF_CASE("id_bits 16 z_bits 32", 13, cfg.zeb.id_bits = 16; cfg.zeb.z_bits = 32)
DIFF_CASE("tile 8x4 with partial edge tiles", 14, cfg.tile.width = 8; cfg.tile.height = 4; sh.screen_w = 101;
          sh.screen_h = 59)
DIFF_CASE("tile 32x32 three banks", 15, cfg.tile.width = 32; cfg.tile.height = 32; cfg.zeb.banks = 3)
DIFF_CASE("tile 1x1", 16, cfg.tile.width = 1; cfg.tile.height = 1; sh.screen_w = 40; sh.screen_h = 30)
DIFF_CASE("tile 64x2 sixteen banks", 17, cfg.tile.width = 64; cfg.tile.height = 2; cfg.zeb.banks = 16;
          sh.screen_w = 256; sh.screen_h = 100)
DIFF_CASE("hazard stall policy", 18, cfg.sorter.hazard = HazardPolicy::Stall; cfg.feed.queue_depth = 1)
DIFF_CASE("tiny output buffer and region force readbacks", 19, cfg.output.buffer_records = 1;
          cfg.output.burst_records = 1; cfg.output.max_outstanding = 1; cfg.output.region_bytes = 32)
DIFF_CASE("bursts of 8 region of 3 bursts", 20, cfg.output.buffer_records = 8; cfg.output.burst_records = 8;
          cfg.output.region_bytes = 3 * 8 * 16; cfg.tester.output = OutputMode::Pixel)
DIFF_CASE("slow memory one byte per cycle", 21, cfg.memory.bytes_per_cycle = 1; cfg.memory.latency_min = 0;
          cfg.memory.latency_max = 1000; cfg.zeb.banks = 4)
DIFF_CASE("fast feed 64 per cycle", 22, cfg.feed.fragments_per_cycle = 64; cfg.feed.queue_depth = 2)
DIFF_CASE("M 3 T 5 tile output arrival", 23, cfg.zeb.list_length = 3; cfg.tester.stack_depth = 5;
          cfg.tester.output = OutputMode::Tile; cfg.zeb.tie = TiePolicy::Arrival)
DIFF_CASE("M 8 T 3 z_bits 12 id_bits 4 tile 16x8", 24, cfg.tester.stack_depth = 3; cfg.zeb.z_bits = 12;
          cfg.zeb.id_bits = 4; cfg.tile.height = 8)
