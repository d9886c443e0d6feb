// rbcd-gl-raster: the rasterizing half of rbcd-gl2rbt (docs/gl-capture.md).
// Reads a draw stream (gl/draw_stream.h) on standard input, rasterizes every
// frame through the scene front end's tile rasterizer and writes the fragment
// trace; optionally the depth buffer at each frame's snapshot point and one
// JSON line of figures per frame. rbcd-gl2rbt runs it; it is not a user's
// command, but it is held to the same rules: a malformed stream is one line
// naming the call, exit 2, and no output left behind.
//
//   rbcd-gl-raster --trace OUT.rbt[.gz] [--depth-out PREFIX [--llvmpipe-depth-out PREFIX2]]
//                  [--summary FILE] [--name CAPTURE] [--ids-out FILE --ids-frame N]
//
// --llvmpipe-depth-out: beside the depth buffer of GL's exact depths, the one
// Mesa's llvmpipe would hold with the same covered pixels and its own float32
// depth arithmetic (scene/llvmpipe_depth.h), written at the same snapshots in
// the same format; for the depth check only, the trace is the same.
// --ids-out: for frame N, the draw (its index in the frame) nearest the eye
// at every pixel, displayed faces only ("rbcd-ids 1 W H", then W*H u16 little
// endian, 0xFFFF none): rbcd-gl2rbt --list-draws --image labels draws with it.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <new>
#include <set>
#include <string>
#include <vector>

#include "rbcd/common/errors.h"
#include "rbcd/gl/draw_stream.h"
#include "rbcd/io/trace_reader.h"
#include "rbcd/io/trace_writer.h"
#include "rbcd/common/output_file.h"
#include "rbcd/scene/tile_rasterizer.h"

namespace {

struct Options {
    std::string trace, depth_out, llvmpipe_depth_out, summary, ids_out, name = "draw stream";
    std::uint64_t ids_frame = 0;
};

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        const auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw rbcd::InputError(a + ": needs a value");
            return argv[++i];
        };
        if (a == "--trace") o.trace = value();
        else if (a == "--depth-out") o.depth_out = value();
        else if (a == "--llvmpipe-depth-out") o.llvmpipe_depth_out = value();
        else if (a == "--summary") o.summary = value();
        else if (a == "--name") o.name = value();
        else if (a == "--ids-out") o.ids_out = value();
        else if (a == "--ids-frame") {
            const std::string v = value();
            char* end = nullptr;
            o.ids_frame = std::strtoull(v.c_str(), &end, 10);
            if (v.empty() || *end || v[0] == '-') throw rbcd::InputError("--ids-frame: '" + v + "' is not a frame number");
        }
        else throw rbcd::InputError("unknown option '" + a + "' (see gl/gl_raster_main.cpp)");
    }
    if (o.trace.empty()) throw rbcd::InputError("--trace is required");
    if (!o.llvmpipe_depth_out.empty() && o.depth_out.empty())
        throw rbcd::InputError("--llvmpipe-depth-out needs --depth-out");
    return o;
}

// One frame's figures, for rbcd-gl2rbt's report.
struct FrameFigures {
    std::uint64_t tiles = 0, fragments = 0, culled = 0, other = 0, prims = 0, cprims = 0, draws = 0;
    std::set<std::uint32_t> objects;
};

std::string json_line(std::uint64_t frame, std::uint64_t call, const FrameFigures& f) {
    std::string s = "{\"frame\":" + std::to_string(frame) + ",\"end_call\":" + std::to_string(call) +
                    ",\"draws\":" + std::to_string(f.draws) + ",\"tiles\":" + std::to_string(f.tiles) +
                    ",\"fragments\":" + std::to_string(f.fragments) + ",\"culled\":" + std::to_string(f.culled) +
                    ",\"other\":" + std::to_string(f.other) + ",\"prims\":" + std::to_string(f.prims) +
                    ",\"cprims\":" + std::to_string(f.cprims) + ",\"objects\":[";
    bool first = true;
    for (auto id : f.objects) {
        if (!first) s += ',';
        s += std::to_string(id);
        first = false;
    }
    return s + "]}\n";
}

