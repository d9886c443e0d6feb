#include "sc_main/stats_report.h"

#include <algorithm>
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

double overhead_pct(std::uint64_t with, std::uint64_t base) {
    return base ? 100.0 * (double(with) - double(base)) / double(base) : 0.0;
}

nlohmann::json gpu_frame_json(const GpuFrame& g) {
    return {
        {"baseline_cycles", g.baseline_cycles},
        {"cycles_with_unit", g.cycles_with_unit},
        {"overhead_pct", g.overhead_pct()},
        {"extra_raster_cycles", g.extra_raster_cycles},
        {"extra_raster_exposed", g.extra_raster_exposed},
        {"tail_cycles", g.tail_cycles},
        {"stalls",
         {{"no_bank_cycles", g.stall_no_bank_cycles},
          {"queue_full_cycles", g.stall_queue_full_cycles},
          {"no_bank_exposed", g.no_bank_exposed},
          {"queue_full_exposed", g.queue_full_exposed},
          {"feed_excess", g.feed_excess},
          {"no_bank_in_previous_tail", g.no_bank_in_previous_tail}}},
        {"additive_cycles", g.additive_cycles},
    };
}

nlohmann::json energy_blocks_json(const EnergyReport& r) {
    nlohmann::json j = nlohmann::json::object();
    for (const auto& b : r.blocks)
        j[b.name] = {{"dynamic_pj", b.dynamic_pj}, {"leakage_pj", b.leakage_pj}, {"total_pj", b.total_pj()}};
    return j;
}

} // namespace

