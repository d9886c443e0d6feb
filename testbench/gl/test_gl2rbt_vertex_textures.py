"""Vertex shaders that read 2D textures, in captures the tests write (Mesa
runs the vertex shader on the capture's texture images): a triangle moved by
a texel must give the bytes of the same triangle moved by a constant, for
each way GL makes the image (glTexImage2D, glTexStorage2D with
glTexSubImage2D under an odd unpack state, glGenerateMipmap, filtering set
on the texture or overridden by a sampler object, a texture GL calls
incomplete, a deleted one); a reduced capture carries the images and gives
the same bytes; an image the converter cannot give Mesa (rendered into by a
framebuffer or copied from one in a reduced capture that does not carry
it, read from a pixel unpack buffer, shorter than GL reads) is refused
naming the call, nothing left."""
import struct

import pytest

from gl_captures import Calls, gl2rbt_timed as gl2rbt, left_behind, refused
from test_gl2rbt_hostile import shader_calls, shader_draw

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

# The triangle of shader_calls (window units over a 64x48 window), moved by
# the texel's red and green.
VS_TEXEL = ("#version 330 core\nin vec3 p;\nuniform sampler2D heights;\n"
            "void main() { vec4 t = %s;\n"
            "  gl_Position = vec4((p.x + t.r) / 32.0 - 1.0, (p.y + t.g) / 24.0 - 1.0, 0.0, 1.0); }\n")
FETCH = "texelFetch(heights, ivec2(1, 0), 0)"
MIDDLE = "textureLod(heights, vec2(0.5, 0.5), 0.0)"     # between texels 0 and 1
LEVEL_1 = "textureLod(heights, vec2(0.25, 0.5), 1.0)"   # the 1x1 level
VS_MOVED = ("#version 330 core\nin vec3 p;\n"
            "void main() { gl_Position = vec4((p.x + %.1f) / 32.0 - 1.0, (p.y + %.1f) / 24.0 - 1.0, 0.0, 1.0); }\n")
# A 2x1 RGBA32F image: texel 0 (0, 0), texel 1 (6, 2).
TEXELS = struct.pack("<8f", 0, 0, 0, 0, 6, 2, 0, 0)


def draw(c):
    """The triangle of buffer 1 through vertex array 7, object 5, a frame."""
    return shader_draw(c, 7)


def texture(c, name=3, unit=0, filters="GL_NEAREST", image=True):
    c.add("glActiveTexture", texture=f"GL_TEXTURE{unit}")
    c.add("glGenTextures", n=1, textures=[name]).add("glBindTexture", target="GL_TEXTURE_2D", texture=name)
    if image:
        c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2, height=1,
              border=0, format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)
    if filters:
        for pname in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER"):
            c.add("glTexParameteri", target="GL_TEXTURE_2D", pname=pname, param=filters)
    return c


def on_unit(c, unit):
    c.add("glGetUniformLocation", program=2, name="heights", ret=4)
    return c.add("glUniform1i", location=4, v0=unit)


def convert(tmp_path, c, tag, *extra):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz", images=True), "-o", tmp_path / f"{tag}.rbt", *extra)
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return (tmp_path / f"{tag}.rbt").read_bytes()


def moved(tmp_path, dx, dy):
    return convert(tmp_path, draw(shader_calls(VS_MOVED % (dx, dy))), f"moved_{dx}_{dy}")


def test_texel_fetch_from_an_image_of_glteximage2d(tmp_path):
    want = moved(tmp_path, 6, 2)
    assert want.count(b"\nf ") > 100 and want != moved(tmp_path, 0, 0)
    assert convert(tmp_path, draw(texture(shader_calls(VS_TEXEL % FETCH))), "teximage") == want


def test_memory_barriers_change_nothing_drawn(tmp_path):
    """glMemoryBarrier (and its ByRegion form) and glTextureBarrier order
    the GPU's own writes; what those make the converter reads back from
    Mesa's replay, which makes the barriers: passed over (round 13 saw
    every correct image-write-then-sample capture refused at its
    barrier)."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    c.add("glMemoryBarrier", barriers=["GL_SHADER_IMAGE_ACCESS_BARRIER_BIT", "GL_TEXTURE_FETCH_BARRIER_BIT"])
    c.add("glMemoryBarrierByRegion", barriers="GL_ALL_BARRIER_BITS").add("glTextureBarrier")
    assert convert(tmp_path, draw(c), "barriers") == moved(tmp_path, 6, 2)


def test_storage_and_sub_image_under_an_unpack_state_on_another_unit(tmp_path):
    """glTexStorage2D, then glTexSubImage2D of rows 3 texels long after a
    skipped texel, packed to 1-byte alignment, on unit 5 named by the
    sampler's uniform: GL reads texels 1 and 2 of the row."""
    c = shader_calls(VS_TEXEL % FETCH)
    texture(c, unit=5, image=False)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=2, height=1)
    for pname, value in (("GL_UNPACK_ALIGNMENT", 1), ("GL_UNPACK_ROW_LENGTH", 3), ("GL_UNPACK_SKIP_PIXELS", 1)):
        c.add("glPixelStorei", pname=pname, param=value)
    c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
          format="GL_RGBA", type="GL_FLOAT", pixels=struct.pack("<4f", 9, 9, 9, 9) + TEXELS)
    c.add("glPixelStorei", pname="GL_UNPACK_ALIGNMENT", param=3)   # GL_INVALID_VALUE: ignored
    assert convert(tmp_path, draw(on_unit(c, 5)), "storage") == moved(tmp_path, 6, 2)


@pytest.mark.parametrize("sampler, want", [(None, (3, 1)), ("GL_NEAREST", (6, 2))])
def test_filtering_of_the_texture_or_of_a_sampler_object(tmp_path, sampler, want):
    """Linear filtering between the two texels gives their mean; a sampler
    object bound to the unit takes the texture's filtering's place."""
    c = texture(shader_calls(VS_TEXEL % MIDDLE), filters="GL_LINEAR")
    if sampler:
        c.add("glGenSamplers", count=1, samplers=[8]).add("glBindSampler", unit=0, sampler=8)
        c.add("glSamplerParameteri", sampler=8, pname="GL_TEXTURE_MAG_FILTER", param=sampler)
        c.add("glSamplerParameteri", sampler=8, pname="GL_TEXTURE_MIN_FILTER", param=sampler)
    assert convert(tmp_path, draw(c), f"filter_{sampler}") == moved(tmp_path, *want)


