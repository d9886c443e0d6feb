// rbcd-sim: runs the RBCD unit model over a fragment trace or a 3D scene
// (formats.md, "Command line"). Exit 0 done, 2 bad input/config/command line,
// 1 anything else; on a non-zero exit no output file is left behind.
#include <CLI/CLI.hpp>
#include <systemc>   // sc_main's declaration
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/common/output_file.h"
#include "rbcd/run/provenance.h"
#include "rbcd/run/run.h"

int rbcd_sim_main(const std::vector<std::string>& args);

namespace {

// The kernel prints its banner before sc_main runs; it would precede every
// summary and --dump-config. Static initialisation of the program comes first.
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();

// The files the command line names, as the parser read them (its results
// stand even when the parse failed part-way): what a failed run discards.
rbcd::RunPaths named_paths(const CLI::App& app) {
    rbcd::RunPaths paths;
    const auto each = [&app](const char* name, auto add) {
        for (const std::string& v : app.get_option(name)->results()) add(v);
    };
    for (const char* o : {"--collisions", "--stats", "--frame-stats", "--db", "--write-trace"})
        each(o, [&](const std::string& v) { paths.output(v); });
    for (const char* o : {"--vcd", "--fst"}) each(o, [&](const std::string& v) { paths.waveform(v); });
    each("--gtkw", [&](const std::string& v) { paths.gtkw(v); });
    for (const char* o : {"--trace", "--config"}) each(o, [&](const std::string& v) { paths.input(v); });
    each("--scene", [&](const std::string& v) { paths.scene(v); });
    return paths;
}

int fail(int status, const std::string& msg, const rbcd::RunPaths& paths) {
    // One line whatever the input held: control bytes from files, --set values
    // or library messages (toml++) are escaped here, in one place.
    std::fprintf(stderr, "rbcd-sim: %s\n", rbcd::escape_for_message(msg).c_str());
    paths.discard_outputs();
    return status;
}

// Levenshtein distance, for suggesting the option a mistyped argument meant.
std::size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diag = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diag = up;
        }
    }
    return row[b.size()];
}

// "unknown argument '--tracee' (did you mean --trace?)": CLI11 lists the
// arguments it did not expect; the first is named with the nearest option.
std::string unknown_argument_message(const CLI::App& app, const std::vector<std::string>& extras) {
    const std::string arg = extras.empty() ? std::string() : extras.front();
    std::string msg = "unknown argument '" + arg + "'";
    const std::size_t b = arg.find_first_not_of('-');
    if (b > 0 && b != std::string::npos) {
        // Against the long names, dashes aside: "-trace" and "--tracee" both mean --trace.
        const std::string name = arg.substr(b, arg.find('=') - b);
        std::string best;
        std::size_t best_d = std::string::npos;
        for (const CLI::Option* o : app.get_options())
            for (const auto& l : o->get_lnames())
                if (const std::size_t d = edit_distance(name, l); d < best_d) best_d = d, best = l;
        // Close enough to be a typo: at most a third of the name wrong.
        if (!best.empty() && name.size() >= 3 && best_d <= std::max<std::size_t>(1, best.size() / 3))
            msg += " (did you mean --" + best + "?)";
    } else if (b == 0) {
        msg += " (inputs are given as --trace FILE or --scene FILE)";
    }
    return msg;
}

} // namespace

