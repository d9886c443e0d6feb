// rbcd-sim on 3D scenes, as a user runs it: --scene against --write-trace
// replayed with --trace, images, waveforms, and bad scenes failing cleanly.
#include "rbcd/testbench/sim/cli_util.h"

#include <nlohmann/json.hpp>
#include <filesystem>

using namespace rbcd::cli_test;

namespace {

// A 96x64 screen and a camera 6 units in front of the origin.
const std::string kView = R"([screen]
width = 96
height = 64
[camera]
eye = [0.0, 0.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
near = 0.5
far = 50.0
)";

// Two overlapping spheres in front of the camera: collide in every frame.
const std::string kTwoSpheres = "format = \"rbcd-scene 1\"\nframes = 3\n" + kView + R"([[object]]
name = "a"
id = 1
mesh = "sphere"
segments = 16
position = [-0.5, 0.0, 0.0]
[[object]]
name = "b"
id = 2
mesh = "sphere"
segments = 16
position = [0.5, 0.0, 0.0]
[[object]]
name = "wall"
mesh = "box"
position = [0.0, 0.0, -3.0]
scale = [4.0, 4.0, 0.1]
)";

std::size_t count(const std::string& s, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
    return n;
}

} // namespace

TEST_CASE("cli scene: --write-trace replayed with --trace gives the same collisions stats and GPU figures") {
    TempDir td;
    const std::string scene = td.write("s.toml", kTwoSpheres);
    const std::string trace = td.path("s.rbt");
    const std::string c1 = td.path("c1.txt"), c2 = td.path("c2.txt"), s1 = td.path("s1.json"), s2 = td.path("s2.json");
    const std::string f1 = td.path("f1.jsonl"), f2 = td.path("f2.jsonl");
    const Result a = run_sim(td, {"--scene", scene, "--write-trace", trace, "--collisions", c1, "--stats", s1,
                                  "--frame-stats", f1, "-q"});
    INFO(a.err);
    REQUIRE(a.status == 0);
    // The scene's primitive counts and rasterization order travel in the trace.
    const std::string written = slurp(trace);
    CHECK_THAT(written, Contains(" prims="));
    CHECK_THAT(written, Contains(" cprims="));
    CHECK_THAT(written, Contains("\no "));
    const Result b = run_sim(td, {"--trace", trace, "--collisions", c2, "--stats", s2, "--frame-stats", f2, "-q"});
    INFO(b.err);
    REQUIRE(b.status == 0);
    const std::string out = slurp(c1);
    CHECK(out == slurp(c2));
    CHECK(count(out, "frame ") == 3);
    CHECK(count(out, "hit ") > 0);   // the spheres overlap in every frame
    const auto j1 = nlohmann::json::parse(slurp(s1)), j2 = nlohmann::json::parse(slurp(s2));
    CHECK(j1["totals"] == j2["totals"]);
    CHECK(j1["totals"]["cycles"].get<std::uint64_t>() > 0);
    // The paced pipeline sees the same primitives and order: the same GPU time and energy.
    CHECK(j1["gpu"] == j2["gpu"]);
    CHECK(j1["energy"] == j2["energy"]);
    CHECK(j1["blocks"] == j2["blocks"]);
    CHECK(j1["gpu"]["culled_primitives"].get<std::uint64_t>() > 0);
    CHECK(slurp(f1) == slurp(f2));
}

TEST_CASE("cli scene: the embedded default scene runs with no arguments and matches its written trace") {
    TempDir td;
    const std::string trace = td.path("default.rbt"), c1 = td.path("c1.txt"), c2 = td.path("c2.txt");
    const Result a = run_sim(td, {"--write-trace", trace, "--collisions", c1});
    INFO(a.err);
    REQUIRE(a.status == 0);
    CHECK_THAT(a.out, Contains("<default scene>"));
    CHECK_THAT(a.out, Contains("frames 60"));
    REQUIRE(run_sim(td, {"--trace", trace, "--collisions", c2, "-q"}).status == 0);
    const std::string out = slurp(c1);
    CHECK(out == slurp(c2));
    // The scene's plan: balls 1-2 and drop/pedestal 7-8 collide; cube/post 3-4
    // and ring/rod 5-6 never do.
    CHECK_THAT(out, Contains(" 1 2 "));
    CHECK_THAT(out, Contains(" 7 8 "));
    CHECK_THAT(out, !Contains(" 3 4 "));
    CHECK_THAT(out, !Contains(" 5 6 "));
}

