"""Face culling, winding, polygon offset and polygon mode."""
from ..errors import fail_call, printable
from ..gl_tables import CULL
from . import number

class PolygonCalls:
    """Rasterization state of polygons."""

    def h_cull_face(self, no, name, a, args):
        if a[0] not in CULL:
            fail_call(no, f"glCullFace({printable(a[0])}) is not a face")
        self.s.cull_face = a[0]

    def h_front_face(self, no, name, a, args):
        if a[0] not in ("GL_CW", "GL_CCW"):
            fail_call(no, f"glFrontFace({printable(a[0])}) is not a winding")
        self.s.front_face = a[0]

    def h_polygon_offset(self, no, name, a, args):
        self.s.offset = (number(a[0], no, "the offset factor"), number(a[1], no, "the offset units"))

    def h_polygon_mode(self, no, name, a, args):
        if a[1] != "GL_FILL":
            fail_call(no, f"glPolygonMode({printable(a[1])}): only GL_FILL is emulated")

    HANDLERS = {
        "glCullFace": h_cull_face,
        "glFrontFace": h_front_face,
        "glPolygonOffset": h_polygon_offset,
        "glPolygonMode": h_polygon_mode,
    }
