// Mesh files through assimp, and the per-frame pictures.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <png.h>
#include <unistd.h>

#include "rbcd/common/errors.h"
#include "scene_test_util.h"

using namespace scene_test;
using rbcd::InputError;
using rbcd::scene::SceneLimits;
using rbcd::scene::SceneSource;

namespace {

std::filesystem::path temp_dir(const std::string& name) {
    auto d = std::filesystem::temp_directory_path() / ("rbcd_scene_test_" + name + "_" + std::to_string(::getpid()));
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

// (x, y, facing) -> depths, to compare two renderings pixel by pixel.
using PixelMap = std::map<std::tuple<std::uint32_t, std::uint32_t, int>, std::vector<std::uint32_t>>;
PixelMap pixel_map(const Capture& c) {
    PixelMap m;
    for (const auto& t : c.frames.at(0).tiles)
        for (const auto& f : t.frags) m[{f.x, f.y, int(f.facing)}].push_back(f.depth);
    return m;
}

// Same pixels, facings and counts; depths equal within a few units (snapping moves the
// corners off the plane, and the face diagonals may differ).
void check_same_picture(const Capture& a, const Capture& b) {
    PixelMap ma = pixel_map(a), mb = pixel_map(b);
    REQUIRE(ma.size() > 500);
    REQUIRE(ma.size() == mb.size());
    std::size_t differ = 0;
    for (const auto& [k, va] : ma) {
        auto it = mb.find(k);
        if (it == mb.end() || it->second.size() != va.size()) {
            if (differ < 10) UNSCOPED_INFO("pixel " << std::get<0>(k) << "," << std::get<1>(k) << " facing " << std::get<2>(k) << " counts " << va.size() << " vs " << (it == mb.end() ? 0 : it->second.size()));
            ++differ;
            continue;
        }
        auto vb = it->second;
        auto sa = va;
        std::sort(sa.begin(), sa.end());
        std::sort(vb.begin(), vb.end());
        for (std::size_t i = 0; i < sa.size(); ++i) {
            if (std::abs(double(sa[i]) - double(vb[i])) > 8.0 && differ < 10)
                UNSCOPED_INFO("pixel " << std::get<0>(k) << "," << std::get<1>(k) << " depth " << sa[i] << " vs " << vb[i]);
            differ += std::abs(double(sa[i]) - double(vb[i])) > 8.0;
        }
    }
    CHECK(differ == 0u);
}

std::string base64(const std::vector<unsigned char>& in) {
    static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (std::size_t i = 0; i < in.size(); i += 3) {
        unsigned v = unsigned(in[i]) << 16;
        if (i + 1 < in.size()) v |= unsigned(in[i + 1]) << 8;
        if (i + 2 < in.size()) v |= in[i + 2];
        out += t[(v >> 18) & 63];
        out += t[(v >> 12) & 63];
        out += i + 1 < in.size() ? t[(v >> 6) & 63] : '=';
        out += i + 2 < in.size() ? t[v & 63] : '=';
    }
    return out;
}

// Cube of edge 2, outward counter-clockwise (0-based corner i: x = bit 0, ...).
const float kCorners[8][3] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                              {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
const std::uint16_t kCubeTris[36] = {0, 3, 2, 0, 2, 1, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                     3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};

void write_gltf_cube(const std::filesystem::path& path, const std::string& node_transform) {
    std::vector<unsigned char> buf(sizeof kCorners + sizeof kCubeTris);
    std::memcpy(buf.data(), kCorners, sizeof kCorners);
    std::memcpy(buf.data() + sizeof kCorners, kCubeTris, sizeof kCubeTris);
    std::ofstream g(path);
    g << R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],)"
      << R"("nodes":[{"children":[1]},{"mesh":0,)" << node_transform << "}],"
      << R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":4}]}],)"
      << R"("buffers":[{"byteLength":)" << buf.size() << R"(,"uri":"data:application/octet-stream;base64,)"
      << base64(buf) << R"("}],)"
      << R"("bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":96,"target":34962},)"
      << R"({"buffer":0,"byteOffset":96,"byteLength":72,"target":34963}],)"
      << R"("accessors":[{"bufferView":0,"componentType":5126,"count":8,"type":"VEC3","min":[-1,-1,-1],"max":[1,1,1]},)"
      << R"({"bufferView":1,"componentType":5123,"count":36,"type":"SCALAR"}]})";
}

} // namespace

