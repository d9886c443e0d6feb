// The --stats JSON document and the end-of-run summary on stdout, from the
// system's counters and the run's per-frame reduction (report/run_report.h):
//
//   rbcd_system sys("rbcd", cfg, src, sink);
//   RunReport report(sys);                       // per-frame figures, streamed
//   sys.run();
//   nlohmann::json j = make_stats(sys, info, report);
//   std::string text = make_summary(j, report);
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "rbcd/hw/rbcd_system.h"
#include "rbcd/report/energy_model.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/run_snapshot.h"

namespace rbcd {

struct RunInfo {
    std::string input;        // trace path or scene name
    double wall_seconds = 0;
};

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info, const RunReport& report);
// The same document from a snapshot (a run's, or merged runs').
nlohmann::json make_stats(const RunSnapshot& s, double wall_seconds);
std::string make_summary(const nlohmann::json& stats, const RunReport& report);

// What the summary shows of the frames, from a run's report or from the
// files of merged runs (rbcd-sim --jobs): the totals with their energies, the
// frame count, the mean of per-frame overheads, and the --frame-stats objects
// (frame_json) of the first frames (up to RunReport::kFirstFrames) and of the
// worst one (null: none).
struct SummaryFrames {
    FrameFigures totals;
    std::uint64_t frames = 0;
    double mean_overhead_pct = 0;
    std::vector<nlohmann::json> first;
    nlohmann::json worst;
};
SummaryFrames summary_frames(const RunReport& report);
// A snapshot's totals with their energies, as its stats document has them.
FrameFigures snapshot_totals(const RunSnapshot& s);
std::string make_summary(const nlohmann::json& stats, const SummaryFrames& frames);

} // namespace rbcd
