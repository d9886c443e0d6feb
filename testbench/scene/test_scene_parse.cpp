// Scene files: keyframes, header, the embedded default scene, and bad scenes.
#include <cmath>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "rbcd/common/errors.h"
#include "rbcd/scene/scene_file.h"
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

const std::string kHdr = scene_header(64, 48, 40);

} // namespace

TEST_CASE("keyframes interpolate each component linearly and hold what they omit", "[scene][parse][keys]") {
    Obj o;
    o.id = 1;
    o.pos = {0, 0, -5};
    o.rot = {0, 0, 0};
    o.scale = {1, 1, 1};
    o.extra = "[[object.key]]\nframe = 10\nposition = [10.0, 0.0, -5.0]\n"
              "[[object.key]]\nframe = 20\nrotation = [0.0, 90.0, 0.0]\nscale = [2.0, 1.0, 1.0]\n"
              "[[object.key]]\nframe = 30\nposition = [0.0, 4.0, -5.0]\n";
    auto desc = rbcd::scene::parse_scene(kHdr + object_text(o), "t.toml", "", SceneLimits{});
    const auto& obj = desc.objects.at(0);
    REQUIRE(obj.keys.size() == 4);
    auto at = [&](std::uint64_t f) { return rbcd::scene::transform_at(obj, f); };
    CHECK(at(0).position.x() == 0.0);
    CHECK(at(5).position.x() == Approx(5.0));
    CHECK(at(10).position.x() == Approx(10.0));
    // Key 20 gives no position: it holds 10 from key 10, so 10..20 is constant.
    CHECK(at(15).position.x() == Approx(10.0));
    CHECK(at(15).rotation.y() == Approx(45.0));   // Euler angles interpolate too
    CHECK(at(15).scale.x() == Approx(1.5));
    CHECK(at(10).rotation.y() == Approx(0.0));
    CHECK(at(25).position.x() == Approx(5.0));
    CHECK(at(25).position.y() == Approx(2.0));
    CHECK(at(25).rotation.y() == Approx(90.0));   // held from key 20
    CHECK(at(25).scale.x() == Approx(2.0));
    CHECK(at(39).position.y() == Approx(4.0));    // the last key holds after its frame
    CHECK(at(39).position.x() == Approx(0.0));
}

TEST_CASE("a moving object's picture follows its keyframes", "[scene][parse][keys]") {
    // Camera at the origin looking down -z, fov 90, square screen: at distance
    // 10 the screen spans x in [-10, 10], so x maps to pixel 100 + 10 x.
    Cam cam;
    cam.fov_y = 90;
    Obj o;
    o.id = 1;
    o.pos = {-5, 0, -10};
    o.scale = {0.5, 0.5, 0.5};
    o.segments = 32;
    o.extra = "[[object.key]]\nframe = 4\nposition = [5.0, 0.0, -10.0]\n";
    Capture c = capture_text(scene_header(200, 200, 7, cam) + object_text(o));
    REQUIRE(c.frames.size() == 7);
    for (const auto& f : c.frames) {
        double sx = 0;
        std::size_t n = 0;
        for (const auto& t : f.tiles)
            for (const auto& fr : t.frags)
                if (fr.facing == Facing::Front) {
                    sx += fr.x + 0.5;
                    ++n;
                }
        REQUIRE(n > 50);
        const double x = f.frame >= 4 ? 5.0 : -5.0 + 2.5 * double(f.frame);
        INFO("frame " << f.frame);
        CHECK(sx / double(n) == Approx(100.0 + 10.0 * x).margin(0.6));
    }
}

TEST_CASE("the header carries the scene's screen, the limits' tile size and 24-bit depths", "[scene][parse]") {
    SceneLimits lim;
    lim.tile_w = 32;
    lim.tile_h = 8;
    Obj o;
    o.id = 1;
    auto s = SceneSource::from_text(scene_header(321, 123, 2) + object_text(o), "", "<t>", lim);
    CHECK(s->header().screen_w == 321u);
    CHECK(s->header().screen_h == 123u);
    CHECK(s->header().tile_w == 32u);
    CHECK(s->header().tile_h == 8u);
    CHECK(s->header().depth_bits == 24u);
    CHECK(s->name() == "<t>");
    CHECK(s->frame_count() == 2u);
    REQUIRE(s->objects().size() == 1);
    CHECK(s->objects()[0].id == 1u);
    CHECK(s->objects()[0].collisionable);
    // Screen size defaults to 800 x 480 without [screen].
    auto d = SceneSource::from_text("format = \"rbcd-scene 1\"\nframes = 1\n[camera]\neye = [0,0,0]\ntarget = [0,0,-1]\n"
                                    "fov_y = 60\nnear = 0.1\nfar = 10\n" + object_text(o), "", "<t>", SceneLimits{});
    CHECK(d->header().screen_w == 800u);
    CHECK(d->header().screen_h == 480u);
}

