// The RBCD unit as a component (docs/embedding.md): its input side (the GPU's
// rasterizer and fragment processors, which pace the fragment stream as the
// GPU around the unit would, and the unit's input queue), the ZEB banks, the
// insertion sorter, the z-overlap tester and the output buffer, with one
// TLM-2.0 initiator socket as its only connection to memory and a port to the
// host that consumes the records.
//
//   FragmentSource --> rasterizer --> input_queue --> sorter --> zeb_bank[i] --> tester --> output_buffer --mem--> (platform)
//                          +--> fragment_processors                                              |
//                                                          host port (unit_host_if) <------------+  records_ready(...)
//
//   rbcd::rbcd_unit unit("rbcd", cfg, source);
//   unit.mem.bind(router.target_socket);        // any base-protocol target, BUSWIDTH kBusWidth
//   unit.host.bind(my_host);                    // a unit_host_if, e.g. rbcd::host_reader
//   sc_core::sc_start();  ...  unit.check_finished();
//
// The socket carries only blocking b_transport writes (generic payload, whole
// 16-byte records, bursts of output.burst_records) to the output region at
// memory.base + output.region_offset; the delay annotation follows the
// loosely-timed conventions and the unit never waits inside the call.
#pragma once
#include <cstdint>
#include <exception>
#include <memory>
#include <systemc>
#include <tlm>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/fragment.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/hw/insertion_sorter.h"
#include "rbcd/hw/output_buffer.h"
#include "rbcd/hw/fragment_processors.h"
#include "rbcd/hw/input_queue.h"
#include "rbcd/hw/rasterizer.h"
#include "rbcd/hw/unit_host_if.h"
#include "rbcd/hw/zeb_bank.h"
#include "rbcd/hw/zoverlap_tester.h"
#include "rbcd/tlm/bus.h"

namespace rbcd {

class rbcd_unit : public sc_core::sc_module {
public:
    // To memory: the output buffer's writes (hierarchically bound inside).
    tlm::tlm_initiator_socket<kBusWidth> mem;
    // To the host: begin_frame, then records_ready whenever records wait in memory.
    sc_core::sc_port<unit_host_if> host;

    // Throws InputError if cfg does not pass SimConfig::validate(). The unit reads clock, tile,
    // zeb, feed, gpu, sorter, tester, output and memory.base (the region's address);
    // src is read from the unit's own thread until it reports the end.
    rbcd_unit(sc_core::sc_module_name name, const SimConfig& cfg, FragmentSource& src);

    // Notified at the cycle each batch of records is ready (just before the
    // host port's records_ready), for platforms that model an interrupt line.
    const sc_core::sc_event& records_ready_event() const { return records_ready_event_; }
    std::uint64_t records_ready_count() const { return records_ready_count_; }

    // After sc_start() returned (or threw): rethrows the input's error
    // (InputError), throws the memory error that stopped the run (RunError,
    // the message sc_start's report carried), or throws if the stream did not
    // run to its end.
    void check_finished() const;
    bool finished() const { return tester.finished(); }
    std::exception_ptr error() const { return raster.error(); }
    // The end of the last frame (docs/timing.md, frame barrier).
    std::uint64_t total_cycles() const { return raster.end_cycle(); }

    const SimConfig cfg;
    Clocking clk;
    std::vector<std::unique_ptr<zeb_bank>> banks;

private:
    // Relays the blocks' calls to the host port, and raises the event.
    struct host_relay final : unit_host_if {
        rbcd_unit& unit;
        explicit host_relay(rbcd_unit& u) : unit(u) {}
        void begin_frame(std::uint64_t n) override { unit.host->begin_frame(n); }
        std::uint64_t records_ready(std::uint64_t address, std::uint64_t bytes, std::uint64_t cycle,
                                    bool because_full) override;
    };
    static std::vector<std::unique_ptr<zeb_bank>> make_banks(const SimConfig& cfg);
    std::vector<zeb_bank*> bank_ptrs() const;

    host_relay relay_;
    sc_core::sc_event records_ready_event_;
    std::uint64_t records_ready_count_ = 0;

public:
    output_buffer outbuf;
    input_queue queue;
    insertion_sorter sorter;
    zoverlap_tester tester;
    fragment_processors fragments;
    rasterizer raster;
};

} // namespace rbcd
