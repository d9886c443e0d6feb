"""Separable programs and program pipelines (GL 4.1, ES 3.1), in captures
the tests write: a pipeline's vertex stage is drawn as the same shader in a
whole program is; its fragment stage decides discard and gl_FragDepth;
glUniform reaches the pipeline's active program; what GL refuses changes
nothing; a program in use wins over the bound pipeline."""
import json

import pytest

from gl_captures import END_FRAME, GLX_CONTEXT_ARGS, TRIANGLE, Calls, gl2rbt_timed as gl2rbt
from test_gl2rbt_draw_outcomes import ES2_VS, draw, trace
from test_gl2rbt_hostile import es_triangle, shader_calls

pytest.importorskip("OpenGL", reason="python3-opengl is missing (scripts/setup.sh --gl)")

# The triangle moved by a uniform (0 leaves it where VS draws it).
MOVED_VS = ("#version 410 core\nin vec3 p;\nuniform float dx;\nout gl_PerVertex { vec4 gl_Position; };\n"
            "void main() { gl_Position = vec4(p.x / 32.0 - 1.0 + dx, p.y / 24.0 - 1.0, 0.0, 1.0); }\n")
DISCARD_FS = ("#version 410 core\nout vec4 c;\n"
              "void main() { if (gl_FragCoord.x > 10.0) discard; c = vec4(1.0); }\n")


def context(c, major=4, minor=5):
    no, fn, _, ret, flags = c.calls[5]
    assert fn == "glXCreateContextAttribsARB"
    c.calls[5] = (no, fn, GLX_CONTEXT_ARGS + [("attrib_list", [
        "GLX_CONTEXT_MAJOR_VERSION_ARB", major, "GLX_CONTEXT_MINOR_VERSION_ARB", minor, "GLX_CONTEXT_PROFILE_MASK_ARB",
        "GLX_CONTEXT_CORE_PROFILE_BIT_ARB", 0])], ret, flags)
    return c


def separable(vs=MOVED_VS, use=False):
    """shader_calls' program 2 made separable before its link, in pipeline
    5's vertex stage (and not in use, unless `use`)."""
    c = context(shader_calls(vs))
    at = next(i for i, call in enumerate(c.calls) if call[1] == "glLinkProgram")
    c.calls.insert(at, (0, "glProgramParameteri", [("program", 2), ("pname", "GL_PROGRAM_SEPARABLE"),
                                                   ("value", 1)], None, 0))
    c.calls = [call for call in c.calls if use or call[1] != "glUseProgram"]
    c.calls = [(i + 1,) + call[1:] for i, call in enumerate(c.calls)]
    c.add("glGenProgramPipelines", n=1, pipelines=[5]).add("glBindProgramPipeline", pipeline=5)
    return c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT"], program=2)


def frames(tmp_path, c, tag):
    r = gl2rbt(tmp_path, c.write(tmp_path / f"{tag}.xz"), "-o", tmp_path / f"{tag}.rbt",
               "--summary", tmp_path / f"{tag}.jsonl")
    assert r.returncode == 0, f"{tag}: {r.stderr}"
    return [json.loads(line) for line in (tmp_path / f"{tag}.jsonl").read_text().splitlines()]


def test_a_pipeline_s_vertex_stage_draws_as_the_program_would(tmp_path):
    whole = trace(tmp_path, draw(context(shader_calls(MOVED_VS))), "whole")
    assert whole.count(b"\nf ") > 100
    assert trace(tmp_path, draw(separable()), "pipeline") == whole
    # A program in use wins over the bound pipeline; glUseProgram(0) gives
    # the draws back to it.
    def other_in_use():
        c = separable()
        c.add("glCreateShader", type="GL_VERTEX_SHADER", ret=8)
        c.add("glShaderSource", shader=8, count=1, string=[MOVED_VS.replace("+ dx", "+ 1.0")], length=None)
        c.add("glCompileShader", shader=8).add("glCreateProgram", ret=9).add("glAttachShader", program=9, shader=8)
        c.add("glBindAttribLocation", program=9, index=0, name="p").add("glLinkProgram", program=9)
        return c.add("glUseProgram", program=9)
    moved = trace(tmp_path, draw(other_in_use()), "in-use")
    assert moved != whole and moved.count(b"\nf ") > 0
    assert trace(tmp_path, draw(other_in_use().add("glUseProgram", program=0)), "back") == whole


