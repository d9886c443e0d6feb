// The per-tile database (--db run.sqlite, docs/tile-database.md): SQLite
// tables of the run (configuration, provenance), its frames, every tile
// (position, fragments by kind, primitives, each stage's start and end cycles,
// stall cycles by cause, list lengths, overflows, hits, bank) and every burst
// of records written to memory. Rows are written as the model reports them
// and committed at each frame's end, so memory stays bounded (a tile waits
// only between its rasterization and its test: at most the banks' number).
//
// SQLite is Debian's libsqlite3-dev, optional: without it --db says so.
#pragma once
#include <cstdint>
#include <deque>
#include <string>

#include "rbcd/hw/output_buffer.h"
#include "rbcd/hw/rasterizer.h"
#include "rbcd/hw/zoverlap_tester.h"

struct sqlite3;
struct sqlite3_stmt;

namespace rbcd {

class rbcd_system;

bool sqlite_supported();

class TileDatabase final : public RasterObserver, public TestObserver, public WriteObserver {
public:
    // Creates the schema in a new database at `path`; messages name `name`.
    // InputError when it cannot, or when this build has no SQLite.
    TileDatabase(const std::string& path, std::string name, unsigned tile_width, unsigned tile_height);
    ~TileDatabase() override;
    TileDatabase(const TileDatabase&) = delete;
    TileDatabase& operator=(const TileDatabase&) = delete;

    // Before the run: the model's blocks report to this.
    void attach(rbcd_system& sys);
    // A row of the run table (configuration, provenance, inputs).
    void run_fact(const std::string& key, const std::string& value);
    // After the run: the last rows, committed and closed; std::runtime_error
    // naming the file on the first write error (a full disk) of the run.
    void finish();

    void frame_begin(std::uint64_t frame) override;
    void tile_fed(const TileTimes& t) override;
    void frame_end(const FrameTimes& f) override;
    void tile_tested(const TestedTile& t) override;
    void records_written(const RecordWrite& w) override;

private:
    void exec(const char* sql);
    sqlite3_stmt* prepare(const char* sql);
    void step(sqlite3_stmt* st);
    void insert_tile(const TileTimes& r, const TestedTile* t);
    void fail(const std::string& what);

    std::string name_;
    unsigned tile_w_, tile_h_;
    sqlite3* db_ = nullptr;
    sqlite3_stmt *ins_tile_ = nullptr, *ins_frame_ = nullptr, *ins_record_ = nullptr, *ins_run_ = nullptr;
    std::deque<TileTimes> waiting_;   // rasterized, their test not yet reported
    std::uint64_t frame_ = 0;
    std::string error_;               // the first failure; later writes are skipped
};

} // namespace rbcd
