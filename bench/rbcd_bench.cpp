// The speed and memory benchmark (never a timed test: CI machines are noisy).
//   rbcd-bench [--dir DIR] [--fragments N] [--jobs J] [--games DIR [--games-only]]
// 1. generates the busy-frame trace (gen_busy_trace) of N fragments and one of
//    2N, each with per-object bursts and interleaved (--interleaved);
// 2. runs rbcd-sim end to end on each as a child process, writing collisions
//    and stats as a user would: wall time and peak memory (ru_maxrss of the
//    child), so the two sizes show whether memory grows with the trace;
// 3. runs the same with --jobs J (default 2: one worker a core on this
//    project's machine), and the default scene and a 600-frame trace at
//    --jobs 1 and J: the scaling of one long run over the cores;
// 4. loads the N-fragment trace into memory and runs the model alone in this
//    process: the model's own fragments/s, parsing excluded;
// 5. with --games DIR, first runs every expanded entry of the game suite in DIR
//    (scripts/game-suite expand -o DIR) end to end, one process and --jobs J:
//    frames/s, collisionable and other fragments/s (--games-only: only these).
// Peak memory of a --jobs run is the largest of its processes' (ru_maxrss
// of the child counts the descendants it waited for as a maximum, not a sum).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <spawn.h>
#include <string>
#include <sys/resource.h>
#include <tuple>
#include <sys/wait.h>
#include <systemc>
#include <unistd.h>
#include <vector>

#include "rbcd/hw/rbcd_system.h"
#include "rbcd/io/memory_source.h"
#include "rbcd/io/trace_reader.h"

extern char** environ;

namespace {

// The kernel prints its banner before sc_main runs, unless told not to.
const bool banner_off = [] { return ::setenv("SYSTEMC_DISABLE_COPYRIGHT_MESSAGE", "1", 0) == 0; }();

struct ChildRun {
    int status = -1;
    double seconds = 0;
    long max_rss_kb = 0;
};

ChildRun run_child(const std::vector<std::string>& args) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ChildRun r;
    const auto t0 = std::chrono::steady_clock::now();
    pid_t pid;
    if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) return r;
    int status = 0;
    struct rusage ru {};
    wait4(pid, &status, 0, &ru);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.max_rss_kb = ru.ru_maxrss;
    return r;
}

std::string sibling(const char* argv0, const std::string& name) {
    std::string self = argv0;
    const auto slash = self.rfind('/');
    return (slash == std::string::npos ? std::string(".") : self.substr(0, slash)) + "/" + name;
}

// The benchmark's programs, inputs and outputs.
struct Bench {
    std::string gen, sim, dir;
    std::uint64_t fragments = 5000000;
    unsigned jobs = 2;
    std::string col, st;   // the end-to-end runs' collisions and stats

    // Best of three (or `reps`); the --jobs 1 and --jobs J runs of one input
    // alternate, so that a machine busy with other work weighs on both alike.
    std::pair<ChildRun, ChildRun> best_pair(std::vector<std::string> args, int reps = 3) const {
        args.insert(args.begin(), sim);
        args.insert(args.end(), {"-q", "--collisions", col, "--stats", st});
        std::vector<std::string> par = args;
        par.insert(par.end(), {"--jobs", std::to_string(jobs)});
        ChildRun b1, bj;
        for (int rep = 0; rep < reps; ++rep) {
            for (auto [a, b] : {std::pair{&args, &b1}, std::pair{&par, &bj}}) {
                ChildRun r = run_child(*a);
                if (r.status != 0) return std::pair{r, r};
                if (b->status != 0 || r.seconds < b->seconds) *b = r;
            }
        }
        return std::pair{b1, bj};
    }

    void row(const std::string& label, std::uint64_t n, const std::pair<ChildRun, ChildRun>& r) const {
        std::printf("%-34s %12llu %10.3f %14.0f %12.1f %10.3f %14.0f %12.1f %7.2fx\n", label.c_str(),
                    (unsigned long long)n, r.first.seconds, double(n) / r.first.seconds, r.first.max_rss_kb / 1024.0,
                    r.second.seconds, double(n) / r.second.seconds, r.second.max_rss_kb / 1024.0,
                    r.first.seconds / r.second.seconds);
    }

