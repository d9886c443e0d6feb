#include "hw/rbcd_system.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace rbcd {

std::vector<std::unique_ptr<zeb_bank>> rbcd_system::make_banks(const SimConfig& cfg) {
    std::vector<std::unique_ptr<zeb_bank>> v;
    for (unsigned i = 0; i < cfg.zeb.banks; ++i)
        v.push_back(std::make_unique<zeb_bank>(("zeb_bank" + std::to_string(i)).c_str(), cfg.zeb, cfg.tile, i));
    return v;
}

std::vector<zeb_bank*> rbcd_system::bank_ptrs() const {
    std::vector<zeb_bank*> v;
    for (const auto& b : banks) v.push_back(b.get());
    return v;
}

rbcd_system::rbcd_system(sc_core::sc_module_name name, const SimConfig& c, FragmentSource& src, CollisionSink& sink)
    : sc_module(name),
      cfg(c),
      clk(c.clock.period_ps()),
      banks(make_banks(c)),
      memory("memory_controller", c.memory, clk.period()),
      host("host", c, sink),
      outbuf("output_buffer", c, clk, host),
      queue("input_queue", c.feed),
      sorter("insertion_sorter", c),
      tester("zoverlap_tester", c, clk, outbuf, host),
      fragments("fragment_processors", c.gpu),
      raster("rasterizer", cfg, clk, src, bank_ptrs(), fragments, queue, sorter, tester),
      reseed_(memory) {
    outbuf.mem.bind(memory.unit_port);
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
    sc_core::sc_start();
    if (vcd_ && !raster.error()) vcd_->finish(std::max(tester.finish_cycle(), raster.end_cycle()));
    if (raster.error()) std::rethrow_exception(raster.error());
    if (!tester.finished())
        throw std::runtime_error("simulation ended before the z-overlap tester finished (internal error)");
}

} // namespace rbcd
