"""Face culling, winding, polygon offset and polygon mode."""
from ..errors import fail_call, printable
from ..gl_tables import CULL
from . import enum_arg, number
from .transform import fixed_point

class PolygonCalls:
    """Rasterization state of polygons."""

    def h_cull_face(self, no, name, a, args):
        if enum_arg(a[0], no, f"{name}: the face") not in CULL:
            return   # GL_INVALID_ENUM: the call does nothing
        self.s.cull_face = a[0]

    def h_front_face(self, no, name, a, args):
        if enum_arg(a[0], no, f"{name}: the winding") not in ("GL_CW", "GL_CCW"):
            return   # GL_INVALID_ENUM: the call does nothing
        self.s.front_face = a[0]

    def h_polygon_offset(self, no, name, a, args):
        self.s.offset = (number(a[0], no, "the offset factor"), number(a[1], no, "the offset units"))

    def h_polygon_offset_clamp(self, no, name, a, args):
        """glPolygonOffsetClamp: a clamp of 0 is glPolygonOffset; another
        limits the offset, which is not emulated."""
        if number(a[2], no, "the offset clamp") != 0:
            fail_call(no, f"{name} with a clamp other than 0 is not emulated")
        self.h_polygon_offset(no, name, a, args)

    def h_provoking_vertex(self, no, name, a, args):
        # Which vertex is flat shading's changes no fragment; it is read for
        # the depth check, whose llvmpipe emulation orders a clipped
        # polygon's triangles and a triangle's set-up by it.
        if a[0] in ("GL_FIRST_VERTEX_CONVENTION", "GL_LAST_VERTEX_CONVENTION"):
            self.s.provoking_first = a[0] == "GL_FIRST_VERTEX_CONVENTION"

    def h_polygon_mode(self, no, name, a, args):
        if (self.core or self.es) and a[0] != "GL_FRONT_AND_BACK":
            return   # GL_INVALID_ENUM: core profiles set both faces at once
        if a[1] in ("GL_LINE", "GL_POINT"):
            fail_call(no, f"glPolygonMode({printable(a[1])}): only GL_FILL is emulated")
        # GL_FILL, or GL_INVALID_ENUM: nothing changes.

    HANDLERS = {
        "glCullFace": h_cull_face,
        "glFrontFace": h_front_face,
        "glPolygonOffset": h_polygon_offset,
        "glPolygonOffsetClamp": h_polygon_offset_clamp,
        "glPolygonOffsetx": fixed_point(h_polygon_offset),   # OpenGL ES 1, 16.16 fixed point
        "glPolygonMode": h_polygon_mode,
        "glProvokingVertex": h_provoking_vertex,
    }
