#include "rbcd/hw/rbcd_unit.h"

#include <stdexcept>
#include <string>

#include "rbcd/common/errors.h"

namespace rbcd {

std::vector<std::unique_ptr<zeb_bank>> rbcd_unit::make_banks(const SimConfig& cfg) {
    std::vector<std::unique_ptr<zeb_bank>> v;
    for (unsigned i = 0; i < cfg.zeb.banks; ++i)
        v.push_back(std::make_unique<zeb_bank>(("zeb_bank" + std::to_string(i)).c_str(), cfg.zeb, cfg.tile, i));
    return v;
}

std::vector<zeb_bank*> rbcd_unit::bank_ptrs() const {
    std::vector<zeb_bank*> v;
    for (const auto& b : banks) v.push_back(b.get());
    return v;
}

namespace {
// Before any block is built from it: a platform that skipped validate() gets
// its InputError here, not a block built from a zero.
const SimConfig& validated(const SimConfig& c) {
    c.validate();
    return c;
}
} // namespace

rbcd_unit::rbcd_unit(sc_core::sc_module_name name, const SimConfig& c, FragmentSource& src)
    : sc_module(name),
      mem("mem"),
      host("host"),
      cfg(validated(c)),
      clk(c.clock.period_ps()),
      banks(make_banks(c)),
      relay_(*this),
      outbuf("output_buffer", c, clk, relay_),
      queue("input_queue", c.feed),
      sorter("insertion_sorter", c),
      tester("zoverlap_tester", c, clk, outbuf, relay_),
      fragments("fragment_processors", c.gpu),
      raster("rasterizer", cfg, clk, src, bank_ptrs(), fragments, queue, sorter, tester) {
    // Hierarchical binding: the platform sees the output buffer's socket as the unit's.
    outbuf.mem.bind(mem);
}

std::uint64_t rbcd_unit::host_relay::records_ready(std::uint64_t address, std::uint64_t bytes,
                                                   std::uint64_t cycle, bool because_full) {
    ++unit.records_ready_count_;
    const std::uint64_t now = unit.clk.now();
    unit.records_ready_event_.notify(unit.clk.time(cycle > now ? cycle - now : 0));
    return unit.host->records_ready(address, bytes, cycle, because_full);
}

void rbcd_unit::check_finished() const {
    if (raster.error()) std::rethrow_exception(raster.error());
    // The run stopped on a memory error response: name it, not a lost tester.
    if (!outbuf.failure().empty()) throw RunError(outbuf.failure());
    if (!tester.finished())
        throw std::runtime_error("simulation ended before the z-overlap tester finished (internal error)");
}

} // namespace rbcd
