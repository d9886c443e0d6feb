// rbcd-cpucd's three detectors on analytic cases, the geometry file, and the
// per-pixel interval check the accuracy analysis relies on (docs/cpucd.md).
#include <catch2/catch.hpp>

#include <Eigen/Geometry>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "rbcd/common/errors.h"
#include "rbcd/cpu/cd_input.h"
#include "rbcd/cpu/cpu_collision.h"
#include "rbcd/cpu/instruction_count.h"
#include "rbcd/cpu/pixel_overlap.h"
#include "rbcd/scene/mesh.h"

using namespace rbcd;
using namespace rbcd::cpucd;

namespace {

std::shared_ptr<const PartMesh> shape(const char* name, unsigned segments = 32) {
    const scene::Mesh m = scene::builtin_mesh(name, segments);
    auto p = std::make_shared<PartMesh>();
    p->verts = m.verts;
    p->tris = m.tris;
    return p;
}

Eigen::Matrix4d place(Eigen::Vector3d pos, Eigen::Vector3d scale = {1, 1, 1}) {
    Eigen::Affine3d a = Eigen::Affine3d::Identity();
    a.translate(pos);
    a.scale(scale);
    return a.matrix();
}

// A camera at z = 10 looking down -z at the origin (as the scene front end builds it).
Eigen::Matrix4d camera_towards_origin() {
    const double n = 0.5, f = 50, fy = 1.0 / std::tan(30.0 * 3.14159265358979 / 180.0), aspect = 800.0 / 480.0;
    Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
    p(0, 0) = fy / aspect;
    p(1, 1) = fy;
    p(2, 2) = (f + n) / (n - f);
    p(2, 3) = 2 * f * n / (n - f);
    p(3, 2) = -1;
    Eigen::Matrix4d v = Eigen::Matrix4d::Identity();
    v(2, 3) = -10;
    return p * v;
}

CdInput two(std::shared_ptr<const PartMesh> a, const Eigen::Matrix4d& ma, std::shared_ptr<const PartMesh> b,
            const Eigen::Matrix4d& mb) {
    CdInput in;
    in.name = "test";
    in.width = 800;
    in.height = 480;
    in.has_view = true;
    in.view_proj = camera_towards_origin();
    in.parts = {Part{1, "a", a}, Part{2, "b", b}};
    in.model = {{ma, mb}};
    return in;
}

PairResult only_pair(const CdInput& in) {
    CpuDetector d(in);
    FrameResult r = d.run_frame(0, 1);
    if (r.pairs.empty()) return PairResult{1, 2};
    REQUIRE(r.pairs.size() == 1);
    return r.pairs[0];
}

} // namespace

TEST_CASE("two spheres apart: no method reports them", "[cpucd]") {
    const PairResult p = only_pair(two(shape("sphere"), place({-1.5, 0, 0}), shape("sphere"), place({1.5, 0, 0})));
    CHECK_FALSE(p.aabb);
    CHECK_FALSE(p.gjk);
    CHECK_FALSE(p.exact);
}

TEST_CASE("two spheres touching: every method reports them", "[cpucd]") {
    // Centres 1.98 apart: the tessellated surfaces overlap by a sliver.
    const PairResult p = only_pair(two(shape("sphere"), place({-0.99, 0, 0}), shape("sphere"), place({0.99, 0, 0})));
    CHECK(p.aabb);
    CHECK(p.gjk);
    CHECK(p.exact);
    CHECK_FALSE(p.contained);
    CHECK(p.on_screen);
    CHECK(p.contacts > 0);
}

TEST_CASE("a sphere inside another: ground truth by containment", "[cpucd]") {
    const PairResult p =
        only_pair(two(shape("sphere"), place({0, 0, 0}, {2, 2, 2}), shape("sphere"), place({0.3, 0.2, 0}, {0.4, 0.4, 0.4})));
    CHECK(p.aabb);
    CHECK(p.gjk);
    CHECK(p.exact);
    CHECK(p.contained);
    CHECK(p.on_screen);
}

