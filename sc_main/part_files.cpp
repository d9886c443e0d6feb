#include "rbcd/sc_main/part_files.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"
#include "rbcd/io/collision_check.h"
#include "rbcd/io/collision_format.h"

namespace rbcd {

namespace {

// A --frame-stats line is one frame's figures, well under a kilobyte.
constexpr std::size_t kMaxFrameStatsLineBytes = 64 << 10;

// Calls line(text) for every line of a regular file (text without its LF),
// refusing a line longer than max_line before it is held. Returns whether the
// file ended with LF (true for an empty file).
template <class F>
bool for_each_line(const std::string& path, const std::string& what, std::size_t max_line, F line) {
    const int fd = open_input(path, what);
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    std::string carry;
    char buf[1 << 16];
    std::uint64_t n = 0;
    for (;;) {
        const ssize_t got = ::read(fd, buf, sizeof buf);
        if (got < 0) {
            if (errno == EINTR) continue;
            throw InputError(cannot_read_message(path, what, std::strerror(errno)));
        }
        if (got == 0) break;
        std::size_t b = 0;
        for (std::size_t i = 0; i < std::size_t(got); ++i) {
            if (buf[i] != '\n') continue;
            carry.append(buf + b, i - b);
            ++n;
            if (carry.size() > max_line)
                throw input_error_at(path, n, "line longer than " + std::to_string(max_line) + " bytes");
            line(std::string_view(carry));
            carry.clear();
            b = i + 1;
        }
        carry.append(buf + b, std::size_t(got) - b);
        if (carry.size() > max_line)
            throw input_error_at(path, n + 1, "line longer than " + std::to_string(max_line) + " bytes");
    }
    if (carry.empty()) return true;
    line(std::string_view(carry));
    return false;
}

} // namespace

// The parts' collision files, each read and checked against its part's
// frames (io/collision_check.h) as it is copied.
void copy_part_collisions(const std::vector<PartFiles>& parts, OutputFile& out) {
    out.write(std::string(kCollisionsMagic));
    std::string buf;
    for (const auto& p : parts) {
        CollisionFileCheck check(p.collisions, p.first_frame, p.frames);
        bool first = true;
        const bool lf = for_each_line(p.collisions, "collisions file", CollisionFileCheck::kMaxLineBytes,
                                      [&](std::string_view line) {
                                          check.line(line);
                                          if (first) {
                                              first = false;   // the magic line, written once
                                              return;
                                          }
                                          buf.append(line);
                                          buf += '\n';
                                          if (buf.size() >= (1u << 16)) {
                                              out.write(buf);
                                              buf.clear();
                                          }
                                      });
        check.finish(lf);
    }
    out.write(buf);
}

void append_own_part_collisions(const PartFiles& part, bool first, OutputFile& out) {
    const std::string magic(kCollisionsMagic);
    const int fd = open_input(part.collisions, "collisions file");
    struct Closer {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    std::string head(magic.size(), '\0');
    std::size_t got = 0;
    while (got < head.size()) {
        const ssize_t n = ::pread(fd, head.data() + got, head.size() - got, static_cast<off_t>(got));
        if (n < 0 && errno == EINTR) continue;
        if (n < 0) throw RunError(cannot_read_message(part.collisions, "collisions file", std::strerror(errno)));
        if (n == 0) break;
        got += static_cast<std::size_t>(n);
    }
    if (got == 0) throw RunError(part.collisions + ": a worker's collisions file is empty");
    if (head != magic) throw RunError(part.collisions + ": a worker's collisions file does not start with its magic line");
    if (first) out.write(magic);
    out.append_from(fd, magic.size(), part.collisions);
}

// The parts' per-frame lines, their cycles counted from the whole run's start;
// each part's lines must be its frames, in order.
void copy_part_frame_stats(const std::vector<PartFiles>& parts, OutputFile& out) {
    std::uint64_t offset = 0;
    for (const auto& p : parts) {
        append_part_frame_stats(p, offset, out);
        offset += p.cycles;
    }
}

namespace {

// One part's line `n` counted from `offset`: checked as a JSON object of the
// part's frame n - 1, its start_cycle and end_cycle moved on by `offset`.
std::string offset_frame_line(const PartFiles& p, std::uint64_t n, std::string_view line, std::uint64_t offset) {
    const std::string& path = p.frame_stats;
    nlohmann::json f = nlohmann::json::parse(line, nullptr, false);
    if (!f.is_object()) throw input_error_at(path, n, "not a JSON object");
    const std::uint64_t expected = p.first_frame + n - 1;
    if (n > p.frames || !f.contains("frame") || !f["frame"].is_number_unsigned() ||
        f["frame"].get<std::uint64_t>() != expected)
        throw input_error_at(path, n, "frame: expected frame " + std::to_string(expected) +
                                          (n > p.frames ? " (beyond the part's frames)" : ""));
    for (const char* key : {"start_cycle", "end_cycle"}) {
        if (!f.contains(key) || !f[key].is_number_unsigned())
            throw input_error_at(path, n, std::string(key) + ": missing");
        std::uint64_t v = 0;
        if (__builtin_add_overflow(f[key].get<std::uint64_t>(), offset, &v))
            throw input_error_at(path, n, std::string(key) + ": beyond 2^64 - 1 once offset");
        f[key] = v;
    }
    return f.dump() + "\n";
}

// The three numbers the join needs from a line as the library writes a
// frame's object (compact: no space outside strings; every object's keys in
// order, none twice), found in one pass that tracks strings and nesting:
// [begin, end) of each one's digits. False for anything else: another shape,
// a key missing, given twice or only inside a nested object, keys out of
// order, a number that is not a plain unsigned one, a key where a value goes
// or a value where a key goes, brackets that do not close at the end. (It
// does not check that the other numbers and strings are written as the
// library writes them: the file is this process's own worker's.)
struct FrameNumbers {
    std::size_t begin[3] = {0, 0, 0}, end[3] = {0, 0, 0};   // end_cycle, frame, start_cycle
    std::uint64_t value[3] = {0, 0, 0};
};
bool frame_numbers(std::string_view line, FrameNumbers& out) {
    static constexpr std::string_view kKeys[3] = {"end_cycle", "frame", "start_cycle"};
    if (line.size() < 2 || line.front() != '{' || line.back() != '}') return false;
    struct Level {
        bool object;
        std::string_view last_key;   // an object's: the next must sort after it
    };
    std::vector<Level> levels;
    // Where the string opening at line[i] closes (line.size() when it does not).
    const auto string_end = [&line](std::size_t i) {
        std::size_t e = i + 1;
        while (e < line.size() && line[e] != '"') e += line[e] == '\\' ? 2 : 1;
        return std::min(e, line.size());
    };
    bool key_next = false;   // in an object, after '{' or ',': a key (or '}' after '{')
    int found = 0;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        const bool key = key_next && !(c == '}' && line[i - 1] == '{');
        key_next = false;
        if (key) {
            if (c != '"') return false;
            const std::size_t e = string_end(i);
            if (e + 1 >= line.size() || line[e + 1] != ':') return false;
            const std::string_view name = line.substr(i + 1, e - i - 1);
            Level& lv = levels.back();
            if (!lv.last_key.empty() && !(lv.last_key < name)) return false;   // out of order, or twice
            lv.last_key = name;
            i = e + 1;   // the ':'
            if (levels.size() != 1) continue;
            for (int k = 0; k < 3; ++k) {
                if (name != kKeys[k]) continue;
                std::size_t b = i + 1, d = b;
                std::uint64_t v = 0;
                while (d < line.size() && line[d] >= '0' && line[d] <= '9') {
                    if (__builtin_mul_overflow(v, 10u, &v) || __builtin_add_overflow(v, std::uint64_t(line[d] - '0'), &v))
                        return false;
                    ++d;
                }
                if (d == b || (line[b] == '0' && d - b > 1) || (line[d] != ',' && line[d] != '}')) return false;
                out.begin[k] = b;
                out.end[k] = d;
                out.value[k] = v;
                ++found;
                i = d - 1;
            }
            continue;
        }
        switch (c) {
        case '"':
            i = string_end(i);
            if (i == line.size()) return false;
            break;
        case '{':
            levels.push_back({true, {}});
            key_next = true;
            break;
        case '[':
            levels.push_back({false, {}});
            break;
        case '}':
        case ']':
            if (levels.empty() || levels.back().object != (c == '}')) return false;
            levels.pop_back();
            if (levels.empty() && i + 1 != line.size()) return false;
            break;
        case ',':
            if (levels.empty()) return false;
            key_next = levels.back().object;
            break;
        case ':':
            return false;   // only after a key, where the key's branch takes it
        case ' ':
        case '\t':
        case '\n':
        case '\r':
            return false;   // not compact
        default:
            break;
        }
    }
    return levels.empty() && found == 3;
}

// The line the JSON path above writes, without parsing it: only the two
// cycle numbers change (offset 0: none). False when the line is not of the
// library's shape; the JSON path then says what is wrong.
bool offset_frame_line_quick(const PartFiles& p, std::uint64_t n, std::string_view line, std::uint64_t offset,
                             std::string& out) {
    FrameNumbers f;
    std::uint64_t start = 0, end = 0;
    if (n > p.frames || !frame_numbers(line, f) || f.value[1] != p.first_frame + n - 1 ||
        __builtin_add_overflow(f.value[2], offset, &start) || __builtin_add_overflow(f.value[0], offset, &end))
        return false;
    if (offset == 0) {
        out.append(line);
    } else {
        // end_cycle comes first (keys in order), start_cycle last.
        out.append(line.substr(0, f.begin[0]));
        out += std::to_string(end);
        out.append(line.substr(f.end[0], f.begin[2] - f.end[0]));
        out += std::to_string(start);
        out.append(line.substr(f.end[2]));
    }
    out += '\n';
    return true;
}

template <class LineText>
void append_frame_stats(const PartFiles& p, OutputFile& out, LineText text) {
    const std::string& path = p.frame_stats;
    std::uint64_t n = 0;
    std::string buf;
    const bool lf = for_each_line(path, "frame stats file", kMaxFrameStatsLineBytes, [&](std::string_view line) {
        text(++n, line, buf);
        if (buf.size() >= (1u << 16)) {
            out.write(buf);
            buf.clear();
        }
    });
    out.write(buf);
    if (!lf) throw input_error_at(path, n, "the last line does not end with LF (the file is cut short)");
    if (n != p.frames)
        throw InputError(path + ": " + std::to_string(n) + " lines where the part has " + std::to_string(p.frames) +
                         " frames");
}

} // namespace

bool frame_line_is_library_shaped(std::string_view line) {
    FrameNumbers f;
    return frame_numbers(line, f);
}

void append_part_frame_stats(const PartFiles& p, std::uint64_t offset, OutputFile& out) {
    append_frame_stats(p, out, [&](std::uint64_t n, std::string_view line, std::string& buf) {
        buf += offset_frame_line(p, n, line, offset);
    });
}

void append_own_part_frame_stats(const PartFiles& p, std::uint64_t offset, OutputFile& out) {
    append_frame_stats(p, out, [&](std::uint64_t n, std::string_view line, std::string& buf) {
        if (!offset_frame_line_quick(p, n, line, offset, buf)) buf += offset_frame_line(p, n, line, offset);
    });
}

} // namespace rbcd