int run(const Options& o) {
    rbcd::gl::DrawStreamReader in(std::cin, o.name);
    const auto& h = in.header();
    rbcd::scene::TileRasterizer raster(h.width, h.height, h.tile_w, h.tile_h, h.depth_bits);
    // A tile of more fragments than rbcd-sim reads at its default (its
    // input.max_tile_fragments) is refused as it is rasterized: a few
    // bytes of capture drawing the screen over and over would otherwise
    // take gigabytes and minutes, for a trace rbcd-sim refuses.
    const std::uint64_t max_tile = rbcd::TraceLimits{}.max_tile_fragments;
    raster.limit_tile_fragments(max_tile);
    raster.keep_depth_buffer(!o.depth_out.empty());
    // The replay runs on this machine: its JIT code fuses multiply-adds when the CPU can.
    if (!o.llvmpipe_depth_out.empty()) raster.keep_llvmpipe_depth(rbcd::scene::LlvmpipeDepth::host_has_fma());

    // Every output is committed only at the end: a run that fails leaves none.
    rbcd::OutputFile trace_file(o.trace);
    rbcd::StreamHeader sh;
    sh.screen_w = h.width;
    sh.screen_h = h.height;
    sh.tile_w = h.tile_w;
    sh.tile_h = h.tile_h;
    sh.depth_bits = h.depth_bits;
    rbcd::TraceWriter trace(trace_file.shared_fd(), sh, rbcd::trace_compression_for(o.trace), o.trace);
    rbcd::OutputFile summary;
    if (!o.summary.empty()) {
        summary = rbcd::OutputFile(o.summary);
    }
    std::vector<rbcd::OutputFile> depth_files;
    rbcd::OutputFile ids;
    rbcd::scene::SceneSource::FrameImage image;
    std::uint32_t draws_in_frame = 0;

    FrameFigures fig;
    bool snapshot = false;
    rbcd::Tile tile;
    for (;;) {
        const auto kind = in.next();
        if (kind == rbcd::gl::DrawStreamReader::Kind::End) break;
        switch (kind) {
        case rbcd::gl::DrawStreamReader::Kind::FrameStart:
            raster.begin_frame(in.frame());
            fig = FrameFigures{};
            snapshot = false;
            draws_in_frame = 0;
            break;
        case rbcd::gl::DrawStreamReader::Kind::Draw: {
            const auto& d = in.draw();
            auto state = d.state;
            // Labels for --ids-out: the draw's index in the frame (saturating).
            state.object = static_cast<std::uint16_t>(std::min<std::uint32_t>(draws_in_frame++, 0xFFFEu));
            const auto draw = raster.add_draw(std::move(state));
            ++fig.draws;
            if (!raster.add_mesh(draw, d.clip.data(), d.clip.size(), d.tris.data(), d.tris.size()))
                throw rbcd::InputError(o.name + ": call " + std::to_string(d.call) +
                                       ": a vertex projects to a non-finite or out-of-range window coordinate");
            break;
        }
        case rbcd::gl::DrawStreamReader::Kind::DepthClear:
            raster.add_depth_clear(in.clear_value(), in.clear_rect());
            break;
        case rbcd::gl::DrawStreamReader::Kind::Snapshot:
            raster.snapshot_depth_here();
            snapshot = true;
            break;
        case rbcd::gl::DrawStreamReader::Kind::FrameEnd: {
            trace.frame(in.frame());   // at the swap: a frame never swapped is not written
            const bool want_ids = !o.ids_out.empty() && in.frame() == o.ids_frame;
            if (want_ids) {
                image.width = h.width;
                image.height = h.height;
                image.pixels.assign(std::size_t(h.width) * h.height, rbcd::scene::SceneSource::ImagePixel{});
            }
            for (;;) {
                try {
                    if (!raster.next_tile(tile, want_ids ? &image : nullptr)) break;
                } catch (const rbcd::scene::TileTooFull& e) {
                    throw rbcd::InputError(o.name + ": frame " + std::to_string(in.frame()) + " (its swap, call " +
                                           std::to_string(in.call()) + "): tile " + std::to_string(e.col) + " " +
                                           std::to_string(e.row) + " holds more than " + std::to_string(max_tile) +
                                           " fragments, collisionable and other (rbcd-sim reads at most as many collisionable ones a "
                                           "tile, input.max_tile_fragments; docs/gl-capture.md, limits)");
                }
                trace.tile(tile);
                ++fig.tiles;
                fig.other += tile.other;
                fig.prims += tile.prims;
                fig.cprims += tile.cprims;
                fig.fragments += tile.frags.size();
                for (const auto& f : tile.frags) {
                    fig.culled += f.culled;
                    fig.objects.insert(f.id);
                }
            }
            if (summary.active()) summary.write(json_line(in.frame(), in.call(), fig));
            if (want_ids) {
                ids = rbcd::OutputFile(o.ids_out);
                ids.write("rbcd-ids 1 " + std::to_string(h.width) + " " + std::to_string(h.height) + "\n");
                std::vector<std::uint16_t> row(h.width);
                for (unsigned y = 0; y < h.height; ++y) {
                    for (unsigned x = 0; x < h.width; ++x) row[x] = image.at(x, y).object;
                    ids.write(reinterpret_cast<const char*>(row.data()), row.size() * sizeof row[0]);
                }
            }
            // rbcd-depth 2 W H BITS, then W*H u32 little endian, rows from the
            // top, then W*H u8: 1 where a draw whose fragment stage can
            // discard or write depth wrote the pixel's depth last.
            const auto dump = [&](const std::string& prefix, const std::vector<std::uint32_t>& buf,
                                  const std::vector<std::uint8_t>& marks) {
                depth_files.emplace_back(prefix + "." + std::to_string(in.frame()) + ".depth");
                rbcd::OutputFile& df = depth_files.back();
                df.write("rbcd-depth 2 " + std::to_string(h.width) + " " + std::to_string(h.height) + " " +
                         std::to_string(h.depth_bits) + "\n");
                df.write(reinterpret_cast<const char*>(buf.data()), buf.size() * sizeof buf[0]);
                df.write(reinterpret_cast<const char*>(marks.data()), marks.size());
            };
            if (snapshot && !o.depth_out.empty()) dump(o.depth_out, raster.depth_buffer(), raster.depth_marks());
            if (snapshot && !o.llvmpipe_depth_out.empty())
                dump(o.llvmpipe_depth_out, raster.llvmpipe_depth_buffer(), raster.llvmpipe_depth_marks());
            break;
        }
        default: break;
        }
    }
    trace.close();
    trace_file.commit();
    if (summary.active()) summary.commit();
    for (auto& df : depth_files) df.commit();
    if (!o.ids_out.empty() && !ids.active())
        throw rbcd::InputError("--ids-frame " + std::to_string(o.ids_frame) + ": the stream has no such frame");
    if (ids.active()) ids.commit();
    rbcd::outputs_complete();
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    rbcd::report_file_size_limit_as_write_error();
    std::ios::sync_with_stdio(false);
    Options o;
    try {
        o = parse(argc, argv);
        return run(o);
    } catch (const rbcd::InputError& e) {
        std::fprintf(stderr, "rbcd-gl-raster: %s\n", e.what());
        return 2;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "rbcd-gl-raster: %s%sout of memory; no output written\n", o.name.c_str(),
                     o.name.empty() ? "" : ": ");
        return 1;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "rbcd-gl-raster: %s\n", e.what());
        return 1;
    }
}
