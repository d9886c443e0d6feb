#include "rbcd/common/vcd_writer.h"

#include <algorithm>
#include <ctime>
#include <map>

namespace rbcd {

namespace {

std::string id_code(unsigned n) {
    // VCD identifiers: printable ASCII 33..126, little-endian base 94.
    std::string s;
    do {
        s += static_cast<char>(33 + n % 94);
        n /= 94;
    } while (n);
    return s;
}

} // namespace

VcdWriter::VcdWriter(Output out, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle,
                     std::string version)
    : out_(std::move(out)), period_ps_(period_ps), start_(start_cycle), end_(end_cycle), version_(std::move(version)) {}

VcdWriter::VcdWriter(WaveEncoder& enc, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle,
                     std::string version)
    : enc_(&enc), period_ps_(period_ps), start_(start_cycle), end_(end_cycle), version_(std::move(version)) {}

VcdWriter::Sig VcdWriter::add(const std::string& scope, const std::string& name, unsigned width,
                              std::uint64_t initial) {
    const Sig id = static_cast<Sig>(sigs_.size());
    sigs_.push_back({scope, name, id_code(id), width, initial, initial, false});
    return id;
}

void VcdWriter::header() {
    header_done_ = true;
    std::string h;
    char date[64];
    const std::time_t now = std::time(nullptr);
    std::strftime(date, sizeof date, "%Y-%m-%d %H:%M:%S", std::gmtime(&now));
    if (enc_) enc_->begin(date, version_, period_ps_);
    h += "$date\n  " + std::string(date) + "\n$end\n";
    h += "$version\n  " + version_ + "\n$end\n";
    h += "$comment\n  one cycle = " + std::to_string(period_ps_) + " ps\n$end\n";
    h += "$timescale 1ps $end\n";
    // Scopes are dotted paths; group signals by scope, opening nested modules.
    std::map<std::string, std::vector<Sig>> by_scope;
    for (Sig i = 0; i < sigs_.size(); ++i) by_scope[sigs_[i].scope].push_back(i);
    std::vector<std::string> open;
    for (const auto& [scope, ids] : by_scope) {
        std::vector<std::string> parts;
        for (std::size_t p = 0, q; p <= scope.size(); p = q + 1) {
            q = scope.find('.', p);
            if (q == std::string::npos) q = scope.size();
            parts.push_back(scope.substr(p, q - p));
        }
        std::size_t common = 0;
        while (common < open.size() && common < parts.size() && open[common] == parts[common]) ++common;
        while (open.size() > common) {
            h += "$upscope $end\n";
            if (enc_) enc_->upscope();
            open.pop_back();
        }
        for (std::size_t i = common; i < parts.size(); ++i) {
            h += "$scope module " + parts[i] + " $end\n";
            if (enc_) enc_->scope(parts[i]);
            open.push_back(parts[i]);
        }
        for (Sig id : ids) {
            if (enc_) enc_->var(id, sigs_[id].name, sigs_[id].width);
            h += "$var wire " + std::to_string(sigs_[id].width) + " " + sigs_[id].code + " " + sigs_[id].name +
                 (sigs_[id].width > 1 ? " [" + std::to_string(sigs_[id].width - 1) + ":0]" : "") + " $end\n";
        }
    }
    while (!open.empty()) {
        h += "$upscope $end\n";
        if (enc_) enc_->upscope();
        open.pop_back();
    }
    h += "$enddefinitions $end\n";
    if (enc_) enc_->end_definitions();
    else out_(h);
}

void VcdWriter::stamp(std::uint64_t cycle) {
    if (enc_) enc_->time(cycle * period_ps_);
    else buf_ += "#" + std::to_string(cycle * period_ps_) + "\n";
    last_stamp_ = cycle;
    stamped_any_ = true;
}

void VcdWriter::write_value(const Signal& s) {
    if (enc_) {
        enc_->value(static_cast<Sig>(&s - sigs_.data()), s.width, s.value);
        return;
    }
    if (s.width == 1) {
        buf_ += (s.value & 1) ? '1' : '0';
    } else {
        buf_ += 'b';
        int top = static_cast<int>(s.width) - 1;
        while (top > 0 && !((s.value >> top) & 1)) --top;
        for (int b = top; b >= 0; --b) buf_ += ((s.value >> b) & 1) ? '1' : '0';
        buf_ += ' ';
    }
    buf_ += s.code;
    buf_ += '\n';
}

void VcdWriter::open_window(std::uint64_t cycle) {
    window_open_ = true;
    stamp(cycle);
    if (enc_) enc_->dumpvars(true);
    else buf_ += "$dumpvars\n";
    for (auto& s : sigs_) {
        write_value(s);
        s.written = s.value;
    }
    if (enc_) enc_->dumpvars(false);
    else buf_ += "$end\n";
}

void VcdWriter::emit(std::uint64_t cycle) {
    // All of this cycle's events are applied; write what changed.
    const bool in_window = cycle >= start_ && cycle <= end_;
    if (in_window && !window_open_) {
        for (Sig id : touched_) sigs_[id].dirty = false;
        touched_.clear();
        open_window(cycle);
        return;
    }
    bool stamped = false;
    for (Sig id : touched_) {
        Signal& s = sigs_[id];
        s.dirty = false;
        if (!in_window || s.value == s.written) continue;
        if (!stamped) {
            stamp(cycle);
            stamped = true;
        }
        write_value(s);
        s.written = s.value;
    }
    touched_.clear();
    if (!enc_ && buf_.size() > (1u << 16)) {
        out_(buf_);
        buf_.clear();
    }
}

void VcdWriter::flush_before(std::uint64_t cycle) {
    if (!header_done_) header();
    auto mid = std::partition(events_.begin(), events_.end(), [&](const Event& e) { return e.cycle < cycle; });
    std::sort(events_.begin(), mid, [](const Event& a, const Event& b) {
        return a.cycle != b.cycle ? a.cycle < b.cycle : a.seq < b.seq;
    });
    for (auto it = events_.begin(); it != mid;) {
        const std::uint64_t c = it->cycle;
        for (; it != mid && it->cycle == c; ++it) {
            Signal& s = sigs_[it->sig];
            s.value = it->delta ? s.value + it->value : it->value;
            if (s.width < 64) s.value &= (std::uint64_t(1) << s.width) - 1;
            if (!s.dirty) {
                s.dirty = true;
                touched_.push_back(it->sig);
            }
        }
        emit(c);
    }
    events_.erase(events_.begin(), mid);
}

void VcdWriter::finish(std::uint64_t end_cycle) {
    if (finished_) return;
    finished_ = true;
    flush_before(~std::uint64_t(0));
    if (!window_open_ && end_cycle >= start_) open_window(std::max(start_, std::uint64_t(0)));
    // A closing time stamp so viewers show the last interval.
    const std::uint64_t last = std::min(end_cycle, end_);
    if (last >= start_ && (!stamped_any_ || last > last_stamp_)) stamp(last);
    if (enc_) enc_->finish();
    else out_(buf_);
    buf_.clear();
}

} // namespace rbcd