    // End to end as a user runs it: the collisions and the stats written.
    // Every trace but t1 (the model-only run's) is removed after.
    int end_to_end(const std::string& t1, const std::string& t2, const std::string& i1, const std::string& i2) const {
        const std::string jn = "--jobs " + std::to_string(jobs);
        std::printf("\n%-34s %12s %10s %14s %12s %10s %14s %12s %8s\n", "run (collisions, stats written)", "fragments",
                    "seconds", "fragments/s", "peak MiB", jn.c_str(), "fragments/s", "peak MiB", "speedup");
        for (const auto& [trace, n, kind] : {std::tuple{t1, fragments, ""}, std::tuple{t2, 2 * fragments, ""},
                                             std::tuple{i1, fragments, " interleaved"},
                                             std::tuple{i2, 2 * fragments, " interleaved"}}) {
            const auto r = best_pair({"--trace", trace});
            if (r.first.status != 0 || r.second.status != 0) {
                std::fprintf(stderr, "rbcd-bench: rbcd-sim failed on %s\n", trace.c_str());
                return 1;
            }
            row("rbcd-sim end to end, " + std::to_string(n / 1000000) + "M" + kind, n, r);
        }
        for (const auto& t : {t2, i1, i2}) std::remove(t.c_str());
        return 0;
    }

    // One long input over the cores: the default scene (60 frames; its
    // fragments, collisionable and other, from the stats) and 600 frames.
    int scaling() const {
        const std::string t600 = dir + "/rbcd-bench-600.rbt";
        // The busy trace's density (about ten occupied tiles a frame), over 600 frames.
        if (run_child({gen, t600, std::to_string(2 * fragments), "600", "--tiles", "10"}).status != 0) {
            std::fprintf(stderr, "rbcd-bench: trace generation failed\n");
            return 1;
        }
        const auto scene = best_pair({});
        const auto frames600 = best_pair({"--trace", t600});
        if (scene.first.status != 0 || frames600.first.status != 0 || scene.second.status != 0 ||
            frames600.second.status != 0) {
            std::fprintf(stderr, "rbcd-bench: rbcd-sim failed on the scaling runs\n");
            return 1;
        }
        // The scene's fragments, collisionable and other: those its fragment
        // processors shade, from the last run's stats.
        const std::uint64_t scene_n =
            run_child({sim, "-q", "--stats", st}).status == 0 ? stat("fragment_processors", "fragments") : 0;
        row("default scene (60 frames)", scene_n, scene);
        row("600-frame trace", 2 * fragments, frames600);
        std::remove(t600.c_str());
        return 0;
    }

    // A number of a block of the last run's stats (the stats are
    // pretty-printed, a key a line): 0 when absent.
    std::uint64_t stat(const char* block, const char* key) const {
        std::uint64_t out = 0;
        if (std::FILE* f = std::fopen(st.c_str(), "r")) {
            char line[512];
            const std::string pattern = std::string(" \"") + key + "\": %llu";
            unsigned long long v = 0;
            bool in_block = false;
            while (std::fgets(line, sizeof line, f))
                if (!in_block) in_block = std::strstr(line, (std::string("\"") + block + "\": {").c_str()) != nullptr;
                else if (std::sscanf(line, pattern.c_str(), &v) == 1) {
                    out = v;
                    break;
                }
            std::fclose(f);
        }
        return out;
    }

    // Game frames as users run them: every expanded entry of the game suite
    // in `games` (scripts/game-suite expand -o DIR: NAME.rbt.zst; NAME.rbt.gz too), end to end
    // with collisions and stats, one process and --jobs J, one run each (a
    // game entry takes seconds, not milliseconds).
    // A suite trace's entry name (its file name without .rbt.zst or .rbt.gz); empty for another file.
    static std::string trace_name(const std::string& path) {
        const std::string f = std::filesystem::path(path).filename().string();
        for (const std::string suffix : {".rbt.zst", ".rbt.gz"})
            if (f.size() > suffix.size() && f.compare(f.size() - suffix.size(), suffix.size(), suffix) == 0)
                return f.substr(0, f.size() - suffix.size());
        return {};
    }

