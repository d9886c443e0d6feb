"""GL 4.3 / ES 3.1 vertex attribute binding, GL 4.5 direct state access on
buffers and vertex array objects, and glBlitFramebuffer, in captures the
tests write (reduced captures; Mesa runs the vertex shader): each way of
setting up the same triangle must give the bytes glVertexAttribPointer
gives; calls GL ignores must change nothing; a depth copy the converter
changes the trace in no way, and the frames whose camera-pass depth buffer
the converter's cannot follow are counted (--check-depth leaves them
out)."""
import struct

import pytest

from gl_captures import TRIANGLE, gl2rbt_timed as gl2rbt
from test_gl2rbt_hostile import VS, shader_calls

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

# The triangle's three vertices, each between a float of padding before and
# after it (20-byte records), after a 16-byte header: the data a shared
# binding with a relative offset reads.
PADDED = b"\xff" * 16 + b"".join(struct.pack("<f", -7.0) + TRIANGLE[12 * i:12 * i + 12] + struct.pack("<f", 9.0)
                                 for i in range(3))


def tagged_draw(c, draw="glDrawArrays", **kw):
    c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    if draw == "glDrawArrays":
        c.add(draw, mode="GL_TRIANGLES", first=0, count=3)
    else:
        c.add(draw, mode="GL_TRIANGLES", count=3, type="GL_UNSIGNED_SHORT", indices=0)
    c.add("glPopDebugGroup")
    return c.swap()


def reference(c):
    """glVertexAttribPointer on buffer 1, as GL 3.3 draws it."""
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0, pointer=0)
    return tagged_draw(c)


def padded_buffer(c, name=2):
    c.add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=name)
    return c.add("glBufferData", target="GL_ARRAY_BUFFER", size=len(PADDED), data=PADDED, usage="GL_STATIC_DRAW")


def at_point_three(c):
    """Attribute 0 of vertex array 7 reads binding point 3: the padded
    records at offset 16, stride 20, relative offset 4."""
    padded_buffer(c)
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribFormat", attribindex=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", relativeoffset=4)
    c.add("glVertexAttribBinding", attribindex=0, bindingindex=3)
    return c.add("glBindVertexBuffer", bindingindex=3, buffer=2, offset=16, stride=20)


def shared_binding(c):
    return tagged_draw(at_point_three(c))


def ignored_calls(c):
    """The shared binding, then calls GL refuses with an error, each of which
    would move the triangle: a relative offset past 2047, a stride past 2048,
    a binding point past 15, a divisor on it, attribute 16."""
    at_point_three(c)
    c.add("glVertexAttribFormat", attribindex=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", relativeoffset=4096)
    c.add("glBindVertexBuffer", bindingindex=3, buffer=2, offset=16, stride=4096)
    c.add("glVertexAttribBinding", attribindex=0, bindingindex=16)
    c.add("glVertexBindingDivisor", bindingindex=3, divisor=0)
    c.add("glVertexAttribFormat", attribindex=16, size=3, type="GL_FLOAT", normalized="GL_FALSE", relativeoffset=0)
    return tagged_draw(c)


def pointer_after_binding(c):
    """glVertexAttribPointer after the binding calls: attribute 0 reads its
    own binding point 0 again, on buffer 1, packed (GL's definition of the
    call), whatever binding 3 holds."""
    at_point_three(c)
    c.add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=1)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0, pointer=0)
    return tagged_draw(c)


def direct_state_access(c):
    """GL 4.5: buffers and a vertex array object made and filled by name,
    never bound but the object at the draw; indices through the object's
    element buffer."""
    c.add("glCreateBuffers", n=2, buffers=[11, 12])
    c.calls.append((len(c.calls) + 1, "glNamedBufferStorage", [("buffer", 11), ("size", len(PADDED)), ("data", PADDED),
                                                               ("flags", 0)], None, 0))   # (add's flags are the call's)
    c.add("glNamedBufferData", buffer=12, size=6, data=struct.pack("<3H", 0, 1, 2), usage="GL_STATIC_DRAW")
    c.add("glCreateVertexArrays", n=1, arrays=[9])
    c.add("glVertexArrayVertexBuffer", vaobj=9, bindingindex=1, buffer=11, offset=16, stride=20)
    c.add("glVertexArrayAttribFormat", vaobj=9, attribindex=0, size=3, type="GL_FLOAT", normalized="GL_FALSE",
          relativeoffset=4)
    c.add("glVertexArrayAttribBinding", vaobj=9, attribindex=0, bindingindex=1)
    c.add("glEnableVertexArrayAttrib", vaobj=9, index=0)
    c.add("glVertexArrayElementBuffer", vaobj=9, buffer=12)
    c.add("glBindVertexArray", array=9)
    return tagged_draw(c, "glDrawElements")


