// rbcd-sim --jobs N: one run on N cores. Frames are independent (every frame
// starts on a drained unit with its memory latency reseeded: docs/timing.md),
// so the run's frames are cut into N contiguous ranges, each simulated by a
// worker (a fork of rbcd-sim running its own --frames A:B command line) into a private
// directory, and the workers' stats, collision and per-frame files are joined
// as rbcd-merge joins them: the same bytes as one process.
//
//     const auto parts = plan_trace_parts(scan_frames(trace), range, 2);
//     Workers w(main, worker_argvs, errs);   // starts them
//     w.wait();                           // throws the first failed part's error
//
// A worker does not read what comes before its frames: it starts at its
// first frame's byte of a trace (found by scan_frames, io/frame_scan.h), or
// renders a scene from that frame on, as one process does. A trace's frames
// before it are the previous worker's, which reads and checks them; the
// first worker reads from the start, so that an input error before the range
// is reported as one process reports it.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/io/frame_range_source.h"
#include "rbcd/io/frame_scan.h"

namespace rbcd {

struct JobPart {
    FrameRange range;            // its --frames (last open, UINT64_MAX, for the part that runs to the input's end)
    bool skip = false;           // starts at range.first without reading (or rendering) the frames before it
    std::uint64_t offset = 0, line = 0;   // a trace's: where frame range.first's record is (line 0: to be counted)
};

// Contiguous parts covering `range` of a trace, balanced by bytes; fewer than
// `jobs` when the trace has fewer frames in the range. One part (or none, when
// the range selects nothing) means: run as one process.
std::vector<JobPart> plan_trace_parts(const FrameScan& scan, FrameRange range, unsigned jobs);
// The same for a scene of `frames` frames, balanced by frames.
std::vector<JobPart> plan_scene_parts(std::uint64_t frames, FrameRange range, unsigned jobs);

// The hidden option a worker gets: "first", "scene" or "trace:OFFSET:LINE".
std::string worker_part_text(const JobPart& p, bool trace);
// Its parse; throws InputError naming --worker-part.
JobPart parse_worker_part(const std::string& text, FrameRange range);

// A worker's blocks of the trace's digest (run/part_digest.h): bytes
// [from, to), multiples of 1,024; a part not from 0 writes its block sums to
// a file. The hidden option's text, "FROM:TO", and its parse, which throws
// InputError naming --worker-digest (or --worker-digest-sums, missing for a
// part not from 0).
struct DigestBlocks {
    std::uint64_t from = 0, to = 0;
};
std::string worker_digest_text(const DigestBlocks& b);
DigestBlocks parse_worker_digest(const std::string& text, const std::string& sums_path);

// A worker's program: what the process would run from its command line
// `argv` (argv[0] the program); returns the exit status.
using WorkerMain = int (*)(const std::vector<std::string>& argv);

// The workers, started by the constructor with argvs[k] (argvs[k][0] the
// program), standard output into out_fds[k] (missing or -1: discarded),
// standard error into err_paths[k]. Each is a fork of this process that runs
// `main` on its argv and exits, not a new program: the dynamic linking and
// the SystemC library's start-up (about 5 ms a process) are already done.
// Call with no other thread running in this process.
class Workers {
public:
    Workers(WorkerMain main, const std::vector<std::vector<std::string>>& argvs,
            const std::vector<std::string>& err_paths, const std::vector<int>& out_fds = {});
    ~Workers();   // waits for any still running (after killing them)
    Workers(const Workers&) = delete;
    Workers& operator=(const Workers&) = delete;
    // Waits for worker k alone; whether it succeeded. The others run on, so
    // what a part wrote is joined while the later parts are still simulated.
    bool wait_for(std::size_t k);
    // After wait_for(k): whether worker k refused its input (exit status 2).
    bool refused_input(std::size_t k) const;
    // Blocks until some worker has ended, without reaping it (wait_for still
    // does); false when it ended unsuccessfully (the run then fails).
    bool first_end_ok() const;
    // Waits for all. When some failed: throws the error of the first one (in
    // frame order), the exit status it had (InputError for 2, RunError else).
    void wait();

private:
    void stop_all();   // SIGTERM to those still running, then each waited for
    std::vector<int> pids_, status_;
    std::vector<int> lost_;   // errno of a wait that failed: the status is unknown
    std::vector<bool> done_;
    std::vector<std::string> err_;
    bool waited_ = false;
};

// A private temporary directory (mkdtemp, mode 0700) in `parent`, removed
// with what it holds. The workers' collision files, as large as the run's,
// go beside the output they become (the same file system, which must hold
// them anyway), not into a TMPDIR that may be memory.
class TempDirectory {
public:
    explicit TempDirectory(const std::string& parent);
    ~TempDirectory();
    TempDirectory(const TempDirectory&) = delete;
    TempDirectory& operator=(const TempDirectory&) = delete;
    std::string path(const std::string& name) const { return dir_ + "/" + name; }
    // The file `name` will be written in it: removed, and the directory with
    // it, if the run is interrupted (SIGINT, SIGTERM, SIGHUP; output_file.h).
    // Call before the workers start.
    void will_hold(const std::string& name);

private:
    std::string dir_;
    std::vector<std::string> held_;
};

} // namespace rbcd
