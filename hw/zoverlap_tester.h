// The z-overlap tester: walks each non-empty list of a filled ZEB bank front
// to back through an FF-stack of T entries (id, matched bit), finds the
// interval overlaps the contract defines, and hands hit and overflow records
// to the output buffer. Banks are tested in tile (rasterization) order.
//
// Per tile: the occupancy bitmap skips empty lists for free; one list row is
// read (1 cycle, overlapped with the previous list's walk after the first);
// each element takes one cycle, except a back face whose match leaves k > 1
// hits above it: the hit priority encoder emits one hit per cycle, so it takes
// k cycles. Records wait for a free output-buffer slot (tester stall).
#pragma once
#include <cstdint>
#include <deque>
#include <systemc>
#include <unordered_set>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/hw/clocking.h"
#include "rbcd/hw/output_buffer.h"
#include "rbcd/common/vcd_writer.h"
#include "rbcd/hw/zeb_bank.h"

namespace rbcd {

// One tile as the tester saw it (absolute cycles), for a TestObserver.
struct TestedTile {
    std::uint64_t frame = 0;
    std::uint32_t col = 0, row = 0;
    unsigned bank = 0;
    std::uint64_t start = 0, end = 0;          // walking its lists; end: bank released
    std::uint64_t done = 0;                    // ... and its overflow record accepted
    std::uint64_t lists = 0, elements = 0, max_list = 0;
    std::uint64_t hits = 0, filtered_hits = 0, stack_overflows = 0, orphan_back_faces = 0;
    std::uint64_t output_stall = 0;            // cycles held by a full output buffer
    std::uint64_t lists_overflowed = 0, fragments_dropped = 0;
};

class TestObserver {
public:
    virtual ~TestObserver() = default;
    virtual void tile_tested(const TestedTile&) = 0;
};

class zoverlap_tester : public sc_core::sc_module {
public:
    SC_HAS_PROCESS(zoverlap_tester);

    struct Job {
        enum Kind { FrameStart, TileJob, FrameEnd, Finish } kind;
        std::uint64_t frame = 0;
        zeb_bank* bank = nullptr;
        std::uint64_t ready = 0;   // cycle the bank holds the whole tile
        std::uint64_t fragments = 0;   // collisionable fragments the rasterizer sent for the tile
    };

    struct stats_t {
        std::uint64_t tiles = 0;
        std::uint64_t lists = 0;                // non-empty lists walked
        std::uint64_t elements = 0;             // list elements walked
        std::uint64_t pushes = 0;               // front faces pushed
        std::uint64_t stack_overflows = 0;      // pushes dropped by a full stack
        std::uint64_t id_compares = 0;          // equality comparators fired (T per back face)
        std::uint64_t orphan_back_faces = 0;
        std::uint64_t matches = 0;              // back faces that matched an entry
        std::uint64_t raw_hits = 0;             // hits produced before output filtering
        std::uint64_t hits = 0;                 // hit records written
        std::uint64_t filtered_hits = 0;        // hits removed by tester.output
        std::uint64_t overflow_records = 0;
        std::uint64_t busy_cycles = 0;          // cycles walking lists (incl. encoder cycles)
        std::uint64_t output_stall_cycles = 0;  // cycles held by a full output buffer
        std::uint64_t readback_cycles = 0;      // cycles waiting for the host at frame ends
        std::uint64_t idle_cycles = 0;          // cycles with no filled bank to test
        RBCD_STATS_VISITOR {
            RBCD_STAT(f, s, tiles, "tiles tested");
            RBCD_STAT(f, s, lists, "non-empty lists walked");
            RBCD_STAT(f, s, elements, "list elements walked");
            RBCD_STAT(f, s, pushes, "front faces pushed onto the FF-stack");
            RBCD_STAT(f, s, stack_overflows, "pushes dropped by a full FF-stack");
            RBCD_STAT(f, s, id_compares, "id equality comparators fired (T per back face)");
            RBCD_STAT(f, s, orphan_back_faces, "back faces with no unmatched entry of their id");
            RBCD_STAT(f, s, matches, "back faces that matched an entry");
            RBCD_STAT(f, s, raw_hits, "hits found before output filtering");
            RBCD_STAT(f, s, hits, "hit records written");
            RBCD_STAT(f, s, filtered_hits, "hits dropped by the pixel/tile output filter");
            RBCD_STAT(f, s, overflow_records, "overflow records written");
            RBCD_STAT(f, s, busy_cycles, "cycles walking lists");
            RBCD_STAT(f, s, output_stall_cycles, "cycles held by a full output buffer");
            RBCD_STAT(f, s, readback_cycles, "cycles waiting at frame ends for the host to free the next output region");
            RBCD_STAT(f, s, idle_cycles, "cycles with no filled bank to test");
        }
    };

