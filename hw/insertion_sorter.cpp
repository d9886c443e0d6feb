#include "rbcd/hw/insertion_sorter.h"

#include <algorithm>

namespace rbcd {

insertion_sorter::insertion_sorter(sc_core::sc_module_name name, const SimConfig& cfg)
    : sc_module(name),
      m_(cfg.zeb.list_length),
      tile_w_(cfg.tile.width),
      tile_h_(cfg.tile.height),
      z_bits_(cfg.zeb.z_bits),
      id_shift_(cfg.zeb.id_bits + 1),
      front_first_(cfg.zeb.tie == TiePolicy::FrontFirst),
      stall_on_hazard_(cfg.sorter.hazard == HazardPolicy::Stall),
      layout_(cfg.zeb.layout()) {}

void insertion_sorter::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_issue_ = vcd.add(scope, "issue", 1);
    vcd_hazard_ = vcd.add(scope, "hazard_stall", 1);
    vcd_bank_ = vcd.add(scope, "bank", 4);
}

void insertion_sorter::begin_tile(zeb_bank& bank, std::uint64_t ready, const Tile& tile) {
    bank_ = &bank;
    bank_ready_ = ready;
    x0_ = tile.col * tile_w_;
    y0_ = tile.row * tile_h_;
    // insert()'s path (path() in the header): all slots when the count
    // changed in more than an eighth of the insertions of the tiles counted,
    // weighted by their fragments and halved each counted tile, so that one
    // sparse tile does not send a busy trace back to the loops.
    if (path_ != Loops && tile_frags_) {
        recent_changes_ = recent_changes_ / 2 + count_changes_;
        recent_insertions_ = recent_insertions_ / 2 + tile_frags_;
        const bool fixed_m = m_ == 4 || m_ == 8 || m_ == 16;
        path_ = fixed_m && recent_changes_ * 8 > recent_insertions_ ? AllSlots : Loops;
    } else if (path_ == LoopsCounted) {
        path_ = Loops;
    }
    if (path_ == Loops && tiles_to_sample_-- == 0) {
        path_ = LoopsCounted;
        tiles_to_sample_ = kSampleEvery - 1;
    }
    count_changes_ = 0;
    tile_frags_ = 0;
    // Hazards are between rows of one bank: a new tile starts a new window.
    prev_list_[0] = prev_list_[1] = ~0u;
    first_of_tile_ = true;
}

std::uint64_t insertion_sorter::hazard(unsigned li, std::uint64_t issue) {
    const std::uint64_t unhindered = issue;
    bool hit = false;
    for (int k = 0; k < 2; ++k) {
        if (prev_list_[k] != li || prev_issue_[k] + kStages <= issue) continue;
        hit = true;
        if (stall_on_hazard_) issue = std::max(issue, prev_issue_[k] + kStages);
    }
    if (hit && !stall_on_hazard_) ++stats_.hazard_forwards;
    stats_.hazard_stall_cycles += issue - unhindered;
    if (vcd_ && issue > unhindered) {
        vcd_->set(vcd_hazard_, unhindered, 1);
        vcd_->set(vcd_hazard_, issue, 0);
    }
    return issue;
}

void insertion_sorter::trace_issue(std::uint64_t issue) {
    vcd_->set(vcd_issue_, issue, 1);
    vcd_->set(vcd_issue_, issue + 1, 0);
    if (first_of_tile_) vcd_->set(vcd_bank_, issue, bank_->index());
    first_of_tile_ = false;
}

std::uint64_t insertion_sorter::end_tile() {
    stats_.insertions += tile_frags_;
    stats_.busy_cycles += tile_frags_;
    return last_issue_ + kStages;
}

void insertion_sorter::restart(std::uint64_t t) {
    // Issue no earlier than t: as if the last insertion issued at t - 1.
    last_issue_ = t ? t - 1 : 0;
    any_issued_ = t > 0;
    prev_list_[0] = prev_list_[1] = ~0u;
}

} // namespace rbcd
