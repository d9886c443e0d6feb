// rbcd-sim: runs the RBCD unit model over a fragment trace or a 3D scene
// (formats.md, "Command line"). Exit 0 done, 2 bad input/config/command line,
// 1 anything else; on a non-zero exit no output file is left behind.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <future>
#include <optional>
#include <fcntl.h>
#include <sys/wait.h>
#include <memory>
#include <system_error>
#include <thread>
#include <systemc>
#include <sys/stat.h>
#include <unistd.h>
#include <utility>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/io/prefetch_source.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/io/frame_range_source.h"
#include "rbcd/common/input_file.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/trace_writer.h"
#include "rbcd/sc_main/collision_file.h"
#include "rbcd/sc_main/fst_writer.h"
#include "rbcd/sc_main/gtkwave_layout.h"
#include "rbcd/sc_main/heat_maps.h"
#include "rbcd/sc_main/tile_database.h"
#include "rbcd/sc_main/image_sink.h"
#include "rbcd/sc_main/jobs.h"
#include "rbcd/sc_main/part_digest.h"
#include "rbcd/sc_main/part_files.h"
#include "rbcd/report/run_snapshot.h"
#include "rbcd/sc_main/output_file.h"
#include "rbcd/sc_main/progress.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/stats_report.h"
#include "rbcd/sc_main/provenance.h"
#include "rbcd/sc_main/sanitizer_stack.h"
#include "rbcd/hw/rbcd_system.h"
#include "rbcd/hw/self_check.h"

int rbcd_sim_main(const std::vector<std::string>& args);

namespace {

// The kernel prints its banner before sc_main runs; it would precede every
// summary and --dump-config. Static initialisation of the program comes first.
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();

struct Options {
    std::string config_file;
    std::vector<std::string> sets;
    std::string trace, scene, collisions, stats, frame_stats, write_trace, images, vcd, fst, gtkw, db, heat_maps;
    std::string frames;   // --frames A:B
    bool frames_given = false;   // --frames '' is an error, not "all frames"
    unsigned threads = 2;  // 2: a trace is parsed on its own thread
    unsigned jobs = 1;     // worker processes, each a contiguous range of the frames (sc_main/jobs.h)
    std::string worker_part;   // set in a worker: where its frames start (jobs.h)
    std::string worker_collisions_name;   // a worker's --collisions -: the run's output, named in errors
    std::string worker_digest;        // a worker's part of the trace's digest, FROM:TO (part_digest.h)
    std::string worker_digest_sums;   // where a later part's block sums go
    bool dump_config = false;
    bool config_reference = false;
    bool quiet = false;
    std::vector<std::string> argv;   // for the stats' provenance
};

// The directories a run made for its outputs (--images, --heat-maps): a
// failed run removes those it made, once their files are gone, so that it
// leaves no empty output directory behind.
struct MadeDirectories {
    std::vector<std::string> made;   // deepest first
    bool keep = false;
    MadeDirectories() = default;
    MadeDirectories(const MadeDirectories&) = delete;
    MadeDirectories& operator=(const MadeDirectories&) = delete;
    ~MadeDirectories() {
        if (keep) return;
        for (const auto& d : made) ::rmdir(d.c_str());   // fails, as it should, on one not empty
    }
};

void make_directory(const std::string& dir, MadeDirectories& made) {
    std::error_code ec;
    std::vector<std::string> missing;
    for (std::filesystem::path p = dir; !p.empty() && !std::filesystem::exists(std::filesystem::symlink_status(p, ec));
         p = p.parent_path()) {
        missing.push_back(p.string());
        if (p == p.parent_path()) break;
    }
    std::filesystem::create_directories(dir, ec);
    // Recorded before the check: levels made before a failure go too.
    made.made.insert(made.made.begin(), missing.begin(), missing.end());
    if (ec || !std::filesystem::is_directory(dir))
        throw rbcd::InputError(dir + ": cannot create directory: " + (ec ? ec.message() : "not a directory"));
}

void quiet_kernel() {
    // sc_stop() and end-of-simulation notes are not the user's business.
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
}

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

// The GTKWave save file: --gtkw, else beside a waveform written through a
// temporary (run.fst -> run.gtkw); its state filter beside it. Empty: none.
std::pair<std::string, std::string> layout_paths(const std::string& gtkw, const std::string& wave) {
    std::string path = gtkw;
    if (path.empty() && !wave.empty() && wave != "-") {
        struct stat st {};
        const bool regular_or_new = ::lstat(wave.c_str(), &st) != 0 || S_ISREG(st.st_mode);
        if (regular_or_new) {
            const std::size_t dot = wave.rfind('.'), slash = wave.rfind('/');
            const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash);
            path = (has_ext ? wave.substr(0, dot) : wave) + ".gtkw";
        }
    }
    if (path.empty()) return {};
    return {path, rbcd::GtkwaveLayout::filter_path_for(path)};
}

std::string range_text(const rbcd::FrameRange& r) {
    return std::to_string(r.first) + ":" + (r.last == UINT64_MAX ? std::string() : std::to_string(r.last));
}

