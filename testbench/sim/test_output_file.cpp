// An older output held open across its unlink (sc_main/output_file.h,
// OlderOutput): its name goes when the new output is opened, its pages when
// it is released; only a regular file of 1 MiB or more is held.
#include <catch2/catch.hpp>

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>

#include "rbcd/sc_main/output_file.h"
#include "rbcd/testbench/common/temp_dir.h"

using namespace rbcd;

namespace {

// Whether this process holds a descriptor of the unlinked file once at `path`.
bool holds_deleted(const std::string& path) {
    DIR* d = ::opendir("/proc/self/fd");
    REQUIRE(d != nullptr);
    bool found = false;
    while (const dirent* e = ::readdir(d)) {
        char target[4096];
        const ssize_t n = ::readlink(("/proc/self/fd/" + std::string(e->d_name)).c_str(), target, sizeof target - 1);
        if (n <= 0) continue;
        target[n] = '\0';
        if (std::string(target) == path + " (deleted)") found = true;
    }
    ::closedir(d);
    return found;
}

using test::slurp;

} // namespace

TEST_CASE("older output: a large older result loses its name at once and its pages at release") {
    test::TempDir td;
    // As /proc names it: the temporary directory's path may hold a symlink.
    const std::string path =
        std::filesystem::canonical(td.dir).string() + "/collisions.txt";
    td.write("collisions.txt", std::string(std::size_t(2) << 20, 'x'));
    OlderOutput older(path);
    REQUIRE(older.held());
    OutputFile out(path);
    struct stat st {};
    CHECK(::stat(path.c_str(), &st) != 0);   // gone from the path before the run
    CHECK(holds_deleted(path));
    older.release();
    CHECK_FALSE(holds_deleted(path));
    out.write("new\n");
    out.commit();
    CHECK(slurp(path) == "new\n");
}

TEST_CASE("older output: a small file, none, or not a regular file is not held") {
    test::TempDir td;
    const std::string small = td.write("small.txt", std::string(100000, 'x'));
    CHECK_FALSE(OlderOutput(small).held());
    CHECK_FALSE(OlderOutput(td.path("none.txt")).held());
    CHECK_FALSE(OlderOutput("").held());
    CHECK_FALSE(OlderOutput("-").held());
    CHECK_FALSE(OlderOutput("/dev/null").held());
    const std::string fifo = td.path("fifo");
    REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
    CHECK_FALSE(OlderOutput(fifo).held());   // written in place, never opened here
    // A symlink to a large file: written through (in place), never held.
    const std::string big = td.write("big.txt", std::string(std::size_t(2) << 20, 'x'));
    const std::string link = td.path("link.txt");
    REQUIRE(::symlink(big.c_str(), link.c_str()) == 0);
    CHECK_FALSE(OlderOutput(link).held());
}

TEST_CASE("older output: held only with four times the space it takes free") {
    const std::uint64_t MiB = std::uint64_t(1) << 20;
    CHECK_FALSE(older_worth_holding(MiB - 1, std::uint64_t(1) << 40));   // too small to be worth it
    CHECK(older_worth_holding(MiB, 4 * MiB + 1));
    CHECK_FALSE(older_worth_holding(MiB, 4 * MiB));
    CHECK_FALSE(older_worth_holding(std::uint64_t(1) << 30, std::uint64_t(300) << 20));   // 1 GiB, 300 MiB free
    CHECK_FALSE(older_worth_holding(std::uint64_t(1) << 62, ~std::uint64_t(0)));          // no overflow
    CHECK(older_worth_holding(std::uint64_t(1) << 61, ~std::uint64_t(0)));
}
