#include "rbcd/report/stats_report.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <toml++/toml.h>

namespace rbcd {

namespace {

template <class Stats>
nlohmann::json block_json(const Stats& s) {
    nlohmann::json j = nlohmann::json::object();
    s.for_each([&](const char* name, std::uint64_t v, const char*) { j[name] = v; });
    return j;
}

nlohmann::json config_json(const SimConfig& cfg) {
    // Round-trip through the TOML dump so the JSON shows exactly what --dump-config prints.
    nlohmann::json j = nlohmann::json::object();
    const toml::table t = toml::parse(dump_config_toml(cfg));
    for (const auto& [sec, node] : t) {
        nlohmann::json s = nlohmann::json::object();
        for (const auto& [k, v] : *node.as_table()) {
            const std::string key(k.str());
            if (v.is_integer()) s[key] = *v.value<std::int64_t>();
            else if (v.is_floating_point()) s[key] = *v.value<double>();
            else if (v.is_string()) s[key] = *v.value<std::string>();
            else if (v.is_boolean()) s[key] = *v.value<bool>();
        }
        j[std::string(sec.str())] = s;
    }
    return j;
}

double pct(std::uint64_t part, std::uint64_t whole) { return whole ? 100.0 * double(part) / double(whole) : 0.0; }

nlohmann::json num_or_null(double v) { return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v); }

nlohmann::json energy_blocks_json(const EnergyReport& r) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& b : r.blocks)
        j[b.name] = {{"dynamic_pj", b.dynamic_pj}, {"leakage_pj", b.leakage_pj}, {"total_pj", b.total_pj()}};
    return j;
}

// ---- GPU time (docs/gpu-model.md)
nlohmann::json gpu_json(const RunSnapshot& s, const FrameFigures& t) {
    const FrameReduction& r = s.frames;
    return {
        {"model", "paced raster pipeline, docs/gpu-model.md"},
        {"bank_wait", to_string(s.cfg.gpu.bank_wait)},
        {"baseline_cycles", t.t.baseline},
        {"cycles_with_unit", t.t.with_unit},
        {"overhead_pct", num_or_null(t.overhead_pct())},
        {"overhead_cycles",
         {{"extra_primitives", t.extra_prims},
          {"extra_fragments", t.extra_fragments},
          {"unit_no_bank", t.unit_no_bank},
          {"unit_queue", t.unit_queue},
          {"tail", t.tail}}},
        {"stalls",
         {{"no_bank_cycles", t.t.stall_no_bank},
          {"queue_full_cycles", t.t.stall_queue_full},
          {"fragment_queue_cycles", t.t.stall_fragment_queue}}},
        {"primitives", t.t.prims},
        {"culled_primitives", t.t.cprims},
        {"tiles", t.t.tiles},
        {"tiles_with_base", t.t.tiles_with_base},
        {"shaded_fragments", t.t.shaded},
        {"culled_fragments", t.t.culled},
        {"per_frame_overhead_pct",
         {{"mean", num_or_null(r.mean_overhead_pct())},
          {"max", r.has_worst ? num_or_null(r.worst_pct) : nlohmann::json(nullptr)},
          {"max_frame", r.has_worst ? nlohmann::json(r.worst_frame) : nlohmann::json(nullptr)},
          {"frames_without_baseline", r.frames - r.frames_with_baseline},
          {"sum_e6", r.overhead_sum_overflow ? nlohmann::json(nullptr) : nlohmann::json(r.overhead_sum_e6)}}},
    };
}

