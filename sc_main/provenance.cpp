#include "rbcd/sc_main/provenance.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <systemc>

#include "rbcd/common/sha256.h"
#include "rbcd/sc_main/build_info.h"    // generated at configure time (sc_main/CMakeLists.txt)
#include "rbcd/sc_main/git_describe.h"  // generated at build time

namespace rbcd {

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

nlohmann::json input_info(const ProvenanceInput& in) {
    nlohmann::json j;
    j["role"] = in.role;
    j["path"] = in.path;
    if (in.text) {
        j["size"] = in.text->size();
        j["sha256"] = sha256_hex(*in.text);
        return j;
    }
    // The file was read successfully already; if it cannot be read again (a
    // pipe, or it went away), say so rather than fail the run at its end.
    std::FILE* f = std::fopen(in.path.c_str(), "rb");
    std::error_code ec;
    if (!f || !std::filesystem::is_regular_file(in.path, ec)) {
        if (f) std::fclose(f);
        j["size"] = nullptr;
        j["sha256"] = nullptr;
        j["note"] = f ? "not a regular file" : std::string("cannot read: ") + std::strerror(errno);
        return j;
    }
    Sha256 h;
    std::uint64_t size = 0;
    char buf[1 << 16];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) {
        h.update(buf, n);
        size += n;
    }
    const bool bad = std::ferror(f);
    std::fclose(f);
    j["size"] = size;
    j["sha256"] = bad ? nlohmann::json(nullptr) : nlohmann::json(h.hex_digest());
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
