// Provenance (docs/provenance.md): XXH3-128 against digests `xxhsum -H2`
// printed, shell quoting, input sizes and hashes, and the hash of the
// effective configuration.
#include <catch2/catch.hpp>

#include "rbcd/testbench/common/temp_dir.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "rbcd/common/config.h"
#include "rbcd/run/provenance.h"

using namespace rbcd;
using Catch::Matchers::Contains;

TEST_CASE("xxh128: digests as xxhsum -H2 prints them") {
    CHECK(xxh128_hex("", 0) == "99aa06d3014798d86001c324468d497f");
    CHECK(xxh128_hex("abc", 3) == "06b05ab6733a618578af5f94892f3950");
    const std::string a(1000000, 'a');
    CHECK(xxh128_hex(a.data(), a.size()) == "a545df8e384a9579b1fd6fae5285c4eb");
}

TEST_CASE("provenance: a file read in several blocks hashes as xxhsum -H2 hashes it") {
    test::TempDir td;
    // Three 1 MiB reads and a short one.
    std::string bytes(3000017, '\0');
    for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i % 251);
    const std::string path = td.write("big.rbt", bytes);
    const auto j = input_info({"trace", path});
    CHECK(j["size"] == bytes.size());
    CHECK(j["xxh128"] == "24b128e0c946640038162c5844f0f8ef");
    CHECK(j["xxh128"] == xxh128_hex(bytes.data(), bytes.size()));
    CHECK_FALSE(j.contains("note"));
}

TEST_CASE("provenance: a file hashed again by name is checked against the one the run found") {
    test::TempDir td;
    const std::string path = td.write("t.rbt", "rbcd-trace 1\nthe file the run read\n");
    ProvenanceInput in{"trace", path};
    in.expected = file_id_at(path);
    REQUIRE(in.expected);
    const auto same = input_info(in);
    CHECK(same["xxh128"] == xxh128_hex("rbcd-trace 1\nthe file the run read\n", 35));
    // Another file renamed over it (rbcd-sim --jobs on a gzip trace hashes
    // by name once the first worker ends).
    const std::string other = td.write("other.rbt", "rbcd-trace 1\nanother file\n");
    REQUIRE(std::rename(other.c_str(), path.c_str()) == 0);
    const auto replaced = input_info(in);
    CHECK(replaced["xxh128"].is_null());
    CHECK(replaced["note"] == "the file was replaced or rewritten during the run");
    // Without the identity, the file there is hashed, as before.
    CHECK(input_info({"trace", path})["xxh128"] == xxh128_hex("rbcd-trace 1\nanother file\n", 26));
}

TEST_CASE("provenance: shell quoting reads back as the same words") {
    CHECK(shell_quote("build/bin/rbcd-sim") == "build/bin/rbcd-sim");
    CHECK(shell_quote("--set=zeb.tie=arrival") == "--set=zeb.tie=arrival");
    CHECK(shell_quote("") == "''");
    CHECK(shell_quote("a b") == "'a b'");
    CHECK(shell_quote("it's") == "'it'\\''s'");
    CHECK(shell_quote("$HOME") == "'$HOME'");
    CHECK(shell_quote("x;rm") == "'x;rm'");
}

TEST_CASE("provenance: inputs carry path, size and XXH3-128, the configuration its XXH3-128 too") {
    test::TempDir td;
    const std::string trace = td.write("t.rbt", "rbcd-trace 1\n");
    const std::string embedded = "format = 1\n";
    SimConfig cfg;
    const auto p = make_provenance({"rbcd-sim", "--trace", trace, "--set", "a b"}, cfg,
                                   {{"trace", trace}, {"scene", "<embedded>", &embedded}, {"mesh", td.path("gone.obj")}});
    CHECK(p["command_line"] == "rbcd-sim --trace " + trace + " --set 'a b'");
    CHECK(p["argv"].size() == 5);
    const std::string config = dump_config_toml(cfg);
    CHECK(p["config_xxh128"] == xxh128_hex(config.data(), config.size()));
    CHECK(p["build"]["program"] == "rbcd-sim");
    CHECK(p["build"]["systemc"].get<std::string>().rfind("2.3", 0) == 0);
    for (const char* k : {"version", "compiler", "build_type"}) CHECK_FALSE(p["build"][k].get<std::string>().empty());
    for (const char* k : {"sanitize", "profile_guided"}) CHECK(p["build"][k].is_boolean());
    // A sanitizer build is never profile-guided (RBCD_PGO refuses it).
    CHECK_FALSE((p["build"]["sanitize"].get<bool>() && p["build"]["profile_guided"].get<bool>()));
    REQUIRE(p["inputs"].size() == 3);
    CHECK(p["inputs"][0]["role"] == "trace");
    CHECK(p["inputs"][0]["path"] == trace);
    CHECK(p["inputs"][0]["size"] == 13);
    CHECK(p["inputs"][0]["xxh128"] == "babbd33b98e1446b42e375e71cf8bda4");
    CHECK(p["inputs"][1]["size"] == embedded.size());
    CHECK(p["inputs"][1]["xxh128"] == xxh128_hex(embedded.data(), embedded.size()));
    CHECK(p["inputs"][2]["xxh128"].is_null());
    CHECK(p["inputs"][2]["size"].is_null());
    CHECK_THAT(p["inputs"][2]["note"].get<std::string>(), Contains("cannot read"));

    SimConfig other;
    apply_config_set(other, "zeb.list_length=4");
    CHECK(make_provenance({}, other, {})["config_xxh128"] != p["config_xxh128"]);
}

