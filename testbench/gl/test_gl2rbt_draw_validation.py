"""Draws GL refuses for the state they run under, whatever their mode and
arrays, as Mesa 22.3 checks it at each draw: active samplers of different
types on one texture unit (in the program in use, and across a pipeline's
programs), and dual-source blend factors on a draw buffer past the first.
Each capture is written by the test; a refused draw draws nothing and is
counted among the GL errors, as Mesa drops it."""
import json

import pytest

from gl_captures import gl2rbt_timed as gl2rbt
from test_gl2rbt_draw_outcomes import draw
from test_gl2rbt_hostile import shader_calls
from test_gl2rbt_pipelines import MOVED_VS, context, separable

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

# A fragment shader reading a 2D and a cube texture (both active).
TWO_TYPES_FS = ("#version 410 core\n{layout}uniform sampler2D a;\nuniform samplerCube b;\nout vec4 c;\n"
                "void main() {{ c = texture(a, vec2(0.5)) + texture(b, vec3(1.0, 0.0, 0.0)); }}\n")
ONE_TYPE_FS = ("#version 410 core\nuniform sampler2D a;\nuniform sampler2D b;\nout vec4 c;\n"
               "void main() { c = texture(a, vec2(0.5)) + texture(b, vec2(0.25)); }\n")
PLAIN_FS = "#version 410 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"


def fragments(tmp_path, c, tag):
    """Fragments of the converted capture, and the converter's report."""
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return (tmp_path / f"{tag}.rbt").read_bytes().count(b"\nf "), r.stdout + r.stderr


def with_fragment_shader(fs):
    """shader_calls' program 2 (in use) linked with fragment shader fs, its
    samplers' locations asked as the capture asked them (a at 7, b at 9:
    not Mesa's own numbers)."""
    c = context(shader_calls(MOVED_VS))
    at = next(i for i, call in enumerate(c.calls) if call[1] == "glLinkProgram")
    c.calls[at:at] = [(0, "glCreateShader", [("type", "GL_FRAGMENT_SHADER")], 8, 0),
                      (0, "glShaderSource", [("shader", 8), ("count", 1), ("string", [fs]), ("length", None)], None, 0),
                      (0, "glCompileShader", [("shader", 8)], None, 0),
                      (0, "glAttachShader", [("program", 2), ("shader", 8)], None, 0)]
    c.calls = [(i + 1,) + call[1:] for i, call in enumerate(c.calls)]
    c.add("glGetUniformLocation", program=2, name="a", ret=7)
    return c.add("glGetUniformLocation", program=2, name="b", ret=9)


@pytest.mark.parametrize("fs, units, drawn", [
    (TWO_TYPES_FS.format(layout=""), [], False),
    (TWO_TYPES_FS.format(layout=""), [("glUniform1i", 9, 1)], True),
    (TWO_TYPES_FS.format(layout=""), [("glUniform1iv", 9, [3])], True),
    (TWO_TYPES_FS.format(layout=""), [("glUniform1i", 9, 1), ("glUniform1i", 9, 0)], False),
    (TWO_TYPES_FS.format(layout=""), [("glUniform1i", 7, 4), ("glUniform1i", 9, 4)], False),
    # Set through glProgramUniform on a program in use, and by the
    # shader's own binding.
    (TWO_TYPES_FS.format(layout=""), [("glProgramUniform1i", 9, 2)], True),
    (TWO_TYPES_FS.format(layout="").replace("uniform samplerCube", "layout(binding = 5) uniform samplerCube")
     .replace("410", "420"), [], True),
    # A sampler given a float, or a unit past Mesa's 192: GL refuses the
    # call, the unit stays 0.
    (TWO_TYPES_FS.format(layout=""), [("glUniform1f", 9, 1.0)], False),
    (TWO_TYPES_FS.format(layout=""), [("glUniform1i", 9, 192)], False),
    (ONE_TYPE_FS, [], True),
], ids=["both_unit_0", "cube_at_1", "cube_at_3_by_v_form", "cube_at_1_then_0", "both_at_4", "program_uniform",
        "cube_bound_by_the_shader", "float_refused", "unit_past_the_last_refused", "one_type"])
def test_two_types_of_sampler_on_one_unit(tmp_path, fs, units, drawn):
    """Active samplers of different types on one texture unit make every
    draw of the program GL_INVALID_OPERATION (GL 4.6 §11.1.3.11; Mesa's
    check follows every glUniform of a sampler): the draws had been drawn
    (27.17% against Mesa; R21-1). The units are set by the capture's
    locations, which the converter maps by name to Mesa's."""
    c = with_fragment_shader(fs)
    for fn, loc, value in units:
        if fn == "glProgramUniform1i":
            c.add(fn, program=2, location=loc, v0=value)
        elif fn.endswith("v"):
            c.add(fn, location=loc, count=len(value), value=value)
        else:
            c.add(fn, location=loc, v0=value)
    got, report = fragments(tmp_path, draw(c), "samplers")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "active samplers of different types on one texture unit" in report, report


@pytest.mark.parametrize("units, drawn", [
    ({}, True),                    # both at unit 0, which Mesa's pipeline check passes over
    ({"a": 2, "b": 2}, False),
    ({"a": 2, "b": 3}, True),
    ({"a": 2}, True),
], ids=["both_unit_0", "both_at_2", "at_2_and_3", "one_at_2"])
def test_two_types_of_sampler_on_one_unit_of_a_pipeline(tmp_path, units, drawn):
    """A pipeline's validation compares its programs' samplers, unit 0
    aside (Mesa 22.3 _mesa_sampler_uniforms_pipeline_are_valid): the
    fragment stage's 2D and cube samplers on unit 2 fail it."""
    c = separable()
    c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[TWO_TYPES_FS.format(layout="")],
          ret=11)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=11)
    for loc, (uniform, unit) in enumerate(units.items()):
        c.add("glGetUniformLocation", program=11, name=uniform, ret=20 + loc)
        c.add("glProgramUniform1i", program=11, location=20 + loc, v0=unit)
    got, report = fragments(tmp_path, draw(c), "pipeline")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "reads texture unit 2 as a second type of texture" in report, report


def test_a_compute_program_s_samplers_count_in_a_pipeline(tmp_path):
    """A pipeline's compute program is validated with the others: its cube
    sampler on the unit the fragment program reads as 2D fails the
    pipeline (Mesa iterates every stage's program; it had been passed
    over: 27.83% against Mesa; R22-2)."""
    compute = ("#version 430 core\nlayout(local_size_x = 1) in;\nuniform samplerCube k;\nlayout(std430) buffer B { vec4 o; };\n"
               "void main() { o = texture(k, vec3(1.0, 0.0, 0.0)); }\n")
    def pipeline(unit):
        c = separable()
        c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[ONE_TYPE_FS], ret=11)
        c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=11)
        c.add("glCreateShaderProgramv", type="GL_COMPUTE_SHADER", count=1, strings=[compute], ret=12)
        c.add("glUseProgramStages", pipeline=5, stages=["GL_COMPUTE_SHADER_BIT"], program=12)
        c.add("glGetUniformLocation", program=11, name="a", ret=20).add("glProgramUniform1i", program=11, location=20, v0=2)
        c.add("glGetUniformLocation", program=12, name="k", ret=21)
        return draw(c.add("glProgramUniform1i", program=12, location=21, v0=unit))
    drawn, _ = fragments(tmp_path, pipeline(3), "apart")
    refused, report = fragments(tmp_path, pipeline(2), "shared")
    assert drawn > 100 and refused == 0, (drawn, refused, report)
    assert "program 12, in pipeline 5, reads texture unit 2 as a second type of texture" in report, report


