// Properties the paced GPU model must hold (docs/gpu-model.md), checked by
// running rbcd-sim over random traces and the default scene with one key
// changed at a time:
//   - a deeper fragment queue or unit input queue never increases the overhead;
//   - two ZEB banks never take longer than one;
//   - the baseline never exceeds the time with the unit, in any frame;
//   - without collisionable fragments the overhead is 0;
//   - the bulk runs (FragmentPipe::shade_run's jumps over periodic stretches)
//     give, byte for byte, what stepping every fragment gives.
#include "rbcd/testbench/sim/cli_util.h"

#include <nlohmann/json.hpp>

#include "rbcd/common/fragment.h"
#include "rbcd/io/trace_writer.h"

using namespace rbcd::cli_test;

namespace {

// Random frames of random tiles: fragments on random pixels and objects, some
// tagged c, non-collisionable runs between them (`o`) or given as other=,
// prims= and cprims=.
// long_runs: runs of up to 3,000 non-collisionable fragments, other= up to
// 40,000, and a shade= cost on some tiles, so that runs reach the pipeline's
// periodic regime and leave it at setups, c fragments and cost changes, and
// tiles without collisionable fragments let timelines follow timeline 0.
std::string random_trace(const TempDir& td, unsigned seed, bool collisionable = true, bool long_runs = false) {
    std::uint64_t s = seed * 0x9e3779b97f4a7c15ull + 1;
    const auto rnd = [&](std::uint64_t n) {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        return s % n;
    };
    const std::string path = td.dir + "/random" + std::to_string(seed) + ".rbt";
    rbcd::StreamHeader h;
    rbcd::TraceWriter w(path, h);
    for (unsigned f = 0; f < 3; ++f) {
        w.frame(f);
        for (std::uint32_t t = 0; t < 12; ++t) {
            rbcd::Tile tile;
            tile.frame = f;
            tile.col = t * 4 + static_cast<std::uint32_t>(rnd(4));
            tile.row = static_cast<std::uint32_t>(rnd(30));
            tile.ordered_other = rnd(2);
            // Long runs: half the tiles without collisionable fragments, as in a game frame.
            const unsigned n = collisionable && !(long_runs && rnd(2)) ? static_cast<unsigned>(rnd(400)) : 0;
            for (unsigned i = 0; i < n; ++i) {
                if (tile.ordered_other && rnd(4) == 0) {
                    tile.other_runs.push_back(
                        {static_cast<std::uint32_t>(tile.frags.size()), rnd(long_runs && rnd(3) == 0 ? 3000 : 30) + 1});
                    tile.other += tile.other_runs.back().count;
                }
                rbcd::Fragment fr;
                fr.x = tile.col * 16 + static_cast<std::uint32_t>(rnd(16));
                fr.y = tile.row * 16 + static_cast<std::uint32_t>(rnd(16));
                fr.depth = static_cast<std::uint32_t>(rnd(1u << 24));
                fr.id = static_cast<std::uint32_t>(rnd(20) + 1);
                fr.facing = rnd(2) ? rbcd::Facing::Back : rbcd::Facing::Front;
                fr.culled = fr.facing == rbcd::Facing::Back && rnd(3) != 0;
                tile.frags.push_back(fr);
            }
            if (!tile.ordered_other) tile.other = rnd(long_runs && rnd(2) ? 40000 : 600);
            if (long_runs && rnd(3) == 0) {
                tile.has_shade = true;
                tile.shade = static_cast<std::uint32_t>(1 + rnd(rnd(2) ? 300 : 10000));
            }
            tile.has_prims = tile.has_cprims = true;
            tile.prims = rnd(long_runs && rnd(4) == 0 ? 2 : 60);
            tile.cprims = collisionable ? rnd(30) : 0;   // no collisionable object: nothing to defer
            w.tile(tile);
        }
    }
    w.close();
    return path;
}

nlohmann::json run_stats(const TempDir& td, std::vector<std::string> args) {
    args.push_back("--stats");
    args.push_back(td.stats());
    args.push_back("-q");
    const Result r = run_sim(td, args);
    INFO(r.cmd << "\n" << r.err);
    REQUIRE(r.status == 0);
    return nlohmann::json::parse(slurp(td.stats()));
}

double overhead(const nlohmann::json& j) { return j["gpu"]["overhead_pct"].get<double>(); }
std::uint64_t with_unit(const nlohmann::json& j) { return j["gpu"]["cycles_with_unit"].get<std::uint64_t>(); }

// The key's values in increasing order never increase the overhead.
void check_monotone(const TempDir& td, const std::vector<std::string>& input, const std::string& key,
                    const std::vector<unsigned>& values, std::vector<std::string> extra = {}) {
    double prev = 1e300;
    for (unsigned v : values) {
        std::vector<std::string> args = input;
        args.insert(args.end(), extra.begin(), extra.end());
        args.insert(args.end(), {"--set", key + "=" + std::to_string(v)});
        const double o = overhead(run_stats(td, args));
        INFO(key << " = " << v << ": overhead " << o << "% after " << prev << "%");
        CHECK(o <= prev + 1e-9);
        prev = o;
    }
}

} // namespace

TEST_CASE("gpu properties: a deeper input queue never increases the overhead on random traces") {
    TempDir td;
    for (unsigned seed = 1; seed <= 4; ++seed) {
        const std::string t = random_trace(td, seed);
        for (const char* banks : {"1", "2"})
            check_monotone(td, {"--trace", t}, "feed.queue_depth", {1, 2, 4, 8, 16, 32, 64, 256},
                           {"--set", std::string("zeb.banks=") + banks, "--set", "gpu.cycles_per_fragment=2"});
    }
}

