// Parser throughput: reads a .rbt trace (plain or gzip) with TraceReader and
// nothing else, and reports fragments per second of wall time.
//
//   bench_trace_read TRACE [--repeat N] [--portable-parse]
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/io/trace_reader.h"

int main(int argc, char** argv) {
    CLI::App app{"Measures TraceReader throughput"};
    std::string path;
    unsigned repeat = 3;
    rbcd::TraceLimits lim;
    app.add_option("trace", path, "trace to read")->required();
    app.add_option("--repeat", repeat, "runs; the fastest is reported")->check(CLI::Range(1u, 100u));
    app.add_option("--tile-width", lim.tile_w, "unit tile width")->check(CLI::Range(1u, 256u));
    app.add_option("--tile-height", lim.tile_h, "unit tile height")->check(CLI::Range(1u, 256u));
    app.add_option("--id-bits", lim.id_bits, "unit object id bits")->check(CLI::Range(1u, 16u));
    bool portable = false;
    app.add_flag("--portable-parse", portable, "the portable whole-line parse even where AVX-512 is available");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int rc = app.exit(e);
        return rc == 0 ? 0 : 2;
    }
    lim.wide_parse = !portable;
    try {
        double best = 0;
        for (unsigned r = 0; r < repeat; ++r) {
            auto t0 = std::chrono::steady_clock::now();
            rbcd::TraceReader reader(path, lim);
            if (r == 0) std::printf("whole-line parse: %s\n", reader.parses_wide() ? "AVX-512" : "portable");
            rbcd::Tile t;
            std::uint64_t frames = 0, tiles = 0, frags = 0, sum = 0;
            for (;;) {
                auto ev = reader.next(t);
                if (ev == rbcd::FragmentSource::Event::End) break;
                if (ev == rbcd::FragmentSource::Event::Frame) { ++frames; continue; }
                ++tiles;
                frags += t.frags.size();
                // Touch the data, as a consumer would; every field counts, so
                // that two parses that differ anywhere give different sums.
                for (const auto& f : t.frags)
                    sum = sum * 31 + ((std::uint64_t(f.x) << 48) ^ (std::uint64_t(f.y) << 32) ^ (std::uint64_t(f.id) << 24) ^
                                      f.depth ^ (std::uint64_t(f.facing == rbcd::Facing::Back) << 62) ^
                                      (std::uint64_t(f.culled) << 63));
            }
            double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            double rate = static_cast<double>(frags) / s;
            if (rate > best) best = rate;
            std::printf("run %u: %llu frames, %llu tiles, %llu fragments in %.3f s = %.2f M fragments/s (checksum %llu)\n",
                        r + 1, static_cast<unsigned long long>(frames), static_cast<unsigned long long>(tiles),
                        static_cast<unsigned long long>(frags), s, rate / 1e6, static_cast<unsigned long long>(sum));
        }
        std::printf("best: %.2f M fragments/s\n", best / 1e6);
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "bench_trace_read: %s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_trace_read: %s\n", e.what());
        return 1;
    }
    return 0;
}
