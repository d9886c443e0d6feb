#include "rbcd/common/config.h"

#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <toml++/toml.h>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/common/records.h"

namespace rbcd {

std::uint64_t ClockConfig::period_ps() const {
    return static_cast<std::uint64_t>(std::llround(1e6 / mhz));
}

const char* to_string(TiePolicy t) { return t == TiePolicy::FrontFirst ? "front_first" : "arrival"; }
const char* to_string(OutputMode m) {
    switch (m) {
    case OutputMode::Raw: return "raw";
    case OutputMode::Pixel: return "pixel";
    case OutputMode::Tile: return "tile";
    }
    return "?";
}
const char* to_string(HazardPolicy h) { return h == HazardPolicy::Forward ? "forward" : "stall"; }
const char* to_string(BankWait b) { return b == BankWait::Tile ? "tile" : "unit"; }
const char* to_string(ZebDevice z) {
    switch (z) {
    case ZebDevice::Lop: return "lop";
    case ZebDevice::Lstp: return "lstp";
    case ZebDevice::Hp: return "hp";
    }
    return "?";
}

namespace {

std::string where_of(const std::string& where, const toml::node& n) {
    const auto& src = n.source();
    if (src.begin.line != 0 && src.path && !src.path->empty())
        return *src.path + ":" + std::to_string(src.begin.line);
    if (src.begin.line != 0 && !where.empty() && where.rfind("--set", 0) != 0)
        return where + ":" + std::to_string(src.begin.line);
    return where;
}

[[noreturn]] void fail(const std::string& where, const toml::node& n, const std::string& key, const std::string& what) {
    throw InputError(where_of(where, n) + ": " + key + ": " + what);
}

std::string out_of_range(std::uint64_t lo, std::uint64_t hi, const std::string& got) {
    return "out of range " + std::to_string(lo) + ".." + std::to_string(hi) + ", got " + got;
}

std::string out_of_range(double lo, double hi, double got) {
    std::ostringstream os;
    os << "out of range " << lo << ".." << hi << ", got " << got;
    return os.str();
}

template <class T, class Get>
ConfigKey int_key(std::string name, std::string block, std::string unit, std::string help,
                  std::uint64_t lo, std::uint64_t hi, Get get) {
    ConfigKey k;
    k.name = name; k.block = std::move(block); k.unit = std::move(unit); k.help = std::move(help);
    k.type = "integer";
    k.set = [name, lo, hi, get](SimConfig& c, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<std::int64_t>();
        if (!n.is_integer() || !v) fail(where, n, name, "expected an integer");
        if (*v < 0 || static_cast<std::uint64_t>(*v) < lo || static_cast<std::uint64_t>(*v) > hi)
            fail(where, n, name, out_of_range(lo, hi, std::to_string(*v)));
        get(c) = static_cast<T>(*v);
    };
    k.to_toml = [get](const SimConfig& c) { return std::to_string(get(const_cast<SimConfig&>(c))); };
    k.check = [lo, hi, get](const SimConfig& c) {
        const std::uint64_t v = get(const_cast<SimConfig&>(c));
        return v < lo || v > hi ? out_of_range(lo, hi, std::to_string(v)) : std::string();
    };
    return k;
}

template <class Get>
ConfigKey real_key(std::string name, std::string block, std::string unit, std::string help,
                   double lo, double hi, Get get) {
    ConfigKey k;
    k.name = name; k.block = std::move(block); k.unit = std::move(unit); k.help = std::move(help);
    k.type = "float";
    k.set = [name, lo, hi, get](SimConfig& c, const toml::node& n, const std::string& where) {
        if (!n.is_number()) fail(where, n, name, "expected a number");
        double v = n.is_integer() ? static_cast<double>(*n.value<std::int64_t>()) : *n.value<double>();
        if (!(v >= lo && v <= hi)) fail(where, n, name, out_of_range(lo, hi, v));
        get(c) = v;
    };
    k.check = [lo, hi, get](const SimConfig& c) {
        const double v = get(const_cast<SimConfig&>(c));
        return v >= lo && v <= hi ? std::string() : out_of_range(lo, hi, v);   // NaN too
    };
    k.to_toml = [get](const SimConfig& c) {
        // The shortest decimal that reads back as the same double (0.025, not
        // 0.025000000000000001).
        char buf[32];
        const auto r = std::to_chars(buf, buf + sizeof buf, get(const_cast<SimConfig&>(c)));
        std::string s(buf, r.ptr);
        if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
        return s;
    };
    return k;
}

template <class E, class Get>
ConfigKey enum_key(std::string name, std::string block, std::string help,
                   std::vector<std::pair<std::string, E>> choices, Get get) {
    ConfigKey k;
    std::string list;
    for (auto& ch : choices) list += (list.empty() ? "" : " | ") + ch.first;
    k.name = name; k.block = std::move(block); k.unit = list; k.help = std::move(help);
    k.type = "string";
    k.set = [name, choices, list, get](SimConfig& c, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<std::string>();
        if (!v) fail(where, n, name, "expected a string (" + list + ")");
        for (auto& ch : choices)
            if (ch.first == *v) { get(c) = ch.second; return; }
        fail(where, n, name, "unknown value \"" + *v + "\", expected " + list);
    };
    k.to_toml = [choices, get](const SimConfig& c) {
        for (auto& ch : choices)
            if (ch.second == get(const_cast<SimConfig&>(c))) return "\"" + ch.first + "\"";
        return std::string("\"?\"");
    };
    k.check = [choices, list, get](const SimConfig& c) {
        const E v = get(const_cast<SimConfig&>(c));
        for (auto& ch : choices)
            if (ch.second == v) return std::string();
        return "unknown value " + std::to_string(static_cast<long long>(v)) + ", expected " + list;
    };
    return k;
}

ConfigKey bool_key(std::string name, std::string block, std::string help, std::function<bool&(SimConfig&)> get) {
    ConfigKey k;
    k.name = name; k.block = std::move(block); k.unit = "true | false"; k.help = std::move(help);
    k.type = "boolean";
    k.set = [name, get](SimConfig& c, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<bool>();
        if (!v) fail(where, n, name, "expected true or false");
        get(c) = *v;
    };
    k.to_toml = [get](const SimConfig& c) { return std::string(get(const_cast<SimConfig&>(c)) ? "true" : "false"); };
    k.check = [](const SimConfig&) { return std::string(); };
    return k;
}

std::vector<ConfigKey> make_keys() {
    constexpr std::uint64_t big = std::uint64_t(1) << 40;
    std::vector<ConfigKey> k;
    k.push_back(real_key("clock.mhz", "all", "MHz", "unit clock; cycles convert to time with an integer ps period",
                         1.0, 10000.0, [](SimConfig& c) -> double& { return c.clock.mhz; }));
    k.push_back(int_key<unsigned>("tile.width", "zeb_bank", "pixels", "tile width", 1, 256,
                                  [](SimConfig& c) -> unsigned& { return c.tile.width; }));
    k.push_back(int_key<unsigned>("tile.height", "zeb_bank", "pixels", "tile height", 1, 256,
                                  [](SimConfig& c) -> unsigned& { return c.tile.height; }));
    k.push_back(int_key<unsigned>("zeb.banks", "zeb_bank", "banks", "ZEB banks: tiles filled while earlier ones are tested",
                                  1, 16, [](SimConfig& c) -> unsigned& { return c.zeb.banks; }));
    k.push_back(int_key<unsigned>("zeb.list_length", "zeb_bank", "elements", "M, elements per pixel list", 1, 64,
                                  [](SimConfig& c) -> unsigned& { return c.zeb.list_length; }));
    k.push_back(int_key<unsigned>("zeb.z_bits", "zeb_bank", "bits", "quantized depth bits of an element", 1, 32,
                                  [](SimConfig& c) -> unsigned& { return c.zeb.z_bits; }));
    k.push_back(int_key<unsigned>("zeb.id_bits", "zeb_bank", "bits", "object id bits of an element", 1, 16,
                                  [](SimConfig& c) -> unsigned& { return c.zeb.id_bits; }));
    k.push_back(enum_key<TiePolicy>("zeb.tie", "insertion_sorter",
                                    "sort key: (dq, facing) or dq alone (the paper's less-than comparators)",
                                    {{"front_first", TiePolicy::FrontFirst}, {"arrival", TiePolicy::Arrival}},
                                    [](SimConfig& c) -> TiePolicy& { return c.zeb.tie; }));
    k.push_back(int_key<unsigned>("feed.fragments_per_cycle", "rasterizer", "fragments/cycle",
                                  "rasterizer output rate", 1, 64,
                                  [](SimConfig& c) -> unsigned& { return c.feed.fragments_per_cycle; }));
    k.push_back(int_key<unsigned>("feed.queue_depth", "input_queue", "fragments",
                                  "the unit's input queue between rasterizer and sorter", 1, 65536,
                                  [](SimConfig& c) -> unsigned& { return c.feed.queue_depth; }));
    k.push_back(enum_key<HazardPolicy>("sorter.hazard", "insertion_sorter",
                                       "same-pixel read-after-write in the sorter pipeline: forward the merged list, or stall until written",
                                       {{"forward", HazardPolicy::Forward}, {"stall", HazardPolicy::Stall}},
                                       [](SimConfig& c) -> HazardPolicy& { return c.sorter.hazard; }));
    k.push_back(int_key<unsigned>("tester.stack_depth", "zoverlap_tester", "entries", "T, FF-stack entries", 1, 64,
                                  [](SimConfig& c) -> unsigned& { return c.tester.stack_depth; }));
    k.push_back(enum_key<OutputMode>("tester.output", "zoverlap_tester", "which hits are written",
                                     {{"raw", OutputMode::Raw}, {"pixel", OutputMode::Pixel}, {"tile", OutputMode::Tile}},
                                     [](SimConfig& c) -> OutputMode& { return c.tester.output; }));
    k.push_back(int_key<unsigned>("output.buffer_records", "output_buffer", "records",
                                  "output buffer capacity (16-byte records); the tester stalls when full", 1, 65536,
                                  [](SimConfig& c) -> unsigned& { return c.output.buffer_records; }));
    k.push_back(int_key<unsigned>("output.burst_records", "output_buffer", "records", "records per memory write burst",
                                  1, 4096, [](SimConfig& c) -> unsigned& { return c.output.burst_records; }));
    k.push_back(int_key<unsigned>("output.max_outstanding", "output_buffer", "transactions",
                                  "memory writes in flight at once", 1, 256,
                                  [](SimConfig& c) -> unsigned& { return c.output.max_outstanding; }));
    k.push_back(int_key<std::uint64_t>("output.region_offset", "output_buffer", "bytes",
                                       "start of the output region inside the memory", 0, big,
                                       [](SimConfig& c) -> std::uint64_t& { return c.output.region_offset; }));
    k.push_back(int_key<std::uint64_t>("output.region_bytes", "output_buffer", "bytes",
                                       "size of an output region; when full the unit waits for the CPU to read it",
                                       16, big, [](SimConfig& c) -> std::uint64_t& { return c.output.region_bytes; }));
    k.push_back(bool_key("output.double_buffer", "output_buffer",
                         "two output regions: the unit writes one while the host reads the other back",
                         [](SimConfig& c) -> bool& { return c.output.double_buffer; }));
    k.push_back(int_key<std::uint64_t>("memory.base", "memory_controller", "address", "first address of the memory",
                                       0, big, [](SimConfig& c) -> std::uint64_t& { return c.memory.base; }));
    k.push_back(int_key<std::uint64_t>("memory.size_bytes", "memory_controller", "bytes", "size of the memory model",
                                       16, std::uint64_t(1) << 32,
                                       [](SimConfig& c) -> std::uint64_t& { return c.memory.size_bytes; }));
    k.push_back(int_key<unsigned>("memory.latency_min", "memory_controller", "cycles", "shortest access latency",
                                  0, 1000000, [](SimConfig& c) -> unsigned& { return c.memory.latency_min; }));
    k.push_back(int_key<unsigned>("memory.latency_max", "memory_controller", "cycles", "longest access latency",
                                  0, 1000000, [](SimConfig& c) -> unsigned& { return c.memory.latency_max; }));
    k.push_back(int_key<unsigned>("memory.bytes_per_cycle", "memory_controller", "bytes/cycle", "channel bandwidth",
                                  1, 4096, [](SimConfig& c) -> unsigned& { return c.memory.bytes_per_cycle; }));
    k.push_back(int_key<std::uint64_t>("memory.seed", "memory_controller", "", "seed of the latency draw", 0,
                                       std::uint64_t(std::numeric_limits<std::int64_t>::max()),
                                       [](SimConfig& c) -> std::uint64_t& { return c.memory.seed; }));
    k.push_back(int_key<std::uint64_t>("host.readback_cycles", "host", "cycles",
                                       "the unit's output waits this long while the CPU reads the region back", 0, big,
                                       [](SimConfig& c) -> std::uint64_t& { return c.host.readback_cycles; }));

    k.push_back(int_key<unsigned>("gpu.setup_cycles_per_primitive", "rasterizer", "cycles",
                                  "rasterizer cycles to set up one primitive of a tile (prims=, cprims=)", 0, 1000000,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.setup_cycles_per_primitive; }));
    k.push_back(int_key<unsigned>("gpu.tile_overhead_cycles", "rasterizer", "cycles",
                                  "rasterizer cycles at the start of every tile", 0, 1000000,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.tile_overhead_cycles; }));
    k.push_back(int_key<unsigned>("gpu.fragment_queue_depth", "fragment_processors", "fragments",
                                  "fragment queue between rasterizer and early-Z (paper, Table 2)", 1, 65536,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.fragment_queue_depth; }));
    k.push_back(int_key<unsigned>("gpu.early_z_cycles", "fragment_processors", "cycles",
                                  "early-Z latency from the queue to a fragment processor", 0, 1000,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.early_z_cycles; }));
    k.push_back(int_key<unsigned>("gpu.fragment_processors", "fragment_processors", "processors",
                                  "fragment processors", 1, 256,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.fragment_processors; }));
    k.push_back(int_key<unsigned>("gpu.cycles_per_fragment", "fragment_processors", "cycles",
                                  "cycles one fragment processor spends per fragment", 1, 100000,
                                  [](SimConfig& c) -> unsigned& { return c.gpu.cycles_per_fragment; }));
    k.push_back(enum_key<BankWait>("gpu.bank_wait", "rasterizer",
                                   "what waits for a free ZEB bank: the whole tile at the tile scheduler, or only "
                                   "the unit's input",
                                   {{"tile", BankWait::Tile}, {"unit", BankWait::Unit}},
                                   [](SimConfig& c) -> BankWait& { return c.gpu.bank_wait; }));

    auto energy = [&](const char* name, const char* unit, const char* help, double EnergyConfig::*m) {
        k.push_back(real_key(std::string("energy.") + name, "energy_model", unit, help, 0.0, 1e9,
                             [m](SimConfig& c) -> double& { return c.energy.*m; }));
    };
    k.push_back(enum_key<ZebDevice>("energy.zeb_device", "energy_model",
                                    "ZEB bank SRAM device type, 1R1W macro (CACTI 7, 32 nm, 8 KiB, 32-byte rows): "
                                    "low operating power, low standby power, high performance",
                                    {{"lop", ZebDevice::Lop}, {"lstp", ZebDevice::Lstp}, {"hp", ZebDevice::Hp}},
                                    [](SimConfig& c) -> ZebDevice& { return c.energy.zeb_device; }));
    energy("comparator_pj_per_bit", "pJ/bit", "sorter key comparator, per key bit",
           &EnergyConfig::comparator_pj_per_bit);
    energy("mux_pj_per_bit", "pJ/bit", "sorter mux moving one element bit", &EnergyConfig::mux_pj_per_bit);
    energy("stack_pj_per_bit", "pJ/bit", "FF-stack entry bit written", &EnergyConfig::stack_pj_per_bit);
    energy("id_compare_pj_per_bit", "pJ/bit", "tester id equality comparator, per id bit",
           &EnergyConfig::id_compare_pj_per_bit);
    energy("queue_pj_per_bit", "pJ/bit", "input queue entry bit written", &EnergyConfig::queue_pj_per_bit);
    energy("buffer_pj_per_bit", "pJ/bit", "output buffer record bit written", &EnergyConfig::buffer_pj_per_bit);
    energy("memory_pj_per_byte", "pJ/byte", "system memory access through the controller",
           &EnergyConfig::memory_pj_per_byte);
    energy("logic_leakage_mw", "mW", "leakage of the unit's logic (sorter, tester, queue, buffer)",
           &EnergyConfig::logic_leakage_mw);
    energy("gpu_fragment_pj", "pJ", "GPU: one fragment shaded by a fragment processor", &EnergyConfig::gpu_fragment_pj);
    energy("gpu_raster_fragment_pj", "pJ", "GPU: one fragment rasterized and early-Z tested",
           &EnergyConfig::gpu_raster_fragment_pj);
    energy("gpu_primitive_pj", "pJ", "GPU: one primitive set up for a tile", &EnergyConfig::gpu_primitive_pj);
    energy("gpu_tile_cache_pj_per_byte", "pJ/byte", "GPU: tile-cache read of the primitive lists",
           &EnergyConfig::gpu_tile_cache_pj_per_byte);
    energy("gpu_static_mw", "mW", "GPU leakage, charged over each frame's time", &EnergyConfig::gpu_static_mw);
    k.push_back(int_key<unsigned>("energy.gpu_primitive_bytes", "energy_model", "bytes",
                                  "GPU: bytes of one primitive read from the tile cache", 0, 1 << 20,
                                  [](SimConfig& c) -> unsigned& { return c.energy.gpu_primitive_bytes; }));
    k.push_back(int_key<unsigned>("energy.gpu_tile_flush_bytes", "energy_model", "bytes",
                                  "GPU: colour buffer bytes written to memory per tile", 0, 1 << 24,
                                  [](SimConfig& c) -> unsigned& { return c.energy.gpu_tile_flush_bytes; }));

    k.push_back(bool_key("trace.feed", "vcd", "trace the rasterizer and fragment processors in --vcd",
                         [](SimConfig& c) -> bool& { return c.trace.feed; }));
    k.push_back(bool_key("trace.zeb", "vcd", "trace the ZEB banks in --vcd", [](SimConfig& c) -> bool& { return c.trace.zeb; }));
    k.push_back(bool_key("trace.sorter", "vcd", "trace the insertion sorter and input queue in --vcd",
                         [](SimConfig& c) -> bool& { return c.trace.sorter; }));
    k.push_back(bool_key("trace.tester", "vcd", "trace the z-overlap tester in --vcd",
                         [](SimConfig& c) -> bool& { return c.trace.tester; }));
    k.push_back(bool_key("trace.output", "vcd", "trace the output buffer in --vcd",
                         [](SimConfig& c) -> bool& { return c.trace.output; }));
    k.push_back(bool_key("trace.memory", "vcd", "trace the memory controller in --vcd",
                         [](SimConfig& c) -> bool& { return c.trace.memory; }));
    k.push_back(int_key<std::uint64_t>("trace.start", "vcd", "cycles", "first cycle dumped to --vcd", 0,
                                       std::uint64_t(1) << 62,
                                       [](SimConfig& c) -> std::uint64_t& { return c.trace.start; }));
    k.push_back(int_key<std::uint64_t>("trace.end", "vcd", "cycles", "last cycle dumped to --vcd", 0,
                                       std::uint64_t(1) << 62,
                                       [](SimConfig& c) -> std::uint64_t& { return c.trace.end; }));

    k.push_back(int_key<std::uint64_t>("input.max_line_bytes", "readers", "bytes",
                                       "longest line of a trace (after gzip inflation)", 64, big,
                                       [](SimConfig& c) -> std::uint64_t& { return c.input.max_line_bytes; }));
    k.push_back(int_key<std::uint64_t>("input.max_tile_fragments", "readers", "fragments",
                                       "most collisionable fragments in one tile of a trace or scene", 1, big,
                                       [](SimConfig& c) -> std::uint64_t& { return c.input.max_tile_fragments; }));
    k.push_back(int_key<std::uint64_t>("input.max_scene_bytes", "readers", "bytes", "largest scene file", 64, big,
                                       [](SimConfig& c) -> std::uint64_t& { return c.input.max_scene_bytes; }));
    k.push_back(int_key<std::uint64_t>("input.max_scene_triangles", "readers", "triangles",
                                       "most triangles over all objects of a scene (memory per frame grows with them)",
                                       1, big, [](SimConfig& c) -> std::uint64_t& { return c.input.max_scene_triangles; }));
    return k;
}

