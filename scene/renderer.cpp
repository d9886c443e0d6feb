#include "rbcd/scene/renderer.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <Eigen/Geometry>

#include "rbcd/common/errors.h"
#include "rbcd/scene/mesh_check.h"

namespace rbcd::scene {
namespace {

// Guard band: triangles are clipped against |x|, |y| <= kGuard * w rather than
// the screen edges. Off-screen parts are scissored away by the tile loop, so the
// picture is the same, and new edges appear only where they cannot be seen.
// With screens up to kMaxScreenSide, coordinates stay below 2^23 sub-pixels.
constexpr double kGuard = 4.0;

enum Plane : unsigned { kNear, kFar, kLeft, kRight, kBottom, kTop, kPlanes };

inline double plane_dist(const Eigen::Vector4d& v, unsigned p) {
    switch (p) {
    case kNear: return v.z() + v.w();
    case kFar: return v.w() - v.z();
    case kLeft: return v.x() + kGuard * v.w();
    case kRight: return kGuard * v.w() - v.x();
    case kBottom: return v.y() + kGuard * v.w();
    default: return kGuard * v.w() - v.y();
    }
}

inline std::uint8_t outcode(const Eigen::Vector4d& v) {
    std::uint8_t oc = 0;
    for (unsigned p = 0; p < kPlanes; ++p)
        if (plane_dist(v, p) < 0.0) oc |= std::uint8_t(1u << p);
    return oc;
}

inline std::int64_t floor_div_sub(std::int64_t v) { return v >> kSubBits; }   // arithmetic shift: floor

Eigen::Matrix4d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
    const Eigen::Vector3d f = (target - eye).normalized();
    const Eigen::Vector3d s = f.cross(up).normalized();
    const Eigen::Vector3d u = s.cross(f);
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.block<1, 3>(0, 0) = s.transpose();
    m.block<1, 3>(1, 0) = u.transpose();
    m.block<1, 3>(2, 0) = -f.transpose();
    m(0, 3) = -s.dot(eye);
    m(1, 3) = -u.dot(eye);
    m(2, 3) = f.dot(eye);
    return m;
}

// OpenGL convention: NDC z in [-1, 1], -1 at the near plane.
Eigen::Matrix4d perspective(double fov_y_deg, double aspect, double n, double f) {
    const double fy = 1.0 / std::tan(fov_y_deg * 3.14159265358979323846 / 360.0);
    Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
    m(0, 0) = fy / aspect;
    m(1, 1) = fy;
    m(2, 2) = (f + n) / (n - f);
    m(2, 3) = 2.0 * f * n / (n - f);
    m(3, 2) = -1.0;
    return m;
}

} // namespace

SceneRenderer::SceneRenderer(SceneDesc desc, const SceneLimits& limits)
    : desc_(std::move(desc)), tile_w_(limits.tile_w), tile_h_(limits.tile_h) {
    tiles_x_ = (desc_.width + tile_w_ - 1) / tile_w_;
    tiles_y_ = (desc_.height + tile_h_ - 1) / tile_h_;
    bins_.resize(std::size_t(tiles_x_) * tiles_y_);

    std::map<std::string, std::shared_ptr<const Mesh>> files;
    std::map<std::pair<std::string, unsigned>, std::shared_ptr<const Mesh>> shapes;
    std::set<std::string> warned;
    for (const ObjectDesc& od : desc_.objects) {
        Object o;
        if (od.builtin) {
            const unsigned seg = od.mesh == "box" ? 0 : od.segments;
            auto& m = shapes[{od.mesh, seg}];
            if (!m) m = std::make_shared<const Mesh>(builtin_mesh(od.mesh, od.segments));
            o.mesh = m;
        } else {
            auto& m = files[od.mesh];
            if (!m) {
                auto mesh = std::make_shared<Mesh>();
                std::string err;
                if (!load_mesh_file(od.mesh, *mesh, err))
                    throw input_error_at(desc_.display_name, od.mesh_line,
                                         od.key_path + ".mesh: cannot read mesh file '" + od.mesh + "': " + err);
                m = std::move(mesh);
            }
            o.mesh = m;
        }
        // docs/scene.md "Mesh checks": one warning per file, unless silenced.
        if (!od.builtin && od.check_mesh && warned.insert(od.mesh).second) warn_mesh_problems(desc_.display_name, od, *o.mesh);
        o.collisionable = od.id.has_value();
        o.id = od.id.value_or(0);
        o.cull = od.cull;
        objects_.push_back(o);
        SceneSource::ObjectInfo info;
        info.name = od.name;
        info.collisionable = o.collisionable;
        info.id = o.id;
        info.triangles = o.mesh->tris.size();
        info_.push_back(info);
    }

    const CameraDesc& c = desc_.camera;
    view_proj_ = perspective(c.fov_y, double(desc_.width) / double(desc_.height), c.near, c.far) *
                 look_at(c.eye, c.target, c.up);
}

