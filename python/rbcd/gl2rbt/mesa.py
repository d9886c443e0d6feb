"""Mesa, headless, as the converter's vertex stage (docs/gl-capture.md, "The
shader path"): an EGL context on Mesa's surfaceless platform (no X server),
desktop OpenGL 4.5 compatibility for GL captures (every GLSL version, the
default vertex array object and client arrays, as the capture's context had)
or OpenGL ES 3.2 for ES captures, through PyOpenGL (Debian python3-opengl).

The capture's vertex-stage calls are replayed into this context (glstate's
shader and buffer groups translate object names and uniform locations) and
each draw the trace needs runs once with transform feedback of gl_Position
and the rasterizer discarded: Mesa runs the capture's own shaders on the
captured buffers, uniforms and textures, and hands back each primitive's
clip-space positions, assembled as GL assembles them (strips, fans,
primitive restart, base vertex, instances in order)."""
import contextlib
import ctypes
import glob
import os
import re
import resource
import select
import signal
import threading
import time

from ..cli import remove_temporaries, say
from .errors import LAST_WORD, ToolError, printable

# PyOpenGL picks its platform when first imported: EGL, for a context that
# needs no display.
os.environ["PYOPENGL_PLATFORM"] = "egl"

EGL_PLATFORM_SURFACELESS_MESA = 0x31DD
# OpenGL ES enumerants PyOpenGL's desktop module lacks (their values differ
# from the desktop ones of the same meaning).
ES_ENUMS = {"GL_HALF_FLOAT_OES": 0x8D61}


# The stack Mesa's GLSL compiler may use: it recurses once a term of an
# expression (a sum of 20,000 terms overflowed the default 8 MiB and killed
# the converter with SIGSEGV). scripts/rbcd-gl2rbt runs itself again with 2
# GiB; a converter imported otherwise raises the soft limit here, and the
# main thread's stack grows up to it into the gap of at least 128 MiB Linux
# keeps below it (sums of 200,000 terms compile there).
MESA_STACK_BYTES = 120 << 20


def raise_stack_limit():
    soft, hard = resource.getrlimit(resource.RLIMIT_STACK)
    if soft != resource.RLIM_INFINITY and soft < MESA_STACK_BYTES:
        want = MESA_STACK_BYTES if hard == resource.RLIM_INFINITY else min(MESA_STACK_BYTES, hard)
        if want > soft:
            resource.setrlimit(resource.RLIMIT_STACK, (want, hard))


_EXTENSION_ENUMS = None
EXTENSION_ENUM = re.compile(r"^(GL_\w+)=_C\('\1',(0x[0-9A-Fa-f]+|\d+)\)", re.M)


def extension_enums():
    """The enumerants of every GL and GL ES extension PyOpenGL knows (its
    registry-made modules), by name: the EXT, KHR and vendor names its core
    namespace lacks (GL_COMPRESSED_RGB_S3TC_DXT1_EXT, GL_TEXTURE_MAX_ANISOTROPY_EXT),
    read from its files once, on the first name the core namespace lacks."""
    global _EXTENSION_ENUMS
    if _EXTENSION_ENUMS is None:
        import OpenGL
        _EXTENSION_ENUMS = {}
        root = os.path.join(os.path.dirname(OpenGL.__file__), "raw")
        for api in ("GL", "GLES2", "GLES3", "GLES1"):
            for path in glob.glob(os.path.join(root, api, "*", "*.py")):
                try:
                    with open(path, encoding="utf-8") as f:
                        text = f.read()
                except OSError:
                    continue
                for m in EXTENSION_ENUM.finditer(text):
                    _EXTENSION_ENUMS.setdefault(m.group(1), int(m.group(2), 0))
    return _EXTENSION_ENUMS


def _load():
    raise_stack_limit()
    # Mesa's EGL says why it failed on stderr beside the converter's one
    # line (a driver it cannot load, out of memory): the line says it.
    os.environ.setdefault("EGL_LOG_LEVEL", "fatal")
    try:
        from OpenGL import EGL, GL
        return EGL, GL
    except ImportError as e:
        raise ToolError(f"the shader path needs PyOpenGL and Mesa's EGL (scripts/setup.sh --gl installs "
                        f"python3-opengl and libegl1): {e}")


