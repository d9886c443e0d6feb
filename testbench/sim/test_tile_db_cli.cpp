// The per-tile database (--db, docs/tile-database.md): its sums equal the
// stats JSON's totals and block counters on every vector and on the default
// scene; failures (bad paths, a full disk, a build without SQLite) are one line
// and leave no file.
#include "cli_util.h"

#include <nlohmann/json.hpp>

#ifdef RBCD_TEST_HAVE_SQLITE
#include <sqlite3.h>
#endif

using namespace rbcd::cli_test;

namespace {

#ifdef RBCD_TEST_HAVE_SQLITE
// One integer from a query (NULL: 0).
struct Db {
    sqlite3* db = nullptr;
    explicit Db(const std::string& path) {
        REQUIRE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
    }
    ~Db() { sqlite3_close(db); }
    std::int64_t value(const std::string& sql) const {
        sqlite3_stmt* st = nullptr;
        INFO(sql);
        REQUIRE(sqlite3_prepare_v2(db, sql.c_str(), -1, &st, nullptr) == SQLITE_OK);
        REQUIRE(sqlite3_step(st) == SQLITE_ROW);
        const std::int64_t v = sqlite3_column_int64(st, 0);
        sqlite3_finalize(st);
        return v;
    }
};

void check_sums(const std::vector<std::string>& input) {
    TempDir td;
    const std::string db_path = td.out_dir() + "/run.sqlite", stats_path = td.stats();
    std::vector<std::string> args = input;
    args.insert(args.end(), {"--db", db_path, "--stats", stats_path, "-q"});
    const Result r = run_sim(td, args);
    INFO(r.cmd << "\n" << r.err);
    REQUIRE(r.status == 0);
    const auto stats = nlohmann::json::parse(slurp(stats_path));
    const auto& t = stats["totals"];
    const auto& b = stats["blocks"];
    const Db db(db_path);
    const auto u = [](const nlohmann::json& j) { return j.get<std::int64_t>(); };
    CHECK(db.value("SELECT count(*) FROM frames") == u(t["frames"]));
    CHECK(db.value("SELECT count(*) FROM tiles") == u(t["tiles"]));
    CHECK(db.value("SELECT total(fragments) FROM tiles") == u(t["fragments"]));
    CHECK(db.value("SELECT total(fragments_dropped) FROM tiles") == u(t["overflows"]));
    CHECK(db.value("SELECT total(stack_overflows) FROM tiles") == u(t["stack_overflows"]));
    CHECK(db.value("SELECT total(orphan_back_faces) FROM tiles") == u(t["orphan_back_faces"]));
    CHECK(db.value("SELECT total(hits) FROM tiles") == u(t["hits"]));
    CHECK(db.value("SELECT max(end_cycle) FROM frames") == u(t["cycles"]));
    const auto& ra = b["rasterizer"];
    CHECK(db.value("SELECT total(culled) FROM tiles") == u(ra["culled_fragments"]));
    CHECK(db.value("SELECT total(other) FROM tiles") == u(ra["other_fragments"]));
    CHECK(db.value("SELECT total(prims) FROM tiles") == u(ra["primitives"]));
    CHECK(db.value("SELECT total(cprims) FROM tiles") == u(ra["culled_primitives"]));
    CHECK(db.value("SELECT count(bank) FROM tiles") == u(ra["tiles_with_fragments"]));
    for (const char* c : {"stall_no_bank", "stall_queue_full", "stall_fragment_queue"}) {
        CHECK(db.value(std::string("SELECT total(") + c + ") FROM tiles") == u(ra[std::string(c) + "_cycles"]));
        CHECK(db.value(std::string("SELECT total(") + c + ") FROM frames") == u(ra[std::string(c) + "_cycles"]));
    }
    const auto& te = b["zoverlap_tester"];
    CHECK(db.value("SELECT total(stall_output) FROM tiles") == u(te["output_stall_cycles"]));
    CHECK(db.value("SELECT total(lists) FROM tiles") == u(te["lists"]));
    CHECK(db.value("SELECT total(elements) FROM tiles") == u(te["elements"]));
    CHECK(db.value("SELECT total(filtered_hits) FROM tiles") == u(te["filtered_hits"]));
    CHECK(db.value("SELECT count(*) FROM tiles WHERE lists_overflowed > 0") == u(te["overflow_records"]));
    const auto& ob = b["output_buffer"];
    CHECK(db.value("SELECT count(*) FROM records") == u(ob["bursts"]));
    CHECK(db.value("SELECT total(bytes) FROM records") == u(ob["bytes"]));
    CHECK(db.value("SELECT total(records) FROM records") == u(ob["records"]));
    // Stages in order within each tile, each tile inside its frame.
    CHECK(db.value("SELECT count(*) FROM tiles WHERE raster_start < raster_arrive OR raster_end < raster_start "
                   "OR fill_end < fill_start OR test_start < fill_end OR test_end < test_start OR test_done < test_end") == 0);
    CHECK(db.value("SELECT count(*) FROM tiles JOIN frames USING (frame) WHERE raster_arrive < start_cycle "
                   "OR coalesce(test_done, raster_end) > end_cycle") == 0);
    CHECK(db.value("SELECT count(*) FROM tiles WHERE max_list > fragments OR elements + fragments_dropped != fragments") == 0);
    CHECK(db.value("SELECT count(*) FROM run WHERE key IN ('config', 'provenance', 'input')") == 3);
}
#endif

} // namespace