def test_a_sampler_s_parameters_given_by_the_vector_forms(tmp_path):
    """glSamplerParameteriv and glSamplerParameterfv (apitrace names their
    values `param`, not `params`): filters, a wrap mode and a border colour
    a vertex shader's fetch outside the texture reads (round 31's R31-2:
    refused as 'parameter values that are not a list')."""
    c = texture(shader_calls(VS_TEXEL % "textureLod(heights, vec2(1.5, 0.5), 0.0)"), filters=None)
    c.add("glGenSamplers", count=1, samplers=[8]).add("glBindSampler", unit=0, sampler=8)
    for pname, value in (("GL_TEXTURE_MAG_FILTER", "GL_NEAREST"), ("GL_TEXTURE_MIN_FILTER", "GL_NEAREST"),
                         ("GL_TEXTURE_WRAP_S", "GL_CLAMP_TO_BORDER")):
        c.add("glSamplerParameteriv", sampler=8, pname=pname, param=[value])
    c.add("glSamplerParameterfv", sampler=8, pname="GL_TEXTURE_BORDER_COLOR", param=[3.0, 1.0, 0.0, 0.0])
    assert convert(tmp_path, draw(c), "sampler_v") == moved(tmp_path, 3, 1)


@pytest.mark.parametrize("bias, core, want", [(None, False, (0, 0)), (1.0, False, (3, 1)), (0.0, False, (0, 0)),
                                             (1.0, True, (0, 0))], ids=["none", "one", "zero", "core"])
def test_a_texture_unit_s_lod_bias_moves_a_vertex_shader_s_level(tmp_path, bias, core, want):
    """A compatibility profile's texture unit bias (glTexEnvf(
    GL_TEXTURE_FILTER_CONTROL, GL_TEXTURE_LOD_BIAS, 1)) moves texture()'s
    level in a vertex shader from 0 (texel 0 magnified) to 1 (the mean of
    the two texels): given to Mesa's context (round 16's R16-2: ignored,
    level 0 read where Mesa read level 1). A core profile has no
    glTexEnv (GL_INVALID_OPERATION): nothing changes there."""
    vs = VS_TEXEL % "texture(heights, vec2(0.25, 0.5))"
    c = texture(shader_calls(vs, core=core), filters=None)
    c.add("glTexParameteri", target="GL_TEXTURE_2D", pname="GL_TEXTURE_MIN_FILTER", param="GL_LINEAR_MIPMAP_NEAREST")
    c.add("glTexParameteri", target="GL_TEXTURE_2D", pname="GL_TEXTURE_MAG_FILTER", param="GL_NEAREST")
    c.add("glGenerateMipmap", target="GL_TEXTURE_2D")
    if bias is not None:
        c.add("glTexEnvf", target="GL_TEXTURE_FILTER_CONTROL", pname="GL_TEXTURE_LOD_BIAS", param=bias)
    assert convert(tmp_path, draw(c), f"bias_{bias}_{core}") == moved(tmp_path, *want)


def test_mipmaps_and_what_gl_reads_from_an_incomplete_or_deleted_texture(tmp_path):
    """glGenerateMipmap's 1x1 level is the texels' mean; with the default
    minifying filter and no mipmaps the texture is incomplete, and a deleted
    one leaves the unit's default texture: both read as zeros."""
    c = texture(shader_calls(VS_TEXEL % LEVEL_1), filters=None)
    c.add("glTexParameteri", target="GL_TEXTURE_2D", pname="GL_TEXTURE_MIN_FILTER", param="GL_LINEAR_MIPMAP_NEAREST")
    c.add("glGenerateMipmap", target="GL_TEXTURE_2D")
    assert convert(tmp_path, draw(c), "mipmap") == moved(tmp_path, 3, 1)
    zero = moved(tmp_path, 0, 0)
    assert convert(tmp_path, draw(texture(shader_calls(VS_TEXEL % FETCH), filters=None)), "incomplete") == zero
    c = texture(shader_calls(VS_TEXEL % FETCH)).add("glDeleteTextures", n=1, textures=[3])
    assert convert(tmp_path, draw(c), "deleted") == zero


