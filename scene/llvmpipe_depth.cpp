#include "rbcd/scene/llvmpipe_depth.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rbcd/scene/tile_rasterizer.h"

// Every float expression here is one IEEE single-precision operation per
// operator, rounded to nearest: this file is compiled without FP contraction
// (scene/CMakeLists.txt), so a * b + c stays two roundings unless written as
// std::fma, which is how the JIT's fused multiply-adds are written.

namespace rbcd::scene {
namespace {

// draw_pipe_clip's planes, in clipmask bit order: x <= w, -w <= x, y <= w,
// -w <= y, near (z + w >= 0), far (w - z >= 0). The distance is dot4 with
// its left-to-right float32 sum.
constexpr float kPlanes[6][4] = {{-1, 0, 0, 1}, {1, 0, 0, 1}, {0, -1, 0, 1}, {0, 1, 0, 1}, {0, 0, 1, 1}, {0, 0, -1, 1}};

// Sutherland-Hodgman adds at most one vertex a plane: 3 + 6 + 8 user planes.
constexpr int kMaxPoly = 3 + 6 + 8 + 1;

inline float dot4(const float* a, const float* b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3]; }

// The JIT clip test (draw_llvm.c generate_clipmask): unordered compares, so
// a NaN coordinate counts as outside.
unsigned clipmask(const float* c, const std::vector<std::array<float, 4>>& user) {
    const float x = c[0], y = c[1], z = c[2], w = c[3];
    unsigned m = 0;
    if (!(x <= w)) m |= 1u << 0;
    if (!(0.0f <= x + w)) m |= 1u << 1;
    if (!(y <= w)) m |= 1u << 2;
    if (!(0.0f <= y + w)) m |= 1u << 3;
    if (!(0.0f <= z + w)) m |= 1u << 4;
    if (!(z <= w)) m |= 1u << 5;
    for (std::size_t i = 0; i < user.size(); ++i)
        if (!(0.0f <= dot4(c, user[i].data()))) m |= 1u << (6 + i);
    return m;
}

// The pixel's snapped position, as calc_fixed_position: (X - 0.5) * 256 in
// float32, converted with round-half-even (cvtps2dq).
inline std::int64_t snap(float v) { return std::int64_t(std::nearbyint((v - 0.5f) * 256.0f)); }

} // namespace

LlvmpipeDepth::LlvmpipeDepth(unsigned fb_height, unsigned depth_bits, bool fma)
    : fb_height_(float(fb_height)), depth_scale_(float((std::uint64_t(1) << depth_bits) - 1)), fma_(fma) {}

bool LlvmpipeDepth::host_has_fma() {
#if defined(__x86_64__) || defined(__i386__)
    return __builtin_cpu_supports("fma");
#else
    return false;
#endif
}

void LlvmpipeDepth::set_draw(const DrawState& s) {
    // _mesa_get_viewport_xform, then st_update_viewport's flip for the
    // window's framebuffer (Y_0_TOP). GL's viewport y counts up from the
    // bottom; the draw state's from the top.
    const float x = float(s.vx), w = float(s.vw), h = float(s.vh);
    const float y = float(double(fb_height_) - s.vy - s.vh);
    const float half_w = 0.5f * w, half_h = 0.5f * h;
    sx_ = half_w;
    tx_ = half_w + x;
    sy_ = -half_h;
    ty_ = fb_height_ - (half_h + y);
    sz_ = float(0.5 * (s.depth_far - s.depth_near));
    tz_ = float(0.5 * (s.depth_near + s.depth_far));
    // The draw stream's units are steps of the buffer (Mesa's two per GL
    // unit, already doubled); llvmpipe adds them as units * (1 / (2^bits - 1)).
    units_ = float(s.offset_units * (1.0 / double(depth_scale_)));
    factor_ = float(s.offset_factor);
    flatshade_first_ = s.first_vertex_provokes;
    user_planes_.clear();
    for (const auto& p : s.clip_planes) user_planes_.push_back({float(p[0]), float(p[1]), float(p[2]), float(p[3])});
}

// generate_viewport: 1/w a true division, then llvm.fmuladd (fused with FMA).
void LlvmpipeDepth::window_jit(Vert& v) const {
    const float ow = 1.0f / v.c[3];
    const float s[3] = {sx_, sy_, sz_}, t[3] = {tx_, ty_, tz_};
    for (int k = 0; k < 3; ++k) {
        const float p = v.c[k] * ow;
        v.win[k] = fma_ ? std::fma(p, s[k], t[k]) : p * s[k] + t[k];
    }
}

