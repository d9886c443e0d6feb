#include "rbcd/report/run_report.h"

#include <cmath>
#include <limits>

#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

nlohmann::json pct_or_null(double v) { return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }

} // namespace

double FrameFigures::overhead_pct() const {
    return t.baseline ? 100.0 * (double(t.with_unit) - double(t.baseline)) / double(t.baseline) : kNaN;
}

double FrameFigures::energy_overhead_pct() const {
    return gpu_baseline_pj > 0 ? 100.0 * (with_unit_pj() - gpu_baseline_pj) / gpu_baseline_pj : kNaN;
}

void FrameFigures::add(const FrameFigures& f) {
    FrameTimes& a = t;
    const FrameTimes& b = f.t;
    a.with_unit += b.with_unit;
    a.gpu_done += b.gpu_done;
    a.flushed += b.flushed;
    a.baseline += b.baseline;
    a.prims_only += b.prims_only;
    a.work += b.work;
    a.tiles += b.tiles;
    a.tiles_with_fragments += b.tiles_with_fragments;
    a.tiles_with_base += b.tiles_with_base;
    a.fragments += b.fragments;
    a.culled += b.culled;
    a.other += b.other;
    a.shaded += b.shaded;
    a.prims += b.prims;
    a.cprims += b.cprims;
    a.stall_no_bank += b.stall_no_bank;
    a.stall_queue_full += b.stall_queue_full;
    a.stall_fragment_queue += b.stall_fragment_queue;
    a.setup_cycles += b.setup_cycles;
    a.extra_setup_cycles += b.extra_setup_cycles;
    a.end_cycle = std::max(a.end_cycle, b.end_cycle);
    extra_prims += f.extra_prims;
    extra_fragments += f.extra_fragments;
    unit_no_bank += f.unit_no_bank;
    unit_queue += f.unit_queue;
    tail += f.tail;
    hits += f.hits;
    overflows += f.overflows;
}

void fill_energies(FrameFigures& f, const EnergyCosts& k, const Activity& unit) {
    const FrameTimes& t = f.t;
    Activity a = unit;
    a.bank_reads.clear();
    a.bank_writes.clear();
    const EnergyReport e = energy_of(k, a, t.with_unit);
    f.unit_dynamic_pj = e.dynamic_pj;
    f.unit_leakage_pj = e.leakage_pj;
    f.gpu_baseline_pj = gpu_energy_pj(k, GpuWork{t.shaded, t.shaded, t.prims, t.tiles}, t.baseline);
    f.gpu_with_unit_pj =
        gpu_energy_pj(k, GpuWork{t.shaded, t.shaded + t.culled, t.prims + t.cprims, t.tiles}, t.with_unit);
}

FrameReduction::NewExtrema FrameReduction::add_frame(const FrameFigures& f) {
    NewExtrema now;
    if (frames == 0) first_frame = f.t.frame;
    last_frame = f.t.frame;
    ++frames;
    if (f.has_baseline()) {
        ++frames_with_baseline;
        const double pct = f.overhead_pct();
        const double q = std::nearbyint(pct * 1e6);
        if (!(std::fabs(q) < 9e18) || __builtin_add_overflow(overhead_sum_e6, std::int64_t(q), &overhead_sum_e6))
            overhead_sum_overflow = true;
        if (!has_worst || pct > worst_pct) {
            has_worst = now.worst = true;
            worst_frame = f.t.frame;
            worst_pct = pct;
        }
    }
    // Compared in nJ, as reported, so that a merge of reports picks the same frame.
    const double nj = f.unit_pj() * 1e-3;
    if (!has_max_energy || nj > max_energy_nj) {
        has_max_energy = now.max_energy = true;
        max_energy_frame = f.t.frame;
        max_energy_nj = nj;
    }
    return now;
}