# Mesa's work for one draw or one link (compiling and linking the vertex
# stage, LLVM's code for it, the draw) is bounded by Mesa in neither time
# nor memory (a vertex shader with a local float[1000000]: minutes in LLVM
# at 1.9 GB), and a signal's handler waits until Mesa returns: a watchdog
# thread bounds both. The memory Mesa takes for a draw, buffers apart
# (uploaded before it), is the JIT's and the fed-back positions' (48 bytes
# a triangle, 2^22 triangles at most: 192 MiB). The time is the processor
# time the process spent meanwhile (every thread: Mesa's own and llvmpipe's),
# which a busy machine does not stretch (a 3 s draw had been refused at 30 s
# of wall-clock time beside other work, load 4 on 2 processors); the wall
# clock bounds work that waits rather than computes, at ten times that.
MESA_SECONDS = 30
MESA_WALL_SECONDS = 300
MESA_GROWTH = 1 << 30


def over_time(wall0, cpu0, wall, cpu, cpu_bound, wall_bound):
    """Why a piece of Mesa's work that started at (wall0, cpu0) and is at
    (wall, cpu) is out of bounds, or None."""
    if cpu - cpu0 > cpu_bound:
        return f"Mesa worked on it for more than {cpu_bound} s of processor time"
    if wall - wall0 > wall_bound:
        return f"Mesa took more than {wall_bound} s on it"
    return None


def resident_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


class Watchdog:
    """One thread for the run: while the main thread is in Mesa's work
    (`with watchdog.on(what, grows=...)`: a draw, a link), it checks every
    0.1 s the time that work took (processor and wall-clock) and, for
    `grows`, the resident memory it added. Past MESA_SECONDS,
    MESA_WALL_SECONDS or MESA_GROWTH it says so in one line naming
    the capture and `what`, removes the run's temporaries and outputs,
    closes the rasterizer's input (which then removes what it was writing)
    and ends the process, exit status 2: the capture asks for work out of
    proportion. (PyOpenGL's calls leave Python's lock while Mesa works.)"""

    def __init__(self, conv):
        self.conv = conv   # the converter: the capture's path, and its rasterizer once started
        self.work = None   # (what, work clocks at the start, resident bytes then or None)
        self.lock = threading.Lock()
        self.set_aside = [0.0, 0.0]   # the wall-clock and processor time spent aside in the run
        # A signal's number is written here by Python's own handler at once:
        # SIGINT, SIGTERM or SIGHUP while Mesa works ends the run from this
        # thread (the main thread's handler would wait until Mesa returns).
        self.signals, w = os.pipe()
        os.set_blocking(w, False)
        try:
            signal.set_wakeup_fd(w, warn_on_full_buffer=False)
        except ValueError:
            pass   # not the main thread (a library's use): signals wait for Mesa
        threading.Thread(target=self.watch, daemon=True).start()

    def on(self, what, grows=False):
        return _Work(self, what, grows)

    def clocks(self):
        """The wall-clock and processor time of Mesa's work: the process's,
        less what was spent aside."""
        return time.monotonic() - self.set_aside[0], time.process_time() - self.set_aside[1]

    @contextlib.contextmanager
    def aside(self):
        """A wait within Mesa's work that is not Mesa's work (Mesa's replay
        reaching a call to read textures back, bounded by --check-timeout):
        not counted, signals taken by the main thread's handler."""
        with self.lock:
            work, self.work = self.work, None
        t, c = time.monotonic(), time.process_time()
        try:
            yield
        finally:
            with self.lock:
                self.set_aside[0] += time.monotonic() - t
                self.set_aside[1] += time.process_time() - c
                self.work = work

    def watch(self):
        while True:
            ready = select.select([self.signals], [], [], 0.1)[0]
            got = os.read(self.signals, 64) if ready else b""
            with self.lock:
                work = self.work
            if work is None:
                continue
            if any(n in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP) for n in got):
                self.end(f"{printable(self.conv.args.trace)}: interrupted", 130)
            what, t0, cpu0, rss0 = work
            why = over_time(t0, cpu0, *self.clocks(), MESA_SECONDS, MESA_WALL_SECONDS)
            if why:
                self.expire(what, why)
            if rss0 is not None and resident_bytes() - rss0 > MESA_GROWTH:
                self.expire(what, f"Mesa took more than {MESA_GROWTH >> 20} MiB of memory for it")

    def expire(self, what, why):
        self.end(f"{printable(self.conv.args.trace)}: {what}: {why} (docs/gl-capture.md, limits)", 2)

    def end(self, message, status):
        if not LAST_WORD.acquire(blocking=False):
            return   # the main thread is saying how the run ended (a signal it took first)
        say("rbcd-gl2rbt", message)
        remove_temporaries()
        proc = getattr(self.conv, "raster_proc", None)
        if proc is not None:
            try:
                proc.stdin.close()
                proc.wait(10)
            except Exception:   # noqa: BLE001: a closed pipe, or TimeoutExpired: ending all the same
                proc.kill()
        os._exit(status)


