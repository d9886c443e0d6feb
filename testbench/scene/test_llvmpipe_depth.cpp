// LlvmpipeDepth (scene/llvmpipe_depth.h): Mesa llvmpipe's float32 clip,
// set-up and per-pixel depth on hand-made triangles, and the second depth
// buffer TileRasterizer keeps with it. The expected values were derived with
// a separate restatement of the same steps in numpy float32 (fused
// multiply-adds as exact products and sums rounded once), not with this code.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <catch2/catch.hpp>

#include "rbcd/scene/llvmpipe_depth.h"
#include "rbcd/scene/tile_rasterizer.h"

using rbcd::scene::DrawState;
using rbcd::scene::LlvmpipeDepth;
using rbcd::scene::TileRasterizer;

namespace {

struct Expect {
    float a0, dzdx, dzdy;
    std::int32_t px, py;   // a pixel inside the triangle
    std::uint32_t depth;   // llvmpipe's 24-bit depth there
};

LlvmpipeDepth::Range add(LlvmpipeDepth& lp, const std::array<Eigen::Vector4d, 3>& v, bool first_provokes = false) {
    DrawState s = DrawState::full_screen(800, 480);
    s.first_vertex_provokes = first_provokes;
    lp.set_draw(s);
    return lp.add_triangle(v[0], v[1], v[2]);
}

void check(const LlvmpipeDepth& lp, LlvmpipeDepth::Range r, const std::vector<Expect>& want) {
    REQUIRE(r.count == want.size());
    for (std::size_t i = 0; i < want.size(); ++i) {
        const auto& p = lp.planes()[r.first + i];
        INFO("triangle " << i);
        CHECK(p.a0 == want[i].a0);
        CHECK(p.dzdx == want[i].dzdx);
        CHECK(p.dzdy == want[i].dzdy);
        CHECK(lp.depth_at(r, want[i].px, want[i].py) == want[i].depth);
    }
}

// 800 x 480, the full viewport, depth range (0, 1): X = 400 x/w + 400,
// Y = 240 - 240 y/w (the window's rows run down), Z = z/w / 2 + 1/2.
const std::array<Eigen::Vector4d, 3> kFlat = {Eigen::Vector4d(-0.5, -0.5, 0.1, 1.0), Eigen::Vector4d(0.5, -0.25, 0.3, 1.0),
                                              Eigen::Vector4d(0.0, 0.5, 0.7, 1.0)};
// The same, listed clockwise on the screen: set up as (v1, v0, v2).
const std::array<Eigen::Vector4d, 3> kFlatCw = {kFlat[2], kFlat[1], kFlat[0]};
// Perspective: w from 1.7 to 3.1, inside every plane.
const std::array<Eigen::Vector4d, 3> kPersp = {Eigen::Vector4d(-0.7, -0.6, 0.35, 1.7), Eigen::Vector4d(1.1, -0.4, 1.2, 2.3),
                                               Eigen::Vector4d(0.1, 1.3, 2.9, 3.1)};
// Vertex 0 behind the near plane (z + w = -0.5) and left of x = -w: clipped
// at x = -w first, then at the near plane, into a quadrilateral, two triangles.
const std::array<Eigen::Vector4d, 3> kNearLeft = {Eigen::Vector4d(-3.0, 0.2, -2.5, 2.0), Eigen::Vector4d(0.5, -0.5, 1.0, 3.0),
                                                  Eigen::Vector4d(0.2, 0.6, 4.0, 5.0)};

} // namespace

TEST_CASE("llvmpipe depth: a triangle inside the view volume", "[llvmpipe]") {
    for (bool fma : {true, false}) {
        LlvmpipeDepth lp(480, 24, fma);
        check(lp, add(lp, kFlat), {{0x1.ed6d88p-1f, 0x1.2b97b4p-14f, -0x1.381382p-10f, 400, 260, 11455043}});
    }
}

TEST_CASE("llvmpipe depth: a clockwise triangle is set up from its second vertex", "[llvmpipe]") {
    // The same plane as kFlat's but for dz/dx's last bit: the set-up's
    // differences start from another vertex.
    LlvmpipeDepth lp(480, 24, true);
    check(lp, add(lp, kFlatCw), {{0x1.ed6d88p-1f, 0x1.2b97b8p-14f, -0x1.381382p-10f, 400, 260, 11455043}});
}

TEST_CASE("llvmpipe depth: perspective vertices", "[llvmpipe]") {
    LlvmpipeDepth lp(480, 24, true);
    check(lp, add(lp, kPersp), {{0x1.1d2a74p+0f, 0x1.e8ac98p-13f, -0x1.c968aap-10f, 413, 248, 13043214}});
}

