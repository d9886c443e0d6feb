#include "rbcd/run/run.h"

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <future>
#include <system_error>
#include <systemc>
#include <tuple>
#include <utility>

#include <nlohmann/json.hpp>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/common/output_file.h"
#include "rbcd/hw/rbcd_system.h"
#include "rbcd/hw/self_check.h"
#include "rbcd/io/frame_range_source.h"
#include "rbcd/io/frame_scan.h"
#include "rbcd/io/prefetch_source.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/trace_writer.h"
#include "rbcd/outputs/collision_file.h"
#include "rbcd/outputs/fst_writer.h"
#include "rbcd/outputs/gtkwave_layout.h"
#include "rbcd/outputs/heat_maps.h"
#include "rbcd/outputs/image_sink.h"
#include "rbcd/outputs/tile_database.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/stats_report.h"
#include "rbcd/run/jobs_run.h"
#include "rbcd/run/part_digest.h"
#include "rbcd/run/progress.h"
#include "rbcd/run/provenance.h"
#include "rbcd/run/sanitizer_stack.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd {

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
    return {path, GtkwaveLayout::filter_path_for(path)};
}

void RunPaths::output(const std::string& path) { outputs_.push_back(path); }
void RunPaths::waveform(const std::string& path) { waves_.push_back(path); }
void RunPaths::gtkw(const std::string& path) { gtkw_.push_back(path); }
void RunPaths::input(const std::string& path) { inputs_.push_back(path); }

void RunPaths::scene(const std::string& path) {
    inputs_.push_back(path);
    for (std::string& mesh : scene::SceneSource::mesh_files_named(path)) inputs_.push_back(std::move(mesh));
}

void RunPaths::discard_outputs() const {
    std::vector<std::string> outputs = outputs_;
    outputs.insert(outputs.end(), waves_.begin(), waves_.end());
    for (const std::string& wave : waves_) {
        const auto [g, f] = layout_paths(gtkw_.empty() ? std::string() : gtkw_.back(), wave);
        outputs.push_back(g);
        outputs.push_back(f);
    }
    outputs.insert(outputs.end(), gtkw_.begin(), gtkw_.end());
    rbcd::discard_outputs(outputs, inputs_);
}

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

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
        throw InputError(dir + ": cannot create directory: " + (ec ? ec.message() : "not a directory"));
}

// The images a failed run wrote are removed with it.
struct ImageGuard {
    ImageSink* sink = nullptr;
    bool keep = false;
    ~ImageGuard() {
        if (keep || !sink) return;
        for (const auto& f : sink->written()) ::unlink(f.c_str());
    }
};

void quiet_kernel() {
    // sc_stop() and end-of-simulation notes are not the user's business.
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
}

// Progress on stderr (only on a terminal, only after a few seconds),
// --write-trace and the waveform layout's frame markers, per frame.
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
};

// What watches the system as it runs: waveforms, their layout, the per-frame
// report, the tile database and heat maps, attached at construction.
struct Observers {
    std::unique_ptr<VcdWriter> vcd;
    std::unique_ptr<GtkwaveLayout> layout;
    RunReport report;   // GPU time and energy per frame, reduced as frames end
    Watch watch;
    Observers(rbcd_system& sys, const SimConfig& cfg, OutputFile& vcd_out, FstWriter* fst, bool gtkw,
              OutputFile& frame_stats_out, TraceWriter* trace_out, TileDatabase* db, HeatMaps* heat)
        : vcd(make_vcd(sys, cfg, vcd_out, fst)),
          layout(vcd && gtkw ? std::make_unique<GtkwaveLayout>(*vcd, sys.clk.period_ps(), cfg.trace.start, cfg.trace.end)
                             : nullptr),
          report(sys), watch(sys, trace_out, layout.get()) {
        if (frame_stats_out.active())
            report.stream_to([&frame_stats_out](const std::string& line) { frame_stats_out.write(line); });
        sys.raster.add_observer(&watch);
        if (db) db->attach(sys);
        if (heat) heat->attach(sys);
    }
    // The blocks' signals are added as the writer is attached, before the
    // layout's: their order is the waveform's.
    static std::unique_ptr<VcdWriter> make_vcd(rbcd_system& sys, const SimConfig& cfg, OutputFile& vcd_out, FstWriter* fst) {
        std::unique_ptr<VcdWriter> vcd;
        if (vcd_out.active())
            vcd = std::make_unique<VcdWriter>([&vcd_out](const std::string& s) { vcd_out.write(s); },
                                              sys.clk.period_ps(), cfg.trace.start, cfg.trace.end);
        else if (fst)
            vcd = std::make_unique<VcdWriter>(*fst, sys.clk.period_ps(), cfg.trace.start, cfg.trace.end);
        if (vcd) sys.attach_vcd(*vcd);
        return vcd;
    }
};

} // namespace