// --jobs: the parts run by workers (sc_main/jobs.h) and their files joined
// into the outputs, which are already open. False when the parts' frames hold
// no fragment at all (the caller then runs as one process: see there), with
// the provenance already computed in `provenance` (null when none was).
bool run_jobs(const Options& opt, const std::vector<rbcd::JobPart>& parts,
              const std::vector<rbcd::ProvenanceInput>& prov_inputs, const rbcd::SimConfig& cfg,
              rbcd::OutputFile& collisions_out, rbcd::OutputFile& stats_out, rbcd::OutputFile& frame_stats_out,
              nlohmann::json& provenance) {
    using namespace rbcd;
    const auto t0 = std::chrono::steady_clock::now();
    // A worker reads its trace on one thread unless there are cores to spare.
    const unsigned threads = std::thread::hardware_concurrency() >= 2 * parts.size() ? opt.threads : 1;
    const bool trace = !opt.trace.empty();
    // Beside a regular output (the same file system), else in TMPDIR: a
    // device or FIFO's directory (/dev) is seldom writable.
    std::string parent;
    if (collisions_out.active() && !collisions_out.in_place()) {
        std::error_code pe;
        parent = std::filesystem::absolute(opt.collisions, pe).parent_path().string();
    }
    if (parent.empty()) {
        // TMPDIR as the C library reads it: unset or empty means /tmp.
        const char* tmpdir = std::getenv("TMPDIR");
        parent = tmpdir && *tmpdir ? tmpdir : "/tmp";
    }
    TempDirectory dir(parent);
    // A plain trace's digest is taken by the workers, each over the blocks of
    // the bytes it reads (sc_main/part_digest.h), and joined here when the
    // last ends: not the whole file read again. Worker k hashes from the block
    // its frames start in to the one the next part's start in; the last, to
    // the file's last block, which is the parent's.
    std::optional<SplitDigest> split;
    std::vector<DigestBlocks> digest_blocks;
    // Not for a range that ends before the file does: the parent would hash
    // the rest after the last worker, where the whole file's hash from the
    // first worker's end is mostly done by then.
    if (trace && stats_out.active() && plain_trace_bytes(opt.trace) > 0 && parts.back().range.last == UINT64_MAX &&
        std::all_of(parts.begin() + 1, parts.end(), [](const JobPart& p) { return p.skip; })) {
        const int fd = ::open(opt.trace.c_str(), O_RDONLY | O_CLOEXEC);
        const std::optional<FileId> id = fd >= 0 ? file_id(fd) : std::nullopt;
        if (fd >= 0) ::close(fd);
        if (id) {
            split.emplace();
            split->planned = *id;
            const auto block_of = [](std::uint64_t off) { return off / xxh3_blocks::kBlockBytes * xxh3_blocks::kBlockBytes; };
            for (std::size_t k = 0; k < parts.size(); ++k) {
                const std::uint64_t from = k == 0 ? 0 : block_of(parts[k].offset);
                const std::uint64_t to = k + 1 < parts.size() ? block_of(parts[k + 1].offset)
                                                              : xxh3_blocks::chained_blocks(id->size) * xxh3_blocks::kBlockBytes;
                digest_blocks.push_back({from, std::max(from, to)});
            }
        }
    }
    std::vector<std::vector<std::string>> argvs;
    std::vector<std::string> errs;
    std::vector<int> out_fds;
    // The first part of a trace writes its collisions straight into the
    // output (its standard output, --collisions -): the largest copy of the
    // join is not made. Not for a scene, which may be run again as one
    // process (below) after its workers wrote nothing worth keeping.
    const bool first_direct = trace && collisions_out.active();
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const std::string n = std::to_string(k);
        std::vector<std::string> a{opt.argv.empty() ? std::string("rbcd-sim") : opt.argv[0]};
        if (!opt.config_file.empty()) a.insert(a.end(), {"--config", opt.config_file});
        for (const auto& set : opt.sets) a.insert(a.end(), {"--set", set});
        if (trace) a.insert(a.end(), {"--trace", opt.trace});
        else if (!opt.scene.empty()) a.insert(a.end(), {"--scene", opt.scene});
        a.insert(a.end(), {"--frames", range_text(parts[k].range), "--threads", std::to_string(threads), "-q",
                           "--stats", dir.path(n + ".json"), "--frame-stats", dir.path(n + ".jsonl"),
                           "--worker-part", worker_part_text(parts[k], trace)});
        if (split) {
            a.insert(a.end(), {"--worker-digest", worker_digest_text(digest_blocks[k])});
            if (digest_blocks[k].from > 0) {
                a.insert(a.end(), {"--worker-digest-sums", dir.path(n + ".xxh")});
                dir.will_hold(n + ".xxh");
            }
        }
        if (k == 0 && first_direct) {
            a.insert(a.end(), {"--collisions", "-", "--worker-collisions-name", opt.collisions});
            out_fds.push_back(collisions_out.shared_fd());
        } else {
            // Its write errors name the run's output, whose file system it fills.
            if (collisions_out.active())
                a.insert(a.end(), {"--collisions", dir.path(n + ".txt"), "--worker-collisions-name", opt.collisions});
            out_fds.push_back(-1);
        }
        argvs.push_back(std::move(a));
        errs.push_back(dir.path(n + ".err"));
        for (const char* ext : {".json", ".jsonl", ".txt", ".err"}) dir.will_hold(n + ext);
    }
    // The hashed inputs, then the hash, which reads them (destroyed the other
    // way round), before the workers, so that on an error they are stopped
    // before the hash is waited for.
    std::vector<ProvenanceInput> inputs = prov_inputs;
    if (split)
        for (ProvenanceInput& in : inputs)
            if (in.role == "trace") in.split = &*split;
    std::future<nlohmann::json> provenance_job;
    Workers workers(rbcd_sim_main, argvs, errs, out_fds);
    // Without the workers' digest (a gzip trace, whose parts start in the
    // inflated bytes; a scene's meshes), the inputs are hashed whole, from
    // when the first worker ends: before, the hash would take a core from
    // them (as many workers as cores); after, it has the core that worker
    // leaves, beside the join (docs/performance.md, seventh pass).
    const auto start_hash = [&] {
        // The hashing thread starts with the interrupts blocked: the handler,
        // which signals the workers, runs on this thread only, never beside
        // the joins that forget and reap them.
        const InterruptsHeld held;
        provenance_job = std::async(std::launch::async, [&] { return make_provenance(opt.argv, cfg, inputs); });
    };
    // (Waited for without reaping: the joins below reap the workers in
    // order.) A worker that failed fails the run: nothing to hash for.
    if (stats_out.active() && !split && (!trace || workers.first_end_ok())) start_hash();

    RunSnapshot all;
    std::vector<PartFiles> files;
    // A trace's bound on the run's declared work (docs/limits.md) is one
    // process's: each worker counts its own frames' work, the parts' sums are
    // added in frame order, and the part that crosses the bound is read again
    // from the work before it, which raises the error one process raises.
    const TraceLimits limits = trace_limits(cfg);
    std::uint64_t work_before = 0;   // declared by the parts already read
    // Part k's frames read again from the work before them: throws the first
    // error one process meets there; returns when there is none.
    const auto read_again = [&](std::size_t k) {
        TraceReader again(opt.trace, limits);
        if (parts[k].skip) again.start_at_frame(parts[k].range.first, parts[k].offset, parts[k].line);
        again.stop_after_frame(parts[k].range.last);
        again.count_work_from(work_before);
        Tile t;
        while (again.next(t) != FragmentSource::Event::End) {}
    };
    const auto check_work = [&](std::size_t k, const nlohmann::json& j) {
        if (!trace || limits.max_work_cycles == 0) return;
        const std::uint64_t w = j.at("worker").at("declared_work").get<std::uint64_t>();
        std::uint64_t sum = 0;
        if (!__builtin_add_overflow(work_before, w, &sum) && sum <= limits.max_work_cycles) {
            work_before = sum;
            return;
        }
        read_again(k);
        throw RunError("--jobs: part " + std::to_string(k) + " declared less work when read again");
    };
    const auto read_part = [&](std::size_t k) {
        const std::string n = std::to_string(k);
        const std::string path = dir.path(n + ".json");
        const nlohmann::json j = nlohmann::json::parse(read_input_text(path, "stats file", std::uint64_t(1) << 30, ""));
        check_work(k, j);
        if (split) {
            if (!j.contains("worker") || !j["worker"].contains("digest"))
                throw RunError("--jobs: part " + n + " did not say its blocks of the trace's digest");
            split->add(j["worker"]["digest"], dir.path(n + ".xxh"));
        }
        RunSnapshot snap = snapshot_from_stats(j);
        files.push_back({dir.path(n + ".txt"), dir.path(n + ".jsonl"), snap.frames.first_frame, snap.frames.frames,
                         snap.cycles});
        if (k == 0) all = std::move(snap);
        else merge_snapshots(all, snap);
    };
    std::uint64_t cycles_before = 0;   // of the parts already joined
    const auto join_part = [&](std::size_t k) {
        if (collisions_out.active() && !(k == 0 && first_direct))
            append_own_part_collisions(files[k], k == 0, collisions_out);
        if (frame_stats_out.active()) append_part_frame_stats(files[k], cycles_before, frame_stats_out);
        cycles_before += files[k].cycles;
    };
    if (trace) {
        // A part is joined as soon as it and the parts before it are done,
        // while the later ones still run: only the last part's join is left
        // when the last worker ends. A failed part stops the joining; wait()
        // reports the first failure, and the outputs are abandoned.
        for (std::size_t k = 0; k < parts.size(); ++k) {
            if (!workers.wait_for(k)) {
                // A worker that refused its input counted its frames' work
                // from zero; one process, counting from the frames before
                // them, may cross the bound before the error the worker met.
                if (work_before > 0 && workers.refused_input(k)) read_again(k);
                break;
            }
            read_part(k);
            // Every part's digest is in: joined beside the last part's join.
            if (split && k + 1 == parts.size()) start_hash();
            join_part(k);
        }
        workers.wait();
    } else {
        // A scene whose parts hold no fragment at all is run again as one
        // process (below): nothing is written before that is known.
        workers.wait();
        for (std::size_t k = 0; k < parts.size(); ++k) read_part(k);
        if (all.counters.raster.fragments + all.counters.raster.other_fragments == 0) {
            // The same inputs and command line as the one process that follows:
            // its provenance, not hashed again.
            if (provenance_job.valid()) provenance = provenance_job.get();
            return false;
        }
        for (std::size_t k = 0; k < parts.size(); ++k) join_part(k);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    nlohmann::json stats = make_stats(all, wall);
    if (provenance_job.valid()) stats["provenance"] = provenance_job.get();
    if (collisions_out.active()) collisions_out.commit();
    if (frame_stats_out.active()) frame_stats_out.commit();
    if (stats_out.active()) {
        stats_out.write(stats.dump(2) + "\n");
        stats_out.commit();
    }
    outputs_complete();
    if (!opt.quiet) {
        // The summary's frame rows from the workers' per-frame lines.
        SummaryFrames sf;
        sf.totals = snapshot_totals(all);
        sf.frames = all.frames.frames;
        sf.mean_overhead_pct = all.frames.mean_overhead_pct();
        const bool worst = all.frames.has_worst;
        for (const PartFiles& p : files) {
            const bool has_worst = worst && all.frames.worst_frame >= p.first_frame &&
                                   all.frames.worst_frame - p.first_frame < p.frames;
            if (sf.first.size() >= RunReport::kFirstFrames && !has_worst) continue;
            std::ifstream in(p.frame_stats);
            std::string line;
            while (std::getline(in, line)) {
                nlohmann::json f = nlohmann::json::parse(line);
                const std::uint64_t n = f.value("frame", std::uint64_t(0));
                if (has_worst && n == all.frames.worst_frame) sf.worst = f;
                if (sf.first.size() < RunReport::kFirstFrames) sf.first.push_back(std::move(f));
                else if (!has_worst || n >= all.frames.worst_frame) break;
            }
        }
        std::fputs(make_summary(stats, sf).c_str(), stdout);
    }
    return true;
}

