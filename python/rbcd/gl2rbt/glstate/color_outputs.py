"""Where the fragment shader's colour outputs go: each draw buffer's blend
factors and each framebuffer's list of draw buffers. Neither moves a
fragment; together they decide whether GL draws at all: a blend factor that
reads the second colour output (dual-source blending) on a draw buffer past
the first of several is GL_INVALID_OPERATION at the draw (GL 4.6 §17.3.6.3;
Mesa 22.3 _mesa_update_valid_to_render_state, whatever GL_BLEND says, with
llvmpipe's GL_MAX_DUAL_SOURCE_DRAW_BUFFERS of 1), and so is an advanced
blend equation (KHR_blend_equation_advanced) into more than one buffer or
under a fragment shader that does not declare it.
"""
import re

from ...cli import I32, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import base_name
from . import enum_arg
from .glsl_text import conditional_on

MAX_DRAW_BUFFERS = 8              # llvmpipe's GL_MAX_DRAW_BUFFERS and GL_MAX_COLOR_ATTACHMENTS
MAX_DUAL_SOURCE_DRAW_BUFFERS = 1  # llvmpipe's GL_MAX_DUAL_SOURCE_DRAW_BUFFERS
# The blend factors GL takes (by name as apitrace writes them, and by
# value), those of the second colour output marked.
BLEND_FACTORS = {
    "GL_ZERO": 0, "GL_ONE": 1, "GL_SRC_COLOR": 0x300, "GL_ONE_MINUS_SRC_COLOR": 0x301, "GL_SRC_ALPHA": 0x302,
    "GL_ONE_MINUS_SRC_ALPHA": 0x303, "GL_DST_ALPHA": 0x304, "GL_ONE_MINUS_DST_ALPHA": 0x305, "GL_DST_COLOR": 0x306,
    "GL_ONE_MINUS_DST_COLOR": 0x307, "GL_SRC_ALPHA_SATURATE": 0x308, "GL_CONSTANT_COLOR": 0x8001,
    "GL_ONE_MINUS_CONSTANT_COLOR": 0x8002, "GL_CONSTANT_ALPHA": 0x8003, "GL_ONE_MINUS_CONSTANT_ALPHA": 0x8004,
    "GL_SRC1_ALPHA": 0x8589, "GL_SRC1_COLOR": 0x88F9, "GL_ONE_MINUS_SRC1_COLOR": 0x88FA,
    "GL_ONE_MINUS_SRC1_ALPHA": 0x88FB,
    # Other names of the same values, as a table may spell them.
    "GL_SOURCE1_ALPHA": 0x8589, "GL_FALSE": 0, "GL_NONE": 0, "GL_POINTS": 0, "GL_TRUE": 1, "GL_LINES": 1,
}
DUAL_SOURCE = {0x8589, 0x88F9, 0x88FA, 0x88FB}
DEFAULT_BLEND = (1, 0, 1, 0)      # GL_ONE, GL_ZERO for colour and alpha
# Draw buffers: the window's colour buffers each name selects (a
# double-buffered, monoscopic window, as Mesa's replay has: the right
# buffers and GL_AUXi select none), by name and value.
GL_NONE, GL_BACK = 0, 0x405
WINDOW_BUFFERS = {"GL_FRONT_LEFT": 1, "GL_BACK_LEFT": 1, "GL_FRONT": 1, "GL_BACK": 1, "GL_LEFT": 2,
                  "GL_FRONT_AND_BACK": 2, "GL_FRONT_RIGHT": 0, "GL_BACK_RIGHT": 0, "GL_RIGHT": 0,
                  "GL_AUX0": 0, "GL_AUX1": 0, "GL_AUX2": 0, "GL_AUX3": 0}
BUFFER_VALUES = {"GL_NONE": 0, "GL_FRONT_LEFT": 0x400, "GL_FRONT_RIGHT": 0x401, "GL_BACK_LEFT": 0x402,
                 "GL_BACK_RIGHT": 0x403, "GL_FRONT": 0x404, "GL_BACK": 0x405, "GL_LEFT": 0x406, "GL_RIGHT": 0x407,
                 "GL_FRONT_AND_BACK": 0x408, "GL_AUX0": 0x409, "GL_AUX1": 0x40A, "GL_AUX2": 0x40B, "GL_AUX3": 0x40C,
                 **{f"GL_COLOR_ATTACHMENT{i}": 0x8CE0 + i for i in range(32)}}
