#include "rbcd/sc_main/provenance.h"

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

#include "rbcd/common/sha256.h"
#include "rbcd/sc_main/build_info.h"    // generated at configure time (sc_main/CMakeLists.txt)
#include "rbcd/sc_main/git_describe.h"  // generated at build time

namespace rbcd {

namespace {

// Large reads: the hash runs at memory speed, so the calls are what cost.
constexpr std::size_t kHashReadBytes = std::size_t(1) << 20;

// The digest as xxhsum -H2 prints it: the canonical (big-endian) bytes in hex.
std::string canonical_hex(XXH128_hash_t h) {
    XXH128_canonical_t c;
    XXH128_canonicalFromHash(&c, h);
    static const char digits[] = "0123456789abcdef";
    std::string s(2 * sizeof c.digest, '0');
    for (std::size_t i = 0; i < sizeof c.digest; ++i) {
        s[2 * i] = digits[c.digest[i] >> 4];
        s[2 * i + 1] = digits[c.digest[i] & 15];
    }
    return s;
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
    return j;
}

std::string version_text() {
    const nlohmann::json b = build_info();
    std::string s = "rbcd-sim " + b["version"].get<std::string>() + "\n";
    s += "git: " + (b["git"].is_null() ? std::string("(not built from a git checkout)") : b["git"].get<std::string>()) + "\n";
    s += "SystemC: " + b["systemc"].get<std::string>() + "\n";
    s += "compiler: " + b["compiler"].get<std::string>() + "\n";
    s += "build type: " + b["build_type"].get<std::string>() + (b["sanitize"].get<bool>() ? " (sanitizers)" : "");
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

nlohmann::json input_info(const ProvenanceInput& in) {
    nlohmann::json j;
    j["role"] = in.role;
    j["path"] = in.path;
    if (in.text) {
        j["size"] = in.text->size();
        j["xxh128"] = xxh128_hex(in.text->data(), in.text->size());
        return j;
    }
    // The file was read successfully already; if it cannot be read again (a
    // pipe, or it went away), say so rather than fail the run at its end.
    const int fd = ::open(in.path.c_str(), O_RDONLY | O_CLOEXEC);
    struct stat st {};
    if (fd < 0 || ::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const int err = errno;
        const bool opened = fd >= 0;
        if (opened) ::close(fd);
        j["size"] = nullptr;
        j["xxh128"] = nullptr;
        j["note"] = opened ? "not a regular file" : std::string("cannot read: ") + std::strerror(err);
        return j;
    }
    ::posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
    XXH3_state_t state;
    XXH3_INITSTATE(&state);
    XXH3_128bits_reset(&state);
    std::uint64_t size = 0;
    bool bad = false;
    const std::unique_ptr<char[]> buf(new char[kHashReadBytes]);
    for (;;) {
        const ssize_t n = ::read(fd, buf.get(), kHashReadBytes);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            bad = n < 0;
            break;
        }
        XXH3_128bits_update(&state, buf.get(), static_cast<std::size_t>(n));
        size += static_cast<std::uint64_t>(n);
    }
    ::close(fd);
    j["size"] = size;
    j["xxh128"] = bad ? nlohmann::json(nullptr) : nlohmann::json(canonical_hex(XXH3_128bits_digest(&state)));
    if (bad) j["note"] = "read error";
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
    j["config_sha256"] = sha256_hex(dump_config_toml(cfg));
    j["inputs"] = nlohmann::json::array();
    for (const auto& in : inputs) j["inputs"].push_back(input_info(in));
    return j;
}

} // namespace rbcd
