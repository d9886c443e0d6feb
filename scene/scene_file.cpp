#include "rbcd/scene/scene_file.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <initializer_list>
#include <sstream>

#include <unistd.h>

#include <Eigen/Geometry>
#include <toml++/toml.h>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/scene/mesh.h"

namespace rbcd::scene {
namespace {

constexpr const char* kFormat = "rbcd-scene 1";
constexpr double kMaxCoordinate = 1e9;
// A scale component this close to zero makes the transform singular.
constexpr double kSingular = 1e-9;
const char* const kBuiltins[] = {"sphere", "box", "torus", "cylinder"};

struct Reader {
    std::string file;

    [[noreturn]] void fail(unsigned long line, const std::string& what) const {
        if (line == 0) throw InputError(file + ": " + what);
        throw input_error_at(file, line, what);
    }
    [[noreturn]] void fail(const toml::node& n, const std::string& what) const {
        fail(static_cast<unsigned long>(n.source().begin.line), what);
    }

    static std::string type_name(const toml::node& n) {
        switch (n.type()) {
        case toml::node_type::table: return "a table";
        case toml::node_type::array: return "an array";
        case toml::node_type::string: return "a string";
        case toml::node_type::integer: return "an integer";
        case toml::node_type::floating_point: return "a float";
        case toml::node_type::boolean: return "a boolean";
        default: return "a date/time";
        }
    }

    // Every key of `t` must be one of `allowed`: a misspelt key would otherwise
    // silently fall back to a default.
    void only_keys(const toml::table& t, const std::string& path, std::initializer_list<const char*> allowed) const {
        for (auto&& kv : t) {
            // Named, not a structured binding: clang 14 cannot capture those in a lambda.
            const toml::key& k = kv.first;
            const toml::node& v = kv.second;
            bool ok = std::any_of(allowed.begin(), allowed.end(), [&](const char* a) { return k.str() == a; });
            if (!ok) {
                std::string list;
                for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
                unsigned long line = k.source().begin.line ? k.source().begin.line : v.source().begin.line;
                fail(line, "unknown key '" + join(path, std::string(k.str())) + "' (known: " + list + ")");
            }
        }
    }

    static std::string join(const std::string& path, const std::string& key) {
        return path.empty() ? key : path + "." + key;
    }

    double number(const toml::node& n, const std::string& key) const {
        double v;
        if (auto i = n.as_integer()) v = static_cast<double>(i->get());
        else if (auto f = n.as_floating_point()) v = f->get();
        else fail(n, key + ": expected a number, got " + type_name(n));
        if (!std::isfinite(v)) fail(n, key + ": must be a finite number");
        return v;
    }

    std::int64_t integer(const toml::node& n, const std::string& key) const {
        auto i = n.as_integer();
        if (!i) fail(n, key + ": expected an integer, got " + type_name(n));
        return i->get();
    }

    std::int64_t integer_in(const toml::node& n, const std::string& key, std::int64_t lo, std::int64_t hi) const {
        std::int64_t v = integer(n, key);
        if (v < lo || v > hi)
            fail(n, key + ": " + std::to_string(v) + " is out of range " + std::to_string(lo) + ".." + std::to_string(hi));
        return v;
    }

    std::string string(const toml::node& n, const std::string& key) const {
        auto s = n.as_string();
        if (!s) fail(n, key + ": expected a string, got " + type_name(n));
        return s->get();
    }

    Eigen::Vector3d vec3(const toml::node& n, const std::string& key) const {
        auto a = n.as_array();
        if (!a || a->size() != 3) fail(n, key + ": expected an array of 3 numbers");
        Eigen::Vector3d v;
        for (int i = 0; i < 3; ++i) {
            const toml::node& e = *a->get(static_cast<std::size_t>(i));
            v[i] = number(e, key);
            // Far beyond any scene, and small enough that products of
            // transforms and the projection stay finite and precise.
            if (std::abs(v[i]) > kMaxCoordinate)
                fail(e, key + ": component " + std::to_string(i) + " beyond +-1e9 (the documented limit of " +
                            "positions, angles and scales; docs/limits.md)");
        }
        return v;
    }

