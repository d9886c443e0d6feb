// Analytic collision cases, judged by a per-pixel depth-interval overlap check
// over the rendered fragments (scene_test_util.h), and the default scene's plan.
#include "scene_test_util.h"

using namespace scene_test;

namespace {

const std::string kHdr = scene_header(200, 150, 1);

Obj sphere(int id, V3 pos, double r = 1.0) {
    Obj o;
    o.name = "s" + std::to_string(id);
    o.id = id;
    o.pos = pos;
    o.scale = {r, r, r};
    o.segments = 32;
    return o;
}

} // namespace

TEST_CASE("two overlapping spheres collide, two apart ones do not", "[scene][collide]") {
    SECTION("overlapping side by side") {
        Capture c = capture_text(kHdr + object_text(sphere(1, {-0.6, 0, -6})) + object_text(sphere(2, {0.6, 0, -6})));
        CHECK(colliding_pairs(c.frames[0], c.h) == std::set<Pair>{{1, 2}});
    }
    SECTION("overlapping one behind the other") {
        Capture c = capture_text(kHdr + object_text(sphere(5, {0, 0, -6})) + object_text(sphere(2, {0.3, 0.2, -7.5})));
        CHECK(colliding_pairs(c.frames[0], c.h) == std::set<Pair>{{2, 5}});
    }
    SECTION("apart, one behind the other: they share pixels but not depths") {
        Capture c = capture_text(kHdr + object_text(sphere(1, {0, 0, -5})) + object_text(sphere(2, {0.5, 0, -9})));
        CHECK(shared_pixels(c.frames[0], c.h, 1, 2) > 500u);
        CHECK(colliding_pairs(c.frames[0], c.h).empty());
    }
    SECTION("apart by a tenth of the radius along the view") {
        Capture c = capture_text(kHdr + object_text(sphere(1, {0, 0, -5})) + object_text(sphere(2, {0, 0, -7.1})));
        CHECK(shared_pixels(c.frames[0], c.h, 1, 2) > 500u);
        CHECK(colliding_pairs(c.frames[0], c.h).empty());
    }
    SECTION("apart side by side") {
        Capture c = capture_text(kHdr + object_text(sphere(1, {-1.5, 0, -6})) + object_text(sphere(2, {1.5, 0, -6})));
        CHECK(shared_pixels(c.frames[0], c.h, 1, 2) == 0u);
        CHECK(colliding_pairs(c.frames[0], c.h).empty());
    }
    SECTION("approaching over an animation") {
        Obj a = sphere(1, {-4, 0, -7});
        a.extra = "[[object.key]]\nframe = 8\nposition = [0.0, 0.0, -7.0]\n";
        Capture c = capture_text(scene_header(200, 150, 9) + object_text(a) + object_text(sphere(2, {1.2, 0, -7})));
        // Centre distance 5.2 - 0.5 f: 2.7 or more up to frame 5, 1.7 or less from frame 7.
        for (int f = 0; f <= 5; ++f) CHECK(colliding_pairs(c.frames[f], c.h).empty());
        for (int f = 7; f <= 8; ++f) CHECK(colliding_pairs(c.frames[f], c.h) == std::set<Pair>{{1, 2}});
    }
}

TEST_CASE("a rod through a torus hole does not collide; touching the tube it does", "[scene][collide][concave]") {
    Obj torus;
    torus.name = "ring";
    torus.mesh = "torus";
    torus.id = 3;
    torus.pos = {0, 0, -6};
    torus.rot = {60, 0, 0};   // the hole half faces the camera
    torus.scale = {1.5, 1.5, 1.5};
    torus.segments = 40;
    Obj rod;
    rod.name = "rod";
    rod.mesh = "cylinder";
    rod.id = 4;
    rod.pos = torus.pos;
    rod.rot = torus.rot;
    rod.scale = {0.15, 2.5, 0.15};
    rod.segments = 16;
    Capture c = capture_text(kHdr + object_text(torus) + object_text(rod));
    CHECK(shared_pixels(c.frames[0], c.h, 3, 4) > 100u);   // overlapping footprints (and bounding boxes)
    CHECK(colliding_pairs(c.frames[0], c.h).empty());

    // Moved 1.2 along x: the rod (radius 0.15) reaches into the tube, whose
    // inner edge is at 1.125.
    rod.pos.x = 1.2;
    Capture t = capture_text(kHdr + object_text(torus) + object_text(rod));
    CHECK(colliding_pairs(t.frames[0], t.h) == std::set<Pair>{{3, 4}});
}

TEST_CASE("an object inside another collides with it", "[scene][collide]") {
    Obj box;
    box.name = "box";
    box.mesh = "box";
    box.id = 7;
    box.pos = {0, 0, -8};
    box.rot = {10, 20, 0};
    box.scale = {2, 2, 2};
    Capture c = capture_text(kHdr + object_text(box) + object_text(sphere(3, {0.2, -0.1, -8}, 0.3)));
    CHECK(colliding_pairs(c.frames[0], c.h) == std::set<Pair>{{3, 7}});
}

TEST_CASE("objects hidden behind a non-collisionable wall still collide", "[scene][collide][other]") {
    Obj wall;
    wall.name = "wall";
    wall.mesh = "box";
    wall.pos = {0, 0, -3};
    wall.scale = {4, 4, 0.1};
    Capture c = capture_text(kHdr + object_text(wall) + object_text(sphere(1, {-0.6, 0, -8})) +
                             object_text(sphere(2, {0.6, 0, -8})));
    CHECK(colliding_pairs(c.frames[0], c.h) == std::set<Pair>{{1, 2}});
    // The wall covers the whole screen: every tile has other fragments.
    const std::size_t tiles = ((200 + 15) / 16) * ((150 + 15) / 16);
    CHECK(c.frames[0].tiles.size() == tiles);
    for (const auto& t : c.frames[0].tiles) CHECK(t.other > 0);
    CHECK(c.frames[0].other() == 200u * 150u);   // front faces only (cull = back), each pixel once
}

TEST_CASE("the default scene collides, passes close and threads the ring as designed", "[scene][collide][default]") {
    auto s = rbcd::scene::SceneSource::from_text(rbcd::scene::default_scene_text(), "", "<default scene>", {});
    Capture c = capture(*s);
    REQUIRE(c.frames.size() == 60u);
    std::set<Pair> all;
    std::vector<std::set<Pair>> per_frame;
    std::size_t ring_rod_overlap = 0, cube_post_overlap = 0;
    for (const auto& f : c.frames) {
        const PixelFrags px = per_pixel(f, c.h);
        per_frame.push_back(colliding_pairs(px));
        all.insert(per_frame.back().begin(), per_frame.back().end());
        ring_rod_overlap += shared_pixels(px, 5, 6) > 0;
        cube_post_overlap += shared_pixels(px, 3, 4) > 0;
    }
    CHECK(all == std::set<Pair>{{1, 2}, {7, 8}});
    for (int f = 0; f <= 24; ++f) CHECK(per_frame[f].count({1, 2}) == 0);
    for (int f = 28; f <= 33; ++f) CHECK(per_frame[f].count({1, 2}) == 1);
    for (int f = 38; f <= 41; ++f) CHECK(per_frame[f].count({7, 8}) == 1);
    for (int f = 0; f <= 34; ++f) CHECK(per_frame[f].count({7, 8}) == 0);
    CHECK(ring_rod_overlap == 60u);    // the concave case: always overlapping on screen
    CHECK(cube_post_overlap > 0u);     // the close pass is visible as screen overlap
}
