#include "rbcd/scene/mesh_check.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <numeric>
#include <sstream>
#include <vector>

#include <Eigen/Geometry>

namespace rbcd::scene {
namespace {

using V3 = Eigen::Vector3d;
using Tri = std::array<std::uint32_t, 3>;

// Welded vertex ids: equal positions, equal id.
std::vector<std::uint32_t> weld(const Mesh& m) {
    std::vector<std::uint32_t> order(m.verts.size());
    std::iota(order.begin(), order.end(), 0u);
    auto less = [&](std::uint32_t a, std::uint32_t b) {
        const V3 &p = m.verts[a], &q = m.verts[b];
        return std::tie(p.x(), p.y(), p.z()) < std::tie(q.x(), q.y(), q.z());
    };
    std::sort(order.begin(), order.end(), less);
    std::vector<std::uint32_t> id(m.verts.size());
    std::uint32_t next = 0;
    for (std::size_t i = 0; i < order.size(); ++i) {
        if (i > 0 && less(order[i - 1], order[i])) ++next;
        id[order[i]] = next;
    }
    return id;
}

// Sign of the volume of tetrahedron (a, b, c, d) beyond a tolerance `eps`:
// +1, -1, or 0 for (nearly) coplanar.
int orient3(const V3& a, const V3& b, const V3& c, const V3& d, double eps) {
    const double v = (b - a).dot((c - a).cross(d - a));
    return v > eps ? 1 : (v < -eps ? -1 : 0);
}

// Where segment pq meets triangle abc, its ends strictly on either side of
// the plane: kThrough (the interior), kEdge + k (edge k: ab, bc, ca, away
// from the corners) or kMiss. A segment through a corner, or one that only
// touches the plane, misses.
constexpr int kMiss = -1, kThrough = 3, kEdge = 0;
int segment_hit(const V3& p, const V3& q, const V3& a, const V3& b, const V3& c, double eps) {
    const int sp = orient3(a, b, c, p, eps), sq = orient3(a, b, c, q, eps);
    if (sp == 0 || sq == 0 || sp == sq) return kMiss;
    const int s[3] = {orient3(p, q, a, b, eps), orient3(p, q, b, c, eps), orient3(p, q, c, a, eps)};
    const int zeros = (s[0] == 0) + (s[1] == 0) + (s[2] == 0);
    if (zeros > 1) return kMiss;
    if (!((s[0] >= 0 && s[1] >= 0 && s[2] >= 0) || (s[0] <= 0 && s[1] <= 0 && s[2] <= 0))) return kMiss;
    if (zeros == 0) return kThrough;
    return kEdge + (s[0] == 0 ? 0 : s[1] == 0 ? 1 : 2);
}

double orient2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// Two triangles in one plane, facing the same way, overlap in more than a
// shared boundary. Facing opposite ways they are two solids touching face to
// face, which is no defect.
bool coplanar_overlap(const std::array<V3, 3>& t, const std::array<V3, 3>& u, double eps2) {
    const V3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (n.dot((u[1] - u[0]).cross(u[2] - u[0])) <= 0.0) return false;
    int drop = 0;
    n.cwiseAbs().maxCoeff(&drop);
    auto proj = [drop](const V3& p) {
        return drop == 0 ? Eigen::Vector2d(p.y(), p.z()) : drop == 1 ? Eigen::Vector2d(p.z(), p.x()) : Eigen::Vector2d(p.x(), p.y());
    };
    std::array<Eigen::Vector2d, 3> a{proj(t[0]), proj(t[1]), proj(t[2])}, b{proj(u[0]), proj(u[1]), proj(u[2])};
    auto sgn = [eps2](double v) { return v > eps2 ? 1 : (v < -eps2 ? -1 : 0); };
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const auto &p = a[i], &q = a[(i + 1) % 3], &r = b[j], &s = b[(j + 1) % 3];
            const int d1 = sgn(orient2(p, q, r)), d2 = sgn(orient2(p, q, s));
            const int d3 = sgn(orient2(r, s, p)), d4 = sgn(orient2(r, s, q));
            if (d1 && d2 && d3 && d4 && d1 != d2 && d3 != d4) return true;   // edges cross properly
        }
    auto inside = [&](const std::array<Eigen::Vector2d, 3>& tri, const Eigen::Vector2d& p) {
        const int s0 = sgn(orient2(tri[0], tri[1], p)), s1 = sgn(orient2(tri[1], tri[2], p)), s2 = sgn(orient2(tri[2], tri[0], p));
        return s0 != 0 && s0 == s1 && s1 == s2;
    };
    // One inside the other (no edge crossing): its centroid is strictly inside.
    return inside(a, (b[0] + b[1] + b[2]) / 3.0) || inside(b, (a[0] + a[1] + a[2]) / 3.0);
}

struct Box {
    V3 lo, hi;
};

// The mesh with welded corners and, per undirected edge, the triangles using it.
struct Topology {
    const Mesh& m;
    const std::vector<Tri>& w;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> edge_tris;   // sorted (edge key, triangle)