    const toml::table& table(const toml::node& n, const std::string& key) const {
        auto t = n.as_table();
        if (!t) fail(n, key + ": expected a table, got " + type_name(n));
        return *t;
    }
};

std::string object_path(std::size_t i, const std::string& name) {
    std::string p = "object[" + std::to_string(i) + "]";
    if (!name.empty()) p += " (\"" + name + "\")";
    return p;
}

void read_camera(const Reader& rd, const toml::table& t, unsigned long line, CameraDesc& cam) {
    rd.only_keys(t, "camera", {"eye", "target", "up", "fov_y", "near", "far"});
    auto need = [&](const char* k) -> const toml::node& {
        auto n = t.get(k);
        if (!n) rd.fail(line, std::string("missing key 'camera.") + k + "'");
        return *n;
    };
    cam.eye = rd.vec3(need("eye"), "camera.eye");
    cam.target = rd.vec3(need("target"), "camera.target");
    if (auto n = t.get("up")) cam.up = rd.vec3(*n, "camera.up");
    const toml::node& fov = need("fov_y");
    cam.fov_y = rd.number(fov, "camera.fov_y");
    if (!(cam.fov_y >= kMinFovY && cam.fov_y < 180.0))
        rd.fail(fov, "camera.fov_y: must lie between 0.01 (the documented minimum: narrower views lose fragments "
                     "to rounding) and 180 degrees (180 excluded)");
    const toml::node& nn = need("near");
    cam.near = rd.number(nn, "camera.near");
    if (!(cam.near > 0.0)) rd.fail(nn, "camera.near: must be > 0");
    const toml::node& fn = need("far");
    cam.far = rd.number(fn, "camera.far");
    if (!(cam.far > cam.near)) rd.fail(fn, "camera.far: must be > camera.near");

    Eigen::Vector3d dir = cam.target - cam.eye;
    if (dir.norm() < 1e-12) rd.fail(*t.get("target"), "camera.target: must differ from camera.eye");
    if (cam.up.norm() < 1e-12 || dir.normalized().cross(cam.up.normalized()).norm() < 1e-9) {
        const toml::node* un = t.get("up");
        rd.fail(un ? un->source().begin.line : line, "camera.up: must not be zero or parallel to the viewing direction");
    }
}

void read_transform_keys(const Reader& rd, const toml::table& t, const std::string& path, Keyframe& k) {
    if (auto n = t.get("position")) k.t.position = rd.vec3(*n, path + ".position");
    if (auto n = t.get("rotation")) k.t.rotation = rd.vec3(*n, path + ".rotation");
    if (auto n = t.get("scale")) {
        k.t.scale = rd.vec3(*n, path + ".scale");
        k.scale_line = n->source().begin.line;
    }
}

ObjectDesc read_object(const Reader& rd, const toml::table& t, std::size_t index, const std::string& base_dir,
                       const SceneLimits& limits) {
    ObjectDesc o;
    const unsigned long line = t.source().begin.line;
    if (auto n = t.get("name")) o.name = rd.string(*n, object_path(index, "") + ".name");
    o.key_path = object_path(index, o.name);
    const std::string& p = o.key_path;
    rd.only_keys(t, p, {"name", "id", "mesh", "segments", "cull", "check_mesh", "position", "rotation", "scale", "key"});

    if (auto n = t.get("id")) {
        const std::int64_t max_id = (std::int64_t{1} << limits.id_bits) - 1;
        std::int64_t v = rd.integer(*n, p + ".id");
        if (v < 0 || v > max_id)
            rd.fail(*n, p + ".id: " + std::to_string(v) + " does not fit zeb.id_bits = " + std::to_string(limits.id_bits) +
                            " (0.." + std::to_string(max_id) + ")");
        o.id = static_cast<std::uint32_t>(v);
    }

    const toml::node* mesh = t.get("mesh");
    if (!mesh) rd.fail(line, "missing key '" + p + ".mesh'");
    o.mesh = rd.string(*mesh, p + ".mesh");
    o.mesh_line = mesh->source().begin.line;
    o.builtin = std::any_of(std::begin(kBuiltins), std::end(kBuiltins), [&](const char* b) { return o.mesh == b; });
    if (!o.builtin) {
        namespace fs = std::filesystem;
        fs::path mp(o.mesh);
        if (mp.is_relative() && !base_dir.empty()) mp = fs::path(base_dir) / mp;
        std::error_code ec;
        if (!fs::is_regular_file(mp, ec)) {
            if (!mp.has_extension() && !fs::exists(mp, ec))
                rd.fail(*mesh, p + ".mesh: unknown shape '" + o.mesh +
                                   "' (built-in shapes: sphere, box, torus, cylinder; otherwise a mesh file path)");
        }
        // The same wording as every other input that cannot be read.
        try {
            ::close(open_input(mp.string(), "mesh file"));
        } catch (const InputError& e) {
            rd.fail(*mesh, p + ".mesh: " + e.what());
        }
        o.mesh = mp.string();
    }

    if (auto n = t.get("segments")) {
        if (!o.builtin) rd.fail(*n, p + ".segments: applies to built-in shapes only, not to mesh files");
        o.segments = static_cast<unsigned>(rd.integer_in(*n, p + ".segments", 3, 1024));
    }
    if (auto n = t.get("cull")) {
        std::string c = rd.string(*n, p + ".cull");
        if (c == "back") o.cull = Cull::Back;
        else if (c == "front") o.cull = Cull::Front;
        else if (c == "none") o.cull = Cull::None;
        else rd.fail(*n, p + ".cull: '" + c + "' is not one of back, front, none");
    }

    if (auto n = t.get("check_mesh")) {
        auto b = n->as_boolean();
        if (!b) rd.fail(*n, p + ".check_mesh: expected a boolean, got " + Reader::type_name(*n));
        o.check_mesh = b->get();
    }

    Keyframe k0;
    k0.frame = 0;
    k0.line = line;
    k0.scale_line = line;
    read_transform_keys(rd, t, p, k0);
    o.keys.push_back(k0);

    if (auto kn = t.get("key")) {
        auto arr = kn->as_array();
        if (!arr) rd.fail(*kn, p + ".key: expected an array of tables ([[object.key]]), got " + Reader::type_name(*kn));
        for (std::size_t i = 0; i < arr->size(); ++i) {
            const std::string kp = p + ".key[" + std::to_string(i) + "]";
            const toml::table& kt = rd.table(*arr->get(i), kp);
            rd.only_keys(kt, kp, {"frame", "position", "rotation", "scale"});
            Keyframe k = o.keys.back();   // what this key leaves out holds from the key before
            k.line = kt.source().begin.line;
            const toml::node* fn = kt.get("frame");
            if (!fn) rd.fail(k.line, "missing key '" + kp + ".frame'");
            std::int64_t f = rd.integer_in(*fn, kp + ".frame", 1, std::int64_t(kMaxFrames));
            if (static_cast<std::uint64_t>(f) <= o.keys.back().frame)
                rd.fail(*fn, kp + ".frame: " + std::to_string(f) + " must be greater than the frame of the key before (" +
                                 std::to_string(o.keys.back().frame) + ")");
            k.frame = static_cast<std::uint64_t>(f);
            read_transform_keys(rd, kt, kp, k);
            o.keys.push_back(k);
        }
    }
    return o;
}

} // namespace

std::vector<std::string> mesh_files_named(const std::string& toml_text, const std::string& base_dir) {
    toml::table doc;
    try {
        doc = toml::parse(toml_text);
    } catch (const toml::parse_error&) {
        return {};
    }
    std::vector<std::string> meshes;
    const toml::array* objects = doc["object"].as_array();
    if (!objects) return meshes;
    for (const toml::node& o : *objects) {
        const toml::table* t = o.as_table();
        const toml::value<std::string>* mesh = t ? t->get_as<std::string>("mesh") : nullptr;
        if (!mesh || std::any_of(std::begin(kBuiltins), std::end(kBuiltins), [&](const char* b) { return mesh->get() == b; }))
            continue;
        std::filesystem::path mp(mesh->get());
        if (mp.is_relative() && !base_dir.empty()) mp = std::filesystem::path(base_dir) / mp;
        meshes.push_back(mp.string());
    }
    return meshes;
}

Transform transform_at(const ObjectDesc& obj, std::uint64_t frame) {
    const auto& keys = obj.keys;
    if (frame >= keys.back().frame) return keys.back().t;
    // keys[0].frame == 0 <= frame < keys.back().frame: a segment exists.
    auto it = std::upper_bound(keys.begin(), keys.end(), frame,
                               [](std::uint64_t f, const Keyframe& k) { return f < k.frame; });
    const Keyframe& b = *it;
    const Keyframe& a = *(it - 1);
    const double s = double(frame - a.frame) / double(b.frame - a.frame);
    Transform t;
    t.position = a.t.position + (b.t.position - a.t.position) * s;
    t.rotation = a.t.rotation + (b.t.rotation - a.t.rotation) * s;
    t.scale = a.t.scale + (b.t.scale - a.t.scale) * s;
    return t;
}

Eigen::Matrix4d model_matrix(const Transform& t) {
    constexpr double kDeg = 3.14159265358979323846 / 180.0;
    Eigen::Affine3d m = Eigen::Affine3d::Identity();
    m.translate(t.position);
    m.rotate(Eigen::AngleAxisd(t.rotation.z() * kDeg, Eigen::Vector3d::UnitZ()));
    m.rotate(Eigen::AngleAxisd(t.rotation.y() * kDeg, Eigen::Vector3d::UnitY()));
    m.rotate(Eigen::AngleAxisd(t.rotation.x() * kDeg, Eigen::Vector3d::UnitX()));
    m.scale(t.scale);
    return m.matrix();
}

SceneDesc parse_scene(const std::string& toml_text, const std::string& display_name, const std::string& base_dir,
                      const SceneLimits& limits) {
    Reader rd{display_name};
    if (limits.id_bits < 1 || limits.id_bits > 31) throw InputError(display_name + ": id_bits must be 1..31");
    if (limits.tile_w < 1 || limits.tile_h < 1) throw InputError(display_name + ": the tile size must be at least 1x1");

    check_toml_text(toml_text, display_name);
    toml::table root;
    try {
        root = toml::parse(toml_text, display_name);
    } catch (const toml::parse_error& e) {
        std::string d(e.description());
        std::replace(d.begin(), d.end(), '\n', ' ');
        rd.fail(static_cast<unsigned long>(e.source().begin.line), "TOML syntax: " + d);
    }

    SceneDesc sc;
    sc.display_name = display_name;
    rd.only_keys(root, "", {"format", "frames", "screen", "camera", "object"});

    const toml::node* fmt = root.get("format");
    if (!fmt) rd.fail(0, "missing key 'format' (expected format = \"" + std::string(kFormat) + "\")");
    if (rd.string(*fmt, "format") != kFormat)
        rd.fail(*fmt, "format: expected \"" + std::string(kFormat) + "\", got \"" + rd.string(*fmt, "format") + "\"");

    const toml::node* fr = root.get("frames");
    if (!fr) rd.fail(0, "missing key 'frames'");
    sc.frames = static_cast<std::uint64_t>(rd.integer_in(*fr, "frames", 1, std::int64_t(kMaxFrames)));

    if (auto sn = root.get("screen")) {
        const toml::table& st = rd.table(*sn, "screen");
        rd.only_keys(st, "screen", {"width", "height"});
        if (auto n = st.get("width")) sc.width = static_cast<unsigned>(rd.integer_in(*n, "screen.width", 1, kMaxScreenSide));
        if (auto n = st.get("height")) sc.height = static_cast<unsigned>(rd.integer_in(*n, "screen.height", 1, kMaxScreenSide));
    }

    const toml::node* cn = root.get("camera");
    if (!cn) rd.fail(0, "missing table [camera]");
    read_camera(rd, rd.table(*cn, "camera"), cn->source().begin.line, sc.camera);

    if (auto on = root.get("object")) {
        auto arr = on->as_array();
        if (!arr) rd.fail(*on, "object: expected an array of tables ([[object]]), got " + Reader::type_name(*on));
        if (arr->size() >= SceneSource::kNoObject) rd.fail(*on, "object: too many objects");
        for (std::size_t i = 0; i < arr->size(); ++i) {
            const toml::table& ot = rd.table(*arr->get(i), object_path(i, ""));
            sc.objects.push_back(read_object(rd, ot, i, base_dir, limits));
        }
    }

    // Scale components interpolate linearly, so a sign change between keys
    // passes through zero; only whole frames are rendered, hence checked. Each
    // segment between two keys is solved for where a component comes within
    // kSingular of zero, and only the frames around there are evaluated (with
    // transform_at itself): linear in the number of keys, not of frames.
    for (const ObjectDesc& o : sc.objects) {
        std::uint64_t first = UINT64_MAX;
        for (std::size_t ki = 0; ki < o.keys.size() && first == UINT64_MAX; ++ki) {
            const Keyframe& a = o.keys[ki];
            if (a.frame >= sc.frames) break;
            const bool last = ki + 1 == o.keys.size();
            const std::uint64_t end = last ? a.frame : std::min(o.keys[ki + 1].frame, sc.frames - 1);
            std::vector<std::uint64_t> cand{a.frame, end};
            if (!last) {
                const Keyframe& b = o.keys[ki + 1];
                const double span = double(b.frame - a.frame);
                for (int c = 0; c < 3; ++c) {
                    const double sa = a.t.scale[c], sb = b.t.scale[c];
                    if (sa == sb) continue;
                    for (double target : {-kSingular, 0.0, kSingular}) {
                        const double f = double(a.frame) + (target - sa) / (sb - sa) * span;
                        if (!(f >= double(a.frame) - 2.0 && f <= double(end) + 2.0)) continue;
                        const auto base = static_cast<std::int64_t>(std::floor(f));
                        for (std::int64_t d = -2; d <= 2; ++d) {
                            const std::int64_t g = base + d;
                            if (g >= std::int64_t(a.frame) && std::uint64_t(g) <= end) cand.push_back(std::uint64_t(g));
                        }
                    }
                }
            }
            for (std::uint64_t f : cand) {
                const Transform t = transform_at(o, f);
                if (std::abs(t.scale.x()) < kSingular || std::abs(t.scale.y()) < kSingular ||
                    std::abs(t.scale.z()) < kSingular)
                    first = std::min(first, f);
            }
        }
        if (first != UINT64_MAX) {
            const std::uint64_t f = first;
            const Transform t = transform_at(o, f);
            // The key at f, or the one the interpolation heads for.
            auto it = std::lower_bound(o.keys.begin(), o.keys.end(), f,
                                       [](const Keyframe& k, std::uint64_t fr) { return k.frame < fr; });
            const Keyframe& k = (it == o.keys.end()) ? o.keys.back() : *it;
            std::ostringstream s;
            s << o.key_path << ".scale: the transform is singular (determinant 0) at frame " << f << " (scale ["
              << t.scale.x() << ", " << t.scale.y() << ", " << t.scale.z() << "])";
            rd.fail(k.scale_line ? k.scale_line : k.line, s.str());
        }
    }

    // Meshes are built once per shape and tessellation, but every object's
    // triangles are set up each frame: their sum bounds the memory per frame.
    std::uint64_t triangles = 0;
    for (const ObjectDesc& o : sc.objects) {
        if (!o.builtin) continue;
        triangles += builtin_triangles(o.mesh, o.segments);
        if (triangles > limits.max_scene_triangles)
            rd.fail(o.mesh_line, o.key_path + ".mesh: the scene's objects add up to more than " +
                                     std::to_string(limits.max_scene_triangles) +
                                     " triangles (the limit input.max_scene_triangles; docs/limits.md)");
    }
    return sc;
}

} // namespace rbcd::scene
