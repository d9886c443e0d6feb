// What a run's stats document is computed from: its configuration, every
// block's counters, the GPU timelines' integer sums and the per-frame
// reductions. All of it merges exactly across consecutive frame ranges
// (`merge_snapshots`), and a stats document holds enough to rebuild it
// (`snapshot_from_stats`), so rbcd-merge turns the stats of `--frames` runs
// into the document one run over all their frames would have written.
//
//   RunSnapshot s = snapshot_of(sys, report, input_name);   // after sys.run()
//   nlohmann::json j = make_stats(s, wall_seconds);
//
//   RunSnapshot all = snapshot_from_stats(part0);
//   merge_snapshots(all, snapshot_from_stats(part1));        // part1 follows part0
#pragma once
#include <cstdint>
#include <string>

#include <nlohmann/json.hpp>

#include "rbcd/common/config.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/unit_counters.h"

namespace rbcd {

class rbcd_system;

struct RunSnapshot {
    std::string input;
    SimConfig cfg;
    std::uint64_t cycles = 0;   // totals.cycles: the end of the last frame
    UnitCounters counters;
    FrameFigures gpu;           // integer sums over the frames; energies from fill_energies
    FrameReduction frames;
};

RunSnapshot snapshot_of(const rbcd_system& sys, const RunReport& report, const std::string& input);

// From a stats document ("rbcd-stats 2"). Throws InputError naming the
// missing or malformed key.
RunSnapshot snapshot_from_stats(const nlohmann::json& stats);

// Appends `later`, the run over the frames right after `a`'s. Throws
// InputError when the two cannot be one run: other input, other
// configuration, frames that do not follow on.
//
// Counters merge by name (docs/stats.md): `max_*_cycle` is a point in time
// (the later run's counted from `a`'s end), `max_*` a maximum, every other
// counter a sum.
void merge_snapshots(RunSnapshot& a, const RunSnapshot& later);

} // namespace rbcd