    int game_rows(const std::string& games) const {
        std::vector<std::string> traces;
        std::error_code ec;
        for (const auto& e : std::filesystem::directory_iterator(games, ec))
            if (!trace_name(e.path().string()).empty()) traces.push_back(e.path().string());
        if (ec || traces.empty()) {
            std::fprintf(stderr, "rbcd-bench: --games %s: no expanded entries (NAME.rbt.zst; scripts/game-suite expand -o DIR)\n",
                         games.c_str());
            return 2;
        }
        std::sort(traces.begin(), traces.end());
        const std::string jn = "--jobs " + std::to_string(jobs);
        std::printf("\n%-28s %6s %11s %12s %9s %9s %13s %13s %9s %9s %8s\n", "game entry (end to end)", "frames",
                    "fragments", "other", "seconds", "frames/s", "fragments/s", "other/s", jn.c_str(), "frames/s",
                    "speedup");
        for (const auto& t : traces) {
            const auto r = best_pair({"--trace", t}, 1);
            if (r.first.status != 0 || r.second.status != 0) {
                std::fprintf(stderr, "rbcd-bench: rbcd-sim failed on %s\n", t.c_str());
                return 1;
            }
            const std::uint64_t frames = stat("rasterizer", "frames"), frags = stat("rasterizer", "fragments"),
                                other = stat("rasterizer", "other_fragments");
            const std::string name = trace_name(t);
            const double s1 = r.first.seconds, sj = r.second.seconds;
            std::printf("%-28s %6llu %11llu %12llu %9.2f %9.1f %13.0f %13.0f %9.2f %9.1f %7.2fx\n", name.c_str(),
                        (unsigned long long)frames, (unsigned long long)frags, (unsigned long long)other, s1,
                        double(frames) / s1, double(frags) / s1, double(other) / s1, sj, double(frames) / sj, s1 / sj);
        }
        return 0;
    }

    // Long runs: peak memory must not grow with the number of frames (per-frame
    // figures stream to --frame-stats). Frames of one small tile each. Before the
    // model-only run: a child's ru_maxrss counts the parent's pages until exec.
    int long_runs() const {
        std::printf("\n%-34s %12s %10s %12s\n", "long run, frames of one tile", "frames", "seconds", "peak MiB");
        for (const std::uint64_t frames : {std::uint64_t(1000), std::uint64_t(100000), std::uint64_t(1000000)}) {
            const std::string t = dir + "/rbcd-bench-frames.rbt", fs = dir + "/rbcd-bench-frames.jsonl",
                              st = dir + "/rbcd-bench-frames.json";
            std::FILE* f = std::fopen(t.c_str(), "w");
            if (!f) return 1;
            std::fputs("rbcd-trace 1\n", f);
            for (std::uint64_t i = 0; i < frames; ++i)
                std::fprintf(f, "frame %llu\ntile %llu 0 other=20\nf %llu 1 100 1 F\nf %llu 1 200 1 B\n",
                             (unsigned long long)i, (unsigned long long)(i % 50), (unsigned long long)(i % 50 * 16),
                             (unsigned long long)(i % 50 * 16));
            std::fclose(f);
            const ChildRun r = run_child({sim, "--trace", t, "-q", "--stats", st, "--frame-stats", fs});
            if (r.status != 0) {
                std::fprintf(stderr, "rbcd-bench: rbcd-sim failed on the %llu-frame trace\n", (unsigned long long)frames);
                return 1;
            }
            std::printf("%-34s %12llu %10.3f %12.1f\n", "rbcd-sim with --stats --frame-stats", (unsigned long long)frames,
                        r.seconds, r.max_rss_kb / 1024.0);
            std::remove(t.c_str());
            std::remove(fs.c_str());
            std::remove(st.c_str());
        }
        return 0;
    }
};

