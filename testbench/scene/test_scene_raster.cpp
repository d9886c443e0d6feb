// Rasterizer: watertightness, clipping, facing, deferred culling, other counts.
#include <cmath>
#include <random>

#include "scene_test_util.h"

using namespace scene_test;
using rbcd::scene::SceneLimits;

namespace {

struct Watertight {
    std::size_t covered = 0;            // pixels with at least one fragment
    std::size_t unbalanced = 0;         // pixels where fronts != backs
    std::size_t overcovered = 0;        // pixels with more fronts than the shape can have, away from silhouettes
    std::size_t doubled = 0;            // two same-facing fragments at (nearly) one depth: a seam counted twice
    std::size_t orphans_inside = 0;     // back without an open front, away from silhouettes
    std::size_t back_nearest_inside = 0;// nearest fragment a back face, away from silhouettes
    std::size_t silhouette = 0;
};

Watertight analyse(const Frame& f, const StreamHeader& h, int max_fronts) {
    Watertight w;
    auto px = per_pixel(f, h);
    const int W = int(h.screen_w), H = int(h.screen_h);
    std::vector<int> fronts(px.size(), 0), backs(px.size(), 0);
    for (std::size_t i = 0; i < px.size(); ++i)
        for (const auto& fr : px[i]) (fr.facing == Facing::Front ? fronts : backs)[i]++;
    for (int y = 0; y < H; ++y) {
        for (int x = 0; x < W; ++x) {
            const std::size_t i = std::size_t(y) * W + x;
            if (px[i].empty()) continue;
            ++w.covered;
            if (fronts[i] != backs[i]) ++w.unbalanced;
            for (std::size_t a = 0; a < px[i].size(); ++a)
                for (std::size_t b = a + 1; b < px[i].size(); ++b)
                    w.doubled += px[i][a].facing == px[i][b].facing &&
                                 std::abs(double(px[i][a].depth) - double(px[i][b].depth)) <= 4.0;
            bool sil = false;
            const int dx[4] = {1, -1, 0, 0}, dy[4] = {0, 0, 1, -1};
            for (int k = 0; k < 4; ++k) {
                const int nx = x + dx[k], ny = y + dy[k];
                const int nf = (nx < 0 || ny < 0 || nx >= W || ny >= H) ? 0 : fronts[std::size_t(ny) * W + nx];
                sil |= nf != fronts[i];
            }
            if (sil) {
                ++w.silhouette;
                continue;
            }
            // A polyhedral torus grazed near its silhouette can be crossed more
            // often than the smooth one; elsewhere a line meets it at most 4 times.
            if (fronts[i] > max_fronts) ++w.overcovered;
            auto frs = px[i];
            std::sort(frs.begin(), frs.end(), [](const Fragment& a, const Fragment& b) {
                if (a.depth != b.depth) return a.depth < b.depth;
                return a.facing == Facing::Front && b.facing == Facing::Back;
            });
            if (frs.front().facing == Facing::Back) ++w.back_nearest_inside;
            int open = 0;
            for (const auto& fr : frs) {
                if (fr.facing == Facing::Front) ++open;
                else if (open == 0) ++w.orphans_inside;
                else --open;
            }
        }
    }
    return w;
}

double bounding_radius(const std::string& shape) {
    if (shape == "sphere") return 1.0;
    if (shape == "torus") return 1.25;
    if (shape == "cylinder") return std::sqrt(2.0);
    return std::sqrt(3.0);
}

void random_poses(const std::string& shape, int max_fronts, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u01(0.0, 1.0);
    const unsigned W = 333, H = 250;   // not a multiple of the tile size
    const double aspect = double(W) / H, t = std::tan(30.0 * 3.14159265358979 / 180.0);
    const int segs[] = {5, 8, 13, 24, 40};
    SceneLimits lim;
    lim.tile_w = 16;
    lim.tile_h = 8;
    int mirrored_cases = 0;
    for (int trial = 0; trial < 24; ++trial) {
        Obj o;
        o.mesh = shape;
        o.id = 3;
        o.cull = trial % 3 == 0 ? "none" : "back";
        o.segments = shape == "box" ? 0 : segs[trial % 5];
        o.scale = {0.3 + 1.2 * u01(rng), 0.3 + 1.2 * u01(rng), 0.3 + 1.2 * u01(rng)};
        if (trial % 4 == 1) {   // mirror along one or all three axes
            o.scale.x = -o.scale.x;
            if (trial % 8 == 5) {
                o.scale.y = -o.scale.y;
                o.scale.z = -o.scale.z;
            }
            ++mirrored_cases;
        }
        o.rot = {360.0 * u01(rng), 360.0 * u01(rng), 360.0 * u01(rng)};
        const double R = bounding_radius(shape) * std::max({std::abs(o.scale.x), std::abs(o.scale.y), std::abs(o.scale.z)});
        const double z = R + R / t * 1.2 + 0.3 + 8.0 * u01(rng);
        const double half_y = (z - R) * t - R, half_x = (z - R) * t * aspect - R;
        REQUIRE(half_y > 0.0);
        o.pos = {half_x * (2 * u01(rng) - 1) * 0.95, half_y * (2 * u01(rng) - 1) * 0.95, -z};

        std::string text = scene_header(W, H, 1) + object_text(o);
        Capture c = capture_text(text, lim);
        REQUIRE(c.frames.size() == 1);
        Watertight w = analyse(c.frames[0], c.h, max_fronts);
        INFO("shape " << shape << " trial " << trial << "\n" << text);
        CHECK(w.covered > 20);
        CHECK(w.unbalanced == 0);
        CHECK(w.overcovered == 0);
        CHECK(w.doubled == 0);
        CHECK(w.orphans_inside == 0);
        CHECK(w.back_nearest_inside == 0);
        CHECK(w.silhouette < w.covered);
    }
    CHECK(mirrored_cases > 0);
}

} // namespace

