#include "rbcd/outputs/gtkwave_layout.h"

#include <cstdio>
#include <map>

namespace rbcd {

namespace {

// GTKWave trace flags (its save-file format): 0x20 right-justified, with
// 0x4 decimal or 0x8 binary; 0x2000 shown through a translate filter file;
// a group opens with 0x800200 and closes with 0x1000200 (blank rows that
// carry the group's name).
constexpr unsigned kDecimal = 0x24, kBinary = 0x28, kTranslated = 0x2000;
constexpr unsigned kGroupBegin = 0x800200, kGroupEnd = 0x1000200;

// Blocks in the order a fragment meets them; the ZEB banks sort by number.
int pipeline_rank(const std::string& block) {
    static const char* const order[] = {"rasterizer",   "fragment_processors", "input_queue",   "insertion_sorter",
                                        "zeb_bank",     "zoverlap_tester",     "output_buffer", "memory_controller"};
    for (int i = 0; i < 8; ++i)
        if (block.compare(0, std::string(order[i]).size(), order[i]) == 0) return i;
    return 8;
}

std::string hex(unsigned v) {
    char b[16];
    std::snprintf(b, sizeof b, "@%x\n", v);
    return b;
}

} // namespace

GtkwaveLayout::GtkwaveLayout(const VcdWriter& wave, std::uint64_t period_ps, std::uint64_t start_cycle,
                             std::uint64_t end_cycle)
    : wave_(wave), period_ps_(period_ps), start_(start_cycle), end_(end_cycle) {}

void GtkwaveLayout::frame_start(std::uint64_t frame, std::uint64_t cycle) {
    if (markers_.size() < kMarkers && cycle >= start_ && cycle <= end_) markers_.emplace_back(frame, cycle);
}

std::string GtkwaveLayout::filter_path_for(const std::string& gtkw) {
    const std::string ext = ".gtkw";
    const bool has_ext = gtkw.size() > ext.size() && gtkw.compare(gtkw.size() - ext.size(), ext.size(), ext) == 0;
    return (has_ext ? gtkw.substr(0, gtkw.size() - ext.size()) : gtkw) + ".states.txt";
}

std::string GtkwaveLayout::state_filter() { return "0 free\n1 filling\n2 testing\n"; }

std::string GtkwaveLayout::save_file(const std::string& dump, const std::string& filter) const {
    std::string s = "[*] GTKWave save file written by rbcd-sim for this run (docs/waveforms.md)\n";
    s += "[dumpfile] \"" + dump + "\"\n";
    s += "[timestart] " + std::to_string(start_ * period_ps_) + "\n";
    s += "[size] 1400 800\n[pos] -1 -1\n";
    // Zoom (log2 of time units a pixel, negative zooms in), the primary marker
    // (none), then the 26 named markers' times (-1: unused).
    s += "*-18.000000 -1";
    for (std::size_t i = 0; i < kMarkers; ++i)
        s += " " + (i < markers_.size() ? std::to_string(markers_[i].second * period_ps_) : std::string("-1"));
    s += "\n";
    for (std::size_t i = 0; i < markers_.size(); ++i)
        s += "[markername] " + std::string(1, static_cast<char>('A' + i)) + "frame " +
             std::to_string(markers_[i].first) + "\n";

    // Scopes "rbcd.<block>": group the signals of each block, blocks ranked.
    std::map<std::pair<int, std::string>, std::vector<VcdWriter::Sig>> blocks;
    for (VcdWriter::Sig i = 0; i < wave_.signals(); ++i) {
        const std::string& scope = wave_.scope_of(i);
        const std::size_t dot = scope.rfind('.');
        const std::string block = dot == std::string::npos ? scope : scope.substr(dot + 1);
        // zeb_bank10 after zeb_bank9: by the number's length first.
        const std::string key = block.size() < 16 ? std::string(16 - block.size(), ' ') + block : block;
        blocks[{pipeline_rank(block), key}].push_back(i);
    }
    int filters = 0;
    for (const auto& [key, sigs] : blocks) {
        const std::string& scope = wave_.scope_of(sigs.front());
        const std::size_t dot = scope.rfind('.');
        const std::string block = dot == std::string::npos ? scope : scope.substr(dot + 1);
        s += hex(kGroupBegin) + "-" + block + "\n";
        unsigned flags = 0;
        for (VcdWriter::Sig id : sigs) {
            const unsigned w = wave_.width_of(id);
            const bool state = block.compare(0, 8, "zeb_bank") == 0 && wave_.name_of(id) == "state";
            const unsigned want = state ? (kDecimal | kTranslated) : w == 1 ? kBinary : kDecimal;
            if (want != flags) s += hex(flags = want);
            if (state) s += "^" + std::to_string(++filters) + " " + filter + "\n";
            s += scope + "." + wave_.name_of(id) + (w > 1 ? "[" + std::to_string(w - 1) + ":0]" : "") + "\n";
        }
        s += hex(kGroupEnd) + "-" + block + "\n";
    }
    return s;
}

} // namespace rbcd
