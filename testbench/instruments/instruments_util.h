// A system run with the per-frame report wired as rbcd-sim wires it.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "rbcd/hw/rbcd_system.h"
#include "rbcd/io/memory_source.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/report/run_report.h"
#include "rbcd/report/stats_report.h"
#include "rbcd/testbench/hw/tb_util.h"

namespace rbcd::tb {

struct ReportedRun {
    RecordingSink records;
    std::unique_ptr<rbcd_system> sys;
    std::unique_ptr<RunReport> report;
    std::vector<nlohmann::json> frames;   // the --frame-stats lines, parsed
    ReportedRun(const SimConfig& cfg, FragmentSource& src) {
        sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
        sys = std::make_unique<rbcd_system>("rbcd", cfg, src, records);
        report = std::make_unique<RunReport>(*sys);
        report->stream_to([this](const std::string& line) {
            REQUIRE(!line.empty());
            REQUIRE(line.back() == '\n');
            REQUIRE(line.find('\n') == line.size() - 1);
            frames.push_back(nlohmann::json::parse(line));
        });
        sys->run();
    }
    nlohmann::json stats() const { return make_stats(*sys, RunInfo{"test", 0.0}, *report); }
    std::string summary() const { return make_summary(stats(), *report); }
    FrameFigures totals() const { return report->totals(); }
};

// Memory latency fixed at 50 cycles, as docs/timing.md's worked example.
inline SimConfig fixed_latency_config() {
    SimConfig cfg;
    cfg.memory.latency_min = cfg.memory.latency_max = 50;
    return cfg;
}

inline std::string instruments_file(const char* name) {
    return std::string(RBCD_SOURCE_DIR) + "/testbench/instruments/" + name;
}

inline TraceLimits limits(const SimConfig& cfg) { return {cfg.tile.width, cfg.tile.height, cfg.zeb.id_bits}; }

} // namespace rbcd::tb
