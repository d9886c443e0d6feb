// What rbcd-cpucd detects collisions on: the collisionable objects' meshes in
// object space and, per frame, each one's model matrix (world = M * object), so
// the world-space meshes of every frame; plus the camera, for the accuracy
// analysis (where a contact lies on screen). Read from a scene (the same
// geometry the rasterizer draws) or from a geometry file (docs/cpucd.md), the
// input for traces whose geometry is given separately.
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

namespace rbcd::cpucd {

struct PartMesh {
    std::vector<Eigen::Vector3d> verts;
    std::vector<std::array<std::uint32_t, 3>> tris;
};

// One rigid part; parts sharing an id are one object (pairs inside it are not collisions).
struct Part {
    std::uint32_t id = 0;
    std::string name;
    std::shared_ptr<const PartMesh> mesh;
};

// What a frame of a format-2 geometry file adds to the parts of the whole run:
// its own meshes (world coordinates, this frame only: game models change shape
// every frame) and its own view.
struct FrameExtra {
    bool has_view = false;
    Eigen::Matrix4d view_proj = Eigen::Matrix4d::Identity();
    std::vector<Part> meshes;
};

struct CdInput {
    std::string name;
    unsigned width = 0, height = 0;   // screen; 0 when the input gives no camera
    bool has_view = false;
    Eigen::Matrix4d view_proj = Eigen::Matrix4d::Identity();   // OpenGL clip space
    std::vector<Part> parts;
    std::vector<std::vector<Eigen::Matrix4d>> model;          // [frame][part]
    std::vector<FrameExtra> extra;   // [frame], format 2 only (empty: every frame is the parts alone)
    std::uint64_t frames() const { return model.size(); }
    bool per_frame() const { return !extra.empty(); }
    // Frame f alone, as an input of one frame: the parts at their frame-f
    // matrices, and the frame's own meshes (identity matrices) and view.
    CdInput frame_input(std::uint64_t f) const;
};

// What a geometry file may hold (docs/limits.md, "rbcd-cpucd").
struct GeometryLimits {
    std::uint64_t max_bytes = std::uint64_t(256) << 20;   // --max-geometry-bytes
};
// The bounds the scene reader puts on a scene, put on a geometry file too.
inline constexpr double kMaxGeometryCoordinate = 1e9;   // |vertex|, |matrix entry|
inline constexpr double kMinGeometryScale = 1e-9;       // a column's length (scale) at least
inline constexpr double kRigidTolerance = 1e-6;         // |cos| between a matrix's columns at most
inline constexpr std::size_t kMaxGeometryLineBytes = 4096;

// Both throw InputError naming file:line (or the key) on bad input.
CdInput load_scene_input(const std::string& scene_path);
CdInput load_geometry_file(const std::string& path, const GeometryLimits& limits = {});
// The same from text in memory (`name` for messages), as the fuzz target reads it.
CdInput load_geometry_text(std::string_view text, const std::string& name);
// The text of a geometry file holding `in` (load_geometry_file reads it back exactly).
std::string geometry_file_text(const CdInput& in);

// Whether every edge of the mesh is shared by exactly two triangles (closed,
// so point-in-mesh by ray parity is meaningful).
bool is_closed(const PartMesh& m);

} // namespace rbcd::cpucd
