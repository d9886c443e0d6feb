// rbcd-cpucd under hostile input: outputs written as rbcd-sim
// writes them (common/output_file.h), geometry files read as rbcd-sim reads
// its inputs (regular files, line and size limits, magnitudes bounded as in
// scenes, rigid-plus-scale matrices), work bounded in the input, one-line
// escaped messages. Each case failed on the code before.
#define RBCD_SIM RBCD_CPUCD
#include "rbcd/testbench/sim/cli_util.h"

#include <sys/stat.h>

#include <chrono>
#include <regex>

using namespace rbcd::cli_test;

namespace {

// A unit cube (12 triangles) as a part of a geometry file.
std::string cube_part(unsigned id) {
    std::string s = "part " + std::to_string(id) + " 8 12\n";
    for (int i = 0; i < 8; ++i)
        s += "v " + std::to_string(i & 1) + " " + std::to_string((i >> 1) & 1) + " " + std::to_string((i >> 2) & 1) + "\n";
    const char* tris[] = {"0 2 1", "1 2 3", "4 5 6", "5 7 6", "0 1 4", "1 5 4",
                          "2 6 3", "3 6 7", "0 4 2", "2 4 6", "1 3 5", "3 7 5"};
    for (const char* t : tris) s += std::string("t ") + t + "\n";
    return s;
}

// Two cubes; the second's matrix line (12 numbers) as given.
std::string two_cubes(const std::string& second_matrix) {
    return "rbcd-geometry 1\n" + cube_part(1) + cube_part(2) + "frame 0\nm 0 1 0 0 0 0 1 0 0 0 0 1 0\nm 1 " +
           second_matrix + "\n";
}

const std::string kIdentity = "1 0 0 0 0 1 0 0 0 0 1 0";

Result cpucd(const TempDir& td, std::vector<std::string> args) {
    args.insert(args.begin(), {"-q", "--repeat", "1"});
    return run_program(td, RBCD_CPUCD, args);
}

// One line, exit 2, holding every needle.
void expect_refused(const Result& r, const std::vector<std::string>& needles) {
    INFO("command: " << r.cmd);
    INFO("stderr: " << r.err);
    CHECK(r.status == 2);
    CHECK(count_lines(r.err) == 1);
    for (const auto& n : needles) CHECK_THAT(r.err, Contains(n));
}

} // namespace

TEST_CASE("rbcd-cpucd: an output naming the input is refused and the input kept", "[cpucd_cli]") {
    TempDir td;
    const std::string geo = td.write("in.geo", two_cubes(kIdentity));
    const std::string before = slurp(geo);
    for (const char* flag : {"--write-geometry", "--pairs", "--frames"}) {
        expect_refused(cpucd(td, {"--geometry", geo, flag, geo}), {flag, "is the input file"});
        CHECK(slurp(geo) == before);
    }
    // Two outputs into one file: one would be lost with exit 0.
    expect_refused(cpucd(td, {"--geometry", geo, "--pairs", td.collisions(), "--frames", td.collisions()}),
                   {"--frames", "is also --pairs's output"});
    CHECK(td.out_entries().empty());
}

TEST_CASE("rbcd-cpucd: a failed run leaves a FIFO at an output path in place", "[cpucd_cli]") {
    TempDir td;
    const std::string fifo = td.out_dir() + "/pairs.fifo";
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    // A reader holds the FIFO open, so that the run's open for writing returns.
    const int reader = ::open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    REQUIRE(reader >= 0);
    const std::string bad = td.write("bad.geo", "rbcd-geometry 1\nbogus\n");
    // Written in place, never unlinked, also when the run fails: whatever
    // stands at an output path is not removed first.
    expect_refused(cpucd(td, {"--geometry", bad, "--frames", fifo}), {"bad.geo:2"});
    ::close(reader);
    struct stat st {};
    REQUIRE(::lstat(fifo.c_str(), &st) == 0);
    CHECK(S_ISFIFO(st.st_mode));
}

