#include "rbcd/run/merge.h"

#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/common/output_file.h"
#include "rbcd/io/frame_range_source.h"
#include "rbcd/report/run_snapshot.h"
#include "rbcd/report/stats_report.h"
#include "rbcd/run/part_files.h"
#include "rbcd/run/provenance.h"

namespace rbcd {

namespace {

// What is kept of a part: its stats document is parsed, read and dropped, so
// that memory holds one document at a time whatever the parts' number.
struct Part {
    std::string path;
    nlohmann::json provenance;
    double wall = 0;
    RunSnapshot snapshot;
    FrameRange range;   // its --frames (the whole input without)
    std::string collisions, frame_stats;   // where it wrote them, when merged
};

nlohmann::json read_json(const std::string& path, std::uint64_t max_bytes) {
    const std::string text = read_input_text(path, "stats file", max_bytes, "--max-stats-bytes");
    try {
        return nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
        throw InputError(path + ": not JSON: " + e.what());
    }
}

const nlohmann::json& provenance_of(const Part& p) { return p.provenance; }

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
    const auto values = option_values(argv_of(p), {option.c_str()});
    const std::string v = values.empty() ? std::string() : values.front();
    if (v.empty() || v == "-") throw InputError(p.path + ": the run wrote no " + option + " file");
    const nlohmann::json& pv = provenance_of(p);
    std::filesystem::path f(v);
    if (f.is_relative() && pv.contains("working_directory") && pv["working_directory"].is_string())
        f = std::filesystem::path(pv["working_directory"].get<std::string>()) / f;
    return f.string();
}

// The command line one run over all the frames would have had: the first
// part's, its --frames and outputs rewritten (an empty value drops the
// option), and without the outputs that are not merged (--vcd, --images,
// --write-trace).
std::vector<std::string> whole_run_argv(const std::vector<std::string>& argv,
                                        const std::vector<std::pair<std::string, std::string>>& outputs) {
    const std::vector<std::string> dropped = {"--vcd", "--images", "--write-trace"};
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

std::string range_text(std::uint64_t first, std::uint64_t last) {
    return std::to_string(first) + ":" + (last == UINT64_MAX ? std::string() : std::to_string(last));
}

// The frames a part says it ran (its --frames) against those its stats hold:
// a part is its range's frames from the first, all of them unless the input
// ended (then no part may follow).
void check_part_frames(const Part& p) {
    const FrameReduction& r = p.snapshot.frames;
    if (r.frames == 0) throw InputError(p.path + ": stats: totals.frames: 0 (a part without frames)");
    if (r.last_frame < r.first_frame || r.last_frame - r.first_frame != r.frames - 1)
        throw InputError(p.path + ": stats: totals.frames: " + std::to_string(r.frames) + " does not match frame_range " +
                         std::to_string(r.first_frame) + ".." + std::to_string(r.last_frame));
    if (r.first_frame != p.range.first || r.last_frame > p.range.last)
        throw InputError(p.path + ": stats: frame_range: " + std::to_string(r.first_frame) + ".." +
                         std::to_string(r.last_frame) + " is not what its --frames " +
                         range_text(p.range.first, p.range.last) + " selects");
}

} // namespace

int merge_runs(const MergeOptions& opt) {
    std::vector<Part> parts;
    for (const auto& path : opt.parts) {
        Part p;
        p.path = path;
        nlohmann::json stats = read_json(path, opt.max_stats_bytes);
        try {
            p.snapshot = snapshot_from_stats(stats);
        } catch (const InputError& e) {
            throw InputError(path + ": " + e.what());
        }
        if (!stats.contains("provenance") || !stats["provenance"].is_object())
            throw InputError(path + ": stats: provenance: missing");
        p.provenance = std::move(stats["provenance"]);
        const nlohmann::json& t = stats["time"];
        if (t.is_object() && t.contains("wall_seconds") && t["wall_seconds"].is_number())
            p.wall = t["wall_seconds"].get<double>();
        const auto frames = option_values(argv_of(p), {"--frames"});
        if (!frames.empty()) {
            try {
                p.range = parse_frame_range(frames.back());
            } catch (const InputError& e) {
                throw InputError(path + ": stats: provenance.argv: " + e.what());
            }
        }
        check_part_frames(p);
        parts.push_back(std::move(p));
    }

    RunSnapshot all = parts.front().snapshot;
    double wall = 0;
    for (std::size_t i = 0; i < parts.size(); ++i) {
        if (i > 0) {
            // The ranges tile the frames: no gap, no overlap, and nothing
            // after a part that reached the input's end.
            const Part& prev = parts[i - 1];
            if (prev.range.last == UINT64_MAX || prev.snapshot.frames.last_frame < prev.range.last)
                throw InputError(parts[i].path + ": follows " + prev.path + ", which ran to the input's end");
            if (parts[i].range.first != prev.range.last + 1)
                throw InputError(parts[i].path + ": frame_range: frame " + std::to_string(parts[i].range.first) +
                                 " does not follow frame " + std::to_string(prev.range.last) + " (its --frames " +
                                 range_text(parts[i].range.first, parts[i].range.last) + " after " + prev.path + "'s " +
                                 range_text(prev.range.first, prev.range.last) + ")");
            try {
                merge_snapshots(all, parts[i].snapshot);
            } catch (const InputError& e) {
                throw InputError(parts[i].path + ": " + e.what());
            }
        }
        wall += parts[i].wall;
    }
    // One program, one configuration, the same inputs: else not one run.
    const nlohmann::json& pv0 = provenance_of(parts.front());
    for (const auto& p : parts)
        for (const char* key : {"build", "config_xxh128", "inputs"})
            if (provenance_of(p).value(key, nlohmann::json()) != pv0.value(key, nlohmann::json()))
                throw InputError(p.path + ": stats: provenance." + key + ": differs from " + parts.front().path + "'s");

    for (auto& p : parts) {
        if (!opt.collisions.empty()) p.collisions = part_output(p, "--collisions");
        if (!opt.frame_stats.empty()) p.frame_stats = part_output(p, "--frame-stats");
    }

    // The merged run's frames: the whole input when the first part starts at
    // frame 0 and the last ran to the input's end, else the range it covers,
    // kept in the recorded command line (docs/sweeps.md).
    const Part& last = parts.back();
    const bool to_end = last.range.last == UINT64_MAX || last.snapshot.frames.last_frame < last.range.last;
    const std::string frames =
        parts.front().range.first == 0 && to_end ? std::string() : range_text(parts.front().range.first, last.range.last);

    nlohmann::json stats = make_stats(all, wall);
    nlohmann::json pv = pv0;
    const std::vector<std::string> argv =
        whole_run_argv(argv_of(parts.front()), {{"--frames", frames},
                                                {"--stats", opt.stats},
                                                {"--collisions", opt.collisions},
                                                {"--frame-stats", opt.frame_stats}});
    pv["argv"] = argv;
    pv["command_line"] = command_line(argv);
    stats["provenance"] = pv;

    // Nothing is opened (which removes an older file at an output path)
    // before every output is known to be neither an input nor another output.
    std::vector<NamedPath> inputs;
    for (const auto& p : parts) {
        inputs.push_back({"", p.path});
        inputs.push_back({"", p.collisions});
        inputs.push_back({"", p.frame_stats});
    }
    check_output_paths(
        {{"--stats", opt.stats}, {"--collisions", opt.collisions}, {"--frame-stats", opt.frame_stats}}, inputs);

    OutputFile stats_out(opt.stats), collisions_out, frames_out;
    std::vector<PartFiles> files;
    for (const auto& p : parts)
        files.push_back({p.collisions, p.frame_stats, p.snapshot.frames.first_frame, p.snapshot.frames.frames,
                         p.snapshot.cycles});
    if (!opt.collisions.empty()) {
        collisions_out = OutputFile(opt.collisions);
        copy_part_collisions(files, collisions_out);
    }
    if (!opt.frame_stats.empty()) {
        frames_out = OutputFile(opt.frame_stats);
        copy_part_frame_stats(files, frames_out);
    }
    stats_out.write(stats.dump(2) + "\n");
    if (collisions_out.active()) collisions_out.commit();
    if (frames_out.active()) frames_out.commit();
    stats_out.commit();
    outputs_complete();
    return 0;
}

void discard_merge_outputs(const MergeOptions& opt) {
    // A part's own collision or frame stats file is an input too (found through
    // its provenance, which may itself be what failed: then compared by name).
    std::vector<std::string> inputs = opt.parts;
    for (const auto& path : opt.parts) {
        try {
            Part p;
            p.path = path;
            const nlohmann::json stats = nlohmann::json::parse(
                read_input_text(path, "stats file", opt.max_stats_bytes, ""), nullptr, false);
            if (!stats.is_object() || !stats.contains("provenance") || !stats["provenance"].is_object()) continue;
            p.provenance = stats["provenance"];
            for (const char* o : {"--collisions", "--frame-stats"}) {
                try {
                    inputs.push_back(part_output(p, o));
                } catch (const std::exception&) {
                }
            }
        } catch (const std::exception&) {
        }
    }
    discard_outputs({opt.stats, opt.collisions, opt.frame_stats}, inputs);
}


} // namespace rbcd
