#include "rbcd/run/provenance.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
// Debian's libxxhash: its *_dispatch entry points pick the widest vector unit
// the CPU has at run time (AVX2 hashes a trace in two thirds of SSE2's time,
// which the portable build would be held to). The state's layout is public
// (XXH_STATIC_LINKING_ONLY), so it lives on the stack.
#define XXH_STATIC_LINKING_ONLY
#include <xxhash.h>
#include <xxh_x86dispatch.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>
#include <systemc>

#include "rbcd/run/part_digest.h"
#include "rbcd/run/build_info.h"    // generated at configure time (run/CMakeLists.txt)
#include "rbcd/run/git_describe.h"  // generated at build time

namespace rbcd {

namespace {

// Large reads: the hash runs at memory speed, so the calls are what cost.
constexpr std::size_t kHashReadBytes = std::size_t(1) << 20;

std::string to_hex(const unsigned char* p, std::size_t n) {
    static const char* const digits = "0123456789abcdef";
    std::string hex;
    hex.reserve(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
        hex += digits[p[i] >> 4];
        hex += digits[p[i] & 15];
    }
    return hex;
}

// The digest as xxhsum -H2 prints it: the canonical (big-endian) bytes in hex.
std::string canonical_hex(XXH128_hash_t h) {
    XXH128_canonical_t c;
    XXH128_canonicalFromHash(&c, h);
    return to_hex(c.digest, sizeof c.digest);
}

} // namespace

nlohmann::json build_info() {
    nlohmann::json j;
    j["program"] = "rbcd-sim";
    j["version"] = RBCD_PROJECT_VERSION;
    const std::string git = RBCD_GIT_DESCRIBE;
    j["git"] = git.empty() ? nlohmann::json(nullptr) : nlohmann::json(git);
    j["systemc"] = sc_core::sc_release();
    j["compiler"] = RBCD_COMPILER;
    j["build_type"] = RBCD_BUILD_TYPE;
    j["sanitize"] = RBCD_SANITIZE_BUILD != 0;
    j["profile_guided"] = RBCD_PGO_BUILD != 0;
    return j;
}

std::string version_text() {
    const nlohmann::json b = build_info();
    std::string s = "rbcd-sim " + b["version"].get<std::string>() + "\n";
    s += "git: " + (b["git"].is_null() ? std::string("(not built from a git checkout)") : b["git"].get<std::string>()) + "\n";
    s += "SystemC: " + b["systemc"].get<std::string>() + "\n";
    s += "compiler: " + b["compiler"].get<std::string>() + "\n";
    s += "build type: " + b["build_type"].get<std::string>() + (b["sanitize"].get<bool>() ? " (sanitizers)" : "") +
         (b["profile_guided"].get<bool>() ? " (profile-guided)" : "");
    return s;   // CLI11 adds the final newline
}

std::string shell_quote(const std::string& w) {
    if (!w.empty() && w.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-+=./:,@%") ==
                          std::string::npos)
        return w;
    std::string q = "'";
    for (char c : w) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}

std::string xxh128_hex(const void* data, std::size_t len) {
    return canonical_hex(XXH3_128bits(data, len));
}

namespace {

// The rest of an open file, from its current offset, into `state`; adds the
// bytes to `size`. False on a read error.
bool hash_rest(int fd, XXH3_state_t& state, std::uint64_t& size) {
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
    const std::unique_ptr<char[]> buf(new char[kHashReadBytes]);
    for (;;) {
        const ssize_t n = ::read(fd, buf.get(), kHashReadBytes);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return n == 0;
        XXH3_128bits_update(&state, buf.get(), static_cast<std::size_t>(n));
        size += static_cast<std::uint64_t>(n);
    }
}

// An input's "size" and "xxh128" from `state` over `size` bytes; after a read
// error, a null digest and the note.
void put_digest(nlohmann::json& j, std::uint64_t size, const XXH3_state_t& state, bool read_ok) {
    j["size"] = size;
    j["xxh128"] = read_ok ? nlohmann::json(canonical_hex(XXH3_128bits_digest(&state))) : nlohmann::json(nullptr);
    if (!read_ok) j["note"] = "read error";
}
// No digest for an input, and why.
void put_no_digest(nlohmann::json& j, const std::string& note) {
    j["size"] = nullptr;
    j["xxh128"] = nullptr;
    j["note"] = note;
}

// A regular file opened for hashing; -1 with `note` set when it is not one or
// cannot be opened.
int open_regular(const std::string& path, std::string& note) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    struct stat st {};
    if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const int err = errno;
        const bool opened = fd >= 0;
        if (opened) ::close(fd);
        note = opened ? "not a regular file" : std::string("cannot read: ") + std::strerror(err);
        return -1;
    }
    return fd;
}

} // namespace

struct ReadDigest::State {
    XXH3_state_t s;
};

