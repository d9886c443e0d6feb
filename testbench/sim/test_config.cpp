// The configuration layer (common/config.*) against formats.md "Command line"
// and rbcd-contract.md "Ranges": defaults, every fixed key by TOML file and by
// --set, the --set rules, every kind of bad key or value with a message that
// names the key (and file:line for files), the cross-key checks of validate(),
// and the --dump-config round trip.
#include <catch2/catch.hpp>

#include "rbcd/testbench/common/temp_dir.h"

#include <stdlib.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "rbcd/common/config.h"
#include "rbcd/common/errors.h"

using namespace rbcd;
using Catch::Matchers::Contains;
using Catch::Matchers::StartsWith;
namespace fs = std::filesystem;

namespace {

struct TempDir : rbcd::test::TempDir {
    TempDir() : rbcd::test::TempDir("rbcd_config_test") {}
};

const ConfigKey& key(const std::string& name) {
    for (const auto& k : config_keys())
        if (k.name == name) return k;
    FAIL("no configuration key " << name);
    throw 0;   // not reached
}

std::string value_of(const SimConfig& cfg, const std::string& name) { return key(name).to_toml(cfg); }

// The message of the InputError that f throws; fails the test if it throws
// nothing or something else.
template <class F>
std::string input_error(F&& f) {
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    } catch (const std::exception& e) {
        FAIL("expected InputError, got another exception: " << e.what());
    }
    FAIL("expected InputError, nothing was thrown");
    return {};
}

// One line, no line break inside: what rbcd-sim prints as-is after "rbcd-sim: ".
void check_one_line(const std::string& msg) {
    INFO(msg);
    CHECK(!msg.empty());
    CHECK(msg.find('\n') == std::string::npos);
}

std::string set_error(const std::string& assignment) {
    SimConfig cfg;
    INFO("--set " << assignment);
    std::string msg = input_error([&] { apply_config_set(cfg, assignment); });
    check_one_line(msg);
    return msg;
}

std::string file_error(const TempDir& td, const std::string& text) {
    SimConfig cfg;
    const std::string p = td.write("bad.toml", text);
    INFO("file:\n" << text);
    std::string msg = input_error([&] { apply_config_file(cfg, p); });
    check_one_line(msg);
    return msg;
}

// "[sec]\nname = value\n" for "sec.name"; the value line is line 2.
std::string toml_for(const std::string& dotted, const std::string& value) {
    auto dot = dotted.find('.');
    return "[" + dotted.substr(0, dot) + "]\n" + dotted.substr(dot + 1) + " = " + value + "\n";
}

struct Ranged {
    const char* name;
    std::uint64_t lo, hi;
};
// rbcd-contract.md, "Ranges".
const Ranged kRanged[] = {
    {"tile.width", 1, 256},     {"tile.height", 1, 256},        {"zeb.banks", 1, 16},
    {"zeb.list_length", 1, 64}, {"tester.stack_depth", 1, 64}, {"zeb.z_bits", 1, 32},
    {"zeb.id_bits", 1, 16},
};

// A valid non-default value for every fixed key, with where it must land.
struct FixedCase {
    const char* name;
    const char* toml;                          // the value as TOML
    std::function<bool(const SimConfig&)> landed;
};
std::vector<FixedCase> fixed_cases() {
    return {
        {"tile.width", "8", [](const SimConfig& c) { return c.tile.width == 8; }},
        {"tile.height", "4", [](const SimConfig& c) { return c.tile.height == 4; }},
        {"zeb.banks", "3", [](const SimConfig& c) { return c.zeb.banks == 3; }},
        {"zeb.list_length", "5", [](const SimConfig& c) { return c.zeb.list_length == 5; }},
        {"zeb.z_bits", "16", [](const SimConfig& c) { return c.zeb.z_bits == 16; }},
        {"zeb.id_bits", "12", [](const SimConfig& c) { return c.zeb.id_bits == 12; }},
        {"zeb.tie", "\"arrival\"", [](const SimConfig& c) { return c.zeb.tie == TiePolicy::Arrival; }},
        {"tester.stack_depth", "3", [](const SimConfig& c) { return c.tester.stack_depth == 3; }},
        {"tester.output", "\"pixel\"", [](const SimConfig& c) { return c.tester.output == OutputMode::Pixel; }},
        {"tester.output", "\"tile\"", [](const SimConfig& c) { return c.tester.output == OutputMode::Tile; }},
    };
}