@pytest.mark.parametrize("bound, drawn", [(True, False), (False, True)], ids=["bound", "not_bound"])
def test_a_sampler_set_has_the_bound_pipeline_validated_again(tmp_path, bound, drawn):
    """Mesa clears the bound pipeline's validation at every glUniform1i of
    a sampler: a pipeline validated at a draw, its fragment sampler then
    moved onto the unit another stage's program reads as another type,
    draws nothing at the next draw (it had kept the first validation:
    78.79% against Mesa; R22-1); moved while the pipeline is not bound, the
    pipeline keeps its validation, as Mesa's."""
    c = separable()
    c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[TWO_TYPES_FS.format(layout="")],
          ret=11)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=11)
    c.add("glGetUniformLocation", program=11, name="a", ret=20).add("glGetUniformLocation", program=11, name="b", ret=21)
    c.add("glProgramUniform1i", program=11, location=20, v0=2).add("glProgramUniform1i", program=11, location=21, v0=3)
    draw(c)
    if not bound:
        c.add("glBindProgramPipeline", pipeline=0)
    c.add("glProgramUniform1i", program=11, location=21, v0=2)
    c.add("glBindProgramPipeline", pipeline=5)
    c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3).add("glPopDebugGroup").swap()
    r = gl2rbt(tmp_path, c.write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt", "--summary", tmp_path / "c.jsonl")
    assert r.returncode == 0, r.stderr
    got = [json.loads(line)["fragments"] > 100 for line in (tmp_path / "c.jsonl").read_text().splitlines()]
    assert got == [True, drawn], (got, r.stdout)


def blending(calls):
    """The triangle under a plain fragment shader drawn after `calls`
    ((function, arguments) each), its vertex array object bound before them
    (binding one has Mesa decide again whether draws are valid)."""
    c = with_fragment_shader(PLAIN_FS).add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    for fn, args in calls:
        c.add(fn, **args)
    return draw(c, vao=None)


SRC1 = ("glBlendFunc", dict(sfactor="GL_SRC1_COLOR", dfactor="GL_ONE"))
BOTH = ("glDrawBuffer", dict(mode="GL_FRONT_AND_BACK"))
FBO = ("glCreateFramebuffers", dict(n=1, framebuffers=[3]))   # (a glGen name is no object until bound)
COMPLETE = ("glCheckNamedFramebufferStatus", dict(framebuffer=3, target="GL_FRAMEBUFFER", ret="GL_FRAMEBUFFER_COMPLETE"))
SAMPLER_PROGRAM = [("glCreateShaderProgramv", dict(type="GL_FRAGMENT_SHADER", count=1, strings=[ONE_TYPE_FS], ret=11)),
                   ("glGetUniformLocation", dict(program=11, name="a", ret=20))]
# The same with sampler a at unit 2 from the link (layout(binding = 2)).
BOUND_FS = ONE_TYPE_FS.replace("410", "420").replace("uniform sampler2D a;", "layout(binding = 2) uniform sampler2D a;")
SAMPLER_PROGRAM_BOUND = [("glCreateShaderProgramv", dict(type="GL_FRAGMENT_SHADER", count=1, strings=[BOUND_FS],
                                                         ret=11)),
                         ("glGetUniformLocation", dict(program=11, name="a", ret=20))]


@pytest.mark.parametrize("calls, drawn", [
    ([SRC1], True),
    ([BOTH], True),
    ([BOTH, SRC1], False),
    ([SRC1, BOTH, ("glEnable", dict(cap="GL_BLEND"))], False),
    ([BOTH, ("glDrawBuffer", dict(mode="GL_LEFT")), SRC1], False),
    # Mesa decides at the calls it revalidates at (REVALIDATING), which
    # glDrawBuffer is not: two buffers after the blend still draw, one after
    # it still draws nothing, until a call Mesa revalidates at (R22-4).
    ([BOTH, SRC1, ("glDrawBuffer", dict(mode="GL_BACK"))], False),
    ([SRC1, BOTH], True),
    ([SRC1, BOTH, ("glUseProgram", dict(program=0)), ("glUseProgram", dict(program=2))], False),
    ([BOTH, SRC1, ("glDrawBuffer", dict(mode="GL_BACK")), ("glUseProgram", dict(program=0)),
      ("glUseProgram", dict(program=2))], True),
    ([BOTH, ("glBlendFunci", dict(buf=0, src="GL_SRC1_ALPHA", dst="GL_ONE"))], True),
    ([BOTH, ("glBlendFuncSeparatei", dict(buf=1, srcRGB="GL_ONE", dstRGB="GL_ZERO", srcAlpha="GL_ONE",
                                          dstAlpha="GL_ONE_MINUS_SRC1_ALPHA"))], False),
    ([BOTH, ("glBlendFunci", dict(buf=8, src="GL_SRC1_COLOR", dst="GL_ONE"))], True),
    ([BOTH, SRC1, ("glBlendFunc", dict(sfactor="GL_FRONT", dfactor="GL_ONE"))], False),
    ([BOTH, SRC1, ("glBlendFunc", dict(sfactor="GL_ONE", dfactor="GL_ZERO"))], True),
    ([("glDrawBuffers", dict(n=2, bufs=["GL_NONE", "GL_BACK_LEFT"])), SRC1], False),
    # apitrace writes a 0 in a list of enumerants by the first name it has
    # for 0 (a list with GL_NONE had been refused as GL_INVALID_ENUM; R22-3).
    ([("glDrawBuffers", dict(n=2, bufs=["GL_ZERO", "GL_BACK_LEFT"])), SRC1], False),
    ([BOTH, ("glDrawBuffers", dict(n=2, bufs=["GL_BACK_LEFT", "GL_ZERO"])), SRC1], True),
    ([("glDrawBuffers", dict(n=2, bufs=["GL_BACK_LEFT", "GL_NONE"])), SRC1], True),
    ([("glDrawBuffers", dict(n=2, bufs=["GL_BACK_LEFT", "GL_BACK_LEFT"])), BOTH, SRC1], False),
    ([BOTH, ("glDrawBuffers", dict(n=2, bufs=["GL_BACK_LEFT", "GL_BACK_LEFT"])), SRC1], False),
    ([BOTH, ("glDrawBuffer", dict(mode="GL_RIGHT")), SRC1], False),
    ([("glGenFramebuffers", dict(n=1, framebuffers=[3])), ("glBindFramebuffer", dict(target="GL_FRAMEBUFFER",
                                                                                      framebuffer=3)),
      ("glDrawBuffers", dict(n=2, bufs=["GL_COLOR_ATTACHMENT0", "GL_COLOR_ATTACHMENT1"])),
      ("glBindFramebuffer", dict(target="GL_FRAMEBUFFER", framebuffer=0)), SRC1], True),
    ([("glNamedFramebufferDrawBuffer", dict(framebuffer=0, buf="GL_FRONT_AND_BACK")), SRC1], False),
    # Other calls at which Mesa decides again, on any framebuffer or program
    # (R23-3: draws kept drawing): an image attached, a completeness test, a
    # read framebuffer bound, a sampler of a program not in use moved to
    # another unit; not a glUniform1i that leaves it where it was.
    ([SRC1, BOTH, FBO, ("glNamedFramebufferRenderbuffer", dict(
        framebuffer=3, attachment="GL_COLOR_ATTACHMENT0", renderbuffertarget="GL_RENDERBUFFER", renderbuffer=0))],
     False),
    ([SRC1, BOTH, FBO, ("glCheckNamedFramebufferStatus", dict(framebuffer=3, target="GL_FRAMEBUFFER"))], False),
    # Not at a texture attached, nor at a test of a framebuffer found
    # complete before (Mesa keeps its status).
    ([SRC1, BOTH, FBO, ("glNamedFramebufferTexture", dict(framebuffer=3, attachment="GL_COLOR_ATTACHMENT0",
                                                          texture=0, level=0))], True),
    ([FBO, COMPLETE, SRC1, BOTH, COMPLETE], True),
    ([SRC1, BOTH, FBO, ("glBindFramebuffer", dict(target="GL_READ_FRAMEBUFFER", framebuffer=3))], False),
    ([SRC1, BOTH] + SAMPLER_PROGRAM + [("glProgramUniform1i", dict(program=11, location=20, v0=3))], False),
    ([SRC1, BOTH] + SAMPLER_PROGRAM + [("glProgramUniform1i", dict(program=11, location=20, v0=0))], True),
    # A sampler starts at the unit its layout(binding) gives it (R24-6).
    ([SRC1, BOTH] + SAMPLER_PROGRAM_BOUND + [("glProgramUniform1i", dict(program=11, location=20, v0=2))], True),
    ([SRC1, BOTH] + SAMPLER_PROGRAM_BOUND + [("glProgramUniform1i", dict(program=11, location=20, v0=0))], False),
], ids=["blend_one_buffer", "two_buffers_no_blend", "two_buffers_src1", "blend_enabled_after", "left",
        "back_again", "two_buffers_after_the_blend", "use_program_after", "back_again_then_bind", "src1_on_buffer_0_only", "src1_alpha_on_buffer_1", "buffer_past_the_last_refused",
        "bad_factor_refused", "blend_undone", "none_then_back_left", "back_left_then_none", "zero_then_back_left",
        "back_left_then_zero",
        "a_buffer_twice_refused", "a_buffer_twice_refused_after", "right_refused", "framebuffer_s_own_list",
        "named_window", "attached_elsewhere", "completeness_tested", "texture_attached", "found_complete_again", "read_framebuffer_bound",
        "another_program_s_sampler_moved", "another_program_s_sampler_kept", "bound_sampler_kept",
        "bound_sampler_moved"])
def test_dual_source_blending_on_a_second_draw_buffer(tmp_path, calls, drawn):
    """A blend factor of the second colour output on any draw buffer past
    the first makes the draw GL_INVALID_OPERATION (GL_MAX_DUAL_SOURCE_DRAW_
    BUFFERS is 1 in llvmpipe; Mesa checks the factors whether GL_BLEND is
    enabled or not): two draw buffers with GL_SRC1_COLOR had been drawn
    (27.17% against Mesa; R21-10). The draw buffers are the framebuffer's
    own, counted as Mesa last decided; what GL refuses (a factor, a buffer,
    a list) changes nothing."""
    got, report = fragments(tmp_path, blending(calls), "blend")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "the second colour output" in report, report



# Framebuffer 3 with renderbuffer 5 (64 x 48) attached, found complete by a
# status check, bound for reading before the blend decision.
RB_STORAGE = ("glRenderbufferStorage", dict(target="GL_RENDERBUFFER", internalformat="GL_RGBA8", width=64, height=48))
WITH_IMAGE = [FBO, ("glGenRenderbuffers", dict(n=1, renderbuffers=[5])),
              ("glBindRenderbuffer", dict(target="GL_RENDERBUFFER", renderbuffer=5)), RB_STORAGE,
              ("glNamedFramebufferRenderbuffer", dict(framebuffer=3, attachment="GL_COLOR_ATTACHMENT0",
                                                      renderbuffertarget="GL_RENDERBUFFER", renderbuffer=5))]
READ_3 = ("glBindFramebuffer", dict(target="GL_READ_FRAMEBUFFER", framebuffer=3))
READ_WINDOW = ("glBindFramebuffer", dict(target="GL_READ_FRAMEBUFFER", framebuffer=0))
TEXTURE_4 = [("glGenTextures", dict(n=1, textures=[4])), ("glBindTexture", dict(target="GL_TEXTURE_2D", texture=4))]
TEX_IMAGE = ("glTexImage2D", dict(target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA8", width=64, height=48,
                                  border=0, format="GL_RGBA", type="GL_UNSIGNED_BYTE", pixels=None))
ATTACH_4 = ("glNamedFramebufferTexture", dict(framebuffer=3, attachment="GL_COLOR_ATTACHMENT0", texture=4, level=0))
WITH_TEXTURE = [FBO] + TEXTURE_4 + [TEX_IMAGE, ATTACH_4]
CLEAR = ("glClear", dict(mask="GL_COLOR_BUFFER_BIT"))


def colour_framebuffer(fmt, point="GL_COLOR_ATTACHMENT0", fb=3, rb=5):
    """Framebuffer fb (made) with renderbuffer rb of format fmt, 64 x 48,
    attached at `point`."""
    return [("glCreateFramebuffers", dict(n=1, framebuffers=[fb])),
            ("glGenRenderbuffers", dict(n=1, renderbuffers=[rb])),
            ("glBindRenderbuffer", dict(target="GL_RENDERBUFFER", renderbuffer=rb)),
            ("glRenderbufferStorage", dict(target="GL_RENDERBUFFER", internalformat=fmt, width=64, height=48)),
            ("glNamedFramebufferRenderbuffer", dict(framebuffer=fb, attachment=point,
                                                    renderbuffertarget="GL_RENDERBUFFER", renderbuffer=rb))]


# Renderbuffer 6, a depth buffer of the screen's size, attached to
# framebuffer 3 (made before); framebuffer 3 bound for drawing.
SCREEN_DEPTH = colour_framebuffer("GL_DEPTH_COMPONENT24", "GL_DEPTH_ATTACHMENT", rb=6)[1:]
DRAW_3 = ("glBindFramebuffer", dict(target="GL_DRAW_FRAMEBUFFER", framebuffer=3))


def attach_texture_4(texture=4, level=0, textarget="GL_TEXTURE_2D"):
    return ("glFramebufferTexture2D", dict(target="GL_READ_FRAMEBUFFER", attachment="GL_COLOR_ATTACHMENT1",
                                           textarget=textarget, texture=texture, level=level))


def face_image(face):
    return ("glTexImage2D", dict(target=face, level=0, internalformat="GL_RGBA8", width=64, height=64, border=0,
                                 format="GL_RGBA", type="GL_UNSIGNED_BYTE", pixels=None))


def cube_framebuffer():
    """Framebuffer 3 (bound for reading while cube map 4's +X face is
    attached, then not bound)."""
    faces = [face_image(f"GL_TEXTURE_CUBE_MAP_{s}_{a}") for a in "XYZ" for s in ("POSITIVE", "NEGATIVE")]
    return [FBO, ("glGenTextures", dict(n=1, textures=[4])),
            ("glBindTexture", dict(target="GL_TEXTURE_CUBE_MAP", texture=4))] + faces + [
        READ_3, ("glFramebufferTexture2D", dict(target="GL_READ_FRAMEBUFFER", attachment="GL_COLOR_ATTACHMENT0",
                                                textarget="GL_TEXTURE_CUBE_MAP_POSITIVE_X", texture=4, level=0)),
        READ_WINDOW]


def copy_image(w, h):
    return ("glCopyTexImage2D", dict(target="GL_TEXTURE_2D", level=0, internalformat="GL_RGBA8", x=0, y=0, width=w,
                                     height=h, border=0))


def layered_cube(skip=None):
    """Framebuffer 3 with all of cube map 4 attached (face `skip` never
    given an image)."""
    faces = [face_image(f"GL_TEXTURE_CUBE_MAP_{s}_{a}") for a in "XYZ" for s in ("POSITIVE", "NEGATIVE")]
    return [FBO, ("glGenTextures", dict(n=1, textures=[4])),
            ("glBindTexture", dict(target="GL_TEXTURE_CUBE_MAP", texture=4))] + [
        f for n, f in enumerate(faces) if n != skip] + [ATTACH_4]


def array_layer(layer):
    """Framebuffer 3 with layer `layer` of 2D array texture 4 (2 layers)
    attached."""
    return [FBO, ("glGenTextures", dict(n=1, textures=[4])),
            ("glBindTexture", dict(target="GL_TEXTURE_2D_ARRAY", texture=4)),
            ("glTexImage3D", dict(target="GL_TEXTURE_2D_ARRAY", level=0, internalformat="GL_RGBA8", width=64,
                                  height=48, depth=2, border=0, format="GL_RGBA", type="GL_UNSIGNED_BYTE",
                                  pixels=None)),
            ("glNamedFramebufferTextureLayer", dict(framebuffer=3, attachment="GL_COLOR_ATTACHMENT0", texture=4,
                                                    level=0, layer=layer))]


def depth_stencil_texture(fmt, fmt_type):
    """Texture 4 of depth format fmt (64 x 48) attached to framebuffer 3
    at GL_DEPTH_STENCIL_ATTACHMENT beside its colour image."""
    pixel_format = "GL_DEPTH_STENCIL" if "STENCIL" in fmt else "GL_DEPTH_COMPONENT"
    return WITH_IMAGE + TEXTURE_4 + [("glTexImage2D", dict(
        target="GL_TEXTURE_2D", level=0, internalformat=fmt, width=64, height=48, border=0, format=pixel_format,
        type=fmt_type, pixels=None)), ("glNamedFramebufferTexture", dict(
            framebuffer=3, attachment="GL_DEPTH_STENCIL_ATTACHMENT", texture=4, level=0))]


def multisample_texture(call, samples):
    """Framebuffer 3 with multisample texture 4 (64 x 48, `samples`
    samples, given by `call`) attached."""
    return [FBO, ("glGenTextures", dict(n=1, textures=[4])),
            ("glBindTexture", dict(target="GL_TEXTURE_2D_MULTISAMPLE", texture=4)),
            (call, dict(target="GL_TEXTURE_2D_MULTISAMPLE", samples=samples, internalformat="GL_RGBA8", width=64,
                        height=48, fixedsamplelocations="GL_TRUE")), ATTACH_4]


def multisampled(samples):
    """Framebuffer 3 (not bound) with renderbuffer 5 of `samples` samples."""
    return colour_framebuffer("GL_RGBA8")[:3] + [("glRenderbufferStorageMultisample", dict(
        target="GL_RENDERBUFFER", samples=samples, internalformat="GL_RGBA8", width=64, height=48))] + \
        colour_framebuffer("GL_RGBA8")[4:]


@pytest.mark.parametrize("calls, drawn", [
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH], True),
    # Its status cleared: an attachment, new storage of an attached image,
    # an attached image deleted; the next draw tests it, and decides.
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + TEXTURE_4 + [("glFramebufferTexture2D", dict(
        target="GL_READ_FRAMEBUFFER", attachment="GL_COLOR_ATTACHMENT1", textarget="GL_TEXTURE_2D", texture=4,
        level=0))], False),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glRenderbufferStorage", dict(
        target="GL_RENDERBUFFER", internalformat="GL_RGBA8", width=32, height=24))], False),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, RB_STORAGE], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glDeleteRenderbuffers", dict(n=1, renderbuffers=[5]))], False),
    (WITH_TEXTURE + [COMPLETE, READ_3, SRC1, BOTH, TEX_IMAGE], False),
    (WITH_TEXTURE + [COMPLETE, READ_3, SRC1, BOTH, ("glTexSubImage2D", dict(
        target="GL_TEXTURE_2D", level=0, xoffset=0, yoffset=0, width=1, height=1, format="GL_RGBA",
        type="GL_UNSIGNED_BYTE", pixels=b"\0\0\0\0"))], True),
    (WITH_TEXTURE + [COMPLETE, READ_3, SRC1, BOTH, ("glDeleteTextures", dict(n=1, textures=[4]))], False),
    # Not bound: cleared, but tested only by a status check.
    (WITH_IMAGE + [COMPLETE, SRC1, BOTH, ("glRenderbufferStorage", dict(
        target="GL_RENDERBUFFER", internalformat="GL_RGBA8", width=32, height=24))], True),
    (WITH_IMAGE + [COMPLETE, SRC1, BOTH, ("glRenderbufferStorage", dict(
        target="GL_RENDERBUFFER", internalformat="GL_RGBA8", width=32, height=24)), COMPLETE], False),
    (WITH_TEXTURE + [COMPLETE, SRC1, BOTH, TEX_IMAGE, COMPLETE], False),
    # An incomplete one is tested at every state update a change of
    # buffers flags (glDrawBuffer), a complete one not again.
    ([FBO, READ_3, ("glDrawBuffer", dict(mode="GL_BACK")), SRC1, BOTH], False),
    (WITH_IMAGE + [COMPLETE, READ_3, ("glDrawBuffer", dict(mode="GL_BACK")), SRC1, BOTH], True),
    (WITH_IMAGE + [READ_3, ("glDrawBuffer", dict(mode="GL_BACK")), SRC1, BOTH], False),
    ([FBO, READ_3, ("glClear", dict(mask="GL_DEPTH_BUFFER_BIT")), SRC1, BOTH,
      ("glDrawBuffer", dict(mode="GL_FRONT_AND_BACK"))], False),
    # A read framebuffer bound, unbound or deleted decides nothing when it
    # is complete (R24-2), nor does a status check of one a state update
    # found complete.
    (WITH_IMAGE + [COMPLETE, SRC1, BOTH, READ_3], True),
    (WITH_IMAGE + [COMPLETE, SRC1, BOTH, READ_3, READ_WINDOW], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glDeleteFramebuffers", dict(n=1, framebuffers=[3]))], True),
    (WITH_IMAGE + [READ_3, ("glClear", dict(mask="GL_DEPTH_BUFFER_BIT")), SRC1, BOTH, COMPLETE], True),
    (WITH_IMAGE + [READ_3, SRC1, BOTH, COMPLETE], False),
    # Mesa's own completeness rules the converter follows: incomplete ones
    # are tested again at each change of buffers (R25-1); an answer the
    # capture holds stays until the framebuffer changes (R25-2).
    (colour_framebuffer("GL_DEPTH_COMPONENT24") + [READ_3, CLEAR, SRC1, BOTH], False),
    (colour_framebuffer("GL_RGBA8", "GL_DEPTH_ATTACHMENT") + [READ_3, CLEAR, SRC1, BOTH], False),
    (colour_framebuffer("GL_RGBA8") + [READ_3, CLEAR, SRC1, BOTH], True),
    (colour_framebuffer("GL_RGBA8") + SCREEN_DEPTH
     + colour_framebuffer("GL_STENCIL_INDEX8", "GL_STENCIL_ATTACHMENT", rb=7)[1:]
     + [READ_3, CLEAR, SRC1, BOTH], False),
    (WITH_IMAGE + [("glCheckNamedFramebufferStatus", dict(framebuffer=3, target="GL_FRAMEBUFFER",
                                                          ret="GL_FRAMEBUFFER_INCOMPLETE_ATTACHMENT")),
                   READ_3, CLEAR, SRC1, BOTH], False),
    (colour_framebuffer("GL_RGBA8") + colour_framebuffer("GL_RGBA8", "GL_STENCIL_ATTACHMENT", rb=6)[1:]
     + [READ_3, CLEAR, SRC1, BOTH], False),
    # A status check GL refuses (a target that is no framebuffer's) tests nothing.
    (WITH_IMAGE + [SRC1, BOTH, ("glCheckNamedFramebufferStatus", dict(framebuffer=3, target="GL_TEXTURE_2D",
                                                                      ret=0))], True),
    # A direct state access clear of another framebuffer binds it and the
    # one before again (R25-3); a raster position is a state update (R25-5).
    (WITH_IMAGE + [COMPLETE, SRC1, BOTH, ("glClearNamedFramebufferfv", dict(
        framebuffer=3, buffer="GL_COLOR", drawbuffer=0, value=[0.0, 0.0, 0.0, 0.0]))], False),
    (WITH_IMAGE + [READ_3, ("glRasterPos2f", dict(x=0.0, y=0.0)), SRC1, BOTH, COMPLETE], True),
    # Attachments GL refuses change nothing (R25-6).
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + TEXTURE_4 + [TEX_IMAGE, attach_texture_4(level=100)], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, attach_texture_4(texture=987654)], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + TEXTURE_4 + [
        TEX_IMAGE, attach_texture_4(textarget="GL_TEXTURE_CUBE_MAP_POSITIVE_X")], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + TEXTURE_4 + [("glTexStorage2D", dict(
        target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA8", width=64, height=48)),
        attach_texture_4(level=1)], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + TEXTURE_4 + [("glTexStorage2D", dict(
        target="GL_TEXTURE_2D", levels=2, internalformat="GL_RGBA8", width=64, height=48)),
        attach_texture_4(level=1)], False),
    # Only the attached face's new image clears the status (R25-7); a copy
    # into a level as it was is no new image (R25-8); llvmpipe gives 2
    # samples as 4, so asking 2 again is new storage (R25-9).
    (cube_framebuffer() + [COMPLETE, SRC1, BOTH, face_image("GL_TEXTURE_CUBE_MAP_NEGATIVE_Y"), COMPLETE], True),
    (cube_framebuffer() + [COMPLETE, SRC1, BOTH, face_image("GL_TEXTURE_CUBE_MAP_POSITIVE_X"), COMPLETE], False),
    (WITH_TEXTURE + [COMPLETE, SRC1, BOTH, copy_image(64, 48), COMPLETE], True),
    (WITH_TEXTURE + [COMPLETE, SRC1, BOTH, copy_image(32, 24), COMPLETE], False),
    (multisampled(2) + [COMPLETE, SRC1, BOTH] + multisampled(2)[-2:-1] + [COMPLETE], False),
    (multisampled(4) + [COMPLETE, SRC1, BOTH] + multisampled(4)[-2:-1] + [COMPLETE], True),
    # A multisampled texture alone is computed (complete), as renderbuffers are.
    (multisample_texture("glTexStorage2DMultisample", 4) + [READ_3, CLEAR, SRC1, BOTH], True),
    # A blit tests the two framebuffers it names, bound or not.
    (WITH_TEXTURE + [SRC1, BOTH, ("glBlitNamedFramebuffer", dict(
        readFramebuffer=3, drawFramebuffer=0, srcX0=0, srcY0=0, srcX1=8, srcY1=8, dstX0=0, dstY0=0, dstX1=8, dstY1=8,
        mask="GL_COLOR_BUFFER_BIT", filter="GL_NEAREST"))], False),
    # GL_DEPTH_STENCIL_ATTACHMENT is the depth and the stencil attachment:
    # a depth-only texture there leaves the framebuffer incomplete; a
    # renderbuffer with storage of another format there is GL_INVALID_OPERATION.
    (depth_stencil_texture("GL_DEPTH_COMPONENT24", "GL_UNSIGNED_INT") + [READ_3, CLEAR, SRC1, BOTH], False),
    (depth_stencil_texture("GL_DEPTH24_STENCIL8", "GL_UNSIGNED_INT_24_8") + [READ_3, CLEAR, SRC1, BOTH], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + colour_framebuffer(
        "GL_DEPTH_COMPONENT24", "GL_DEPTH_STENCIL_ATTACHMENT", rb=6)[1:], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH] + colour_framebuffer(
        "GL_DEPTH24_STENCIL8", "GL_DEPTH_STENCIL_ATTACHMENT", rb=6)[1:], False),
    (depth_stencil_texture("GL_DEPTH24_STENCIL8", "GL_UNSIGNED_INT_24_8") + [
        ("glNamedFramebufferTexture", dict(framebuffer=3, attachment="GL_STENCIL_ATTACHMENT", texture=0, level=0)),
        READ_3, CLEAR, SRC1, BOTH], True),
    # Layers, faces and whole cube maps are computed (round 25's v215, a
    # complete layered cube map, had been refused).
    (layered_cube() + [READ_3, CLEAR, SRC1, BOTH], True),
    (layered_cube(skip=5) + [READ_3, CLEAR, SRC1, BOTH], False),
    (array_layer(1) + [READ_3, CLEAR, SRC1, BOTH], True),
    (array_layer(2) + [READ_3, CLEAR, SRC1, BOTH], False),
    # Calls Mesa refuses change nothing (round 26): a buffer texture
    # attached, a renderbuffer name never bound, direct state access on a
    # name that is no framebuffer, a glClear of a bit that names no buffer
    # (no state update: the status check tests and decides).
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glCreateTextures", dict(
        target="GL_TEXTURE_BUFFER", n=1, textures=[8])), ("glNamedFramebufferTexture", dict(
            framebuffer=3, attachment="GL_COLOR_ATTACHMENT1", texture=8, level=0))], True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glGenRenderbuffers", dict(n=1, renderbuffers=[9])),
                   ("glNamedFramebufferRenderbuffer", dict(framebuffer=3, attachment="GL_COLOR_ATTACHMENT1",
                                                           renderbuffertarget="GL_RENDERBUFFER", renderbuffer=9))],
     True),
    (WITH_IMAGE + [COMPLETE, READ_3, SRC1, BOTH, ("glGenFramebuffers", dict(n=1, framebuffers=[4])),
                   ("glNamedFramebufferRenderbuffer", dict(framebuffer=4, attachment="GL_COLOR_ATTACHMENT0",
                                                           renderbuffertarget="GL_RENDERBUFFER", renderbuffer=5)),
                   ("glCheckNamedFramebufferStatus", dict(framebuffer=4, target="GL_FRAMEBUFFER", ret=0))], True),
    (WITH_IMAGE + [READ_3, ("glClear", dict(mask=1)), SRC1, BOTH, COMPLETE], False),
    # An image deleted while only a framebuffer not bound holds it keeps
    # its format (RGBA8 on the depth point: incomplete); a multisample
    # image of no samples is GL_INVALID_VALUE (no image: incomplete).
    (colour_framebuffer("GL_RGBA8", "GL_DEPTH_ATTACHMENT") + [
        ("glDeleteRenderbuffers", dict(n=1, renderbuffers=[5])), READ_3, CLEAR, SRC1, BOTH], False),
    (multisample_texture("glTexImage2DMultisample", 0) + [READ_3, CLEAR, SRC1, BOTH], False),
    # Mesa tests an incomplete framebuffer again at each change of buffers:
    # a face no attachment names completes a layered cube map, and the test
    # after it finds it complete (no test at the draw).
    (layered_cube(skip=5) + [READ_3, CLEAR, face_image("GL_TEXTURE_CUBE_MAP_NEGATIVE_Z"), READ_WINDOW, READ_3,
                             CLEAR, SRC1, BOTH], True),
    (layered_cube(skip=5) + [READ_3, CLEAR, READ_WINDOW, READ_3, CLEAR, SRC1, BOTH], False),
], ids=["control", "texture_attached", "storage_changed", "same_storage", "renderbuffer_deleted",
        "texture_image_given", "texture_sub_image", "texture_deleted", "not_bound_storage_changed",
        "not_bound_checked_again", "not_bound_texture_checked_again", "incomplete_after_draw_buffer",
        "complete_after_draw_buffer", "untested_after_draw_buffer", "incomplete_after_a_clear", "complete_read_bound", "complete_read_unbound",
        "complete_read_deleted", "found_complete_by_a_clear", "untested_checked",
        "depth_format_on_colour", "colour_format_on_depth", "colour_format_complete", "separate_depth_and_stencil",
        "capture_s_incomplete_answer", "colour_format_on_stencil", "check_of_no_framebuffer_target",
        "named_clear_of_another", "raster_position", "level_past_the_last",
        "no_such_texture", "face_of_a_2d_texture", "level_past_immutable_levels", "immutable_level_1",
        "another_face_s_image", "the_attached_face_s_image", "copy_into_the_same_level", "copy_of_another_size",
        "two_samples_again", "four_samples_again", "multisampled_texture_alone", "named_blit",
        "depth_only_texture_at_depth_stencil", "depth_stencil_texture_at_depth_stencil",
        "depth_only_renderbuffer_at_depth_stencil", "depth_stencil_renderbuffer_at_depth_stencil",
        "stencil_detached_after_depth_stencil", "layered_cube_complete", "layered_cube_face_missing",
        "array_layer_inside", "array_layer_past", "buffer_texture_attached", "renderbuffer_never_bound",
        "no_such_framebuffer", "clear_of_no_buffer", "deleted_image_keeps_its_format", "no_samples",
        "completed_by_a_face_not_attached", "still_incomplete"])
