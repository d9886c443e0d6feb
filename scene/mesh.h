// Triangle meshes in object space: the built-in closed shapes and mesh files
// read through assimp. Internal to rbcd_scene.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rbcd::scene {

// Counter-clockwise seen from the outside. Vertices shared by index, so that
// adjacent triangles see bit-identical corners (the rasterizer's watertightness
// depends on it).
struct Mesh {
    std::vector<Eigen::Vector3d> verts;
    std::vector<std::array<std::uint32_t, 3>> tris;
    bool bad_index = false;   // load_mesh_file only: a face index past its mesh's vertices
};

// sphere (radius 1), box (edge 2), torus (major radius 1, minor 0.25, around Y),
// cylinder (radius 1, height 2, along Y); all closed and centred on the origin.
// `segments` is the number of divisions around the main circle; the secondary
// one (sphere stacks, torus tube) gets half as many (at least 2, resp. 3).
// The box ignores it. An unknown name is a logic error (the parser checked it).
Mesh builtin_mesh(const std::string& shape, unsigned segments);
// The number of triangles builtin_mesh(shape, segments) has, without building it.
std::uint64_t builtin_triangles(const std::string& shape, unsigned segments);

// Every mesh of the file with its node transforms applied, as one mesh.
// Returns false and sets `error` when assimp cannot read it or it holds no triangle.
// assimp runs in a child process: a crash or a run longer than timeout_s is
// an error too, never the end of the caller (docs/limits.md).
bool load_mesh_file(const std::string& path, Mesh& out, std::string& error, unsigned timeout_s = 60);
// The same in this process (what the fuzz target drives, for coverage).
bool load_mesh_file_in_process(const std::string& path, Mesh& out, std::string& error);
// Tests only: the next load_mesh_file's child process aborts before reading,
// as assimp does on some files, so that its containment stays tested whatever
// inputs the PLY check refuses before assimp.
void abort_next_mesh_reader_for_test();

} // namespace rbcd::scene