BUFFER_NAMES = {v: k for k, v in BUFFER_VALUES.items() if k != "GL_NONE"} | {0: "GL_NONE"}
# apitrace writes a 0 in an array of enumerants by the first name its table
# has for 0: GL_NONE in a list of draw buffers may come as any of these.
BUFFER_VALUES.update(dict.fromkeys(("GL_ZERO", "GL_FALSE", "GL_POINTS", "GL_NO_ERROR"), 0))
MULTIPLE = {"GL_FRONT", "GL_BACK", "GL_LEFT", "GL_RIGHT", "GL_FRONT_AND_BACK"}
# The calls after which Mesa 22.3 decides again whether draws are valid
# (_mesa_update_valid_to_render_state), its ValidPrimMask, which draws then
# read until the next (DrawCalls.revalidate): a change of the program in
# use, the bound pipeline (with no program in use), the draw framebuffer,
# transform feedback's state, a core profile's vertex array binding to or
# from object 0 (REVALIDATING, when bindings() changes); a link
# (ALWAYS_REVALIDATING, every time); a MakeCurrent that changes the context
# or a drawable, a renderbuffer attached to any framebuffer object by a
# call GL takes (Converter.decides); a test of a framebuffer object's
# completeness whose status is not complete, by a status check
# (h_check_framebuffer_status) or by the state update a draw or clear
# starts with after a change of buffers (FramebufferCalls.
# update_framebuffers); the blend factors, the advanced equation and
# GL_BLEND when they change (ColorOutputCalls); a sampler moved to another
# texture unit (ProgramCalls.sampler_set); the stages or active program of
# the pipeline draws run (ProgramCalls). Not among them: a change of the
# read framebuffer alone, glDrawBuffer(s), glValidateProgramPipeline, a
# glUniform1i that leaves a sampler where it was, glColorMaski, a
# glUseProgram of the program in use.
ALWAYS_REVALIDATING = frozenset({"glLinkProgram"})
REVALIDATING = frozenset({
    "glUseProgram", "glBindProgramPipeline", "glDeleteProgramPipelines", "glBindFramebuffer", "glDeleteFramebuffers",
    "glBindVertexArray",
    "glBeginTransformFeedback", "glEndTransformFeedback", "glPauseTransformFeedback",
    "glResumeTransformFeedback"}) | ALWAYS_REVALIDATING


# Blend equations (glBlendEquation*): GL's own, and the advanced ones of
# KHR_blend_equation_advanced (NV's names too), each by the layout qualifier
# a fragment shader declares it with (blend_support_NAME).
SIMPLE_EQUATIONS = {"GL_FUNC_ADD", "GL_FUNC_SUBTRACT", "GL_FUNC_REVERSE_SUBTRACT", "GL_MIN", "GL_MAX",
                    0x8006, 0x800A, 0x800B, 0x8007, 0x8008}
ADVANCED_EQUATIONS = {f"GL_{mode.upper()}_{suffix}": mode for suffix in ("KHR", "NV") for mode in (
    "multiply", "screen", "overlay", "darken", "lighten", "colordodge", "colorburn", "hardlight", "softlight",
    "difference", "exclusion", "hsl_hue", "hsl_saturation", "hsl_color", "hsl_luminosity")}


# A fragment shader's declaration of the advanced equations it supports:
# layout(blend_support_NAME, ...) out; (its text as the compiler reads it).
LAYOUT_OUT = re.compile(r"\blayout\s*\(([^()]*)\)\s*out\s*;")


FRAMEBUFFER_TARGETS = ("GL_FRAMEBUFFER", "GL_DRAW_FRAMEBUFFER", "GL_READ_FRAMEBUFFER")


class NotFollowed(str):
    """Why draws may be refused, where the converter cannot decide it as
    Mesa does: a draw under it is refused in one line naming it."""