def test_a_framebuffer_tested_again_decides(tmp_path, calls, drawn):
    """Mesa keeps each framebuffer object's completeness status: a change
    to its attachments or their images clears it, and the next test (a
    status check, or for a bound framebuffer the next draw's or clear's
    state update after a change of buffers) has Mesa decide again whether
    draws are valid; a complete one bound for reading decides nothing. The
    two draw buffers after the blend decision make the draw refused only
    when Mesa decides again (R24-1 and R24-2: 27.83% against Mesa)."""
    got, report = fragments(tmp_path, blending(calls), "tested")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "the second colour output" in report, report


@pytest.mark.parametrize("fmt, drawn", [("GL_RGBA8", True), ("GL_DEPTH_COMPONENT24", False),
                                         ("GL_RGB9_E5", False)])
def test_a_framebuffer_of_the_screen_s_size_draws_only_when_complete(tmp_path, fmt, drawn):
    """Framebuffer 3, with a depth buffer of the screen's size, is the
    camera pass only when complete: Mesa draws nothing into an incomplete
    one (GL_INVALID_FRAMEBUFFER_OPERATION; round 26's R26-1 had converted
    its draws into the frame)."""
    calls = colour_framebuffer(fmt) + SCREEN_DEPTH + [DRAW_3]
    got, report = fragments(tmp_path, blending(calls), "screen")
    assert (got > 100) == drawn, (got, report)


