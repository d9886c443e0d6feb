#include "sc_main/output_file.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <csignal>
#include <sys/stat.h>
#include <vector>
#include <unistd.h>
#include <utility>

#include "common/errors.h"

namespace rbcd {

namespace {
// unlink, not remove: a path that names a directory is never deleted.
void unlink_file(const std::string& p) { ::unlink(p.c_str()); }

// Paths to remove if the run is interrupted: filled before the simulation
// starts and read-only afterwards, so the signal handler may walk it.
std::vector<std::string>& cleanup_paths() {
    static std::vector<std::string> paths;
    return paths;
}

extern "C" void on_fatal_signal(int sig) {
    for (const auto& p : cleanup_paths()) ::unlink(p.c_str());
    ::_exit(128 + sig);
}
} // namespace

void remove_on_interrupt(const std::string& path) {
    static const bool installed = [] {
        struct sigaction sa {};
        sa.sa_handler = on_fatal_signal;
        sigemptyset(&sa.sa_mask);
        for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::sigaction(sig, &sa, nullptr);
        return true;
    }();
    (void)installed;
    cleanup_paths().push_back(path);
}

bool same_file(const std::string& a, const std::string& b) {
    struct stat sa {}, sb {};
    return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

void discard_output(const std::string& path) {
    if (!path.empty()) unlink_file(path);
}

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
    struct stat st {};
    if (::stat(path_.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw InputError(path_ + ": cannot create: is a directory");
    tmp_ = path_ + ".tmp." + std::to_string(::getpid());
    // An older result must not outlive this run, even one killed before it
    // could clean up: it goes now, and the temporary on an interrupt.
    unlink_file(path_);
    remove_on_interrupt(tmp_);
    f_ = std::fopen(tmp_.c_str(), "wb");
    if (!f_) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
}

OutputFile::~OutputFile() { abandon(); }

OutputFile::OutputFile(OutputFile&& o) noexcept { *this = std::move(o); }

OutputFile& OutputFile::operator=(OutputFile&& o) noexcept {
    if (this != &o) {
        abandon();
        path_ = std::move(o.path_);
        tmp_ = std::move(o.tmp_);
        f_ = std::exchange(o.f_, nullptr);
        failed_ = o.failed_;
    }
    return *this;
}

void OutputFile::write(const char* p, std::size_t n) {
    if (f_ && n && std::fwrite(p, 1, n, f_) != n) failed_ = true;
}

void OutputFile::commit() {
    if (!f_) return;
    const bool flushed = std::fflush(f_) == 0 && !std::ferror(f_);
    const bool closed = std::fclose(f_) == 0;
    f_ = nullptr;
    if (failed_ || !flushed || !closed) {
        const std::string why = std::strerror(errno);
        unlink_file(tmp_);
        unlink_file(path_);
        throw std::runtime_error(path_ + ": write failed: " + why);
    }
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        unlink_file(tmp_);
        unlink_file(path_);
        throw std::runtime_error(path_ + ": cannot rename into place: " + why);
    }
    tmp_.clear();
}

void OutputFile::abandon() {
    if (f_) {
        std::fclose(f_);
        f_ = nullptr;
    }
    if (!tmp_.empty()) {
        unlink_file(tmp_);
        unlink_file(path_);
        tmp_.clear();
    }
}

} // namespace rbcd
