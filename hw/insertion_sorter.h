// The M-way comparator/mux insertion sorter (paper, Figure 4).
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
// Timing is computed per fragment as the rasterizer hands it over, not
// ticked: a fragment that entered the input queue at e issues at
// max(e + 1, previous issue + 1, the bank's ready cycle, hazard rule).
//
//   sorter.begin_tile(bank, ready, tile);   // bank Filling, usable from `ready`
//   std::uint64_t s = sorter.accept(frag, enqueue_cycle, depth_bits);
//   std::uint64_t filled = sorter.end_tile();   // the bank holds the whole tile
#pragma once
#include <algorithm>
#include <cstdint>
#include <systemc>
#if defined(__SSE2__)
#include <emmintrin.h>   // part of x86-64 itself
#endif
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/fragment.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/zeb_bank.h"

namespace rbcd {

namespace sorter_detail {
// Set bits of a byte (popcount is a library call without -mpopcnt).
struct Popcount8 {
    std::uint8_t v[256] = {};
    constexpr Popcount8() {
        for (unsigned i = 1; i < 256; ++i) v[i] = static_cast<std::uint8_t>(v[i >> 1] + (i & 1));
    }
};
inline constexpr Popcount8 kPopcount8{};
} // namespace sorter_detail

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
        std::uint64_t bank_wait_cycles = 0;      // issue cycles lost waiting for the tile's bank
        std::uint64_t busy_cycles = 0;           // cycles with an insertion issued
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, insertions, "fragments inserted (one per issue cycle)");
            RBCD_STAT(f, s, comparator_activations, "key comparators fired (M per insertion)");
            RBCD_STAT(f, s, mux_shifts, "elements shifted down one slot by the muxes");
            RBCD_STAT(f, s, overflows, "fragments dropped by full lists");
            RBCD_STAT(f, s, dropped_new, "overflows where the new element sorted last and was dropped");
            RBCD_STAT(f, s, dropped_last, "overflows where the last element was shifted out");
            RBCD_STAT(f, s, hazard_forwards, "same-pixel hazards bypassed by forwarding");
            RBCD_STAT(f, s, hazard_stall_cycles, "issue cycles lost to same-pixel hazards");
            RBCD_STAT(f, s, bank_wait_cycles, "issue cycles lost waiting for the tile's ZEB bank (gpu.bank_wait = unit)");
            RBCD_STAT(f, s, busy_cycles, "cycles with an insertion issued");
        }
    };

    insertion_sorter(sc_core::sc_module_name name, const SimConfig& cfg);

    // The tile's fragments go into `bank` (already Filling), which the READ
    // stage may use from cycle `ready` on.
    void begin_tile(zeb_bank& bank, std::uint64_t ready, const Tile& tile);
    // How insert() sorts the tile's fragments (the same rows either way, up
    // to slots past the count, which nothing reads): loops over the list
    // count, cheap when counts repeat from one fragment to the next (per-
    // object bursts, a rendered scene), or fixed work over all M slots (M =
    // 4, 8, 16), cheaper when they vary (a rasterizer's order over many
    // small primitives), where each loop's exit mispredicts (callgrind
    // --branch-sim: 1.2 a fragment on rbcd-bench's interleaved trace). The
    // choice follows how often the count changed in recent counted tiles
    // (begin_tile()); loops count one tile in kSampleEvery, all slots every
    // tile. The
    // caller runs a tile's fragments with accept<path()>, so that each path
    // is its own straight code (one path with a test per fragment cost the
    // default scene 4%).
    enum Path : unsigned { Loops = 0, LoopsCounted = 1, AllSlots = 2 };
    Path path() const { return path_; }
    // A fragment of the tile entered the input queue at `enq`: returns its
    // issue cycle and inserts it. depth_bits is the input stream's.
    template <Path P>
    [[gnu::always_inline]] std::uint64_t accept(const Fragment& f, std::uint64_t enq, unsigned depth_bits) {
        std::uint64_t issue = enq + 1;
        if (any_issued_) issue = std::max(issue, last_issue_ + 1);
        if (issue < bank_ready_) {
            stats_.bank_wait_cycles += bank_ready_ - issue;
            issue = bank_ready_;
        }
        const unsigned li = (f.y - y0_) * tile_w_ + (f.x - x0_);
        if (li == prev_list_[0] || li == prev_list_[1]) issue = hazard(li, issue);
        if (vcd_) trace_issue(issue);
        prev_list_[1] = prev_list_[0];
        prev_issue_[1] = prev_issue_[0];
        prev_list_[0] = li;
        prev_issue_[0] = issue;
        last_issue_ = issue;
        any_issued_ = true;
        ++tile_frags_;

        Element e;
        e.dq = quantize_depth(f.depth, depth_bits, z_bits_);
        e.id = f.id;
        e.facing = f.facing;
        const std::uint64_t key = sort_key(e, front_first_ ? TiePolicy::FrontFirst : TiePolicy::Arrival);
        insert<P>(*bank_, li, layout_.pack(e), key);
        return issue;
    }
    // The same, on the tile's path.
    std::uint64_t accept(const Fragment& f, std::uint64_t enq, unsigned depth_bits) {
        switch (path_) {
        case Loops: return accept<Loops>(f, enq, depth_bits);
        case LoopsCounted: return accept<LoopsCounted>(f, enq, depth_bits);
        default: return accept<AllSlots>(f, enq, depth_bits);
        }
    }
    // After the tile's last fragment: the cycle from which the bank holds the whole tile.
    std::uint64_t end_tile();
    // Frame barrier: the pipeline is empty from cycle t on.
    void restart(std::uint64_t t);

    const stats_t& stats() const { return stats_; }

    // Waveforms: issue and hazard activity, the bank being filled.
    void attach_vcd(VcdWriter& vcd, const std::string& scope);

