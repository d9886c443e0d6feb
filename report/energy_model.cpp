#include "rbcd/report/energy_model.h"

#include <cmath>

#include "rbcd/common/records.h"
#include "rbcd/hw/insertion_sorter.h"
#include "rbcd/hw/rbcd_system.h"

namespace rbcd {

namespace {

unsigned ceil_log2(std::uint64_t n) {
    unsigned b = 0;
    while ((std::uint64_t(1) << b) < n) ++b;
    return b;
}

} // namespace

ZebSramFigures zeb_sram_figures(ZebDevice d) {
    // CACTI 7, 32 nm, 8 KiB, 32-byte rows, 1R1W (docs/energy.md).
    switch (d) {
    case ZebDevice::Lop: return {3.46, 6.70, 1.20};
    case ZebDevice::Lstp: return {8.43, 18.83, 0.0024};
    case ZebDevice::Hp: return {6.46, 14.70, 3.38};
    }
    return {0, 0, 0};
}

EnergyCosts energy_costs(const SimConfig& cfg) {
    const EnergyConfig& e = cfg.energy;
    EnergyCosts k;
    const unsigned width = cfg.zeb.layout().width();
    const std::uint64_t lists = cfg.tile.pixels();
    k.banks = cfg.zeb.banks;
    k.row_bits = cfg.zeb.list_length * width;
    k.bank_bits = lists * k.row_bits;
    // The figures are for the reference macro; an access scales with the row's
    // width and (bit lines, decoders) with the square root of the array size.
    const ZebSramFigures z = zeb_sram_figures(e.zeb_device);
    k.sram_scale = double(k.row_bits) / 256.0 * std::sqrt(double(k.bank_bits) / 65536.0);
    k.row_read_pj = z.read_pj * k.sram_scale;
    k.row_write_pj = z.write_pj * k.sram_scale;
    k.queue_entry_bits = ceil_log2(lists) + width;
    k.queue_write_pj = e.queue_pj_per_bit * k.queue_entry_bits;
    k.key_bits = cfg.zeb.z_bits + (cfg.zeb.tie == TiePolicy::FrontFirst ? 1 : 0);
    k.comparator_pj = e.comparator_pj_per_bit * k.key_bits;
    k.mux_element_pj = e.mux_pj_per_bit * width;
    k.stack_push_pj = e.stack_pj_per_bit * (cfg.zeb.id_bits + 1);
    k.stack_match_pj = e.stack_pj_per_bit * 1;
    k.id_compare_pj = e.id_compare_pj_per_bit * cfg.zeb.id_bits;
    k.buffer_record_pj = e.buffer_pj_per_bit * (kRecordBytes * 8);
    k.memory_byte_pj = e.memory_pj_per_byte;

    k.bank_leakage_mw = z.leakage_mw * double(k.bank_bits) / 65536.0;
    // The logic's leakage, split by the storage each block holds.
    k.queue_bits = std::uint64_t(cfg.feed.queue_depth) * k.queue_entry_bits;
    k.sorter_bits = std::uint64_t(insertion_sorter::kStages) * k.row_bits;
    k.tester_bits = std::uint64_t(cfg.tester.stack_depth) * (cfg.zeb.id_bits + 1) + k.row_bits;
    k.buffer_bits = std::uint64_t(cfg.output.buffer_records) * kRecordBytes * 8;
    const double all = double(k.queue_bits + k.sorter_bits + k.tester_bits + k.buffer_bits);
    k.queue_leakage_mw = e.logic_leakage_mw * double(k.queue_bits) / all;
    k.sorter_leakage_mw = e.logic_leakage_mw * double(k.sorter_bits) / all;
    k.tester_leakage_mw = e.logic_leakage_mw * double(k.tester_bits) / all;
    k.buffer_leakage_mw = e.logic_leakage_mw * double(k.buffer_bits) / all;
    k.period_ns = double(cfg.clock.period_ps()) / 1000.0;
    k.gpu_fragment_pj = e.gpu_fragment_pj;
    k.gpu_raster_fragment_pj = e.gpu_raster_fragment_pj;
    k.gpu_primitive_pj = e.gpu_primitive_pj + double(e.gpu_primitive_bytes) * e.gpu_tile_cache_pj_per_byte;
    k.gpu_tile_flush_pj = double(e.gpu_tile_flush_bytes) * e.memory_pj_per_byte;
    k.gpu_static_mw = e.gpu_static_mw;
    return k;
}

Activity Activity::operator-(const Activity& o) const {
    Activity d;
    d.queue_writes = queue_writes - o.queue_writes;
    d.comparator_activations = comparator_activations - o.comparator_activations;
    d.mux_moves = mux_moves - o.mux_moves;
    d.sorter_row_reads = sorter_row_reads - o.sorter_row_reads;
    d.row_writes = row_writes - o.row_writes;
    d.tester_row_reads = tester_row_reads - o.tester_row_reads;
    d.stack_pushes = stack_pushes - o.stack_pushes;
    d.stack_matches = stack_matches - o.stack_matches;
    d.id_compares = id_compares - o.id_compares;
    d.buffer_records = buffer_records - o.buffer_records;
    d.memory_bytes = memory_bytes - o.memory_bytes;
    return d;
}

Activity activity_of(const UnitCounters& c) {
    Activity a;
    const auto& so = c.sorter;
    const auto& te = c.tester;
    a.queue_writes = c.queue.writes;
    a.comparator_activations = so.comparator_activations;
    a.mux_moves = so.mux_shifts + (so.insertions - so.dropped_new);
    a.sorter_row_reads = so.insertions;   // the READ stage fires once per insertion
    for (const auto& [name, b] : c.banks) {
        a.row_writes += b.row_writes;
        a.bank_reads.push_back(b.row_reads);
        a.bank_writes.push_back(b.row_writes);
    }
    a.tester_row_reads = te.lists;
    a.stack_pushes = te.pushes;
    a.stack_matches = te.matches;
    a.id_compares = te.id_compares;
    a.buffer_records = c.outbuf.records;
    a.memory_bytes = c.memory.bytes_written + c.memory.bytes_read;
    return a;
}

Activity activity_of(const rbcd_system& sys) { return activity_of(UnitCounters::of(sys)); }

const BlockEnergy* EnergyReport::find(const std::string& name) const {
    for (const auto& b : blocks)
        if (b.name == name) return &b;
    return nullptr;
}

EnergyReport energy_of(const EnergyCosts& k, const Activity& a, std::uint64_t cycles) {
    EnergyReport r;
    const double ns = double(cycles) * k.period_ns;   // mW x ns = pJ
    r.blocks.push_back({"input_queue", double(a.queue_writes) * k.queue_write_pj, k.queue_leakage_mw * ns});
    if (!a.bank_reads.empty()) {
        for (std::size_t i = 0; i < a.bank_reads.size(); ++i)
            r.blocks.push_back({"zeb_bank" + std::to_string(i),
                                double(a.bank_reads[i]) * k.row_read_pj + double(a.bank_writes[i]) * k.row_write_pj,
                                k.bank_leakage_mw * ns});
    } else {
        r.blocks.push_back({"zeb",
                            double(a.sorter_row_reads + a.tester_row_reads) * k.row_read_pj +
                                double(a.row_writes) * k.row_write_pj,
                            k.bank_leakage_mw * k.banks * ns});
    }
    r.blocks.push_back({"insertion_sorter",
                        double(a.comparator_activations) * k.comparator_pj + double(a.mux_moves) * k.mux_element_pj,
                        k.sorter_leakage_mw * ns});
    r.blocks.push_back({"zoverlap_tester",
                        double(a.stack_pushes) * k.stack_push_pj + double(a.stack_matches) * k.stack_match_pj +
                            double(a.id_compares) * k.id_compare_pj,
                        k.tester_leakage_mw * ns});
    r.blocks.push_back({"output_buffer", double(a.buffer_records) * k.buffer_record_pj, k.buffer_leakage_mw * ns});
    r.blocks.push_back({"memory", double(a.memory_bytes) * k.memory_byte_pj, 0.0});
    for (const auto& b : r.blocks) {
        r.dynamic_pj += b.dynamic_pj;
        r.leakage_pj += b.leakage_pj;
    }
    return r;
}

double gpu_energy_pj(const EnergyCosts& k, const GpuWork& w, std::uint64_t cycles) {
    return double(w.shaded) * k.gpu_fragment_pj + double(w.rasterized) * k.gpu_raster_fragment_pj +
           double(w.primitives) * k.gpu_primitive_pj + double(w.tiles) * k.gpu_tile_flush_pj +
           k.gpu_static_mw * double(cycles) * k.period_ns;
}

} // namespace rbcd
