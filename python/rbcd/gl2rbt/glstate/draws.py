"""Draw calls and immediate mode, into the draw records rbcd-gl-raster reads (docs/gl-capture.md)."""
import hashlib
import struct

import numpy as np

from ...cli import I32, I64, U32, U63, integer
from ..errors import checked, fail_call, printable
from ..gl_tables import CULL, DEPTH_FUNCS, INDEX_TYPES, PRIM_NO_AREA, PRIM_TRIANGLES, base_name
from ..glmath import mat_mul, triangle_indices
from . import enum_arg, number
from .attributes import check_vertex_data
from .color_outputs import NotFollowed

# Points and lines, the adjacency forms too: no area without a geometry shader.
NO_AREA_MODES = PRIM_NO_AREA | {"GL_LINES_ADJACENCY", "GL_LINE_STRIP_ADJACENCY"}
PRIM_MODES = PRIM_TRIANGLES | NO_AREA_MODES | {"GL_TRIANGLES_ADJACENCY", "GL_TRIANGLE_STRIP_ADJACENCY", "GL_PATCHES"}
# Modes a core profile and OpenGL ES do not have (GL_INVALID_ENUM there).
LEGACY_MODES = {"GL_QUADS", "GL_QUAD_STRIP", "GL_POLYGON"}
# The triangles a draw of n vertices under a program gives at most, by mode;
# with no geometry shader the adjacency modes draw their triangles and pass
# over the adjacent vertices (Mesa's transform feedback hands back those).
TRIANGLES_PER_VERTICES = {"GL_TRIANGLES": lambda n: n // 3, "GL_TRIANGLE_STRIP": lambda n: max(0, n - 2),
                          "GL_TRIANGLE_FAN": lambda n: max(0, n - 2), "GL_TRIANGLES_ADJACENCY": lambda n: n // 6,
                          "GL_TRIANGLE_STRIP_ADJACENCY": lambda n: max(0, (n - 4) // 2)}
# The primitives n vertices of each other mode make (a last incomplete one
# dropped, as GL drops it).
PRIMITIVES_PER_VERTICES = {"GL_POINTS": lambda n: n, "GL_LINES": lambda n: n // 2,
                           "GL_LINE_STRIP": lambda n: max(0, n - 1), "GL_LINE_LOOP": lambda n: n if n >= 2 else 0,
                           "GL_LINES_ADJACENCY": lambda n: n // 4, "GL_LINE_STRIP_ADJACENCY": lambda n: max(0, n - 3),
                           "GL_QUADS": lambda n: n // 4, "GL_QUAD_STRIP": lambda n: max(0, (n - 2) // 2),
                           "GL_POLYGON": lambda n: int(n >= 3)} | TRIANGLES_PER_VERTICES
MESA_STEPS_PER_UNIT = 2.0
MAX_INSTANCES = 1 << 16        # instances of one draw (each becomes a draw record)
MAX_MULTI_DRAWS = 1 << 16      # draws of one multi-draw
MAX_FRAME_RECORDS = 1 << 17    # draw records of one frame (a game's frame has a few thousand)
MAX_FRAME_VERTICES = 1 << 24   # vertices one frame's draws set up or run (a game's: under a million)
# The same over all the frames converted, each at least 256 a byte of the
# capture's file (the committed game captures draw at most 8 a byte of
# their reduced capture): at least 2^30 vertices in all (a game's frame of
# a million vertices, a thousand frames), of which at least 2^26 made by
# tessellation or geometry shaders (which amplify a few bytes most). Mesa
# takes about 1.5 us a vertex: a small file may ask for about half an hour
# of plain draws and a minute and a half of amplified ones, not for hours.
CAPTURE_VERTICES_PER_BYTE, MIN_CAPTURE_VERTICES, MIN_CAPTURE_AMPLIFIED = 256, 1 << 30, 1 << 26


def capture_vertex_bounds(size):
    """The vertices the frames converted from a capture of `size` bytes
    (reduced.source_bytes) may set up or run, and of them those
    tessellation or geometry shaders may make (DrawCalls.frame_work)."""
    return (max(MIN_CAPTURE_VERTICES, CAPTURE_VERTICES_PER_BYTE * size),
            max(MIN_CAPTURE_AMPLIFIED, CAPTURE_VERTICES_PER_BYTE * size))
# A draw record holds at most 2^22 vertices (rbcd-gl-raster's bound): a draw
# that could need more is refused before anything is computed for it.
MAX_RECORD_VERTICES = 1 << 22
MAX_DRAW_VERTICES = 1 << 24     # first, offsets and base vertex of one draw
MAX_DRAW_PRIMITIVES = 1 << 22   # triangles of one draw under a program, all its instances
# Per frame, draws under a fragment shader that can remove fragments
# (discard) or move them in depth (gl_FragDepth): the converter keeps all
# their fragments, at the depth the rasterizer computes (docs/gl-capture.md).
FRAGMENT_EFFECT_KEYS = ("discard_draws", "discard_collisionable", "frag_depth_draws", "frag_depth_collisionable")


def restart_triangles(mode, lengths):
    """The triangles of primitives of `lengths` vertices each, one after
    another in one vertex list (primitive restart cut them apart: each is
    assembled alone, as GL assembles a primitive)."""
    parts, at = [], 0
    for n in lengths:
        if n > 0:
            parts.append(triangle_indices(mode, n) + np.uint32(at))
            at += n
    return np.concatenate(parts) if parts else np.zeros((0, 3), np.uint32)


class DrawCalls:
    """Draws: positions through the fixed-function transform into draw records."""

    def renders(self):
        """Whether draws now reach pixels: not in glRenderMode's selection
        or feedback mode."""
        return self.s.render_mode == "GL_RENDER"

    def shader_stores(self, no, name):
        """What a draw's shaders may store into: textures bound to image
        units for writing (read back again when a vertex shader reads
        them), and buffers: those of buffer textures bound so, and, under a
        program that declares shader storage blocks or atomic counters, those
        bound to their binding points (a later draw that reads them as
        data is refused: checked_buffer)."""
        if self.s.image_writes:
            self.gpu_wrote()
            for unit in self.s.image_writes:
                tex = self.s.image_units[unit][0]
                if tex in self.s.texture_buffers:
                    self.gpu_wrote_buffer(no, self.s.texture_buffers[tex][1],
                                          f"{base_name(name)} with its buffer texture {tex} bound to image unit "
                                          f"{unit} for writing")
        self.feedback_writes(no, name)
        if any(p.stores for _, p in self.stage_programs().values()):
            for (target, index), (b, _, _) in self.s.indexed.items():
                if b and target in ("GL_SHADER_STORAGE_BUFFER", "GL_ATOMIC_COUNTER_BUFFER"):
                    self.gpu_wrote_buffer(no, b, f"{base_name(name)}, whose program may store into {target} "
                                                 f"binding {index}")

    def draw_invalid(self, no=None, name=None):
        """Why Mesa refuses every draw now with GL_INVALID_OPERATION,
        whatever its mode and arrays: what it last decided (revalidate).
        None when it draws. A decision the converter does not follow
        (NotFollowed) refuses the capture at draw `no` (call `name`) when
        it is drawn."""
        fault = self.s.render_fault
        if isinstance(fault, NotFollowed) and no is not None and self.active and not self.s.rasterizer_discard \
                and self.renders():
            fail_call(no, f"{printable(name)}: {fault}")
        return fault

    def revalidate(self):
        """Mesa decides again whether draws are valid, after one of the
        calls color_outputs.REVALIDATING names, in the order Mesa 22.3
        checks (_mesa_update_valid_to_render_state): the bound pipeline's
        validation (only if not validated since it last changed), the
        samplers of the program in use, dual-source blending against the
        draw buffers as they are now, an advanced blend equation, an
        integer colour buffer with no fragment shader. Draws
        keep the answer until the next such call, whatever changes
        meanwhile."""
        self.s.render_fault = self.pipeline_invalid() or self.samplers_invalid() or self.dual_source_invalid() \
            or self.advanced_blend_invalid() or self.integer_buffers_invalid()

    # ---- draws
    def draw(self, no, mode, positions, name, tris=None):
        """positions: (n, 4) object-space vertices in GL order for `mode`,
        through the fixed-function transform; tris, the triangles GL
        assembles from them when primitive restart cut them into pieces."""
        invalid = self.draw_invalid(no, name)
        if invalid is not None:
            if self.active and not self.s.rasterizer_discard and self.renders():
                self.rejected_draws.append((no, f"GL_INVALID_OPERATION: {invalid}"))
            return
        self.shader_stores(no, name)
        if not self.active or self.s.rasterizer_discard or not self.renders():
            return
        if self.vertex_program():
            fail_call(no, f"{name} with program {self.stage_programs()['vertex'][0]} bound: immediate-mode and glRect draws "
                      "under a vertex shader are not emulated")
        if not self.draws_into_camera_pass():
            return
        if mode in NO_AREA_MODES:
            self.ignored_prims += 1
            return
        if mode not in PRIM_MODES or mode == "GL_PATCHES":
            return   # GL_INVALID_ENUM, or _OPERATION (patches with no tessellation): nothing is drawn
        if self.s.depth_test and len(positions):
            self.depth_tested(no, name)
        self.open_frame(no)
        if tris is None:
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
        # Its vertex data for the rules: the object-space positions it draws,
        # in single precision, in the order drawn.
        self.vertex_data = lambda: hashlib.blake2b(repr(("positions", mode)).encode() +
                                                   positions.astype("<f4").tobytes(), digest_size=8).hexdigest()
        obj_id = self.object_of(no, mv, proj, len(positions), clip)
        eye = (lambda: mat_mul(positions, mv.T)) if self.geo is not None else None
        # A program (or pipeline) of only a fragment shader: its discard or
        # gl_FragDepth count as under a vertex shader.
        p = self.stage_programs().get("fragment", (0, None))[1]
        self.draw_effects = p is not None and (p.discards or p.frag_depth)
        self.draw_record(no, name, clip, tris, obj_id, len(positions), mv, proj, eye)
        self.draw_effects = False
        self.vertex_data = None
        if p is not None:
            self.note_fragment_effects(p, obj_id is not None)

    def frame_work(self, no, name, vertices, amplified=False):
        """A draw's vertices (every instance's; `amplified`: made by its
        tessellation or geometry shaders), counted against the frame's and
        the capture's bounds before they are fetched or run: each draw is
        bounded alone, and a frame of many (one buffer's indices drawn again
        and again), or many such frames, would otherwise cost hours from a
        kilobyte."""
        self.frame_vertices += vertices
        if self.frame_vertices > MAX_FRAME_VERTICES:
            fail_call(no, f"{name}: more than {MAX_FRAME_VERTICES} vertices drawn in one frame "
                      "(docs/gl-capture.md, limits)")
        self.capture_vertices += vertices
        if amplified:
            self.capture_amplified += vertices
        most, most_amplified = self.max_capture_vertices
        if self.capture_vertices > most or self.capture_amplified > most_amplified:
            what, bound, least = (("vertices made by tessellation or geometry shaders", most_amplified,
                                   MIN_CAPTURE_AMPLIFIED) if self.capture_amplified > most_amplified
                                  else ("vertices drawn", most, MIN_CAPTURE_VERTICES))
            fail_call(no, f"{name}: more than {bound} {what} in the frames converted, the bound for a capture of "
                      f"this size ({CAPTURE_VERTICES_PER_BYTE} a byte, at least {least}; docs/gl-capture.md, "
                      "limits)")

    def draw_record(self, no, name, clip, tris, obj_id, nverts, mv, proj, eye):
        """The draw record of clip-space vertices and their triangles, for
        object obj_id (None: other work); eye() gives the eye-space vertices
        for the geometry output (None: a draw under a program, whose geometry
        is written in normalized device coordinates)."""
        if self.s.clip_control is not None:
            at, origin, depth = self.s.clip_control
            fail_call(no, f"{name}: glClipControl({origin}, {depth}) at call {at} is not emulated")
        self.frame_records += 1
        if self.frame_records > MAX_FRAME_RECORDS:
            fail_call(no, f"{name}: more than {MAX_FRAME_RECORDS} draw records (draws and their instances) in one "
                      "frame (docs/gl-capture.md, limits)")
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
            self.add_geometry(no, obj_id, clip, tris, eye, proj)
        st = self.s
        w, h = self.screen
        vx, vy, vw, vh = st.viewport if st.viewport else (0, 0, w, h)
        top = h - (vy + vh)   # the viewport's top row, screen rows down
        if vw <= 0 or vh <= 0 or vx >= w or vx + vw <= 0 or top >= h or top + vh <= 0:
            return   # the viewport (as Mesa clamps it) meets no pixel of the screen: nothing is drawn
        if (vx + vw > w or vy + vh > h) and not self.args.screen:
            # GL cuts it to the window; but a window resized, or made anew
            # with the same context, keeps no size in the capture (apitrace
            # records one at a context's first MakeCurrent): the report
            # says so, naming the first such draw.
            self.viewport_past[0] += 1
            if self.viewport_past[1] is None:
                self.viewport_past[1:] = [no, (vx, vy, vw, vh)]
        scissor = self.scissor_rect()
        planes = []
        if any(st.clip_enabled):
            if proj is None:
                fail_call(no, f"{name}: user clip planes (glClipPlane) or clip distances (GL_CLIP_DISTANCEi) "
                          "under a program are not emulated")
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
        if st.offset_other and st.offset != (0.0, 0.0):
            # GL offsets filled polygons by GL_POLYGON_OFFSET_FILL alone;
            # llvmpipe offsets them then too, by another path and amount
            # (measured: depth 0.2906 for 0.3025 unoffset, 0.1825 with
            # FILL).
            fail_call(no, f"{name}: {' and '.join(sorted(st.offset_other))} enabled with a polygon offset: llvmpipe "
                      "offsets filled triangles then, unlike GL; not emulated")
        of, ou = st.offset if st.offset_fill else (0.0, 0.0)
        # The draw stream counts units in steps of the depth buffer; Mesa's
        # llvmpipe takes one glPolygonOffset unit as two (measured: units 1,
        # 100, 20000 move a 24-bit depth 1, 199, 39999 steps; a 16-bit one
        # 2, 200, and to its clamp).
        ou *= MESA_STEPS_PER_UNIT
        if ou:
            # A unit is a step of the depth buffer drawn into (GL 4.5,
            # 14.6.5): a 16-bit one's is 2^(bits - 16) of the trace's steps.
            # A floating-point one's depends on each primitive's largest
            # depth exponent, which the draw stream cannot say: refused
            # where the depths matter (tested, or the unit's).
            if (st.depth_test or collisionable) and self.float_depth():
                fail_call(no, f"{name}: a polygon offset's units into a floating-point depth buffer "
                          "(GL_DEPTH_COMPONENT32F, GL_DEPTH32F_STENCIL8): not emulated")
            ou *= 2.0 ** (self.args.depth_bits - self.depth_bits())
        rec = bytearray(b"D")
        # Flags: bit 0 collisionable; bit 1 its fragment shader can discard or
        # write gl_FragDepth (the depth it writes is an upper bound); bit 2
        # the first vertex provokes (read by the depth check's emulation only).
        flags = (1 if collisionable else 0) | (2 if self.draw_effects else 0) | (4 if st.provoking_first else 0)
        rec += struct.pack("<QIBBBBBBBH", no, obj_id if collisionable else 0, flags, cull,
                           1 if front_ccw else 0, 1 if st.depth_test else 0, depth_func,
                           1 if st.depth_mask else 0, len(planes), self.draw_shade)
        # GL's window y grows upwards; the screen's rows downwards.
        rec += struct.pack("<8d", vx, top, vw, vh, st.depth_range[0], st.depth_range[1], of, ou)
        rec += struct.pack("<4i", *scissor)
        for p in planes:
            rec += struct.pack("<4d", *p)
        rec += struct.pack("<II", len(clip), len(tris))
        rec += np.ascontiguousarray(clip, dtype="<f8").tobytes()
        rec += np.ascontiguousarray(tris, dtype="<u4").tobytes()
        self.emit(bytes(rec))
        if st.depth_test:
            self.last_depth_draw, self.last_depth_wrong = no, self.kept_wrong or self.multisample_depth()
            self.last_depth_bits = self.depth_bits()
            if not self.s.draw_fbo and self.read_drawable != self.current_drawable:
                # Mesa's replay dumps a window's depth with glReadPixels,
                # which reads the read drawable: another window's here.
                self.read_elsewhere.add(no)
        self.note_draw(no, name, obj_id if collisionable else None, nverts, mv, proj, clip)

    def immediate_vertex(self, no, base, a):
        vals = a[0] if len(a) == 1 and isinstance(a[0], (list, tuple)) else a
        if not 2 <= len(vals) <= 4:
            fail_call(no, f"{base}: {len(vals)} coordinates")
        v = [number(x, no, "a coordinate") for x in vals] + [0.0, 1.0][len(vals) - 2:]
        if len(v) == 3:
            v.append(1.0)
        if len(self.s.begin_verts) >= MAX_RECORD_VERTICES:
            fail_call(no, "more than 4194304 vertices between glBegin and glEnd")
        self.s.begin_verts.append(v)

    # ---- draws under a program: the vertex stage run by Mesa
    def vertex_stage(self):
        if self.vertex_stage_ is None:
            from ..vertex_stage import VertexStage   # PyOpenGL and EGL: only for captures that need them
            self.vertex_stage_ = VertexStage(self.es, self)
        return self.vertex_stage_

    def program_shade(self, p):
        """The cost of the program's fragment shader (rbcd.gl2rbt.shading), in
        percent of a reference fragment; 0 when Mesa gives none."""
        if self.shading_costs is None:
            from ..shading import ShadingCosts
            self.shading_costs = ShadingCosts(self.es)
        return self.shading_costs.shade_of(p.digest, p.linked[0] if p.linked else {}) or 0

    def shader_draw(self, no, name, d):
        """A draw under a program: its triangles as Mesa assembles them from
        the capture's own vertex shader, one draw record per instance (an
        instanced draw's instance i of object N is object N + i)."""
        instances = d.get("instancecount", d.get("primcount", 1))
        count = d["count"]
        if instances > MAX_INSTANCES:
            fail_call(no, f"{name}: {instances} instances, more than {MAX_INSTANCES}")
        mode = d["mode"]
        if mode not in PRIM_MODES or (self.core and self.s.vao == 0) or \
                (d.get("type", "GL_UNSIGNED_INT") not in INDEX_TYPES and "Elements" in name) or \
                ((self.core or self.es) and mode in LEGACY_MODES) or instances == 0 or \
                (count // self.s.patch_vertices if mode == "GL_PATCHES" else PRIMITIVES_PER_VERTICES[mode](count)) == 0:
            # GL_INVALID_ENUM (also quads and polygons in a core profile or
            # ES), no vertex array object in a core context, or no whole
            # primitive: nothing is drawn, stored or recorded
            return
        refused = self.feedback_kind_refused(no, name, mode, self.stage_programs())
        if refused is not None:
            self.rejected_draws.append((no, refused))
            return
        invalid = self.draw_invalid(no, name)
        if invalid is not None:
            if self.active and not self.s.rasterizer_discard and self.renders():
                self.rejected_draws.append((no, f"GL_INVALID_OPERATION: {invalid}"))
            return
        # What the draw's shaders store, and what transform feedback
        # records, in every frame (converted or not, rasterized or not).
        self.shader_stores(no, name)
        if not self.active or self.s.rasterizer_discard or not self.renders():
            return
        stages = self.stage_programs()
        later = [stage for stage in ("geometry", "tess_control", "tess_evaluation") if stage in stages]
        # The fragment stage's program decides discard, gl_FragDepth and
        # the shading cost (a pipeline's may not be the vertex stage's).
        p = stages.get("fragment", stages["vertex"])[1]
        if mode == "GL_PATCHES" and not any(stage.startswith("tess") for stage in later):
            return   # GL_INVALID_OPERATION with no tessellation stage: nothing is drawn
        if not later:
            if mode in NO_AREA_MODES:
                self.ignored_prims += 1
                return
            if mode not in TRIANGLES_PER_VERTICES:
                fail_call(no, f"{name}: primitive mode {printable(mode)} under a program is not emulated")
        if not self.draws_into_camera_pass():
            # (what its program reads is not known without Mesa: its
            # enabled attributes all, as for a draw the converter makes)
            indices = d.get("indices")
            check_vertex_data(self, no, name, d, instances, indices if isinstance(indices, (bytes, bytearray)) else None,
                              False, left_out=True)
            return
        if later:
            # Tessellation and geometry shaders run in Mesa with the vertex
            # stage (a draw into another pass, a layered shadow map's, needs
            # none: left out above); refused: such a stage of a pipeline's
            # other program, and an instanced draw (its primitives an
            # instance are not known). Points, lines and patches go
            # through: Mesa decides what they make (GL_INVALID_OPERATION:
            # nothing).
            for stage in later:
                v, sp = stages[stage]
                if v != stages["vertex"][0]:
                    fail_call(no, f"{name}: program {v} (linked at call {sp.link_call}) has the "
                              f"{stage.replace('_', ' ')} shader beside program {stages['vertex'][0]}'s vertex "
                              "shader (a pipeline): not emulated yet")
            if instances > 1:
                fail_call(no, f"{name}: {instances} instances under program {v}'s {later[-1].replace('_', ' ')} "
                          "shader: not emulated (its primitives an instance are not known)")
            per = max(count, 1)   # a first room: Mesa's count of the primitives made sizes the next
        else:
            per = TRIANGLES_PER_VERTICES[mode](count)   # at most, with no restart
        if per * instances > MAX_DRAW_PRIMITIVES or 3 * per > MAX_RECORD_VERTICES:
            fail_call(no, f"{name}: {per * instances} triangles in one draw, more than {MAX_DRAW_PRIMITIVES} "
                      f"(or {MAX_RECORD_VERTICES // 3} an instance; docs/gl-capture.md)")
        self.frame_work(no, name, count * instances)
        self.open_frame(no)
        tagged = False
        self.draw_instances = instances
        self.vertex_data = lambda: self.vertex_data_digest(base_name(name), d)
        self.draw_effects = "fragment" in stages and (p.discards or p.frag_depth)
        self.draw_shade = self.program_shade(p) if "fragment" in stages else 0
        from ..vertex_stage import DrawRejected
        try:
            clips = self.vertex_stage().run(self, no, base_name(name), d, instances, per * instances,
                                            *stages["vertex"])
        except DrawRejected as e:
            # The draw as the capture set it up is a GL error: GL draws
            # nothing, and neither does the converter; the report counts it.
            self.rejected_draws.append((no, str(e)))
            clips = []
        if self.s.depth_test and clips:
            self.depth_tested(no, name)
        for i, clip in enumerate(clips):
            # A primitive with a vertex at NaN or infinity is not drawn (GL
            # leaves its rasterization undefined; Mesa's clipper, or its
            # triangle setup, drops it). Nor is one whose three vertices
            # have w = 0: the clip volume meets the plane w = 0 only at its
            # origin (gl_Position = vec4(0.0), a common way to cull a
            # vertex, draws nothing).
            finite = np.isfinite(clip)
            if (finite[:, :3].all(axis=1) & (clip[:, 3] == np.inf)).any():
                # Inside every clip plane, at the viewport's centre once
                # divided: Mesa draws it where its primitive needs no
                # clipping, and drops it otherwise (round 31's R31-5).
                fail_call(no, f"{name}: a vertex at w = +infinity with finite x, y and z (Mesa draws or drops its "
                          "primitive as its clipping decides): not emulated")
            good = finite.all(axis=1).reshape(-1, 3).all(axis=1) & (clip[:, 3] != 0).reshape(-1, 3).any(axis=1)
            tris = np.arange(len(clip), dtype=np.uint32).reshape(-1, 3)[good]
            if len(tris) == 0:
                continue
            self.draw_instance = d.get("baseinstance", 0) + i
            obj = self.object_of(no, None, None, d["count"], clip)
            self.draw_instance = None
            tagged = tagged or obj is not None
            if obj is not None and not self.last_rule_table.get("group_instances") \
                    and not self.last_rule_table.get("group_by"):
                obj += i   # one object per instance, unless the rule that chose it groups them
                if obj > U32[1]:
                    fail_call(no, f"{name}: instance {i} of object {obj - i} would be object {obj}, past "
                              f"{U32[1]} (an instanced draw's instance i of object N is object N + i)")
            self.draw_record(no, name, clip, tris, obj, d["count"], None, None, None)
        self.draw_instances = 1
        self.vertex_data = None
        self.draw_effects = False
        self.draw_shade = 0
        if "fragment" in stages:
            self.note_fragment_effects(p, tagged)

    def note_fragment_effects(self, p, tagged):
        fx = self.fragment_effects.setdefault(self.out_frame, dict.fromkeys(FRAGMENT_EFFECT_KEYS, 0))
        for flag, key in ((p.discards, "discard"), (p.frag_depth, "frag_depth")):
            if flag:
                fx[key + "_draws"] += 1
                fx[key + "_collisionable"] += tagged

    def draw_args(self, no, name, a, args):
        """The arguments of a draw call, checked: counts, offsets and
        instances; None when GL ignores the call (GL_INVALID_VALUE: a
        negative count, first or instance count, or glDrawRangeElements'
        end before its start)."""
        d = dict(args)
        for k in ("mode", "count"):
            if k not in d:
                fail_call(no, f"{name}: no {k}")
        enum_arg(d["mode"], no, f"{name}: the mode")
        if "type" in d:
            enum_arg(d["type"], no, f"{name}: the index type")
        for k in ("first", "count", "instancecount", "primcount", "start", "end", "basevertex"):
            if k in d:
                v = checked(no, integer, d[k], f"{name}: {k}", -MAX_DRAW_VERTICES, MAX_DRAW_VERTICES)
                if v < 0 and k != "basevertex":
                    return None
        if "baseinstance" in d:
            # A GLuint, which Mesa takes whole (round 16's R16-12: 2^32 - 16
            # refused); it moves only instanced attributes' reads.
            checked(no, integer, d["baseinstance"], f"{name}: baseinstance", *U32)
        if d.get("end", 0) < d.get("start", 0):
            return None
        if not isinstance(d.get("indices"), (bytes, bytearray, type(None))):
            # An offset into the element buffer: what a pointer holds.
            checked(no, integer, d["indices"], f"{name}: the index buffer offset", *U63)
        elif d.get("indices") is not None and self.s.bound.get("GL_ELEMENT_ARRAY_BUFFER"):
            # With an element buffer bound the pointer is an offset into
            # it, and apitrace records it so (round 34's D6: the bytes read).
            fail_call(no, f"{name}: indices recorded as bytes while element buffer "
                      f"{self.s.bound['GL_ELEMENT_ARRAY_BUFFER']} is bound (apitrace records an offset into it)")
        return d

    def h_draw_under_program(self, no, name, a, args):
        """Draw calls that exist only for programs: instanced, base vertex, base instance."""
        d = self.draw_args(no, name, a, args)
        if d is None:
            return   # GL_INVALID_VALUE
        if d.get("instancecount", d.get("primcount", 1)) == 0 or d["count"] == 0:
            return   # no instance or no vertex: Mesa draws nothing, with or without a vertex shader
        if not self.vertex_program():
            if self.core or self.es2:
                return   # no vertex shader in a core profile or OpenGL ES 2 and later: nothing is drawn (Mesa)
            fail_call(no, f"{name} without a vertex shader is not emulated")
        self.shader_draw(no, name, d)

    def h_multi_draw(self, no, name, a, args):
        """glMultiDraw*: the draws it stands for, one after another; nothing
        when any count is negative (Mesa checks them all first:
        GL_INVALID_VALUE for the whole call). Its firsts are not checked
        there: a negative one reads before the array, which is refused."""
        d = dict(args)
        n = d.get("drawcount", d.get("primcount"))
        lists = {k: d.get(k) for k in ("first", "count", "indices", "basevertex") if k in d}
        if isinstance(n, int) and not isinstance(n, bool) and n < 0:
            return   # GL_INVALID_VALUE: the call does nothing
        if not isinstance(n, int) or isinstance(n, bool) or \
                not all(isinstance(v, list) and len(v) >= min(n, MAX_MULTI_DRAWS + 1) for v in lists.values()):
            fail_call(no, f"{name}: impossible draw count or lists")
        if n > MAX_MULTI_DRAWS:
            fail_call(no, f"{name}: {n} draws, more than {MAX_MULTI_DRAWS} in one multi-draw (docs/gl-capture.md, "
                      "limits)")
        for k in ("first", "count"):
            if k in lists:
                lists[k] = [checked(no, integer, v, f"{name}: a {k}", *I32) for v in lists[k][:n]]
        if any(v < 0 for v in lists.get("count", [])):
            return   # GL_INVALID_VALUE: the call does nothing
        if any(v < 0 for v in lists.get("first", [])):
            fail_call(no, f"{name}: a negative first: Mesa reads before the array; not emulated")
        single, handler = ("glDrawArrays", self.h_draw_arrays) if "Arrays" in name else \
            ("glDrawElementsBaseVertex", self.h_draw_under_program) if "BaseVertex" in name else \
            ("glDrawElements", self.h_draw_elements)
        try:
            for i in range(n):
                one = [("mode", d.get("mode"))] + [(k, v[i]) for k, v in lists.items()]
                if "type" in d:
                    one.append(("type", d["type"]))
                self.multi_draw_index, self.multi_draw_name = i, name
                handler(no, single, None, one)
        finally:
            self.multi_draw_index = 0

    def h_draw_indirect(self, no, name, a, args):
        """glDrawArraysIndirect, glDrawElementsIndirect, their glMultiDraw
        forms and GL 4.6's Count forms: each command read, as the capture's
        buffer holds it at the call, from the buffer bound to
        GL_DRAW_INDIRECT_BUFFER at `indirect` (GL 4.6, 10.4: count,
        instances, first or first index, [base vertex,] base instance,
        `stride` apart, 16 or 20 bytes when 0), and the Count forms' number
        of draws from GL_PARAMETER_BUFFER (at most maxdrawcount); each drawn
        as glDrawArraysInstancedBaseInstance or
        glDrawElementsInstancedBaseVertexBaseInstance (messages name those).
        What GL refuses draws nothing, as in Mesa: no indirect buffer in a
        core profile or OpenGL ES, an offset or stride that is not a
        multiple of 4 or a negative count, commands past the buffer's end;
        commands in client memory (a compatibility profile with no indirect
        buffer) are not in the capture: refused."""
        d = dict(args)
        base = base_name(name)
        elements = "Elements" in base
        size = 20 if elements else 16
        counted = base.endswith("Count")
        if base.startswith("glMultiDraw"):
            n = checked(no, integer, d.get("maxdrawcount" if counted else "drawcount"), f"{name}: the draw count",
                        *I32)
            stride = checked(no, integer, d.get("stride"), f"{name}: the stride", *I32)
        else:
            n, stride = 1, 0
        offset = d.get("indirect")
        if n < 0 or stride < 0 or stride % 4 or (isinstance(offset, int) and offset % 4):
            return   # GL_INVALID_VALUE: nothing is drawn
        buf = self.s.bound.get("GL_DRAW_INDIRECT_BUFFER", 0)
        if not buf:
            if self.core or self.es or isinstance(offset, int) and not isinstance(offset, bool) and offset == 0:
                return   # GL_INVALID_OPERATION (a NULL command in a compatibility profile: the same in Mesa)
            fail_call(no, f"{name}: its commands are in client memory, which the capture does not hold")
        offset = checked(no, integer, offset, f"{name}: the indirect buffer offset", *U63)
        pbuf = self.s.bound.get("GL_PARAMETER_BUFFER", 0)
        if counted:
            at = checked(no, integer, d.get("drawcount"), f"{name}: the parameter buffer offset", *I64)
            params = self.checked_buffer(no, name, pbuf, "its draw count") if pbuf else None
            if params is None or at < 0 or at % 4 or at + 4 > len(params):
                return   # GL_INVALID_OPERATION or GL_INVALID_VALUE: nothing is drawn
        elif pbuf and not self.es:
            # Mesa 22.3 draws a plain indirect draw (multi or single) as a
            # Count form whose count is the bound parameter buffer's first
            # word (measured: at most that many commands, none for 0): what
            # the capture's driver drew, though GL says the buffer is read
            # by the Count forms alone (round 17's R17-1).
            at, params = 0, self.checked_buffer(no, name, pbuf, "its draw count (Mesa 22.3 reads the bound "
                                                               "GL_PARAMETER_BUFFER's first word for it)")
            if params is None or len(params) < 4:
                fail_call(no, f"{name}: parameter buffer {pbuf} is bound with {len(params or b'')} bytes, whose "
                          "first word Mesa 22.3 reads as the draw count: not emulated")
            counted = True
        data = self.checked_buffer(no, name, buf, "its commands")
        stride = stride or size
        if n and (data is None or offset + (n - 1) * stride + size > len(data)):
            # GL_INVALID_OPERATION: commands past the buffer's end, nothing
            # is drawn (a Count form's bound is maxdrawcount's, whatever
            # count the parameter buffer holds: Mesa checks it so).
            return
        if counted:
            n = min(n, struct.unpack_from("<I", params, at)[0])
        if n > MAX_MULTI_DRAWS:
            fail_call(no, f"{name}: {n} draws, more than {MAX_MULTI_DRAWS} in one multi-draw (docs/gl-capture.md, "
                      "limits)")
        index_type = d.get("type") if elements else None
        if elements and (index_type not in INDEX_TYPES or not self.s.bound.get("GL_ELEMENT_ARRAY_BUFFER")):
            return   # GL_INVALID_ENUM, or GL_INVALID_OPERATION with no element buffer (every profile)
        if n > 1 and self.active and self.renders() and self.camera_pass():
            # The draw records its commands would make at most (one an
            # instance), against the frame's limit before any is run (each
            # costs Mesa about 0.4 ms: past it, a minute of work first).
            records = 0
            for i in range(n):
                count, instances = struct.unpack_from("<II", data, offset + i * stride)
                records += instances if count else 0
                if self.frame_records + records > MAX_FRAME_RECORDS:
                    records = sum(instances for count, instances in (struct.unpack_from("<II", data, offset + j * stride)
                                                                     for j in range(n)) if count)
                    break
            if self.frame_records + records > MAX_FRAME_RECORDS:
                fail_call(no, f"{name}: its {n} commands would make {records} draw records, more than "
                          f"{MAX_FRAME_RECORDS} in one frame with the frame's {self.frame_records} "
                          "(docs/gl-capture.md, limits)")
        if n > 1:
            self.batched = self.indirect_batch(no, name, d.get("mode"), index_type, data, offset, stride, n)
        try:
            for i in range(n):
                single, one = indirect_command(d.get("mode"), index_type, data, offset + i * stride)
                self.multi_draw_index, self.multi_draw_name = i, name
                self.h_draw_under_program(no, single, None, one)
        finally:
            self.multi_draw_index = 0
            self.batched = None

    def indirect_batch(self, no, name, mode, index_type, data, offset, stride, n):
        """An indirect multi-draw run in Mesa as the capture called it, a
        run for as many consecutive commands as MAX_DRAW_PRIMITIVES
        triangles hold (IndirectBatch): a fraction of the time of one Mesa
        call a command (about 0.4 ms each), and gl_DrawID right in every
        command when one run holds them all. None where the commands are
        run one by one (the draw of each then says what it refuses, as
        before): no program, a draw that would not reach the camera pass
        or would be refused, a command past a limit, a program that may
        store (a later command could read what an earlier one stored),
        primitive restart (its primitives a command are not known before),
        geometry or tessellation stages, OpenGL ES; and (IndirectBatch) a
        program reading gl_DrawID whose commands need more than one run."""
        if self.es or not self.active or not self.renders() \
                or not self.vertex_program() or (self.core and self.s.vao == 0) \
                or mode not in TRIANGLES_PER_VERTICES or (index_type is not None and (self.s.restart or
                                                                                    self.s.restart_fixed)) \
                or self.s.rasterizer_discard or self.s.image_writes or self.draw_invalid() is not None:
            return None
        stages = self.stage_programs()
        if set(stages) - {"vertex", "fragment"} or any(p.stores for _, p in stages.values()):
            return None
        size = 20 if index_type is not None else 16
        commands, runs, total, first_cmd = [], [], 0, 0
        for i in range(n):
            single, args = indirect_command(mode, index_type, data, offset + i * stride)
            one = dict(args)
            count, instances = one["count"], one["instancecount"]
            first = one["first"] if index_type is None else one["indices"] // np.dtype(INDEX_TYPES[index_type]).itemsize
            per = TRIANGLES_PER_VERTICES[mode](count)
            if instances > MAX_INSTANCES or per * instances > MAX_DRAW_PRIMITIVES or 3 * per > MAX_RECORD_VERTICES \
                    or max(count, first, instances, abs(one.get("basevertex", 0))) > MAX_DRAW_VERTICES:
                return None
            if not (count and instances):
                per = instances = 0
            if total + per * instances > MAX_DRAW_PRIMITIVES:
                runs.append((first_cmd, i, total))
                first_cmd, total = i, 0
            total += per * instances
            commands.append((single, one, per, instances))
        runs.append((first_cmd, n, total))
        if not any(one["count"] and one["instancecount"] for _, one, _, _ in commands) or not self.camera_pass():
            return None   # (the camera pass asked last, as the first command that draws asks it)
        return IndirectBatch(self, no, base_name(name), mode, index_type, data, offset, stride, size, commands, runs,
                             stages["vertex"])


    def h_draw_arrays(self, no, name, a, args):
        d = self.draw_args(no, name, a, args)
        if d is None:
            return   # GL_INVALID_VALUE
        if self.vertex_program():
            return self.shader_draw(no, name, d)
        if self.core or self.es2:
            return   # no vertex shader in a core profile or OpenGL ES 2 and later: nothing is drawn (Mesa)
        mode, first, count = enum_arg(d["mode"], no, f"{name}: the mode"), d.get("first", 0), d["count"]
        if mode not in PRIM_MODES:
            return   # GL_INVALID_ENUM: no vertex is read
        if count > MAX_RECORD_VERTICES:
            fail_call(no, f"{name}: {count} vertices, more than a draw record's {MAX_RECORD_VERTICES}")
        if not self.active or count == 0:
            return
        self.frame_work(no, name, count)
        arr = self.vertex_source(no, name)
        self.draw(no, mode, self.array_values(arr, first, count, no), name)

    def h_draw_elements(self, no, name, a, args):
        d = self.draw_args(no, name, a, args)
        if d is None:
            return   # GL_INVALID_VALUE
        if self.vertex_program():
            return self.shader_draw(no, name, d)
        if self.core or self.es2:
            return   # no vertex shader in a core profile or OpenGL ES 2 and later: nothing is drawn (Mesa)
        mode, count, type_, indices = d["mode"], d["count"], d.get("type"), d.get("indices")
        if enum_arg(mode, no, f"{name}: the mode") not in PRIM_MODES:
            return   # GL_INVALID_ENUM: no index or vertex is read
        if count > MAX_RECORD_VERTICES:
            fail_call(no, f"{name}: {count} indices, more than a draw record's {MAX_RECORD_VERTICES} vertices")
        if not self.active or count == 0 or type_ not in INDEX_TYPES:
            return   # nothing to draw, or GL_INVALID_ENUM
        self.frame_work(no, name, count)
        arr = self.vertex_source(no, name)
        # Indices outside glDrawRangeElements' [start, end] are drawn (GL
        # leaves them undefined; Mesa draws them).
        idx = self.index_values(type_, indices, count, no)
        # Primitive restart (the fixed index first, as GL orders them): the
        # index ends one primitive and starts the next, each assembled alone.
        # GL_PRIMITIVE_RESTART_FIXED_INDEX's index is the type's largest value.
        restart = int(np.iinfo(INDEX_TYPES[type_]).max) if self.s.restart_fixed else \
            self.s.restart_index if self.s.restart else None
        cut = idx == restart if restart is not None else None
        kept = idx[~cut] if cut is not None else idx
        hi = int(kept.max()) + 1 if len(kept) else 0
        if hi > MAX_RECORD_VERTICES:
            fail_call(no, f"{name}: index {hi - 1} is past any vertex array this converter takes")
        verts = self.array_values(arr, 0, hi, no)
        tris = None
        if cut is not None and cut.any():
            bounds = np.flatnonzero(np.concatenate(([True], cut, [True])))
            tris = restart_triangles(mode, (bounds[1:] - bounds[:-1] - 1).tolist())
        self.draw(no, mode, verts[kept], name, tris)

    def h_rect(self, no, name, a, args):
        vals = a[0] + a[1] if len(a) == 2 else a[:4]
        x1, y1, x2, y2 = [number(v, no, "a corner") for v in vals]
        if self.active:
            self.draw(no, "GL_POLYGON", np.array([[x1, y1, 0, 1], [x2, y1, 0, 1], [x2, y2, 0, 1], [x1, y2, 0, 1]],
                                                 dtype=np.float64), name)

    def h_begin(self, no, name, a, args):
        mode = enum_arg(a[0] if a else None, no, f"{name}: the mode")
        if mode not in PRIM_MODES:
            return   # GL_INVALID_ENUM: not inside glBegin/glEnd, and what follows is not a vertex list
        self.s.begin_mode = mode
        self.s.begin_verts = []
        self.s.begin_cuts = []

    def end_primitive(self, no):
        """glEnd: the vertices since glBegin drawn, each piece that
        glPrimitiveRestartNV cut off assembled alone."""
        s = self.s
        mode, verts, cuts = s.begin_mode, s.begin_verts, s.begin_cuts
        s.begin_mode, s.begin_verts, s.begin_cuts = None, [], []
        if not verts:
            return
        tris = None
        if cuts:
            ends = cuts + [len(verts)]
            tris = restart_triangles(mode, [b - a for a, b in zip([0] + cuts, ends)])
        self.draw(no, mode, np.array(verts, dtype=np.float64), "glBegin/glEnd", tris)

    def h_end(self, no, name, a, args):
        pass   # glEnd without glBegin: GL_INVALID_OPERATION, the call does nothing

    def h_primitive_restart_nv(self, no, name, a, args):
        pass   # outside glBegin/glEnd (converter.handle takes it there): GL_INVALID_OPERATION

    def h_render_mode(self, no, name, a, args):
        mode = enum_arg(a[0] if a else None, no, f"{name}: the mode")
        # Selection and feedback exist in the compatibility profile only.
        if mode in ("GL_RENDER", "GL_SELECT", "GL_FEEDBACK") and not self.core and not self.es:
            self.s.render_mode = mode   # (Mesa sets it even without glSelectBuffer, after its error)

    def h_pixel_rectangle(self, no, name, a, args):
        """glDrawPixels, glCopyPixels, glBitmap: rectangles of fragments at the
        raster position, which the unit does not take as an object's. They
        change no depth unless the depth test is on with depth writes: then
        later draws' visibility depends on them, which is not emulated."""
        d = dict(args)
        w = checked(no, integer, d.get("width"), f"{name}: the width", *I32)
        h = checked(no, integer, d.get("height"), f"{name}: the height", *I32)
        if w <= 0 or h <= 0:
            return   # no fragment (glBitmap(0, 0, ...) moves the raster position), or GL_INVALID_VALUE
        if self.active and self.renders() and not self.s.rasterizer_discard and self.s.depth_test \
                and self.s.depth_mask and self.camera_pass():
            fail_call(no, f"{printable(name)} with the depth test on writes depth: not emulated")

    def draws_into_camera_pass(self):
        """Whether a draw now reaches the camera pass: one that does not is
        counted as another pass's work."""
        if self.s.draw_fbo:
            self.gpu_wrote()
        else:
            if self.main_drawable is None and self.current_drawable not in self.pbuffers:
                self.check_screen(self.last_call, self.current_drawable, "is the first drawn into")
                self.main_drawable = self.current_drawable   # the first draw into a window: the main one
            if self.current_drawable == self.main_drawable:
                self.main_idle = {}
            self.drawn_since_swap.add(self.current_drawable)
        if not self.camera_pass():
            self.offscreen_draws += 1
            return False
        return True

    HANDLERS = {
        "glDrawArraysInstanced": h_draw_under_program,
        "glDrawElementsInstanced": h_draw_under_program,
        "glDrawElementsBaseVertex": h_draw_under_program,
        "glDrawRangeElementsBaseVertex": h_draw_under_program,
        "glDrawElementsInstancedBaseVertex": h_draw_under_program,
        "glDrawArraysInstancedBaseInstance": h_draw_under_program,
        "glDrawElementsInstancedBaseInstance": h_draw_under_program,
        "glDrawElementsInstancedBaseVertexBaseInstance": h_draw_under_program,
        "glMultiDrawArrays": h_multi_draw,
        "glDrawArraysIndirect": h_draw_indirect,
        "glDrawElementsIndirect": h_draw_indirect,
        "glMultiDrawArraysIndirect": h_draw_indirect,
        "glMultiDrawElementsIndirect": h_draw_indirect,
        "glMultiDrawArraysIndirectCount": h_draw_indirect,
        "glMultiDrawElementsIndirectCount": h_draw_indirect,
        "glMultiDrawElements": h_multi_draw,
        "glMultiDrawElementsBaseVertex": h_multi_draw,
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
        "glPrimitiveRestartNV": h_primitive_restart_nv,
        "glRenderMode": h_render_mode,
        "glDrawPixels": h_pixel_rectangle,
        "glCopyPixels": h_pixel_rectangle,
        "glBitmap": h_pixel_rectangle,
    }


def indirect_command(mode, index_type, data, at):
    """The indirect command at byte `at` of `data` (GL 4.6, 10.4: count,
    instances, first or first index, [base vertex,] base instance; an
    indexed one when `index_type` names the indices' type) as the draw
    it stands for: (its name, its arguments as apitrace's reader gives
    them), its first index made the byte offset a direct draw takes."""
    if index_type is not None:
        count, instances, first, base_vertex, base_instance = struct.unpack_from("<IIIiI", data, at)
        return "glDrawElementsInstancedBaseVertexBaseInstance", [
            ("mode", mode), ("count", count), ("type", index_type),
            ("indices", first * np.dtype(INDEX_TYPES[index_type]).itemsize), ("instancecount", instances),
            ("basevertex", base_vertex), ("baseinstance", base_instance)]
    count, instances, first, base_instance = struct.unpack_from("<4I", data, at)
    return "glDrawArraysInstancedBaseInstance", [("mode", mode), ("first", first), ("count", count),
                                                 ("instancecount", instances), ("baseinstance", base_instance)]


class IndirectBatch:
    """The positions of an indirect multi-draw's commands, run by Mesa a run
    of consecutive commands at a time (DrawCalls.indirect_batch), as the
    draws of the commands ask for them, in order: for command i, one
    float64 array an instance, a DrawRejected (Mesa refused the run), or
    None: the command is run alone, as without the batch (Mesa wrote other
    primitives than counted, or the vertex shader reads gl_DrawID, which a
    run of part of the commands would number from 0)."""

    def __init__(self, conv, no, name, mode, index_type, data, offset, stride, size, commands, runs, vertex):
        self.conv, self.no, self.name, self.mode, self.index_type = conv, no, name, mode, index_type
        self.data, self.offset, self.stride, self.size = data, offset, stride, size
        self.commands, self.runs, self.vertex = commands, runs, vertex
        self.run_at, self.got = None, None

    def get(self, i):
        from ..vertex_stage import DrawRejected
        k = next(k for k, (a, b, _) in enumerate(self.runs) if a <= i < b)
        if self.run_at != k:
            a, b, total = self.runs[k]
            self.run_at, self.got = k, None   # (the run before freed first)
            draws = [(single, one) for single, one, _, _ in self.commands[a:b] if one["count"] and one["instancecount"]]
            at = self.offset + a * self.stride
            try:
                clip = self.conv.vertex_stage().run_indirect(
                    self.conv, self.no, self.name, self.mode, self.index_type,
                    self.data[at:at + (b - a - 1) * self.stride + self.size], self.stride, b - a, draws, total,
                    len(self.runs) == 1, *self.vertex)
            except DrawRejected as e:
                self.got = e
                return e
            if clip is not None and len(clip) == 3 * total:
                self.got, pos = {}, 0
                for j in range(a, b):
                    _, _, per, instances = self.commands[j]
                    self.got[j] = [clip[pos + m * 3 * per:pos + (m + 1) * 3 * per] for m in range(instances)]
                    pos += 3 * per * instances
        if self.got is None or isinstance(self.got, Exception):
            return self.got
        return [c.astype(np.float64) for c in self.got[i]]