namespace {
// A file of n bytes that no two offsets of which look alike for long.
std::string patterned(std::size_t n) {
    std::string b(n, '\0');
    for (std::size_t i = 0; i < n; ++i) b[i] = static_cast<char>((i * 7 + i / 251) % 256);
    return b;
}
} // namespace

TEST_CASE("provenance: a file hashed as it was read, then from where the reader stopped, hashes whole") {
    test::TempDir td;
    const std::string bytes = patterned(2500003);
    const std::string path = td.write("t.rbt", bytes);
    const std::string whole = xxh128_hex(bytes.data(), bytes.size());
    const std::size_t seen = GENERATE(std::size_t(0), std::size_t(1), std::size_t(4096), std::size_t(1048577),
                                      std::size_t(2500003));
    INFO("the reader read " << seen << " bytes");
    ReadDigest d;
    // As a reader reads: pieces of uneven sizes.
    for (std::size_t at = 0, piece = 1; at < seen; at += piece, piece = piece * 3 + 1)
        d.raw(bytes.data() + at, std::min(piece, seen - at));
    CHECK(d.bytes() == seen);
    REQUIRE(d.usable());
    const auto j = input_info({"trace", path, nullptr, &d});
    CHECK(j["size"] == bytes.size());
    CHECK(j["xxh128"] == whole);
}

TEST_CASE("provenance: a read with a gap is not gone on from") {
    test::TempDir td;
    const std::string bytes = patterned(100000);
    const std::string path = td.write("t.rbt", bytes);
    ReadDigest d;
    d.raw(bytes.data(), 10);
    d.gap(0);
    d.raw(bytes.data() + 5000, 10);
    CHECK_FALSE(d.usable());
    // Hashed whole from the file instead.
    CHECK(input_info({"trace", path, nullptr, &d})["xxh128"] == xxh128_hex(bytes.data(), bytes.size()));
}

TEST_CASE("provenance: a file read to its end is not read again; one replaced since is not hashed as the run's") {
    test::TempDir td;
    const std::string bytes = patterned(300000), other = patterned(300001);
    const std::string path = td.write("t.rbt", bytes);
    {
        // Read to the end (a read saw it): the digest is of what was read,
        // even with the file gone since.
        ReadDigest d;
        const int fd = ::open(path.c_str(), O_RDONLY);
        REQUIRE(fd >= 0);
        d.file(fd);
        d.raw(bytes.data(), bytes.size());
        d.end();
        ::close(fd);
        REQUIRE(std::remove(path.c_str()) == 0);
        const auto j = input_info({"trace", path, nullptr, &d});
        CHECK(j["size"] == bytes.size());
        CHECK(j["xxh128"] == xxh128_hex(bytes.data(), bytes.size()));
    }
    {
        // Half read, then another file put at the path: no digest, a note.
        td.write("t.rbt", bytes);
        ReadDigest d;
        const int fd = ::open(path.c_str(), O_RDONLY);
        REQUIRE(fd >= 0);
        d.file(fd);
        d.raw(bytes.data(), 1000);
        ::close(fd);
        const std::string moved = td.write("new.rbt", other);
        REQUIRE(std::rename(moved.c_str(), path.c_str()) == 0);
        const auto j = input_info({"trace", path, nullptr, &d});
        CHECK(j["xxh128"].is_null());
        CHECK_THAT(j["note"].get<std::string>(), Contains("replaced"));
    }
}