def mapped_named(c):
    """The padded data written through glMapNamedBufferRange (apitrace
    records the write as a memcpy into the mapped range) and copied by
    glCopyNamedBufferSubData into a second buffer, which the draw reads."""
    c.add("glCreateBuffers", n=2, buffers=[11, 13])
    c.add("glNamedBufferData", buffer=11, size=len(PADDED), data=None, usage="GL_DYNAMIC_DRAW")
    c.add("glNamedBufferData", buffer=13, size=len(PADDED), data=None, usage="GL_DYNAMIC_DRAW")
    c.add("glMapNamedBufferRange", buffer=11, offset=0, length=len(PADDED), access="GL_MAP_WRITE_BIT",
          ret=0x10000)
    c.add("memcpy", dest=0x10000, src=PADDED, n=len(PADDED))
    c.add("glUnmapNamedBuffer", buffer=11)
    c.add("glCopyNamedBufferSubData", readBuffer=11, writeBuffer=13, readOffset=0, writeOffset=0, size=len(PADDED))
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribFormat", attribindex=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", relativeoffset=4)
    c.add("glVertexAttribBinding", attribindex=0, bindingindex=0)
    c.add("glBindVertexBuffer", bindingindex=0, buffer=13, offset=16, stride=20)
    return tagged_draw(c)


def trace(tmp_path, c, tag):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return (tmp_path / f"{tag}.rbt").read_bytes()


@pytest.mark.parametrize("build", [shared_binding, ignored_calls, pointer_after_binding, direct_state_access,
                                   mapped_named])
def test_the_same_triangle(tmp_path, build):
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    assert want.count(b"\nf ") > 100, "the reference triangle drew no fragments"
    assert trace(tmp_path, build(shader_calls(VS)), build.__name__) == want


def test_gl_ignores_binding_calls_on_the_default_vertex_array_of_a_core_profile(tmp_path):
    """Core profile, no vertex array object bound: glVertexAttribFormat,
    glVertexAttribBinding and glBindVertexBuffer are GL_INVALID_OPERATION,
    so the draw (which draws nothing there anyway) leaves no fragment; in a
    compatibility profile they set the default object's state and it draws."""
    def calls(core):
        c = padded_buffer(shader_calls(VS, core=core))
        c.add("glEnableVertexAttribArray", index=0)
        c.add("glVertexAttribFormat", attribindex=0, size=3, type="GL_FLOAT", normalized="GL_FALSE",
              relativeoffset=4)
        c.add("glBindVertexBuffer", bindingindex=0, buffer=2, offset=16, stride=20)
        return tagged_draw(c)
    assert trace(tmp_path, calls(False), "compat").count(b"\nf ") > 100
    assert trace(tmp_path, calls(True), "core").count(b"\nf ") == 0


def test_direct_state_access_needs_objects(tmp_path):
    """A name glGenVertexArrays gave but no bind made an object of, and a
    buffer name never bound nor created, are GL_INVALID_OPERATION for the
    direct-state-access calls: the object bound later has none of that
    state, and the draw reads nothing (no fragment, not the triangle)."""
    c = shader_calls(VS)
    c.add("glGenVertexArrays", n=1, arrays=[9])
    c.add("glNamedBufferData", buffer=40, size=len(PADDED), data=PADDED, usage="GL_STATIC_DRAW")
    c.add("glVertexArrayVertexBuffer", vaobj=9, bindingindex=0, buffer=1, offset=0, stride=12)
    c.add("glEnableVertexArrayAttrib", vaobj=9, index=0)
    c.add("glBindVertexArray", array=9)
    assert trace(tmp_path, tagged_draw(c), "dsa").count(b"\nf ") == 0