// The program from its command line: sc_main's, and a --jobs worker's (a fork
// of this process, run/jobs.h).
int rbcd_sim_main(const std::vector<std::string>& args) {
    std::vector<char*> argv_buf;
    for (const auto& a : args) argv_buf.push_back(const_cast<char*>(a.c_str()));
    argv_buf.push_back(nullptr);
    const int argc = static_cast<int>(args.size());
    char** const argv = argv_buf.data();
    rbcd::SimOptions opt;
    opt.argv = args;
    CLI::App app{"rbcd-sim: SystemC/TLM-2.0 model of the RBCD collision-detection unit"};
    app.add_option("--config", opt.config_file, "TOML configuration file");
    app.add_option("--set", opt.sets, "KEY=VALUE, applied after --config in order (repeatable)")->take_all();
    auto* trace_opt = app.add_option("--trace", opt.trace, "fragment trace (.rbt, plain or gzip; - reads standard input)");
    app.add_option("--scene", opt.scene, "3D scene (TOML) rendered by the tile-based rasterizer feed")
        ->excludes(trace_opt);
    auto* frames_opt =
        app.add_option("--frames", opt.frames, "A:B: run only frames A..B of the input (their numbers kept; docs/sweeps.md)");
    app.add_option("--threads", opt.threads,
                   "2 (default): a trace is parsed on a second thread; 1: one thread (what rbcd-sweep runs)")
        ->check(CLI::Range(1u, 2u));
    app.add_option("--jobs", opt.jobs,
                   "N: simulate the frames in N worker processes, contiguous ranges joined into the outputs one "
                   "process writes (docs/performance.md); default 1")
        ->check(CLI::Range(1u, 1024u));
    app.add_option("--worker-part", opt.worker_part, "internal: a --jobs worker's start")->group("");
    app.add_flag("--gpu-stepwise", opt.gpu_stepwise,
                 "internal: the GPU pipeline's runs computed fragment by fragment (the bulk runs' reference in tests)")
        ->group("");
    app.add_option("--worker-stop-at", opt.worker_stop_at, "internal: the byte a --jobs trace worker's data ends at")
        ->group("");
    app.add_option("--worker-collisions-name", opt.worker_collisions_name,
                   "internal: what a --jobs worker's --collisions - is, for its errors")
        ->group("");
    app.add_option("--worker-digest", opt.worker_digest, "internal: a --jobs worker's blocks of the trace's digest")
        ->group("");
    app.add_option("--worker-digest-sums", opt.worker_digest_sums, "internal: where a --jobs worker's block sums go")
        ->group("");
    app.add_option("--write-trace", opt.write_trace, "also save the fragment stream the unit saw as a .rbt trace");
    app.add_option("--images", opt.images, "write a PNG per frame into this directory (scenes only)");
    app.add_option("--collisions", opt.collisions, "write the collision records here (- for standard output)");
    app.add_option("--stats", opt.stats, "write statistics JSON here");
    app.add_option("--frame-stats", opt.frame_stats,
                   "write per-frame figures here, one JSON object a line, as frames end (docs/stats.md)");
    app.add_option("--vcd", opt.vcd, "write a VCD waveform dump here (trace.* keys select blocks and window; "
                                     "a .fst name writes FST)");
    app.add_option("--fst", opt.fst, "write the waveforms as FST here (as --vcd; docs/waveforms.md)");
    app.add_option("--gtkw", opt.gtkw, "write the GTKWave save file for the waveform here (default: beside it, "
                                       "NAME.gtkw, with NAME.states.txt)");
    app.add_option("--heat-maps", opt.heat_maps,
                   "write per-tile heat maps summed over the run into this directory (with --images: also each "
                   "frame's; docs/tile-database.md)");
    app.add_option("--db", opt.db, "write the per-tile SQLite database here (docs/tile-database.md)");
    app.add_flag("--dump-config", opt.dump_config, "print the effective configuration as TOML and exit");
    app.add_flag("-q,--quiet", opt.quiet, "no summary on stdout");
    app.footer("Formats and options: docs/formats.md; configuration keys: docs/config.md; statistics: docs/stats.md.");
    app.set_version_flag("--version", rbcd::version_text(), "print the version, git revision, SystemC, compiler and build type");
    app.add_flag("--config-reference", opt.config_reference, "print the table of configuration keys (docs/config.md)");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ExtrasError&) {
        return fail(2, unknown_argument_message(app, app.remaining()) + " (see --help)", named_paths(app));
    } catch (const CLI::ParseError& e) {
        return fail(2, std::string(e.what()) + " (see --help)", named_paths(app));
    }
    opt.frames_given = frames_opt->count() > 0;
    const rbcd::RunPaths paths = named_paths(app);
    try {
        return rbcd::Run(std::move(opt), rbcd_sim_main).execute();
    } catch (const rbcd::InputError& e) {
        return fail(2, e.what(), paths);
    } catch (const rbcd::RunError& e) {
        return fail(1, e.what(), paths);
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what(), paths);
    }
}

int sc_main(int argc, char* argv[]) {
    rbcd::report_file_size_limit_as_write_error();
    return rbcd_sim_main(std::vector<std::string>(argv, argv + argc));
}
