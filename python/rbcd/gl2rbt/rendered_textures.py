"""Textures the GPU renders, read back from Mesa's replay of the capture.

A vertex shader that samples a texture a framebuffer renders into (a height
map drawn each frame, glmark2's terrain) needs the image the earlier passes
made, which only running them gives: the converter runs no fragment shader.
So Mesa replays the whole capture once (glretrace --markers, in the
background, as the conversion goes), with gl/texture_readback.c preloaded:
at each draw the converter asks for, the textures bound at the units the
draw's vertex shader reads are read back, every level, in a format that
gives the values back exactly (texture_readback.c), and the converter gives
them to its own Mesa context as glTexImage2D calls (vertex_textures.py);
the reduced capture carries those calls, so converting it needs no replay.

One replay serves a conversion: requests go in call order, and the replay
waits at each for the next. It needs glretrace, an X server (Xvfb when there
is no DISPLAY, as --check-depth) and the library (an OpenGL ES capture has
no glGetTexImage: glReadPixels reads each image of a level through a
framebuffer object); a reduced capture (nothing to replay) is refused when
a draw needs it. Bounded: 1 GiB a reply, a level's size GL's; the replay gets
--check-timeout seconds (600 by default) to reach each draw."""
import os
import select
import shutil
import signal
import struct
import subprocess
import time

from ..cli import temporary_folder, unregister_temporary
from .errors import ConvertError, ToolError, printable
from .glretrace import end_replay, glretrace_command, preload_library, session_left, start_replay
from .glstate.texture_formats import ES_COMBINATIONS
from .glstate.texture_levels import CUBE_FACES

LIBRARY = "rbcd-texture-readback.so"
# A replay stopped this long (SIGSTOP) is the tool's failure (RenderedTextures.take).
STOPPED_SECONDS = 5
# Signals that end a replay from outside (a crash, SIGSEGV or SIGABRT, on
# the capture's calls is the capture's error).
STOPPING_SIGNALS = (signal.SIGKILL, signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGQUIT)
MAX_REPLY_BYTES = 1 << 30
# The formats and types texture_readback.c reads back in, and a pixel's
# bytes in each.
READBACK = {(0x1902, 0x1405): ("GL_DEPTH_COMPONENT", "GL_UNSIGNED_INT", 4),
            (0x1902, 0x1406): ("GL_DEPTH_COMPONENT", "GL_FLOAT", 4),
            (0x84F9, 0x84FA): ("GL_DEPTH_STENCIL", "GL_UNSIGNED_INT_24_8", 4),
            (0x84F9, 0x8DAD): ("GL_DEPTH_STENCIL", "GL_FLOAT_32_UNSIGNED_INT_24_8_REV", 8),
            (0x1908, 0x1401): ("GL_RGBA", "GL_UNSIGNED_BYTE", 4),
            (0x1908, 0x1406): ("GL_RGBA", "GL_FLOAT", 16),
            (0x8D99, 0x1404): ("GL_RGBA_INTEGER", "GL_INT", 16),
            (0x8D99, 0x1405): ("GL_RGBA_INTEGER", "GL_UNSIGNED_INT", 16),
            # OpenGL ES's RGB565 and RGB10_A2, in their own packed types.
            (0x1907, 0x8363): ("GL_RGB", "GL_UNSIGNED_SHORT_5_6_5", 2),
            (0x1908, 0x8368): ("GL_RGBA", "GL_UNSIGNED_INT_2_10_10_10_REV", 4)}


# The targets a texture is read back at (their GL numbers).
TARGETS = {"GL_TEXTURE_2D": 0x0DE1, "GL_TEXTURE_3D": 0x806F, "GL_TEXTURE_2D_ARRAY": 0x8C1A,
           "GL_TEXTURE_CUBE_MAP": 0x8513, "GL_TEXTURE_CUBE_MAP_ARRAY": 0x9009, "GL_TEXTURE_1D": 0x0DE0,
           "GL_TEXTURE_1D_ARRAY": 0x8C18, "GL_TEXTURE_RECTANGLE": 0x84F5, "GL_TEXTURE_2D_MULTISAMPLE": 0x9100,
           "GL_TEXTURE_2D_MULTISAMPLE_ARRAY": 0x9102}