def test_uniforms_reach_the_pipeline_s_active_program(tmp_path):
    """glUniform with no program in use sets the bound pipeline's active
    program (glActiveShaderProgram); with none active it does nothing;
    glProgramUniform names the program."""
    base = trace(tmp_path, draw(separable()), "base")
    c = separable().add("glGetUniformLocation", program=2, name="dx", ret=0)
    c.add("glActiveShaderProgram", pipeline=5, program=2).add("glUniform1f", location=0, v0=1.0)
    active = trace(tmp_path, draw(c), "active")
    assert active != base
    c = separable().add("glGetUniformLocation", program=2, name="dx", ret=0)
    assert trace(tmp_path, draw(c.add("glUniform1f", location=0, v0=1.0)), "no-active") == base
    c = separable().add("glGetUniformLocation", program=2, name="dx", ret=0)
    assert trace(tmp_path, draw(c.add("glProgramUniform1f", program=2, location=0, v0=1.0)), "named") == active


def test_what_gl_refuses_in_a_pipeline_changes_nothing(tmp_path):
    """A program not made separable, stage bits GL does not define, a
    pipeline name never generated: the stages stay as they were (here: no
    vertex stage, so a core profile draws nothing); a program deleted while
    a pipeline holds it is drawn until the pipeline lets it go."""
    base = trace(tmp_path, draw(separable()), "base")
    c = context(shader_calls(MOVED_VS))
    c.calls = [(i + 1,) + call[1:] for i, call in enumerate(call for call in c.calls if call[1] != "glUseProgram")]
    c.add("glGenProgramPipelines", n=1, pipelines=[5]).add("glBindProgramPipeline", pipeline=5)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT"], program=2)
    assert trace(tmp_path, draw(c), "not-separable").count(b"\nf ") == 0
    c = separable().add("glUseProgramStages", pipeline=5, stages=0x40, program=0)
    c.add("glUseProgramStages", pipeline=6, stages=["GL_VERTEX_SHADER_BIT"], program=0)
    c.add("glBindProgramPipeline", pipeline=6)
    assert trace(tmp_path, draw(c), "refused") == base
    c = separable().add("glDeleteProgram", program=2)
    assert trace(tmp_path, draw(c), "deleted") == base
    c.add("glUseProgramStages", pipeline=5, stages="GL_ALL_SHADER_BITS", program=0)
    kept, gone = [f["fragments"] for f in frames(tmp_path, draw(c), "let-go")]
    assert kept > 100 and gone == 0


def test_the_fragment_stage_s_program_counts_discards(tmp_path):
    """A fragment program made with glCreateShaderProgramv that can discard:
    the draw counts as one that discards, and as collisionable."""
    c = separable(MOVED_VS.replace("+ dx", ""))
    c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[DISCARD_FS], ret=11)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=11)
    s = frames(tmp_path, draw(c), "discard")[0]
    assert (s["discard_draws"], s["discard_collisionable"]) == (1, 1), s
    plain = frames(tmp_path, draw(separable(MOVED_VS.replace("+ dx", ""))), "plain")[0]
    assert plain.get("discard_draws", 0) == 0 and s["fragments"] == plain["fragments"]


def test_an_opengl_es_pipeline_of_programs_of_one_stage(tmp_path):
    """OpenGL ES 3.1 links a program of one stage only separable: both
    stages from glCreateShaderProgramv draw the triangle the ES 2 whole
    program draws."""
    es_vs = ("#version 310 es\nin vec3 p;\nvoid main() { gl_Position = vec4(p.x / 32.0 - 1.0, "
             "p.y / 24.0 - 1.0, 0.0, 1.0); }\n")
    es_fs = "#version 310 es\nprecision mediump float;\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
    whole = Calls().add("eglCreateContext", dpy=1, config=1, share_context=0,
                        attrib_list=["EGL_CONTEXT_CLIENT_VERSION", 2, "EGL_NONE"], ret=1)
    whole = frames(tmp_path, es_triangle(whole, ES2_VS, TRIANGLE), "whole")
    c = Calls().add("eglCreateContext", dpy=1, config=1, share_context=0,
                    attrib_list=["EGL_CONTEXT_MAJOR_VERSION", 3, "EGL_CONTEXT_MINOR_VERSION", 1, "EGL_NONE"], ret=1)
    c.add("glCreateShaderProgramv", type="GL_VERTEX_SHADER", count=1, strings=[es_vs], ret=3)
    c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[es_fs], ret=4)
    c.add("glGenProgramPipelines", n=1, pipelines=[5]).add("glBindProgramPipeline", pipeline=5)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT"], program=3)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=4)
    c.add("glBindBuffer", target="GL_ARRAY_BUFFER", buffer=1)
    c.add("glBufferData", target="GL_ARRAY_BUFFER", size=36, data=TRIANGLE, usage="GL_STATIC_DRAW")
    c.add("glEnableVertexAttribArray", index=0)
    c.add("glVertexAttribPointer", index=0, size=3, type="GL_FLOAT", normalized="GL_FALSE", stride=0, pointer=0)
    c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3)
    got = frames(tmp_path, c.add("eglSwapBuffers", dpy=1, surface=1, flags=END_FRAME), "es")
    assert got[0]["other"] > 100 and got[0]["other"] == whole[0]["other"], (got, whole)