def test_a_reduced_capture_carries_the_images_with_the_draw(tmp_path):
    """A reduced capture keeps no texture image in its glTexImage2D (a digest
    in its place), but a draw whose vertex shader reads a texture carries
    the calls that made it: converted, the bytes of the capture. (The
    writer's side: test_gl2rbt_shaders.py, on a capture of gl_shaders.c.)
    Without them the draw is refused, naming it; a malformed one too."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    draw(c)
    want = convert(tmp_path, c, "capture")
    unpack = [0, 0, 0, 0, 0, 4, 0, 0]
    made = [(no, fn, list(args), unpack) for no, fn, args, _, _ in c.calls if fn.startswith("glTex")]
    assert [m[1] for m in made] == ["glTexImage2D", "glTexParameteri", "glTexParameteri"]

    def reduced(tag, extra):
        r = Calls()
        r.calls = [(no, fn, args + ([("rbcd-vertex-textures", extra)] if fn == "glDrawArrays" and extra else []),
                    ret, fl) for no, fn, args, ret, fl in c.calls]
        return gl2rbt(tmp_path, r.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")

    r = reduced("carried", [(3, made)])
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "carried.rbt").read_bytes() == want
    refused(reduced("bare", None), "glDrawArrays", "texture 3, which its vertex shader reads: glTexImage2D (call",
            "pixels are not in the reduced capture")
    refused(reduced("bad", [(3, [made[0][:3]])]), "glDrawArrays", "not (call, name, arguments, unpack state)")
    refused(reduced("bad2", "x"), "glDrawArrays", "its rbcd-vertex-textures (the reduced capture's): not a list")
    assert left_behind(tmp_path, ["capture.xz", "capture.rbt", "carried.xz", "carried.rbt", "bare.xz", "bad.xz",
                                  "bad2.xz"]) == []


def unpack_buffer(c):
    c.add("glGenBuffers", n=1, buffers=[9]).add("glBindBuffer", target="GL_PIXEL_UNPACK_BUFFER", buffer=9)
    c.add("glBufferData", target="GL_PIXEL_UNPACK_BUFFER", size=32, data=TEXELS, usage="GL_STATIC_DRAW")
    c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2, height=1,
          border=0, format="GL_RGBA", type="GL_FLOAT", pixels=0)
    return c.add("glBindBuffer", target="GL_PIXEL_UNPACK_BUFFER", buffer=0)


@pytest.mark.parametrize("make, words", [
    (lambda c: c.add("glGenFramebuffers", n=1, framebuffers=[6]).add("glBindFramebuffer", target="GL_FRAMEBUFFER",
                                                                     framebuffer=6)
     .add("glFramebufferTexture2D", target="GL_FRAMEBUFFER", attachment="GL_COLOR_ATTACHMENT0",
          textarget="GL_TEXTURE_2D", texture=3, level=0)
     .add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=0),
     ("attaches it to framebuffer 6", "a reduced capture carries only the images a conversion of the capture")),
    (lambda c: c.add("glCopyTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, x=0, y=0,
                     width=2, height=1), ("copies the framebuffer into it", "a reduced capture carries only")),
    (unpack_buffer, ("pixel unpack buffer 9",)),
    (lambda c: c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
                     format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS[:31]), ("31 bytes of pixels, 32 read by GL",)),
], ids=["framebuffer", "copy", "unpack_buffer", "short_pixels"])
def test_images_the_converter_cannot_give_mesa_are_refused(tmp_path, make, words):
    """A texture the GPU renders, read by a vertex shader, in a reduced
    capture that does not carry its image (a capture's conversion reads it
    back from Mesa's replay: test_gl2rbt_shaders' "rendered" fault); pixels
    from a pixel unpack buffer, or shorter than GL reads."""
    c = make(texture(shader_calls(VS_TEXEL % FETCH)))
    r = gl2rbt(tmp_path, draw(c).write(tmp_path / "x.xz", images=True), "-o", tmp_path / "x.rbt", "--geometry", tmp_path / "x.geo")
    refused(r, *words)
    assert left_behind(tmp_path, ["x.xz"]) == []


def test_a_texture_past_what_mesa_is_given_is_refused(tmp_path):
    """glTexStorage2D of 16384 x 16384 floats and no pixels: 4 GiB in Mesa."""
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=16384,
          height=16384)
    r = gl2rbt(tmp_path, draw(c).write(tmp_path / "x.xz", images=True), "-o", tmp_path / "x.rbt")
    refused(r, "glDrawArrays", "texture 3", "more than 1 GiB")
    assert left_behind(tmp_path, ["x.xz"]) == []


def test_a_texture_of_more_calls_than_kept_is_refused_when_read(tmp_path):
    """4,097 one-texel writes to distinct texels of one texture: past the
    calls kept for a texture; refused only at a draw that reads it."""
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=4097, height=1)
    for x in range(4097):
        c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=x, yoffset=0, width=1, height=1,
              format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS[16:])
    c.swap()   # a frame that reads nothing converts
    r = gl2rbt(tmp_path, c.write(tmp_path / "ok.xz", images=True), "-o", tmp_path / "ok.rbt")
    assert r.returncode == 0, r.stderr
    r = gl2rbt(tmp_path, draw(c).write(tmp_path / "x.xz", images=True), "-o", tmp_path / "x.rbt")
    refused(r, "glDrawArrays", "texture 3", "4096 calls for one texture")
    assert left_behind(tmp_path, ["ok.xz", "ok.rbt", "x.xz"]) == []


def test_a_texture_rewritten_every_frame_keeps_what_it_holds(tmp_path):
    """Calls GL certainly takes replace those they overwrite: 3,000 frames
    that define the level again and write its rectangle (more calls than a
    texture keeps) read as the last of them."""
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False)
    for i in range(3000):
        c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2, height=1,
              border=0, format="GL_RGBA", type="GL_FLOAT", pixels=bytes(32))
        c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
              format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS if i == 2999 else bytes(32))
        c.swap()
    assert convert(tmp_path, draw(c), "rewritten", "--frames", "3000:3000") == moved(tmp_path, 6, 2)


# ---- direct state access (GL 4.5) on textures, framebuffers, renderbuffers

def created_texture_3(c):
    """Texture 3 made by glCreateTextures, its storage, texels and filters
    given by name."""
    c.add("glCreateTextures", target="GL_TEXTURE_2D", n=1, textures=[3])
    c.add("glTextureStorage2D", texture=3, levels=1, internalformat="GL_RGBA32F", width=2, height=1)
    c.add("glTextureSubImage2D", texture=3, level=0, xoffset=0, yoffset=0, width=2, height=1, format="GL_RGBA",
          type="GL_FLOAT", pixels=TEXELS)
    for pname in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER"):
        c.add("glTextureParameteri", texture=3, pname=pname, param="GL_NEAREST")
    return c


def test_a_texture_made_by_direct_state_access(tmp_path):
    """glCreateTextures, glTextureStorage2D, glTextureSubImage2D and
    glTextureParameteri, bound with glBindTextureUnit: the image of
    glTexImage2D; the same calls on a name that is no texture do nothing."""
    c = shader_calls(VS_TEXEL % FETCH)
    created_texture_3(c)
    c.add("glTextureSubImage2D", texture=8, level=0, xoffset=0, yoffset=0, width=2, height=1, format="GL_RGBA",
          type="GL_FLOAT", pixels=TEXELS[::-1])   # texture 8 does not exist: GL_INVALID_OPERATION
    c.add("glBindTextureUnit", unit=0, texture=3)
    assert convert(tmp_path, draw(c), "dsa") == moved(tmp_path, 6, 2)


def test_a_created_texture_is_bound_after_a_later_glgentextures(tmp_path):
    """A texture glCreateTextures made before the capture's first
    glGenTextures is a name a core profile binds (round 31's R31-1: that
    glGenTextures started the set of generated names without it, and every
    later bind of the created texture did nothing)."""
    c = shader_calls(VS_TEXEL % FETCH)
    created_texture_3(c)
    c.add("glGenTextures", n=1, textures=[4]).add("glBindTexture", target="GL_TEXTURE_2D", texture=4)
    c.add("glBindTexture", target="GL_TEXTURE_2D", texture=3)
    assert convert(tmp_path, draw(c), "created_first") == moved(tmp_path, 6, 2)


@pytest.mark.parametrize("image", ["texture", "renderbuffer"])
def test_a_camera_pass_framebuffer_made_by_direct_state_access(tmp_path, image):
    """A framebuffer of the screen's size made with glCreateFramebuffers and
    a depth texture or renderbuffer attached by name: the camera pass, as
    the window is (a draw into another pass would be left out). (Clears by
    name: test_glstate.py.)"""
    def made(c, dsa):
        if dsa:
            c.add("glCreateFramebuffers", n=1, framebuffers=[5])
            if image == "texture":
                c.add("glCreateTextures", target="GL_TEXTURE_2D", n=1, textures=[6])
                c.add("glTextureStorage2D", texture=6, levels=1, internalformat="GL_DEPTH_COMPONENT24", width=64,
                      height=48)
                c.add("glNamedFramebufferTexture", framebuffer=5, attachment="GL_DEPTH_ATTACHMENT", texture=6, level=0)
            else:
                c.add("glCreateRenderbuffers", n=1, renderbuffers=[6])
                c.add("glNamedRenderbufferStorage", renderbuffer=6, internalformat="GL_DEPTH_COMPONENT24", width=64,
                      height=48)
                c.add("glNamedFramebufferRenderbuffer", framebuffer=5, attachment="GL_DEPTH_ATTACHMENT",
                      renderbuffertarget="GL_RENDERBUFFER", renderbuffer=6)
            c.add("glBindFramebuffer", target="GL_FRAMEBUFFER", framebuffer=5)
        return draw(c.add("glEnable", cap="GL_DEPTH_TEST"))

    want = convert(tmp_path, made(shader_calls(VS_MOVED % (0, 0)), False), "window")
    assert want.count(b"\nf ") > 100
    assert convert(tmp_path, made(shader_calls(VS_MOVED % (0, 0)), True), "dsa") == want


def test_multi_binds_of_null_unbind(tmp_path):
    """glBindTextures and glBindSamplers with NULL (GL 4.4, recorded as 0)
    unbind the units they span: the texture's own filtering again, then the
    default texture, read as zeros (they had been refused)."""
    def unbound(what):
        c = texture(shader_calls(VS_TEXEL % MIDDLE), filters="GL_LINEAR")
        c.add("glGenSamplers", count=1, samplers=[8]).add("glBindSampler", unit=0, sampler=8)
        c.add("glSamplerParameteri", sampler=8, pname="GL_TEXTURE_MAG_FILTER", param="GL_NEAREST")
        c.add("glSamplerParameteri", sampler=8, pname="GL_TEXTURE_MIN_FILTER", param="GL_NEAREST")
        c.add("glBindSamplers", first=0, count=2, samplers=0)
        if what == "textures":
            c.add("glBindTextures", first=0, count=2, textures=0)
        return draw(c)

    assert convert(tmp_path, unbound("samplers"), "samplers") == moved(tmp_path, 3, 1)
    assert convert(tmp_path, unbound("textures"), "textures") == moved(tmp_path, 0, 0)


# ---- round 8: formats, modes and forms the capture's driver took

def test_depth_textures_read_as_the_capture_s_profile_reads_them(tmp_path):
    """A depth texture read through a sampler2D in a core profile is (d, 0,
    0, 1) (Mesa's own context is of the compatibility profile, where it is
    (d, d, d, 1): 66% against Mesa)."""
    c = shader_calls(VS_TEXEL % "vec4(8.0, 8.0, 1.0, 1.0) * texelFetch(heights, ivec2(1, 0), 0)")
    texture(c, image=False)
    c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_DEPTH_COMPONENT32F", width=2,
          height=1, border=0, format="GL_DEPTH_COMPONENT", type="GL_FLOAT", pixels=struct.pack("<2f", 0.25, 0.75))
    assert convert(tmp_path, draw(c), "depth") == moved(tmp_path, 6, 0)


def test_extension_enumerants_and_the_ext_image_call(tmp_path):
    """GL_TEXTURE_MAX_ANISOTROPY_EXT on the texture (PyOpenGL's core names
    lack it: the texture had been refused), and glTextureImage2DEXT
    (EXT_direct_state_access: passed over, the texture read as zeros)."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    c.add("glTexParameterf", target="GL_TEXTURE_2D", pname="GL_TEXTURE_MAX_ANISOTROPY_EXT", param=8.0)
    assert convert(tmp_path, draw(c), "aniso") == moved(tmp_path, 6, 2)
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False)
    c.add("glTextureImage2DEXT", texture=3, target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2,
          height=1, border=0, format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)
    assert convert(tmp_path, draw(c), "ext") == moved(tmp_path, 6, 2)


