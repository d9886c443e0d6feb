"""Framebuffer, renderbuffer, texture and buffer names and lifetimes, in
captures the tests write (reduced captures; Mesa runs the vertex shader):
each odd call must give the bytes the same setup without it gives in GL.

- A core profile binds only framebuffer and renderbuffer names glGen* or
  glCreate* returned (another is GL_INVALID_OPERATION in Mesa: the earlier
  binding stays; the converter had switched to it, leaving a draw out).
- A renderbuffer or texture deleted while attached to the bound framebuffer
  is detached there (the framebuffer, with no other attachment, is
  incomplete: Mesa draws nothing; the converter had counted the draw);
  attached to a framebuffer not bound, it lives on for it.
- A buffer texture deleted while bound leaves its unit reading texture 0
  (zeros); a buffer deleted while a buffer texture holds it lives on for
  the texture (the converter had read the deleted texture and dropped the
  buffer's data)."""
import struct

import pytest

from gl_captures import gl2rbt_timed as gl2rbt
from test_gl2rbt_attrib_binding import reference
from test_gl2rbt_hostile import VS, shader_calls

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")


def trace(tmp_path, c, tag):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return (tmp_path / f"{tag}.rbt").read_bytes()


def fragments(t):
    return t.count(b"\nf ")


# ---- names a core profile binds

def fbo(c, fb=3, rb=4, w=64, h=48, texture=False, gen=True):
    """Framebuffer fb, bound, with a w x h depth renderbuffer rb (or depth
    texture rb) as its only attachment; w x h = 64 x 48 is the screen's
    size: the camera pass."""
    if gen:
        c.add("glGenFramebuffers", n=1, framebuffers=[fb])
    c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=fb)
    if texture:
        c.add("glBindTexture", target="GL_TEXTURE_2D", texture=rb)
        c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_DEPTH_COMPONENT24", width=w,
              height=h, border=0, format="GL_DEPTH_COMPONENT", type="GL_UNSIGNED_INT", pixels=None)
        return c.add("glFramebufferTexture2D", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
                     textarget="GL_TEXTURE_2D", texture=rb, level=0)
    if gen:
        c.add("glGenRenderbuffers", n=1, renderbuffers=[rb])
    c.add("glBindRenderbuffer", target="GL_RENDERBUFFER", renderbuffer=rb)
    c.add("glRenderbufferStorage", target="GL_RENDERBUFFER", internalformat="GL_DEPTH_COMPONENT24", width=w,
          height=h)
    return c.add("glFramebufferRenderbuffer", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
                 renderbuffertarget="GL_RENDERBUFFER", renderbuffer=rb)


@pytest.mark.parametrize("attach", ["face", "layered", "slice"])
def test_a_cube_face_or_a_slice_of_the_screen_s_size_is_another_pass(tmp_path, attach):
    """A depth cube map of 64 x 64 (the screen's width, taller than it) with
    a face attached by glFramebufferTexture2D, the whole cube map by
    glFramebufferTexture (layered), or a 3D texture's slice by
    glFramebufferTexture3D (GL 3.0 core; it had been refused): a point
    light's shadow, not the camera pass, so the triangle drawn there is
    left out (round 14's R14-7: a face was taken as the camera pass)."""
    c = shader_calls(VS).add("glGenTextures", n=1, textures=[4])
    target = "GL_TEXTURE_3D" if attach == "slice" else "GL_TEXTURE_CUBE_MAP"
    c.add("glBindTexture", target=target, texture=4)
    if attach == "slice":
        c.add("glTexStorage3D", target=target, levels=1, internalformat="GL_DEPTH_COMPONENT24", width=64, height=64,
              depth=4)
    else:
        c.add("glTexStorage2D", target=target, levels=1, internalformat="GL_DEPTH_COMPONENT24", width=64, height=64)
    c.add("glGenFramebuffers", n=1, framebuffers=[3]).add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=3)
    if attach == "face":
        c.add("glFramebufferTexture2D", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
              textarget="GL_TEXTURE_CUBE_MAP_POSITIVE_Y", texture=4, level=0)
    elif attach == "layered":
        c.add("glFramebufferTexture", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT", texture=4, level=0)
    else:
        c.add("glFramebufferTexture3D", target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
              textarget="GL_TEXTURE_3D", texture=4, level=0, zoffset=2)
    assert fragments(trace(tmp_path, reference(c), attach)) == 0


@pytest.mark.parametrize("how", ["never generated", "deleted"])
def test_a_core_profile_binds_only_generated_framebuffers(tmp_path, how):
    """glBindFramebuffer of a name glGenFramebuffers did not give (the
    capture shows that call for another name) or of one deleted: Mesa
    keeps the window's framebuffer, and the triangle is drawn there."""
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    assert fragments(want) > 100
    c = shader_calls(VS).add("glGenFramebuffers", n=1, framebuffers=[3])
    if how == "deleted":
        c.add("glDeleteFramebuffers", n=1, framebuffers=[3])
    c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=3 if how == "deleted" else 77)
    assert trace(tmp_path, reference(c), "bound") == want
    # A compatibility profile binds any name: an object with no attachment,
    # no camera pass.
    c = shader_calls(VS, core=False).add("glGenFramebuffers", n=1, framebuffers=[3])
    c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=77)
    assert fragments(trace(tmp_path, reference(c), "compat")) == 0


