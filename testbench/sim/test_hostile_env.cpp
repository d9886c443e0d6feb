// rbcd-sim in a hostile environment, one process and --jobs: a file-size
// limit, two outputs at one file, a standard-output name redirected to a
// file, an output named like a scene's mesh, an older --write-trace after an
// early failure, an unusable TMPDIR, a signal between two outputs' commits,
// a worker whose pipe reader went away, a stopped worker and a parent killed
// outright. Each found by a helper's run against the built program.
#include "rbcd/testbench/sim/cli_util.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

using namespace rbcd::cli_test;

namespace {

// A program run through bash, for what only a shell sets up (a limit, a
// redirection, a pipeline): `script` sees the simulator as $0 and `args` as $@.
Result run_shell(const TempDir& td, const std::string& script, const std::vector<std::string>& args) {
    std::vector<std::string> a{"-c", script, RBCD_SIM};
    a.insert(a.end(), args.begin(), args.end());
    return run_program(td, "/bin/bash", a);
}

std::vector<pid_t> children_of(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/task/" + std::to_string(pid) + "/children");
    std::vector<pid_t> v;
    for (pid_t c; in >> c;) v.push_back(c);
    return v;
}

// Gone: reaped, or a zombie nobody reaps (a container's first process may not).
bool process_gone(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string line;
    if (!std::getline(in, line)) return true;
    const auto close = line.rfind(')');
    return close != std::string::npos && close + 2 < line.size() && line[close + 2] == 'Z';
}

// A busy trace of 200,000 fragments in 4 frames (116 KB of collisions): a
// --jobs run's first worker writes its collisions straight into a pipe.
std::string busy_trace(const TempDir& td) {
    const std::string t = td.path("busy.rbt");
    const Result g = run_program(td, RBCD_GEN_BUSY_TRACE, {t, "200000", "4"});
    INFO(g.err);
    REQUIRE(g.status == 0);
    return t;
}

template <class Pred>
bool within_seconds(int seconds, Pred pred) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    while (!pred()) {
        if (std::chrono::steady_clock::now() > end) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
}

// A worker of a --jobs 2 run, stopped (SIGSTOP) once set up (its standard
// error is its error file, opened after it asked to die with its parent), so
// that the run cannot end by itself; its pid, or 0 when the run ended before
// a worker could be caught.
pid_t stop_a_worker(pid_t parent) {
    pid_t worker = 0;
    const auto set_up = [](pid_t kid) {
        std::error_code ec;
        const auto err = std::filesystem::read_symlink("/proc/" + std::to_string(kid) + "/fd/2", ec);
        const std::string s = ec ? std::string() : err.string();
        return s.size() > 4 && s.compare(s.size() - 4, 4, ".err") == 0;
    };
    within_seconds(60, [&] {
        for (const pid_t kid : children_of(parent))
            if (set_up(kid)) worker = kid;
        return worker != 0 || process_gone(parent);
    });
    if (worker) ::kill(worker, SIGSTOP);
    return worker;
}

} // namespace

TEST_CASE("hostile env: a file-size limit fails the write with one line and leaves nothing", "[hostile_env]") {
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        TempDir td;
        td.plant_old_outputs();
        const Result r = run_shell(td, "ulimit -f 20; exec \"$0\" \"$@\"",
                                   {"-q", "--jobs", jobs, "--collisions", td.collisions(), "--stats", td.stats()});
        expect_error(td, r, 1, {td.collisions(), "write failed: File too large"});
        CHECK(td.out_entries().empty());
    }
    TempDir td;
    const std::string trace = td.out_dir() + "/w.rbt";
    const Result w = run_shell(td, "ulimit -f 20; exec \"$0\" \"$@\"", {"-q", "--write-trace", trace});
    expect_error(td, w, 1, {trace + ": write failed: File too large"});
    CHECK(td.out_entries().empty());
}

