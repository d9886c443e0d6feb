#include "rbcd/report/unit_counters.h"

#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

UnitCounters UnitCounters::of(const rbcd_system& sys) {
    UnitCounters c;
    c.raster = sys.raster.stats();
    c.fragments = sys.fragments.stats();
    c.queue = sys.queue.stats();
    for (const auto& b : sys.banks) c.banks.emplace_back(b->basename(), b->stats());
    c.sorter = sys.sorter.stats();
    c.tester = sys.tester.stats();
    c.outbuf = sys.outbuf.stats();
    c.memory = sys.memory.stats();
    c.host = sys.host.stats();
    return c;
}

} // namespace rbcd