def test_a_capture_that_shows_no_glgenframebuffers_binds_none(tmp_path):
    """An apitrace capture, or a reduced capture of version 2, shows every
    glGenFramebuffers: with none at all, glBindFramebuffer(77) is refused
    and the triangle drawn into the window (the converter had left it out
    as another pass's, and --check-depth had not seen it)."""
    c = shader_calls(VS).add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=77)
    assert trace(tmp_path, reference(c), "nogen") == trace(tmp_path, reference(shader_calls(VS)), "reference")


def test_a_reduced_capture_of_version_1_is_taken_as_it_binds(tmp_path, monkeypatch):
    """A reduced capture written before glGenFramebuffers and
    glGenRenderbuffers were kept (version 1): its binds are taken until it
    shows one (framebuffer 3, the screen's size: the camera pass; 77, no
    attachment: another pass)."""
    from rbcd.gl2rbt import reduced
    monkeypatch.setattr(reduced, "REDUCED_HEADER", ("rbcd-reduced-capture", 1))
    want = trace(tmp_path, reference(shader_calls(VS)), "reference")
    assert trace(tmp_path, reference(fbo(shader_calls(VS), gen=False)), "v1") == want
    c = shader_calls(VS).add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=77)
    assert fragments(trace(tmp_path, reference(c), "v1_77")) == 0


@pytest.mark.parametrize("gen", [False, True])
def test_a_core_profile_binds_only_generated_renderbuffers(tmp_path, gen):
    """glBindRenderbuffer(99), a name never generated, is refused, so the
    glRenderbufferStorage after it re-specifies renderbuffer 4, attached to
    the bound framebuffer: 16 x 16, not the camera pass, nothing drawn
    there. With 99 generated, renderbuffer 4 keeps the screen's size."""
    c = fbo(shader_calls(VS))
    if gen:
        c.add("glGenRenderbuffers", n=1, renderbuffers=[99])
    c.add("glBindRenderbuffer", target="GL_RENDERBUFFER", renderbuffer=99)
    c.add("glRenderbufferStorage", target="GL_RENDERBUFFER", internalformat="GL_DEPTH_COMPONENT24", width=16,
          height=16)
    got = trace(tmp_path, reference(c), "rb")
    if gen:
        assert got == trace(tmp_path, reference(shader_calls(VS)), "reference")
    else:
        assert fragments(got) == 0


# ---- images deleted while attached

@pytest.mark.parametrize("texture", [False, True], ids=["renderbuffer", "texture"])
def test_an_attachment_deleted_while_its_framebuffer_is_bound_is_detached(tmp_path, texture):
    """As glFramebufferRenderbuffer (glFramebufferTexture2D) with 0: the
    framebuffer has no attachment left, is incomplete, and Mesa draws
    nothing (GL_INVALID_FRAMEBUFFER_OPERATION)."""
    detach = "glFramebufferTexture2D" if texture else "glFramebufferRenderbuffer"
    args = dict(textarget="GL_TEXTURE_2D", texture=0, level=0) if texture else \
        dict(renderbuffertarget="GL_RENDERBUFFER", renderbuffer=0)
    want = trace(tmp_path, reference(fbo(shader_calls(VS), texture=texture)
                                     .add(detach, target="GL_FRAMEBUFFER", attachment="GL_DEPTH_ATTACHMENT",
                                          **args)), "detached")
    assert fragments(want) == 0
    c = fbo(shader_calls(VS), texture=texture)
    if texture:
        c.add("glDeleteTextures", n=1, textures=[4])
    else:
        c.add("glDeleteRenderbuffers", n=1, renderbuffers=[4])
    assert trace(tmp_path, reference(c), "deleted") == want


@pytest.mark.parametrize("texture", [False, True], ids=["renderbuffer", "texture"])
def test_an_attachment_deleted_while_its_framebuffer_is_not_bound_lives_on(tmp_path, texture):
    """GL 4.5, 9.2.7 and 9.2.8: the image is not detached from a
    framebuffer that is not bound, and lives on there (5.1.3): framebuffer
    3 is still the camera pass when bound again, even after a new 16 x 16
    object took the name."""
    want = trace(tmp_path, reference(fbo(shader_calls(VS), texture=texture)), "kept")
    assert fragments(want) > 100
    c = fbo(shader_calls(VS), texture=texture).add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=0)
    if texture:
        c.add("glDeleteTextures", n=1, textures=[4]).add("glBindTexture", target="GL_TEXTURE_2D", texture=4)
        c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_DEPTH_COMPONENT24", width=16,
              height=16, border=0, format="GL_DEPTH_COMPONENT", type="GL_UNSIGNED_INT", pixels=None)
    else:
        c.add("glDeleteRenderbuffers", n=1, renderbuffers=[4]).add("glGenRenderbuffers", n=1, renderbuffers=[4])
        c.add("glBindRenderbuffer", target="GL_RENDERBUFFER", renderbuffer=4)
        c.add("glRenderbufferStorage", target="GL_RENDERBUFFER", internalformat="GL_DEPTH_COMPONENT24", width=16,
              height=16)
    c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=3)
    assert trace(tmp_path, reference(c), "deleted") == want


