// The scene front end: reads a scene (docs/scene.md, docs/formats.md)
// and renders it frame by frame through a tile-based rasterizer into the
// Frame/Tile stream the unit consumes, exactly what a trace file would carry.
#pragma once
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rbcd/common/fragment.h"

namespace rbcd::scene {

// What the unit accepts; the scene is checked against it when it is read.
struct SceneLimits {
    unsigned tile_w = 16, tile_h = 16;
    unsigned id_bits = 7;   // object ids must fit: an error naming the key otherwise
    // Resource bounds (docs/limits.md); the messages name the key that raises them.
    std::uint64_t max_scene_bytes = std::uint64_t(64) << 20;        // input.max_scene_bytes
    std::uint64_t max_scene_triangles = std::uint64_t(1) << 22;     // input.max_scene_triangles
    std::uint64_t max_tile_fragments = std::uint64_t(1) << 24;      // input.max_tile_fragments
};

class SceneRenderer;   // scene/renderer.h; internal

class SceneSource final : public FragmentSource {
public:
    // Reads and checks the scene file and every mesh it names; throws InputError
    // ("file:line: ...") on a bad scene, a missing or unreadable mesh, an id that
    // does not fit, or a transform that is singular at any frame.
    SceneSource(const std::string& path, const SceneLimits& limits);
    // The same from text: relative mesh paths are taken relative to base_dir
    // ("" = the working directory), messages name display_name.
    static std::unique_ptr<SceneSource> from_text(const std::string& toml_text, const std::string& base_dir,
                                                  const std::string& display_name, const SceneLimits& limits);
    ~SceneSource() override;
    SceneSource(const SceneSource&) = delete;
    SceneSource& operator=(const SceneSource&) = delete;

    // screen from the scene, tile size from the limits, depth_bits 24.
    const StreamHeader& header() const override;
    // Frame N, then the tiles of frame N that hold at least one fragment
    // (collisionable or counted in `other`) in row-major order, ..., End.
    // Each frame is rendered when its Frame event is produced; only one frame's
    // geometry is held. After the last frame, a scene that produced no fragment
    // at all throws InputError "NAME: nothing in view in any frame (...)".
    Event next(Tile& tile) override;
    std::string name() const override;

    std::uint64_t frame_count() const;

    // rbcd-sim --frames A:B, and a --jobs worker: frames before `frame` (one
    // of the scene's) are not rendered, since a frame is a function of its
    // number alone and nothing the run computes depends on them. "Nothing in
    // view in any frame" needs every frame: with BeforeStart::LookIfEmpty
    // (one process) a run that reaches the scene's end without a fragment
    // renders the skipped frames, until one holds a fragment, to decide it as
    // a whole run would (and, as a whole run would, stops at a transform that
    // goes out of range in one of them); with OthersSay (a worker) it is the
    // parent's to say, which runs the scene again as one process. Call before
    // next().
    enum class BeforeStart { OthersSay, LookIfEmpty };
    void start_at_frame(std::uint64_t frame, BeforeStart before = BeforeStart::OthersSay);
    // Ends the stream after frame `last`: frame last + 1 is not set up (its
    // geometry, its binning, its checks). Call before next().
    void stop_after_frame(std::uint64_t last);

    // Per-object information, in submission order (the order of [[object]]).
    struct ObjectInfo {
        std::string name;
        bool collisionable = false;
        std::uint32_t id = 0;          // valid when collisionable
        std::size_t triangles = 0;     // of the tessellated / loaded mesh
    };
    const std::vector<ObjectInfo>& objects() const;
    // The mesh files the scene loads, each once, in the order objects name them
    // (for provenance: their sizes and hashes go into stats.json).
    std::vector<std::string> mesh_files() const;
    // The same from the scene file alone, read and parsed but no mesh loaded:
    // what no output may overwrite, known before the outputs are opened.
    static std::vector<std::string> mesh_files_of(const std::string& path, const SceneLimits& limits);
    // Every mesh file the scene file's objects name, read leniently and never
    // failing: a scene that does not pass its checks (or not under the
    // default limits) still names its meshes as long as its TOML parses.
    // Nothing unless `path` is a regular file (a FIFO would block). What a
    // failed run must not remove as an older output.
    static std::vector<std::string> mesh_files_named(const std::string& path);

    // ---- Pictures (--images) ----
    static constexpr std::uint32_t kNoDepth = 0xFFFFFFFFu;
    static constexpr std::uint16_t kNoObject = 0xFFFFu;
    // The nearest surface the GPU would display at one pixel: culled faces
    // (the `c` fragments and the dropped faces of non-collisionable objects)
    // are not displayed.
    struct ImagePixel {
        std::uint32_t depth = kNoDepth;          // depth_bits wide; kNoDepth: background
        std::uint16_t object = kNoObject;        // index into FrameImage::objects
        Facing facing = Facing::Front;
    };
    struct FrameImage {
        std::uint64_t frame = 0;
        unsigned width = 0, height = 0;
        std::vector<ImagePixel> pixels;          // row-major, width * height
        std::vector<ObjectInfo> objects;         // what ImagePixel::object indexes
        const ImagePixel& at(unsigned x, unsigned y) const { return pixels[std::size_t(y) * width + x]; }
    };
    // Off by default: it costs a depth test per fragment and a buffer per frame.
    // Call before the first next().
    void enable_images(bool on);
    // A frame's image becomes available once next() has moved past that frame
    // (returned the following Frame or End). Each image can be taken once;
    // images not taken stay in memory, so the caller takes every frame.
    std::optional<FrameImage> take_frame_image(std::uint64_t frame);

private:
    SceneSource(std::unique_ptr<SceneRenderer> r, std::string name, const SceneLimits& limits);
    void finish_frame();

    std::unique_ptr<SceneRenderer> r_;
    std::string name_;
    StreamHeader header_;
    enum class State { BeforeFrame, InFrame, Done } state_ = State::BeforeFrame;
    std::uint64_t frame_ = 0;             // the frame being produced (InFrame) or the next one
    std::uint64_t total_fragments_ = 0;   // collisionable and other, over all frames so far
    std::uint64_t start_ = 0;             // the first frame rendered (start_at_frame)
    bool look_before_start_ = false;      // BeforeStart::LookIfEmpty
    std::uint64_t stop_after_ = UINT64_MAX;   // the last frame produced (stop_after_frame)
    bool any_fragment_before_start();
    std::uint64_t max_tile_fragments_;
    bool images_ = false;
    std::optional<FrameImage> current_image_;
    std::map<std::uint64_t, FrameImage> ready_images_;
};

// The embedded default scene (scene/default_scene.toml): animated built-in
// objects that collide, pass close without touching, and a rod through a torus.
const char* default_scene_text();

// Writes DIR/frame_NNNNN.png (frame number zero-padded to 5 digits): each
// collisionable object in its own colour, non-collisionable ones in grey, all
// shaded by depth (back faces seen from inside darker); pixels in hit_pixels
// (x, y) in magenta; tiles in overflow_tiles (col, row) outlined in yellow.
// Throws InputError when the file cannot be written.
// Returns the path written.
std::string write_frame_png(const std::string& dir, const SceneSource::FrameImage& image,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& hit_pixels,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& overflow_tiles,
                     unsigned tile_w, unsigned tile_h);

} // namespace rbcd::scene