TEST_CASE("llvmpipe depth: a triangle crossing the near plane and the viewport's left edge", "[llvmpipe]") {
    // With FMA the unclipped vertex 1 lands at X = 466.66666 (one rounding
    // after the product), without it at 466.66669; the new vertices' window
    // positions are computed without FMA either way.
    LlvmpipeDepth with_fma(480, 24, true);
    check(with_fma, add(with_fma, kNearLeft),
          {{0x1.30d26cp+0f, 0x1.aad208p-10f, -0x1.2cd844p-8f, 294, 242, 9369929},
           {0x1.30d278p+0f, 0x1.aad204p-10f, -0x1.2cd850p-8f, 138, 220, 6802912}});
    LlvmpipeDepth without(480, 24, false);
    check(without, add(without, kNearLeft),
          {{0x1.30d26cp+0f, 0x1.aad204p-10f, -0x1.2cd844p-8f, 294, 242, 9369927},
           {0x1.30d278p+0f, 0x1.aad204p-10f, -0x1.2cd850p-8f, 138, 220, 6802914}});
}

TEST_CASE("llvmpipe depth: with the first vertex provoking", "[llvmpipe]") {
    // The clipped polygon fans out from its first vertex, (p0, p[i-1], p[i]),
    // and a clockwise triangle is set up as (v0, v2, v1): other roundings.
    LlvmpipeDepth lp(480, 24, true);
    check(lp, add(lp, kNearLeft, true),
          {{0x1.30d26cp+0f, 0x1.aad206p-10f, -0x1.2cd844p-8f, 294, 242, 9369927},
           {0x1.30d274p+0f, 0x1.aad206p-10f, -0x1.2cd84ep-8f, 138, 220, 6802910}});
    check(lp, add(lp, kFlatCw, true), {{0x1.ed6d88p-1f, 0x1.2b97cp-14f, -0x1.381382p-10f, 400, 260, 11455043}});
}

TEST_CASE("llvmpipe depth: triangles wholly outside one plane draw nothing", "[llvmpipe]") {
    LlvmpipeDepth lp(480, 24, true);
    const std::array<Eigen::Vector4d, 3> behind = {Eigen::Vector4d(0, 0, -2, 1), Eigen::Vector4d(0.5, 0, -3, 1),
                                                   Eigen::Vector4d(0, 0.5, -4, 1)};
    CHECK(add(lp, behind).count == 0);
    const std::array<Eigen::Vector4d, 3> line = {Eigen::Vector4d(0, 0, 0, 1), Eigen::Vector4d(0.5, 0, 0, 1),
                                                 Eigen::Vector4d(1, 0, 0, 1)};
    CHECK(add(lp, line).count == 0);   // no area once snapped
}

TEST_CASE("llvmpipe depth buffer: the same pixels as the exact one, the trace unchanged", "[llvmpipe]") {
    // Two overlapping draws, one clipped at the near plane and the left edge:
    // the llvmpipe buffer covers exactly the pixels the exact one does, its
    // depths differ by a few steps at most, and the fragments are the same.
    const auto run = [](bool llvmpipe, std::vector<rbcd::Fragment>& frags) {
        TileRasterizer r(800, 480, 16, 16, 24);
        r.keep_depth_buffer(true);
        if (llvmpipe) r.keep_llvmpipe_depth(true);
        r.begin_frame(0);
        r.add_depth_clear(1.0, rbcd::scene::PixelRect{0, 0, 799, 479});
        const std::array<std::uint32_t, 3> tri = {0, 1, 2};
        for (const auto* mesh : {&kPersp, &kNearLeft}) {
            DrawState s = DrawState::full_screen(800, 480);
            s.cull = rbcd::scene::CullFace::None;
            s.collisionable = true;
            s.id = 1;
            s.depth_from_unsnapped = true;
            const auto d = r.add_draw(s);
            REQUIRE(r.add_mesh(d, mesh->data(), 3, &tri, 1));
        }
        rbcd::Tile tile;
        while (r.next_tile(tile, nullptr)) frags.insert(frags.end(), tile.frags.begin(), tile.frags.end());
        return r;
    };
    std::vector<rbcd::Fragment> exact_frags, lp_frags;
    const TileRasterizer exact = run(false, exact_frags);
    const TileRasterizer lp = run(true, lp_frags);
    REQUIRE(exact_frags.size() == lp_frags.size());
    std::size_t frags_differ = 0;
    for (std::size_t i = 0; i < exact_frags.size(); ++i)
        frags_differ += exact_frags[i].x != lp_frags[i].x || exact_frags[i].y != lp_frags[i].y ||
                        exact_frags[i].depth != lp_frags[i].depth;
    CHECK(frags_differ == 0);
    CHECK(exact.depth_buffer() == lp.depth_buffer());
    const auto& e = exact.depth_buffer();
    const auto& l = lp.llvmpipe_depth_buffer();
    REQUIRE(l.size() == e.size());
    std::size_t covered = 0, coverage_differs = 0, differ = 0;
    std::int64_t max_diff = 0;
    for (std::size_t i = 0; i < e.size(); ++i) {
        coverage_differs += (e[i] == 0xFFFFFFu) != (l[i] == 0xFFFFFFu);
        covered += e[i] != 0xFFFFFFu;
        const std::int64_t d = std::abs(std::int64_t(e[i]) - std::int64_t(l[i]));
        differ += d != 0;
        max_diff = std::max(max_diff, d);
    }
    CHECK(coverage_differs == 0);
    CHECK(covered > 10000);
    CHECK(differ > 0);   // the arithmetic differs somewhere
    CHECK(max_diff <= 8);
}
