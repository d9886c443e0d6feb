"""Generic vertex attributes and vertex array objects (OpenGL 2.0+ and ES):
each attribute's array (format, buffer and offset or client memory, divisor)
and its current value when the array is disabled, the element array buffer
of each vertex array object, and primitive restart."""
from ..errors import fail_call, printable

MAX_ATTRIBS = 64


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

    def attrib(self, index):
        a = self.attribs.get(index)
        if a is None:
            a = self.attribs[index] = Attrib()
        return a


def attrib_index(no, name, v):
    if not isinstance(v, int) or not 0 <= v < MAX_ATTRIBS:
        fail_call(no, f"{name}: attribute index {printable(v)} out of range")
    return v


class AttributeCalls:
    """self.s.vaos: name -> VertexArrayObject (0, the default one, always
    there); self.s.vao the bound one, whose element buffer is kept in
    self.s.bound["GL_ELEMENT_ARRAY_BUFFER"] while it is bound."""

    def current_vao(self):
        return self.s.vaos[self.s.vao]

    def h_gen_vertex_arrays(self, no, name, a, args):
        for v in dict(args).get("arrays") or []:
            if isinstance(v, int) and v > 0:
                self.s.vaos.setdefault(v, VertexArrayObject())

    def h_bind_vertex_array(self, no, name, a, args):
        v = dict(args).get("array")
        if not isinstance(v, int) or v < 0:
            fail_call(no, f"{name}: impossible name")
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
        i = attrib_index(no, name, dict(args).get("index"))
        self.current_vao().attrib(i).enabled = name.startswith("glEnable")

    def h_attrib_pointer(self, no, name, a, args):
        d = dict(args)
        i = attrib_index(no, name, d.get("index"))
        size, stride = d.get("size"), d.get("stride", 0)
        if not (size in (1, 2, 3, 4) or size == "GL_BGRA") or not isinstance(stride, int) or stride < 0:
            fail_call(no, f"{name}: impossible size or stride")
        at = self.current_vao().attrib(i)
        at.call, at.size, at.type, at.stride = name, size, d.get("type"), stride
        at.normalized = d.get("normalized", "GL_FALSE") in ("GL_TRUE", True, 1)
        p = d.get("pointer")
        at.buffer = self.s.bound.get("GL_ARRAY_BUFFER", 0)
        if at.buffer:
            at.offset, at.client = int(p or 0), None
        else:
            # Client memory: apitrace records what the draws read as a blob.
            at.offset, at.client = 0, p if isinstance(p, (bytes, bytearray)) else None

    def h_attrib_divisor(self, no, name, a, args):
        d = dict(args)
        i = attrib_index(no, name, d.get("index"))
        div = d.get("divisor")
        if not isinstance(div, int) or div < 0:
            fail_call(no, f"{name}: impossible divisor")
        self.current_vao().attrib(i).divisor = div

    def h_attrib_value(self, no, name, a, args):
        """glVertexAttrib*: the value of a disabled attribute, replayed as called."""
        i = attrib_index(no, name, a[0] if a else None)
        self.s.attrib_values[i] = (name, list(a[1:]))

    def h_primitive_restart_index(self, no, name, a, args):
        v = a[0] if a else None
        if not isinstance(v, int) or v < 0:
            fail_call(no, f"{name}: impossible index")
        self.s.restart_index = v

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
    } | dict.fromkeys([f"glVertexAttrib{n}{t}{v}" for n in "1234" for t in ("f", "d", "s") for v in ("", "v")]
                     + [f"glVertexAttribI4{t}{v}" for t in ("i", "ui") for v in ("", "v")]
                     + [f"glVertexAttrib4N{t}v" for t in ("b", "s", "i", "ub", "us", "ui")]
                     + [f"glVertexAttrib4{t}v" for t in ("b", "i", "ub", "us", "ui")], h_attrib_value)
