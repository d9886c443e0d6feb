#include "rbcd/run/jobs.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "rbcd/common/errors.h"
#include "rbcd/common/output_file.h"

namespace rbcd {

namespace {

bool parse_u64(const std::string& s, std::uint64_t& v) {
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos) return false;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
    return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

// Part k's range ends where part k + 1 starts; the last keeps the run's end.
std::vector<JobPart> close_ranges(std::vector<JobPart> parts, std::uint64_t last) {
    for (std::size_t k = 0; k + 1 < parts.size(); ++k) parts[k].range.last = parts[k + 1].range.first - 1;
    if (!parts.empty()) parts.back().range.last = last;
    return parts;
}

} // namespace

std::vector<JobPart> plan_trace_parts(const FrameScan& scan, FrameRange range, unsigned jobs) {
    if (!scan.ok || scan.marks.empty() || jobs < 2) return {};
    // The bytes the range spans, as far as the marks tell.
    std::uint64_t lo = 0, hi = scan.bytes;
    bool any = false;
    for (const FrameMark& m : scan.marks) {
        if (m.frame <= range.first) lo = m.offset;
        if (m.frame >= range.first && m.frame <= range.last) any = true;
        if (m.frame > range.last) {
            hi = m.offset;
            break;
        }
    }
    if (!any || hi <= lo) return {};
    std::vector<JobPart> parts(1);
    parts[0].range.first = range.first;
    std::size_t i = 0;
    for (unsigned k = 1; k < jobs; ++k) {
        const std::uint64_t target = lo + (hi - lo) / jobs * k + (hi - lo) % jobs * k / jobs;
        while (i < scan.marks.size() &&
               (scan.marks[i].offset < target || scan.marks[i].frame <= parts.back().range.first))
            ++i;
        if (i == scan.marks.size() || scan.marks[i].frame > range.last) break;
        JobPart p;
        p.range.first = scan.marks[i].frame;
        p.skip = true;
        p.offset = scan.marks[i].offset;
        p.line = scan.marks[i].line;
        parts.push_back(p);
    }
    return close_ranges(std::move(parts), range.last);
}

std::vector<JobPart> plan_scene_parts(std::uint64_t frames, FrameRange range, unsigned jobs) {
    if (jobs < 2 || range.first >= frames) return {};
    const std::uint64_t last = std::min(range.last, frames - 1), n = last - range.first + 1;
    const std::uint64_t count = std::min<std::uint64_t>(jobs, n);
    std::vector<JobPart> parts(count);
    for (std::uint64_t k = 0; k < count; ++k) {
        // n * k / count without overflow: n < 2^64, count <= jobs.
        parts[k].range.first = range.first + n / count * k + n % count * k / count;
        parts[k].skip = parts[k].range.first > 0;   // as one process, no frame before the range is rendered
    }
    return close_ranges(std::move(parts), range.last);
}

std::string worker_part_text(const JobPart& p, bool trace) {
    if (!p.skip) return "first";
    if (!trace) return "scene";
    return "trace:" + std::to_string(p.offset) + ":" + std::to_string(p.line);
}

JobPart parse_worker_part(const std::string& text, FrameRange range) {
    JobPart p;
    p.range = range;
    if (text == "first") return p;
    p.skip = true;
    if (text == "scene") return p;
    const auto bad = [&] { return InputError("--worker-part: \"" + text + "\" is not first, scene or trace:OFFSET:LINE"); };
    if (text.rfind("trace:", 0) != 0) throw bad();
    const std::string rest = text.substr(6);
    const auto colon = rest.find(':');
    if (colon == std::string::npos || !parse_u64(rest.substr(0, colon), p.offset) ||
        !parse_u64(rest.substr(colon + 1), p.line))
        throw bad();
    return p;
}

std::string worker_digest_text(const DigestBlocks& b) { return std::to_string(b.from) + ":" + std::to_string(b.to); }

DigestBlocks parse_worker_digest(const std::string& text, const std::string& sums_path) {
    DigestBlocks b;
    const auto colon = text.find(':');
    if (colon == std::string::npos || !parse_u64(text.substr(0, colon), b.from) ||
        !parse_u64(text.substr(colon + 1), b.to) || b.from % 1024 || b.to % 1024 || b.to < b.from)
        throw InputError("--worker-digest: \"" + text + "\" is not FROM:TO, byte offsets in whole blocks of 1024, FROM <= TO");
    if (b.from > 0 && sums_path.empty()) throw InputError("--worker-digest: a part not from byte 0 needs --worker-digest-sums");
    return b;
}

namespace {

// Descriptor `target` opened on `path` (the descriptors above 2 are closed,
// so the open cannot run out of them); false when it cannot be.
bool open_as(int target, const char* path, int flags) {
    const int fd = ::open(path, flags, 0600);
    if (fd < 0) return false;
    if (fd == target) return true;
    const bool ok = ::dup2(fd, target) == target;
    ::close(fd);
    return ok;
}

// Every descriptor above 2: the parent's files (its outputs, the input it
// scanned) are not the worker's, and a pipe held open here would not see its
// end. close_range(2) where the kernel has it (5.9 on), else one by one.
void close_above_2() {
    if (::close_range(3, ~0u, 0) == 0) return;
    const long max = ::sysconf(_SC_OPEN_MAX);
    for (long fd = 3; fd < (max > 0 ? std::min(max, 1L << 20) : 1024); ++fd) ::close(static_cast<int>(fd));
}

// A worker that could not set itself up: its status, which the parent reads
// as "cannot start" (a program exits 127 when it cannot be run).
constexpr int kCannotStart = 127;
// Bytes reserved for a worker's standard error: its one line, with room for
// a scene's warnings before it.
constexpr off_t kErrorRoom = 64 * 1024;

// The forked worker: its descriptors and signals as a new process would have
// them, then its program. Never returns: the frames below are the parent's,
// whose objects (its outputs, its workers) are not the worker's to destroy.
[[noreturn]] void become_worker(WorkerMain main, const std::vector<std::string>& argv, int out_fd,
                                const std::string& err_path, const sigset_t& mask, pid_t parent) {
    forget_parents_cleanup();
    // A parent killed outright (SIGKILL, which no handler sees) takes its
    // workers with it, rather than leaving them to run their frames to the
    // end for nobody; checked after, for a parent gone before the request.
    if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) ::_exit(kCannotStart);
    // The output first: started without a standard input or error, the parent
    // may hold it as descriptor 0 or 2, which the opens replace.
    if (out_fd >= 0 && out_fd != 1 && ::dup2(out_fd, 1) != 1) ::_exit(kCannotStart);
    close_above_2();
    // Not truncated: its blocks were reserved by the parent (Workers).
    if (!open_as(2, err_path.c_str(), O_WRONLY | O_CREAT | O_APPEND)) ::_exit(kCannotStart);
    const auto cannot = [](const char* what) {
        std::fprintf(stderr, "rbcd-sim: --jobs: a worker cannot open /dev/null as its %s: %s\n", what,
                     std::strerror(errno));
        std::fflush(stderr);
        ::_exit(kCannotStart);
    };
    if (!open_as(0, "/dev/null", O_RDONLY)) cannot("standard input");
    if (out_fd < 0 && !open_as(1, "/dev/null", O_WRONLY)) cannot("standard output");
    ::pthread_sigmask(SIG_SETMASK, &mask, nullptr);
    int status = 1;
    try {
        status = main(argv);
    } catch (...) {
        status = 1;
    }
    std::fflush(nullptr);
    // No LeakSanitizer check here: a fork's check counts the parent's objects,
    // alive in frames the worker never returns to, as leaks. The workers' own
    // code is checked where a worker's command line runs as a program of its
    // own (test_jobs, "a worker's command line run alone").
    ::_exit(status);
}

} // namespace

