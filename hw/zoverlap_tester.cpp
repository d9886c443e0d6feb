#include "rbcd/hw/zoverlap_tester.h"

#include <algorithm>

#include "rbcd/common/errors.h"
#include "rbcd/hw/self_check.h"

namespace rbcd {

zoverlap_tester::zoverlap_tester(sc_core::sc_module_name name, const SimConfig& cfg, const Clocking& clk,
                                 output_buffer& out, unit_host_if& host)
    : sc_module(name),
      clk_(clk),
      out_(out),
      host_(host),
      t_depth_(cfg.tester.stack_depth),
      tile_w_(cfg.tile.width),
      tile_h_(cfg.tile.height),
      id_shift_(cfg.zeb.id_bits + 1),
      id_mask_((1u << cfg.zeb.id_bits) - 1),
      mode_(cfg.tester.output),
      layout_(cfg.zeb.layout()),
      stack_id_(cfg.tester.stack_depth),
      stack_matched_(cfg.tester.stack_depth) {
    SC_THREAD(run);
}

void zoverlap_tester::attach_vcd(VcdWriter& vcd, const std::string& scope) {
    vcd_ = &vcd;
    vcd_busy_ = vcd.add(scope, "busy", 1);
    vcd_bank_ = vcd.add(scope, "bank", 4);
    vcd_frame_ = vcd.add(scope, "frame", 32);
    vcd_list_ = vcd.add(scope, "list", 16);
    vcd_stack_ = vcd.add(scope, "stack_depth", 7);
    vcd_hit_ = vcd.add(scope, "hit", 1);
    vcd_stall_ = vcd.add(scope, "output_stall", 1);
    vcd_readback_ = vcd.add(scope, "readback_wait", 1);
}

std::uint64_t zoverlap_tester::emit_hit(std::uint32_t x, std::uint32_t y, std::uint32_t id1, std::uint32_t id2,
                                        std::uint32_t dq, std::uint64_t t) {
    ++stats_.raw_hits;
    HitRecord h{x, y, std::min(id1, id2), std::max(id1, id2), dq};
    if (mode_ != OutputMode::Raw) {
        const std::uint32_t pair = (h.id_a << 16) | h.id_b;
        bool seen;
        if (mode_ == OutputMode::Pixel) {
            seen = std::find(pixel_pairs_.begin(), pixel_pairs_.end(), pair) != pixel_pairs_.end();
            if (!seen) pixel_pairs_.push_back(pair);
        } else {
            seen = !tile_pairs_.insert(pair).second;
        }
        if (seen) {
            ++stats_.filtered_hits;
            return t;
        }
    }
    ++stats_.hits;
    const std::uint64_t accepted = out_.push(MemRecord::hit(h), t);
    stats_.output_stall_cycles += accepted - t;
    if (vcd_) {
        if (accepted > t) {
            vcd_->set(vcd_stall_, t, 1);
            vcd_->set(vcd_stall_, accepted, 0);
        }
        vcd_->set(vcd_hit_, accepted, 1);
        vcd_->set(vcd_hit_, accepted + 1, 0);
    }
    return accepted;
}

std::uint64_t zoverlap_tester::test_tile(zeb_bank& bank, std::uint64_t t) {
    ++stats_.tiles;
    tile_pairs_.clear();
    const std::uint32_t x0 = bank.tile_col() * tile_w_, y0 = bank.tile_row() * tile_h_;
    const auto& occ = bank.occupancy();
    bool first_list = true;

    for (std::size_t wi = 0; wi < occ.size(); ++wi) {
        for (std::uint64_t bits = occ[wi]; bits; bits &= bits - 1) {
            const unsigned li = static_cast<unsigned>(wi * 64 + __builtin_ctzll(bits));
            const unsigned n = bank.count(li);
            const std::uint64_t* row = bank.list(li);
            bank.note_read();
            ++stats_.lists;
            if (first_list) {
                ++t;   // the first row read is not hidden behind a previous walk
                first_list = false;
            }
            const std::uint32_t x = x0 + li % tile_w_, y = y0 + li / tile_w_;
            unsigned sp = 0;
            if (vcd_) {
                vcd_->set(vcd_list_, t, li);
                vcd_->set(vcd_stack_, t, 0);
            }
            pixel_pairs_.clear();

            for (unsigned e = 0; e < n; ++e) {
                const std::uint64_t w = row[e];
                const std::uint32_t id = static_cast<std::uint32_t>(w >> 1) & id_mask_;
                ++stats_.elements;
                if ((w & 1u) == 0) {   // front face
                    if (sp == t_depth_) {
                        ++stats_.stack_overflows;
                    } else {
                        stack_id_[sp] = id;
                        stack_matched_[sp] = 0;
                        ++sp;
                        ++stats_.pushes;
                        if (vcd_) vcd_->set(vcd_stack_, t + 1, sp);
                    }
                    ++t;
                    continue;
                }
                // Back face: equality comparators on every entry, the lowest
                // unmatched match wins (priority encoder).
                stats_.id_compares += t_depth_;
                unsigned m = 0;
                while (m < sp && !(stack_id_[m] == id && !stack_matched_[m])) ++m;
                if (m == sp) {
                    ++stats_.orphan_back_faces;
                    ++t;
                    continue;
                }
                ++stats_.matches;
                const std::uint32_t dq = static_cast<std::uint32_t>(w >> id_shift_);
                unsigned emitted = 0;
                for (unsigned i = m + 1; i < sp; ++i) {
                    if (stack_id_[i] == id) continue;
                    t = emit_hit(x, y, stack_id_[i], id, dq, t) + 1;
                    ++emitted;
                }
                if (emitted == 0) ++t;
                stack_matched_[m] = 1;
            }
        }
    }

    return t;
}

TestedTile zoverlap_tester::tested_tile(zeb_bank& bank, std::uint64_t start, std::uint64_t end,
                                        const stats_t& before) const {
    TestedTile s;
    s.frame = bank.frame();
    s.col = bank.tile_col();
    s.row = bank.tile_row();
    s.bank = bank.index();
    s.start = start;
    s.end = end;
    s.lists = stats_.lists - before.lists;
    s.elements = stats_.elements - before.elements;
    const auto& occ = bank.occupancy();
    for (std::size_t wi = 0; wi < occ.size(); ++wi)
        for (std::uint64_t bits = occ[wi]; bits; bits &= bits - 1)
            s.max_list = std::max<std::uint64_t>(s.max_list, bank.count(static_cast<unsigned>(wi * 64 + __builtin_ctzll(bits))));
    s.hits = stats_.hits - before.hits;
    s.filtered_hits = stats_.filtered_hits - before.filtered_hits;
    s.stack_overflows = stats_.stack_overflows - before.stack_overflows;
    s.orphan_back_faces = stats_.orphan_back_faces - before.orphan_back_faces;
    s.lists_overflowed = bank.lists_overflowed();
    s.fragments_dropped = bank.fragments_dropped();
    return s;
}

void zoverlap_tester::lose_element(zeb_bank& bank) {
    const auto& occ = bank.occupancy();
    for (std::size_t wi = 0; wi < occ.size(); ++wi) {
        if (!occ[wi]) continue;
        --bank.count(static_cast<unsigned>(wi * 64 + __builtin_ctzll(occ[wi])));
        return;
    }
}

std::uint64_t zoverlap_tester::emit_overflow(const OverflowRecord& o, std::uint64_t t) {
    ++stats_.overflow_records;
    const std::uint64_t accepted = out_.push(MemRecord::overflow(o), t);
    stats_.output_stall_cycles += accepted - t;
    if (vcd_ && accepted > t) {
        vcd_->set(vcd_stall_, t, 1);
        vcd_->set(vcd_stall_, accepted, 0);
    }
    return accepted + 1;
}

void zoverlap_tester::run() {
    std::uint64_t t = 0;
    for (;;) {
        while (jobs_.empty()) {
            const std::uint64_t before = clk_.now();
            wait(job_posted_);
            stats_.idle_cycles += clk_.now() - before;
        }
        const Job job = jobs_.front();
        jobs_.pop_front();
        t = std::max(t, clk_.now());
        switch (job.kind) {
        case Job::FrameStart:
            host_.begin_frame(job.frame);
            break;
        case Job::TileJob: {
            if (job.ready > t) {
                stats_.idle_cycles += job.ready - t;
                t = job.ready;
            }
            clk_.wait_until(t);
            job.bank->begin_test(t);
            const std::uint64_t start = t;
            if (vcd_) {
                vcd_->set(vcd_busy_, t, 1);
                vcd_->set(vcd_bank_, t, job.bank->index());
                vcd_->set(vcd_frame_, t, job.bank->frame());
            }
            const bool observed = !observers_.empty();
            const stats_t before = observed ? stats_ : stats_t{};
            if (stats_.tiles == lose_tile_) lose_element(*job.bank);
            const std::uint64_t walked_before = stats_.elements;
            t = test_tile(*job.bank, t);
            // Fragment conservation per tile (hw/self_check.h): the elements
            // walked are what the bank stored. Two adds and a compare a tile.
            if (stats_.elements - walked_before + job.bank->fragments_dropped() != job.fragments)
                throw RunError(tile_conservation_failure(job.bank->frame(), job.bank->tile_col(), job.bank->tile_row(),
                                                         job.fragments, stats_.elements - walked_before,
                                                         job.bank->fragments_dropped()));
            // The overflow notice is taken from the bank's flags before it is
            // released: the bank is reusable once its last list has been read,
            // whatever the output buffer makes the notice wait for.
            const bool overflowed = job.bank->lists_overflowed() > 0;
            const OverflowRecord o{job.bank->tile_col(), job.bank->tile_row(), job.bank->lists_overflowed(),
                                   job.bank->fragments_dropped()};
            clk_.wait_until(t);
            TestedTile seen;
            if (observed) seen = tested_tile(*job.bank, start, t, before);
            job.bank->release(t);
            if (overflowed) t = emit_overflow(o, t);
            if (vcd_) vcd_->set(vcd_busy_, t, 0);
            stats_.busy_cycles += t - start;
            if (observed) {
                seen.done = t;
                seen.output_stall = stats_.output_stall_cycles - before.output_stall_cycles;
                for (auto* o : observers_) o->tile_tested(seen);
            }
            break;
        }
        case Job::FrameEnd: {
            const std::uint64_t flushed = out_.flush(t);
            t = out_.end_frame(flushed);
            if (vcd_ && t > flushed) {
                vcd_->set(vcd_readback_, flushed, 1);
                vcd_->set(vcd_readback_, t, 0);
            }
            stats_.readback_cycles += t - flushed;
            last_flushed_ = flushed;
            ++frames_flushed_;
            frame_flushed.notify(sc_core::SC_ZERO_TIME);
            clk_.wait_until(t);
            break;
        }
        case Job::Finish:
            finish_cycle_ = t;
            finished_ = true;
            return;
        }
    }
}

} // namespace rbcd
