// rbcd-sim: runs the RBCD unit model over a fragment trace or a 3D scene
// (formats.md, "Command line"). Exit 0 done, 2 bad input/config/command line,
// 1 anything else; on a non-zero exit no output file is left behind.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <systemc>

#include "common/config.h"
#include "common/errors.h"
#include "io/trace_reader.h"
#include "sc_main/collision_file.h"
#include "sc_main/default_input.h"
#include "sc_main/output_file.h"
#include "sc_main/stats_report.h"
#include "hw/rbcd_system.h"

namespace {

struct Options {
    std::string config_file;
    std::vector<std::string> sets;
    std::string trace, collisions, stats;
    bool dump_config = false;
    bool quiet = false;
};

void quiet_kernel() {
    // sc_stop() and end-of-simulation notes are not the user's business.
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
}

int run(const Options& opt) {
    using namespace rbcd;
    SimConfig cfg;
    if (!opt.config_file.empty()) apply_config_file(cfg, opt.config_file);
    for (const auto& s : opt.sets) apply_config_set(cfg, s);
    cfg.validate();

    if (opt.dump_config) {
        std::fputs(dump_config_toml(cfg).c_str(), stdout);
        return 0;
    }

    // Outputs are created before the run so an uncreatable path fails fast.
    OutputFile collisions_out, stats_out;
    if (!opt.collisions.empty()) collisions_out = OutputFile(opt.collisions);
    if (!opt.stats.empty()) stats_out = OutputFile(opt.stats);

    const TraceLimits limits{cfg.tile.width, cfg.tile.height, cfg.zeb.id_bits};
    std::unique_ptr<FragmentSource> src;
    std::string input_name;
    if (!opt.trace.empty()) {
        src = std::make_unique<TraceReader>(opt.trace, limits);
        input_name = opt.trace;
    } else {
        src = open_default_input(limits);
        input_name = src->name();
    }

    std::unique_ptr<CollisionFileSink> file_sink;
    struct NullSink final : CollisionSink {
        void frame(std::uint64_t) override {}
        void hit(const HitRecord&) override {}
        void overflow(const OverflowRecord&) override {}
    } null_sink;
    CollisionSink* sink = &null_sink;
    if (collisions_out.active()) {
        file_sink = std::make_unique<CollisionFileSink>(collisions_out);
        sink = file_sink.get();
    }

    quiet_kernel();
    const auto t0 = std::chrono::steady_clock::now();
    rbcd_system sys("rbcd", cfg, *src, *sink);
    sys.run();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    const nlohmann::json stats = make_stats(sys, RunInfo{input_name, wall});
    if (file_sink) {
        file_sink->finish();
        collisions_out.commit();
    }
    if (stats_out.active()) {
        stats_out.write(stats.dump(2) + "\n");
        stats_out.commit();
    }
    if (!opt.quiet) std::fputs(make_summary(stats).c_str(), stdout);
    return 0;
}

} // namespace

int sc_main(int argc, char* argv[]) {
    Options opt;
    CLI::App app{"rbcd-sim: SystemC/TLM-2.0 model of the RBCD collision-detection unit"};
    app.add_option("--config", opt.config_file, "TOML configuration file");
    app.add_option("--set", opt.sets, "KEY=VALUE, applied after --config in order (repeatable)")->take_all();
    app.add_option("--trace", opt.trace, "fragment trace (.rbt, plain or gzip)");
    app.add_option("--collisions", opt.collisions, "write the collision records here");
    app.add_option("--stats", opt.stats, "write statistics JSON here");
    app.add_flag("--dump-config", opt.dump_config, "print the effective configuration as TOML and exit");
    app.add_flag("-q,--quiet", opt.quiet, "no summary on stdout");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::fprintf(stderr, "rbcd-sim: %s (see --help)\n", e.what());
        return 2;
    }
    try {
        return run(opt);
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "rbcd-sim: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rbcd-sim: internal error: %s\n", e.what());
        return 1;
    }
}
