#include "rbcd/hw/zeb_bank.h"

#include <algorithm>

namespace rbcd {

zeb_bank::zeb_bank(sc_core::sc_module_name name, const ZebConfig& zeb, const TileConfig& tile, unsigned index)
    : sc_module(name),
      index_(index),
      lists_(tile.pixels()),
      m_(zeb.list_length),
      width_bits_(zeb.layout().width()),
      words_(std::size_t(lists_) * m_, 0),
      count_(lists_, 0),
      occupancy_((lists_ + 63) / 64, 0),
      overflowed_((lists_ + 63) / 64, 0) {}

void zeb_bank::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_state_ = vcd.add(scope, "state", 2);   // 0 free, 1 filling, 2 testing
    vcd_frame_ = vcd.add(scope, "frame", 32);
    vcd_col_ = vcd.add(scope, "tile_col", 16);
    vcd_row_ = vcd.add(scope, "tile_row", 16);
}

void zeb_bank::trace_state(std::uint64_t cycle) {
    if (!vcd_) return;
    vcd_->set(vcd_state_, cycle, static_cast<std::uint64_t>(state_));
    vcd_->set(vcd_frame_, cycle, frame_);
    vcd_->set(vcd_col_, cycle, col_);
    vcd_->set(vcd_row_, cycle, row_);
}

void zeb_bank::clear() {
    // Counts and bitmaps are flops beside the SRAM, reset in one cycle; the
    // element rows themselves are never cleared, a count of 0 makes them dead.
    std::fill(count_.begin(), count_.end(), 0);
    std::fill(occupancy_.begin(), occupancy_.end(), 0);
    std::fill(overflowed_.begin(), overflowed_.end(), 0);
    lists_overflowed_ = 0;
    dropped_ = 0;
    ++stats_.flash_clears;
}

void zeb_bank::begin_fill(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::uint64_t cycle) {
    sc_assert(state_ == State::Free);
    clear();
    frame_ = frame;
    col_ = col;
    row_ = row;
    state_ = State::Filling;
    state_since_ = cycle;
    ++stats_.tiles;
    trace_state(cycle);
}

void zeb_bank::begin_test(std::uint64_t cycle) {
    sc_assert(state_ == State::Filling);
    stats_.filling_cycles += cycle - state_since_;
    state_ = State::Testing;
    state_since_ = cycle;
    trace_state(cycle);
}

void zeb_bank::release(std::uint64_t cycle) {
    sc_assert(state_ == State::Testing);
    stats_.testing_cycles += cycle - state_since_;
    state_ = State::Free;
    state_since_ = cycle;
    trace_state(cycle);
    freed.notify(sc_core::SC_ZERO_TIME);
}

void zeb_bank::note_overflow(unsigned i) {
    ++dropped_;
    std::uint64_t& w = overflowed_[i >> 6];
    const std::uint64_t bit = 1ull << (i & 63);
    if (!(w & bit)) {
        w |= bit;
        ++lists_overflowed_;
    }
}

} // namespace rbcd