int run(Options opt) {
    using namespace rbcd;
    // --vcd run.fst: the format follows the file's extension.
    if (ends_with(opt.vcd, ".fst")) {
        if (!opt.fst.empty()) throw InputError("--vcd: " + opt.vcd + " is an FST file and --fst is given too");
        opt.fst = std::exchange(opt.vcd, std::string());
    }
    if (!opt.fst.empty() && !opt.vcd.empty())
        throw InputError("--fst: cannot be combined with --vcd (one waveform a run)");
    if (!opt.fst.empty() && !fst_supported())
        throw InputError("--fst: this rbcd-sim was built without FST support (install Debian's verilator package: "
                         "scripts/setup.sh --waves, then rebuild)");
    if (!opt.db.empty() && !sqlite_supported())
        throw InputError("--db: this rbcd-sim was built without SQLite (install Debian's libsqlite3-dev: "
                         "scripts/setup.sh --waves, then rebuild)");
    if (!opt.gtkw.empty() && opt.vcd.empty() && opt.fst.empty())
        throw InputError("--gtkw: needs a waveform (--vcd or --fst)");
    const auto [gtkw_path, filter_path] = layout_paths(opt.gtkw, opt.fst.empty() ? opt.vcd : opt.fst);
    SimConfig cfg;
    if (!opt.config_file.empty()) apply_config_file(cfg, opt.config_file);
    for (const auto& s : opt.sets) apply_config_set(cfg, s);
    cfg.validate();

    if (opt.config_reference) {
        std::fputs(config_reference_markdown().c_str(), stdout);
        return 0;
    }
    if (opt.dump_config) {
        std::fputs(dump_config_toml(cfg).c_str(), stdout);
        return 0;
    }

    if (opt.jobs > 1) {
        // Outputs that only one process can write: refused rather than run on one core unasked.
        const std::pair<const char*, const std::string*> whole[] = {
            {"--vcd", &opt.vcd},     {"--fst", &opt.fst},           {"--gtkw", &opt.gtkw},
            {"--db", &opt.db},       {"--images", &opt.images},     {"--heat-maps", &opt.heat_maps},
            {"--write-trace", &opt.write_trace}};
        for (const auto& [flag, path] : whole)
            if (!path->empty())
                throw InputError(std::string("--jobs: cannot be combined with ") + flag +
                                 " (written by one process; use --jobs 1)");
        if (opt.trace == "-") throw InputError("--jobs: cannot split standard input (--trace -); use --jobs 1");
    }
    const bool worker = !opt.worker_part.empty();
    if (worker && !opt.frames_given) throw InputError("--worker-part: needs --frames");
    if (!worker && !opt.worker_collisions_name.empty())
        throw InputError("--worker-collisions-name: only for a --jobs worker (with --worker-part)");
    if ((!worker || opt.trace.empty()) && !opt.worker_digest.empty())
        throw InputError("--worker-digest: only for a --jobs worker of a trace (with --worker-part and --trace)");
    if (opt.worker_digest.empty() && !opt.worker_digest_sums.empty())
        throw InputError("--worker-digest-sums: only with --worker-digest");

    // An output over an input (a scene's meshes too) would destroy it before
    // it is read; two outputs in one file would leave only the last written.
    const scene::SceneLimits scene_limits{cfg.tile.width,           cfg.tile.height,
                                          cfg.zeb.id_bits,          cfg.input.max_scene_bytes,
                                          cfg.input.max_scene_triangles, cfg.input.max_tile_fragments};
    std::vector<NamedPath> inputs{{"", opt.trace}, {"", opt.scene}, {"", opt.config_file}};
    if (!opt.scene.empty())
        for (const std::string& mesh : scene::SceneSource::mesh_files_of(opt.scene, scene_limits))
            inputs.push_back({"", mesh});
    check_output_paths({{"--collisions", opt.collisions},
                        {"--stats", opt.stats},
                        {"--frame-stats", opt.frame_stats},
                        {"--vcd", opt.vcd},
                        {"--fst", opt.fst},
                        {"--gtkw", gtkw_path},
                        {"--gtkw", filter_path},
                        {"--db", opt.db},
                        {"--write-trace", opt.write_trace}},
                       inputs);

    // Outputs are created before the run so an uncreatable path fails fast.
    OutputFile collisions_out, stats_out, frame_stats_out, vcd_out, fst_out;
    if (!opt.collisions.empty()) collisions_out = OutputFile(opt.collisions);
    if (!opt.worker_collisions_name.empty()) collisions_out.show_as(opt.worker_collisions_name);
    if (!opt.stats.empty()) stats_out = OutputFile(opt.stats);
    if (!opt.frame_stats.empty()) frame_stats_out = OutputFile(opt.frame_stats);
    if (!opt.vcd.empty()) vcd_out = OutputFile(opt.vcd);
    std::unique_ptr<FstWriter> fst;
    if (!opt.fst.empty()) {
        fst_out = OutputFile(opt.fst, OutputFile::ByName{});
        fst = std::make_unique<FstWriter>(fst_out.library_path(), opt.fst);
    }
    OutputFile db_out;
    std::unique_ptr<TileDatabase> db;
    if (!opt.db.empty()) {
        db_out = OutputFile(opt.db, OutputFile::ByName{});
        db = std::make_unique<TileDatabase>(db_out.library_path(), opt.db, cfg.tile.width, cfg.tile.height);
    }
    OutputFile gtkw_out, filter_out;
    if (!gtkw_path.empty()) {
        gtkw_out = OutputFile(gtkw_path);
        filter_out = OutputFile(filter_path);
    }

    const FrameRange range = opt.frames_given ? parse_frame_range(opt.frames) : FrameRange{};
    const JobPart part = worker ? parse_worker_part(opt.worker_part, range) : JobPart{};
    // A trace read from its first byte is hashed as it is read, and the
    // provenance reads only what the reader did not (docs/provenance.md):
    // one process writing stats (not for --db, which records the provenance
    // before the run, nor --frames, whose reader stops early). So standard
    // input, which cannot be read again, gets a digest too.
    // Declared before the reader, which holds it.
    std::unique_ptr<ReadDigest> read_digest;
    if (!opt.trace.empty() && !worker && stats_out.active() && !opt.frames_given && opt.db.empty())
        read_digest = std::make_unique<ReadDigest>();
    // A --jobs worker's blocks of that digest, from the bytes it reads (part_digest.h).
    std::unique_ptr<PartDigest> part_digest;
    if (!opt.worker_digest.empty()) {
        const DigestBlocks b = parse_worker_digest(opt.worker_digest, opt.worker_digest_sums);
        part_digest = std::make_unique<PartDigest>(b.from, b.to, opt.worker_digest_sums);
    }
    RawObserver* const read_observer = read_digest ? static_cast<RawObserver*>(read_digest.get()) : part_digest.get();
    std::unique_ptr<FragmentSource> src;
    scene::SceneSource* scene_src = nullptr;
    std::vector<JobPart> parts;   // more than one: the frames are the workers'
    TraceReader* trace_reader = nullptr;   // the trace's reader, when one process runs it
    if (!opt.trace.empty()) {
        if (opt.jobs > 1) {
            // A plain file is read only near the cuts; a gzip one (or a range
            // to find) needs a pass over the data, fragments unparsed.
            FrameScan scan;
            if (const std::uint64_t bytes = opt.frames_given ? 0 : plain_trace_bytes(opt.trace)) {
                std::vector<std::uint64_t> cuts;
                for (unsigned k = 1; k < opt.jobs; ++k) cuts.push_back(bytes / opt.jobs * k + bytes % opt.jobs * k / opt.jobs);
                scan = find_frames_near(opt.trace, cuts);
            }
            if (!scan.ok) scan = scan_frames(opt.trace);
            parts = plan_trace_parts(scan, range, opt.jobs);
        }
        if (parts.size() < 2) {
            // Parsed a few tiles ahead on another core (io/prefetch_source.h),
            // unless the cores are the caller's to share (rbcd-sweep's workers).
            auto reader = std::make_unique<TraceReader>(opt.trace, trace_limits(cfg), read_observer);
            // A plain trace's line number is counted only if a message needs it.
            if (part.skip) reader->start_at_frame(range.first, part.offset, part.line);
            // Not even read ahead: what follows the range is another worker's.
            if (opt.frames_given) reader->stop_after_frame(range.last);
            trace_reader = reader.get();
            if (opt.threads > 1) src = std::make_unique<PrefetchSource>(std::move(reader));
            else src = std::move(reader);
        }
    } else {
        auto s = opt.scene.empty()
                     ? scene::SceneSource::from_text(scene::default_scene_text(), "", "<default scene>", scene_limits)
                     : std::make_unique<scene::SceneSource>(opt.scene, scene_limits);
        // No frame outside the range is rendered: one process looks at the
        // frames before it only to say "nothing in view" (scene_source.h).
        // A range past the end is refused before any frame is.
        if (range.first >= s->frame_count()) throw no_frame_selected(range, s->frame_count());
        if (part.skip) s->start_at_frame(range.first);
        else if (!worker && range.first > 0)
            s->start_at_frame(range.first, scene::SceneSource::BeforeStart::LookIfEmpty);
        if (opt.frames_given) s->stop_after_frame(range.last);
        if (opt.jobs > 1) parts = plan_scene_parts(s->frame_count(), range, opt.jobs);
        scene_src = s.get();
        src = std::move(s);
    }
    // The files the run read, for provenance (docs/provenance.md); the default
    // scene is named and hashed from its text.
    const std::string default_scene = scene::default_scene_text();
    const auto provenance_inputs = [&](const std::string& input_name) {
        std::vector<ProvenanceInput> inputs;
        if (!opt.config_file.empty()) inputs.push_back({"config", opt.config_file});
        if (!opt.trace.empty()) {
            inputs.push_back({"trace", opt.trace, nullptr, read_digest.get()});
            if (opt.trace != "-") inputs.back().expected = file_id_at(opt.trace);
        }
        else if (opt.scene.empty()) inputs.push_back({"scene", input_name, &default_scene});
        else inputs.push_back({"scene", opt.scene});
        if (scene_src)
            for (const auto& m : scene_src->mesh_files()) inputs.push_back({"mesh", m});
        return inputs;
    };
    nlohmann::json provenance;   // for stats_out (computed by run_jobs, or below)
    if (parts.size() >= 2) {
        const auto prov_inputs = provenance_inputs(src ? src->name() : opt.trace);
        if (run_jobs(opt, parts, prov_inputs, cfg, collisions_out, stats_out, frame_stats_out, provenance))
            return 0;
        // No fragment in any of the parts' frames: whether the scene has none
        // at all is one process's to say (it looks at every frame).
    }
    if (!src) {
        auto reader = std::make_unique<TraceReader>(opt.trace, trace_limits(cfg), read_digest.get());
        if (opt.threads > 1) src = std::make_unique<PrefetchSource>(std::move(reader));
        else src = std::move(reader);
    }
    if (opt.frames_given) {
        // A trace's frames count from 0: a range written out would not read back.
        if (!opt.write_trace.empty()) throw InputError("--frames: cannot be combined with --write-trace");
        src = std::make_unique<FrameRangeSource>(std::move(src), parse_frame_range(opt.frames));
    }
    const std::string input_name = src->name();
    // Inputs are hashed now, as they were read, and only for a stats file
    // (docs/provenance.md).
    const auto prov_inputs = provenance_inputs(input_name);
    // With a second core to use, the hashing (a trace's every byte) runs beside
    // the simulation instead of before it; the database records it up front.
    std::future<nlohmann::json> provenance_job;
    if (worker) {
        // The run's provenance is the one that started the workers.
    } else if (!provenance.is_null()) {
        // Computed by the workers' run that found nothing to simulate.
    } else if (read_digest) {
        // Hashed as it is read: finished after the run.
    } else if (db || (stats_out.active() && opt.threads == 1)) provenance = make_provenance(opt.argv, cfg, prov_inputs);
    else if (stats_out.active())
        provenance_job = std::async(std::launch::async, [&] { return make_provenance(opt.argv, cfg, prov_inputs); });
    if (db) {
        db->run_fact("input", input_name);
        db->run_fact("config", dump_config_toml(cfg));
        db->run_fact("provenance", provenance.dump(2));
        db->run_fact("tile_width", std::to_string(cfg.tile.width));
        db->run_fact("tile_height", std::to_string(cfg.tile.height));
        db->run_fact("screen_width", std::to_string(src->header().screen_w));
        db->run_fact("screen_height", std::to_string(src->header().screen_h));
    }

    std::unique_ptr<CollisionFileSink> file_sink;
    TeeSink tee;
    if (collisions_out.active()) {
        file_sink = std::make_unique<CollisionFileSink>(collisions_out);
        tee.add(file_sink.get());
    }
    MadeDirectories made_dirs;   // removed after the files in them, on failure
    std::unique_ptr<ImageSink> images;
    if (!opt.images.empty()) {
        if (!scene_src) throw InputError("--images: needs a scene (--scene, or no --trace)");
        make_directory(opt.images, made_dirs);
        scene_src->enable_images(true);
        images = std::make_unique<ImageSink>(*scene_src, opt.images, cfg.tile.width, cfg.tile.height);
        tee.add(images.get());
    }
    CollisionSink* sink = &tee;
    // Heat maps into --heat-maps DIR: summed over the run; with --images, also
    // each frame's (the images directory keeps one PNG a frame: scripts count them).
    std::unique_ptr<HeatMaps> heat;
    if (!opt.heat_maps.empty()) {
        make_directory(opt.heat_maps, made_dirs);
        heat = std::make_unique<HeatMaps>(opt.heat_maps, !opt.images.empty(), src->header().screen_w,
                                          src->header().screen_h, cfg.tile.width, cfg.tile.height);
    }

    // --write-trace: the stream the unit saw, replayable with --trace.
    std::unique_ptr<TraceWriter> trace_out;
    OutputFile trace_file;   // the temporary beside the path, or the path itself when not a regular file
    if (!opt.write_trace.empty()) {
        trace_file = OutputFile(opt.write_trace);
        trace_out = std::make_unique<TraceWriter>(trace_file.shared_fd(), src->header(), false, opt.write_trace);
    }
    struct ImageGuard {
        ImageSink* sink;
        bool keep = false;
        ~ImageGuard() {
            if (keep || !sink) return;
            for (const auto& f : sink->written()) ::unlink(f.c_str());
        }
    } image_guard{images.get()};

    quiet_kernel();
    const auto t0 = std::chrono::steady_clock::now();
    rbcd_system sys("rbcd", cfg, *src, *sink);
    std::unique_ptr<VcdWriter> vcd;
    if (vcd_out.active()) {
        vcd = std::make_unique<VcdWriter>([&](const std::string& s) { vcd_out.write(s); }, sys.clk.period_ps(),
                                          cfg.trace.start, cfg.trace.end);
        sys.attach_vcd(*vcd);
    } else if (fst) {
        vcd = std::make_unique<VcdWriter>(*fst, sys.clk.period_ps(), cfg.trace.start, cfg.trace.end);
        sys.attach_vcd(*vcd);
    }
    std::unique_ptr<GtkwaveLayout> layout;
    if (vcd && gtkw_out.active()) layout = std::make_unique<GtkwaveLayout>(*vcd, sys.clk.period_ps(), cfg.trace.start, cfg.trace.end);
    RunReport report(sys);               // GPU time and energy per frame, reduced as frames end
    if (frame_stats_out.active()) report.stream_to([&](const std::string& line) { frame_stats_out.write(line); });
    // Progress on stderr (only on a terminal, only after a few seconds) and --write-trace.
    struct Watch final : RasterObserver {
        rbcd_system& sys;
        TraceWriter* trace;
        GtkwaveLayout* layout;
        Progress progress;
        Watch(rbcd_system& s, TraceWriter* t, GtkwaveLayout* l) : sys(s), trace(t), layout(l) {}
        void frame_begin(std::uint64_t n) override {
            progress.on_frame(n, sys.raster.stats().fragments);
            if (trace) trace->frame(n);
            if (layout) layout->frame_start(n, sys.clk.now());
        }
        void tile(const Tile& t) override {
            if (trace) trace->tile(t);
        }
    } watch(sys, trace_out.get(), layout.get());
    sys.raster.add_observer(&watch);
    if (db) db->attach(sys);
    if (heat) heat->attach(sys);
    {
        const rbcd::MainStackForSanitizer main_stack;
        sys.run();
    }
    if (const std::string bad = self_check(self_check_counters(sys)); !bad.empty()) throw std::runtime_error(bad);
    Progress& progress = watch.progress;
    progress.finish();
    if (images) images->finish();
    if (heat) {
        heat->finish();
        if (!heat->error().empty()) throw RunError(heat->error());
    }
    if (trace_out) {
        trace_out->close();
        trace_file.commit();
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    nlohmann::json stats = make_stats(sys, RunInfo{input_name, wall}, report);
    // For the parent, which checks the run's bound on declared work over all
    // the parts as one process checks it (run_jobs); not in its stats.
    if (worker && trace_reader) stats["worker"] = {{"declared_work", trace_reader->declared_work()}};
    if (part_digest) stats["worker"]["digest"] = part_digest->finish();
    if (!worker && read_digest && stats_out.active()) provenance = make_provenance(opt.argv, cfg, prov_inputs);
    if (provenance_job.valid()) provenance = provenance_job.get();
    if (stats_out.active()) stats["provenance"] = provenance;
    if (file_sink) {
        file_sink->finish();
        collisions_out.commit();
    }
    if (vcd_out.active()) vcd_out.commit();
    if (fst) {
        fst->close();
        fst_out.commit();
    }
    if (db) {
        db->run_fact("cycles", std::to_string(sys.total_cycles()));
        db->run_fact("wall_seconds", std::to_string(wall));
        db->finish();
        db_out.commit();
    }
    if (layout) {
        const std::string wave = opt.fst.empty() ? opt.vcd : opt.fst;
        std::error_code ec;
        const std::string dump = wave == "-" ? wave : std::filesystem::absolute(wave, ec).string();
        const std::string filter = std::filesystem::absolute(filter_path, ec).string();
        gtkw_out.write(layout->save_file(dump, filter));
        filter_out.write(GtkwaveLayout::state_filter());
        filter_out.commit();
        gtkw_out.commit();
    }
    if (frame_stats_out.active()) frame_stats_out.commit();
    if (stats_out.active()) {
        stats_out.write(stats.dump(2) + "\n");
        stats_out.commit();
    }
    // Only now: a failed commit above removes the images, maps and their
    // directories with the rest.
    image_guard.keep = true;
    if (heat) heat->keep();
    made_dirs.keep = true;
    outputs_complete();
    if (!opt.quiet) std::fputs(make_summary(stats, report).c_str(), stdout);
    return 0;
}

// The mesh files a scene names, for a failed run's clean-up: an output named
// like one must not be removed as an older result. Read from its text alone
// when the scene does not parse (or not under the default limits: a run may
// have failed before its --set was read). Only a regular file is read (a
// FIFO would block the exit).
std::vector<std::string> scene_meshes_best_effort(const std::string& scene) {
    struct stat st {};
    if (scene.empty() || ::stat(scene.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return {};
    try {
        return rbcd::scene::SceneSource::mesh_files_of(scene, rbcd::scene::SceneLimits{});
    } catch (...) {
    }
    std::vector<std::string> meshes;
    std::ifstream in(scene);
    const std::filesystem::path dir = std::filesystem::path(scene).parent_path();
    std::string line;
    for (std::uint64_t read = 0; read < (std::uint64_t(64) << 20) && std::getline(in, line); read += line.size() + 1) {
        const auto key = line.find_first_not_of(" \t");
        if (key == std::string::npos || line.compare(key, 4, "mesh") != 0) continue;
        const auto open = line.find('"', key), close = open == std::string::npos ? open : line.find('"', open + 1);
        if (close == std::string::npos) continue;
        const std::filesystem::path mesh = line.substr(open + 1, close - open - 1);
        meshes.push_back((mesh.is_absolute() ? mesh : dir / mesh).string());
    }
    return meshes;
}

int fail(int status, const std::string& msg, int argc, char* argv[]) {
    // One line whatever the input held: control bytes from files, --set values
    // or library messages (toml++) are escaped here, in one place.
    std::fprintf(stderr, "rbcd-sim: %s\n", rbcd::escape_for_message(msg).c_str());
    // formats.md: on a non-zero exit nothing stands at an output path, not even an
    // older file; but an output path that names one of the inputs is the input.
    const std::vector<std::string> args(argv, argv + argc);
    auto outputs = rbcd::option_values(
        args, {"--collisions", "--stats", "--frame-stats", "--vcd", "--fst", "--gtkw", "--db", "--write-trace"});
    const auto gtkw = rbcd::option_values(args, {"--gtkw"});
    for (const auto& wave : rbcd::option_values(args, {"--vcd", "--fst"})) {
        const auto [g, f] = layout_paths(gtkw.empty() ? std::string() : gtkw.back(), wave);
        outputs.push_back(g);
        outputs.push_back(f);
    }
    auto inputs = rbcd::option_values(args, {"--trace", "--scene", "--config"});
    for (const auto& scene : rbcd::option_values(args, {"--scene"}))
        for (const auto& mesh : scene_meshes_best_effort(scene)) inputs.push_back(mesh);
    rbcd::discard_outputs(outputs, inputs);
    return status;
}

// Levenshtein distance, for suggesting the option a mistyped argument meant.
std::size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
        std::size_t diag = row[0];
        row[0] = i;
        for (std::size_t j = 1; j <= b.size(); ++j) {
            const std::size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diag = up;
        }
    }
    return row[b.size()];
}

// "unknown argument '--tracee' (did you mean --trace?)": CLI11 lists the
// arguments it did not expect; the first is named with the nearest option.
std::string unknown_argument_message(const CLI::App& app, const std::vector<std::string>& extras) {
    const std::string arg = extras.empty() ? std::string() : extras.front();
    std::string msg = "unknown argument '" + arg + "'";
    const std::size_t b = arg.find_first_not_of('-');
    if (b > 0 && b != std::string::npos) {
        // Against the long names, dashes aside: "-trace" and "--tracee" both mean --trace.
        const std::string name = arg.substr(b, arg.find('=') - b);
        std::string best;
        std::size_t best_d = std::string::npos;
        for (const CLI::Option* o : app.get_options())
            for (const auto& l : o->get_lnames())
                if (const std::size_t d = edit_distance(name, l); d < best_d) best_d = d, best = l;
        // Close enough to be a typo: at most a third of the name wrong.
        if (!best.empty() && name.size() >= 3 && best_d <= std::max<std::size_t>(1, best.size() / 3))
            msg += " (did you mean --" + best + "?)";
    } else if (b == 0) {
        msg += " (inputs are given as --trace FILE or --scene FILE)";
    }
    return msg;
}

} // namespace

