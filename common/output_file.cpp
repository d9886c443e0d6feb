#include "rbcd/common/output_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <linux/magic.h>
#include <sys/vfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <utility>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/common/write_all.h"

namespace rbcd {

namespace {
// Paths to remove if the run is interrupted: changed only with the
// interrupts held on the thread that changes it (the main thread), so the
// handler may walk it. Never destroyed: a signal during exit() (a summary
// flushed into a closed pipe) must not find it freed.
std::vector<std::string>& cleanup_paths() {
    static auto* paths = new std::vector<std::string>;
    return *paths;
}

// Worker processes (rbcd-sim --jobs) that write into those paths: stopped and
// waited for first, so that nothing is written there after the removal.
// SIGPIPE too: an output on a pipe whose reader went away (`| head`) ends the
// run as an interrupt does, its temporaries and workers' directory removed.
constexpr int kInterrupts[] = {SIGINT, SIGTERM, SIGHUP, SIGPIPE};

constexpr int kMaxChildren = 1024;
volatile sig_atomic_t g_children[kMaxChildren];   // 0: ended and forgotten
volatile sig_atomic_t g_child_count = 0;

// Set once every output stands complete: a signal then ends nothing (the
// summary on a closed pipe fails quietly; SIGTERM finds the run ending well).
volatile sig_atomic_t g_outputs_complete = 0;

extern "C" void on_fatal_signal(int sig) {
    if (g_outputs_complete) return;
    // SIGCONT too: a stopped worker would never act on the SIGTERM, and the
    // wait below would never end.
    for (int i = 0; i < g_child_count; ++i)
        if (g_children[i] > 0) {
            ::kill(g_children[i], SIGTERM);
            ::kill(g_children[i], SIGCONT);
        }
    for (int i = 0; i < g_child_count; ++i)
        if (g_children[i] > 0)
            while (::waitpid(g_children[i], nullptr, 0) < 0 && errno == EINTR) {}
    // A ByName output's directory is listed after the files in it.
    for (const auto& p : cleanup_paths())
        if (::unlink(p.c_str()) != 0) ::rmdir(p.c_str());
    ::_exit(128 + sig);
}


// What lstat says stands at the path: written in place unless it is a regular
// file or nothing.
bool needs_in_place(const std::string& path) {
    if (path == "-") return true;
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) return false;
    return !S_ISREG(st.st_mode);
}

std::string dir_of(const std::string& path) {
    const auto slash = path.rfind('/');
    if (slash == std::string::npos) return ".";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

std::string base_of(const std::string& path) {
    const auto slash = path.rfind('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}
} // namespace

void report_file_size_limit_as_write_error() { ::signal(SIGXFSZ, SIG_IGN); }

void outputs_complete() { g_outputs_complete = 1; }

void result_stands(const std::string& temporary, const std::string& path) {
    const InterruptsHeld held;
    for (auto& p : cleanup_paths())
        if (!temporary.empty() && p == temporary) {
            p = path;
            return;
        }
    cleanup_paths().push_back(path);
}

void forget_on_interrupt(const std::string& path) {
    // Only before the simulation runs (see cleanup_paths), or after it.
    auto& v = cleanup_paths();
    for (auto& p : v)
        if (p == path) p.clear();
}

void forget_child(int pid) {
    for (int i = 0; i < g_child_count; ++i)
        if (g_children[i] == pid) g_children[i] = 0;
}

void forget_parents_cleanup() {
    cleanup_paths().clear();
    g_child_count = 0;
}

void stop_on_interrupt(int pid) {
    if (g_child_count < kMaxChildren) {
        g_children[g_child_count] = pid;
        g_child_count = g_child_count + 1;
    }
}

InterruptsHeld::InterruptsHeld() {
    sigset_t block;
    sigemptyset(&block);
    for (int sig : kInterrupts) sigaddset(&block, sig);
    ::pthread_sigmask(SIG_BLOCK, &block, &old_);
}

InterruptsHeld::~InterruptsHeld() { ::pthread_sigmask(SIG_SETMASK, &old_, nullptr); }

void remove_on_interrupt(const std::string& path) {
    static const bool installed = [] {
        struct sigaction sa {};
        sa.sa_handler = on_fatal_signal;
        sigemptyset(&sa.sa_mask);
        for (int sig : kInterrupts) {
            // SIGINT or SIGHUP ignored when the program started (a script's
            // background job, nohup) stays ignored, as in every Unix tool.
            struct sigaction old {};
            if ((sig == SIGINT || sig == SIGHUP) && ::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN)
                continue;
            ::sigaction(sig, &sa, nullptr);
        }
        return true;
    }();
    (void)installed;
    cleanup_paths().push_back(path);
}

namespace {
bool same_file_as_descriptor(const std::string& path, int fd) {
    struct stat sp {}, sf {};
    return ::stat(path.c_str(), &sp) == 0 && ::fstat(fd, &sf) == 0 && sp.st_dev == sf.st_dev && sp.st_ino == sf.st_ino;
}
} // namespace

bool same_file(const std::string& a, const std::string& b) {
    struct stat sa {}, sb {};
    return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

void discard_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs) {
    for (const auto& out : outputs) {
        if (out.empty()) continue;
        bool is_input = false;
        for (const auto& in : inputs) is_input = is_input || same_file(out, in);
        if (!is_input) discard_output(out);
    }
}

namespace {
// A path as the file system would resolve it, for outputs that do not exist yet.
std::string resolved(const std::string& path) {
    std::error_code ec;
    const auto p = std::filesystem::weakly_canonical(path, ec);
    return ec ? path : p.string();
}

bool is_regular_or_absent(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return true;
    return S_ISREG(st.st_mode);
}
} // namespace

void check_output_paths(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs) {
    for (std::size_t i = 0; i < outputs.size(); ++i) {
        const NamedPath& o = outputs[i];
        if (o.path.empty()) continue;
        for (const NamedPath& in : inputs)
            if (!in.path.empty() && o.path != "-" && same_file(o.path, in.path))
                throw InputError(o.flag + ": " + o.path + " is the input file " + in.path +
                                 (in.flag.empty() ? std::string() : " (" + in.flag + ")"));
        if (o.path == "-" || !is_regular_or_absent(o.path)) continue;
        for (std::size_t j = 0; j < i; ++j) {
            const NamedPath& e = outputs[j];
            if (e.path.empty() || e.path == "-") continue;
            if (same_file(o.path, e.path) || resolved(o.path) == resolved(e.path))
                throw InputError(o.flag + ": " + o.path + " is also " + e.flag + "'s output");
        }
    }
}

void discard_output(const std::string& path) {
    if (path.empty() || needs_in_place(path)) return;
    ::unlink(path.c_str());   // unlink, not remove: never a directory
}

namespace {
// File systems whose copy_file_range copies on the server's side: the bytes
// do not cross the network twice. Elsewhere (ext4, XFS, btrfs, tmpfs) the
// kernel copies through a pipe, slower than plain reads and writes: 3.7 ms
// against 2.7 ms for 10 MB on ext4, 8 ms against 6 ms on a --jobs 2 run's
// tail. (XFS and btrfs would share blocks instead, but only for offsets on
// block boundaries, which an append after a part's magic line never is.)
bool copies_on_server(int fd) {
    struct statfs fs {};
    if (::fstatfs(fd, &fs) != 0) return false;
    switch (static_cast<unsigned long>(fs.f_type)) {
    case NFS_SUPER_MAGIC:
    case CIFS_SUPER_MAGIC:
    case SMB2_SUPER_MAGIC:
    case CEPH_SUPER_MAGIC:
        return true;
    default:
        return false;
    }
}
} // namespace

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
    struct stat st {};
    if (::stat(path_.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw InputError(path_ + ": cannot create: is a directory");
    int fd = -1;
    if (needs_in_place(path_)) {
        in_place_ = true;
        // A name for this process's standard output or error (/dev/stdout,
        // /proc/self/fd/1) is that descriptor, as "-" is: opened again, a
        // redirected file would be truncated and written from its start,
        // under the summary written through the descriptor itself.
        const int std_fd = path_ == "-" ? 1 : same_file_as_descriptor(path_, 1) ? 1 : same_file_as_descriptor(path_, 2) ? 2 : -1;
        fd = std_fd >= 0 ? ::fcntl(std_fd, F_DUPFD_CLOEXEC, 3) : ::open(path_.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
        if (fd < 0) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
        // A symlink to a regular file is written through, from the start.
        if (std_fd < 0 && ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) (void)::ftruncate(fd, 0);
    } else {
        // An older result must not outlive this run, even one killed before it
        // could clean up: it goes now (formats.md).
        ::unlink(path_.c_str());
        std::string tmpl = dir_of(path_) + "/." + base_of(path_) + ".XXXXXX";
        {
            // A signal between the creation and the registration would leave
            // the temporary behind (an rbcd-sim --jobs worker is stopped just
            // as it starts): held back until the handler knows the path.
            const InterruptsHeld held;
            // mkostemp: O_CREAT|O_EXCL with a random name, so nothing planted at
            // a predictable name (a symlink) can redirect the output.
            fd = ::mkostemp(tmpl.data(), O_CLOEXEC);
            if (fd < 0) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
            tmp_ = tmpl;
            remove_on_interrupt(tmp_);
        }
        // mkstemp creates 0600; the result gets what fopen would give it.
        const mode_t mask = ::umask(0);
        ::umask(mask);
        (void)::fchmod(fd, 0666 & ~mask);
    }
    f_ = ::fdopen(fd, "wb");
    if (!f_) {
        const std::string why = std::strerror(errno);
        ::close(fd);
        abandon();
        throw InputError(path_ + ": cannot create: " + why);
    }
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
}

// What a ByName library may leave beside its file: fstapi's hierarchy, SQLite's
// journals. Removed with the directory.
static const char* const kCompanions[] = {"", ".hier", "-journal", "-wal", "-shm"};

OutputFile::OutputFile(std::string path, ByName) : path_(std::move(path)) {
    struct stat st {};
    if (::stat(path_.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        throw InputError(path_ + ": cannot create: is a directory");
    if (needs_in_place(path_))
        throw InputError(path_ + ": cannot write here: must be a regular file or a new path (the file is written with seeks)");
    ::unlink(path_.c_str());
    std::string tmpl = dir_of(path_) + "/." + base_of(path_) + ".XXXXXX";
    // Held back between the creation and the registration, as for a plain
    // output: a signal there would leave the directory behind.
    const InterruptsHeld held;
    if (!::mkdtemp(tmpl.data())) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
    dir_ = tmpl;
    named_ = dir_ + "/" + base_of(path_);
    for (const char* c : kCompanions) remove_on_interrupt(named_ + c);
    remove_on_interrupt(dir_);
}

OutputFile::~OutputFile() { abandon(); }

OutputFile::OutputFile(OutputFile&& o) noexcept { *this = std::move(o); }

OutputFile& OutputFile::operator=(OutputFile&& o) noexcept {
    if (this != &o) {
        abandon();
        path_ = std::move(o.path_);
        shown_ = std::move(o.shown_);
        tmp_ = std::exchange(o.tmp_, std::string());
        dir_ = std::exchange(o.dir_, std::string());
        named_ = std::exchange(o.named_, std::string());
        f_ = std::exchange(o.f_, nullptr);
        in_place_ = o.in_place_;
        failed_ = o.failed_;
        failed_errno_ = o.failed_errno_;
    }
    return *this;
}

std::string OutputFile::open_file_path() const {
    return f_ ? "/proc/self/fd/" + std::to_string(::fileno(f_)) : std::string();
}

void OutputFile::write(const char* p, std::size_t n) {
    if (f_ && n && std::fwrite(p, 1, n, f_) != n) fail_with(errno);
}

void OutputFile::fail_with(int err) {
    if (!failed_) failed_errno_ = err;
    failed_ = true;
}

int OutputFile::shared_fd() {
    if (!f_) return -1;
    if (std::fflush(f_) != 0) fail_with(errno);
    return ::fileno(f_);
}

std::uint64_t OutputFile::append_from(int fd, std::uint64_t offset, const std::string& what) {
    if (!f_) return 0;
    const auto cannot_read = [&](int err) { return RunError(what + ": cannot read: " + std::strerror(err)); };
    std::uint64_t copied = 0;
    // What stdio holds goes first; a failed flush is the output's failure
    // (stdio drops its buffer then, and a second flush would say nothing).
    if (std::fflush(f_) != 0) {
        fail_with(errno);
        return copied;
    }
    bool kernel = !in_place_ && copies_on_server(::fileno(f_));
    loff_t in_off = static_cast<loff_t>(offset);
    while (kernel) {
        const ssize_t n = ::copy_file_range(fd, &in_off, ::fileno(f_), nullptr, std::size_t(1) << 30, 0);
        if (n > 0) {
            copied += static_cast<std::uint64_t>(n);
            continue;
        }
        if (n == 0) return copied;
        if (errno == EINTR) continue;
        // Another file system, or one that cannot: copied here instead. Nothing
        // was written by the failed call.
        // (EIO: the read or the write; the copy below tells which.)
        if (errno == EXDEV || errno == EINVAL || errno == ENOSYS || errno == EOPNOTSUPP || errno == EBADF ||
            errno == EIO)
            break;
        // A full disk, a quota: the output's failure, which commit() reports
        // with this errno.
        fail_with(errno);
        return copied;
    }
    // Chunks of 256 KiB: the buffer stays in the core's L2 cache between the
    // read and the write (1 MiB chunks took 10% longer).
    // Written past stdio's buffer (flushed above), not copied into it too.
    std::vector<char> buf(std::size_t(1) << 18);
    for (;;) {
        const ssize_t n = ::pread(fd, buf.data(), buf.size(), in_off);
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw cannot_read(errno);
        if (n == 0) return copied;
        if (const int err = write_all(::fileno(f_), buf.data(), static_cast<std::size_t>(n))) {
            // A full disk, a quota: reported by commit().
            fail_with(err);
            return copied;
        }
        in_off += n;
        copied += static_cast<std::uint64_t>(n);
    }
}

void OutputFile::commit() {
    if (!dir_.empty()) {
        struct stat st {};
        if (::stat(named_.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
            abandon();
            throw RunError(shown() + ": write failed: the file was not written");
        }
        {
            // No signal between the rename and the registration.
            const InterruptsHeld held;
            if (std::rename(named_.c_str(), path_.c_str()) == 0) result_stands({}, path_);
            else {
                const std::string why = std::strerror(errno);
                abandon();
                throw RunError(shown() + ": cannot rename into place: " + why);
            }
        }
        abandon();   // the directory and what else the library left in it
        return;
    }
    if (!f_) return;
    const bool flushed = std::fflush(f_) == 0 && !std::ferror(f_);
    const int flush_errno = errno;
    const bool closed = std::fclose(f_) == 0;
    f_ = nullptr;
    if (failed_ || !flushed || !closed) {
        const std::string why = std::strerror(failed_ && failed_errno_ ? failed_errno_ : flushed ? errno : flush_errno);
        abandon();
        throw RunError(shown() + ": write failed: " + why);
    }
    if (in_place_) return;
    {
        // No signal between the rename and the registration.
        const InterruptsHeld held;
        if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
            const std::string why = std::strerror(errno);
            abandon();
            throw RunError(shown() + ": cannot rename into place: " + why);
        }
        result_stands(tmp_, path_);
    }
    tmp_.clear();
}

void OutputFile::abandon() {
    if (!dir_.empty()) {
        for (const char* c : kCompanions) {
            ::unlink((named_ + c).c_str());
            forget_on_interrupt(named_ + c);
        }
        ::rmdir(dir_.c_str());
        forget_on_interrupt(dir_);
        dir_.clear();
        named_.clear();
    }
    if (f_) {
        std::fclose(f_);
        f_ = nullptr;
    }
    if (!tmp_.empty()) {
        ::unlink(tmp_.c_str());   // ours; whatever stands at path_ is not
        forget_on_interrupt(tmp_);
        tmp_.clear();
    }
}

} // namespace rbcd