bool FrameReduction::merge(const FrameReduction& b) {
    if (b.frames == 0) return true;
    if (frames > 0 && b.first_frame != last_frame + 1) return false;
    if (frames == 0) first_frame = b.first_frame;
    last_frame = b.last_frame;
    frames += b.frames;
    frames_with_baseline += b.frames_with_baseline;
    if (b.overhead_sum_overflow ||
        __builtin_add_overflow(overhead_sum_e6, b.overhead_sum_e6, &overhead_sum_e6))
        overhead_sum_overflow = true;
    if (b.has_worst && (!has_worst || b.worst_pct > worst_pct)) {
        has_worst = true;
        worst_frame = b.worst_frame;
        worst_pct = b.worst_pct;
    }
    if (b.has_max_energy && (!has_max_energy || b.max_energy_nj > max_energy_nj)) {
        has_max_energy = true;
        max_energy_frame = b.max_energy_frame;
        max_energy_nj = b.max_energy_nj;
    }
    return true;
}

double FrameReduction::mean_overhead_pct() const {
    if (!frames_with_baseline || overhead_sum_overflow) return kNaN;
    return double(overhead_sum_e6) * 1e-6 / double(frames_with_baseline);
}

nlohmann::json frame_json(const FrameFigures& f) {
    const FrameTimes& t = f.t;
    return {
        {"frame", t.frame},
        {"start_cycle", t.start_cycle},
        {"end_cycle", t.end_cycle},
        {"baseline_cycles", t.baseline},
        {"cycles_with_unit", t.with_unit},
        {"overhead_pct", pct_or_null(f.overhead_pct())},
        {"overhead_cycles",
         {{"extra_primitives", f.extra_prims},
          {"extra_fragments", f.extra_fragments},
          {"unit_no_bank", f.unit_no_bank},
          {"unit_queue", f.unit_queue},
          {"tail", f.tail}}},
        {"gpu_done_cycles", t.gpu_done},
        {"flushed_cycles", t.flushed},
        {"tiles", t.tiles},
        {"fragments", t.fragments},
        {"culled_fragments", t.culled},
        {"other_fragments", t.other},
        {"primitives", t.prims},
        {"culled_primitives", t.cprims},
        {"stalls",
         {{"no_bank_cycles", t.stall_no_bank},
          {"queue_full_cycles", t.stall_queue_full},
          {"fragment_queue_cycles", t.stall_fragment_queue}}},
        {"hits", f.hits},
        {"overflows", f.overflows},
        {"energy_pj",
         {{"unit", f.unit_pj()},
          {"gpu_baseline", f.gpu_baseline_pj},
          {"gpu_with_unit", f.with_unit_pj()},
          {"overhead_pct", pct_or_null(f.energy_overhead_pct())}}},
    };
}

RunReport::RunReport(rbcd_system& sys) : sys_(sys), k_(energy_costs(sys.cfg)) {
    sys.raster.add_observer(this);
}

void RunReport::frame_end(const FrameTimes& t) {
    FrameFigures f;
    f.t = t;
    // Every timeline only adds constraints to the one before it, so each
    // difference is a cost (docs/gpu-model.md, "Where the overhead comes from").
    f.extra_prims = t.cost_extra_prims();
    f.extra_fragments = t.cost_extra_fragments();
    const std::uint64_t unit = t.cost_unit();
    const std::uint64_t waits = t.stall_no_bank + t.stall_queue_full;
    f.unit_no_bank = waits ? std::uint64_t((unsigned __int128)unit * t.stall_no_bank / waits) : 0;
    f.unit_queue = unit - f.unit_no_bank;
    f.tail = t.cost_tail();

    Activity now = activity_of(sys_);
    now.bank_reads.clear();
    now.bank_writes.clear();
    fill_energies(f, k_, now - prev_);
    prev_ = now;
    const std::uint64_t hits = sys_.tester.stats().hits, overflows = sys_.sorter.stats().overflows;
    f.hits = hits - prev_hits_;
    f.overflows = overflows - prev_overflows_;
    prev_hits_ = hits;
    prev_overflows_ = overflows;

    totals_.add(f);
    const FrameReduction::NewExtrema became = red_.add_frame(f);
    if (became.worst) worst_ = f;
    if (became.max_energy) max_energy_ = f;
    if (first_.size() < kFirstFrames) first_.push_back(f);
    if (out_) out_(frame_json(f).dump() + "\n");
}

FrameFigures RunReport::totals() const {
    FrameFigures f = totals_;
    fill_energies(f, k_, prev_);
    return f;
}

} // namespace rbcd
