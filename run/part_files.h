// The collision and per-frame files of rbcd-sim runs over consecutive frame
// ranges, joined into one run's (rbcd-merge, and rbcd-sim --jobs for its
// workers' files): each file is read line by line and checked against its
// part's frames as it is copied, so another part's file, garbage or a file cut
// short is refused (InputError naming the file and line), never copied.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/common/output_file.h"

namespace rbcd {

struct PartFiles {
    std::string collisions, frame_stats;   // the part's files (empty: not merged)
    std::uint64_t first_frame = 0, frames = 0;
    std::uint64_t cycles = 0;              // the part's totals.cycles: the next part's clock starts there
};

// The magic line once, then every part's records in order.
void copy_part_collisions(const std::vector<PartFiles>& parts, OutputFile& out);
// One part's file, written by this process's own worker (rbcd-sim --jobs, in
// its private directory), appended to `out`: checked only for its magic line,
// which goes to `out` only for the first part; the rest is copied by
// OutputFile::append_from. Throws RunError on a read error.
void append_own_part_collisions(const PartFiles& part, bool first, OutputFile& out);
// Every part's lines, their start_cycle and end_cycle counted from the first part's start.
void copy_part_frame_stats(const std::vector<PartFiles>& parts, OutputFile& out);
// One part's lines, counted from `offset` (the cycles of the parts before it).
void append_part_frame_stats(const PartFiles& part, std::uint64_t offset, OutputFile& out);

} // namespace rbcd
