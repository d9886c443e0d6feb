// The collisionable objects of a scene as geometry, frame by frame: what a CPU
// collision detector gets from the application (docs/cpucd.md). The meshes are
// the very ones the rasterizer draws (same loading, same tessellation) and the
// transforms the ones it uses, so CPU and RBCD see the same world.
//
//   SceneGeometry g("workloads/runner.toml", limits);
//   for (std::uint64_t f = 0; f < g.frame_count(); ++f)
//       for (std::size_t i = 0; i < g.parts().size(); ++i)
//           Eigen::Matrix4d m = g.model_matrix(i, f);   // world = m * object space
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rbcd/scene/mesh.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd::scene {

class SceneRenderer;

class SceneGeometry {
public:
    // One collisionable [[object]] of the scene (objects without an id are
    // left out). Objects sharing an id are separate parts of one object for the unit.
    struct Part {
        std::uint32_t id = 0;
        std::string name;
        const Mesh* mesh = nullptr;   // object space, owned by the SceneGeometry
        std::size_t scene_index = 0;  // index among all [[object]]s
    };

    // Throws InputError as SceneSource does (same checks).
    SceneGeometry(const std::string& path, const SceneLimits& limits);
    ~SceneGeometry();
    SceneGeometry(const SceneGeometry&) = delete;
    SceneGeometry& operator=(const SceneGeometry&) = delete;

    std::uint64_t frame_count() const;
    unsigned width() const;
    unsigned height() const;
    // Projection * view, OpenGL clip space (docs/scene.md "The rasterizer").
    const Eigen::Matrix4d& view_projection() const;
    const std::vector<Part>& parts() const { return parts_; }
    // Object space to world space of part i at frame f (scale, rotate X Y Z, translate).
    Eigen::Matrix4d model_matrix(std::size_t part, std::uint64_t frame) const;

private:
    std::unique_ptr<SceneRenderer> r_;
    std::vector<Part> parts_;
};

} // namespace rbcd::scene