class Run::Impl {
public:
    Impl(SimOptions opt, WorkerMain worker_main) : opt_(std::move(opt)), worker_main_(worker_main) {}

    int execute() {
        if (!validate()) return 0;
        open_outputs();
        open_source();
        if (parts_.size() >= 2 && run_parts()) return 0;
        finish_source();
        start_provenance();
        attach_sinks();
        return run_system();
    }

private:
    bool validate();
    void validate_jobs() const;
    void check_paths();
    void open_outputs();
    void open_source();
    void open_trace();
    void open_scene();
    std::vector<ProvenanceInput> provenance_inputs(const std::string& input_name) const;
    bool run_parts();
    void finish_source();
    void start_provenance();
    void attach_sinks();
    int run_system();
    void finish_outputs(rbcd_system& sys, Observers& obs, double wall);
    void commit_layout(GtkwaveLayout& layout);

    // Declared in the order they are made: destroyed the other way round, a
    // reader before the digest it feeds, the hash thread before what it
    // reads, the images and maps before the directories that hold them.
    SimOptions opt_;
    WorkerMain worker_main_;
    std::string gtkw_path_, filter_path_;
    SimConfig cfg_;
    scene::SceneLimits scene_limits_;
    bool worker_ = false;
    // Outputs are created before the run so an uncreatable path fails fast.
    OutputFile collisions_out_, stats_out_, frame_stats_out_, vcd_out_, fst_out_;
    std::unique_ptr<FstWriter> fst_;
    OutputFile db_out_;
    std::unique_ptr<TileDatabase> db_;
    OutputFile gtkw_out_, filter_out_;
    FrameRange range_;
    JobPart part_;
    // Declared before the reader, which holds it.
    std::unique_ptr<ReadDigest> read_digest_;
    std::unique_ptr<PartDigest> part_digest_;
    std::unique_ptr<FragmentSource> src_;
    scene::SceneSource* scene_src_ = nullptr;
    std::vector<JobPart> parts_;           // more than one: the frames are the workers'
    TraceReader* trace_reader_ = nullptr;  // the trace's reader, when one process runs it
    const std::string default_scene_ = scene::default_scene_text();
    nlohmann::json provenance_;            // for stats_out_ (computed by the workers' run, or here)
    std::string input_name_;
    std::vector<ProvenanceInput> prov_inputs_;
    std::future<nlohmann::json> provenance_job_;
    std::unique_ptr<CollisionFileSink> file_sink_;
    TeeSink tee_;
    MadeDirectories made_dirs_;            // removed after the files in them, on failure
    std::unique_ptr<ImageSink> images_;
    std::unique_ptr<HeatMaps> heat_;
    std::unique_ptr<TraceWriter> trace_out_;
    OutputFile trace_file_;   // the temporary beside the path, or the path itself when not a regular file
    ImageGuard image_guard_;
};

// Options, configuration and output paths; false when the run is a listing
// (--config-reference, --dump-config) and nothing is simulated.
bool Run::Impl::validate() {
    // --vcd run.fst: the format follows the file's extension.
    if (ends_with(opt_.vcd, ".fst")) {
        if (!opt_.fst.empty()) throw InputError("--vcd: " + opt_.vcd + " is an FST file and --fst is given too");
        opt_.fst = std::exchange(opt_.vcd, std::string());
    }
    if (!opt_.fst.empty() && !opt_.vcd.empty())
        throw InputError("--fst: cannot be combined with --vcd (one waveform a run)");
    if (!opt_.fst.empty() && !fst_supported())
        throw InputError("--fst: this rbcd-sim was built without FST support (install Debian's verilator package: "
                         "scripts/setup.sh --waves, then rebuild)");
    if (!opt_.db.empty() && !sqlite_supported())
        throw InputError("--db: this rbcd-sim was built without SQLite (install Debian's libsqlite3-dev: "
                         "scripts/setup.sh --waves, then rebuild)");
    if (!opt_.gtkw.empty() && opt_.vcd.empty() && opt_.fst.empty())
        throw InputError("--gtkw: needs a waveform (--vcd or --fst)");
    std::tie(gtkw_path_, filter_path_) = layout_paths(opt_.gtkw, opt_.fst.empty() ? opt_.vcd : opt_.fst);
    if (!opt_.config_file.empty()) apply_config_file(cfg_, opt_.config_file);
    for (const auto& s : opt_.sets) apply_config_set(cfg_, s);
    cfg_.validate();
    FragmentPipe::stepwise = opt_.gpu_stepwise;

    if (opt_.config_reference) {
        std::fputs(config_reference_markdown().c_str(), stdout);
        return false;
    }
    if (opt_.dump_config) {
        std::fputs(dump_config_toml(cfg_).c_str(), stdout);
        return false;
    }
    validate_jobs();
    check_paths();
    return true;
}

