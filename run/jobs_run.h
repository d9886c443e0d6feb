// rbcd-sim --jobs: the parts of a run (run/jobs.h) simulated by worker
// processes, and their files joined into the run's outputs, which are
// already open: the same bytes as one process.
#pragma once
#include <chrono>
#include <cstdint>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/common/config.h"
#include "rbcd/common/output_file.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/report/run_snapshot.h"
#include "rbcd/run/jobs.h"
#include "rbcd/run/part_digest.h"
#include "rbcd/run/part_files.h"
#include "rbcd/run/provenance.h"
#include "rbcd/run/run.h"

namespace rbcd {

class JobsRun {
public:
    // The outputs of the run the parts make up.
    struct Outputs {
        OutputFile& collisions;
        OutputFile& stats;
        OutputFile& frame_stats;
    };
    // Plans the workers' command lines; `inputs` are the run's, for its provenance.
    JobsRun(const SimOptions& opt, const SimConfig& cfg, const std::vector<JobPart>& parts,
            std::vector<ProvenanceInput> inputs, Outputs out, WorkerMain worker_main);
    ~JobsRun();
    JobsRun(const JobsRun&) = delete;
    JobsRun& operator=(const JobsRun&) = delete;
    // Starts the workers and joins their parts; the outputs committed and the
    // summary printed. False when the parts' frames hold no fragment at all
    // (a scene: the caller then runs it as one process, which alone says
    // whether the scene has none), with the provenance already computed in
    // `provenance` (null when none was).
    bool run(nlohmann::json& provenance);

private:
    void plan_split_digest();
    void plan_workers();
    void start_hash();
    void read_again(std::size_t k);
    void check_work(std::size_t k, const nlohmann::json& j);
    void read_part(std::size_t k);
    void join_part(std::size_t k);
    void join_trace_parts();
    void commit(double wall);
    void print_summary(const nlohmann::json& stats) const;

    const std::chrono::steady_clock::time_point t0_;
    const SimOptions& opt_;
    const SimConfig& cfg_;
    const std::vector<JobPart>& parts_;
    Outputs out_;
    WorkerMain worker_main_;
    const bool trace_;
    unsigned threads_ = 1;
    std::unique_ptr<TempDirectory> dir_;
    std::optional<SplitDigest> split_;
    std::vector<DigestBlocks> digest_blocks_;
    std::vector<std::vector<std::string>> argvs_;
    std::vector<std::string> errs_;
    std::vector<int> out_fds_;
    bool first_direct_ = false;
    // The hashed inputs, then the hash, which reads them (destroyed the other
    // way round), before the workers, so that on an error they are stopped
    // before the hash is waited for.
    std::vector<ProvenanceInput> inputs_;
    std::future<nlohmann::json> provenance_job_;
    std::unique_ptr<Workers> workers_;
    RunSnapshot all_;
    std::vector<PartFiles> files_;
    TraceLimits limits_;
    std::uint64_t work_before_ = 0;    // declared by the parts already read
    std::uint64_t cycles_before_ = 0;  // of the parts already joined
};

} // namespace rbcd
