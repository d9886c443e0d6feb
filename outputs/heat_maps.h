// Heat maps of the screen, one cell a tile (docs/tile-database.md): stall
// cycles (the rasterizer's three causes and the tester's output stalls),
// overflows (fragments dropped by full lists), collisionable depth complexity
// (collisionable fragments per pixel of the tile) and hits. Summed over the
// run (--heat-maps DIR), and also per frame when --images is given.
//
// Each PNG has a colour scale with its legend and title, and carries its
// values in a tEXt chunk ("rbcd-heat-map": the grid, row by row), so that
// tools and tests read the numbers rather than the colours.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "rbcd/hw/rasterizer.h"
#include "rbcd/hw/zoverlap_tester.h"

namespace rbcd {

class rbcd_system;

class HeatMaps final : public RasterObserver, public TestObserver {
public:
    enum Metric { Stall, Overflow, Depth, Hits, kMetrics };
    static const char* file_name(Metric m);   // "stall", "overflow", "depth", "hits"

    // Maps into `dir`: run_<metric>.png at the end; frame_NNNNN_<metric>.png
    // at each frame's end when `per_frame`.
    HeatMaps(std::string dir, bool per_frame, unsigned screen_w, unsigned screen_h, unsigned tile_w, unsigned tile_h);
    ~HeatMaps() override;   // removes every map written unless keep()
    void attach(rbcd_system& sys);
    // After the run: the run's maps.
    void finish();
    // The first map that could not be written, in one line; empty: none.
    // (Reported, not thrown: maps are written from the simulation's processes.)
    const std::string& error() const { return error_; }
    void keep() { keep_ = true; }
    const std::vector<std::string>& written() const { return written_; }

    void tile_fed(const TileTimes& t) override;
    void tile_tested(const TestedTile& t) override;
    void frame_end(const FrameTimes& f) override;

    // The PNG of one map (for tests and tools): values are per tile, row-major.
    static std::string render(const std::vector<double>& values, unsigned cols, unsigned rows, Metric m,
                              const std::string& title);

private:
    struct Grid {
        std::vector<double> v[kMetrics];
    };
    double& at(Grid& g, Metric m, std::uint32_t col, std::uint32_t row);
    void write(const Grid& g, const std::string& name, const std::string& title, double depth_scale);

    std::string dir_;
    bool per_frame_;
    unsigned cols_, rows_, tile_pixels_;
    Grid frame_, run_;
    std::uint64_t frames_ = 0;
    std::vector<std::string> written_;
    bool keep_ = false;
    std::string error_;
};

} // namespace rbcd
