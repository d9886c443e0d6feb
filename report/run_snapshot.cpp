#include "rbcd/report/run_snapshot.h"

#include <algorithm>
#include <vector>

#include <toml++/toml.h>

#include "rbcd/common/errors.h"
#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

RunSnapshot snapshot_of(const rbcd_system& sys, const RunReport& report, const std::string& input) {
    RunSnapshot s;
    s.input = input;
    s.cfg = sys.cfg;
    s.cycles = sys.total_cycles();
    s.counters = UnitCounters::of(sys);
    s.gpu = report.totals();
    s.frames = report.reduction();
    return s;
}

namespace {

[[noreturn]] void bad(const std::string& key, const std::string& what) {
    throw InputError("stats: " + key + ": " + what);
}

const nlohmann::json& at(const nlohmann::json& j, const std::string& path, const char* key) {
    if (!j.is_object() || !j.contains(key)) bad(path + key, "missing");
    return j[key];
}

std::uint64_t u64(const nlohmann::json& j, const std::string& path, const char* key) {
    const nlohmann::json& v = at(j, path, key);
    if (!v.is_number_unsigned()) bad(path + key, "not an unsigned integer");
    return v.get<std::uint64_t>();
}

// A double, or NaN for null.
double num(const nlohmann::json& j, const std::string& path, const char* key) {
    const nlohmann::json& v = at(j, path, key);
    if (v.is_null()) return std::numeric_limits<double>::quiet_NaN();
    if (!v.is_number()) bad(path + key, "not a number");
    return v.get<double>();
}

SimConfig config_from_json(const nlohmann::json& c) {
    toml::table t;
    for (auto sec = c.begin(); sec != c.end(); ++sec) {
        if (!sec.value().is_object()) bad("config." + sec.key(), "not a table");
        toml::table s;
        for (auto k = sec.value().begin(); k != sec.value().end(); ++k) {
            const nlohmann::json& v = k.value();
            if (v.is_boolean()) s.insert(k.key(), v.get<bool>());
            else if (v.is_number_integer()) s.insert(k.key(), v.get<std::int64_t>());
            else if (v.is_number_float()) s.insert(k.key(), v.get<double>());
            else if (v.is_string()) s.insert(k.key(), v.get<std::string>());
            else bad("config." + sec.key() + "." + k.key(), "not a configuration value");
        }
        t.insert(sec.key(), std::move(s));
    }
    SimConfig cfg;
    apply_config_table(cfg, t, "stats config");
    return cfg;
}

// Every counter of every block, in order, as (block.key, value).
template <class C, class V> void each_counter(C& counters, V v) {
    counters.for_each_block([&](const std::string& block, auto& stats) {
        stats.for_each([&](const char* key, auto& value, const char*) { v(block, key, value); });
    });
}

} // namespace

RunSnapshot snapshot_from_stats(const nlohmann::json& j) {
    if (!j.is_object() || !j.contains("format") || j["format"] != "rbcd-stats 2")
        bad("format", "not \"rbcd-stats 2\"");
    RunSnapshot s;
    const nlohmann::json& input = at(j, "", "input");
    if (!input.is_string()) bad("input", "not a string");
    s.input = input.get<std::string>();
    s.cfg = config_from_json(at(j, "", "config"));
    s.cycles = u64(at(j, "", "totals"), "totals.", "cycles");

    // The banks' names come from the configuration, as in the model.
    for (unsigned i = 0; i < s.cfg.zeb.banks; ++i) s.counters.banks.emplace_back("zeb_bank" + std::to_string(i), zeb_bank::stats_t{});
    const nlohmann::json& blocks = at(j, "", "blocks");
    each_counter(s.counters, [&](const std::string& block, const char* key, std::uint64_t& v) {
        v = u64(at(blocks, "blocks.", block.c_str()), "blocks." + block + ".", key);
    });

    const nlohmann::json& g = at(j, "", "gpu");
    FrameTimes& t = s.gpu.t;
    t.baseline = u64(g, "gpu.", "baseline_cycles");
    t.with_unit = u64(g, "gpu.", "cycles_with_unit");
    t.tiles = u64(g, "gpu.", "tiles");
    t.shaded = u64(g, "gpu.", "shaded_fragments");
    t.culled = u64(g, "gpu.", "culled_fragments");
    t.prims = u64(g, "gpu.", "primitives");
    t.cprims = u64(g, "gpu.", "culled_primitives");
    t.tiles_with_base = u64(g, "gpu.", "tiles_with_base");
    const nlohmann::json& oc = at(g, "gpu.", "overhead_cycles");
    s.gpu.extra_prims = u64(oc, "gpu.overhead_cycles.", "extra_primitives");
    s.gpu.extra_fragments = u64(oc, "gpu.overhead_cycles.", "extra_fragments");
    s.gpu.unit_no_bank = u64(oc, "gpu.overhead_cycles.", "unit_no_bank");
    s.gpu.unit_queue = u64(oc, "gpu.overhead_cycles.", "unit_queue");
    s.gpu.tail = u64(oc, "gpu.overhead_cycles.", "tail");
    const nlohmann::json& st = at(g, "gpu.", "stalls");
    t.stall_no_bank = u64(st, "gpu.stalls.", "no_bank_cycles");
    t.stall_queue_full = u64(st, "gpu.stalls.", "queue_full_cycles");
    t.stall_fragment_queue = u64(st, "gpu.stalls.", "fragment_queue_cycles");

    FrameReduction& r = s.frames;
    r.frames = u64(at(j, "", "totals"), "totals.", "frames");
    const nlohmann::json& range = at(j, "", "frame_range");
    if (r.frames > 0) {
        r.first_frame = u64(range, "frame_range.", "first");
        r.last_frame = u64(range, "frame_range.", "last");
    }
    const nlohmann::json& pf = at(g, "gpu.", "per_frame_overhead_pct");
    const std::uint64_t without = u64(pf, "gpu.per_frame_overhead_pct.", "frames_without_baseline");
    if (without > r.frames) bad("gpu.per_frame_overhead_pct.frames_without_baseline", "more than totals.frames");
    r.frames_with_baseline = r.frames - without;
    const nlohmann::json& sum = at(pf, "gpu.per_frame_overhead_pct.", "sum_e6");
    if (sum.is_null()) r.overhead_sum_overflow = r.frames_with_baseline > 0;
    else if (sum.is_number_integer()) r.overhead_sum_e6 = sum.get<std::int64_t>();
    else bad("gpu.per_frame_overhead_pct.sum_e6", "not an integer");
    if (!at(pf, "gpu.per_frame_overhead_pct.", "max_frame").is_null()) {
        r.has_worst = true;
        r.worst_frame = u64(pf, "gpu.per_frame_overhead_pct.", "max_frame");
        r.worst_pct = num(pf, "gpu.per_frame_overhead_pct.", "max");
    }
    const nlohmann::json& ef = at(at(j, "", "energy"), "energy.", "per_frame");
    if (!at(ef, "energy.per_frame.", "max_frame").is_null()) {
        r.has_max_energy = true;
        r.max_energy_frame = u64(ef, "energy.per_frame.", "max_frame");
        r.max_energy_nj = num(ef, "energy.per_frame.", "max_nj");
    }
    return s;
}