# A target's dimensions as glTexImage*D, glTexSubImage*D and glTexStorage*D
# count them (a cube map's faces 2D images each, a 1D array's layers rows).
DIMENSIONS = {"GL_TEXTURE_1D": 1, "GL_TEXTURE_3D": 3, "GL_TEXTURE_2D_ARRAY": 3, "GL_TEXTURE_CUBE_MAP_ARRAY": 3}
SIZES, OFFSETS = ("width", "height", "depth"), ("xoffset", "yoffset", "zoffset")


def level_calls(no, call, target, base, level):
    """A level read back given as `call` (glTexImage or glTexSubImage, of
    the target's dimensions) with `base`'s arguments beside its own: one
    call (a cube map's, one a face)."""
    lv, w, h, d, fmt, kind, pixels = level
    dims = DIMENSIONS.get(target, 2)
    args = dict(base, level=lv, format=fmt, type=kind, **dict(zip(SIZES[:dims], (w, h, d))))
    if call == "glTexSubImage":
        args.update(dict.fromkeys(OFFSETS[:dims], 0))
    if target == "GL_TEXTURE_CUBE_MAP":
        face = len(pixels) // 6
        return [(no, f"{call}2D", dict(args, target=f, pixels=pixels[i * face:(i + 1) * face]))
                for i, f in enumerate(CUBE_FACES)]
    return [(no, f"{call}{dims}D", dict(args, target=target, pixels=pixels))]


def image_calls(no, target, internal, levels, es, immutable=0):
    """The calls that give the converter's Mesa context a texture's levels
    read back: (call, name, arguments) each, by target (a cube map's faces
    one by one; in OpenGL ES a 2D texture's as storage and sub-images)."""
    if levels and levels[0][0] == 0 and (immutable or es and target == "GL_TEXTURE_2D"):
        # Immutable storage, as the replay's texture has (its levels'
        # completeness is the storage's: an image unit reads a level past
        # the first of a mutable one filtered without mipmaps as nothing);
        # OpenGL ES binds only such a texture to an image unit.
        _, w, h, d, fmt, kind, _ = levels[0]
        dims = DIMENSIONS.get(target, 2)
        storage = dict(target=target, levels=immutable or max(lv[0] for lv in levels) + 1,
                       internalformat=upload_format(internal, fmt, kind, es), **dict(zip(SIZES[:dims], (w, h, d))))
        return [(no, f"glTexStorage{dims}D", storage)] + \
            [c for level in levels for c in level_calls(no, "glTexSubImage", target, {}, level)]
    return [c for level in levels
            for c in level_calls(no, "glTexImage", target,
                                 dict(internalformat=upload_format(internal, level[4], level[5], es), border=0), level)]


HALF_FLOAT_FORMATS = {"GL_RGBA16F", "GL_RGB16F", "GL_RG16F", "GL_R16F", "GL_R11F_G11F_B10F", "GL_RGB9_E5"}
ES_FALLBACK = {("GL_RGBA", "GL_UNSIGNED_BYTE"): "GL_RGBA8", ("GL_RGBA_INTEGER", "GL_INT"): "GL_RGBA32I",
               ("GL_RGBA_INTEGER", "GL_UNSIGNED_INT"): "GL_RGBA32UI"}


_COMPRESSED = None
# Parts of a compressed format's name and the uncompressed format that
# holds its decoded texels exactly, the first that matches.
COMPRESSED_BASES = (("SLUMINANCE_ALPHA", "GL_SLUMINANCE8_ALPHA8"), ("SLUMINANCE", "GL_SLUMINANCE8"),
                    ("LUMINANCE_ALPHA", "GL_LUMINANCE_ALPHA32F_ARB"), ("LUMINANCE", "GL_LUMINANCE32F_ARB"),
                    ("INTENSITY", "GL_INTENSITY32F_ARB"), ("SRGB", "GL_SRGB8_ALPHA8"))


def compressed_formats():
    """{value: name} of every compressed internal format PyOpenGL names
    (core and extensions: S3TC, RGTC, BPTC, ETC2, ASTC)."""
    global _COMPRESSED
    if _COMPRESSED is None:
        from OpenGL import GL
        from .mesa import extension_enums
        names = {n: getattr(GL, n) for n in dir(GL) if n.startswith("GL_COMPRESSED_")} | extension_enums()
        _COMPRESSED = {int(v): n for n, v in names.items() if n.startswith("GL_COMPRESSED_") and isinstance(v, int)}
    return _COMPRESSED