TEST_CASE("cli scene: --images writes one PNG per frame") {
    TempDir td;
    const std::string scene = td.write("s.toml", kTwoSpheres);
    const std::string dir = td.path("png");
    const Result r = run_sim(td, {"--scene", scene, "--images", dir, "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    for (const char* f : {"frame_00000.png", "frame_00001.png", "frame_00002.png"}) {
        INFO(f);
        REQUIRE(fs::exists(dir + "/" + f));
        const std::string png = slurp(dir + "/" + f);
        CHECK(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
    }
}

TEST_CASE("cli scene: --images with a trace is a command-line error") {
    TempDir td;
    const Result r = run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--images", td.path("png")});
    expect_input_error(td, r, {"--images"});
    CHECK_FALSE(fs::exists(td.path("png")));
}

TEST_CASE("cli scene: --scene and --trace together are a command-line error") {
    TempDir td;
    const std::string scene = td.write("s.toml", kTwoSpheres);
    const Result r = run_with_outputs(td, {"--scene", scene, "--trace", kVectors + "/rule-fig5-case2.rbt"});
    expect_input_error(td, r, {"--scene"});
}

TEST_CASE("cli scene: a missing mesh file exits 2 naming the scene and key and leaves nothing") {
    TempDir td;
    std::string text = kTwoSpheres;
    text.replace(text.find("mesh = \"box\""), 12, "mesh = \"nowhere.obj\"");
    const std::string scene = td.write("bad.toml", text);
    const std::string vcd = td.out_dir() + "/w.vcd", trace = td.out_dir() + "/w.rbt";
    std::ofstream(vcd) << kOld;
    const Result r = run_with_outputs(td, {"--scene", scene, "--vcd", vcd, "--write-trace", trace});
    expect_input_error(td, r, {scene + ":", "mesh"});
}

TEST_CASE("cli scene: an unknown shape exits 2 naming file:line and the key") {
    TempDir td;
    std::string text = kTwoSpheres;
    text.replace(text.find("mesh = \"box\""), 12, "mesh = \"cone\"");
    const std::string scene = td.write("bad.toml", text);
    const Result r = run_with_outputs(td, {"--scene", scene});
    expect_input_error(td, r, {scene + ":", "mesh"});
}

TEST_CASE("cli scene: a singular transform exits 2") {
    TempDir td;
    std::string text = kTwoSpheres;
    text.replace(text.find("scale = [4.0, 4.0, 0.1]"), 23, "scale = [4.0, 0.0, 0.1]");
    const std::string scene = td.write("bad.toml", text);
    const Result r = run_with_outputs(td, {"--scene", scene});
    expect_input_error(td, r, {scene + ":", "scale"});
}

TEST_CASE("cli scene: a camera looking away from everything exits 2 and leaves nothing") {
    TempDir td;
    std::string text = kTwoSpheres;
    text.replace(text.find("target = [0.0, 0.0, 0.0]"), 24, "target = [0.0, 0.0, 12.0]");
    const std::string scene = td.write("bad.toml", text);
    const std::string trace = td.out_dir() + "/w.rbt";
    const Result r = run_with_outputs(td, {"--scene", scene, "--write-trace", trace});
    expect_input_error(td, r, {"nothing in view"});
}

// Sphere "a" starts close to the camera, its tiles deeper than the limit
// the tests set, and from frame 10 on sits at "b"'s place, colliding.
const std::string kNearThenFar = "format = \"rbcd-scene 1\"\nframes = 20\n" + kView + R"([[object]]
name = "a"
id = 1
mesh = "sphere"
segments = 16
position = [0.0, 0.0, 3.0]
  [[object.key]]
  frame = 10
  position = [-0.2, 0.0, -30.0]
[[object]]
name = "b"
id = 2
mesh = "sphere"
segments = 16
position = [0.2, 0.0, -30.0]
)";

TEST_CASE("cli scene: --frames renders no frame before its range", "[frames_cli]") {
    // A frame is a function of its number: the frames before the range touch
    // nothing the run computes, so their errors are not the run's. Were they
    // rendered, frame 0's deep tiles would refuse every range.
    TempDir td;
    const std::string scene = td.write("near.toml", kNearThenFar);
    const std::vector<std::string> limit{"--set", "input.max_tile_fragments=200"};
    std::vector<std::string> args{"-q", "--scene", scene};
    args.insert(args.end(), limit.begin(), limit.end());
    expect_input_error(td, run_with_outputs(td, args), {scene, "frame 0, tile", "input.max_tile_fragments"});
    auto from_1 = args;   // the range's own frames are checked as ever
    from_1.insert(from_1.end(), {"--frames", "1:"});
    expect_input_error(td, run_with_outputs(td, from_1), {scene, "frame 1, tile", "input.max_tile_fragments"});

    const Result whole = run_with_outputs(td, {"-q", "--scene", scene});
    REQUIRE(whole.status == 0);
    const std::string all = slurp(td.collisions());
    const std::size_t at = all.find("frame 10\n");
    REQUIRE(at != std::string::npos);
    const std::string expected = "rbcd-collisions 1\n" + all.substr(at);
    REQUIRE(count(expected, "hit ") > 0);
    for (const std::vector<std::string>& more : {std::vector<std::string>{"--frames", "10:"},
                                                 std::vector<std::string>{"--frames", "10:", "--jobs", "2"},
                                                 std::vector<std::string>{"--frames", "10:", "--jobs", "3"}}) {
        auto a = args;
        a.insert(a.end(), more.begin(), more.end());
        const Result r = run_with_outputs(td, a);
        INFO(r.cmd << "\n" << r.err);
        REQUIRE(r.status == 0);
        CHECK(slurp(td.collisions()) == expected);
        CHECK(nlohmann::json::parse(slurp(td.stats()))["totals"]["frames"] == 10);
    }

    // Nor after it, nor any when the range is past the end: the sphere comes
    // close in the last frames instead, and a range past them is refused for
    // what it is.
    std::string late = kNearThenFar;
    late.replace(late.find("[0.0, 0.0, 3.0]"), 15, "[-0.2, 0.0, -30.0]");
    late.replace(late.find("frame = 10"), 10, "frame = 19");
    late.replace(late.find("  position = [-0.2, 0.0, -30.0]"), 31, "  position = [0.0, 0.0, 3.0]");
    const std::string near_last = td.write("late.toml", late);
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        auto a = limit;
        a.insert(a.end(), {"-q", "--scene", near_last, "--jobs", jobs, "--frames"});
        auto past = a, last = a, before = a;
        past.push_back("25:");
        last.push_back("19");
        before.push_back("0:16");
        expect_input_error(td, run_with_outputs(td, past),
                           {"--frames: 25: selects no frame: the input has 20 frames (0..19)"});
        expect_input_error(td, run_with_outputs(td, last), {near_last, "frame 19, tile", "input.max_tile_fragments"});
        CHECK(run_with_outputs(td, before).status == 0);
    }
}

