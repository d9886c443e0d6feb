// The M-way comparator/mux insertion sorter (paper, Figure 4) and the unit's
// input queue in front of it.
//
// Pipeline, one insertion issued per cycle:
//   READ  (cycle s)   the pixel's list row is read from the ZEB bank
//   SORT  (cycle s+1) M "key <= new key" comparators give a thermometer code;
//                     M muxes keep, place or shift each slot
//   WRITE (cycle s+2) the merged row is written back
// A fragment for the same pixel as one of the two before it would read a stale
// row. sorter.hazard = "forward" bypasses the SORT output into the next SORT
// (no stall); "stall" holds the READ until the older WRITE is done (s' >= s+3).
//
// Timing is computed per tile in one call, not ticked: the feed's emission
// schedule (R fragments/cycle), the queue's capacity and the pipeline's issue
// rule give each fragment's enqueue and issue cycle by a recurrence.
#pragma once
#include <cstdint>
#include <systemc>
#include <vector>

#include "common/config.h"
#include "common/fragment.h"
#include "hw/clocking.h"
#include "common/vcd_writer.h"
#include "hw/zeb_bank.h"

namespace rbcd {

class insertion_sorter : public sc_core::sc_module {
public:
    static constexpr unsigned kStages = 3;

    struct stats_t {
        std::uint64_t insertions = 0;            // fragments issued into the pipeline
        std::uint64_t comparator_activations = 0;
        std::uint64_t mux_shifts = 0;            // elements moved one slot down
        std::uint64_t overflows = 0;             // fragments dropped by full lists
        std::uint64_t dropped_new = 0;           // ... of which the new element itself
        std::uint64_t dropped_last = 0;          // ... of which a shifted-out last element
        std::uint64_t hazard_forwards = 0;       // same-pixel hazards resolved by forwarding
        std::uint64_t hazard_stall_cycles = 0;   // cycles lost to same-pixel hazards (stall policy)
        std::uint64_t busy_cycles = 0;           // cycles with an insertion issued
        std::uint64_t queue_full_cycles = 0;     // cycles the feed was held by a full queue
        std::uint64_t queue_max_occupancy = 0;
        template <class F> void for_each(F f) const {
            RBCD_STAT(f, *this, insertions, "fragments inserted (one per issue cycle)");
            RBCD_STAT(f, *this, comparator_activations, "key comparators fired (M per insertion)");
            RBCD_STAT(f, *this, mux_shifts, "elements shifted down one slot by the muxes");
            RBCD_STAT(f, *this, overflows, "fragments dropped by full lists");
            RBCD_STAT(f, *this, dropped_new, "overflows where the new element sorted last and was dropped");
            RBCD_STAT(f, *this, dropped_last, "overflows where the last element was shifted out");
            RBCD_STAT(f, *this, hazard_forwards, "same-pixel hazards bypassed by forwarding");
            RBCD_STAT(f, *this, hazard_stall_cycles, "issue cycles lost to same-pixel hazards");
            RBCD_STAT(f, *this, busy_cycles, "cycles with an insertion issued");
            RBCD_STAT(f, *this, queue_full_cycles, "cycles the rasterizer was held by a full input queue");
            RBCD_STAT(f, *this, queue_max_occupancy, "deepest input-queue occupancy seen");
        }
    };

    struct FillResult {
        std::uint64_t feed_done = 0;       // cycle after the feed's last emission
        std::uint64_t fill_done = 0;       // cycle from which the bank holds the whole tile
        std::uint64_t queue_stall = 0;     // cycles the feed was held by the full queue
        std::uint64_t first_issue = 0, last_issue = 0;
    };

    insertion_sorter(sc_core::sc_module_name name, const SimConfig& cfg);

    // Inserts every fragment of `tile` into `bank` (already Filling), the feed
    // starting to emit at cycle `start`. depth_bits is the input stream's.
    FillResult fill_tile(const Tile& tile, zeb_bank& bank, std::uint64_t start, unsigned depth_bits);

    const stats_t& stats() const { return stats_; }

    // Waveforms: queue occupancy, issue and hazard activity; the feed's
    // queue-full stall flag lives in the feed's scope but is known here.
    void attach_vcd(VcdWriter& vcd, const std::string& scope);
    void attach_feed_stall(VcdWriter& vcd, VcdWriter::Sig queue_full) {
        vcd_feed_ = &vcd;
        vcd_queue_full_ = queue_full;
    }

private:
    void insert(zeb_bank& bank, unsigned list, std::uint64_t word, std::uint64_t key);

    unsigned m_, rate_, queue_depth_;
    unsigned tile_w_, tile_h_;
    unsigned z_bits_, id_shift_;
    bool front_first_;
    bool stall_on_hazard_;
    ElementLayout layout_;

    // Issue cycle of each of the last queue_depth_ fragments (ring, global
    // fragment order): a slot frees when the fragment queue_depth_ earlier issues.
    std::vector<std::uint64_t> issue_ring_;
    std::uint64_t seq_ = 0;
    std::uint64_t queue_head_ = 0;   // oldest fragment not yet issued, as of the last enqueue
    std::uint64_t last_issue_ = 0;
    bool any_issued_ = false;
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter* vcd_feed_ = nullptr;
    VcdWriter::Sig vcd_occupancy_ = 0, vcd_issue_ = 0, vcd_hazard_ = 0, vcd_bank_ = 0, vcd_queue_full_ = 0;
};

} // namespace rbcd