def test_ext_calls_on_texture_0_edit_the_default_texture(tmp_path):
    """glTextureImage2DEXT and glTextureParameteriEXT naming texture 0 give
    the target's default texture its image and filters (Mesa's
    _mesa_lookup_or_create_texture), which a vertex shader reads where
    texture 0 is bound (the calls had done nothing: texels of 0 read)."""
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False, filters=None)
    c.add("glBindTexture", target="GL_TEXTURE_2D", texture=0)
    c.add("glTextureImage2DEXT", texture=0, target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2,
          height=1, border=0, format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)
    for pname in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER"):
        c.add("glTextureParameteriEXT", texture=0, target="GL_TEXTURE_2D", pname=pname, param="GL_NEAREST")
    assert convert(tmp_path, draw(c), "ext_0") == moved(tmp_path, 6, 2)


def view_of_3(c):
    return c.add("glGenTextures", n=1, textures=[4]).add(
        "glTextureView", texture=4, target="GL_TEXTURE_2D", origtexture=3, internalformat="GL_RGBA32F", minlevel=0,
        numlevels=1, minlayer=0, numlayers=1)


def storage_of_3(c):
    """Texture 3 (bound) given immutable storage and the texels."""
    return c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=2,
                 height=1).add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2,
                               height=1, format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)


def test_a_view_gl_refuses_leaves_the_texture_read(tmp_path):
    """A view of a mutable texture is GL_INVALID_OPERATION: nothing
    changes, and the texture is read as before."""
    assert convert(tmp_path, draw(view_of_3(texture(shader_calls(VS_TEXEL % FETCH)))), "view") == moved(tmp_path, 6, 2)


