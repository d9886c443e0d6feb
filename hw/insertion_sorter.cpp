#include "hw/insertion_sorter.h"

#include <algorithm>

namespace rbcd {

insertion_sorter::insertion_sorter(sc_core::sc_module_name name, const SimConfig& cfg)
    : sc_module(name),
      m_(cfg.zeb.list_length),
      rate_(cfg.feed.fragments_per_cycle),
      queue_depth_(cfg.feed.queue_depth),
      tile_w_(cfg.tile.width),
      tile_h_(cfg.tile.height),
      z_bits_(cfg.zeb.z_bits),
      id_shift_(cfg.zeb.id_bits + 1),
      front_first_(cfg.zeb.tie == TiePolicy::FrontFirst),
      stall_on_hazard_(cfg.sorter.hazard == HazardPolicy::Stall),
      layout_(cfg.zeb.layout()),
      issue_ring_(cfg.feed.queue_depth, 0) {}

void insertion_sorter::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_occupancy_ = vcd.add(scope, "queue_occupancy", 17);
    vcd_issue_ = vcd.add(scope, "issue", 1);
    vcd_hazard_ = vcd.add(scope, "hazard_stall", 1);
    vcd_bank_ = vcd.add(scope, "bank", 4);
}

void insertion_sorter::insert(zeb_bank& bank, unsigned li, std::uint64_t word, std::uint64_t key) {
    std::uint64_t* row = bank.list(li);
    std::uint8_t& n = bank.count(li);
    bank.note_read();
    stats_.comparator_activations += m_;

    // The comparators see every slot; invalid slots (beyond the count) answer
    // "greater", so the "<=" outputs form a thermometer code whose popcount is
    // the insertion position.
    unsigned pos = 0;
    for (unsigned i = 0; i < n; ++i) {
        const std::uint64_t w = row[i];
        const std::uint64_t k = front_first_ ? ((w >> id_shift_) << 1) | (w & 1u) : (w >> id_shift_);
        pos += (k <= key);
    }

    if (n == m_) {
        bank.note_overflow(li);
        ++stats_.overflows;
        if (pos == m_) {
            // Write enable stays low: the row is unchanged.
            ++stats_.dropped_new;
            return;
        }
        ++stats_.dropped_last;
        for (unsigned i = m_ - 1; i > pos; --i) row[i] = row[i - 1];
        stats_.mux_shifts += m_ - 1 - pos;
    } else {
        for (unsigned i = n; i > pos; --i) row[i] = row[i - 1];
        stats_.mux_shifts += n - pos;
        ++n;
        bank.mark_occupied(li);
    }
    row[pos] = word;
    bank.note_write();
}

insertion_sorter::FillResult insertion_sorter::fill_tile(const Tile& tile, zeb_bank& bank, std::uint64_t start,
                                                         unsigned depth_bits) {
    FillResult r;
    const std::uint32_t x0 = tile.col * tile_w_, y0 = tile.row * tile_h_;

    std::uint64_t feed_cycle = start;   // cycle the feed is emitting in
    unsigned emitted_this_cycle = 0;
    unsigned prev_list[2] = {~0u, ~0u};  // pixels of the two previous insertions (hazard window)
    std::uint64_t prev_issue[2] = {0, 0};
    bool first = true;

    for (const Fragment& f : tile.frags) {
        // Feed side: R per cycle, held while the queue is full.
        if (emitted_this_cycle == rate_) {
            ++feed_cycle;
            emitted_this_cycle = 0;
        }
        std::uint64_t& ring = issue_ring_[seq_ % queue_depth_];
        if (seq_ >= queue_depth_ && ring > feed_cycle) {
            // Same-cycle pop and push are allowed: the slot is usable in the issue cycle.
            if (vcd_feed_) {
                vcd_feed_->set(vcd_queue_full_, emitted_this_cycle ? feed_cycle + 1 : feed_cycle, 1);
                vcd_feed_->set(vcd_queue_full_, ring, 0);
            }
            feed_cycle = ring;
            emitted_this_cycle = 0;
        }
        const std::uint64_t enq = feed_cycle;
        ++emitted_this_cycle;

        // Sorter side: issue no earlier than the cycle after enqueue, one per cycle.
        std::uint64_t issue = enq + 1;
        if (any_issued_) issue = std::max(issue, last_issue_ + 1);
        const std::uint64_t unhindered = issue;
        const unsigned li = (f.y - y0) * tile_w_ + (f.x - x0);
        bool hazard = false;
        for (int k = 0; k < 2; ++k) {
            if (prev_list[k] != li || prev_issue[k] + kStages <= issue) continue;
            hazard = true;
            if (stall_on_hazard_) issue = std::max(issue, prev_issue[k] + kStages);
        }
        if (hazard && !stall_on_hazard_) ++stats_.hazard_forwards;
        stats_.hazard_stall_cycles += issue - unhindered;
        if (vcd_) {
            vcd_->add_delta(vcd_occupancy_, enq, +1);
            vcd_->add_delta(vcd_occupancy_, issue, -1);
            vcd_->set(vcd_issue_, issue, 1);
            vcd_->set(vcd_issue_, issue + 1, 0);
            if (issue > unhindered) {
                vcd_->set(vcd_hazard_, unhindered, 1);
                vcd_->set(vcd_hazard_, issue, 0);
            }
            if (first) vcd_->set(vcd_bank_, issue, bank.index());
        }

        // Occupancy seen by this enqueue: older fragments not yet issued, plus this one.
        // Read before the ring slot of fragment seq_-Q is overwritten below.
        while (queue_head_ < seq_ && issue_ring_[queue_head_ % queue_depth_] <= enq) ++queue_head_;
        stats_.queue_max_occupancy = std::max<std::uint64_t>(stats_.queue_max_occupancy, seq_ - queue_head_ + 1);
        ring = issue;
        ++seq_;
        prev_list[1] = prev_list[0];
        prev_issue[1] = prev_issue[0];
        prev_list[0] = li;
        prev_issue[0] = issue;
        if (first) r.first_issue = issue;
        first = false;
        last_issue_ = issue;
        any_issued_ = true;

        Element e;
        e.dq = quantize_depth(f.depth, depth_bits, z_bits_);
        e.id = f.id;
        e.facing = f.facing;
        const std::uint64_t key = sort_key(e, front_first_ ? TiePolicy::FrontFirst : TiePolicy::Arrival);
        insert(bank, li, layout_.pack(e), key);
    }
    // The stall is the time lost against an unhindered feed, not the sum of
    // per-fragment waits (a held cycle may still emit fewer than R fragments).
    const std::uint64_t n = tile.frags.size();
    if (n) r.queue_stall = (feed_cycle + 1 - start) - (n + rate_ - 1) / rate_;
    stats_.insertions += tile.frags.size();
    stats_.busy_cycles += tile.frags.size();
    stats_.queue_full_cycles += r.queue_stall;
    r.feed_done = tile.frags.empty() ? start : feed_cycle + 1;
    r.last_issue = last_issue_;
    r.fill_done = tile.frags.empty() ? start : last_issue_ + kStages;
    return r;
}

} // namespace rbcd
