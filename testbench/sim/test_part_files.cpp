// Joining a --jobs worker's per-frame lines (sc_main/part_files.h): the quick
// path for the lines a worker writes (nlohmann's compact dump, keys in order)
// gives the bytes of the JSON path, for any offset; a line it cannot take
// goes the JSON path, with its error.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/report/run_report.h"
#include "rbcd/sc_main/output_file.h"
#include "rbcd/sc_main/part_files.h"
#include "rbcd/testbench/common/temp_dir.h"

using namespace rbcd;

namespace {

using test::slurp;

// A frame's line as rbcd-sim writes it (report/run_report.h): fractions,
// nested objects, and with no baseline null percentages.
std::string frame_line(std::uint64_t frame, std::uint64_t start, std::uint64_t end) {
    FrameFigures f;
    f.t.frame = frame;
    f.t.start_cycle = start;
    f.t.end_cycle = end;
    f.t.baseline = frame % 3 == 0 ? 0 : 51473 + frame;
    f.t.with_unit = 57624 + frame;
    f.t.fragments = 19506;
    f.extra_prims = 3;
    f.unit_dynamic_pj = 2520868.552 + frame;
    f.gpu_baseline_pj = 16057238.0;
    f.gpu_with_unit_pj = 17057938.25;
    return frame_json(f).dump();
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
    for (std::uint64_t f = 7; f < 307; ++f) {
        lines += frame_line(f, 1000 * (f - 7), 1000 * (f - 6)) + "\n";
        // The quick path is the one taken, for every line the worker writes.
        CHECK(frame_line_is_library_shaped(frame_line(f, 1000 * (f - 7), 1000 * (f - 6))));
    }
    CHECK(frame_line_is_library_shaped(frame_line(1, 0, ~std::uint64_t(0))));
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
    // Not the library's shape (the quick path must not take them): the top
    // level's key only in a nested object; not JSON; keys out of order (the
    // JSON path sorts them); a space elsewhere; a key twice; a key where an
    // array's value goes.
    const std::string not_shaped[] = {
        "{\"frame\":3,\"start_cycle\":10,\"x\":{\"end_cycle\":20}}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10}}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":[1,2}",
        "{\"frame\":3,\"start_cycle\":10,\"end_cycle\":20}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"z\":1,\"y\":2}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":{\"b\":1,\"a\":2}}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\": 1}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":1,\"x\":2}",
        "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":[\"k\":1]}",
    };
    std::vector<std::string> all(std::begin(shapes), std::end(shapes));
    all.insert(all.end(), std::begin(not_shaped), std::end(not_shaped));
    // A string holding what looks like a key is a string.
    const std::string tricky = "{\"end_cycle\":20,\"frame\":3,\"start_cycle\":10,\"x\":\"a\\\",\\\"end_cycle\\\":5\"}";
    all.push_back(tricky);
    for (const std::string& bad : all) {
        INFO(bad);
        for (const std::uint64_t offset : {std::uint64_t(0), std::uint64_t(100)}) {
            expect_same(td, good + "\n" + bad + "\n", 2, 2, offset);
            expect_same(td, bad + "\n", 3, 1, offset);
        }
    }
    for (const std::string& bad : not_shaped) {
        INFO(bad);
        CHECK_FALSE(frame_line_is_library_shaped(bad));
    }
    CHECK(frame_line_is_library_shaped(tricky));
    // A file cut short, a line too many, a line too few.
    expect_same(td, frame_line(3, 10, 20), 3, 1, 5);
    expect_same(td, frame_line(3, 10, 20) + "\n" + frame_line(4, 20, 30) + "\n", 3, 1, 5);
    expect_same(td, frame_line(3, 10, 20) + "\n", 3, 2, 5);
    CHECK_FALSE(join(td, frame_line(3, 10, 20), 3, 1, 5, true).error.empty());
}
