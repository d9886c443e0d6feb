"""The shader path's vertex stage: a draw under a program, run by Mesa.

The converter keeps the capture's state in Python (glstate's buffers,
attributes, programs and framebuffers groups); at each draw the trace needs,
this module brings Mesa's copy up to date with what that draw reads (the
program, built from the sources its last link saw, with gl_Position as its
transform feedback output; its uniforms and uniform blocks; the buffers its
attributes, indices, blocks and texture buffers name, uploaded again only
when their version changed; the vertex array object; current attribute
values; primitive restart) and issues the capture's own draw call with
transform feedback on (mesa.py). Only what a draw reads reaches Mesa: frames
outside --frames, and draws that are not the camera pass, cost nothing."""
import contextlib
import ctypes
import re

import numpy as np

from .errors import fail_call, printable
from .glstate.attributes import check_vertex_data, element_bytes
from .glstate.buffers import merge_extents
from .glstate.programs import COMMENTS, SAMPLER_SETTERS
from .glstate.textures import DEFAULT_BUFFER_TEXTURE
from .mesa import Mesa, Watchdog
from .vertex_textures import IMAGE_TARGETS, SAMPLER_TARGETS, VertexTextures

# Sampler types a vertex shader may read: texture buffers, whose contents
# are buffer objects, and 2D textures (vertex_textures.py). Other textures'
# images are not kept (docs/gl-capture.md).
BUFFER_SAMPLERS = {"GL_SAMPLER_BUFFER", "GL_INT_SAMPLER_BUFFER", "GL_UNSIGNED_INT_SAMPLER_BUFFER"}
SAMPLER = re.compile(r"GL_(INT_|UNSIGNED_INT_)?(SAMPLER|IMAGE)_")
GL_OUT_OF_MEMORY = 0x505
# The program interface query of transform feedback buffers (GL 4.4,
# ARB_enhanced_layouts), called directly (Mesa.proc).
GL_TRANSFORM_FEEDBACK_BUFFER, GL_ACTIVE_RESOURCES, GL_BUFFER_BINDING = 0x8C8E, 0x92F5, 0x9302
# The program interface of uniforms, and the properties that say which
# stage reads one (GL_REFERENCED_BY_*_SHADER).
GL_UNIFORM = 0x92E1
REFERENCED_BY = {"vertex": 0x9306, "tess_control": 0x9307, "tess_evaluation": 0x9308, "geometry": 0x9309,
                 "fragment": 0x930A, "compute": 0x930B}
GL_ERRORS = {0x500: "GL_INVALID_ENUM", 0x501: "GL_INVALID_VALUE", 0x502: "GL_INVALID_OPERATION",
             GL_OUT_OF_MEMORY: "GL_OUT_OF_MEMORY", 0x506: "GL_INVALID_FRAMEBUFFER_OPERATION"}
UNIFORM_DTYPES = {"f": np.float32, "d": np.float64, "i": np.int32, "ui": np.uint32}
MAX_MESA_BUFFER_BYTES = 2 << 30   # the declared sizes of the buffers given to Mesa, in all
# Built-in inputs a vertex shader may read that the draw call itself gives.
# Of the compatibility profile's fixed-function state, gl_Vertex and the
# model-view and projection matrices with what GL derives from them are
# given to Mesa's context from the converter's (a GL 2.x program's
# `gl_ModelViewProjectionMatrix * gl_Vertex` or `ftransform()`); every other
# gl_ input or uniform (gl_Normal, gl_MultiTexCoord0, gl_TextureMatrix,
# gl_LightSource, ...) Mesa's program would read from its own context, not
# the capture's: refused.
# The C type of a glVertexAttrib*v's values, by its suffix.
ATTRIB_VALUE_TYPES = {"b": np.int8, "s": np.int16, "i": np.int32, "ub": np.uint8, "us": np.uint16, "ui": np.uint32,
                      "f": np.float32, "d": np.float64}
CLIP_DISTANCES = re.compile(r"\bgl_(Clip|Cull)Distance\b")
# Outputs that choose the viewport a primitive is drawn in (ARB/AMD
# shader_viewport_layer_array, NV_viewport_array2).
VIEWPORT_OUTPUTS = re.compile(r"\bgl_(ViewportIndex|ViewportMask)\b")
BUILTIN_INPUTS = {"gl_VertexID", "gl_InstanceID", "gl_DrawID", "gl_BaseVertex", "gl_BaseInstance",
                  "gl_VertexIndex", "gl_InstanceIndex", "gl_DrawIDARB", "gl_BaseVertexARB", "gl_BaseInstanceARB"}
# The index of a draw within its multi-draw (GLSL 4.60, ARB_shader_draw_parameters).
DRAW_ID_INPUTS = {"gl_DrawID", "gl_DrawIDARB"}
FIXED_MATRICES = {f"gl_{m}Matrix{form}" for m in ("ModelView", "Projection", "ModelViewProjection")
                  for form in ("", "Inverse", "Transpose", "InverseTranspose")} | {"gl_NormalMatrix"}


def name_str(name):
    return name.decode("ascii", "replace") if isinstance(name, bytes) else str(name)


def varying_names(names):
    """Output names as glTransformFeedbackVaryings takes them (C strings;
    a NUL inside a capture's name ends it, as in C)."""
    arr = (ctypes.c_char_p * len(names))(*[n.encode("utf-8", "replace").split(b"\0")[0] for n in names])
    return ctypes.cast(arr, ctypes.POINTER(ctypes.POINTER(ctypes.c_char)))


def feedback_varying(GL, prog, i):
    """The name of a linked program's transform feedback varying i."""
    length, size, kind = ctypes.c_int(), ctypes.c_int(), ctypes.c_uint()
    name = ctypes.create_string_buffer(256)
    GL.glGetTransformFeedbackVarying(prog, i, 256, ctypes.byref(length), ctypes.byref(size), ctypes.byref(kind),
                                     name)
    return name.value.decode("ascii", "replace")


def block_name(GL, prog, i):
    """The name of a linked program's active uniform block i."""
    length, name = ctypes.c_int(), ctypes.create_string_buffer(1024)
    GL.glGetActiveUniformBlockName(prog, i, 1024, ctypes.byref(length), name)
    return name.value.decode("ascii", "replace")


def es_fragment_shader(vertex_source):
    """An empty fragment shader of the vertex shader's language version
    (comments may come before its #version: GLSL ES 3.20, 3.4)."""
    m = re.search(r"^\s*#\s*version\s+(\d+)(\s+es)?", COMMENTS.sub(" ", vertex_source), re.M)
    version = m.group(1) if m else "100"
    if version == "100":
        return "#version 100\nprecision mediump float;\nvoid main() { gl_FragColor = vec4(0.0); }\n"
    return f"#version {version} es\nprecision mediump float;\nout vec4 c;\nvoid main() {{ c = vec4(0.0); }}\n"


class RunAlone(Exception):
    """run_indirect's commands are to be run one by one."""


class DrawRejected(Exception):
    """Mesa answered the draw with a GL error: in GL the draw does nothing."""


