"""The GL state that decides where a fragment lands and whether it reaches the
unit, and the handlers of the calls that change it, one module a state group:

    transform       matrix stacks, viewport, depth range, user clip planes
    per_fragment    scissor, depth test and writes, clears, glEnable/glDisable
    polygon         culling, winding, polygon offset and mode
    vertex_arrays   the vertex array and buffer objects
    draws           draw calls and immediate mode, into draw records
    objects         which object a draw is: debug groups, selection rules

Each module holds a mixin of rbcd.gl2rbt.converter.Converter whose HANDLERS
map GL function names (without ARB/EXT) to its handlers, called as
h(self, call_no, name, argument values, (name, value) arguments)."""
import numpy as np

from ..errors import fail_call
from ..gl_tables import MAX_CLIP_PLANES

# ---------------------------------------------------------------- the GL state

class Array:
    __slots__ = ("size", "type", "stride", "data", "buffer", "offset")

    def __init__(self):
        self.size, self.type, self.stride, self.data, self.buffer, self.offset = 4, "GL_FLOAT", 0, None, 0, 0


class GLState:
    def __init__(self):
        I = np.identity(4)
        self.stacks = {"GL_MODELVIEW": [I.copy()], "GL_PROJECTION": [I.copy()], "GL_TEXTURE": [I.copy()],
                       "GL_COLOR": [I.copy()]}
        self.mode = "GL_MODELVIEW"
        self.viewport = None
        self.scissor = None
        self.scissor_test = False
        self.depth_range = (0.0, 1.0)
        self.depth_test = False
        self.depth_func = "GL_LESS"
        self.depth_mask = True
        self.clear_depth = 1.0
        self.cull = False
        self.cull_face = "GL_BACK"
        self.front_face = "GL_CCW"
        self.offset_fill = False
        self.offset = (0.0, 0.0)
        self.clip_planes = [None] * MAX_CLIP_PLANES
        self.clip_enabled = [False] * MAX_CLIP_PLANES
        self.vertex_array_enabled = False
        self.vertex_array = Array()
        self.buffers = {}
        self.bound = {"GL_ARRAY_BUFFER": 0, "GL_ELEMENT_ARRAY_BUFFER": 0}
        self.texture = 0
        self.program = 0
        self.groups = []   # innermost last: object id or None
        self.begin_mode = None
        self.begin_verts = []
        self.list_compiling = False


def as_bool(v):
    if isinstance(v, str):
        return v in ("GL_TRUE", "True", "true", "1")
    return bool(v)


def number(v, no, what):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        fail_call(no, f"{what} is not a number")
    return float(v)