// ---- Energy (docs/energy.md)
nlohmann::json energy_json(const RunSnapshot& s, const EnergyCosts& k, const FrameFigures& t, double simulated_ns) {
    const FrameReduction& r = s.frames;
    const EnergyReport et = energy_of(k, activity_of(s.counters), s.cycles);
    return {
        {"model", "docs/energy.md"},
        {"zeb_device", to_string(s.cfg.energy.zeb_device)},
        {"bank_bits", k.bank_bits},
        {"row_bits", k.row_bits},
        {"sram_scale", k.sram_scale},
        {"per_event_pj",
         {{"zeb_row_read", k.row_read_pj},
          {"zeb_row_write", k.row_write_pj},
          {"queue_write", k.queue_write_pj},
          {"comparator", k.comparator_pj},
          {"mux_element", k.mux_element_pj},
          {"stack_push", k.stack_push_pj},
          {"stack_match", k.stack_match_pj},
          {"id_compare", k.id_compare_pj},
          {"buffer_record", k.buffer_record_pj},
          {"memory_byte", k.memory_byte_pj}}},
        {"leakage_mw",
         {{"zeb_bank_each", k.bank_leakage_mw},
          {"input_queue", k.queue_leakage_mw},
          {"insertion_sorter", k.sorter_leakage_mw},
          {"zoverlap_tester", k.tester_leakage_mw},
          {"output_buffer", k.buffer_leakage_mw}}},
        {"blocks", energy_blocks_json(et)},
        {"dynamic_pj", et.dynamic_pj},
        {"leakage_pj", et.leakage_pj},
        {"total_pj", et.total_pj()},
        {"total_nj", et.total_pj() * 1e-3},
        {"average_power_mw", simulated_ns > 0 ? et.total_pj() / simulated_ns : 0.0},
        {"gpu",
         {{"baseline_pj", t.gpu_baseline_pj},
          {"with_unit_pj", t.with_unit_pj()},
          {"gpu_with_unit_pj", t.gpu_with_unit_pj},
          {"unit_pj", t.unit_pj()},
          {"overhead_pct", num_or_null(t.energy_overhead_pct())}}},
        {"per_frame",
         {{"basis", "the unit's counters at each frame barrier; leakage over the frame's time with the unit"},
          {"mean_nj", r.mean_frame_nj(t.unit_pj())},
          {"max_nj", r.has_max_energy ? r.max_energy_nj : 0.0},
          {"max_frame", r.has_max_energy ? nlohmann::json(r.max_energy_frame) : nlohmann::json(nullptr)}}},
    };
}

} // namespace

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info, const RunReport& report) {
    return make_stats(snapshot_of(sys, report, info.input), info.wall_seconds);
}

nlohmann::json make_stats(const RunSnapshot& s, double wall_seconds) {
    nlohmann::json j;
    const UnitCounters& c = s.counters;
    const auto& raster = c.raster;
    const auto& sorter = c.sorter;
    const auto& tester = c.tester;
    const std::uint64_t cycles = s.cycles;
    const std::uint64_t period_ps = s.cfg.clock.period_ps();
    const double simulated_ns = double(cycles) * double(period_ps) * 1e-3;
    const EnergyCosts k = energy_costs(s.cfg);
    FrameFigures t = s.gpu;
    fill_energies(t, k, activity_of(c));
    const FrameReduction& r = s.frames;

    j["format"] = "rbcd-stats 2";
    j["input"] = s.input;
    j["totals"] = {
        {"frames", raster.frames},
        {"tiles", raster.tiles},
        {"fragments", raster.fragments},
        {"overflows", sorter.overflows},
        {"stack_overflows", tester.stack_overflows},
        {"orphan_back_faces", tester.orphan_back_faces},
        {"hits", tester.hits},
        {"cycles", cycles},
    };
    j["frame_range"] = r.frames ? nlohmann::json{{"first", r.first_frame}, {"last", r.last_frame}} : nlohmann::json(nullptr);
    j["time"] = {
        {"clock_mhz", s.cfg.clock.mhz},
        {"period_ps", period_ps},
        {"simulated_us", simulated_ns * 1e-3},
        {"wall_seconds", wall_seconds},
        {"fragments_per_second", wall_seconds > 0 ? double(raster.fragments) / wall_seconds : 0.0},
    };

    nlohmann::json blocks;
    c.for_each_block([&](const std::string& name, const auto& stats) { blocks[name] = block_json(stats); });
    j["blocks"] = blocks;

    // Derived figures, each a formula over the counters above.
    const auto& fp = c.fragments;
    j["derived"] = {
        {"sorter_utilization_pct", pct(sorter.busy_cycles, cycles)},
        {"tester_utilization_pct", pct(tester.busy_cycles, cycles)},
        {"fragment_processor_utilization_pct", pct(fp.busy_cycles, fp.busy_cycles + fp.idle_cycles)},
        {"rasterizer_stall_pct",
         pct(raster.stall_no_bank_cycles + raster.stall_queue_full_cycles + raster.stall_fragment_queue_cycles, cycles)},
        {"overflow_pct_of_fragments", pct(sorter.overflows, raster.fragments)},
        {"fragments_per_cycle", cycles ? double(raster.fragments) / double(cycles) : 0.0},
        {"zeb_bank_bits", k.bank_bits},
    };

    j["gpu"] = gpu_json(s, t);
    j["energy"] = energy_json(s, k, t, simulated_ns);
    j["config"] = config_json(s.cfg);
    return j;
}

namespace {

std::uint64_t u(const nlohmann::json& j, const char* key) {
    return j.contains(key) && j[key].is_number() ? j[key].get<std::uint64_t>() : 0;
}
double d(const nlohmann::json& j, const char* key) {
    return j.contains(key) && j[key].is_number() ? j[key].get<double>() : 0.0;
}

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...) {
    char buf[512];
    va_list ap;
    va_start(ap, f);
    std::vsnprintf(buf, sizeof buf, f, ap);
    va_end(ap);
    return buf;
}

