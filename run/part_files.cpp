#include "rbcd/run/part_files.h"

#include <unistd.h>

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

void append_part_frame_stats(const PartFiles& p, std::uint64_t offset, OutputFile& out) {
    const std::string& path = p.frame_stats;
    std::uint64_t n = 0;
    const bool lf = for_each_line(path, "frame stats file", kMaxFrameStatsLineBytes, [&](std::string_view line) {
        ++n;
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
        out.write(f.dump() + "\n");
    });
    if (!lf) throw input_error_at(path, n, "the last line does not end with LF (the file is cut short)");
    if (n != p.frames)
        throw InputError(path + ": " + std::to_string(n) + " lines where the part has " + std::to_string(p.frames) +
                         " frames");
}

} // namespace rbcd