def test_a_program_in_some_of_its_stages_makes_the_pipeline_draw_nothing(tmp_path):
    """A separable program of a vertex and a fragment shader in the
    pipeline's vertex stage alone, another program in its fragment stage:
    GL_INVALID_OPERATION at the draw, nothing drawn (round 13's R13-3: drawn)."""
    fs = "#version 410 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
    c = separable()
    c.add("glCreateShader", type="GL_FRAGMENT_SHADER", ret=8)
    c.add("glShaderSource", shader=8, count=1, string=[fs], length=None)
    c.add("glCompileShader", shader=8).add("glAttachShader", program=2, shader=8).add("glLinkProgram", program=2)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT"], program=2)
    c.add("glCreateShaderProgramv", type="GL_FRAGMENT_SHADER", count=1, strings=[fs], ret=11)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=11)
    assert trace(tmp_path, draw(c), "invalid").count(b"\nf ") == 0
    c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT", "GL_FRAGMENT_SHADER_BIT"], program=2)
    assert trace(tmp_path, draw(c), "valid").count(b"\nf ") > 100, "the pipeline's second frame draws"


FEEDBACK_VS = MOVED_VS.replace("out gl_PerVertex", "out vec3 q;\nout gl_PerVertex").replace(
    "void main() {", "void main() { q = p;")


def recording_separable(feedback=True):
    """separable(FEEDBACK_VS), recording its output q (when `feedback`)
    into buffer 6, at binding 0 of the default transform feedback object."""
    c = separable(FEEDBACK_VS)
    if feedback:
        at = next(i for i, call in enumerate(c.calls) if call[1] == "glLinkProgram")
        c.calls.insert(at, (0, "glTransformFeedbackVaryings", [("program", 2), ("count", 1), ("varyings", ["q"]),
                                                               ("bufferMode", "GL_INTERLEAVED_ATTRIBS")], None, 0))
        c.calls = [(i + 1,) + call[1:] for i, call in enumerate(c.calls)]
    c.add("glBindBuffer", target="GL_TRANSFORM_FEEDBACK_BUFFER", buffer=6)
    c.add("glBufferData", target="GL_TRANSFORM_FEEDBACK_BUFFER", size=1024, data=None, usage="GL_STREAM_COPY")
    return c.add("glBindBufferBase", target="GL_TRANSFORM_FEEDBACK_BUFFER", index=0, buffer=6)


@pytest.mark.parametrize("feedback", [("q",), ()], ids=["recording", "not_recording"])
def test_use_program_stages_on_the_bound_pipeline_while_recording_changes_nothing(tmp_path, feedback):
    """glUseProgramStages on the pipeline draws run while transform feedback
    records is GL_INVALID_OPERATION (Mesa): the stage keeps its program,
    and the triangle is drawn where it was (it had been drawn by the new
    one, 22.91% against Mesa; R19-3); with nothing recorded it takes the
    new program."""
    def capture(restage):
        c = recording_separable(bool(feedback))
        c.add("glCreateShader", type="GL_VERTEX_SHADER", ret=8)
        c.add("glShaderSource", shader=8, count=1, string=[MOVED_VS.replace("+ dx", "+ 1.0")], length=None)
        c.add("glCompileShader", shader=8).add("glCreateProgram", ret=9).add("glAttachShader", program=9, shader=8)
        c.add("glProgramParameteri", program=9, pname="GL_PROGRAM_SEPARABLE", value=1)
        c.add("glBindAttribLocation", program=9, index=0, name="p").add("glLinkProgram", program=9)
        if feedback:
            c.add("glBeginTransformFeedback", primitiveMode="GL_TRIANGLES")
        if restage:
            c.add("glUseProgramStages", pipeline=5, stages=["GL_VERTEX_SHADER_BIT"], program=9)
        return draw(c)
    kept, restaged = trace(tmp_path, capture(False), "kept"), trace(tmp_path, capture(True), "restaged")
    assert kept.count(b"\nf ") > 100
    assert (kept == restaged) == bool(feedback)