def attach_stage(GL, prog, kind, texts, shaders):
    """A stage's shader objects, each of `texts` compiled on its own and
    attached to `prog`, as the capture linked them (each made is added to
    `shaders`, for the caller to delete): the first that does not compile,
    or None. The capture's bytes as they were (apitrace's text keeps bytes
    that are not UTF-8 as surrogates; GLSL allows them in comments)."""
    failed = None
    for text in texts:
        sh = GL.glCreateShader(kind)
        shaders.append(sh)
        GL.glShaderSource(sh, text.encode("utf-8", "surrogateescape"))
        GL.glCompileShader(sh)
        if failed is None and not GL.glGetShaderiv(sh, GL.GL_COMPILE_STATUS):
            failed = sh
        GL.glAttachShader(prog, sh)
    return failed


# The stages a program draws with, as Mesa links them together.
LINKED_STAGES = {"vertex": "GL_VERTEX_SHADER", "fragment": "GL_FRAGMENT_SHADER", "geometry": "GL_GEOMETRY_SHADER",
                 "tess_control": "GL_TESS_CONTROL_SHADER", "tess_evaluation": "GL_TESS_EVALUATION_SHADER"}
ALL_STAGES = {**LINKED_STAGES, "compute": "GL_COMPUTE_SHADER"}


class MesaProgram:
    def __init__(self, name, version):
        self.name, self.version = name, version
        self.locations = {}   # active uniform name (and name[i]) -> Mesa location
        self.uniform_of = {}  # Mesa location -> the active uniform (its index) whose storage it names
        self.mapped = {}      # (capture location, the name the capture asked it of) -> Mesa location (mesa_location)
        self.applied = {}     # Program.uniforms key -> the value last given Mesa
        self.texture_locations = []   # Mesa locations of its samplers (each element of an array), with targets
        self.image_locations = []     # the same of its images
        self.buffer_samplers = []     # the locations of its buffer texture samplers
        self.reads_draw_id = False    # its vertex shader reads gl_DrawID
        self.fixed_matrices = False   # it reads the model-view or projection matrix (FIXED_MATRICES)
        self.reads_vertex = False     # it reads gl_Vertex
        self.amplifies = False        # it has tessellation or geometry shaders (as many primitives as they make)
        self.tessellates = False      # it has a tessellation evaluation shader
        self.area = True              # its last stage makes triangles (not a geometry shader's points or lines)
        # The kind of primitives its tessellation or geometry shader makes
        # (GL_POINTS, GL_LINES, GL_TRIANGLES: what transform feedback must
        # have begun), as Mesa linked it; None without either.
        self.output_kind = None