private:
    template <Path P>
    void insert(zeb_bank& bank, unsigned list, std::uint64_t word, std::uint64_t key);
    // The M comparators over every slot, masked by the count, two slots to an
    // SSE2 compare: a masked word is below 2^49, so with the exponent bits of
    // 2^52 set it reads as the double 2^52 + w, ordered as the word is (SSE2
    // has no 64-bit integer compare). Their popcount is the position.
    template <unsigned M>
    [[gnu::always_inline]] static unsigned position_all(const std::uint64_t* row, unsigned n, std::uint64_t keep,
                                                        std::uint64_t limit) {
#if defined(__SSE2__)
        constexpr std::uint64_t kTwo52 = 0x4330000000000000ull;
        // Past 2^52 - 1 the limit is above every word either way.
        const std::uint64_t lim = std::min<std::uint64_t>(limit, (std::uint64_t(1) << 52) - 1);
        const __m128i magic = _mm_set1_epi64x(static_cast<long long>(kTwo52));
        const __m128i k = _mm_set1_epi64x(static_cast<long long>(keep));
        const __m128d l = _mm_castsi128_pd(_mm_set1_epi64x(static_cast<long long>(kTwo52 | lim)));
        unsigned le = 0;
        for (unsigned j = 0; j < M / 2; ++j) {
            const __m128i w = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + 2 * j));
            const __m128d d = _mm_castsi128_pd(_mm_or_si128(_mm_and_si128(w, k), magic));
            le |= static_cast<unsigned>(_mm_movemask_pd(_mm_cmple_pd(d, l))) << (2 * j);
        }
        le &= (1u << n) - 1;
        return sorter_detail::kPopcount8.v[le & 0xFFu] + (M > 8 ? sorter_detail::kPopcount8.v[le >> 8] : 0u);
#else
        unsigned pos = 0;
        for (unsigned i = 0; i < M; ++i) pos += (i < n) & ((row[i] & keep) <= limit);
        return pos;
#endif
    }
    unsigned position_all(const std::uint64_t* row, unsigned n, std::uint64_t keep, std::uint64_t limit) const {
        switch (m_) {
        case 4: return position_all<4>(row, n, keep, limit);
        case 8: return position_all<8>(row, n, keep, limit);
        default: return position_all<16>(row, n, keep, limit);
        }
    }
    // The M muxes: slot i keeps its element below pos, takes the new one at
    // pos and its upper neighbour's above (slots past the count take whatever
    // comes), as selects between the row and the row moved down one slot.
    template <unsigned M>
    [[gnu::always_inline]] static void place_all(std::uint64_t* row, unsigned pos, std::uint64_t word) {
#if defined(__SSE2__)
        const __m128i w = _mm_set1_epi64x(static_cast<long long>(word));
        const __m128i p = _mm_set1_epi32(static_cast<int>(pos));
        __m128i above = w;   // the pair of slots before this one (none: the new element)
        for (unsigned j = 0; j < M / 2; ++j) {
            const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + 2 * j));
            // Slots 2j and 2j+1 moved down: slot 2j - 1's element, then slot 2j's.
            const __m128i down = _mm_castpd_si128(_mm_shuffle_pd(_mm_castsi128_pd(above), _mm_castsi128_pd(v), 1));
            const __m128i slot = _mm_set_epi32(int(2 * j + 1), int(2 * j + 1), int(2 * j), int(2 * j));
            const __m128i gt = _mm_cmpgt_epi32(slot, p), eq = _mm_cmpeq_epi32(slot, p);
            __m128i r = _mm_or_si128(_mm_andnot_si128(gt, v), _mm_and_si128(gt, down));
            r = _mm_or_si128(_mm_andnot_si128(eq, r), _mm_and_si128(eq, w));
            _mm_storeu_si128(reinterpret_cast<__m128i*>(row + 2 * j), r);
            above = v;
        }