// Choices of an enum key, from its unit text "a | b | c".
std::vector<std::string> enum_choices(const ConfigKey& k) {
    std::vector<std::string> out;
    std::string s = k.unit;
    std::size_t pos = 0;
    while (pos <= s.size()) {
        std::size_t bar = s.find(" | ", pos);
        out.push_back(s.substr(pos, bar == std::string::npos ? std::string::npos : bar - pos));
        if (bar == std::string::npos) break;
        pos = bar + 3;
    }
    return out;
}

} // namespace

TEST_CASE("config: defaults") {
    const SimConfig c;
    CHECK(c.tile.width == 16);
    CHECK(c.tile.height == 16);
    CHECK(c.zeb.banks == 2);
    CHECK(c.zeb.list_length == 8);
    CHECK(c.zeb.z_bits == 24);
    CHECK(c.zeb.id_bits == 7);
    CHECK(c.zeb.tie == TiePolicy::FrontFirst);
    CHECK(c.tester.stack_depth == 8);
    CHECK(c.tester.output == OutputMode::Raw);
    CHECK(c.sorter.hazard == HazardPolicy::Forward);
    CHECK(c.memory.latency_min <= c.memory.latency_max);
    CHECK_NOTHROW(c.validate());

    CHECK(value_of(c, "tile.width") == "16");
    CHECK(value_of(c, "tile.height") == "16");
    CHECK(value_of(c, "zeb.banks") == "2");
    CHECK(value_of(c, "zeb.list_length") == "8");
    CHECK(value_of(c, "zeb.z_bits") == "24");
    CHECK(value_of(c, "zeb.id_bits") == "7");
    CHECK(value_of(c, "zeb.tie") == "\"front_first\"");
    CHECK(value_of(c, "tester.stack_depth") == "8");
    CHECK(value_of(c, "tester.output") == "\"raw\"");
}

TEST_CASE("config: key registry holds every fixed key once with its type") {
    const std::map<std::string, std::string> fixed = {
        {"tile.width", "integer"},      {"tile.height", "integer"}, {"zeb.banks", "integer"},
        {"zeb.list_length", "integer"}, {"zeb.z_bits", "integer"},  {"zeb.id_bits", "integer"},
        {"zeb.tie", "string"},          {"tester.stack_depth", "integer"}, {"tester.output", "string"},
    };
    std::map<std::string, int> seen;
    for (const auto& k : config_keys()) {
        ++seen[k.name];
        INFO(k.name);
        CHECK(k.name.find('.') != std::string::npos);
        CHECK(k.set);
        CHECK(k.to_toml);
    }
    for (const auto& [name, n] : seen) {
        INFO(name);
        CHECK(n == 1);
    }
    for (const auto& [name, type] : fixed) {
        INFO(name);
        REQUIRE(seen.count(name) == 1);
        CHECK(key(name).type == type);
    }
}

TEST_CASE("config: every fixed key set by --set") {
    for (const auto& fc : fixed_cases()) {
        SimConfig cfg;
        const std::string a = std::string(fc.name) + "=" + fc.toml;
        INFO("--set " << a);
        REQUIRE_NOTHROW(apply_config_set(cfg, a));
        CHECK(fc.landed(cfg));
        CHECK(value_of(cfg, fc.name) == fc.toml);
    }
}

TEST_CASE("config: every fixed key set by TOML file") {
    TempDir td;
    for (const auto& fc : fixed_cases()) {
        SimConfig cfg;
        const std::string text = toml_for(fc.name, fc.toml);
        INFO(text);
        const std::string p = td.write("ok.toml", text);
        REQUIRE_NOTHROW(apply_config_file(cfg, p));
        CHECK(fc.landed(cfg));
        CHECK(value_of(cfg, fc.name) == fc.toml);
    }
}

