"""Draws under a program whose outcome GL defines, or whose data the capture
lacks, in captures the tests write (Mesa runs their vertex shader): primitive
modes a profile does not have, patches with no tessellation stage and the
adjacency modes draw what Mesa draws; an indexed draw with no indices and
client data shorter than the draw reads are refused naming the call, with
nothing left (Mesa would read memory outside the capture: the converter
had crashed with SIGSEGV on the first)."""
import struct

import pytest

from gl_captures import TRIANGLE, gl2rbt_timed as gl2rbt, left_behind, refused
from test_gl2rbt_hostile import VS, shader_calls

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

FILLER = struct.pack("<3f", 60.0, 44.0, -10.0)   # an adjacent vertex, far from the triangle


def draw(c, mode="GL_TRIANGLES", count=3, vao=7, elements=None, pointer=0):
    if vao:
        c.add("glGenVertexArrays", n=1, arrays=[vao]).add("glBindVertexArray", array=vao)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0,
          pointer=pointer)
    c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    if elements is None:
        c.add("glDrawArrays", mode=mode, first=0, count=count)
    else:
        c.add("glDrawElements", mode=mode, count=count, type="GL_UNSIGNED_SHORT", indices=elements)
    c.add("glPopDebugGroup")
    return c.swap()


def adjacency_buffer(c):
    """Buffer 1 again, with the triangle's vertices at 0, 2 and 4 and
    adjacent ones between them."""
    data = b"".join(TRIANGLE[12 * i:12 * i + 12] + FILLER for i in range(3))
    return c.add("glBufferData", target="GL_ARRAY_BUFFER", size=len(data), data=data, usage="GL_STATIC_DRAW")


def trace(tmp_path, c, tag):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return (tmp_path / f"{tag}.rbt").read_bytes()


def test_adjacency_modes_draw_their_triangles(tmp_path):
    """With no geometry shader GL draws the triangles of the adjacency modes
    and passes over the adjacent vertices (Mesa 22.3 too): the bytes of the
    plain triangle."""
    want = trace(tmp_path, draw(shader_calls(VS)), "reference")
    assert want.count(b"\nf ") > 100
    for mode in ("GL_TRIANGLES_ADJACENCY", "GL_TRIANGLE_STRIP_ADJACENCY"):
        assert trace(tmp_path, draw(adjacency_buffer(shader_calls(VS)), mode, 6), mode) == want, mode


@pytest.mark.parametrize("mode, count, core", [
    ("GL_QUADS", 4, True), ("GL_QUAD_STRIP", 4, True), ("GL_POLYGON", 3, True),   # GL_INVALID_ENUM in core
    ("GL_PATCHES", 3, True), ("GL_PATCHES", 3, False),   # GL_INVALID_OPERATION without a tessellation stage
    ("GL_LINES_ADJACENCY", 4, True),                      # lines: no area
])
def test_modes_that_draw_nothing(tmp_path, mode, count, core):
    got = trace(tmp_path, draw(shader_calls(VS, core=core), mode, count), "m")
    assert got.count(b"\nf ") == 0 and b"\nframe 0" in got


def test_an_indexed_draw_with_no_indices_is_refused(tmp_path):
    """No element array buffer, and an offset where the indices would be:
    an address in the program, not in the capture (the converter's Mesa
    had read address 0 and crashed); nothing left behind."""
    c = draw(shader_calls(VS), elements=0)
    r = gl2rbt(tmp_path, c.write(tmp_path / "e.xz"), "-o", tmp_path / "e.rbt")
    refused(r, "glDrawElements", "no element array buffer is bound")
    assert left_behind(tmp_path, ["e.xz"]) == []


@pytest.mark.parametrize("cut, words", [
    ("indices", "the capture's indices are 4 bytes, the draw reads 6"),
    ("vertices", "attribute 0's client array in the capture is 35 bytes, the draw reads 36"),
    ("empty", "attribute 0's client array in the capture is 0 bytes, the draw reads 36"),
])
def test_client_data_shorter_than_the_draw_reads_is_refused(tmp_path, cut, words):
    """Client memory (a compatibility profile, no buffer bound): apitrace
    records the bytes the draw reads; fewer than that is the capture's
    error, not a triangle of zeros."""
    c = shader_calls(VS, core=False).add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=0)
    vertices = {"vertices": TRIANGLE[:35], "empty": b""}.get(cut, TRIANGLE)
    indices = struct.pack("<3H", 0, 1, 2)[:4 if cut == "indices" else 6]
    c = draw(c, vao=0, elements=indices, pointer=vertices)
    r = gl2rbt(tmp_path, c.write(tmp_path / "s.xz"), "-o", tmp_path / "s.rbt")
    refused(r, "glDrawElements", words)
    assert left_behind(tmp_path, ["s.xz"]) == []
    # The same whole: drawn.
    whole = draw(shader_calls(VS, core=False).add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=0), vao=0,
                 elements=struct.pack("<3H", 0, 1, 2), pointer=TRIANGLE)
    assert trace(tmp_path, whole, "whole").count(b"\nf ") > 100


VS_XFB = ("#version 440 core\nin vec3 p;\nlayout(xfb_buffer = 0, xfb_offset = 0) out vec4 tf;\n"
          "void main() { tf = vec4(9.0); gl_Position = vec4(p.x / 32.0 - 1.0, p.y / 24.0 - 1.0, 0.0, 1.0); }\n")
VS_CLIP = VS.replace("void main() {", "void main() { gl_ClipDistance[0] = p.x - 20.0;")


@pytest.mark.parametrize("source, words", [
    # The shader's own transform feedback layout took the place of the
    # converter's gl_Position: every vertex had landed at tf's (9, 9, 9, 9).
    (VS_XFB, "declares its own transform feedback outputs"),
    # Mesa 22.3 clips by gl_ClipDistance even with GL_CLIP_DISTANCE0
    # disabled (GL says it does not): not emulated, so refused.
    (VS_CLIP, "writes clip or cull distances"),
], ids=["xfb_outputs", "clip_distance"])
def test_vertex_shaders_whose_output_the_converter_cannot_follow_are_refused(tmp_path, source, words):
    r = gl2rbt(tmp_path, draw(shader_calls(source)).write(tmp_path / "v.xz"), "-o", tmp_path / "v.rbt")
    refused(r, "call ", "program 2", words)
    assert left_behind(tmp_path, ["v.xz"]) == []


def test_clip_distances_named_only_in_a_comment_convert(tmp_path):
    source = VS.replace("void main() {", "// gl_ClipDistance is not written\nvoid main() {")
    assert trace(tmp_path, draw(shader_calls(source)), "c") == trace(tmp_path, draw(shader_calls(VS)), "r")
