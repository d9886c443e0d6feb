// Where a result came from (docs/provenance.md): the build (--version), and for
// stats.json the command line, the effective configuration's hash and every
// input file's size and hash, so that a results table can be traced back.
#pragma once
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/common/config.h"
#include "rbcd/io/gzip_stream.h"

namespace rbcd {

// {"program", "version", "git", "systemc", "compiler", "build_type", "sanitize"};
// "git" is null when the build did not come from a git checkout.
nlohmann::json build_info();
// The text `rbcd-sim --version` prints: one "key: value" line per field.
std::string version_text();

// A word as a POSIX shell reads it back: unchanged when it holds only safe
// characters, otherwise in single quotes.
std::string shell_quote(const std::string& word);

// argv as one line a POSIX shell reads back: the words shell_quote()d, joined by spaces.
std::string command_line(const std::vector<std::string>& argv);

// The values OPTION takes on a command line ("--x V" or "--x=V"), for any of
// `options`, in order; found without CLI11, on a command line that was only
// recorded (a part's provenance, which rbcd-merge reads).
std::vector<std::string> option_values(const std::vector<std::string>& argv,
                                       std::initializer_list<const char*> options);

// A regular file as read: a different one at the path later means it was
// replaced or rewritten.
struct FileId {
    std::uint64_t dev = 0, ino = 0, size = 0;
    std::int64_t mtime_ns = 0;
    bool operator==(const FileId& o) const {
        return dev == o.dev && ino == o.ino && size == o.size && mtime_ns == o.mtime_ns;
    }
    bool operator!=(const FileId& o) const { return !(*this == o); }
};
// The file open at `fd`, when it is a regular one.
std::optional<FileId> file_id(int fd);

// A file's XXH3-128 state over the bytes its reader read, from its first, as
// they passed (a RawObserver given to the reader): the provenance goes on from
// there and reads only what the reader did not (nothing, when it read to the
// end), instead of reading the whole file a second time.
class ReadDigest final : public RawObserver {
public:
    ReadDigest();
    ~ReadDigest() override;
    ReadDigest(const ReadDigest&) = delete;
    ReadDigest& operator=(const ReadDigest&) = delete;
    void file(int fd) override;
    void raw(const void* bytes, std::size_t n) override;
    void end() override { complete_ = true; }
    void gap(std::uint64_t) override { whole_ = false; }
    // The bytes seen run unbroken from the file's start.
    bool usable() const { return whole_; }
    std::uint64_t bytes() const { return bytes_; }
    // input_info's "size" and "xxh128" (or a null digest and a "note") for
    // the file at `path`: this state, then the file's bytes from bytes() on;
    // nothing read again when the reader read to the end. False when this
    // state cannot serve (a gap, or the file cannot be opened): hash it whole.
    bool finish(const std::string& path, nlohmann::json& j) const;

private:
    struct State;
    std::unique_ptr<State> st_;
    std::uint64_t bytes_ = 0;
    bool whole_ = true, complete_ = false;
    // The file read (a regular file's): a different one at the path when the
    // hash goes on means it was replaced or rewritten during the run.
    std::optional<FileId> id_;
};

struct SplitDigest;   // run/part_digest.h

// An input as it was read: role ("trace", "scene", "mesh", "config"), path and,
// for a file, its size in bytes and XXH3-128 digest. `text` set: an embedded
// input (the default scene) hashed from memory. `read` set: the file as its
// reader read it (ReadDigest), hashed on from there. `split` set: the file as
// rbcd-sim --jobs's workers read it, in parts, joined.
struct ProvenanceInput {
    std::string role, path;
    const std::string* text = nullptr;
    const ReadDigest* read = nullptr;
    const SplitDigest* split = nullptr;
    // The file as the run found it, for a file hashed again by name after it
    // was read (--jobs on a gzip trace, --frames): another file there by then
    // (renamed over it, rewritten) gets no digest and a note, not its own.
    std::optional<FileId> expected = std::nullopt;
};
// The file at `path` now, when it is a regular one.
std::optional<FileId> file_id_at(const std::string& path);
nlohmann::json input_info(const ProvenanceInput& in);

// An input's or the configuration's digest: XXH3-128 (libxxhash), 32
// lower-case hex digits, as `xxhsum -H2` prints it. Not SHA-256: a trace of
// gigabytes is hashed on every run, and SHA-256 (1.7 GB/s with the x86 SHA
// extensions) cost as much CPU as parsing the trace (docs/provenance.md).
std::string xxh128_hex(const void* data, std::size_t len);

// The "provenance" object of stats.json: {"build": build_info(), "command_line",
// "argv", "working_directory", "config_xxh128" (of dump_config_toml(cfg)),
// "inputs": [input_info...]}.
nlohmann::json make_provenance(const std::vector<std::string>& argv, const SimConfig& cfg,
                               const std::vector<ProvenanceInput>& inputs);

} // namespace rbcd
