#include "rbcd/hw/self_check.h"

#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

SelfCheckCounters self_check_counters(const rbcd_system& sys) {
    SelfCheckCounters c;
    const auto& feed = sys.raster.stats();   // the rasterizer feeds the unit
    const auto& sorter = sys.sorter.stats();
    const auto& tester = sys.tester.stats();
    const auto& out = sys.outbuf.stats();
    const auto& host = sys.host.stats();
    c.feed_fragments = feed.fragments;
    c.feed_tiles_with_fragments = feed.tiles_with_fragments;
    c.feed_busy_cycles = feed.busy_cycles;
    c.sorter_insertions = sorter.insertions;
    c.sorter_overflows = sorter.overflows;
    c.sorter_dropped_new = sorter.dropped_new;
    c.sorter_dropped_last = sorter.dropped_last;
    c.sorter_busy_cycles = sorter.busy_cycles;
    c.tester_elements = tester.elements;
    c.tester_tiles = tester.tiles;
    c.tester_raw_hits = tester.raw_hits;
    c.tester_hits = tester.hits;
    c.tester_filtered_hits = tester.filtered_hits;
    c.tester_overflow_records = tester.overflow_records;
    c.tester_busy_cycles = tester.busy_cycles;
    for (const auto& b : sys.banks) {
        c.bank_tiles += b->stats().tiles;
        c.banks_not_free += b->state() != zeb_bank::State::Free;
    }
    c.outbuf_records = out.records;
    c.outbuf_bytes = out.bytes;
    c.host_records = host.records;
    c.host_hit_records = host.hit_records;
    c.host_overflow_records = host.overflow_records;
    c.total_cycles = sys.total_cycles();
    return c;
}

namespace {
std::string n(std::uint64_t v) { return std::to_string(v); }
std::string failed(const char* name, const std::string& detail) {
    return std::string("self-check '") + name + "' failed: " + detail + " (a model bug, not bad input)";
}
} // namespace

std::string self_check(const SelfCheckCounters& c) {
    if (c.feed_fragments != c.sorter_insertions)
        return failed("input_queue_empty", n(c.feed_fragments) + " fragments sent, " + n(c.sorter_insertions) +
                                               " left the input queue");
    if (c.sorter_insertions != c.tester_elements + c.sorter_overflows)
        return failed("fragment_conservation", "in " + n(c.sorter_insertions) + " != stored " + n(c.tester_elements) +
                                                   " + dropped " + n(c.sorter_overflows));
    if (c.sorter_overflows != c.sorter_dropped_new + c.sorter_dropped_last)
        return failed("overflow_split", n(c.sorter_overflows) + " overflows != " + n(c.sorter_dropped_new) +
                                            " new + " + n(c.sorter_dropped_last) + " shifted out");
    if (c.banks_not_free != 0 || c.bank_tiles != c.feed_tiles_with_fragments || c.tester_tiles != c.bank_tiles)
        return failed("banks_released", n(c.banks_not_free) + " banks not free; tiles: feed " +
                                            n(c.feed_tiles_with_fragments) + ", banks " + n(c.bank_tiles) +
                                            ", tester " + n(c.tester_tiles));
    if (c.outbuf_records != c.host_records || c.outbuf_bytes != 16 * c.outbuf_records)
        return failed("output_queue_empty", n(c.outbuf_records) + " records accepted, " + n(c.outbuf_bytes) +
                                                " bytes written, " + n(c.host_records) + " read back");
    if (c.tester_hits != c.host_hit_records || c.tester_overflow_records != c.host_overflow_records ||
        c.host_records != c.host_hit_records + c.host_overflow_records)
        return failed("records_reported", "tester " + n(c.tester_hits) + " hits + " + n(c.tester_overflow_records) +
                                              " overflow records, host read " + n(c.host_hit_records) + " + " +
                                              n(c.host_overflow_records) + " of " + n(c.host_records));
    if (c.tester_raw_hits != c.tester_hits + c.tester_filtered_hits)
        return failed("hits_filtered", n(c.tester_raw_hits) + " raw hits != " + n(c.tester_hits) + " written + " +
                                           n(c.tester_filtered_hits) + " filtered");
    if (c.feed_busy_cycles > c.total_cycles || c.sorter_busy_cycles > c.total_cycles ||
        c.tester_busy_cycles > c.total_cycles)
        return failed("cycles_consistent", "busy cycles feed " + n(c.feed_busy_cycles) + ", sorter " +
                                               n(c.sorter_busy_cycles) + ", tester " + n(c.tester_busy_cycles) +
                                               " exceed the run's " + n(c.total_cycles));
    return "";
}

std::string tile_conservation_failure(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::uint64_t in,
                                      std::uint64_t stored, std::uint64_t dropped) {
    return failed("tile_conservation", "frame " + n(frame) + ", tile column " + n(col) + " row " + n(row) + ": in " +
                                           n(in) + " != stored " + n(stored) + " + dropped " + n(dropped));
}

} // namespace rbcd
