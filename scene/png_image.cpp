#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <png.h>

#include "rbcd/common/errors.h"
#include "rbcd/scene/scene_source.h"

namespace rbcd::scene {
namespace {

struct Rgb {
    double r, g, b;
};

Rgb hsv(double h, double s, double v) {
    h = h - std::floor(h);
    const double i = std::floor(h * 6.0), f = h * 6.0 - i;
    const double p = v * (1 - s), q = v * (1 - f * s), t = v * (1 - (1 - f) * s);
    switch (static_cast<int>(i) % 6) {
    case 0: return {v, t, p};
    case 1: return {q, v, p};
    case 2: return {p, v, t};
    case 3: return {p, q, v};
    case 4: return {t, p, v};
    default: return {v, p, q};
    }
}

// Golden-ratio hue steps keep neighbouring indices far apart on the colour wheel.
Rgb object_colour(const SceneSource::ObjectInfo& o, std::size_t index) {
    if (!o.collisionable) return {0.75, 0.75, 0.75};
    return hsv(0.08 + 0.6180339887 * double(index), 0.7, 1.0);
}

} // namespace

std::string write_frame_png(const std::string& dir, const SceneSource::FrameImage& image,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& hit_pixels,
                     const std::vector<std::pair<std::uint32_t, std::uint32_t>>& overflow_tiles, unsigned tile_w,
                     unsigned tile_h) {
    const unsigned w = image.width, h = image.height;
    std::vector<png_byte> rgb(std::size_t(w) * h * 3);

    // Depth range per object: shading each object over its own range shows its
    // shape (a sphere brighter in the middle) whatever its distance.
    std::vector<std::uint32_t> dmin(image.objects.size(), SceneSource::kNoDepth), dmax(image.objects.size(), 0);
    for (const auto& p : image.pixels) {
        if (p.depth == SceneSource::kNoDepth || p.object >= image.objects.size()) continue;
        dmin[p.object] = std::min(dmin[p.object], p.depth);
        dmax[p.object] = std::max(dmax[p.object], p.depth);
    }

    for (unsigned y = 0; y < h; ++y) {
        for (unsigned x = 0; x < w; ++x) {
            const auto& p = image.at(x, y);
            png_byte* out = &rgb[(std::size_t(y) * w + x) * 3];
            if (p.depth == SceneSource::kNoDepth || p.object >= image.objects.size()) {
                out[0] = 18;
                out[1] = 20;
                out[2] = 32;
                continue;
            }
            Rgb c = object_colour(image.objects[p.object], p.object);
            // Nearer is brighter; a back face in view means we look into an
            // object (cut by the near plane, or cull = none): darker.
            const double span = dmax[p.object] > dmin[p.object] ? double(dmax[p.object] - dmin[p.object]) : 1.0;
            double shade = 1.0 - 0.6 * (double(p.depth - dmin[p.object]) / span);
            if (p.facing == Facing::Back) shade *= 0.45;
            out[0] = png_byte(std::lround(255.0 * c.r * shade));
            out[1] = png_byte(std::lround(255.0 * c.g * shade));
            out[2] = png_byte(std::lround(255.0 * c.b * shade));
        }
    }

    auto put = [&](std::uint32_t x, std::uint32_t y, png_byte r, png_byte g, png_byte b) {
        if (x >= w || y >= h) return;
        png_byte* out = &rgb[(std::size_t(y) * w + x) * 3];
        out[0] = r;
        out[1] = g;
        out[2] = b;
    };
    if (tile_w > 0 && tile_h > 0) {
        for (const auto& [col, row] : overflow_tiles) {
            const std::uint64_t x0 = std::uint64_t(col) * tile_w, y0 = std::uint64_t(row) * tile_h;
            if (x0 >= w || y0 >= h) continue;
            const std::uint32_t x1 = std::uint32_t(std::min<std::uint64_t>(x0 + tile_w, w) - 1);
            const std::uint32_t y1 = std::uint32_t(std::min<std::uint64_t>(y0 + tile_h, h) - 1);
            for (std::uint32_t x = std::uint32_t(x0); x <= x1; ++x) {
                put(x, std::uint32_t(y0), 255, 230, 0);
                put(x, y1, 255, 230, 0);
            }
            for (std::uint32_t y = std::uint32_t(y0); y <= y1; ++y) {
                put(std::uint32_t(x0), y, 255, 230, 0);
                put(x1, y, 255, 230, 0);
            }
        }
    }
    for (const auto& [x, y] : hit_pixels) put(x, y, 255, 0, 255);

    char fname[32];
    std::snprintf(fname, sizeof fname, "frame_%05llu.png", static_cast<unsigned long long>(image.frame));
    const std::string path = (dir.empty() ? std::string(".") : dir) + "/" + fname;

    png_image img{};
    img.version = PNG_IMAGE_VERSION;
    img.width = w;
    img.height = h;
    img.format = PNG_FORMAT_RGB;
    if (!png_image_write_to_file(&img, path.c_str(), 0, rgb.data(), png_int_32(w * 3), nullptr)) {
        std::string msg = img.message;
        png_image_free(&img);
        throw InputError(path + ": cannot write image: " + msg);
    }
    return path;
}

} // namespace rbcd::scene
