// The tile-based rasterizer shared by the two geometry front ends: the 3D scene
// (scene/renderer.*) and captured OpenGL streams (gl/). Per frame, draws come
// in submission order, each a state (viewport, depth range, culling, polygon
// offset, scissor, clip planes, depth test) and a mesh of clip-space vertices;
// triangles are clipped, projected, snapped, culled and binned to tiles. Then,
// tile by tile, integer edge-function rasterization of the tile's list in
// submission order.
//
// The rules (docs/scene.md, "Rasterization"): pixel centres sample, 8
// sub-pixel bits, top-left fill rule (bottom-left for captured GL draws),
// window depth affine in screen space and rounded to depth_bits at the
// pixel centre, a guard band of 4x the screen
// instead of side clipping. A triangle culled by its draw's face culling still
// reaches the unit when its draw is collisionable (tagged `c`); otherwise it is
// dropped before binning.
//
//   TileRasterizer r(800, 480, 16, 16, 24);
//   r.begin_frame(0);
//   DrawState s = DrawState::full_screen(800, 480); s.collisionable = true; s.id = 5;
//   const auto d = r.add_draw(s);
//   if (!r.add_mesh(d, clip, n, tris, ntris)) /* a vertex projects out of range */;
//   while (r.next_tile(tile, nullptr)) ...;
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rbcd/common/fragment.h"
#include "rbcd/scene/llvmpipe_depth.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd::scene {

constexpr int kSubBits = 8;                  // sub-pixel bits of snapped vertex positions
constexpr std::int64_t kSub = 1 << kSubBits;
constexpr unsigned kMaxUserClipPlanes = 8;

enum class CullFace : std::uint8_t { None, Back, Front, FrontAndBack };
// OpenGL's depth comparisons, in GL's order (GL_NEVER + i).
enum class DepthFunc : std::uint8_t { Never, Less, Equal, Lequal, Greater, Notequal, Gequal, Always };

// Screen pixels, y down, inclusive.
struct PixelRect {
    std::int32_t x0 = 0, y0 = 0, x1 = -1, y1 = -1;
};

// What one draw's triangles share.
struct DrawState {
    // Viewport in screen pixels with y down: (vx, vy) is its top-left corner.
    double vx = 0, vy = 0, vw = 0, vh = 0;
    double depth_near = 0.0, depth_far = 1.0;   // glDepthRange
    CullFace cull = CullFace::Back;
    bool front_ccw = true;                      // glFrontFace(GL_CCW); false for GL_CW or a mirrored object
    // Polygon offset in depth units (one unit = one step of depth_bits):
    // factor * max(|dz/dx|, |dz/dy|) + units, added before rounding.
    double offset_factor = 0.0, offset_units = 0.0;
    PixelRect scissor;                          // fragments outside are dropped; the whole screen when off
    // User clip planes in clip space: a point c is kept where plane . c >= 0.
    std::vector<Eigen::Vector4d> clip_planes;
    bool collisionable = false;
    std::uint32_t id = 0;                       // object id, when collisionable
    std::uint16_t object = 0;                   // index into FrameImage::objects
    // The depth buffer (kept only when asked for: keep_depth_buffer()).
    bool depth_test = true;
    DepthFunc depth_func = DepthFunc::Less;
    bool depth_write = true;
    // The depth plane through the vertices' window positions before
    // sub-pixel snapping (as Mesa's llvmpipe interpolates), rather than
    // through the snapped corners (the scene front end's rule).
    bool depth_from_unsnapped = false;
    // A sample exactly on an edge belongs to the triangle when the edge is a
    // left or a bottom one on screen (OpenGL's rule as Mesa applies it: in
    // GL's window coordinates, y up, in a window and a framebuffer object
    // alike), rather than a left or a top one (the scene front end's rule).
    bool bottom_left_fill = false;
    // Its fragment stage can discard fragments or write their depth (a
    // captured draw under such a fragment shader): the depth it writes to
    // the kept buffer is an upper bound, marked in depth_marks().
    bool fragment_effects = false;
    // glProvokingVertex(GL_FIRST_VERTEX_CONVENTION): no fragment changes;
    // read by the llvmpipe emulation (keep_llvmpipe_depth), whose clipped
    // polygons fan out and whose clockwise triangles are reordered by it.
    bool first_vertex_provokes = false;
    // What shading one of its fragments costs, in percent of
    // gpu.cycles_per_fragment (a captured draw's fragment shader; 0: not
    // given, counted as 100). A tile any such draw reaches carries the mean
    // over its shaded fragments as shade= (docs/gpu-model.md).
    std::uint16_t shade = 0;