Workers::Workers(WorkerMain main, const std::vector<std::vector<std::string>>& argvs,
                 const std::vector<std::string>& err_paths, const std::vector<int>& out_fds)
    : err_(err_paths) {
    // A signal between a worker's start and its registration would leave it
    // writing after the clean-up: held back until every worker is known; the
    // workers start with the mask this process had.
    const InterruptsHeld held;
    // A SIGCHLD ignored by whoever started this process would have the kernel
    // reap the workers itself, and their statuses would be lost.
    struct sigaction dfl {};
    dfl.sa_handler = SIG_DFL;
    sigemptyset(&dfl.sa_mask);
    ::sigaction(SIGCHLD, &dfl, nullptr);
    // Nothing buffered here may be written twice, by a worker too.
    std::fflush(nullptr);
    // Each worker's error file is made here with room reserved for its
    // message (without growing its size): a worker that fails because its
    // file system filled up can still say so, rather than lose its one line
    // with the space ("worker 0 failed"). Best effort: a file system
    // without fallocate, or already full, reserves nothing.
    for (const std::string& err : err_paths) {
        const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
        if (fd < 0) continue;   // the worker's own open says why
        (void)::fallocate(fd, FALLOC_FL_KEEP_SIZE, 0, kErrorRoom);
        ::close(fd);
    }
    const pid_t self = ::getpid();
    for (std::size_t k = 0; k < argvs.size(); ++k) {
        const int out = k < out_fds.size() ? out_fds[k] : -1;
        const pid_t pid = ::fork();
        if (pid == 0) become_worker(main, argvs[k], out, err_paths[k], held.previous(), self);
        if (pid < 0) {
            const int err = errno;
            // The workers already started would run on, writing where this
            // run's error leaves nothing: stopped first.
            stop_all();
            throw RunError("--jobs: cannot start a worker: " + std::string(std::strerror(err)));
        }
        pids_.push_back(pid);
        status_.push_back(0);
        lost_.push_back(0);
        done_.push_back(false);
        stop_on_interrupt(pid);
    }
}

Workers::~Workers() {
    if (!waited_) stop_all();
}

