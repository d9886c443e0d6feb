// The tile-based rasterizer behind SceneSource: per frame, geometry (model,
// view, projection, clipping, viewport, snapping) and a polygon list builder
// that bins triangles to tiles; then tile by tile, integer edge-function
// rasterization of the tile's list in submission order. Internal to rbcd_scene.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "rbcd/common/fragment.h"
#include "rbcd/scene/mesh.h"
#include "rbcd/scene/scene_file.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd::scene {

constexpr unsigned kDepthBits = 24;
constexpr std::uint32_t kDepthMax = (1u << kDepthBits) - 1;
constexpr int kSubBits = 8;                  // sub-pixel bits of snapped vertex positions
constexpr std::int64_t kSub = 1 << kSubBits;

class SceneRenderer {
public:
    // Builds or loads every object's mesh; throws InputError naming the mesh key.
    SceneRenderer(SceneDesc desc, const SceneLimits& limits);

    const SceneDesc& desc() const { return desc_; }
    const std::vector<SceneSource::ObjectInfo>& objects() const { return info_; }
    unsigned tiles_x() const { return tiles_x_; }
    unsigned tiles_y() const { return tiles_y_; }
    // Read by SceneGeometry (scene/scene_geometry.h): the same meshes and camera.
    const Mesh& mesh(std::size_t object) const { return *objects_[object].mesh; }
    const Eigen::Matrix4d& view_projection() const { return view_proj_; }

    // Geometry and binning of frame `f`; resets the tile cursor.
    void begin_frame(std::uint64_t f);
    // Rasterizes tiles in row-major order from the cursor and returns the next
    // one holding at least one fragment (collisionable, or counted in `other`);
    // false once the frame has no more. When `image` is given, the nearest
    // displayed surface of every pixel is recorded into it.
    bool next_tile(Tile& tile, SceneSource::FrameImage* image);

    // Of the current frame, after begin_frame.
    std::size_t triangles_set_up() const { return tris_.size(); }

private:
    struct Object {
        std::shared_ptr<const Mesh> mesh;
        bool collisionable = false;
        std::uint32_t id = 0;
        Cull cull = Cull::Back;
    };
    // A triangle after setup: edge functions E(p) = a*px + b*py + c over
    // fixed-point pixel coordinates, positive inside, c carrying the fill-rule
    // bias; depth as a plane over pixel coordinates.
    struct Tri {
        std::int64_t a[3], b[3], c[3];
        double zx, zy, z0;             // depth at pixel centre (px, py) = z0 + zx*(px - x0) + zy*(py - y0)
        double x0, y0;                 // first vertex, pixels
        std::int32_t px0, py0, px1, py1;   // pixel bounding box, inclusive, on screen
        std::uint16_t object;
        std::uint32_t id;
        Facing facing;
        bool culled, collisionable;
    };
    struct ScreenVert {
        std::int32_t x, y;   // fixed point, kSubBits
        double z;            // 0..kDepthMax
    };

    void project(const Eigen::Vector4d& clip, ScreenVert& out) const;
    void setup(const ScreenVert& v0, const ScreenVert& v1, const ScreenVert& v2, std::uint16_t obj_index,
               const Object& obj, bool mirrored);
    void clip_and_setup(const Eigen::Vector4d* c[3], std::uint16_t obj_index, const Object& obj, bool mirrored);
    void bin(std::uint32_t tri_index);
    [[noreturn]] void throw_nonfinite(std::size_t object, std::uint64_t frame) const;
    void raster_tile(unsigned col, unsigned row, Tile& tile, SceneSource::FrameImage* image);

    SceneDesc desc_;
    std::vector<Object> objects_;
    std::vector<SceneSource::ObjectInfo> info_;
    unsigned tile_w_, tile_h_, tiles_x_, tiles_y_;
    Eigen::Matrix4d view_proj_;

    std::uint64_t frame_ = 0;
    std::vector<Tri> tris_;
    std::vector<std::vector<std::uint32_t>> bins_;   // per tile, triangle indices in submission order
    std::size_t cursor_ = 0;
    // Per-vertex scratch of the object being set up.
    std::vector<Eigen::Vector4d> clip_;
    std::vector<std::uint8_t> outcode_;
    std::vector<ScreenVert> screen_;
    mutable bool nonfinite_ = false;   // set by project(): a coordinate NaN, inf or far out of range
};

} // namespace rbcd::scene
