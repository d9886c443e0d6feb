#include "rbcd/hw/rbcd_system.h"

#include <algorithm>
#include <string>

#include "rbcd/common/errors.h"

namespace rbcd {

rbcd_system::rbcd_system(sc_core::sc_module_name name, const SimConfig& c, FragmentSource& src, CollisionSink& sink)
    : sc_module(name),
      unit("unit", c, src),
      memory("memory_controller", c.memory, unit.clk.period()),
      host("host", c, sink),
      cfg(unit.cfg),
      clk(unit.clk),
      banks(unit.banks),
      outbuf(unit.outbuf),
      queue(unit.queue),
      sorter(unit.sorter),
      tester(unit.tester),
      fragments(unit.fragments),
      raster(unit.raster),
      reseed_(memory) {
    unit.mem.bind(memory.unit_port);
    unit.host.bind(host);
    host.mem.bind(memory.host_port);
    raster.add_observer(&reseed_);
}

void rbcd_system::attach_vcd(VcdWriter& vcd) {
    vcd_ = &vcd;
    const std::string top = basename();
    if (cfg.trace.feed) {
        raster.attach_vcd(vcd, top + ".rasterizer");
        fragments.attach_vcd(vcd, top + ".fragment_processors");
    }
    if (cfg.trace.zeb)
        for (auto& b : banks) b->attach_vcd(vcd, top + "." + b->basename());
    if (cfg.trace.sorter) {
        queue.attach_vcd(vcd, top + ".input_queue");
        sorter.attach_vcd(vcd, top + ".insertion_sorter");
    }
    if (cfg.trace.tester) tester.attach_vcd(vcd, top + ".zoverlap_tester");
    if (cfg.trace.output) outbuf.attach_vcd(vcd, top + ".output_buffer");
    if (cfg.trace.memory) memory.attach_vcd(vcd, top + ".memory_controller");
    raster.set_vcd_flush(&vcd);
}

void rbcd_system::run() {
    try {
        sc_core::sc_start();
    } catch (const sc_core::sc_report& r) {
        // An exception out of a process (e.g. a memory error response) reaches
        // sc_start as a report whose message is the exception's.
        throw RunError(r.get_msg());
    }
    if (vcd_ && !raster.error()) vcd_->finish(std::max(tester.finish_cycle(), raster.end_cycle()));
    unit.check_finished();
}

} // namespace rbcd