void Run::Impl::validate_jobs() const {
    if (opt_.jobs > 1) {
        // Outputs that only one process can write: refused rather than run on one core unasked.
        const std::pair<const char*, const std::string*> whole[] = {
            {"--vcd", &opt_.vcd},     {"--fst", &opt_.fst},           {"--gtkw", &opt_.gtkw},
            {"--db", &opt_.db},       {"--images", &opt_.images},     {"--heat-maps", &opt_.heat_maps},
            {"--write-trace", &opt_.write_trace}};
        for (const auto& [flag, path] : whole)
            if (!path->empty())
                throw InputError(std::string("--jobs: cannot be combined with ") + flag +
                                 " (written by one process; use --jobs 1)");
        if (opt_.trace == "-") throw InputError("--jobs: cannot split standard input (--trace -); use --jobs 1");
    }
    const bool worker = !opt_.worker_part.empty();
    if (worker && !opt_.frames_given) throw InputError("--worker-part: needs --frames");
    if (!worker && !opt_.worker_collisions_name.empty())
        throw InputError("--worker-collisions-name: only for a --jobs worker (with --worker-part)");
    if ((!worker || opt_.trace.empty()) && !opt_.worker_digest.empty())
        throw InputError("--worker-digest: only for a --jobs worker of a trace (with --worker-part and --trace)");
    if ((!worker || opt_.trace.empty()) && opt_.worker_stop_at != UINT64_MAX)
        throw InputError("--worker-stop-at: only for a --jobs worker of a trace (with --worker-part and --trace)");
    if (opt_.worker_digest.empty() && !opt_.worker_digest_sums.empty())
        throw InputError("--worker-digest-sums: only with --worker-digest");
}

// An output over an input (a scene's meshes too) would destroy it before it
// is read; two outputs in one file would leave only the last written.
void Run::Impl::check_paths() {
    worker_ = !opt_.worker_part.empty();
    scene_limits_ = scene::SceneLimits{cfg_.tile.width,           cfg_.tile.height,
                                       cfg_.zeb.id_bits,          cfg_.input.max_scene_bytes,
                                       cfg_.input.max_scene_triangles, cfg_.input.max_tile_fragments};
    std::vector<NamedPath> inputs{{"", opt_.trace}, {"", opt_.scene}, {"", opt_.config_file}};
    if (!opt_.scene.empty())
        for (const std::string& mesh : scene::SceneSource::mesh_files_of(opt_.scene, scene_limits_))
            inputs.push_back({"", mesh});
    check_output_paths({{"--collisions", opt_.collisions},
                        {"--stats", opt_.stats},
                        {"--frame-stats", opt_.frame_stats},
                        {"--vcd", opt_.vcd},
                        {"--fst", opt_.fst},
                        {"--gtkw", gtkw_path_},
                        {"--gtkw", filter_path_},
                        {"--db", opt_.db},
                        {"--write-trace", opt_.write_trace}},
                       inputs);
}

void Run::Impl::open_outputs() {
    if (!opt_.collisions.empty()) collisions_out_ = OutputFile(opt_.collisions);
    if (!opt_.worker_collisions_name.empty()) collisions_out_.show_as(opt_.worker_collisions_name);
    if (!opt_.stats.empty()) stats_out_ = OutputFile(opt_.stats);
    if (!opt_.frame_stats.empty()) frame_stats_out_ = OutputFile(opt_.frame_stats);
    if (!opt_.vcd.empty()) vcd_out_ = OutputFile(opt_.vcd);
    if (!opt_.fst.empty()) {
        fst_out_ = OutputFile(opt_.fst, OutputFile::ByName{});
        fst_ = std::make_unique<FstWriter>(fst_out_.library_path(), opt_.fst);
    }
    if (!opt_.db.empty()) {
        db_out_ = OutputFile(opt_.db, OutputFile::ByName{});
        db_ = std::make_unique<TileDatabase>(db_out_.library_path(), opt_.db, cfg_.tile.width, cfg_.tile.height);
    }
    if (!gtkw_path_.empty()) {
        gtkw_out_ = OutputFile(gtkw_path_);
        filter_out_ = OutputFile(filter_path_);
    }
}

