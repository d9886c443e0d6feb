// Every block's counters of a run, copied out of the live system or rebuilt
// from a stats document (report/run_snapshot.h), so that energy and stats are
// computed from the same numbers either way.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "rbcd/hw/fragment_processors.h"
#include "rbcd/hw/host_reader.h"
#include "rbcd/hw/input_queue.h"
#include "rbcd/hw/insertion_sorter.h"
#include "rbcd/hw/output_buffer.h"
#include "rbcd/hw/rasterizer.h"
#include "rbcd/hw/zeb_bank.h"
#include "rbcd/hw/zoverlap_tester.h"
#include "rbcd/tlm/memory_controller.h"

namespace rbcd {

class rbcd_system;

struct UnitCounters {
    rasterizer::stats_t raster;
    fragment_processors::stats_t fragments;
    input_queue::stats_t queue;
    std::vector<std::pair<std::string, zeb_bank::stats_t>> banks;   // by instance name, zeb_bank0 ...
    insertion_sorter::stats_t sorter;
    zoverlap_tester::stats_t tester;
    output_buffer::stats_t outbuf;
    memory_stats memory;
    host_reader::stats_t host;

    static UnitCounters of(const rbcd_system& sys);

    // f(block name, stats struct) for every block, in the stats document's
    // names; the struct is mutable when *this is.
    template <class F> void for_each_block(F f) const { visit(*this, f); }
    template <class F> void for_each_block(F f) { visit(*this, f); }

private:
    template <class S, class F> static void visit(S& s, F f) {
        f("rasterizer", s.raster);
        f("fragment_processors", s.fragments);
        f("input_queue", s.queue);
        for (auto& b : s.banks) f(b.first, b.second);
        f("insertion_sorter", s.sorter);
        f("zoverlap_tester", s.tester);
        f("output_buffer", s.outbuf);
        f("memory_controller", s.memory);
        f("host", s.host);
    }
};

} // namespace rbcd