#else
        if (pos >= M) return;   // the new element sorts last: the row stays
        for (unsigned i = M - 1; i > pos; --i) row[i] = row[i - 1];
        row[pos] = word;
#endif
    }
    void place_all(std::uint64_t* row, unsigned pos, std::uint64_t word) const {
        switch (m_) {
        case 4: return place_all<4>(row, pos, word);
        case 8: return place_all<8>(row, pos, word);
        default: return place_all<16>(row, pos, word);
        }
    }
    std::uint64_t hazard(unsigned li, std::uint64_t issue);
    void trace_issue(std::uint64_t issue);

    unsigned m_;
    unsigned tile_w_, tile_h_;
    unsigned z_bits_, id_shift_;
    bool front_first_;
    bool stall_on_hazard_;
    ElementLayout layout_;

    zeb_bank* bank_ = nullptr;
    std::uint32_t x0_ = 0, y0_ = 0;
    std::uint64_t bank_ready_ = 0;
    std::uint64_t tile_frags_ = 0;
    unsigned prev_list_[2] = {~0u, ~0u};   // pixels of the two previous insertions (hazard window)
    std::uint64_t prev_issue_[2] = {0, 0};
    std::uint64_t last_issue_ = 0;
    bool any_issued_ = false;
    bool first_of_tile_ = false;
    static constexpr unsigned kSampleEvery = 8;
    Path path_ = Loops;
    unsigned tiles_to_sample_ = 0;
    unsigned last_count_ = 0;            // list count at the previous insertion (counted tiles)
    std::uint64_t count_changes_ = 0;    // insertions whose count differed from the previous one's
    std::uint64_t recent_changes_ = 0, recent_insertions_ = 0;   // over the tiles counted, decaying
    stats_t stats_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_issue_ = 0, vcd_hazard_ = 0, vcd_bank_ = 0;
};

// Per fragment: in the header, so that accept() and the rasterizer's walk
// inline it (a call a fragment costs a tenth of its time).
template <insertion_sorter::Path P>
[[gnu::always_inline]] inline void insertion_sorter::insert(zeb_bank& bank, unsigned li, std::uint64_t word, std::uint64_t key) {
    std::uint64_t* row = bank.list(li);
    std::uint8_t& n = bank.count(li);
    bank.note_read();
    stats_.comparator_activations += m_;

    // The comparators see every slot; invalid slots (beyond the count) answer
    // "greater", so the "<=" outputs form a thermometer code whose popcount is
    // the insertion position.
    // Compared as stored words, not as keys rebuilt from them: a word is
    // [dq | id | facing], so with its id zeroed it orders as (dq, facing)
    // does, and under arrival w >> s <= key is w <= ((key + 1) << s) - 1
    // (no overflow: an element is at most 49 bits wide).
    if (P != Loops) {
        count_changes_ += n != last_count_;
        last_count_ = n;
    }
    const std::uint64_t id_mask = ((std::uint64_t(1) << (id_shift_ - 1)) - 1) << 1;
    const std::uint64_t keep = front_first_ ? ~id_mask : ~std::uint64_t(0);
    const std::uint64_t limit =
        front_first_ ? ((key >> 1) << id_shift_) | (key & 1u) : ((key + 1) << id_shift_) - 1;
    if constexpr (P == AllSlots) {
        // Straight code, no branch on the outcome (each one mispredicts on a
        // trace whose counts vary): a full list counts its overflow, and
        // pos = M (the new element sorts last) leaves the row as it was.
        const unsigned pos = position_all(row, n, keep, limit);
        const unsigned full = n == m_, dropped_new = full & (pos == m_);
        bank.note_overflow_if(li, full);
        stats_.overflows += full;
        stats_.dropped_new += dropped_new;
        stats_.dropped_last += full - dropped_new;
        stats_.mux_shifts += n - pos - full + dropped_new;
        n = static_cast<std::uint8_t>(n + 1 - full);
        bank.mark_occupied(li);
        place_all(row, pos, word);
        bank.note_writes(1 - dropped_new);
        return;
    }
    const auto le = [=](std::uint64_t w) { return (w & keep) <= limit; };
    unsigned pos = 0;
    for (unsigned i = 0; i < n; ++i) pos += le(row[i]);

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

} // namespace rbcd