TEST_CASE("cli scene: --frames says nothing in view only when no frame of the scene has a fragment", "[frames_cli]") {
    // Rendered from the range on, a run whose frames hold nothing looks at
    // the skipped frames (until one holds a fragment) to say it as a whole
    // run would; a range that ends before the scene does never said it.
    TempDir td;
    std::string early = kNearThenFar;   // in view in frames 0 to 4 only
    early.replace(early.find("[0.0, 0.0, 3.0]"), 15, "[0.0, 0.0, 0.0]");
    early.replace(early.find("frame = 10"), 10, "frame = 5");
    early.replace(early.find("[-0.2, 0.0, -30.0]"), 18, "[60.0, 0.0, 0.0]");
    early.replace(early.find("[0.2, 0.0, -30.0]"), 17, "[-60.0, 0.0, 0.0]");
    const std::string seen_early = td.write("early.toml", early);
    std::string none = early;
    none.replace(none.find("[0.0, 0.0, 0.0]"), 15, "[0.0, 60.0, 0.0]");
    const std::string never_seen = td.write("none.toml", none);
    for (const char* jobs : {"1", "2", "3"}) {
        INFO("--jobs " << jobs);
        const Result whole_none = run_with_outputs(td, {"-q", "--scene", never_seen, "--jobs", jobs});
        expect_input_error(td, whole_none, {"nothing in view in any frame"});
        const Result late_none = run_with_outputs(td, {"-q", "--scene", never_seen, "--frames", "5:", "--jobs", jobs});
        expect_input_error(td, late_none, {"nothing in view in any frame"});
        CHECK(late_none.err == whole_none.err);
        CHECK(run_with_outputs(td, {"-q", "--scene", never_seen, "--frames", "5:9", "--jobs", jobs}).status == 0);
        // A range past the end is the command line's error, whatever the scene holds.
        expect_input_error(td, run_with_outputs(td, {"-q", "--scene", never_seen, "--frames", "20:", "--jobs", jobs}),
                           {"--frames: 20: selects no frame: the input has 20 frames (0..19)"});

        const Result late = run_with_outputs(td, {"-q", "--scene", seen_early, "--frames", "5:", "--jobs", jobs});
        INFO(late.err);
        REQUIRE(late.status == 0);
        const auto totals = nlohmann::json::parse(slurp(td.stats()))["totals"];
        CHECK(totals["frames"] == 15);
        CHECK(totals["fragments"] == 0);
        REQUIRE(run_with_outputs(td, {"-q", "--scene", seen_early, "--frames", "0:4", "--jobs", jobs}).status == 0);
        CHECK(nlohmann::json::parse(slurp(td.stats()))["totals"]["fragments"] > 0);
    }
}

