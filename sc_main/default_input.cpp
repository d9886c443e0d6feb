#include "sc_main/default_input.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>
#include <sys/mman.h>
#include <unistd.h>

extern const char* rbcd_default_trace_text();
extern const char* rbcd_default_trace_name();

namespace rbcd {

namespace {

// The embedded trace is handed to the ordinary reader through an anonymous
// in-memory file, so it is parsed exactly as a trace on disk would be.
class EmbeddedTrace final : public FragmentSource {
public:
    explicit EmbeddedTrace(const TraceLimits& limits) : fd_(make_fd()), reader_(fd_path(), limits) {}
    ~EmbeddedTrace() override { ::close(fd_); }
    const StreamHeader& header() const override { return reader_.header(); }
    Event next(Tile& t) override { return reader_.next(t); }
    std::string name() const override { return std::string("<embedded ") + rbcd_default_trace_name() + ">"; }

private:
    static int make_fd() {
        const int fd = ::memfd_create("rbcd-default-trace", 0);
        if (fd < 0) throw std::runtime_error(std::string("memfd_create: ") + std::strerror(errno));
        const char* text = rbcd_default_trace_text();
        std::size_t left = std::strlen(text);
        while (left) {
            const ssize_t n = ::write(fd, text, left);
            if (n <= 0) throw std::runtime_error(std::string("writing the default trace: ") + std::strerror(errno));
            text += n;
            left -= static_cast<std::size_t>(n);
        }
        return fd;
    }
    std::string fd_path() const { return "/proc/self/fd/" + std::to_string(fd_); }

    int fd_;
    TraceReader reader_;
};

} // namespace

std::unique_ptr<FragmentSource> open_default_input(const TraceLimits& limits) {
    return std::make_unique<EmbeddedTrace>(limits);
}

} // namespace rbcd
