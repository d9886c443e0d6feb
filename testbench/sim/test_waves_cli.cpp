// FST waveforms (--fst, or --vcd NAME.fst) against the VCD of the same run:
// read back with fst2vcd (Debian's gtkwave), both must hold the same signals
// under the same scopes and the same value changes at the same times
// (docs/waveforms.md). Write failures leave nothing behind.
#include "cli_util.h"

#include <algorithm>
#include <map>
#include <tuple>

using namespace rbcd::cli_test;

namespace {

// A VCD as what it says: signal paths with widths, and every value change
// (time ps, path, value) in order; the first time stamp's values are changes
// from "unknown". Encodings differ (tabs, leading zeros, identifier codes,
// $dumpvars), meanings may not.
struct Waves {
    std::map<std::string, unsigned> vars;   // path -> width
    std::vector<std::tuple<std::uint64_t, std::string, std::uint64_t>> changes;   // time, path, value
    std::uint64_t last_time = 0;
};

Waves parse_vcd(const std::string& text) {
    Waves w;
    std::istringstream in(text);
    std::vector<std::string> scope;
    std::map<std::string, std::string> code_path;
    std::map<std::string, std::uint64_t> current;
    std::uint64_t now = 0;
    std::string tok;
    const auto change = [&](const std::string& code, std::uint64_t v) {
        const auto it = code_path.find(code);
        REQUIRE(it != code_path.end());
        const auto cur = current.find(it->second);
        if (cur != current.end() && cur->second == v) return;
        current[it->second] = v;
        w.changes.emplace_back(now, it->second, v);
    };
    while (in >> tok) {
        if (tok == "$scope") {
            std::string kind, name;
            in >> kind >> name;
            scope.push_back(name);
        } else if (tok == "$upscope") {
            scope.pop_back();
        } else if (tok == "$var") {
            std::string type, code, name;
            unsigned width = 0;
            in >> type >> width >> code >> name;
            std::string path;
            for (const auto& s : scope) path += s + ".";
            path += name;
            code_path[code] = path;
            w.vars[path] = width;
        } else if (tok == "$date" || tok == "$version" || tok == "$comment" || tok == "$timescale") {
            while (in >> tok && tok != "$end") {}
        } else if (tok[0] == '#') {
            now = std::stoull(tok.substr(1));
            w.last_time = now;
        } else if (tok[0] == 'b') {
            std::string code;
            in >> code;
            change(code, std::stoull(tok.substr(1), nullptr, 2));
        } else if (tok[0] == '0' || tok[0] == '1') {
            change(tok.substr(1), static_cast<std::uint64_t>(tok[0] - '0'));
        }
    }
    // Within a time stamp the order of changes carries no meaning.
    std::stable_sort(w.changes.begin(), w.changes.end());
    return w;
}

std::string show(const std::tuple<std::uint64_t, std::string, std::uint64_t>& c) {
    return std::to_string(std::get<0>(c)) + " " + std::get<1>(c) + " " + std::to_string(std::get<2>(c));
}

bool have_fst2vcd() { return std::system("command -v fst2vcd >/dev/null 2>&1") == 0; }

bool fst_built(const TempDir& td) {
    const Result r = run_sim(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--fst", td.path("probe.fst"), "-q"});
    return r.status == 0;
}

void compare_fst_with_vcd(const std::string& input_flag, const std::string& input, const std::vector<std::string>& sets) {
    TempDir td;
    if (!fst_built(td) || !have_fst2vcd()) {
        WARN("rbcd-sim built without FST or no fst2vcd (scripts/setup.sh --waves): skipped");
        return;
    }
    std::vector<std::string> base{input_flag, input, "-q"};
    for (const auto& s : sets) base.insert(base.end(), {"--set", s});
    auto with = [&](std::vector<std::string> extra) {
        std::vector<std::string> a = base;
        a.insert(a.end(), extra.begin(), extra.end());
        return a;
    };
    const std::string vcd = td.out_dir() + "/w.vcd", fst = td.out_dir() + "/w.fst";
    REQUIRE(run_sim(td, with({"--vcd", vcd})).status == 0);
    const Result rf = run_sim(td, with({"--fst", fst}));
    INFO(rf.err);
    REQUIRE(rf.status == 0);
    const std::string back = td.path("back.vcd");
    REQUIRE(std::system(("fst2vcd -f '" + fst + "' -o '" + back + "' >/dev/null 2>&1").c_str()) == 0);
    const Waves a = parse_vcd(slurp(vcd)), b = parse_vcd(slurp(back));
    REQUIRE(!a.vars.empty());
    CHECK(a.vars == b.vars);
    REQUIRE(!a.changes.empty());
    CHECK(a.changes.size() == b.changes.size());
    const std::size_t n = std::min(a.changes.size(), b.changes.size());
    std::size_t first_diff = n;
    for (std::size_t i = 0; i < n && first_diff == n; ++i)
        if (a.changes[i] != b.changes[i]) first_diff = i;
    INFO("first difference at change " << first_diff << ": VCD '" << (first_diff < n ? show(a.changes[first_diff]) : "")
                                       << "' FST '" << (first_diff < n ? show(b.changes[first_diff]) : "") << "'");
    CHECK(first_diff == n);
    CHECK(a.last_time == b.last_time);
    // The extension alone chooses FST.
    const std::string by_name = td.out_dir() + "/n.fst";
    REQUIRE(run_sim(td, with({"--vcd", by_name})).status == 0);
    CHECK(slurp(by_name).substr(0, 1) == std::string(1, '\0'));   // an FST header block, not VCD text
}

} // namespace

TEST_CASE("waves: FST equals the VCD of a window of vectors/default.rbt") {
    compare_fst_with_vcd("--trace", kVectors + "/default.rbt",
                         {"trace.start=100", "trace.end=400", "trace.memory=false"});
}

TEST_CASE("waves: FST equals the VCD of a whole run with every block") {
    compare_fst_with_vcd("--trace", kVectors + "/multi-frame-mixed.rbt", {"zeb.banks=3"});
}

TEST_CASE("waves: --fst with --vcd, or over a device, is one line and no file") {
    TempDir td;
    if (!fst_built(td)) {
        const Result r = run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--fst",
                                               td.out_dir() + "/w.fst"});
        expect_input_error(td, r, {"--fst", "without FST support", "verilator"});
        return;
    }
    const std::string fst = td.out_dir() + "/w.fst";
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--fst", fst,
                                                 "--vcd", td.out_dir() + "/w.vcd"}),
                       {"--fst", "--vcd"});
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--fst", "/dev/full"}),
                       {"/dev/full", "regular file"});
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--fst",
                                                 td.path("no/such/dir/w.fst")}),
                       {"no/such/dir/w.fst", "cannot create"});
}