// draw_pipe_clip's interp(): C, no FMA, (c * (1/w)) * scale + translate.
void LlvmpipeDepth::window_c(Vert& v) const {
    const float oow = 1.0f / v.c[3];
    v.win[0] = v.c[0] * oow * sx_ + tx_;
    v.win[1] = v.c[1] * oow * sy_ + ty_;
    v.win[2] = v.c[2] * oow * sz_ + tz_;
}

LlvmpipeDepth::Range LlvmpipeDepth::add_triangle(const Eigen::Vector4d& c0, const Eigen::Vector4d& c1,
                                                 const Eigen::Vector4d& c2) {
    Range r{static_cast<std::uint32_t>(planes_.size()), 0};
    Vert v[3];
    const Eigen::Vector4d* c[3] = {&c0, &c1, &c2};
    unsigned or_mask = 0, and_mask = ~0u;
    for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 4; ++k) v[i].c[k] = float((*c[i])[k]);
        window_jit(v[i]);
        const unsigned m = clipmask(v[i].c, user_planes_);
        or_mask |= m;
        and_mask &= m;
    }
    if (and_mask) return r;
    if (!or_mask) {
        setup(v[0], v[1], v[2]);
        r.count = static_cast<std::uint32_t>(planes_.size()) - r.first;
        return r;
    }
    // do_clip_tri: the planes in ascending bit order, each pass starting at
    // the polygon's first vertex.
    Vert buf_a[kMaxPoly + 1], buf_b[kMaxPoly + 1];
    Vert* in = buf_a;
    Vert* out = buf_b;
    int n = 3;
    for (int i = 0; i < 3; ++i) in[i] = v[i];
    unsigned mask = or_mask;
    while (mask && n >= 3) {
        const unsigned p = unsigned(__builtin_ctz(mask));
        mask &= ~(1u << p);
        const float* plane = p < 6 ? kPlanes[p] : user_planes_[p - 6].data();
        const auto dist = [&](const Vert& q) { return dot4(q.c, plane); };
        in[n] = in[0];
        float dp_prev = dist(in[0]);
        if (!std::isfinite(dp_prev)) return r;
        int m = 0;
        for (int i = 1; i <= n; ++i) {
            const Vert& prev = in[i - 1];
            const Vert& cur = in[i];
            const float dp = dist(cur);
            if (!std::isfinite(dp)) return r;
            bool different;
            if (dp_prev >= 0.0f) {
                out[m++] = prev;
                different = dp < 0.0f;
            } else {
                different = !(dp < 0.0f);
            }
            if (different) {
                // From the end nearer the plane (t <= 0.5), the inside one on
                // a tie: LINTERP(t, base, other) = base + t * (other - base).
                const float denom = dp - dp_prev;
                const Vert* base;
                const Vert* other;
                float t;
                if (dp < 0.0f) {
                    if (-dp < dp_prev) t = dp / denom, base = &cur, other = &prev;
                    else t = -dp_prev / denom, base = &prev, other = &cur;
                } else {
                    if (-dp_prev < dp) t = -dp_prev / denom, base = &prev, other = &cur;
                    else t = dp / denom, base = &cur, other = &prev;
                }
                Vert& nv = out[m++];
                for (int k = 0; k < 4; ++k) nv.c[k] = base->c[k] + t * (other->c[k] - base->c[k]);
                window_c(nv);
            }
            dp_prev = dp;
        }
        std::swap(in, out);
        n = m;
    }
    // emit_poly: the provoking vertex stays where the convention puts it.
    for (int i = 2; i < n; ++i) {
        if (flatshade_first_) setup(in[0], in[i - 1], in[i]);
        else setup(in[i - 1], in[i], in[0]);
    }
    r.count = static_cast<std::uint32_t>(planes_.size()) - r.first;
    return r;
}