TEST_CASE("gpu properties: a deeper fragment queue never increases the overhead on random traces") {
    TempDir td;
    for (unsigned seed = 5; seed <= 8; ++seed) {
        const std::string t = random_trace(td, seed);
        for (const char* wait : {"tile", "unit"})
            check_monotone(td, {"--trace", t}, "gpu.fragment_queue_depth", {1, 4, 16, 64, 256, 1024},
                           {"--set", std::string("gpu.bank_wait=") + wait});
    }
}

TEST_CASE("gpu properties: two banks never take longer than one") {
    TempDir td;
    for (unsigned seed = 9; seed <= 14; ++seed) {
        const std::string t = random_trace(td, seed);
        for (const char* wait : {"tile", "unit"}) {
            const auto one = run_stats(td, {"--trace", t, "--set", "zeb.banks=1", "--set", std::string("gpu.bank_wait=") + wait});
            const auto two = run_stats(td, {"--trace", t, "--set", "zeb.banks=2", "--set", std::string("gpu.bank_wait=") + wait});
            const auto four = run_stats(td, {"--trace", t, "--set", "zeb.banks=4", "--set", std::string("gpu.bank_wait=") + wait});
            INFO("seed " << seed << " bank_wait " << wait);
            CHECK(with_unit(two) <= with_unit(one));
            CHECK(with_unit(four) <= with_unit(two));
            CHECK(two["gpu"]["baseline_cycles"] == one["gpu"]["baseline_cycles"]);
        }
    }
}

TEST_CASE("gpu properties: the baseline never exceeds the time with the unit in any frame") {
    TempDir td;
    for (unsigned seed = 15; seed <= 18; ++seed) {
        const std::string t = random_trace(td, seed);
        const std::string fs = td.out_dir() + "/frames.jsonl";
        const Result r = run_sim(td, {"--trace", t, "--frame-stats", fs, "-q", "--set", "zeb.banks=1"});
        REQUIRE(r.status == 0);
        std::istringstream in(slurp(fs));
        std::string line;
        unsigned frames = 0;
        while (std::getline(in, line)) {
            const auto j = nlohmann::json::parse(line);
            CHECK(j["baseline_cycles"].get<std::uint64_t>() <= j["cycles_with_unit"].get<std::uint64_t>());
            ++frames;
        }
        CHECK(frames == 3);
    }
}

TEST_CASE("gpu properties: without collisionable fragments the overhead is 0") {
    TempDir td;
    const std::string t = random_trace(td, 21, false);
    const auto j = run_stats(td, {"--trace", t});
    CHECK(j["totals"]["fragments"] == 0);
    CHECK(j["gpu"]["baseline_cycles"].get<std::uint64_t>() > 0);
    CHECK(overhead(j) == 0.0);
}

TEST_CASE("gpu properties: the default scene is monotone in queue depths and banks") {
    TempDir td;
    check_monotone(td, {}, "feed.queue_depth", {8, 32, 128});
    check_monotone(td, {}, "gpu.fragment_queue_depth", {32, 64, 256});
    const auto one = run_stats(td, {"--set", "zeb.banks=1"});
    const auto two = run_stats(td, {});
    CHECK(with_unit(two) < with_unit(one));
    CHECK(one["gpu"]["baseline_cycles"] == two["gpu"]["baseline_cycles"]);
}

// The bulk runs against stepping, on random tiles and pipelines: fast and
// slow rasterizers, shallow and deep queues, few and many processors, both
// bank waits, one and two banks. Every output byte must agree: stats (but
// the wall time and the command line), per-frame figures, collisions.
TEST_CASE("gpu properties: bulk runs equal stepping fragment by fragment on random tiles") {
    TempDir td;
    const std::vector<std::vector<std::string>> configs = {
        {},
        {"--set", "feed.fragments_per_cycle=1", "--set", "gpu.cycles_per_fragment=1"},
        {"--set", "feed.fragments_per_cycle=3", "--set", "gpu.fragment_queue_depth=7", "--set",
         "gpu.fragment_processors=5", "--set", "gpu.cycles_per_fragment=2", "--set", "gpu.early_z_cycles=0"},
        {"--set", "feed.fragments_per_cycle=16", "--set", "gpu.fragment_queue_depth=3", "--set",
         "gpu.fragment_processors=2", "--set", "gpu.cycles_per_fragment=9", "--set", "gpu.bank_wait=unit"},
        {"--set", "zeb.banks=1", "--set", "gpu.tile_overhead_cycles=5", "--set", "gpu.setup_cycles_per_primitive=3"},
    };
    const auto strip = [](nlohmann::json j) {
        j.erase("time");
        j.erase("provenance");
        return j.dump(1);
    };
    for (unsigned seed = 30; seed < 36; ++seed) {
        const std::string t = random_trace(td, seed, seed % 3 != 2, true);
        for (const auto& cfg : configs) {
            std::string outs[2][3];
            for (int stepwise = 0; stepwise < 2; ++stepwise) {
                std::vector<std::string> args{"--trace", t, "--collisions", td.out_dir() + "/c.txt", "--frame-stats",
                                              td.out_dir() + "/f.jsonl"};
                args.insert(args.end(), cfg.begin(), cfg.end());
                if (stepwise) args.push_back("--gpu-stepwise");
                const auto j = run_stats(td, args);
                outs[stepwise][0] = strip(j);
                outs[stepwise][1] = slurp(td.out_dir() + "/f.jsonl");
                outs[stepwise][2] = slurp(td.out_dir() + "/c.txt");
            }
            std::string shown;
            for (const auto& a : cfg) shown += a + " ";
            INFO("seed " << seed << " config " << shown);
            CHECK(outs[0][0] == outs[1][0]);
            CHECK(outs[0][1] == outs[1][1]);
            CHECK(outs[0][2] == outs[1][2]);
        }
    }
}