def blit(c, mask, src_rect, dst_rect, read=3, draw=0, filt="GL_NEAREST"):
    c.add("glBindFramebuffer", target="GL_READ_FRAMEBUFFER", framebuffer=read)
    c.add("glBindFramebuffer", target="GL_DRAW_FRAMEBUFFER", framebuffer=draw)
    return c.add("glBlitFramebuffer", srcX0=src_rect[0], srcY0=src_rect[1], srcX1=src_rect[2], srcY1=src_rect[3],
                 dstX0=dst_rect[0], dstY0=dst_rect[1], dstX1=dst_rect[2], dstY1=dst_rect[3], mask=mask,
                 filter=filt)


def with_fbo(c, w=64, h=48):
    """Framebuffer 3 with a w x h depth renderbuffer (the screen's size: the
    camera pass), unbound again."""
    c.add("glGenFramebuffers", n=1, framebuffers=[3]).add("glBindFramebuffer", target="GL_FRAMEBUFFER",
                                                          framebuffer=3)
    c.add("glGenRenderbuffers", n=1, renderbuffers=[4]).add("glBindRenderbuffer", target="GL_RENDERBUFFER",
                                                            renderbuffer=4)
    c.add("glRenderbufferStorage", target="GL_RENDERBUFFER", internalformat="GL_DEPTH_COMPONENT24", width=w,
          height=h)
    c.add("glFramebufferRenderbuffer", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
          renderbuffertarget="GL_RENDERBUFFER", renderbuffer=4)
    return c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=0)


FULL = (0, 0, 64, 48)


@pytest.mark.parametrize("core", [True, False], ids=["core", "compatibility"])
def test_a_multi_bind_of_a_name_that_is_no_buffer_skips_that_entry(tmp_path, core):
    """glBindVertexBuffers with a name no buffer object has (a multi-bind
    creates none, in either profile) leaves that point as it was and binds
    the others (round 10's R10-7: refused at the draw in a compatibility
    profile, 'the draw reads buffer 999')."""
    want = trace(tmp_path, shared_binding(shader_calls(VS, core)), "want")
    c = at_point_three(shader_calls(VS, core))
    c.add("glBindVertexBuffers", first=3, count=2, buffers=[999, 2], offsets=[0, 0], strides=[12, 12])
    assert trace(tmp_path, tagged_draw(c), "multi") == want


@pytest.mark.parametrize("mask, src, dst, filt, w", [
    ("GL_COLOR_BUFFER_BIT", (0, 0, 32, 24), FULL, "GL_LINEAR", 64),       # colour only, scaled
    ("GL_DEPTH_BUFFER_BIT | GL_COLOR_BUFFER_BIT", FULL, FULL, "GL_NEAREST", 64),   # a resolve of the camera pass
    ("GL_DEPTH_BUFFER_BIT", (0, 0, 32, 24), FULL, "GL_LINEAR", 64),       # GL_INVALID_OPERATION: nothing
    ("GL_DEPTH_BUFFER_BIT | GL_ACCUM_BUFFER_BIT", (0, 0, 32, 24), FULL, "GL_NEAREST", 64),   # GL_INVALID_VALUE
])
def test_blits_that_change_no_depth_of_the_camera_pass(tmp_path, mask, src, dst, filt, w):
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    got = trace(tmp_path, reference(blit(with_fbo(shader_calls(VS), w), mask, src, dst, filt=filt)
                                    .add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=0)), "blit")
    assert got == want


VS_OFF = VS.replace("in vec3 p;", "in vec3 p;\nin vec4 off;\nin ivec4 k;").replace(
    "p.x / 32.0 - 1.0", "p.x / 32.0 - 1.0 + off.x + float(k.y) / 32.0")


def with_current_values(*calls):
    """The reference triangle under VS_OFF, whose disabled attributes 1 (off)
    and 2 (k) take the current values the calls set."""
    c = shader_calls(VS_OFF)
    c.add("glBindAttribLocation", program=2, index=1, name="off").add("glBindAttribLocation", program=2, index=2,
                                                                        name="k")
    c.add("glLinkProgram", program=2).add("glUseProgram", program=2)
    for fn, kw in calls:
        c.add(fn, **kw)
    return reference(c)