# ---- buffer textures

# The triangle moved by texel 0 of the buffer texture on unit 0.
VS_TB = ("#version 330 core\nin vec3 p;\nuniform samplerBuffer tb;\nvoid main() {\n"
         "  vec2 o = texelFetch(tb, 0).xy;\n"
         "  gl_Position = vec4((p.x + o.x) / 32.0 - 1.0, (p.y + o.y) / 24.0 - 1.0, 0.0, 1.0);\n}\n")
OFFSET = struct.pack("<4f", 12.0, 6.0, 0.0, 0.0)


def buffer_texture(c, tex=8, buf=9, data=OFFSET):
    c.add("glBindBuffer", target="GL_TEXTURE_BUFFER", buffer=buf)
    c.add("glBufferData", target="GL_TEXTURE_BUFFER", size=len(data), data=data, usage="GL_STATIC_DRAW")
    c.add("glBindTexture", target="GL_TEXTURE_BUFFER", texture=tex)
    return c.add("glTexBuffer", target="GL_TEXTURE_BUFFER", internalformat="GL_RGBA32F", buffer=buf)


def two_frames(between):
    """The moved triangle in frame 0; `between(c)`; the triangle again in
    frame 1."""
    c = reference(buffer_texture(shader_calls(VS_TB)))
    between(c)
    c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3).add("glPopDebugGroup")
    return c.swap()


def test_a_buffer_texture_deleted_while_bound_is_read_as_texture_0(tmp_path):
    """GL unbinds a deleted texture from its units: frame 1's texelFetch
    reads zeros (Mesa 22.3), as after the buffer's texel is zeroed; and as
    after glBindTexture(GL_TEXTURE_BUFFER, 0), which Mesa's copy of the
    unit must see too (it had kept the texture an earlier draw bound)."""
    zeroed = trace(tmp_path, two_frames(lambda c: c.add("glBufferSubData", target="GL_TEXTURE_BUFFER", offset=0,
                                                          size=16, data=bytes(16))), "zeroed")
    moved = trace(tmp_path, two_frames(lambda c: None), "moved")
    assert zeroed != moved and fragments(zeroed) > 100
    deleted = trace(tmp_path, two_frames(lambda c: c.add("glDeleteTextures", n=1, textures=[8])), "deleted")
    assert deleted == zeroed
    unbound = trace(tmp_path, two_frames(lambda c: c.add("glBindTexture", target="GL_TEXTURE_BUFFER", texture=0)),
                    "unbound")
    assert unbound == zeroed


def test_the_default_buffer_texture_takes_a_buffer(tmp_path):
    """glTexBuffer with no texture bound at GL_TEXTURE_BUFFER gives the
    default one (name 0) the buffer, and a vertex shader reads it as a
    named one's (Mesa, core profile: no error; round 13 saw it refused);
    glTexBuffer at another target is GL_INVALID_ENUM and sets nothing."""
    moved = trace(tmp_path, two_frames(lambda c: None), "moved")
    default = reference(buffer_texture(shader_calls(VS_TB), tex=0))
    default.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    default.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3).add("glPopDebugGroup").swap()
    assert trace(tmp_path, default, "default") == moved and fragments(moved) > 100
    zeroed = trace(tmp_path, two_frames(lambda c: c.add("glBufferSubData", target="GL_TEXTURE_BUFFER", offset=0,
                                                          size=16, data=bytes(16))), "zeroed")
    # The named texture unbound, another target's glTexBuffer: the default
    # texture has no buffer, and frame 1 reads zeros.
    assert trace(tmp_path, two_frames(lambda c: c.add("glBindTexture", target="GL_TEXTURE_BUFFER", texture=0).add(
        "glTexBuffer", target="GL_TEXTURE_2D", internalformat="GL_RGBA32F", buffer=9)), "other") == zeroed


def test_a_buffer_deleted_while_a_buffer_texture_holds_it_lives_on(tmp_path):
    """GL frees the name, but the texture keeps the data (GL 4.5, 5.1.2;
    Mesa draws with it): frame 1 is moved as frame 0, also after a new
    buffer of zeros took the name."""
    moved = trace(tmp_path, two_frames(lambda c: None), "moved")
    for tag, rebind in (("deleted", False), ("reused", True)):
        def between(c):
            c.add("glDeleteBuffers", n=1, buffers=[9])
            if rebind:
                c.add("glBindBuffer", target="GL_TEXTURE_BUFFER", buffer=9)
                c.add("glBufferData", target="GL_TEXTURE_BUFFER", size=16, data=bytes(16), usage="GL_STATIC_DRAW")
        assert trace(tmp_path, two_frames(between), tag) == moved, tag
