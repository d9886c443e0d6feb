// One ZEB (Z-depth Extended Buffer) bank: an SRAM with one row of M packed
// elements per pixel list of the tile, a per-list occupancy count, and the
// occupancy bitmap the z-overlap tester uses to skip empty lists.
//
//   zeb_bank bank("zeb0", cfg.zeb, cfg.tile);
//   bank.begin_fill(frame, col, row);      // Free -> Filling
//   std::uint64_t* row = bank.list(i);      // sorter: read-modify-write one row
//   bank.begin_test();  ...  bank.release(); // Testing -> Free, notifies freed
#pragma once
#include <cstdint>
#include <systemc>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/stat_counters.h"
#include "rbcd/common/vcd_writer.h"

namespace rbcd {

class zeb_bank : public sc_core::sc_module {
public:
    enum class State : std::uint8_t { Free = 0, Filling = 1, Testing = 2 };

    struct stats_t {
        std::uint64_t row_reads = 0;        // list rows read (sorter read port and tester read port)
        std::uint64_t row_writes = 0;       // list rows written by the sorter
        std::uint64_t tiles = 0;            // tiles this bank held
        std::uint64_t flash_clears = 0;     // occupancy resets between tiles
        std::uint64_t filling_cycles = 0;   // cycles in state Filling
        std::uint64_t testing_cycles = 0;   // cycles in state Testing
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, row_reads, "list rows read (sorter and tester ports)");
            RBCD_STAT(f, s, row_writes, "list rows written by the sorter");
            RBCD_STAT(f, s, tiles, "tiles held");
            RBCD_STAT(f, s, flash_clears, "occupancy flash clears (one per tile taken)");
            RBCD_STAT(f, s, filling_cycles, "cycles filling");
            RBCD_STAT(f, s, testing_cycles, "cycles being tested");
        }
    };

    zeb_bank(sc_core::sc_module_name name, const ZebConfig& zeb, const TileConfig& tile, unsigned index);

    unsigned index() const { return index_; }
    unsigned lists() const { return lists_; }
    unsigned list_length() const { return m_; }
    std::uint64_t bits() const { return std::uint64_t(lists_) * m_ * width_bits_; }

    State state() const { return state_; }
    // The cycle the bank entered its current state (for a Free bank: released).
    std::uint64_t state_since() const { return state_since_; }
    std::uint64_t frame() const { return frame_; }
    std::uint32_t tile_col() const { return col_; }
    std::uint32_t tile_row() const { return row_; }

    void begin_fill(std::uint64_t frame, std::uint32_t col, std::uint32_t row, std::uint64_t cycle);
    void begin_test(std::uint64_t cycle);
    void release(std::uint64_t cycle);

    // Row access. Counting is the caller's business via note_*: the sorter
    // and the tester know when a port really fires.
    std::uint64_t* list(unsigned i) { return &words_[std::size_t(i) * m_]; }
    const std::uint64_t* list(unsigned i) const { return &words_[std::size_t(i) * m_]; }
    std::uint8_t& count(unsigned i) { return count_[i]; }
    std::uint8_t count(unsigned i) const { return count_[i]; }
    void mark_occupied(unsigned i) { occupancy_[i >> 6] |= 1ull << (i & 63); }
    const std::vector<std::uint64_t>& occupancy() const { return occupancy_; }
    void note_read() { ++stats_.row_reads; }
    void note_write() { ++stats_.row_writes; }
    void note_writes(unsigned k) { stats_.row_writes += k; }

    // Overflow bookkeeping of the tile held (contract: "Sorted insertion").
    void note_overflow(unsigned i);
    // The same when `full` (0 or 1) is 1, without a branch on it.
    void note_overflow_if(unsigned i, unsigned full) {
        dropped_ += full;
        std::uint64_t& w = overflowed_[i >> 6];
        const std::uint64_t bit = std::uint64_t(full) << (i & 63);
        lists_overflowed_ += (~w & bit) != 0;
        w |= bit;
    }
    std::uint32_t lists_overflowed() const { return lists_overflowed_; }
    std::uint64_t fragments_dropped() const { return dropped_; }

    const stats_t& stats() const { return stats_; }
    sc_core::sc_event freed;

    void attach_vcd(VcdWriter& vcd, const std::string& scope);

private:
    void clear();

    unsigned index_;
    unsigned lists_, m_, width_bits_;
    std::vector<std::uint64_t> words_;
    std::vector<std::uint8_t> count_;
    std::vector<std::uint64_t> occupancy_;
    std::vector<std::uint64_t> overflowed_;
    std::uint32_t lists_overflowed_ = 0;
    std::uint64_t dropped_ = 0;
    State state_ = State::Free;
    std::uint64_t state_since_ = 0;
    std::uint64_t frame_ = 0;
    std::uint32_t col_ = 0, row_ = 0;
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_state_ = 0, vcd_frame_ = 0, vcd_col_ = 0, vcd_row_ = 0;
    void trace_state(std::uint64_t cycle);
};

} // namespace rbcd