class _Work:
    def __init__(self, dog, what, grows):
        self.dog, self.what, self.grows = dog, what, grows

    def __enter__(self):
        with self.dog.lock:
            self.outer = self.dog.work
            start = self.dog.clocks() if self.outer is None else self.outer[1:3]
            self.dog.work = (self.what, *start, resident_bytes() if self.grows else None)

    def __exit__(self, *exc):
        with self.dog.lock:
            self.dog.work = self.outer


# The address space Mesa's llvmpipe needs to start and compile a first
# shader (Mesa 22.3, measured: below about 320 MB it fails at its first
# compile with SIGSEGV or "double free", past anything the converter can
# say; each llvmpipe thread adds its stack and malloc arena).
MESA_MIN_ADDRESS_SPACE = 512 << 20


def check_address_space():
    """An address-space limit (ulimit -v) too small for Mesa to start is
    said before Mesa runs: one line, out of memory, exit 1 (round 15's
    R15-7: a crash, and the run's temporary folder left)."""
    soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    if soft != resource.RLIM_INFINITY and soft < MESA_MIN_ADDRESS_SPACE:
        raise MemoryError(f"the address-space limit of {soft >> 20} MiB is below the "
                          f"{MESA_MIN_ADDRESS_SPACE >> 20} MiB Mesa's llvmpipe needs to start")