// Kept out of line and compiled without FP contraction (scene/CMakeLists.txt):
// a vertex shared by two triangles, one clipped and one not, must snap to the
// same sub-pixel position on both paths.
void SceneRenderer::project(const Eigen::Vector4d& clip, ScreenVert& out) const {
    const double iw = 1.0 / clip.w();
    const double sx = (clip.x() * iw * 0.5 + 0.5) * double(desc_.width);
    const double sy = (0.5 - clip.y() * iw * 0.5) * double(desc_.height);   // screen y grows downwards
    const double z = (clip.z() * iw * 0.5 + 0.5) * double(kDepthMax);
    // Refused by begin_frame: converting NaN or inf to an integer is undefined.
    if (!(std::isfinite(sx) && std::isfinite(sy) && std::isfinite(z) && std::abs(sx) < 1e9 && std::abs(sy) < 1e9)) {
        nonfinite_ = true;
        out = ScreenVert{0, 0, 0.0};
        return;
    }
    out.x = static_cast<std::int32_t>(std::llround(sx * double(kSub)));
    out.y = static_cast<std::int32_t>(std::llround(sy * double(kSub)));
    out.z = std::clamp(z, 0.0, double(kDepthMax));
}

void SceneRenderer::begin_frame(std::uint64_t f) {
    frame_ = f;
    tris_.clear();
    for (auto& b : bins_) b.clear();
    cursor_ = 0;

    for (std::size_t oi = 0; oi < objects_.size(); ++oi) {
        const Object& obj = objects_[oi];
        const Transform t = transform_at(desc_.objects[oi], f);
        // Rotations have determinant 1: the sign is the scale's.
        const bool mirrored = t.scale.x() * t.scale.y() * t.scale.z() < 0.0;
        const Eigen::Matrix4d mvp = view_proj_ * model_matrix(t);
        const Mesh& mesh = *obj.mesh;
        const std::size_t nv = mesh.verts.size();
        clip_.resize(nv);
        outcode_.resize(nv);
        screen_.resize(nv);
        for (std::size_t v = 0; v < nv; ++v) {
            clip_[v] = mvp * mesh.verts[v].homogeneous();
            outcode_[v] = outcode(clip_[v]);
            if (outcode_[v] == 0) project(clip_[v], screen_[v]);
        }
        const auto obj_index = static_cast<std::uint16_t>(oi);
        for (const auto& tri : mesh.tris) {
            const std::uint8_t o0 = outcode_[tri[0]], o1 = outcode_[tri[1]], o2 = outcode_[tri[2]];
            if (o0 & o1 & o2) continue;   // wholly outside one plane
            if ((o0 | o1 | o2) == 0) {
                setup(screen_[tri[0]], screen_[tri[1]], screen_[tri[2]], obj_index, obj, mirrored);
            } else {
                const Eigen::Vector4d* c[3] = {&clip_[tri[0]], &clip_[tri[1]], &clip_[tri[2]]};
                clip_and_setup(c, obj_index, obj, mirrored);
            }
        }
        if (nonfinite_ || !mvp.allFinite()) throw_nonfinite(oi, f);
    }
}

void SceneRenderer::throw_nonfinite(std::size_t oi, std::uint64_t f) const {
    const ObjectDesc& od = desc_.objects[oi];
    std::size_t k = 0;   // the key in force at frame f
    while (k + 1 < od.keys.size() && od.keys[k + 1].frame <= f) ++k;
    const std::string key = k == 0 ? od.key_path : od.key_path + ".key[" + std::to_string(k - 1) + "]";
    throw input_error_at(desc_.display_name, od.keys[k].line,
                         key + ": at frame " + std::to_string(f) +
                             " the transform (position, rotation, scale) with the camera makes a projected "
                             "coordinate or depth non-finite or out of range");
}