    zoverlap_tester(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk, output_buffer& out,
                    unit_host_if& host);

    void post(const Job& j) {
        jobs_.push_back(j);
        job_posted_.notify(sc_core::SC_ZERO_TIME);
    }
    // Cycle the last job (Finish) completed.
    std::uint64_t finish_cycle() const { return finish_cycle_; }
    bool finished() const { return finished_; }
    const stats_t& stats() const { return stats_; }
    void attach_vcd(VcdWriter& vcd, const std::string& scope);
    // Told each tile's figures as its test ends; none: nothing is gathered.
    void add_test_observer(TestObserver* o) { observers_.push_back(o); }

    // Test-only hook (testbench/hw/test_self_check.cpp): before testing the
    // tile-th tile (from 0) the tester takes one element out of its bank, as a
    // sorter that lost a fragment would, so that tile_conservation fires.
    void lose_element_for_test(std::uint64_t tile) { lose_tile_ = tile; }

    // Frame ends: after each FrameEnd job, the cycle the frame's records were
    // all in memory, announced by frame_flushed (the rasterizer's frame barrier).
    std::uint64_t last_flushed() const { return last_flushed_; }
    std::uint64_t frames_flushed() const { return frames_flushed_; }
    sc_core::sc_event frame_flushed;

private:
    void run();
    std::uint64_t test_tile(zeb_bank& bank, std::uint64_t t);
    void lose_element(zeb_bank& bank);
    TestedTile tested_tile(zeb_bank& bank, std::uint64_t start, std::uint64_t end, const stats_t& before) const;
    std::uint64_t emit_overflow(const OverflowRecord& o, std::uint64_t t);
    std::uint64_t emit_hit(std::uint32_t x, std::uint32_t y, std::uint32_t id1, std::uint32_t id2,
                           std::uint32_t dq, std::uint64_t t);

    const Clocking& clk_;
    output_buffer& out_;
    unit_host_if& host_;
    unsigned t_depth_, tile_w_, tile_h_, id_shift_;
    std::uint32_t id_mask_;
    OutputMode mode_;
    ElementLayout layout_;

    std::deque<Job> jobs_;
    sc_core::sc_event job_posted_;
    std::vector<std::uint32_t> stack_id_;
    std::vector<std::uint8_t> stack_matched_;
    // Pairs already written in this pixel (pixel mode) or tile (tile mode).
    std::vector<std::uint32_t> pixel_pairs_;
    std::unordered_set<std::uint32_t> tile_pairs_;
    std::uint64_t last_flushed_ = 0, frames_flushed_ = 0;
    std::uint64_t finish_cycle_ = 0;
    bool finished_ = false;
    std::uint64_t lose_tile_ = ~std::uint64_t(0);
    stats_t stats_;
    std::vector<TestObserver*> observers_;
    VcdWriter* vcd_ = nullptr;
    VcdWriter::Sig vcd_busy_ = 0, vcd_bank_ = 0, vcd_list_ = 0, vcd_stack_ = 0, vcd_hit_ = 0, vcd_stall_ = 0,
                   vcd_readback_ = 0, vcd_frame_ = 0;
};

} // namespace rbcd
