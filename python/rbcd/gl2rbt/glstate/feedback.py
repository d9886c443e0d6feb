"""The capture's own transform feedback (GL 3.0+, ES 3.0+): a program's
outputs recorded into buffers, as GPU particle systems update their
particles. The recorded values are GPU work, not in the capture: a draw
while feedback is active (not paused) makes the buffers at the current
transform feedback object's binding points GPU-written, so that a later
draw reading them as vertices is refused, naming both calls
(BufferCalls.checked_buffer). Transform feedback objects keep their own
binding points, as GL defines them; a draw whose vertex count a feedback
object recorded (glDrawTransformFeedback) is refused when it reaches the
camera pass and left out otherwise."""
from ...cli import I64, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import base_name
from .buffers import FEEDBACK_TARGET as TARGET, binding_ignored


class FeedbackCalls:
    """self.s.feedback: the bound transform feedback object's name, whether
    feedback is active and paused; self.s.feedback_bindings: each object
    not bound now -> {index: (buffer, offset, size)} (the bound one's are
    in self.s.indexed under TARGET, where glBindBufferBase puts them)."""

    def feedback_writes(self, no, name):
        """At a draw: the buffers feedback records into now are the GPU's."""
        active, paused = self.s.feedback[1:]
        if not active or paused:
            return
        for (target, index), (b, _, _) in self.s.indexed.items():
            if target == TARGET and b:
                self.gpu_wrote_buffer(no, b, f"{base_name(name)} with transform feedback recording into "
                                             f"binding {index}")

    def feedback_object(self, no, name, v):
        """A transform feedback object's name, or None when GL ignores the
        call (a name never generated, or deleted: GL_INVALID_OPERATION)."""
        v = checked(no, integer, v, f"{name}: the transform feedback object", *U32)
        return v if v == 0 or v in self.s.feedback_bindings or v == self.s.feedback[0] else None

    def h_gen_feedbacks(self, no, name, a, args):
        ids = dict(args).get("ids")
        for v in ids if isinstance(ids, list) else []:
            v = checked(no, integer, v, f"{name}: a name", *U32)
            if v and v != self.s.feedback[0]:
                self.s.feedback_bindings.setdefault(v, {})

    def h_bind_feedback(self, no, name, a, args):
        d = dict(args)
        v = self.feedback_object(no, name, d.get("id"))
        obj, active, paused = self.s.feedback
        if v is None or d.get("target") != "GL_TRANSFORM_FEEDBACK" or (active and not paused) or v == obj:
            return   # GL_INVALID_OPERATION or _ENUM, or nothing to change
        self.s.feedback_bindings[obj] = {i: bound for (t, i), bound in self.s.indexed.items() if t == TARGET}
        for key in [k for k in self.s.indexed if k[0] == TARGET]:
            del self.s.indexed[key]
        for i, bound in self.s.feedback_bindings.pop(v, {}).items():
            self.s.indexed[(TARGET, i)] = bound
        # (Each object's active and paused state is its own: one bound
        # while another is active was refused above, so this one is idle.)
        self.s.feedback = (v, False, False)

    def h_delete_feedbacks(self, no, name, a, args):
        ids = dict(args).get("ids")
        for v in ids if isinstance(ids, list) else []:
            v = checked(no, integer, v, f"{name}: a name", *U32)
            if not v:
                continue
            if v == self.s.feedback[0]:
                if self.s.feedback[1]:
                    continue   # GL_INVALID_OPERATION: an active object is not deleted
                self.h_bind_feedback(no, name, a, [("target", "GL_TRANSFORM_FEEDBACK"), ("id", 0)])
            self.s.feedback_bindings.pop(v, None)

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
        if v is None or (buf and buf not in self.s.buffer_objects) or binding_ignored(
                TARGET, index, buf, offset, size, feedback_active=v == self.s.feedback[0] and self.s.feedback[1],
                dsa=True):
            return   # GL_INVALID_OPERATION or _VALUE: the call changes nothing
        if v == self.s.feedback[0]:
            self.s.indexed[(TARGET, index)] = (buf, offset, size)
        else:
            self.s.feedback_bindings.setdefault(v, {})[index] = (buf, offset, size)

    def h_begin_feedback(self, no, name, a, args):
        obj, active, _ = self.s.feedback
        if not active:
            self.s.feedback = (obj, True, False)

    def h_end_feedback(self, no, name, a, args):
        self.s.feedback = (self.s.feedback[0], False, False)

    def h_pause_feedback(self, no, name, a, args):
        obj, active, _ = self.s.feedback
        if active:
            self.s.feedback = (obj, True, base_name(name) == "glPauseTransformFeedback")

    def h_draw_feedback(self, no, name, a, args):
        """glDrawTransformFeedback*: as many vertices as a feedback object
        recorded, which the capture does not hold."""
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