void Run::Impl::open_source() {
    range_ = opt_.frames_given ? parse_frame_range(opt_.frames) : FrameRange{};
    part_ = worker_ ? parse_worker_part(opt_.worker_part, range_) : JobPart{};
    // A trace read from its first byte is hashed as it is read, and the
    // provenance reads only what the reader did not (docs/provenance.md):
    // one process writing stats (not for --db, which records the provenance
    // before the run, nor --frames, whose reader stops early). So standard
    // input, which cannot be read again, gets a digest too.
    if (!opt_.trace.empty() && !worker_ && stats_out_.active() && !opt_.frames_given && opt_.db.empty())
        read_digest_ = std::make_unique<ReadDigest>();
    // A --jobs worker's blocks of that digest, from the bytes it reads (part_digest.h).
    if (!opt_.worker_digest.empty()) {
        const DigestBlocks b = parse_worker_digest(opt_.worker_digest, opt_.worker_digest_sums);
        part_digest_ = std::make_unique<PartDigest>(b.from, b.to, opt_.worker_digest_sums);
    }
    if (!opt_.trace.empty()) open_trace();
    else open_scene();
}

void Run::Impl::open_trace() {
    if (opt_.jobs > 1) {
        // A plain file is read only near the cuts; a gzip one (or a range to
        // find) needs a pass over the data, fragments unparsed.
        FrameScan scan;
        if (const std::uint64_t bytes = opt_.frames_given ? 0 : plain_trace_bytes(opt_.trace)) {
            std::vector<std::uint64_t> cuts;
            for (unsigned k = 1; k < opt_.jobs; ++k)
                cuts.push_back(bytes / opt_.jobs * k + bytes % opt_.jobs * k / opt_.jobs);
            scan = find_frames_near(opt_.trace, cuts);
        }
        if (!scan.ok) scan = scan_frames(opt_.trace);
        parts_ = plan_trace_parts(scan, range_, opt_.jobs);
    }
    if (parts_.size() >= 2) return;
    RawObserver* const read_observer =
        read_digest_ ? static_cast<RawObserver*>(read_digest_.get()) : part_digest_.get();
    // Parsed a few tiles ahead on another core (io/prefetch_source.h), unless
    // the cores are the caller's to share (rbcd-sweep's workers).
    // A compressed one is also decompressed on a core of its own (io/read_ahead.h).
    TraceLimits limits = trace_limits(cfg_);
    limits.read_ahead = opt_.threads > 1;
    auto reader = std::make_unique<TraceReader>(opt_.trace, limits, read_observer);
    // A plain trace's line number is counted only if a message needs it.
    if (part_.skip) reader->start_at_frame(range_.first, part_.offset, part_.line);
    // Not even read ahead: what follows the range is another worker's.
    if (opt_.frames_given) reader->stop_after_frame(range_.last);
    if (opt_.worker_stop_at != UINT64_MAX) reader->expect_stop_at(opt_.worker_stop_at);
    trace_reader_ = reader.get();
    if (opt_.threads > 1) src_ = std::make_unique<PrefetchSource>(std::move(reader));
    else src_ = std::move(reader);
}

void Run::Impl::open_scene() {
    auto s = opt_.scene.empty()
                 ? scene::SceneSource::from_text(scene::default_scene_text(), "", "<default scene>", scene_limits_)
                 : std::make_unique<scene::SceneSource>(opt_.scene, scene_limits_);
    // No frame outside the range is rendered: one process looks at the frames
    // before it only to say "nothing in view" (scene_source.h). A range past
    // the end is refused before any frame is.
    if (range_.first >= s->frame_count()) throw no_frame_selected(range_, s->frame_count());
    if (part_.skip) s->start_at_frame(range_.first);
    else if (!worker_ && range_.first > 0) s->start_at_frame(range_.first, scene::SceneSource::BeforeStart::LookIfEmpty);
    if (opt_.frames_given) s->stop_after_frame(range_.last);
    if (opt_.jobs > 1) parts_ = plan_scene_parts(s->frame_count(), range_, opt_.jobs);
    scene_src_ = s.get();
    src_ = std::move(s);
}

