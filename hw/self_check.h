// Self-checks: invariants that hold in every correct run. A violation is a
// model bug, not bad input: rbcd-sim exits 1 naming the check (docs/testing.md).
//
// Per tile, the z-overlap tester checks fragment conservation as it finishes
// each tile (tile_conservation): the fragments the rasterizer sent for the
// tile = the elements the bank stored + those its full lists dropped. A
// violation stops the run at that tile. The others are read at the end of the
// run from the blocks' public statistics:
//
//   const SelfCheckCounters c = self_check_counters(sys);   // after sys.run()
//   if (const std::string v = self_check(c); !v.empty()) fail(v);
//
// The counters are a plain struct so that tests can break each invariant on
// purpose and see its check fire.
#pragma once
#include <cstdint>
#include <string>

namespace rbcd {

class rbcd_system;

struct SelfCheckCounters {
    // Fragment conservation: in = stored + dropped.
    std::uint64_t feed_fragments = 0;        // collisionable fragments the feed sent
    std::uint64_t sorter_insertions = 0;     // fragments that left the input queue into the sorter
    std::uint64_t sorter_overflows = 0;      // fragments dropped by full lists
    std::uint64_t sorter_dropped_new = 0;
    std::uint64_t sorter_dropped_last = 0;
    std::uint64_t tester_elements = 0;       // list elements the tester walked (stored fragments)
    // Banks: every tile that took a bank was tested and the bank released.
    std::uint64_t feed_tiles_with_fragments = 0;
    std::uint64_t bank_tiles = 0;            // sum over banks of tiles held
    std::uint64_t tester_tiles = 0;
    std::uint64_t banks_not_free = 0;        // banks not in state Free at the end
    // Records: what the tester produced reached memory and was read back.
    std::uint64_t tester_raw_hits = 0, tester_hits = 0, tester_filtered_hits = 0;
    std::uint64_t tester_overflow_records = 0;
    std::uint64_t outbuf_records = 0;        // records the output buffer accepted
    std::uint64_t outbuf_bytes = 0;          // bytes it wrote to memory
    std::uint64_t host_records = 0, host_hit_records = 0, host_overflow_records = 0;
    // Cycles: no block is busy longer than the run.
    std::uint64_t total_cycles = 0;
    std::uint64_t feed_busy_cycles = 0, sorter_busy_cycles = 0, tester_busy_cycles = 0;
};

SelfCheckCounters self_check_counters(const rbcd_system& sys);

// "" when every invariant holds, else "self-check '<name>' failed: <detail>"
// for the first violated one. Names: fragment_conservation, overflow_split,
// banks_released, input_queue_empty, output_queue_empty, records_reported,
// hits_filtered, cycles_consistent.
std::string self_check(const SelfCheckCounters& c);

// The message for a failed tile_conservation check, naming the tile.
std::string tile_conservation_failure(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::uint64_t in,
                                      std::uint64_t stored, std::uint64_t dropped);

} // namespace rbcd