    static std::uint64_t key(std::uint32_t u, std::uint32_t v) {
        return std::uint64_t(std::min(u, v)) << 32 | std::max(u, v);
    }
    std::array<V3, 3> corners(std::uint32_t t) const {
        return {m.verts[m.tris[t][0]], m.verts[m.tris[t][1]], m.verts[m.tris[t][2]]};
    }
    // The other triangle on edge k of t, when exactly two use it.
    bool neighbour(std::uint32_t t, int k, std::uint32_t& out) const {
        const std::uint64_t e = key(w[t][k], w[t][(k + 1) % 3]);
        auto it = std::lower_bound(edge_tris.begin(), edge_tris.end(), std::make_pair(e, std::uint32_t(0)));
        std::uint32_t others[2];
        int n = 0, uses = 0;
        for (; it != edge_tris.end() && it->first == e; ++it, ++uses)
            if (it->second != t && n < 2) others[n++] = it->second;
        if (uses != 2 || n != 1) return false;
        out = others[0];
        return true;
    }
};

// Segment pq (of some triangle) crosses the surface at triangle t. Through an
// edge it crosses only if it also crosses the neighbour's plane: so a quad's
// diagonal counts (a box moved along its own diagonal meets the other's faces
// there), a solid resting face to face on another does not.
bool crosses_surface(const Topology& topo, const V3& p, const V3& q, std::uint32_t t, double eps) {
    const auto c = topo.corners(t);
    const int hit = segment_hit(p, q, c[0], c[1], c[2], eps);
    if (hit == kMiss) return false;
    if (hit == kThrough) return true;
    std::uint32_t o;
    if (!topo.neighbour(t, hit - kEdge, o)) return false;
    const auto n = topo.corners(o);
    const int sp = orient3(n[0], n[1], n[2], p, eps), sq = orient3(n[0], n[1], n[2], q, eps);
    return sp != 0 && sq != 0 && sp != sq;
}

// Triangles t and u cross. Pairs sharing an edge cannot cross without
// overlapping in their plane, which is not looked for; pairs sharing one
// vertex can only cross through the edges opposite it.
bool triangles_cross(const Topology& topo, std::uint32_t ti, std::uint32_t ui, double scale) {
    const double eps = 1e-12 * scale * scale * scale;
    const Tri &wt = topo.w[ti], &wu = topo.w[ui];
    const auto t = topo.corners(ti), u = topo.corners(ui);
    int shared = 0, st = -1, su = -1;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            if (wt[i] == wu[j]) ++shared, st = i, su = j;
    if (shared >= 2) return false;
    // Most candidates lie wholly on one side of the other's plane.
    auto one_side = [eps](const std::array<V3, 3>& p, const std::array<V3, 3>& q) {
        const int s0 = orient3(p[0], p[1], p[2], q[0], eps), s1 = orient3(p[0], p[1], p[2], q[1], eps),
                  s2 = orient3(p[0], p[1], p[2], q[2], eps);
        return (s0 >= 0 && s1 >= 0 && s2 >= 0 && (s0 | s1 | s2)) || (s0 <= 0 && s1 <= 0 && s2 <= 0 && (s0 | s1 | s2));
    };
    if (one_side(t, u) || one_side(u, t)) return false;
    if (shared == 1)
        return crosses_surface(topo, t[(st + 1) % 3], t[(st + 2) % 3], ui, eps) ||
               crosses_surface(topo, u[(su + 1) % 3], u[(su + 2) % 3], ti, eps);
    for (int i = 0; i < 3; ++i) {
        if (crosses_surface(topo, t[i], t[(i + 1) % 3], ui, eps)) return true;
        if (crosses_surface(topo, u[i], u[(i + 1) % 3], ti, eps)) return true;
    }
    if (orient3(t[0], t[1], t[2], u[0], eps) == 0 && orient3(t[0], t[1], t[2], u[1], eps) == 0 &&
        orient3(t[0], t[1], t[2], u[2], eps) == 0)
        return coplanar_overlap(t, u, 1e-12 * scale * scale);
    return false;
}

void find_intersection(const Topology& topo, const std::vector<std::uint32_t>& tris, std::size_t max_pairs, MeshCheck& r) {
    const Mesh& m = topo.m;
    const std::size_t n = tris.size();
    if (n < 2) return;
    std::vector<Box> box(n);
    Box all{V3::Constant(INFINITY), V3::Constant(-INFINITY)};
    double extent_sum = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const auto& t = m.tris[tris[i]];
        box[i].lo = m.verts[t[0]].cwiseMin(m.verts[t[1]]).cwiseMin(m.verts[t[2]]);
        box[i].hi = m.verts[t[0]].cwiseMax(m.verts[t[1]]).cwiseMax(m.verts[t[2]]);
        all.lo = all.lo.cwiseMin(box[i].lo);
        all.hi = all.hi.cwiseMax(box[i].hi);
        extent_sum += (box[i].hi - box[i].lo).maxCoeff();
    }
    const double diag = (all.hi - all.lo).norm();
    if (!(diag > 0.0)) return;
    // Cells about the size of a triangle; coarser when large triangles would
    // fill too many cells.
    double h = std::max(extent_sum / double(n), diag / 1024.0);
    std::vector<std::pair<std::uint64_t, std::uint32_t>> cells;
    std::array<std::uint64_t, 3> dims{};
    auto cell_of = [&](const V3& p, int axis) {
        return std::min<std::uint64_t>(dims[axis] - 1, std::uint64_t(std::max(0.0, (p[axis] - all.lo[axis]) / h)));
    };
    for (int attempt = 0;; ++attempt) {
        for (int a = 0; a < 3; ++a) dims[a] = std::uint64_t((all.hi[a] - all.lo[a]) / h) + 1;
        std::uint64_t total = 0;
        for (std::size_t i = 0; i < n; ++i) {
            std::uint64_t c = 1;
            for (int a = 0; a < 3; ++a) c *= cell_of(box[i].hi, a) - cell_of(box[i].lo, a) + 1;
            total += c;
        }
        if (total <= 16 * n + 1000000) break;
        if (attempt == 20) {
            r.intersection_checked = false;
            return;
        }
        h *= 2.0;
    }
    cells.reserve(n * 2);
    for (std::size_t i = 0; i < n; ++i)
        for (std::uint64_t x = cell_of(box[i].lo, 0); x <= cell_of(box[i].hi, 0); ++x)
            for (std::uint64_t y = cell_of(box[i].lo, 1); y <= cell_of(box[i].hi, 1); ++y)
                for (std::uint64_t z = cell_of(box[i].lo, 2); z <= cell_of(box[i].hi, 2); ++z)
                    cells.emplace_back((x * dims[1] + y) * dims[2] + z, std::uint32_t(i));
    std::sort(cells.begin(), cells.end());

