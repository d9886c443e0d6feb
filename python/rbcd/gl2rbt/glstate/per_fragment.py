"""The scissor, the depth test and its writes, depth clears, and the capabilities of glEnable."""
import re
import struct

import numpy as np

from ...cli import I32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import CAPS_IGNORED, CAPS_MESA_LACKS, DEPTH_FUNCS, MAX_CLIP_PLANES, base_name
from . import bitfield, clamped01, enum_arg, first_of_array, gl_boolean
from .transform import fixed_point

CLEAR_BITS = {0x100: "GL_DEPTH_BUFFER_BIT", 0x200: "GL_ACCUM_BUFFER_BIT", 0x400: "GL_STENCIL_BUFFER_BIT",
              0x4000: "GL_COLOR_BUFFER_BIT"}

class PerFragmentCalls:
    """Per-fragment operations that decide which fragments reach the unit."""

    def h_scissor(self, no, name, a, args):
        x, y, w, h = [checked(no, integer, v, f"{name}: a scissor value", *I32) for v in a[:4]]
        if w < 0 or h < 0:
            return   # GL_INVALID_VALUE: the call does nothing
        self.s.scissor = (x, y, w, h)

    def h_scissor_indexed(self, no, name, a, args):
        """glScissorIndexed(v) and glScissorArrayv: scissor 0 is glScissor's;
        the others are selected only by a geometry shader, which is refused."""
        d = dict(args)
        if "Array" in name:
            vals = first_of_array(no, name, d, "scissor", lambda x, n, w: checked(n, integer, x, w, *I32))
            if vals is None:
                return
        else:
            index = checked(no, integer, d.get("index"), f"{name}: index", *I32)
            if index != 0:
                return
            vals = d.get("v") if "v" in d else [d.get(k) for k in ("left", "bottom", "width", "height")]
        if not isinstance(vals, list) or len(vals) < 4:
            fail_call(no, f"{name}: not four scissor values")
        self.h_scissor(no, name, vals[:4], args)

    def scissor_rect(self):
        """The scissor box in screen rows down, inclusive, cut to the screen
        (a box reaching past it, as GL allows, clips nothing more)."""
        w, h = self.screen
        if not (self.s.scissor_test and self.s.scissor):
            return self.full_screen()
        sx, sy, sw, sh = self.s.scissor
        x0, y0, x1, y1 = sx, h - (sy + sh), sx + sw - 1, h - sy - 1
        return (min(max(x0, -1), w), min(max(y0, -1), h), min(max(x1, -1), w), min(max(y1, -1), h))

    def h_depth_func(self, no, name, a, args):
        if enum_arg(a[0], no, f"{name}: the function") not in DEPTH_FUNCS:
            return   # GL_INVALID_ENUM: the call does nothing
        self.s.depth_func = a[0]

    def h_depth_mask(self, no, name, a, args):
        self.s.depth_mask = gl_boolean(a[0], no, f"{name}: the flag")

    def h_clear_depth(self, no, name, a, args):
        self.s.clear_depth = clamped01(a[0], no, "the clear depth")

    def clear_bits(self, no, name, mask):
        """glClear's mask as bit names, or None when GL ignores the call
        (GL_INVALID_VALUE: a bit that names no buffer, or the accumulation
        buffer, which core and ES contexts lack)."""
        bits, unknown = bitfield(mask, no, f"{name}: the mask", CLEAR_BITS)
        if unknown:
            return None
        allowed = set(CLEAR_BITS.values()) - ({"GL_ACCUM_BUFFER_BIT"} if self.core or self.es else set())
        return bits if bits <= allowed else None

    def h_clear(self, no, name, a, args):
        bits = self.clear_bits(no, name, a[0])
        if bits is None or self.s.rasterizer_discard or self.s.render_mode != "GL_RENDER":
            # GL_INVALID_VALUE, discarded with the rasterizer, or in selection
            # or feedback mode (Mesa clears then only in GL_RENDER; glClearBuffer
            # clears in every mode): nothing is cleared.
            return
        if self.s.draw_fbo:
            self.gpu_wrote()
        if "GL_DEPTH_BUFFER_BIT" in bits:
            self.depth_clear(no, self.s.clear_depth)

    def depth_clear(self, no, value):
        """A depth clear to `value` in [0, 1] (glClear, glClearBuffer), under
        the scissor; nothing without depth writes, outside the frames, or
        while a framebuffer that is not the camera pass's is bound (its own
        depth buffer is cleared, not the frame's)."""
        if self.active and self.s.depth_mask and self.camera_pass():
            self.open_frame(no)
            self.depth_cleared(no, value, self.scissor_rect())   # (first: it may give a buffer back)
            self.emit(b"C" + struct.pack("<Qd4i", no, value, *self.scissor_rect()))

    def h_clear_buffer(self, no, name, a, args):
        """glClearBufferfv(GL_DEPTH, 0, [d]) and glClearBufferfi(GL_DEPTH_STENCIL,
        0, d, s): a depth clear as glClear's, to d clamped to [0, 1]; the
        colour and stencil forms change no depth."""
        d = dict(args)
        if self.s.draw_fbo:
            self.gpu_wrote()   # any buffer of a framebuffer object (a texture the GPU renders)
        buffer = enum_arg(d.get("buffer"), no, f"{name}: the buffer")
        if (buffer, base_name(name)) not in (("GL_DEPTH", "glClearBufferfv"), ("GL_DEPTH_STENCIL", "glClearBufferfi")):
            return
        if checked(no, integer, d.get("drawbuffer"), f"{name}: the draw buffer", *I32) != 0:
            return   # GL_INVALID_VALUE
        value = d.get("value")
        depth = value[0] if isinstance(value, list) and value else d.get("depth", value)
        depth = clamped01(depth, no, f"{name}: the depth")
        if not self.s.rasterizer_discard:
            self.depth_clear(no, depth)

    def enable(self, no, cap, on):
        s = self.s
        simple = {"GL_DEPTH_TEST": "depth_test", "GL_CULL_FACE": "cull", "GL_SCISSOR_TEST": "scissor_test",
                  "GL_POLYGON_OFFSET_FILL": "offset_fill", "GL_RASTERIZER_DISCARD": "rasterizer_discard",
                  "GL_PRIMITIVE_RESTART": "restart", "GL_PRIMITIVE_RESTART_FIXED_INDEX": "restart_fixed",
                  "GL_TEXTURE_CUBE_MAP_SEAMLESS": "cube_seamless"}
        if cap in simple:
            setattr(s, simple[cap], on)
            return
        if cap in ("GL_POLYGON_OFFSET_LINE", "GL_POLYGON_OFFSET_POINT"):
            (s.offset_other.add if on else s.offset_other.discard)(cap)
            return
        m = re.fullmatch(r"GL_CLIP_(?:PLANE|DISTANCE)(\d)", str(cap))
        if m and int(m.group(1)) < MAX_CLIP_PLANES:
            i = int(m.group(1))
            if on and s.clip_planes[i] is None:
                s.clip_planes[i] = np.zeros(4)   # GL's default plane (0,0,0,0) keeps everything
            s.clip_enabled[i] = on
            return
        if cap == "GL_BLEND":
            self.blend_enabled(on)
            return
        # GL_PRIMITIVE_RESTART_NV is a client state (glEnableClientState):
        # glEnable of it is GL_INVALID_ENUM in Mesa, as of a value no
        # enumerant has (a number: gl_registry.named_enumerants names the rest).
        if cap in CAPS_IGNORED or cap in CAPS_MESA_LACKS or cap == "GL_PRIMITIVE_RESTART_NV" or not on \
                or isinstance(cap, int):
            return
        fail_call(no, f"glEnable({printable(cap)}) is not emulated and may change geometry or visibility")

    def h_enable(self, no, name, a, args):
        self.enable(no, enum_arg(a[0], no, f"{name}: the capability"), True)

    def h_disable(self, no, name, a, args):
        self.enable(no, enum_arg(a[0], no, f"{name}: the capability"), False)

    HANDLERS = {
        "glScissor": h_scissor,
        "glScissorIndexed": h_scissor_indexed,
        "glScissorIndexedv": h_scissor_indexed,
        "glScissorArrayv": h_scissor_indexed,
        "glDepthFunc": h_depth_func,
        "glDepthMask": h_depth_mask,
        "glClearDepth": h_clear_depth,
        "glClearDepthx": fixed_point(h_clear_depth),   # OpenGL ES 1, 16.16 fixed point
        "glClearDepthf": h_clear_depth,
        "glClear": h_clear,
        "glClearBufferfv": h_clear_buffer,
        "glClearBufferfi": h_clear_buffer,
        "glClearBufferiv": h_clear_buffer,
        "glClearBufferuiv": h_clear_buffer,
        "glEnable": h_enable,
        "glDisable": h_disable,
    }
