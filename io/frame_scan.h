// Where a trace's frames start, for rbcd-sim --jobs: one pass over the data
// (inflated when it is gzip) that looks for lines starting "frame N" and
// parses nothing else, so that the workers each start at their first frame's
// byte instead of reading, and parsing, every fragment before it.
//
//     const FrameScan s = scan_frames("long.rbt.gz");
//     if (s.ok) for (const FrameMark& m : s.marks) ...;   // m.frame starts at byte m.offset, line m.line
//
// Nothing is checked: a malformed trace gives marks where its lines look like
// frame records, and the worker whose frames hold the fault reports it, as a
// whole run would. A zstd trace whose frames declare their sizes (as
// TraceWriter writes it) is scanned by its frames' headers and first bytes
// only: its marks are the frame records that start a zstd frame. The marks are a sample once there are more than
// max_marks frames (every 2^k-th), so memory does not grow with the trace.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rbcd {

struct FrameMark {
    std::uint64_t frame = 0;    // the number on the line
    std::uint64_t offset = 0;   // the line's first byte in the (inflated) data
    std::uint64_t line = 0;     // its line number, from 1
};

struct FrameScan {
    bool ok = false;              // false: not readable as a trace (a whole run says why)
    std::vector<FrameMark> marks; // in file order
    std::uint64_t frame_lines = 0;   // lines that look like frame records
    std::uint64_t bytes = 0;         // length of the data
};

// Never throws for the file's sake: an unreadable or corrupt file gives ok = false.
// chunk: bytes inflated at a time; small values exercise the refills (tests).
FrameScan scan_frames(const std::string& path, std::size_t max_marks = 4096, std::size_t chunk = std::size_t(1) << 20);

// A plain trace (not gzip, a regular file) needs no pass over all of it: the
// first frame record at or after each of `targets` (byte offsets), read from
// there, a few KiB each. Their line numbers are left 0 (unknown): a worker's
// reader counts them (count_lines_before) only if a message needs one. ok = false
// for a gzip file or anything that is not a regular file: use scan_frames.
FrameScan find_frames_near(const std::string& path, const std::vector<std::uint64_t>& targets);
// The size of the file, 0 when it is gzip or not a regular file.
std::uint64_t plain_trace_bytes(const std::string& path);
// The number of the line that starts at byte `offset` of a trace's data
// (decompressed when the file is). Throws InputError when it cannot be read.
std::uint64_t count_lines_before(const std::string& path, std::uint64_t offset);

} // namespace rbcd
