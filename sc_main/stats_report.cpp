#include "sc_main/stats_report.h"

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

} // namespace

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info) {
    nlohmann::json j;
    const auto& feed = sys.feed.stats();
    const auto& sorter = sys.sorter.stats();
    const auto& tester = sys.tester.stats();
    const std::uint64_t cycles = sys.total_cycles();

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
        {"simulated_us", double(cycles) * double(sys.clk.period_ps()) * 1e-6},
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

    nlohmann::json frames = nlohmann::json::array();
    const auto& tf = sys.tester.frames();
    for (std::size_t i = 0; i < sys.feed.frames().size(); ++i) {
        const auto& f = sys.feed.frames()[i];
        nlohmann::json fj = {
            {"frame", f.frame},
            {"feed_start_cycle", f.start},
            {"feed_end_cycle", f.end},
            {"tiles", f.tiles},
            {"fragments", f.fragments},
            {"culled_fragments", f.culled},
            {"other_fragments", f.other},
            {"stall_no_bank_cycles", f.stall_no_bank},
            {"stall_queue_full_cycles", f.stall_queue_full},
        };
        if (i < tf.size()) fj["done_cycle"] = tf[i].done;
        frames.push_back(fj);
    }
    j["frames"] = frames;
    j["config"] = config_json(sys.cfg);
    return j;
}

std::string make_summary(const nlohmann::json& s) {
    const auto& t = s["totals"];
    const auto& b = s["blocks"];
    char buf[1024];
    std::string out;
    std::snprintf(buf, sizeof buf,
                  "rbcd-sim: %s\n"
                  "  frames %llu  tiles %llu  fragments %llu  cycles %llu (%.1f us at %.0f MHz)\n"
                  "  hits %llu  overflows %llu  stack_overflows %llu  orphan_back_faces %llu\n",
                  s["input"].get<std::string>().c_str(), t["frames"].get<unsigned long long>(),
                  t["tiles"].get<unsigned long long>(), t["fragments"].get<unsigned long long>(),
                  t["cycles"].get<unsigned long long>(), s["time"]["simulated_us"].get<double>(),
                  s["time"]["clock_mhz"].get<double>(), t["hits"].get<unsigned long long>(),
                  t["overflows"].get<unsigned long long>(), t["stack_overflows"].get<unsigned long long>(),
                  t["orphan_back_faces"].get<unsigned long long>());
    out += buf;
    std::snprintf(buf, sizeof buf,
                  "  sorter busy %.1f%%  tester busy %.1f%%  feed stalls: no bank %llu, queue full %llu cycles\n"
                  "  memory: %llu writes, %llu bytes\n",
                  s["derived"]["sorter_utilization_pct"].get<double>(),
                  s["derived"]["tester_utilization_pct"].get<double>(),
                  b["rasterizer_feed"]["stall_no_bank_cycles"].get<unsigned long long>(),
                  b["rasterizer_feed"]["stall_queue_full_cycles"].get<unsigned long long>(),
                  b["memory_controller"]["writes"].get<unsigned long long>(),
                  b["memory_controller"]["bytes_written"].get<unsigned long long>());
    out += buf;
    return out;
}

} // namespace rbcd