const ConfigKey* find_key(const std::string& name) {
    for (const auto& k : config_keys())
        if (k.name == name) return &k;
    return nullptr;
}

void apply_table(SimConfig& cfg, const toml::table& tbl, const std::string& prefix, const std::string& file) {
    for (const auto& [key, node] : tbl) {
        std::string name = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
        if (const auto* sub = node.as_table()) {
            apply_table(cfg, *sub, name, file);
            continue;
        }
        const ConfigKey* k = find_key(name);
        if (!k) fail(file, node, name, "unknown configuration key");
        k->set(cfg, node, file);
    }
}

} // namespace

const std::vector<ConfigKey>& config_keys() {
    static const std::vector<ConfigKey> keys = make_keys();
    return keys;
}

std::uint64_t SimConfig::max_run_cycles() const {
    const std::uint64_t p = clock.period_ps();
    return p ? (std::uint64_t(1) << 62) / p : 0;
}

void SimConfig::validate() const {
    auto bad = [](const std::string& key, const std::string& what) { throw InputError("config: " + key + ": " + what); };
    for (const auto& k : config_keys()) {
        const std::string why = k.check(*this);
        if (!why.empty()) bad(k.name, why);
    }
    if (zeb.z_bits + zeb.id_bits + 1 > 49) bad("zeb.z_bits", "element wider than 49 bits");
    if (memory.latency_min > memory.latency_max)
        bad("memory.latency_min", "greater than memory.latency_max (" + std::to_string(memory.latency_max) + ")");
    if (output.burst_records > output.buffer_records)
        bad("output.burst_records", "greater than output.buffer_records (" + std::to_string(output.buffer_records) + ")");
    // Records land at 16-byte aligned addresses (docs/memory-layout.md), so every
    // burst starts on a 64-bit bus word and a record is naturally aligned, as a
    // host reading it with 128-bit loads expects.
    if (memory.base % kRecordBytes != 0) bad("memory.base", "not a multiple of the 16-byte record");
    if (output.region_offset % kRecordBytes != 0) bad("output.region_offset", "not a multiple of the 16-byte record");
    if (output.region_bytes % kRecordBytes != 0)
        bad("output.region_bytes", "not a multiple of the 16-byte record");
    if (output.region_bytes < std::uint64_t(output.burst_records) * kRecordBytes)
        bad("output.region_bytes", "smaller than one burst (output.burst_records x 16 bytes)");
    // Written so that no sum can wrap, whatever the ranges above allow.
    if (memory.size_bytes - 1 > ~std::uint64_t(0) - memory.base)
        bad("memory.base", "the memory [base, base + size_bytes) wraps past the end of the 64-bit address space");
    if (output.region_bytes > memory.size_bytes / output.regions() ||
        output.region_offset > memory.size_bytes - output.region_bytes * output.regions())
        bad("output.region_bytes", std::string(output.double_buffer ? "regions (offset + 2 x size)" : "region (offset + size)") +
                                       " do not fit in memory.size_bytes (" + std::to_string(memory.size_bytes) + ")");
    if (clock.period_ps() == 0) bad("clock.mhz", "period rounds to 0 ps");
    if (trace.start > trace.end) bad("trace.start", "after trace.end (" + std::to_string(trace.end) + ")");
}

