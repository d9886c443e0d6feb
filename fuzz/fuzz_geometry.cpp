// rbcd-cpucd's geometry file (docs/cpucd.md), read as load_geometry_file reads
// it. Whatever is accepted is written back (geometry_file_text) and read
// again: the two texts must match. The candidate pairs of every frame are
// bounded as rbcd-cpucd bounds them, and a small accepted input's first frame
// goes through the three detectors (Bullet, GJK, FCL and the containment
// test): the values the reader lets through must be ones they take.
#include <string>
#include <string_view>

#include "rbcd/common/errors.h"
#include "rbcd/cpu/cd_input.h"
#include "rbcd/cpu/cpu_collision.h"
#include "rbcd/fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    rbcd::cpucd::CdInput in;
    try {
        in = rbcd::cpucd::load_geometry_text(text, "fuzz");
    } catch (const rbcd::InputError&) {
        return 0;
    }
    const std::string written = rbcd::cpucd::geometry_file_text(in);
    try {
        const rbcd::cpucd::CdInput again = rbcd::cpucd::load_geometry_text(written, "written");
        if (rbcd::cpucd::geometry_file_text(again) != written) rbcd::fuzz::finding("written, read back, writes differently");
    } catch (const rbcd::InputError& e) {
        rbcd::fuzz::finding(std::string("written text does not read back: ") + e.what());
    }
    constexpr std::uint64_t kPairs = 64;
    const auto small_input = [](const rbcd::cpucd::CdInput& c) {
        bool small = c.parts.size() <= 8;
        for (const auto& p : c.parts) small = small && p.mesh->tris.size() <= 64;
        return small;
    };
    if (in.per_frame()) {
        // As rbcd-cpucd runs a format-2 file: frame by frame, each its own input.
        for (std::uint64_t f = 0; f < in.frames() && f < 4; ++f) {
            const rbcd::cpucd::CdInput one = in.frame_input(f);
            if (small_input(one) && !rbcd::cpucd::overlapping_aabb_pairs(one, 0, kPairs).over_limit) {
                rbcd::cpucd::CpuDetector det(one);
                det.run_frame(0, 1);
            }
        }
        return 0;
    }
    bool small = small_input(in);
    for (std::uint64_t f = 0; f < in.frames() && f < 16; ++f)
        if (rbcd::cpucd::overlapping_aabb_pairs(in, f, kPairs).over_limit) small = false;
    if (small && in.frames() <= 16) {
        rbcd::cpucd::CpuDetector det(in);
        det.run_frame(0, 1);
    }
    return 0;
}
