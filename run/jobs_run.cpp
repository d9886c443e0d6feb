#include "rbcd/run/jobs_run.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <thread>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/stats_report.h"

namespace rbcd {

namespace {

std::string range_text(const FrameRange& r) {
    return std::to_string(r.first) + ":" + (r.last == UINT64_MAX ? std::string() : std::to_string(r.last));
}

// Beside a regular output (the same file system), else in TMPDIR: a device or
// FIFO's directory (/dev) is seldom writable.
std::string workers_directory_parent(const OutputFile& collisions, const std::string& collisions_path) {
    std::string parent;
    if (collisions.active() && !collisions.in_place()) {
        std::error_code pe;
        parent = std::filesystem::absolute(collisions_path, pe).parent_path().string();
    }
    if (parent.empty()) {
        // TMPDIR as the C library reads it: unset or empty means /tmp.
        const char* tmpdir = std::getenv("TMPDIR");
        parent = tmpdir && *tmpdir ? tmpdir : "/tmp";
    }
    return parent;
}

} // namespace

JobsRun::JobsRun(const SimOptions& opt, const SimConfig& cfg, const std::vector<JobPart>& parts,
                 std::vector<ProvenanceInput> inputs, Outputs out, WorkerMain worker_main)
    : t0_(std::chrono::steady_clock::now()), opt_(opt), cfg_(cfg), parts_(parts), out_(out), worker_main_(worker_main), trace_(!opt.trace.empty()),
      inputs_(std::move(inputs)), limits_(trace_limits(cfg)) {
    // A worker reads its trace on one thread unless there are cores to spare.
    threads_ = std::thread::hardware_concurrency() >= 2 * parts.size() ? opt.threads : 1;
    dir_ = std::make_unique<TempDirectory>(workers_directory_parent(out_.collisions, opt.collisions));
    plan_split_digest();
    plan_workers();
    if (split_)
        for (ProvenanceInput& in : inputs_)
            if (in.role == "trace") in.split = &*split_;
}

JobsRun::~JobsRun() = default;

// A plain trace's digest is taken by the workers, each over the blocks of the
// bytes it reads (run/part_digest.h), and joined here when the last ends: not
// the whole file read again. Worker k hashes from the block its frames start
// in to the one the next part's start in; the last, to the file's last block,
// which is the parent's. Not for a range that ends before the file does: the
// parent would hash the rest after the last worker, where the whole file's
// hash from the first worker's end is mostly done by then.
void JobsRun::plan_split_digest() {
    if (!trace_ || !out_.stats.active() || plain_trace_bytes(opt_.trace) == 0 || parts_.back().range.last != UINT64_MAX ||
        !std::all_of(parts_.begin() + 1, parts_.end(), [](const JobPart& p) { return p.skip; }))
        return;
    const int fd = ::open(opt_.trace.c_str(), O_RDONLY | O_CLOEXEC);
    const std::optional<FileId> id = fd >= 0 ? file_id(fd) : std::nullopt;
    if (fd >= 0) ::close(fd);
    if (!id) return;
    split_.emplace();
    split_->planned = *id;
    const auto block_of = [](std::uint64_t off) { return off / xxh3_blocks::kBlockBytes * xxh3_blocks::kBlockBytes; };
    for (std::size_t k = 0; k < parts_.size(); ++k) {
        const std::uint64_t from = k == 0 ? 0 : block_of(parts_[k].offset);
        const std::uint64_t to = k + 1 < parts_.size() ? block_of(parts_[k + 1].offset)
                                                       : xxh3_blocks::chained_blocks(id->size) * xxh3_blocks::kBlockBytes;
        digest_blocks_.push_back({from, std::max(from, to)});
    }
}

// Each worker's command line, its files in the private directory. The first
// part of a trace writes its collisions straight into the output (its
// standard output, --collisions -): the largest copy of the join is not made.
// Not for a scene, which may be run again as one process after its workers
// wrote nothing worth keeping.
void JobsRun::plan_workers() {
    first_direct_ = trace_ && out_.collisions.active();
    const TempDirectory& dir = *dir_;
    for (std::size_t k = 0; k < parts_.size(); ++k) {
        const std::string n = std::to_string(k);
        std::vector<std::string> a{opt_.argv.empty() ? std::string("rbcd-sim") : opt_.argv[0]};
        if (!opt_.config_file.empty()) a.insert(a.end(), {"--config", opt_.config_file});
        for (const auto& set : opt_.sets) a.insert(a.end(), {"--set", set});
        if (trace_) a.insert(a.end(), {"--trace", opt_.trace});
        else if (!opt_.scene.empty()) a.insert(a.end(), {"--scene", opt_.scene});
        a.insert(a.end(), {"--frames", range_text(parts_[k].range), "--threads", std::to_string(threads_), "-q",
                           "--stats", dir.path(n + ".json"), "--frame-stats", dir.path(n + ".jsonl"),
                           "--worker-part", worker_part_text(parts_[k], trace_)});
        if (opt_.gpu_stepwise) a.push_back("--gpu-stepwise");
        if (trace_ && k + 1 < parts_.size()) a.insert(a.end(), {"--worker-stop-at", std::to_string(parts_[k + 1].offset)});
        if (split_) {
            a.insert(a.end(), {"--worker-digest", worker_digest_text(digest_blocks_[k])});
            if (digest_blocks_[k].from > 0) {
                a.insert(a.end(), {"--worker-digest-sums", dir.path(n + ".xxh")});
                dir_->will_hold(n + ".xxh");
            }
        }
        if (k == 0 && first_direct_) {
            a.insert(a.end(), {"--collisions", "-", "--worker-collisions-name", opt_.collisions});
            out_fds_.push_back(out_.collisions.shared_fd());
        } else {
            // Its write errors name the run's output, whose file system it fills.
            if (out_.collisions.active())
                a.insert(a.end(), {"--collisions", dir.path(n + ".txt"), "--worker-collisions-name", opt_.collisions});
            out_fds_.push_back(-1);
        }
        argvs_.push_back(std::move(a));
        errs_.push_back(dir.path(n + ".err"));
        for (const char* ext : {".json", ".jsonl", ".txt", ".err"}) dir_->will_hold(n + ext);
    }
}

// Without the workers' digest (a gzip trace, whose parts start in the
// inflated bytes; a scene's meshes), the inputs are hashed whole, from when
// the first worker ends: before, the hash would take a core from them (as
// many workers as cores); after, it has the core that worker leaves, beside
// the join.
void JobsRun::start_hash() {
    // The hashing thread starts with the interrupts blocked: the handler,
    // which signals the workers, runs on this thread only, never beside the
    // joins that forget and reap them.
    const InterruptsHeld held;
    provenance_job_ = std::async(std::launch::async, [this] { return make_provenance(opt_.argv, cfg_, inputs_); });
}

// A trace's bound on the run's declared work (docs/limits.md) is one
// process's: each worker counts its own frames' work, the parts' sums are
// added in frame order, and the part that crosses the bound is read again
// from the work before it, which raises the error one process raises.
// Part k's frames read again from the work before them: throws the first
// error one process meets there; returns when there is none.
void JobsRun::read_again(std::size_t k) {
    TraceReader again(opt_.trace, limits_);
    if (parts_[k].skip) again.start_at_frame(parts_[k].range.first, parts_[k].offset, parts_[k].line);
    again.stop_after_frame(parts_[k].range.last);
    again.count_work_from(work_before_);
    Tile t;
    while (again.next(t) != FragmentSource::Event::End) {}
}

void JobsRun::check_work(std::size_t k, const nlohmann::json& j) {
    if (!trace_ || limits_.max_work_cycles == 0) return;
    const std::uint64_t w = j.at("worker").at("declared_work").get<std::uint64_t>();
    std::uint64_t sum = 0;
    if (!__builtin_add_overflow(work_before_, w, &sum) && sum <= limits_.max_work_cycles) {
        work_before_ = sum;
        return;
    }
    read_again(k);
    throw RunError("--jobs: part " + std::to_string(k) + " declared less work when read again");
}

void JobsRun::read_part(std::size_t k) {
    const std::string n = std::to_string(k);
    const std::string path = dir_->path(n + ".json");
    const nlohmann::json j = nlohmann::json::parse(read_input_text(path, "stats file", std::uint64_t(1) << 30, ""));
    check_work(k, j);
    if (split_) {
        if (!j.contains("worker") || !j["worker"].contains("digest"))
            throw RunError("--jobs: part " + n + " did not say its blocks of the trace's digest");
        split_->add(j["worker"]["digest"], dir_->path(n + ".xxh"));
    }
    RunSnapshot snap = snapshot_from_stats(j);
    files_.push_back({dir_->path(n + ".txt"), dir_->path(n + ".jsonl"), snap.frames.first_frame, snap.frames.frames,
                      snap.cycles});
    if (k == 0) all_ = std::move(snap);
    else merge_snapshots(all_, snap);
}

void JobsRun::join_part(std::size_t k) {
    if (out_.collisions.active() && !(k == 0 && first_direct_))
        append_own_part_collisions(files_[k], k == 0, out_.collisions);
    if (out_.frame_stats.active()) append_part_frame_stats(files_[k], cycles_before_, out_.frame_stats);
    cycles_before_ += files_[k].cycles;
}

// A part is joined as soon as it and the parts before it are done, while the
// later ones still run: only the last part's join is left when the last
// worker ends. A failed part stops the joining; wait() reports the first
// failure, and the outputs are abandoned.
void JobsRun::join_trace_parts() {
    for (std::size_t k = 0; k < parts_.size(); ++k) {
        if (!workers_->wait_for(k)) {
            // A worker that refused its input counted its frames' work from
            // zero; one process, counting from the frames before them, may
            // cross the bound before the error the worker met.
            if (work_before_ > 0 && workers_->refused_input(k)) read_again(k);
            break;
        }
        read_part(k);
        // Every part's digest is in: joined beside the last part's join.
        if (split_ && k + 1 == parts_.size()) start_hash();
        join_part(k);
    }
    workers_->wait();
}

bool JobsRun::run(nlohmann::json& provenance) {
    workers_ = std::make_unique<Workers>(worker_main_, argvs_, errs_, out_fds_);
    // (Waited for without reaping: the joins reap the workers in order.) A
    // worker that failed fails the run: nothing to hash for.
    if (out_.stats.active() && !split_ && (!trace_ || workers_->first_end_ok())) start_hash();
    if (trace_) {
        join_trace_parts();
    } else {
        // A scene whose parts hold no fragment at all is run again as one
        // process: nothing is written before that is known.
        workers_->wait();
        for (std::size_t k = 0; k < parts_.size(); ++k) read_part(k);
        if (all_.counters.raster.fragments + all_.counters.raster.other_fragments == 0) {
            // The same inputs and command line as the one process that follows:
            // its provenance, not hashed again.
            if (provenance_job_.valid()) provenance = provenance_job_.get();
            return false;
        }
        for (std::size_t k = 0; k < parts_.size(); ++k) join_part(k);
    }
    commit(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count());
    return true;
}

void JobsRun::commit(double wall) {
    nlohmann::json stats = make_stats(all_, wall);
    if (provenance_job_.valid()) stats["provenance"] = provenance_job_.get();
    if (out_.collisions.active()) out_.collisions.commit();
    if (out_.frame_stats.active()) out_.frame_stats.commit();
    if (out_.stats.active()) {
        out_.stats.write(stats.dump(2) + "\n");
        out_.stats.commit();
    }
    outputs_complete();
    if (!opt_.quiet) print_summary(stats);
}

// The summary's frame rows from the workers' per-frame lines.
void JobsRun::print_summary(const nlohmann::json& stats) const {
    SummaryFrames sf;
    sf.totals = snapshot_totals(all_);
    sf.frames = all_.frames.frames;
    sf.mean_overhead_pct = all_.frames.mean_overhead_pct();
    const bool worst = all_.frames.has_worst;
    for (const PartFiles& p : files_) {
        const bool has_worst =
            worst && all_.frames.worst_frame >= p.first_frame && all_.frames.worst_frame - p.first_frame < p.frames;
        if (sf.first.size() >= RunReport::kFirstFrames && !has_worst) continue;
        std::ifstream in(p.frame_stats);
        std::string line;
        while (std::getline(in, line)) {
            nlohmann::json f = nlohmann::json::parse(line);
            const std::uint64_t n = f.value("frame", std::uint64_t(0));
            if (has_worst && n == all_.frames.worst_frame) sf.worst = f;
            if (sf.first.size() < RunReport::kFirstFrames) sf.first.push_back(std::move(f));
            else if (!has_worst || n >= all_.frames.worst_frame) break;
        }
    }
    std::fputs(make_summary(stats, sf).c_str(), stdout);
}

} // namespace rbcd