TEST_CASE("a scene file reads meshes relative to itself", "[scene][parse]") {
    auto dir = temp_dir("relative");
    std::filesystem::create_directories(dir / "meshes");
    {
        std::ofstream obj(dir / "meshes" / "tri.obj");
        obj << "v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n";
    }
    Obj o;
    o.mesh = "meshes/tri.obj";
    o.id = 4;
    o.cull = "none";
    {
        std::ofstream sc(dir / "scene.toml");
        sc << scene_header(64, 48, 1) << object_text(o);
    }
    SceneSource s((dir / "scene.toml").string(), SceneLimits{});
    Capture c = capture(s);
    CHECK(c.frames.at(0).fragments() > 100u);
    CHECK(s.objects().at(0).triangles == 1u);
    std::filesystem::remove_all(dir);
}

TEST_CASE("the embedded default scene parses and renders fragments in most frames", "[scene][default]") {
    auto s = SceneSource::from_text(rbcd::scene::default_scene_text(), "", "<default scene>", SceneLimits{});
    CHECK(s->header().screen_w == 800u);
    CHECK(s->header().screen_h == 480u);
    bool has_other_only = false;
    std::size_t collisionable = 0;
    for (const auto& o : s->objects()) collisionable += o.collisionable;
    CHECK(collisionable >= 6u);
    CHECK(collisionable < s->objects().size());   // a non-collisionable object too
    Capture c = capture(*s);
    REQUIRE(c.frames.size() >= 50u);
    REQUIRE(c.frames.size() <= 70u);
    std::size_t with_frags = 0;
    for (const auto& f : c.frames) {
        with_frags += f.fragments() > 1000;
        for (const auto& t : f.tiles) has_other_only |= t.frags.empty() && t.other > 0;
    }
    CHECK(with_frags >= c.frames.size() * 9 / 10);
    CHECK(has_other_only);
}

