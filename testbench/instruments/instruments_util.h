// A system run with the RunProbe wired as rbcd-sim wires it (sink tee, feed hooks).
#pragma once
#include <memory>
#include <string>

#include "hw/rbcd_system.h"
#include "io/memory_source.h"
#include "io/trace_reader.h"
#include "sc_main/stats_report.h"
#include "testbench/hw/tb_util.h"

namespace rbcd::tb {

struct ProbedRun {
    RecordingSink records;
    TeeSink tee;
    std::unique_ptr<rbcd_system> sys;
    std::unique_ptr<RunProbe> probe;
    ProbedRun(const SimConfig& cfg, FragmentSource& src) {
        sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);
        tee.add(&records);
        sys = std::make_unique<rbcd_system>("rbcd", cfg, src, tee);
        probe = std::make_unique<RunProbe>(*sys);
        tee.add(&probe->unit_frames());
        probe->attach();
        sys->run();
    }
    nlohmann::json stats() { return make_stats(*sys, RunInfo{"test", 0.0}, probe.get()); }
    const std::vector<GpuFrame>& gpu() { return probe->gpu.finish(); }
};

// Memory latency fixed at 50 cycles, as docs/timing.md's worked example; the
// GPU's shading cost pinned at 4 cycles a fragment, which the hand-worked
// figures in these tests assume (the key's default may move).
inline SimConfig fixed_latency_config() {
    SimConfig cfg;
    cfg.memory.latency_min = cfg.memory.latency_max = 50;
    cfg.gpu.cycles_per_fragment = 4;
    return cfg;
}

inline std::string instruments_file(const char* name) {
    return std::string(RBCD_SOURCE_DIR) + "/testbench/instruments/" + name;
}

inline TraceLimits limits(const SimConfig& cfg) { return {cfg.tile.width, cfg.tile.height, cfg.zeb.id_bits}; }

} // namespace rbcd::tb