// The program from its command line: sc_main's, and a --jobs worker's (a fork
// of this process, sc_main/jobs.h).
int rbcd_sim_main(const std::vector<std::string>& args) {
    std::vector<char*> argv_buf;
    for (const auto& a : args) argv_buf.push_back(const_cast<char*>(a.c_str()));
    argv_buf.push_back(nullptr);
    const int argc = static_cast<int>(args.size());
    char** const argv = argv_buf.data();
    Options opt;
    opt.argv = args;
    CLI::App app{"rbcd-sim: SystemC/TLM-2.0 model of the RBCD collision-detection unit"};
    app.add_option("--config", opt.config_file, "TOML configuration file");
    app.add_option("--set", opt.sets, "KEY=VALUE, applied after --config in order (repeatable)")->take_all();
    auto* trace_opt = app.add_option("--trace", opt.trace, "fragment trace (.rbt, plain or gzip; - reads standard input)");
    app.add_option("--scene", opt.scene, "3D scene (TOML) rendered by the tile-based rasterizer feed")
        ->excludes(trace_opt);
    auto* frames_opt =
        app.add_option("--frames", opt.frames, "A:B: run only frames A..B of the input (their numbers kept; docs/sweeps.md)");
    app.add_option("--threads", opt.threads,
                   "2 (default): a trace is parsed on a second thread; 1: one thread (what rbcd-sweep runs)")
        ->check(CLI::Range(1u, 2u));
    app.add_option("--jobs", opt.jobs,
                   "N: simulate the frames in N worker processes, contiguous ranges joined into the outputs one "
                   "process writes (docs/performance.md); default 1")
        ->check(CLI::Range(1u, 1024u));
    app.add_option("--worker-part", opt.worker_part, "internal: a --jobs worker's start")->group("");
    app.add_option("--worker-collisions-name", opt.worker_collisions_name,
                   "internal: what a --jobs worker's --collisions - is, for its errors")
        ->group("");
    app.add_option("--worker-digest", opt.worker_digest, "internal: a --jobs worker's blocks of the trace's digest")
        ->group("");
    app.add_option("--worker-digest-sums", opt.worker_digest_sums, "internal: where a --jobs worker's block sums go")
        ->group("");
    app.add_option("--write-trace", opt.write_trace, "also save the fragment stream the unit saw as a .rbt trace");
    app.add_option("--images", opt.images, "write a PNG per frame into this directory (scenes only)");
    app.add_option("--collisions", opt.collisions, "write the collision records here (- for standard output)");
    app.add_option("--stats", opt.stats, "write statistics JSON here");
    app.add_option("--frame-stats", opt.frame_stats,
                   "write per-frame figures here, one JSON object a line, as frames end (docs/stats.md)");
    app.add_option("--vcd", opt.vcd, "write a VCD waveform dump here (trace.* keys select blocks and window; "
                                     "a .fst name writes FST)");
    app.add_option("--fst", opt.fst, "write the waveforms as FST here (as --vcd; docs/waveforms.md)");
    app.add_option("--gtkw", opt.gtkw, "write the GTKWave save file for the waveform here (default: beside it, "
                                       "NAME.gtkw, with NAME.states.txt)");
    app.add_option("--heat-maps", opt.heat_maps,
                   "write per-tile heat maps summed over the run into this directory (with --images: also each "
                   "frame's; docs/tile-database.md)");
    app.add_option("--db", opt.db, "write the per-tile SQLite database here (docs/tile-database.md)");
    app.add_flag("--dump-config", opt.dump_config, "print the effective configuration as TOML and exit");
    app.add_flag("-q,--quiet", opt.quiet, "no summary on stdout");
    app.footer("Formats and options: docs/formats.md; configuration keys: docs/config.md; statistics: docs/stats.md.");
    app.set_version_flag("--version", rbcd::version_text(), "print the version, git revision, SystemC, compiler and build type");
    app.add_flag("--config-reference", opt.config_reference, "print the table of configuration keys (docs/config.md)");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ExtrasError&) {
        return fail(2, unknown_argument_message(app, app.remaining()) + " (see --help)", argc, argv);
    } catch (const CLI::ParseError& e) {
        return fail(2, std::string(e.what()) + " (see --help)", argc, argv);
    }
    opt.frames_given = frames_opt->count() > 0;
    try {
        return run(opt);
    } catch (const rbcd::InputError& e) {
        return fail(2, e.what(), argc, argv);
    } catch (const rbcd::RunError& e) {
        return fail(1, e.what(), argc, argv);
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what(), argc, argv);
    }
}

int sc_main(int argc, char* argv[]) {
    rbcd::report_file_size_limit_as_write_error();
    return rbcd_sim_main(std::vector<std::string>(argv, argv + argc));
}
