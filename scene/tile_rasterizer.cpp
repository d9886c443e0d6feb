#include "rbcd/scene/tile_rasterizer.h"

#include <algorithm>
#include <cmath>

namespace rbcd::scene {
namespace {

// Guard band: triangles are clipped against |x|, |y| <= kGuard * w rather than
// the screen edges. Off-screen parts are scissored away by the tile loop, so the
// picture is the same, and new edges appear only where they cannot be seen.
// With screens up to kMaxScreenSide, coordinates stay below 2^23 sub-pixels.
constexpr double kGuard = 4.0;

enum Plane : unsigned { kNear, kFar, kLeft, kRight, kBottom, kTop, kFrustumPlanes };

inline double plane_dist(const Eigen::Vector4d& v, unsigned p, const DrawState& s) {
    switch (p) {
    case kNear: return v.z() + v.w();
    case kFar: return v.w() - v.z();
    case kLeft: return v.x() + kGuard * v.w();
    case kRight: return kGuard * v.w() - v.x();
    case kBottom: return v.y() + kGuard * v.w();
    case kTop: return kGuard * v.w() - v.y();
    default: return s.clip_planes[p - kFrustumPlanes].dot(v);
    }
}

inline std::int64_t floor_div_sub(std::int64_t v) { return v >> kSubBits; }   // arithmetic shift: floor

inline bool depth_passes(DepthFunc f, std::uint32_t z, std::uint32_t stored) {
    switch (f) {
    case DepthFunc::Never: return false;
    case DepthFunc::Less: return z < stored;
    case DepthFunc::Equal: return z == stored;
    case DepthFunc::Lequal: return z <= stored;
    case DepthFunc::Greater: return z > stored;
    case DepthFunc::Notequal: return z != stored;
    case DepthFunc::Gequal: return z >= stored;
    default: return true;
    }
}

// A fragment's depth test and write at `at` of a kept depth buffer and its
// marks (where a draw with fragment effects wrote last).
inline void test_and_write(std::vector<std::uint32_t>& buf, std::vector<std::uint8_t>& marks, std::size_t at,
                           const DrawState& s, std::uint32_t depth) {
    if (s.depth_write && depth_passes(s.depth_func, depth, buf[at])) {
        buf[at] = depth;
        marks[at] = s.fragment_effects;
    }
}

// A tile's header and empty lists, before its triangles are walked.
void begin_tile(Tile& tile, std::uint64_t frame, unsigned col, unsigned row) {
    tile.frame = frame;
    tile.col = col;
    tile.row = row;
    tile.other = 0;
    tile.has_base = false;
    tile.base = 0;
    // Every binned triangle is set up, covered pixels or not; the culled ones
    // are binned only because collision detection defers their culling.
    tile.has_prims = tile.has_cprims = true;
    tile.prims = tile.cprims = 0;
    tile.ordered_other = true;
    tile.other_runs.clear();
    tile.frags.clear();
}

// A depth clear's rectangle [x0, x1] x [y0, y1]: depth v, no marks.
void clear_depth(std::vector<std::uint32_t>& depth, std::vector<std::uint8_t>& marks, std::size_t width, std::int32_t x0,
                 std::int32_t x1, std::int32_t y0, std::int32_t y1, std::uint32_t v) {
    for (std::int32_t y = y0; y <= y1; ++y) {
        std::fill_n(&depth[std::size_t(y) * width + std::size_t(x0)], std::size_t(x1 - x0 + 1), v);
        std::fill_n(&marks[std::size_t(y) * width + std::size_t(x0)], std::size_t(x1 - x0 + 1), 0);
    }
}

// Non-collisionable fragments are emitted in primitive order between the
// collisionable ones: adjacent runs merge.
[[gnu::always_inline]] inline void add_other(Tile& tile, std::uint64_t n) {
    if (n == 0) return;
    tile.other += n;
    const auto before = static_cast<std::uint32_t>(tile.frags.size());
    if (!tile.other_runs.empty() && tile.other_runs.back().before == before) tile.other_runs.back().count += n;
    else tile.other_runs.push_back({before, n});
}

// The shading cost of a tile's shaded fragments (other, and collisionable
// ones not tagged c): their mean, when a draw gives one.
struct ShadeSum {
    std::uint64_t shaded = 0, sum = 0;
    bool given = false;
    [[gnu::always_inline]] void add(std::uint32_t shade, std::uint64_t n) {
        shaded += n;
        sum += n * (shade ? shade : 100u);
        given |= shade != 0 && n != 0;
    }
    void set(Tile& tile) const {
        tile.has_shade = given;
        tile.shade = given ? static_cast<std::uint32_t>(std::clamp<std::uint64_t>((sum + shaded / 2) / shaded, kShadeMin, kShadeMax))
                           : 100;
    }
};

} // namespace

DrawState DrawState::full_screen(unsigned width, unsigned height) {
    DrawState s;
    s.vw = double(width);
    s.vh = double(height);
    s.scissor = PixelRect{0, 0, std::int32_t(width) - 1, std::int32_t(height) - 1};
    return s;
}

TileRasterizer::TileRasterizer(unsigned width, unsigned height, unsigned tile_w, unsigned tile_h, unsigned depth_bits)
    : width_(width), height_(height), tile_w_(tile_w), tile_h_(tile_h), depth_bits_(depth_bits),
      depth_max_(double((std::uint64_t(1) << depth_bits) - 1)) {
    tiles_x_ = (width_ + tile_w_ - 1) / tile_w_;
    tiles_y_ = (height_ + tile_h_ - 1) / tile_h_;
    bins_.resize(std::size_t(tiles_x_) * tiles_y_);
}

void TileRasterizer::begin_frame(std::uint64_t f) {
    frame_ = f;
    draws_.clear();
    tris_.clear();
    for (auto& b : bins_) b.clear();
    cursor_ = 0;
    depth_limit_ = SIZE_MAX;
    // As in GL, the depth buffer lasts from frame to frame until a clear; its
    // first content (undefined in GL) is zero, as Mesa allocates it.
    if (keep_depth_ && depth_.empty()) {
        depth_.assign(std::size_t(width_) * height_, 0);
        marks_.assign(depth_.size(), 0);
    }
    if (lp_) {
        lp_->clear();
        lp_range_.clear();
        if (lp_depth_.empty()) {
            lp_depth_.assign(std::size_t(width_) * height_, 0);
            lp_marks_.assign(lp_depth_.size(), 0);
        }
    }
}

void TileRasterizer::keep_llvmpipe_depth(bool fma) { lp_ = std::make_unique<LlvmpipeDepth>(height_, depth_bits_, fma); }

// The planes llvmpipe sets up for one triangle, shared by the entries of
// tris_ it gave from first_tri on.
void TileRasterizer::note_llvmpipe(const Eigen::Vector4d& c0, const Eigen::Vector4d& c1, const Eigen::Vector4d& c2,
                                   std::size_t first_tri) {
    if (tris_.size() == first_tri) return;
    const auto r = lp_->add_triangle(c0, c1, c2);
    lp_range_.resize(first_tri, LlvmpipeDepth::Range{});
    lp_range_.resize(tris_.size(), r);
}

// The llvmpipe buffer's depth test and write at one covered pixel, whose
// exact depth is `exact`: a pixel of a triangle llvmpipe draws nothing of
// keeps it.
void TileRasterizer::write_llvmpipe_depth(std::uint32_t ti, const DrawState& s, std::int32_t x, std::int32_t y,
                                          std::uint32_t exact) {
    const LlvmpipeDepth::Range r = ti < lp_range_.size() ? lp_range_[ti] : LlvmpipeDepth::Range{};
    test_and_write(lp_depth_, lp_marks_, std::size_t(y) * width_ + std::size_t(x), s,
                   r.count ? lp_->depth_at(r, x, y) : exact);
}

std::uint32_t TileRasterizer::add_draw(DrawState s) {
    draws_.push_back(std::move(s));
    return static_cast<std::uint32_t>(draws_.size() - 1);
}

std::uint16_t TileRasterizer::outcode(const DrawState& s, const Eigen::Vector4d& v) const {
    std::uint16_t oc = 0;
    const unsigned planes = kFrustumPlanes + unsigned(s.clip_planes.size());
    for (unsigned p = 0; p < planes; ++p)
        if (plane_dist(v, p, s) < 0.0) oc |= std::uint16_t(1u << p);
    return oc;
}

// Kept out of line and compiled without FP contraction (scene/CMakeLists.txt):
// a vertex shared by two triangles, one clipped and one not, must snap to the
// same sub-pixel position on both paths.
bool TileRasterizer::project(const DrawState& s, const Eigen::Vector4d& clip, ScreenVert& out) const {
    const double iw = 1.0 / clip.w();
    const double sx = s.vx + (clip.x() * iw * 0.5 + 0.5) * s.vw;
    const double sy = s.vy + (0.5 - clip.y() * iw * 0.5) * s.vh;   // screen y grows downwards
    const double z = (s.depth_near + (s.depth_far - s.depth_near) * (clip.z() * iw * 0.5 + 0.5)) * depth_max_;
    // Converting NaN or inf to an integer is undefined: the caller refuses.
    if (!(std::isfinite(sx) && std::isfinite(sy) && std::isfinite(z) && std::abs(sx) < 1e9 && std::abs(sy) < 1e9)) {
        out = ScreenVert{0, 0, 0.0, 0.0, 0.0};
        return false;
    }
    out.x = static_cast<std::int32_t>(std::llround(sx * double(kSub)));
    out.y = static_cast<std::int32_t>(std::llround(sy * double(kSub)));
    out.z = std::clamp(z, 0.0, depth_max_);
    out.fx = sx;
    out.fy = sy;
    return true;
}

bool TileRasterizer::add_mesh(std::uint32_t draw, const Eigen::Vector4d* clip, std::size_t nv,
                              const std::array<std::uint32_t, 3>* tris, std::size_t ntris) {
    const DrawState& s = draws_[draw];
    if (lp_) lp_->set_draw(s);
    outcode_.resize(nv);
    screen_.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) {
        outcode_[v] = outcode(s, clip[v]);
        if (outcode_[v] == 0 && !project(s, clip[v], screen_[v])) return false;
    }
    for (std::size_t i = 0; i < ntris; ++i) {
        const auto& tri = tris[i];
        const std::uint16_t o0 = outcode_[tri[0]], o1 = outcode_[tri[1]], o2 = outcode_[tri[2]];
        if (o0 & o1 & o2) continue;   // wholly outside one plane
        const std::size_t first_tri = tris_.size();
        if ((o0 | o1 | o2) == 0) {
            setup(screen_[tri[0]], screen_[tri[1]], screen_[tri[2]], draw);
        } else {
            const Eigen::Vector4d* c[3] = {&clip[tri[0]], &clip[tri[1]], &clip[tri[2]]};
            if (!clip_and_setup(c, draw)) return false;
        }
        if (lp_) note_llvmpipe(clip[tri[0]], clip[tri[1]], clip[tri[2]], first_tri);
    }
    return true;
}