def upload_format(internal, fmt, kind, es):
    """The internal format a level read back is given to the converter's
    Mesa context in: its own (desktop GL converts any pixels), but for a
    compressed one the uncompressed format that holds its decoded texels
    exactly (Mesa would encode them again, and its encoders do not give
    the blocks back), or in OpenGL
    ES, where the format and type must be its table's, its own when they
    are, else the RGBA one of the same values that samples the same (a
    missing component reads as GL's default either way)."""
    compressed = compressed_formats().get(internal)
    if compressed is not None and kind == "GL_FLOAT":
        # The uncompressed format of the same base (the compatibility
        # profile's luminance, intensity and alpha ones too: read back as
        # RGBA, they take their own components of it again).
        for part, plain in COMPRESSED_BASES:
            if part in compressed:
                return plain
        return "GL_RGBA32F"
    if not es:
        return internal
    from OpenGL import GL
    names = {int(getattr(GL, n)): n for n in ES_COMBINATIONS if hasattr(GL, n)}
    name = names.get(internal)
    if name is not None and (fmt, kind) in ES_COMBINATIONS[name]:
        return name
    if kind == "GL_FLOAT":
        return "GL_RGBA16F" if name in HALF_FLOAT_FORMATS else "GL_RGBA32F"
    return ES_FALLBACK.get((fmt, kind), internal)


WHAT = "reading back a texture the GPU renders"