TEST_CASE("an OBJ cube read through assimp renders like the built-in box", "[scene][mesh]") {
    auto dir = temp_dir("obj");
    {
        // Quads, so that assimp triangulates them (its diagonals need not be ours).
        std::ofstream obj(dir / "cube.obj");
        obj << "# cube of edge 2\n";
        for (const auto& c : kCorners) obj << "v " << c[0] << " " << c[1] << " " << c[2] << "\n";
        obj << "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\nf 2 3 7 6\n";
    }
    Obj o;
    o.id = 2;
    o.pos = {0.3, -0.2, -6};
    o.rot = {25, 40, 10};
    o.scale = {1.2, 0.7, 1.0};
    const std::string hdr = scene_header(160, 120, 1);
    o.mesh = "box";
    Capture builtin = capture_text(hdr + object_text(o));
    o.mesh = "cube.obj";
    auto src = SceneSource::from_text(hdr + object_text(o), dir.string(), "<obj>", SceneLimits{});
    CHECK(src->objects().at(0).triangles == 12u);
    Capture file = capture(*src);
    check_same_picture(builtin, file);
    std::filesystem::remove_all(dir);
}

TEST_CASE("a glTF mesh gets its node transforms, mirroring ones included", "[scene][mesh]") {
    auto dir = temp_dir("gltf");
    write_gltf_cube(dir / "cube.gltf", R"("translation":[1.5,0,0],"scale":[0.5,0.5,0.5])");
    write_gltf_cube(dir / "mirrored.gltf", R"("translation":[1.5,0,0],"scale":[-0.5,0.5,0.5])");
    const std::string hdr = scene_header(160, 120, 1);
    Obj o;
    o.id = 2;
    o.pos = {-1.0, 0.2, -5};
    o.rot = {30, 30, 0};
    // The node transform applies before the object's: at rotation (30, 30, 0)
    // the node's +1.5 x offset lands at R * (1.5, 0, 0).
    Obj ref = o;
    ref.mesh = "box";
    ref.rot = o.rot;
    ref.scale = {0.5, 0.5, 0.5};
    const double c30 = std::cos(30 * 3.14159265358979323846 / 180), s30 = std::sin(30 * 3.14159265358979323846 / 180);
    // R = Rz(0) Ry(30) Rx(30) applied to (1.5, 0, 0): Rx leaves it, Ry turns it to (1.5 c, 0, -1.5 s).
    ref.pos = {o.pos.x + 1.5 * c30, o.pos.y, o.pos.z - 1.5 * s30};
    Capture builtin = capture_text(hdr + object_text(ref));
    for (const char* file : {"cube.gltf", "mirrored.gltf"}) {
        INFO(file);
        o.mesh = file;
        auto src = SceneSource::from_text(hdr + object_text(o), dir.string(), "<gltf>", SceneLimits{});
        Capture c = capture(*src);
        check_same_picture(builtin, c);
    }
    std::filesystem::remove_all(dir);
}

