// The scene reader and renderer: the input is a scene file; up to three frames
// are rendered. Limits are small so that the fuzzer explores, not allocates.
#include <string>

#include "rbcd/common/errors.h"
#include "rbcd/fuzz/fuzz_util.h"
#include "rbcd/scene/scene_source.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    rbcd::scene::SceneLimits lim;
    lim.max_scene_triangles = 20000;
    lim.max_tile_fragments = 1u << 16;
    try {
        // No base directory: mesh paths resolve from the working directory,
        // which scripts/fuzz.sh makes an empty one.
        auto s = rbcd::scene::SceneSource::from_text(text, "", "fuzz.toml", lim);
        if (s->header().screen_w > 2048 || s->header().screen_h > 2048) return 0;   // speed, not safety
        rbcd::Tile t;
        int frames = 0;
        for (;;) {
            const auto ev = s->next(t);
            if (ev == rbcd::FragmentSource::Event::End) break;
            if (ev == rbcd::FragmentSource::Event::Frame && ++frames > 3) break;
            if (ev == rbcd::FragmentSource::Event::Tile)
                for (const auto& f : t.frags)
                    if (f.x >= s->header().screen_w || f.y >= s->header().screen_h || f.depth >= (1u << 24))
                        rbcd::fuzz::finding("fragment out of range");
        }
    } catch (const rbcd::InputError& e) {
        const std::string m = e.what();
        (void)m;
    }
    return 0;
}