TEST_CASE("bad scenes give one-line input errors naming the file, line and key", "[scene][parse][errors]") {
    Obj o;
    o.id = 1;
    auto check = [](const std::string& msg, std::initializer_list<const char*> parts) {
        INFO(msg);
        CHECK(msg.rfind("bad.toml", 0) == 0);
        CHECK(msg.find('\n') == std::string::npos);
        for (const char* p : parts) CHECK(msg.find(p) != std::string::npos);
    };

    SECTION("unknown shape") {
        Obj b = o;
        b.mesh = "pyramid";
        check(error_of(kHdr + object_text(b)), {"bad.toml:", "object[0] (\"obj\").mesh", "unknown shape 'pyramid'"});
    }
    SECTION("missing mesh file") {
        Obj b = o;
        b.mesh = "no/such/mesh.obj";
        check(error_of(kHdr + object_text(b)), {"bad.toml:", ".mesh", "no/such/mesh.obj: cannot read mesh file: No such file or directory"});
    }
    SECTION("unreadable mesh file") {
        auto dir = temp_dir("garbage");
        {
            std::ofstream g(dir / "junk.stl");
            g << "this is not a mesh\n";
        }
        Obj b = o;
        b.mesh = "junk.stl";
        try {
            SceneSource::from_text(kHdr + object_text(b), dir.string(), "bad.toml", SceneLimits{});
            FAIL("no error");
        } catch (const InputError& e) {
            check(e.what(), {"bad.toml:", ".mesh", "cannot read mesh file", "junk.stl"});
        }
        std::filesystem::remove_all(dir);
    }
    SECTION("unknown key") {
        Obj b = o;
        b.extra = "colour = \"red\"\n";
        const std::string text = kHdr + object_text(b);
        // The line of the offending key.
        const auto line = 1 + std::count(text.begin(), text.begin() + long(text.find("colour")), '\n');
        check(error_of(text), {("bad.toml:" + std::to_string(line) + ":").c_str(), "unknown key", "colour"});
    }
    SECTION("unknown top-level key and unknown camera key") {
        check(error_of("frame = 3\n" + kHdr + object_text(o)), {"bad.toml:1:", "unknown key 'frame'"});
        std::string t = kHdr;
        t.replace(t.find("near"), 4, "nearr");
        check(error_of(t + object_text(o)), {"camera.nearr"});
    }
    SECTION("wrong type") {
        std::string t = kHdr;
        t.replace(t.find("fov_y = 60"), 10, "fov_y = \"wide\"");
        const auto line = 1 + std::count(t.begin(), t.begin() + long(t.find("fov_y")), '\n');
        check(error_of(t + object_text(o)), {("bad.toml:" + std::to_string(line) + ":").c_str(), "camera.fov_y", "expected a number"});
        Obj b = o;
        b.extra = "[[object.key]]\nframe = 2.5\n";
        check(error_of(kHdr + object_text(b)), {"object[0] (\"obj\").key[0].frame", "expected an integer"});
    }
    SECTION("out of range") {
        Obj b = o;
        b.segments = 2;
        check(error_of(kHdr + object_text(b)), {".segments", "out of range"});
        std::string t = kHdr;
        t.replace(t.find("fov_y = 60"), 10, "fov_y = 180");
        check(error_of(t + object_text(o)), {"camera.fov_y"});
        t = kHdr;
        t.replace(t.find("far = 100"), 9, "far = 0.05");
        check(error_of(t + object_text(o)), {"camera.far"});
        check(error_of(scene_header(0, 48, 1) + object_text(o)), {"screen.width", "out of range"});
        Obj c = o;
        c.cull = "sideways";
        check(error_of(kHdr + object_text(c)), {".cull", "sideways"});
    }
    SECTION("id that does not fit id_bits") {
        Obj b = o;
        b.id = 128;
        check(error_of(kHdr + object_text(b)), {".id", "128", "id_bits = 7"});
        SceneLimits wide;
        wide.id_bits = 8;
        CHECK(error_of(kHdr + object_text(b), wide).empty());
        b.id = -1;
        check(error_of(kHdr + object_text(b)), {".id"});
    }
    SECTION("keyframes out of order") {
        Obj b = o;
        b.extra = "[[object.key]]\nframe = 10\n[[object.key]]\nframe = 10\n";
        check(error_of(kHdr + object_text(b)), {"key[1].frame", "greater"});
    }
    SECTION("singular transform at frame 0") {
        Obj b = o;
        b.scale = {1, 0, 1};
        check(error_of(kHdr + object_text(b)), {".scale", "singular", "frame 0"});
    }
    SECTION("singular transform between keys") {
        Obj b = o;
        b.extra = "[[object.key]]\nframe = 10\nscale = [1.0, -1.0, 1.0]\n";
        const std::string text = kHdr + object_text(b);
        const auto line = 1 + std::count(text.begin(), text.begin() + long(text.rfind("scale")), '\n');
        check(error_of(text), {("bad.toml:" + std::to_string(line) + ":").c_str(), ".scale", "singular", "frame 5"});
    }
    SECTION("camera problems") {
        std::string t = kHdr;
        t.replace(t.find("target = [0, 0, -1]"), 19, "target = [0, 0, 0]");
        check(error_of(t + object_text(o)), {"camera.target"});
        Cam c;
        c.target = {0, -5, 0};   // looking straight down the default up vector
        check(error_of(scene_header(64, 48, 1, c) + object_text(o)), {"camera.up"});
    }
    SECTION("syntax, format and missing keys") {
        check(error_of(kHdr + "[[object]\n"), {"bad.toml:", "TOML syntax"});
        std::string t = kHdr;
        t.replace(t.find("rbcd-scene 1"), 12, "rbcd-scene 2");
        check(error_of(t), {"bad.toml:1:", "format"});
        check(error_of("format = \"rbcd-scene 1\"\n[camera]\n"), {"'frames'"});
        Obj b = o;
        b.mesh = "";
        std::string no_mesh = object_text(b);
        no_mesh.replace(no_mesh.find("mesh = \"\"\n"), 10, "");
        check(error_of(kHdr + no_mesh), {"object[0] (\"obj\").mesh"});
    }
    SECTION("nothing in view in any frame") {
        Obj b = o;
        b.pos = {0, 0, 5};   // behind the camera in every frame
        b.extra = "[[object.key]]\nframe = 20\nposition = [3.0, 0.0, 8.0]\n";
        const std::string msg = error_of(kHdr + object_text(b), SceneLimits{}, true);
        check(msg, {"nothing in view in any frame"});
        // A scene with no objects at all is the same error.
        check(error_of(kHdr, SceneLimits{}, true), {"nothing in view"});
    }
    SECTION("missing scene file") {
        try {
            SceneSource s("/nonexistent/dir/scene.toml", SceneLimits{});
            FAIL("no error");
        } catch (const InputError& e) {
            CHECK(std::string(e.what()).find("/nonexistent/dir/scene.toml") == 0);
        }
    }
}
