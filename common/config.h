// Hardware and run parameters: one struct per block, validated once, plus the
// key registry that maps TOML keys onto them. docs/config.md lists every key.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rbcd/common/element.h"

namespace toml { inline namespace v3 { class table; class node; } }

namespace rbcd {

struct ClockConfig {
    double mhz = 400.0;
    // Integer picoseconds so that cycles <-> sc_time conversions are exact.
    std::uint64_t period_ps() const;
};

struct TileConfig {
    unsigned width = 16, height = 16;
    unsigned pixels() const { return width * height; }
};

struct ZebConfig {
    unsigned banks = 2;
    unsigned list_length = 8;   // M
    unsigned z_bits = 24;
    unsigned id_bits = 7;
    TiePolicy tie = TiePolicy::FrontFirst;
    ElementLayout layout() const { return {z_bits, id_bits}; }
};

struct FeedConfig {
    unsigned fragments_per_cycle = 4;   // rasterizer output rate
    unsigned queue_depth = 32;          // the unit's input queue, fragments
};

// What waits for a free ZEB bank (docs/timing.md): the whole tile at the tile
// scheduler (paper, section 3.5), or only the unit's input (section 5.2).
enum class BankWait { Tile, Unit };

enum class HazardPolicy { Forward, Stall };
struct SorterConfig {
    HazardPolicy hazard = HazardPolicy::Forward;
};

struct TesterConfig {
    unsigned stack_depth = 8;           // T
    OutputMode output = OutputMode::Raw;
};

struct OutputBufferConfig {
    unsigned buffer_records = 16;       // capacity, records of 16 bytes
    unsigned burst_records = 4;         // records per memory write
    unsigned max_outstanding = 4;       // writes in flight
    std::uint64_t region_offset = 0;    // output region inside the memory, bytes
    std::uint64_t region_bytes = 65536; // each region, when double-buffered
    // Two regions: the unit writes one while the host reads the other back.
    bool double_buffer = true;
    unsigned regions() const { return double_buffer ? 2u : 1u; }
};

struct MemoryConfig {
    std::uint64_t base = 0x80000000ull;
    std::uint64_t size_bytes = 1ull << 20;
    unsigned latency_min = 50, latency_max = 100;   // cycles
    unsigned bytes_per_cycle = 4;
    std::uint64_t seed = 1;
};

struct HostConfig {
    // Cycles the unit's output waits while the CPU reads the output region back
    // (at each frame end and whenever the region is full).
    std::uint64_t readback_cycles = 500;
};

// The raster pipeline of the tile-based GPU around the unit (paper, Figure 3
// and Table 2; docs/gpu-model.md). The rasterizer's rate is feed.fragments_per_cycle.
struct GpuConfig {
    unsigned setup_cycles_per_primitive = 1;   // rasterizer cycles to set up one primitive of a tile
    unsigned tile_overhead_cycles = 0;         // rasterizer cycles at each tile's start
    unsigned fragment_queue_depth = 64;        // the queue in front of early-Z (Table 2)
    unsigned early_z_cycles = 1;               // queue exit to fragment processor start
    unsigned fragment_processors = 4;
    unsigned cycles_per_fragment = 8;          // per fragment processor (docs/gpu-model.md)
    BankWait bank_wait = BankWait::Tile;
};

// The ZEB bank's SRAM device type: a 1R1W macro (the sorter reads and writes
// a row every cycle), CACTI 7, 32 nm, 8 KiB, 32-byte rows (docs/energy.md).
enum class ZebDevice { Lop, Lstp, Hp };

// Per-event dynamic energy (pJ) and leakage (mW); 32 nm, 1 V (docs/energy.md).
struct EnergyConfig {
    ZebDevice zeb_device = ZebDevice::Lop;
    double comparator_pj_per_bit = 0.0015;     // one magnitude comparator bit
    double mux_pj_per_bit = 0.0020;            // one element bit moved by a mux
    double stack_pj_per_bit = 0.0020;          // FF-stack flop written
    double id_compare_pj_per_bit = 0.0010;     // equality comparator bit
    double queue_pj_per_bit = 0.0020;          // input queue entry written
    double buffer_pj_per_bit = 0.0020;         // output buffer entry written
    double memory_pj_per_byte = 40.0;          // LPDDR access incl. I/O
    double logic_leakage_mw = 0.10;            // sorter + tester + buffers
    // The GPU around the unit, for normalized energy (paper, Figure 9b).
    double gpu_fragment_pj = 300.0;            // one fragment shaded
    double gpu_raster_fragment_pj = 8.0;       // one fragment rasterized and depth-tested
    double gpu_primitive_pj = 60.0;            // one primitive set up for a tile
    double gpu_tile_cache_pj_per_byte = 0.5;   // tile-cache (polygon list) read
    unsigned gpu_primitive_bytes = 64;         // bytes of one primitive read from the tile cache
    unsigned gpu_tile_flush_bytes = 1024;      // colour buffer written to memory per tile
    double gpu_static_mw = 60.0;               // GPU leakage over the frame's time
};

// Bounds on what the readers accept, so that a small hostile input cannot make
// the program allocate without limit (docs/limits.md). Defaults lie far above
// anything a real GPU trace or scene needs.
struct InputConfig {
    std::uint64_t max_line_bytes = std::uint64_t(1) << 20;           // trace line, after gzip inflation
    std::uint64_t max_tile_fragments = std::uint64_t(1) << 24;       // collisionable fragments of one tile
    std::uint64_t max_scene_bytes = std::uint64_t(64) << 20;         // scene file size
    std::uint64_t max_scene_triangles = std::uint64_t(1) << 22;      // triangles of all objects of a scene
};

// --vcd: which blocks are traced and the window, in cycles.
struct TraceConfig {
    bool feed = true, zeb = true, sorter = true, tester = true, output = true, memory = true;
    std::uint64_t start = 0;
    std::uint64_t end = std::uint64_t(1) << 62;
};

struct SimConfig {
    ClockConfig clock;
    TileConfig tile;
    ZebConfig zeb;
    FeedConfig feed;
    SorterConfig sorter;
    TesterConfig tester;
    OutputBufferConfig output;
    MemoryConfig memory;
    HostConfig host;
    GpuConfig gpu;
    EnergyConfig energy;
    TraceConfig trace;
    InputConfig input;

