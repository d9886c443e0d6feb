// Joining a --jobs worker's per-frame lines (sc_main/part_files.h): the quick
// path for the lines a worker writes (nlohmann's compact dump, keys in order)
// gives the bytes of the JSON path, for any offset; a line it cannot take
// goes the JSON path, with its error.
#include <catch2/catch.hpp>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/sc_main/output_file.h"
#include "rbcd/sc_main/part_files.h"
#include "rbcd/testbench/common/temp_dir.h"

using namespace rbcd;

namespace {

std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

// A frame's line as rbcd-sim writes it: compact, keys in order, nested
// objects and fractions.
std::string frame_line(std::uint64_t frame, std::uint64_t start, std::uint64_t end) {
    nlohmann::json f;
    f["frame"] = frame;
    f["start_cycle"] = start;
    f["end_cycle"] = end;
    f["baseline_cycles"] = 51473 + frame;
    f["energy_pj"] = {{"gpu_baseline", 16057238.0}, {"overhead_pct", 21.931184877498865 + frame}};
    f["stalls"] = {{"fragment_queue_cycles", 40490}, {"no_bank_cycles", 4025}};
    f["overhead_pct"] = 11.949954344996407;
    return f.dump();
}

struct Joined {
    std::string text, error;
};

Joined join(const test::TempDir& td, const std::string& lines, std::uint64_t first, std::uint64_t frames,
            std::uint64_t offset, bool own) {
    PartFiles p;
    p.frame_stats = td.write("part.jsonl", lines);
    p.first_frame = first;
    p.frames = frames;
    const std::string out_path = td.path(own ? "own.jsonl" : "json.jsonl");
    std::remove(out_path.c_str());
    OutputFile out(out_path);
    Joined j;
    try {
        if (own) append_own_part_frame_stats(p, offset, out);
        else append_part_frame_stats(p, offset, out);
        out.commit();
        j.text = slurp(out_path);
    } catch (const InputError& e) {
        j.error = e.what();
    }
    return j;
}

void expect_same(const test::TempDir& td, const std::string& lines, std::uint64_t first, std::uint64_t frames,
                 std::uint64_t offset) {
    const Joined own = join(td, lines, first, frames, offset, true);
    const Joined json = join(td, lines, first, frames, offset, false);
    CHECK(own.error == json.error);
    CHECK(own.text == json.text);
}

} // namespace

TEST_CASE("part files: a worker's per-frame lines joined quickly are the JSON path's bytes") {
    test::TempDir td;
    std::string lines;
    for (std::uint64_t f = 7; f < 307; ++f) lines += frame_line(f, 1000 * (f - 7), 1000 * (f - 6)) + "\n";
    for (const std::uint64_t offset : {std::uint64_t(0), std::uint64_t(1), std::uint64_t(987654321),
                                       std::uint64_t(1) << 63}) {
        INFO("offset " << offset);
        expect_same(td, lines, 7, 300, offset);
        const Joined own = join(td, lines, 7, 300, offset, true);
        REQUIRE(own.error.empty());
        const auto first = nlohmann::json::parse(own.text.substr(0, own.text.find('\n')));
        CHECK(first["start_cycle"] == offset);
        CHECK(first["end_cycle"] == offset + 1000);
    }
    // Past 2^64 once offset: the JSON path's error.
    const Joined over = join(td, lines, 7, 300, ~std::uint64_t(0) - 500, true);
    CHECK_THAT(over.error, Catch::Contains("beyond 2^64 - 1 once offset"));
    expect_same(td, lines, 7, 300, ~std::uint64_t(0) - 500);
}

TEST_CASE("part files: a per-frame line of another shape takes the JSON path") {
    test::TempDir td;
    const std::string good = frame_line(3, 10, 20);
    const std::string shapes[] = {
        // Not compact, keys repeated in a nested object, leading zeros, a
        // sign, a fraction, an exponent, missing keys, not an object.
        "{\"frame\": 3, \"start_cycle\": 10, \"end_cycle\": 20}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":{\"end_cycle\":5}}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":010}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":-10}",
        "{\"end_cycle\":20.5,\"frame\":3,\"start_cycle\":10}",
        "{\"end_cycle\":2e1,\"frame\":3,\"start_cycle\":10}",
        "{\"end_cycle\":20,\"frame\":3}",
        "{\"frame\":3,\"start_cycle\":10}",
        "[\"frame\":3]",
        "{\"end_cycle\":20,\"frame\":4,\"start_cycle\":10}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"frame\":3}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":99999999999999999999999}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"xend_cycle\":1}",
        "",
    };
    for (const std::string& bad : shapes) {
        INFO(bad);
        for (const std::uint64_t offset : {std::uint64_t(0), std::uint64_t(100)}) {
            expect_same(td, good + "\n" + bad + "\n", 2, 2, offset);
            expect_same(td, bad + "\n", 3, 1, offset);
        }
    }
    // A file cut short, a line too many, a line too few.
    expect_same(td, frame_line(3, 10, 20), 3, 1, 5);
    expect_same(td, frame_line(3, 10, 20) + "\n" + frame_line(4, 20, 30) + "\n", 3, 1, 5);
    expect_same(td, frame_line(3, 10, 20) + "\n", 3, 2, 5);
    CHECK_FALSE(join(td, frame_line(3, 10, 20), 3, 1, 5, true).error.empty());
}
