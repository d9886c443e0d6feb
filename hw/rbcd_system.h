// The modelled system: the RBCD unit (rbcd_unit: rasterizer feed, ZEB banks,
// insertion sorter, z-overlap tester, output buffer) and, over TLM-2.0, the
// memory controller and the host CPU that reads the collision records back,
// bound the way any other platform binds the unit (docs/embedding.md).
//
//   feed --fill_tile--> sorter --rows--> zeb_bank[i] <--rows-- tester --records--> output_buffer
//                                                                                     | b_transport
//   host_reader --DMI/debug read--> memory_controller <------------------------------+
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
#include "hw/rasterizer_feed.h"
#include "hw/rbcd_unit.h"
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
    std::uint64_t total_cycles() const { return tester.finish_cycle(); }
    // Before run(): the blocks that cfg.trace enables record into `vcd`.
    void attach_vcd(VcdWriter& vcd);

    rbcd_unit unit;
    memory_controller memory;
    host_reader host;
    // The unit's parts, by their old names.
    const SimConfig& cfg;
    Clocking& clk;
    std::vector<std::unique_ptr<zeb_bank>>& banks;
    output_buffer& outbuf;
    insertion_sorter& sorter;
    zoverlap_tester& tester;
    rasterizer_feed& feed;

private:
    VcdWriter* vcd_ = nullptr;
};

} // namespace rbcd
