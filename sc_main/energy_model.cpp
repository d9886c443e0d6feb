#include "sc_main/energy_model.h"

#include <cmath>

#include "common/records.h"
#include "hw/insertion_sorter.h"
#include "hw/rbcd_system.h"

namespace rbcd {

namespace {

unsigned ceil_log2(std::uint64_t n) {
    unsigned b = 0;
    while ((std::uint64_t(1) << b) < n) ++b;
    return b;
}

} // namespace

EnergyCosts energy_costs(const SimConfig& cfg) {
    const EnergyConfig& e = cfg.energy;
    EnergyCosts k;
    const unsigned width = cfg.zeb.layout().width();
    const std::uint64_t lists = cfg.tile.pixels();
    k.banks = cfg.zeb.banks;
    k.row_bits = cfg.zeb.list_length * width;
    k.bank_bits = lists * k.row_bits;
    k.sram_scale = std::sqrt(double(k.bank_bits) / 65536.0);
    k.row_read_pj = e.sram_read_pj_per_bit * k.row_bits * k.sram_scale;
    k.row_write_pj = e.sram_write_pj_per_bit * k.row_bits * k.sram_scale;
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

    k.bank_leakage_mw = e.sram_leakage_mw_per_kib * double(k.bank_bits) / 8192.0;
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

Activity activity_of(const rbcd_system& sys) {
    Activity a;
    const auto& so = sys.sorter.stats();
    const auto& te = sys.tester.stats();
    a.queue_writes = so.insertions;
    a.comparator_activations = so.comparator_activations;
    a.mux_moves = so.mux_shifts + (so.insertions - so.dropped_new);
    a.sorter_row_reads = so.insertions;   // the READ stage fires once per insertion
    for (const auto& b : sys.banks) {
        a.row_writes += b->stats().row_writes;
        a.bank_reads.push_back(b->stats().row_reads);
        a.bank_writes.push_back(b->stats().row_writes);
    }
    a.tester_row_reads = te.lists;
    a.stack_pushes = te.pushes;
    a.stack_matches = te.matches;
    a.id_compares = te.id_compares;
    a.buffer_records = sys.outbuf.stats().records;
    a.memory_bytes = sys.memory.stats().bytes_written + sys.memory.stats().bytes_read;
    return a;
}

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

FrameEnergyProbe::FrameEnergyProbe(const rbcd_system& sys) : sys_(sys) { sink_.probe = this; }

void FrameEnergyProbe::on_feed_frame(std::uint64_t) {
    // The k-th frame start ends feed frame k-1.
    if (feed_calls_++ > 0) {
        feed_snaps_.push_back(activity_of(sys_));
        feed_snaps_.back().bank_reads.clear();
        feed_snaps_.back().bank_writes.clear();
    }
}

void FrameEnergyProbe::on_unit_frame(std::uint64_t) {
    unit_seen_ = true;
    if (unit_calls_++ > 0) {
        unit_snaps_.push_back(activity_of(sys_));
        unit_snaps_.back().bank_reads.clear();
        unit_snaps_.back().bank_writes.clear();
    }
}

std::vector<Activity> FrameEnergyProbe::frames() const {
    const std::size_t n = sys_.feed.frames().size();
    Activity total = activity_of(sys_);
    total.bank_reads.clear();
    total.bank_writes.clear();
    auto cum = [&](const std::vector<Activity>& snaps, std::size_t i) -> const Activity& {
        return i < snaps.size() ? snaps[i] : total;
    };
    const std::vector<Activity>& unit = unit_seen_ ? unit_snaps_ : feed_snaps_;
    std::vector<Activity> out;
    Activity prev_feed, prev_unit;
    for (std::size_t i = 0; i < n; ++i) {
        const Activity& f = cum(feed_snaps_, i);
        const Activity& u = cum(unit, i);
        const Activity df = f - prev_feed, du = u - prev_unit;
        Activity a = df;   // feed side: queue, sorter, the sorter's row reads and writes
        a.tester_row_reads = du.tester_row_reads;
        a.stack_pushes = du.stack_pushes;
        a.stack_matches = du.stack_matches;
        a.id_compares = du.id_compares;
        a.buffer_records = du.buffer_records;
        a.memory_bytes = du.memory_bytes;
        out.push_back(a);
        prev_feed = f;
        prev_unit = u;
    }
    return out;
}

} // namespace rbcd
