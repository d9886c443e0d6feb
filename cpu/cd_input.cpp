#include "rbcd/cpu/cd_input.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <map>

#include <Eigen/LU>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/scene/scene_geometry.h"

namespace rbcd::cpucd {

CdInput load_scene_input(const std::string& scene_path) {
    // The CPU side never runs the unit: any id up to the contract's 16 bits is accepted.
    const scene::SceneLimits limits{16, 16, 16};
    scene::SceneGeometry g(scene_path, limits);
    CdInput in;
    in.name = scene_path;
    in.width = g.width();
    in.height = g.height();
    in.has_view = true;
    in.view_proj = g.view_projection();
    std::map<const scene::Mesh*, std::shared_ptr<const PartMesh>> shared;
    for (const auto& p : g.parts()) {
        auto& m = shared[p.mesh];
        if (!m) {
            auto pm = std::make_shared<PartMesh>();
            pm->verts = p.mesh->verts;
            pm->tris = p.mesh->tris;
            m = std::move(pm);
        }
        in.parts.push_back(Part{p.id, p.name, m});
    }
    in.model.resize(g.frame_count());
    for (std::uint64_t f = 0; f < g.frame_count(); ++f) {
        in.model[f].reserve(in.parts.size());
        for (std::size_t i = 0; i < in.parts.size(); ++i) in.model[f].push_back(g.model_matrix(i, f));
    }
    return in;
}

namespace {

// A token as messages show it: at most 40 bytes (a 100 MB token is not
// printed whole); main() escapes what is not printable.
std::string show(std::string_view t) {
    return t.size() <= 40 ? "'" + std::string(t) + "'"
                          : "'" + std::string(t.substr(0, 40)) + "...' (" + std::to_string(t.size()) + " bytes)";
}

struct LineReader {
    std::string file;
    std::string_view text;
    std::size_t pos = 0;
    unsigned long line = 0;
    std::vector<std::string_view> tok;   // into `text`

    [[noreturn]] void fail(const std::string& what) const { throw input_error_at(file, line, what); }

