// rbcd-sim with mesh files: the one-line warning for a defective mesh (and the
// run goes on), check_mesh = false, the bundled default scene silent, and the
// mesh files listed with their sizes and hashes in the stats' provenance.
#include "rbcd/testbench/sim/cli_util.h"

#include <nlohmann/json.hpp>


using namespace rbcd::cli_test;

namespace {

// A box of edge 2 as OBJ quads, one face left out when `open`, every face
// reversed when `inverted`.
std::string box_obj(bool open, bool inverted) {
    std::string s = "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";
    const char* faces[] = {"1 4 3 2", "5 6 7 8", "1 2 6 5", "4 8 7 3", "1 5 8 4", "2 3 7 6"};
    for (int i = open ? 1 : 0; i < 6; ++i) {
        std::string f = faces[i];
        if (inverted) f = std::string(f.rbegin(), f.rend());
        s += "f " + f + "\n";
    }
    return s;
}

std::string scene(const std::string& mesh, const std::string& extra = "") {
    return "format = \"rbcd-scene 1\"\nframes = 2\n[screen]\nwidth = 64\nheight = 48\n"
           "[camera]\neye = [0.0, 0.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 45.0\nnear = 0.5\nfar = 50.0\n"
           "[[object]]\nname = \"m\"\nid = 1\nmesh = \"" + mesh + "\"\n" + extra +
           "[[object]]\nid = 2\nmesh = \"sphere\"\nposition = [0.5, 0.0, 0.0]\n";
}

} // namespace

TEST_CASE("cli scene: an open mesh file gets one warning line naming file and defect, and the run completes") {
    TempDir td;
    td.write("open.obj", box_obj(true, false));
    const std::string sc = td.write("s.toml", scene("open.obj"));
    const Result r = run_with_outputs(td, {"--scene", sc, "-q"});
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, StartsWith(sc + ":15: warning: object[0] (\"m\").mesh: mesh file '"));
    CHECK_THAT(r.err, Contains("open.obj' is open (4 boundary edges)"));
    CHECK_THAT(r.err, Contains("check_mesh = false"));
    CHECK(fs::exists(td.stats()));
}

TEST_CASE("cli scene: an inside-out mesh file is warned about, check_mesh = false silences it") {
    TempDir td;
    td.write("inv.obj", box_obj(false, true));
    const Result r = run_sim(td, {"--scene", td.write("s.toml", scene("inv.obj")), "-q"});
    CHECK(r.status == 0);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, Contains("inv.obj' is wound inside out (signed volume -8)"));
    const Result q = run_sim(td, {"--scene", td.write("q.toml", scene("inv.obj", "check_mesh = false\n")), "-q"});
    CHECK(q.status == 0);
    CHECK(q.err.empty());
}

TEST_CASE("cli scene: a self-intersecting mesh file is warned about") {
    TempDir td;
    // The box and a copy moved by (0.5, 0.5, 0.5) in one file.
    std::string two = box_obj(false, false);
    for (const char* v : {"v -0.5 -0.5 -0.5\nv 1.5 -0.5 -0.5\nv 1.5 1.5 -0.5\nv -0.5 1.5 -0.5\n",
                          "v -0.5 -0.5 1.5\nv 1.5 -0.5 1.5\nv 1.5 1.5 1.5\nv -0.5 1.5 1.5\n"})
        two += v;
    two += "f 9 12 11 10\nf 13 14 15 16\nf 9 10 14 13\nf 12 16 15 11\nf 9 13 16 12\nf 10 11 15 14\n";
    td.write("two.obj", two);
    const Result r = run_sim(td, {"--scene", td.write("s.toml", scene("two.obj")), "-q"});
    CHECK(r.status == 0);
    CHECK(count_lines(r.err) == 1);
    CHECK_THAT(r.err, Contains("two.obj' is self-intersecting (triangles "));
}

TEST_CASE("cli scene: the default scene and a clean mesh file run without a word on stderr") {
    TempDir td;
    const Result d = run_sim(td, {"-q"});
    CHECK(d.status == 0);
    CHECK(d.err.empty());
    td.write("box.obj", box_obj(false, false));
    const Result r = run_sim(td, {"--scene", td.write("s.toml", scene("box.obj")), "-q"});
    CHECK(r.status == 0);
    CHECK(r.err.empty());
}

TEST_CASE("cli scene: the provenance lists the scene and each mesh file once with size and hash") {
    TempDir td;
    const std::string obj = td.write("box.obj", box_obj(false, false));
    const std::string sc = td.write("s.toml", scene("box.obj") + "[[object]]\nmesh = \"box.obj\"\nposition = [0.0, 2.0, 0.0]\n");
    const Result r = run_with_outputs(td, {"--scene", sc, "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const auto p = nlohmann::json::parse(slurp(td.stats()))["provenance"];
    REQUIRE(p["inputs"].size() == 2);
    CHECK(p["inputs"][0]["role"] == "scene");
    CHECK(p["inputs"][0]["path"] == sc);
    CHECK(p["inputs"][0]["xxh128"] == xxh128_of(slurp(sc)));
    CHECK(p["inputs"][1]["role"] == "mesh");
    CHECK(fs::equivalent(p["inputs"][1]["path"].get<std::string>(), obj));
    CHECK(p["inputs"][1]["size"] == fs::file_size(obj));
    CHECK(p["inputs"][1]["xxh128"] == xxh128_of(slurp(obj)));
}