TEST_CASE("config: all fixed keys in one TOML file with dotted and table forms") {
    TempDir td;
    const std::string p = td.write("all.toml",
                                   "# every fixed key\n"
                                   "tile.width = 8\n"
                                   "tile.height = 4\n"
                                   "[zeb]\n"
                                   "banks = 3\n"
                                   "list_length = 5\n"
                                   "z_bits = 16\n"
                                   "id_bits = 12\n"
                                   "tie = 'arrival'\n"
                                   "[tester]\n"
                                   "stack_depth = 3\n"
                                   "output = \"tile\"\n");
    SimConfig cfg;
    REQUIRE_NOTHROW(apply_config_file(cfg, p));
    CHECK(cfg.tile.width == 8);
    CHECK(cfg.tile.height == 4);
    CHECK(cfg.zeb.banks == 3);
    CHECK(cfg.zeb.list_length == 5);
    CHECK(cfg.zeb.z_bits == 16);
    CHECK(cfg.zeb.id_bits == 12);
    CHECK(cfg.zeb.tie == TiePolicy::Arrival);
    CHECK(cfg.tester.stack_depth == 3);
    CHECK(cfg.tester.output == OutputMode::Tile);
    CHECK_NOTHROW(cfg.validate());
}

TEST_CASE("config: every key accepts its own default by --set and by file") {
    TempDir td;
    const SimConfig def;
    for (const auto& k : config_keys()) {
        INFO(k.name);
        const std::string v = k.to_toml(def);
        SimConfig a;
        REQUIRE_NOTHROW(apply_config_set(a, k.name + "=" + v));
        CHECK(k.to_toml(a) == v);
        SimConfig b;
        REQUIRE_NOTHROW(apply_config_file(b, td.write("k.toml", toml_for(k.name, v))));
        CHECK(k.to_toml(b) == v);
    }
}

TEST_CASE("config: --set applies in order and the last one wins") {
    SimConfig cfg;
    apply_config_set(cfg, "zeb.list_length=4");
    apply_config_set(cfg, "zeb.list_length=5");
    CHECK(cfg.zeb.list_length == 5);
    apply_config_set(cfg, "zeb.tie=arrival");
    apply_config_set(cfg, "zeb.tie=front_first");
    CHECK(cfg.zeb.tie == TiePolicy::FrontFirst);
    apply_config_set(cfg, "zeb.list_length=3");
    CHECK(cfg.zeb.list_length == 3);
}

TEST_CASE("config: --set after --config overrides the file and keeps its other keys") {
    TempDir td;
    const std::string p = td.write("c.toml", "[zeb]\nlist_length = 4\nbanks = 5\n[tester]\nstack_depth = 2\n");
    SimConfig cfg;
    apply_config_file(cfg, p);
    apply_config_set(cfg, "zeb.list_length=6");
    CHECK(cfg.zeb.list_length == 6);
    CHECK(cfg.zeb.banks == 5);
    CHECK(cfg.tester.stack_depth == 2);
}

TEST_CASE("config: a failed --set leaves the key unchanged") {
    SimConfig cfg;
    apply_config_set(cfg, "zeb.list_length=4");
    CHECK_THROWS_AS(apply_config_set(cfg, "zeb.list_length=65"), InputError);
    CHECK(cfg.zeb.list_length == 4);
}

TEST_CASE("config: string keys take a bare word or a TOML string in --set") {
    SimConfig cfg;
    apply_config_set(cfg, "zeb.tie=arrival");
    CHECK(cfg.zeb.tie == TiePolicy::Arrival);
    apply_config_set(cfg, "zeb.tie=\"front_first\"");
    CHECK(cfg.zeb.tie == TiePolicy::FrontFirst);
    apply_config_set(cfg, "zeb.tie='arrival'");
    CHECK(cfg.zeb.tie == TiePolicy::Arrival);
    apply_config_set(cfg, "tester.output=pixel");
    CHECK(cfg.tester.output == OutputMode::Pixel);
    apply_config_set(cfg, "tester.output=\"tile\"");
    CHECK(cfg.tester.output == OutputMode::Tile);
    apply_config_set(cfg, "tester.output=raw");
    CHECK(cfg.tester.output == OutputMode::Raw);
    apply_config_set(cfg, "sorter.hazard=stall");
    CHECK(cfg.sorter.hazard == HazardPolicy::Stall);
}

