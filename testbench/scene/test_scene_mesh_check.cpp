// Mesh hygiene (docs/scene.md, "Mesh checks"): an open, inside-out or
// self-intersecting mesh file gets one warning line naming the file and the
// defect, check_mesh = false silences it, the built-in shapes and the default
// scene pass, and misleading assimp messages are replaced by clear ones.
#include <catch2/catch.hpp>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include <Eigen/Geometry>

#include "rbcd/common/errors.h"
#include "rbcd/scene/mesh.h"
#include "rbcd/scene/mesh_check.h"
#include "rbcd/scene/scene_source.h"
#include "rbcd/testbench/common/temp_dir.h"

using namespace rbcd::scene;
using Catch::Matchers::Contains;

namespace {

// Writes m as OBJ (shared vertices) or ASCII STL (three corners per facet).
std::string write_obj(const rbcd::test::TempDir& td, const std::string& name, const Mesh& m) {
    std::ostringstream s;
    s.precision(17);
    for (const auto& v : m.verts) s << "v " << v.x() << " " << v.y() << " " << v.z() << "\n";
    for (const auto& t : m.tris) s << "f " << t[0] + 1 << " " << t[1] + 1 << " " << t[2] + 1 << "\n";
    return td.write(name, s.str());
}
std::string write_stl(const rbcd::test::TempDir& td, const std::string& name, const Mesh& m) {
    std::ostringstream s;
    s.precision(17);
    s << "solid t\n";
    for (const auto& t : m.tris) {
        s << "facet normal 0 0 0\nouter loop\n";
        for (auto i : t) s << "vertex " << m.verts[i].x() << " " << m.verts[i].y() << " " << m.verts[i].z() << "\n";
        s << "endloop\nendfacet\n";
    }
    s << "endsolid t\n";
    return td.write(name, s.str());
}

Mesh reversed(Mesh m) {
    for (auto& t : m.tris) std::swap(t[1], t[2]);
    return m;
}
// Two copies of m, the second moved by `d`: intersecting when |d| is small.
Mesh twice(const Mesh& m, const Eigen::Vector3d& d) {
    Mesh r = m;
    const auto base = std::uint32_t(m.verts.size());
    for (const auto& v : m.verts) r.verts.push_back(v + d);
    for (const auto& t : m.tris) r.tris.push_back({t[0] + base, t[1] + base, t[2] + base});
    return r;
}

Mesh loaded(const std::string& path) {
    Mesh m;
    std::string err;
    INFO(path);
    REQUIRE(load_mesh_file(path, m, err));
    return m;
}

// Everything written to std::cerr while f runs.
template <class F>
std::string cerr_of(F f) {
    std::ostringstream cap;
    std::streambuf* old = std::cerr.rdbuf(cap.rdbuf());
    try {
        f();
    } catch (...) {
        std::cerr.rdbuf(old);
        throw;
    }
    std::cerr.rdbuf(old);
    return cap.str();
}

std::string scene_with(const std::string& mesh, const std::string& extra = "") {
    return "format = \"rbcd-scene 1\"\nframes = 1\n[screen]\nwidth = 64\nheight = 48\n"
           "[camera]\neye = [0.0, 0.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 45.0\nnear = 0.5\nfar = 50.0\n"
           "[[object]]\nname = \"m\"\nid = 1\nmesh = \"" + mesh + "\"\n" + extra;
}

} // namespace

TEST_CASE("mesh check: the built-in shapes are closed, outward and free of self-intersection", "[scene][meshcheck]") {
    for (const char* shape : {"sphere", "box", "torus", "cylinder"})
        for (unsigned seg : {3u, 4u, 7u, 32u, 200u}) {
            INFO(shape << " " << seg);
            const MeshCheck c = check_mesh(builtin_mesh(shape, seg));
            CHECK(c.problems().empty());
            CHECK(c.closed);
            CHECK(c.signed_volume > 0.0);
            CHECK(c.intersection_checked);
        }
    // Volumes as a check of the sum: box 8, sphere (32 segments) just under 4/3 pi.
    CHECK(check_mesh(builtin_mesh("box", 0)).signed_volume == Approx(8.0));
    const double sv = check_mesh(builtin_mesh("sphere", 32)).signed_volume;
    CHECK(sv < 4.18879);
    CHECK(sv > 4.0);
}