bool TileRasterizer::clip_and_setup(const Eigen::Vector4d* c[3], std::uint32_t draw) {
    // Sutherland-Hodgman. Each intersection is computed from the inside end of
    // the edge towards the outside end, so the two triangles sharing an edge
    // create bit-identical vertices on it and stay watertight after clipping.
    constexpr unsigned kMaxPlanes = kFrustumPlanes + kMaxUserClipPlanes;
    const DrawState& s = draws_[draw];
    const unsigned planes = kFrustumPlanes + unsigned(s.clip_planes.size());
    Eigen::Vector4d buf_a[3 + kMaxPlanes], buf_b[3 + kMaxPlanes];
    Eigen::Vector4d* in = buf_a;
    Eigen::Vector4d* out = buf_b;
    int n = 3;
    for (int i = 0; i < 3; ++i) in[i] = *c[i];
    for (unsigned p = 0; p < planes && n >= 3; ++p) {
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const Eigen::Vector4d& P = in[i];
            const Eigen::Vector4d& Q = in[(i + 1) % n];
            const double dp = plane_dist(P, p, s), dq = plane_dist(Q, p, s);
            const bool pin = dp >= 0.0, qin = dq >= 0.0;
            if (pin) out[m++] = P;
            if (pin != qin) {
                const Eigen::Vector4d& I = pin ? P : Q;
                const Eigen::Vector4d& O = pin ? Q : P;
                const double di = pin ? dp : dq, dout = pin ? dq : dp;
                const double t = di / (di - dout);
                out[m++] = I + t * (O - I);
            }
        }
        std::swap(in, out);
        n = m;
    }
    if (n < 3) return true;
    ScreenVert sv[3 + kMaxPlanes];
    for (int i = 0; i < n; ++i)
        if (!project(s, in[i], sv[i])) return false;
    for (int i = 1; i + 1 < n; ++i) setup(sv[0], sv[i], sv[i + 1], draw);
    return true;
}

