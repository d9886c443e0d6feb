// A trace's XXH3-128 digest taken in parts by rbcd-sim --jobs's workers and
// joined by the parent (run/part_digest.h): libxxhash's digest of the
// whole file, for every kind of length and cut, every vector unit, parts fed
// as a trace reader feeds them (a header chunk, a skip to the part's first
// frame, uneven reads past its end), parts that stop early or are missing;
// no digest for a file replaced since the cut; a worker's entry that does
// not parse is refused.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <sys/resource.h>
#include <sys/stat.h>

#include <algorithm>
#include <csignal>
#include <cstdio>
#include <random>

#include "rbcd/common/errors.h"
#include "rbcd/run/part_digest.h"
#include "rbcd/run/provenance.h"
#include "rbcd/testbench/common/temp_dir.h"

using namespace rbcd;
using namespace rbcd::xxh3_blocks;

namespace {

std::string random_bytes(std::size_t n, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::string s(n, '\0');
    for (char& c : s) c = static_cast<char>(rng());
    return s;
}

std::uint64_t block_of(std::uint64_t off) { return off / kBlockBytes * kBlockBytes; }

// The file at `path` as the parent finds it when it cuts the parts.
FileId planned_id(const std::string& path) {
    const int fd = ::open(path.c_str(), O_RDONLY);
    REQUIRE(fd >= 0);
    const std::optional<FileId> id = file_id(fd);
    ::close(fd);
    REQUIRE(id);
    return *id;
}

// A later part's reader over all of `bytes` from `start` (its header chunk
// first, then a skip): what its digest says.
nlohmann::json read_from(PartDigest& d, int fd, const std::string& bytes, std::size_t start) {
    d.file(fd);
    d.raw(bytes.data(), 4096);
    d.gap(start);
    d.raw(bytes.data() + start, bytes.size() - start);
    return d.finish();
}

// One worker of a run cut at `offsets` (offsets[0] = 0), as the parent plans
// it and its reader feeds it: the first 4 KiB (the trace's header lines),
// then, for a part past them, a skip to its first frame, and reads of uneven
// sizes up to `stop` (the reader reads past its part's end, or stops early).
nlohmann::json run_part(const test::TempDir& td, const std::string& path, const std::string& bytes,
                        const std::vector<std::uint64_t>& offsets, std::size_t k, std::uint64_t stop,
                        std::mt19937_64& rng) {
    const std::uint64_t len = bytes.size();
    const std::uint64_t from = k == 0 ? 0 : block_of(offsets[k]);
    const std::uint64_t to = k + 1 < offsets.size() ? block_of(offsets[k + 1]) : chained_blocks(len) * kBlockBytes;
    PartDigest d(from, std::max(from, to), td.path(std::to_string(k) + ".xxh"));
    const int fd = ::open(path.c_str(), O_RDONLY);
    REQUIRE(fd >= 0);
    d.file(fd);
    const std::uint64_t head = std::min<std::uint64_t>(4096, len);
    d.raw(bytes.data(), static_cast<std::size_t>(head));
    std::uint64_t at = head;
    if (offsets[k] > at) {
        d.gap(offsets[k]);
        at = offsets[k];
    }
    while (at < stop) {
        const std::uint64_t n = std::min<std::uint64_t>(stop - at, 1 + rng() % 70000);
        d.raw(bytes.data() + at, static_cast<std::size_t>(n));
        at += n;
    }
    d.end();
    const nlohmann::json j = d.finish();
    ::close(fd);
    return j;
}

// A split of `bytes` (in the file at `path`) into parts at random offsets,
// each part's reader stopping somewhere past the next part's start (or at the
// end); `early` makes one part stop before its blocks are done, `drop` leaves
// one part out of the join.
std::string split_digest(const test::TempDir& td, const std::string& path, const std::string& bytes,
                         std::size_t parts, std::mt19937_64& rng, bool early = false, bool drop = false) {
    const std::uint64_t len = bytes.size();
    std::vector<std::uint64_t> offsets{0};
    for (std::size_t k = 1; k < parts; ++k) offsets.push_back(1 + rng() % (len - 1));
    std::sort(offsets.begin(), offsets.end());
    const std::size_t short_part = rng() % parts, dropped = rng() % parts;
    SplitDigest split;
    split.planned = planned_id(path);
    for (std::size_t k = 0; k < parts; ++k) {
        std::uint64_t stop = k + 1 < parts ? std::min<std::uint64_t>(len, offsets[k + 1] + rng() % 5000) : len;
        if (early && k == short_part) stop = offsets[k] + (stop - offsets[k]) / 2;
        const nlohmann::json j = run_part(td, path, bytes, offsets, k, stop, rng);
        if (drop && k == dropped) continue;
        split.add(j, td.path(std::to_string(k) + ".xxh"));
    }
    const FileDigest d = digest_from_parts(path, split);
    INFO(d.note);
    CHECK(d.size == len);
    return d.hex;
}

// A file of `len` random bytes cut at `cut`, its first part joined: the
// second part's to be tried; `fd` open on it.
struct FirstPartJoined {
    test::TempDir td;
    std::string bytes, path;
    int fd = -1;
    SplitDigest split;
    FirstPartJoined(std::size_t len, std::uint64_t seed, std::uint64_t cut)
        : bytes(random_bytes(len, seed)), path(td.write("t.bin", bytes)) {
        split.planned = planned_id(path);
        std::mt19937_64 rng(seed);
        split.add(run_part(td, path, bytes, {0, cut}, 0, cut + 500, rng), td.path("0.xxh"));
        fd = ::open(path.c_str(), O_RDONLY);
        REQUIRE(fd >= 0);
    }
    ~FirstPartJoined() { ::close(fd); }
    std::string whole() const { return xxh128_hex(bytes.data(), bytes.size()); }
};

} // namespace