TEST_CASE("config: integer keys take no bare word in --set") {
    for (const char* a : {"zeb.list_length=four", "tile.width=abc", "zeb.banks=x2", "tester.stack_depth=eight"}) {
        const std::string msg = set_error(a);
        const std::string name = std::string(a).substr(0, std::string(a).find('='));
        CHECK_THAT(msg, Contains(name));
    }
}

TEST_CASE("config: malformed --set assignments") {
    CHECK_THAT(set_error("zeb.list_length"), Contains("zeb.list_length"));
    set_error("=4");
    CHECK_THAT(set_error("zeb.list_length="), Contains("zeb.list_length"));
    CHECK_THAT(set_error("zeb.tie="), Contains("zeb.tie"));
    CHECK_THAT(set_error("zeb.list_length=4 5"), Contains("zeb.list_length"));
}

TEST_CASE("config: unknown key in --set names the key") {
    for (const char* k : {"zeb.bogus", "bogus.x", "bogus", "zeb", "tile.width.x", "Tile.width"}) {
        const std::string msg = set_error(std::string(k) + "=1");
        CHECK_THAT(msg, Contains(k));
    }
}

TEST_CASE("config: unknown key in a file names the key and file:line") {
    TempDir td;
    const std::string p = td.path("bad.toml");
    {
        const std::string msg = file_error(td, "[zeb]\nlist_length = 4\nbogus = 1\n");
        CHECK_THAT(msg, StartsWith(p + ":3"));
        CHECK_THAT(msg, Contains("zeb.bogus"));
    }
    {
        const std::string msg = file_error(td, "# comment\n[bogus]\nx = 1\n");
        CHECK_THAT(msg, StartsWith(p + ":3"));
        CHECK_THAT(msg, Contains("bogus.x"));
    }
    {
        const std::string msg = file_error(td, "bogus = 1\n");
        CHECK_THAT(msg, StartsWith(p + ":1"));
        CHECK_THAT(msg, Contains("bogus"));
    }
    {
        const std::string msg = file_error(td, "\n\nzeb.bogus = 2\n");
        CHECK_THAT(msg, StartsWith(p + ":3"));
        CHECK_THAT(msg, Contains("zeb.bogus"));
    }
    {
        // A key given as a table where a value belongs.
        const std::string msg = file_error(td, "[zeb.list_length]\nx = 1\n");
        CHECK_THAT(msg, StartsWith(p + ":2"));
        CHECK_THAT(msg, Contains("zeb.list_length.x"));
    }
    {
        // A section name that is a key, given a value.
        const std::string msg = file_error(td, "\nzeb = 4\n");
        CHECK_THAT(msg, StartsWith(p + ":2"));
        CHECK_THAT(msg, Contains("zeb"));
    }
}

TEST_CASE("config: wrong value type names the key") {
    const std::vector<std::string> cases = {
        "zeb.list_length=\"4\"", "zeb.list_length=4.0",  "zeb.list_length=true", "zeb.list_length=[4]",
        "tile.width=1e1",        "tile.height='16'",     "zeb.tie=4",            "zeb.tie=1.5",
        "zeb.tie=true",          "tester.output=1",      "tester.stack_depth=2.5", "zeb.id_bits=\"7\"",
        "clock.mhz=\"400\"",
    };
    for (const auto& a : cases) {
        const std::string msg = set_error(a);
        CHECK_THAT(msg, Contains(a.substr(0, a.find('='))));
    }
}

TEST_CASE("config: wrong value type in a file names the key and file:line") {
    TempDir td;
    const std::string p = td.path("bad.toml");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"zeb.list_length", "\"4\""}, {"zeb.list_length", "4.0"}, {"tile.width", "true"},
        {"zeb.tie", "4"},             {"tester.output", "2.5"},   {"tester.stack_depth", "'8'"},
    };
    for (const auto& [k, v] : cases) {
        const std::string msg = file_error(td, toml_for(k, v));
        CHECK_THAT(msg, StartsWith(p + ":2"));
        CHECK_THAT(msg, Contains(k));
    }
}

