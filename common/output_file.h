// An output that appears at its path only when the run succeeds (formats.md: on
// any non-zero exit no file is left at an output path, not even an older one).
//
// A path that is a regular file or does not exist yet is written through a
// temporary beside it: created by mkstemp (unpredictable name, O_EXCL, so a
// planted symlink is never followed), renamed over the path on commit, removed
// on failure. Anything else at the path (a device, a FIFO, a socket, a symlink,
// /dev/stdout, or "-" for standard output) is written in place: opened as it
// is, never unlinked, never replaced by a regular file. docs/limits.md.
#pragma once
#include <signal.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

namespace rbcd {

// Removes a regular file left at an output path by an earlier run; anything
// else there (directory, device, FIFO, symlink) is left alone.
void discard_output(const std::string& path);
// On SIGINT, SIGTERM, SIGHUP or SIGPIPE the path is unlinked before the process exits.
// Call before the simulation starts.
void remove_on_interrupt(const std::string& path);
// A child process that writes into such paths: on those signals it is sent
// SIGTERM and waited for before the paths are removed.
void stop_on_interrupt(int pid);
// The process has ended (waited for, not yet reaped): no longer signalled.
void forget_child(int pid);
// In a process just forked from one that registered paths and children: none
// of them is its own to remove or stop.
void forget_parents_cleanup();
// SIGINT, SIGTERM, SIGHUP and SIGPIPE (the signals above) held back on this thread for
// the object's life: between creating a temporary or a worker and registering
// it, where a signal would leave it behind; a thread started meanwhile keeps
// them blocked.
class InterruptsHeld {
public:
    InterruptsHeld();
    ~InterruptsHeld();
    InterruptsHeld(const InterruptsHeld&) = delete;
    InterruptsHeld& operator=(const InterruptsHeld&) = delete;
    // The mask before: what a child should start with.
    const sigset_t& previous() const { return old_; }

private:
    sigset_t old_;
};
// No longer: the path is gone.
void forget_on_interrupt(const std::string& path);
// An output renamed into place (OutputFile::commit) is removed on an
// interrupt as its temporary was, in its place in the list: outputs stand
// one by one, and a run interrupted before the last leaves none of them.
void result_stands(const std::string& temporary, const std::string& path);
// Every output stands complete: from now on the interrupt handler does
// nothing, so that a signal (SIGPIPE from a summary on a closed pipe, a late
// SIGTERM) neither removes a finished run's outputs nor says it failed.
void outputs_complete();
// A file-size limit (ulimit -f) fails the write that crosses it (EFBIG, "File
// too large", reported and cleaned up as any failed write) instead of killing
// the program with SIGXFSZ, which leaves its temporaries behind. Every
// program that writes OutputFiles calls it first; children inherit it.
void report_file_size_limit_as_write_error();
// Both paths exist and name the same file.
bool same_file(const std::string& a, const std::string& b);
// After a failed run: discard_output() for every output path that is not one
// of the inputs (an output named like an input is the input, left alone).
void discard_outputs(const std::vector<std::string>& outputs, const std::vector<std::string>& inputs);

// Before any output is opened (opening removes an older regular file): throws
// InputError "FLAG: PATH is the input file INPUT" when an output names one of
// the inputs, and "FLAG: PATH is also FLAG2's output" when two outputs would
// land in the same regular file (or the same new path). Outputs written in
// place (a device, a FIFO, "-") may be shared. Entries with an empty path are
// skipped.
struct NamedPath {
    std::string flag, path;
};
void check_output_paths(const std::vector<NamedPath>& outputs, const std::vector<NamedPath>& inputs);

class OutputFile {
public:
    OutputFile() = default;
    // Opens the temporary (or the path in place); throws InputError naming the
    // path when it cannot.
    explicit OutputFile(std::string path);
    // For a library that opens its file by name and keeps companions beside it
    // (fstapi's NAME.hier, SQLite's NAME-journal): a private directory (mkdtemp,
    // mode 0700) beside the path holds the file, library_path() names it;
    // commit() renames it over the path and removes the directory with whatever
    // else the library left there. Such writers seek and rename, so the path
    // must be a regular file or new: anything else is an InputError.
    struct ByName {};
    OutputFile(std::string path, ByName);
    ~OutputFile();
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;
    OutputFile(OutputFile&& o) noexcept;
    OutputFile& operator=(OutputFile&& o) noexcept;

    bool active() const { return f_ != nullptr || !dir_.empty(); }
    bool in_place() const { return in_place_; }
    const std::string& path() const { return path_; }
    // A path naming the open file itself (/proc/self/fd/N), for writers that
    // open their own stream by name; what they write is committed with this.
    std::string open_file_path() const;
    // ByName: the file the library creates (empty otherwise).
    const std::string& library_path() const { return named_; }
    void write(const std::string& s) { write(s.data(), s.size()); }
    void write(const char* p, std::size_t n);
    // Appends the rest of the regular file open at `fd`, from byte `offset` to
    // its end, as write() would: read and written in 256 KiB chunks, or by
    // copy_file_range on a network file system that copies on the server.
    // Returns the bytes appended; throws RunError naming `what` when `fd`
    // cannot be read.
    std::uint64_t append_from(int fd, std::uint64_t offset, const std::string& what);
    // The open file's descriptor, flushed, for another process to write into
    // before this one writes more (-1 for ByName). Whatever it writes lands
    // where write() would have, and write() goes on after it: the two share
    // the file's offset.
    int shared_fd();
    // Flush, close, rename over the path (in place: flush and close). Throws
    // RunError on I/O errors.
    void commit();
    // The name its errors give: a --jobs worker writes its collisions into
    // the run's output as its standard output ("-"), whose errors are the
    // user's file's.
    void show_as(std::string name) { shown_ = std::move(name); }
    // Removes the temporary this run created; nothing else.
    void abandon();

private:
    const std::string& shown() const { return shown_.empty() ? path_ : shown_; }
    std::string path_, tmp_, shown_;
    std::string dir_, named_;   // ByName
    std::FILE* f_ = nullptr;
    bool in_place_ = false;
    bool failed_ = false;
    int failed_errno_ = 0;   // the first failure's
    void fail_with(int err);
};

} // namespace rbcd