def test_a_pipeline_deleted_while_recording_stays_current(tmp_path):
    """glDeleteProgramPipelines of the bound pipeline while transform
    feedback records: Mesa's unbind of it is GL_INVALID_OPERATION then, so
    it stays current and the next draw is drawn with it (it had drawn
    nothing: 27.17% against Mesa; R19-8); not recording, the draw has no
    pipeline and draws nothing."""
    def capture(recording):
        c = recording_separable()
        if recording:
            c.add("glBeginTransformFeedback", primitiveMode="GL_TRIANGLES")
        return draw(c.add("glDeleteProgramPipelines", n=1, pipelines=[5]))
    assert trace(tmp_path, capture(True), "recording").count(b"\nf ") > 100
    assert trace(tmp_path, capture(False), "idle").count(b"\nf ") == 0


@pytest.mark.parametrize("case", ["lone_use_program_0", "use_program_then_0"],
                         ids=["lone_use_program_0", "use_program_then_0"])
def test_a_pipeline_deleted_while_recording_after_use_program_0(tmp_path, case):
    """After the pipeline deleted while recording (still current) and the
    recording ended: glUseProgram(0) after a program was in use makes
    Mesa bind the current pipeline again by its name, which is free now
    (GL_INVALID_OPERATION), and no pipeline is in effect: the next frame's
    draw draws nothing in a core profile (it had been drawn through the
    deleted pipeline: 38.59% against Mesa; R20-6). A glUseProgram(0) with
    no program in use before changes nothing: the pipeline still draws."""
    c = recording_separable().add("glBeginTransformFeedback", primitiveMode="GL_TRIANGLES")
    draw(c.add("glDeleteProgramPipelines", n=1, pipelines=[5]))
    c.add("glEndTransformFeedback")
    if case == "use_program_then_0":
        c.add("glUseProgram", program=2)
    c.add("glUseProgram", program=0)
    c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
    c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3).add("glPopDebugGroup")
    got = frames(tmp_path, c.swap(), case)
    assert got[0]["fragments"] > 100
    assert (got[1]["fragments"] == 0) == (case == "use_program_then_0"), got


COMPAT_FS = "#version 410 core\nout vec4 c;\nvoid main() { c = vec4(1.0); }\n"
COMPAT_GS = ("#version 410 core\nlayout(triangles) in;\nlayout(triangle_strip, max_vertices = 3) out;\n"
             "in gl_PerVertex { vec4 gl_Position; } gl_in[];\nout gl_PerVertex { vec4 gl_Position; };\n"
             "void main() { for (int i = 0; i < 3; i++) { gl_Position = gl_in[i].gl_Position; EmitVertex(); } }\n")


COMPUTE = "#version 430 core\nlayout(local_size_x = 1) in;\nvoid main() {}\n"


@pytest.mark.parametrize("stages, drawn", [
    ([("GL_FRAGMENT_SHADER", "GL_FRAGMENT_SHADER_BIT", COMPAT_FS)], True),
    ([("GL_COMPUTE_SHADER", "GL_COMPUTE_SHADER_BIT", COMPUTE)], True),
    ([("GL_GEOMETRY_SHADER", "GL_GEOMETRY_SHADER_BIT", COMPAT_GS)], False),
    ([("GL_GEOMETRY_SHADER", "GL_GEOMETRY_SHADER_BIT", COMPAT_GS),
      ("GL_FRAGMENT_SHADER", "GL_FRAGMENT_SHADER_BIT", COMPAT_FS)], False),
    ([], False),
], ids=["fragment_stage", "compute_stage", "geometry_stage", "geometry_and_fragment_stages", "empty"])
def test_a_compatibility_pipeline_validated_for_fixed_function_vertices(tmp_path, stages, drawn):
    """A compatibility context's fixed-function draw (glVertexPointer) with
    a pipeline bound and no program in use: Mesa validates the pipeline
    first (_mesa_validate_program_pipeline). A fragment stage alone draws,
    its vertices fixed-function; a geometry stage with no vertex stage, or
    an empty pipeline, is GL_INVALID_OPERATION and draws nothing (each had
    been drawn, 27.17% against Mesa; R20-5); a compute program in the
    compute stage alone leaves the draw fixed-function (it had been taken
    for a program in some of its stages: nothing drawn; R21-9)."""
    c = Calls()
    c.add("glXCreateContextAttribsARB", dpy=1, config=1, share_context=0, direct=1,
          attrib_list=["GLX_CONTEXT_MAJOR_VERSION_ARB", 4,
          "GLX_CONTEXT_MINOR_VERSION_ARB", 5, "GLX_CONTEXT_PROFILE_MASK_ARB",
          "GLX_CONTEXT_COMPATIBILITY_PROFILE_BIT_ARB", 0], ret=1)
    c.add("glGenProgramPipelines", n=1, pipelines=[5]).add("glBindProgramPipeline", pipeline=5)
    for i, (kind, bit, source) in enumerate(stages):
        c.add("glCreateShaderProgramv", type=kind, count=1, strings=[source], ret=11 + i)
        c.add("glUseProgramStages", pipeline=5, stages=[bit], program=11 + i)
    r = gl2rbt(tmp_path, c.triangle(obj=5).swap().write(tmp_path / "c.xz"), "-o", tmp_path / "c.rbt",
               "--summary", tmp_path / "c.jsonl")
    assert r.returncode == 0, r.stderr
    got = json.loads((tmp_path / "c.jsonl").read_text().splitlines()[0])["fragments"]
    assert (got > 100) == drawn, got
    assert drawn or "draws are GL errors" in r.stdout + r.stderr, r.stdout