TEST_CASE("config: every ranged key at both bounds and one beyond by --set") {
    for (const auto& r : kRanged) {
        INFO(r.name);
        for (std::uint64_t v : {r.lo, r.hi}) {
            SimConfig cfg;
            REQUIRE_NOTHROW(apply_config_set(cfg, std::string(r.name) + "=" + std::to_string(v)));
            CHECK(value_of(cfg, r.name) == std::to_string(v));
        }
        for (std::uint64_t v : {r.lo - 1, r.hi + 1}) {
            const std::string msg = set_error(std::string(r.name) + "=" + std::to_string(v));
            CHECK_THAT(msg, Contains(r.name));
        }
        // Negative numbers and ones far beyond 64 bits are out of range too.
        CHECK_THAT(set_error(std::string(r.name) + "=-1"), Contains(r.name));
        CHECK_THAT(set_error(std::string(r.name) + "=4294967297"), Contains(r.name));
    }
}

TEST_CASE("config: every ranged key at both bounds and one beyond by file") {
    TempDir td;
    const std::string p = td.path("bad.toml");
    for (const auto& r : kRanged) {
        INFO(r.name);
        for (std::uint64_t v : {r.lo, r.hi}) {
            SimConfig cfg;
            REQUIRE_NOTHROW(apply_config_file(cfg, td.write("ok.toml", toml_for(r.name, std::to_string(v)))));
            CHECK(value_of(cfg, r.name) == std::to_string(v));
        }
        for (std::uint64_t v : {r.lo - 1, r.hi + 1}) {
            const std::string msg = file_error(td, toml_for(r.name, std::to_string(v)));
            CHECK_THAT(msg, StartsWith(p + ":2"));
            CHECK_THAT(msg, Contains(r.name));
        }
    }
}

TEST_CASE("config: unknown enum value names the key and the value") {
    TempDir td;
    const std::string p = td.path("bad.toml");
    for (const char* k : {"zeb.tie", "tester.output", "sorter.hazard"}) {
        INFO(k);
        const std::string msg = set_error(std::string(k) + "=bogus");
        CHECK_THAT(msg, Contains(k));
        CHECK_THAT(msg, Contains("bogus"));
        CHECK_THAT(set_error(std::string(k) + "=\"Raw\""), Contains(k));
        const std::string fmsg = file_error(td, toml_for(k, "\"bogus\""));
        CHECK_THAT(fmsg, StartsWith(p + ":2"));
        CHECK_THAT(fmsg, Contains(k));
        CHECK_THAT(fmsg, Contains("bogus"));
    }
}

TEST_CASE("config: TOML syntax error gives file:line") {
    TempDir td;
    const std::string p = td.path("bad.toml");
    CHECK_THAT(file_error(td, "[zeb]\nlist_length = = 4\n"), StartsWith(p + ":2"));
    CHECK_THAT(file_error(td, "# a\n# b\n[zeb\nbanks = 2\n"), StartsWith(p + ":3"));
    // A bare word is not a TOML string in a file.
    CHECK_THAT(file_error(td, "[zeb]\nbanks = 2\ntie = arrival\n"), StartsWith(p + ":3"));
    // The same key twice is a TOML error too.
    CHECK_THAT(file_error(td, "[zeb]\nbanks = 2\nbanks = 3\n"), StartsWith(p + ":3"));
}

TEST_CASE("config: missing config file names the file") {
    TempDir td;
    const std::string p = td.path("nonexistent.toml");
    SimConfig cfg;
    const std::string msg = input_error([&] { apply_config_file(cfg, p); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains(p));
}

TEST_CASE("config: validate accepts the limits of the cross-key checks") {
    SimConfig c;
    c.memory.latency_min = c.memory.latency_max = 70;
    CHECK_NOTHROW(c.validate());
    c = SimConfig{};
    c.output.burst_records = c.output.buffer_records = 8;
    CHECK_NOTHROW(c.validate());
    c = SimConfig{};
    c.output.region_bytes = std::uint64_t(c.output.burst_records) * 16;
    CHECK_NOTHROW(c.validate());
    c = SimConfig{};
    // Double-buffered by default: two regions back to back.
    c.output.region_offset = c.memory.size_bytes - 2 * c.output.region_bytes;
    CHECK_NOTHROW(c.validate());
    c.output.region_offset += 16;
    CHECK_THROWS(c.validate());
    c.output.double_buffer = false;
    c.output.region_offset = c.memory.size_bytes - c.output.region_bytes;
    CHECK_NOTHROW(c.validate());
}

TEST_CASE("config: validate rejects latency_min above latency_max") {
    SimConfig c;
    c.memory.latency_min = 101;
    c.memory.latency_max = 100;
    const std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("memory.latency_min"));
}

