// Streaming reader of .rbt fragment traces (formats.md), plain or gzip.
// Holds one tile in memory at a time, so memory does not grow with the trace.
#pragma once
#include <memory>
#include <string>

#include "rbcd/common/fragment.h"

namespace rbcd { struct SimConfig; }

namespace rbcd {

class RawObserver;   // io/gzip_stream.h

// What the unit accepts; the trace is checked against it while it is read.
struct TraceLimits {
    unsigned tile_w = 16, tile_h = 16;   // must equal the trace's tile_size
    unsigned id_bits = 7;                // object ids must fit
    // Resource bounds (docs/limits.md); the messages name the key that raises them.
    std::uint64_t max_line_bytes = std::uint64_t(1) << 20;        // input.max_line_bytes
    std::uint64_t max_tile_fragments = std::uint64_t(1) << 24;    // input.max_tile_fragments
    // The run's declared work, sum over tiles of (fragments + other) x
    // cycles_per_fragment + (prims + cprims) x cycles_per_primitive +
    // tile_overhead + base, may not exceed max_work_cycles (0: unchecked),
    // so that simulated time stays far inside 64-bit picoseconds.
    std::uint64_t max_work_cycles = 0;
    std::uint64_t cycles_per_fragment = 1;
    std::uint64_t cycles_per_primitive = 0;   // prims= and cprims= setups
    std::uint64_t tile_overhead = 0;          // per tile record
    double clock_mhz = 0;                // for the message only
    // Bytes per read(2) of the file; small values exercise buffer refills (tests, fuzzing).
    std::size_t read_chunk = std::size_t(1) << 20;
    // A compressed trace decompressed on a thread of its own, from the first
    // next() on (io/read_ahead.h): rbcd-sim's --threads 2.
    bool read_ahead = false;
    // The usual fragment line parsed with AVX-512 where the CPU has it; false:
    // the portable parse everywhere. Both take the same lines to the same
    // fragments (tests and the trace fuzz target compare them).
    bool wide_parse = true;
};

// Whether this machine parses the usual fragment line with AVX-512
// (TraceLimits::wide_parse): the CPU has AVX-512 F, BW, VL, VBMI and VBMI2
// and the operating system saves their registers.
bool trace_wide_parse_available();

// The limits rbcd-sim applies for a configuration.
TraceLimits trace_limits(const SimConfig& cfg);

class TraceReader final : public FragmentSource {
public:
    // Reads the magic and header records. Throws InputError ("file:line: ...")
    // on malformed input, or cannot_read_message() when the file cannot be
    // opened or is not a regular file. "-" reads standard input.
    // observer: shown every byte read from the file (io/gzip_stream.h), the
    // header's included.
    TraceReader(const std::string& path, const TraceLimits& limits, RawObserver* observer = nullptr);
    ~TraceReader() override;
    const StreamHeader& header() const override;
    Event next(Tile& tile) override;
    std::string name() const override;

    // rbcd-sim --jobs: a worker whose frames start at `frame` goes straight to
    // that frame's record, at byte `offset` of the (inflated) data, line `line`
    // (as scan_frames() found them); the frames before it are the previous
    // worker's to read and check. Call before the first next(). line = 0: not
    // known (a plain file, found by find_frames_near()); a message counts the
    // lines before `offset` in the file when it needs the number.
    void start_at_frame(std::uint64_t frame, std::uint64_t offset, std::uint64_t line);
    // The work the tiles read so far declared (see TraceLimits::max_work_cycles),
    // counted from `work_before`: what the frames before a --jobs worker's
    // first declared, so that the run's bound is checked as one process checks it.
    std::uint64_t declared_work() const;
    void count_work_from(std::uint64_t work_before);
    // The data ends at the record of frame last + 1 (checked, not passed on):
    // a --jobs worker reads nothing of the next worker's frames.
    void stop_after_frame(std::uint64_t last);
    // ... and that record must start at byte `offset` of the data, where the
    // next worker starts (a zstd trace's marks start zstd frames, which a
    // hostile file may cut inside a line): an InputError otherwise, as the
    // run would take some lines twice or miss them.
    void expect_stop_at(std::uint64_t offset);
    // Fragment lines taken by the whole-line parse (AVX-512 or portable) so
    // far, the rest having gone byte by byte: both parses must take the same
    // lines, or one would be slower without any output showing it (tests).
    std::uint64_t lines_taken_whole() const;
    // Whether this reader's whole-line parse is the AVX-512 one (wide_parse
    // asked for it and trace_wide_parse_available()).
    bool parses_wide() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace rbcd
