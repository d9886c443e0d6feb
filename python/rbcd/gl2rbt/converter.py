"""The converter: the GL state of a captured stream, call by call, into the
draw stream rbcd-gl-raster reads (docs/gl-capture.md)."""
import struct


from .entities import EntityTracker
from .errors import ConvertError, RasterStopped, fail_call, printable
from .geometry import GeometryOutput
from .gl_registry import named_enumerants
from .gl_tables import (CALL_FLAG_END_FRAME, CALL_FLAGS_APITRACE, COMPAT_ONLY, COMPAT_ONLY_FORMS, END_FRAME_CALLS,
                        ES_ONLY_FORMS, IGNORED_PREFIXES, MESA_NO_OPS, SWAP_HANDLES, TEXTURE_CHANGING, TEXTURE_IGNORED,
                        base_name)
from .glstate import CONVERSION_STATE, SHARED_STATE, GLState
from .glstate.image_calls import checked_calls, image_call_args
from .glstate.attributes import AttributeCalls
from .glstate.buffers import BufferCalls
from .glstate.draws import DrawCalls, capture_vertex_bounds
from .glstate.feedback import FeedbackCalls
from .glstate.camera_depth import CameraDepthCalls
from .glstate.color_outputs import ALWAYS_REVALIDATING, REVALIDATING, ColorOutputCalls
from .glstate.framebuffers import FramebufferCalls
from .glstate.textures import REDUCED_TEXTURES, TextureImageCalls
from .glstate.texture_formats import whole
from .glstate.texture_levels import PASSED_OVER_IMAGES, TextureLevelCalls
from .glstate.dsa import DirectStateCalls
from .glstate.objects import ObjectCalls
from .glstate.per_fragment import PerFragmentCalls
from .glstate.polygon import PolygonCalls
from .glstate.programs import ProgramCalls
from .glstate.transform import TransformCalls
from .glstate.vertex_arrays import VertexArrayCalls
from .selection import Selection
from .window_registry import window_registry

MAX_TILES = 1 << 20   # rbcd-gl-raster's bound: a bin per tile (8192 x 8192 in 8 x 8 tiles)


def context_attributes(no, name, attrs, end):
    """Call `no`'s attribute list (WindowRegistry.attributes: up to `end`),
    the capture's error where it holds anything but enumerants and
    numbers."""
    try:
        return window_registry().attributes(attrs, end)
    except ValueError as e:
        fail_call(no, f"{printable(name)}: the attribute list {e}")


def context_is_core(pairs, major_key, minor_key, mask_key, core_bit):
    """Whether a context created with these attributes (context_attributes'
    by value) is a core profile: 3.2 or later, with the core bit alone in
    its profile mask (the default; more than one bit is the window system's
    error, and no context is made)."""
    ws = window_registry()
    version = (pairs.get(ws.value(major_key), 1), pairs.get(ws.value(minor_key), 0))
    if version < (3, 2):
        return False
    return pairs.get(ws.value(mask_key), ws.value(core_bit)) == ws.value(core_bit)


# The versions a context can be asked for (GLX_ARB_create_context and its
# ES profile extension, EGL_KHR_create_context): no driver makes another.
GL_VERSIONS = {(1, m) for m in range(6)} | {(2, 0), (2, 1)} | {(3, m) for m in range(4)} | {(4, m) for m in range(7)}
ES_VERSIONS = {(1, 0), (1, 1), (2, 0), (3, 0), (3, 1), (3, 2)}
# What a failed MakeCurrent returns as apitrace records it: GLX's Bool
# ("False"), WGL's BOOL ("FALSE"), EGL's EGLBoolean, or a number.
MAKE_CURRENT_FAILED = ("False", "FALSE", "EGL_FALSE", "GL_FALSE", 0)


def check_version(no, name, es, version):
    """A context made of a version no OpenGL (ES) has is the capture's error."""
    if version not in (ES_VERSIONS if es else GL_VERSIONS):
        fail_call(no, f"{printable(name)}: a context of {'OpenGL ES' if es else 'OpenGL'} "
                  f"{printable(version[0], 20)}.{printable(version[1], 20)}, a version that does not exist, "
                  "was made")


STATE_GROUPS = (TransformCalls, PerFragmentCalls, PolygonCalls, VertexArrayCalls, BufferCalls, AttributeCalls,
                ProgramCalls, FramebufferCalls, CameraDepthCalls, TextureImageCalls, TextureLevelCalls,
                DirectStateCalls, DrawCalls, FeedbackCalls, ObjectCalls, ColorOutputCalls)


