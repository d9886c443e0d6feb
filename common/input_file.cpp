#include "rbcd/common/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "rbcd/common/errors.h"

namespace rbcd {

std::string cannot_read_message(const std::string& path, const std::string& what, const std::string& reason) {
    return path + ": cannot read " + what + ": " + reason;
}

int open_input(const std::string& path, const std::string& what, bool allow_stdin) {
    if (allow_stdin && path == "-") return 0;
    // O_NONBLOCK: opening a FIFO must not wait for a writer before it is refused.
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) throw InputError(cannot_read_message(path, what, std::strerror(errno)));
    struct stat st {};
    if (::fstat(fd, &st) != 0) {
        const int e = errno;
        ::close(fd);
        throw InputError(cannot_read_message(path, what, std::strerror(e)));
    }
    if (!S_ISREG(st.st_mode)) {
        ::close(fd);
        const char* kind = S_ISDIR(st.st_mode) ? "a directory" : S_ISCHR(st.st_mode) ? "a character device"
                           : S_ISBLK(st.st_mode) ? "a block device" : S_ISFIFO(st.st_mode) ? "a FIFO"
                           : S_ISSOCK(st.st_mode) ? "a socket" : "not a file";
        throw InputError(cannot_read_message(path, what, std::string("is ") + kind + ", not a regular file" +
                                                             (allow_stdin ? " (use - for standard input)" : "")));
    }
    const int flags = ::fcntl(fd, F_GETFL);
    if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
    return fd;
}

std::string read_input_text(const std::string& path, const std::string& what, std::uint64_t max_bytes,
                            const std::string& limit_key) {
    const int fd = open_input(path, what);
    std::string text;
    char buf[65536];
    for (;;) {
        const ssize_t n = ::read(fd, buf, sizeof buf);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int e = errno;
            ::close(fd);
            throw InputError(cannot_read_message(path, what, std::strerror(e)));
        }
        if (n == 0) break;
        if (text.size() + std::uint64_t(n) > max_bytes) {
            ::close(fd);
            throw InputError(path + ": " + what + " larger than " + std::to_string(max_bytes) + " bytes (the limit" +
                             (limit_key.empty() ? std::string(", fixed") : ", raised by " + limit_key) +
                             "; docs/limits.md)");
        }
        text.append(buf, static_cast<std::size_t>(n));
    }
    ::close(fd);
    return text;
}

namespace {
// Length of the valid UTF-8 sequence at s[i] (2..4), 0 if there is none.
std::size_t utf8_len(std::string_view s, std::size_t i, char32_t& cp) {
    const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[i + k]); };
    const unsigned char c = b(0);
    std::size_t n;
    if (c >= 0xc2 && c <= 0xdf) { n = 2; cp = c & 0x1f; }
    else if (c >= 0xe0 && c <= 0xef) { n = 3; cp = c & 0x0f; }
    else if (c >= 0xf0 && c <= 0xf4) { n = 4; cp = c & 0x07; }
    else return 0;
    if (i + n > s.size()) return 0;
    for (std::size_t k = 1; k < n; ++k) {
        if ((b(k) & 0xc0) != 0x80) return 0;
        cp = (cp << 6) | (b(k) & 0x3f);
    }
    // Overlong forms, surrogates and code points past U+10FFFF.
    if ((n == 3 && cp < 0x800) || (n == 4 && (cp < 0x10000 || cp > 0x10ffff)) || (cp >= 0xd800 && cp <= 0xdfff))
        return 0;
    return n;
}

// The code points for which toml++ 3.3's is_non_ascii_horizontal_whitespace()
// falls through its switch to __builtin_unreachable: search blocks 0, 11 and
// 63 of its table, less the three whitespace code points it tests before.
bool toml_unreachable(char32_t c) {
    if (c < 0xa0 || c > 0xfeff || c == 0xa0 || c == 0x3000 || c == 0xfeff) return false;
    const auto block = (std::uint64_t(c) - 0xa0u) / 0x3fau;
    return block == 0 || block == 11 || block == 63;
}

std::string hex_cp(char32_t c) {
    static const char* digits = "0123456789ABCDEF";
    std::string s = "U+";
    for (int sh = 12; sh >= 0; sh -= 4) s += digits[(c >> sh) & 15];
    return s;
}
} // namespace

