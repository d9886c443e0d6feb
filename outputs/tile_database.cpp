#include "rbcd/outputs/tile_database.h"

#include <functional>
#include <stdexcept>

#include "rbcd/common/errors.h"
#include "rbcd/hw/rbcd_system.h"

#ifdef RBCD_HAVE_SQLITE
#include <sqlite3.h>
#endif

namespace rbcd {

#ifdef RBCD_HAVE_SQLITE

namespace {

// docs/tile-database.md describes every column.
const char* const kSchema = R"sql(
CREATE TABLE run (key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE frames (
  frame INTEGER PRIMARY KEY, start_cycle INTEGER, end_cycle INTEGER,
  with_unit INTEGER, gpu_done INTEGER, flushed INTEGER,
  baseline INTEGER, prims_only INTEGER, work INTEGER,
  tiles INTEGER, tiles_with_fragments INTEGER,
  fragments INTEGER, culled INTEGER, other INTEGER, prims INTEGER, cprims INTEGER,
  stall_no_bank INTEGER, stall_queue_full INTEGER, stall_fragment_queue INTEGER,
  cost_extra_prims INTEGER, cost_extra_fragments INTEGER, cost_unit INTEGER, cost_tail INTEGER);
CREATE TABLE tiles (
  id INTEGER PRIMARY KEY, frame INTEGER, col INTEGER, row INTEGER, x INTEGER, y INTEGER,
  bank INTEGER,
  fragments INTEGER, culled INTEGER, other INTEGER, prims INTEGER, cprims INTEGER,
  raster_arrive INTEGER, raster_start INTEGER, raster_end INTEGER,
  fill_start INTEGER, fill_end INTEGER, test_start INTEGER, test_end INTEGER, test_done INTEGER,
  stall_no_bank INTEGER, stall_queue_full INTEGER, stall_fragment_queue INTEGER, stall_output INTEGER,
  lists INTEGER, elements INTEGER, max_list INTEGER,
  lists_overflowed INTEGER, fragments_dropped INTEGER, stack_overflows INTEGER, orphan_back_faces INTEGER,
  hits INTEGER, filtered_hits INTEGER);
CREATE TABLE records (
  frame INTEGER, address INTEGER, bytes INTEGER, records INTEGER, issue_cycle INTEGER, done_cycle INTEGER);
)sql";

} // namespace

bool sqlite_supported() { return true; }

TileDatabase::TileDatabase(const std::string& path, std::string name, unsigned tile_width, unsigned tile_height)
    : name_(std::move(name)), tile_w_(tile_width), tile_h_(tile_height) {
    if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) != SQLITE_OK) {
        const std::string why = db_ ? sqlite3_errmsg(db_) : "out of memory";
        sqlite3_close(db_);
        db_ = nullptr;
        throw InputError(name_ + ": cannot create the database: " + why);
    }
    // The file is a temporary until the run succeeds (OutputFile): no journal,
    // no syncs; a failed run discards it whole.
    exec("PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF; PRAGMA cache_size=-4096;");
    exec(kSchema);
    ins_run_ = prepare("INSERT OR REPLACE INTO run VALUES (?,?)");
    ins_frame_ = prepare("INSERT INTO frames VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
    ins_tile_ = prepare("INSERT INTO tiles VALUES (?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?,?)");
    ins_record_ = prepare("INSERT INTO records VALUES (?,?,?,?,?,?)");
    exec("BEGIN");
    if (!error_.empty()) throw InputError(error_);
}

TileDatabase::~TileDatabase() {
    for (sqlite3_stmt* st : {ins_run_, ins_frame_, ins_tile_, ins_record_}) sqlite3_finalize(st);
    if (db_) sqlite3_close(db_);
}

void TileDatabase::fail(const std::string& what) {
    if (error_.empty()) error_ = name_ + ": database write failed: " + what + ": " + sqlite3_errmsg(db_);
}

void TileDatabase::exec(const char* sql) {
    if (!error_.empty()) return;
    if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK) fail("executing SQL");
}

sqlite3_stmt* TileDatabase::prepare(const char* sql) {
    sqlite3_stmt* st = nullptr;
    if (error_.empty() && sqlite3_prepare_v2(db_, sql, -1, &st, nullptr) != SQLITE_OK) fail("preparing SQL");
    return st;
}

void TileDatabase::step(sqlite3_stmt* st) {
    if (error_.empty() && sqlite3_step(st) != SQLITE_DONE) fail("inserting a row");
    sqlite3_reset(st);
    sqlite3_clear_bindings(st);
}

void TileDatabase::attach(rbcd_system& sys) {
    sys.raster.add_tile_observer(this);
    sys.tester.add_test_observer(this);
    sys.outbuf.set_write_observer(this);
}

