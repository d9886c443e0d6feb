// rbcd-merge: the outputs of rbcd-sim runs over consecutive frame ranges
// (--frames A:B) turned into the outputs of one run over all their frames,
// byte for byte (docs/sweeps.md, "One long input across workers"):
//
//   rbcd-sim --trace t.rbt --frames 0:99    --stats a.json --collisions a.txt
//   rbcd-sim --trace t.rbt --frames 100:199 --stats b.json --collisions b.txt
//   rbcd-merge --stats all.json --collisions all.txt a.json b.json
//
// Every frame starts on a drained unit with its memory latency reseeded
// (docs/timing.md), so a frame's results do not depend on the frames before
// it; what is left is arithmetic on the parts' stats (report/run_snapshot.h).
// The parts' collision and per-frame files are found where each part's
// provenance says it wrote them.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <systemc>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/report/run_snapshot.h"
#include "rbcd/report/stats_report.h"
#include "rbcd/sc_main/output_file.h"
#include "rbcd/sc_main/provenance.h"

namespace {

using rbcd::InputError;

// The kernel prints its banner before sc_main runs, unless told not to.
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();

// A stats document is a page of JSON; this keeps a hostile one from filling memory.
constexpr std::uint64_t kMaxStatsBytes = std::uint64_t(64) << 20;

struct Part {
    std::string path;
    nlohmann::json stats;
    rbcd::RunSnapshot snapshot;
};

nlohmann::json read_json(const std::string& path) {
    const std::string text = rbcd::read_input_text(path, "stats file", kMaxStatsBytes, "");
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(path + ": not JSON: " + e.what());
    }
}

const nlohmann::json& provenance_of(const Part& p) {
    if (!p.stats.contains("provenance") || !p.stats["provenance"].is_object())
        throw InputError(p.path + ": stats: provenance: missing");
    return p.stats["provenance"];
}

std::vector<std::string> argv_of(const Part& p) {
    const nlohmann::json& pv = provenance_of(p);
    if (!pv.contains("argv") || !pv["argv"].is_array()) throw InputError(p.path + ": stats: provenance.argv: missing");
    std::vector<std::string> argv;
    for (const auto& a : pv["argv"]) {
        if (!a.is_string()) throw InputError(p.path + ": stats: provenance.argv: not strings");
        argv.push_back(a.get<std::string>());
    }
    return argv;
}

// Where a part wrote OPTION's file: its recorded path, from its working directory.
std::string part_output(const Part& p, const std::string& option) {
    const auto values = rbcd::option_values(argv_of(p), {option.c_str()});
    const std::string v = values.empty() ? std::string() : values.front();
    if (v.empty() || v == "-") throw InputError(p.path + ": the run wrote no " + option + " file");
    const nlohmann::json& wd = provenance_of(p)["working_directory"];
    std::filesystem::path f(v);
    if (f.is_relative() && wd.is_string()) f = std::filesystem::path(wd.get<std::string>()) / f;
    return f.string();
}

// The command line one run over all the frames would have had: the first
// part's, without --frames, its outputs the merged ones, and without the
// outputs that are not merged (--vcd, --images, --write-trace).
std::vector<std::string> whole_run_argv(const std::vector<std::string>& argv,
                                        const std::vector<std::pair<std::string, std::string>>& outputs) {
    const std::vector<std::string> dropped = {"--frames", "--vcd", "--images", "--write-trace"};
    std::vector<std::string> out;
    if (!argv.empty()) out.push_back(argv[0]);
    for (std::size_t i = 1; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        bool handled = false;
        auto rewrite = [&](const std::string& opt, const std::string* value) {
            const bool spaced = a == opt, joined = a.rfind(opt + "=", 0) == 0;
            if (!spaced && !joined) return;
            handled = true;
            if (spaced) ++i;
            if (!value) return;
            if (spaced) {
                out.push_back(opt);
                out.push_back(*value);
            } else {
                out.push_back(opt + "=" + *value);
            }
        };
        for (const auto& d : dropped) rewrite(d, nullptr);
        for (const auto& [opt, value] : outputs) {
            if (handled) break;
            rewrite(opt, value.empty() ? nullptr : &value);
        }
        if (!handled) out.push_back(a);
    }
    return out;
}

void copy_collisions(const std::vector<Part>& parts, rbcd::OutputFile& out) {
    static const std::string magic = "rbcd-collisions 1";
    bool first = true;
    for (const auto& p : parts) {
        const std::string path = part_output(p, "--collisions");
        std::ifstream in(path, std::ios::binary);
        if (!in) throw InputError(path + ": cannot read");
        std::string head;
        if (!std::getline(in, head) || head != magic) throw InputError(path + ":1: not a collisions file");
        if (first) out.write(head + "\n");
        first = false;
        char buf[1 << 16];
        while (in.read(buf, sizeof buf) || in.gcount() > 0) out.write(buf, std::size_t(in.gcount()));
        if (in.bad()) throw InputError(path + ": read error");
    }
}