void TileRasterizer::setup(const ScreenVert& v0, const ScreenVert& v1in, const ScreenVert& v2in, std::uint32_t draw) {
    const DrawState& s = draws_[draw];
    const std::int64_t area = std::int64_t(v1in.x - v0.x) * (v2in.y - v0.y) - std::int64_t(v2in.x - v0.x) * (v1in.y - v0.y);
    if (area == 0) return;   // degenerate after snapping: covers no sample point
    // Counter-clockwise in window coordinates (y up) is negative with y down.
    const bool ccw = area < 0;
    const Facing facing = (ccw == s.front_ccw) ? Facing::Front : Facing::Back;
    const bool culled = s.cull == CullFace::FrontAndBack || (s.cull == CullFace::Back && facing == Facing::Back) ||
                        (s.cull == CullFace::Front && facing == Facing::Front);
    if (culled && !s.collisionable) return;

    // Orient so that the edge functions are positive inside.
    const ScreenVert* v[3] = {&v0, &v1in, &v2in};
    if (area < 0) std::swap(v[1], v[2]);

    Tri t;
    std::int64_t minx = v[0]->x, maxx = v[0]->x, miny = v[0]->y, maxy = v[0]->y;
    for (int i = 0; i < 3; ++i) {
        const ScreenVert& a = *v[i];
        const ScreenVert& b = *v[(i + 1) % 3];
        const std::int64_t dx = std::int64_t(b.x) - a.x, dy = std::int64_t(b.y) - a.y;
        t.a[i] = -dy;
        t.b[i] = dx;
        t.c[i] = dy * a.x - dx * a.y;
        // Fill rule (y down, clockwise on screen): a sample exactly on an edge
        // belongs to the triangle only if the edge is a left one (going up) or
        // a top one (going right; bottom_left_fill: a bottom one, going left).
        // The edge shared by two triangles runs in opposite directions in them,
        // so exactly one of them owns the samples on it.
        const bool owned = dy < 0 || (dy == 0 && (s.bottom_left_fill ? dx < 0 : dx > 0));
        if (!owned) t.c[i] -= 1;
        minx = std::min<std::int64_t>(minx, a.x);
        maxx = std::max<std::int64_t>(maxx, a.x);
        miny = std::min<std::int64_t>(miny, a.y);
        maxy = std::max<std::int64_t>(maxy, a.y);
    }
    // Pixel x's sample is at x * kSub + kSub / 2. The scissor (the screen
    // when off) bounds the box: fragments outside it are never generated.
    std::int64_t px0 = floor_div_sub(minx - kSub / 2 + kSub - 1);
    std::int64_t px1 = floor_div_sub(maxx - kSub / 2);
    std::int64_t py0 = floor_div_sub(miny - kSub / 2 + kSub - 1);
    std::int64_t py1 = floor_div_sub(maxy - kSub / 2);
    px0 = std::max<std::int64_t>(px0, s.scissor.x0);
    py0 = std::max<std::int64_t>(py0, s.scissor.y0);
    px1 = std::min<std::int64_t>(px1, s.scissor.x1);
    py1 = std::min<std::int64_t>(py1, s.scissor.y1);
    if (px0 > px1 || py0 > py1) return;
    t.px0 = std::int32_t(px0);
    t.py0 = std::int32_t(py0);
    t.px1 = std::int32_t(px1);
    t.py1 = std::int32_t(py1);

    // Window depth is affine in screen space: a plane through the snapped
    // corners, or through the unsnapped ones when the draw asks.
    const double inv = 1.0 / double(kSub);
    double x0, y0, x1, y1, x2, y2;
    const auto unsnapped_det = [&] {
        return (v[1]->fx - v[0]->fx) * (v[2]->fy - v[0]->fy) - (v[2]->fx - v[0]->fx) * (v[1]->fy - v[0]->fy);
    };
    // A sliver with area once snapped may have none before: the snapped plane then.
    if (s.depth_from_unsnapped && std::abs(unsnapped_det()) > 1e-6) {
        x0 = v[0]->fx, y0 = v[0]->fy;
        x1 = v[1]->fx - x0, y1 = v[1]->fy - y0;
        x2 = v[2]->fx - x0, y2 = v[2]->fy - y0;
    } else {
        x0 = v[0]->x * inv, y0 = v[0]->y * inv;
        x1 = v[1]->x * inv - x0, y1 = v[1]->y * inv - y0;
        x2 = v[2]->x * inv - x0, y2 = v[2]->y * inv - y0;
    }
    const double z1 = v[1]->z - v[0]->z, z2 = v[2]->z - v[0]->z;
    const double det = x1 * y2 - x2 * y1;
    t.zx = (z1 * y2 - z2 * y1) / det;
    t.zy = (x1 * z2 - x2 * z1) / det;
    t.z0 = v[0]->z;
    if (s.offset_factor != 0.0 || s.offset_units != 0.0)
        t.z0 += s.offset_factor * std::max(std::abs(t.zx), std::abs(t.zy)) + s.offset_units;
    t.x0 = x0;
    t.y0 = y0;
    t.draw = draw;
    t.facing = facing;
    t.culled = culled;
    t.clear = false;

    tris_.push_back(t);
    bin(static_cast<std::uint32_t>(tris_.size() - 1));
}