TEST_CASE("part digest: every vector unit gives the portable sums and chain") {
    const std::string bytes = random_bytes(64 * kBlockBytes, 7);
    const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
    std::vector<Lanes> want(64), got(64);
    blocks(Isa::portable, p, 64, nullptr, want.data());
    Lanes want_acc = start();
    blocks(Isa::portable, p, 64, &want_acc, nullptr);
    // The chain of the sums is the blocks chained.
    Lanes chained = start();
    chain(chained, want.data(), want.size());
    CHECK(std::equal(std::begin(chained.v), std::end(chained.v), std::begin(want_acc.v)));
    int ran = 0;
    for (const Isa isa : {Isa::sse2, Isa::avx2, Isa::avx512}) {
        if (!available(isa)) {
            WARN(isa_name(isa) << ": not on this CPU, not compared");
            continue;
        }
        INFO(isa_name(isa));
        ++ran;
        blocks(isa, p, 64, nullptr, got.data());
        for (std::size_t b = 0; b < 64; ++b) CHECK(std::equal(std::begin(got[b].v), std::end(got[b].v), std::begin(want[b].v)));
        Lanes acc = start();
        blocks(isa, p, 64, &acc, nullptr);
        CHECK(std::equal(std::begin(acc.v), std::end(acc.v), std::begin(want_acc.v)));
    }
#if defined(__x86_64__)
    CHECK(ran >= 1);   // SSE2 is every x86-64's
#endif
}

TEST_CASE("part digest: one part, the whole input, is libxxhash's digest for every kind of length") {
    test::TempDir td;
    std::mt19937_64 rng(11);
    // Short inputs (their own algorithms), a last block of one byte, of a
    // stripe and one byte less or more, whole, and longer files.
    for (const std::size_t len : {1u, 17u, 240u, 241u, 255u, 1023u, 1024u, 1025u, 1087u, 1088u, 1089u, 2047u, 2048u,
                                  2049u, 3071u, 65536u, 65600u, 300007u}) {
        INFO("length " << len);
        const std::string bytes = random_bytes(len, len);
        const std::string path = td.write("t.bin", bytes);
        CHECK(split_digest(td, path, bytes, 1, rng) == xxh128_hex(bytes.data(), bytes.size()));
    }
}

TEST_CASE("part digest: any cut into parts gives libxxhash's digest of the whole file") {
    test::TempDir td;
    std::mt19937_64 rng(12345);
    for (int round = 0; round < 120; ++round) {
        // Short files, files of a few hundred blocks, and a few of parts of
        // over 1,024 blocks (their sums written in more than one piece).
        const std::size_t len = 241 + rng() % (round < 60 ? 5000 : round < 110 ? 400000 : 4000000);
        const std::size_t parts = 2 + rng() % 4;
        INFO("round " << round << ": " << len << " bytes in " << parts << " parts");
        const std::string bytes = random_bytes(len, round);
        const std::string path = td.write("t.bin", bytes);
        const std::string want = xxh128_hex(bytes.data(), bytes.size());
        CHECK(split_digest(td, path, bytes, parts, rng) == want);
        // A part that stopped early, or one never joined: the parent hashes
        // what is missing from the file.
        CHECK(split_digest(td, path, bytes, parts, rng, true, false) == want);
        CHECK(split_digest(td, path, bytes, parts, rng, false, true) == want);
    }
}

