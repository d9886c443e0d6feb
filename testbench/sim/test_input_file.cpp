// common/input_file: the escaping of messages and the toml++ guard, directly.
#include <catch2/catch.hpp>

#include "rbcd/common/errors.h"
#include "rbcd/common/input_file.h"

using rbcd::check_toml_text;
using rbcd::escape_for_message;
using rbcd::InputError;

TEST_CASE("input_file: escape_for_message keeps printable text and UTF-8, escapes the rest", "[input_file]") {
    CHECK(escape_for_message("plain text: 'x' = 1") == "plain text: 'x' = 1");
    CHECK(escape_for_message("caf\xc3\xa9 \xe2\x82\xac") == "caf\xc3\xa9 \xe2\x82\xac");
    CHECK(escape_for_message(std::string("a\nb\rc\td\x1b[2J\x7f", 12)) == "a\\x0ab\\x0dc\\x09d\\x1b[2J\\x7f");
    CHECK(escape_for_message(std::string("\0", 1)) == "\\x00");
    CHECK(escape_for_message("\xc2\x85 \xc2\x9b") == "\\xc2\\x85 \\xc2\\x9b");       // C1 controls (NEL, CSI)
    CHECK(escape_for_message("\xe2\x80\xa8") == "\\xe2\\x80\\xa8");                  // U+2028 line separator
    CHECK(escape_for_message("\xff\xc3") == "\\xff\\xc3");                          // not UTF-8
    CHECK(escape_for_message("\xe0\x80\x80") == "\\xe0\\x80\\x80");                  // overlong
}

TEST_CASE("input_file: check_toml_text refuses toml++'s unreachable code points outside comments", "[input_file]") {
    auto msg = [](const std::string& t) {
        try {
            check_toml_text(t, "f.toml");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    CHECK(msg("\xc2\xa1") == "f.toml:1: character U+00A1 outside a comment is not accepted: the TOML parser (toml++ "
                             "3.3) mishandles U+00A1..U+0499, U+2D6E..U+3167 and U+FBA6..U+FEFE; in a string write "
                             "it as \\u00A1");
    CHECK(msg("a = 1\nb = \"\xd0\x96\"\n").rfind("f.toml:2: character U+0416", 0) == 0);
    CHECK(msg("\xe3\x80\x81").rfind("f.toml:1: character U+3001", 0) == 0);
    CHECK(msg("\xef\xbb\xbe").rfind("f.toml:1: character U+FEFE", 0) == 0);
    CHECK(msg("\"\"\"a\\\xc2\xa1\"\"\"").find("U+00A1") != std::string::npos);   // escaped: toml++ still looks at it
    // Whitespace toml++ handles, code points outside the blocks, comments.
    CHECK(msg("\xc2\xa0\xe3\x80\x80\xef\xbb\xbf").empty());
    CHECK(msg("a = \"\xe2\x82\xac \xf0\x9f\x98\x80\"").empty());
    CHECK(msg("# caf\xc3\xa9 \xc2\xa1\na = 1 # \xd0\x96\n").empty());
    CHECK(msg("a = \"# not a comment \xc2\xa1\"").find("U+00A1") != std::string::npos);
    CHECK(msg("a = '''x\n# still a string \xc2\xa1'''").find("f.toml:2:") == 0);
    CHECK(msg("a = \"\\\"\" # \xc2\xa1").empty());   // an escaped quote does not end the string
}