    std::size_t visited = 0;
    for (std::size_t s = 0; s < cells.size();) {
        std::size_t e = s;
        while (e < cells.size() && cells[e].first == cells[s].first) ++e;
        const std::uint64_t key = cells[s].first;
        for (std::size_t i = s; i < e; ++i) {
            for (std::size_t j = i + 1; j < e; ++j) {
                if (++visited > max_pairs) {
                    r.intersection_checked = false;
                    return;
                }
                const std::uint32_t a = cells[i].second, b = cells[j].second;
                const Box &ba = box[a], &bb = box[b];
                if ((ba.hi.array() < bb.lo.array()).any() || (bb.hi.array() < ba.lo.array()).any()) continue;
                // Each pair once: in the cell holding the low corner of the boxes' overlap.
                const V3 lo = ba.lo.cwiseMax(bb.lo);
                if ((cell_of(lo, 0) * dims[1] + cell_of(lo, 1)) * dims[2] + cell_of(lo, 2) != key) continue;
                const double scale = (ba.hi.cwiseMax(bb.hi) - ba.lo.cwiseMin(bb.lo)).maxCoeff();
                if (triangles_cross(topo, tris[a], tris[b], scale)) {
                    r.self_intersecting = true;
                    r.tri_a = std::min(tris[a], tris[b]);
                    r.tri_b = std::max(tris[a], tris[b]);
                    return;
                }
            }
        }
        s = e;
    }
}

} // namespace

