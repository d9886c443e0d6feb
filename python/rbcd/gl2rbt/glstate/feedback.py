"""The capture's own transform feedback (GL 3.0+, ES 3.0+): a program's
outputs recorded into buffers, as GPU particle systems update their
particles. The recorded values are GPU work, not in the capture: a draw
while feedback is active (not paused) makes the buffers at the current
transform feedback object's binding points GPU-written, so that a later
draw reading them as vertices is refused, naming both calls
(BufferCalls.checked_buffer). Transform feedback objects keep their own
binding points, as GL defines them; a draw whose vertex count a feedback
object recorded (glDrawTransformFeedback) is refused when it reaches the
camera pass and left out otherwise.

What Mesa 22.3 refuses (transformfeedback.c, draw_validate.c) changes
nothing here either: beginning without a program that records outputs,
in another primitive mode than points, lines or triangles, while active,
or with a binding point the program records into left empty; pausing,
resuming or ending out of turn, resuming under another program; binding
another object, glUseProgram, glBindProgramPipeline or glUseProgramStages
on the bound pipeline while active and not paused (and the unbind that
deleting the bound pipeline makes); linking a program an active object
(paused too) records from; glTransformFeedbackVaryings, and unbinding a
deleted buffer from a binding point, while the bound object is active; and
a draw whose primitives are not of the kind begun (the kind Mesa links for
a geometry shader's output, or tessellation's, when there is one), or of no
whole primitive, draws and records nothing."""
from ...cli import I32, I64, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import base_name
from . import enum_arg
from .buffers import FEEDBACK_TARGET as TARGET, binding_ignored
from .draws import PRIM_MODES


MAX_VERTEX_STREAMS = 4   # (Mesa's)


class FeedbackObject:
    """A transform feedback object not bound now: its binding points
    ({index: (buffer, offset, size)}), whether it is active and paused,
    and the program it records from (Mesa's obj->program, set at begin)."""

    def __init__(self):
        self.bindings = {}
        self.active = self.paused = False
        self.source = None


# The primitives of each kind glBeginTransformFeedback takes (Mesa's
# valid-primitive mask; every other mode is of the triangles' kind).
KIND_OF_MODE = {"GL_POINTS": "GL_POINTS", "GL_LINES": "GL_LINES", "GL_LINE_LOOP": "GL_LINES",
                "GL_LINE_STRIP": "GL_LINES"}


