// What rbcd-sim leaves on disk when a run cannot complete: never an older
// result, never a temporary, never the user's input or directories.
#include "testbench/sim/cli_util.h"

#include <csignal>
#include <thread>

using namespace rbcd::cli_test;

namespace {

const std::string kTrace = "rbcd-trace 1\nframe 0\ntile 0 0\nf 0 0 100 1 F\nf 0 0 200 2 F\nf 0 0 300 1 B\n";

} // namespace

TEST_CASE("cli outputs: --write-trace naming the input trace is refused and the input survives") {
    TempDir td;
    const std::string in = td.write("in.rbt", kTrace + "bogus\n");
    const Result r = run_with_outputs(td, {"--trace", in, "--write-trace", in});
    expect_input_error(td, r, {"--write-trace", "is the input file"});
    CHECK(slurp(in) == kTrace + "bogus\n");
}

TEST_CASE("cli outputs: --collisions naming the input trace is refused and the input survives") {
    TempDir td;
    const std::string in = td.write("in.rbt", kTrace);
    const Result r = run_sim(td, {"--trace", in, "--collisions", in});
    CHECK(r.status == 2);
    CHECK_THAT(r.err, Contains("is the input file"));
    CHECK(slurp(in) == kTrace);
}

TEST_CASE("cli outputs: --stats naming the config file is refused and the config survives") {
    TempDir td;
    const std::string cfg = td.write("c.toml", "[zeb]\nbanks = 1\n");
    const Result r = run_sim(td, {"--trace", td.write("in.rbt", kTrace), "--config", cfg, "--stats", cfg});
    CHECK(r.status == 2);
    CHECK_THAT(r.err, Contains("is the input file"));
    CHECK(slurp(cfg) == "[zeb]\nbanks = 1\n");
}

TEST_CASE("cli outputs: --write-trace into a directory is refused and the directory survives") {
    TempDir td;
    const std::string dir = td.path("adir");
    fs::create_directory(dir);
    const Result r = run_with_outputs(td, {"--trace", td.write("in.rbt", kTrace), "--write-trace", dir});
    expect_input_error(td, r, {dir, "is a directory"});
    CHECK(fs::is_directory(dir));
}

TEST_CASE("cli outputs: a bad trace with --write-trace leaves no trace file and keeps a directory named like it") {
    TempDir td;
    const std::string out = td.out_dir() + "/w.rbt";
    const Result r = run_with_outputs(td, {"--trace", td.write("bad.rbt", kTrace + "f 99 0 1 1 F\n"), "--write-trace", out});
    expect_input_error(td, r, {"bad.rbt:7:"});
    CHECK_FALSE(fs::exists(out));
}

TEST_CASE("cli outputs: a run killed by SIGTERM leaves neither the older outputs nor temporaries") {
    TempDir td;
    td.plant_old_outputs();
    const std::string fifo = td.path("in.fifo");
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    std::vector<std::string> args{RBCD_SIM, "--trace", fifo, "--collisions", td.collisions(), "--stats", td.stats()};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
    pid_t pid = 0;
    REQUIRE(posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ) == 0);
    posix_spawn_file_actions_destroy(&fa);
    // rbcd-sim creates its outputs, then blocks opening the FIFO: wait for the
    // temporaries to appear, then stop it as a user would.
    bool created = false;
    for (int i = 0; i < 500 && !created; ++i) {
        created = td.out_entries().size() >= 2 && !fs::exists(td.collisions());
        if (!created) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    CHECK(created);
    REQUIRE(kill(pid, SIGTERM) == 0);
    int st = 0;
    REQUIRE(waitpid(pid, &st, 0) == pid);
    CHECK(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 128 + SIGTERM);
    std::string names;
    for (const auto& e : td.out_entries()) names += e + " ";
    INFO("left behind: " << names);
    CHECK(td.out_entries().empty());
}