void RunProbe::attach() {
    auto tile_hook = sys_.feed.on_tile;
    auto frame_hook = sys_.feed.on_frame;
    sys_.feed.on_tile = [this, tile_hook](const Tile& t) {
        on_tile(t);
        if (tile_hook) tile_hook(t);
    };
    sys_.feed.on_frame = [this, frame_hook](std::uint64_t n) {
        on_frame(n);
        if (frame_hook) frame_hook(n);
    };
}

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info, RunProbe* probe) {
    nlohmann::json j;
    const auto& feed = sys.feed.stats();
    const auto& sorter = sys.sorter.stats();
    const auto& tester = sys.tester.stats();
    const std::uint64_t cycles = sys.total_cycles();
    const double simulated_ns = double(cycles) * double(sys.clk.period_ps()) * 1e-3;

    j["format"] = "rbcd-stats 1";
    j["input"] = info.input;
    j["totals"] = {
        {"frames", feed.frames},
        {"tiles", feed.tiles},
        {"fragments", feed.fragments},
        {"overflows", sorter.overflows},
        {"stack_overflows", tester.stack_overflows},
        {"orphan_back_faces", tester.orphan_back_faces},
        {"hits", tester.hits},
        {"cycles", cycles},
    };
    j["time"] = {
        {"clock_mhz", sys.cfg.clock.mhz},
        {"period_ps", sys.clk.period_ps()},
        {"simulated_us", simulated_ns * 1e-3},
        {"wall_seconds", info.wall_seconds},
        {"fragments_per_second", info.wall_seconds > 0 ? double(feed.fragments) / info.wall_seconds : 0.0},
    };

    nlohmann::json blocks;
    blocks["rasterizer_feed"] = block_json(feed);
    for (const auto& b : sys.banks) blocks[b->basename()] = block_json(b->stats());
    blocks["insertion_sorter"] = block_json(sorter);
    blocks["zoverlap_tester"] = block_json(tester);
    blocks["output_buffer"] = block_json(sys.outbuf.stats());
    blocks["memory_controller"] = block_json(sys.memory.stats());
    blocks["host"] = block_json(sys.host.stats());
    j["blocks"] = blocks;

    // Derived figures, each a formula over the counters above.
    j["derived"] = {
        {"sorter_utilization_pct", pct(sorter.busy_cycles, cycles)},
        {"tester_utilization_pct", pct(tester.busy_cycles, cycles)},
        {"feed_stall_pct", pct(feed.stall_no_bank_cycles + feed.stall_queue_full_cycles, cycles)},
        {"overflow_pct_of_fragments", pct(sorter.overflows, feed.fragments)},
        {"fragments_per_cycle", cycles ? double(feed.fragments) / double(cycles) : 0.0},
        {"zeb_bank_bits", sys.banks.empty() ? 0 : sys.banks[0]->bits()},
    };

    // ---- GPU context (docs/gpu-model.md)
    const std::vector<GpuFrame> gframes = probe ? probe->gpu.finish() : GpuModel::per_frame(sys);
    GpuFrame gt;   // totals
    double pct_sum = 0, pct_max = 0;
    std::uint64_t pct_max_frame = 0;
    for (const auto& g : gframes) {
        gt.tiles += g.tiles;
        gt.tiles_with_base += g.tiles_with_base;
        gt.baseline_cycles += g.baseline_cycles;
        gt.extra_raster_cycles += g.extra_raster_cycles;
        gt.extra_raster_exposed += g.extra_raster_exposed;
        gt.estimate_mismatches += g.estimate_mismatches;
        gt.raster_cycles += g.raster_cycles;
        gt.tail_cycles += g.tail_cycles;
        gt.cycles_with_unit += g.cycles_with_unit;
        gt.stall_no_bank_cycles += g.stall_no_bank_cycles;
        gt.stall_queue_full_cycles += g.stall_queue_full_cycles;
        gt.no_bank_exposed += g.no_bank_exposed;
        gt.queue_full_exposed += g.queue_full_exposed;
        gt.feed_excess += g.feed_excess;
        gt.no_bank_in_previous_tail += g.no_bank_in_previous_tail;
        gt.additive_cycles += g.additive_cycles;
        pct_sum += g.overhead_pct();
        if (&g == &gframes.front() || g.overhead_pct() > pct_max) {
            pct_max = g.overhead_pct();
            pct_max_frame = g.frame;
        }
    }
    j["gpu"] = {
        {"model", "tile-paced overlap, docs/gpu-model.md"},
        {"granularity", probe ? "tile" : "frame"},
        {"baseline_cycles", gt.baseline_cycles},
        {"cycles_with_unit", gt.cycles_with_unit},
        {"overhead_pct", gt.overhead_pct()},
        {"overhead_cycles",
         {{"extra_raster", gt.extra_raster_exposed},
          {"stall_no_bank", gt.no_bank_exposed},
          {"stall_queue_full", gt.queue_full_exposed},
          {"feed_excess", gt.feed_excess},
          {"tail", gt.tail_cycles}}},
        {"stalls",
         {{"no_bank_cycles", gt.stall_no_bank_cycles},
          {"queue_full_cycles", gt.stall_queue_full_cycles},
          {"no_bank_exposed", gt.no_bank_exposed},
          {"queue_full_exposed", gt.queue_full_exposed},
          {"no_bank_in_previous_tail", gt.no_bank_in_previous_tail}}},
        {"extra_raster_cycles", gt.extra_raster_cycles},
        {"extra_raster_exposed", gt.extra_raster_exposed},
        {"tail_cycles", gt.tail_cycles},
        {"tiles_with_base", gt.tiles_with_base},
        {"estimate_mismatches", gt.estimate_mismatches},
        {"tiles_estimated", feed.tiles - gt.tiles_with_base},
        {"per_frame_overhead_pct",
         {{"mean", gframes.empty() ? 0.0 : pct_sum / double(gframes.size())},
          {"max", pct_max},
          {"max_frame", pct_max_frame}}},
        {"additive_upper_bound",
         {{"cycles", gt.additive_cycles}, {"overhead_pct", overhead_pct(gt.additive_cycles, gt.baseline_cycles)}}},
    };

    // ---- Energy (docs/energy.md)
    const EnergyCosts k = energy_costs(sys.cfg);
    const EnergyReport et = energy_of(k, activity_of(sys), cycles);
    const auto& ff = sys.feed.frames();
    const auto& tf = sys.tester.frames();
    std::vector<EnergyReport> eframes;
    std::string basis;
    {
        // Leakage runs over each frame's share of the timeline: from the unit's end of
        // the previous frame to its end of this one; the last frame runs to the end.
        std::vector<std::uint64_t> span(ff.size(), 0);
        std::uint64_t prev = 0;
        for (std::size_t i = 0; i < ff.size(); ++i) {
            std::uint64_t end = i < tf.size() ? tf[i].done : ff[i].end;
            if (i + 1 == ff.size()) end = cycles;
            end = std::max(end, prev);
            span[i] = end - prev;
            prev = end;
        }
        if (probe) {
            const std::vector<Activity> acts = probe->energy.frames();
            basis = probe->energy.unit_boundaries_seen()
                        ? "counter snapshots: feed-side blocks at the feed's frame end, unit-side at the unit's"
                        : "counter snapshots at the feed's frame ends (unit-side boundaries not wired)";
            for (std::size_t i = 0; i < ff.size(); ++i) eframes.push_back(energy_of(k, acts[i], span[i]));
        } else {
            basis = "the run's dynamic energy apportioned by the frame's fragments";
            Activity none;
            for (std::size_t i = 0; i < ff.size(); ++i) {
                EnergyReport r = energy_of(k, none, span[i]);   // leakage only, per block
                const double share = feed.fragments ? double(ff[i].fragments) / double(feed.fragments) : 0.0;
                r.dynamic_pj = 0;
                for (auto& b : r.blocks) {
                    const BlockEnergy* tb = et.find(b.name);
                    if (!tb && b.name == "zeb") {
                        for (const auto& x : et.blocks)
                            if (x.name.rfind("zeb_bank", 0) == 0) b.dynamic_pj += x.dynamic_pj * share;
                    } else if (tb) {
                        b.dynamic_pj = tb->dynamic_pj * share;
                    }
                    r.dynamic_pj += b.dynamic_pj;
                }
                eframes.push_back(r);
            }
        }
    }
    double e_max = 0, e_sum = 0;
    std::uint64_t e_max_frame = 0;
    for (std::size_t i = 0; i < eframes.size(); ++i) {
        const double nj = eframes[i].total_pj() * 1e-3;
        e_sum += nj;
        if (i == 0 || nj > e_max) {
            e_max = nj;
            e_max_frame = ff[i].frame;
        }
    }
    j["energy"] = {
        {"model", "docs/energy.md"},
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
        {"per_frame",
         {{"basis", basis},
          {"mean_nj", eframes.empty() ? 0.0 : e_sum / double(eframes.size())},
          {"max_nj", e_max},
          {"max_frame", e_max_frame}}},
    };

    // ---- Per-frame entries and series
    nlohmann::json frames = nlohmann::json::array();
    nlohmann::json s_frame = nlohmann::json::array(), s_base = nlohmann::json::array(),
                   s_with = nlohmann::json::array(), s_pct = nlohmann::json::array(),
                   s_nj = nlohmann::json::array();
    for (std::size_t i = 0; i < ff.size(); ++i) {
        const auto& f = ff[i];
        nlohmann::json fj = {
            {"frame", f.frame},
            {"feed_start_cycle", f.start},
            {"feed_end_cycle", f.end},
            {"tiles", f.tiles},
            {"tiles_with_base", f.tiles_with_base},
            {"fragments", f.fragments},
            {"culled_fragments", f.culled},
            {"other_fragments", f.other},
            {"stall_no_bank_cycles", f.stall_no_bank},
            {"stall_queue_full_cycles", f.stall_queue_full},
        };
        if (i < tf.size()) {
            fj["flushed_cycle"] = tf[i].flushed;
            fj["done_cycle"] = tf[i].done;
        }
        fj["gpu"] = gpu_frame_json(gframes[i]);
        nlohmann::json ej = nlohmann::json::object();
        for (const auto& b : eframes[i].blocks) ej[b.name] = b.total_pj();
        ej["dynamic"] = eframes[i].dynamic_pj;
        ej["leakage"] = eframes[i].leakage_pj;
        ej["total"] = eframes[i].total_pj();
        fj["energy_pj"] = ej;
        fj["energy_nj"] = eframes[i].total_pj() * 1e-3;
        frames.push_back(fj);
        s_frame.push_back(f.frame);
        s_base.push_back(gframes[i].baseline_cycles);
        s_with.push_back(gframes[i].cycles_with_unit);
        s_pct.push_back(gframes[i].overhead_pct());
        s_nj.push_back(eframes[i].total_pj() * 1e-3);
    }
    j["frames"] = frames;
    j["series"] = {{"frame", s_frame},
                   {"baseline_cycles", s_base},
                   {"cycles_with_unit", s_with},
                   {"overhead_pct", s_pct},
                   {"energy_nj", s_nj}};
    j["config"] = config_json(sys.cfg);
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

std::string make_summary(const nlohmann::json& s) {
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
    out += fmt("\n  %-18s %7s %11s  %s\n", "block", "busy", "energy nJ", "stalls (cycles) | counters");
    auto row = [&](const std::string& name, const std::string& bz, const std::string& en, const std::string& rest) {
        out += fmt("  %-18s %7s %11s  %s\n", name.c_str(), bz.c_str(), en.c_str(), rest.c_str());
    };
    {
        const auto& f = b["rasterizer_feed"];
        row("rasterizer_feed", busy(u(f, "busy_cycles")), "-",
            fmt("no bank %llu, queue full %llu | fragments %llu (c %llu), other %llu", ull(u(f, "stall_no_bank_cycles")),
                ull(u(f, "stall_queue_full_cycles")), ull(u(f, "fragments")), ull(u(f, "culled_fragments")),
                ull(u(f, "other_fragments"))));
        const auto& so = b["insertion_sorter"];
        row("input_queue", "-", energy("input_queue"),
            fmt("- | writes %llu, max occupancy %llu", ull(u(so, "insertions")), ull(u(so, "queue_max_occupancy"))));
        for (auto it = b.begin(); it != b.end(); ++it) {
            if (it.key().rfind("zeb_bank", 0) != 0) continue;
            const auto& z = it.value();
            row(it.key(), busy(u(z, "filling_cycles") + u(z, "testing_cycles")), energy(it.key()),
                fmt("- | tiles %llu, row reads %llu, row writes %llu", ull(u(z, "tiles")), ull(u(z, "row_reads")),
                    ull(u(z, "row_writes"))));
        }
        row("insertion_sorter", busy(u(so, "busy_cycles")), energy("insertion_sorter"),
            fmt("hazard %llu | insertions %llu, overflows %llu", ull(u(so, "hazard_stall_cycles")),
                ull(u(so, "insertions")), ull(u(so, "overflows"))));
        const auto& te = b["zoverlap_tester"];
        row("zoverlap_tester", busy(u(te, "busy_cycles")), energy("zoverlap_tester"),
            fmt("output %llu, readback %llu | lists %llu, elements %llu, hits %llu", ull(u(te, "output_stall_cycles")),
                ull(u(te, "readback_cycles")), ull(u(te, "lists")), ull(u(te, "elements")), ull(u(te, "hits"))));
        const auto& ob = b["output_buffer"];
        row("output_buffer", "-", energy("output_buffer"),
            fmt("full %llu, outstanding %llu | records %llu, bursts %llu", ull(u(ob, "full_stall_cycles")),
                ull(u(ob, "outstanding_stall_cycles")), ull(u(ob, "records")), ull(u(ob, "bursts"))));
        const auto& m = b["memory_controller"];
        row("memory", busy(u(m, "busy_cycles")), energy("memory"),
            fmt("queue %llu | writes %llu, bytes %llu", ull(u(m, "queue_cycles")), ull(u(m, "writes")),
                ull(u(m, "bytes_written"))));
    }
    if (s.contains("energy")) {
        const auto& e = s["energy"];
        out += fmt("  energy: %.1f nJ (dynamic %.1f, leakage %.1f), %.2f nJ per frame, average power %.3f mW\n",
                   d(e, "total_nj"), d(e, "dynamic_pj") * 1e-3, d(e, "leakage_pj") * 1e-3,
                   d(e["per_frame"], "mean_nj"), d(e, "average_power_mw"));
    }

    // ---- GPU overhead
    if (s.contains("gpu")) {
        const auto& g = s["gpu"];
        const auto& oc = g["overhead_cycles"];
        out += fmt("\n  GPU time (docs/gpu-model.md): baseline %llu cycles, with the unit %llu: overhead %+.2f%%\n",
                   ull(u(g, "baseline_cycles")), ull(u(g, "cycles_with_unit")), d(g, "overhead_pct"));
        out += fmt("    extra raster %llu (of %llu), no-bank stall %llu (of %llu), queue-full stall %llu (of %llu), "
                   "feed excess %llu, tail %llu\n",
                   ull(u(oc, "extra_raster")), ull(u(g, "extra_raster_cycles")), ull(u(oc, "stall_no_bank")),
                   ull(u(g["stalls"], "no_bank_cycles")),
                   ull(u(oc, "stall_queue_full")), ull(u(g["stalls"], "queue_full_cycles")),
                   ull(u(oc, "feed_excess")), ull(u(oc, "tail")));
        const auto& fr = s["frames"];
        if (!fr.empty()) {
            out += fmt("  %8s %12s %12s %10s %11s\n", "frame", "baseline", "with unit", "overhead", "energy nJ");
            auto frame_row = [&](const std::string& label, const nlohmann::json& f) {
                out += fmt("  %8s %12llu %12llu %9.2f%% %11.1f\n", label.c_str(), ull(u(f["gpu"], "baseline_cycles")),
                           ull(u(f["gpu"], "cycles_with_unit")), d(f["gpu"], "overhead_pct"), d(f, "energy_nj"));
            };
            const std::size_t n = fr.size();
            constexpr std::size_t kAll = 8, kFirst = 3;
            if (n <= kAll) {
                for (const auto& f : fr) frame_row(std::to_string(u(f, "frame")), f);
            } else {
                for (std::size_t i = 0; i < kFirst; ++i) frame_row(std::to_string(u(fr[i], "frame")), fr[i]);
                out += fmt("  %8s\n", "...");
                std::size_t worst = 0;
                double sb = 0, sw = 0, sn = 0;
                for (std::size_t i = 0; i < n; ++i) {
                    if (d(fr[i]["gpu"], "overhead_pct") > d(fr[worst]["gpu"], "overhead_pct")) worst = i;
                    sb += double(u(fr[i]["gpu"], "baseline_cycles"));
                    sw += double(u(fr[i]["gpu"], "cycles_with_unit"));
                    sn += d(fr[i], "energy_nj");
                }
                frame_row("worst " + std::to_string(u(fr[worst], "frame")), fr[worst]);
                out += fmt("  %8s %12.0f %12.0f %9.2f%% %11.1f   (over %zu frames; mean of per-frame %%: %.2f%%)\n",
                           "mean", sb / double(n), sw / double(n), sb > 0 ? 100.0 * (sw - sb) / sb : 0.0,
                           sn / double(n), n, d(g["per_frame_overhead_pct"], "mean"));
            }
        }
    }
    return out;
}

} // namespace rbcd