TEST_CASE("rbcd-cpucd: outputs go through unpredictable temporaries", "[cpucd_cli]") {
    TempDir td;
    const std::string geo = td.write("in.geo", two_cubes(kIdentity));
    // A symlink planted at a predictable temporary name (PATH.tmp.PID for
    // any PID): never followed, so its target is untouched.
    const std::string target = td.write("target.txt", "not to be overwritten\n");
    const std::string out = td.out_dir() + "/pairs.csv";
    for (int pid = 1; pid < 4; ++pid) fs::create_symlink(target, out + ".tmp." + std::to_string(pid));
    const Result r = cpucd(td, {"--geometry", geo, "--pairs", out});
    INFO(r.err);
    REQUIRE(r.status == 0);
    CHECK(slurp(target) == "not to be overwritten\n");
    CHECK_THAT(slurp(out), StartsWith("frame,id_a,id_b"));
    for (const auto& e : td.out_entries()) CHECK((e == "pairs.csv" || e.rfind("pairs.csv.tmp.", 0) == 0));

    // While a run writes, its temporary is mkstemp's hidden .pairs.csv.XXXXXX,
    // not a predictable PATH.tmp.PID anyone could plant a symlink at.
    std::string s2 = "rbcd-geometry 1\n" + cube_part(1) + cube_part(2);
    for (int f = 0; f < 2000; ++f) s2 += "frame " + std::to_string(f) + "\nm 0 " + kIdentity + "\nm 1 " + kIdentity + "\n";
    const std::string long_geo = td.write("long.geo", s2);
    const std::string out2 = td.out_dir() + "/second.csv";
    const pid_t pid = spawn_program({RBCD_CPUCD, "-q", "--repeat", "1000", "--geometry", long_geo, "--pairs", out2});
    std::string temp;
    for (int i = 0; i < 200 && temp.empty(); ++i) {
        for (const auto& e : td.out_entries())
            if (e != "pairs.csv" && e.rfind("pairs.csv.tmp.", 0) != 0) temp = e;
        if (temp.empty()) ::usleep(20000);
    }
    ::kill(pid, SIGTERM);
    int st = 0;
    REQUIRE(::waitpid(pid, &st, 0) == pid);
    INFO("temporary: " << temp);
    CHECK(std::regex_match(temp, std::regex(R"(\.second\.csv\.[A-Za-z0-9]{6})")));
}

TEST_CASE("rbcd-cpucd: a sheared or out-of-range model matrix is refused", "[cpucd_cli]") {
    TempDir td;
    // Shear: column 1 leans into x. The old reader refused only a singular matrix.
    expect_refused(cpucd(td, {"--geometry", td.write("shear.geo", two_cubes("1 0.5 0 0.5 0 1 0 0 0 0 1 0"))}),
                   {"shear.geo:", "not orthogonal", "no shear"});
    // Magnitudes past the scene reader's 1e9.
    expect_refused(cpucd(td, {"--geometry", td.write("far.geo", two_cubes("1 0 0 1e308 0 1 0 0 0 0 1 0"))}),
                   {"far.geo:", "beyond +-1e9"});
    expect_refused(cpucd(td, {"--geometry", td.write("big.geo", two_cubes("1e300 0 0 0 0 1e300 0 0 0 0 1e300 0"))}),
                   {"big.geo:", "beyond +-1e9"});
    // A rotation with scale passes.
    const Result ok = cpucd(td, {"--geometry", td.write("ok.geo", two_cubes("0 -2 0 0.5 2 0 0 0 0 0 2 0"))});
    INFO(ok.err);
    CHECK(ok.status == 0);
}

TEST_CASE("rbcd-cpucd: a geometry file must be a regular file within its limits", "[cpucd_cli]") {
    TempDir td;
    const std::string fifo = td.path("geo.fifo");
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    expect_refused(cpucd(td, {"--geometry", fifo}), {"cannot read geometry file: is a FIFO, not a regular file"});
    expect_refused(cpucd(td, {"--geometry", "/dev/zero"}), {"/dev/zero: cannot read geometry file: is a character device"});
    expect_refused(cpucd(td, {"--geometry", td.path("missing.geo")}),
                   {"missing.geo: cannot read geometry file: No such file or directory"});
    const std::string long_line = td.write("long.geo", "rbcd-geometry 1\n# " + std::string(5000, 'x') + "\n");
    expect_refused(cpucd(td, {"--geometry", long_line}), {"long.geo:2: line longer than 4096 bytes"});
    const std::string geo = td.write("in.geo", two_cubes(kIdentity));
    expect_refused(cpucd(td, {"--geometry", geo, "--max-geometry-bytes", "100"}),
                   {"larger than 100 bytes", "--max-geometry-bytes"});
}