TEST_CASE("config: validate rejects a burst bigger than the buffer") {
    SimConfig c;
    c.output.buffer_records = 4;
    c.output.burst_records = 5;
    const std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("output.burst_records"));
}

TEST_CASE("config: validate rejects a region not a multiple of 16 bytes") {
    SimConfig c;
    c.output.region_bytes = 65536 + 8;
    const std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("output.region_bytes"));
}

TEST_CASE("config: validate rejects a region smaller than one burst") {
    SimConfig c;
    c.output.burst_records = 4;
    c.output.region_bytes = 48;
    const std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("output.region_bytes"));
}

TEST_CASE("config: validate rejects a region outside the memory") {
    SimConfig c;
    c.output.region_offset = c.memory.size_bytes - c.output.region_bytes + 16;
    std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("output.region"));

    c = SimConfig{};
    c.memory.size_bytes = 4096;
    c.output.region_bytes = 8192;
    msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    CHECK_THAT(msg, Contains("output.region"));
}

// What validate() says of a configuration whose fields were set in C++.
template <class Mutate>
std::string cpp_error(Mutate&& mutate) {
    SimConfig c;
    mutate(c);
    std::string msg = input_error([&] { c.validate(); });
    check_one_line(msg);
    return msg;
}

// The reason in the error the --set path gives ("--set KEY: KEY: REASON").
std::string set_reason(const std::string& key, const std::string& value) {
    const std::string msg = set_error(key + "=" + value);
    const std::string prefix = "--set " + key + ": " + key + ": ";
    REQUIRE_THAT(msg, StartsWith(prefix));
    return msg.substr(prefix.size());
}

TEST_CASE("config: fields set in C++ are range-checked by validate with the --set message") {
    // Each of these hung, crashed or ran wrong when set in code and passed to
    // validate() (issue 19): the same rule as TOML, the same words.
    struct Case {
        const char* key;
        const char* toml;
        std::function<void(SimConfig&)> set;
    };
    const Case cases[] = {
        {"output.burst_records", "0", [](SimConfig& c) { c.output.burst_records = 0; }},
        {"output.max_outstanding", "0", [](SimConfig& c) { c.output.max_outstanding = 0; }},
        {"zeb.banks", "0", [](SimConfig& c) { c.zeb.banks = 0; }},
        {"gpu.fragment_processors", "0", [](SimConfig& c) { c.gpu.fragment_processors = 0; }},
        {"zeb.list_length", "0", [](SimConfig& c) { c.zeb.list_length = 0; }},
        {"clock.mhz", "0", [](SimConfig& c) { c.clock.mhz = 0; }},
        {"tile.width", "0", [](SimConfig& c) { c.tile.width = 0; }},
        {"memory.base", "2199023255552", [](SimConfig& c) { c.memory.base = std::uint64_t(1) << 41; }},
        {"memory.size_bytes", "1099511627776", [](SimConfig& c) { c.memory.size_bytes = std::uint64_t(1) << 40; }},
        {"feed.queue_depth", "0", [](SimConfig& c) { c.feed.queue_depth = 0; }},
        {"tester.stack_depth", "65", [](SimConfig& c) { c.tester.stack_depth = 65; }},
        {"gpu.cycles_per_fragment", "0", [](SimConfig& c) { c.gpu.cycles_per_fragment = 0; }},
        {"energy.memory_pj_per_byte", "-1.0", [](SimConfig& c) { c.energy.memory_pj_per_byte = -1.0; }},
    };
    for (const auto& cs : cases) {
        INFO(cs.key << " = " << cs.toml);
        const std::string reason = set_reason(cs.key, cs.toml);
        CHECK_THAT(reason, StartsWith("out of range"));
        CHECK(cpp_error(cs.set) == "config: " + std::string(cs.key) + ": " + reason);
    }
    // A value the parser could not have produced: an enum outside its choices.
    CHECK_THAT(cpp_error([](SimConfig& c) { c.zeb.tie = static_cast<TiePolicy>(7); }),
               StartsWith("config: zeb.tie: unknown value 7, expected front_first | arrival"));
    CHECK_THAT(cpp_error([](SimConfig& c) { c.clock.mhz = std::numeric_limits<double>::quiet_NaN(); }),
               StartsWith("config: clock.mhz: out of range"));
}

