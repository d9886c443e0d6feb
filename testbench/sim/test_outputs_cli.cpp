// What rbcd-sim leaves on disk when a run cannot complete: never an older
// result, never a temporary, never the user's input or directories.
#include "rbcd/testbench/sim/cli_util.h"

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
    // Standard input is a pipe nobody writes to: rbcd-sim blocks reading it.
    int pfd[2];
    REQUIRE(::pipe(pfd) == 0);
    const pid_t pid = spawn_program({RBCD_SIM, "--trace", "-", "--collisions", td.collisions(), "--stats", td.stats()},
                                    "/dev/null", "/dev/null", pfd[0], pfd[1]);
    ::close(pfd[0]);
    // rbcd-sim creates its outputs, then blocks reading the pipe: wait for the
    // temporaries to appear, then stop it as a user would.
    // Both older outputs gone and two temporaries there: both outputs are open.
    // A little more time lets the last one's clean-up registration follow its
    // creation (slow sanitizer builds); rbcd-sim then blocks on the pipe.
    bool created = false;
    for (int i = 0; i < 500 && !created; ++i) {
        created = td.out_entries().size() == 2 && !fs::exists(td.collisions()) && !fs::exists(td.stats());
        if (!created) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    CHECK(created);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    REQUIRE(kill(pid, SIGTERM) == 0);
    int st = 0;
    REQUIRE(waitpid(pid, &st, 0) == pid);
    ::close(pfd[1]);
    CHECK(WIFEXITED(st));
    CHECK(WEXITSTATUS(st) == 128 + SIGTERM);
    std::string names;
    for (const auto& e : td.out_entries()) names += e + " ";
    INFO("left behind: " << names);
    CHECK(td.out_entries().empty());
}

// ---------------------------------------------------------------- safe output files (issue 12)

namespace {
const std::string kGoodTrace = "rbcd-trace 1\nframe 0\ntile 0 0\nf 0 0 100 1 F\nf 0 0 300 1 B\nf 0 0 200 2 F\n";

// The pid the next process will most likely get, and a span after it.
long next_pid_guess() {
    std::ifstream in("/proc/sys/kernel/ns_last_pid");
    long p = 0;
    in >> p;
    return p + 1;
}
} // namespace

TEST_CASE("cli outputs: a symlink planted at the old predictable temporary name is not followed") {
    TempDir td;
    const std::string victim = td.write("victim.txt", "precious\n");
    const std::string out = td.collisions();
    // The old code wrote to <out>.tmp.<pid> with fopen: plant links for the pids
    // the child is likely to get.
    const long p0 = next_pid_guess();
    for (long p = p0; p < p0 + 400; ++p) REQUIRE(::symlink(victim.c_str(), (out + ".tmp." + std::to_string(p)).c_str()) == 0);
    const Result r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--collisions", out, "-q"});
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(slurp(victim) == "precious\n");
    CHECK_THAT(slurp(out), StartsWith("rbcd-collisions 1\nframe 0\nhit 0 0 1 2"));
    // Only the links and the output: no temporary left.
    std::size_t others = 0;
    for (const auto& e : td.out_entries()) others += e.find(".tmp.") == std::string::npos && e != "collisions.txt";
    CHECK(others == 0);
}

TEST_CASE("cli outputs: a symlink at an output path is written through and never replaced or removed") {
    TempDir td;
    const std::string target = td.write("target.txt", "old\n");
    const std::string link = td.out_dir() + "/link.txt";
    REQUIRE(::symlink(target.c_str(), link.c_str()) == 0);
    Result r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--collisions", link, "-q"});
    CHECK(r.status == 0);
    CHECK(fs::is_symlink(link));
    CHECK_THAT(slurp(target), StartsWith("rbcd-collisions 1\n"));
    // A failed run (bad --set) leaves the link and its target's file in place.
    r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--collisions", link, "--set", "zeb.banks=99"});
    CHECK(r.status == 2);
    CHECK(fs::is_symlink(link));
    CHECK(fs::exists(target));
}

TEST_CASE("cli outputs: a FIFO at an output path is written in place and survives a failed run") {
    TempDir td;
    const std::string fifo = td.out_dir() + "/c.fifo";
    REQUIRE(mkfifo(fifo.c_str(), 0600) == 0);
    std::string got;
    std::thread reader([&] { got = slurp(fifo); });
    Result r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--collisions", fifo, "-q"});
    reader.join();
    CHECK(r.status == 0);
    CHECK_THAT(got, StartsWith("rbcd-collisions 1\nframe 0\nhit 0 0 1 2"));
    struct stat st {};
    REQUIRE(::lstat(fifo.c_str(), &st) == 0);
    CHECK(S_ISFIFO(st.st_mode));
    // The old code unlinked whatever stood at an output path on failure
    // (--collisions /dev/stdout with a bad --set deleted /dev/stdout as root).
    r = run_sim(td, {"--collisions", fifo, "--set", "zeb.banks=99"});
    CHECK(r.status == 2);
    REQUIRE(::lstat(fifo.c_str(), &st) == 0);
    CHECK(S_ISFIFO(st.st_mode));
}