TEST_CASE("rbcd-cpucd: work is bounded: co-located parts and --repeat", "[cpucd_cli]") {
    TempDir td;
    // 800 co-located cubes: 319,600 pairs whose boxes overlap; refused at
    // the limit before Bullet or FCL sees them, in well under a second.
    std::string s = "rbcd-geometry 1\n";
    for (unsigned i = 0; i < 800; ++i) s += cube_part(i + 1);
    s += "frame 0\n";
    for (unsigned i = 0; i < 800; ++i) s += "m " + std::to_string(i) + " " + kIdentity + "\n";
    const std::string geo = td.write("crowd.geo", s);
    const auto t0 = std::chrono::steady_clock::now();
    expect_refused(cpucd(td, {"--geometry", geo, "--max-pairs", "1000"}),
                   {"crowd.geo: frame 0: more than 1000 pairs", "--max-pairs"});
    CHECK(std::chrono::steady_clock::now() - t0 < std::chrono::seconds(20));
    expect_refused(run_program(td, RBCD_CPUCD, {"-q", "--geometry", td.write("in.geo", two_cubes(kIdentity)), "--repeat", "4294967295"}),
                   {"--repeat", "1..1000"});
}

TEST_CASE("rbcd-cpucd: messages are one line, escaped, long tokens cut", "[cpucd_cli]") {
    TempDir td;
    const Result esc = cpucd(td, {"--geometry", td.write("esc.geo", "rbcd-geometry 1\n\x1b[31mred\xff\n")});
    expect_refused(esc, {"esc.geo:2: unknown record", "\\x1b[31mred\\xff"});
    CHECK(esc.err.find('\x1b') == std::string::npos);
    const Result nl = cpucd(td, {"--geometry", td.write("new\nline.geo", "rbcd-geometry 3\n")});
    expect_refused(nl, {"new\\x0aline.geo:1"});
    const Result big = cpucd(td, {"--geometry", td.write("tok.geo", "rbcd-geometry 1\n" + std::string(4000, 'a') + "\n")});
    expect_refused(big, {"tok.geo:2: unknown record 'aaaa", "...' (4000 bytes)"});
    CHECK(big.err.size() < 300);
}

TEST_CASE("rbcd-cpucd: SIGTERM during a run leaves nothing at the output paths", "[cpucd_cli]") {
    TempDir td;
    // Many frames and repeats: the run is still going when the signal comes.
    std::string s = "rbcd-geometry 1\n" + cube_part(1) + cube_part(2);
    for (int f = 0; f < 2000; ++f) s += "frame " + std::to_string(f) + "\nm 0 " + kIdentity + "\nm 1 " + kIdentity + "\n";
    const std::string geo = td.write("long.geo", s);
    const std::string pairs = td.out_dir() + "/pairs.csv";
    const pid_t pid = spawn_program({RBCD_CPUCD, "-q", "--repeat", "1000", "--geometry", geo, "--pairs", pairs});
    // Until its temporary exists (the output is open), then stop it.
    for (int i = 0; i < 200 && td.out_entries().empty(); ++i) ::usleep(20000);
    REQUIRE_FALSE(td.out_entries().empty());
    ::usleep(100000);
    ::kill(pid, SIGTERM);
    int st = 0;
    REQUIRE(::waitpid(pid, &st, 0) == pid);
    CHECK((WIFEXITED(st) && WEXITSTATUS(st) == 128 + SIGTERM));
    std::string left;
    for (const auto& e : td.out_entries()) left += e + " ";
    INFO("left: " << left);
    CHECK(td.out_entries().empty());
}