@pytest.mark.parametrize("make, words", [
    (lambda c: view_of_3(storage_of_3(c)), "glTextureView makes texture 4 a view of texture 3"),
    (lambda c: c.add("glPixelTransferf", pname="GL_RED_SCALE", param=0.5)
     .add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2, height=1, border=0,
          format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS), "pixel transfer state (GL_RED_SCALE)"),
    (lambda c: c.add("glGenSamplers", count=1, samplers=[8]).add("glBindSampler", unit=0, sampler=8)
     .add("glSamplerParameterf", sampler=8, pname="GL_TEXTURE_MAX_ANISOTROPY_EXT", param=8.0),
     "filters anisotropically: Mesa 22.3's llvmpipe crashes"),
    (lambda c: c.add("glTexturePageCommitmentEXT", texture=3, level=0, xoffset=0, yoffset=0, zoffset=0, width=2,
                     height=1, depth=1, commit="GL_TRUE"), "glTexturePageCommitmentEXT is not emulated"),
], ids=["view", "pixel_transfer", "anisotropic_sampler", "unhandled_texture_dsa"])
def test_textures_round_8_refuses(tmp_path, make, words):
    """A texture view, pixel transfer state (compatibility profile), a
    sampler filtering anisotropically (Mesa crashed with SIGSEGV on the
    draw), an unhandled direct-state call on a texture: refused naming the
    call (they had converted, reading zeros, or crashed)."""
    c = make(texture(shader_calls(VS_TEXEL % FETCH)))
    r = gl2rbt(tmp_path, draw(c).write(tmp_path / "x.xz", images=True), "-o", tmp_path / "x.rbt")
    refused(r, words)
    assert left_behind(tmp_path, ["x.xz"]) == []


# ---- round 9: calls GL refuses, in the texture path

@pytest.mark.parametrize("bad", [
    dict(fn="glTexImage2D", border=1), dict(fn="glTexImage2D", internalformat=0x1234),
    dict(fn="glTexImage2D", width=16385, pixels=bytes(16385 * 16)),
    dict(fn="glTexSubImage2D", type="GL_UNSIGNED_SHORT_5_6_5"),
    dict(fn="glTexParameteri", pname="GL_TEXTURE_MIN_FILTER", param="GL_REPEAT"),
    # Round 10 (R10-1): what the "plain checks" did not see.
    dict(fn="glTexImage2D", format="GL_RGBA_INTEGER", type="GL_INT"),
    dict(fn="glTexImage2D", internalformat="GL_DEPTH_COMPONENT24"),
    dict(fn="glTexSubImage2D", format="GL_RGBA_INTEGER", type="GL_INT"),
    dict(fn="glTexSubImage2D", xoffset=1),
    dict(fn="glTexStorage2D", levels=5), dict(fn="glTexStorage2D", width=0),
    dict(fn="glTexStorage2D", internalformat="GL_RGBA"),
], ids=["border", "format", "too_wide", "packed_rgba", "filter", "integer_pixels", "depth_format", "integer_part",
        "part_outside", "storage_levels", "storage_width_0", "storage_unsized"])
def test_a_call_gl_refuses_leaves_the_texture_as_it_was(tmp_path, bad):
    """A call GL refuses after a valid one of the same level, rectangle or
    parameter, or storage GL refuses after an image, changes nothing (it
    had taken the valid one's place among the calls kept: 52 to 85%
    against Mesa)."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    fn = bad.pop("fn")
    if fn == "glTexParameteri":
        c.add(fn, target="GL_TEXTURE_2D", **bad)
    elif fn == "glTexStorage2D":
        c.add(fn, **dict(dict(target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=2, height=1),
                         **bad))
    else:
        args = dict(target="GL_TEXTURE_2D", level=0, width=2, height=1, format="GL_RGBA", type="GL_FLOAT",
                    pixels=TEXELS)
        args.update(dict(internalformat="GL_RGBA32F", border=0) if fn == "glTexImage2D" else dict(xoffset=0, yoffset=0))
        args.update(bad)
        c.add(fn, **args)
    assert convert(tmp_path, draw(c), "refused") == moved(tmp_path, 6, 2)


def test_what_a_core_profile_or_desktop_gl_does_not_have_changes_nothing(tmp_path):
    """In a core profile, a luminance image and GL_GENERATE_MIPMAP are
    GL_INVALID_ENUM (Mesa's own compatibility context took them: 43-67%);
    glTexStorage2DEXT is OpenGL ES's alone (Mesa made storage: 52%)."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_LUMINANCE8", width=2, height=1,
          border=0, format="GL_LUMINANCE", type="GL_UNSIGNED_BYTE", pixels=b"\x10\x20")
    c.add("glTexParameteri", target="GL_TEXTURE_2D", pname="GL_GENERATE_MIPMAP", param=1)
    assert convert(tmp_path, draw(c), "core") == moved(tmp_path, 6, 2)
    c = texture(shader_calls(VS_TEXEL % FETCH), image=False)
    c.add("glTexStorage2DEXT", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=2, height=1)
    c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
          format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)
    assert convert(tmp_path, draw(c), "ext") == moved(tmp_path, 0, 0)


