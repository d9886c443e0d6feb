// The --stats JSON document and the end-of-run summary on stdout.
//
// The GPU overhead (docs/gpu-model.md) is worked out per tile and the energy
// (docs/energy.md) per frame from counter snapshots; both need a RunProbe
// watching the run:
//
//   TeeSink tee;  rbcd_system sys("rbcd", cfg, src, tee);
//   RunProbe probe(sys);
//   tee.add(&probe.unit_frames());                 // unit-side frame boundaries
//   sys.feed.on_tile  = [&](const Tile& t) { probe.on_tile(t); ... };
//   sys.feed.on_frame = [&](std::uint64_t n) { probe.on_frame(n); ... };
//   sys.run();
//   nlohmann::json j = make_stats(sys, info, &probe);
//
// Without a probe the GPU model runs per frame (each frame as one tile) and a
// frame's dynamic energy is the run's, apportioned by the frame's fragments;
// the JSON says which ("gpu"."granularity", "energy"."per_frame"."basis").
#pragma once
#include <nlohmann/json.hpp>
#include <string>

#include "hw/rbcd_system.h"
#include "sc_main/energy_model.h"
#include "sc_main/gpu_model.h"

namespace rbcd {

struct RunInfo {
    std::string input;        // trace path or scene name
    double wall_seconds = 0;
};

class RunProbe {
public:
    explicit RunProbe(rbcd_system& sys) : gpu(sys), energy(sys), sys_(sys) {}
    void on_tile(const Tile& t) { gpu.on_tile(t); }
    void on_frame(std::uint64_t n) { energy.on_feed_frame(n); }
    // Add to the system's TeeSink: the unit's frame starts reach the probe through it.
    CollisionSink& unit_frames() { return energy.unit_frames(); }
    // Wraps the feed's hooks as they are now (set them first), calling the probe before them.
    void attach();

    GpuModel gpu;
    FrameEnergyProbe energy;

private:
    rbcd_system& sys_;
};

nlohmann::json make_stats(const rbcd_system& sys, const RunInfo& info, RunProbe* probe = nullptr);
std::string make_summary(const nlohmann::json& stats);

} // namespace rbcd
