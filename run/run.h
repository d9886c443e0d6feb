// One rbcd-sim run (docs/formats.md, "Command line"): the options as the
// command line gave them, the files it names, and the run itself.
//
//     SimOptions opt = ...;                 // sc_main/main.cpp reads them
//     RunPaths paths;  paths.output(opt.stats);  paths.input(opt.trace);  ...
//     try { return Run(opt, rbcd_sim_main).execute(); }
//     catch (...) { paths.discard_outputs(); ... }
//
// Run::execute() goes through the phases in order: validate (options,
// configuration, output paths against the inputs), open outputs, open the
// source, split into --jobs workers when asked (run/jobs_run.h), build the
// system, attach the observers (waveforms, tile database, heat maps, images,
// --write-trace, progress), simulate, commit (every output renamed into
// place, the stats last, then the summary).
#pragma once
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "rbcd/run/jobs.h"

namespace rbcd {

struct SimOptions {
    std::string config_file;
    std::vector<std::string> sets;
    std::string trace, scene, collisions, stats, frame_stats, write_trace, images, vcd, fst, gtkw, db, heat_maps;
    std::string frames;   // --frames A:B
    bool frames_given = false;   // --frames '' is an error, not "all frames"
    unsigned threads = 2;  // 2: a trace is parsed on its own thread
    unsigned jobs = 1;     // worker processes, each a contiguous range of the frames (run/jobs.h)
    std::string worker_part;   // set in a worker: where its frames start (jobs.h)
    bool gpu_stepwise = false;   // the GPU pipeline's runs fragment by fragment (tests)
    std::uint64_t worker_stop_at = UINT64_MAX;   // a trace worker but the last: where the next one starts
    std::string worker_collisions_name;   // a worker's --collisions -: the run's output, named in errors
    std::string worker_digest;        // a worker's part of the trace's digest, FROM:TO (part_digest.h)
    std::string worker_digest_sums;   // where a later part's block sums go
    bool dump_config = false;
    bool config_reference = false;
    bool quiet = false;
    std::vector<std::string> argv;   // for the stats' provenance
};

// The GTKWave save file of a waveform: `gtkw` when given, else beside a
// waveform written through a temporary (run.fst -> run.gtkw); its state
// filter beside it. Empty: none.
std::pair<std::string, std::string> layout_paths(const std::string& gtkw, const std::string& wave);

// The files a run names, registered as the command line names them: on a
// non-zero exit nothing stands at an output path, not even an older file
// (docs/formats.md), but an output path that names one of the inputs (a
// scene's mesh files too) is the input and stays.
class RunPaths {
public:
    void output(const std::string& path);
    // --vcd or --fst: the waveform, and the GTKWave layout beside it unless
    // --gtkw names it.
    void waveform(const std::string& path);
    void gtkw(const std::string& path);
    void input(const std::string& path);
    // The scene and every mesh file it names (scene::SceneSource::mesh_files_named).
    void scene(const std::string& path);
    // discard_outputs() (common/output_file.h) of every output but the inputs.
    void discard_outputs() const;

private:
    std::vector<std::string> outputs_, waves_, gtkw_, inputs_;
};

class Run {
public:
    // `worker_main` is what a --jobs worker runs: rbcd-sim's own main.
    Run(SimOptions opt, WorkerMain worker_main);
    ~Run();
    Run(const Run&) = delete;
    Run& operator=(const Run&) = delete;
    // The phases; returns the exit status (0). Throws InputError for a bad
    // input, configuration or command line (exit 2), anything else for exit 1;
    // the outputs it opened are then abandoned.
    int execute();

private:
    class Impl;
    std::unique_ptr<Impl> impl_;
};

} // namespace rbcd