TEST_CASE("spheres are watertight at random poses and sizes", "[scene][raster]") { random_poses("sphere", 1, 11); }
TEST_CASE("tori are watertight at random poses and sizes", "[scene][raster]") { random_poses("torus", 2, 22); }
TEST_CASE("cylinders are watertight at random poses and sizes", "[scene][raster]") { random_poses("cylinder", 1, 33); }
TEST_CASE("boxes are watertight at random poses and sizes", "[scene][raster]") { random_poses("box", 1, 44); }

TEST_CASE("the viewport and fill rule cover an axis-aligned square exactly", "[scene][raster]") {
    // A box face filling x, y in [-1, 1] at distance 1 + 1 with fov 90 and a square
    // screen maps to exactly the central half of the screen: 64 x 64 pixels of 128.
    Cam cam;
    cam.fov_y = 90.0;
    Obj o;
    o.mesh = "box";
    o.id = 1;
    o.pos = {0, 0, -3};   // front face at z = -2
    Capture c = capture_text(scene_header(128, 128, 1, cam) + object_text(o));
    auto px = per_pixel(c.frames[0], c.h);
    std::size_t fronts = 0, outside = 0;
    std::uint32_t minx = 999, maxx = 0, miny = 999, maxy = 0;
    for (std::size_t i = 0; i < px.size(); ++i) {
        for (const auto& f : px[i]) {
            if (f.facing != Facing::Front) continue;
            ++fronts;
            minx = std::min(minx, f.x);
            maxx = std::max(maxx, f.x);
            miny = std::min(miny, f.y);
            maxy = std::max(maxy, f.y);
            outside += f.culled;
        }
    }
    CHECK(fronts == 64u * 64u);
    CHECK(minx == 32u);
    CHECK(maxx == 95u);
    CHECK(miny == 32u);
    CHECK(maxy == 95u);
    CHECK(outside == 0u);
    // Depth of the front face: window depth of z_eye = -2 with near 0.1, far 100.
    const double n = 0.1, fa = 100.0, ze = -2.0;
    const double ndc = ((fa + n) / (n - fa) * ze + 2 * fa * n / (n - fa)) / -ze;
    const auto expect = std::uint32_t(std::lround((ndc * 0.5 + 0.5) * double((1u << 24) - 1)));
    const auto& centre = px[64 * 128 + 64];
    REQUIRE(centre.size() == 2);
    const auto& front = centre[0].facing == Facing::Front ? centre[0] : centre[1];
    CHECK(std::abs(double(front.depth) - double(expect)) <= 1.0);
    CHECK(c.h.depth_bits == 24u);
}

