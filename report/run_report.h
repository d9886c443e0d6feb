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

#include "hw/rasterizer.h"
#include "report/energy_model.h"

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
    void add(const FrameFigures& f);         // sums (not the frame number)
};

// The frame as one JSON object (one --frame-stats line; docs/stats.md).
nlohmann::json frame_json(const FrameFigures& f);

class RunReport final : public RasterObserver {
public:
    explicit RunReport(rbcd_system& sys);   // registers itself with sys.raster
    // Each frame's JSON line (with its newline) goes here as the frame ends.
    void stream_to(std::function<void(const std::string&)> out) { out_ = std::move(out); }

    void frame_end(const FrameTimes& t) override;

    const FrameFigures& totals() const { return totals_; }
    std::uint64_t frames() const { return frames_; }
    // Over frames with a baseline: mean of per-frame overhead %, the worst frame.
    std::uint64_t frames_with_baseline() const { return frames_with_baseline_; }
    double mean_frame_overhead_pct() const;
    const FrameFigures* worst_frame() const { return has_worst_ ? &worst_ : nullptr; }
    // The unit's energy per frame: mean and the largest.
    double mean_frame_nj() const;
    const FrameFigures* max_energy_frame() const { return has_max_energy_ ? &max_energy_ : nullptr; }
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
    FrameFigures totals_;
    std::uint64_t frames_ = 0, frames_with_baseline_ = 0;
    double pct_sum_ = 0;
    FrameFigures worst_, max_energy_;
    bool has_worst_ = false, has_max_energy_ = false;
    std::vector<FrameFigures> first_;
};

} // namespace rbcd
