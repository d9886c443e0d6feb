"""Generic vertex attributes and vertex array objects (OpenGL 2.0+ and ES):
each attribute's array (format, buffer and offset or client memory, divisor)
and its current value when the array is disabled, the element array buffer
of each vertex array object, and primitive restart."""
import hashlib

import numpy as np

from ...cli import I32, U32, U63, integer
from ..errors import checked, fail_call
from ..gl_tables import ARRAY_TYPES, INDEX_TYPES, base_name

MAX_ATTRIBS = 32   # GL_MAX_VERTEX_ATTRIBS as Mesa (llvmpipe) answers it
# Bytes a component of an attribute array (the packed formats: a quarter of
# their four-component word).
ATTRIB_SIZES = {t: np.dtype(v).itemsize for t, v in ARRAY_TYPES.items()} | {
    "GL_HALF_FLOAT_OES": 2, "GL_FIXED": 4, "GL_INT_2_10_10_10_REV": 1, "GL_UNSIGNED_INT_2_10_10_10_REV": 1}


# The attribute types Mesa 22.3 takes (GL 4.5 and OpenGL ES 3.2, 10.3.1):
# the integer ones for glVertexAttribIPointer; GL_BGRA only of
# GL_UNSIGNED_BYTE and the packed 2_10_10_10 types, normalized; the packed
# types of four components (or GL_BGRA), GL_UNSIGNED_INT_10F_11F_11F_REV of
# three.
INTEGER_ATTRIB_TYPES = {"GL_BYTE", "GL_UNSIGNED_BYTE", "GL_SHORT", "GL_UNSIGNED_SHORT", "GL_INT", "GL_UNSIGNED_INT"}
PACKED_ATTRIB_TYPES = {"GL_INT_2_10_10_10_REV", "GL_UNSIGNED_INT_2_10_10_10_REV"}
ATTRIB_TYPES = INTEGER_ATTRIB_TYPES | PACKED_ATTRIB_TYPES | {
    "GL_FLOAT", "GL_DOUBLE", "GL_HALF_FLOAT", "GL_HALF_FLOAT_ARB", "GL_HALF_FLOAT_OES", "GL_FIXED",
    "GL_UNSIGNED_INT_10F_11F_11F_REV"}


def attrib_format_valid(name, size, kind, normalized):
    """Whether glVertexAttribPointer or glVertexAttribIPointer of this size
    and type is a call Mesa takes (the size is 1 to 4 or GL_BGRA)."""
    if base_name(name) == "glVertexAttribIPointer":
        return kind in INTEGER_ATTRIB_TYPES and size != "GL_BGRA"
    if kind not in ATTRIB_TYPES:
        return False
    if size == "GL_BGRA":
        return (kind == "GL_UNSIGNED_BYTE" or kind in PACKED_ATTRIB_TYPES) and normalized
    if kind in PACKED_ATTRIB_TYPES:
        return size == 4
    return kind != "GL_UNSIGNED_INT_10F_11F_11F_REV" or size == 3


class Attrib:
    """One generic attribute's array, as glVertexAttrib*Pointer left it."""
    __slots__ = ("enabled", "call", "size", "type", "normalized", "stride", "buffer", "offset", "client", "divisor")

    def __init__(self):
        self.enabled, self.call, self.size, self.type = False, None, 4, "GL_FLOAT"
        self.normalized, self.stride, self.buffer, self.offset, self.client, self.divisor = False, 0, 0, 0, None, 0


class VertexArrayObject:
    def __init__(self):
        self.attribs = {}     # index -> Attrib
        self.element = 0      # the element array buffer
        self.fixed = None     # glVertexPointer's array (glstate.Array), made when first used
        self.fixed_enabled = False   # GL_VERTEX_ARRAY

    def attrib(self, index):
        a = self.attribs.get(index)
        if a is None:
            a = self.attribs[index] = Attrib()
        return a


def attrib_index(no, name, v):
    """The attribute index, or None when GL ignores the call for it
    (GL_INVALID_VALUE: past GL_MAX_VERTEX_ATTRIBS)."""
    v = checked(no, integer, v, f"{name}: the attribute index", *U32)
    return v if v < MAX_ATTRIBS else None


