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
    : desc_(std::move(desc)), raster_(desc_.width, desc_.height, limits.tile_w, limits.tile_h, kDepthBits) {

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

void SceneRenderer::begin_frame(std::uint64_t f) {
    raster_.begin_frame(f);
    for (std::size_t oi = 0; oi < objects_.size(); ++oi) {
        const Object& obj = objects_[oi];
        const Transform t = transform_at(desc_.objects[oi], f);
        DrawState s = DrawState::full_screen(desc_.width, desc_.height);
        // Rotations have determinant 1: the sign is the scale's, and a mirrored
        // object's outward side is the other one.
        s.front_ccw = !(t.scale.x() * t.scale.y() * t.scale.z() < 0.0);
        s.cull = obj.cull == Cull::Back ? CullFace::Back : obj.cull == Cull::Front ? CullFace::Front : CullFace::None;
        s.collisionable = obj.collisionable;
        s.id = obj.id;
        s.object = static_cast<std::uint16_t>(oi);
        const std::uint32_t draw = raster_.add_draw(std::move(s));
        const Eigen::Matrix4d mvp = view_proj_ * model_matrix(t);
        const Mesh& mesh = *obj.mesh;
        clip_.resize(mesh.verts.size());
        for (std::size_t v = 0; v < clip_.size(); ++v) clip_[v] = mvp * mesh.verts[v].homogeneous();
        if (!mvp.allFinite() || !raster_.add_mesh(draw, clip_.data(), clip_.size(), mesh.tris.data(), mesh.tris.size()))
            throw_nonfinite(oi, f);
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

} // namespace rbcd::scene
