"""Matrix stacks, the viewport, the depth range and user clip planes."""
import math
import re

import numpy as np

from ...cli import I32, U32, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import CALL_FLAG_FAKE, MAX_CLIP_PLANES
from ..glmath import mat_frustum, mat_mul, mat_ortho, mat_rotate, mat_scale, mat_translate
from . import MAX_VIEWPORTS, clamped01, enum_arg, first_of_array, number

# Mesa's limits (llvmpipe, Mesa 22.3): matrix stack depths, the largest
# viewport, and the range a viewport's corner is clamped to.
STACK_DEPTHS = {"GL_MODELVIEW": 32, "GL_PROJECTION": 32, "GL_TEXTURE": 10}
MAX_VIEWPORT = 16384
VIEWPORT_BOUNDS = (-32768, 32767)


class TransformCalls:
    """The model-view and projection stacks and the viewport transform."""

    def cur(self):
        return self.s.stacks[self.s.mode][-1]

    def set_cur(self, m, no):
        if not np.all(np.isfinite(m)) and self.s.mode != "GL_TEXTURE":
            fail_call(no, "the matrix becomes non-finite (NaN or infinity)")
        self.s.stacks[self.s.mode][-1] = m

    def matrix_numbers(self, vals, no, what):
        """The numbers of a matrix call, finite; on the texture stack, whose
        matrices move no vertex (they transform texture coordinates, which
        the converter does not use), any float: None when one is NaN or
        infinite there (the matrix becomes NaN: nothing reads it)."""
        if self.s.mode == "GL_TEXTURE" and any(isinstance(v, float) and not math.isfinite(v) for v in vals):
            self.s.stacks["GL_TEXTURE"][-1] = np.full((4, 4), np.nan)
            return None
        return [number(v, no, what) for v in vals]

    def matrix_arg(self, call, no, transpose=False):
        vals = call[2][0][1]
        if not isinstance(vals, (list, tuple)) or len(vals) != 16:
            fail_call(no, f"{call[1]}: the matrix does not have 16 numbers")
        vals = self.matrix_numbers(vals, no, "a matrix element")
        if vals is None:
            return None
        m = np.array(vals, dtype=np.float64).reshape(4, 4)
        return m if transpose else m.T   # GL matrices are column-major

    def h_matrix_mode(self, no, name, a, args):
        if enum_arg(a[0], no, f"{name}: the mode") not in self.s.stacks:
            if isinstance(a[0], str) and a[0].startswith("GL_MATRIX"):
                fail_call(no, f"glMatrixMode({printable(a[0])}) is not emulated")
            return   # GL_INVALID_ENUM: the call does nothing
        self.s.mode = a[0]

    def h_load_identity(self, no, name, a, args):
        self.set_cur(np.identity(4), no)

    def h_load_matrix(self, no, name, a, args):
        m = self.matrix_arg((no, name, args), no, transpose="Transpose" in name)
        if m is not None:
            self.set_cur(m, no)

    def h_mult_matrix(self, no, name, a, args):
        m = self.matrix_arg((no, name, args), no, transpose="Transpose" in name)
        if m is not None:
            self.set_cur(mat_mul(self.cur(), m), no)

    def h_translate(self, no, name, a, args):
        v = self.matrix_numbers(a[:3], no, "an offset")
        if v is not None:
            self.set_cur(mat_mul(self.cur(), mat_translate(*v)), no)

    def h_scale(self, no, name, a, args):
        v = self.matrix_numbers(a[:3], no, "a scale")
        if v is not None:
            self.set_cur(mat_mul(self.cur(), mat_scale(*v)), no)

    def h_rotate(self, no, name, a, args):
        v = self.matrix_numbers(a[:4], no, "a rotation")
        if v is None:
            return
        angle, x, y, z = v
        if sum(v != 0.0 for v in (x, y, z)) > 1:
            # An axis off the coordinate axes is normalised in single
            # precision (Mesa's _math_matrix_rotate): one of length 1e-4 or
            # less leaves the matrix as it is, and one whose squared length
            # overflows a float becomes (0, 0, 0), a scale by cos(angle).
            x32, y32, z32 = np.float32(x), np.float32(y), np.float32(z)
            with np.errstate(over="ignore"):
                mag = np.sqrt(x32 * x32 + y32 * y32 + z32 * z32)
            if mag <= np.float32(1e-4):
                return
            if np.isinf(mag):
                m = np.identity(4)
                m[0, 0] = m[1, 1] = m[2, 2] = math.cos(math.radians(angle))
                self.set_cur(mat_mul(self.cur(), m), no)
                return
        self.set_cur(mat_mul(self.cur(), mat_rotate(angle, x, y, z)), no)

    def h_ortho(self, no, name, a, args):
        v = self.matrix_numbers(a[:6], no, "a bound")
        if v is None:
            return
        l, r, b, t, n, f = v
        if l == r or b == t or n == f:
            return   # GL_INVALID_VALUE: the call does nothing
        self.set_cur(mat_mul(self.cur(), mat_ortho(l, r, b, t, n, f)), no)

    def h_frustum(self, no, name, a, args):
        v = self.matrix_numbers(a[:6], no, "a bound")
        if v is None:
            return
        l, r, b, t, n, f = v
        if n <= 0 or f <= 0 or l == r or b == t or n == f:
            return   # GL_INVALID_VALUE: the call does nothing
        self.set_cur(mat_mul(self.cur(), mat_frustum(l, r, b, t, n, f)), no)

    def h_push_matrix(self, no, name, a, args):
        st = self.s.stacks[self.s.mode]
        if len(st) >= STACK_DEPTHS[self.s.mode]:
            return   # GL_STACK_OVERFLOW: the call does nothing
        st.append(st[-1].copy())

    def h_pop_matrix(self, no, name, a, args):
        st = self.s.stacks[self.s.mode]
        if len(st) <= 1:
            return   # GL_STACK_UNDERFLOW: the call does nothing
        st.pop()

    def h_viewport(self, no, name, a, args):
        x, y, w, h = [checked(no, integer, v, f"{name}: a viewport value", *I32) for v in a[:4]]
        if w < 0 or h < 0:
            return   # GL_INVALID_VALUE: the call does nothing
        # Clamped as Mesa clamps them: the size to the largest viewport,
        # the corner to the viewport bounds.
        w, h = min(w, MAX_VIEWPORT), min(h, MAX_VIEWPORT)
        x, y = (min(max(v, VIEWPORT_BOUNDS[0]), VIEWPORT_BOUNDS[1]) for v in (x, y))
        self.s.viewport = (x, y, w, h)
        if self.flags & CALL_FLAG_FAKE and w > 0 and h > 0:
            self.drawable_sizes[self.current_drawable] = (w, h)   # apitrace's record of its size at MakeCurrent

    def h_viewport_indexed(self, no, name, a, args):
        """glViewportIndexedf(v) and glViewportArrayv: viewport 0 is glViewport's
        (clamped as Mesa clamps it, its corner and size kept as the floats
        they are); the others are selected only by a geometry shader, which
        is refused, so they change nothing drawn."""
        d = dict(args)
        if "Array" in name:
            vals = first_of_array(no, name, d, "viewport", number)
            if vals is None:
                return
        else:
            index = checked(no, integer, d.get("index"), f"{name}: index", *I32)
            if index != 0:
                return   # another viewport, or GL_INVALID_VALUE
            vals = d.get("v")[:4] if isinstance(d.get("v"), list) else [d.get(k) for k in ("x", "y", "w", "h")]
        if not isinstance(vals, list) or len(vals) != 4:
            fail_call(no, f"{name}: not four viewport values")
        x, y, w, h = [number(v, no, f"{name}: a viewport value") for v in vals]
        if w < 0 or h < 0:
            return   # GL_INVALID_VALUE
        w, h = min(w, MAX_VIEWPORT), min(h, MAX_VIEWPORT)
        x, y = (min(max(v, VIEWPORT_BOUNDS[0]), VIEWPORT_BOUNDS[1]) for v in (x, y))
        self.s.viewport = (x, y, w, h)

    def h_clip_control(self, no, name, a, args):
        """glClipControl: GL's default (lower-left origin, depth from -1 to 1)
        is what the converter computes; a draw made under another is refused
        (draws.draw_record), one set and reset before any draw is not."""
        d = dict(args)
        origin, depth = d.get("origin"), d.get("depth")
        if origin not in ("GL_LOWER_LEFT", "GL_UPPER_LEFT") or depth not in ("GL_NEGATIVE_ONE_TO_ONE", "GL_ZERO_TO_ONE"):
            return   # GL_INVALID_ENUM: the call does nothing
        default = (origin, depth) == ("GL_LOWER_LEFT", "GL_NEGATIVE_ONE_TO_ONE")
        self.s.clip_control = None if default else (no, origin, depth)

    def h_depth_range(self, no, name, a, args):
        n, f = [clamped01(v, no, "a depth range bound") for v in a[:2]]
        self.s.depth_range = (n, f)

    def h_depth_range_indexed(self, no, name, a, args):
        """glDepthRangeIndexed and glDepthRangeArrayv (and their ES and NV
        forms): viewport 0's range is glDepthRange's (clamped alike); the
        others are selected only by a geometry shader, which is refused,
        so they change nothing drawn (as glViewportIndexedf's)."""
        d = dict(args)
        if "Array" in name:
            first = checked(no, integer, d.get("first"), f"{name}: first", *U32)
            count = checked(no, integer, d.get("count"), f"{name}: count", *I32)
            v = d.get("v")
            if not isinstance(v, list) or len(v) < 2 * max(count, 0):
                fail_call(no, f"{name}: fewer values than two a viewport")
            if count < 0 or first + count > MAX_VIEWPORTS or first != 0 or count == 0:
                return   # GL_INVALID_VALUE for the whole call, or no range of viewport 0
            vals = v[:2]
        else:
            if checked(no, integer, d.get("index"), f"{name}: index", *U32) != 0:
                return   # another viewport's, or GL_INVALID_VALUE past Mesa's 16
            vals = [d.get("n"), d.get("f")]
        self.s.depth_range = tuple(clamped01(v, no, "a depth range bound") for v in vals)

    def h_clip_plane(self, no, name, a, args):
        plane = a[0]
        m = re.fullmatch(r"GL_CLIP_(?:PLANE|DISTANCE)(\d)", str(plane))
        if not m or int(m.group(1)) >= MAX_CLIP_PLANES:
            fail_call(no, f"glClipPlane({printable(plane)}) is not a clip plane")
        eq = a[1]
        if not isinstance(eq, (list, tuple)) or len(eq) != 4:
            fail_call(no, "glClipPlane without four coefficients")
        p = np.array([number(x, no, "a plane coefficient") for x in eq])
        # Stored in eye coordinates: multiplied by the inverse model-view in force.
        try:
            self.s.clip_planes[int(m.group(1))] = p @ np.linalg.inv(self.s.stacks["GL_MODELVIEW"][-1])
        except np.linalg.LinAlgError:
            fail_call(no, "glClipPlane with a singular model-view matrix")

    HANDLERS_ES1 = {   # OpenGL ES 1's float and 16.16 fixed-point forms
        "glOrthof": "glOrtho", "glFrustumf": "glFrustum", "glClipPlanef": "glClipPlane",
        "glOrthox": "glOrtho", "glFrustumx": "glFrustum", "glTranslatex": "glTranslatef", "glRotatex": "glRotatef",
        "glScalex": "glScalef", "glLoadMatrixx": "glLoadMatrixf", "glMultMatrixx": "glMultMatrixf",
        "glDepthRangex": "glDepthRange", "glClipPlanex": "glClipPlane",
    }
    HANDLERS = {
        "glMatrixMode": h_matrix_mode,
        "glLoadIdentity": h_load_identity,
        "glLoadMatrixf": h_load_matrix,
        "glLoadMatrixd": h_load_matrix,
        "glLoadTransposeMatrixf": h_load_matrix,
        "glLoadTransposeMatrixd": h_load_matrix,
        "glMultMatrixf": h_mult_matrix,
        "glMultMatrixd": h_mult_matrix,
        "glMultTransposeMatrixf": h_mult_matrix,
        "glMultTransposeMatrixd": h_mult_matrix,
        "glTranslatef": h_translate,
        "glTranslated": h_translate,
        "glScalef": h_scale,
        "glScaled": h_scale,
        "glRotatef": h_rotate,
        "glRotated": h_rotate,
        "glOrtho": h_ortho,
        "glFrustum": h_frustum,
        "glPushMatrix": h_push_matrix,
        "glPopMatrix": h_pop_matrix,
        "glViewport": h_viewport,
        "glViewportIndexedf": h_viewport_indexed,
        "glViewportIndexedfv": h_viewport_indexed,
        "glViewportArrayv": h_viewport_indexed,
        "glClipControl": h_clip_control,
        "glDepthRange": h_depth_range,
        **dict.fromkeys(("glDepthRangeIndexed", "glDepthRangeIndexedf", "glDepthRangeIndexedfNV",
                         "glDepthRangeIndexeddNV", "glDepthRangeArrayv", "glDepthRangeArrayfv",
                         "glDepthRangeArrayfvNV", "glDepthRangeArraydvNV"), h_depth_range_indexed),
        "glDepthRangef": h_depth_range,
        "glClipPlane": h_clip_plane,
    }


def fixed_point(handler):
    """The handler of a float call, for its OpenGL ES 1 form of 16.16
    fixed-point values (GLfixed: an integer, 1/65536 a unit)."""
    def h(self, no, name, a, args):
        def value(v):
            if isinstance(v, list):
                return [value(x) for x in v]
            return v / 65536.0 if isinstance(v, int) and not isinstance(v, bool) else v
        args = [(k, value(v)) for k, v in args]
        handler(self, no, name, [v for _, v in args], args)
    return h


TransformCalls.HANDLERS |= {name: (fixed_point(TransformCalls.HANDLERS[core]) if name.endswith("x")
                                   else TransformCalls.HANDLERS[core])
                            for name, core in TransformCalls.HANDLERS_ES1.items()}
