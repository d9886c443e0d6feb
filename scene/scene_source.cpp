#include "rbcd/scene/scene_source.h"

#include <sys/stat.h>

#include <stdexcept>

#include <algorithm>
#include <filesystem>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/scene/renderer.h"

namespace rbcd::scene {

namespace {

// A regular file of bounded size: the whole text is parsed at once.
std::string read_text_file(const std::string& path, const SceneLimits& limits) {
    return read_input_text(path, "scene file", limits.max_scene_bytes, "input.max_scene_bytes");
}

// Mesh paths in it are taken relative to its directory.
SceneDesc parse_scene_file(const std::string& path, const SceneLimits& limits) {
    return parse_scene(read_text_file(path, limits), path, std::filesystem::path(path).parent_path().string(), limits);
}

} // namespace

SceneSource::SceneSource(const std::string& path, const SceneLimits& limits)
    : SceneSource(std::make_unique<SceneRenderer>(parse_scene_file(path, limits), limits), path, limits) {}

SceneSource::SceneSource(std::unique_ptr<SceneRenderer> r, std::string name, const SceneLimits& limits)
    : r_(std::move(r)), name_(std::move(name)), max_tile_fragments_(limits.max_tile_fragments) {
    const SceneDesc& d = r_->desc();
    header_.screen_w = d.width;
    header_.screen_h = d.height;
    header_.tile_w = limits.tile_w;
    header_.tile_h = limits.tile_h;
    header_.depth_bits = kDepthBits;
    // Mesh files are counted once loaded (built-in shapes were counted when parsed).
    std::uint64_t triangles = 0;
    for (const auto& o : r_->objects()) triangles += o.triangles;
    if (triangles > limits.max_scene_triangles)
        throw InputError(name_ + ": the scene's objects add up to " + std::to_string(triangles) + " triangles, more than " +
                         std::to_string(limits.max_scene_triangles) +
                         " (the limit input.max_scene_triangles; docs/limits.md)");
}

std::unique_ptr<SceneSource> SceneSource::from_text(const std::string& toml_text, const std::string& base_dir,
                                                    const std::string& display_name, const SceneLimits& limits) {
    auto r = std::make_unique<SceneRenderer>(parse_scene(toml_text, display_name, base_dir, limits), limits);
    return std::unique_ptr<SceneSource>(new SceneSource(std::move(r), display_name, limits));
}

SceneSource::~SceneSource() = default;

const StreamHeader& SceneSource::header() const { return header_; }
std::string SceneSource::name() const { return name_; }
std::uint64_t SceneSource::frame_count() const { return r_->desc().frames; }
const std::vector<SceneSource::ObjectInfo>& SceneSource::objects() const { return r_->objects(); }

namespace {
// The mesh files a scene's objects name, each once, in their order.
std::vector<std::string> mesh_files_in(const SceneDesc& d) {
    std::vector<std::string> files;
    for (const ObjectDesc& o : d.objects)
        if (!o.builtin && std::find(files.begin(), files.end(), o.mesh) == files.end()) files.push_back(o.mesh);
    return files;
}
} // namespace

std::vector<std::string> SceneSource::mesh_files_of(const std::string& path, const SceneLimits& limits) {
    return mesh_files_in(parse_scene_file(path, limits));
}

std::vector<std::string> SceneSource::mesh_files_named(const std::string& path) {
    struct stat st {};
    if (path.empty() || ::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return {};
    const SceneLimits defaults{};
    try {
        return mesh_files_of(path, defaults);
    } catch (const std::exception&) {
    }
    try {
        return scene::mesh_files_named(read_text_file(path, defaults), std::filesystem::path(path).parent_path().string());
    } catch (const std::exception&) {
        return {};
    }
}

std::vector<std::string> SceneSource::mesh_files() const { return mesh_files_in(r_->desc()); }

void SceneSource::enable_images(bool on) { images_ = on; }

void SceneSource::start_at_frame(std::uint64_t frame, BeforeStart before) {
    if (state_ != State::BeforeFrame || frame_ != 0 || start_ != 0)
        throw std::logic_error("SceneSource::start_at_frame: already started");
    if (frame >= r_->desc().frames) throw std::logic_error("SceneSource::start_at_frame: past the scene's last frame");
    frame_ = start_ = frame;
    look_before_start_ = before == BeforeStart::LookIfEmpty;
}

void SceneSource::stop_after_frame(std::uint64_t last) { stop_after_ = last; }

bool SceneSource::any_fragment_before_start() {
    Tile tile;
    for (std::uint64_t f = 0; f < start_; ++f) {
        r_->begin_frame(f);
        if (r_->next_tile(tile, nullptr)) return true;   // a tile is returned only when it holds a fragment
    }
    return false;
}

std::optional<SceneSource::FrameImage> SceneSource::take_frame_image(std::uint64_t frame) {
    auto it = ready_images_.find(frame);
    if (it == ready_images_.end()) return std::nullopt;
    FrameImage img = std::move(it->second);
    ready_images_.erase(it);
    return img;
}

void SceneSource::finish_frame() {
    if (current_image_) {
        ready_images_.emplace(current_image_->frame, std::move(*current_image_));
        current_image_.reset();
    }
    ++frame_;
    state_ = State::BeforeFrame;
}

FragmentSource::Event SceneSource::next(Tile& tile) {
    for (;;) {
        switch (state_) {
        case State::Done:
            return Event::End;
        case State::BeforeFrame:
            if (frame_ >= r_->desc().frames) {
                state_ = State::Done;
                if (total_fragments_ == 0 && (start_ == 0 || (look_before_start_ && !any_fragment_before_start())))
                    throw InputError(name_ +
                                     ": nothing in view in any frame (no object's triangle covers a pixel; check "
                                     "camera.eye, camera.target, near/far and the objects' positions)");
                return Event::End;
            }
            if (frame_ > stop_after_) {
                // Not the scene's end: whether anything is in view is not said.
                state_ = State::Done;
                return Event::End;
            }
            r_->begin_frame(frame_);
            if (images_) {
                FrameImage img;
                img.frame = frame_;
                img.width = header_.screen_w;
                img.height = header_.screen_h;
                img.pixels.assign(std::size_t(img.width) * img.height, ImagePixel{});
                img.objects = r_->objects();
                current_image_ = std::move(img);
            }
            state_ = State::InFrame;
            tile.frame = frame_;
            return Event::Frame;
        case State::InFrame:
            if (r_->next_tile(tile, current_image_ ? &*current_image_ : nullptr)) {
                if (tile.frags.size() > max_tile_fragments_)
                    throw InputError(name_ + ": frame " + std::to_string(frame_) + ", tile " + std::to_string(tile.col) +
                                     " " + std::to_string(tile.row) + ": more than " +
                                     std::to_string(max_tile_fragments_) +
                                     " fragments (the limit input.max_tile_fragments; docs/limits.md)");
                total_fragments_ += tile.frags.size() + tile.other;
                return Event::Tile;
            }
            finish_frame();
            break;
        }
    }
}

} // namespace rbcd::scene
