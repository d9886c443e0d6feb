// rbcd-merge: the outputs of rbcd-sim runs over consecutive frame ranges
// (--frames A:B) as those of one run over all their frames (run/merge.h,
// docs/sweeps.md).
#include <cstdio>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>
#include <systemc>   // sc_main's declaration

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/common/output_file.h"
#include "rbcd/run/merge.h"

namespace {

// The kernel prints its banner before sc_main runs, unless told not to.
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();

int fail(int status, const std::string& msg, const rbcd::MergeOptions& opt) {
    std::fprintf(stderr, "rbcd-merge: %s\n", rbcd::escape_for_message(rbcd::cut_long_tokens(msg)).c_str());
    rbcd::discard_merge_outputs(opt);
    return status;
}

} // namespace

// A SystemC program only because the report library it shares with rbcd-sim
// links the kernel; no module is elaborated.
int sc_main(int argc, char* argv[]) {
    rbcd::report_file_size_limit_as_write_error();
    rbcd::MergeOptions opt;
    CLI::App app{"rbcd-merge: the outputs of rbcd-sim runs over consecutive frame ranges (--frames) as those of one "
                 "run over all their frames (docs/sweeps.md)"};
    app.add_option("--stats", opt.stats, "write the merged statistics JSON here")->required();
    app.add_option("--collisions", opt.collisions,
                   "also merge the parts' collision files (where their provenance says they are) into this one");
    app.add_option("--frame-stats", opt.frame_stats, "also merge the parts' --frame-stats files into this one");
    app.add_option("--max-stats-bytes", opt.max_stats_bytes, "refuse a larger part stats file, default 4 MiB");
    app.add_option("parts", opt.parts, "the parts' stats JSON files, in frame order")->required();
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        if (e.get_exit_code() == 0) return app.exit(e);
        return fail(2, std::string(e.what()) + " (see --help)", opt);
    }
    try {
        return rbcd::merge_runs(opt);
    } catch (const rbcd::InputError& e) {
        return fail(2, e.what(), opt);
    } catch (const rbcd::RunError& e) {
        return fail(1, e.what(), opt);
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what(), opt);
    }
}