class RenderedTextures:
    def __init__(self, trace, timeout):
        self.trace, self.timeout = trace, timeout
        self.lib = preload_library(LIBRARY, WHAT, "desktop GL", "libgl-dev")
        glretrace_command([], WHAT)   # glretrace missing: said at once, not when the replay starts
        self.proc = self.dir = None
        self.requests = self.replies = None

    def start(self):
        self.dir = temporary_folder("rbcd-gl2rbt-textures.")
        for fifo in ("requests", "replies"):
            os.mkfifo(os.path.join(self.dir, fifo), 0o600)
        # O_RDWR: a FIFO opened so never waits for the other side (Linux),
        # and the replay's library opens its ends when it first draws.
        self.requests = os.open(os.path.join(self.dir, "requests"), os.O_RDWR | os.O_CLOEXEC)
        self.replies = os.open(os.path.join(self.dir, "replies"), os.O_RDWR | os.O_CLOEXEC)
        cmd = glretrace_command(["--markers", self.trace], WHAT, preload=self.lib,
                                env=[f"RBCD_TEXTURE_FIFOS={self.dir}"])
        self.log = open(os.path.join(self.dir, "replay.log"), "w+b")
        # One llvmpipe rasterizer thread: its vertex shaders do not wait for
        # the others (depth_check.mesa_depth_at), and the replay's draws
        # must make what the capture's did.
        self.proc = start_replay(cmd, stdout=subprocess.DEVNULL, stderr=self.log,
                                 # (xvfb-run's own temporary folder in ours: removed with it
                                 # when xvfb-run is ended before it removes it)
                                 env=dict(os.environ, LP_NUM_THREADS="0", TMPDIR=self.dir))

    def read(self, no, name, units):
        """The textures bound at `units` [(unit, target name)] just before
        call `no` (a draw `name`), as Mesa's replay has them: {(unit,
        target): (internal format, [(parameter, [4 values])], [(level,
        width, height, depth, format, type, pixels)])}."""
        self.what = f"call {no}: {printable(name)}"
        if self.proc is None:
            self.start()
        os.write(self.requests, (f"{no} " + " ".join(f"{u}:{TARGETS[t]}" for u, t in units) + "\n").encode())
        deadline = time.monotonic() + self.timeout
        magic = self.take(4, no, deadline)
        if magic == b"RBTE":
            n, = struct.unpack("<I", self.take(4, no, deadline))
            raise ConvertError(f"{self.what}: reading back the textures its vertex shader reads: "
                               f"{printable(self.take(min(n, 4096), no, deadline).decode('utf-8', 'replace'))}")
        if magic != b"RBTX":
            raise ConvertError(f"{self.what}: Mesa's replay answered {printable(magic)} for the textures its "
                               "vertex shader reads")
        count, = struct.unpack("<I", self.take(4, no, deadline))
        out, total = {}, 0
        names = {v: k for k, v in TARGETS.items()}
        for _ in range(min(count, len(units))):
            unit, target, internal, nparams = struct.unpack("<IIiI", self.take(16, no, deadline))
            params = []
            for _ in range(min(nparams, 32)):
                pname, *values = struct.unpack("<I4f", self.take(20, no, deadline))
                params.append((pname, values))
            nlevels, = struct.unpack("<I", self.take(4, no, deadline))
            levels = []
            for _ in range(min(nlevels, 15)):
                level, w, h, d, fmt, kind, n = struct.unpack("<6IQ", self.take(32, no, deadline))
                fmt, kind, px = READBACK.get((fmt, kind), (None, None, 0))
                total += n
                if not (px and level < 15 and w <= 16384 and h <= 16384 and d <= 16384 and n == w * h * d * px
                        and total <= MAX_REPLY_BYTES):
                    raise ConvertError(f"{self.what}: Mesa's replay read back a level of {w} x {h} x {d} in {n} "
                                       "bytes")
                levels.append((level, w, h, d, fmt, kind, self.take(n, no, deadline)))
            if target not in names:
                raise ConvertError(f"{self.what}: Mesa's replay read back a texture of target {target}")
            out[(unit, names[target])] = (internal, params, levels)
        return out

    def take(self, n, no, deadline):
        """n bytes of the replay's answer, or why there are none."""
        parts, left, stopped = [], n, 0
        while left:
            ready, _, _ = select.select([self.replies], [], [], 1.0)
            if ready:
                chunk = os.read(self.replies, min(left, 1 << 20))
                parts.append(chunk)
                left -= len(chunk)
                continue
            # Stopped from outside (SIGSTOP: in a session of its own, the
            # terminal's Ctrl-Z does not reach it) for STOPPED_SECONDS:
            # the tool's failure, not the capture's, said well before
            # --check-timeout.
            stopped = stopped + 1 if self.stopped() else 0
            if stopped >= STOPPED_SECONDS:
                raise ToolError(f"{self.trace}: {self.what}: Mesa's replay of the capture (glretrace), reading "
                                "back the textures its vertex shader reads, was stopped (SIGSTOP) and did not go "
                                "on; no output written")
            if self.proc.poll() is not None:
                self.log.seek(0)
                tail = self.log.read()[-4096:].decode("utf-8", "replace").strip().splitlines()
                rc = self.proc.returncode
                sig = next((x for x in (-rc, rc - 128) if x in STOPPING_SIGNALS), None)
                if sig is not None:
                    # Ended from outside (SIGKILL, the kernel out of memory,
                    # SIGTERM, SIGINT, SIGHUP, SIGQUIT; through xvfb-run, 128
                    # + it): the tool failed, not the capture (a crash on the
                    # capture's calls, SIGSEGV or SIGABRT, is the capture's).
                    raise ToolError(f"{self.trace}: {self.what}: Mesa's replay of the capture (glretrace), reading "
                                    f"back the textures its vertex shader reads, was ended by signal {sig}; no "
                                    "output written")
                raise ConvertError(f"{self.what}: Mesa's replay of the capture (glretrace) ended before it read "
                                   f"back the textures its vertex shader reads"
                                   f" ({printable(tail[-1] if tail else 'no message')})")
            if time.monotonic() > deadline:
                raise ConvertError(f"{self.what}: Mesa's replay of the capture (glretrace) did not reach the draw "
                                   f"in {self.timeout} s (--check-timeout)")
        return b"".join(parts)

    def stopped(self):
        """Whether a process of the replay's session (xvfb-run, glretrace)
        is stopped by a signal (its state T in /proc)."""
        return any(state in ("T", "t") for _, state in session_left(self.proc.pid))

    def close(self):
        """Ends the replay at once, on every path (the conversion done, a
        refusal, a signal): its whole session ended (end_replay: Xvfb with
        it), then the folder removed, xvfb-run's own within it."""
        if self.requests is not None:
            os.close(self.requests)
            self.requests = None
        if self.proc is not None:
            end_replay(self.proc)
            self.log.close()
        if self.replies is not None:
            os.close(self.replies)
        if self.dir is not None:
            shutil.rmtree(self.dir, ignore_errors=True)
            unregister_temporary(self.dir)
        self.proc = self.dir = self.requests = self.replies = None