TEST_CASE("a rod through a ring: AABB and hull report contact, ground truth does not", "[cpucd]") {
    // Torus: major radius 1, tube 0.25 (hole radius 0.75) around Y; the rod has radius 0.2.
    const PairResult p = only_pair(two(shape("torus"), place({0, 0, 0}), shape("cylinder", 16), place({0, 0, 0}, {0.2, 1.5, 0.2})));
    CHECK(p.aabb);
    CHECK(p.gjk);
    CHECK_FALSE(p.exact);
}

TEST_CASE("a contact behind the camera is not on screen", "[cpucd]") {
    const PairResult p = only_pair(two(shape("sphere"), place({-0.99, 0, 20}), shape("sphere"), place({0.99, 0, 20})));
    CHECK(p.exact);
    CHECK_FALSE(p.on_screen);
}

TEST_CASE("parts sharing an id are one object", "[cpucd]") {
    CdInput in = two(shape("sphere"), place({-0.5, 0, 0}), shape("sphere"), place({0.5, 0, 0}));
    in.parts[1].id = 1;
    CpuDetector d(in);
    CHECK(d.run_frame(0, 1).pairs.empty());
}

// The collision world, (d) and (e), against the bare queries (a) and (b) on
// the analytic cases: (d) is (a); (e) is (b) where both shapes are convex,
// and where one is concave (the ring, GImpact) it follows the surfaces, as
// the ground truth does.
TEST_CASE("collision world: the bare queries' pairs on the analytic cases", "[cpucd][world]") {
    struct Case {
        const char* what;
        CdInput in;
        bool world;   // expected (e)
    };
    const Case cases[] = {
        {"apart", two(shape("sphere"), place({-1.5, 0, 0}), shape("sphere"), place({1.5, 0, 0})), false},
        {"touching", two(shape("sphere"), place({-0.99, 0, 0}), shape("sphere"), place({0.99, 0, 0})), true},
        {"contained", two(shape("sphere"), place({0, 0, 0}, {2, 2, 2}), shape("sphere"), place({0.3, 0.2, 0}, {0.4, 0.4, 0.4})),
         true},
        {"boxes overlapping, scaled", two(shape("box"), place({0, 0, 0}, {2, 1, 1}), shape("box"), place({1.9, 0.5, 0})), true},
        {"spheres whose boxes overlap", two(shape("sphere"), place({0, 0, 0}), shape("sphere"), place({1.6, 1.6, 0})), false},
        {"rod through a ring", two(shape("torus"), place({0, 0, 0}), shape("cylinder", 16), place({0, 0, 0}, {0.2, 1.5, 0.2})),
         false},
    };
    // Fresh (a format-2 frame: every section from an empty broad phase and
    // world, repeated) or incremental: the same pairs.
    for (const bool fresh : {false, true})
    for (const Case& c : cases) {
        INFO(c.what << (fresh ? ", fresh" : ""));
        DetectorOptions opt;
        opt.fresh = fresh;
        CpuDetector d(c.in, opt);
        const FrameResult r = d.run_frame(0, fresh ? 3 : 1);
        REQUIRE(r.pairs.size() <= 1);
        const PairResult p = r.pairs.empty() ? PairResult{1, 2} : r.pairs[0];
        CHECK(p.world_aabb == p.aabb);
        CHECK(p.world == c.world);
        if (d.concave_parts() == 0) CHECK(p.world == p.gjk);
        else CHECK(p.world == p.exact);
    }
}