TEST_CASE("hostile env: two outputs at one file are refused before either is opened", "[hostile_env]") {
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        TempDir td;
        const std::string same = td.collisions();
        expect_input_error(td, run_sim(td, {"-q", "--jobs", jobs, "--collisions", same, "--stats", same}),
                           {"--stats: " + same + " is also --collisions's output"});
        const std::string dotted = td.out_dir() + "/./stats.json";
        expect_input_error(td, run_sim(td, {"-q", "--jobs", jobs, "--stats", td.stats(), "--frame-stats", dotted}),
                           {"--frame-stats: " + dotted + " is also --stats's output"});
    }
    TempDir td;
    // Both names are the shell's file here, not a terminal or a pipe.
    const std::string file = td.path("both.txt");
    const Result s = run_shell(td, "exec \"$0\" \"$@\" > " + file, {"-q", "--collisions", "/dev/stdout", "--stats", "/dev/stdout"});
    CHECK(s.status == 2);
    CHECK_THAT(s.err, Contains("--stats: /dev/stdout is also --collisions's output"));
}

TEST_CASE("hostile env: --collisions /dev/stdout redirected to a file is what --collisions - writes", "[hostile_env]") {
    TempDir td;
    const std::string trace = busy_trace(td);   // the first worker writes into it too
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        const std::string named = td.path("named.txt"), dash = td.path("dash.txt");
        const Result a =
            run_shell(td, "exec \"$0\" \"$@\" > " + named, {"--trace", trace, "--jobs", jobs, "--collisions", "/dev/stdout"});
        const Result b = run_shell(td, "exec \"$0\" \"$@\" > " + dash, {"--trace", trace, "--jobs", jobs, "--collisions", "-"});
        REQUIRE(a.status == 0);
        REQUIRE(b.status == 0);
        const std::string got = slurp(named);
        CHECK(got.rfind("rbcd-collisions 1\n", 0) == 0);   // the summary follows, not over, the records
        CHECK(got == slurp(dash));
    }
}

TEST_CASE("hostile env: an output named like a scene's mesh file is refused and the mesh kept", "[hostile_env]") {
    TempDir td;
    const std::string mesh_text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    const std::string mesh = td.write("tet.obj", mesh_text);
    const std::string scene =
        td.write("s.toml", "format = \"rbcd-scene 1\"\nframes = 4\n[screen]\nwidth = 64\nheight = 48\n"
                           "[camera]\neye = [0.0, 0.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 45.0\nnear = 0.5\n"
                           "far = 50.0\n[[object]]\nid = 1\nmesh = \"tet.obj\"\n[[object]]\nid = 2\nmesh = "
                           "\"sphere\"\nposition = [0.3, 0.0, 0.0]\n");
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        const Result r = run_sim(td, {"-q", "--scene", scene, "--jobs", jobs, "--stats", mesh});
        CHECK(r.status == 2);
        CHECK_THAT(r.err, Contains("--stats: " + mesh + " is the input file"));
        CHECK(slurp(mesh) == mesh_text);
    }
    // Nor by a run that fails before it reads the scene, or on the scene.
    const std::string bad = td.write("bad.toml", slurp(scene) + "bogus = 1\n");
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"--scene", scene, "--set", "zeb.banks=foo"},
          std::vector<std::string>{"--scene", scene, "--no-such-option"}, std::vector<std::string>{"--scene", bad}}) {
        auto a = args;
        a.insert(a.end(), {"-q", "--stats", mesh});
        const Result r = run_sim(td, a);
        INFO(r.cmd << "\n" << r.err);
        CHECK(r.status == 2);
        CHECK(slurp(mesh) == mesh_text);
    }
}

TEST_CASE("hostile env: an older --write-trace file goes on an early failure too", "[hostile_env]") {
    TempDir td;
    const std::string trace = td.out_dir() + "/w.rbt";
    std::ofstream(trace) << "an older trace\n";
    td.plant_old_outputs();
    const Result r = run_with_outputs(td, {"--set", "zeb.banks=foo", "--write-trace", trace}, false);
    expect_input_error(td, r, {"zeb.banks"});
    CHECK_FALSE(std::filesystem::exists(trace));
}