def test_a_carried_unpack_state_gl_cannot_hold_is_refused(tmp_path):
    """An alignment of 3 (or a negative skip) in the calls a reduced capture
    carries: Mesa refuses it and reads the pixels with another stride than
    the one checked against their length: the file's error."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    made = [(no, fn, list(args), [0, 0, 0, 0, 0, 3, 0, 0]) for no, fn, args, _, _ in c.calls if fn == "glTexImage2D"]
    draw(c)
    r = Calls()
    r.calls = [(no, fn, args + ([("rbcd-vertex-textures", [(3, made)])] if fn == "glDrawArrays" else []), ret, fl)
               for no, fn, args, ret, fl in c.calls]
    refused(gl2rbt(tmp_path, r.write(tmp_path / "a.xz"), "-o", tmp_path / "a.rbt"), "an unpack state GL cannot hold")


@pytest.mark.parametrize("sampler, fetch, words", [
    ("sampler2DMS", "imageLoad(heights, ivec2(1, 0), 0)",
     ("glDrawArrays", "GL_TEXTURE_2D_MULTISAMPLE, image unit 0", "a reduced capture carries only the images")),
    ("samplerCube", "textureLod(heights, vec3(1.0, 0.0, 0.0), 0.0)",
     ("glDrawArrays", "GL_TEXTURE_CUBE_MAP", "a reduced capture carries only the images")),
], ids=["multisample_image_in_a_reduced_capture", "cube_in_a_reduced_capture"])
def test_textures_of_other_targets_refused(tmp_path, sampler, fetch, words):
    """A cube map, and a multisample texture read as an image, are read
    back from Mesa's replay of a capture (test_gl2rbt_shaders' "cube" and
    "msimage" faults), which a reduced capture that does not carry them
    cannot give: refused naming the draw, nothing left."""
    vs = VS_TEXEL.replace("sampler2D", sampler) % fetch
    if sampler == "sampler2DMS":
        vs = vs.replace("#version 330 core", "#version 420 core").replace(
            "uniform sampler2DMS", "layout(rgba32f) readonly uniform image2DMS")
    c = shader_calls(vs)
    c.add("glActiveTexture", texture="GL_TEXTURE0")
    image = sampler == "sampler2DMS"
    c.add("glGenTextures", n=1, textures=[3]).add("glBindTexture", target="GL_TEXTURE_2D_MULTISAMPLE" if image
                                                  else "GL_TEXTURE_CUBE_MAP", texture=3)
    if image:
        c.add("glBindImageTexture", unit=0, texture=3, level=0, layered="GL_FALSE", layer=0,
              access="GL_READ_ONLY", format="GL_RGBA32F")
    r = gl2rbt(tmp_path, draw(c).write(tmp_path / "x.xz", images=True), "-o", tmp_path / "x.rbt")
    refused(r, *words)
    assert left_behind(tmp_path, ["x.xz"]) == []


def test_calls_gl_refuses_are_not_kept(tmp_path):
    """4,200 sub-images GL refuses (integer pixels into a float image, a
    rectangle outside the level) after a valid image: they change nothing
    and are not kept, so the texture stays under the 4,096 calls kept
    (round 11's R11-9: refused at the draw)."""
    c = texture(shader_calls(VS_TEXEL % FETCH))
    for i in range(2100):
        c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
              format="GL_RGBA_INTEGER", type="GL_INT", pixels=bytes(32))
        c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=1, yoffset=0, width=2, height=1,
              format="GL_RGBA", type="GL_FLOAT", pixels=bytes(32))
    assert convert(tmp_path, draw(c), "refused_many") == moved(tmp_path, 6, 2)


def test_mipmaps_made_again_every_frame_replace_the_last(tmp_path):
    """Storage of two levels, then each of 4,200 frames a new level 0 and
    glGenerateMipmap: each regeneration replaces the one before, so the
    calls kept stay a handful (round 11's R11-8: 81 s for 2,000 frames,
    refused at 4,200); the last frame's level 1 moves the triangle."""
    vs = VS_TEXEL % "textureLod(heights, vec2(0.5, 0.5), 1.0)"
    c = texture(shader_calls(vs), image=False, filters=None)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=2, internalformat="GL_RGBA32F", width=2, height=1)
    for pname in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER"):
        c.add("glTexParameteri", target="GL_TEXTURE_2D", pname=pname, param="GL_NEAREST_MIPMAP_NEAREST"
              if pname == "GL_TEXTURE_MIN_FILTER" else "GL_NEAREST")
    for i in range(4200):
        c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
              format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS if i == 4199 else bytes(32))
        c.add("glGenerateMipmap", target="GL_TEXTURE_2D")
        if i < 4199:
            c.swap()
    # Level 1 is the mean of texels (0, 0) and (6, 2): (3, 1).
    assert convert(tmp_path, draw(c), "mipmaps", "--frames", "4199:4199") == moved(tmp_path, 3, 1)


@pytest.mark.parametrize("target, internal, fmt, kind, layers", [
    ("GL_TEXTURE_2D_MULTISAMPLE", "GL_RGBA32F", "GL_RGBA", "GL_FLOAT", 1),
    ("GL_TEXTURE_2D_MULTISAMPLE", "GL_RGBA32I", "GL_RGBA_INTEGER", "GL_INT", 1),
    ("GL_TEXTURE_2D_MULTISAMPLE", "GL_R32UI", "GL_RGBA_INTEGER", "GL_UNSIGNED_INT", 1),
    ("GL_TEXTURE_2D_MULTISAMPLE", "GL_DEPTH_COMPONENT32F", "GL_RGBA", "GL_FLOAT", 1),
    ("GL_TEXTURE_2D_MULTISAMPLE_ARRAY", "GL_RGBA16F", "GL_RGBA", "GL_FLOAT", 3),
], ids=["float", "int", "uint", "depth", "array"])
@pytest.mark.parametrize("es", [False, True], ids=["gl", "es"])
def test_multisample_images_read_back_are_drawn_sample_by_sample(target, internal, fmt, kind, layers, es):
    """A multisample texture read back from the replay is given to Mesa's
    context (desktop GL's, OpenGL ES's) sample by sample: every sample of
    every layer fetched again from Mesa's copy holds what was read (depth
    in the first component, the components the format lacks as GL's
    defaults)."""
    import ctypes

    import numpy as np

    from rbcd.gl2rbt.mesa import Mesa
    from rbcd.gl2rbt.vertex_textures import VertexTextures
    m = Mesa(es)
    GL = m.gl
    vt = VertexTextures(m)
    vt.no, vt.draw = 1, "glDrawArrays"
    samples, w, h = 4, 3, 2
    n = w * h * layers * samples
    dtype = {"GL_FLOAT": "<f4", "GL_INT": "<i4", "GL_UNSIGNED_INT": "<u4"}[kind]
    values = (np.arange(n * 4).reshape(n, 4) % 97).astype(dtype)
    if "DEPTH" in internal:
        values = (np.arange(n * 4).reshape(n, 4) % 64 / 64.0).astype(dtype)
    mt = int(GL.glGenTextures(1))
    GL.glBindTexture(m.enum(target), mt)
    vt.fill_samples("test", mt, dict(target=target, samples=samples, fixedsamplelocations=1, internalformat=internal,
                                     width=w, height=h, depth=layers * samples, format=fmt, type=kind,
                                     pixels=values.tobytes()))
    prefix = {"GL_FLOAT": "", "GL_INT": "i", "GL_UNSIGNED_INT": "u"}[kind]
    array = target.endswith("ARRAY")
    src = (("#version 320 es\n" if es else "#version 430\n") + "layout(local_size_x = 1) in;\n"
           f"uniform highp {prefix}sampler2DMS{'Array' if array else ''} t;\n"
           f"layout(std430, binding = 0) buffer O {{ highp {prefix}vec4 v[]; }};\n"
           "void main() { ivec3 p = ivec3(gl_GlobalInvocationID); int w = int(gl_NumWorkGroups.x), "
           "h = int(gl_NumWorkGroups.y);\n"
           f"  for (int s = 0; s < {samples}; s++) v[((p.z * {samples} + s) * h + p.y) * w + p.x] = "
           f"texelFetch(t, {'p' if array else 'p.xy'}, s); }}\n")
    sh = GL.glCreateShader(GL.GL_COMPUTE_SHADER)
    GL.glShaderSource(sh, src)
    GL.glCompileShader(sh)
    prog = GL.glCreateProgram()
    GL.glAttachShader(prog, sh)
    GL.glLinkProgram(prog)
    assert GL.glGetProgramiv(prog, GL.GL_LINK_STATUS), GL.glGetProgramInfoLog(prog)
    GL.glUseProgram(prog)
    GL.glUniform1i(GL.glGetUniformLocation(prog, "t"), 0)
    buf = GL.glGenBuffers(1)
    GL.glBindBuffer(GL.GL_SHADER_STORAGE_BUFFER, buf)
    GL.glBufferData(GL.GL_SHADER_STORAGE_BUFFER, n * 16, None, GL.GL_STREAM_READ)
    GL.glBindBufferBase(GL.GL_SHADER_STORAGE_BUFFER, 0, buf)
    # Mesa's entry points called directly (PyOpenGL's wrappers cannot read
    # an OpenGL ES context's version).
    u = ctypes.c_uint
    m.proc("glDispatchCompute", u, u, u)(w, h, layers)
    m.proc("glMemoryBarrier", u)(GL.GL_ALL_BARRIER_BITS)
    map_range = ctypes.CFUNCTYPE(ctypes.c_void_p, u, ctypes.c_ssize_t, ctypes.c_ssize_t, u)(
        m.egl.eglGetProcAddress(b"glMapBufferRange"))
    got = np.frombuffer(ctypes.string_at(map_range(GL.GL_SHADER_STORAGE_BUFFER, 0, n * 16, GL.GL_MAP_READ_BIT),
                                         n * 16), dtype).reshape(n, 4)
    components = {"GL_R32UI": 1, "GL_DEPTH_COMPONENT32F": 1}.get(internal, 4)
    assert np.array_equal(got[:, :components], values[:, :components]), (got, values)