TEST_CASE("config: every key's check accepts what its setter accepts") {
    const SimConfig def;
    for (const auto& k : config_keys()) {
        INFO(k.name);
        REQUIRE(k.check);
        CHECK(k.check(def).empty());
    }
    // The setter's bounds are the check's: lowest and highest through --set, then validate().
    for (const auto& k : config_keys()) {
        if (k.type != "integer") continue;
        INFO(k.name);
        const std::string reason = set_reason(k.name, "-1");
        // "out of range LO..HI, got -1"
        const auto dots = reason.find("..");
        const auto comma = reason.find(',');
        REQUIRE(dots != std::string::npos);
        REQUIRE(comma != std::string::npos);
        const std::string lo = reason.substr(std::string("out of range ").size(), dots - 13);
        const std::string hi = reason.substr(dots + 2, comma - dots - 2);
        for (const auto& v : {lo, hi}) {
            SimConfig c;
            REQUIRE_NOTHROW(apply_config_set(c, k.name + "=" + v));
            CHECK(k.check(c).empty());
        }
    }
}

TEST_CASE("config: a memory map that wraps past 2^64 is refused") {
    CHECK_THAT(cpp_error([](SimConfig& c) { c.memory.base = 0xFFFFFFFFFFFF0000ull; }),
               StartsWith("config: memory.base: out of range"));
    CHECK_THAT(cpp_error([](SimConfig& c) { c.output.region_offset = ~std::uint64_t(0) - 15; }),
               StartsWith("config: output.region_offset: out of range"));
    CHECK_THAT(cpp_error([](SimConfig& c) { c.output.region_bytes = ~std::uint64_t(0) - 15; }),
               StartsWith("config: output.region_bytes: out of range"));
    // The highest memory the ranges allow ends well inside 64 bits and is accepted.
    SimConfig c;
    c.memory.base = std::uint64_t(1) << 40;
    c.memory.size_bytes = std::uint64_t(1) << 32;
    c.output.region_offset = c.memory.size_bytes - 2 * c.output.region_bytes;
    CHECK_NOTHROW(c.validate());
}

TEST_CASE("config: records are 16-byte aligned: memory.base and output.region_offset") {
    CHECK(cpp_error([](SimConfig& c) { c.output.region_offset = 3; }) ==
          "config: output.region_offset: not a multiple of the 16-byte record");
    CHECK(cpp_error([](SimConfig& c) { c.memory.base = 0x40000008; }) ==
          "config: memory.base: not a multiple of the 16-byte record");
    // Through --set as well: the value is in range, validate() refuses it.
    SimConfig c;
    apply_config_set(c, "output.region_offset=8");
    CHECK(input_error([&] { c.validate(); }) == "config: output.region_offset: not a multiple of the 16-byte record");
    c = SimConfig{};
    apply_config_set(c, "memory.base=0x40000008");
    CHECK(input_error([&] { c.validate(); }) == "config: memory.base: not a multiple of the 16-byte record");
    c = SimConfig{};
    c.memory.base = 0x40000010;
    c.output.region_offset = 0x30;
    CHECK_NOTHROW(c.validate());
}

TEST_CASE("config: validate errors reached through --set") {
    SimConfig c;
    apply_config_set(c, "memory.latency_max=10");
    apply_config_set(c, "memory.latency_min=20");
    CHECK_THAT(input_error([&] { c.validate(); }), Contains("memory.latency_min"));
}