TEST_CASE("waves: a full disk while writing the FST is one line and no file") {
    TempDir td;
    if (!fst_built(td)) {
        WARN("rbcd-sim built without FST: skipped");
        return;
    }
    // A file size limit stands for the full disk: writes past it fail (EFBIG)
    // once SIGXFSZ is ignored, as ENOSPC would.
    // vectors/default.rbt's FST is about 2 KiB.
    const std::string fst = td.out_dir() + "/w.fst";
    const std::string cmd = "ulimit -f 1; trap '' XFSZ; exec \"$0\" \"$@\"";
    const Result r = run_program(td, "/bin/sh", {"-c", cmd, RBCD_SIM, "--trace", kVectors + "/default.rbt", "-q",
                                                 "--fst", fst});
    expect_error(td, r, 1, {"w.fst", "write failed"});
}

TEST_CASE("waves: the GTKWave save file lists the run's signals by block in pipeline order") {
    TempDir td;
    const std::string vcd = td.out_dir() + "/run.vcd";
    const Result r = run_sim(td, {"--trace", kVectors + "/multi-frame-mixed.rbt", "--config",
                                  kVectors + "/multi-frame-mixed.toml", "--set", "zeb.banks=3", "--set",
                                  "trace.memory=false", "--vcd", vcd, "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    // Beside the waveform by default.
    const std::string gtkw = slurp(td.out_dir() + "/run.gtkw");
    CHECK(slurp(td.out_dir() + "/run.states.txt") == "0 free\n1 filling\n2 testing\n");
    CHECK_THAT(gtkw, Contains("[dumpfile] \"" + fs::absolute(vcd).string() + "\""));
    const Waves w = parse_vcd(slurp(vcd));
    // Every signal of the dump once, each named as GTKWave names it; groups open and close.
    std::vector<std::string> listed, groups;
    std::istringstream in(gtkw);
    std::string line, open_group;
    for (std::string prev; std::getline(in, line); prev = line) {
        if (line.rfind("rbcd.", 0) == 0) {
            listed.push_back(line);
            // Bank states are shown by name; counts in decimal, bits as bits.
            if (line.find(".state[") != std::string::npos) CHECK_THAT(prev, StartsWith("^"));
        } else if (line[0] == '-' && open_group.empty()) {
            open_group = line.substr(1);
            groups.push_back(open_group);
        } else if (line[0] == '-') {
            CHECK(line.substr(1) == open_group);
            open_group.clear();
        }
    }
    CHECK(open_group.empty());
    std::vector<std::string> expected;
    for (const auto& [path, width] : w.vars) expected.push_back(width > 1 ? path + "[" + std::to_string(width - 1) + ":0]" : path);
    std::vector<std::string> sorted = listed;
    std::sort(sorted.begin(), sorted.end());
    CHECK(sorted == expected);
    const std::vector<std::string> order{"rasterizer", "fragment_processors", "input_queue", "insertion_sorter",
                                         "zeb_bank0",  "zeb_bank1",           "zeb_bank2",   "zoverlap_tester",
                                         "output_buffer"};
    CHECK(groups == order);
    // A named marker per frame start (the vector has frames 0..2).
    CHECK_THAT(gtkw, Contains("[markername] Aframe 0\n") && Contains("[markername] Cframe 2\n"));
    CHECK_THAT(gtkw, !Contains("[markername] D"));
}

TEST_CASE("waves: --gtkw without a waveform, or to a bad path, is one line and no file") {
    TempDir td;
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--gtkw",
                                                 td.out_dir() + "/x.gtkw"}),
                       {"--gtkw", "waveform"});
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/rule-fig5-case2.rbt", "--vcd",
                                                 td.out_dir() + "/w.vcd", "--gtkw", td.path("no/such/x.gtkw")}),
                       {"no/such/x.gtkw", "cannot create"});
}