void LlvmpipeDepth::setup(const Vert& a, const Vert& b, const Vert& c) {
    // calc_fixed_position and triangle_both: the snapped area's sign picks
    // the order (v1, v0, v2 when clockwise; v0, v2, v1 when the first vertex
    // provokes), a zero area draws nothing.
    const Vert* v[3] = {&a, &b, &c};
    std::int64_t x[3], y[3];
    for (int i = 0; i < 3; ++i) x[i] = snap(v[i]->win[0]), y[i] = snap(v[i]->win[1]);
    const std::int64_t area = (x[0] - x[1]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[0] - y[1]);
    if (area == 0) return;
    if (area < 0) {
        const int i = flatshade_first_ ? 1 : 0;
        std::swap(v[i], v[i + 1]);
        std::swap(x[i], x[i + 1]);
        std::swap(y[i], y[i + 1]);
    }
    const float X0 = v[0]->win[0], Y0 = v[0]->win[1], Z0 = v[0]->win[2];
    const float X1 = v[1]->win[0], Y1 = v[1]->win[1], Z1 = v[1]->win[2];
    const float X2 = v[2]->win[0], Y2 = v[2]->win[1], Z2 = v[2]->win[2];
    // lp_state_setup.c init_args, lp_do_offset_tri and calc_coef4.
    const float xc = X0 - 0.5f, yc = Y0 - 0.5f;
    const float dx01 = X0 - X1, dy01 = Y0 - Y1, dx20 = X2 - X0, dy20 = Y2 - Y0;
    const float dz01 = Z0 - Z1, dz20 = Z2 - Z0;
    const float ooa = 1.0f / (dx01 * dy20 - dy01 * dx20);
    Plane pl;
    if (factor_ != 0.0f || units_ != 0.0f) {
        const float ox = std::fabs((dz20 * dy01 - dy20 * dz01) * ooa);
        const float oy = std::fabs((dx20 * dz01 - dz20 * dx01) * ooa);
        const float max = !(ox <= oy) ? ox : oy;   // an unordered greater-than
        pl.zoffset = units_ + max * factor_;
    }
    const float dx20o = dx20 * ooa, dy20o = dy20 * ooa, dx01o = dx01 * ooa, dy01o = dy01 * ooa;
    pl.dzdx = dz01 * dy20o - dz20 * dy01o;
    pl.dzdy = dz20 * dx01o - dz01 * dx20o;
    pl.a0 = Z0 - (pl.dzdx * xc + pl.dzdy * yc);
    for (int i = 0; i < 3; ++i) pl.x[i] = x[i], pl.y[i] = y[i];
    planes_.push_back(pl);
}

std::uint32_t LlvmpipeDepth::depth_at(Range r, std::int32_t px, std::int32_t py) const {
    const Plane* best = &planes_[r.first];
    if (r.count > 1) {
        // The triangle whose snapped edges hold the pixel centre (at px * 256
        // in snapped units); else the one it lies least outside of.
        const std::int64_t sx = std::int64_t(px) * 256, sy = std::int64_t(py) * 256;
        double best_score = -std::numeric_limits<double>::infinity();
        for (std::uint32_t i = r.first; i < r.first + r.count; ++i) {
            const Plane& p = planes_[i];
            double score = std::numeric_limits<double>::infinity();
            for (int e = 0; e < 3; ++e) {
                const int f = (e + 1) % 3;
                const std::int64_t ex = p.x[f] - p.x[e], ey = p.y[f] - p.y[e];
                // Positive inside: after setup's reordering (area > 0) the
                // vertices run clockwise on the y-down grid.
                const double side = double(ey * (sx - p.x[e]) - ex * (sy - p.y[e]));
                score = std::min(score, side / std::hypot(double(ex), double(ey)));
            }
            if (score > best_score) best_score = score, best = &p;
        }
    }
    // lp_bld_interp.c attribs_update_simple: a0 + dzdx * x, then + dzdy * y,
    // with llvm.fmuladd; the polygon offset; the clamp to [0, 1] of a unorm
    // buffer; the float-to-unorm conversion (lp_build_clamped_float_to_unsigned_norm).
    const float fx = float(px), fy = float(py);
    float z = fma_ ? std::fma(best->dzdy, fy, std::fma(best->dzdx, fx, best->a0))
                   : best->dzdy * fy + (best->dzdx * fx + best->a0);
    z = z + best->zoffset;
    z = std::min(std::max(z, 0.0f), 1.0f);
    return static_cast<std::uint32_t>(std::nearbyint(z * depth_scale_));
}

} // namespace rbcd::scene