#ifdef RBCD_TEST_HAVE_SQLITE
TEST_CASE("tile db: sums equal the stats totals on every vector") {
    for (const auto& e : fs::directory_iterator(kVectors)) {
        if (e.path().extension() != ".rbt") continue;
        std::vector<std::string> args{"--trace", e.path().string()};
        fs::path toml = e.path();
        toml.replace_extension(".toml");
        if (fs::exists(toml)) args.insert(args.end(), {"--config", toml.string()});
        INFO(e.path().filename().string());
        check_sums(args);
    }
}

TEST_CASE("tile db: sums equal the stats totals on the default scene") { check_sums({}); }

TEST_CASE("tile db: a full disk is one line and no file") {
    TempDir td;
    const std::string db_path = td.out_dir() + "/run.sqlite";
    // 256 blocks of 512 bytes: the empty tables fit, the default scene's 4 MB
    // of rows do not.
    const std::string cmd = "ulimit -f 256; trap '' XFSZ; exec \"$0\" \"$@\"";
    const Result r = run_program(td, "/bin/sh", {"-c", cmd, RBCD_SIM, "-q", "--db", db_path});
    expect_error(td, r, 1, {"run.sqlite", "write failed"});
}
#endif

TEST_CASE("tile db: bad paths are one line and no file") {
    TempDir td;
    const std::string rbt = kVectors + "/rule-fig5-case2.rbt";
    if (std::system((std::string(RBCD_SIM) + " --trace " + rbt + " -q --db /dev/null/x.sqlite 2>&1 | grep -q 'without SQLite'").c_str()) == 0) {
        expect_input_error(td, run_with_outputs(td, {"--trace", rbt, "--db", td.out_dir() + "/x.sqlite"}),
                           {"--db", "without SQLite", "libsqlite3-dev"});
        return;
    }
    expect_input_error(td, run_with_outputs(td, {"--trace", rbt, "--db", "/dev/full"}), {"/dev/full", "regular file"});
    expect_input_error(td, run_with_outputs(td, {"--trace", rbt, "--db", td.path("no/such/x.sqlite")}),
                       {"no/such/x.sqlite", "cannot create"});
    expect_input_error(td, run_with_outputs(td, {"--trace", rbt, "--db", td.out_dir()}), {"is a directory"});
}

#ifdef RBCD_TEST_HAVE_SQLITE
namespace {

// The values a heat map carries (its "rbcd-heat-map" tEXt chunk): NaN where
// no tile was.
std::vector<std::vector<double>> heat_map_values(const std::string& png) {
    std::size_t at = 8;
    while (at + 12 <= png.size()) {
        std::uint32_t len = 0;
        for (int i = 0; i < 4; ++i) len = len << 8 | static_cast<unsigned char>(png[at + i]);
        const std::string type = png.substr(at + 4, 4);
        const std::string data = png.substr(at + 8, len);
        if (type == "tEXt" && data.rfind(std::string("rbcd-heat-map") + '\0', 0) == 0) {
            std::istringstream in(data.substr(14));
            unsigned cols = 0, rows = 0;
            in >> cols >> rows;
            std::vector<std::vector<double>> v(rows, std::vector<double>(cols));
            for (auto& row : v)
                for (double& x : row) {
                    std::string tok;
                    in >> tok;
                    x = tok == "-" ? NAN : std::stod(tok);
                }
            return v;
        }
        at += 12 + len;
    }
    FAIL("no rbcd-heat-map chunk");
    return {};
}

} // namespace