STORAGE_4 = TEXTURE_4 + [("glTexStorage2D", dict(target="GL_TEXTURE_2D", levels=1, internalformat="GL_RGBA8",
                                                  width=64, height=48))]


def ext_image_4(target):
    return ("glTextureImage2DEXT", dict(texture=4, target=target, level=0, internalformat="GL_RGBA8", width=64,
                                        height=48, border=0, format="GL_RGBA", type="GL_UNSIGNED_BYTE", pixels=None))


def view_8(target, fmt, minlevel, minlayer, numlevels=1):
    """Texture 8 made a view of texture 4 and attached to framebuffer 3."""
    return [("glGenTextures", dict(n=1, textures=[8])), ("glTextureView", dict(
        texture=8, target=target, origtexture=4, internalformat=fmt, minlevel=minlevel, numlevels=numlevels,
        minlayer=minlayer, numlayers=1)), ("glNamedFramebufferTexture", dict(
            framebuffer=3, attachment="GL_COLOR_ATTACHMENT0", texture=8, level=0))]


@pytest.mark.parametrize("colour, outcome", [
    # Texture 4's own storage, of the screen's size: the camera pass.
    (STORAGE_4 + [ATTACH_4], "drawn"),
    # A view of it (R26-6 and R27-1 had left its draws out), of level 1 of
    # a texture twice as large, of a layer of an array texture, in
    # another format of the class: the view's images are the original's.
    (STORAGE_4 + view_8("GL_TEXTURE_2D", "GL_RGBA8", 0, 0), "drawn"),
    ([TEXTURE_4[0], TEXTURE_4[1], ("glTexStorage2D", dict(STORAGE_4[2][1], levels=2, width=128, height=96))]
     + view_8("GL_TEXTURE_2D", "GL_RGBA8", 1, 0), "drawn"),
    (array_layer(0)[1:3] + [("glTexStorage3D", dict(target="GL_TEXTURE_2D_ARRAY", levels=1,
                                                    internalformat="GL_RGBA8", width=64, height=48, depth=2))]
     + view_8("GL_TEXTURE_2D", "GL_R32F", 0, 1), "drawn"),
    # One whose range the converter does not follow (no level): its size
    # is not known, and the pass rests on it.
    (STORAGE_4 + view_8("GL_TEXTURE_2D", "GL_RGBA8", 0, 0, numlevels=0), "refused"),
    # A copy from the read framebuffer (an image the converter cannot tell
    # GL gave): refused, unless Mesa answered the framebuffer complete, the
    # image then there at the size the copy asked.
    (TEXTURE_4 + [copy_image(64, 48), ATTACH_4], "refused"),
    (TEXTURE_4 + [copy_image(64, 48), ATTACH_4, COMPLETE], "drawn"),
    # EXT_direct_state_access's image call at the texture's target, and
    # at another (R29-1: GL_INVALID_OPERATION, no image, incomplete).
    (TEXTURE_4 + [ext_image_4("GL_TEXTURE_2D"), ATTACH_4], "drawn"),
    (TEXTURE_4 + [ext_image_4("GL_TEXTURE_CUBE_MAP_POSITIVE_X"), ATTACH_4], "left out"),
    # A layer of an array texture of the screen's size: another pass, as
    # documented, whatever its size.
    (array_layer(0)[1:], "left out"),
    # A smaller texture, its attachment point given by value (R26-11's
    # m32: the driver takes 0x8CE0 as GL_COLOR_ATTACHMENT0): another pass.
    ([STORAGE_4[0], STORAGE_4[1],
      ("glTexStorage2D", dict(STORAGE_4[2][1], width=32, height=24)),
      ("glNamedFramebufferTexture", dict(framebuffer=3, attachment=0x8CE0, texture=4, level=0))], "left out"),
], ids=["storage", "view", "view_of_level_1", "view_of_a_layer", "view_of_no_level", "copied", "copied_complete",
        "ext_image", "ext_image_of_another_target", "array_layer", "smaller_by_value"])
