"""Generic vertex attributes and vertex array objects (OpenGL 2.0+ and ES),
in GL 4.3's terms (ARB_vertex_attrib_binding, ES 3.1): each attribute's
format and the vertex buffer binding it reads (buffer and offset or client
memory, stride, divisor), which glVertexAttrib*Pointer sets both of, as GL
defines it; its current value when the array is disabled; the element array
buffer of each vertex array object; the direct-state-access forms (GL 4.5)
naming the vertex array object; primitive restart."""
import hashlib

import numpy as np

from ...cli import I32, I64, U32, U63, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import ARRAY_TYPES, INDEX_TYPES, base_name

# As Mesa 22.3 (llvmpipe) answers them, in GL 4.5 and ES 3.2 contexts alike:
# GL_MAX_VERTEX_ATTRIBS, GL_MAX_VERTEX_ATTRIB_BINDINGS,
# GL_MAX_VERTEX_ATTRIB_RELATIVE_OFFSET, GL_MAX_VERTEX_ATTRIB_STRIDE.
MAX_ATTRIBS = 16
MAX_VERTEX_BINDINGS = 16
MAX_RELATIVE_OFFSET = 2047
MAX_STRIDE = 2048
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


def attrib_format_valid(integer_form, size, kind, normalized, long_form=False):
    """Whether a format of this size and type (glVertexAttrib*Pointer,
    glVertexAttrib*Format; integer_form for their I forms) is one Mesa takes:
    a size of 1 to 4 or GL_BGRA (GL_INVALID_VALUE otherwise), a type and
    size of the rules above."""
    if not (size in (1, 2, 3, 4) or size == "GL_BGRA"):
        return False
    if long_form:   # the L forms (GL 4.1): doubles read as doubles
        return kind == "GL_DOUBLE" and size != "GL_BGRA"
    if integer_form:
        return kind in INTEGER_ATTRIB_TYPES and size != "GL_BGRA"
    if kind not in ATTRIB_TYPES:
        return False
    if size == "GL_BGRA":
        return (kind == "GL_UNSIGNED_BYTE" or kind in PACKED_ATTRIB_TYPES) and normalized
    if kind in PACKED_ATTRIB_TYPES:
        return size == 4
    return kind != "GL_UNSIGNED_INT_10F_11F_11F_REV" or size == 3


class Attrib:
    """One generic attribute: its format (glVertexAttrib*Format, or that half
    of glVertexAttrib*Pointer; `integer` for the I forms; `format_call` the
    (call number, name) that set it, None for GL's initial one) and the
    binding point it reads."""
    __slots__ = ("enabled", "integer", "long", "size", "type", "normalized", "relative", "binding", "format_call")

    def __init__(self, index):
        self.enabled, self.integer, self.size, self.type, self.normalized = False, False, 4, "GL_FLOAT", False
        self.long = False   # the L forms: 64-bit doubles
        self.relative, self.binding = 0, index
        self.format_call = None


class Binding:
    """A vertex buffer binding point: a buffer and an offset into it, or
    client memory (glVertexAttribPointer with no buffer bound: apitrace
    records what the draws read as a blob); the stride (0 reads one element
    for every vertex: glVertexAttribPointer's 0 is the packed size, as GL
    defines it); the divisor."""
    __slots__ = ("buffer", "offset", "client", "stride", "divisor")

    def __init__(self):
        self.buffer, self.offset, self.client, self.stride, self.divisor = 0, 0, None, 16, 0


def element_bytes(size, kind):
    """Bytes of one element of an attribute of `size` components of `kind`
    (GL_BGRA: four; a packed type's element is one 32-bit word, whatever its
    size)."""
    if kind in PACKED_ATTRIB_TYPES or kind == "GL_UNSIGNED_INT_10F_11F_11F_REV":
        return 4
    return (4 if size == "GL_BGRA" else size) * ATTRIB_SIZES.get(kind, 4)


