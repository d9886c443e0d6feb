// The unit's input queue: Q = feed.queue_depth fragments between the
// rasterizer and the insertion sorter. A fragment leaves it in the cycle the
// sorter issues it, so the next fragment may enter once the fragment Q places
// earlier has issued (a pop and a push in the same cycle are allowed); a full
// queue holds the rasterizer back.
//
// Computed, not ticked: the queue keeps the issue cycle of each of its last Q
// fragments.
//
//   std::uint64_t e = q.room(cycle);   // earliest cycle a fragment can enter
//   q.push(e, issue);                  // entered at e, issued by the sorter at `issue`
#pragma once
#include <algorithm>
#include <cstdint>
#include <string>
#include <systemc>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/clocking.h"

namespace rbcd {

class input_queue : public sc_core::sc_module {
public:
    struct stats_t {
        std::uint64_t writes = 0;            // fragments entered
        std::uint64_t max_occupancy = 0;     // deepest occupancy seen
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, writes, "fragments entered");
            RBCD_STAT(f, s, max_occupancy, "deepest occupancy seen");
        }
    };

    input_queue(sc_core::sc_module_name name, const FeedConfig& feed)
        : sc_module(name), depth_(feed.queue_depth), issue_(feed.queue_depth, 0) {}

    unsigned depth() const { return depth_; }
    std::uint64_t room(std::uint64_t t) const { return n_ >= depth_ ? std::max(t, issue_[i_]) : t; }

    [[gnu::always_inline]] void push(std::uint64_t enq, std::uint64_t issue) {
        // Occupancy seen by this entry: older fragments not issued by `enq`, plus
        // this one. Read before the slot of the fragment Q places earlier is reused.
        // It cannot exceed the depth (room() holds an entry back until the one
        // Q places earlier has issued), so once the deepest occupancy is the
        // depth nothing is left to measure, and a busy trace stops paying for
        // the pops early in the run.
        if (stats_.max_occupancy < depth_) {
            while (head_ < n_ && issue_[hi_] <= enq) {
                ++head_;
                if (++hi_ == depth_) hi_ = 0;
            }
            stats_.max_occupancy = std::max<std::uint64_t>(stats_.max_occupancy, n_ - head_ + 1);
        }
        issue_[i_] = issue;
        if (++i_ == depth_) i_ = 0;
        ++n_;
        ++stats_.writes;
        if (vcd_) {
            vcd_->add_delta(vcd_occupancy_, enq, +1);
            vcd_->add_delta(vcd_occupancy_, issue, -1);
        }
    }
    // Frame barrier: every fragment has issued.
    void restart() { n_ = head_ = 0; i_ = hi_ = 0; }

    const stats_t& stats() const { return stats_; }
    void attach_vcd(VcdWriter& vcd, const std::string& scope) {
        vcd_ = &vcd;
        vcd_occupancy_ = vcd.add(scope, "occupancy", 17);
    }

private:
    unsigned depth_;
    std::vector<std::uint64_t> issue_;   // issue cycle of the last Q fragments (ring)
    std::uint64_t n_ = 0, head_ = 0;     // fragments entered; oldest not yet known to have issued
    unsigned i_ = 0, hi_ = 0;             // ring positions of the next entry and of head_
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_occupancy_ = 0;
};

} // namespace rbcd