TEST_CASE("tile db: heat maps hold the database's per-tile sums") {
    TempDir td;
    const std::string db_path = td.out_dir() + "/run.sqlite", maps = td.path("maps");
    const Result r = run_sim(td, {"--trace", kVectors + "/multi-frame-mixed.rbt", "--config",
                                  kVectors + "/multi-frame-mixed.toml", "--db", db_path, "--heat-maps", maps, "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const Db db(db_path);
    const std::int64_t frames = db.value("SELECT count(*) FROM frames");
    const std::int64_t pixels = db.value("SELECT (SELECT value FROM run WHERE key='tile_width') * "
                                         "(SELECT value FROM run WHERE key='tile_height')");
    const std::pair<const char*, const char*> metrics[] = {
        {"stall", "stall_no_bank + stall_queue_full + stall_fragment_queue + stall_output"},
        {"overflow", "fragments_dropped"},
        {"depth", "fragments"},
        {"hits", "hits"}};
    bool any_nonzero = false;
    for (const auto& [name, expr] : metrics) {
        INFO(name);
        const std::string png = slurp(maps + "/run_" + name + ".png");
        REQUIRE(png.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0);
        const auto v = heat_map_values(png);
        REQUIRE(!v.empty());
        std::size_t cells = 0;
        for (std::size_t row = 0; row < v.size(); ++row)
            for (std::size_t col = 0; col < v[row].size(); ++col) {
                const std::string where = " FROM tiles WHERE col = " + std::to_string(col) + " AND row = " + std::to_string(row);
                const bool present = db.value("SELECT count(*)" + where) > 0;
                INFO("tile " << col << "," << row);
                CHECK(present == !std::isnan(v[row][col]));
                if (!present) continue;
                ++cells;
                double expected = static_cast<double>(db.value("SELECT total(" + std::string(expr) + ")" + where));
                if (std::string(name) == "depth") expected /= double(pixels * frames);
                CHECK(v[row][col] == Approx(expected));
                any_nonzero = any_nonzero || expected > 0;
            }
        CHECK(cells == static_cast<std::size_t>(db.value("SELECT count(*) FROM (SELECT DISTINCT col, row FROM tiles)")));
    }
    CHECK(any_nonzero);
}
#endif

#ifdef RBCD_TEST_HAVE_SQLITE
TEST_CASE("tile db: with --images, each frame's heat maps hold that frame's sums") {
    TempDir td;
    const std::string db_path = td.out_dir() + "/run.sqlite", maps = td.path("maps"), images = td.path("png");
    const Result r = run_sim(td, {"--frames", "3:4", "--images", images, "--db", db_path, "--heat-maps", maps, "-q"});
    INFO(r.err);
    REQUIRE(r.status == 0);
    const Db db(db_path);
    // The images directory keeps one PNG a frame.
    std::size_t pngs = 0;
    for (const auto& e : fs::directory_iterator(images)) pngs += e.path().extension() == ".png";
    CHECK(pngs == 2);
    for (int frame : {3, 4}) {
        char name[64];
        std::snprintf(name, sizeof name, "/frame_%05d_hits.png", frame);
        const auto v = heat_map_values(slurp(maps + name));
        REQUIRE(!v.empty());
        double sum = 0;
        for (const auto& row : v)
            for (double x : row) sum += std::isnan(x) ? 0 : x;
        CHECK(sum == Approx(static_cast<double>(
                         db.value("SELECT total(hits) FROM tiles WHERE frame = " + std::to_string(frame)))));
        std::snprintf(name, sizeof name, "/frame_%05d_stall.png", frame);
        const auto s = heat_map_values(slurp(maps + name));
        double stall = 0;
        for (const auto& row : s)
            for (double x : row) stall += std::isnan(x) ? 0 : x;
        CHECK(stall == Approx(static_cast<double>(db.value(
                           "SELECT total(stall_no_bank + stall_queue_full + stall_fragment_queue + stall_output) "
                           "FROM tiles WHERE frame = " + std::to_string(frame)))));
        CHECK(stall > 0);
    }
}
#endif

TEST_CASE("heat maps: a full disk or a file for the directory is one line and no map") {
    TempDir td;
    // Each map is a few KiB; a limit of 1 KiB fails the first.
    const std::string cmd = "ulimit -f 2; trap '' XFSZ; exec \"$0\" \"$@\"";
    const Result r = run_program(td, "/bin/sh", {"-c", cmd, RBCD_SIM, "--trace", kVectors + "/default.rbt", "-q",
                                                 "--heat-maps", td.out_dir()});
    expect_error(td, r, 1, {"run_", ".png", "write failed"});
    const std::string file = td.write("not-a-dir", "x");
    expect_input_error(td, run_with_outputs(td, {"--trace", kVectors + "/default.rbt", "--heat-maps", file}),
                       {"not-a-dir", "cannot create directory"});
}
