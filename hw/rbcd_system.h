// The modelled system: the RBCD unit (rbcd_unit: the GPU's rasterizer and
// fragment processors that pace it, the input queue, ZEB banks, insertion
// sorter, z-overlap tester and output buffer) and, over TLM-2.0, the memory
// controller and the host CPU that reads the collision records back, bound
// the way any other platform binds the unit (docs/embedding.md).
//
//   rasterizer --fragments--> fragment_processors (fragment queue, early-Z)
//        |
//        +--> input_queue --> sorter --rows--> zeb_bank[i] <--rows-- tester --records--> output_buffer
//                                                                                           | unit.mem
//   host_reader --DMI/debug read--> memory_controller <-------------------------------------+
#pragma once
#include <cstdint>
#include <memory>
#include <systemc>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/fragment.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/collision_sink.h"
#include "rbcd/hw/host_reader.h"
#include "rbcd/hw/rbcd_unit.h"
#include "rbcd/tlm/memory_controller.h"

namespace rbcd {

class rbcd_system : public sc_core::sc_module {
public:
    rbcd_system(sc_core::sc_module_name name, const SimConfig& cfg, FragmentSource& src, CollisionSink& sink);

    // Runs to the end of the stream. Rethrows the source's InputError.
    void run();
    // The end of the last frame: every frame's GPU work and records done.
    std::uint64_t total_cycles() const { return unit.total_cycles(); }
    // Before run(): the blocks that cfg.trace enables record into `vcd`.
    void attach_vcd(VcdWriter& vcd);

    rbcd_unit unit;
    memory_controller memory;
    host_reader host;
    // The unit's parts, by their own names.
    const SimConfig& cfg;
    Clocking& clk;
    std::vector<std::unique_ptr<zeb_bank>>& banks;
    output_buffer& outbuf;
    input_queue& queue;
    insertion_sorter& sorter;
    zoverlap_tester& tester;
    fragment_processors& fragments;
    rasterizer& raster;

private:
    // Frame barrier: the memory's latency stream restarts per frame.
    struct Reseed final : RasterObserver {
        memory_controller& m;
        explicit Reseed(memory_controller& mem) : m(mem) {}
        void frame_begin(std::uint64_t frame) override { m.reseed_for_frame(frame); }
    } reseed_;
    VcdWriter* vcd_ = nullptr;
};

} // namespace rbcd
