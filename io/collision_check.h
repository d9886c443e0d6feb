// Checks a collisions file (formats.md, "Collision output") line by line
// against the frames it must hold, so that rbcd-merge never copies a part's
// file it has not read: another part's file, binary garbage, or a file cut
// short (a last line without LF would run into the next part's first) is
// refused naming the file and line. Memory does not grow with the file.
//
//   CollisionFileCheck c("a.txt", 10, 20);     // frames 10..29
//   for each line (without its LF): c.line(text);
//   c.finish(last_line_ended_with_lf);
#pragma once
#include <cstdint>
#include <string>
#include <string_view>

namespace rbcd {

class CollisionFileCheck {
public:
    // The file must hold `frames` frame lines numbered first, first+1, ...
    CollisionFileCheck(std::string name, std::uint64_t first, std::uint64_t frames);
    // One line, without its LF. Throws InputError "NAME:LINE: ...".
    void line(std::string_view text);
    // After the last line. Throws when frames are missing or the file did not
    // end with LF.
    void finish(bool ended_with_lf);
    // The longest line a valid file holds, with margin: a reader may refuse
    // longer ones before they are held.
    static constexpr std::size_t kMaxLineBytes = 256;

private:
    [[noreturn]] void fail(const std::string& what) const;
    std::string name_;
    std::uint64_t first_, frames_;
    std::uint64_t line_no_ = 0, seen_frames_ = 0;
};

} // namespace rbcd