TEST_CASE("part digest: a file replaced or rewritten since the cut has no digest") {
    test::TempDir td;
    std::mt19937_64 rng(5);
    const std::string bytes = random_bytes(100000, 1), other = random_bytes(100000, 2);
    const std::string path = td.write("t.bin", bytes);
    SplitDigest split;
    split.planned = planned_id(path);
    split.add(run_part(td, path, bytes, {0}, 0, bytes.size(), rng), td.path("0.xxh"));
    REQUIRE(digest_from_parts(path, split).hex == xxh128_hex(bytes.data(), bytes.size()));
    // Another file at the path: its digest would be neither's.
    const std::string moved = td.write("new.bin", other);
    REQUIRE(std::rename(moved.c_str(), path.c_str()) == 0);
    FileDigest d = digest_from_parts(path, split);
    CHECK(d.hex.empty());
    CHECK_THAT(d.note, Catch::Contains("replaced or rewritten"));
    // A worker that read another file than the one cut.
    td.write("t.bin", bytes);
    split.planned = planned_id(path);
    split.parts[0].file->ino += 1;
    d = digest_from_parts(path, split);
    CHECK(d.hex.empty());
    CHECK_THAT(d.note, Catch::Contains("replaced or rewritten"));
    // Rewritten in place, the same inode and size: its time says so.
    {
        const std::string ours = td.write("t.bin", bytes);
        split.planned = planned_id(ours);
        split.parts[0].file = split.planned;
        REQUIRE(digest_from_parts(path, split).hex == xxh128_hex(bytes.data(), bytes.size()));
        const int w = ::open(ours.c_str(), O_WRONLY);
        REQUIRE(w >= 0);
        REQUIRE(::pwrite(w, "x", 1, 50000) == 1);
        // A clock coarser than the two writes would keep the time: moved on.
        const struct timespec later[2] = {{0, UTIME_OMIT}, {static_cast<time_t>(split.planned.mtime_ns / 1000000000 + 1), 0}};
        REQUIRE(::futimens(w, later) == 0);
        ::close(w);
        d = digest_from_parts(path, split);
        CHECK(d.hex.empty());
        CHECK_THAT(d.note, Catch::Contains("replaced or rewritten"));
    }
    // Gone: said so.
    REQUIRE(std::remove(path.c_str()) == 0);
    d = digest_from_parts(path, split);
    CHECK(d.hex.empty());
    CHECK_THAT(d.note, Catch::Contains("cannot read"));
}

TEST_CASE("part digest: a worker's entry that does not parse is refused") {
    SplitDigest split;
    const auto acc = nlohmann::json::array({"0000000000000000", "0000000000000000", "0000000000000000",
                                            "0000000000000000", "0000000000000000", "0000000000000000",
                                            "0000000000000000", "0000000000000000"});
    const nlohmann::json file = {{"dev", 1}, {"ino", 2}, {"size", 3}, {"mtime_ns", 4}};
    CHECK_NOTHROW(split.add({{"from", 0}, {"blocks", 3}, {"acc", acc}, {"file", file}}, "x"));
    CHECK_NOTHROW(split.add({{"from", 2048}, {"blocks", 3}, {"file", file}}, "x"));
    CHECK_NOTHROW(split.add({{"from", 2048}, {"blocks", 0}}, "x"));
    // Blocks of a file it does not name.
    CHECK_THROWS_AS(split.add({{"from", 2048}, {"blocks", 3}}, "x"), RunError);
    const nlohmann::json bad[] = {
        nlohmann::json::object(),
        {{"from", 0}, {"blocks", 3}},                          // from 0 without its accumulators
        {{"from", 1000}, {"blocks", 3}},                       // not a whole block
        {{"from", 2048}, {"blocks", 3}, {"acc", acc}},         // accumulators not from 0
        {{"from", 0}, {"blocks", 3}, {"acc", {"12"}}},         // too few
        {{"from", "0"}, {"blocks", 3}, {"acc", acc}},          // a string
        {{"from", 0}, {"blocks", -1}, {"acc", acc}},           // negative
        {{"from", 2048}, {"blocks", 3}, {"file", {{"dev", 1}}}},   // a file without its inode
        {{"from", 2048}, {"blocks", 18014398509481982u}},          // past 2^64 bytes
    };
    for (const auto& j : bad) {
        INFO(j.dump());
        CHECK_THROWS_AS(split.add(j, "x"), RunError);
    }
    nlohmann::json upper = {{"from", 0}, {"blocks", 3}, {"acc", acc}};
    upper["acc"][7] = "000000000000000G";
    CHECK_THROWS_AS(split.add(upper, "x"), RunError);
}

