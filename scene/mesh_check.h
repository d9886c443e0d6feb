// Checks a loaded mesh file for the defects that make collision results wrong
// (docs/scene.md, "Mesh checks"): holes (a back face with no front face before
// it), inside-out winding (back faces seen first) and self-intersection (pairs
// reported where the solids do not meet). Internal to rbcd_scene.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "rbcd/scene/mesh.h"
#include "rbcd/scene/scene_file.h"

namespace rbcd::scene {

struct MeshCheck {
    // Vertices are compared by position (bit-exact), not by index: file
    // formats split vertices at normal or texture seams.
    std::size_t boundary_edges = 0;      // edges of one triangle only: the mesh is open
    std::size_t nonmanifold_edges = 0;   // edges of three or more triangles
    std::size_t misoriented_edges = 0;   // edges two triangles run the same way: winding flips there
    bool closed = false;                 // no boundary edge (and at least one triangle)
    double signed_volume = 0.0;          // of the triangles, outward counter-clockwise positive
    bool inside_out = false;             // closed with a negative signed volume
    bool self_intersecting = false;      // two triangles cross (touching does not count)
    std::uint32_t tri_a = 0, tri_b = 0;  // the first crossing pair found
    bool intersection_checked = true;    // false: the work limit stopped the search first

    // What is wrong, e.g. "open (4 boundary edges), self-intersecting (triangles
    // 3 and 17 cross)"; empty when nothing is.
    std::string problems() const;
};

// The self-intersection search visits candidate pairs from a uniform grid
// (about 30 per triangle on a tessellated sphere); it stops after this many,
// leaving larger or pathological meshes unchecked for it. A 10^6-triangle
// sphere needs 3.8 x 10^7 and takes about 5 s in all on a loaded machine.
constexpr std::size_t kMeshCheckMaxPairs = 50000000;

MeshCheck check_mesh(const Mesh& m, std::size_t max_pairs = kMeshCheckMaxPairs);

// Checks the mesh file object `od` loaded and, when something is wrong, writes
// one line to stderr: "SCENE:LINE: warning: KEY.mesh: mesh file 'PATH' is
// PROBLEMS; ... (KEY.check_mesh = false silences this)". Returns that line.
std::string warn_mesh_problems(const std::string& scene_name, const ObjectDesc& od, const Mesh& m);

} // namespace rbcd::scene
