// rbcd-scene-bench [SCENE.toml] [--repeat N] [--images DIR]
// Renders a scene (the embedded default one without SCENE) through the
// rasterizer alone, no unit, and prints frames/s and stream totals. With
// --images, writes the frames' pictures (no hits: the unit is not run).
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/scene/scene_source.h"

int main(int argc, char** argv) {
    using namespace rbcd;
    std::string path, images;
    unsigned repeat = 1;
    for (int i = 1; i < argc; ++i) {
        if (!std::strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = unsigned(std::strtoul(argv[++i], nullptr, 10));
        else if (!std::strcmp(argv[i], "--images") && i + 1 < argc) images = argv[++i];
        else if (argv[i][0] == '-') {
            std::fprintf(stderr, "usage: %s [SCENE.toml] [--repeat N] [--images DIR]\n", argv[0]);
            return 2;
        } else path = argv[i];
    }
    if (repeat == 0) repeat = 1;
    try {
        scene::SceneLimits limits;
        std::uint64_t frames = 0, tiles = 0, frags = 0, culled = 0, other = 0;
        double seconds = 0.0;
        for (unsigned r = 0; r < repeat; ++r) {
            std::unique_ptr<scene::SceneSource> src =
                path.empty() ? scene::SceneSource::from_text(scene::default_scene_text(), "", "<default scene>", limits)
                             : std::make_unique<scene::SceneSource>(path, limits);
            const bool pictures = !images.empty() && r == 0;
            src->enable_images(pictures);
            Tile t;
            auto t0 = std::chrono::steady_clock::now();
            for (;;) {
                auto ev = src->next(t);
                if (ev == FragmentSource::Event::End) break;
                if (ev == FragmentSource::Event::Frame) {
                    ++frames;
                    if (pictures && t.frame > 0)
                        if (auto img = src->take_frame_image(t.frame - 1)) scene::write_frame_png(images, *img, {}, {}, limits.tile_w, limits.tile_h);
                    continue;
                }
                ++tiles;
                frags += t.frags.size();
                other += t.other;
                for (const auto& f : t.frags) culled += f.culled;
            }
            if (pictures)
                if (auto img = src->take_frame_image(src->frame_count() - 1)) scene::write_frame_png(images, *img, {}, {}, limits.tile_w, limits.tile_h);
            seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        }
        std::printf("frames %llu  tiles %llu  fragments %llu (culled-tagged %llu)  other %llu\n",
                    (unsigned long long)frames, (unsigned long long)tiles, (unsigned long long)frags,
                    (unsigned long long)culled, (unsigned long long)other);
        std::printf("%.3f s  %.1f frames/s  %.1f Mfragments/s\n", seconds, double(frames) / seconds,
                    double(frags + other) / seconds / 1e6);
    } catch (const InputError& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
