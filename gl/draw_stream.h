// The draw stream: what rbcd-gl2rbt's GL emulation (scripts/rbcd-gl2rbt)
// hands the rasterizer (rbcd-gl-raster), one frame at a time. Binary, little
// endian, on a pipe; docs/gl-capture.md defines it:
//
//   header  "RBCDGLD2" u32 width, height, tile_w, tile_h, depth_bits
//   'F' u64 call                    a frame starts (frames count up from 0)
//   'D' u64 call, draw state, mesh  a draw (DrawRecord below)
//   'C' u64 call, f64 value, i32 x0 y0 x1 y1   a depth clear (scissor, y down)
//   'S' u64 call                    depth-buffer snapshot point (the Mesa check)
//   'E' u64 call                    the frame ends (the buffer swap)
//   'Z'                             the end of the stream (inside a frame:
//                                   that frame, never swapped, is dropped)
//
// Every field is checked here (counts, enums, finite numbers, indices below
// the vertex count, frames in order): the emulation is a separate program, and
// the stream is fuzzed (fuzz/fuzz_draw_stream.cpp).
#pragma once
#include <array>
#include <cstdint>
#include <istream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rbcd/scene/tile_rasterizer.h"

namespace rbcd::gl {

struct DrawStreamHeader {
    std::uint32_t width = 0, height = 0, tile_w = 0, tile_h = 0, depth_bits = 0;
};

// Bounds on one record, so that a corrupt count cannot ask for unbounded memory.
struct DrawStreamLimits {
    std::uint32_t max_vertices = 1u << 22;    // per draw
    std::uint32_t max_triangles = 1u << 22;   // per draw
};

struct DrawRecord {
    std::uint64_t call = 0;
    scene::DrawState state;
    std::vector<Eigen::Vector4d> clip;                  // clip-space vertices
    std::vector<std::array<std::uint32_t, 3>> tris;     // indices into clip
};

class DrawStreamReader {
public:
    enum class Kind { FrameStart, Draw, DepthClear, Snapshot, FrameEnd, End };

    // Reads and checks the header; throws InputError("NAME: ...").
    DrawStreamReader(std::istream& in, std::string name, DrawStreamLimits limits = {});
    const DrawStreamHeader& header() const { return header_; }

    // The next record; throws InputError("NAME: call N: ...") on a malformed
    // one or a truncated stream. After End, returns End again.
    Kind next();
    std::uint64_t call() const { return call_; }
    std::uint64_t frame() const { return frame_; }        // of the current frame
    const DrawRecord& draw() const { return draw_; }      // after Draw
    double clear_value() const { return clear_value_; }   // after DepthClear
    const scene::PixelRect& clear_rect() const { return clear_rect_; }
    // After End: the stream stopped inside a frame, which is not part of the output.
    bool dropped_partial_frame() const { return dropped_partial_frame_; }

private:
    [[noreturn]] void fail(const std::string& what) const;
    void read(void* p, std::size_t n);
    template <typename T> T get();
    double get_finite(const char* what);
    void read_draw();

    std::istream& in_;
    std::string name_;
    DrawStreamLimits limits_;
    DrawStreamHeader header_;
    std::uint64_t call_ = 0, frame_ = 0, frames_started_ = 0;
    bool in_frame_ = false, ended_ = false, dropped_partial_frame_ = false;
    DrawRecord draw_;
    double clear_value_ = 1.0;
    scene::PixelRect clear_rect_;
};

} // namespace rbcd::gl