TEST_CASE("collision world: parts of one object never pair, over moving frames", "[cpucd][world]") {
    CdInput in = two(shape("sphere"), place({-0.5, 0, 0}), shape("sphere"), place({0.5, 0, 0}));
    in.parts.push_back(Part{2, "c", shape("sphere")});
    in.model[0].push_back(place({3, 0, 0}));
    in.parts[1].id = 1;   // a and b: one object; c approaches it
    for (double x : {2.0, 1.2, 0.8}) in.model.push_back({place({-0.5, 0, 0}), place({0.5, 0, 0}), place({x, 0, 0})});
    CpuDetector d(in);
    for (std::uint64_t f = 0; f < in.frames(); ++f) {
        const FrameResult r = d.run_frame(f, 2);
        for (const PairResult& p : r.pairs) {
            CHECK(p.a != p.b);
            CHECK(p.world_aabb == p.aabb);
            CHECK(p.world == p.gjk);
        }
        if (f == 3) CHECK(r.pairs.size() == 1);   // c at 0.8 overlaps b (0.5), the one object's pair
    }
}

TEST_CASE("convexity: a game's choice of shape", "[cpucd][world]") {
    CHECK(is_convex(*shape("sphere")));
    CHECK(is_convex(*shape("box")));
    CHECK(is_convex(*shape("cylinder", 16)));
    CHECK_FALSE(is_convex(*shape("torus")));
}

// A callgrind dump as `valgrind --tool=callgrind --compress-strings=no
// --compress-pos=no` writes it: 1000 instructions in all, of which main's
// calls to malloc (120, with _int_malloc inside) and operator new (75, calling
// malloc: counted once) are the allocator's: 1000 - 195 = 805 counted.
TEST_CASE("callgrind dump: the total less the allocator's inclusive cost", "[cpucd][count]") {
    std::istringstream dump(R"(# callgrind format
version: 1
positions: line
events: Ir
summary: 1000

ob=libc.so.6
fn=_int_malloc
10 80

fn=malloc
5 40
cfn=_int_malloc
calls=2 10
5 80

fn=operator new(unsigned long)
3 25
cfn=malloc
calls=1 5
3 50

ob=build/bin/program
fn=main
1 600
cfn=malloc
calls=3 5
2 120
cfn=operator new(unsigned long)
calls=1 3
4 75
cfn=btDbvt::update(btDbvtNode*, int)
calls=2 0
5 130
fn=btDbvt::update(btDbvtNode*, int)
0 130

totals: 1000
)");
    const CallgrindCounts c = parse_callgrind_dump(dump);
    CHECK(c.has_total);
    CHECK(c.total == 1000);
    CHECK(c.allocator == 195);
    CHECK(is_allocator_function("operator delete(void*, unsigned long)"));
    CHECK_FALSE(is_allocator_function("btAlignedAllocInternal(unsigned long, int)"));
}

TEST_CASE("a pair with an open mesh is flagged open", "[cpucd]") {
    auto open = std::make_shared<PartMesh>(*shape("box"));
    open->tris.pop_back();
    CHECK(only_pair(two(open, place({-0.5, 0, 0}), shape("sphere"), place({0.5, 0, 0}))).open);
    CHECK_FALSE(only_pair(two(shape("box"), place({-0.5, 0, 0}), shape("sphere"), place({0.5, 0, 0}))).open);
}

TEST_CASE("point in mesh by ray parity", "[cpucd]") {
    const auto box = shape("box");
    CHECK(point_in_mesh(*box, {0.1, 0.2, 0.3}));
    CHECK_FALSE(point_in_mesh(*box, {1.5, 0, 0}));
    CHECK(is_closed(*box));
    PartMesh open = *box;
    open.tris.pop_back();
    CHECK_FALSE(is_closed(open));
}

