// The depth Mesa's llvmpipe (22.3, the driver rbcd-gl2rbt's check replays
// captures with) computes for a triangle, in its own single-precision
// arithmetic: draw_pipe_clip's float32 clipping against the view volume
// (llvmpipe has no guard band when a depth buffer is bound), the viewport
// transform with the replay host's fused multiply-add, llvmpipe's float32
// plane set-up from the framebuffer's origin, its per-pixel evaluation and
// its conversion to depth units. Used only by the depth check
// (TileRasterizer::keep_llvmpipe_depth), to tell the driver's rounding from
// differences of geometry or state; the trace keeps GL's exact depths.
//
// What it follows, step by step (docs/gl-capture.md, "The check against
// Mesa"):
//  - clip-space vertices rounded to float32 (the shader path's are Mesa's
//    own float32 outputs, so exact there);
//  - vertices inside every plane: X = fma(f32(x * f32(1/w)), sx, tx), the
//    JIT's llvm.fmuladd (fused on a host with FMA), likewise Y, Z;
//  - a triangle crossing x = +-w, y = +-w, the near or the far plane (then
//    user planes): Sutherland-Hodgman in float32 in that plane order, each
//    new vertex interpolated from the end nearer the plane, its window
//    position recomputed without FMA, the polygon fanned out as
//    (p[i-1], p[i], p[0]), or (p[0], p[i-1], p[i]) when the first vertex
//    provokes;
//  - per triangle: positions snapped to 1/256 pixel decide the winding
//    (vertices 0 and 1 swapped when it is clockwise, 1 and 2 when the first
//    vertex provokes; dropped when the area is zero), then the float32
//    plane a0 + dzdx * px + dzdy * py over the
//    framebuffer's pixel coordinates, a0 taken at pixel (0, 0);
//  - per pixel z = fma(dzdy, py, fma(dzdx, px, a0)) (+ polygon offset),
//    clamped to [0, 1], depth = round-half-even(f32(z * (2^bits - 1))).
// The framebuffer is the window's (Mesa's y runs down it, as the screen's
// rows do here); depth clamp and clip control are not modelled (the draw
// stream carries neither).
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace rbcd::scene {

struct DrawState;

class LlvmpipeDepth {
public:
    // One triangle as llvmpipe sets it up: the depth plane over pixel
    // coordinates (y down) and the positions snapped to 1/256 pixel with
    // the pixel centre at 0 (which of a clipped polygon's triangles a pixel
    // belongs to).
    struct Plane {
        float a0 = 0, dzdx = 0, dzdy = 0, zoffset = 0;
        std::int64_t x[3] = {}, y[3] = {};
    };
    // A triangle's planes: [first, first + count) of planes().
    struct Range {
        std::uint32_t first = 0, count = 0;
    };

    // fma: whether the replay's JIT code fuses multiply-add (the host has
    // FMA, as host_has_fma() says of this machine).
    LlvmpipeDepth(unsigned fb_height, unsigned depth_bits, bool fma);
    static bool host_has_fma();

    // The draw whose triangles follow: its viewport, depth range, polygon
    // offset and user clip planes.
    void set_draw(const DrawState& s);
    // Clips and sets up one triangle of clip-space vertices as llvmpipe does;
    // count 0 when llvmpipe draws nothing of it.
    Range add_triangle(const Eigen::Vector4d& c0, const Eigen::Vector4d& c1, const Eigen::Vector4d& c2);
    // Depth units at pixel (x, y) of the triangle's planes: the plane of the
    // triangle holding the pixel centre, or the nearest one when none does
    // (a pixel the converter covers and llvmpipe does not).
    std::uint32_t depth_at(Range r, std::int32_t x, std::int32_t y) const;
    // Forgets the planes (a new frame).
    void clear() { planes_.clear(); }
    const std::vector<Plane>& planes() const { return planes_; }

private:
    struct Vert {
        float c[4];     // clip position
        float win[3];   // window position (y down), Z in [0, 1]
    };
    void setup(const Vert& v0, const Vert& v1, const Vert& v2);
    void window_jit(Vert& v) const;
    void window_c(Vert& v) const;

    float fb_height_;
    float depth_scale_;
    bool fma_;
    float sx_ = 0, tx_ = 0, sy_ = 0, ty_ = 0, sz_ = 0, tz_ = 0;
    float units_ = 0, factor_ = 0;
    bool flatshade_first_ = false;
    std::vector<std::array<float, 4>> user_planes_;
    std::vector<Plane> planes_;
};

} // namespace rbcd::scene