def test_compressed_images_read_back_are_given_back_uncompressed():
    """Texels of a compressed texture read back (as floats) are given to
    Mesa in a format that holds them exactly, sRGB ones in sRGB (round
    12's R12-9: given back in the compressed format, Mesa encoded them
    again, and BPTC, ETC2, S3TC and ASTC blocks came out other: 0%);
    uncompressed formats are their own, and OpenGL ES's table still
    rules there."""
    from rbcd.gl2rbt.rendered_textures import upload_format
    for value, want in ((0x8E8C, "GL_RGBA32F"),        # GL_COMPRESSED_RGBA_BPTC_UNORM
                        (0x8E8D, "GL_SRGB8_ALPHA8"),   # GL_COMPRESSED_SRGB_ALPHA_BPTC_UNORM
                        (0x8DBC, "GL_RGBA32F"),        # GL_COMPRESSED_SIGNED_RED_RGTC1
                        (0x9274, "GL_RGBA32F"),        # GL_COMPRESSED_RGB8_ETC2
                        (0x83F0, "GL_RGBA32F"),        # GL_COMPRESSED_RGB_S3TC_DXT1_EXT
                        (0x93B0, "GL_RGBA32F"),        # GL_COMPRESSED_RGBA_ASTC_4x4_KHR
                        (0x93D0, "GL_SRGB8_ALPHA8"),   # GL_COMPRESSED_SRGB8_ALPHA8_ASTC_4x4_KHR
                        (0x84EA, "GL_LUMINANCE32F_ARB"),   # GL_COMPRESSED_LUMINANCE (read back as (L, 0, 0, 1))
                        (0x8C4B, "GL_SLUMINANCE8_ALPHA8"),   # GL_COMPRESSED_SLUMINANCE_ALPHA
                        (0x84EC, "GL_INTENSITY32F_ARB"),   # GL_COMPRESSED_INTENSITY
                        (0x8814, 0x8814)):             # GL_RGBA32F itself
        assert upload_format(value, "GL_RGBA", "GL_FLOAT", False) == want, hex(value)


def test_opengl_es_packed_images_read_back_in_their_own_types():
    """OpenGL ES reads an RGB565 or RGB10_A2 level back in its own packed
    type (RGBA bytes rounded RGB565's 5 and 6-bit values, and RGB10_A2's
    were refused as a depth format: round 12's R12-11); the converter takes
    those replies and gives them back in the texture's own format."""
    from rbcd.gl2rbt.rendered_textures import READBACK, upload_format
    assert READBACK[(0x1907, 0x8363)] == ("GL_RGB", "GL_UNSIGNED_SHORT_5_6_5", 2)
    assert READBACK[(0x1908, 0x8368)] == ("GL_RGBA", "GL_UNSIGNED_INT_2_10_10_10_REV", 4)
    assert upload_format(0x8D62, "GL_RGB", "GL_UNSIGNED_SHORT_5_6_5", True) == "GL_RGB565"
    assert upload_format(0x8059, "GL_RGBA", "GL_UNSIGNED_INT_2_10_10_10_REV", True) == "GL_RGB10_A2"
    assert upload_format(0x8057, "GL_RGBA", "GL_UNSIGNED_BYTE", True) == "GL_RGB5_A1"   # bytes, rounded back