class Mesa:
    """One headless context; `gl` is PyOpenGL's GL module, current on it."""

    def __init__(self, es=False):
        check_address_space()
        EGL, GL = _load()
        self.gl, self.egl, self.es = GL, EGL, es
        self.procs = {}   # (name, argument types) -> the entry point (proc)
        try:
            dpy = EGL.eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL.EGL_DEFAULT_DISPLAY, None)
            major, minor = EGL.EGLint(), EGL.EGLint()
            if not dpy or not EGL.eglInitialize(dpy, ctypes.pointer(major), ctypes.pointer(minor)):
                raise ToolError("Mesa's surfaceless EGL platform is not available (libegl-mesa0)")
            if es:
                EGL.eglBindAPI(EGL.EGL_OPENGL_ES_API)
                attrs = [EGL.EGL_CONTEXT_MAJOR_VERSION, 3, EGL.EGL_CONTEXT_MINOR_VERSION, 2, EGL.EGL_NONE]
            else:
                EGL.eglBindAPI(EGL.EGL_OPENGL_API)
                attrs = [EGL.EGL_CONTEXT_MAJOR_VERSION, 4, EGL.EGL_CONTEXT_MINOR_VERSION, 5,
                         EGL.EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL.EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT,
                         EGL.EGL_NONE]
            ctx = EGL.eglCreateContext(dpy, None, EGL.EGL_NO_CONTEXT, (EGL.EGLint * len(attrs))(*attrs))
            if not ctx or not EGL.eglMakeCurrent(dpy, EGL.EGL_NO_SURFACE, EGL.EGL_NO_SURFACE, ctx):
                raise ToolError("Mesa gives no " + ("OpenGL ES 3.2" if es else "OpenGL 4.5 compatibility")
                                + " context on the surfaceless platform")
        except EGL.EGLError as e:
            # (the error's name alone: PyOpenGL's text of it runs over lines)
            err = getattr(e, "err", None)
            raise ToolError(f"Mesa's EGL could not start: {getattr(err, 'name', None) or type(e).__name__} (out "
                            "of memory, or no llvmpipe: scripts/setup.sh --gl)")
        except (AttributeError, TypeError) as e:
            raise ToolError(f"Mesa's EGL: {printable(e, 200)}")
        self.version = GL.glGetString(GL.GL_VERSION).decode("ascii", "replace")
        # The draws run into a framebuffer of our own (a surfaceless context
        # has no default one), with the rasterizer discarded all the same.
        self.fbo = GL.glGenFramebuffers(1)
        rb = GL.glGenRenderbuffers(1)
        GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
        GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, GL.GL_RGBA8, 1, 1)
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_RENDERBUFFER, rb)
        self.feedback = GL.glGenBuffers(1)
        self.feedback_size = 0
        self.queries = GL.glGenQueries(2)
        # GL 4.3 / ES 3.1 vertex attribute binding, from EGL: PyOpenGL's
        # desktop module reads the version string as desktop GL's before
        # its first call of a GL 4.x function, and cannot read an ES one.
        u, i, e, b = ctypes.c_uint, ctypes.c_int, ctypes.c_uint, ctypes.c_ubyte
        self.attrib_format = self.function(EGL, "glVertexAttribFormat", u, i, e, b, u)
        self.attrib_i_format = self.function(EGL, "glVertexAttribIFormat", u, i, e, u)
        self.attrib_l_format = self.function(EGL, "glVertexAttribLFormat", u, i, e, u)
        self.attrib_binding = self.function(EGL, "glVertexAttribBinding", u, u)
        self.bind_vertex_buffer = self.function(EGL, "glBindVertexBuffer", u, u, ctypes.c_ssize_t, i)
        self.binding_divisor = self.function(EGL, "glVertexBindingDivisor", u, u)

    @staticmethod
    def function(EGL, name, *argtypes):
        address = EGL.eglGetProcAddress(name.encode("ascii"))
        if not address:
            raise ToolError(f"Mesa's EGL gives no {name}")
        return ctypes.CFUNCTYPE(None, *argtypes)(address)

    def proc(self, name, *argtypes):
        """A GL entry point of Mesa's, called with no wrapper (made once)."""
        key = (name,) + argtypes
        fn = self.procs.get(key)
        if fn is None:
            fn = self.procs[key] = self.function(self.egl, name, *argtypes)
        return fn

    def separable(self, program):
        """glProgramParameteri(program, GL_PROGRAM_SEPARABLE, GL_TRUE), called
        directly: PyOpenGL's wrapper cannot read an ES context's version."""
        self.proc("glProgramParameteri", ctypes.c_uint, ctypes.c_uint, ctypes.c_int)(program, 0x8258, 1)

    def enum(self, value):
        """A GL enumerant as apitrace writes it ("GL_FLOAT", a tuple of bit
        names, or a number) as the number PyOpenGL takes."""
        if isinstance(value, (tuple, list)):
            bits = 0
            for v in value:
                bits |= self.enum(v)
            return bits
        if isinstance(value, int):
            return value
        if isinstance(value, str):
            v = getattr(self.gl, value, None)
            if v is None:
                v = ES_ENUMS.get(value)
            if v is None:
                v = extension_enums().get(value)
            if v is None and value == "GL_ZERO":
                return 0
            if v is not None:
                return int(v)
        raise ValueError(f"{value!r} is not an enumerant of this GL")

    def feedback_positions(self, draw, prims, fits=True):
        """Runs `draw` (a callable issuing the draw call) with transform
        feedback of gl_Position into a buffer of room for `prims` primitives;
        the clip-space positions as a (vertices, 4) float32 array, in the
        order GL wrote them. With `fits` False, the number of primitives
        the draw made when they had no room (a geometry shader's)."""
        import numpy as np
        GL = self.gl
        size = max(16, prims * 3 * 16)
        GL.glBindBuffer(GL.GL_TRANSFORM_FEEDBACK_BUFFER, self.feedback)
        if size > self.feedback_size:
            GL.glBufferData(GL.GL_TRANSFORM_FEEDBACK_BUFFER, size, None, GL.GL_STREAM_READ)
            self.feedback_size = size
        GL.glBindBufferBase(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0, self.feedback)
        GL.glEnable(GL.GL_RASTERIZER_DISCARD)
        GL.glBeginQuery(GL.GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN, self.queries[0])
        GL.glBeginQuery(GL.GL_PRIMITIVES_GENERATED, self.queries[1])
        GL.glBeginTransformFeedback(GL.GL_TRIANGLES)
        try:
            draw()
        finally:
            GL.glEndTransformFeedback()
            GL.glEndQuery(GL.GL_PRIMITIVES_GENERATED)
            GL.glEndQuery(GL.GL_TRANSFORM_FEEDBACK_PRIMITIVES_WRITTEN)
            GL.glDisable(GL.GL_RASTERIZER_DISCARD)
        written = GL.glGetQueryObjectuiv(self.queries[0], GL.GL_QUERY_RESULT)
        generated = GL.glGetQueryObjectuiv(self.queries[1], GL.GL_QUERY_RESULT)
        if written != generated and not fits and generated > written:
            return int(generated)
        if written != generated:
            raise ToolError(f"transform feedback kept {written} of {generated} primitives (room for {prims})")
        n = written * 3 * 16
        if n == 0:
            return np.zeros((0, 4), dtype="<f4")
        # Read through a mapping: OpenGL ES has no glGetBufferSubData.
        ptr = GL.glMapBufferRange(GL.GL_TRANSFORM_FEEDBACK_BUFFER, 0, n, GL.GL_MAP_READ_BIT)
        try:
            data = ctypes.string_at(ptr, n)
        finally:
            GL.glUnmapBuffer(GL.GL_TRANSFORM_FEEDBACK_BUFFER)
        return np.frombuffer(data, dtype="<f4").reshape(-1, 4)