void SceneRenderer::clip_and_setup(const Eigen::Vector4d* c[3], std::uint16_t obj_index, const Object& obj, bool mirrored) {
    // Sutherland-Hodgman. Each intersection is computed from the inside end of
    // the edge towards the outside end, so the two triangles sharing an edge
    // create bit-identical vertices on it and stay watertight after clipping.
    Eigen::Vector4d buf_a[3 + kPlanes], buf_b[3 + kPlanes];
    Eigen::Vector4d* in = buf_a;
    Eigen::Vector4d* out = buf_b;
    int n = 3;
    for (int i = 0; i < 3; ++i) in[i] = *c[i];
    for (unsigned p = 0; p < kPlanes && n >= 3; ++p) {
        int m = 0;
        for (int i = 0; i < n; ++i) {
            const Eigen::Vector4d& P = in[i];
            const Eigen::Vector4d& Q = in[(i + 1) % n];
            const double dp = plane_dist(P, p), dq = plane_dist(Q, p);
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
    if (n < 3) return;
    ScreenVert sv[3 + kPlanes];
    for (int i = 0; i < n; ++i) project(in[i], sv[i]);
    for (int i = 1; i + 1 < n; ++i) setup(sv[0], sv[i], sv[i + 1], obj_index, obj, mirrored);
}

void SceneRenderer::setup(const ScreenVert& v0, const ScreenVert& v1in, const ScreenVert& v2in, std::uint16_t obj_index,
                          const Object& obj, bool mirrored) {
    const std::int64_t area = std::int64_t(v1in.x - v0.x) * (v2in.y - v0.y) - std::int64_t(v2in.x - v0.x) * (v1in.y - v0.y);
    if (area == 0) return;   // degenerate after snapping: covers no sample point
    // Counter-clockwise in NDC (y up) is negative with y down. A mirrored
    // object's outward side is the other one, hence the xor.
    const bool ccw = area < 0;
    const Facing facing = (ccw != mirrored) ? Facing::Front : Facing::Back;
    const bool culled = (obj.cull == Cull::Back && facing == Facing::Back) || (obj.cull == Cull::Front && facing == Facing::Front);
    if (culled && !obj.collisionable) return;

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
        // Top-left rule (y down, clockwise on screen): a sample exactly on an
        // edge belongs to the triangle only if the edge is a top or a left one.
        // The edge shared by two triangles runs in opposite directions in them,
        // so exactly one of them owns the samples on it.
        const bool top_left = dy < 0 || (dy == 0 && dx > 0);
        if (!top_left) t.c[i] -= 1;
        minx = std::min<std::int64_t>(minx, a.x);
        maxx = std::max<std::int64_t>(maxx, a.x);
        miny = std::min<std::int64_t>(miny, a.y);
        maxy = std::max<std::int64_t>(maxy, a.y);
    }
    // Pixel x's sample is at x * kSub + kSub / 2.
    std::int64_t px0 = floor_div_sub(minx - kSub / 2 + kSub - 1);
    std::int64_t px1 = floor_div_sub(maxx - kSub / 2);
    std::int64_t py0 = floor_div_sub(miny - kSub / 2 + kSub - 1);
    std::int64_t py1 = floor_div_sub(maxy - kSub / 2);
    px0 = std::max<std::int64_t>(px0, 0);
    py0 = std::max<std::int64_t>(py0, 0);
    px1 = std::min<std::int64_t>(px1, std::int64_t(desc_.width) - 1);
    py1 = std::min<std::int64_t>(py1, std::int64_t(desc_.height) - 1);
    if (px0 > px1 || py0 > py1) return;
    t.px0 = std::int32_t(px0);
    t.py0 = std::int32_t(py0);
    t.px1 = std::int32_t(px1);
    t.py1 = std::int32_t(py1);

    // Window depth is affine in screen space: a plane through the snapped corners.
    const double inv = 1.0 / double(kSub);
    const double x0 = v[0]->x * inv, y0 = v[0]->y * inv;
    const double x1 = v[1]->x * inv - x0, y1 = v[1]->y * inv - y0;
    const double x2 = v[2]->x * inv - x0, y2 = v[2]->y * inv - y0;
    const double z1 = v[1]->z - v[0]->z, z2 = v[2]->z - v[0]->z;
    const double det = x1 * y2 - x2 * y1;
    t.zx = (z1 * y2 - z2 * y1) / det;
    t.zy = (x1 * z2 - x2 * z1) / det;
    t.z0 = v[0]->z;
    t.x0 = x0;
    t.y0 = y0;
    t.object = obj_index;
    t.id = obj.id;
    t.facing = facing;
    t.culled = culled;
    t.collisionable = obj.collisionable;

    tris_.push_back(t);
    bin(static_cast<std::uint32_t>(tris_.size() - 1));
}

void SceneRenderer::bin(std::uint32_t ti) {
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

bool SceneRenderer::next_tile(Tile& tile, SceneSource::FrameImage* image) {
    while (cursor_ < bins_.size()) {
        const std::size_t idx = cursor_++;
        if (bins_[idx].empty()) continue;
        raster_tile(unsigned(idx % tiles_x_), unsigned(idx / tiles_x_), tile, image);
        bins_[idx].clear();
        if (!tile.frags.empty() || tile.other != 0) return true;
    }
    return false;
}

void SceneRenderer::raster_tile(unsigned col, unsigned row, Tile& tile, SceneSource::FrameImage* image) {
    tile.frame = frame_;
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
    // Non-collisionable fragments are emitted in primitive order between the
    // collisionable ones: adjacent runs merge.
    const auto add_other = [&tile](std::uint64_t n) {
        if (n == 0) return;
        tile.other += n;
        const auto before = static_cast<std::uint32_t>(tile.frags.size());
        if (!tile.other_runs.empty() && tile.other_runs.back().before == before) tile.other_runs.back().count += n;
        else tile.other_runs.push_back({before, n});
    };

    const std::int32_t tx0 = std::int32_t(col * tile_w_), ty0 = std::int32_t(row * tile_h_);
    const std::int32_t tx1 = std::min<std::int32_t>(tx0 + std::int32_t(tile_w_), std::int32_t(desc_.width)) - 1;
    const std::int32_t ty1 = std::min<std::int32_t>(ty0 + std::int32_t(tile_h_), std::int32_t(desc_.height)) - 1;

    for (std::uint32_t ti : bins_[std::size_t(row) * tiles_x_ + col]) {
        const Tri& t = tris_[ti];
        ++(t.culled ? tile.cprims : tile.prims);
        const std::int32_t x0 = std::max(tx0, t.px0), x1 = std::min(tx1, t.px1);
        const std::int32_t y0 = std::max(ty0, t.py0), y1 = std::min(ty1, t.py1);
        if (x0 > x1 || y0 > y1) continue;

        const std::int64_t sx = std::int64_t(x0) * kSub + kSub / 2, sy = std::int64_t(y0) * kSub + kSub / 2;
        std::int64_t r0 = t.a[0] * sx + t.b[0] * sy + t.c[0];
        std::int64_t r1 = t.a[1] * sx + t.b[1] * sy + t.c[1];
        std::int64_t r2 = t.a[2] * sx + t.b[2] * sy + t.c[2];
        const std::int64_t ax0 = t.a[0] * kSub, ax1 = t.a[1] * kSub, ax2 = t.a[2] * kSub;
        const std::int64_t by0 = t.b[0] * kSub, by1 = t.b[1] * kSub, by2 = t.b[2] * kSub;
        double zr = t.z0 + t.zx * (x0 + 0.5 - t.x0) + t.zy * (y0 + 0.5 - t.y0);

        if (!t.collisionable && !image) {
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
            add_other(n);
            continue;
        }
        std::uint64_t other_here = 0;

        const bool displayed = !t.culled;
        for (std::int32_t y = y0; y <= y1; ++y) {
            std::int64_t e0 = r0, e1 = r1, e2 = r2;
            double z = zr;
            for (std::int32_t x = x0; x <= x1; ++x) {
                if ((e0 | e1 | e2) >= 0) {
                    const double zc = z < 0.0 ? 0.0 : (z > double(kDepthMax) ? double(kDepthMax) : z);
                    const auto depth = static_cast<std::uint32_t>(zc + 0.5);
                    if (t.collisionable) {
                        Fragment f;
                        f.x = std::uint32_t(x);
                        f.y = std::uint32_t(y);
                        f.depth = depth;
                        f.id = t.id;
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
                            p.object = t.object;
                            p.facing = t.facing;
                        }
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
        add_other(other_here);
    }
}

} // namespace rbcd::scene
