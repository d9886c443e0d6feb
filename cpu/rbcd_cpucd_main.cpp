// rbcd-cpucd: CPU collision detection on the frames of a scene (or of a
// geometry file), the paper's CPU baselines and the exact ground truth
// (docs/cpucd.md). Exit 0 done, 2 bad input or command line, 1 anything else;
// on a non-zero exit no file is left at an output path.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <set>
#include <unistd.h>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/cpu/cd_input.h"
#include "rbcd/cpu/cpu_collision.h"
#include "rbcd/cpu/instruction_count.h"
#include "rbcd/cpu/pixel_overlap.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/common/output_file.h"
#include "rbcd/scene/scene_source.h"

namespace {

// Timed repeats per frame: each runs the broad phase and GJK twice over every
// part; more than this says nothing the median of fewer would not.
constexpr unsigned kMaxRepeat = 1000;

struct Options {
    std::string scene, geometry, trace, pairs, frames, write_geometry, depth_hist;
    unsigned repeat = 5;
    std::uint64_t frame_step = 1;   // detect on frames 0, K, 2K, ...
    std::uint64_t max_pairs = 100000;
    std::uint64_t max_geometry_bytes = std::uint64_t(256) << 20;
    bool pixels = false;
    unsigned tolerance = 1;
    bool quiet = false;
    bool count = false;
};

std::string fmt(const char* f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

void check_options(const Options& opt) {
    using rbcd::InputError;
    if (opt.scene.empty() == opt.geometry.empty()) throw InputError("command line: give exactly one of --scene, --geometry");
    if (!opt.trace.empty() && !opt.scene.empty())
        throw InputError("command line: --trace goes with --geometry (a scene is rasterized itself)");
    if (opt.pixels && opt.scene.empty() && opt.trace.empty())
        throw InputError("command line: --pixels with --geometry needs --trace FILE (the frames' fragments)");
    if (opt.repeat < 1 || opt.repeat > kMaxRepeat)
        throw InputError("--repeat: " + std::to_string(opt.repeat) + " is out of range 1.." + std::to_string(kMaxRepeat));
    if (opt.max_pairs < 1) throw InputError("--max-pairs: must be at least 1");
    if (opt.frame_step < 1) throw InputError("--frame-step: must be at least 1");
    // A counted run is the detection alone under callgrind (50 times slower):
    // its times mean nothing and the exact phase and pixels are left out, so
    // it writes the frames' counts and nothing that would look like a full run.
    if (opt.count && (!opt.pairs.empty() || opt.pixels || !opt.write_geometry.empty() || !opt.trace.empty()))
        throw InputError("command line: --count-instructions writes --frames only (no --pairs, --pixels, --trace, "
                         "--write-geometry)");

    if (!opt.depth_hist.empty() && !opt.pixels) throw InputError("command line: --depth-histogram needs --pixels");
}

// Work bounded in the input: every frame's candidate pairs counted before
// Bullet or FCL sees any (docs/limits.md). A format-2 file's frames each
// carry meshes of their own (game models change shape every frame): each
// frame is then its own input, and the broad phase starts afresh every frame
// (docs/cpucd.md).
void check_pair_limits(const rbcd::cpucd::CdInput& in, const Options& opt) {
    using namespace rbcd::cpucd;
    for (std::uint64_t f = 0; f < in.frames(); ++f)
        if (in.per_frame() ? overlapping_aabb_pairs(in.frame_input(f), 0, opt.max_pairs).over_limit
                           : overlapping_aabb_pairs(in, f, opt.max_pairs).over_limit)
            throw rbcd::InputError((opt.scene.empty() ? opt.geometry : opt.scene) + ": frame " + std::to_string(f) +
                                   ": more than " + std::to_string(opt.max_pairs) +
                                   " pairs of parts with overlapping bounding boxes (the limit, raised by --max-pairs; "
                                   "docs/limits.md)");
}

// --pixels: every frame's pixel overlaps from the scene or trace, and the
// depth histogram into `hist_out`.
std::vector<rbcd::cpucd::FramePixels> pixel_overlaps(const Options& opt, const rbcd::cpucd::CdInput& in,
                                                     rbcd::OutputFile& hist_out) {
    using namespace rbcd;
    using namespace rbcd::cpucd;
    std::unique_ptr<FragmentSource> src;
    if (!opt.scene.empty()) src = std::make_unique<scene::SceneSource>(opt.scene, scene::SceneLimits{16, 16, 16});
    else src = std::make_unique<TraceReader>(opt.trace, TraceLimits{16, 16, 16});
    // Tiles of any size work: intervals are per pixel. The trace's own tile size is accepted.
    DepthHistogram hist(kDepthBins, 0);
    std::vector<FramePixels> px = pixel_overlap(*src, opt.tolerance, &hist);
    hist_out.write("fragments_per_pixel,pixels\n");
    for (std::size_t n = 1; n < hist.size(); ++n)
        if (hist[n]) hist_out.write(std::to_string(n) + (n + 1 == kDepthBins ? "+" : "") + "," + std::to_string(hist[n]) + "\n");
    if (px.size() != in.frames())
        throw InputError((opt.trace.empty() ? opt.scene : opt.trace) + ": " + std::to_string(px.size()) +
                         " frames of fragments for " + std::to_string(in.frames()) + " frames of geometry");
    return px;
}

// The input's parts, how many are closed meshes, and the objects with a part
// that is not.
struct MeshCounts {
    std::size_t parts = 0, closed = 0;
    std::set<std::uint32_t> open_ids;
};

MeshCounts count_meshes(const rbcd::cpucd::CdInput& in) {
    MeshCounts m;
    m.parts = in.parts.size();
    const auto note_closed = [&](const rbcd::cpucd::Part& p) {
        const bool c = rbcd::cpucd::is_closed(*p.mesh);
        m.closed += c;
        if (!c) m.open_ids.insert(p.id);
    };
    for (const auto& p : in.parts) note_closed(p);
    for (const auto& fx : in.extra) {
        m.parts += fx.meshes.size();
        for (const auto& p : fx.meshes) note_closed(p);
    }
    return m;
}

// Sums over the frames, for the summary.
struct RunTotals {
    double broad = 0, gjk = 0, exact = 0, world_broad = 0, world = 0;   // us
    std::uint64_t aabb_pairs = 0, gjk_pairs = 0, exact_pairs = 0, world_aabb_pairs = 0, world_pairs = 0;
    std::uint64_t instr[std::size_t(rbcd::cpucd::Section::count)] = {};
};

// One frame's rows of --pairs and --frames, added to `t`.
void write_frame(const Options& opt, std::uint64_t f, const rbcd::cpucd::FrameResult& r, std::size_t frame_parts,
                 std::size_t frame_concave, const rbcd::cpucd::FramePixels* px, const std::set<std::uint32_t>& open_ids,
                 rbcd::OutputFile& pairs_out, rbcd::OutputFile& frames_out, RunTotals& t) {
    using namespace rbcd::cpucd;
    std::map<PairKey, PairResult> all;
    for (const auto& p : r.pairs) all[{p.a, p.b}] = p;
    if (px)
        for (const auto& [k, c] : *px)
            if (!all.count(k)) all[k] = PairResult{k.first, k.second};
    unsigned na = 0, ng = 0, ne = 0, nwa = 0, nw = 0;
    for (const auto& [k, p] : all) {
        na += p.aabb;
        ng += p.gjk;
        ne += p.exact;
        nwa += p.world_aabb;
        nw += p.world;
        PixelCounts c;
        if (px)
            if (auto it = px->find(k); it != px->end()) c = it->second;
        pairs_out.write(std::to_string(f) + "," + std::to_string(p.a) + "," + std::to_string(p.b) + "," +
                        std::to_string(p.aabb) + "," + std::to_string(p.gjk) + "," + std::to_string(p.exact) + "," +
                        std::to_string(p.contained) + "," + std::to_string(p.on_screen) + "," +
                        std::to_string(p.contacts) + "," + std::to_string(c.overlap) + "," +
                        std::to_string(c.near) + "," + std::to_string(open_ids.count(p.a) || open_ids.count(p.b)) +
                        "," + std::to_string(p.world_aabb) + "," + std::to_string(p.world) + "\n");
    }
    // A counted run leaves empty what it did not measure: its times are
    // valgrind's, and it runs no exact phase.
    const auto us = [&](double v) { return opt.count ? std::string() : fmt("%.3f", v); };
    std::string counts;
    for (std::size_t k = 0; k < std::size_t(Section::count); ++k) {
        counts += "," + (opt.count ? std::to_string(r.instr[k]) : std::string());
        t.instr[k] += r.instr[k];
    }
    frames_out.write(std::to_string(f) + "," + std::to_string(frame_parts) + "," + std::to_string(na) + "," +
                     std::to_string(ng) + "," + (opt.count ? std::string() : std::to_string(ne)) + "," +
                     us(r.t.broad_us) + "," + us(r.t.gjk_us) + "," + us(r.t.exact_us) + "," +
                     std::to_string(r.t.gjk_no_result) + "," + std::to_string(nwa) + "," + std::to_string(nw) +
                     "," + us(r.t.world_broad_us) + "," + us(r.t.world_us) + "," + std::to_string(frame_concave) +
                     counts + "\n");
    t.broad += r.t.broad_us;
    t.gjk += r.t.gjk_us;
    t.exact += r.t.exact_us;
    t.world_broad += r.t.world_broad_us;
    t.world += r.t.world_us;
    t.aabb_pairs += na;
    t.gjk_pairs += ng;
    t.exact_pairs += ne;
    t.world_aabb_pairs += nwa;
    t.world_pairs += nw;
}

void print_summary(const Options& opt, const rbcd::cpucd::CdInput& in, const MeshCounts& m, std::size_t concave,
                   const RunTotals& t) {
    const std::uint64_t detected = in.frames() ? (in.frames() - 1) / opt.frame_step + 1 : 0;
    const double nf = double(std::max<std::uint64_t>(detected, 1));
    std::printf("rbcd-cpucd: %s\n  frames %llu", rbcd::escape_for_message(in.name).c_str(),
                (unsigned long long)in.frames());
    if (opt.frame_step > 1)
        std::printf(" (every %llu-th detected: %llu)", (unsigned long long)opt.frame_step, (unsigned long long)detected);
    std::printf("  parts %zu (%zu closed meshes, %zu concave in the world)\n", m.parts, m.closed, concave);
    std::printf("  pair-frames: aabb %llu  gjk %llu  exact %llu  world aabb %llu  world contact %llu\n",
                (unsigned long long)t.aabb_pairs, (unsigned long long)t.gjk_pairs, (unsigned long long)t.exact_pairs,
                (unsigned long long)t.world_aabb_pairs, (unsigned long long)t.world_pairs);
    if (opt.count)
        std::printf("  mean instructions per frame: broad phase %.0f, broad + GJK %.0f, world broad phase %.0f, "
                    "world %.0f\n",
                    double(t.instr[0]) / nf, double(t.instr[1]) / nf, double(t.instr[2]) / nf, double(t.instr[3]) / nf);
    else
        std::printf("  mean time per frame: broad phase %.1f us, broad + GJK %.1f us, exact %.1f us, world broad "
                    "phase %.1f us, world %.1f us (median of %u repeats)\n",
                    t.broad / nf, t.gjk / nf, t.exact / nf, t.world_broad / nf, t.world / nf, opt.repeat);
}

int run(const Options& opt) {
    using namespace rbcd;
    using namespace rbcd::cpucd;
    check_options(opt);
    // Before any output is opened: opening one removes an older file there.
    check_output_paths({{"--pairs", opt.pairs}, {"--frames", opt.frames}, {"--write-geometry", opt.write_geometry},
                        {"--depth-histogram", opt.depth_hist}},
                       {{"--scene", opt.scene}, {"--geometry", opt.geometry}, {"--trace", opt.trace}});
    OutputFile pairs_out, frames_out, geo_out, hist_out;
    if (!opt.pairs.empty()) pairs_out = OutputFile(opt.pairs);
    if (!opt.frames.empty()) frames_out = OutputFile(opt.frames);
    if (!opt.write_geometry.empty()) geo_out = OutputFile(opt.write_geometry);
    if (!opt.depth_hist.empty()) hist_out = OutputFile(opt.depth_hist);
    const CdInput in = opt.scene.empty() ? load_geometry_file(opt.geometry, GeometryLimits{opt.max_geometry_bytes})
                                         : load_scene_input(opt.scene);
    check_pair_limits(in, opt);
    std::vector<FramePixels> px;
    if (opt.pixels) px = pixel_overlaps(opt, in, hist_out);
    if (geo_out.active()) geo_out.write(geometry_file_text(in));
    const MeshCounts meshes = count_meshes(in);

    DetectorOptions dopt;
    dopt.exact = !opt.count;
    std::unique_ptr<CallgrindCounter> counter;
    if (opt.count) counter = std::make_unique<CallgrindCounter>();
    std::unique_ptr<CpuDetector> whole;   // the parts of the whole run; per-frame inputs get their own
    if (!in.per_frame()) whole = std::make_unique<CpuDetector>(in, dopt);
    pairs_out.write("frame,id_a,id_b,aabb,gjk,exact,contained,on_screen,contacts,px_overlap,px_near,open,world_aabb,"
                    "world\n");
    frames_out.write("frame,parts,aabb_pairs,gjk_pairs,exact_pairs,broad_us,gjk_us,exact_us,gjk_no_result,"
                     "world_aabb_pairs,world_pairs,world_broad_us,world_us,concave_parts,broad_instr,gjk_instr,"
                     "world_broad_instr,world_instr\n");
    // Counted: callgrind instruments the frame's detection only (loading,
    // the input's parse and each frame's hulls, trees and worlds, runs
    // uninstrumented; CallgrindCounter::instrument).
    const auto detect = [&](CpuDetector& det, std::uint64_t f) {
        if (counter) counter->instrument(true);
        FrameResult r = det.run_frame(f, opt.repeat, counter.get());
        if (counter) counter->instrument(false);
        return r;
    };
    RunTotals totals;
    std::size_t concave = whole ? whole->concave_parts() : 0;
    // A frame left out by --frame-step is not built either (its hulls, trees and worlds).
    for (std::uint64_t f = 0; f < in.frames(); f += opt.frame_step) {
        std::size_t frame_parts = in.parts.size(), frame_concave = concave;
        FrameResult r;
        if (whole) {
            r = detect(*whole, f);
        } else {
            const CdInput one = in.frame_input(f);
            frame_parts = one.parts.size();
            DetectorOptions fresh = dopt;
            fresh.fresh = true;
            CpuDetector det(one, fresh);
            frame_concave = det.concave_parts();
            concave = std::max(concave, frame_concave);
            r = detect(det, 0);
        }
        write_frame(opt, f, r, frame_parts, frame_concave, opt.pixels ? &px[f] : nullptr, meshes.open_ids, pairs_out,
                    frames_out, totals);
    }
    pairs_out.commit();
    frames_out.commit();
    geo_out.commit();
    hist_out.commit();
    rbcd::outputs_complete();   // a summary on a closed pipe leaves them standing
    if (!opt.quiet) print_summary(opt, in, meshes, concave, totals);
    return 0;
}

// One line whatever the input held; on a non-zero exit nothing this run
// created is left at an output path (the outputs' temporaries are removed by
// their destructors; an older file is removed when its output is opened).
int fail(int status, const std::string& msg, const Options& opt) {
    std::fprintf(stderr, "rbcd-cpucd: %s\n", rbcd::escape_for_message(rbcd::cut_long_tokens(msg)).c_str());
    rbcd::discard_outputs({opt.pairs, opt.frames, opt.write_geometry, opt.depth_hist},
                          {opt.scene, opt.geometry, opt.trace});
    return status;
}

} // namespace

int main(int argc, char* argv[]) {
    rbcd::report_file_size_limit_as_write_error();
    // Before anything allocates through Bullet (docs/cpucd.md, "Counted work").
    if (rbcd::cpucd::counting_under_callgrind()) rbcd::cpucd::use_deterministic_bullet_heap();
    Options opt;
    CLI::App app{"rbcd-cpucd: CPU collision detection (Bullet broad phase, GJK on hulls, FCL ground truth) per frame"};
    app.add_option("--scene", opt.scene, "scene (TOML): its collisionable objects at each frame");
    app.add_option("--geometry", opt.geometry, "geometry file (docs/cpucd.md) instead of a scene");
    app.add_option("--trace", opt.trace, "with --geometry and --pixels: the frames' fragment trace");
    app.add_option("--pairs", opt.pairs, "per frame and pair CSV");
    app.add_option("--frames", opt.frames, "per frame CSV: pair counts and times");
    app.add_option("--write-geometry", opt.write_geometry, "also write the input as a geometry file");
    app.add_option("--repeat", opt.repeat, "timed repeats per frame (median reported), 1..1000, default 5");
    app.add_option("--frame-step", opt.frame_step,
                   "detect on frames 0, K, 2K, ... only (a sample of a long input; the outputs' rows are those "
                   "frames'), default 1");
    app.add_option("--max-pairs", opt.max_pairs,
                   "refuse a frame with more candidate pairs of overlapping bounding boxes, default 100000");
    app.add_option("--max-geometry-bytes", opt.max_geometry_bytes, "refuse a larger geometry file, default 256 MiB");
    app.add_flag("--pixels", opt.pixels, "also count, per pair, pixels where the depth intervals overlap / nearly overlap");
    app.add_option("--depth-histogram", opt.depth_hist, "with --pixels: CSV of pixels by fragments on them (all frames)");
    app.add_option("--depth-tolerance", opt.tolerance, "depth units for --pixels' near overlaps, default 1");
    app.add_flag("-q,--quiet", opt.quiet, "no summary on stdout");
    app.add_flag("--count-instructions", opt.count,
                 "run under valgrind's callgrind and write each frame's executed instructions per detector to "
                 "--frames instead of times (docs/cpucd.md)");
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        return fail(2, std::string(e.what()) + " (see --help)", opt);
    }
    try {
        // The counting run is this program again, under callgrind.
        if (opt.count) {
            // A count is exact: one run of each section, whatever the default repeats.
            if (app.count("--repeat") && opt.repeat != 1)
                throw rbcd::InputError("--repeat: a count is exact, --count-instructions takes no repeats");
            opt.repeat = 1;
            if (!rbcd::cpucd::counting_under_callgrind()) return rbcd::cpucd::run_under_callgrind(argc, argv);
        }
        return run(opt);
    } catch (const rbcd::InputError& e) {
        return fail(2, e.what(), opt);
    } catch (const rbcd::RunError& e) {
        return fail(1, e.what(), opt);
    } catch (const std::exception& e) {
        return fail(1, std::string("internal error: ") + e.what(), opt);
    }
}