TEST_CASE("a camera inside a sphere sees every pixel exactly once, as a back face", "[scene][raster][clip]") {
    // The sphere crosses the near plane and every guard-band plane: clipping
    // must leave no pixel uncovered and none covered twice.
    Obj o;
    o.id = 2;
    o.cull = "none";
    o.segments = 48;
    o.pos = {0.3, -0.2, 0.1};
    o.scale = {5, 5, 5};
    o.rot = {10, 20, 30};
    Capture c = capture_text(scene_header(200, 150, 1) + object_text(o));
    auto px = per_pixel(c.frames[0], c.h);
    std::size_t once = 0;
    for (const auto& p : px) once += p.size() == 1 && p[0].facing == Facing::Back && !p[0].culled;
    CHECK(once == 200u * 150u);
}

TEST_CASE("a large box crossing the guard band stays watertight on screen", "[scene][raster][clip]") {
    Obj o;
    o.mesh = "box";
    o.id = 1;
    o.pos = {3, -0.5, -7};
    o.rot = {15, 25, 0};
    o.scale = {400, 1, 3};
    Capture c = capture_text(scene_header(160, 120, 1) + object_text(o));
    Watertight w = analyse(c.frames[0], c.h, 1);
    CHECK(w.covered > 1000);
    CHECK(w.unbalanced == 0);
    CHECK(w.overcovered == 0);
    CHECK(w.orphans_inside == 0);
}

TEST_CASE("nothing behind the camera or beyond the far plane produces fragments", "[scene][raster][clip]") {
    Obj behind;
    behind.id = 1;
    behind.name = "behind";
    behind.pos = {0, 0, 5};   // the camera looks down -z
    Obj far;
    far.id = 2;
    far.name = "far";
    far.pos = {0, 0, -150};   // far = 100
    Obj seen;
    seen.id = 3;
    seen.name = "seen";
    seen.pos = {0, 0, -5};
    seen.scale = {0.5, 0.5, 0.5};
    Capture c = capture_text(scene_header(100, 100, 1) + object_text(behind) + object_text(far) + object_text(seen));
    std::set<std::uint32_t> ids;
    for (const auto& t : c.frames[0].tiles)
        for (const auto& f : t.frags) ids.insert(f.id);
    CHECK(ids == std::set<std::uint32_t>{3});

    // Straddling the near plane: only the part in front survives; the cut
    // surface is open, so backs outnumber fronts, but nothing breaks.
    Obj straddle;
    straddle.id = 4;
    straddle.pos = {0, 0, 0.5};
    straddle.scale = {2, 2, 2};
    Capture s = capture_text(scene_header(100, 100, 1) + object_text(straddle));
    std::size_t fronts = 0, backs = 0;
    for (const auto& t : s.frames[0].tiles)
        for (const auto& f : t.frags) (f.facing == Facing::Front ? fronts : backs)++;
    CHECK(fronts == 0u);   // the camera is inside: the front half is behind it
    CHECK(backs == 100u * 100u);
}

TEST_CASE("faces the object's cull would remove are tagged c", "[scene][raster][cull]") {
    Obj o;
    o.id = 5;
    o.pos = {0.2, 0.1, -4};
    for (const char* mode : {"back", "front", "none"}) {
        o.cull = mode;
        Capture c = capture_text(scene_header(120, 90, 1) + object_text(o));
        std::size_t fb = 0, ff = 0, cb = 0, cf = 0;
        for (const auto& t : c.frames[0].tiles)
            for (const auto& f : t.frags) {
                if (f.facing == Facing::Front) (f.culled ? cf : ff)++;
                else (f.culled ? cb : fb)++;
            }
        INFO("cull " << mode);
        CHECK(ff + cf > 500u);
        CHECK(ff + cf == fb + cb);   // watertight: as many fronts as backs
        if (std::string(mode) == "back") {
            CHECK(cb == fb + cb);
            CHECK(cf == 0u);
        } else if (std::string(mode) == "front") {
            CHECK(cf == ff + cf);
            CHECK(cb == 0u);
        } else {
            CHECK(cf + cb == 0u);
        }
    }
}