void apply_config_table(SimConfig& cfg, const toml::table& tbl, const std::string& file) {
    apply_table(cfg, tbl, "", file);
}

// A configuration is a page of keys; this keeps a hostile one from filling memory.
constexpr std::uint64_t kMaxConfigBytes = std::uint64_t(1) << 20;

void apply_config_file(SimConfig& cfg, const std::string& path) {
    const std::string text = read_input_text(path, "configuration file", kMaxConfigBytes, "");
    check_toml_text(text, path);
    toml::table tbl;
    try {
        tbl = toml::parse(text, path);
    } catch (const toml::parse_error& e) {
        const auto& src = e.source();
        const std::string msg = escape_for_message(e.description());
        if (src.begin.line == 0) throw InputError(path + ": " + msg);
        throw InputError(path + ":" + std::to_string(src.begin.line) + ": " + msg);
    }
    apply_config_table(cfg, tbl, path);
}

void apply_config_set(SimConfig& cfg, const std::string& assignment) {
    auto eq = assignment.find('=');
    if (eq == std::string::npos || eq == 0)
        throw InputError("--set " + assignment + ": expected KEY=VALUE");
    std::string key = assignment.substr(0, eq);
    std::string value = assignment.substr(eq + 1);
    const ConfigKey* k = find_key(key);
    if (!k) throw InputError("--set " + key + ": unknown configuration key");
    const std::string where = "--set " + key;
    check_toml_text(value, where);
    toml::table tbl;
    try {
        tbl = toml::parse("v = " + value);
    } catch (const toml::parse_error&) {
        if (k->type != "string" || value.empty())
            throw InputError(where + ": cannot parse value \"" + value + "\" as " + k->type);
        toml::table t;
        t.insert("v", value);
        k->set(cfg, *t.get("v"), where);
        return;
    }
    if (tbl.size() != 1) throw InputError(where + ": cannot parse value \"" + value + "\"");
    k->set(cfg, *tbl.get("v"), where);
}

std::string dump_config_toml(const SimConfig& cfg) {
    std::string out;
    std::string section;
    for (const auto& k : config_keys()) {
        auto dot = k.name.find('.');
        std::string sec = k.name.substr(0, dot);
        if (sec != section) {
            out += (out.empty() ? "[" : "\n[") + sec + "]\n";
            section = sec;
        }
        out += k.name.substr(dot + 1) + " = " + k.to_toml(cfg) + "   # " + k.help +
               (k.unit.empty() ? "" : " [" + k.unit + "]") + "\n";
    }
    return out;
}

} // namespace rbcd

namespace rbcd {

std::string config_reference_markdown() {
    const SimConfig defaults;
    std::string out = "| key | default | unit / values | read by | meaning |\n|---|---|---|---|---|\n";
    for (const auto& k : config_keys())
        out += "| `" + k.name + "` | `" + k.to_toml(defaults) + "` | " + k.unit + " | " + k.block + " | " + k.help + " |\n";
    return out;
}

} // namespace rbcd