std::string cut_long_tokens(std::string_view s, std::size_t max) {
    std::string out;
    out.reserve(std::min(s.size(), std::size_t(4096)));
    std::size_t i = 0;
    while (i < s.size()) {
        if (s[i] == ' ') {
            out += ' ';
            ++i;
            continue;
        }
        const std::size_t e = std::min(s.find(' ', i), s.size());
        if (e - i <= max) {
            out.append(s.substr(i, e - i));
        } else {
            // Not inside a UTF-8 sequence: back up to a lead byte.
            std::size_t cut = max;
            while (cut > 0 && (static_cast<unsigned char>(s[i + cut]) & 0xc0) == 0x80) --cut;
            out.append(s.substr(i, cut));
            out += "...(" + std::to_string(e - i) + " bytes)";
        }
        i = e;
    }
    return out;
}

std::string escape_for_message(std::string_view s) {
    static const char* digits = "0123456789abcdef";
    std::string out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        if (c >= 0x20 && c < 0x7f) {
            out += static_cast<char>(c);
            ++i;
            continue;
        }
        char32_t cp = 0;
        const std::size_t n = c >= 0x80 ? utf8_len(s, i, cp) : 0;
        if (n && cp >= 0xa0 && cp != 0x2028 && cp != 0x2029) {   // C1 controls and line separators stay escaped
            out.append(s.substr(i, n));
            i += n;
            continue;
        }
        out += "\\x";
        out += digits[c >> 4];
        out += digits[c & 15];
        ++i;
    }
    return out;
}

void check_toml_text(std::string_view s, const std::string& name) {
    enum class St { Normal, Comment, Basic, Literal, MlBasic, MlLiteral } st = St::Normal;
    unsigned long long line = 1;
    const auto at = [&](std::size_t i, char c) { return i < s.size() && s[i] == c; };
    const auto ascii_after = [&](std::size_t i) {
        return i + 1 < s.size() && s[i + 1] != '\n' && static_cast<unsigned char>(s[i + 1]) < 0x80;
    };
    for (std::size_t i = 0; i < s.size();) {
        const char c = s[i];
        const unsigned char u = static_cast<unsigned char>(c);
        if (c == '\n') ++line;
        if (u >= 0x80) {
            char32_t cp = 0;
            const std::size_t n = utf8_len(s, i, cp);
            if (n && st != St::Comment && toml_unreachable(cp))
                throw input_error_at(name, line,
                                     "character " + hex_cp(cp) +
                                         " outside a comment is not accepted: the TOML parser (toml++ 3.3) "
                                         "mishandles U+00A1..U+0499, U+2D6E..U+3167 and U+FBA6..U+FEFE; in a "
                                         "string write it as \\u" + hex_cp(cp).substr(2));
            i += n ? n : 1;   // invalid UTF-8 is the parser's to report
            continue;
        }
        switch (st) {
        case St::Normal:
            if (c == '#') st = St::Comment;
            else if (c == '"' && at(i + 1, '"') && at(i + 2, '"')) { st = St::MlBasic; i += 3; continue; }
            else if (c == '"') st = St::Basic;
            else if (c == '\'' && at(i + 1, '\'') && at(i + 2, '\'')) { st = St::MlLiteral; i += 3; continue; }
            else if (c == '\'') st = St::Literal;
            break;
        case St::Comment:
            if (c == '\n') st = St::Normal;
            break;
        case St::Basic:
            // An escaped ASCII character is skipped (it may be a quote); a
            // non-ASCII one is looked at like any other (toml++ tests it too).
            if (c == '\\' && ascii_after(i)) { i += 2; continue; }
            if (c == '"' || c == '\n') st = St::Normal;
            break;
        case St::Literal:
            if (c == '\'' || c == '\n') st = St::Normal;
            break;
        case St::MlBasic:
        case St::MlLiteral: {
            const char q = st == St::MlBasic ? '"' : '\'';
            if (st == St::MlBasic && c == '\\' && ascii_after(i)) { i += 2; continue; }
            if (c == q && at(i + 1, q) && at(i + 2, q)) {
                i += 3;
                // Up to two more quotes belong to the string ("""a"""" is a").
                for (int k = 0; k < 2 && at(i, q); ++k) ++i;
                st = St::Normal;
                continue;
            }
            break;
        }
        }
        ++i;
    }
}

} // namespace rbcd