TEST_CASE("frame images hold the nearest displayed surface and are taken once", "[scene][image]") {
    Obj wall;
    wall.name = "wall";
    wall.mesh = "box";
    wall.pos = {0, 0, -9};
    wall.scale = {8, 8, 0.1};
    Obj ball;
    ball.name = "ball";
    ball.id = 1;
    ball.pos = {0, 0, -6};
    ball.extra = "[[object.key]]\nframe = 2\nposition = [1.0, 0.0, -6.0]\n";
    auto src = SceneSource::from_text(scene_header(96, 64, 3) + object_text(wall) + object_text(ball), "", "<img>", SceneLimits{});
    src->enable_images(true);
    Tile t;
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> nearest_ball_front;   // frame 0
    REQUIRE(src->next(t) == FragmentSource::Event::Frame);
    CHECK_FALSE(src->take_frame_image(0).has_value());   // not finished yet
    for (;;) {
        auto ev = src->next(t);
        if (ev != FragmentSource::Event::Tile) break;
        for (const auto& f : t.frags)
            if (!f.culled) nearest_ball_front[{f.x, f.y}] = f.depth;
    }
    auto img = src->take_frame_image(0);
    REQUIRE(img.has_value());
    CHECK_FALSE(src->take_frame_image(0).has_value());   // taken once
    CHECK(img->frame == 0u);
    CHECK(img->width == 96u);
    CHECK(img->height == 64u);
    REQUIRE(img->objects.size() == 2);
    CHECK(img->objects[0].name == "wall");
    CHECK_FALSE(img->objects[0].collisionable);
    CHECK(img->objects[1].collisionable);
    const auto& centre = img->at(48, 32);
    CHECK(centre.object == 1);
    CHECK(centre.facing == Facing::Front);
    CHECK(centre.depth == nearest_ball_front.at({48, 32}));
    CHECK(img->at(2, 2).object == 0);   // the wall behind, around the ball
    std::size_t ball_px = 0;
    for (const auto& p : img->pixels) ball_px += p.object == 1;
    CHECK(ball_px == nearest_ball_front.size());

    while (src->next(t) != FragmentSource::Event::End) {}
    CHECK(src->take_frame_image(2).has_value());
    CHECK(src->take_frame_image(1).has_value());
    CHECK_FALSE(src->take_frame_image(3).has_value());

    // Off by default.
    auto quiet = SceneSource::from_text(scene_header(96, 64, 1) + object_text(ball), "", "<img>", SceneLimits{});
    capture(*quiet);
    CHECK_FALSE(quiet->take_frame_image(0).has_value());
}

TEST_CASE("frame PNGs show objects, hits and overflowed tiles", "[scene][image]") {
    Obj wall;
    wall.name = "wall";
    wall.mesh = "box";
    wall.pos = {0, 0, -9};
    wall.scale = {8, 8, 0.1};
    Obj ball;
    ball.name = "ball";
    ball.id = 1;
    ball.pos = {0, 0, -6};
    auto src = SceneSource::from_text(scene_header(96, 64, 1) + object_text(wall) + object_text(ball), "", "<img>", SceneLimits{});
    src->enable_images(true);
    capture(*src);
    auto img = src->take_frame_image(0);
    REQUIRE(img.has_value());
    img->frame = 12;
    auto dir = temp_dir("png");
    rbcd::scene::write_frame_png(dir.string(), *img, {{48, 30}}, {{1, 1}}, 16, 16);
    const auto file = dir / "frame_00012.png";
    REQUIRE(std::filesystem::exists(file));

    png_image pi{};
    pi.version = PNG_IMAGE_VERSION;
    REQUIRE(png_image_begin_read_from_file(&pi, file.c_str()));
    pi.format = PNG_FORMAT_RGB;
    std::vector<png_byte> px(PNG_IMAGE_SIZE(pi));
    REQUIRE(png_image_finish_read(&pi, nullptr, px.data(), 0, nullptr));
    REQUIRE(pi.width == 96u);
    REQUIRE(pi.height == 64u);
    auto rgb = [&](unsigned x, unsigned y) {
        const png_byte* p = &px[(std::size_t(y) * 96 + x) * 3];
        return std::tuple<int, int, int>(p[0], p[1], p[2]);
    };
    CHECK(rgb(48, 30) == std::tuple<int, int, int>(255, 0, 255));   // hit
    CHECK(rgb(16, 16) == std::tuple<int, int, int>(255, 230, 0));   // overflow outline, tile (1, 1)
    CHECK(rgb(31, 20) == std::tuple<int, int, int>(255, 230, 0));
    auto [wr, wg, wb] = rgb(4, 40);                                  // the grey wall
    CHECK(wr == wg);
    CHECK(wg == wb);
    CHECK(wr > 50);
    auto [br, bg, bb] = rgb(50, 34);                                 // the coloured ball
    CHECK((br != bg || bg != bb));

    CHECK_THROWS_AS(rbcd::scene::write_frame_png((dir / "no" / "such" / "dir").string(), *img, {}, {}, 16, 16), InputError);
    std::filesystem::remove_all(dir);
}