# The calls that start with Mesa's state update (_mesa_update_state), which
# tests the bound framebuffer objects when _NEW_BUFFERS is pending
# (FramebufferCalls.update_framebuffers): draws, clears, pixel reads, draws
# and copies, copies into textures, raster positions. (A blit tests the
# framebuffers it names itself: h_blit_framebuffer.)
STATE_UPDATES = (set(DrawCalls.HANDLERS) - {"glEnd", "glPrimitiveRestartNV", "glRenderMode"}) | {
    "glClear", "glClearBufferfv", "glClearBufferiv", "glClearBufferuiv", "glClearBufferfi",
    "glReadPixels", "glReadnPixels",
    "glCopyTexImage1D", "glCopyTexImage2D", "glCopyTexSubImage1D", "glCopyTexSubImage2D", "glCopyTexSubImage3D",
    "glCopyTextureSubImage1D", "glCopyTextureSubImage2D", "glCopyTextureSubImage3D"} | {
    f"glRasterPos{n}{t}{v}" for n in "234" for t in "sifd" for v in ("", "v")}
# Direct state access clears: Mesa 22.3 binds the named framebuffer for
# drawing, clears, and binds the one before again (FramebufferCalls.named_clear).
NAMED_CLEARS = {"glClearNamedFramebufferfv", "glClearNamedFramebufferiv", "glClearNamedFramebufferuiv",
                "glClearNamedFramebufferfi"}
# Arguments that name a buffer target, and the suffixes of an extension's
# name for one (GL_ARRAY_BUFFER_ARB is GL_ARRAY_BUFFER).
BUFFER_TARGET_ARGS = {"target", "readTarget", "writeTarget"}
TARGET_SUFFIXES = ("_BUFFER_ARB", "_BUFFER_EXT", "_BUFFER_OES")


def swapped_drawable(name, args, no):
    """The window or surface buffer swap `name` (call `no`) names
    (SWAP_HANDLES: glXSwapBuffers' drawable, eglSwapBuffers' surface,
    wglSwapBuffers' device context): a handle, as apitrace records one, or
    None (a frame terminator names none); anything else, or none where
    apitrace records one, is the capture's error."""
    key = SWAP_HANDLES.get(name)
    if key is None:
        return None
    d = dict(args)
    if key not in d:
        fail_call(no, f"{printable(name)} without its {key} (apitrace records the one swapped)")
    v = d[key]
    if not isinstance(v, int) or isinstance(v, bool) or not 0 <= v < 1 << 64:
        fail_call(no, f"the buffer swap's drawable {printable(v, 40)} is not a handle")
    return v