def test_a_screen_sized_framebuffer_s_colour_texture_decides_the_pass(tmp_path, colour, outcome):
    """Framebuffer 3 with a depth buffer of the screen's size is the camera
    pass when its colour attachment is as large: a texture's size comes
    from the images the converter follows, a view's from the original's,
    and one it does not know is refused in one line naming the texture,
    nothing left (round 26's v410 and round 27's R27-1 had left a view's
    draws out of the frame, where Mesa drew them)."""
    from gl_captures import left_behind, refused
    calls = [FBO] + SCREEN_DEPTH + colour + [DRAW_3]
    c = blending(calls)
    if outcome == "refused":
        r = gl2rbt(tmp_path, c.write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt")
        refused(r, "glDrawArrays", "framebuffer 3 depends on the size of its attachment of texture")
        assert left_behind(tmp_path, ["c.xz"]) == []
    else:
        got, report = fragments(tmp_path, c, "pass")
        assert (got > 100) == (outcome == "drawn"), (got, report)


@pytest.mark.parametrize("colour, drawn", [
    (colour_framebuffer("GL_RGBA8"), True),
    (colour_framebuffer("GL_RGBA8UI"), False),
    (colour_framebuffer("GL_RGB10_A2UI"), False),
    # An integer attachment no draw buffer names counts too (Mesa keeps
    # one bit an attachment).
    (colour_framebuffer("GL_RGBA8") + colour_framebuffer("GL_R32I", "GL_COLOR_ATTACHMENT1", rb=7)[1:], False),
    # A texture whose base level was set: its format still known.
    ([FBO] + TEXTURE_4 + [TEX_IMAGE, ("glTexParameteri", dict(target="GL_TEXTURE_2D", pname="GL_TEXTURE_MAX_LEVEL",
                                                              param=0)),
                          ATTACH_4, COMPLETE], True),
], ids=["rgba8", "rgba8ui", "rgb10_a2ui", "integer_not_drawn", "max_level_set"])
def test_fixed_function_draws_into_an_integer_colour_buffer_are_refused(tmp_path, colour, drawn):
    """In a compatibility profile, a draw with no fragment shader into a
    framebuffer with an integer colour attachment is GL_INVALID_OPERATION
    (EXT_texture_integer; Mesa 22.3's _IntegerBuffers): it draws nothing
    and is counted among the GL errors (R27-2 had converted such draws
    into the frame, 0.00% against Mesa)."""
    from gl_captures import Calls
    c = Calls()
    for fn, args in colour[:1] + SCREEN_DEPTH + colour[1:] + [DRAW_3]:
        c.add(fn, **args)
    got, report = fragments(tmp_path, c.triangle(obj=1).swap(), "integer")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "integer format" in report, report


def test_a_fragment_shader_draws_into_an_integer_colour_buffer(tmp_path):
    """The same integer attachment under a fragment shader (here of a core
    profile's program) draws: only fixed-function fragments cannot write it."""
    calls = colour_framebuffer("GL_RGBA8UI") + SCREEN_DEPTH + [DRAW_3]
    got, report = fragments(tmp_path, blending(calls), "shader")
    assert got > 100, (got, report)


@pytest.mark.parametrize("first_bind", [None, "GL_DEPTH_TEST", "GL_PROXY_TEXTURE_2D", 0x0DE1],
                         ids=["none", "not_a_target", "proxy", "2d_by_value"])
def test_a_bind_gl_refuses_gives_the_texture_no_target(tmp_path, first_bind):
    """glBindTexture of a target GL does not bind (GL_INVALID_ENUM)
    changes nothing: texture 4 bound next as a 2D texture takes its image,
    and framebuffer 3 (of the screen's size) draws (R27-3 had kept the
    refused target, dropped the 2D bind and its image, and left the draws
    out). A target given by value is that target."""
    calls = [FBO, ("glGenTextures", dict(n=1, textures=[4]))]
    if first_bind is not None:
        calls.append(("glBindTexture", dict(target=first_bind, texture=4)))
    calls += [TEXTURE_4[1], TEX_IMAGE, ATTACH_4]
    calls += SCREEN_DEPTH + [DRAW_3]
    got, report = fragments(tmp_path, blending(calls), "bind")
    assert got > 100, (got, report)


def test_a_multisample_depth_buffer_is_left_out_of_the_check(tmp_path):
    """A camera pass into a multisample framebuffer converts, and its frame
    is named as one --check-depth cannot compare (glretrace reads such a
    depth buffer back one sample a pixel: R28-4's 4.31% against Mesa)."""
    depth = [("glGenRenderbuffers", dict(n=1, renderbuffers=[6])),
             ("glBindRenderbuffer", dict(target="GL_RENDERBUFFER", renderbuffer=6)),
             ("glRenderbufferStorageMultisample", dict(target="GL_RENDERBUFFER", samples=4,
                                                       internalformat="GL_DEPTH_COMPONENT24", width=64, height=48)),
             ("glNamedFramebufferRenderbuffer", dict(framebuffer=3, attachment="GL_DEPTH_ATTACHMENT",
                                                     renderbuffertarget="GL_RENDERBUFFER", renderbuffer=6))]
    calls = multisampled(4) + depth + [DRAW_3,
                                       ("glEnable", dict(cap="GL_DEPTH_TEST")),
                                       ("glClear", dict(mask="GL_DEPTH_BUFFER_BIT"))]
    got, report = fragments(tmp_path, blending(calls), "ms")
    assert got > 100 and "framebuffer 3's depth buffer is multisampled" in report, (got, report)


def test_a_reduced_capture_before_version_5_leaves_array_textures_unknown(tmp_path, monkeypatch):
    """A reduced capture of version 4 or earlier kept no glTexImage3D: a 2D
    array texture's attachment read from one has a completeness the
    converter does not compute, and a draw whose validity depends on it
    is refused in one line naming it, nothing left; version 5 keeps the
    call, and the converter computes it (layer 2 of 2: incomplete)."""
    import rbcd.gl2rbt.reduced as reduced
    from gl_captures import left_behind, refused
    c = blending(array_layer(2) + [READ_3, CLEAR, SRC1, BOTH])
    assert fragments(tmp_path, c, "five")[0] == 0
    monkeypatch.setattr(reduced, "REDUCED_HEADER", ("rbcd-reduced-capture", 4, 0))
    r = gl2rbt(tmp_path, c.write(tmp_path / "four.xz"), "-o", tmp_path / "four.rbt")
    refused(r, "glDrawArrays", "a reduced capture of version 4 or earlier")
    assert left_behind(tmp_path, ["five.xz", "five.rbt", "four.xz"]) == []


def test_a_reduced_capture_keeps_blend_factors_and_draw_buffers(tmp_path):
    """A reduced capture of version 4 keeps the blend factors and draw
    buffers, so that it draws as its capture does."""
    from rbcd.gl2rbt.reduced import read_reduced_calls
    names = [call[1] for call in read_reduced_calls(str(blending([BOTH, SRC1]).write(tmp_path / "c.xz")))]
    assert "glDrawBuffer" in names and "glBlendFunc" in names
    assert fragments(tmp_path, blending([BOTH, SRC1]), "refused")[0] == 0


def test_a_draw_buffer_list_not_its_count_is_refused(tmp_path):
    """A glDrawBuffers whose list is not its count is a capture altered
    (apitrace records every buffer the call read): one line naming the
    call, exit 2, nothing left; past GL's 8 buffers GL reads no list."""
    from gl_captures import left_behind, refused
    c = blending([("glDrawBuffers", dict(n=2, bufs=["GL_BACK_LEFT"])), SRC1])
    r = gl2rbt(tmp_path, c.write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt")
    refused(r, "glDrawBuffers", "1 buffers, not its count (2)")
    assert left_behind(tmp_path, ["c.xz"]) == []
    # A tuple is not apitrace's form of the list (round 36's N1: "no
    # buffers, not its count (1)" of a tuple of one).
    c = blending([("glDrawBuffers", dict(n=1, bufs=("GL_BACK_LEFT",))), SRC1])
    r = gl2rbt(tmp_path, c.write(tmp_path / "t.xz"), "-o", tmp_path / "t.rbt")
    refused(r, "glDrawBuffers", "the buffers are ('GL_BACK_LEFT',), not a list (apitrace's form) of 1")
    assert left_behind(tmp_path, ["c.xz", "t.xz"]) == []
    got, _ = fragments(tmp_path, blending([BOTH, ("glDrawBuffers", dict(n=9, bufs=None)), SRC1]), "nine")
    assert got == 0, "GL_INVALID_VALUE: the window's two buffers stay"


MULTIPLY = ("glBlendEquation", dict(mode="GL_MULTIPLY_KHR"))
BLEND = ("glEnable", dict(cap="GL_BLEND"))
SUPPORTING_FS = ("#version 410 core\n#extension GL_KHR_blend_equation_advanced : require\n"
                 "layout(blend_support_multiply) out;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n")


@pytest.mark.parametrize("fs, calls, drawn", [
    (PLAIN_FS, [MULTIPLY], True),
    (PLAIN_FS, [MULTIPLY, BLEND], False),
    (PLAIN_FS, [BLEND, MULTIPLY], False),
    (PLAIN_FS, [BLEND, MULTIPLY, ("glBlendEquation", dict(mode="GL_FUNC_ADD"))], True),
    (PLAIN_FS, [BLEND, ("glBlendEquationSeparate", dict(modeRGB="GL_MULTIPLY_KHR", modeAlpha="GL_FUNC_ADD"))], True),
    (SUPPORTING_FS, [BLEND, MULTIPLY], True),
    (SUPPORTING_FS, [BLEND, ("glBlendEquation", dict(mode="GL_SCREEN_KHR"))], False),
    (SUPPORTING_FS, [BOTH, BLEND, MULTIPLY], False),
    # A separate per-buffer equation on any buffer ends it (Mesa's
    # blend_equation_separatei; R24-4), one mode on another buffer does not.
    (PLAIN_FS, [BLEND, MULTIPLY, ("glBlendEquationSeparatei", dict(buf=1, modeRGB="GL_FUNC_ADD",
                                                                    modeAlpha="GL_FUNC_SUBTRACT"))], True),
    (PLAIN_FS, [BLEND, MULTIPLY, ("glBlendEquationi", dict(buf=1, mode="GL_FUNC_ADD"))], False),
    # A conditional elsewhere in the shader leaves the declaration certain.
    (SUPPORTING_FS.replace("out vec4 c;", "#ifdef GL_FRAGMENT_PRECISION_HIGH\nprecision highp float;\n#endif\n"
                                          "out vec4 c;"), [BLEND, MULTIPLY], True),
    # Only a layout(...) out; declaration counts, not a name that holds the word.
    (PLAIN_FS.replace("out vec4 c;", "out vec4 c;\nfloat blend_support_multiply;"), [BLEND, MULTIPLY], False),
], ids=["blend_off", "enabled_after", "equation_after", "equation_undone", "separate_refused", "declared",
        "another_declared", "two_buffers", "separate_on_another_buffer_ends_it", "one_mode_on_another_buffer",
        "a_conditional_elsewhere", "a_name_is_no_declaration"])
def test_advanced_blending_needs_its_layout_and_one_buffer(tmp_path, fs, calls, drawn):
    """An advanced blend equation (KHR_blend_equation_advanced) with
    blending enabled draws nothing under a fragment shader that does not
    declare it (layout(blend_support_NAME)) or into more than one colour
    buffer (GL_INVALID_OPERATION, Mesa 22.3); glBlendEquation had been
    passed over (27.83% against Mesa; R23-8). glBlendEquationSeparate takes
    no advanced equation (GL_INVALID_ENUM: nothing changes)."""
    c = with_fragment_shader(fs).add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    for fn, args in calls:
        c.add(fn, **args)
    got, report = fragments(tmp_path, draw(c, vao=None), "advanced")
    assert (got > 100) == drawn, (got, report)
    assert drawn or "advanced blending (" in report, report


@pytest.mark.parametrize("fs", [
    SUPPORTING_FS.replace("layout(blend_support_multiply) out;", "#if 0\nlayout(blend_support_multiply) out;\n#endif"),
    SUPPORTING_FS.replace("layout(blend_support_multiply) out;",
                          "#ifdef NOT_DEFINED\nlayout(blend_support_multiply) out;\n#else\n#endif"),
], ids=["if_0", "ifdef"])
def test_blend_support_among_conditionals_is_refused(tmp_path, fs):
    """The text scans keep every branch of a conditional, so a
    blend_support qualifier under #if 0 had been taken as declared (27.83%
    against Mesa; R24-5): a draw whose validity depends on one among
    conditionals is refused in one line, nothing left."""
    from gl_captures import left_behind, refused
    c = with_fragment_shader(fs).add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    for fn, args in [BLEND, MULTIPLY]:
        c.add(fn, **args)
    r = gl2rbt(tmp_path, draw(c, vao=None).write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt")
    refused(r, "glDrawArrays", "blend_support among preprocessor conditionals")
    assert left_behind(tmp_path, ["c.xz"]) == []


def level_range(pname, value):
    return ("glTexParameteri", dict(target="GL_TEXTURE_2D", pname=f"GL_TEXTURE_{pname}_LEVEL", param=value))


# Level 0 of 128 x 96 and level 1 of the screen's size, 64 x 48 (a
# level-1 attachment is then the camera pass when complete).
BIG_0 = ("glTexImage2D", dict(TEX_IMAGE[1], width=128, height=96))
LEVEL_1 = ("glTexImage2D", dict(TEX_IMAGE[1], level=1))


@pytest.mark.parametrize("levels, attached, drawn", [
    ([TEX_IMAGE, level_range("MAX", 0)], 0, True),
    ([TEX_IMAGE, level_range("BASE", 0), level_range("MAX", 0)], 0, True),
    ([BIG_0, LEVEL_1, level_range("BASE", 1)], 1, True),
    ([BIG_0, LEVEL_1, level_range("MAX", 1)], 1, True),
    ([BIG_0, LEVEL_1, level_range("MAX", 0)], 1, True),
    ([BIG_0, LEVEL_1], 1, False),
    ([BIG_0, LEVEL_1, level_range("MAX", 2)], 1, False),
    ([BIG_0, LEVEL_1, level_range("BASE", 1), level_range("MAX", 0)], 1, True),
    ([BIG_0, LEVEL_1, level_range("BASE", -1), level_range("MAX", 1)], 1, True),
], ids=["max_0", "base_0_max_0", "base_1_level_1", "max_1_level_1", "max_0_level_1", "level_1_chain_short",
        "max_2_chain_short", "max_below_base_at_base", "negative_base_refused"])
def test_a_render_target_s_base_and_maximum_levels_are_followed(tmp_path, levels, attached, drawn):
    """A texture render target with GL_TEXTURE_MAX_LEVEL or BASE_LEVEL set
    (engines set the maximum to 0 on their render targets), no status asked
    by the capture: the framebuffer's completeness is computed as Mesa's
    (a level past the base asks for mipmap completeness up to the maximum
    level; test_gl2rbt_completeness compares each rule with Mesa), and its
    draws kept where Mesa draws them (the capture had been refused: "depends
    on the framebuffer's completeness, which the converter does not
    compute")."""
    from gl_captures import Calls
    c = Calls()
    attach = ("glNamedFramebufferTexture", dict(ATTACH_4[1], level=attached))
    for fn, args in [FBO] + TEXTURE_4 + levels + [attach] + SCREEN_DEPTH + [DRAW_3]:
        c.add(fn, **args)
    r = gl2rbt(tmp_path, c.triangle(obj=1).triangle(obj=2).swap().write(tmp_path / "c.xz", images=True), "-o",
               tmp_path / "c.rbt", "--summary", tmp_path / "c.jsonl")
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "c.jsonl").read_text())["draws"] == (2 if drawn else 0), r.stdout


@pytest.mark.parametrize("calls, refused", [
    ([READ_3, CLEAR, SRC1, BOTH], True),
    ([READ_3, CLEAR, SRC1], False),
], ids=["decision_would_change", "decision_unchanged"])
def test_a_completeness_the_converter_does_not_compute_is_refused_where_it_matters(tmp_path, calls, refused):
    """Level 1 of a mutable texture whose base level was set to a value
    the converter does not read as Mesa does (0.5, by glTexParameterf)
    attached: Mesa asks it to be mipmap complete from that base, which the
    converter does not compute, so whether Mesa tests the framebuffer
    again at a change of buffers is not known. Where the test would
    change Mesa's decision the draw is refused in one line naming it
    (R25-1: a wrong guess had drawn what Mesa refused), and where it
    would not, the capture converts."""
    from gl_captures import left_behind
    from gl_captures import refused as refused_line
    level_1 = dict(TEX_IMAGE[1], level=1, width=32, height=24)
    c = blending([FBO] + TEXTURE_4 + [TEX_IMAGE, ("glTexImage2D", level_1), ("glTexParameterf", dict(
        target="GL_TEXTURE_2D", pname="GL_TEXTURE_BASE_LEVEL", param=0.5)), ("glNamedFramebufferTexture", dict(
            framebuffer=3, attachment="GL_COLOR_ATTACHMENT0", texture=4, level=1))] + calls)
    r = gl2rbt(tmp_path, c.write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt")
    if refused:
        refused_line(r, "glDrawArrays", "framebuffer 3's completeness, which the converter does not compute")
        assert left_behind(tmp_path, ["c.xz"]) == []
    else:
        assert r.returncode == 0 and (tmp_path / "c.rbt").read_bytes().count(b"\nf ") > 100, r.stderr