// The parts' per-frame lines, their cycles counted from the whole run's start.
void copy_frame_stats(const std::vector<Part>& parts, rbcd::OutputFile& out) {
    std::uint64_t offset = 0;
    for (const auto& p : parts) {
        const std::string path = part_output(p, "--frame-stats");
        std::ifstream in(path, std::ios::binary);
        if (!in) throw InputError(path + ": cannot read");
        std::string line;
        for (std::uint64_t n = 1; std::getline(in, line); ++n) {
            nlohmann::json f;
            try {
                f = nlohmann::json::parse(line);
            } catch (const nlohmann::json::parse_error&) {
                throw InputError(path + ":" + std::to_string(n) + ": not a JSON object");
            }
            for (const char* key : {"start_cycle", "end_cycle"}) {
                if (!f.is_object() || !f.contains(key) || !f[key].is_number_unsigned())
                    throw InputError(path + ":" + std::to_string(n) + ": " + key + ": missing");
                f[key] = f[key].get<std::uint64_t>() + offset;
            }
            out.write(f.dump() + "\n");
        }
        if (in.bad()) throw InputError(path + ": read error");
        offset += p.snapshot.cycles;
    }
}

struct Options {
    std::string stats, collisions, frame_stats;
    std::vector<std::string> parts;
};

int run(const Options& opt) {
    std::vector<Part> parts;
    for (const auto& path : opt.parts) {
        Part p;
        p.path = path;
        p.stats = read_json(path);
        try {
            p.snapshot = rbcd::snapshot_from_stats(p.stats);
        } catch (const InputError& e) {
            throw InputError(path + ": " + e.what());
        }
        parts.push_back(std::move(p));
    }

    rbcd::RunSnapshot all = parts.front().snapshot;
    double wall = 0;
    for (std::size_t i = 0; i < parts.size(); ++i) {
        if (i > 0) {
            try {
                rbcd::merge_snapshots(all, parts[i].snapshot);
            } catch (const InputError& e) {
                throw InputError(parts[i].path + ": " + e.what());
            }
        }
        const nlohmann::json& t = parts[i].stats["time"];
        if (t.is_object() && t.contains("wall_seconds") && t["wall_seconds"].is_number())
            wall += t["wall_seconds"].get<double>();
    }
    // One program, one configuration, the same inputs: else not one run.
    const nlohmann::json& pv0 = provenance_of(parts.front());
    for (const auto& p : parts)
        for (const char* key : {"build", "config_sha256", "inputs"})
            if (provenance_of(p).value(key, nlohmann::json()) != pv0.value(key, nlohmann::json()))
                throw InputError(p.path + ": stats: provenance." + key + ": differs from " + parts.front().path + "'s");

    nlohmann::json stats = rbcd::make_stats(all, wall);
    nlohmann::json pv = pv0;
    const std::vector<std::string> argv = whole_run_argv(
        argv_of(parts.front()),
        {{"--stats", opt.stats}, {"--collisions", opt.collisions}, {"--frame-stats", opt.frame_stats}});
    pv["argv"] = argv;
    pv["command_line"] = rbcd::command_line(argv);
    stats["provenance"] = pv;

    rbcd::OutputFile stats_out(opt.stats), collisions_out, frames_out;
    if (!opt.collisions.empty()) {
        collisions_out = rbcd::OutputFile(opt.collisions);
        copy_collisions(parts, collisions_out);
    }
    if (!opt.frame_stats.empty()) {
        frames_out = rbcd::OutputFile(opt.frame_stats);
        copy_frame_stats(parts, frames_out);
    }
    stats_out.write(stats.dump(2) + "\n");
    if (collisions_out.active()) collisions_out.commit();
    if (frames_out.active()) frames_out.commit();
    stats_out.commit();
    return 0;
}

// As rbcd-sim: on a non-zero exit nothing stands at an output path, not even
// an older file, unless the path names one of the inputs.
int fail(int status, const std::string& msg, const Options& opt) {
    std::fprintf(stderr, "rbcd-merge: %s\n", rbcd::escape_for_message(msg).c_str());
    rbcd::discard_outputs({opt.stats, opt.collisions, opt.frame_stats}, opt.parts);
    return status;
}

} // namespace

// A SystemC program only because the report library it shares with rbcd-sim
// links the kernel; no module is elaborated.
int sc_main(int argc, char* argv[]) {
    Options opt;
    CLI::App app{"rbcd-merge: the outputs of rbcd-sim runs over consecutive frame ranges (--frames) as those of one "
                 "run over all their frames (docs/sweeps.md)"};
    app.add_option("--stats", opt.stats, "write the merged statistics JSON here")->required();
    app.add_option("--collisions", opt.collisions,
                   "also merge the parts' collision files (where their provenance says they are) into this one");
    app.add_option("--frame-stats", opt.frame_stats, "also merge the parts' --frame-stats files into this one");
    app.add_option("parts", opt.parts, "the parts' stats JSON files, in frame order")->required();
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);
        return fail(2, std::string(e.what()) + " (see --help)", opt);
    }
    try {
        return run(opt);
    } catch (const InputError& e) {
        return fail(2, e.what(), opt);
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what(), opt);
    }
}
