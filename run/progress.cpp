#include "rbcd/run/progress.h"

#include <chrono>
#include <cstdio>
#include <unistd.h>

namespace rbcd {

namespace {
double steady_seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
} // namespace

Progress::Progress()
    : Progress(::isatty(STDERR_FILENO) == 1, steady_seconds,
               [](const std::string& s) {
                   std::fputs(s.c_str(), stderr);
                   std::fflush(stderr);
               }) {}

Progress::Progress(bool enabled, Clock clock, Writer out, double delay_s, double interval_s)
    : enabled_(enabled), clock_(std::move(clock)), out_(std::move(out)), delay_s_(delay_s), interval_s_(interval_s) {
    if (enabled_) start_ = clock_();
}

void Progress::on_frame(std::uint64_t frame, std::uint64_t fragments) {
    if (!enabled_) return;
    const double now = clock_();
    const double elapsed = now - start_;
    if (elapsed < delay_s_) return;
    if (shown_ && now - last_ < interval_s_) return;
    last_ = now;
    char buf[160];
    const int n = std::snprintf(buf, sizeof buf, "rbcd-sim: %llu frames done, %llu fragments, %.0f fragments/s",
                                (unsigned long long)frame, (unsigned long long)fragments,
                                elapsed > 0 ? double(fragments) / elapsed : 0.0);
    std::string line(buf, n > 0 ? std::size_t(n) : 0);
    const std::size_t w = line.size();
    if (w < width_) line.append(width_ - w, ' ');   // cover a longer previous line
    width_ = w;
    out_("\r" + line);
    shown_ = true;
}

void Progress::finish() {
    if (!shown_) return;
    out_("\r" + std::string(width_, ' ') + "\r");
    shown_ = false;
}

} // namespace rbcd