class VertexStage:
    def __init__(self, es, conv):
        self.mesa = Mesa(es)
        self.watchdog = Watchdog(conv)
        self.gl = self.mesa.gl
        self.buffers = {}    # capture buffer -> [Mesa buffer, version uploaded]
        self.programs = {}   # capture program -> MesaProgram
        self.link_status = {}   # (sources' digest, attribute bindings) -> whether Mesa links them (links)
        self.vaos = {}       # capture vertex array -> Mesa vertex array
        self.textures = {}   # capture texture buffer -> Mesa texture
        self.vertex_textures = VertexTextures(self.mesa, self.watchdog)   # 2D textures and samplers
        self.scratch = []    # client memory (attributes, indices) goes through these buffers
        self.indirect = None  # an indirect multi-draw's commands (run_indirect)
        self.mesa_bytes = 0  # the declared sizes of the buffers Mesa holds copies of
        self.no = self.name = None   # the draw call being run and its name, for messages
        GL = self.gl
        # Mesa's values of the sampler and image types that are neither
        # texture buffers nor of the targets vertex_textures gives (an
        # external image's samplerExternalOES), and of those it gives, with
        # their targets.
        self.texture_samplers = {int(getattr(GL, n)): n for n in dir(GL)
                                 if SAMPLER.match(n) and isinstance(getattr(GL, n), int)
                                 and n not in BUFFER_SAMPLERS | set(SAMPLER_TARGETS) | set(IMAGE_TARGETS)}
        self.sampler_targets = {int(getattr(GL, n)): t for n, t in SAMPLER_TARGETS.items() if hasattr(GL, n)}
        self.image_targets = {int(getattr(GL, n)): n for n in IMAGE_TARGETS if hasattr(GL, n)}
        self.buffer_sampler_types = {int(getattr(GL, n)) for n in BUFFER_SAMPLERS if hasattr(GL, n)}
        # Every sampler type with its texture target, for the check of two
        # types on one unit (a buffer sampler's is GL_TEXTURE_BUFFER, an
        # external image's its own).
        self.sampler_kinds = {**{v: n for v, n in self.texture_samplers.items() if "SAMPLER" in n},
                              **{v: "GL_TEXTURE_BUFFER" for v in self.buffer_sampler_types},
                              **self.sampler_targets}

    # ---- objects
    def forget_objects(self):
        """Deletes Mesa's copies of the capture's objects: their names now
        belong to another context (a new one, made current after the one
        that named them was destroyed)."""
        GL = self.gl
        if self.buffers:
            GL.glDeleteBuffers(len(self.buffers), [e[0] for e in self.buffers.values()])
        for mp in self.programs.values():
            GL.glDeleteProgram(mp.name)
        if self.vaos:
            GL.glDeleteVertexArrays(len(self.vaos), list(self.vaos.values()))
        if self.textures:
            GL.glDeleteTextures(len(self.textures), list(self.textures.values()))
        self.vertex_textures.forget()
        self.buffers, self.programs, self.vaos, self.textures = {}, {}, {}, {}
        self.mesa_bytes = 0

    def buffer(self, conv, b):
        """Mesa's copy of capture buffer b, up to date."""
        GL = self.gl
        data = conv.s.buffers.get(b)
        if data is None:
            fail_call(self.no, f"the draw reads buffer {b}, which holds no data (never given any, or deleted)")
        entry = self.buffers.get(b)
        if entry is None:
            entry = self.buffers[b] = [int(GL.glGenBuffers(1)), None, 0]
        if entry[2] != len(data):
            # Mesa's copy has the declared size, zero-filled: its memory,
            # unlike the converter's, is taken at once.
            self.mesa_bytes += len(data) - entry[2]
            entry[2] = len(data)
            if self.mesa_bytes > MAX_MESA_BUFFER_BYTES:
                fail_call(self.no, f"the draws' buffers would take more than {MAX_MESA_BUFFER_BYTES >> 30} GiB in "
                          "Mesa, which allocates a buffer's declared size (docs/gl-capture.md, limits)")
        version = conv.s.buffer_versions.get(b)
        if entry[1] != version:
            GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, entry[0])
            written = conv.s.buffer_written.get(b)
            if written is None:
                GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, len(data), np.frombuffer(data, np.uint8) if len(data)
                                else None, GL.GL_STATIC_DRAW)
            else:
                # A large buffer: only what the capture wrote is given to
                # Mesa, so a buffer declared without data costs no memory
                # there either (its other bytes read as Mesa's fresh storage).
                GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, len(data), None, GL.GL_STATIC_DRAW)
                view = np.frombuffer(data, np.uint8)
                for s, e in merge_extents(written):
                    GL.glBufferSubData(GL.GL_COPY_WRITE_BUFFER, s, e - s, view[s:e])
            entry[1] = version
        return entry[0]

    def client(self, data):
        """Client memory in a scratch buffer of its own, from offset 0."""
        GL = self.gl
        buf = int(GL.glGenBuffers(1))
        self.scratch.append(buf)
        GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, buf)
        GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, len(data), bytes(data), GL.GL_STREAM_DRAW)
        return buf

    def clear_element(self, internal, fmt, kind, data, n):
        """The n bytes of one element of internal format `internal` that
        glClearBufferData(internal, fmt, kind, data) writes (data: bytes, or
        None for zeros), as Mesa converts the value; None if Mesa refuses
        the call."""
        from OpenGL.error import GLError
        GL = self.gl
        try:
            enums = [self.mesa.enum(v) for v in (internal, fmt, kind)]
        except ValueError:
            return None   # not an enumerant: GL_INVALID_ENUM
        # One value is at most four components of 4 bytes; room for more,
        # zeros, if apitrace recorded fewer bytes than the format reads.
        value = None if data is None else (ctypes.c_ubyte * 32).from_buffer_copy(bytes(data[:32]).ljust(32, b"\0"))
        buf = int(GL.glGenBuffers(1))
        GL.glBindBuffer(GL.GL_COPY_WRITE_BUFFER, buf)
        try:
            GL.glBufferData(GL.GL_COPY_WRITE_BUFFER, 48, None, GL.GL_STATIC_DRAW)   # a multiple of every size
            GL.glClearBufferData(GL.GL_COPY_WRITE_BUFFER, *enums, value)
            return bytes(GL.glGetBufferSubData(GL.GL_COPY_WRITE_BUFFER, 0, n))
        except GLError:
            return None
        finally:
            GL.glDeleteBuffers(1, [buf])

    def free_scratch(self):
        if self.scratch:
            self.gl.glDeleteBuffers(len(self.scratch), self.scratch)
            self.scratch = []

    def program(self, no, pname, p):
        if p.linked is None:
            fail_call(no, f"a draw with program {pname}, which was never linked")
        mp = self.programs.get(pname)
        if mp is None or mp.version != p.version:
            mp = self.programs[pname] = self.build(no, pname, p)
        GL = self.gl
        GL.glUseProgram(mp.name)
        from OpenGL.error import GLError
        for key, value in p.uniforms.items():
            if mp.applied.get(key) != value:
                mp.applied[key] = value
                mloc = self.mesa_location(mp, p, key[0])
                if mloc < 0:
                    continue   # not read by the vertex stage
                try:
                    self.set_uniform(mloc, value)
                except GLError:
                    continue   # GL_INVALID_OPERATION (a type or count its uniform lacks): the call did nothing
                # Another form at this location, or an array and its elements
                # (they share storage, whether the capture named them or
                # gave their locations in the shader): what was set through
                # them is no longer what Mesa holds.
                storage = mp.uniform_of.get(mloc)
                for other in [o for o in mp.applied if o != key and (
                        o[0] == key[0] or mp.uniform_of.get(self.mesa_location(mp, p, o[0])) == storage)]:
                    del mp.applied[other]
        for idx, binding in p.block_bindings.items():
            block = p.block_names.get(idx)
            if block is None:
                # An index the capture never had named (a program's only
                # block is 0): the block Mesa numbers so in the whole
                # program, as the capture's driver did.
                names = self.full_link(p)[1]
                block = names[idx] if idx < len(names) else None
            if block is not None:
                mi = GL.glGetUniformBlockIndex(mp.name, block)
                if mi != GL.GL_INVALID_INDEX:
                    GL.glUniformBlockBinding(mp.name, mi, binding)
        return mp

    def links(self, p):
        """Whether Mesa links the program as its last link saw it, every
        stage that draws (the capture's own link, whose failure leaves the
        executable in use as it was: ProgramCalls.program_in_use)."""
        return self.full_link(p)[0]

    def feedback_bindings(self, p):
        """The transform feedback binding points program p's executable
        records into, as Mesa links it (linked_feedback_bindings); empty when it
        records nothing or Mesa does not link it."""
        return self.full_link(p)[2]

    def full_link(self, p):
        """Mesa's link of the program as its last link saw it, every stage
        that draws: whether it links, its active uniform blocks' names by
        index, the binding points its transform feedback records into, and
        the name at each location of its default-block uniforms."""
        key = (p.digest, tuple(sorted(p.linked[1].items())), p.separable, p.feedback)
        if key not in self.link_status:
            GL = self.gl
            with self.whole_program(p) as prog:
                ok = prog is not None
                blocks = [block_name(GL, prog, i) for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_UNIFORM_BLOCKS))] \
                    if ok else []
                self.link_status[key] = (ok, blocks, self.linked_feedback_bindings(prog) if ok else frozenset(),
                                         self.location_names(prog) if ok else {})
        return self.link_status[key]

    def location_names(self, prog):
        """Location -> name of each default-block uniform of Mesa's program
        `prog`, every element of an array ("a[0]", "a[1]", ...)."""
        GL, out = self.gl, {}
        for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_UNIFORMS)):
            uname, size, _ = GL.glGetActiveUniform(prog, i)
            uname = name_str(uname)
            base = uname[:-3] if uname.endswith("[0]") else uname
            for each in [uname] + [f"{base}[{k}]" for k in range(1, size)]:
                loc = GL.glGetUniformLocation(prog, each)
                if loc >= 0:
                    out[loc] = each
        return out

    @contextlib.contextmanager
    def whole_program(self, p, stages=LINKED_STAGES):
        """Mesa's link of the program as its last link saw it, every stage
        that draws (or `stages`), with the capture's attribute bindings,
        separability and transform feedback outputs (its link may fail on
        them): the program's name, or None when Mesa does not link it;
        deleted after."""
        from OpenGL.error import GLError
        GL = self.gl
        prog, shaders = GL.glCreateProgram(), []
        try:
            with self.watchdog.on(f"the program linked at call {p.link_call}", grows=True):
                try:
                    for stage, texts in p.objects.items():
                        if stage in stages:
                            attach_stage(GL, prog, getattr(GL, stages[stage]), texts, shaders)
                    for attr, index in p.linked[1].items():
                        GL.glBindAttribLocation(prog, index, attr)
                    if p.separable:   # (OpenGL ES links a program of one stage only so)
                        self.mesa.separable(prog)
                    if p.feedback:
                        names, mode = p.feedback
                        GL.glTransformFeedbackVaryings(prog, len(names), varying_names(names), getattr(GL, mode))
                    GL.glLinkProgram(prog)
                    ok = bool(GL.glGetProgramiv(prog, GL.GL_LINK_STATUS))
                except GLError:
                    ok = False   # GL_INVALID_OPERATION: a binding GL refuses, no link
                yield prog if ok else None
        finally:
            for sh in shaders:
                GL.glDeleteShader(sh)
            GL.glDeleteProgram(prog)

    def sampler_validation(self, p):
        """Mesa's view of program p's samplers as the capture left them:
        (whether a draw with p in use passes Mesa's check that no two
        active samplers of different types refer to one texture unit,
        {stage: ((unit, target) of each active sampler the stage reads)}).
        The first is Mesa's own answer: it follows the check through the
        link and every glUniform that changed a sampler since, the answer
        depending on which stages the last such call changed
        (_mesa_sampler_uniforms_are_valid); a copy of the program is
        linked, given the capture's glUniform1i(v) values in the order
        last set, and validated (glValidateProgram). The second is what a
        pipeline's validation compares across its programs. Kept for the
        program's link and the values and order of its glUniform1i(v) calls
        (a capture that sets the same units before each draw links once)."""
        calls = (p.link_call, p.version, p.int_uniform_calls)
        checked = p.samplers_checked
        if checked is not None and checked[0] == calls:
            return checked[2]
        # The capture's calls that set a sampler (no other call changes
        # what Mesa answers), in the order last set.
        names, locations = self.sampler_uniforms(p)
        sets = [(loc, p.uniform_names.get(loc), value[1]) for (loc, func, _), value in p.uniforms.items()
                if func in SAMPLER_SETTERS and (
                    p.uniform_names[loc] in names if loc in p.uniform_names else loc in locations)]
        key = (p.link_call, p.version, tuple((loc, name, tuple(values)) for loc, name, values in sets))
        if checked is not None and checked[1] == key:
            p.samplers_checked = (calls, key, checked[2])
            return checked[2]
        GL = self.gl
        answer = (True, {})
        with self.whole_program(p, ALL_STAGES) as prog:   # (a compute program's samplers count in a pipeline)
            if prog is not None:
                u, ip = ctypes.c_uint, ctypes.POINTER(ctypes.c_int)
                set_units = self.mesa.proc("glProgramUniform1iv", u, ctypes.c_int, ctypes.c_int, ip)
                for loc, name, values in sets:
                    at = GL.glGetUniformLocation(prog, name) if name is not None else loc
                    if at < 0:
                        continue
                    units = np.array(values, dtype=np.int32).ravel()
                    set_units(prog, at, len(units), units.ctypes.data_as(ip))
                    # (A call Mesa refuses, GL_INVALID_OPERATION or _VALUE,
                    # did nothing in the capture either; its error is
                    # cleared for the calls after.)
                    GL.glGetError()
                GL.glValidateProgram(prog)
                answer = (bool(GL.glGetProgramiv(prog, GL.GL_VALIDATE_STATUS)), self.stage_samplers(prog))
        p.samplers_checked = (calls, key, answer)
        return answer

    def sampler_uniforms(self, p):
        """(names, locations) of program p's active samplers as Mesa links
        it, each element of an array by its own name and location too: what
        a glUniform1i call sets a sampler through. Kept for the link."""
        return self.linked_samplers(p)[:2]

    def sampler_start_units(self, p):
        """({name: unit}, {location: unit}) of program p's active sampler
        elements as Mesa's link leaves them (a layout(binding = N) sets
        the first unit; 0 otherwise), by the names and locations of
        sampler_uniforms."""
        return self.linked_samplers(p)[2:]

    def linked_samplers(self, p):
        key = (p.link_call, p.version)
        if p.sampler_uniforms is None or p.sampler_uniforms[0] != key:
            names, locations, by_name, by_location = set(), set(), {}, {}
            unit = np.zeros(1, np.int32)
            with self.whole_program(p, ALL_STAGES) as prog:
                for _, base, _, elements in self.active_samplers(prog) if prog is not None else ():
                    names.add(base)
                    names.update(f"{base}[{k}]" for k in range(len(elements)))
                    locations.update(elements)
                    for k, at in enumerate(elements):
                        if at >= 0:
                            self.gl.glGetUniformiv(prog, at, unit)
                            by_name[f"{base}[{k}]"] = by_location[at] = int(unit[0])
                            if k == 0:
                                by_name[base] = int(unit[0])
            p.sampler_uniforms = (key, frozenset(names), frozenset(locations) - {-1}, by_name, by_location)
        return p.sampler_uniforms[1:]

    def active_samplers(self, prog):
        """(index, name, texture target, location of each element) of linked
        program `prog`'s active samplers (an array's elements in order; a
        plain sampler's one location by its own name)."""
        GL = self.gl
        for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_UNIFORMS)):
            uname, size, utype = GL.glGetActiveUniform(prog, i)
            target = self.sampler_kinds.get(int(utype))
            if target is not None:
                base = name_str(uname).removesuffix("[0]")
                yield i, base, target, [GL.glGetUniformLocation(prog, f"{base}[{k}]" if size > 1 else base)
                                        for k in range(size)]

    def stage_samplers(self, prog):
        """{stage: ((unit, target), ...)} of linked program `prog`'s active
        samplers, each element of an array, by the stages that read them."""
        u, ip = ctypes.c_uint, ctypes.POINTER(ctypes.c_int)
        resource = self.mesa.proc("glGetProgramResourceiv", u, u, u, ctypes.c_int, ctypes.POINTER(u), ctypes.c_int,
                                  ip, ip)
        props = (u * len(REFERENCED_BY))(*REFERENCED_BY.values())
        referenced = (ctypes.c_int * len(REFERENCED_BY))()
        get_unit, unit = self.mesa.proc("glGetUniformiv", u, ctypes.c_int, ip), ctypes.c_int()
        out = {}
        for i, _, target, elements in self.active_samplers(prog):
            resource(prog, GL_UNIFORM, i, len(props), props, len(props), None, referenced)
            units = []
            for at in elements:
                if at >= 0:
                    get_unit(prog, at, ctypes.byref(unit))
                    units.append((unit.value, target))
            for stage, flag in zip(REFERENCED_BY, referenced):
                if flag:
                    out[stage] = out.get(stage, ()) + tuple(units)
        return out

    def linked_feedback_bindings(self, prog):
        """The binding points linked program `prog` records into, as Mesa
        linked its transform feedback: its last vertex-processing stage's
        xfb_ qualifiers, else the outputs glTransformFeedbackVaryings named
        (ignored when there are qualifiers), interleaved into binding 0 and
        one more after each gl_NextBuffer, or one each. OpenGL ES has no
        qualifiers nor gl_NextBuffer, nor the query of the buffers."""
        GL = self.gl
        n = GL.glGetProgramiv(prog, GL.GL_TRANSFORM_FEEDBACK_VARYINGS)
        if not n:
            return frozenset()
        if self.mesa.es:
            separate = GL.glGetProgramiv(prog, GL.GL_TRANSFORM_FEEDBACK_BUFFER_MODE) == GL.GL_SEPARATE_ATTRIBS
            return frozenset(range(n) if separate else (0,))
        u, ip = ctypes.c_uint, ctypes.POINTER(ctypes.c_int)
        count = ctypes.c_int()
        self.mesa.proc("glGetProgramInterfaceiv", u, u, u, ip)(
            prog, GL_TRANSFORM_FEEDBACK_BUFFER, GL_ACTIVE_RESOURCES, ctypes.byref(count))
        resource = self.mesa.proc("glGetProgramResourceiv", u, u, u, ctypes.c_int, ctypes.POINTER(u), ctypes.c_int,
                                  ip, ip)
        prop, binding = u(GL_BUFFER_BINDING), ctypes.c_int()
        out = set()
        for i in range(count.value):
            resource(prog, GL_TRANSFORM_FEEDBACK_BUFFER, i, 1, ctypes.byref(prop), 1, None, ctypes.byref(binding))
            out.add(binding.value)
        return frozenset(out)

    def build(self, no, pname, p):
        """The program as its last link saw it, vertex stage only (the
        fragment stage cannot move a vertex), with gl_Position fed back."""
        GL = self.gl
        sources, bindings = p.linked
        where = f"program {pname} (linked at call {p.link_call})"
        if "vertex" not in sources:
            fail_call(no, f"{where} has no vertex shader")
        # The stages before rasterization, which Mesa runs.
        stages = [s for s in ("vertex", "tess_control", "tess_evaluation", "geometry") if s in p.objects]
        for stage in stages:
            text, said = p.scanned[stage], stage.replace("_", " ")   # (as the compiler reads it: glsl_text)
            if CLIP_DISTANCES.search(text):
                # Mesa 22.3 clips by them even with GL_CLIP_DISTANCEi disabled.
                fail_call(no, f"{where}: its {said} shader writes clip or cull distances (gl_ClipDistance, "
                          "gl_CullDistance): not emulated")
            if VIEWPORT_OUTPUTS.search(text):
                fail_call(no, f"{where}: its {said} shader chooses the viewport (gl_ViewportIndex): not emulated")
        prog = GL.glCreateProgram()
        shaders = []
        for stage in stages:
            failed = attach_stage(GL, prog, getattr(GL, LINKED_STAGES[stage]), p.objects[stage], shaders)
            if failed is not None:
                log = GL.glGetShaderInfoLog(failed).decode("utf-8", "replace").strip().splitlines()
                fail_call(no, f"{where}: Mesa does not compile its {stage.replace('_', ' ')} shader: "
                          f"{printable((log or ['no log'])[0])}")
        if self.mesa.es:
            # OpenGL ES links only whole programs: a fragment shader of the
            # vertex shader's language version that reads nothing.
            fs = GL.glCreateShader(GL.GL_FRAGMENT_SHADER)
            GL.glShaderSource(fs, es_fragment_shader(sources["vertex"]))
            GL.glCompileShader(fs)
            GL.glAttachShader(prog, fs)
            GL.glDeleteShader(fs)
        for attr, index in bindings.items():
            GL.glBindAttribLocation(prog, index, attr)
        GL.glTransformFeedbackVaryings(prog, 1, varying_names(["gl_Position"]), GL.GL_INTERLEAVED_ATTRIBS)
        GL.glLinkProgram(prog)
        for sh in shaders:
            GL.glDeleteShader(sh)
        if not GL.glGetProgramiv(prog, GL.GL_LINK_STATUS):
            log = GL.glGetProgramInfoLog(prog).decode("utf-8", "replace").strip().splitlines()
            fail_call(no, f"{where}: Mesa does not link its vertex stage: {printable((log or ['no log'])[0])}")
        # xfb_buffer / xfb_offset qualifiers (GLSL 4.40) in the shader take
        # the place of the gl_Position asked for above.
        fed = [feedback_varying(GL, prog, i) for i in range(GL.glGetProgramiv(prog, GL.GL_TRANSFORM_FEEDBACK_VARYINGS))]
        if fed != ["gl_Position"]:
            GL.glDeleteProgram(prog)
            last = next(s for s in ("geometry", "tess_evaluation", "vertex") if s in stages)
            fail_call(no, f"{where}: its {last.replace('_', ' ')} shader declares its own transform feedback outputs "
                      "(xfb_ layout qualifiers): not emulated")
        mp = MesaProgram(prog, p.version)
        mp.amplifies = len(stages) > 1
        mp.tessellates = "tess_evaluation" in stages
        if "geometry" in stages:
            # A geometry shader that makes points or lines draws no area.
            out = GL.glGetProgramiv(prog, GL.GL_GEOMETRY_OUTPUT_TYPE)
            mp.output_kind = "GL_TRIANGLES" if out == GL.GL_TRIANGLE_STRIP else \
                "GL_LINES" if out == GL.GL_LINE_STRIP else "GL_POINTS"
        elif "tess_evaluation" in stages:
            # Nor does tessellation into isolines or points.
            mp.output_kind = "GL_POINTS" if GL.glGetProgramiv(prog, GL.GL_TESS_GEN_POINT_MODE) else \
                "GL_LINES" if GL.glGetProgramiv(prog, GL.GL_TESS_GEN_MODE) == GL.GL_ISOLINES else "GL_TRIANGLES"
        mp.area = mp.output_kind in (None, "GL_TRIANGLES")
        for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_ATTRIBUTES)):
            aname = name_str(GL.glGetActiveAttrib(prog, i)[0])
            mp.reads_draw_id |= aname in DRAW_ID_INPUTS
            mp.reads_vertex |= aname == "gl_Vertex"
            if aname.startswith("gl_") and aname not in BUILTIN_INPUTS | {"gl_Vertex"}:
                fail_call(no, f"{where}: its vertex shader reads {printable(aname)}, a fixed-function vertex "
                          "array of the compatibility profile: not emulated")
        for i in range(GL.glGetProgramiv(prog, GL.GL_ACTIVE_UNIFORMS)):
            uname, size, utype = GL.glGetActiveUniform(prog, i)
            uname = name_str(uname)
            if uname in FIXED_MATRICES:
                mp.fixed_matrices = True
                continue
            if uname.startswith("gl_"):
                fail_call(no, f"{where}: its vertex shader reads {printable(uname)}, fixed-function state of "
                          "the compatibility profile: not emulated")
            if int(utype) in self.texture_samplers:
                fail_call(no, f"{where}: its vertex shader reads {printable(uname)} "
                          f"({self.texture_samplers[int(utype)]}), a kind of texture not emulated")
            base = uname[:-3] if uname.endswith("[0]") else uname
            loc = GL.glGetUniformLocation(prog, uname)
            mp.locations[uname] = loc
            mp.locations[base] = loc
            for k in range(1, size):
                mp.locations[f"{base}[{k}]"] = GL.glGetUniformLocation(prog, f"{base}[{k}]")
            elements = [loc] + [mp.locations[f"{base}[{k}]"] for k in range(1, size)]   # (an array's each)
            mp.uniform_of.update((at, i) for at in elements if at >= 0)
            if int(utype) in self.sampler_targets:
                mp.texture_locations += [(at, self.sampler_targets[int(utype)]) for at in elements]
            elif int(utype) in self.buffer_sampler_types:
                mp.buffer_samplers += elements
            elif int(utype) in self.image_targets:
                mp.image_locations += elements
        return mp

    def mesa_location(self, mp, p, loc):
        """The location in Mesa's program of the capture's location `loc`
        of program p (-1: not read by the vertex stage): that of the name
        the capture asked it of, or else of the name at `loc` in Mesa's
        link of the whole program, which numbers the uniforms as the
        capture's did (a location asked of a twin program or before a
        relink of the same sources, read by glGetProgramResourceiv, or
        given in the shader: round 32's R32-1). The vertex stage linked
        alone numbers them otherwise: it drops those only later stages
        read."""
        name = p.uniform_names.get(loc)
        key = (loc, name)
        if key not in mp.mapped:
            if name is None:
                names = self.full_link(p)[3]
                name = names.get(loc) if names else next((n for n, at in mp.locations.items() if at == loc), None)
            mp.mapped[key] = -1 if name is None else mp.locations.get(name, mp.locations.get(name.removesuffix("[0]"), -1))
        return mp.mapped[key]

    def set_uniform(self, mloc, value):
        GL = self.gl
        func, values, transpose, kind, count = value
        fn = getattr(GL, func)
        if count is None:
            fn(mloc, *values)
            return
        arr = np.array(values, dtype=UNIFORM_DTYPES[kind])
        if "Matrix" in func:
            fn(mloc, count, GL.GL_TRUE if transpose else GL.GL_FALSE, arr)
        else:
            fn(mloc, count, arr)

    # ---- state a draw reads
    def vertex_array(self, conv, no, client_indices, mp):
        GL = self.gl
        vao = conv.current_vao()
        mv = self.vaos.get(conv.s.vao)
        if mv is None:
            mv = self.vaos[conv.s.vao] = int(GL.glGenVertexArrays(1))
        GL.glBindVertexArray(mv)
        # Each attribute on a binding point of its own, at its binding's
        # offset plus its relative offset: what it reads whichever points
        # the capture's attributes shared.
        for i, at, b in vao.sources():
            if not at.enabled:
                GL.glDisableVertexAttribArray(i)
                continue
            if b.buffer:
                conv.checked_buffer(no, self.name, b.buffer, f"attribute {i}")
                buf, offset = self.buffer(conv, b.buffer), b.offset + at.relative
            elif b.client is not None:
                buf, offset = self.client(b.client), at.relative
            else:
                fail_call(no, f"attribute {i} is enabled with no buffer and no data in the capture")
            size = self.mesa.enum(at.size) if isinstance(at.size, str) else at.size
            kind = self.mesa.enum(at.type)
            if at.type == "GL_FIXED" and self.mesa.es and b.stride:
                # OpenGL ES takes GL_FIXED in glVertexAttribPointer, not in
                # glVertexAttribFormat (GL_INVALID_ENUM: round 16's R16-3,
                # every draw of such an attribute a GL error): the pointer
                # on binding point i, as the format's path would set it.
                GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buf)
                self.mesa.proc("glVertexAttribPointer", ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_ubyte,
                               ctypes.c_int, ctypes.c_void_p)(i, size, kind, 1 if at.normalized else 0, b.stride,
                                                              offset)
                self.mesa.binding_divisor(i, b.divisor)
                GL.glEnableVertexAttribArray(i)
                continue
            if at.long:
                self.mesa.attrib_l_format(i, size, kind, 0)
            elif at.integer:
                self.mesa.attrib_i_format(i, size, kind, 0)
            else:
                self.mesa.attrib_format(i, size, kind, 1 if at.normalized else 0, 0)
            self.mesa.attrib_binding(i, i)
            self.mesa.bind_vertex_buffer(i, buf, offset, b.stride)
            self.mesa.binding_divisor(i, b.divisor)
            GL.glEnableVertexAttribArray(i)
        if 0 not in vao.attribs:
            GL.glDisableVertexAttribArray(0)   # (the fixed-function array an earlier draw gave there)
        if mp.reads_vertex and not (0 in vao.attribs and vao.attribs[0].enabled):
            self.fixed_vertex_array(conv, no)
        # An arrays draw reads no indices: the element array buffer is
        # neither checked nor copied (it may hold no data, or the GPU's).
        elem = conv.s.bound.get("GL_ELEMENT_ARRAY_BUFFER", 0) if "Elements" in self.name else 0
        if client_indices is not None:
            GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self.client(client_indices))
        else:
            if elem:
                conv.checked_buffer(no, self.name, elem, "indices")
            GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, self.buffer(conv, elem) if elem else 0)
        for i, (func, vals) in conv.s.attrib_values.items():
            fn = getattr(GL, func.removesuffix("ARB"))
            if func.startswith("glVertexAttribP"):   # packed: (type, normalized, value)
                kind, normalized, value = vals
                getattr(GL, func.removesuffix("v"))(i, self.mesa.enum(kind), 1 if normalized else 0, value)
            elif func.endswith("v"):
                fn(i, np.array(vals[0] if len(vals) == 1 and isinstance(vals[0], list) else vals,
                               dtype=ATTRIB_VALUE_TYPES[re.search(r"(ub|us|ui|b|s|i|f|d)v$", func).group(1)]))
            else:
                fn(i, *vals)

    def fixed_vertex_array(self, conv, no):
        """gl_Vertex from the fixed-function vertex array (glVertexPointer),
        given to Mesa as generic attribute 0, which a compatibility
        profile's gl_Vertex reads when it is enabled (GL 2.1, 2.7: generic
        attribute 0 and the vertex position are one), as it would have read
        the capture's generic attribute 0 had that been enabled."""
        GL = self.gl
        if not conv.s.vertex_array_enabled:
            fail_call(no, f"{self.name}: its vertex shader reads gl_Vertex, with neither generic attribute 0 nor "
                      "the vertex array (GL_VERTEX_ARRAY) enabled: not emulated")
        arr = conv.s.vertex_array
        if arr.buffer:
            conv.checked_buffer(no, self.name, arr.buffer, "the vertex array")
            buf, offset = self.buffer(conv, arr.buffer), arr.offset
        elif arr.data is not None:
            buf, offset = self.client(arr.data), 0
        else:
            fail_call(no, f"{self.name}: the vertex array (gl_Vertex) has no buffer and no data in the capture")
        self.mesa.attrib_format(0, arr.size, self.mesa.enum(arr.type), 0, 0)
        self.mesa.attrib_binding(0, 0)
        self.mesa.bind_vertex_buffer(0, buf, offset, arr.stride or element_bytes(arr.size, arr.type))
        self.mesa.binding_divisor(0, 0)
        GL.glEnableVertexAttribArray(0)

    def patch_state(self, conv):
        """The capture's patch size and default tessellation levels (which
        apply with no control shader) in Mesa's context."""
        GL = self.gl
        self.mesa.proc("glPatchParameteri", ctypes.c_uint, ctypes.c_int)(GL.GL_PATCH_VERTICES,
                                                                        conv.s.patch_vertices)
        if not self.mesa.es:   # (OpenGL ES has no default levels)
            for pname, n in (("GL_PATCH_DEFAULT_OUTER_LEVEL", 4), ("GL_PATCH_DEFAULT_INNER_LEVEL", 2)):
                GL.glPatchParameterfv(getattr(GL, pname), np.array(conv.s.patch_levels.get(pname, (1.0,) * n),
                                                                  np.float32))

    def load_fixed_matrices(self, conv):
        """The capture's model-view and projection matrices (the tops of its
        stacks) in Mesa's context, for a program that reads them: Mesa
        derives the products, inverses and the normal matrix from them."""
        GL = self.gl
        for mode in ("GL_PROJECTION", "GL_MODELVIEW"):
            GL.glMatrixMode(getattr(GL, mode))
            GL.glLoadMatrixd(np.ascontiguousarray(conv.s.stacks[mode][-1].T, dtype=np.float64))

    def blocks_read(self, mp):
        """{(target, binding)} of the uniform and shader storage blocks
        Mesa's program of the draw reads, as bound now."""
        GL = self.gl
        out, binding = set(), np.zeros(1, np.int32)
        for i in range(GL.glGetProgramiv(mp.name, GL.GL_ACTIVE_UNIFORM_BLOCKS)):
            GL.glGetActiveUniformBlockiv(mp.name, i, GL.GL_UNIFORM_BLOCK_BINDING, binding)
            out.add(("GL_UNIFORM_BUFFER", int(binding[0])))
        # Mesa's entry points called directly (PyOpenGL's wrappers of these
        # cannot read an OpenGL ES context's version).
        u, p = ctypes.c_uint, ctypes.c_void_p
        n, prop = np.zeros(1, np.int32), np.array([GL.GL_BUFFER_BINDING], np.uint32)
        self.mesa.proc("glGetProgramInterfaceiv", u, u, u, p)(mp.name, GL.GL_SHADER_STORAGE_BLOCK,
                                                             GL.GL_ACTIVE_RESOURCES, n.ctypes.data)
        resource = self.mesa.proc("glGetProgramResourceiv", u, u, u, ctypes.c_int, p, ctypes.c_int, p, p)
        for i in range(int(n[0])):
            resource(mp.name, GL.GL_SHADER_STORAGE_BLOCK, i, 1, prop.ctypes.data, 1, None, binding.ctypes.data)
            out.add(("GL_SHADER_STORAGE_BUFFER", int(binding[0])))
        # Buffer textures its samplers and images read, by their unit.
        unit = np.zeros(1, np.int32)
        for loc in mp.buffer_samplers:
            GL.glGetUniformiv(mp.name, loc, unit)
            out.add(("GL_TEXTURE_BUFFER", int(unit[0])))
        for loc in mp.image_locations:
            GL.glGetUniformiv(mp.name, loc, unit)
            out.add(("image", int(unit[0])))
        return out

    def bindings(self, conv, mp):
        from OpenGL.error import GLError
        GL = self.gl
        # Blocks reading a buffer the GPU wrote are refused (checked_buffer);
        # the binding points no block reads are not checked.
        read = self.blocks_read(mp) if conv.s.gpu_buffers else set()
        for (target, index), (buf, offset, size) in conv.s.indexed.items():
            if target not in ("GL_UNIFORM_BUFFER", "GL_SHADER_STORAGE_BUFFER"):
                continue
            if (target, index) in read:
                conv.checked_buffer(self.no, self.name, buf, f"its {target} binding {index}")
            if buf in conv.s.buffers and size is not None and not 0 <= offset <= len(conv.s.buffers[buf]):
                # Mesa binds a range that starts outside its buffer and
                # takes the lesser of its size and the buffer's size less
                # the offset (unsigned, wrapped): it reads memory outside
                # the buffer, which GL does not define.
                fail_call(self.no, f"{target} binding {index} starts at {offset}, outside buffer {buf} "
                          f"({len(conv.s.buffers[buf])} bytes): what Mesa reads there is not defined")
            # 0: unbound since an earlier draw bound it here, or a buffer
            # with no data store yet, which a shader reads as zeros as it
            # reads an unbound block (and a program of no blocks not at all).
            mb = self.buffer(conv, buf) if buf in conv.s.buffers else 0
            try:
                if size is None or not buf:
                    GL.glBindBufferBase(self.mesa.enum(target), index, mb)
                else:
                    GL.glBindBufferRange(self.mesa.enum(target), index, mb, offset, size)
            except GLError:
                pass   # past Mesa's binding points, or a range it refuses: GL ignores the capture's call
        for kind, unit in read:
            tex = (conv.s.units.get((unit, "GL_TEXTURE_BUFFER")) or DEFAULT_BUFFER_TEXTURE) \
                if kind == "GL_TEXTURE_BUFFER" else conv.s.image_units.get(unit, (None,))[0] if kind == "image" \
                else None
            if tex in conv.s.texture_buffers:
                conv.checked_buffer(self.no, self.name, conv.s.texture_buffers[tex][1],
                                    f"the buffer texture at its {'image ' if kind == 'image' else ''}unit {unit}")
        # Every unit the draw reads a buffer texture at, and every one an
        # earlier draw may have bound in Mesa's copy: the capture's texture,
        # or the default one (its buffer set by glTexBuffer, or none).
        units = {unit: tex for (unit, target), tex in conv.s.units.items() if target == "GL_TEXTURE_BUFFER"}
        units.update({unit: 0 for kind, unit in read if kind == "GL_TEXTURE_BUFFER" and unit not in units})
        for unit, tex in units.items():
            if not tex and DEFAULT_BUFFER_TEXTURE in conv.s.texture_buffers:
                tex = DEFAULT_BUFFER_TEXTURE
            if not tex:
                # Unbound (or its texture deleted) since an earlier draw
                # bound it in Mesa's copy: texture 0, read as zeros.
                GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
                GL.glBindTexture(GL.GL_TEXTURE_BUFFER, 0)
                continue
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            self.texture_buffer(conv, tex)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        if not self.mesa.es:
            (GL.glEnable if conv.s.restart else GL.glDisable)(GL.GL_PRIMITIVE_RESTART)
            GL.glPrimitiveRestartIndex(conv.s.restart_index)
        (GL.glEnable if conv.s.restart_fixed else GL.glDisable)(GL.GL_PRIMITIVE_RESTART_FIXED_INDEX)

    def texture_buffer(self, conv, tex):
        """Mesa's copy of capture buffer texture `tex`, bound at the active
        unit, its buffer up to date."""
        GL = self.gl
        mt = self.textures.get(tex)
        if mt is None:
            mt = self.textures[tex] = int(GL.glGenTextures(1))
        GL.glBindTexture(GL.GL_TEXTURE_BUFFER, mt)
        if tex not in conv.s.texture_buffers:
            return mt   # bound with no buffer yet (GL leaves its reads undefined): Mesa's as the capture's
        fmt, buf, offset, size = conv.s.texture_buffers[tex]
        # A buffer of no data store yet (or 0, none) is read as none.
        mb = self.buffer(conv, buf) if buf in conv.s.buffers else 0
        if size is None or not mb:
            GL.glTexBuffer(GL.GL_TEXTURE_BUFFER, self.mesa.enum(fmt), mb)
        else:
            # (called directly: PyOpenGL's wrapper cannot read an ES context's version)
            self.mesa.proc("glTexBufferRange", ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_ssize_t,
                           ctypes.c_ssize_t)(GL.GL_TEXTURE_BUFFER, self.mesa.enum(fmt), mb, offset, size)
        return mt

    # ---- the draw
    def run(self, conv, no, name, d, instances, prims, pname, p):
        """The clip-space positions of one draw call (`name` without its
        extension suffix, `d` its arguments, room for `prims` triangles) run
        by program `pname`'s vertex stage (`p` its executable):
        (vertices, 4) float64, three a triangle, one array per instance.
        A command of an indirect multi-draw run in batches (conv.batched,
        glstate.draws.IndirectBatch) takes its own from there."""
        if conv.batched is not None:
            got = conv.batched.get(conv.multi_draw_index)
            if isinstance(got, DrawRejected):
                raise got
            if got is not None:
                return got
        indices = d.get("indices")
        client_indices = indices if isinstance(indices, (bytes, bytearray)) else None

        def checks(mp):
            if mp.reads_draw_id and conv.multi_draw_index:
                # Each draw of a multi-draw runs in Mesa alone, where
                # gl_DrawID is 0.
                fail_call(no, f"{printable(conv.multi_draw_name)}: its draw {conv.multi_draw_index}, whose vertex "
                          "shader reads gl_DrawID: not emulated")
            check_vertex_data(conv, no, name, d, instances, client_indices, mp.reads_vertex)
        clip = self.positions(conv, no, name, checks, client_indices,
                              lambda: self.issue(name, d, client_indices is not None), prims, pname, p)
        # Every instance has the same primitives (primitive restart cuts them
        # alike), written instance after instance.
        per = len(clip) // max(instances, 1)
        return [clip[i * per:(i + 1) * per].astype(np.float64) for i in range(instances)]

    def run_indirect(self, conv, no, name, mode, index_type, commands, stride, n, draws, prims, whole, pname, p):
        """An indirect multi-draw run whole in Mesa, as the capture called it
        (`commands`: its `n` commands' bytes from the first, `stride` apart;
        `draws`: the name and arguments of each that draws, as the
        converter reads them): one Mesa call instead of one a command, each command's
        gl_DrawID its own. The clip-space positions of all, command after
        command and in each instance after instance, (vertices, 4)
        float32; room for `prims` triangles. None, nothing run, when the
        vertex shader reads gl_DrawID and the commands are not the whole
        multi-draw's (`whole`): they would be numbered from 0."""
        def checks(mp):
            if mp.reads_draw_id and not whole:
                raise RunAlone()
            for single, d in draws:
                check_vertex_data(conv, no, single, d, d["instancecount"], None, mp.reads_vertex)

        def issue():
            GL = self.gl
            if self.indirect is None:
                self.indirect = int(GL.glGenBuffers(1))
            GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, self.indirect)
            GL.glBufferData(GL.GL_DRAW_INDIRECT_BUFFER, len(commands), bytes(commands), GL.GL_STREAM_DRAW)
            u, i, v = ctypes.c_uint, ctypes.c_int, ctypes.c_void_p
            if index_type is None:
                self.mesa.proc("glMultiDrawArraysIndirect", u, v, i, i)(
                    self.mesa.enum(mode), None, n, stride)
            else:
                self.mesa.proc("glMultiDrawElementsIndirect", u, u, v, i, i)(
                    self.mesa.enum(mode), self.mesa.enum(index_type), None, n, stride)
            err = GL.glGetError()   # (before a PyOpenGL call would raise it as its own)
            GL.glBindBuffer(GL.GL_DRAW_INDIRECT_BUFFER, 0)
            if err == GL_OUT_OF_MEMORY:
                raise MemoryError(f"GL_OUT_OF_MEMORY in {name}")
            if err:
                raise DrawRejected(f"{GL_ERRORS.get(int(err), f'GL error {int(err)}')} in {name}")
        try:
            return self.positions(conv, no, name, checks, None, issue, prims, pname, p)
        except RunAlone:
            return None

    def output_kind(self, no, name, pname, p):
        """MesaProgram.output_kind of program `pname` (`p` its executable),
        linked in Mesa if it is not yet."""
        with self.watchdog.on(f"call {no}: {name}"):
            return self.program(no, pname, p).output_kind

    def positions(self, conv, no, name, checks, client_indices, issue, prims, pname, p):
        """What run and run_indirect share: the program, checks(mp) of what
        the draw reads, the vertex array, bindings and textures, then
        issue() under transform feedback: (vertices, 4) float32."""
        from OpenGL.error import GLError
        GL = self.gl
        self.no, self.name = no, name
        try:
            with self.watchdog.on(f"call {no}: {name}"):
                mp = self.program(no, pname, p)
                if not mp.area:
                    return np.zeros((0, 4), np.float32)
                if (mp.fixed_matrices or mp.reads_vertex) and conv.core:
                    fail_call(no, f"{name}: its vertex shader reads the compatibility profile's gl_Vertex or "
                              "matrices in a core-profile context, whose driver does not compile it: not emulated")
                checks(mp)
                self.vertex_array(conv, no, client_indices, mp)
                if mp.fixed_matrices:
                    self.load_fixed_matrices(conv)
                if mp.tessellates:
                    self.patch_state(conv)
                self.bindings(conv, mp)
                self.vertex_textures.bind(conv, no, name, mp, self.texture_buffer)
                with self.watchdog.on(f"call {no}: {name}", grows=True):
                    if not mp.amplifies:
                        return self.mesa.feedback_positions(issue, prims)
                    # Tessellation and geometry shaders make as many
                    # primitives as they make: Mesa's count of them sizes a
                    # second run, within a draw record's vertices (3 a
                    # triangle: such a draw is one instance).
                    from .glstate.draws import MAX_DRAW_PRIMITIVES, MAX_RECORD_VERTICES
                    made = self.mesa.feedback_positions(issue, prims, fits=False)
                    if isinstance(made, int):
                        limit = min(MAX_DRAW_PRIMITIVES, MAX_RECORD_VERTICES // 3)
                        if made > limit:
                            fail_call(no, f"{name}: its tessellation or geometry shaders make {made} triangles, "
                                      f"more than {limit} (a draw record's {MAX_RECORD_VERTICES} vertices; "
                                      "docs/gl-capture.md)")
                        # What they make is the frame's work too, before
                        # the run that feeds it back.
                        conv.frame_work(no, name, 3 * made, amplified=True)
                        return self.mesa.feedback_positions(issue, made)
                    conv.frame_work(no, name, len(made), amplified=True)   # (room enough from an earlier draw)
                    return made
        except GLError as e:
            op = getattr(getattr(e, "baseOperation", None), "__name__", "a call")
            if getattr(e, "err", None) == GL_OUT_OF_MEMORY:
                # Mesa's copy could not be given the capture's data: the
                # converter's memory, not the capture's error.
                raise MemoryError(f"GL_OUT_OF_MEMORY in {op}")
            code = GL_ERRORS.get(getattr(e, "err", None), f"GL error {getattr(e, 'err', '?')}")
            raise DrawRejected(f"{code} in {op}")
        finally:
            self.free_scratch()
            GL.glBindVertexArray(0)

    def issue(self, name, d, client_indices):
        GL = self.gl
        mode = self.mesa.enum(d["mode"])
        if "Elements" in name:
            kind = self.mesa.enum(d.get("type"))
            offset = 0 if client_indices else d.get("indices") or 0
            args = [mode, d["count"], kind, ctypes.c_void_p(offset)]
            if "Range" in name:
                args = [mode, d["start"], d["end"]] + args[1:]
        else:
            args = [mode, d.get("first", 0), d["count"]]
        if "Instanced" in name:
            args.append(d.get("instancecount", d.get("primcount", 1)))
        if "BaseVertex" in name:
            args.append(d.get("basevertex", 0))
        if "BaseInstance" in name:
            args.append(d.get("baseinstance", 0))
        if self.mesa.es and "BaseInstance" in name:
            # EXT_base_instance's entry point, called directly: PyOpenGL's
            # wrapper of the desktop one cannot read an ES context's version.
            u, i, p = ctypes.c_uint, ctypes.c_int, ctypes.c_void_p
            types = [u, i, u, p] + [i] * (len(args) - 5) + [u] if "Elements" in name else [u, i, i, i, u]
            self.mesa.proc(name + "EXT", *types)(*args)
            err = GL.glGetError()
            if err == GL_OUT_OF_MEMORY:
                raise MemoryError(f"GL_OUT_OF_MEMORY in {name}EXT")
            if err:
                raise DrawRejected(f"{GL_ERRORS.get(int(err), f'GL error {int(err)}')} in {name}EXT")
            return
        getattr(GL, name)(*args)