void merge_snapshots(RunSnapshot& a, const RunSnapshot& b) {
    if (a.input != b.input) throw InputError("stats: input: \"" + b.input + "\" is not \"" + a.input + "\"");
    if (dump_config_toml(a.cfg) != dump_config_toml(b.cfg)) throw InputError("stats: config: differs between the runs");
    const std::uint64_t first = b.frames.frames ? b.frames.first_frame : 0;
    if (!a.frames.merge(b.frames))
        throw InputError("stats: frame_range: frame " + std::to_string(first) + " does not follow frame " +
                         std::to_string(a.frames.last_frame));

    // Sums that wrap past 2^64 would give a wrong answer that looks right
    // (tampered or hostile parts): refused naming the key.
    const auto sum = [](std::uint64_t x, std::uint64_t y, const std::string& key) {
        std::uint64_t r = 0;
        if (__builtin_add_overflow(x, y, &r)) bad(key, "the parts' sum is beyond 2^64 - 1");
        return r;
    };
    std::vector<std::uint64_t> later;
    each_counter(b.counters, [&](const std::string&, const char*, std::uint64_t v) { later.push_back(v); });
    std::size_t i = 0;
    const std::uint64_t offset = a.cycles;
    RunSnapshot merged = a;
    each_counter(merged.counters, [&](const std::string& block, const char* key, std::uint64_t& v) {
        const std::uint64_t w = later.at(i++);
        const std::string k = key;
        const bool is_max = k.rfind("max_", 0) == 0;
        const bool is_time = k.size() > 6 && k.compare(k.size() - 6, 6, "_cycle") == 0;
        if (is_max && is_time) v = w ? std::max(v, sum(offset, w, "blocks." + block + "." + k)) : v;
        else if (is_max) v = std::max(v, w);
        else v = sum(v, w, "blocks." + block + "." + k);
    });
    merged.cycles = sum(a.cycles, b.cycles, "totals.cycles");
    // The GPU sums a stats document holds (snapshot_from_stats), checked
    // before FrameFigures::add sums them.
    const FrameTimes &ta = a.gpu.t, &tb = b.gpu.t;
    sum(ta.baseline, tb.baseline, "gpu.baseline_cycles");
    sum(ta.with_unit, tb.with_unit, "gpu.cycles_with_unit");
    sum(ta.tiles, tb.tiles, "gpu.tiles");
    sum(ta.shaded, tb.shaded, "gpu.shaded_fragments");
    sum(ta.culled, tb.culled, "gpu.culled_fragments");
    sum(ta.prims, tb.prims, "gpu.primitives");
    sum(ta.cprims, tb.cprims, "gpu.culled_primitives");
    sum(ta.tiles_with_base, tb.tiles_with_base, "gpu.tiles_with_base");
    sum(a.gpu.extra_prims, b.gpu.extra_prims, "gpu.overhead_cycles.extra_primitives");
    sum(a.gpu.extra_fragments, b.gpu.extra_fragments, "gpu.overhead_cycles.extra_fragments");
    sum(a.gpu.unit_no_bank, b.gpu.unit_no_bank, "gpu.overhead_cycles.unit_no_bank");
    sum(a.gpu.unit_queue, b.gpu.unit_queue, "gpu.overhead_cycles.unit_queue");
    sum(a.gpu.tail, b.gpu.tail, "gpu.overhead_cycles.tail");
    sum(ta.stall_no_bank, tb.stall_no_bank, "gpu.stalls.no_bank_cycles");
    sum(ta.stall_queue_full, tb.stall_queue_full, "gpu.stalls.queue_full_cycles");
    sum(ta.stall_fragment_queue, tb.stall_fragment_queue, "gpu.stalls.fragment_queue_cycles");
    merged.gpu.add(b.gpu);
    merged.frames = a.frames;
    a = std::move(merged);
}

} // namespace rbcd
