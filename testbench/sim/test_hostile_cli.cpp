// rbcd-sim against hostile inputs (issue 12): cases that, unchecked, exit 0
// with a wrong answer, exit 1 after std::bad_alloc, hang, or print raw control
// bytes. Each must exit 2 with one line naming the limit and the key that
// raises it, and leave nothing at the output paths.
#include "rbcd/testbench/sim/cli_util.h"

using namespace rbcd::cli_test;

namespace {
const std::string kTrace = "rbcd-trace 1\nframe 0\ntile 0 0\nf 0 0 100 1 F\nf 0 0 300 1 B\nf 0 0 200 2 F\n";
const std::string kScene = "format = \"rbcd-scene 1\"\nframes = 2\n[camera]\neye = [0.0, 0.0, 0.0]\n"
                           "target = [0.0, 0.0, -1.0]\nfov_y = 60.0\nnear = 0.1\nfar = 100.0\n"
                           "[[object]]\nid = 1\nmesh = \"sphere\"\nposition = [0.0, 0.0, -5.0]\n";
} // namespace

TEST_CASE("cli hostile: --config naming a directory or /dev/zero is refused") {
    TempDir td;
    for (const std::string& c : {td.dir, std::string("/dev/zero")}) {
        const Result r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--config", c});
        expect_input_error(td, r, {c + ": cannot read configuration file: is a "});
    }
}

TEST_CASE("cli hostile: /dev/zero as trace or scene is refused at once, not read until memory runs out") {
    TempDir td;
    Result r = run_with_outputs(td, {"--trace", "/dev/zero"});
    expect_input_error(td, r, {"/dev/zero: cannot read trace: is a character device, not a regular file"});
    r = run_with_outputs(td, {"--scene", "/dev/zero"});
    expect_input_error(td, r, {"/dev/zero: cannot read scene file: is a character device, not a regular file"});
}

TEST_CASE("cli hostile: a missing input has the same wording whatever its kind") {
    TempDir td;
    const std::string missing = td.path("missing");
    const std::pair<std::vector<std::string>, std::string> cases[] = {
        {{"--trace", missing}, "trace"},
        {{"--scene", missing}, "scene file"},
        {{"--config", missing}, "configuration file"},
    };
    for (const auto& [args, what] : cases) {
        const Result r = run_with_outputs(td, args);
        expect_input_error(td, r, {missing + ": cannot read " + what + ": No such file or directory"});
    }
    const std::string scene = td.write("s.toml", kScene + "[[object]]\nmesh = \"missing.obj\"\n");
    const Result r = run_with_outputs(td, {"--scene", scene});
    expect_input_error(td, r, {td.path("missing.obj") + ": cannot read mesh file: No such file or directory"});
}

TEST_CASE("cli hostile: a trace whose simulated time would overflow 64-bit picoseconds is refused") {
    // Wrapped, totals.cycles would come out below the sum of the tiles' own cycles.
    TempDir td;
    std::string t = "rbcd-trace 1\nscreen 2048 2048\nframe 0\n";
    for (int i = 0; i < 4000; ++i)
        t += "tile " + std::to_string(i % 128) + " " + std::to_string(i / 128) + " other=1099511627776\n";
    const Result r = run_with_outputs(td, {"--trace", td.write("long.rbt", t)});
    expect_input_error(td, r, {"long.rbt:", "the run is too long to simulate", "clock.mhz = 400", "docs/limits.md"});
}

TEST_CASE("cli hostile: toml++'s unreachable path (bytes c2 a1) is refused before parsing") {
    TempDir td;
    Result r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--config", td.write("c.toml", "\xc2\xa1")});
    expect_input_error(td, r, {"c.toml:1: character U+00A1 outside a comment"});
    r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--set", "zeb.tie=\xc2\xa1"});
    expect_input_error(td, r, {"--set zeb.tie:1: character U+00A1"});
    r = run_with_outputs(td, {"--scene", td.write("s.toml", kScene + "name = \"\xc2\xa1\"\n")});
    expect_input_error(td, r, {"s.toml:", "U+00A1"});
}

TEST_CASE("cli hostile: control bytes from the input are escaped: messages stay one line") {
    TempDir td;
    // A scene name that would set the terminal title, echoed by an error about
    // the object (TOML decodes the escapes into raw bytes).
    Result r = run_with_outputs(td, {"--scene", td.write("s.toml", kScene + "name = \"a\\u001b]0;t\\u0007\\nb\"\ncull = \"x\"\n")});
    expect_input_error(td, r, {"s.toml:", ".cull", "(\"a\\x1b]0;t\\x07\\x0ab\")"});
    CHECK(r.err.find('\x1b') == std::string::npos);
    // A bare --set word for a string key is echoed in its error.
    r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--set", "zeb.tie=a\x1b[2Jb\rc"});
    expect_input_error(td, r, {"--set zeb.tie", "a\\x1b[2Jb\\x0dc"});
    CHECK(r.err.find('\x1b') == std::string::npos);
    // toml++'s own message echoes the raw byte it saw.
    r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--config", td.write("c.toml", "a = tru\x01" "e\n")});
    expect_input_error(td, r, {"c.toml:1:", "saw 'tru\\x01'"});
    CHECK(r.err.find('\x01') == std::string::npos);
}

TEST_CASE("cli hostile: limits are raised by the keys their messages name") {
    TempDir td;
    const std::string t = td.write("t.rbt", "rbcd-trace 1\n# " + std::string(2000, 'x') + "\nframe 0\n");
    Result r = run_with_outputs(td, {"--trace", t, "--set", "input.max_line_bytes=1000"});
    expect_input_error(td, r, {"t.rbt:2: line longer than 1000 bytes", "input.max_line_bytes"});
    r = run_with_outputs(td, {"--trace", t, "--set", "input.max_line_bytes=4000", "-q"});
    CHECK(r.status == 0);
    r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--set", "input.max_tile_fragments=2"});
    expect_input_error(td, r, {"in.rbt:6: tile 0 0 has more than 2 fragments", "input.max_tile_fragments"});
    r = run_with_outputs(td, {"--scene", td.write("s.toml", kScene), "--set", "input.max_scene_triangles=100"});
    expect_input_error(td, r, {"s.toml:", "input.max_scene_triangles"});
    r = run_with_outputs(td, {"--scene", td.write("s.toml", kScene), "--set", "input.max_scene_bytes=64"});
    expect_input_error(td, r, {"s.toml: scene file larger than 64 bytes", "input.max_scene_bytes"});
}

TEST_CASE("cli hostile: a trace on standard input (-) is read") {
    TempDir td;
    const std::string in = td.write("in.rbt", kTrace);
    // run_sim gives the child /dev/null as stdin; a shell redirect is the user's way.
    const std::string cmd = std::string(RBCD_SIM) + " --trace - -q --collisions " + td.collisions() + " < " + in;
    CHECK(std::system(cmd.c_str()) == 0);
    CHECK_THAT(slurp(td.collisions()), StartsWith("rbcd-collisions 1\nframe 0\nhit 0 0 1 2"));
}