TEST_CASE("mesh check: an open mesh, from OBJ and from STL", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    Mesh box = builtin_mesh("box", 0);
    box.tris.resize(10);   // one face (two triangles) missing: a square hole of 4 edges
    for (const std::string& p : {write_obj(td, "open.obj", box), write_stl(td, "open.stl", box)}) {
        INFO(p);
        const MeshCheck c = check_mesh(loaded(p));
        CHECK(c.boundary_edges == 4);
        CHECK_FALSE(c.closed);
        CHECK_FALSE(c.inside_out);   // an open surface has no inside
        CHECK_FALSE(c.self_intersecting);
        CHECK(c.problems() == "open (4 boundary edges)");
    }
}

TEST_CASE("mesh check: a closed mesh wound inside out", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    const Mesh inv = reversed(builtin_mesh("sphere", 12));
    for (const std::string& p : {write_obj(td, "inv.obj", inv), write_stl(td, "inv.stl", inv)}) {
        INFO(p);
        const MeshCheck c = check_mesh(loaded(p));
        CHECK(c.closed);
        CHECK(c.inside_out);
        CHECK(c.signed_volume < 0.0);
        CHECK_THAT(c.problems(), Contains("wound inside out (signed volume -"));
        CHECK(c.boundary_edges + c.misoriented_edges + c.nonmanifold_edges == 0);
    }
    // The same sphere the right way round, as STL: vertices welded by position.
    CHECK(check_mesh(loaded(write_stl(td, "ok.stl", builtin_mesh("sphere", 12)))).problems().empty());
}

TEST_CASE("mesh check: one triangle flipped against its neighbours", "[scene][meshcheck]") {
    Mesh box = builtin_mesh("box", 0);
    std::swap(box.tris[3][1], box.tris[3][2]);
    const MeshCheck c = check_mesh(box);
    CHECK(c.misoriented_edges == 3);
    CHECK_THAT(c.problems(), Contains("inconsistently wound (3 edges"));
}

TEST_CASE("mesh check: self-intersection, and not for solids that only touch", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    const Mesh box = builtin_mesh("box", 0);
    const Mesh crossing = twice(box, {0.5, 0.3, 0.2});
    const MeshCheck c = check_mesh(loaded(write_obj(td, "x.obj", crossing)));
    CHECK(c.closed);
    CHECK_FALSE(c.inside_out);
    CHECK(c.self_intersecting);
    CHECK(c.tri_b >= 12u);   // one triangle of each copy
    CHECK(c.tri_a < 12u);
    CHECK_THAT(c.problems(), Contains("self-intersecting (triangles "));
    // Moved along the diagonal: every crossing lies on a face diagonal.
    CHECK(check_mesh(twice(box, {0.5, 0.5, 0.5})).self_intersecting);
    // Face to face (touching) and apart: no crossing.
    CHECK_FALSE(check_mesh(twice(box, {2.0, 0.0, 0.0})).self_intersecting);
    CHECK_FALSE(check_mesh(twice(box, {2.0, 0.5, 0.5})).self_intersecting);
    // A face doubled the same way round overlaps in its plane.
    Mesh doubled = box;
    doubled.verts.push_back({-1.0, -0.5, -0.5});
    doubled.verts.push_back({-1.0, 0.5, -0.5});
    doubled.verts.push_back({-1.0, 0.0, 0.5});
    for (const auto& t : box.tris)   // copy the winding of a face at x = -1
        if (box.verts[t[0]].x() == -1.0 && box.verts[t[1]].x() == -1.0 && box.verts[t[2]].x() == -1.0) {
            const Eigen::Vector3d n = (box.verts[t[1]] - box.verts[t[0]]).cross(box.verts[t[2]] - box.verts[t[0]]);
            doubled.tris.push_back(n.x() < 0 ? std::array<std::uint32_t, 3>{8, 10, 9} : std::array<std::uint32_t, 3>{8, 9, 10});
            break;
        }
    CHECK(check_mesh(doubled).self_intersecting);
    CHECK_FALSE(check_mesh(twice(box, {2.5, 0.1, 0.0})).self_intersecting);
    // A torus pushed through a copy of itself, from a large mesh.
    const Mesh torus = builtin_mesh("torus", 128);
    CHECK(check_mesh(twice(torus, {1.0, 0.0, 0.0})).self_intersecting);
    // The work limit: stopped before it can tell.
    const MeshCheck capped = check_mesh(crossing, 3);
    CHECK_FALSE(capped.intersection_checked);
    CHECK_FALSE(capped.self_intersecting);
}