def test_current_values_of_every_form(tmp_path):
    """glVertexAttrib4Nub, the I forms of one to three components and of
    bytes and shorts: the values Mesa's attribute
    takes, as the float and int forms give them (off.x = 1 moves the
    triangle 32 pixels right, k.y = 8 eight more)."""
    want = trace(tmp_path, with_current_values(("glVertexAttrib4f", dict(index=1, x=1.0, y=0.0, z=0.0, w=1.0)),
                                               ("glVertexAttribI4i", dict(index=2, x=0, y=8, z=0, w=0))), "want")
    assert want != trace(tmp_path, reference(shader_calls(VS)), "plain")
    forms = [
        [("glVertexAttrib4Nub", dict(index=1, x=255, y=0, z=0, w=255)), ("glVertexAttribI2i", dict(index=2, x=0, y=8))],
        [("glVertexAttrib4Nubv", dict(index=1, v=[255, 0, 0, 255])),
         ("glVertexAttribI4ubv", dict(index=2, v=[0, 8, 0, 0]))],
        [("glVertexAttrib1f", dict(index=1, x=1.0)), ("glVertexAttribI3uiv", dict(index=2, v=[0, 8, 0]))],
        [("glVertexAttrib4Nsv", dict(index=1, v=[32767, 0, 0, 32767])),
         ("glVertexAttribI4sv", dict(index=2, v=[0, 8, 0, 0]))],
    ]
    for k, calls in enumerate(forms):
        assert trace(tmp_path, with_current_values(*calls), f"form{k}") == want, calls


def test_a_bgra_format_and_null_multi_binds(tmp_path):
    """glVertexAttribFormat of size GL_BGRA, which apitrace records as the
    number 0x80E1 (the call had been taken as one GL refuses: the attribute
    kept its float format), reads (B, G, R, A) bytes as (R, G, B, A): off =
    (1, 0, 0, 1) as glVertexAttrib4f gives it; glBindVertexBuffers with NULL
    arrays (apitrace's 0) unbinds its points (it had been refused)."""
    want = trace(tmp_path, with_current_values(("glVertexAttrib4f", dict(index=1, x=1.0, y=0.0, z=0.0, w=1.0)),
                                               ("glVertexAttribI4i", dict(index=2, x=0, y=8, z=0, w=0))), "want")
    c = shader_calls(VS_OFF)
    c.add("glBindAttribLocation", program=2, index=1, name="off").add("glBindAttribLocation", program=2, index=2,
                                                                        name="k")
    c.add("glLinkProgram", program=2).add("glUseProgram", program=2)
    c.add("glVertexAttribI4i", index=2, x=0, y=8, z=0, w=0)
    c.add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=3)
    c.add("glBufferData", target="GL_ARRAY_BUFFER", size=12, data=bytes([0, 0, 255, 255]) * 3, usage="GL_STATIC_DRAW")
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=1)
    c.add("glVertexAttribFormat", attribindex=1, size=0x80E1, type="GL_UNSIGNED_BYTE", normalized="GL_TRUE",
          relativeoffset=0)
    c.add("glVertexAttribBinding", attribindex=1, bindingindex=5)
    c.add("glBindVertexBuffer", bindingindex=5, buffer=3, offset=0, stride=4)
    c.add("glBindVertexBuffers", first=9, count=2, buffers=0, offsets=0, strides=0)
    c.add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=1)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0, pointer=0)
    assert trace(tmp_path, tagged_draw(c), "bgra") == want


# ---- the 64-bit L forms (GL 4.1) and the packed P current values (GL 3.3)

VS_DOUBLE = ("#version 410 core\nin dvec3 p;\n"
             "void main() { gl_Position = vec4(float(p.x) / 32.0 - 1.0, float(p.y) / 24.0 - 1.0, 0.0, 1.0); }\n")
DOUBLES = struct.pack("<9d", *struct.unpack("<9f", TRIANGLE))


