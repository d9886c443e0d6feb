// Untimed reference model of rbcd-contract.md: the testbench's oracle.
// It shares only common/element.h, common/records.h and common/fragment.h (and
// SimConfig's fields) with the SystemC model, never algorithm code, so that it
// stays an independent check.
#pragma once
#include <cstdint>
#include <variant>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/element.h"
#include "rbcd/common/fragment.h"
#include "rbcd/common/records.h"

namespace rbcd::ref {

struct RefConfig {
    unsigned tile_w = 16, tile_h = 16;
    unsigned list_length = 8;      // M
    unsigned z_bits = 24, id_bits = 7;
    TiePolicy tie = TiePolicy::FrontFirst;
    unsigned stack_depth = 8;      // T
    OutputMode output = OutputMode::Raw;
    unsigned depth_bits = 24;      // of the input stream
};

struct RefCounts {
    std::uint64_t frames = 0, tiles = 0, fragments = 0, overflows = 0;
    std::uint64_t stack_overflows = 0, orphan_back_faces = 0, hits = 0;
};

// One output record, in the order the unit writes them.
using RefRecord = std::variant<HitRecord, OverflowRecord>;

struct RefFrame {
    std::uint64_t frame = 0;
    std::vector<RefRecord> records;
};

struct RefResult {
    std::vector<RefFrame> frames;
    RefCounts counts;
};

// The contract's keys of a SimConfig (only field reads: no link dependency on rbcd_common).
RefConfig ref_config_from(const SimConfig& sim, unsigned depth_bits);

// Runs the contract over a whole stream (frames and tiles as the source yields them).
// depth_bits is taken from src.header() (cfg.depth_bits is ignored here); a
// header tile size other than cfg's, or a tile before the first frame, is an InputError.
RefResult run_reference(const RefConfig& cfg, FragmentSource& src);
// One tile: appends that tile's records to `out` and adds to `counts` (tiles and fragments included).
// A fragment outside the tile, an id wider than id_bits or a depth wider than
// depth_bits breaks the contract's preconditions: InputError, nothing appended.
void reference_tile(const RefConfig& cfg, const Tile& tile, std::vector<RefRecord>& out, RefCounts& counts);

// The contract's sorted insertion into one list of at most `list_length`
// elements; returns the fragments it dropped (0 or 1). Exposed for unit tests.
unsigned insert_element(std::vector<Element>& list, const Element& e, unsigned list_length, TiePolicy tie);

} // namespace rbcd::ref
