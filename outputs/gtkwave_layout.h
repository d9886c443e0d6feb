// The GTKWave save file written beside a run's waveform (--gtkw): the run's
// signals grouped per block in pipeline order (only the blocks and ZEB banks
// this configuration traced), one-bit signals as bits, counts in decimal, the
// banks' states by name through a translate filter file written beside it,
// and a named marker at each frame's start (GTKWave keeps 26: A..Z).
//
//   GtkwaveLayout layout(wave, period_ps, trace_start);
//   layout.frame_start(frame, cycle);           // from a RasterObserver
//   out.write(layout.save_file(dump_path, filter_path));
//   filter.write(GtkwaveLayout::state_filter());
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/common/vcd_writer.h"

namespace rbcd {

class GtkwaveLayout {
public:
    static constexpr std::size_t kMarkers = 26;

    GtkwaveLayout(const VcdWriter& wave, std::uint64_t period_ps, std::uint64_t start_cycle, std::uint64_t end_cycle);
    // Frames that start inside the window get a marker, the first 26 of them.
    void frame_start(std::uint64_t frame, std::uint64_t cycle);
    // `dump` is the waveform's path, `filter` the state filter's (both as
    // GTKWave should open them: absolute).
    std::string save_file(const std::string& dump, const std::string& filter) const;
    // The ZEB bank state names, for the filter file.
    static std::string state_filter();
    // FILE.gtkw's filter file: FILE.states.txt.
    static std::string filter_path_for(const std::string& gtkw);

private:
    const VcdWriter& wave_;
    std::uint64_t period_ps_, start_, end_;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> markers_;   // frame, cycle
};

} // namespace rbcd