@pytest.mark.parametrize("es", [False, True], ids=["gl", "es"])
def test_a_vertex_shader_reads_an_image_as_the_texture_holds_it(tmp_path, es):
    """imageLoad of texel 1 of an immutable 2D texture bound to image unit 2
    (desktop GL 4.2, OpenGL ES 3.1, where images in a vertex shader had been
    refused): the triangle moved by the texel."""
    want = moved(tmp_path, 6, 2)
    version = "#version 310 es\nprecision highp float;\n" if es else "#version 420 core\n"
    vs = (version + "in vec3 p;\nlayout(rgba32f, binding = 2) readonly uniform highp image2D heights;\n"
          "void main() { vec4 t = imageLoad(heights, ivec2(1, 0));\n"
          "  gl_Position = vec4((p.x + t.r) / 32.0 - 1.0, (p.y + t.g) / 24.0 - 1.0, 0.0, 1.0); }\n")
    c = shader_calls(vs)
    if es:
        fs = "#version 310 es\nprecision mediump float;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
        c.calls[5] = (6, "eglCreateContext", [("dpy", 1), ("config", 1), ("share_context", 0), (
            "attrib_list", ["EGL_CONTEXT_MAJOR_VERSION", 3, "EGL_CONTEXT_MINOR_VERSION", 1, "EGL_NONE"])], 1, 0)
        c.add("glCreateShader", type="GL_FRAGMENT_SHADER", ret=3)
        c.add("glShaderSource", shader=3, count=1, string=[fs], length=None)
        c.add("glCompileShader", shader=3).add("glAttachShader", program=2, shader=3)
        c.add("glLinkProgram", program=2).add("glUseProgram", program=2)
    c.add("glGenTextures", n=1, textures=[3]).add("glBindTexture", target="GL_TEXTURE_2D", texture=3)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA32F", width=2, height=1)
    c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=2, height=1,
          format="GL_RGBA", type="GL_FLOAT", pixels=TEXELS)
    c.add("glBindTexture", target="GL_TEXTURE_2D", texture=0)
    c.add("glBindImageTexture", unit=2, texture=3, level=0, layered="GL_FALSE", layer=0, access="GL_READ_ONLY",
          format="GL_RGBA32F")
    got = convert(tmp_path, draw(c), "image")
    fragments = [[line for line in t.split(b"\n") if line.startswith(b"f ")] for t in (got, want)]
    assert fragments[0] == fragments[1] and len(fragments[0]) > 100   # (ES: a fragment shader's cost beside)


def test_two_textures_made_for_one_draw_stay_each_on_its_unit(tmp_path):
    """A vertex shader reading texture 3 on unit 0 and texture 5 on unit 1,
    both given to Mesa for the same draw: making the second must not take
    the first's place on unit 0 (it had: the triangle moved by texture 5's
    texel twice)."""
    vs = ("#version 330 core\nin vec3 p;\nuniform sampler2D a;\nuniform sampler2D b;\n"
          "void main() { vec4 t = texelFetch(a, ivec2(1, 0), 0) + texelFetch(b, ivec2(1, 0), 0);\n"
          "  gl_Position = vec4((p.x + t.r) / 32.0 - 1.0, (p.y + t.g) / 24.0 - 1.0, 0.0, 1.0); }\n")
    c = texture(shader_calls(vs), name=3, unit=0)
    c = texture(c, name=5, unit=1, image=False)
    c.add("glTexImage2D", target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA32F", width=2, height=1,
          border=0, format="GL_RGBA", type="GL_FLOAT", pixels=struct.pack("<8f", 0, 0, 0, 0, 4, 1, 0, 0))
    for loc, (uname, unit) in enumerate((("a", 0), ("b", 1))):
        c.add("glGetUniformLocation", program=2, name=uname, ret=loc + 4).add("glUniform1i", location=loc + 4, v0=unit)
    assert convert(tmp_path, draw(c), "two") == moved(tmp_path, 10, 3)


def test_a_core_profile_depth_texture_reads_as_red(tmp_path):
    """A depth texture in a core profile's capture reads (d, 0, 0, 1), its
    swizzle too: Mesa's compatibility context reads (d, d, d, 1) whatever
    GL_DEPTH_TEXTURE_MODE says (round 13's R13-8: the triangle moved by d
    in y as well)."""
    vs = VS_TEXEL % FETCH.replace("ivec2(1, 0)", "ivec2(0, 0)")
    vs = vs.replace("(p.x + t.r)", "(p.x + 8.0 * t.r)").replace("(p.y + t.g)", "(p.y + 8.0 * t.g + 2.0 * t.a)")
    c = shader_calls(vs)
    c.add("glGenTextures", n=1, textures=[3]).add("glBindTexture", target="GL_TEXTURE_2D", texture=3)
    c.add("glTexStorage2D", target="GL_TEXTURE_2D", levels=1, internalformat="GL_DEPTH_COMPONENT32F", width=1,
          height=1)
    c.add("glTexSubImage2D", target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=1, height=1,
          format="GL_DEPTH_COMPONENT", type="GL_FLOAT", pixels=struct.pack("<f", 0.5))
    for pname in ("GL_TEXTURE_MIN_FILTER", "GL_TEXTURE_MAG_FILTER"):
        c.add("glTexParameteri", target="GL_TEXTURE_2D", pname=pname, param="GL_NEAREST")
    assert convert(tmp_path, draw(c), "depth") == moved(tmp_path, 4, 2)   # (d, 0, 0, 1): 8 d in x, 2 in y


def test_an_immutable_texture_read_back_is_immutable():
    """A texture the replay made with storage (its levels' completeness is
    the storage's: an image unit reads level 1 of it) is given to Mesa as
    storage and sub-images (round 13's R13-1: as glTexImage3D levels, level
    1 read as zeros); a mutable one as its levels."""
    from rbcd.gl2rbt.rendered_textures import image_calls
    levels = [(0, 4, 4, 3, "GL_RGBA", "GL_FLOAT", bytes(4 * 4 * 3 * 16)),
              (1, 2, 2, 3, "GL_RGBA", "GL_FLOAT", bytes(2 * 2 * 3 * 16))]
    calls = image_calls(7, "GL_TEXTURE_2D_ARRAY", 0x8814, levels, False, immutable=2)
    assert [c[1] for c in calls] == ["glTexStorage3D", "glTexSubImage3D", "glTexSubImage3D"]
    assert calls[0][2] == dict(target="GL_TEXTURE_2D_ARRAY", levels=2, internalformat=0x8814, width=4, height=4,
                               depth=3)
    assert [c[1] for c in image_calls(7, "GL_TEXTURE_2D_ARRAY", 0x8814, levels, False)] == ["glTexImage3D"] * 2
    cube = [(0, 2, 2, 6, "GL_RGBA", "GL_FLOAT", bytes(2 * 2 * 6 * 16))]
    faces = image_calls(7, "GL_TEXTURE_CUBE_MAP", 0x8814, cube, False, immutable=1)
    assert [c[1] for c in faces] == ["glTexStorage2D"] + ["glTexSubImage2D"] * 6
    assert [len(c[2]["pixels"]) for c in faces[1:]] == [64] * 6
