// rbcd-merge's inputs: bit 0 of the first byte chooses between a part's stats
// document (the rest, as JSON) and a part's collisions file (the rest; the
// next two bytes are the part's first frame and frame count). A stats
// document accepted by snapshot_from_stats is merged with itself: the sums
// either fit or are refused, never wrap. A collisions file goes line by line
// through the check rbcd-merge applies (io/collision_check.h).
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/io/collision_check.h"
#include "rbcd/report/run_snapshot.h"
#include "rbcd/fuzz/fuzz_util.h"

namespace {

void stats(std::string_view text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded()) return;
    rbcd::RunSnapshot s;
    try {
        s = rbcd::snapshot_from_stats(j);
    } catch (const rbcd::InputError&) {
        return;
    }
    // The same part twice follows on only with frames 0 frames; either way the
    // merge must end in a snapshot or an InputError.
    rbcd::RunSnapshot later = s;
    if (s.frames.frames > 0 && s.frames.last_frame < UINT64_MAX - s.frames.frames) {
        later.frames.first_frame = s.frames.last_frame + 1;
        later.frames.last_frame = s.frames.last_frame + s.frames.frames;
    }
    try {
        rbcd::merge_snapshots(s, later);
    } catch (const rbcd::InputError&) {
        return;
    }
    if (s.cycles < later.cycles) rbcd::fuzz::finding("merged cycles below a part's: a sum wrapped");
}

void collisions(std::string_view text, std::uint64_t first, std::uint64_t frames) {
    rbcd::CollisionFileCheck check("fuzz", first, frames);
    try {
        std::size_t b = 0;
        bool lf = true;
        while (b < text.size()) {
            const std::size_t e = text.find('\n', b);
            if (e == std::string_view::npos) {
                check.line(text.substr(b));
                lf = false;
                break;
            }
            check.line(text.substr(b, e - b));
            b = e + 1;
        }
        check.finish(lf);
    } catch (const rbcd::InputError&) {
    }
}

} // namespace

// The report library links the SystemC kernel (run_snapshot.cpp reads a
// finished rbcd_system), whose shared library wants an sc_main; the fuzzer's
// main (or replay_main) is the program's, so this is never called.
int sc_main(int, char*[]) { return 0; }

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 3) return 0;
    const std::string_view rest(reinterpret_cast<const char*>(data + 3), size - 3);
    if (data[0] & 1) collisions(rest, data[1], data[2]);
    else stats(std::string_view(reinterpret_cast<const char*>(data + 1), size - 1));
    return 0;
}