void Workers::stop_all() {
    for (std::size_t k = 0; k < pids_.size(); ++k)
        if (!done_[k]) {
            ::kill(pids_[k], SIGTERM);
            ::kill(pids_[k], SIGCONT);   // a stopped worker acts on it only once continued
        }
    for (std::size_t k = 0; k < pids_.size(); ++k)
        if (!done_[k]) wait_for(k);
}

bool Workers::wait_for(std::size_t k) {
    if (!done_[k]) {
        // Waited for without reaping, so that its pid cannot be reused while
        // the interrupt handler still knows it; then forgotten, then reaped.
        siginfo_t info{};
        int rc;
        while ((rc = ::waitid(P_PID, static_cast<id_t>(pids_[k]), &info, WEXITED | WNOWAIT)) < 0 && errno == EINTR) {}
        if (rc < 0) lost_[k] = errno;
        forget_child(pids_[k]);
        while (::waitpid(pids_[k], &status_[k], 0) < 0) {
            if (errno == EINTR) continue;
            if (!lost_[k]) lost_[k] = errno;
            break;
        }
        done_[k] = true;
    }
    return !lost_[k] && WIFEXITED(status_[k]) && WEXITSTATUS(status_[k]) == 0;
}

bool Workers::refused_input(std::size_t k) const {
    return done_[k] && !lost_[k] && WIFEXITED(status_[k]) && WEXITSTATUS(status_[k]) == 2;
}

bool Workers::first_end_ok() const {
    siginfo_t info{};
    while (::waitid(P_ALL, 0, &info, WEXITED | WNOWAIT) < 0)
        if (errno != EINTR) return true;   // the joins find out what happened
    return info.si_code == CLD_EXITED && info.si_status == 0;
}

void Workers::wait() {
    for (std::size_t k = 0; k < pids_.size(); ++k) wait_for(k);
    waited_ = true;
    for (std::size_t k = 0; k < pids_.size(); ++k) {
        const int st = status_[k];
        if (lost_[k])
            throw RunError("--jobs: worker " + std::to_string(k) + ": its exit status is lost (" +
                           std::strerror(lost_[k]) + ")");
        if (WIFEXITED(st) && WEXITSTATUS(st) == 0) continue;
        // Ended by a signal: killed by it, or through its interrupt handler's
        // exit (128 + the signal).
        const int sig = WIFSIGNALED(st)                                              ? WTERMSIG(st)
                        : WEXITSTATUS(st) > 128 && WEXITSTATUS(st) < 128 + NSIG ? WEXITSTATUS(st) - 128
                                                                                  : 0;
        // A worker writing into a pipe whose reader went away (--collisions -
        // | head) ends the run as one process would: silently, by the same
        // signal, through this process's interrupt clean-up.
        if (sig == SIGPIPE) ::raise(SIGPIPE);
        // The worker's own one line, without its program name (the caller's
        // message adds it); its other lines (a scene's warnings) were said once
        // by the caller already.
        std::ifstream in(err_[k]);
        std::string line, last;
        while (std::getline(in, line))
            if (line.rfind("rbcd-sim: ", 0) == 0) last = line.substr(10);
        if (WIFEXITED(st) && WEXITSTATUS(st) == 2) throw InputError(last.empty() ? "a worker refused its input" : last);
        if (last.empty())
            last = sig ? "--jobs: worker " + std::to_string(k) + " ended by signal " + std::to_string(sig) + " (" +
                             ::strsignal(sig) + ")"
                   : WEXITSTATUS(st) == kCannotStart
                       ? "--jobs: cannot start worker " + std::to_string(k) + " (its error file " + err_[k] +
                             " cannot be opened)"
                       : "--jobs: worker " + std::to_string(k) + " failed without a message (exit status " +
                             std::to_string(WEXITSTATUS(st)) + ")";
        throw RunError(last);
    }
}

TempDirectory::TempDirectory(const std::string& parent) {
    std::string tmpl = (std::filesystem::path(parent) / ".rbcd-sim-jobs.XXXXXX").string();
    std::vector<char> b(tmpl.begin(), tmpl.end());
    b.push_back('\0');
    // Held back between the creation and the registration, as OutputFile does.
    const InterruptsHeld held;
    if (!::mkdtemp(b.data()))
        throw RunError("--jobs: cannot create the workers' directory in " + parent + ": " + std::strerror(errno));
    dir_ = b.data();
    remove_on_interrupt(dir_);
}

void TempDirectory::will_hold(const std::string& name) {
    // The handler removes paths in order: the directory must come after its
    // files. Held back meanwhile: a signal between the two would find the
    // directory on no list and leave it behind (a CI run caught it once in
    // the ASan build, SIGTERM sent as the directory appeared).
    const InterruptsHeld held;
    forget_on_interrupt(dir_);
    held_.push_back(path(name));
    remove_on_interrupt(held_.back());
    remove_on_interrupt(dir_);
}

TempDirectory::~TempDirectory() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
    for (const auto& p : held_) forget_on_interrupt(p);
    forget_on_interrupt(dir_);
}

} // namespace rbcd
