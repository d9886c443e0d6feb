// The modelled system: the GPU's rasterizer and fragment processors, the RBCD
// unit's blocks (input queue, ZEB banks, insertion sorter, z-overlap tester,
// output buffer) and, over TLM-2.0, the memory controller and the host CPU
// that reads the collision records back.
//
//   rasterizer --fragments--> fragment_processors (fragment queue, early-Z)
//        |
//        +--> input_queue --> sorter --rows--> zeb_bank[i] <--rows-- tester --records--> output_buffer
//                                                                                           | b_transport
//   host_reader --DMI/debug read--> memory_controller <-------------------------------------+
#pragma once
#include <cstdint>
#include <memory>
#include <systemc>
#include <vector>

#include "common/config.h"
#include "common/fragment.h"
#include "hw/clocking.h"
#include "hw/collision_sink.h"
#include "hw/host_reader.h"
#include "hw/insertion_sorter.h"
#include "hw/output_buffer.h"
#include "hw/fragment_processors.h"
#include "hw/input_queue.h"
#include "hw/rasterizer.h"
#include "hw/zeb_bank.h"
#include "common/vcd_writer.h"
#include "hw/zoverlap_tester.h"
#include "tlm/memory_controller.h"

namespace rbcd {

class rbcd_system : public sc_core::sc_module {
public:
    rbcd_system(sc_core::sc_module_name name, const SimConfig& cfg, FragmentSource& src, CollisionSink& sink);

    // Runs to the end of the stream. Rethrows the source's InputError.
    void run();
    // The end of the last frame: every frame's GPU work and records done.
    std::uint64_t total_cycles() const { return raster.end_cycle(); }
    // Before run(): the blocks that cfg.trace enables record into `vcd`.
    void attach_vcd(VcdWriter& vcd);

    const SimConfig cfg;
    Clocking clk;
    std::vector<std::unique_ptr<zeb_bank>> banks;
    memory_controller memory;
    host_reader host;
    output_buffer outbuf;
    input_queue queue;
    insertion_sorter sorter;
    zoverlap_tester tester;
    fragment_processors fragments;
    rasterizer raster;

private:
    // Frame barrier: the memory's latency stream restarts per frame.
    struct Reseed final : RasterObserver {
        memory_controller& m;
        explicit Reseed(memory_controller& mem) : m(mem) {}
        void frame_begin(std::uint64_t frame) override { m.reseed_for_frame(frame); }
    } reseed_;
    static std::vector<std::unique_ptr<zeb_bank>> make_banks(const SimConfig& cfg);
    VcdWriter* vcd_ = nullptr;
    std::vector<zeb_bank*> bank_ptrs() const;
};

} // namespace rbcd