TEST_CASE("cli scene: a failed run removes the output directories it made, and only those") {
    TempDir td;
    const std::string scene = td.write("near.toml", kNearThenFar);
    const std::string made = td.path("made"), there = td.path("there");
    std::filesystem::create_directory(there);
    const Result r = run_with_outputs(td, {"-q", "--scene", scene, "--set", "input.max_tile_fragments=200", "--images",
                                           made + "/deep/images", "--heat-maps", there + "/maps"});
    expect_input_error(td, r, {"frame 0, tile", "input.max_tile_fragments"});
    CHECK_FALSE(std::filesystem::exists(made));
    CHECK(std::filesystem::is_directory(there));
    CHECK_FALSE(std::filesystem::exists(there + "/maps"));
    // A run that succeeds keeps them.
    const Result ok = run_with_outputs(td, {"-q", "--scene", scene, "--frames", "10:11", "--images", made + "/images"});
    INFO(ok.err);
    REQUIRE(ok.status == 0);
    CHECK(std::filesystem::exists(made + "/images/frame_00011.png"));
}

TEST_CASE("cli scene: an unknown scene key exits 2 naming it") {
    TempDir td;
    const std::string scene = td.write("bad.toml", kTwoSpheres + "colour = \"red\"\n");
    const Result r = run_with_outputs(td, {"--scene", scene});
    expect_input_error(td, r, {scene + ":", "colour"});
}

TEST_CASE("cli vcd: a failed run leaves no waveform and a good one a complete dump") {
    TempDir td;
    const std::string vcd = td.out_dir() + "/run.vcd";
    std::ofstream(vcd) << kOld;
    const Result bad = run_sim(td, {"--trace", td.write("bad.rbt", "rbcd-trace 1\nframe 1\n"), "--vcd", vcd});
    CHECK(bad.status == 2);
    CHECK_FALSE(fs::exists(vcd));
    const Result good = run_sim(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--vcd", vcd, "-q"});
    REQUIRE(good.status == 0);
    const std::string text = slurp(vcd);
    CHECK_THAT(text, Contains("$enddefinitions $end"));
    CHECK_THAT(text, Contains("$scope module zoverlap_tester $end"));
    CHECK_THAT(text, Contains("$dumpvars"));
}