TEST_CASE("hostile env: --jobs with an empty TMPDIR uses /tmp, with an unusable one says so", "[hostile_env]") {
    TempDir td;
    const Result ok = run_shell(td, "TMPDIR= exec \"$0\" \"$@\"", {"-q", "--jobs", "2", "--collisions", "/dev/null"});
    INFO(ok.err);
    CHECK(ok.status == 0);
    const std::string missing = td.path("no such dir");
    const Result bad =
        run_shell(td, "TMPDIR=\"$1\" exec \"$0\" \"${@:2}\"", {missing, "-q", "--jobs", "2", "--collisions", "/dev/null"});
    expect_error(td, bad, 1, {"--jobs: cannot create the workers' directory in " + missing});
}

TEST_CASE("hostile env: a signal between two outputs' commits leaves none of them", "[hostile_env]") {
    // The stats go into a FIFO whose 4 KiB buffer nobody empties: the run
    // blocks writing them after the collisions and per-frame stats stand.
    for (const char* jobs : {"1", "2"}) {
        INFO("--jobs " << jobs);
        TempDir td;
        const std::string fifo = td.out_dir() + "/stats.fifo", frames = td.out_dir() + "/frames.jsonl";
        REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
        const int rd = ::open(fifo.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
        REQUIRE(rd >= 0);
        (void)::fcntl(rd, F_SETPIPE_SZ, 4096);
        const pid_t pid = spawn_program({RBCD_SIM, "-q", "--jobs", jobs, "--collisions", td.collisions(),
                                         "--frame-stats", frames, "--stats", fifo});
        const bool stood = within_seconds(120, [&] { return std::filesystem::exists(td.collisions()); });
        CHECK(stood);
        std::this_thread::sleep_for(std::chrono::milliseconds(50));   // on to the stats
        REQUIRE(::kill(pid, SIGTERM) == 0);
        int st = 0;
        REQUIRE(::waitpid(pid, &st, 0) == pid);
        ::close(rd);
        CHECK(WIFEXITED(st));
        CHECK(WEXITSTATUS(st) == 128 + SIGTERM);
        CHECK_FALSE(std::filesystem::exists(td.collisions()));
        CHECK_FALSE(std::filesystem::exists(frames));
    }
}

TEST_CASE("hostile env: a worker's pipe reader gone ends the run as one process ends", "[hostile_env]") {
    // A trace's first worker writes its collisions into the pipe itself, and
    // meets the closed end first.
    TempDir td;
    const std::string trace = busy_trace(td);
    for (const char* jobs : {"1", "2", "3"}) {
        INFO("--jobs " << jobs);
        const Result r = run_shell(td, "set -o pipefail; \"$0\" \"$@\" | head -c 100 > /dev/null",
                                   {"-q", "--trace", trace, "--jobs", jobs, "--collisions", "-", "--stats", td.stats()});
        CHECK(r.status == 128 + SIGPIPE);
        CHECK(r.err.empty());
        CHECK(td.out_entries().empty());
    }
}

TEST_CASE("hostile env: a stopped worker does not keep an interrupted run from ending", "[hostile_env]") {
    TempDir td;
    const pid_t pid = spawn_program({RBCD_SIM, "-q", "--jobs", "2", "--collisions", td.collisions(), "--stats", td.stats()});
    const pid_t worker = stop_a_worker(pid);
    if (!worker) {
        ::waitpid(pid, nullptr, 0);
        WARN("skipped: the run ended before a worker could be stopped");
        return;
    }
    REQUIRE(::kill(pid, SIGTERM) == 0);
    const bool ended = within_seconds(60, [&] {
        int st = 0;
        return ::waitpid(pid, &st, WNOHANG) == pid;
    });
    if (!ended) {
        ::kill(worker, SIGKILL);
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
    }
    CHECK(ended);
    CHECK(td.out_entries().empty());
}

TEST_CASE("hostile env: workers end with a parent killed outright", "[hostile_env]") {
    TempDir td;
    const pid_t pid = spawn_program({RBCD_SIM, "-q", "--jobs", "2", "--collisions", td.collisions(), "--stats", td.stats()});
    const pid_t worker = stop_a_worker(pid);
    REQUIRE(::kill(pid, SIGKILL) == 0);
    REQUIRE(::waitpid(pid, nullptr, 0) == pid);
    if (!worker) {
        WARN("the run ended before a worker could be stopped");
        return;
    }
    const bool gone = within_seconds(60, [&] { return process_gone(worker); });
    if (!gone) ::kill(worker, SIGKILL);
    CHECK(gone);
}

TEST_CASE("hostile env: a worker whose file system fills up still says so", "[hostile_env]") {
    // A small tmpfs in a mount namespace of the test's own (it goes with the
    // namespace), holding the collisions and so the workers' parts: a worker
    // fails for the space, and its error file had room reserved for its line.
    TempDir td;
    const std::string mnt = td.path("small");
    std::filesystem::create_directory(mnt);
    const Result probe = run_program(td, "/usr/bin/unshare", {"-m", "/bin/sh", "-c", "mount -t tmpfs -o size=256k tmpfs \"$0\"", mnt});
    if (probe.status != 0) {
        WARN("skipped: no mount namespace with a tmpfs here (needs root and unshare): " << probe.err);
        return;
    }
    for (int run = 0; run < 4; ++run) {
        const Result r = run_program(
            td, "/usr/bin/unshare",
            {"-m", "/bin/sh", "-c",
             "mount -t tmpfs -o size=256k tmpfs \"$1\" && \"$0\" -q --jobs 2 --collisions \"$1/c.txt\"; s=$?; "
             "ls -A \"$1\"; exit $s",
             RBCD_SIM, mnt});
        INFO(r.err);
        CHECK(r.status == 1);
        CHECK_THAT(r.err, Contains("write failed: No space left on device"));
        CHECK(count_lines(r.err) == 1);
        CHECK(r.out.empty());   // nothing left on the small file system
    }
}

TEST_CASE("hostile env: --write-trace to a redirected standard output keeps the file's offset", "[hostile_env]") {
    TempDir td;
    const std::string scene =
        td.write("s.toml", "format = \"rbcd-scene 1\"\nframes = 3\n[screen]\nwidth = 64\nheight = 48\n[camera]\n"
                           "eye = [0.0, 0.0, 6.0]\ntarget = [0.0, 0.0, 0.0]\nfov_y = 45.0\nnear = 0.5\nfar = 50.0\n"
                           "[[object]]\nid = 1\nmesh = \"sphere\"\n[[object]]\nid = 2\nmesh = \"sphere\"\n"
                           "position = [0.3, 0.0, 0.0]\n");
    const std::string ref = td.path("ref.rbt");
    REQUIRE(run_sim(td, {"-q", "--scene", scene, "--write-trace", ref}).status == 0);
    const std::string trace = slurp(ref);
    for (const char* name : {"/dev/stdout", "-"}) {
        INFO(name);
        // The summary follows the trace instead of overwriting its start.
        const std::string out = td.path("out.rbt");
        REQUIRE(run_shell(td, "exec \"$0\" \"$@\" > " + out, {"--scene", scene, "--write-trace", name}).status == 0);
        const std::string got = slurp(out);
        CHECK(got.substr(0, trace.size()) == trace);
        CHECK(got.size() > trace.size());
        // Appended to, not truncated.
        const std::string log = td.path("log.txt");
        std::ofstream(log) << "an earlier line\n";
        REQUIRE(run_shell(td, "exec \"$0\" \"$@\" >> " + log, {"-q", "--scene", scene, "--write-trace", name}).status == 0);
        CHECK(slurp(log) == "an earlier line\n" + trace);
    }
}