TEST_CASE("config: dump lists every key") {
    const std::string dump = dump_config_toml(SimConfig{});
    for (const auto& k : config_keys()) {
        INFO(k.name);
        const std::string leaf = k.name.substr(k.name.find('.') + 1);
        const std::string sec = k.name.substr(0, k.name.find('.'));
        CHECK_THAT(dump, Contains("[" + sec + "]"));
        CHECK_THAT(dump, Contains("\n" + leaf + " = "));
    }
}

TEST_CASE("config: dump of the defaults parses back to the defaults") {
    TempDir td;
    const SimConfig def;
    const std::string p = td.write("dump.toml", dump_config_toml(def));
    SimConfig back;
    // Start from something else, so that every key must really be read.
    back.zeb.list_length = 3;
    back.tile.width = 5;
    back.zeb.tie = TiePolicy::Arrival;
    REQUIRE_NOTHROW(apply_config_file(back, p));
    for (const auto& k : config_keys()) {
        INFO(k.name);
        CHECK(k.to_toml(back) == k.to_toml(def));
    }
    CHECK(dump_config_toml(back) == dump_config_toml(def));
}

TEST_CASE("config: dump of a changed configuration parses back to it") {
    TempDir td;
    // Every key moved off its default to another valid value.
    SimConfig cfg;
    for (const auto& k : config_keys()) {
        INFO(k.name);
        const std::string def = k.to_toml(cfg);
        std::vector<std::string> tries;
        if (k.type == "integer") {
            const long long v = std::stoll(def);
            tries = {std::to_string(v + 1), std::to_string(v - 1)};
        } else if (k.type == "float") {
            tries = {"333.3333333333333", "123.456", "1.5"};
        } else if (k.type == "string") {
            for (const auto& ch : enum_choices(k))
                if ("\"" + ch + "\"" != def) tries.push_back("\"" + ch + "\"");
        } else {
            tries = {def == "true" ? "false" : "true"};
        }
        bool moved = false;
        for (const auto& t : tries) {
            try {
                apply_config_set(cfg, k.name + "=" + t);
                moved = true;
                break;
            } catch (const InputError&) {
            }
        }
        CHECK(moved);
        CHECK(k.to_toml(cfg) != def);
    }
    const std::string p = td.write("dump.toml", dump_config_toml(cfg));
    SimConfig back;
    REQUIRE_NOTHROW(apply_config_file(back, p));
    for (const auto& k : config_keys()) {
        INFO(k.name);
        CHECK(k.to_toml(back) == k.to_toml(cfg));
    }
    CHECK(dump_config_toml(back) == dump_config_toml(cfg));
}

// --dump-config writes the shortest decimal that reads back as the same double:
// 0.025, not 0.025000000000000001 (std::to_chars), and every value survives the
// round trip through the dump bit for bit.
TEST_CASE("config: --dump-config writes floats as the shortest decimal that reads back the same") {
    TempDir td;
    const SimConfig def;
    const std::string dump = dump_config_toml(def);
    CHECK_THAT(dump, Contains("\ncomparator_pj_per_bit = 0.0015   #"));
    CHECK_THAT(dump, Contains("\nmhz = 400.0   #"));
    CHECK(dump.find("00000000") == std::string::npos);
    CHECK(dump.find("99999999") == std::string::npos);

    const std::vector<std::pair<std::string, std::string>> cases = {
        {"0.1", "0.1"}, {"0.3", "0.3"}, {"1e-7", "1e-07"}, {"123456.789", "123456.789"},
        {"0.3333333333333333", "0.3333333333333333"}, {"1e9", "1e+09"}, {"5e-324", "5e-324"}, {"7", "7.0"}};
    for (const auto& [in, shortest] : cases) {
        INFO(in);
        SimConfig a;
        apply_config_set(a, "energy.gpu_raster_fragment_pj=" + in);
        const std::string d = dump_config_toml(a);
        CHECK_THAT(d, Contains("\ngpu_raster_fragment_pj = " + shortest + "   #"));
        SimConfig b;
        apply_config_file(b, td.write("d.toml", d));
        CHECK(b.energy.gpu_raster_fragment_pj == a.energy.gpu_raster_fragment_pj);
        CHECK(dump_config_toml(b) == d);
    }
}
