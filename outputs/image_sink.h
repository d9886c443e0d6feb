// --images: one PNG per frame from the scene's nearest-surface buffer, with the
// pixels and tiles that the unit reported (read back from memory) marked.
#pragma once
#include <string>
#include <utility>
#include <vector>

#include "rbcd/hw/collision_sink.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd {

class ImageSink final : public CollisionSink {
public:
    ImageSink(scene::SceneSource& src, std::string dir, unsigned tile_w, unsigned tile_h)
        : src_(src), dir_(std::move(dir)), tile_w_(tile_w), tile_h_(tile_h) {}

    // A frame's image is complete once the scene moved past it, which it has
    // when the unit announces the next frame (or the run ended).
    void frame(std::uint64_t n) override {
        flush();
        current_ = n;
        open_ = true;
    }
    void hit(const HitRecord& h) override { hits_.emplace_back(h.x, h.y); }
    void overflow(const OverflowRecord& o) override { tiles_.emplace_back(o.col, o.row); }
    void finish() { flush(); }
    const std::vector<std::string>& written() const { return written_; }

private:
    void flush() {
        if (!open_) return;
        if (auto img = src_.take_frame_image(current_)) {
            written_.push_back(scene::write_frame_png(dir_, *img, hits_, tiles_, tile_w_, tile_h_));
        }
        hits_.clear();
        tiles_.clear();
        open_ = false;
    }

    scene::SceneSource& src_;
    std::string dir_;
    unsigned tile_w_, tile_h_;
    std::uint64_t current_ = 0;
    bool open_ = false;
    std::vector<std::pair<std::uint32_t, std::uint32_t>> hits_, tiles_;
    std::vector<std::string> written_;
};

} // namespace rbcd
