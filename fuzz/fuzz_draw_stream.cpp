// The draw stream rbcd-gl2rbt hands rbcd-gl-raster (gl/draw_stream.h): read
// and, on small screens, rasterized as rbcd-gl-raster does. Findings: a crash
// or sanitizer report, a multi-line message, a fragment outside its tile or
// the screen, a depth above the maximum, End that is not sticky.
#include <sstream>
#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/fuzz/fuzz_util.h"
#include "rbcd/gl/draw_stream.h"
#include "rbcd/scene/tile_rasterizer.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
    rbcd::gl::DrawStreamLimits lim;
    lim.max_vertices = 4096;
    lim.max_triangles = 4096;
    try {
        rbcd::gl::DrawStreamReader r(in, "stream", lim);
        const auto& h = r.header();
        // Large screens are parsed, not rasterized: the run explores the reader.
        const bool raster = std::uint64_t(h.width) * h.height <= 256 * 256 &&
                            std::uint64_t((h.width + h.tile_w - 1) / h.tile_w) * ((h.height + h.tile_h - 1) / h.tile_h) <= 4096;
        std::unique_ptr<rbcd::scene::TileRasterizer> ras;
        if (raster) {
            ras = std::make_unique<rbcd::scene::TileRasterizer>(h.width, h.height, h.tile_w, h.tile_h, h.depth_bits);
            ras->keep_depth_buffer(true);
        }
        rbcd::Tile t;
        for (;;) {
            const auto k = r.next();
            if (k == rbcd::gl::DrawStreamReader::Kind::End) break;
            if (!ras) continue;
            switch (k) {
            case rbcd::gl::DrawStreamReader::Kind::FrameStart: ras->begin_frame(r.frame()); break;
            case rbcd::gl::DrawStreamReader::Kind::Draw: {
                const auto& d = r.draw();
                const auto i = ras->add_draw(d.state);
                (void)ras->add_mesh(i, d.clip.data(), d.clip.size(), d.tris.data(), d.tris.size());
                break;
            }
            case rbcd::gl::DrawStreamReader::Kind::DepthClear: ras->add_depth_clear(r.clear_value(), r.clear_rect()); break;
            case rbcd::gl::DrawStreamReader::Kind::Snapshot: ras->snapshot_depth_here(); break;
            case rbcd::gl::DrawStreamReader::Kind::FrameEnd:
                while (ras->next_tile(t, nullptr)) {
                    for (const auto& f : t.frags) {
                        if (f.x >= h.width || f.y >= h.height) rbcd::fuzz::finding("fragment outside the screen");
                        if (f.x / h.tile_w != t.col || f.y / h.tile_h != t.row) rbcd::fuzz::finding("fragment outside its tile");
                        if (f.depth > ras->depth_max()) rbcd::fuzz::finding("depth above the maximum");
                    }
                }
                break;
            default: break;
            }
        }
        if (r.next() != rbcd::gl::DrawStreamReader::Kind::End) rbcd::fuzz::finding("End is not sticky");
    } catch (const rbcd::InputError& e) {
        const std::string m = e.what();
        if (m.find('\n') != std::string::npos) rbcd::fuzz::finding("multi-line message: " + m);
    }
    return 0;
}