MeshCheck check_mesh(const Mesh& m, std::size_t max_pairs) {
    MeshCheck r;
    const std::vector<std::uint32_t> id = weld(m);
    std::vector<Tri> w(m.tris.size());
    std::vector<std::uint32_t> live;   // triangles with three distinct corners
    for (std::size_t i = 0; i < m.tris.size(); ++i) {
        const auto& t = m.tris[i];
        w[i] = {id[t[0]], id[t[1]], id[t[2]]};
        if (w[i][0] != w[i][1] && w[i][1] != w[i][2] && w[i][0] != w[i][2]) live.push_back(std::uint32_t(i));
    }

    // Edges: (low id, high id) and the direction this triangle runs it.
    Topology topo{m, w, {}};
    auto& edges = topo.edge_tris;
    edges.reserve(live.size() * 3);
    for (std::uint32_t i : live)
        for (int k = 0; k < 3; ++k) edges.emplace_back(Topology::key(w[i][k], w[i][(k + 1) % 3]), i);
    std::sort(edges.begin(), edges.end());
    for (std::size_t s = 0; s < edges.size();) {
        std::size_t e = s;
        int sum = 0;   // +1 for each triangle running the edge low id to high id, -1 the other way
        for (; e < edges.size() && edges[e].first == edges[s].first; ++e) {
            const Tri& t = w[edges[e].second];
            const std::uint32_t lo = std::uint32_t(edges[e].first >> 32);
            int k = 0;
            while (t[k] != lo) ++k;
            sum += t[(k + 1) % 3] == std::uint32_t(edges[e].first) ? 1 : -1;
        }
        const std::size_t uses = e - s;
        if (uses == 1) ++r.boundary_edges;
        else if (uses > 2) ++r.nonmanifold_edges;
        else if (sum != 0) ++r.misoriented_edges;
        s = e;
    }
    r.closed = !live.empty() && r.boundary_edges == 0;

    // Signed volume about the centre of the bounding box (less cancellation).
    if (!m.verts.empty()) {
        V3 lo = m.verts[0], hi = m.verts[0];
        for (const auto& v : m.verts) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
        const V3 c = (lo + hi) / 2.0;
        double vol = 0.0;
        for (std::uint32_t i : live) {
            const auto& t = m.tris[i];
            vol += (m.verts[t[0]] - c).dot((m.verts[t[1]] - c).cross(m.verts[t[2]] - c));
        }
        r.signed_volume = vol / 6.0;
        const double size = (hi - lo).maxCoeff();
        // Only a closed surface has an inside; a relative tolerance for flat meshes.
        r.inside_out = r.closed && r.signed_volume < -1e-9 * size * size * size;
    }

    find_intersection(topo, live, max_pairs, r);
    return r;
}

std::string warn_mesh_problems(const std::string& scene_name, const ObjectDesc& od, const Mesh& m) {
    const std::string what = check_mesh(m).problems();
    if (what.empty()) return what;
    const std::string line = scene_name + ":" + std::to_string(od.mesh_line) + ": warning: " + od.key_path +
                             ".mesh: mesh file '" + od.mesh + "' is " + what +
                             "; collision results may be wrong (" + od.key_path + ".check_mesh = false silences this)";
    std::cerr << line << std::endl;
    return line;
}

std::string MeshCheck::problems() const {
    std::ostringstream s;
    auto sep = [&] { if (s.tellp() > 0) s << ", "; };
    if (boundary_edges) sep(), s << "open (" << boundary_edges << " boundary edges)";
    if (nonmanifold_edges) sep(), s << "not manifold (" << nonmanifold_edges << " edges shared by 3 or more triangles)";
    if (misoriented_edges) sep(), s << "inconsistently wound (" << misoriented_edges << " edges where neighbours disagree)";
    if (inside_out) sep(), s << "wound inside out (signed volume " << signed_volume << ")";
    if (self_intersecting) sep(), s << "self-intersecting (triangles " << tri_a << " and " << tri_b << " cross)";
    return s.str();
}

} // namespace rbcd::scene
