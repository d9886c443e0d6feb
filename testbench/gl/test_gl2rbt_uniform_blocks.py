"""Uniform block bindings by index, in captures the tests write (Mesa runs
the vertex shader): glUniformBlockBinding names a block by its index, which
the capture may have from glGetUniformBlockIndex, from enumerating the
program's blocks (glGetActiveUniformBlockName, glGetProgramResourceName),
or not at all (a program's only block is 0). Each must move the triangle
as the bound buffer says (the converter had bound only blocks whose index
glGetUniformBlockIndex had named: 80-85% against Mesa)."""
import struct

import pytest

from test_gl2rbt_hostile import shader_calls
from test_gl2rbt_vertex_textures import convert, draw, moved

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

VS_BLOCK = ("#version 330 core\nin vec3 p;\nlayout(std140) uniform Other { vec4 unused; };\n"
            "layout(std140) uniform Move { vec4 d; };\n"
            "void main() { gl_Position = vec4((p.x + d.x + unused.x) / 32.0 - 1.0, (p.y + d.y) / 24.0 - 1.0, 0.0, "
            "1.0); }\n")
VS_ONE_BLOCK = ("#version 330 core\nin vec3 p;\nlayout(std140) uniform Move { vec4 d; };\n"
                "void main() { gl_Position = vec4((p.x + d.x) / 32.0 - 1.0, (p.y + d.y) / 24.0 - 1.0, 0.0, 1.0); }\n")


def mesa_block_names(source):
    """The program's blocks as Mesa numbers them (the capture's driver):
    Mesa 22.3 numbers Move before Other."""
    from rbcd.gl2rbt.mesa import Mesa
    from rbcd.gl2rbt.vertex_stage import block_name
    GL = Mesa().gl
    prog, sh = GL.glCreateProgram(), GL.glCreateShader(GL.GL_VERTEX_SHADER)
    GL.glShaderSource(sh, source)
    GL.glCompileShader(sh)
    GL.glAttachShader(prog, sh)
    GL.glLinkProgram(prog)
    return [block_name(GL, prog, i) for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_UNIFORM_BLOCKS))]


def with_block(source, named):
    c = shader_calls(source)
    c.add("glGenBuffers", n=1, buffers=[9]).add("glBindBuffer", target="GL_UNIFORM_BUFFER", buffer=9)
    c.add("glBufferData", target="GL_UNIFORM_BUFFER", size=16, data=struct.pack("<4f", 6, 2, 0, 0),
          usage="GL_STATIC_DRAW")
    c.add("glBindBufferBase", target="GL_UNIFORM_BUFFER", index=3, buffer=9)
    names = mesa_block_names(source)
    index = names.index("Move")
    if named == "index":
        c.add("glGetUniformBlockIndex", program=2, uniformBlockName="Move", ret=index)
    elif named == "active name":
        for i, block in enumerate(names):
            c.add("glGetActiveUniformBlockName", program=2, uniformBlockIndex=i, bufSize=64, length=len(block),
                  uniformBlockName=block)
    elif named == "resource name":
        for i, block in enumerate(names):
            c.add("glGetProgramResourceName", program=2, programInterface="GL_UNIFORM_BLOCK", index=i, bufSize=64,
                  length=len(block), name=block)
    c.add("glUniformBlockBinding", program=2, uniformBlockIndex=index, uniformBlockBinding=3)
    return draw(c)


@pytest.mark.parametrize("source, named", [
    (VS_BLOCK, "index"), (VS_BLOCK, "active name"), (VS_BLOCK, "resource name"), (VS_BLOCK, None),
    (VS_ONE_BLOCK, None),
], ids=["index", "active_name", "resource_name", "numbered_as_mesa", "only_block"])
def test_a_block_bound_by_its_index(tmp_path, source, named):
    assert convert(tmp_path, with_block(source, named), "block") == moved(tmp_path, 6, 2)


@pytest.mark.parametrize("call", ["glBindBuffersBase", "glBindBuffersRange"])
def test_multi_bind_of_uniform_buffers(tmp_path, call):
    """glBindBuffersBase and glBindBuffersRange (GL 4.4) bind each buffer at
    its index, as glBindBufferBase does (they had been refused), and NULL
    unbinds them (the block then reads zeros)."""
    def made(null):
        c = shader_calls(VS_ONE_BLOCK)
        c.add("glGenBuffers", n=1, buffers=[9]).add("glBindBuffer", target="GL_UNIFORM_BUFFER", buffer=9)
        c.add("glBufferData", target="GL_UNIFORM_BUFFER", size=512, data=struct.pack("<4f", 9, 9, 0, 0) * 16
              + struct.pack("<4f", 6, 2, 0, 0) * 16, usage="GL_STATIC_DRAW")
        extra = dict(offsets=[0, 256], sizes=[16, 16]) if call.endswith("Range") else {}
        c.add(call, target="GL_UNIFORM_BUFFER", first=2, count=2, buffers=[9, 9], **extra)
        if null:
            c.add(call, target="GL_UNIFORM_BUFFER", first=2, count=2, buffers=0,
                  **({"offsets": 0, "sizes": 0} if extra else {}))
        c.add("glUniformBlockBinding", program=2, uniformBlockIndex=0, uniformBlockBinding=3)
        return draw(c)
    want = (6, 2) if call.endswith("Range") else (9, 9)
    assert convert(tmp_path, made(False), "bound") == moved(tmp_path, *want)
    assert convert(tmp_path, made(True), "unbound") == moved(tmp_path, 0, 0)


def test_a_block_beside_a_buffer_the_gpu_wrote(tmp_path):
    """Once any buffer holds what the GPU wrote, each draw's blocks are
    checked against it: a program with a uniform block whose own buffer the
    GPU never wrote draws as before (round 14's R14-10: every such draw was
    refused, a PyOpenGL call made with an argument short), and one whose
    block reads the written buffer is refused naming the write."""
    def written(buffer):
        c = shader_calls(VS_ONE_BLOCK)
        c.add("glGenBuffers", n=2, buffers=[9, 10]).add("glBindBuffer", target="GL_UNIFORM_BUFFER", buffer=9)
        c.add("glBufferData", target="GL_UNIFORM_BUFFER", size=16, data=struct.pack("<4f", 6, 2, 0, 0),
              usage="GL_STATIC_DRAW")
        c.add("glBindBufferBase", target="GL_UNIFORM_BUFFER", index=0, buffer=9)
        c.add("glBindBuffer", target="GL_PIXEL_PACK_BUFFER", buffer=buffer)
        if buffer == 10:
            c.add("glBufferData", target="GL_PIXEL_PACK_BUFFER", size=16, data=None, usage="GL_STREAM_READ")
        c.add("glReadPixels", x=0, y=0, width=1, height=1, format="GL_RGBA", type="GL_FLOAT", pixels=0)
        c.add("glBindBuffer", target="GL_PIXEL_PACK_BUFFER", buffer=0)
        return draw(c)
    assert convert(tmp_path, written(10), "other") == moved(tmp_path, 6, 2)
    from gl_captures import gl2rbt_timed, refused
    r = gl2rbt_timed(tmp_path, written(9).write(tmp_path / "own.xz", images=True), "-o", tmp_path / "own.rbt")
    refused(r, "reads its GL_UNIFORM_BUFFER binding 0 from buffer 9, which the GPU wrote at call", "glReadPixels")