@pytest.mark.parametrize("how", ["pointer", "format"])
def test_double_attributes_read_as_doubles(tmp_path, how):
    """glVertexAttribLPointer, or glVertexAttribLFormat with a binding point:
    the triangle as doubles gives the floats' bytes (they had been refused)."""
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    c = shader_calls(VS_DOUBLE)
    c.add("glBufferData", target="GL_ARRAY_BUFFER", size=len(DOUBLES), data=DOUBLES, usage="GL_STATIC_DRAW")
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    if how == "pointer":
        c.add("glVertexAttribLPointer", index=0, size=3, type="GL_DOUBLE", stride=0, pointer=0)
    else:
        c.add("glVertexAttribLFormat", attribindex=0, size=3, type="GL_DOUBLE", relativeoffset=0)
        c.add("glVertexAttribBinding", attribindex=0, bindingindex=2)
        c.add("glBindVertexBuffer", bindingindex=2, buffer=1, offset=0, stride=24)
    c.add("glVertexAttribLPointer", index=0, size=3, type="GL_FLOAT", stride=0, pointer=0)   # GL_INVALID_ENUM
    assert trace(tmp_path, tagged_draw(c), how) == want


# The triangle as GL_UNSIGNED_INT_10F_11F_11F_REV words: x and y 11-bit
# floats (4 is 1088, 40 is 1296), z 0.
PACKED_FLOATS = struct.pack("<3I", *(x | y << 11 for x, y in ((1088, 1088), (1296, 1088), (1088, 1296))))


@pytest.mark.parametrize("stride", [0, 4])
def test_a_packed_float_attribute_is_one_word_a_vertex(tmp_path, stride):
    """GL_UNSIGNED_INT_10F_11F_11F_REV packs three components in one 32-bit
    word: stride 0 is 4 bytes (round 31's R31-4: 12, the vertices past the
    first read as zeros, the triangle gone)."""
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    c = shader_calls(VS)
    c.add("glBufferData", target="GL_ARRAY_BUFFER", size=12, data=PACKED_FLOATS, usage="GL_STATIC_DRAW")
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_UNSIGNED_INT_10F_11F_11F_REV", normalized="GL_FALSE",
          stride=stride, pointer=0)
    assert trace(tmp_path, tagged_draw(c), f"stride_{stride}") == want


VS_OFFSET = ("#version 330 core\nin vec3 p;\nlayout(location = 1) in vec4 off;\n"
             "void main() { gl_Position = vec4((p.x + off.x) / 32.0 - 1.0, (p.y + off.y) / 24.0 - 1.0, 0.0, 1.0); }\n")


def test_packed_and_double_current_values(tmp_path):
    """glVertexAttribP4ui(v) (2_10_10_10: x 6, y 2) gives a disabled
    attribute its value as the float call does (it had been refused); a
    packed type GL does not take there changes nothing."""
    def moved(setter):
        c = shader_calls(VS_OFFSET)
        setter(c)
        c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
        c.add("glEnableVertexAttribArray", index=0)
        c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0,
              pointer=0)
        return trace(tmp_path, tagged_draw(c), "t")
    want = moved(lambda c: c.add("glVertexAttrib4f", index=1, x=6.0, y=2.0, z=0.0, w=1.0))
    assert want != moved(lambda c: None)
    packed = 6 | (2 << 10) | (1 << 30)
    assert moved(lambda c: c.add("glVertexAttribP4ui", index=1, type="GL_UNSIGNED_INT_2_10_10_10_REV",
                                 normalized="GL_FALSE", value=packed)) == want
    assert moved(lambda c: c.add("glVertexAttribP4uiv", index=1, type="GL_INT_2_10_10_10_REV",
                                 normalized="GL_FALSE", value=[packed])) == want
    assert moved(lambda c: c.add("glVertexAttrib4f", index=1, x=6.0, y=2.0, z=0.0, w=1.0)
                 .add("glVertexAttribP4ui", index=1, type="GL_FLOAT", normalized="GL_FALSE", value=0)) == want


# ---- the camera pass's depth buffers (glstate/camera_depth.py)