void TileDatabase::run_fact(const std::string& key, const std::string& value) {
    if (!error_.empty()) return;
    sqlite3_bind_text(ins_run_, 1, key.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(ins_run_, 2, value.c_str(), -1, SQLITE_TRANSIENT);
    step(ins_run_);
}

void TileDatabase::frame_begin(std::uint64_t frame) { frame_ = frame; }

void TileDatabase::tile_fed(const TileTimes& t) {
    // A tile with a bank waits for its test; tests come in rasterization order.
    if (t.bank >= 0) waiting_.push_back(t);
    else insert_tile(t, nullptr);
}

void TileDatabase::tile_tested(const TestedTile& t) {
    if (waiting_.empty() || waiting_.front().frame != t.frame || waiting_.front().col != t.col ||
        waiting_.front().row != t.row) {
        if (error_.empty()) error_ = name_ + ": internal error: a tested tile was not rasterized in that order";
        return;
    }
    insert_tile(waiting_.front(), &t);
    waiting_.pop_front();
}

void TileDatabase::insert_tile(const TileTimes& r, const TestedTile* t) {
    if (!error_.empty()) return;
    sqlite3_stmt* st = ins_tile_;
    int i = 0;
    const auto put = [&](std::uint64_t v) { sqlite3_bind_int64(st, ++i, static_cast<sqlite3_int64>(v)); };
    const auto put_or_null = [&](bool has, std::uint64_t v) {
        if (has) put(v);
        else sqlite3_bind_null(st, ++i);
    };
    put(r.seq);
    put(r.frame);
    put(r.col);
    put(r.row);
    put(std::uint64_t(r.col) * tile_w_);
    put(std::uint64_t(r.row) * tile_h_);
    put_or_null(r.bank >= 0, static_cast<std::uint64_t>(r.bank));
    for (std::uint64_t v : {r.fragments, r.culled, r.other, r.prims, r.cprims, r.arrive, r.start, r.end}) put(v);
    put_or_null(t, r.fill_start);
    put_or_null(t, r.fill_end);
    put_or_null(t, t ? t->start : 0);
    put_or_null(t, t ? t->end : 0);
    put_or_null(t, t ? t->done : 0);
    for (std::uint64_t v : {r.stall_no_bank, r.stall_queue_full, r.stall_fragment_queue}) put(v);
    const TestedTile none{};
    const TestedTile& s = t ? *t : none;
    for (std::uint64_t v : {s.output_stall, s.lists, s.elements, s.max_list, s.lists_overflowed, s.fragments_dropped,
                            s.stack_overflows, s.orphan_back_faces, s.hits, s.filtered_hits})
        put(v);
    step(st);
}

void TileDatabase::frame_end(const FrameTimes& f) {
    if (!error_.empty()) return;
    sqlite3_stmt* st = ins_frame_;
    int i = 0;
    for (std::uint64_t v :
         {f.frame, f.start_cycle, f.end_cycle, f.with_unit, f.gpu_done, f.flushed, f.baseline, f.prims_only, f.work,
          f.tiles, f.tiles_with_fragments, f.fragments, f.culled, f.other, f.prims, f.cprims, f.stall_no_bank,
          f.stall_queue_full, f.stall_fragment_queue, f.cost_extra_prims(), f.cost_extra_fragments(), f.cost_unit(),
          f.cost_tail()})
        sqlite3_bind_int64(st, ++i, static_cast<sqlite3_int64>(v));
    step(st);
    // A frame's rows land together: the page cache stays small however long the run.
    exec("COMMIT");
    exec("BEGIN");
}

void TileDatabase::records_written(const RecordWrite& w) {
    if (!error_.empty()) return;
    int i = 0;
    for (std::uint64_t v : {frame_, w.address, w.bytes, w.records, w.issue, w.done})
        sqlite3_bind_int64(ins_record_, ++i, static_cast<sqlite3_int64>(v));
    step(ins_record_);
}

void TileDatabase::finish() {
    if (error_.empty() && !waiting_.empty()) error_ = name_ + ": internal error: tiles rasterized but never tested";
    exec("COMMIT");
    for (sqlite3_stmt*& st : {std::ref(ins_run_), std::ref(ins_frame_), std::ref(ins_tile_), std::ref(ins_record_)}) {
        sqlite3_finalize(st);
        st = nullptr;
    }
    if (error_.empty() && sqlite3_close(db_) != SQLITE_OK) fail("closing");
    else if (!error_.empty()) sqlite3_close(db_);
    db_ = nullptr;
    if (!error_.empty()) throw std::runtime_error(error_);
}

#else

bool sqlite_supported() { return false; }

TileDatabase::TileDatabase(const std::string&, std::string, unsigned, unsigned) {
    throw InputError("--db: this rbcd-sim was built without SQLite (install Debian's libsqlite3-dev: "
                     "scripts/setup.sh --waves, then rebuild)");
}
TileDatabase::~TileDatabase() = default;
void TileDatabase::attach(rbcd_system&) {}
void TileDatabase::run_fact(const std::string&, const std::string&) {}
void TileDatabase::finish() {}
void TileDatabase::frame_begin(std::uint64_t) {}
void TileDatabase::tile_fed(const TileTimes&) {}
void TileDatabase::frame_end(const FrameTimes&) {}
void TileDatabase::tile_tested(const TestedTile&) {}
void TileDatabase::records_written(const RecordWrite&) {}
void TileDatabase::exec(const char*) {}
sqlite3_stmt* TileDatabase::prepare(const char*) { return nullptr; }
void TileDatabase::step(sqlite3_stmt*) {}
void TileDatabase::insert_tile(const TileTimes&, const TestedTile*) {}
void TileDatabase::fail(const std::string&) {}

#endif

} // namespace rbcd