class AttributeCalls:
    """self.s.vaos: name -> VertexArrayObject (0, the default one, always
    there); self.s.vao the bound one, whose element buffer is kept in
    self.s.bound["GL_ELEMENT_ARRAY_BUFFER"] while it is bound."""

    def current_vao(self):
        return self.s.vaos[self.s.vao]

    def vertex_data_digest(self, name, d):
        """What a rule's `vertex_data` names a draw under a program by: the
        digest (BLAKE2b, 16 hex digits) of the data it reads that is its
        mesh's own, whatever the buffer's name or the data's place in it:
        an indexed draw's index type, base vertex and indices; an array
        draw's first per-vertex attribute (the lowest enabled one without a
        divisor), its format and the bytes of the vertices it draws. "" when
        that data is not in the capture."""
        h = hashlib.blake2b(digest_size=8)
        if "Elements" in name:
            kind, count, indices = d.get("type"), d["count"], d.get("indices")
            if kind not in INDEX_TYPES:
                return ""
            size = np.dtype(INDEX_TYPES[kind]).itemsize
            if isinstance(indices, (bytes, bytearray)):
                data, start = indices, 0
            else:
                data = self.s.buffers.get(self.s.bound.get("GL_ELEMENT_ARRAY_BUFFER", 0))
                start = indices if isinstance(indices, int) else 0
            if data is None or start < 0 or start + count * size > len(data):
                return ""
            h.update(repr(("elements", kind, d.get("basevertex", 0))).encode())
            h.update(bytes(data[start:start + count * size]))
            return h.hexdigest()
        for i, at in sorted(self.current_vao().attribs.items()):
            if not at.enabled or at.divisor or not isinstance(at.size, int) or at.type not in ATTRIB_SIZES:
                continue
            elem = at.size * ATTRIB_SIZES[at.type]
            stride = at.stride or elem
            first, count = d.get("first", 0), d["count"]
            data = self.s.buffers.get(at.buffer) if at.buffer else at.client
            start = (at.offset if at.buffer else 0) + first * stride
            end = start + (count - 1) * stride + elem
            if data is None or start < 0 or end > len(data):
                return ""
            h.update(repr(("arrays", at.type, at.size, stride)).encode())
            h.update(bytes(data[start:end]))
            return h.hexdigest()
        return ""

    def instance_origin(self, no, index, instance):
        """The first three components of attribute `index` of the bound
        vertex array object for one instance (a per-instance float array,
        divisor >= 1, from a buffer object): an object's position in its
        world, for group_by = "instance_origin"."""
        at = self.current_vao().attribs.get(index)
        if at is None or not at.enabled or at.divisor == 0 or not at.buffer or at.type != "GL_FLOAT" \
                or not isinstance(at.size, int):
            fail_call(no, f"group_by = \"instance_origin\": attribute {index} is not a per-instance float "
                      "array in a buffer object (settings.origin_attribute)")
        data = self.s.buffers.get(at.buffer)
        at_byte = at.offset + (instance // at.divisor) * (at.stride or 4 * at.size)
        n = min(at.size, 3)
        if data is None or at_byte < 0 or at_byte + 4 * n > len(data):
            fail_call(no, f"attribute {index}'s instance {instance} reaches past its buffer's data")
        origin = np.zeros(3)
        origin[:n] = np.frombuffer(data, dtype="<f4", count=n, offset=at_byte)
        return origin

    def h_gen_vertex_arrays(self, no, name, a, args):
        for v in dict(args).get("arrays") or []:
            if isinstance(v, int) and v > 0:
                self.s.vaos.setdefault(v, VertexArrayObject())

    def h_bind_vertex_array(self, no, name, a, args):
        v = checked(no, integer, dict(args)["array"], f"{name}: the vertex array", *U32)
        if v and v not in self.s.vaos:
            return   # not a name glGenVertexArrays gave (or one deleted): GL_INVALID_OPERATION (Mesa, every profile)
        self.current_vao().element = self.s.bound.get("GL_ELEMENT_ARRAY_BUFFER", 0)
        self.s.vao = v
        vao = self.s.vaos.setdefault(v, VertexArrayObject())
        self.s.bound["GL_ELEMENT_ARRAY_BUFFER"] = vao.element

    def h_delete_vertex_arrays(self, no, name, a, args):
        for v in dict(args).get("arrays") or []:
            if isinstance(v, int) and v > 0 and v in self.s.vaos:
                if v == self.s.vao:
                    self.h_bind_vertex_array(no, name, a, [("array", 0)])
                del self.s.vaos[v]

    def h_enable_attrib(self, no, name, a, args):
        i = attrib_index(no, name, dict(args)["index"])
        if i is not None:
            self.current_vao().attrib(i).enabled = name.startswith("glEnable")

    def h_attrib_pointer(self, no, name, a, args):
        d = dict(args)
        i = attrib_index(no, name, d["index"])
        size = d["size"]
        stride = checked(no, integer, d.get("stride", 0), f"{name}: the stride", *I32)
        from . import gl_boolean   # the package imports this module before it defines gl_boolean
        normalized = gl_boolean(d.get("normalized", "GL_FALSE"), no, f"{name}: normalized", nonzero=True)
        if i is None or not (size in (1, 2, 3, 4) or size == "GL_BGRA") or stride < 0:
            return   # GL_INVALID_VALUE: the call does nothing
        if not attrib_format_valid(name, size, d.get("type"), normalized):
            return   # GL_INVALID_ENUM, GL_INVALID_VALUE or GL_INVALID_OPERATION in Mesa: the earlier pointer stays
        at = self.current_vao().attrib(i)
        at.call, at.size, at.type, at.stride = name, size, d.get("type"), stride
        at.normalized = normalized
        p = d.get("pointer")
        at.buffer = self.s.bound.get("GL_ARRAY_BUFFER", 0)
        if at.buffer:
            # An offset into the buffer: what a pointer holds.
            at.offset = checked(no, integer, 0 if p is None else p, f"{name}: the buffer offset", *U63)
            at.client = None
        else:
            # Client memory: apitrace records what the draws read as a blob.
            at.offset, at.client = 0, p if isinstance(p, (bytes, bytearray)) else None

    def h_attrib_divisor(self, no, name, a, args):
        d = dict(args)
        i = attrib_index(no, name, d["index"])
        div = checked(no, integer, d["divisor"], f"{name}: the divisor", *U32)
        if i is not None:
            self.current_vao().attrib(i).divisor = div

    def h_attrib_value(self, no, name, a, args):
        """glVertexAttrib*: the value of a disabled attribute, replayed as called."""
        i = attrib_index(no, name, a[0])
        for v in a[1:]:
            for x in v if isinstance(v, list) else [v]:
                if isinstance(x, bool) or not isinstance(x, (int, float)):
                    fail_call(no, f"{name}: a value that is not a number")
        if i is not None:
            self.s.attrib_values[i] = (name, list(a[1:]))

    def h_primitive_restart_index(self, no, name, a, args):
        self.s.restart_index = checked(no, integer, a[0], f"{name}: the index", *U32)

    HANDLERS = {
        "glGenVertexArrays": h_gen_vertex_arrays,
        "glBindVertexArray": h_bind_vertex_array,
        "glDeleteVertexArrays": h_delete_vertex_arrays,
        "glEnableVertexAttribArray": h_enable_attrib,
        "glDisableVertexAttribArray": h_enable_attrib,
        "glVertexAttribPointer": h_attrib_pointer,
        "glVertexAttribIPointer": h_attrib_pointer,
        "glVertexAttribDivisor": h_attrib_divisor,
        "glPrimitiveRestartIndex": h_primitive_restart_index,
        "glPrimitiveRestartIndexNV": h_primitive_restart_index,
    } | dict.fromkeys([f"glVertexAttrib{n}{t}{v}" for n in "1234" for t in ("f", "d", "s") for v in ("", "v")]
                     + [f"glVertexAttribI4{t}{v}" for t in ("i", "ui") for v in ("", "v")]
                     + [f"glVertexAttrib4N{t}v" for t in ("b", "s", "i", "ub", "us", "ui")]
                     + [f"glVertexAttrib4{t}v" for t in ("b", "i", "ub", "us", "ui")], h_attrib_value)
