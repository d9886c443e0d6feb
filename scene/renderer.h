// The scene behind SceneSource: per frame, every object's mesh through its
// model, view and projection into the shared tile rasterizer
// (scene/tile_rasterizer.h), one draw an object. Internal to rbcd_scene.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "rbcd/common/fragment.h"
#include "rbcd/scene/mesh.h"
#include "rbcd/scene/scene_file.h"
#include "rbcd/scene/scene_source.h"
#include "rbcd/scene/tile_rasterizer.h"

namespace rbcd::scene {

constexpr unsigned kDepthBits = 24;

class SceneRenderer {
public:
    // Builds or loads every object's mesh; throws InputError naming the mesh key.
    SceneRenderer(SceneDesc desc, const SceneLimits& limits);

    const SceneDesc& desc() const { return desc_; }
    const std::vector<SceneSource::ObjectInfo>& objects() const { return info_; }
    unsigned tiles_x() const { return raster_.tiles_x(); }
    unsigned tiles_y() const { return raster_.tiles_y(); }
    // Read by SceneGeometry (scene/scene_geometry.h): the same meshes and camera.
    const Mesh& mesh(std::size_t object) const { return *objects_[object].mesh; }
    const Eigen::Matrix4d& view_projection() const { return view_proj_; }

    // Geometry and binning of frame `f`; resets the tile cursor.
    void begin_frame(std::uint64_t f);
    // Rasterizes tiles in row-major order from the cursor and returns the next
    // one holding at least one fragment (collisionable, or counted in `other`);
    // false once the frame has no more. When `image` is given, the nearest
    // displayed surface of every pixel is recorded into it.
    bool next_tile(Tile& tile, SceneSource::FrameImage* image) { return raster_.next_tile(tile, image); }

    // Of the current frame, after begin_frame.
    std::size_t triangles_set_up() const { return raster_.triangles_set_up(); }

private:
    struct Object {
        std::shared_ptr<const Mesh> mesh;
        bool collisionable = false;
        std::uint32_t id = 0;
        Cull cull = Cull::Back;
    };

    [[noreturn]] void throw_nonfinite(std::size_t object, std::uint64_t frame) const;

    SceneDesc desc_;
    std::vector<Object> objects_;
    std::vector<SceneSource::ObjectInfo> info_;
    Eigen::Matrix4d view_proj_;
    TileRasterizer raster_;
    std::vector<Eigen::Vector4d> clip_;   // scratch: the object being drawn, in clip space
};

} // namespace rbcd::scene