def factor(v, no, what):
    """A blend factor's value, or None for one GL refuses (GL_INVALID_ENUM)."""
    v = enum_arg(v, no, what)
    return BLEND_FACTORS.get(v) if isinstance(v, str) else v if v in BLEND_FACTORS.values() else None


def buffer_name(v, no, what):
    """A draw buffer's name (a value named as GL names it), or None for a
    value that names no buffer (GL_INVALID_ENUM)."""
    v = enum_arg(v, no, what)
    if isinstance(v, int):
        return BUFFER_NAMES.get(v)
    return BUFFER_NAMES.get(BUFFER_VALUES[v]) if v in BUFFER_VALUES else None


class ColorOutputCalls:
    """self.s.blend_factors: each draw buffer's (source colour, destination
    colour, source alpha, destination alpha) factors; self.s.window_draw_buffers
    and self.s.fbo_draw_buffers[fbo]: how many colour draw buffers the window
    and each framebuffer object have (Mesa's _NumColorDrawBuffers: one past
    the last that is not GL_NONE, or the two buffers of GL_FRONT_AND_BACK
    and GL_LEFT)."""

    def h_blend_func(self, no, name, a, args):
        """glBlendFunc, glBlendFuncSeparate and their per-buffer forms
        (glBlendFunci, glBlendFuncSeparatei, the AMD Indexed ones): a
        factor GL refuses or a buffer past the last changes nothing."""
        d = dict(args)
        base = base_name(name)
        per_buffer = base.endswith(("i", "IndexedAMD"))
        keys = [k for k, _ in args if k != "buf"]
        values = [factor(d[k], no, f"{name}: {k}") for k in keys]
        if len(values) not in (2, 4) or None in values:
            return   # GL_INVALID_ENUM
        if len(values) == 2:
            values = values * 2
        before = self.dual_source_buffers()
        if per_buffer:
            buf = checked(no, integer, d.get("buf"), f"{name}: the draw buffer", *U32)
            if buf >= MAX_DRAW_BUFFERS:
                return   # GL_INVALID_VALUE
            self.s.blend_factors[buf] = tuple(values)
        else:
            self.s.blend_factors = [tuple(values)] * MAX_DRAW_BUFFERS
        if self.dual_source_buffers() != before:
            self.revalidate()   # (Mesa: _BlendUsesDualSrc changed)

    def h_blend_equation(self, no, name, a, args):
        """glBlendEquation, glBlendEquationSeparate and their per-buffer
        forms: which advanced equation (KHR_blend_equation_advanced) blends,
        as Mesa keeps it (_AdvancedBlendMode: set by glBlendEquation, and by
        glBlendEquationi on buffer 0; a separate form takes GL's own
        equations only and ends it, on any buffer); an equation GL refuses
        changes nothing. A change has Mesa decide again whether draws are
        valid."""
        d = dict(args)
        per_buffer = base_name(name).endswith(("i", "IndexedAMD"))
        modes = [enum_arg(d[k], no, f"{name}: {k}") for k, _ in args if k != "buf"]
        if len(modes) not in (1, 2) or any(m not in SIMPLE_EQUATIONS and (len(modes) == 2 or m not in
                                                                           ADVANCED_EQUATIONS) for m in modes):
            return   # GL_INVALID_ENUM
        if per_buffer:
            buf = checked(no, integer, d.get("buf"), f"{name}: the draw buffer", *U32)
            if buf >= MAX_DRAW_BUFFERS:
                return   # GL_INVALID_VALUE
            if buf != 0 and len(modes) == 1:
                return   # (one mode on another buffer: Mesa's blend_equationi leaves the advanced one)
        mode = ADVANCED_EQUATIONS.get(modes[0]) if len(modes) == 1 else None
        if mode != self.s.advanced_blend:
            self.s.advanced_blend = mode
            self.revalidate()

    def h_check_framebuffer_status(self, no, name, a, args):
        """glCheck(Named)FramebufferStatus: Mesa tests a framebuffer object's
        completeness unless its status is complete (FramebufferCalls), and
        decides again whether draws are valid at each test (complete or
        not); the window's is no test, nor is a name that is no
        framebuffer. The answer is the capture's (the call's return value),
        or the converter's own where the capture has none."""
        d = dict(args)
        ret = self.ret
        if d.get("target") not in FRAMEBUFFER_TARGETS or ret in (0, "GL_NONE", "GL_ZERO", "GL_FALSE"):
            return   # GL_INVALID_ENUM, or another error: no test (the call returns 0)
        fb = self.named_framebuffer(no, name, d, self.s.read_fbo if d.get("target") == "GL_READ_FRAMEBUFFER"
                                    else self.s.draw_fbo)
        if fb is None:
            return
        self.test_framebuffers(no, name, (fb,), ret == "GL_FRAMEBUFFER_COMPLETE" if isinstance(ret, str)
                               and ret.startswith("GL_FRAMEBUFFER_") else None)

    def advanced_blend_invalid(self):
        """Why draws are GL_INVALID_OPERATION for an advanced blend equation
        with blending enabled (KHR_blend_equation_advanced, Mesa 22.3's
        checks): colour output 0 into two buffers (GL_FRONT_AND_BACK) or a
        draw buffer past the first; a fragment shader that does not declare
        the equation (layout(blend_support_NAME) or
        blend_support_all_equations), or none. None when they draw."""
        mode = self.s.advanced_blend
        if mode is None or not self.s.blend_on:
            return None
        fb = self.s.draw_fbo
        where = "the window" if fb == 0 else f"framebuffer {fb}"
        if not (self.s.window_one_output if fb == 0 else self.s.fbo_one_output.get(fb, True)):
            return f"advanced blending ({mode}) into more than one colour buffer of {where}"
        fragment = self.stage_programs().get("fragment")
        text = fragment[1].scanned.get("fragment", "") if fragment is not None else ""
        supports = {q.strip()[len("blend_support_"):] for m in LAYOUT_OUT.finditer(text)
                    for q in m.group(1).split(",") if q.strip().startswith("blend_support_")}
        if "all_equations" in supports or mode in supports:
            if conditional_on(fragment[1].objects.get("fragment", ()), "blend_support"):
                return NotFollowed(f"advanced blending ({mode}) under a fragment shader that declares "
                                   f"blend_support among preprocessor conditionals, which the converter does not "
                                   "evaluate (docs/gl-capture.md)")
            return None
        return f"advanced blending ({mode}) under a fragment shader that does not declare blend_support_{mode}"

    def integer_buffers_invalid(self):
        """Why draws are GL_INVALID_OPERATION for an integer colour buffer
        (EXT_texture_integer; Mesa 22.3 in a compatibility profile): no
        fragment shader runs and the draw framebuffer had a colour
        attachment of an integer format at its last test, drawn into or
        not. None when they draw."""
        fb = self.s.draw_fbo
        if self.core or self.es or not fb or self.stage_programs().get("fragment") is not None:
            return None
        integer = self.s.fbo_integer.get(fb)
        if isinstance(integer, str):
            return NotFollowed(f"whether framebuffer {fb} has an integer colour attachment, which fixed-function "
                               f"fragments cannot write, is not known ({integer}; docs/gl-capture.md)")
        if integer is not None:
            return (f"framebuffer {fb}'s {integer[0]} has integer format {integer[1]}, which only a fragment shader "
                    "writes")
        return None

    def dual_source_buffers(self):
        """The draw buffers whose blend factors read the second colour output."""
        return [i for i, f in enumerate(self.s.blend_factors) if DUAL_SOURCE.intersection(f)]

    def bindings(self):
        """What a REVALIDATING call has Mesa decide again on when it changes
        (of the vertex array binding, in a core profile, only whether it is
        vertex array object 0; of the pipeline, only the one draws run)."""
        s = self.s
        return (s.program, self.current_pipeline(), s.draw_fbo, self.core and s.vao == 0, s.feedback)

    def blend_enabled(self, on):
        """glEnable or glDisable(GL_BLEND): a change has Mesa decide again."""
        if on != self.s.blend_on:
            self.s.blend_on = on
            self.revalidate()

    def draw_buffer_counts(self, name, fb, names):
        """The number of colour draw buffers framebuffer fb (0: the window)
        has after glDrawBuffer (one name, which may select two of the
        window's buffers) or glDrawBuffers (each name one buffer), or None
        when GL refuses the call (Mesa 22.3 draw_buffer, draw_buffers)."""
        single = base_name(name) in ("glDrawBuffer", "glNamedFramebufferDrawBuffer", "glFramebufferDrawBuffer")
        if None in names:
            return None   # GL_INVALID_ENUM
        if single:
            (b,) = names
            if b == "GL_NONE":
                return 0
            n = WINDOW_BUFFERS.get(b, 0) if fb == 0 else int(b.startswith("GL_COLOR_ATTACHMENT") and
                                                                BUFFER_VALUES[b] - 0x8CE0 < MAX_DRAW_BUFFERS)
            return n or None   # (none of them: GL_INVALID_OPERATION)
        if self.es and fb == 0 and (len(names) != 1 or names[0] not in ("GL_NONE", "GL_BACK")):
            return None   # GL_INVALID_OPERATION
        count, used = 0, set()
        for i, b in enumerate(names):
            if b == "GL_NONE":
                continue
            if b in MULTIPLE and not (b == "GL_BACK" and fb == 0 and (self.es or len(names) == 1)):
                return None   # GL_INVALID_ENUM (desktop GL 4.x: GL_BACK alone on the window)
            if fb == 0:
                if WINDOW_BUFFERS.get(b, 0) == 0:
                    return None   # a buffer the window lacks: GL_INVALID_OPERATION
                selected = "GL_BACK_LEFT" if b == "GL_BACK" else b
            else:
                index = BUFFER_VALUES[b] - 0x8CE0 if b.startswith("GL_COLOR_ATTACHMENT") else -1
                if not 0 <= index < MAX_DRAW_BUFFERS or (self.es and index != i):
                    return None   # GL_INVALID_OPERATION
                selected = b
            if selected in used:
                return None   # GL_INVALID_OPERATION: a buffer twice
            used.add(selected)
            count = i + 1
        return count

    def h_draw_buffers(self, no, name, a, args):
        """glDrawBuffer, glDrawBuffers, and their direct state access forms."""
        d = dict(args)
        base = base_name(name)
        if base.startswith(("glNamedFramebuffer", "glFramebuffer")):
            fb = checked(no, integer, d.get("framebuffer"), f"{name}: the framebuffer", *U32)
            if fb and fb not in self.s.fbo_draw_buffers and not self.known_framebuffer(fb):
                return   # GL_INVALID_OPERATION: no such framebuffer
        else:
            fb = self.s.draw_fbo
        if "Buffers" in base:
            n = checked(no, integer, d.get("n"), f"{name}: the count", *I32)
            bufs = d.get("bufs")
            if n < 0 or n > MAX_DRAW_BUFFERS:
                return   # GL_INVALID_VALUE: the list is not read
            if n == 0:
                bufs = []
            if not isinstance(bufs, list):
                fail_call(no, f"{name}: the buffers are {printable(bufs, 40)}, not a list (apitrace's form) of {n}")
            if len(bufs) != n:
                fail_call(no, f"{name}: {len(bufs)} buffers, not its count ({n})")
        else:
            bufs = [d.get("buf", d.get("mode", a[-1] if a else None))]
        names = [buffer_name(b, no, f"{name}: a buffer") for b in bufs]
        count = self.draw_buffer_counts(name, fb, names)
        if count is None:
            return
        # The draw buffers as named (GL_NONE at the end dropped: Mesa sets
        # GL_NONE past the list): a change flags a state update (Mesa's
        # updated_drawbuffers).
        kept = len(names)
        while kept and names[kept - 1] == "GL_NONE":
            kept -= 1
        named = tuple(names[:kept])
        before = self.s.window_buffer_names if fb == 0 else self.s.fbo_buffer_names.get(fb, ("GL_COLOR_ATTACHMENT0",))
        if named != before:
            self.s.new_buffers = True
            if fb == 0:
                self.s.window_buffer_names = named
            else:
                self.s.fbo_buffer_names[fb] = named
        # Only colour output 0 drawn, into one buffer (what advanced blending
        # needs): not GL_FRONT_AND_BACK, no buffer past the first in a list.
        one = count <= 1 if "Buffers" in base else names[0] != "GL_FRONT_AND_BACK"
        if fb == 0:
            self.s.window_draw_buffers, self.s.window_one_output = count, one
        else:
            self.s.fbo_draw_buffers[fb], self.s.fbo_one_output[fb] = count, one

    def h_read_buffer(self, no, name, a, args):
        """glReadBuffer and glNamedFramebufferReadBuffer: one GL takes (a
        buffer the window has, or for a framebuffer object GL_NONE or a
        colour attachment) flags a state update (Mesa's _mesa_readbuffer),
        the buffer changed or not; what is read is not followed."""
        d = dict(args)
        fb = self.named_framebuffer(no, name, d, self.s.read_fbo)
        if fb is None:
            return
        b = buffer_name(d.get("src", d.get("mode", a[-1] if a else None)), no, f"{name}: the buffer")
        if b is None:
            return   # GL_INVALID_ENUM
        if fb == 0:
            taken = b == "GL_NONE" or WINDOW_BUFFERS.get(b, 0) > 0
        else:
            taken = b == "GL_NONE" or b.startswith("GL_COLOR_ATTACHMENT") and BUFFER_VALUES[b] - 0x8CE0 < 8
        if taken:
            self.s.new_buffers = True

    def named_framebuffer(self, no, name, d, bound):
        """The framebuffer a call acts on: the one its direct state access
        form names, else `bound`; None for a name that is no framebuffer
        (GL_INVALID_OPERATION: the call does nothing)."""
        if "Named" not in name:
            return bound
        fb = checked(no, integer, d.get("framebuffer"), f"{name}: the framebuffer", *U32)
        return None if fb and not self.known_framebuffer(fb) else fb

    def known_framebuffer(self, fb):
        """Whether framebuffer object fb exists for a direct state access
        call (made by glCreateFramebuffers, or bound once; a name
        glGenFramebuffers returned is none until bound)."""
        return fb in self.s.framebuffer_objects

    def dual_source_invalid(self):
        """Why draws are GL_INVALID_OPERATION for dual-source blending: a
        draw buffer past llvmpipe's one that takes a second colour output
        has a blend factor reading it (blending enabled or not, as Mesa
        checks). None when they draw."""
        fb = self.s.draw_fbo
        n = self.s.window_draw_buffers if fb == 0 else self.s.fbo_draw_buffers.get(fb, 1)
        for i in range(MAX_DUAL_SOURCE_DRAW_BUFFERS, n):
            if DUAL_SOURCE.intersection(self.s.blend_factors[i]):
                where = "the window" if fb == 0 else f"framebuffer {fb}"
                return (f"draw buffer {i} of {where}'s {n} blends with the second colour output "
                        f"(a GL_SRC1_ factor), which only the first {MAX_DUAL_SOURCE_DRAW_BUFFERS} may")
        return None

    HANDLERS = {
        "glBlendFunc": h_blend_func,
        "glBlendFuncSeparate": h_blend_func,
        "glBlendFunci": h_blend_func,
        "glBlendFuncSeparatei": h_blend_func,
        "glBlendFuncIndexedAMD": h_blend_func,
        "glBlendFuncSeparateIndexedAMD": h_blend_func,
        "glBlendEquation": h_blend_equation,
        "glBlendEquationSeparate": h_blend_equation,
        "glBlendEquationi": h_blend_equation,
        "glBlendEquationSeparatei": h_blend_equation,
        "glBlendEquationIndexedAMD": h_blend_equation,
        "glBlendEquationSeparateIndexedAMD": h_blend_equation,
        "glCheckFramebufferStatus": h_check_framebuffer_status,
        "glCheckNamedFramebufferStatus": h_check_framebuffer_status,
        "glDrawBuffer": h_draw_buffers,
        "glReadBuffer": h_read_buffer,
        "glNamedFramebufferReadBuffer": h_read_buffer,
        "glDrawBuffers": h_draw_buffers,
        "glDrawBuffersATI": h_draw_buffers,
        "glDrawBuffersNV": h_draw_buffers,
        "glNamedFramebufferDrawBuffer": h_draw_buffers,
        "glNamedFramebufferDrawBuffers": h_draw_buffers,
        "glFramebufferDrawBuffer": h_draw_buffers,
        "glFramebufferDrawBuffers": h_draw_buffers,
    }