class VertexArrayObject:
    def __init__(self):
        self.attribs = {}     # index -> Attrib
        self.bindings = {}    # binding index -> Binding
        self.element = 0      # the element array buffer
        self.exists = False   # bound once, or made by glCreateVertexArrays (what direct state access names)
        self.fixed = None     # glVertexPointer's array (glstate.Array), made when first used
        self.fixed_enabled = False   # GL_VERTEX_ARRAY

    def attrib(self, index):
        a = self.attribs.get(index)
        if a is None:
            a = self.attribs[index] = Attrib(index)
        return a

    def binding(self, index):
        b = self.bindings.get(index)
        if b is None:
            b = self.bindings[index] = Binding()
        return b

    def sources(self):
        """(index, attribute, its binding) of every attribute, by index."""
        return [(i, at, self.binding(at.binding)) for i, at in sorted(self.attribs.items())]


def attrib_size(v):
    """An attribute's size as the handlers compare it: GL_BGRA by name
    (apitrace records glVertexAttribFormat's as the number 0x80E1)."""
    return "GL_BGRA" if v in ("GL_BGRA", 0x80E1) and not isinstance(v, bool) else v


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

    def vao_named(self, no, name, v):
        """The vertex array object a direct-state-access call names, or None
        when GL ignores the call (GL_INVALID_OPERATION: 0, or not a name
        glCreateVertexArrays made or glBindVertexArray bound)."""
        v = checked(no, integer, v, f"{name}: the vertex array", *U32)
        vao = self.s.vaos.get(v) if v else None
        return vao if vao is not None and vao.exists else None

    def vao_to_set(self, name):
        """The bound vertex array object, or None when GL ignores a call of
        vertex attribute binding on it (GL_INVALID_OPERATION: the default
        one, in a core profile or OpenGL ES, as Mesa 22.3 has it)."""
        return None if (self.core or self.es) and not self.s.vao else self.current_vao()

    def vao_of(self, no, name, d):
        """The vertex array object a call of vertex attribute binding sets:
        the one a direct-state-access form names (vaobj), or the bound one;
        None when GL ignores the call."""
        return self.vao_named(no, name, d["vaobj"]) if "vaobj" in d else self.vao_to_set(name)

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
        vao = self.current_vao()
        arrays = [(at.type, at.size, b.stride, b.buffer, b.client, b.offset + at.relative)
                  for i, at, b in vao.sources() if at.enabled and not b.divisor and isinstance(at.size, int)
                  and at.type in ATTRIB_SIZES]
        if vao.fixed_enabled and vao.fixed is not None and vao.fixed.type in ATTRIB_SIZES:
            # gl_Vertex from the vertex array (glVertexPointer), last: a
            # compatibility profile's GL 2.x program.
            f = vao.fixed
            arrays.append((f.type, f.size, f.stride or f.size * ATTRIB_SIZES[f.type], f.buffer, f.data, f.offset))
        for kind, size, stride, buf, client, offset in arrays[:1]:
            elem = size * ATTRIB_SIZES[kind]
            first, count = d.get("first", 0), d["count"]
            data = self.s.buffers.get(buf) if buf else client
            start = offset + first * stride   # (client memory: from its start, offset 0 or relative)
            end = start + (count - 1) * stride + elem
            if data is None or start < 0 or end > len(data):
                return ""
            h.update(repr(("arrays", kind, size, stride)).encode())
            h.update(bytes(data[start:end]))
            return h.hexdigest()
        return ""

    def instance_origin(self, no, index, instance):
        """The first three components of attribute `index` of the bound
        vertex array object for one instance (a per-instance float array,
        divisor >= 1, from a buffer object): an object's position in its
        world, for group_by = "instance_origin"."""
        vao = self.current_vao()
        at = vao.attribs.get(index)
        b = vao.binding(at.binding) if at is not None else None
        if at is None or not at.enabled or b.divisor == 0 or not b.buffer or at.type != "GL_FLOAT" \
                or not isinstance(at.size, int):
            fail_call(no, f"group_by = \"instance_origin\": attribute {index} is not a per-instance float "
                      "array in a buffer object (settings.origin_attribute)")
        data = self.s.buffers.get(b.buffer)
        at_byte = b.offset + at.relative + (instance // b.divisor) * b.stride
        n = min(at.size, 3)
        if data is None or at_byte < 0 or at_byte + 4 * n > len(data):
            fail_call(no, f"attribute {index}'s instance {instance} reaches past its buffer's data")
        origin = np.zeros(3)
        origin[:n] = np.frombuffer(data, dtype="<f4", count=n, offset=at_byte)
        return origin

    def h_gen_vertex_arrays(self, no, name, a, args):
        """glGenVertexArrays: names, whose objects exist once bound;
        glCreateVertexArrays: objects at once (direct state access)."""
        names = dict(args).get("arrays") or []
        if isinstance(names, list) and names and dict(args).get("n") != len(names):
            fail_call(no, f"{name}: {len(names)} names, not its count ({printable(dict(args).get('n'), 40)})")
        for v in names:
            if isinstance(v, int) and not isinstance(v, bool) and 0 < v < 1 << 32:
                vao = self.s.vaos.setdefault(v, VertexArrayObject())
                vao.exists = vao.exists or base_name(name) == "glCreateVertexArrays"

    def h_bind_vertex_array(self, no, name, a, args):
        v = checked(no, integer, dict(args)["array"], f"{name}: the vertex array", *U32)
        if v and v not in self.s.vaos:
            return   # not a name glGenVertexArrays gave (or one deleted): GL_INVALID_OPERATION (Mesa, every profile)
        self.current_vao().element = self.s.bound.get("GL_ELEMENT_ARRAY_BUFFER", 0)
        self.s.vao = v
        vao = self.s.vaos.setdefault(v, VertexArrayObject())
        vao.exists = True
        self.s.bound["GL_ELEMENT_ARRAY_BUFFER"] = vao.element

    def h_delete_vertex_arrays(self, no, name, a, args):
        for v in dict(args).get("arrays") or []:
            if isinstance(v, int) and v > 0 and v in self.s.vaos:
                if v == self.s.vao:
                    self.h_bind_vertex_array(no, name, a, [("array", 0)])
                del self.s.vaos[v]

    def h_enable_attrib(self, no, name, a, args):
        d = dict(args)
        dsa = "vaobj" in d
        vao = self.vao_named(no, name, d["vaobj"]) if dsa else self.current_vao()
        i = attrib_index(no, name, d["index"])
        if i is not None and vao is not None:
            vao.attrib(i).enabled = name.startswith("glEnable")

    def h_attrib_pointer(self, no, name, a, args):
        """glVertexAttrib*Pointer: the attribute's format, and binding point
        `index` (which the attribute then reads) on the bound array buffer
        at the pointer's offset, or on client memory; a stride of 0 is the
        element's size there."""
        d = dict(args)
        i = attrib_index(no, name, d["index"])
        size = attrib_size(d["size"])
        stride = checked(no, integer, d.get("stride", 0), f"{name}: the stride", *I32)
        from . import gl_boolean   # the package imports this module before it defines gl_boolean
        normalized = gl_boolean(d.get("normalized", "GL_FALSE"), no, f"{name}: normalized", nonzero=True)
        integer_form = base_name(name) == "glVertexAttribIPointer"
        long_form = base_name(name) == "glVertexAttribLPointer"
        if i is None or stride < 0 or \
                not attrib_format_valid(integer_form, size, d.get("type"), normalized, long_form):
            return   # GL_INVALID_ENUM, GL_INVALID_VALUE or GL_INVALID_OPERATION in Mesa: the earlier pointer stays
        vao = self.current_vao()
        at = vao.attrib(i)
        at.integer, at.size, at.type, at.relative, at.binding = integer_form, size, d.get("type"), 0, i
        at.long, at.format_call = long_form, (no, name)
        at.normalized = not integer_form and not long_form and normalized
        b = vao.binding(i)
        b.stride = stride or element_bytes(size, at.type)
        p = d.get("pointer")
        b.buffer = self.s.bound.get("GL_ARRAY_BUFFER", 0)
        if b.buffer:
            # An offset into the buffer: what a pointer holds.
            b.offset = checked(no, integer, 0 if p is None else p, f"{name}: the buffer offset", *U63)
            b.client = None
        else:
            # Client memory: apitrace records what the draws read as a blob.
            b.offset, b.client = 0, p if isinstance(p, (bytes, bytearray)) else None

    def h_attrib_format(self, no, name, a, args):
        """glVertexAttrib(I)Format and glVertexArrayAttrib(I)Format: an
        attribute's format alone, at a relative offset into its binding's
        elements."""
        d = dict(args)
        vao = self.vao_of(no, name, d)
        i = attrib_index(no, name, d["attribindex"])
        size = attrib_size(d["size"])
        relative = checked(no, integer, d.get("relativeoffset", 0), f"{name}: the relative offset", *U32)
        integer_form = base_name(name) in ("glVertexAttribIFormat", "glVertexArrayAttribIFormat")
        long_form = base_name(name) in ("glVertexAttribLFormat", "glVertexArrayAttribLFormat")
        from . import gl_boolean   # the package imports this module before it defines gl_boolean
        normalized = gl_boolean(d.get("normalized", "GL_FALSE"), no, f"{name}: normalized", nonzero=True)
        if vao is None or i is None or relative > MAX_RELATIVE_OFFSET \
                or not attrib_format_valid(integer_form, size, d.get("type"), normalized, long_form):
            return   # GL_INVALID_OPERATION, GL_INVALID_VALUE or GL_INVALID_ENUM: the call does nothing
        at = vao.attrib(i)
        at.integer, at.size, at.type, at.relative = integer_form, size, d.get("type"), relative
        at.long, at.format_call = long_form, (no, name)
        at.normalized = not integer_form and not long_form and normalized

    def h_attrib_binding(self, no, name, a, args):
        """glVertexAttribBinding, glVertexArrayAttribBinding: which binding
        point an attribute reads."""
        d = dict(args)
        vao = self.vao_of(no, name, d)
        i = attrib_index(no, name, d["attribindex"])
        point = checked(no, integer, d["bindingindex"], f"{name}: the binding index", *U32)
        if vao is not None and i is not None and point < MAX_VERTEX_BINDINGS:
            vao.attrib(i).binding = point

    def bind_vertex_buffer(self, no, name, vao, point, buf, offset, stride):
        """One binding point's buffer, offset and stride, as GL sets them:
        an error (GL_INVALID_VALUE: a point, offset or stride out of range;
        GL_INVALID_OPERATION: a name a core profile does not take) leaves
        the point as it was."""
        if point >= MAX_VERTEX_BINDINGS or offset < 0 or not 0 <= stride <= MAX_STRIDE or not self.generated(buf):
            return
        b = vao.binding(point)
        b.buffer, b.offset, b.stride, b.client = buf, offset if buf else 0, stride, None

    def h_bind_vertex_buffer(self, no, name, a, args):
        """glBindVertexBuffer, glVertexArrayVertexBuffer."""
        d = dict(args)
        vao = self.vao_of(no, name, d)
        point = checked(no, integer, d["bindingindex"], f"{name}: the binding index", *U32)
        buf = checked(no, integer, d["buffer"], f"{name}: the buffer", *U32)
        offset = checked(no, integer, d.get("offset", 0), f"{name}: the offset", *I64)
        stride = checked(no, integer, d.get("stride", 0), f"{name}: the stride", *I32)
        if vao is not None:
            self.bind_vertex_buffer(no, name, vao, point, buf, offset, stride)

    def h_bind_vertex_buffers(self, no, name, a, args):
        """glBindVertexBuffers, glVertexArrayVertexBuffers (GL 4.4/4.5
        multi-bind): points first .. first + count - 1, or none of them
        (GL_INVALID_OPERATION: past the last point); no buffers unbinds
        them all; an entry in error (a name that is no buffer object, in
        every profile) is left and the others are bound."""
        d = dict(args)
        vao = self.vao_of(no, name, d)
        first = checked(no, integer, d["first"], f"{name}: the first binding", *U32)
        count = checked(no, integer, d["count"], f"{name}: the count", *I32)
        if vao is None or count < 0 or first + count > MAX_VERTEX_BINDINGS:
            return
        buffers, offsets, strides = d.get("buffers"), d.get("offsets"), d.get("strides")
        if buffers in (None, 0):   # NULL (apitrace records it as 0)
            for k in range(count):
                self.bind_vertex_buffer(no, name, vao, first + k, 0, 0, 16)
            return
        if not all(isinstance(v, list) and len(v) >= count for v in (buffers, offsets, strides)):
            fail_call(no, f"{name}: the buffers, offsets and strides are not {count} values each")
        for k in range(count):
            buf = checked(no, integer, buffers[k], f"{name}: a buffer", *U32)
            if buf and buf not in self.s.buffer_objects:
                continue   # no such buffer (a multi-bind creates none, in any profile): the point stays
            self.bind_vertex_buffer(no, name, vao, first + k, buf,
                                    checked(no, integer, offsets[k], f"{name}: an offset", *I64),
                                    checked(no, integer, strides[k], f"{name}: a stride", *I32))

    def h_attrib_divisor(self, no, name, a, args):
        """glVertexAttribDivisor: binding point `index` for the attribute,
        with that divisor (as GL defines it)."""
        d = dict(args)
        i = attrib_index(no, name, d["index"])
        div = checked(no, integer, d["divisor"], f"{name}: the divisor", *U32)
        if i is not None:
            vao = self.current_vao()
            vao.attrib(i).binding = i
            vao.binding(i).divisor = div

    def h_binding_divisor(self, no, name, a, args):
        """glVertexBindingDivisor, glVertexArrayBindingDivisor."""
        d = dict(args)
        vao = self.vao_of(no, name, d)
        point = checked(no, integer, d["bindingindex"], f"{name}: the binding index", *U32)
        div = checked(no, integer, d["divisor"], f"{name}: the divisor", *U32)
        if vao is not None and point < MAX_VERTEX_BINDINGS:
            vao.binding(point).divisor = div

    def h_element_buffer(self, no, name, a, args):
        """glVertexArrayElementBuffer: the element array buffer of the named
        vertex array object (the generic binding's too when it is bound)."""
        d = dict(args)
        vao = self.vao_named(no, name, d["vaobj"])
        buf = checked(no, integer, d["buffer"], f"{name}: the buffer", *U32)
        if vao is None or not self.generated(buf):
            return
        if vao is self.current_vao():
            self.s.bound["GL_ELEMENT_ARRAY_BUFFER"] = buf
        else:
            vao.element = buf

    def h_attrib_value(self, no, name, a, args):
        """glVertexAttrib*: the value of a disabled attribute, replayed as called."""
        i = attrib_index(no, name, a[0])
        for v in a[1:]:
            for x in v if isinstance(v, list) else [v]:
                if isinstance(x, bool) or not isinstance(x, (int, float)):
                    fail_call(no, f"{name}: a value that is not a number")
        if i is not None:
            self.s.attrib_values[i] = (name, list(a[1:]))

    def h_attrib_packed_value(self, no, name, a, args):
        """glVertexAttribP{1,2,3,4}ui(v) (GL 3.3): a disabled attribute's value
        packed in one integer, replayed as called; a type Mesa does not take
        for it is GL_INVALID_ENUM and changes nothing."""
        d = dict(args)
        i = attrib_index(no, name, d.get("index"))
        from . import gl_boolean   # the package imports this module before it defines gl_boolean
        normalized = gl_boolean(d.get("normalized", "GL_FALSE"), no, f"{name}: normalized", nonzero=True)
        value = d.get("value")
        if isinstance(value, list):
            value = value[0] if len(value) == 1 else None
        value = checked(no, integer, value, f"{name}: the value", *U32)
        kind = d.get("type")
        if i is None or kind not in PACKED_ATTRIB_TYPES and not (kind == "GL_UNSIGNED_INT_10F_11F_11F_REV"
                                                                and "P3" in name):
            return
        self.s.attrib_values[i] = (name, [kind, normalized, value])

    def h_primitive_restart_index(self, no, name, a, args):
        self.s.restart_index = checked(no, integer, a[0], f"{name}: the index", *U32)

    HANDLERS = {
        "glGenVertexArrays": h_gen_vertex_arrays,
        "glCreateVertexArrays": h_gen_vertex_arrays,
        "glBindVertexArray": h_bind_vertex_array,
        "glDeleteVertexArrays": h_delete_vertex_arrays,
        "glEnableVertexAttribArray": h_enable_attrib,
        "glDisableVertexAttribArray": h_enable_attrib,
        "glEnableVertexArrayAttrib": h_enable_attrib,
        "glDisableVertexArrayAttrib": h_enable_attrib,
        "glVertexAttribPointer": h_attrib_pointer,
        "glVertexAttribIPointer": h_attrib_pointer,
        "glVertexAttribLPointer": h_attrib_pointer,
        "glVertexAttribLFormat": h_attrib_format,
        "glVertexArrayAttribLFormat": h_attrib_format,
        "glVertexAttribDivisor": h_attrib_divisor,
        "glVertexAttribFormat": h_attrib_format,
        "glVertexAttribIFormat": h_attrib_format,
        "glVertexArrayAttribFormat": h_attrib_format,
        "glVertexArrayAttribIFormat": h_attrib_format,
        "glVertexAttribBinding": h_attrib_binding,
        "glVertexArrayAttribBinding": h_attrib_binding,
        "glBindVertexBuffer": h_bind_vertex_buffer,
        "glVertexArrayVertexBuffer": h_bind_vertex_buffer,
        "glBindVertexBuffers": h_bind_vertex_buffers,
        "glVertexArrayVertexBuffers": h_bind_vertex_buffers,
        "glVertexBindingDivisor": h_binding_divisor,
        "glVertexArrayBindingDivisor": h_binding_divisor,
        "glVertexArrayElementBuffer": h_element_buffer,
        "glPrimitiveRestartIndex": h_primitive_restart_index,
        "glPrimitiveRestartIndexNV": h_primitive_restart_index,
    } | dict.fromkeys([f"glVertexAttrib{n}{t}{v}" for n in "1234" for t in ("f", "d", "s") for v in ("", "v")]
                     + [f"glVertexAttribI{n}{t}{v}" for n in "1234" for t in ("i", "ui") for v in ("", "v")]
                     + [f"glVertexAttribI4{t}v" for t in ("b", "s", "ub", "us")]
                     + [f"glVertexAttrib4N{t}v" for t in ("b", "s", "i", "ub", "us", "ui")] + ["glVertexAttrib4Nub"]
                     + [f"glVertexAttrib4{t}v" for t in ("b", "i", "ub", "us", "ui")]
                     + [f"glVertexAttribL{n}d{v}" for n in "1234" for v in ("", "v")], h_attrib_value) \
      | dict.fromkeys([f"glVertexAttribP{n}ui{v}" for n in "1234" for v in ("", "v")], h_attrib_packed_value)


def check_vertex_data(conv, no, name, d, instances, client_indices, reads_vertex, left_out=False):
    """What a draw reads must be data the capture holds: apitrace records,
    for each client array and for client indices, the bytes the draw reads,
    and a buffer object's data as the capture gave it. An indexed draw with
    no element array buffer bound and no indices recorded (an offset, which
    would be an address), and client data shorter than the draw reads (a
    capture cut or altered, or apitrace's blob of no bytes for an ES
    half-float array), are the capture's errors: Mesa would read memory
    outside it. Indices, a first or instances that reach outside an
    attribute's buffer object are refused too: GL leaves what they read
    undefined, and Mesa 22.3's llvmpipe, which read zeros just past a
    buffer's end, crashed far past it (round 31's R31-6). A draw left out
    (`left_out`: another pass's, which Mesa is never given) is checked for
    what it reads of buffer objects alike, GL leaving it undefined; its
    client data, which nothing reads, is not (apitrace records none for an
    ES half-float array). `reads_vertex`: the program reads gl_Vertex (the
    fixed-function vertex array then read too)."""
    lo = hi = None   # the vertices an indexed draw reads, basevertex added
    if "Elements" in name:
        kind = np.dtype(INDEX_TYPES[d["type"]])
        if client_indices is None:
            elem = conv.s.bound.get("GL_ELEMENT_ARRAY_BUFFER", 0)
            if not elem:
                fail_call(no, f"{name}: no element array buffer is bound and the capture holds no indices "
                          f"(indices at address {d.get('indices') or 0})")
            data = conv.checked_buffer(no, name, elem, "indices") or b""
            start = d.get("indices") or 0
            if start + d["count"] * kind.itemsize > len(data):
                # GL leaves what they read undefined (round 16's R16-8: 2^22
                # of them past a 12-byte buffer ran Mesa to 1.9 GB).
                fail_call(no, f"{name}: {d['count']} indices from byte {start} reach past element "
                          f"buffer {elem}'s {len(data)} bytes: not emulated")
            idx = np.frombuffer(data, dtype=kind, count=d["count"], offset=start)
        else:
            if len(client_indices) < d["count"] * kind.itemsize:
                if left_out:
                    return
                fail_call(no, f"{name}: the capture's indices are {len(client_indices)} bytes, the draw reads "
                          f"{d['count'] * kind.itemsize}")
            idx = np.frombuffer(client_indices, dtype=kind, count=d["count"])
        if conv.s.restart_fixed:
            idx = idx[idx != (1 << 8 * kind.itemsize) - 1]
        elif conv.s.restart:
            idx = idx[idx != conv.s.restart_index]
        if len(idx):
            lo, hi = int(idx.min()) + d.get("basevertex", 0), int(idx.max()) + d.get("basevertex", 0)
            if lo < 0:
                fail_call(no, f"{name}: index {int(idx.min())} with base vertex {d.get('basevertex', 0)} reads "
                          "before every attribute's data: not emulated")
    vao = conv.current_vao()
    sources = vao.sources()
    if reads_vertex and conv.s.vertex_array_enabled and not (0 in vao.attribs and vao.attribs[0].enabled):
        sources.append(("0 (the vertex array)",) + fixed_source(conv.s.vertex_array))
    for i, at, b in sources:
        held = b.client if not b.buffer else conv.s.buffers.get(b.buffer)
        if not at.enabled or held is None:
            continue   # (a buffer that holds no data is refused where Mesa is given it)
        if b.divisor:
            n = d.get("baseinstance", 0) + (instances - 1) // b.divisor + 1
        elif "Elements" in name:
            n = hi + 1 if hi is not None else 0
        else:
            n = d.get("first", 0) + d["count"]
        # (client memory: from the array's start, offset 0 or relative)
        need = (b.offset if b.buffer else 0) + at.relative + (n - 1) * b.stride + element_bytes(at.size, at.type) \
            if n > 0 else 0
        if len(held) >= need:
            continue
        if not b.buffer:
            if left_out:
                continue
            fail_call(no, f"{name}: attribute {i}'s client array in the capture is {len(held)} bytes, "
                      f"the draw reads {need}")
        what = f"index {hi - d.get('basevertex', 0)}" if "Elements" in name and not b.divisor else \
            f"instance {n - 1}" if b.divisor else f"vertex {n - 1}"
        fail_call(no, f"{name}: {what} reads attribute {i} past buffer {b.buffer}'s {len(held)} bytes "
                  f"({need} read): not emulated")


def fixed_source(arr):
    """The fixed-function vertex array as the generic attribute and binding
    that give it to Mesa (VertexStage.fixed_vertex_array)."""
    at, b = Attrib(0), Binding()
    at.enabled, at.size, at.type = True, arr.size, arr.type
    b.buffer, b.offset, b.stride = arr.buffer, arr.offset, arr.stride or element_bytes(arr.size, arr.type)
    b.client = None if arr.buffer else arr.data
    return at, b