using ull = unsigned long long;

} // namespace

SummaryFrames summary_frames(const RunReport& report) {
    SummaryFrames f;
    f.totals = report.totals();
    f.frames = report.frames();
    f.mean_overhead_pct = report.mean_frame_overhead_pct();
    for (const auto& x : report.first_frames()) f.first.push_back(frame_json(x));
    if (const FrameFigures* w = report.worst_frame()) f.worst = frame_json(*w);
    return f;
}

FrameFigures snapshot_totals(const RunSnapshot& s) {
    FrameFigures t = s.gpu;
    fill_energies(t, energy_costs(s.cfg), activity_of(s.counters));
    return t;
}

std::string make_summary(const nlohmann::json& s, const RunReport& report) { return make_summary(s, summary_frames(report)); }

std::string make_summary(const nlohmann::json& s, const SummaryFrames& frames) {
    const auto& t = s["totals"];
    const auto& b = s["blocks"];
    const std::uint64_t cycles = u(t, "cycles");
    std::string out;
    out += fmt("rbcd-sim: %s\n", s["input"].get<std::string>().c_str());
    out += fmt("  frames %llu  tiles %llu  fragments %llu  cycles %llu (%.1f us at %.0f MHz)\n", ull(u(t, "frames")),
               ull(u(t, "tiles")), ull(u(t, "fragments")), ull(cycles), d(s["time"], "simulated_us"),
               d(s["time"], "clock_mhz"));
    out += fmt("  hits %llu  overflows %llu  stack_overflows %llu  orphan_back_faces %llu\n", ull(u(t, "hits")),
               ull(u(t, "overflows")), ull(u(t, "stack_overflows")), ull(u(t, "orphan_back_faces")));

    // ---- Blocks
    const nlohmann::json eb = s.contains("energy") ? s["energy"]["blocks"] : nlohmann::json::object();
    auto energy = [&](const std::string& name) -> std::string {
        if (!eb.contains(name)) return "-";
        return fmt("%.1f", d(eb[name], "total_pj") * 1e-3);
    };
    auto busy = [&](std::uint64_t c) { return cycles ? fmt("%.1f%%", 100.0 * double(c) / double(cycles)) : "-"; };
    out += fmt("\n  %-20s %7s %11s  %s\n", "block", "busy", "energy nJ", "stalls (cycles) | counters");
    auto row = [&](const std::string& name, const std::string& bz, const std::string& en, const std::string& rest) {
        out += fmt("  %-20s %7s %11s  %s\n", name.c_str(), bz.c_str(), en.c_str(), rest.c_str());
    };
    {
        const auto& r = b["rasterizer"];
        row("rasterizer", busy(u(r, "busy_cycles")), "-",
            fmt("no bank %llu, unit queue %llu, fragment queue %llu | fragments %llu (c %llu), other %llu, "
                "prims %llu (c %llu)",
                ull(u(r, "stall_no_bank_cycles")), ull(u(r, "stall_queue_full_cycles")),
                ull(u(r, "stall_fragment_queue_cycles")), ull(u(r, "fragments")), ull(u(r, "culled_fragments")),
                ull(u(r, "other_fragments")), ull(u(r, "primitives")), ull(u(r, "culled_primitives"))));
        const auto& fp = b["fragment_processors"];
        const std::uint64_t fp_all = u(fp, "busy_cycles") + u(fp, "idle_cycles");
        row("fragment_processors", fp_all ? fmt("%.1f%%", 100.0 * double(u(fp, "busy_cycles")) / double(fp_all)) : "-",
            "-", fmt("- | fragments shaded %llu", ull(u(fp, "fragments"))));
        const auto& iq = b["input_queue"];
        row("input_queue", "-", energy("input_queue"),
            fmt("- | writes %llu, max occupancy %llu", ull(u(iq, "writes")), ull(u(iq, "max_occupancy"))));
        for (auto it = b.begin(); it != b.end(); ++it) {
            if (it.key().rfind("zeb_bank", 0) != 0) continue;
            const auto& z = it.value();
            row(it.key(), busy(u(z, "filling_cycles") + u(z, "testing_cycles")), energy(it.key()),
                fmt("- | tiles %llu, row reads %llu, row writes %llu", ull(u(z, "tiles")), ull(u(z, "row_reads")),
                    ull(u(z, "row_writes"))));
        }
        const auto& so = b["insertion_sorter"];
        row("insertion_sorter", busy(u(so, "busy_cycles")), energy("insertion_sorter"),
            fmt("hazard %llu, bank %llu | insertions %llu, overflows %llu", ull(u(so, "hazard_stall_cycles")),
                ull(u(so, "bank_wait_cycles")), ull(u(so, "insertions")), ull(u(so, "overflows"))));
        const auto& te = b["zoverlap_tester"];
        row("zoverlap_tester", busy(u(te, "busy_cycles")), energy("zoverlap_tester"),
            fmt("output %llu, readback %llu | lists %llu, elements %llu, hits %llu", ull(u(te, "output_stall_cycles")),
                ull(u(te, "readback_cycles")), ull(u(te, "lists")), ull(u(te, "elements")), ull(u(te, "hits"))));
        const auto& ob = b["output_buffer"];
        row("output_buffer", "-", energy("output_buffer"),
            fmt("full %llu, outstanding %llu, region %llu | records %llu, bursts %llu", ull(u(ob, "full_stall_cycles")),
                ull(u(ob, "outstanding_stall_cycles")), ull(u(ob, "region_wait_cycles")), ull(u(ob, "records")),
                ull(u(ob, "bursts"))));
        const auto& m = b["memory_controller"];
        row("memory", busy(u(m, "busy_cycles")), energy("memory"),
            fmt("queue %llu | writes %llu, bytes %llu", ull(u(m, "queue_cycles")), ull(u(m, "writes")),
                ull(u(m, "bytes_written"))));
    }
    const auto& e = s["energy"];
    out += fmt("  unit energy: %.1f nJ (dynamic %.1f, leakage %.1f), %.2f nJ per frame, average power %.3f mW\n",
               d(e, "total_nj"), d(e, "dynamic_pj") * 1e-3, d(e, "leakage_pj") * 1e-3, d(e["per_frame"], "mean_nj"),
               d(e, "average_power_mw"));

    // ---- GPU time and energy
    const auto& g = s["gpu"];
    const auto& oc = g["overhead_cycles"];
    const FrameFigures& tot = frames.totals;
    const auto pct_text = [](double v) { return std::isnan(v) ? std::string("n/a") : fmt("%+.2f%%", v); };
    out += fmt("\n  GPU time (docs/gpu-model.md, bank wait: %s): baseline %llu cycles, with the unit %llu: %s\n",
               g["bank_wait"].get<std::string>().c_str(), ull(u(g, "baseline_cycles")), ull(u(g, "cycles_with_unit")),
               pct_text(tot.overhead_pct()).c_str());
    out += fmt("    from extra primitives %llu, extra fragments %llu, unit queue %llu, no bank %llu, frame-end tail %llu\n",
               ull(u(oc, "extra_primitives")), ull(u(oc, "extra_fragments")), ull(u(oc, "unit_queue")),
               ull(u(oc, "unit_no_bank")), ull(u(oc, "tail")));
    out += fmt("  GPU energy (docs/energy.md): baseline %.1f nJ, with the unit %.1f nJ (unit %.1f): %s\n",
               tot.gpu_baseline_pj * 1e-3, tot.with_unit_pj() * 1e-3, tot.unit_pj() * 1e-3,
               pct_text(tot.energy_overhead_pct()).c_str());
    const std::uint64_t n = frames.frames;
    if (n) {
        out += fmt("  %10s %12s %12s %10s %10s %11s\n", "frame", "baseline", "with unit", "time", "energy", "unit nJ");
        // From the frame's --frame-stats object, whose numbers read back to the same bits.
        auto frame_row = [&](const std::string& label, const nlohmann::json& f) {
            const auto pct = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : std::nan(""); };
            const nlohmann::json& e = f["energy_pj"];
            out += fmt("  %10s %12llu %12llu %10s %10s %11.1f\n", label.c_str(), ull(u(f, "baseline_cycles")),
                       ull(u(f, "cycles_with_unit")), pct_text(pct(f["overhead_pct"])).c_str(),
                       pct_text(pct(e["overhead_pct"])).c_str(), d(e, "unit") * 1e-3);
        };
        for (const auto& f : frames.first) frame_row(std::to_string(u(f, "frame")), f);
        if (n > frames.first.size()) {
            out += fmt("  %10s\n", "...");
            if (frames.worst.is_object()) frame_row("worst " + std::to_string(u(frames.worst, "frame")), frames.worst);
            out += fmt("  %10s %12.0f %12.0f %10s %10s %11.1f   (over %llu frames; mean of per-frame %%: %s)\n", "mean",
                       double(tot.t.baseline) / double(n), double(tot.t.with_unit) / double(n),
                       pct_text(tot.overhead_pct()).c_str(), pct_text(tot.energy_overhead_pct()).c_str(),
                       tot.unit_pj() * 1e-3 / double(n), ull(n), pct_text(frames.mean_overhead_pct).c_str());
        }
    }
    return out;
}

} // namespace rbcd