    // The longest run, in cycles, whose simulated time (cycles x clock period in
    // ps) stays below 2^62 ps: a quarter of sc_time's 64-bit range, so that
    // timing arithmetic inside a run cannot overflow. Readers refuse input whose
    // work bound exceeds it (docs/limits.md).
    std::uint64_t max_run_cycles() const;

    // Every key's range (the registry's, as when the key is read from TOML or
    // --set, so fields set in C++ meet the same rules and messages), then the
    // cross-key checks: alignment, the memory map within 64 bits, the output
    // regions inside the memory. Throws InputError "config: KEY: what".
    void validate() const;
};

struct ConfigKey {
    std::string name;      // "zeb.list_length"
    std::string block;     // which block reads it
    std::string unit;      // "cycles", "elements", "" ...
    std::string help;
    std::string type;      // "integer", "float", "string", "boolean"
    std::function<void(SimConfig&, const toml::node&, const std::string& where)> set;
    std::function<std::string(const SimConfig&)> to_toml;   // value as TOML text
    // Why the value `cfg` holds is refused ("out of range 1..16, got 0"), or ""
    // when it is accepted: the same rule and text as `set` applies to TOML.
    std::function<std::string(const SimConfig&)> check;
};

const std::vector<ConfigKey>& config_keys();

// Every key of `tbl` must be known; `file` names the source in messages.
void apply_config_table(SimConfig& cfg, const toml::table& tbl, const std::string& file);
void apply_config_file(SimConfig& cfg, const std::string& path);
// KEY=VALUE where VALUE is TOML; a bare word is taken as a string for string keys.
void apply_config_set(SimConfig& cfg, const std::string& assignment);
std::string dump_config_toml(const SimConfig& cfg);
// docs/config.md's key table (every key: name, default, unit, block, meaning).
std::string config_reference_markdown();

const char* to_string(TiePolicy);
const char* to_string(OutputMode);
const char* to_string(HazardPolicy);
const char* to_string(BankWait);
const char* to_string(ZebDevice);

} // namespace rbcd