    // Next non-blank, non-comment line split into fields; false at the end.
    bool next() {
        while (pos < text.size()) {
            const std::size_t nl = text.find('\n', pos);
            const std::size_t end = nl == std::string_view::npos ? text.size() : nl;
            ++line;
            if (end - pos > kMaxGeometryLineBytes)
                fail("line longer than " + std::to_string(kMaxGeometryLineBytes) + " bytes (the limit, fixed; docs/limits.md)");
            std::string_view s = text.substr(pos, end - pos);
            pos = nl == std::string_view::npos ? text.size() : nl + 1;
            if (auto h = s.find('#'); h != std::string_view::npos) s = s.substr(0, h);
            tok.clear();
            std::size_t i = 0;
            while (i < s.size()) {
                while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\v' || s[i] == '\f')) ++i;
                const std::size_t b = i;
                while (i < s.size() && !(s[i] == ' ' || s[i] == '\t' || s[i] == '\r' || s[i] == '\v' || s[i] == '\f')) ++i;
                if (i > b) tok.push_back(s.substr(b, i - b));
            }
            if (!tok.empty()) return true;
        }
        return false;
    }
    void expect_fields(std::size_t n, const char* what) const {
        if (tok.size() != n) fail(std::string(what) + ": expected " + std::to_string(n - 1) + " fields, got " +
                                  std::to_string(tok.size() - 1));
    }
    // A finite number within the scene reader's bound (docs/limits.md).
    // A token from_chars does not read whole (a leading '+', hexadecimal,
    // a value out of range) is read by strtod, so that the same tokens are
    // accepted, with the same values (both round correctly), as by strtod
    // alone; from_chars reads the usual decimal token several times faster.
    double number(std::size_t i) const {
        const std::string_view s = tok.at(i);
        double v = 0;
        const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (ec != std::errc() || p != s.data() + s.size()) {
            const std::string t(s);
            char* end = nullptr;
            v = std::strtod(t.c_str(), &end);
            if (end == t.c_str() || *end != '\0') fail(show(s) + " is not a finite number");
        }
        if (!std::isfinite(v)) fail(show(s) + " is not a finite number");
        if (std::abs(v) > kMaxGeometryCoordinate)
            fail(show(s) + " is beyond +-1e9 (the limit of coordinates and matrix entries, as in scenes; docs/limits.md)");
        return v;
    }
    std::uint64_t count(std::size_t i, std::uint64_t max) const {
        const std::string_view s = tok.at(i);
        if (s.empty() || s.find_first_not_of("0123456789") != std::string_view::npos || s.size() > 12)
            fail(show(s) + " is not an unsigned integer");
        std::uint64_t v = 0;
        for (const char c : s) v = 10 * v + std::uint64_t(c - '0');   // at most 12 digits: no overflow
        if (v > max) fail(std::string(s) + " is out of range 0.." + std::to_string(max));
        return v;
    }
};

// Model matrices are a rotation (or mirror) times a positive scale per axis
// plus a translation, as the scene writes them: Bullet and FCL take rigid
// transforms with the scale applied to the mesh, so a shear would be dropped
// silently and the ground truth be wrong. Columns must be orthogonal to
// kRigidTolerance (|cos| of the angle between two) and of length at least
// kMinGeometryScale.
void check_rigid_plus_scale(const LineReader& r, const Eigen::Matrix4d& m) {
    const Eigen::Matrix3d l = m.block<3, 3>(0, 0);
    for (int k = 0; k < 3; ++k)
        if (!(l.col(k).norm() >= kMinGeometryScale))
            r.fail("m: column " + std::to_string(k) + " has length below 1e-9: the matrix is singular");
    for (int a = 0; a < 3; ++a)
        for (int b = a + 1; b < 3; ++b) {
            const double c = std::abs(l.col(a).dot(l.col(b))) / (l.col(a).norm() * l.col(b).norm());
            if (!(c <= kRigidTolerance))
                r.fail("m: columns " + std::to_string(a) + " and " + std::to_string(b) +
                       " are not orthogonal (|cos| " + std::to_string(c) +
                       " > 1e-6): only rotation, per-axis scale and translation are allowed (no shear)");
        }
}

} // namespace

CdInput load_geometry_file(const std::string& path, const GeometryLimits& limits) {
    const std::string text = read_input_text(path, "geometry file", limits.max_bytes, "--max-geometry-bytes");
    return load_geometry_text(text, path);
}

CdInput load_geometry_text(std::string_view text, const std::string& path) {
    LineReader r;
    r.file = path;
    r.text = text;
    CdInput g;
    g.name = path;
    if (!r.next() || r.tok.size() != 2 || r.tok[0] != "rbcd-geometry" || (r.tok[1] != "1" && r.tok[1] != "2"))
        r.fail("expected the magic line 'rbcd-geometry 1' or 'rbcd-geometry 2'");
    const bool v2 = r.tok[1] == "2";
    constexpr std::uint64_t kMaxCount = 100000000;
    bool in_frames = false, screen_seen = false;
    std::vector<bool> seen;   // parts given a matrix in the current frame
    auto close_frame = [&] {
        if (!in_frames) return;
        for (std::size_t i = 0; i < seen.size(); ++i)
            if (!seen[i]) r.fail("frame " + std::to_string(g.model.size() - 1) + " gives no matrix for part " + std::to_string(i));
    };
    while (r.next()) {
        const std::string k(r.tok[0]);
        if (k == "screen") {
            if (in_frames || screen_seen) r.fail("screen: must come once, before the first part");
            r.expect_fields(3, "screen");
            g.width = unsigned(r.count(1, 8192));
            g.height = unsigned(r.count(2, 8192));
            if (!g.width || !g.height) r.fail("screen: width and height must be at least 1");
            screen_seen = true;
        } else if (k == "view" && v2 && in_frames) {
            FrameExtra& fx = g.extra.back();
            if (fx.has_view) r.fail("view: given twice in this frame");
            r.expect_fields(17, "view");
            for (int i = 0; i < 16; ++i) fx.view_proj(i / 4, i % 4) = r.number(1 + std::size_t(i));
            fx.has_view = true;
        } else if (k == "view") {
            if (in_frames || g.has_view) r.fail("view: must come once, before the first frame");
            r.expect_fields(17, "view");
            for (int i = 0; i < 16; ++i) g.view_proj(i / 4, i % 4) = r.number(1 + std::size_t(i));
            g.has_view = true;
        } else if (k == "part" || (k == "mesh" && v2)) {
            const bool mesh = k == "mesh";
            if (!mesh && in_frames) r.fail("part: parts come before the first frame");
            if (mesh && !in_frames) r.fail("mesh: meshes belong to a frame (parts come before the first)");
            if (r.tok.size() != 4 && r.tok.size() != 5) r.fail(k + ": expected ID NV NT [NAME]");
            Part p;
            p.id = std::uint32_t(r.count(1, 0xFFFFFFFFull));
            const std::uint64_t nv = r.count(2, kMaxCount), nt = r.count(3, kMaxCount);
            if (nv < 3 || nt < 1) r.fail(k + ": needs at least 3 vertices and 1 triangle");
            if (r.tok.size() == 5) p.name = std::string(r.tok[4]);
            auto m = std::make_shared<PartMesh>();
            for (std::uint64_t i = 0; i < nv; ++i) {
                if (!r.next() || r.tok[0] != "v") r.fail("expected vertex " + std::to_string(i) + " ('v X Y Z')");
                r.expect_fields(4, "v");
                m->verts.emplace_back(r.number(1), r.number(2), r.number(3));
            }
            for (std::uint64_t i = 0; i < nt; ++i) {
                if (!r.next() || r.tok[0] != "t") r.fail("expected triangle " + std::to_string(i) + " ('t A B C')");
                r.expect_fields(4, "t");
                m->tris.push_back({std::uint32_t(r.count(1, nv - 1)), std::uint32_t(r.count(2, nv - 1)),
                                   std::uint32_t(r.count(3, nv - 1))});
            }
            p.mesh = std::move(m);
            (mesh ? g.extra.back().meshes : g.parts).push_back(std::move(p));
        } else if (k == "frame") {
            r.expect_fields(2, "frame");
            if (g.parts.empty() && !v2) r.fail("frame: no part before the first frame");
            if (r.count(1, kMaxCount) != g.model.size())
                r.fail("frame: expected frame " + std::to_string(g.model.size()) + " (frames count up from 0)");
            close_frame();
            in_frames = true;
            g.model.emplace_back(g.parts.size(), Eigen::Matrix4d::Identity());
            seen.assign(g.parts.size(), false);
            if (v2) g.extra.emplace_back();
        } else if (k == "m") {
            if (!in_frames) r.fail("m: before the first frame");
            // A format-2 frame may hold meshes alone: then there is no part to move.
            if (g.parts.empty()) r.fail("m: no part to give a matrix (parts come before the first frame)");
            r.expect_fields(14, "m");
            const std::size_t pi = std::size_t(r.count(1, g.parts.size() - 1));
            if (seen[pi]) r.fail("m: part " + std::to_string(pi) + " given twice in this frame");
            seen[pi] = true;
            Eigen::Matrix4d& mm = g.model.back()[pi];
            for (int i = 0; i < 12; ++i) mm(i / 4, i % 4) = r.number(2 + std::size_t(i));
            check_rigid_plus_scale(r, mm);
        } else {
            r.fail("unknown record " + show(k) +
                   (v2 ? " (known: screen, view, part, v, t, frame, m, mesh)" : " (known: screen, view, part, v, t, frame, m)"));
        }
    }
    close_frame();
    if (g.model.empty()) throw InputError(path + ": no frame");
    bool any_view = g.has_view;
    for (const FrameExtra& fx : g.extra) any_view = any_view || fx.has_view;
    if (any_view && !screen_seen) throw InputError(path + ": 'view' needs a 'screen' record");
    return g;
}

CdInput CdInput::frame_input(std::uint64_t f) const {
    CdInput one;
    one.name = name;
    one.width = width;
    one.height = height;
    one.has_view = has_view;
    one.view_proj = view_proj;
    one.parts = parts;
    one.model.push_back(model.at(f));
    if (per_frame()) {
        const FrameExtra& fx = extra.at(f);
        if (fx.has_view) {
            one.has_view = true;
            one.view_proj = fx.view_proj;
        }
        for (const Part& p : fx.meshes) {
            one.parts.push_back(p);
            one.model[0].push_back(Eigen::Matrix4d::Identity());
        }
    }
    return one;
}

std::string geometry_file_text(const CdInput& in) {
    std::string s = in.per_frame() ? "rbcd-geometry 2\n" : "rbcd-geometry 1\n";
    char buf[64];
    auto num = [&](double v) {
        std::snprintf(buf, sizeof buf, " %.17g", v);
        s += buf;
    };
    if (in.width) s += "screen " + std::to_string(in.width) + " " + std::to_string(in.height) + "\n";
    if (in.has_view) {
        s += "view";
        for (int i = 0; i < 16; ++i) num(in.view_proj(i / 4, i % 4));
        s += "\n";
    }
    const auto put_part = [&](const char* record, const Part& p) {
        s += std::string(record) + " " + std::to_string(p.id) + " " + std::to_string(p.mesh->verts.size()) + " " +
             std::to_string(p.mesh->tris.size());
        std::string name = p.name;
        for (char& c : name)
            if (c == ' ' || c == '\t' || c == '#') c = '_';
        if (!name.empty()) s += " " + name;
        s += "\n";
        for (const auto& v : p.mesh->verts) {
            s += "v";
            num(v.x()), num(v.y()), num(v.z());
            s += "\n";
        }
        for (const auto& t : p.mesh->tris)
            s += "t " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
    };
    for (const auto& p : in.parts) put_part("part", p);
    for (std::size_t f = 0; f < in.model.size(); ++f) {
        s += "frame " + std::to_string(f) + "\n";
        if (in.per_frame()) {
            const FrameExtra& fx = in.extra[f];
            if (fx.has_view) {
                s += "view";
                for (int i = 0; i < 16; ++i) num(fx.view_proj(i / 4, i % 4));
                s += "\n";
            }
            for (const auto& p : fx.meshes) put_part("mesh", p);
        }
        for (std::size_t i = 0; i < in.parts.size(); ++i) {
            s += "m " + std::to_string(i);
            for (int k = 0; k < 12; ++k) num(in.model[f][i](k / 4, k % 4));
            s += "\n";
        }
    }
    return s;
}

bool is_closed(const PartMesh& m) {
    // Mesh files repeat a vertex where its normal or texture coordinate
    // changes: weld by position first, so that seams do not count as borders.
    // Sorted arrays, not maps: a game's frame holds tens of thousands of
    // vertices, every frame.
    const std::size_t n = m.verts.size();
    std::vector<std::uint32_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = std::uint32_t(i);
    const auto key = [&](std::uint32_t i) { return std::array<double, 3>{m.verts[i].x(), m.verts[i].y(), m.verts[i].z()}; };
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return key(a) < key(b); });
    std::vector<std::uint32_t> id(n);
    std::uint32_t next = 0;
    for (std::size_t k = 0; k < n; ++k) {
        if (k && key(order[k]) != key(order[k - 1])) ++next;
        id[order[k]] = next;
    }
    // Each edge (welded ends, smaller first) once per triangle side; closed
    // when every edge comes exactly twice.
    std::vector<std::uint64_t> edges;
    edges.reserve(3 * m.tris.size());
    for (const auto& t : m.tris)
        for (int e = 0; e < 3; ++e) {
            std::uint32_t a = id[t[e]], b = id[t[(e + 1) % 3]];
            if (a == b) continue;   // degenerate triangle edge
            if (a > b) std::swap(a, b);
            edges.push_back(std::uint64_t(a) << 32 | b);
        }
    if (edges.empty()) return false;
    std::sort(edges.begin(), edges.end());
    for (std::size_t k = 0; k < edges.size();) {
        std::size_t j = k;
        while (j < edges.size() && edges[j] == edges[k]) ++j;
        if (j - k != 2) return false;
        k = j;
    }
    return true;
}

} // namespace rbcd::cpucd