TEST_CASE("non-collisionable objects only add to other, per tile, without their culled faces", "[scene][raster][other]") {
    const std::string hdr = scene_header(160, 96, 1);
    Obj o;
    o.pos = {-0.3, 0.2, -4};
    o.rot = {20, 30, 40};
    o.mesh = "torus";
    o.scale = {1.5, 1.5, 1.5};
    o.id = 9;
    // Reference: the same object collisionable, counted per tile.
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<std::uint64_t, std::uint64_t>> ref;   // fronts, all
    Capture cc = capture_text(hdr + object_text(o));
    for (const auto& t : cc.frames[0].tiles)
        for (const auto& f : t.frags) {
            auto& r = ref[{t.col, t.row}];
            r.first += f.facing == Facing::Front;
            r.second += 1;
        }
    REQUIRE(ref.size() > 4);

    o.id.reset();
    for (const char* mode : {"back", "none"}) {
        o.cull = mode;
        Capture c = capture_text(hdr + object_text(o));
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint64_t> got;
        for (const auto& t : c.frames[0].tiles) {
            CHECK(t.frags.empty());
            got[{t.col, t.row}] = t.other;
        }
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint64_t> want;
        for (const auto& [k, v] : ref) {
            const std::uint64_t n = std::string(mode) == "back" ? v.first : v.second;
            if (n) want[k] = n;
        }
        INFO("cull " << mode);
        CHECK(got == want);
    }

    // A tile holding only other fragments still has a record, next to a
    // collisionable object's tiles.
    Obj wall;
    wall.name = "wall";
    wall.mesh = "box";
    wall.pos = {-3, 0, -6};
    Obj ball;
    ball.name = "ball";
    ball.id = 1;
    ball.pos = {2, 0, -6};
    ball.scale = {0.5, 0.5, 0.5};
    Capture m = capture_text(hdr + object_text(wall) + object_text(ball));
    std::size_t only_other = 0, only_frags = 0;
    for (const auto& t : m.frames[0].tiles) {
        only_other += t.frags.empty() && t.other > 0;
        only_frags += !t.frags.empty() && t.other == 0;
    }
    CHECK(only_other > 0);
    CHECK(only_frags > 0);
}

TEST_CASE("a mirroring transform flips the winding but not the facing", "[scene][raster][mirror]") {
    for (const char* shape : {"box", "torus", "cylinder"}) {
        Obj o;
        o.mesh = shape;
        o.id = 1;
        o.pos = {0, 0, -5};
        o.rot = {30, 40, 0};
        Capture plain = capture_text(scene_header(160, 120, 1) + object_text(o));
        o.scale = {-1, 1, 1};
        Capture mirrored = capture_text(scene_header(160, 120, 1) + object_text(o));
        o.scale = {-1, -1, -1};
        Capture point = capture_text(scene_header(160, 120, 1) + object_text(o));
        INFO("shape " << shape);
        for (const Capture* c : {&plain, &mirrored, &point}) {
            Watertight w = analyse(c->frames[0], c->h, 2);
            CHECK(w.covered > 300);
            CHECK(w.unbalanced == 0);
            CHECK(w.back_nearest_inside == 0);
            // cull = back: the tagged fragments are exactly the back faces.
            for (const auto& t : c->frames[0].tiles)
                for (const auto& f : t.frags) CHECK(f.culled == (f.facing == Facing::Back));
        }
    }
    // The box is symmetric: mirrored, it covers the same pixels with the same facings.
    Obj b;
    b.mesh = "box";
    b.id = 1;
    b.pos = {0.4, -0.3, -6};
    b.rot = {0, 0, 0};
    Capture p = capture_text(scene_header(160, 120, 1) + object_text(b));
    b.scale = {-1, 1, 1};
    Capture m = capture_text(scene_header(160, 120, 1) + object_text(b));
    auto key = [](const Capture& c) {
        std::multiset<std::tuple<std::uint32_t, std::uint32_t, int>> s;
        for (const auto& t : c.frames[0].tiles)
            for (const auto& f : t.frags) s.insert({f.x, f.y, int(f.facing)});
        return s;
    };
    CHECK(key(p) == key(m));
}

TEST_CASE("within a tile, fragments come triangle by triangle in object order", "[scene][raster][order]") {
    Obj a;
    a.name = "a";
    a.id = 1;
    a.pos = {0, 0, -6};
    Obj b;
    b.name = "b";
    b.id = 2;
    b.pos = {0.5, 0, -5};
    Capture c = capture_text(scene_header(64, 64, 1) + object_text(a) + object_text(b));
    std::size_t mixed = 0;
    for (const auto& t : c.frames[0].tiles) {
        bool seen_b = false;
        for (const auto& f : t.frags) {
            if (f.id == 2) seen_b = true;
            else CHECK_FALSE(seen_b);   // no fragment of the first object after one of the second
        }
        mixed += seen_b && t.frags.front().id == 1;
    }
    CHECK(mixed > 0);
}