class FeedbackCalls:
    """self.s.feedback: the bound transform feedback object's name, whether
    it is active and paused; self.s.feedback_source: the program it records
    from; self.s.feedback_mode: the primitive mode of the last begin (the
    context's, as in Mesa); self.s.feedback_objects: the objects not bound
    now (FeedbackObject). The bound one's binding points are in
    self.s.indexed under TARGET, where glBindBufferBase puts them."""

    def recording(self):
        """Whether the bound object records now (active, not paused)."""
        return self.s.feedback[1] and not self.s.feedback[2]

    def recorded_bindings(self, p):
        """The binding points program p's executable records into, as Mesa
        links it (its last vertex-processing stage's xfb_ qualifiers, else
        the outputs glTransformFeedbackVaryings named): none when it
        records nothing (a begin under it is refused)."""
        return self.vertex_stage().feedback_bindings(p)

    def feedback_writes(self, no, name):
        """At a draw: the buffers feedback records into now are the GPU's."""
        source = self.feedback_source() if self.recording() else None
        used = self.recorded_bindings(source[1]) if source is not None else ()
        for (target, index), (b, _, _) in self.s.indexed.items():
            if target == TARGET and b and index in used:
                self.gpu_wrote_buffer(no, b, f"{base_name(name)} with transform feedback recording into "
                                             f"binding {index}")

    def feedback_kind_refused(self, no, name, mode, stages):
        """A draw of `mode` under `stages` (stage_programs) while feedback
        records: None when its primitives are of the kind begun, else the
        GL_INVALID_OPERATION that makes Mesa draw nothing. A tessellation
        or geometry shader's kind is Mesa's (the program linked there)."""
        if not self.recording():
            return None
        if "geometry" in stages or "tess_evaluation" in stages:
            kind = self.vertex_stage().output_kind(no, base_name(name), *stages["vertex"])
        else:
            kind = KIND_OF_MODE.get(mode, "GL_TRIANGLES")
        if kind is None or kind == self.s.feedback_mode:
            return None
        return f"GL_INVALID_OPERATION: primitives of {kind} while transform feedback records {self.s.feedback_mode}"

    def feedback_source(self):
        """The program whose outputs feedback would record (Mesa's
        get_xfb_source: the last vertex-processing stage's), as (name,
        Program), or None."""
        stages = self.stage_programs()
        for stage in ("geometry", "tess_evaluation", "vertex"):
            if stage in stages:
                return stages[stage]
        return None

    def records_from(self, v):
        """Whether an active transform feedback object (paused too, bound or
        not) records from program v: its link is GL_INVALID_OPERATION."""
        return (self.s.feedback[1] and self.s.feedback_source == v) or \
            any(o.active and o.source == v for o in self.s.feedback_objects.values())

    def feedback_object(self, no, name, v):
        """A transform feedback object's name, or None when GL ignores the
        call (a name never generated, or deleted: GL_INVALID_OPERATION)."""
        v = checked(no, integer, v, f"{name}: the transform feedback object", *U32)
        return v if v == 0 or v in self.s.feedback_objects or v == self.s.feedback[0] else None

    def h_gen_feedbacks(self, no, name, a, args):
        ids = dict(args).get("ids")
        for v in ids if isinstance(ids, list) else []:
            v = checked(no, integer, v, f"{name}: a name", *U32)
            if v and v != self.s.feedback[0]:
                self.s.feedback_objects.setdefault(v, FeedbackObject())

    def h_bind_feedback(self, no, name, a, args):
        d = dict(args)
        target = enum_arg(d.get("target"), no, f"{name}: the target")
        v = self.feedback_object(no, name, d.get("id"))
        obj, active, paused = self.s.feedback
        if v is None or target != "GL_TRANSFORM_FEEDBACK" or self.recording() or v == obj:
            return   # GL_INVALID_OPERATION or _ENUM, or nothing to change
        old = FeedbackObject()
        old.bindings = {i: bound for (t, i), bound in self.s.indexed.items() if t == TARGET}
        old.active, old.paused, old.source = active, paused, self.s.feedback_source
        self.s.feedback_objects[obj] = old
        for key in [k for k in self.s.indexed if k[0] == TARGET]:
            del self.s.indexed[key]
        new = self.s.feedback_objects.pop(v, None) or FeedbackObject()
        for i, bound in new.bindings.items():
            self.s.indexed[(TARGET, i)] = bound
        self.s.feedback = (v, new.active, new.paused)
        self.s.feedback_source = new.source

    def h_delete_feedbacks(self, no, name, a, args):
        ids = dict(args).get("ids")
        for v in ids if isinstance(ids, list) else []:
            v = checked(no, integer, v, f"{name}: a name", *U32)
            if not v:
                continue
            if v == self.s.feedback[0] and self.s.feedback[1] or \
                    v in self.s.feedback_objects and self.s.feedback_objects[v].active:
                return   # GL_INVALID_OPERATION: an active object is not deleted, nor the rest of the list
            if v == self.s.feedback[0]:
                self.h_bind_feedback(no, name, a, [("target", "GL_TRANSFORM_FEEDBACK"), ("id", 0)])
            self.s.feedback_objects.pop(v, None)
            self.s.feedback_ended.discard(v)

    def h_feedback_buffer(self, no, name, a, args):
        """glTransformFeedbackBufferBase/Range (GL 4.5): a binding point of
        the object named, the generic binding left as it was."""
        d = dict(args)
        v = self.feedback_object(no, name, d.get("xfb"))
        index = checked(no, integer, d.get("index"), f"{name}: the index", *U32)
        buf = checked(no, integer, d.get("buffer"), f"{name}: the buffer", *U32)
        offset = checked(no, integer, d.get("offset", 0), f"{name}: the offset", *I64)
        size = d.get("size")
        if size is not None:
            size = checked(no, integer, size, f"{name}: the size", *I64)
        if v is None or (buf and buf not in self.s.buffer_objects):
            return   # GL_INVALID_OPERATION or _VALUE: the call changes nothing
        bound = v == self.s.feedback[0]
        active = self.s.feedback[1] if bound else v in self.s.feedback_objects and self.s.feedback_objects[v].active
        if binding_ignored(TARGET, index, buf, offset, size, feedback_active=active, dsa=True):
            return
        if bound:
            self.s.indexed[(TARGET, index)] = (buf, offset, size)
        else:
            self.s.feedback_objects.setdefault(v, FeedbackObject()).bindings[index] = (buf, offset, size)

    def h_begin_feedback(self, no, name, a, args):
        obj, active, _ = self.s.feedback
        source = self.feedback_source()
        mode = enum_arg(dict(args).get("primitiveMode", a[0] if a else None), no, f"{name}: the primitive mode")
        if source is None or mode not in ("GL_POINTS", "GL_LINES", "GL_TRIANGLES") or active:
            return   # GL_INVALID_OPERATION (no program) or _ENUM: nothing begins
        used = self.recorded_bindings(source[1])
        if not used or any(not self.s.indexed.get((TARGET, i), (0,))[0] for i in used):
            return   # GL_INVALID_OPERATION: nothing recorded, or a binding point recorded into has no buffer
        self.s.feedback = (obj, True, False)
        self.s.feedback_mode, self.s.feedback_source = mode, source[0]

    def h_end_feedback(self, no, name, a, args):
        if self.s.feedback[1]:   # (else GL_INVALID_OPERATION)
            self.s.feedback = (self.s.feedback[0], False, False)
            self.s.feedback_ended.add(self.s.feedback[0])

    def h_pause_feedback(self, no, name, a, args):
        obj, active, paused = self.s.feedback
        if base_name(name) == "glPauseTransformFeedback":
            if active and not paused:
                self.s.feedback = (obj, True, True)
        elif active and paused and (self.feedback_source() or (None,))[0] == self.s.feedback_source:
            self.s.feedback = (obj, True, False)   # (another program than begin's: GL_INVALID_OPERATION)

    def h_draw_feedback(self, no, name, a, args):
        """glDrawTransformFeedback*: as many vertices as a feedback object
        recorded, which the capture does not hold. One GL refuses (an
        unknown mode, an object never generated or never ended, a stream
        past Mesa's 4, a negative instance count) or of no instance draws
        nothing, as in Mesa."""
        d = dict(args)
        mode = enum_arg(d.get("mode"), no, f"{name}: the mode")
        v = self.feedback_object(no, name, d.get("id"))
        stream = checked(no, integer, d.get("stream", 0), f"{name}: the stream", *U32)
        instances = checked(no, integer, d.get("instancecount", 1), f"{name}: the instance count", *I32)
        if mode not in PRIM_MODES or v is None or v not in self.s.feedback_ended or stream >= MAX_VERTEX_STREAMS \
                or instances <= 0:
            return   # GL_INVALID_ENUM, _VALUE or _OPERATION, or no instance: nothing is drawn
        self.shader_stores(no, name)
        if not self.active or self.s.rasterizer_discard or not self.renders():
            return
        if self.draws_into_camera_pass():
            fail_call(no, f"{printable(name)} draws as many vertices as transform feedback object "
                      f"{printable(dict(args).get('id'))} recorded, which the capture does not hold: not emulated")

    HANDLERS = {
        "glGenTransformFeedbacks": h_gen_feedbacks,
        "glCreateTransformFeedbacks": h_gen_feedbacks,
        "glBindTransformFeedback": h_bind_feedback,
        "glDeleteTransformFeedbacks": h_delete_feedbacks,
        "glTransformFeedbackBufferBase": h_feedback_buffer,
        "glTransformFeedbackBufferRange": h_feedback_buffer,
        "glBeginTransformFeedback": h_begin_feedback,
        "glEndTransformFeedback": h_end_feedback,
        "glPauseTransformFeedback": h_pause_feedback,
        "glResumeTransformFeedback": h_pause_feedback,
        "glDrawTransformFeedback": h_draw_feedback,
        "glDrawTransformFeedbackInstanced": h_draw_feedback,
        "glDrawTransformFeedbackStream": h_draw_feedback,
        "glDrawTransformFeedbackStreamInstanced": h_draw_feedback,
    }