// Model alone: the trace is parsed into memory first, then only the SystemC run is timed.
void model_only(const std::string& trace) {
    rbcd::SimConfig cfg;
    rbcd::TraceReader reader(trace, {cfg.tile.width, cfg.tile.height, cfg.zeb.id_bits});
    rbcd::MemorySource mem(reader.header(), trace);
    mem.read_all(reader);
    rbcd::RecordingSink sink;
    rbcd::rbcd_system sys("rbcd", cfg, mem, sink);
    const auto t0 = std::chrono::steady_clock::now();
    sys.run();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto n = sys.raster.stats().fragments;
    std::printf("%-34s %12llu %10.3f %14.0f %12s\n", "model only (trace in memory)", (unsigned long long)n, secs,
                double(n) / secs, "-");
    std::printf("\nsimulated: %llu cycles, %llu hits, %llu overflows\n", (unsigned long long)sys.total_cycles(),
                (unsigned long long)sys.tester.stats().hits, (unsigned long long)sys.sorter.stats().overflows);
}

} // namespace

int sc_main(int argc, char* argv[]) {
    Bench b;
    b.dir = "/tmp";
    CLI::App app{"rbcd-bench: end-to-end and model-only speed, peak memory"};
    app.add_option("--dir", b.dir, "where the generated traces go");
    app.add_option("--fragments", b.fragments, "fragments of the base trace");
    app.add_option("--jobs", b.jobs, "rbcd-sim --jobs for the parallel rows (default 2)")->check(CLI::Range(2u, 1024u));
    std::string games;
    app.add_option("--games", games,
                   "also run the game suite's expanded entries in DIR (scripts/game-suite expand -o DIR)");
    bool games_only = false;
    app.add_flag("--games-only", games_only, "only the game rows (with --games)");
    CLI11_PARSE(app, argc, argv);
    sc_core::sc_report_handler::set_actions(sc_core::SC_INFO, sc_core::SC_DO_NOTHING);

    b.gen = sibling(argv[0], "gen_busy_trace");
    b.sim = sibling(argv[0], "rbcd-sim");
    std::error_code ec;
    std::filesystem::create_directories(b.dir, ec);
    if (ec) {
        std::fprintf(stderr, "rbcd-bench: %s: cannot create: %s\n", b.dir.c_str(), ec.message().c_str());
        return 2;
    }
    if (!games.empty()) {
        b.col = b.dir + "/rbcd-bench.collisions";
        b.st = b.dir + "/rbcd-bench.json";
        const int rc = b.game_rows(games);
        std::remove(b.col.c_str());
        std::remove(b.st.c_str());
        if (rc != 0 || games_only) return rc;
    } else if (games_only) {
        std::fprintf(stderr, "rbcd-bench: --games-only needs --games DIR\n");
        return 2;
    }
    const std::string& dir = b.dir;
    const std::string t1 = dir + "/rbcd-bench-1x.rbt", t2 = dir + "/rbcd-bench-2x.rbt";
    const std::string i1 = dir + "/rbcd-bench-1x-interleaved.rbt", i2 = dir + "/rbcd-bench-2x-interleaved.rbt";
    std::printf("generating %llu and %llu fragment traces in %s, bursty and interleaved ...\n",
                (unsigned long long)b.fragments, (unsigned long long)(2 * b.fragments), dir.c_str());
    const std::string n1 = std::to_string(b.fragments), n2 = std::to_string(2 * b.fragments);
    if (run_child({b.gen, t1, n1, "8"}).status != 0 || run_child({b.gen, t2, n2, "16"}).status != 0 ||
        run_child({b.gen, i1, n1, "8", "--interleaved"}).status != 0 ||
        run_child({b.gen, i2, n2, "16", "--interleaved"}).status != 0) {
        std::fprintf(stderr, "rbcd-bench: trace generation failed\n");
        return 1;
    }
    b.col = dir + "/rbcd-bench.collisions";
    b.st = dir + "/rbcd-bench.json";
    if (b.end_to_end(t1, t2, i1, i2) != 0 || b.scaling() != 0) return 1;
    std::remove(b.col.c_str());
    std::remove(b.st.c_str());
    if (b.long_runs() != 0) return 1;
    model_only(t1);
    std::remove(t1.c_str());
    return 0;
}
