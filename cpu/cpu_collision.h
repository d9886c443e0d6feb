// The CPU collision detection the paper compares RBCD with (docs/cpucd.md):
//   (a) broad phase: Bullet's btDbvtBroadphase over the parts' AABBs, margins
//       zeroed, its pairs filtered by exact AABB overlap;
//   (b) (a) plus a GJK narrow phase (btGjkPairDetector) on the parts' convex
//       hulls (btConvexHullShape);
//   (c) ground truth: FCL mesh-mesh collision (BVHModel<OBBRSS>), plus a
//       containment test (a vertex of either mesh inside the other, by ray
//       parity), since FCL reports only intersecting surfaces;
//   (d) Bullet's collision world (btCollisionWorld, default configuration and
//       dispatcher) stepped to its overlapping pairs: a game's broad phase;
//   (e) the same world's performDiscreteCollisionDetection: broad phase,
//       dispatcher, narrow phase into contact manifolds, on the shapes a game
//       gives its objects (the hull of a convex mesh, GImpact for a concave one).
// (a), (b), (d), (e) are measured per frame (timed, or counted in executed
// instructions); building hulls, BVHs and worlds is loading, unmeasured.
#pragma once
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "rbcd/cpu/cd_input.h"

namespace rbcd::cpucd {

// One pair of objects (ids, a < b) that some method reports or the ground truth holds.
struct PairResult {
    std::uint32_t a = 0, b = 0;
    bool aabb = false;        // (a)
    bool gjk = false;         // (b): hulls intersect (or GJK gave no answer: counted, conservative)
    bool exact = false;       // (c): surfaces intersect or one contains the other
    bool contained = false;   // (c) by containment only
    bool on_screen = false;   // some contact point (or, contained, a vertex of the inner mesh) lies in the view volume
    unsigned contacts = 0;    // FCL contact points found (capped)
    bool open = false;        // a part of a or b is not a closed mesh (RBCD assumes closed surfaces)
    bool world_aabb = false;  // (d)
    bool world = false;       // (e): a contact point at distance <= 0 in the pair's manifolds
};

struct FrameTimes {
    double broad_us = 0;   // (a): median over repeats
    double gjk_us = 0;     // (b) = (a) + narrow phase: median over repeats
    double exact_us = 0;   // (c), once, for information
    double world_broad_us = 0;   // (d): median over repeats
    double world_us = 0;         // (e): median over repeats
    unsigned gjk_no_result = 0;
};

// The measured parts of a frame's detection.
enum class Section { broad, gjk, world_broad, world, count };

// Counts what a section executes (rbcd-cpucd --count-instructions: callgrind).
class SectionCounter {
public:
    virtual ~SectionCounter() = default;
    virtual void start() = 0;
    // The count since start().
    virtual std::uint64_t stop(Section s) = 0;
};

struct DetectorOptions {
    bool exact = true;   // run (c) (and build its BVHs); a counted run leaves it out
    // Each measured section starts from an empty broad phase and world
    // instead of the previous frame's state: a frame of a format-2 file,
    // whose objects are its own (docs/cpucd.md).
    bool fresh = false;
};

struct FrameResult {
    std::uint64_t frame = 0;
    std::vector<PairResult> pairs;   // sorted by (a, b)
    FrameTimes t;
    std::uint64_t instr[std::size_t(Section::count)] = {};   // with a counter: per Section
};

class CpuDetector {
public:
    explicit CpuDetector(const CdInput& in, DetectorOptions opt = {});
    ~CpuDetector();
    CpuDetector(const CpuDetector&) = delete;
    CpuDetector& operator=(const CpuDetector&) = delete;

    // repeats >= 1 timed runs of (a), (b), (d), (e), each from the state of
    // frame f-1; with a counter, the first repeat's sections are also counted.
    FrameResult run_frame(std::uint64_t f, unsigned repeats, SectionCounter* counter = nullptr);

    // Parts given a concave shape (GImpact) in (e): not convex (is_convex).
    std::size_t concave_parts() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

// The pairs (i < j) of parts of distinct objects whose world AABBs overlap
// at frame f, by sort and sweep along the axis on which the boxes' centres
// spread most: n log n plus the candidate pairs (boxes overlapping along that
// axis). `over_limit` when there are more than `limit` candidates (the pairs
// are then incomplete): rbcd-cpucd refuses such a frame (--max-pairs) before
// Bullet or FCL sees it, since co-located parts make the pairs, and the work,
// grow with the square of the parts whatever the broad phase.
struct AabbPairs {
    std::vector<std::pair<std::size_t, std::size_t>> pairs;   // sorted
    bool over_limit = false;
};
AabbPairs overlapping_aabb_pairs(const CdInput& in, std::uint64_t f, std::uint64_t limit);

// Whether no vertex of the mesh lies in front of any triangle's plane (beyond
// a tolerance relative to the mesh's size): a game would give it a convex
// hull; otherwise a concave shape.
bool is_convex(const PartMesh& m);

// Point inside a closed mesh (object space) by the parity of a ray's crossings.
bool point_in_mesh(const PartMesh& m, const Eigen::Vector3d& p);
// Inside OpenGL's clip volume after view_proj.
bool in_view(const Eigen::Matrix4d& view_proj, const Eigen::Vector3d& p);

} // namespace rbcd::cpucd