TEST_CASE("cli outputs: - writes an output to standard output") {
    TempDir td;
    const Result r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--collisions", "-", "-q"});
    CHECK(r.status == 0);
    CHECK_THAT(r.out, StartsWith("rbcd-collisions 1\nframe 0\nhit 0 0 1 2"));
    CHECK_FALSE(fs::exists(td.path("-")));
    CHECK_FALSE(fs::exists("-"));
}

TEST_CASE("cli outputs: --write-trace goes through an unpredictable temporary, never a planted symlink") {
    TempDir td;
    const std::string victim = td.write("victim.txt", "precious\n");
    const std::string out = td.out_dir() + "/w.rbt";
    const long p0 = next_pid_guess();
    for (long p = p0; p < p0 + 400; ++p) REQUIRE(::symlink(victim.c_str(), (out + ".tmp." + std::to_string(p)).c_str()) == 0);
    const Result r = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--write-trace", out, "-q"});
    CHECK(r.status == 0);
    CHECK(slurp(victim) == "precious\n");
    CHECK_THAT(slurp(out), StartsWith("rbcd-trace 1\n"));
    // and in place to standard output
    const Result s = run_sim(td, {"--trace", td.write("in.rbt", kGoodTrace), "--write-trace", "-", "-q"});
    CHECK(s.status == 0);
    CHECK_THAT(s.out, StartsWith("rbcd-trace 1\n"));
}

TEST_CASE("cli outputs: a failed run removes only the temporaries it created") {
    TempDir td;
    const std::string mine = td.write("out/unrelated.txt", "keep\n");
    const Result r = run_with_outputs(td, {"--trace", td.write("bad.rbt", kGoodTrace + "bogus\n")});
    CHECK(r.status == 2);
    CHECK(slurp(mine) == "keep\n");
    CHECK(td.out_entries() == std::vector<std::string>{"unrelated.txt"});
}

// ---------------------------------------------------------------- a large older collisions file at the output path

namespace {
// Two frames, so that --jobs 2 splits them.
const std::string kTwoFrames = "rbcd-trace 1\nframe 0\ntile 0 0\nf 0 0 100 1 F\nf 0 0 300 1 B\nf 0 0 200 2 F\n"
                               "frame 1\ntile 0 0\nf 1 0 100 3 F\nf 1 0 300 3 B\nf 1 0 200 4 F\n";
std::uint64_t inode_of(const std::string& path) {
    struct stat st {};
    REQUIRE(::stat(path.c_str(), &st) == 0);
    return static_cast<std::uint64_t>(st.st_ino);
}
// An older result of 2 MiB, as a rerun finds its previous collisions; its inode.
std::uint64_t plant_big(const std::string& path) {
    std::ofstream(path, std::ios::binary) << std::string(std::size_t(2) << 20, 'x');
    return inode_of(path);
}
} // namespace

TEST_CASE("cli outputs: a rerun over a larger older collisions file gives exactly a fresh run's bytes") {
    TempDir td;
    const std::string in = td.write("in.rbt", kTwoFrames);
    const std::string fresh = td.path("fresh.txt");
    REQUIRE(run_sim(td, {"--trace", in, "--collisions", fresh}).status == 0);
    const std::string want = slurp(fresh);
    REQUIRE(want.size() < 1000);
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        plant_big(td.collisions());
        const Result r = run_sim(td, {"--trace", in, "--collisions", td.collisions(), "--jobs", jobs});
        CHECK(r.status == 0);
        CHECK(slurp(td.collisions()) == want);
        CHECK(td.out_entries() == std::vector<std::string>{"collisions.txt"});
    }
}

// The older file's other names, and whoever still has it open, keep its bytes:
// it is unlinked, never written over.
TEST_CASE("cli outputs: an older collisions file with another link or still open keeps its bytes there") {
    TempDir td;
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        const std::uint64_t ino = plant_big(td.collisions());
        const std::string other = td.path("other-link.txt");
        fs::remove(other);
        REQUIRE(::link(td.collisions().c_str(), other.c_str()) == 0);
        std::ifstream open_reader(td.collisions(), std::ios::binary);
        const Result r = run_sim(td, {"--trace", td.write("in.rbt", kTwoFrames), "--collisions", td.collisions(), "--jobs", jobs});
        CHECK(r.status == 0);
        CHECK(inode_of(td.collisions()) != ino);
        CHECK(slurp(other) == std::string(std::size_t(2) << 20, 'x'));
        const std::string seen((std::istreambuf_iterator<char>(open_reader)), std::istreambuf_iterator<char>());
        CHECK(seen == std::string(std::size_t(2) << 20, 'x'));
        CHECK_THAT(slurp(td.collisions()), StartsWith("rbcd-collisions 1\n"));
    }
}

TEST_CASE("cli outputs: a failed run over a large older collisions file leaves neither it nor a temporary") {
    TempDir td;
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        plant_big(td.collisions());
        const Result r = run_sim(td, {"--trace", td.write("bad.rbt", kTwoFrames + "f 99 0 1 1 F\n"), "--collisions",
                                      td.collisions(), "--jobs", jobs});
        CHECK(r.status == 2);
        CHECK_THAT(r.err, Contains("bad.rbt:12:"));
        CHECK(td.out_entries().empty());
    }
}