class Converter(*STATE_GROUPS, GeometryOutput):
    def __init__(self, args, raster_in, geometry_out):
        self.args = args
        # Whether the capture shows every glGenFramebuffers and
        # glGenRenderbuffers call (capture.shows_every_gen); without a
        # capture (the state tests), as a reduced capture of version 1.
        from .capture import shows_every_gen, shows_every_image
        self.every_gen_shown = bool(getattr(args, "trace", None)) and shows_every_gen(args.trace)
        # Whether every image-giving call is there (texture_levels.py):
        # without a capture (the state tests), it is.
        self.every_image_shown = not getattr(args, "trace", None) or shows_every_image(args.trace)
        from .reduced import is_reduced_capture, source_bytes
        # A reduced capture carries, with a draw whose vertex shader reads
        # textures, the calls that made them (REDUCED_TEXTURES); written
        # there by run_calls when writes_reduced.
        self.reads_reduced = bool(getattr(args, "trace", None)) and is_reduced_capture(args.trace)
        self.writes_reduced = False
        self.reduced_textures = []
        self.s = self.initial_state()
        self.raster = raster_in          # binary stream to rbcd-gl-raster, or None
        self.stream_copy = open(args.stream_out, "wb") if getattr(args, "stream_out", None) else None
        self.geo = geometry_out          # text, or None
        self.frame = 0                   # capture frame (swaps seen)
        self.out_frame = -1              # output frame number
        self.frame_open = False          # its start record is written
        self.frame_records = 0           # draw records in it
        self.frame_vertices = 0          # vertices its draws set up or ran (every instance's)
        self.capture_vertices = 0        # the same, over the frames converted
        self.capture_amplified = 0       # of them, made by tessellation or geometry shaders
        # The size of the capture, or of the one a reduced capture was
        # reduced from, which the bounds scale with (reduced.source_bytes).
        self.source_bytes = source_bytes(args.trace) if getattr(args, "trace", None) else 0
        self.max_capture_vertices = capture_vertex_bounds(self.source_bytes)
        self.multi_draw_index = 0        # the draw of a multi-draw being run (gl_DrawID)
        self.multi_draw_name = None      # that multi-draw's call
        self.batched = None              # an indirect multi-draw's positions, run whole (indirect_batch)
        self.frame_view = None           # the frame's view matrix (the first perspective draw's model-view)
        self.screen = tuple(args.screen) if args.screen else None
        self.current_drawable = None     # the window or surface MakeCurrent named (its handle)
        self.read_drawable = None        # the one it named to read from (glXMakeContextCurrent, eglMakeCurrent)
        self.read_elsewhere = set()      # depth-tested draws into a window read through another (--check-depth)
        self.main_drawable = None        # the one current at the first draw into a window (on_main_drawable)
        self.drawables = set()           # every one MakeCurrent named
        self.drawable_sizes = {}         # drawable -> its size, as apitrace records it at a first MakeCurrent
        self.pbuffers = set()            # off-screen surfaces (never the main window)
        self.drawn_since_swap = set()    # drawables drawn into since their last swap
        self.main_idle = {}              # another window: its swaps with draws since the main one's last
        self.context = None              # the context made current last (None: none named yet; 0: released)
        self.draw_context = None         # the context the frames' draws were made in
        self.state_context = None        # the context whose state self.s holds (the last made current)
        self.unshared_contexts = set()   # made by eglCreateContext sharing no objects, never current yet
        self.destroyed_contexts = set()  # eglDestroyContext's (a handle may be reused by a later context)
        self.context_states = {}         # context -> its own state (GLState's fields) while another is current
        self.context_profiles = {}       # context -> (es, core, es2) as it was made
        self.shares = {}                 # context -> the context whose objects it shares
        self.group_states = {}           # share group -> its objects (SHARED_STATE) while another group's are held
        self.flags = 0                   # of the call being handled
        self.ret = None                  # its return value, as apitrace recorded it
        self.select = Selection(args.select) if args.select else None
        self.tracker = EntityTracker(self.select.settings) if self.select else None
        self.drawn_surfaces = set()
        self.camera_depths_start()
        self.geo_objects = {}            # object id -> list of (eye verts, tris)
        self.geo_view = None             # the projection of the frame's collisionable draws
        self.geo_space = None            # "eye" or "ndc": the space of the frame's geometry
        self.offscreen_draws = 0         # draws left out: not the camera pass
        # Draws whose viewport reaches past the screen's far edges: their
        # number and the first's call and viewport (the report says so).
        self.viewport_past = [0, None, None]
        self.rejected_draws = []         # (call, GL error): draws under a program Mesa refused, as GL does
        self.fragment_effects = {}       # output frame -> {FRAGMENT_EFFECT_KEYS: count}, frames with programs
        self.draw_instances = 1          # instances of the draw being classified
        self.draw_instance = None        # the instance (baseinstance + i) of the draw under a program
        self.draw_effects = False        # its fragment shader can discard or write gl_FragDepth
        self.draw_shade = 0              # its fragment shader's cost, percent of a reference fragment (0: none)
        self.vertex_data = None          # its vertex data's digest, or what computes it (draw_vertex_data)
        self.shading_costs = None        # ShadingCosts, at the first draw under a program
        self.vertex_stage_ = None        # Mesa, started at the first draw under a program
        self.replay = None               # Mesa's replay of the capture, for rendered textures (rendered_textures.py)
        self.es = False                  # an OpenGL ES capture (EGL with the ES API)
        self.egl_api = None              # eglBindAPI's API by value (None: EGL_OPENGL_ES_API, the default)
        self.core = False                # a core-profile context: no default vertex array object
        self.es2 = False                 # OpenGL ES 2 or later: no fixed-function pipeline
        self.last_depth_draw = None      # the frame's last draw with the depth test on
        self.last_depth_wrong = None     # why the converter's depth buffer was wrong for it (CameraDepthCalls)
        self.last_depth_bits = None      # the bits of its depth buffer (CameraDepthCalls.depth_bits)
        self.ignored_prims = 0
        self.partial_frame_dropped = False
        self.listing = None              # --list-draws: one dict per draw of the frame
        self.last_rule = "untagged"
        self.last_rule_table = {}        # the selection rule that decided the last draw, {} if none
        # (output frame, capture frame, call of its last draw with the depth
        # test on, why the converter's depth buffer was wrong for it or None)
        self.last_3d_draws = []
        self.last_call = None
        self.last_name = None   # (the call being handled, for checks made below its handler)
        self.header_written = False
        self.first_frame, self.last_frame = args.frame_range
        self.active = self.in_range(0)   # the current frame is converted

    # ---- output
    def emit(self, data):
        if self.stream_copy is not None:
            self.stream_copy.write(data)
        if self.raster is not None and self.raster is not False:
            try:
                self.raster.write(data)
            except BrokenPipeError:
                raise RasterStopped()

    def write_header(self):
        if self.header_written:
            return
        if self.screen is None:
            # The main window's size as apitrace recorded it (at the first
            # MakeCurrent of a context only: another drawable's, a
            # pbuffer's, may be the one recorded; then the viewport of the
            # window's first draw or clear).
            viewport = self.s.viewport[2:4] if self.s.viewport else None
            window = self.main_drawable if self.main_drawable is not None else self.current_drawable
            self.screen = self.drawable_sizes.get(window) or viewport
        if self.screen is None or min(self.screen) < 1:
            raise ConvertError("the capture sets no viewport before its first draw: give --screen W H")
        w, h = self.screen
        tw, th = self.args.tile
        tiles = -(-w // tw) * -(-h // th)
        if tiles > MAX_TILES:
            raise ConvertError(f"a screen of {w} x {h} in {tw} x {th} tiles is {tiles} tiles, more than {MAX_TILES}")
        self.emit(b"RBCDGLD2" + struct.pack("<5I", w, h, self.args.tile[0], self.args.tile[1], self.args.depth_bits))
        self.header_written = True

    # ---- frames
    def in_range(self, frame):
        return self.first_frame <= frame and (self.last_frame is None or frame <= self.last_frame)

    def check_draw_context(self, no):
        """A draw is made in the context of the frames' earlier draws (the
        converter keeps each context's state, but draws into one window's
        frames from one: two are not merged), and in one at all."""
        if self.context == 0:
            fail_call(no, "a draw with no GL context current (released by a MakeCurrent call)")
        if self.draw_context is not None and self.context != self.draw_context:
            fail_call(no, f"a draw in GL context {printable(self.context)} after draws in "
                      f"{printable(self.draw_context)}: draws of two contexts into one trace are not emulated")

    def open_frame(self, no):
        """Writes the frame's start record before its first record. A record
        comes from the context of the earlier ones: the converter keeps one
        context's state, and a draw with none current does nothing in GL
        (games make a first context current, release it, and draw in a
        second; a capture that draws in two is refused, not merged)."""
        self.check_draw_context(no)
        if self.draw_context is None:
            self.draw_context = self.context
        if self.frame_open:
            return
        self.write_header()
        self.out_frame += 1
        self.emit(b"F" + struct.pack("<Q", no))
        self.frame_open = True

    def end_frame(self, no):
        if self.active:
            self.open_frame(no)
            self.emit(b"E" + struct.pack("<Q", no))
            self.last_3d_draws.append((self.out_frame, self.frame, self.last_depth_draw, self.last_depth_wrong,
                                       self.last_depth_bits))
            if self.geo is not None:
                self.write_geometry_frame()
        self.frame += 1
        self.frame_open = False
        self.frame_records = 0
        self.frame_vertices = 0
        self.active = self.in_range(self.frame)
        if self.active and self.frame == self.first_frame:
            self.camera_depths_start()
        self.drawn_surfaces = set()
        self.geo_objects = {}
        self.geo_view = None
        self.geo_space = None
        self.last_depth_draw = self.last_depth_wrong = self.last_depth_bits = None
        self.frame_view = None
        self.s.marker = ""
        if self.tracker:
            self.tracker.begin_frame()

    # ---- the call handlers
    def handle(self, call):
        no, name, args, ret, flags = call
        if isinstance(flags, bool) or not isinstance(flags, int) or not 0 <= flags <= CALL_FLAGS_APITRACE:
            fail_call(no, f"{printable(name)}: the call's flags {printable(flags, 40)} are not apitrace's")
        if flags & CALL_FLAG_END_FRAME and name not in END_FRAME_CALLS:
            fail_call(no, f"{printable(name)}: the end-of-frame flag on a call that ends no frame "
                      "(apitrace sets it on buffer swaps only)")
        if name in END_FRAME_CALLS and not flags & CALL_FLAG_END_FRAME:
            # apitrace's reader flags a call by its name: a swap without the
            # flag had merged its frame into the next.
            fail_call(no, f"{printable(name)}: a buffer swap without the end-of-frame flag apitrace gives every one")
        self.flags, self.ret = flags, ret
        self.last_call, self.last_name = no, name
        s = self.s
        if args and isinstance(args[-1], tuple) and args[-1][0] == REDUCED_TEXTURES:
            if not self.reads_reduced:
                fail_call(no, f"{printable(name)}: an argument apitrace does not write ({REDUCED_TEXTURES})")
            self.restore_texture_calls(no, name, args[-1][1])
            args = args[:-1]
        base = base_name(name)
        if base in self.HANDLERS:
            args = named_enumerants(name, args)
        if any(k in BUFFER_TARGET_ARGS and isinstance(v, str) and v.endswith(TARGET_SUFFIXES) for k, v in args):
            # apitrace names some buffer targets by their extension's enumerant
            # (GL_PARAMETER_BUFFER_ARB): the same value as the core name.
            args = [(k, v.rsplit("_", 1)[0] if k in BUFFER_TARGET_ARGS and isinstance(v, str)
                     and v.endswith(TARGET_SUFFIXES) else v) for k, v in args]
        if base in self.IMAGE_CALLS:
            args = image_call_args(no, name, args)
            self.pixels_held(no, name, dict(args))
        a = [v for _, v in args]
        if s.begin_mode is not None:
            if base.startswith("glVertex"):
                self.immediate_vertex(no, base, a)
                return
            if base == "glEnd":
                self.end_primitive(no)
                return
            if base == "glPrimitiveRestartNV":   # ends the primitive and starts another of its mode
                if len(s.begin_verts) > (s.begin_cuts[-1] if s.begin_cuts else 0):   # (as many as vertices)
                    s.begin_cuts.append(len(s.begin_verts))
                return
            if base.startswith(("glColor", "glNormal", "glTexCoord", "glMultiTexCoord", "glMaterial",
                                "glSecondaryColor", "glFogCoord", "glEdgeFlag", "glIndex")):
                return
            if base.startswith(("glCallList", "glArrayElement", "glEvalCoord", "glEvalPoint", "glVertexAttrib")):
                fail_call(no, f"{printable(name)} between glBegin and glEnd is not emulated")
            if flags & CALL_FLAG_END_FRAME and self.swaps_main_drawable(no, args):
                # A buffer swap there ends the frame; Mesa keeps the
                # primitive's vertices and draws them at glEnd, into the next.
                self.end_frame(no)
            return   # any other call there is GL_INVALID_OPERATION: it does nothing
        h = self.HANDLERS.get(base) if name not in MESA_NO_OPS else Converter.h_mesa_no_op
        if base in DrawCalls.HANDLERS and self.draw_context is not None and self.active:
            self.check_draw_context(no)   # before the second context's own state refuses it otherwise
        if (self.core or self.es2) and (base in COMPAT_ONLY or name in COMPAT_ONLY_FORMS) \
                or not self.es and name in ES_ONLY_FORMS:
            h = Converter.h_not_in_core
        bound = self.bindings() if base in REVALIDATING else None
        self.decides = False   # set by a handler whose call has Mesa decide (a successful attachment, ...)
        if s.new_buffers and base in STATE_UPDATES and not self.refused_before_update(no, name, base, args):
            self.update_framebuffers(no, name)
        elif base in NAMED_CLEARS:
            self.named_clear(no, name, dict(args))
        if h is not None:
            try:
                h(self, no, name, a, args)
            except (TypeError, ValueError, OverflowError, IndexError, KeyError, struct.error) as e:
                # An argument of a type or size no GL call takes: the
                # capture's error, whichever check it slipped past.
                fail_call(no, f"{printable(name)}: malformed arguments ({type(e).__name__}: {printable(e, 80)})")
        elif base.startswith("glVertex") and not base.startswith("glVertexAttrib"):
            fail_call(no, f"{printable(name)} outside glBegin/glEnd")
        elif base.startswith(IGNORED_PREFIXES) and not (base.startswith("glTexture") and base not in TEXTURE_IGNORED):
            # (an unhandled glTexture* call, direct state access on a texture,
            # may make a 2D one's image). One that may change a texture the
            # converter keeps no calls for has it read back again.
            if base.startswith(TEXTURE_CHANGING):
                self.gpu_wrote()
            if PASSED_OVER_IMAGES.match(base) and self.s.images_passed_over is None:
                self.s.images_passed_over = (no, printable(name))
        else:
            fail_call(no, f"{printable(name)} is not emulated and may change geometry or visibility")
        if self.decides or bound is not None and (base in ALWAYS_REVALIDATING or self.bindings() != bound):
            self.revalidate()
        if flags & CALL_FLAG_END_FRAME and self.swaps_main_drawable(no, args):
            self.end_frame(no)

    def refused_before_update(self, no, name, base, args):
        """Whether Mesa 22.3 refuses a call of STATE_UPDATES before its state
        update, which then tests nothing: glClear of a bit that names no
        buffer, a pixel rectangle of negative size, a copy into a texture
        that does not exist."""
        d = dict(args)
        if base == "glClear":
            return self.clear_bits(no, name, args[0][1] if args else None) is None
        if base in ("glReadPixels", "glReadnPixels", "glCopyPixels", "glDrawPixels", "glBitmap"):
            return any(whole(v) and v < 0 for v in (d.get("width"), d.get("height")))
        if base.startswith("glCopyTextureSubImage"):
            return not (whole(d.get("texture")) and d["texture"] in self.s.texture_targets)
        return False

    def swaps_main_drawable(self, no, args):
        """Whether a buffer swap is the main window's (another window's or
        surface's, one MakeCurrent named, ends no frame: on_main_drawable).
        A window drawn into and swapped twice while the main one had
        neither takes its place (the game moved to a window made anew:
        a resolution change)."""
        swapped = swapped_drawable(self.last_name, args, no)
        if self.main_drawable is None or swapped == self.main_drawable or swapped not in self.drawables:
            self.main_idle = {}
            return True
        if swapped in self.drawn_since_swap and swapped not in self.pbuffers:
            self.main_idle[swapped] = self.main_idle.get(swapped, 0) + 1
            if self.main_idle[swapped] >= 2:
                self.check_screen(no, swapped, "becomes the main window at this swap")
                self.main_drawable, self.main_idle = swapped, {}
        self.drawn_since_swap.discard(swapped)
        return False

    def check_screen(self, no, drawable, how):
        """A trace has one screen: a main window of another size than the
        one chosen (an earlier window's, or --screen's) is refused, naming
        the call, rather than its draws cut to that screen (round 17's
        R17-3); the frames from the next one on convert alone."""
        size = self.drawable_sizes.get(drawable)
        if self.screen is None or size is None or tuple(size) == tuple(self.screen) or self.args.screen:
            return
        fail_call(no, f"window {printable(drawable)} ({size[0]} x {size[1]}) {how}, and the trace's screen is "
                  f"{self.screen[0]} x {self.screen[1]}, an earlier window's: a trace has one screen (convert the "
                  f"frames from {self.frame} on alone, --frames {self.frame}:, or give --screen)")

    def h_pbuffer_created(self, no, name, a, args):
        """glXCreatePbuffer, eglCreatePbufferSurface: an off-screen surface,
        never the main window (a shader warm-up's draws there are another
        target's)."""
        if self.ret:
            self.pbuffers.add(self.ret)

    def h_mesa_no_op(self, no, name, a, args):
        pass   # an entry point Mesa answers with a stub (gl_tables.MESA_NO_OPS)

    def h_not_in_core(self, no, name, a, args):
        pass   # a compatibility-profile call in a core profile: GL_INVALID_OPERATION, nothing changes

    def h_refuse(self, no, name, a, args):
        fail_call(no, f"{printable(name)} is not emulated and may change geometry or visibility")

    def h_egl_bind_api(self, no, name, a, args):
        """eglBindAPI: the API later contexts are of, given by name or by
        value; an API EGL refuses (EGL_FALSE) changes nothing."""
        if self.ret in ("EGL_FALSE", 0, False):
            return
        ws = window_registry()
        api = ws.value(dict(args).get("api"))
        if api not in {ws.value(n) for n in ("EGL_OPENGL_API", "EGL_OPENGL_ES_API", "EGL_OPENVG_API")}:
            fail_call(no, f"{printable(name)}: {printable(dict(args).get('api'), 40)} is no API EGL has, "
                      "and the call succeeded")
        self.egl_api = api

    def h_egl_create_context(self, no, name, a, args):
        """eglCreateContext: a context of the API eglBindAPI bound (OpenGL
        ES, EGL's default, of EGL_CONTEXT_CLIENT_VERSION, 1 by default, or
        OpenGL); one the call did not make (EGL_NO_CONTEXT) changes
        nothing, and one of a version no GL has is the capture's error."""
        ws = window_registry()
        es = self.egl_api != ws.value("EGL_OPENGL_API")
        attrs = context_attributes(no, name, dict(args).get("attrib_list"), "EGL_NONE")
        if not self.ret:
            return
        version = (attrs.get(ws.value("EGL_CONTEXT_MAJOR_VERSION"), 1),
                   attrs.get(ws.value("EGL_CONTEXT_MINOR_VERSION"), 0))
        check_version(no, name, es, version)
        self.context_created(dict(args).get("share_context"))
        self.profile_made(es, not es and context_is_core(attrs, "EGL_CONTEXT_MAJOR_VERSION",
                                                          "EGL_CONTEXT_MINOR_VERSION",
                                                          "EGL_CONTEXT_OPENGL_PROFILE_MASK",
                                                          "EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT"),
                          es and version[0] >= 2)

    def profile_made(self, es, core, es2=False):
        """The API and profile of the context the call made (self.ret; es2:
        OpenGL ES 2 or later, which has no fixed-function pipeline): the
        converter's when no context was made current yet or it is the one
        current, else from when it is made current."""
        if isinstance(self.ret, int) and not isinstance(self.ret, bool) and self.ret:
            self.context_profiles[self.ret] = (es, core, es2)
        if self.state_context is None or self.state_context == self.ret:
            self.es, self.core, self.es2 = es, core, es2

    def use_profile(self, ctx):
        """Context ctx's API and profile, where the capture shows its making."""
        if ctx in self.context_profiles:
            self.es, self.core, self.es2 = self.context_profiles[ctx]

    def h_make_current(self, no, name, a, args):
        """glXMakeCurrent, glXMakeContextCurrent, eglMakeCurrent and
        wglMakeCurrent: the context their last argument names (0: none)."""
        ctx = a[-1] if a else None
        if not isinstance(ctx, int) or isinstance(ctx, bool):
            fail_call(no, f"{printable(name)}: the context {printable(ctx, 40)} is not a handle")
        if self.ret is not None and self.ret in MAKE_CURRENT_FAILED:
            return   # it failed (a destroyed context, a bad surface): what was current stays current
        d = dict(args)
        for k in ("drawable", "draw", "read", "hdc"):
            if k in d and d[k] is not None and (not isinstance(d[k], int) or isinstance(d[k], bool)):
                fail_call(no, f"{printable(name)}: the {k} {printable(d[k], 40)} is not a handle")
        drawable = d.get("drawable", d.get("draw", d.get("hdc")))
        # (the context and drawables already current: GLX returns at once,
        # and Mesa decides nothing)
        self.decides = (ctx, drawable, d.get("read", drawable)) != \
            (self.context, self.current_drawable, self.read_drawable)
        self.current_drawable = drawable
        self.read_drawable = d.get("read", self.current_drawable)
        self.drawables.add(self.current_drawable)
        self.context = ctx
        if ctx and ctx != self.state_context:
            if self.state_context in self.destroyed_contexts and ctx in self.unshared_contexts:
                self.new_context()
                self.use_profile(ctx)
            else:
                self.switch_state(ctx)
            self.state_context = ctx
        self.unshared_contexts.discard(ctx)
        if self.decides:
            self.s.new_buffers = True   # (Mesa's _mesa_make_current)

    def switch_state(self, ctx):
        """Context `ctx` made current after another: the state of the one
        before kept for when it is current again, ctx's own state (GL's
        initial one the first time) in its place, and, unless the two share
        objects, ctx's share group's objects (a loader context's binds and
        viewport leave the drawing context's as they were)."""
        old = self.state_context
        if old is None or ctx not in self.context_profiles or old not in self.context_profiles:
            # The first context: the state so far is its own (of its
            # profile, whichever context was made last); or one whose
            # making the capture does not show: taken as the same context.
            self.use_profile(ctx)
            return
        fields = vars(self.s)
        self.context_states[old] = {k: v for k, v in fields.items() if k not in SHARED_STATE | CONVERSION_STATE}
        fresh = None
        if self.share_group(ctx) != self.share_group(old):
            self.group_states[self.share_group(old)] = {k: fields[k] for k in SHARED_STATE}
            shared = self.group_states.get(self.share_group(ctx))
            if shared is None:
                fresh = vars(self.initial_state())
                shared = {k: fresh[k] for k in SHARED_STATE}
            fields.update(shared)
        own = self.context_states.get(ctx)
        if own is None:
            fresh = fresh or vars(self.initial_state())
            own = {k: v for k, v in fresh.items() if k not in SHARED_STATE | CONVERSION_STATE}
        fields.update(own)
        self.use_profile(ctx)

    def share_group(self, ctx):
        """The context whose objects ctx shares (itself when it shares none)."""
        while ctx in self.shares:
            ctx = self.shares[ctx]
        return ctx

    def context_created(self, share):
        """A context the call returned (self.ret), sharing objects with
        `share` (0 or NULL: none)."""
        ctx = self.ret
        if isinstance(ctx, int) and not isinstance(ctx, bool) and ctx:
            self.destroyed_contexts.discard(ctx)
            self.unshared_contexts.discard(ctx)
            self.context_states.pop(ctx, None)   # a handle reused: a new context
            self.shares.pop(ctx, None)
            if share in (0, None):
                self.unshared_contexts.add(ctx)
            elif isinstance(share, int) and not isinstance(share, bool) and self.share_group(share) != ctx:
                self.shares[ctx] = share

    def h_egl_destroy_context(self, no, name, a, args):
        """eglDestroyContext and glXDestroyContext (which returns nothing)."""
        ctx = dict(args).get("ctx")
        if self.ret in ("EGL_TRUE", 1, True, None) and isinstance(ctx, int) and not isinstance(ctx, bool) and ctx:
            self.destroyed_contexts.add(ctx)

    def h_glx_create_old_context(self, no, name, a, args):
        """glXCreateContext and glXCreateNewContext: a compatibility context
        sharing the objects of shareList or share_list."""
        if not self.ret:
            return   # no context made (NULL)
        d = dict(args)
        self.context_created(d.get("shareList", d.get("share_list")))
        self.profile_made(False, False)

    def new_context(self):
        """The state of a context made current for the first time, created
        sharing no objects, after the context whose state the converter held
        was destroyed (glmark2 makes one to read the GL strings and clear,
        destroys it, and draws in a second): GL's initial state, with no
        objects; the window's contents stay. That context's draws are no
        longer those of another context."""
        old = vars(self.s)
        group = self.share_group(self.state_context) if self.state_context is not None else None
        if any(c != self.state_context and c not in self.destroyed_contexts and self.share_group(c) == group
               for c in self.context_profiles):
            self.group_states[group] = {k: old[k] for k in SHARED_STATE}   # a live context shares them
        else:   # gone with the context: no longer held
            old["buffer_bytes_in_all"] -= sum(old["buffer_held"].values())
            old["texture_bytes_kept"] -= sum(tc.bytes for tc in old["texture_calls"].values())
        self.s = self.initial_state()
        vars(self.s).update({k: old[k] for k in CONVERSION_STATE})
        if self.vertex_stage_ is not None:
            self.vertex_stage_.forget_objects()
        self.draw_context = None

    def initial_state(self):
        """GL's initial state. In a capture that shows every
        glGenFramebuffers and glGenRenderbuffers call, no such name is
        generated yet: a core profile binds none before its glGen*. A
        reduced capture of version 1, which dropped them, is taken as it
        binds until it shows one (glstate.generated_name)."""
        s = GLState()
        if self.every_gen_shown:
            s.framebuffer_names, s.renderbuffer_names = set(), set()
        return s

    def h_glx_create_context(self, no, name, a, args):
        """glXCreateContextAttribsARB: a core profile, or OpenGL ES
        (GLX_EXT_create_context_es2_profile); a context the call did not
        make (NULL) changes nothing, and one of a version no GL has is the
        capture's error."""
        if not self.ret:
            return
        self.context_created(dict(args).get("share_context"))
        pairs = context_attributes(no, name, dict(args).get("attrib_list"), 0)
        ws = window_registry()
        # (GLX_CONTEXT_ES2_PROFILE_BIT_EXT is the same bit)
        es = pairs.get(ws.value("GLX_CONTEXT_PROFILE_MASK_ARB")) == ws.value("GLX_CONTEXT_ES_PROFILE_BIT_EXT")
        version = (pairs.get(ws.value("GLX_CONTEXT_MAJOR_VERSION_ARB"), 1),
                   pairs.get(ws.value("GLX_CONTEXT_MINOR_VERSION_ARB"), 0))
        check_version(no, name, es, version)
        self.profile_made(es, not es and context_is_core(pairs, "GLX_CONTEXT_MAJOR_VERSION_ARB",
                                                          "GLX_CONTEXT_MINOR_VERSION_ARB",
                                                          "GLX_CONTEXT_PROFILE_MASK_ARB",
                                                          "GLX_CONTEXT_CORE_PROFILE_BIT_ARB"),
                          es and version[0] >= 2)

    # The window system's calls that say which API and profile the capture
    # drew with (the rest of them are passed over).
    WINDOW_SYSTEM = {
        "eglBindAPI": h_egl_bind_api,
        "eglCreateContext": h_egl_create_context,
        "eglDestroyContext": h_egl_destroy_context,
        "glXDestroyContext": h_egl_destroy_context,
        "glXCreateContext": h_glx_create_old_context,
        "glXCreateNewContext": h_glx_create_old_context,
        "glXCreateContextAttribs": h_glx_create_context,
        "glXMakeCurrent": h_make_current,
        "glXMakeContextCurrent": h_make_current,
        "eglMakeCurrent": h_make_current,
        "wglMakeCurrent": h_make_current,
        "glXCreatePbuffer": h_pbuffer_created,
        "glXCreateGLXPbufferSGIX": h_pbuffer_created,
        "eglCreatePbufferSurface": h_pbuffer_created,
    }
    def h_empty_list(self, no, name, a, args):
        """glCallList, glCallLists and glEndList: every list a converted
        capture has is empty (glNewList is refused, and is GL's no-op in a
        core profile), so calling one draws nothing, and glEndList with no
        list open is GL_INVALID_OPERATION."""

    LISTS = {"glCallList": h_empty_list, "glCallLists": h_empty_list, "glEndList": h_empty_list}
    # Calls that can change geometry or visibility in ways not emulated.
    REFUSED = {
        "glNewList": h_refuse,
        "glArrayElement": h_refuse,
        "glEvalMesh1": h_refuse,
        "glEvalMesh2": h_refuse,
        "glEvalCoord1f": h_refuse,
        "glEvalCoord2f": h_refuse,
        "glEvalPoint1": h_refuse,
        "glEvalPoint2": h_refuse,
        "glPushAttrib": h_refuse,
        "glPopAttrib": h_refuse,
        "glPushClientAttrib": h_refuse,
        "glPopClientAttrib": h_refuse,
    }
    HANDLERS = WINDOW_SYSTEM | LISTS | REFUSED | {k: v for group in STATE_GROUPS for k, v in group.HANDLERS.items()}
    # The handled texture image, attachment and view calls, their arguments
    # checked before their handler reads them (glstate.image_calls).
    IMAGE_CALLS = checked_calls(HANDLERS)