    static DrawState full_screen(unsigned width, unsigned height);
};

// Thrown by next_tile when a tile holds more fragments than
// limit_tile_fragments allows.
struct TileTooFull : std::runtime_error {
    TileTooFull(std::uint64_t frame, unsigned col, unsigned row, std::uint64_t limit)
        : std::runtime_error("frame " + std::to_string(frame) + ", tile " + std::to_string(col) + " " +
                             std::to_string(row) + ": more than " + std::to_string(limit) + " fragments"),
          frame(frame), col(col), row(row), limit(limit) {}
    std::uint64_t frame;
    unsigned col, row;
    std::uint64_t limit;
};

class TileRasterizer {
public:
    // Screen and tile sizes up to kMaxScreenSide (scene/scene_file.h);
    // depth_bits 1..32.
    TileRasterizer(unsigned width, unsigned height, unsigned tile_w, unsigned tile_h, unsigned depth_bits);

    unsigned width() const { return width_; }
    unsigned height() const { return height_; }
    unsigned tiles_x() const { return tiles_x_; }
    unsigned tiles_y() const { return tiles_y_; }
    double depth_max() const { return depth_max_; }

    // Starts frame f: no draws, the tile cursor at the first tile. The depth
    // buffer (when kept) carries over from the frame before, as GL's does.
    void begin_frame(std::uint64_t f);
    std::uint32_t add_draw(DrawState s);
    // Clips, projects, culls and bins the triangles of `draw` (vertex indices
    // below nverts, checked by the caller). False, with nothing binned from
    // the offending vertex on, when a vertex projects to a non-finite or
    // out-of-range window coordinate.
    bool add_mesh(std::uint32_t draw, const Eigen::Vector4d* clip, std::size_t nverts,
                  const std::array<std::uint32_t, 3>* tris, std::size_t ntris);
    // A depth-buffer clear at this point of the submission order.
    void add_depth_clear(double value01, PixelRect scissor);
    // A tile's fragments, collisionable and other together, past which
    // next_tile throws TileTooFull (collisionable ones before they are
    // stored, other ones, only counted, after each triangle): what bounds
    // the memory and time of a small input drawing over and over the same
    // pixels. Unbounded by default.
    void limit_tile_fragments(std::uint64_t n) { max_tile_fragments_ = n; }

    // Rasterizes tiles in row-major order from the cursor and returns the next
    // one holding at least one fragment (collisionable, or counted in `other`);
    // false once the frame has no more. When `image` is given, the nearest
    // displayed surface of every pixel is recorded into it.
    bool next_tile(Tile& tile, SceneSource::FrameImage* image);

