// The configuration: bit 0 of the first byte chooses between a configuration
// file (the rest) and --set strings (the rest, one a line). Whatever is
// accepted is dumped, read back and dumped again: the two dumps must match.
#include <string>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"
#include "rbcd/fuzz/fuzz_util.h"

namespace {
void round_trip(const rbcd::SimConfig& cfg) {
    const std::string dump = rbcd::dump_config_toml(cfg);
    rbcd::fuzz::MemFile f(dump.data(), dump.size());
    rbcd::SimConfig again;
    try {
        rbcd::apply_config_file(again, f.path());
    } catch (const rbcd::InputError& e) {
        rbcd::fuzz::finding(std::string("dump does not read back: ") + e.what());
    }
    if (rbcd::dump_config_toml(again) != dump) rbcd::fuzz::finding("dump, read back, dumps differently");
}
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    const bool sets = data[0] & 1;
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    rbcd::SimConfig cfg;
    try {
        if (sets) {
            std::size_t b = 0;
            while (b <= text.size()) {
                std::size_t e = text.find('\n', b);
                if (e == std::string::npos) e = text.size();
                rbcd::apply_config_set(cfg, text.substr(b, e - b));
                b = e + 1;
            }
        } else {
            rbcd::fuzz::MemFile f(text.data(), text.size());
            rbcd::apply_config_file(cfg, f.path());
        }
    } catch (const rbcd::InputError&) {
        return 0;
    }
    try {
        cfg.validate();
    } catch (const rbcd::InputError&) {
    }
    round_trip(cfg);
    return 0;
}
