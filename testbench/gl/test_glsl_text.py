"""GLSL source as the converter's scans read it (rbcd.gl2rbt.glstate.
glsl_text): the words the scans look for are found however the
preprocessor spells them (round 14's R14-15, R14-17, R14-18: token
pasting, a line continuation, a macro for a keyword, a `#define` of a
qualifier never used had hidden a clip-distance write, a discard, a
storing block), every branch is kept, and a macro bomb is refused cheaply."""
import re
import time

import pytest
from hypothesis import given, settings, strategies as st

from rbcd.gl2rbt.glstate.glsl_text import ExpansionTooLarge, expanded
from rbcd.gl2rbt.glstate.programs import may_store


def words(text):
    return set(re.findall(r"\w+", text))


@pytest.mark.parametrize("source, word", [
    ("#define CAT(a, b) a ## b\nvoid main() { CAT(gl_Clip, Distance)[0] = 1.0; }\n", "gl_ClipDistance"),
    ("void main() { gl_Cull\\\nDistance[0] = 1.0; }\n", "gl_CullDistance"),
    ("#define CAT(a, b) a##b\n#define K(x) CAT(dis, x)\nvoid main() { if (k) K(card); }\n", "discard"),
    ("#define CAT(a, b) a ## b\n#define Q CAT\nvoid main() { Q(gl_Frag, Depth) = 0.5; }\n", "gl_FragDepth"),
    ("#define BUF buffer\nlayout(std430) BUF O { float v[]; };\n", "buffer"),
    ("#ifdef NEVER\n#define D discard\n#else\n#define D return\n#endif\nvoid main() { D; }\n", "return"),
    ("#if 0\nvoid f() { discard; }\n#endif\n", "discard"),   # every branch kept: a widening scan
    # Round 15's R15-1: arguments over lines, a definition in a branch the
    # compiler drops (and an #undef there), lines ended by CR alone.
    ("#define CAT(a, b) a ## b\nvoid main() { CAT(gl_Clip,\n Distance)[0] = 1.0; }\n", "gl_ClipDistance"),
    ("#define CAT(a, b) a ## b\nvoid main() { CAT\n(gl_Frag, Depth) = 0.5; }\n", "gl_FragDepth"),
    ("#define A 1\n#ifdef A\n#define W(v) gl_ClipDistance[0] = v\n#else\n#define W(v)\n#endif\nvoid main() { W(1.0); }\n",
     "gl_ClipDistance"),
    ("#define K discard\n#if 0\n#undef K\n#define K return\n#endif\nvoid main() { K; }\n", "discard"),
    ("#version 450\r// no define here\rvoid main() { gl_ClipDistance[0] = 1.0; }\r", "gl_ClipDistance"),
    ("#version 450\rvoid main() { gl_Clip\\\rDistance[0] = 1.0; }\r", "gl_ClipDistance"),
], ids=["pasted", "continued", "pasted_inside_a_macro", "through_another_name", "keyword_macro", "redefined",
        "if_0", "arguments_over_lines", "name_then_arguments_on_the_next_line", "definition_in_a_live_branch",
        "undef_in_a_dead_branch", "cr_line_ends", "continued_with_cr"])
def test_words_however_spelled(source, word):
    assert word in words(expanded(source))


def test_storing_blocks_however_spelled():
    """may_store on the expanded text: a macro for `buffer`, a `#define`
    of `readonly` never used, an atomic counter by pasting, store; a block
    `readonly` through a macro does not."""
    assert may_store(expanded("#define BUF buffer\nlayout(std430) BUF O { float v[]; };\n"))
    assert may_store(expanded("#define RO readonly\nlayout(std430) buffer O { float v[]; };\n"))
    assert may_store(expanded("#define C(a, b) a ## b\nlayout(binding = 0) uniform C(atomic_, uint) c;\n"))
    assert not may_store(expanded("#define RO readonly\nlayout(std430) RO buffer O { float v[]; };\n"))
    assert may_store(expanded("#if 1\n#define Q buffer\n#else\n#define Q readonly buffer\n#endif\n"
                              "layout(std430) Q O { float v[]; };\n"))
    assert not may_store(expanded("uniform float readonly_scale;\nvoid main() {}\n"))


def test_a_source_without_macros_is_its_text_without_comments():
    src = "#version 330 core\n// discard\nvoid main() { /* gl_FragDepth */ gl_Position = vec4(0.0); }\n"
    text = expanded(src)
    assert "discard" not in text and "gl_FragDepth" not in text and "gl_Position" in text


def test_macro_bombs_are_refused_cheaply():
    """A macro doubling the one before 40 times, and one naming itself
    through another: refused, or expanded once, in well under a second."""
    bomb = "#define A0 x x\n" + "".join(f"#define A{i} A{i - 1} A{i - 1}\n" for i in range(1, 40)) + "A39\n"
    t0 = time.monotonic()
    with pytest.raises(ExpansionTooLarge):
        expanded(bomb)
    assert words(expanded("#define X Y\n#define Y X\nX;\n")) <= {"X", "Y"}
    assert time.monotonic() - t0 < 30   # (bounded; not a speed figure)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.lists(st.sampled_from(["#define A(x) x ## x\n", "#define B A(B)\n", "A(", ")", "B", "##", "\\\n",
                                 "#undef A\n", "#define C C C\n", "C", "discard", ",", "/*", "*/", "\n", " "]),
                max_size=60))
def test_any_source_expands_or_is_refused(parts):
    """Any arrangement of macros, pasting, continuations and comments
    expands or raises ExpansionTooLarge: never another exception."""
    try:
        expanded("".join(parts))
    except ExpansionTooLarge:
        pass