TEST_CASE("mesh check: a scene warns once per defective mesh file; check_mesh = false silences it", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    Mesh open = builtin_mesh("box", 0);
    open.tris.resize(10);
    write_obj(td, "open.obj", open);
    const rbcd::scene::SceneLimits lim{};
    const std::string err = cerr_of([&] {
        auto src = SceneSource::from_text(scene_with("open.obj") + "[[object]]\nmesh = \"open.obj\"\n", td.dir, "s.toml", lim);
    });
    INFO(err);
    CHECK(std::count(err.begin(), err.end(), '\n') == 1);
    CHECK_THAT(err, Contains("s.toml:"));
    CHECK_THAT(err, Contains("warning"));
    CHECK_THAT(err, Contains("open.obj' is open (4 boundary edges)"));
    CHECK_THAT(err, Contains("check_mesh = false"));

    const std::string quiet = cerr_of([&] {
        auto src = SceneSource::from_text(scene_with("open.obj", "check_mesh = false\n"), td.dir, "s.toml", lim);
    });
    CHECK(quiet.empty());

    CHECK_THROWS_WITH(SceneSource::from_text(scene_with("open.obj", "check_mesh = 0\n"), td.dir, "s.toml", lim),
                      Contains("s.toml:16: object[0] (\"m\").check_mesh: expected a boolean"));
}

TEST_CASE("mesh check: the default scene and the clean mesh files stay silent", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    write_obj(td, "ok.obj", builtin_mesh("torus", 24));
    write_stl(td, "ok.stl", builtin_mesh("cylinder", 16));
    const rbcd::scene::SceneLimits lim{};
    const std::string err = cerr_of([&] {
        SceneSource::from_text(default_scene_text(), "", "<default scene>", lim);
        SceneSource::from_text(scene_with("ok.obj") + "[[object]]\nmesh = \"ok.stl\"\n", td.dir, "s.toml", lim);
    });
    CHECK(err.empty());
}

TEST_CASE("mesh files: misleading assimp messages are replaced", "[scene][meshcheck]") {
    rbcd::test::TempDir td;
    auto error_of = [](const std::string& path) {
        Mesh m;
        std::string err;
        CHECK_FALSE(load_mesh_file(path, m, err));
        return err;
    };
    // glTF 1 whose buffer file is missing: assimp says "No suitable reader found".
    const std::string gltf1 = td.write("tri.gltf", R"({"asset": {"version": "1.0"},
 "buffers": {"b": {"uri": "tri.bin", "byteLength": 42, "type": "arraybuffer"}},
 "bufferViews": {"vi": {"buffer": "b", "byteOffset": 0, "byteLength": 6, "target": 34963},
                 "vp": {"buffer": "b", "byteOffset": 6, "byteLength": 36, "target": 34962}},
 "accessors": {"ai": {"bufferView": "vi", "byteOffset": 0, "componentType": 5123, "count": 3, "type": "SCALAR"},
               "ap": {"bufferView": "vp", "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3"}},
 "meshes": {"m": {"primitives": [{"attributes": {"POSITION": "ap"}, "indices": "ai", "mode": 4}]}},
 "nodes": {"n": {"meshes": ["m"]}},
 "scene": "s", "scenes": {"s": {"nodes": ["n"]}}})");
    CHECK(error_of(gltf1) == "the file 'tri.bin' it refers to is missing (looked for beside it)");
    // With the buffer there it loads: the message was about the missing file only.
    {
        std::ofstream bin(td.path("tri.bin"), std::ios::binary);
        const std::uint16_t idx[3] = {0, 1, 2};
        const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        bin.write(reinterpret_cast<const char*>(idx), sizeof idx);
        bin.write(reinterpret_cast<const char*>(pos), sizeof pos);
    }
    CHECK(loaded(gltf1).tris.size() == 1);
    // An empty ASCII STL: assimp says "Mesh with invalid primitive type".
    CHECK(error_of(td.write("empty.stl", "solid empty\nendsolid empty\n")) == "it holds no triangles");
    CHECK(error_of(td.write("comment.obj", "# nothing\n")) == "it holds no triangles");
    CHECK(error_of(td.write("zero.stl", "")) == "the file is empty");
}