TEST_CASE("is_closed welds vertices by position: seams close, a missing or a third triangle opens", "[cpucd]") {
    // A unit square's two triangles twice, back to back, each side with its own
    // copies of the corners (a seam), one corner as -0.0: closed.
    PartMesh m;
    for (int side = 0; side < 2; ++side)
        for (const Eigen::Vector3d& v : {Eigen::Vector3d(side ? -0.0 : 0.0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                         Eigen::Vector3d(1, 1, 0), Eigen::Vector3d(0, 1, 0)})
            m.verts.push_back(v);
    m.tris = {{0, 1, 2}, {0, 2, 3}, {4, 7, 5}, {5, 7, 6}};   // the back split along the other diagonal
    CHECK(is_closed(m));
    PartMesh three = m;
    three.tris.push_back({0, 1, 3});   // 0-1, 1-3 and 3-0 now thrice
    CHECK_FALSE(is_closed(three));
    PartMesh missing = m;
    missing.tris.pop_back();
    CHECK_FALSE(is_closed(missing));
    PartMesh none = m;
    none.tris = {{0, 4, 0}};   // degenerate only: no edge
    CHECK_FALSE(is_closed(none));
}

TEST_CASE("geometry file: numbers are read as strtod reads them, whatever their form", "[cpucd]") {
    const auto first_vertex_x = [](const std::string& x) {
        return load_geometry_text("rbcd-geometry 1\npart 1 3 1\nv " + x + " 0 0\nv 1 0 0\nv 0 1 0\nt 0 1 2\nframe 0\n"
                                  "m 0 1 0 0 0 0 1 0 0 0 0 1 0\n",
                                  "n")
            .parts[0]
            .mesh->verts[0]
            .x();
    };
    for (const char* x : {"0.1", "-2.5e-3", "+1", "0x1p-1", ".5", "5.", "1e-320", "0.30000000000000004", "-0"}) {
        INFO(x);
        CHECK(first_vertex_x(x) == std::strtod(x, nullptr));
    }
    for (const char* x : {"1e400", "inf", "nan", "1e", "--1", "1,5", "0x"}) {
        INFO(x);
        try {
            first_vertex_x(x);
            FAIL("accepted");
        } catch (const InputError& e) {
            CHECK(std::string(e.what()).find("n:3: '" + std::string(x) + "' is not a finite number") == 0);
        }
    }
}

TEST_CASE("geometry file: written and read back the same, bad input names the line", "[cpucd]") {
    CdInput in = two(shape("sphere", 8), place({-1, 0, 0}), shape("box"), place({1, 0.5, 0}, {1, 2, 1}));
    const std::string path = "test_cpucd_geometry.txt";
    {
        std::ofstream f(path);
        f << geometry_file_text(in);
    }
    const CdInput back = load_geometry_file(path);
    REQUIRE(back.parts.size() == 2);
    CHECK(back.parts[1].mesh->tris == in.parts[1].mesh->tris);
    CHECK(back.parts[0].mesh->verts == in.parts[0].mesh->verts);
    CHECK(back.model[0][1] == in.model[0][1]);
    CHECK(back.view_proj == in.view_proj);
    CHECK(back.width == 800);
    {
        std::ofstream f(path);
        f << "rbcd-geometry 1\npart 1 3 1\nv 0 0 0\nv 1 0 0\nv 0 1 0\nt 0 1 7\n";
    }
    try {
        load_geometry_file(path);
        FAIL("no error");
    } catch (const InputError& e) {
        CHECK(std::string(e.what()).find(path + ":6:") == 0);
    }
    std::remove(path.c_str());
}

TEST_CASE("geometry file format 2: each frame's own meshes and view, written and read back; misplaced records refused",
          "[cpucd]") {
    // Two unit boxes as frame 0's meshes, overlapping; frame 1 moves the second apart and has no view.
    const auto box_at = [](const std::string& rec, double x) {
        std::string s = rec + " 8 12\n";
        for (int i = 0; i < 8; ++i)
            s += "v " + std::to_string(x + (i & 1)) + " " + std::to_string(i >> 1 & 1) + " " + std::to_string(i >> 2 & 1) + "\n";
        for (const char* t : {"0 2 1", "1 2 3", "4 5 6", "5 7 6", "0 1 4", "1 5 4", "2 6 3", "3 6 7", "0 4 2", "2 4 6", "1 3 5", "3 7 5"})
            s += std::string("t ") + t + "\n";
        return s;
    };
    const std::string view = "view 1 0 0 0 0 1 0 0 0 0 -1 -2 0 0 -1 0\n";
    const std::string text = "rbcd-geometry 2\nscreen 64 48\nframe 0\n" + view + box_at("mesh 1", 0) +
                             box_at("mesh 2", 0.5) + "frame 1\n" + box_at("mesh 1", 0) + box_at("mesh 2", 3);
    const CdInput in = load_geometry_text(text, "g2");
    REQUIRE(in.frames() == 2);
    REQUIRE(in.per_frame());
    CHECK(in.parts.empty());
    CHECK(in.extra[0].meshes.size() == 2);
    CHECK(in.extra[0].has_view);
    CHECK_FALSE(in.extra[1].has_view);
    const CdInput f0 = in.frame_input(0), f1 = in.frame_input(1);
    CHECK(f0.parts.size() == 2);
    CHECK(f0.has_view);
    CHECK(f0.view_proj(2, 3) == -2.0);
    CHECK(only_pair(f0).exact);
    CHECK(overlapping_aabb_pairs(f1, 0, 100).pairs.empty());
    // Written back: format 2 again, and read back to the same text.
    const std::string once = geometry_file_text(in);
    CHECK(once.rfind("rbcd-geometry 2\n", 0) == 0);
    CHECK(geometry_file_text(load_geometry_text(once, "again")) == once);
    const auto refused = [](const std::string& t, const std::string& where) {
        try {
            load_geometry_text(t, "bad");
            FAIL("accepted: " << t);
        } catch (const InputError& e) {
            CHECK(std::string(e.what()).find(where) == 0);
        }
    };
    refused("rbcd-geometry 2\n" + box_at("mesh 1", 0), "bad:2: mesh: meshes belong to a frame");
    refused("rbcd-geometry 1\nframe 0\n" + box_at("mesh 1", 0), "bad:2: frame: no part");
    refused("rbcd-geometry 2\nscreen 8 8\nframe 0\n" + view + view, "bad:5: view: given twice");
    refused("rbcd-geometry 2\nframe 0\n" + view, "bad: 'view' needs a 'screen' record");
}

TEST_CASE("pixel intervals: overlap, near within the tolerance, apart", "[cpucd]") {
    auto frag = [](std::uint32_t x, std::uint32_t depth, std::uint32_t id, Facing f) {
        Fragment r;
        r.x = x;
        r.y = 0;
        r.depth = depth;
        r.id = id;
        r.facing = f;
        return r;
    };
    const std::vector<Fragment> frags = {
        // pixel 0: 1 = [10, 20], 2 = [15, 30]: overlap
        frag(0, 10, 1, Facing::Front), frag(0, 20, 1, Facing::Back), frag(0, 15, 2, Facing::Front), frag(0, 30, 2, Facing::Back),
        // pixel 1: 1 = [10, 20], 2 = [21, 30]: one unit apart
        frag(1, 10, 1, Facing::Front), frag(1, 20, 1, Facing::Back), frag(1, 21, 2, Facing::Front), frag(1, 30, 2, Facing::Back),
        // pixel 2: 1 = [10, 20], 2 = [25, 30]: apart; 3 = [12, 14] inside 1 (containment)
        frag(2, 10, 1, Facing::Front), frag(2, 20, 1, Facing::Back), frag(2, 25, 2, Facing::Front), frag(2, 30, 2, Facing::Back),
        frag(2, 12, 3, Facing::Front), frag(2, 14, 3, Facing::Back),
        // pixel 3: touching at equal depth counts as overlap (front before back)
        frag(3, 10, 1, Facing::Front), frag(3, 20, 1, Facing::Back), frag(3, 20, 2, Facing::Front), frag(3, 30, 2, Facing::Back),
    };
    FramePixels px;
    DepthHistogram h;
    pixel_overlap_tile(frags, 1, px, &h);
    CHECK(px[{1, 2}].overlap == 2);
    CHECK(px[{1, 2}].near == 1);
    CHECK(px[{1, 3}].overlap == 1);
    CHECK(px.count({2, 3}) == 0);
    REQUIRE(h.size() == kDepthBins);
    CHECK(h[4] == 3);
    CHECK(h[6] == 1);
}