TEST_CASE("part digest: block sums that cannot be written leave the blocks to the parent") {
    // Not the run's failure (a full disk fails the run's own outputs, named):
    // the part says how many it wrote, and the parent hashes the rest.
    FirstPartJoined f(300000, 3, 100000);
    CHECK_THROWS_AS(PartDigest(1000, 4096, f.td.path("1.xxh")), std::invalid_argument);
    std::vector<std::string> sinks{f.td.path("no/such/dir/1.xxh")};
    if (::access("/dev/full", W_OK) == 0) sinks.push_back("/dev/full");
    else WARN("no /dev/full here: a full disk not tried");
    for (const std::string& sink : sinks) {
        INFO(sink);
        PartDigest d(99328, 299008, sink);
        const nlohmann::json j = read_from(d, f.fd, f.bytes, 100000);
        CHECK(j["blocks"] == 0);
        SplitDigest s = f.split;
        s.add(j, sink);
        CHECK(digest_from_parts(f.path, s).hex == f.whole());
    }
}

TEST_CASE("part digest: an entry claiming blocks past the file's last is not used") {
    test::TempDir td;
    const std::string bytes = random_bytes(100000, 4);
    const std::string path = td.write("t.bin", bytes);
    SplitDigest split;
    split.planned = planned_id(path);
    nlohmann::json acc = nlohmann::json::array();
    for (int i = 0; i < 8; ++i) acc.push_back("0123456789abcdef");
    const FileId& f = split.planned;
    split.add({{"from", 0},
               {"blocks", 1000},
               {"acc", acc},
               {"file", {{"dev", f.dev}, {"ino", f.ino}, {"size", f.size}, {"mtime_ns", f.mtime_ns}}}},
              "");
    CHECK(digest_from_parts(path, split).hex == xxh128_hex(bytes.data(), bytes.size()));
}

TEST_CASE("part digest: sums that stop partway, or a sums file cut short, leave the rest to the parent") {
    FirstPartJoined f(3000000, 8, 500000);
    const std::string want = f.whole();
    const std::uint64_t from = block_of(500000), to = chained_blocks(f.bytes.size()) * kBlockBytes;
    {
        // A file size limit that lets the first 64 KiB of sums through and
        // stops the second piece partway (EFBIG, the signal ignored).
        struct rlimit old {};
        REQUIRE(::getrlimit(RLIMIT_FSIZE, &old) == 0);
        const auto old_handler = std::signal(SIGXFSZ, SIG_IGN);
        struct rlimit lim = old;
        lim.rlim_cur = 100000;
        REQUIRE(::setrlimit(RLIMIT_FSIZE, &lim) == 0);
        PartDigest d(from, to, f.td.path("1.xxh"));
        const nlohmann::json j = read_from(d, f.fd, f.bytes, 500000);
        REQUIRE(::setrlimit(RLIMIT_FSIZE, &old) == 0);
        std::signal(SIGXFSZ, old_handler);
        CHECK(j["blocks"] == 1024);   // the first piece's
        SplitDigest s = f.split;
        s.add(j, f.td.path("1.xxh"));
        CHECK(digest_from_parts(f.path, s).hex == want);
    }
    {
        // All the sums written, then the file cut short behind the part's back.
        PartDigest d(from, to, f.td.path("2.xxh"));
        const nlohmann::json j = read_from(d, f.fd, f.bytes, 500000);
        CHECK(j["blocks"] == (to - from) / kBlockBytes);
        REQUIRE(::truncate(f.td.path("2.xxh").c_str(), 64 * 1000 + 17) == 0);
        SplitDigest s = f.split;
        s.add(j, f.td.path("2.xxh"));
        CHECK(digest_from_parts(f.path, s).hex == want);
        // Gone altogether.
        REQUIRE(std::remove(f.td.path("2.xxh").c_str()) == 0);
        CHECK(digest_from_parts(f.path, s).hex == want);
    }
}
