// Progress on stderr for long runs: frames done and fragments per second,
// rewritten in place on one line, only when stderr is a terminal and only once
// the run has taken longer than a few seconds (short runs print nothing).
//
//   Progress progress;                               // decides from isatty(stderr)
//   // from a RasterObserver's frame_begin(n):
//   progress.on_frame(n, sys.raster.stats().fragments);
//   sys.run();
//   progress.finish();                               // clears the line
#pragma once
#include <cstdint>
#include <functional>
#include <string>

namespace rbcd {

class Progress {
public:
    using Clock = std::function<double()>;              // seconds, monotonic
    using Writer = std::function<void(const std::string&)>;

    // Enabled when stderr is a terminal; writes to stderr.
    Progress();
    // For tests: explicit switch, clock and output.
    Progress(bool enabled, Clock clock, Writer out, double delay_s = 3.0, double interval_s = 0.5);
    // Clears the line, also when an error unwinds past the run (the message goes on a clean line).
    ~Progress() { finish(); }
    Progress(const Progress&) = delete;
    Progress& operator=(const Progress&) = delete;

    // Frame `frame` begins: frames before it are done. `fragments` so far.
    void on_frame(std::uint64_t frame, std::uint64_t fragments);
    // Erases the progress line, if one was shown.
    void finish();

    bool enabled() const { return enabled_; }
    bool shown() const { return shown_; }

private:
    bool enabled_;
    Clock clock_;
    Writer out_;
    double delay_s_, interval_s_;
    double start_ = 0, last_ = -1;
    bool shown_ = false;
    std::size_t width_ = 0;
};

} // namespace rbcd