std::optional<FileId> file_id(int fd) {
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
    FileId id;
    id.dev = static_cast<std::uint64_t>(st.st_dev);
    id.ino = static_cast<std::uint64_t>(st.st_ino);
    id.size = static_cast<std::uint64_t>(st.st_size);
    id.mtime_ns = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
    return id;
}

ReadDigest::ReadDigest() : st_(std::make_unique<State>()) {
    XXH3_INITSTATE(&st_->s);
    XXH3_128bits_reset(&st_->s);
}

ReadDigest::~ReadDigest() = default;

void ReadDigest::file(int fd) { id_ = file_id(fd); }

void ReadDigest::raw(const void* bytes, std::size_t n) {
    XXH3_128bits_update(&st_->s, bytes, n);
    bytes_ += n;
}

bool ReadDigest::finish(const std::string& path, nlohmann::json& j) const {
    if (!whole_) return false;
    XXH3_state_t s;
    XXH3_copyState(&s, &st_->s);
    if (complete_) {
        // Every byte the run read, to the end: nothing to read again (the
        // file may have gone, or been replaced, since).
        put_digest(j, bytes_, s, true);
        return true;
    }
    if (path == "-") {
        put_no_digest(j, "standard input, not read to its end");
        return true;
    }
    std::string note;
    const int fd = open_regular(path, note);
    if (fd < 0) return false;
    if (id_ && file_id(fd) != id_) {
        ::close(fd);
        put_no_digest(j, "the file was replaced or rewritten during the run");
        return true;
    }
    std::uint64_t size = bytes_;
    const bool ok = ::lseek(fd, static_cast<off_t>(bytes_), SEEK_SET) >= 0 && hash_rest(fd, s, size);
    ::close(fd);
    put_digest(j, size, s, ok);
    return true;
}

std::optional<FileId> file_id_at(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return std::nullopt;
    const std::optional<FileId> id = file_id(fd);
    ::close(fd);
    return id;
}

nlohmann::json input_info(const ProvenanceInput& in) {
    nlohmann::json j;
    j["role"] = in.role;
    j["path"] = in.path;
    if (in.text) {
        j["size"] = in.text->size();
        j["xxh128"] = xxh128_hex(in.text->data(), in.text->size());
        return j;
    }
    if (in.split) {
        const FileDigest d = digest_from_parts(in.path, *in.split);
        if (d.hex.empty()) put_no_digest(j, d.note);
        else {
            j["size"] = d.size;
            j["xxh128"] = d.hex;
        }
        return j;
    }
    if (in.read && in.read->finish(in.path, j)) return j;
    if (in.path == "-") {
        // Read once, by the run: nothing to hash again.
        put_no_digest(j, "standard input");
        return j;
    }
    std::uint64_t size = 0;
    // The file was read successfully already; if it cannot be read again (a
    // pipe, or it went away), say so rather than fail the run at its end.
    std::string note;
    const int fd = open_regular(in.path, note);
    if (fd < 0) {
        put_no_digest(j, note);
        return j;
    }
    const auto replaced = [&] { return in.expected && file_id(fd) != in.expected; };
    if (replaced()) {
        ::close(fd);
        put_no_digest(j, "the file was replaced or rewritten during the run");
        return j;
    }
    XXH3_state_t state;
    XXH3_INITSTATE(&state);
    XXH3_128bits_reset(&state);
    const bool good = hash_rest(fd, state, size);
    const bool rewritten = replaced();
    ::close(fd);
    if (rewritten) put_no_digest(j, "the file was replaced or rewritten during the run");
    else put_digest(j, size, state, good);
    return j;
}

std::string command_line(const std::vector<std::string>& argv) {
    std::string line;
    for (const auto& a : argv) line += (line.empty() ? "" : " ") + shell_quote(a);
    return line;
}

std::vector<std::string> option_values(const std::vector<std::string>& argv,
                                       std::initializer_list<const char*> options) {
    std::vector<std::string> values;
    for (std::size_t i = 1; i < argv.size(); ++i) {
        for (const char* o : options) {
            const std::string opt = o;
            if (argv[i] == opt && i + 1 < argv.size()) values.push_back(argv[i + 1]);
            else if (argv[i].rfind(opt + "=", 0) == 0) values.push_back(argv[i].substr(opt.size() + 1));
        }
    }
    return values;
}

nlohmann::json make_provenance(const std::vector<std::string>& argv, const SimConfig& cfg,
                               const std::vector<ProvenanceInput>& inputs) {
    nlohmann::json j;
    j["build"] = build_info();
    j["command_line"] = command_line(argv);
    j["argv"] = argv;
    std::error_code ec;
    const auto cwd = std::filesystem::current_path(ec);
    j["working_directory"] = ec ? nlohmann::json(nullptr) : nlohmann::json(cwd.string());
    const std::string config = dump_config_toml(cfg);
    j["config_xxh128"] = xxh128_hex(config.data(), config.size());
    j["inputs"] = nlohmann::json::array();
    for (const auto& in : inputs) j["inputs"].push_back(input_info(in));
    return j;
}

} // namespace rbcd
