#include "rbcd/scene/scene_geometry.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "rbcd/common/errors.h"
#include "rbcd/scene/renderer.h"
#include "rbcd/scene/scene_file.h"

namespace rbcd::scene {

namespace {

std::string read_scene_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(path + ": cannot open scene file");
    std::ostringstream s;
    s << in.rdbuf();
    if (in.bad()) throw InputError(path + ": cannot read scene file");
    return s.str();
}

} // namespace

SceneGeometry::SceneGeometry(const std::string& path, const SceneLimits& limits)
    : r_(std::make_unique<SceneRenderer>(
          parse_scene(read_scene_text(path), path, std::filesystem::path(path).parent_path().string(), limits),
          limits)) {
    const auto& objs = r_->desc().objects;
    for (std::size_t i = 0; i < objs.size(); ++i) {
        if (!objs[i].id) continue;
        Part p;
        p.id = *objs[i].id;
        p.name = objs[i].name;
        p.mesh = &r_->mesh(i);
        p.scene_index = i;
        parts_.push_back(p);
    }
}

SceneGeometry::~SceneGeometry() = default;

std::uint64_t SceneGeometry::frame_count() const { return r_->desc().frames; }
unsigned SceneGeometry::width() const { return r_->desc().width; }
unsigned SceneGeometry::height() const { return r_->desc().height; }
const Eigen::Matrix4d& SceneGeometry::view_projection() const { return r_->view_projection(); }

Eigen::Matrix4d SceneGeometry::model_matrix(std::size_t part, std::uint64_t frame) const {
    return scene::model_matrix(transform_at(r_->desc().objects[parts_.at(part).scene_index], frame));
}

} // namespace rbcd::scene