void TileRasterizer::add_depth_clear(double value01, PixelRect r) {
    r.x0 = std::max(r.x0, 0);
    r.y0 = std::max(r.y0, 0);
    r.x1 = std::min(r.x1, std::int32_t(width_) - 1);
    r.y1 = std::min(r.y1, std::int32_t(height_) - 1);
    if (!keep_depth_ || r.x0 > r.x1 || r.y0 > r.y1) return;
    Tri t{};
    t.clear = true;
    t.z0 = std::clamp(value01, 0.0, 1.0) * depth_max_;
    t.px0 = r.x0;
    t.py0 = r.y0;
    t.px1 = r.x1;
    t.py1 = r.y1;
    tris_.push_back(t);
    const auto ti = static_cast<std::uint32_t>(tris_.size() - 1);
    for (unsigned row = unsigned(r.y0) / tile_h_; row <= unsigned(r.y1) / tile_h_; ++row)
        for (unsigned col = unsigned(r.x0) / tile_w_; col <= unsigned(r.x1) / tile_w_; ++col)
            bins_[std::size_t(row) * tiles_x_ + col].push_back(ti);
}

void TileRasterizer::bin(std::uint32_t ti) {
    const Tri& t = tris_[ti];
    const unsigned c0 = unsigned(t.px0) / tile_w_, c1 = unsigned(t.px1) / tile_w_;
    const unsigned r0 = unsigned(t.py0) / tile_h_, r1 = unsigned(t.py1) / tile_h_;
    const bool single = c0 == c1 && r0 == r1;
    for (unsigned r = r0; r <= r1; ++r) {
        for (unsigned col = c0; col <= c1; ++col) {
            if (!single) {
                // Skip tiles the bounding box overlaps but the triangle misses:
                // an affine function's maximum over a rectangle is at a corner.
                const std::int64_t x_lo = std::max<std::int64_t>(t.px0, std::int64_t(col) * tile_w_);
                const std::int64_t x_hi = std::min<std::int64_t>(t.px1, std::int64_t(col + 1) * tile_w_ - 1);
                const std::int64_t y_lo = std::max<std::int64_t>(t.py0, std::int64_t(r) * tile_h_);
                const std::int64_t y_hi = std::min<std::int64_t>(t.py1, std::int64_t(r + 1) * tile_h_ - 1);
                bool outside = false;
                for (int e = 0; e < 3 && !outside; ++e) {
                    const std::int64_t sx = (t.a[e] > 0 ? x_hi : x_lo) * kSub + kSub / 2;
                    const std::int64_t sy = (t.b[e] > 0 ? y_hi : y_lo) * kSub + kSub / 2;
                    outside = t.a[e] * sx + t.b[e] * sy + t.c[e] < 0;
                }
                if (outside) continue;
            }
            bins_[std::size_t(r) * tiles_x_ + col].push_back(ti);
        }
    }
}