def test_a_validated_pipeline_stays_valid_until_its_stages_change(tmp_path):
    """Mesa validates a bound pipeline at a draw and keeps that until
    glUseProgramStages changes it: its vertex program relinked without
    GL_PROGRAM_SEPARABLE still draws (it had drawn nothing: 86.65% against
    Mesa; R21-2); after a glUseProgramStages the next draw validates again,
    and fails."""
    c = draw(separable())

    def again(c):
        c.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=5, length=-1, message="rbcd-object")
        return c.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3).add("glPopDebugGroup").swap()
    c.add("glProgramParameteri", program=2, pname="GL_PROGRAM_SEPARABLE", value=0).add("glLinkProgram", program=2)
    again(c)
    again(c.add("glUseProgramStages", pipeline=5, stages=["GL_FRAGMENT_SHADER_BIT"], program=0))
    got = frames(tmp_path, c, "relinked")
    assert [f["fragments"] > 100 for f in got] == [True, True, False], got


def test_a_compute_program_beside_the_vertex_stage_leaves_the_draw(tmp_path):
    """A pipeline's compute stage is no draw's: with a compute program
    there beside the vertex stage's, the draw is the vertex stage's (it
    had been taken for a program in some of its stages, not all: nothing
    drawn, 27.17% against Mesa; R21-9)."""
    base = trace(tmp_path, draw(separable()), "base")
    c = separable().add("glCreateShaderProgramv", type="GL_COMPUTE_SHADER", count=1, strings=[COMPUTE], ret=11)
    c.add("glUseProgramStages", pipeline=5, stages=["GL_COMPUTE_SHADER_BIT"], program=11)
    assert trace(tmp_path, draw(c), "compute") == base and base.count(b"\nf ") > 100


VALIDATE = ("glValidateProgramPipeline", {"pipeline": 5})
DECIDE = ("glActiveShaderProgram", {"pipeline": 5, "program": 0})


@pytest.mark.parametrize("calls, drawn", [
    ((), True), ((VALIDATE,), True), ((VALIDATE, DECIDE), False), ((DECIDE,), True)],
    ids=["kept", "validate_decides_nothing", "validated_then_decided", "kept_when_decided"])
def test_glvalidateprogrampipeline_validates_as_a_draw_does(tmp_path, calls, drawn):
    """Mesa validates the bound pipeline when it decides whether draws are
    valid (its glUseProgramStages here) and keeps pipe->Validated until the
    stages change: its program relinked without GL_PROGRAM_SEPARABLE still
    draws. glValidateProgramPipeline validates it again (and fails) but
    decides nothing: the draws keep Mesa's last decision until a call that
    decides (glActiveShaderProgram on the pipeline draws run), which then
    validates it (R23-1; the converter had taken the call as deciding).
    The vertex array is bound first: in a core profile, binding one in
    place of object 0 decides too."""
    c = separable().add("glGenVertexArrays", n=1, arrays=[7]).add("glBindVertexArray", array=7)
    c.add("glProgramParameteri", program=2, pname="GL_PROGRAM_SEPARABLE", value=0).add("glLinkProgram", program=2)
    for fn, args in calls:
        c.add(fn, **args)
    got = frames(tmp_path, draw(c, vao=None), "validate")
    assert (got[0]["fragments"] > 100) == drawn, got
