// rbcd-merge's work: the outputs of rbcd-sim runs over consecutive frame
// ranges (--frames A:B) turned into the outputs of one run over all their
// frames, byte for byte (docs/sweeps.md, "One long input across workers"):
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
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace rbcd {

struct MergeOptions {
    std::string stats, collisions, frame_stats;
    std::vector<std::string> parts;   // the parts' stats files, in frame order
    std::uint64_t max_stats_bytes = std::uint64_t(4) << 20;
};

// Writes the merged outputs; returns 0. Throws InputError for parts that are
// not one run's (exit 2), anything else for exit 1.
int merge_runs(const MergeOptions& opt);

// As rbcd-sim: on a non-zero exit nothing stands at an output path, not even
// an older file, unless the path names one of the inputs (a part's stats, or
// the collision or frame stats file its provenance names).
void discard_merge_outputs(const MergeOptions& opt);

} // namespace rbcd