bool TileRasterizer::next_tile(Tile& tile, SceneSource::FrameImage* image) {
    while (cursor_ < bins_.size()) {
        const std::size_t idx = cursor_++;
        if (bins_[idx].empty()) continue;
        raster_tile(unsigned(idx % tiles_x_), unsigned(idx / tiles_x_), tile, image);
        bins_[idx].clear();
        if (!tile.frags.empty() || tile.other != 0) return true;
    }
    return false;
}

void TileRasterizer::raster_tile(unsigned col, unsigned row, Tile& tile, SceneSource::FrameImage* image) {
    begin_tile(tile, frame_, col, row);
    ShadeSum shade;

    const std::int32_t tx0 = std::int32_t(col * tile_w_), ty0 = std::int32_t(row * tile_h_);
    const std::int32_t tx1 = std::min<std::int32_t>(tx0 + std::int32_t(tile_w_), std::int32_t(width_)) - 1;
    const std::int32_t ty1 = std::min<std::int32_t>(ty0 + std::int32_t(tile_h_), std::int32_t(height_)) - 1;
    const double zmax = depth_max_;

    for (std::uint32_t ti : bins_[std::size_t(row) * tiles_x_ + col]) {
        const Tri& t = tris_[ti];
        const std::int32_t x0 = std::max(tx0, t.px0), x1 = std::min(tx1, t.px1);
        const std::int32_t y0 = std::max(ty0, t.py0), y1 = std::min(ty1, t.py1);
        if (t.clear) {
            if (ti < depth_limit_) {
                clear_depth(depth_, marks_, width_, x0, x1, y0, y1, static_cast<std::uint32_t>(t.z0 + 0.5));
                if (lp_) clear_depth(lp_depth_, lp_marks_, width_, x0, x1, y0, y1, static_cast<std::uint32_t>(t.z0 + 0.5));
            }
            continue;
        }
        const DrawState& s = draws_[t.draw];
        ++(t.culled ? tile.cprims : tile.prims);
        if (x0 > x1 || y0 > y1) continue;
        // The depth buffer sees what GL would draw: not the culled triangles,
        // nothing after the snapshot point, nothing with the depth test off.
        const bool depth_buffer = keep_depth_ && !t.culled && ti < depth_limit_ && s.depth_test;

        const std::int64_t sx = std::int64_t(x0) * kSub + kSub / 2, sy = std::int64_t(y0) * kSub + kSub / 2;
        std::int64_t r0 = t.a[0] * sx + t.b[0] * sy + t.c[0];
        std::int64_t r1 = t.a[1] * sx + t.b[1] * sy + t.c[1];
        std::int64_t r2 = t.a[2] * sx + t.b[2] * sy + t.c[2];
        const std::int64_t ax0 = t.a[0] * kSub, ax1 = t.a[1] * kSub, ax2 = t.a[2] * kSub;
        const std::int64_t by0 = t.b[0] * kSub, by1 = t.b[1] * kSub, by2 = t.b[2] * kSub;
        double zr = t.z0 + t.zx * (x0 + 0.5 - t.x0) + t.zy * (y0 + 0.5 - t.y0);

        if (!s.collisionable && !image && !depth_buffer) {
            // Only counted: the unit never sees these fragments.
            std::uint64_t n = 0;
            for (std::int32_t y = y0; y <= y1; ++y) {
                std::int64_t e0 = r0, e1 = r1, e2 = r2;
                for (std::int32_t x = x0; x <= x1; ++x) {
                    n += (e0 | e1 | e2) >= 0;
                    e0 += ax0;
                    e1 += ax1;
                    e2 += ax2;
                }
                r0 += by0;
                r1 += by1;
                r2 += by2;
            }
            add_other(tile, n);
            shade.add(s.shade, n);
            if (tile.other + tile.frags.size() > max_tile_fragments_)
                throw TileTooFull(frame_, col, row, max_tile_fragments_);
            continue;
        }
        std::uint64_t other_here = 0;
        const std::size_t frags_before = tile.frags.size();

        const bool displayed = !t.culled;
        for (std::int32_t y = y0; y <= y1; ++y) {
            std::int64_t e0 = r0, e1 = r1, e2 = r2;
            double z = zr;
            for (std::int32_t x = x0; x <= x1; ++x) {
                if ((e0 | e1 | e2) >= 0) {
                    const double zc = z < 0.0 ? 0.0 : (z > zmax ? zmax : z);
                    const auto depth = static_cast<std::uint32_t>(zc + 0.5);
                    if (s.collisionable) {
                        // (Before the vector grows past the limit: a tile's
                        // fragments stay within it in memory.)
                        if (tile.frags.size() + tile.other >= max_tile_fragments_)
                            throw TileTooFull(frame_, col, row, max_tile_fragments_);
                        Fragment f;
                        f.x = std::uint32_t(x);
                        f.y = std::uint32_t(y);
                        f.depth = depth;
                        f.id = s.id;
                        f.facing = t.facing;
                        f.culled = t.culled;
                        tile.frags.push_back(f);
                    } else {
                        ++other_here;
                    }
                    if (image && displayed) {
                        SceneSource::ImagePixel& p = image->pixels[std::size_t(y) * image->width + std::size_t(x)];
                        if (depth < p.depth) {
                            p.depth = depth;
                            p.object = s.object;
                            p.facing = t.facing;
                        }
                    }
                    if (depth_buffer) {
                        test_and_write(depth_, marks_, std::size_t(y) * width_ + std::size_t(x), s, depth);
                        if (lp_) write_llvmpipe_depth(ti, s, x, y, depth);
                    }
                }
                e0 += ax0;
                e1 += ax1;
                e2 += ax2;
                z += t.zx;
            }
            r0 += by0;
            r1 += by1;
            r2 += by2;
            zr += t.zy;
        }
        add_other(tile, other_here);
        shade.add(s.shade, other_here + (t.culled ? 0 : tile.frags.size() - frags_before));
        if (tile.other + tile.frags.size() > max_tile_fragments_)
            throw TileTooFull(frame_, col, row, max_tile_fragments_);
    }
    shade.set(tile);
}

} // namespace rbcd::scene
