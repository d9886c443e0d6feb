// The scene file's content once read and checked (scene-format.md), and the
// per-frame transform it implies. Internal to rbcd_scene.
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "rbcd/scene/scene_source.h"

namespace rbcd::scene {

enum class Cull { Back, Front, None };

struct Transform {
    Eigen::Vector3d position{0.0, 0.0, 0.0};
    Eigen::Vector3d rotation{0.0, 0.0, 0.0};   // Euler degrees, applied X, then Y, then Z
    Eigen::Vector3d scale{1.0, 1.0, 1.0};
};

// A key with every component filled in (omitted ones hold from the key before).
struct Keyframe {
    std::uint64_t frame = 0;
    Transform t;
    unsigned long line = 0;         // where the key (or the object, for frame 0) starts
    unsigned long scale_line = 0;   // where the scale in force at this key was given
};

struct ObjectDesc {
    std::string name;
    std::string key_path;           // "object[2] (\"ball\")", for messages
    std::optional<std::uint32_t> id;
    bool builtin = true;
    std::string mesh;               // built-in shape name, or the resolved file path
    unsigned long mesh_line = 0;
    unsigned segments = 32;
    Cull cull = Cull::Back;
    bool check_mesh = true;         // warn about an open, inside-out or self-intersecting mesh file
    std::vector<Keyframe> keys;     // keys[0] is frame 0; frames strictly increasing
};

struct CameraDesc {
    Eigen::Vector3d eye{0.0, 0.0, 0.0}, target{0.0, 0.0, -1.0}, up{0.0, 1.0, 0.0};
    double fov_y = 60.0, near = 0.1, far = 100.0;
};

struct SceneDesc {
    std::string display_name;
    std::uint64_t frames = 0;
    unsigned width = 800, height = 480;
    CameraDesc camera;
    std::vector<ObjectDesc> objects;
};

// Largest screen side: keeps fixed-point coordinates inside the guard band in
// 32 bits and edge functions in 64 bits (see renderer.cpp).
constexpr unsigned kMaxScreenSide = 8192;
constexpr std::uint64_t kMaxFrames = 100000000;
// Narrowest camera.fov_y, degrees: below it projected coordinates lose the
// precision the rasterizer needs (docs/limits.md).
constexpr double kMinFovY = 0.01;

// Throws InputError naming display_name:line and the key on any violation.
SceneDesc parse_scene(const std::string& toml_text, const std::string& display_name,
                      const std::string& base_dir, const SceneLimits& limits);

// The mesh files named by the `mesh` keys of the text's [[object]] tables,
// relative paths taken from base_dir, built-in shapes left out; no other key
// checked. Empty when the text is not TOML.
std::vector<std::string> mesh_files_named(const std::string& toml_text, const std::string& base_dir);

Transform transform_at(const ObjectDesc& obj, std::uint64_t frame);
// scale, then rotate X, Y, Z, then translate.
Eigen::Matrix4d model_matrix(const Transform& t);

} // namespace rbcd::scene
