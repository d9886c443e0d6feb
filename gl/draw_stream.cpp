#include "rbcd/gl/draw_stream.h"

#include <cmath>
#include <cstring>

#include "rbcd/common/errors.h"
#include "rbcd/scene/scene_file.h"

namespace rbcd::gl {
namespace {

constexpr char kMagic[8] = {'R', 'B', 'C', 'D', 'G', 'L', 'D', '2'};
// Viewports and scissors may reach past the screen, within the guard band's
// reach: four screens either way.
constexpr double kMaxViewport = 4.0 * scene::kMaxScreenSide;
// The tile rasterizer keeps a bin per tile: a screen of at most 2^20 tiles
// (8192 x 8192 in 8 x 8 tiles) keeps that memory in proportion to a frame.
constexpr std::uint64_t kMaxTiles = std::uint64_t(1) << 20;

} // namespace

DrawStreamReader::DrawStreamReader(std::istream& in, std::string name, DrawStreamLimits limits)
    : in_(in), name_(std::move(name)), limits_(limits) {
    char magic[8];
    in_.read(magic, sizeof magic);
    if (in_.gcount() != sizeof magic || std::memcmp(magic, kMagic, sizeof magic) != 0)
        throw InputError(name_ + ": not a draw stream (no RBCDGLD2 header)");
    header_.width = get<std::uint32_t>();
    header_.height = get<std::uint32_t>();
    header_.tile_w = get<std::uint32_t>();
    header_.tile_h = get<std::uint32_t>();
    header_.depth_bits = get<std::uint32_t>();
    const auto side_ok = [](std::uint32_t v) { return v >= 1 && v <= scene::kMaxScreenSide; };
    if (!side_ok(header_.width) || !side_ok(header_.height) || !side_ok(header_.tile_w) || !side_ok(header_.tile_h))
        throw InputError(name_ + ": screen and tile sides must be 1.." + std::to_string(scene::kMaxScreenSide));
    const std::uint64_t tiles = std::uint64_t((header_.width + header_.tile_w - 1) / header_.tile_w) *
                                ((header_.height + header_.tile_h - 1) / header_.tile_h);
    if (tiles > kMaxTiles)
        throw InputError(name_ + ": a screen of " + std::to_string(tiles) + " tiles, more than " +
                         std::to_string(kMaxTiles) + " (larger tiles, or a smaller screen)");
    if (header_.depth_bits < 1 || header_.depth_bits > 32) throw InputError(name_ + ": depth_bits must be 1..32");
}

void DrawStreamReader::fail(const std::string& what) const {
    throw InputError(name_ + ": call " + std::to_string(call_) + ": " + what);
}

void DrawStreamReader::read(void* p, std::size_t n) {
    in_.read(static_cast<char*>(p), static_cast<std::streamsize>(n));
    if (static_cast<std::size_t>(in_.gcount()) != n) fail("the draw stream is truncated");
}

template <typename T> T DrawStreamReader::get() {
    T v;
    read(&v, sizeof v);   // little endian: the only byte order this project builds for
    return v;
}

double DrawStreamReader::get_finite(const char* what) {
    const double v = get<double>();
    if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
    return v;
}

DrawStreamReader::Kind DrawStreamReader::next() {
    if (ended_) return Kind::End;
    char tag;
    in_.read(&tag, 1);
    if (in_.gcount() != 1) fail("the draw stream is truncated (no end record)");
    if (tag == 'Z') {
        // A capture that stops before its last buffer swap: that frame is dropped.
        dropped_partial_frame_ = in_frame_;
        in_frame_ = false;
        ended_ = true;
        return Kind::End;
    }
    const auto call = get<std::uint64_t>();
    if (call < call_) fail("call numbers go backwards (next is " + std::to_string(call) + ")");
    call_ = call;
    switch (tag) {
    case 'F':
        if (in_frame_) fail("a frame starts inside a frame");
        in_frame_ = true;
        frame_ = frames_started_++;
        return Kind::FrameStart;
    case 'E':
        if (!in_frame_) fail("a frame ends outside a frame");
        in_frame_ = false;
        return Kind::FrameEnd;
    case 'S':
        if (!in_frame_) fail("a depth snapshot outside a frame");
        return Kind::Snapshot;
    case 'C': {
        if (!in_frame_) fail("a depth clear outside a frame");
        clear_value_ = get_finite("the clear depth");
        if (clear_value_ < 0.0 || clear_value_ > 1.0) fail("the clear depth is outside [0, 1]");
        clear_rect_.x0 = get<std::int32_t>();
        clear_rect_.y0 = get<std::int32_t>();
        clear_rect_.x1 = get<std::int32_t>();
        clear_rect_.y1 = get<std::int32_t>();
        return Kind::DepthClear;
    }
    case 'D':
        if (!in_frame_) fail("a draw outside a frame");
        read_draw();
        return Kind::Draw;
    default:
        fail("unknown record in the draw stream");
    }
}

void DrawStreamReader::read_draw() {
    DrawRecord& d = draw_;
    d.call = call_;
    scene::DrawState& s = d.state;
    s = scene::DrawState{};
    s.id = get<std::uint32_t>();
    const auto flags = get<std::uint8_t>();
    if (flags & ~7u) fail("unknown draw flags");
    s.collisionable = flags & 1u;
    s.fragment_effects = (flags & 2u) != 0;
    s.first_vertex_provokes = (flags & 4u) != 0;
    const auto cull = get<std::uint8_t>();
    if (cull > std::uint8_t(scene::CullFace::FrontAndBack)) fail("cull mode out of range");
    s.cull = scene::CullFace(cull);
    const auto front_ccw = get<std::uint8_t>(), depth_test = get<std::uint8_t>();
    const auto depth_func = get<std::uint8_t>(), depth_write = get<std::uint8_t>();
    if (front_ccw > 1 || depth_test > 1 || depth_write > 1) fail("a boolean of the draw state is not 0 or 1");
    if (depth_func > std::uint8_t(scene::DepthFunc::Always)) fail("depth function out of range");
    s.front_ccw = front_ccw;
    s.depth_test = depth_test;
    s.depth_func = scene::DepthFunc(depth_func);
    s.depth_write = depth_write;
    // As the GL implementation the captures are checked against.
    s.depth_from_unsnapped = true;
    s.bottom_left_fill = true;
    const auto planes = get<std::uint8_t>();
    s.shade = get<std::uint16_t>();
    if (s.shade > kShadeMax)
        fail("a draw's shading cost is above " + std::to_string(kShadeMax) + "% of a reference fragment");
    if (planes > scene::kMaxUserClipPlanes)
        fail("more than " + std::to_string(scene::kMaxUserClipPlanes) + " user clip planes");
    s.vx = get_finite("the viewport");
    s.vy = get_finite("the viewport");
    s.vw = get_finite("the viewport");
    s.vh = get_finite("the viewport");
    if (!(s.vw > 0.0 && s.vh > 0.0 && s.vw <= kMaxViewport && s.vh <= kMaxViewport && std::abs(s.vx) <= kMaxViewport &&
          std::abs(s.vy) <= kMaxViewport))
        fail("the viewport is empty or reaches too far off the screen");
    s.depth_near = get_finite("the depth range");
    s.depth_far = get_finite("the depth range");
    if (s.depth_near < 0.0 || s.depth_near > 1.0 || s.depth_far < 0.0 || s.depth_far > 1.0)
        fail("the depth range is outside [0, 1]");
    s.offset_factor = get_finite("the polygon offset");
    s.offset_units = get_finite("the polygon offset");
    // glPolygonOffset takes floats, and the units arrive in depth steps (up
    // to two a unit): past that no GL call can put them. Within it the
    // offset is computed in double and the depth clamped, as GL clamps it.
    if (std::abs(s.offset_factor) > 3.5e38 || std::abs(s.offset_units) > 7e38) fail("the polygon offset is out of range");
    s.scissor.x0 = get<std::int32_t>();
    s.scissor.y0 = get<std::int32_t>();
    s.scissor.x1 = get<std::int32_t>();
    s.scissor.y1 = get<std::int32_t>();
    s.scissor.x0 = std::max(s.scissor.x0, 0);
    s.scissor.y0 = std::max(s.scissor.y0, 0);
    s.scissor.x1 = std::min(s.scissor.x1, std::int32_t(header_.width) - 1);
    s.scissor.y1 = std::min(s.scissor.y1, std::int32_t(header_.height) - 1);
    s.clip_planes.resize(planes);
    for (auto& p : s.clip_planes)
        for (int k = 0; k < 4; ++k) p[k] = get_finite("a clip plane");

    const auto nv = get<std::uint32_t>(), nt = get<std::uint32_t>();
    if (nv > limits_.max_vertices) fail("more than " + std::to_string(limits_.max_vertices) + " vertices in one draw");
    if (nt > limits_.max_triangles) fail("more than " + std::to_string(limits_.max_triangles) + " triangles in one draw");
    d.clip.resize(nv);
    for (auto& c : d.clip)
        for (int k = 0; k < 4; ++k) c[k] = get_finite("a vertex's clip coordinate");
    d.tris.resize(nt);
    for (auto& t : d.tris) {
        read(t.data(), sizeof t);
        if (t[0] >= nv || t[1] >= nv || t[2] >= nv) fail("a triangle's vertex index is past the draw's vertices");
    }
}

} // namespace rbcd::gl
