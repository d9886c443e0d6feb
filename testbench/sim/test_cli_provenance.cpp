// rbcd-sim's --version, the stats' provenance block (docs/provenance.md) and
// the first-hour rough edges of issue 13: an unknown argument named with the
// option it most likely meant, --dump-config's shortest decimals.
#include "rbcd/testbench/sim/cli_util.h"

#include <map>
#include <nlohmann/json.hpp>

using namespace rbcd::cli_test;

TEST_CASE("cli: --version prints the version, git revision, SystemC, compiler and build type") {
    TempDir td;
    const Result r = run_sim(td, {"--version"});
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(r.err.empty());
    CHECK_THAT(r.out, StartsWith("rbcd-sim 0."));
    for (const char* line : {"\ngit: ", "\nSystemC: 2.3", "\ncompiler: ", "\nbuild type: "}) CHECK_THAT(r.out, Contains(line));
    CHECK(count_lines(r.out) == 5);
}

TEST_CASE("cli: stats carry the provenance: build, command line, configuration hash, inputs' sizes and hashes") {
    TempDir td;
    const std::string trace = kVectors + "/rule-stack-overflow.rbt", config = kVectors + "/rule-stack-overflow.toml";
    const std::vector<std::string> args{"--trace", trace, "--config", config, "--set", "energy.memory_pj_per_byte=41", "-q"};
    const Result r = run_with_outputs(td, args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    const auto stats = nlohmann::json::parse(slurp(td.stats()));
    REQUIRE(stats.contains("provenance"));
    const auto& p = stats["provenance"];

    const Result v = run_sim(td, {"--version"});
    CHECK_THAT(v.out, StartsWith("rbcd-sim " + p["build"]["version"].get<std::string>() + "\n"));
    CHECK_THAT(v.out, Contains("SystemC: " + p["build"]["systemc"].get<std::string>() + "\n"));

    std::vector<std::string> argv{RBCD_SIM};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.insert(argv.end(), {"--collisions", td.collisions(), "--stats", td.stats()});
    CHECK(p["argv"].get<std::vector<std::string>>() == argv);
    CHECK_THAT(p["command_line"].get<std::string>(), Contains("--set energy.memory_pj_per_byte=41 -q"));

    // The hash of exactly what --dump-config prints for the same settings.
    const Result d = run_sim(td, {"--config", config, "--set", "energy.memory_pj_per_byte=41", "--dump-config"});
    REQUIRE(d.status == 0);
    CHECK(p["config_xxh128"] == xxh128_of(d.out));

    REQUIRE(p["inputs"].size() == 2);
    std::map<std::string, nlohmann::json> by_role;
    for (const auto& in : p["inputs"]) by_role[in["role"].get<std::string>()] = in;
    for (const auto& [role, path] : {std::pair<std::string, std::string>{"trace", trace}, {"config", config}}) {
        INFO(role);
        REQUIRE(by_role.count(role));
        CHECK(by_role[role]["path"] == path);
        CHECK(by_role[role]["size"] == fs::file_size(path));
        CHECK(by_role[role]["xxh128"] == xxh128_of(slurp(path)));
    }
}

TEST_CASE("cli: an unknown argument is named with the option it most likely meant") {
    TempDir td;
    const Result r = run_sim(td, {"--trace", kVectors + "/default.rbt", "--collisons", td.collisions(), "--stats", td.stats()});
    expect_input_error(td, r, {"unknown argument '--collisons'", "did you mean --collisions?"});
    const Result s = run_sim(td, {"-trace", kVectors + "/default.rbt"});
    expect_input_error(td, s, {"'-trace'", "did you mean --trace?"});
    const Result t = run_sim(td, {"--dump-confg"});
    expect_input_error(td, t, {"'--dump-confg'", "did you mean --dump-config?"});
}

TEST_CASE("cli: an argument like no option is named without a guess, a bare word points to --trace and --scene") {
    TempDir td;
    const Result r = run_sim(td, {"--frobnicate"});
    expect_input_error(td, r, {"unknown argument '--frobnicate'"});
    CHECK_THAT(r.err, !Contains("did you mean"));
    const Result s = run_sim(td, {kVectors + "/default.rbt"});
    expect_input_error(td, s, {"unknown argument '" + kVectors + "/default.rbt'", "--trace FILE"});
}

TEST_CASE("cli: --dump-config prints the shortest decimals that read back the same") {
    TempDir td;
    const Result r = run_sim(td, {"--set", "energy.comparator_pj_per_bit=0.1", "--dump-config"});
    REQUIRE(r.status == 0);
    CHECK_THAT(r.out, Contains("\nid_compare_pj_per_bit = 0.001   #"));
    CHECK_THAT(r.out, Contains("\ncomparator_pj_per_bit = 0.1   #"));
    CHECK(r.out.find("0000000") == std::string::npos);
}

TEST_CASE("cli: --help sends the reader to the repository's own docs only") {
    TempDir td;
    const Result r = run_sim(td, {"--help"});
    CHECK(r.status == 0);
    CHECK_THAT(r.out, Contains("--version"));
    CHECK_THAT(r.out, Contains("docs/formats.md"));
    CHECK_THAT(r.out, !Contains("../"));
    CHECK_THAT(r.out, !Contains("shared/"));
    // Every docs/ file named exists in the source tree.
    for (std::size_t p = r.out.find("docs/"); p != std::string::npos; p = r.out.find("docs/", p + 1)) {
        const std::size_t e = r.out.find(".md", p);
        REQUIRE(e != std::string::npos);
        const std::string doc = r.out.substr(p, e + 3 - p);
        INFO(doc);
        CHECK(fs::exists(std::string(RBCD_SOURCE_DIR) + "/" + doc));
    }
}

TEST_CASE("cli: a trace hashed as it is read has the digest of the whole file, plain or gzip, on one thread or two") {
    // The reader's bytes are hashed as they pass (ReadDigest); with --frames
    // the reader stops early and the rest is read for the hash; --db records
    // the provenance before the run and hashes the file then.
    TempDir td;
    const std::string plain = kVectors + "/rule-stack-overflow.rbt";
    const std::string gz = td.write_gz("t.rbt.gz", slurp(plain));
    const auto trace = GENERATE_COPY(plain, gz);
    const auto threads = GENERATE(as<std::string>{}, "1", "2");
    const auto frames = GENERATE(as<std::string>{}, "", "0:0");
    INFO(trace << " --threads " << threads << " --frames " << frames);
    std::vector<std::string> args{"--trace", trace, "-q", "--threads", threads};
    if (!frames.empty()) args.insert(args.end(), {"--frames", frames});
    const Result r = run_with_outputs(td, args);
    INFO(r.err);
    REQUIRE(r.status == 0);
    const auto p = nlohmann::json::parse(slurp(td.stats()))["provenance"];
    REQUIRE(p["inputs"].size() == 1);
    CHECK(p["inputs"][0]["size"] == fs::file_size(trace));
    CHECK(p["inputs"][0]["xxh128"] == xxh128_of(slurp(trace)));
    CHECK_FALSE(p["inputs"][0].contains("note"));
}

TEST_CASE("cli: a trace on standard input gets the digest of what was read; with --frames, a note") {
    TempDir td;
    const std::string trace = kVectors + "/rule-stack-overflow.rbt";
    for (const bool frames : {false, true}) {
        INFO("--frames " << frames);
        std::vector<std::string> args{"-c", "f=$1; shift; exec \"$0\" \"$@\" < \"$f\"", RBCD_SIM, trace, "--trace", "-", "-q",
                                      "--stats", td.stats()};
        if (frames) args.insert(args.end(), {"--frames", "0:0"});
        const Result r = run_program(td, "/bin/sh", args);
        INFO(r.err);
        REQUIRE(r.status == 0);
        const auto in = nlohmann::json::parse(slurp(td.stats()))["provenance"]["inputs"][0];
        CHECK(in["path"] == "-");
        if (frames) {
            CHECK(in["xxh128"].is_null());
            CHECK(in["note"] == "standard input");
        } else {
            CHECK(in["size"] == fs::file_size(trace));
            CHECK(in["xxh128"] == xxh128_of(slurp(trace)));
        }
    }
}