def depth_frame(steps, fbo_width=64):
    """One frame of depth-tested draws of the triangle (untagged, the second
    at the same depth: GL_LESS keeps only the first where they meet), into
    the window (0) or framebuffer 3, a camera-pass one when fbo_width is the
    screen's: ("clear", fb), ("draw", fb), ("blit", src rect, dst rect,
    filter) from 3 into the window."""
    c = with_fbo(shader_calls(VS), fbo_width).add("glEnable", cap="GL_DEPTH_TEST")
    c.add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0, pointer=0)
    for step in steps:
        if step[0] == "blit":
            blit(c, "GL_DEPTH_BUFFER_BIT", step[1], step[2], filt=step[3])
            continue
        c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=step[1])
        if step[0] == "clear":
            c.add("glClear", mask="GL_DEPTH_BUFFER_BIT")
        else:
            c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3)
    return c.swap()


def converted(tmp_path, c, tag):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    unfollowed = [line for line in r.stdout.splitlines() if "camera-pass depth buffer the converter's cannot be compared with" in line]
    return (tmp_path / f"{tag}.rbt").read_bytes(), unfollowed


BLIT = ("blit", FULL, FULL, "GL_NEAREST")


@pytest.mark.parametrize("steps", [
    # A deferred renderer: its geometry pass's depth copied to the window
    # for the forward pass.
    [("clear", 0), ("clear", 3), ("draw", 3), BLIT, ("draw", 0)],
    # Framebuffer 3 drawn after the window was cleared: the window's
    # cleared depth is given back to the one kept buffer (a C record).
    [("clear", 0), ("clear", 3), ("draw", 3), ("draw", 0)],
    # A copy GL refuses (GL_LINEAR) changes nothing.
    [("clear", 3), ("draw", 3), ("draw", 3), ("blit", FULL, FULL, "GL_LINEAR")],
])
def test_depth_buffers_the_converter_follows(tmp_path, steps):
    trace_bytes, unfollowed = converted(tmp_path, depth_frame(steps), "followed")
    assert trace_bytes.count(b"\nf ") == 0 and unfollowed == []


@pytest.mark.parametrize("steps, fbo_width, words", [
    # Both drawn, then the copy over the window's own depths.
    ([("clear", 3), ("draw", 3), ("clear", 0), ("draw", 0), BLIT, ("draw", 0)], 64,
     "window's depth buffer, whose depths were last written by call"),
    # A copy GL refuses: the window keeps its own depths (round 10's R10-6).
    ([("clear", 0), ("draw", 0), ("clear", 3), ("draw", 3), ("blit", FULL, FULL, "GL_LINEAR"), ("draw", 0)], 64,
     "into the window, while the one depth buffer"),
    # The window drawn, then framebuffer 3 cleared and drawn: the window's
    # depths are gone from the one kept buffer.
    ([("draw", 0), ("clear", 3), ("draw", 3), ("draw", 0)], 64, "into the window, while the one depth buffer"),
    ([("clear", 3), ("draw", 3), ("blit", (0, 0, 20, 48), (0, 0, 20, 48), "GL_NEAREST"), ("draw", 0)], 64,
     "a copy of a rectangle of another's, which the converter does not follow"),
    ([("clear", 3), ("draw", 3), ("blit", (0, 0, 32, 24), FULL, "GL_NEAREST"), ("draw", 0)], 64,
     "a copy moved or scaled"),
    ([("clear", 3), ("draw", 3), ("blit", (0, 0, 32, 48), FULL, "GL_NEAREST"), ("draw", 0)], 32,
     "a copy from another pass"),
])
def test_depth_buffers_the_converter_cannot_follow(tmp_path, steps, fbo_width, words):
    """The one camera-pass depth buffer the converter keeps cannot hold
    what the last draw tests against: the trace is whole (the unit sees
    fragments before the depth test: the copies change no byte of it), and
    the report names the frame and why (--check-depth leaves it out; these
    had been refused, or taken as right: 27% against Mesa)."""
    trace_bytes, unfollowed = converted(tmp_path, depth_frame(steps, fbo_width), "unfollowed")
    assert len(unfollowed) == 1 and unfollowed[0].startswith("1 frames") and words in unfollowed[0], unfollowed
    without_copies, _ = converted(tmp_path, depth_frame([s for s in steps if s[0] != "blit"], fbo_width), "plain")
    assert trace_bytes == without_copies
