// Per-frame figures of a run, reduced as frames end: GPU time without and
// with the unit (docs/gpu-model.md), the unit's and the GPU's energy
// (docs/energy.md). Each frame becomes one JSON line for --frame-stats,
// written when its barrier passes, and is folded into totals and bounded
// summaries: memory does not grow with the number of frames.
//
//   RunReport report(sys);                    // before sys.run()
//   report.stream_to([&](const std::string& line) { out.write(line); });   // optional
//   sys.run();
//   report.totals();                          // sums over the frames
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/hw/rasterizer.h"
#include "rbcd/report/energy_model.h"

namespace rbcd {

class rbcd_system;

// One frame's figures (and, summed, the run's).
struct FrameFigures {
    FrameTimes t;                          // the rasterizer's timelines and counts
    // Overhead split; sums to t.with_unit - t.baseline.
    std::uint64_t extra_prims = 0, extra_fragments = 0, unit_no_bank = 0, unit_queue = 0, tail = 0;
    std::uint64_t hits = 0, overflows = 0;   // the unit's, in this frame
    double unit_dynamic_pj = 0, unit_leakage_pj = 0;
    double gpu_baseline_pj = 0;              // the GPU without the unit
    double gpu_with_unit_pj = 0;             // the GPU's own energy with the unit (unit excluded)
    double unit_pj() const { return unit_dynamic_pj + unit_leakage_pj; }
    double with_unit_pj() const { return gpu_with_unit_pj + unit_pj(); }
    bool has_baseline() const { return t.baseline > 0; }
    double overhead_pct() const;             // NaN without a baseline
    double energy_overhead_pct() const;      // NaN without a baseline energy
    void add(const FrameFigures& f);         // sums of the integers (not the frame number, not the energies)
};

// The energies of a run's (or a frame's) integer totals. Every energy is
// linear in the counts and cycles, so a run's is computed once from its sums
// rather than summed frame by frame: the same integers then give the same
// bits, however the frames were split between runs (rbcd-merge).
// `unit`: the unit's activity over those frames (per-bank counts ignored).
void fill_energies(FrameFigures& f, const EnergyCosts& k, const Activity& unit);

// Reductions over frames that merge exactly across consecutive frame ranges
// (docs/stats.md): integer sums, and extrema whose ties go to the earlier frame.
struct FrameReduction {
    std::uint64_t frames = 0, frames_with_baseline = 0;
    std::uint64_t first_frame = 0, last_frame = 0;   // when frames > 0
    // The per-frame overhead percentages summed in millionths of a percent:
    // integers, so that a sum does not depend on how the frames were grouped.
    std::int64_t overhead_sum_e6 = 0;
    bool overhead_sum_overflow = false;
    bool has_worst = false;
    std::uint64_t worst_frame = 0;
    double worst_pct = 0;                // the largest per-frame overhead
    bool has_max_energy = false;
    std::uint64_t max_energy_frame = 0;
    double max_energy_nj = 0;            // the unit's largest per-frame energy

    // Which extrema the frame became.
    struct NewExtrema {
        bool worst = false, max_energy = false;
    };
    NewExtrema add_frame(const FrameFigures& f);
    // `later` holds the frames right after these; false if they are not consecutive.
    bool merge(const FrameReduction& later);
    double mean_overhead_pct() const;    // NaN without frames with a baseline (or on overflow)
    double mean_frame_nj(double unit_pj) const { return frames ? unit_pj * 1e-3 / double(frames) : 0.0; }
};

// The frame as one JSON object (one --frame-stats line; docs/stats.md).
nlohmann::json frame_json(const FrameFigures& f);

class RunReport final : public RasterObserver {
public:
    explicit RunReport(rbcd_system& sys);   // registers itself with sys.raster
    // Each frame's JSON line (with its newline) goes here as the frame ends.
    void stream_to(std::function<void(const std::string&)> out) { out_ = std::move(out); }

    void frame_end(const FrameTimes& t) override;

    // Sums over the frames so far, energies included (fill_energies).
    FrameFigures totals() const;
    // The unit's activity summed over the frames so far.
    const Activity& unit_activity() const { return prev_; }
    const FrameReduction& reduction() const { return red_; }
    std::uint64_t frames() const { return red_.frames; }
    // Over frames with a baseline: mean of per-frame overhead %, the worst frame.
    std::uint64_t frames_with_baseline() const { return red_.frames_with_baseline; }
    double mean_frame_overhead_pct() const { return red_.mean_overhead_pct(); }
    const FrameFigures* worst_frame() const { return red_.has_worst ? &worst_ : nullptr; }
    // The unit's energy per frame: mean and the largest.
    double mean_frame_nj() const { return red_.mean_frame_nj(totals().unit_pj()); }
    const FrameFigures* max_energy_frame() const { return red_.has_max_energy ? &max_energy_ : nullptr; }
    // The first few frames, for the summary on stdout.
    static constexpr std::size_t kFirstFrames = 3;
    const std::vector<FrameFigures>& first_frames() const { return first_; }
    const EnergyCosts& costs() const { return k_; }

private:
    rbcd_system& sys_;
    EnergyCosts k_;
    Activity prev_;                        // cumulative at the previous barrier
    std::uint64_t prev_hits_ = 0, prev_overflows_ = 0;
    std::function<void(const std::string&)> out_;
    FrameFigures totals_;                  // integers only; energies filled by totals()
    FrameReduction red_;
    FrameFigures worst_, max_energy_;      // whole, for the summary's rows
    std::vector<FrameFigures> first_;
};

} // namespace rbcd