// The files the run read, for provenance (docs/provenance.md); the default
// scene is named and hashed from its text.
std::vector<ProvenanceInput> Run::Impl::provenance_inputs(const std::string& input_name) const {
    std::vector<ProvenanceInput> inputs;
    if (!opt_.config_file.empty()) inputs.push_back({"config", opt_.config_file});
    if (!opt_.trace.empty()) {
        inputs.push_back({"trace", opt_.trace, nullptr, read_digest_.get()});
        if (opt_.trace != "-") inputs.back().expected = file_id_at(opt_.trace);
    } else if (opt_.scene.empty()) {
        inputs.push_back({"scene", input_name, &default_scene_});
    } else {
        inputs.push_back({"scene", opt_.scene});
    }
    if (scene_src_)
        for (const auto& m : scene_src_->mesh_files()) inputs.push_back({"mesh", m});
    return inputs;
}

// --jobs: true when the workers ran the whole run. False when the parts'
// frames hold no fragment: whether the scene has none at all is one
// process's to say (it looks at every frame).
bool Run::Impl::run_parts() {
    JobsRun jobs(opt_, cfg_, parts_, provenance_inputs(src_ ? src_->name() : opt_.trace),
                 {collisions_out_, stats_out_, frame_stats_out_}, worker_main_);
    return jobs.run(provenance_);
}

void Run::Impl::finish_source() {
    if (!src_) {
        auto reader = std::make_unique<TraceReader>(opt_.trace, trace_limits(cfg_), read_digest_.get());
        if (opt_.threads > 1) src_ = std::make_unique<PrefetchSource>(std::move(reader));
        else src_ = std::move(reader);
    }
    if (opt_.frames_given) {
        // A trace's frames count from 0: a range written out would not read back.
        if (!opt_.write_trace.empty()) throw InputError("--frames: cannot be combined with --write-trace");
        src_ = std::make_unique<FrameRangeSource>(std::move(src_), parse_frame_range(opt_.frames));
    }
    input_name_ = src_->name();
}

// Inputs are hashed now, as they were read, and only for a stats file
// (docs/provenance.md). With a second core to use, the hashing (a trace's
// every byte) runs beside the simulation instead of before it; the database
// records it up front.
void Run::Impl::start_provenance() {
    prov_inputs_ = provenance_inputs(input_name_);
    if (worker_) {
        // The run's provenance is the one that started the workers.
    } else if (!provenance_.is_null()) {
        // Computed by the workers' run that found nothing to simulate.
    } else if (read_digest_) {
        // Hashed as it is read: finished after the run.
    } else if (db_ || (stats_out_.active() && opt_.threads == 1)) {
        provenance_ = make_provenance(opt_.argv, cfg_, prov_inputs_);
    } else if (stats_out_.active()) {
        provenance_job_ = std::async(std::launch::async, [this] { return make_provenance(opt_.argv, cfg_, prov_inputs_); });
    }
    if (db_) {
        db_->run_fact("input", input_name_);
        db_->run_fact("config", dump_config_toml(cfg_));
        db_->run_fact("provenance", provenance_.dump(2));
        db_->run_fact("tile_width", std::to_string(cfg_.tile.width));
        db_->run_fact("tile_height", std::to_string(cfg_.tile.height));
        db_->run_fact("screen_width", std::to_string(src_->header().screen_w));
        db_->run_fact("screen_height", std::to_string(src_->header().screen_h));
    }
}

// Where the collisions and frames go: the collision file, the images, the heat
// maps, --write-trace (the stream the unit saw, replayable with --trace).
void Run::Impl::attach_sinks() {
    if (collisions_out_.active()) {
        file_sink_ = std::make_unique<CollisionFileSink>(collisions_out_);
        tee_.add(file_sink_.get());
    }
    if (!opt_.images.empty()) {
        if (!scene_src_) throw InputError("--images: needs a scene (--scene, or no --trace)");
        make_directory(opt_.images, made_dirs_);
        scene_src_->enable_images(true);
        images_ = std::make_unique<ImageSink>(*scene_src_, opt_.images, cfg_.tile.width, cfg_.tile.height);
        tee_.add(images_.get());
    }
    // Heat maps into --heat-maps DIR: summed over the run; with --images, also
    // each frame's (the images directory keeps one PNG a frame: scripts count them).
    if (!opt_.heat_maps.empty()) {
        make_directory(opt_.heat_maps, made_dirs_);
        heat_ = std::make_unique<HeatMaps>(opt_.heat_maps, !opt_.images.empty(), src_->header().screen_w,
                                           src_->header().screen_h, cfg_.tile.width, cfg_.tile.height);
    }
    if (!opt_.write_trace.empty()) {
        trace_file_ = OutputFile(opt_.write_trace);
        trace_out_ = std::make_unique<TraceWriter>(trace_file_.shared_fd(), src_->header(),
                                                   trace_compression_for(opt_.write_trace), opt_.write_trace);
    }
    image_guard_.sink = images_.get();
}

