"""The fixed-function vertex array: where a GL 1.x draw's positions come from."""
import numpy as np

from ...cli import I32, U63, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import ARRAY_TYPES, INDEX_TYPES
from . import enum_arg

# The types glVertexPointer takes (Mesa 22.3): desktop GL's, and OpenGL ES 1's.
VERTEX_POINTER_TYPES = {"GL_SHORT", "GL_INT", "GL_FLOAT", "GL_DOUBLE", "GL_HALF_FLOAT", "GL_INT_2_10_10_10_REV",
                        "GL_UNSIGNED_INT_2_10_10_10_REV"}
VERTEX_POINTER_TYPES_ES = {"GL_BYTE", "GL_SHORT", "GL_FLOAT", "GL_FIXED"}
# OpenGL ES 1's GL_FIXED: 32-bit integers of 16.16 fixed point.
FIXED_SCALE = 1.0 / 65536.0


class VertexArrayCalls:
    """The client vertex array (glVertexPointer), from client memory or a buffer object."""

    # ---- vertex data
    def array_values(self, arr, first, count, no):
        """(count, 4) float64 positions of vertices first .. first+count-1."""
        fixed = arr.type == "GL_FIXED"
        if (arr.type not in ARRAY_TYPES and not fixed) or arr.size not in (2, 3, 4):
            fail_call(no, f"vertex array of {arr.size} x {printable(arr.type)} is not emulated")
        dt = np.dtype("<i4" if fixed else ARRAY_TYPES[arr.type])
        elem = dt.itemsize * arr.size
        stride = arr.stride or elem
        if arr.buffer:
            buf = self.checked_buffer(no, "the draw", arr.buffer, "vertices")
            if buf is None:
                fail_call(no, f"the vertex array names buffer {arr.buffer}, which holds no data")
            data, base = buf, arr.offset
        else:
            data, base = arr.data, 0
            if data is None:
                fail_call(no, "the vertex array has no data in the capture")
        if count == 0:
            return np.zeros((0, 4))
        start = base + first * stride
        end = start + (count - 1) * stride + elem
        if first < 0 or start < 0 or end > len(data):
            fail_call(no, f"vertices {first}..{first + count - 1} reach past the vertex array's "
                      f"{len(data)} bytes")
        raw = np.frombuffer(data, dtype=np.uint8, count=end - start, offset=start)
        if stride == elem:
            v = raw.view(dt).reshape(count, arr.size)
        else:
            v = np.lib.stride_tricks.as_strided(raw, shape=(count, elem), strides=(stride, 1)).copy().view(dt) \
                .reshape(count, arr.size)
        out = np.zeros((count, 4))
        out[:, 3] = 1.0
        out[:, :arr.size] = v * FIXED_SCALE if fixed else v
        return out

    def index_values(self, type_, indices, count, no):
        if type_ not in INDEX_TYPES:
            fail_call(no, f"index type {printable(type_)} is not allowed")
        dt = np.dtype(INDEX_TYPES[type_])
        eb = self.s.bound["GL_ELEMENT_ARRAY_BUFFER"]
        if eb:
            buf = self.checked_buffer(no, "the draw", eb, "indices")
            if buf is None:
                fail_call(no, f"the element array buffer {eb} holds no data")
            # An offset into the element buffer: what a pointer holds.
            off = checked(no, integer, 0 if indices is None else indices, "the index buffer offset", *U63)
            data = buf
        else:
            if not isinstance(indices, (bytes, bytearray)):
                fail_call(no, "the indices are not in the capture")
            data, off = indices, 0
        need = off + count * dt.itemsize
        if off < 0 or need > len(data):
            fail_call(no, f"{count} indices reach past the index data's {len(data)} bytes")
        return np.frombuffer(data, dtype=dt, count=count, offset=off).astype(np.int64)

    def h_client_state(self, no, name, a, args):
        if a[0] == "GL_VERTEX_ARRAY":
            self.s.vertex_array_enabled = name.startswith("glEnable")
        elif a[0] == "GL_PRIMITIVE_RESTART_NV":
            # NV_primitive_restart's switch: GL_PRIMITIVE_RESTART's state in Mesa.
            self.s.restart = name.startswith("glEnable")

    def h_vertex_pointer(self, no, name, a, args):
        d = dict(args)
        size = checked(no, integer, d.get("size", 4), f"{name}: the size", *I32)
        stride = checked(no, integer, d.get("stride", 0), f"{name}: the stride", *I32)
        kind = enum_arg(d.get("type", "GL_FLOAT"), no, f"{name}: the type")
        # Mesa's rules for desktop GL: the call does nothing otherwise.
        if kind not in (VERTEX_POINTER_TYPES_ES if self.es else VERTEX_POINTER_TYPES):
            return   # GL_INVALID_ENUM
        if not 2 <= size <= 4:
            return   # GL_INVALID_VALUE
        if kind.endswith("2_10_10_10_REV") and size != 4:
            return   # GL_INVALID_OPERATION
        if stride < 0:
            # GL_INVALID_VALUE, which Mesa 22.3 reports and yet keeps the
            # stride: its draws then fetch before the array's start.
            fail_call(no, f"{name}: a negative stride ({stride}): GL ignores the call, Mesa keeps the stride and "
                      "reads outside the array; not emulated")
        arr = self.s.vertex_array
        arr.size, arr.type, arr.stride = size, kind, stride
        p = d.get("pointer")
        arr.buffer = self.s.bound["GL_ARRAY_BUFFER"]
        if arr.buffer:
            # An offset into the buffer: what a pointer holds.
            arr.offset = checked(no, integer, 0 if p is None else p, f"{name}: the buffer offset", *U63)
            arr.data = None
        else:
            arr.offset = 0
            arr.data = p if isinstance(p, (bytes, bytearray)) else None

    def h_interleaved(self, no, name, a, args):
        fail_call(no, "glInterleavedArrays is not emulated")

    def vertex_source(self, no, name):
        if not self.s.vertex_array_enabled:
            fail_call(no, f"{name} with the vertex array disabled (generic attributes are not emulated)")
        return self.s.vertex_array

    HANDLERS = {
        "glEnableClientState": h_client_state,
        "glDisableClientState": h_client_state,
        "glVertexPointer": h_vertex_pointer,
        "glInterleavedArrays": h_interleaved,
    }
