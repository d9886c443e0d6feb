// Opening and reading the program's input files, and making input text safe to
// print. Every reader (trace, scene, mesh, configuration) goes through here, so
// that a missing, unreadable or non-regular input gets the same one-line wording
// and no reader can be pointed at a device, a directory or a FIFO by mistake.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace rbcd {

// The message of a missing or unreadable input, the same for every kind:
// "<path>: cannot read <what>: <reason>". Returned, not thrown, so that readers
// whose errors come from a library (assimp) can use it too.
std::string cannot_read_message(const std::string& path, const std::string& what, const std::string& reason);

// Opens `path` for reading (O_RDONLY|O_CLOEXEC). Only a regular file is
// accepted; `allow_stdin` also accepts "-" (returns descriptor 0). Throws
// InputError with cannot_read_message otherwise.
int open_input(const std::string& path, const std::string& what, bool allow_stdin = false);

// Reads a whole regular file of at most `max_bytes` bytes. Larger files are
// refused naming the limit and `limit_key` (the key or option that raises it,
// or "" when it is fixed).
std::string read_input_text(const std::string& path, const std::string& what, std::uint64_t max_bytes,
                            const std::string& limit_key);

// The text with every byte that is not printable escaped as \xNN: control
// characters (CR, LF, ESC, ...), DEL, C1 controls and bytes that are not valid
// UTF-8. Valid printable UTF-8 stays as it is. Messages stay one line and
// cannot drive a terminal, whatever produced them.
std::string escape_for_message(std::string_view text);

// The text with every run of more than `max` non-blank bytes cut to its first
// `max` and "...(N bytes)": a 100 MB token from an input (or a library's
// "last read" excerpt) is not printed whole. Apply before escape_for_message.
std::string cut_long_tokens(std::string_view text, std::size_t max = 1024);

// toml++ 3.3 reaches __builtin_unreachable (undefined behaviour) in
// is_non_ascii_horizontal_whitespace() for some code points met outside a
// comment (U+00A1..U+0499, U+2D6E..U+3167 but U+3000, U+FBA6..U+FEFE). Throws
// InputError "<name>:<line>: ..." for the first such code point, and for text
// that is not valid UTF-8, before the text reaches the parser. Comments may
// hold anything; in a string such a character can be written as \uXXXX.
void check_toml_text(std::string_view text, const std::string& name);

} // namespace rbcd