// The system and its observers, the simulation, then every output committed.
int Run::Impl::run_system() {
    quiet_kernel();
    const auto t0 = std::chrono::steady_clock::now();
    rbcd_system sys("rbcd", cfg_, *src_, tee_);
    Observers obs(sys, cfg_, vcd_out_, fst_.get(), gtkw_out_.active(), frame_stats_out_, trace_out_.get(), db_.get(),
                  heat_.get());
    {
        const MainStackForSanitizer main_stack;
        sys.run();
    }
    if (const std::string bad = self_check(self_check_counters(sys)); !bad.empty()) throw std::runtime_error(bad);
    obs.watch.progress.finish();
    if (images_) images_->finish();
    if (heat_) {
        heat_->finish();
        if (!heat_->error().empty()) throw RunError(heat_->error());
    }
    if (trace_out_) {
        trace_out_->close();
        trace_file_.commit();
    }
    finish_outputs(sys, obs, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return 0;
}

// The stats with their provenance, and every output renamed into place, the
// stats last; the summary once they all stand.
void Run::Impl::finish_outputs(rbcd_system& sys, Observers& obs, double wall) {
    nlohmann::json stats = make_stats(sys, RunInfo{input_name_, wall}, obs.report);
    // For the parent, which checks the run's bound on declared work over all
    // the parts as one process checks it (run/jobs_run.h); not in its stats.
    if (worker_ && trace_reader_) stats["worker"] = {{"declared_work", trace_reader_->declared_work()}};
    if (part_digest_) stats["worker"]["digest"] = part_digest_->finish();
    if (!worker_ && read_digest_ && stats_out_.active()) provenance_ = make_provenance(opt_.argv, cfg_, prov_inputs_);
    if (provenance_job_.valid()) provenance_ = provenance_job_.get();
    if (stats_out_.active()) stats["provenance"] = provenance_;
    if (file_sink_) {
        file_sink_->finish();
        collisions_out_.commit();
    }
    if (vcd_out_.active()) vcd_out_.commit();
    if (fst_) {
        fst_->close();
        fst_out_.commit();
    }
    if (db_) {
        db_->run_fact("cycles", std::to_string(sys.total_cycles()));
        db_->run_fact("wall_seconds", std::to_string(wall));
        db_->finish();
        db_out_.commit();
    }
    if (obs.layout) commit_layout(*obs.layout);
    if (frame_stats_out_.active()) frame_stats_out_.commit();
    if (stats_out_.active()) {
        stats_out_.write(stats.dump(2) + "\n");
        stats_out_.commit();
    }
    // Only now: a failed commit above removes the images, maps and their
    // directories with the rest.
    image_guard_.keep = true;
    if (heat_) heat_->keep();
    made_dirs_.keep = true;
    outputs_complete();
    if (!opt_.quiet) std::fputs(make_summary(stats, obs.report).c_str(), stdout);
}

void Run::Impl::commit_layout(GtkwaveLayout& layout) {
    const std::string wave = opt_.fst.empty() ? opt_.vcd : opt_.fst;
    std::error_code ec;
    const std::string dump = wave == "-" ? wave : std::filesystem::absolute(wave, ec).string();
    const std::string filter = std::filesystem::absolute(filter_path_, ec).string();
    gtkw_out_.write(layout.save_file(dump, filter));
    filter_out_.write(GtkwaveLayout::state_filter());
    filter_out_.commit();
    gtkw_out_.commit();
}

Run::Run(SimOptions opt, WorkerMain worker_main) : impl_(std::make_unique<Impl>(std::move(opt), worker_main)) {}
Run::~Run() = default;
int Run::execute() { return impl_->execute(); }

} // namespace rbcd
