"""Draw calls and immediate mode, into the draw records rbcd-gl-raster reads (docs/gl-capture.md)."""
import hashlib
import struct

import numpy as np

from ..errors import fail_call, printable
from ..gl_tables import CULL, DEPTH_FUNCS, PRIM_NO_AREA, PRIM_TRIANGLES
from ..glmath import mat_mul, triangle_indices
from . import number

class DrawCalls:
    """Draws: positions through the fixed-function transform into draw records."""

    # ---- draws
    def draw(self, no, mode, positions, name):
        """positions: (n, 4) object-space vertices in GL order for `mode`."""
        if not self.active:
            return
        if self.s.program:
            fail_call(no, f"{name} with program {self.s.program} bound: shaders are not emulated")
        if mode in PRIM_NO_AREA:
            self.ignored_prims += 1
            return
        if mode not in PRIM_TRIANGLES:
            fail_call(no, f"{name}: primitive mode {printable(mode)} is not emulated")
        self.open_frame(no)
        tris = triangle_indices(mode, len(positions))
        mv = self.s.stacks["GL_MODELVIEW"][-1]
        proj = self.s.stacks["GL_PROJECTION"][-1]
        # As a GL implementation does: single precision, the model-view-projection
        # composed first (Mesa's fixed-function vertex program).
        mvp32 = mat_mul(proj.astype(np.float32), mv.astype(np.float32))
        clip = mat_mul(positions.astype(np.float32), mvp32.T).astype(np.float64)
        if not np.all(np.isfinite(clip)):
            fail_call(no, f"{name}: a vertex transforms to a non-finite position")
        if len(tris) == 0:
            return
        if self.frame_view is None and abs(proj[3, 3]) < 1e-12:
            self.frame_view = mv.copy()
        obj_id = self.object_of(no, mv, proj, len(positions), clip)
        collisionable = obj_id is not None
        if collisionable:
            # A surface drawn in several passes is collisionable once: its first
            # pass; the others are the GPU's work (docs/gl-capture.md).
            key = (obj_id, hashlib.blake2b(clip.tobytes() + tris.tobytes(), digest_size=16).digest())
            if key in self.drawn_surfaces:
                collisionable = False
            else:
                self.drawn_surfaces.add(key)
        if collisionable and self.geo is not None:
            eye = mat_mul(positions, mv.T)   # only the geometry output needs eye space
            self.geo_objects.setdefault(obj_id, []).append((eye[:, 0:3] / eye[:, 3:4], tris.copy()))
            self.geo_view = proj.copy()   # the objects' projection, not a later overlay's
        st = self.s
        w, h = self.screen
        vx, vy, vw, vh = st.viewport if st.viewport else (0, 0, w, h)
        if vw <= 0 or vh <= 0:
            return
        if st.scissor_test and st.scissor:
            sx, sy, sw, sh = st.scissor
            scissor = (sx, h - (sy + sh), sx + sw - 1, h - sy - 1)
        else:
            scissor = (0, 0, w - 1, h - 1)
        planes = []
        if any(st.clip_enabled):
            try:
                pinv = np.linalg.inv(proj)
            except np.linalg.LinAlgError:
                fail_call(no, f"{name}: user clip planes with a singular projection")
            for i, on in enumerate(st.clip_enabled):
                if on:
                    planes.append(st.clip_planes[i] @ pinv)
        # The unit's front faces are the outward ones, those culling keeps: an
        # application that culls GL_FRONT (Quake 3 does, keeping GL_CCW) draws
        # its outside with GL's back faces. The same culling, said as the
        # opposite front face with GL_BACK culled, gives the unit its facing.
        cull = CULL[st.cull_face] if st.cull else 0
        front_ccw = st.front_face == "GL_CCW"
        if cull == CULL["GL_FRONT"]:
            cull, front_ccw = CULL["GL_BACK"], not front_ccw
        depth_func = DEPTH_FUNCS.index(st.depth_func)
        of, ou = st.offset if st.offset_fill else (0.0, 0.0)
        rec = bytearray(b"D")
        rec += struct.pack("<QIBBBBBBB", no, obj_id if collisionable else 0, 1 if collisionable else 0, cull,
                           1 if front_ccw else 0, 1 if st.depth_test else 0, depth_func,
                           1 if st.depth_mask else 0, len(planes))
        # GL's window y grows upwards; the screen's rows downwards.
        rec += struct.pack("<8d", vx, h - (vy + vh), vw, vh, st.depth_range[0], st.depth_range[1], of, ou)
        rec += struct.pack("<4i", *scissor)
        for p in planes:
            rec += struct.pack("<4d", *p)
        rec += struct.pack("<II", len(clip), len(tris))
        rec += np.ascontiguousarray(clip, dtype="<f8").tobytes()
        rec += np.ascontiguousarray(tris, dtype="<u4").tobytes()
        self.emit(bytes(rec))
        if st.depth_test:
            self.last_depth_draw = no
        self.note_draw(no, name, obj_id if collisionable else None, len(positions), mv, proj, clip)

    def immediate_vertex(self, no, base, a):
        vals = a[0] if len(a) == 1 and isinstance(a[0], (list, tuple)) else a
        if not 2 <= len(vals) <= 4:
            fail_call(no, f"{base}: {len(vals)} coordinates")
        v = [number(x, no, "a coordinate") for x in vals] + [0.0, 1.0][len(vals) - 2:]
        if len(v) == 3:
            v.append(1.0)
        if len(self.s.begin_verts) >= (1 << 22):
            fail_call(no, "more than 4194304 vertices between glBegin and glEnd")
        self.s.begin_verts.append(v)


    def h_draw_arrays(self, no, name, a, args):
        d = dict(args)
        mode, first, count = d.get("mode"), d.get("first", 0), d.get("count", 0)
        if not isinstance(first, int) or not isinstance(count, int) or first < 0 or count < 0:
            fail_call(no, f"{name}: impossible first or count")
        if not self.active or count == 0:
            return
        arr = self.vertex_source(no, name)
        self.draw(no, mode, self.array_values(arr, first, count, no), name)

    def h_draw_elements(self, no, name, a, args):
        d = dict(args)
        mode, count, type_, indices = d.get("mode"), d.get("count", 0), d.get("type"), d.get("indices")
        if not isinstance(count, int) or count < 0 or count > (1 << 24):
            fail_call(no, f"{name}: impossible count")
        if not self.active or count == 0:
            return
        arr = self.vertex_source(no, name)
        idx = self.index_values(type_, indices, count, no)
        if "start" in d and isinstance(d["start"], int) and isinstance(d.get("end"), int):
            if len(idx) and (idx.min() < d["start"] or idx.max() > d["end"]):
                fail_call(no, f"{name}: an index lies outside [start, end]")
        hi = int(idx.max()) + 1 if len(idx) else 0
        if hi > (1 << 24):
            fail_call(no, f"{name}: index {hi - 1} is past any vertex array this converter takes")
        verts = self.array_values(arr, 0, hi, no)
        self.draw(no, mode, verts[idx], name)

    def h_rect(self, no, name, a, args):
        vals = a[0] + a[1] if len(a) == 2 else a[:4]
        x1, y1, x2, y2 = [number(v, no, "a corner") for v in vals]
        if self.active:
            self.draw(no, "GL_POLYGON", np.array([[x1, y1, 0, 1], [x2, y1, 0, 1], [x2, y2, 0, 1], [x1, y2, 0, 1]],
                                                 dtype=np.float64), name)

    def h_begin(self, no, name, a, args):
        self.s.begin_mode = a[0]
        self.s.begin_verts = []

    def h_end(self, no, name, a, args):
        fail_call(no, "glEnd without glBegin")

    HANDLERS = {
        "glDrawArrays": h_draw_arrays,
        "glDrawElements": h_draw_elements,
        "glDrawRangeElements": h_draw_elements,
        "glRectf": h_rect,
        "glRectd": h_rect,
        "glRecti": h_rect,
        "glRects": h_rect,
        "glRectfv": h_rect,
        "glRectdv": h_rect,
        "glRectiv": h_rect,
        "glRectsv": h_rect,
        "glBegin": h_begin,
        "glEnd": h_end,
    }
