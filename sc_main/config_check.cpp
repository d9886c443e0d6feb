// rbcd-config-check: rbcd-sim's configuration checks for many configurations in
// one process, for rbcd-sweep (docs/sweeps.md, "Validation"). The same library
// code as `rbcd-sim --dump-config [--config FILE] [--set KEY=VALUE]...`, so the
// same messages and the same effective configuration, without SystemC's start-up
// per configuration (a sweep of 200 points is checked in milliseconds, not seconds).
//
//   stdin:  one JSON array of rbcd-sim arguments a line: ["--config","a.toml","--set","zeb.banks=4"]
//   stdout: one JSON object a line, in order: {"status":0,"config":"<--dump-config text>"}
//           or {"status":2,"error":"<rbcd-sim's one-line message>"} (1: anything else)
// Exit 0 when every line was answered, 2 on a line that is not such an array.
#include <cstdio>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"

namespace {

std::string check(const nlohmann::json& args) {
    using namespace rbcd;
    nlohmann::json out;
    try {
        SimConfig cfg;
        for (std::size_t i = 0; i < args.size(); i += 2) {
            const std::string flag = args[i].get<std::string>();
            if (i + 1 >= args.size()) throw InputError(flag + ": needs a value");
            const std::string value = args[i + 1].get<std::string>();
            if (flag == "--config") apply_config_file(cfg, value);
            else if (flag == "--set") apply_config_set(cfg, value);
            else throw InputError(flag + ": only --config and --set are checked here");
        }
        cfg.validate();
        out = {{"status", 0}, {"config", dump_config_toml(cfg)}};
    } catch (const InputError& e) {
        out = {{"status", 2}, {"error", e.what()}};
    } catch (const std::exception& e) {
        out = {{"status", 1}, {"error", std::string("internal error: ") + e.what()}};
    }
    return out.dump();
}

} // namespace

int main() {
    std::string line;
    unsigned long long n = 0;
    while (std::getline(std::cin, line)) {
        ++n;
        nlohmann::json args = nlohmann::json::parse(line, nullptr, false);
        bool ok = args.is_array();
        for (const auto& a : args) ok = ok && a.is_string();
        if (!ok) {
            std::fprintf(stderr, "rbcd-config-check: <stdin>:%llu: expected a JSON array of strings\n", n);
            return 2;
        }
        std::cout << check(args) << '\n';
    }
    std::cout.flush();
    return std::cout ? 0 : 1;
}