    // The depth buffer OpenGL would hold, by the draws' depth tests, for the
    // triangles and clears added before the snapshot point (all by default).
    void keep_depth_buffer(bool on) { keep_depth_ = on; }
    void snapshot_depth_here() { depth_limit_ = tris_.size(); }
    // Row-major, y down, in depth units; valid once next_tile returned false.
    const std::vector<std::uint32_t>& depth_buffer() const { return depth_; }
    // Per pixel of the kept depth buffer: 1 where its depth was last written
    // by a draw with fragment_effects, 0 elsewhere.
    const std::vector<std::uint8_t>& depth_marks() const { return marks_; }
    // With the depth buffer kept, a second one beside it for the depth
    // check: the same triangles, the same covered pixels, each pixel's depth
    // (and so its depth tests) as Mesa's llvmpipe computes it from the same
    // clip-space vertices (LlvmpipeDepth, scene/llvmpipe_depth.h). Call
    // before the first frame; fma as LlvmpipeDepth's.
    void keep_llvmpipe_depth(bool fma);
    const std::vector<std::uint32_t>& llvmpipe_depth_buffer() const { return lp_depth_; }
    const std::vector<std::uint8_t>& llvmpipe_depth_marks() const { return lp_marks_; }

    // Of the current frame: triangles set up and binned.
    std::size_t triangles_set_up() const { return tris_.size(); }

private:
    // A triangle after setup: edge functions E(p) = a*px + b*py + c over
    // fixed-point pixel coordinates, positive inside, c carrying the fill-rule
    // bias; depth as a plane over pixel coordinates. A depth clear is an entry
    // with `clear` set, binned to the tiles its rectangle touches.
    struct Tri {
        std::int64_t a[3], b[3], c[3];
        double zx, zy, z0;             // depth at pixel centre (px, py) = z0 + zx*(px - x0) + zy*(py - y0)
        double x0, y0;                 // first vertex, pixels
        std::int32_t px0, py0, px1, py1;   // pixel bounding box, inclusive, on screen and in the scissor
        std::uint32_t draw;
        Facing facing;
        bool culled, clear;
    };
    struct ScreenVert {
        std::int32_t x, y;   // fixed point, kSubBits
        double z;            // 0..depth_max
        double fx, fy;       // before snapping, pixels
    };

    bool project(const DrawState& s, const Eigen::Vector4d& clip, ScreenVert& out) const;
    std::uint16_t outcode(const DrawState& s, const Eigen::Vector4d& v) const;
    bool clip_and_setup(const Eigen::Vector4d* c[3], std::uint32_t draw);
    void setup(const ScreenVert& v0, const ScreenVert& v1, const ScreenVert& v2, std::uint32_t draw);
    void bin(std::uint32_t tri_index);
    void raster_tile(unsigned col, unsigned row, Tile& tile, SceneSource::FrameImage* image);
    void note_llvmpipe(const Eigen::Vector4d& c0, const Eigen::Vector4d& c1, const Eigen::Vector4d& c2,
                       std::size_t first_tri);
    void write_llvmpipe_depth(std::uint32_t tri, const DrawState& s, std::int32_t x, std::int32_t y,
                              std::uint32_t exact);

    unsigned width_, height_, tile_w_, tile_h_, tiles_x_, tiles_y_;
    unsigned depth_bits_;
    double depth_max_;

    std::uint64_t frame_ = 0;
    std::vector<DrawState> draws_;
    std::vector<Tri> tris_;
    std::vector<std::vector<std::uint32_t>> bins_;   // per tile, triangle indices in submission order
    std::size_t cursor_ = 0;
    std::uint64_t max_tile_fragments_ = UINT64_MAX;
    bool keep_depth_ = false;
    std::size_t depth_limit_ = SIZE_MAX;   // entries of tris_ from here on leave the depth buffer alone
    std::vector<std::uint32_t> depth_;
    std::vector<std::uint8_t> marks_;
    // The llvmpipe buffer (keep_llvmpipe_depth): per entry of tris_, the
    // planes of the triangle it came from (a clipped triangle's pieces share them).
    std::unique_ptr<LlvmpipeDepth> lp_;
    std::vector<LlvmpipeDepth::Range> lp_range_;
    std::vector<std::uint32_t> lp_depth_;
    std::vector<std::uint8_t> lp_marks_;
    // Per-vertex scratch of the mesh being set up.
    std::vector<std::uint16_t> outcode_;
    std::vector<ScreenVert> screen_;
};

} // namespace rbcd::scene
