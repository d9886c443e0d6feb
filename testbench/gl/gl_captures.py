"""What the GL tests share: the captures of testbench/gl/gl_boxes.c and
gl_shaders.c that test_gl_capture.py makes (RBCD_GL_CAPTURES, set by CTest;
by hand build/testbench/gl/captures), captures the tests write call by call
(Calls, as reduced captures), the converter run as users run it and as the
hostile-input tests run it (peak memory, time, one-line refusals), and a
reader of the traces it writes. What gl_shaders draws is in
test_gl2rbt_shaders.py.

What gl_boxes draws, 128 x 96, glOrtho(0, 128, 0, 96, -100, 100) in frames 0
and 1 (window y up, screen rows down: row = 95 - y):
  frame 0: box 1 [8,28]x[8,28]x[-20,-10] (client arrays), box 2
           [20,40]x[16,36]x[-15,-5] (a buffer object), box 3 [60,70]x[8,18]
           (immediate mode, an EXT_debug_marker group); a 40 x 40 floor and an
           8 x 4 overlay that are not collisionable.
  frame 1: box 2 [20,30]^2 inside box 1 [8,48]^2; box 3 drawn twice, the
           second time as a GL_EQUAL pass.
  frame 2: glFrustum, a sphere (id 4) overlapping box 1, box 2 apart.
Face-on boxes under an orthographic projection give width x height front
fragments and as many back ones (tagged c: culling is on); side faces are
edge-on and cover nothing.
"""
import gzip
import os
import re
import struct
import subprocess
import time

import pytest

from conftest import ROOT, program
from rbcd.gl2rbt.reduced import ReducedWriter

GL2RBT = os.path.join(ROOT, "scripts", "rbcd-gl2rbt")
CAPTURES = os.environ.get("RBCD_GL_CAPTURES") or os.path.join(ROOT, "build", "testbench", "gl", "captures")
FAULTS = ["nan", "index", "ortho", "list", "shader", "line", "underflow"]
SHADER_FAULTS = ["geometry", "rendered", "texture", "cube", "array", "compile", "separable", "image", "multisample", "default", "msimage", "msdepth", "cubeseam"]
DEPTH_MAX = (1 << 24) - 1


# ---- captures written by the tests, call by call

END_FRAME = 32   # apitrace's flag on a call that ends a frame
TRIANGLE = struct.pack("<9f", 4, 4, -10, 40, 4, -10, 4, 40, -10)


# glXCreateContextAttribsARB's arguments but its attribute list.
GLX_CONTEXT_ARGS = [("dpy", 1), ("config", 1), ("share_context", 0), ("direct", 1)]


class Calls:
    """A capture's calls, numbered from 1, as apitrace's reader yields them,
    written as a reduced capture (the converter's own format): every call,
    value and file is the test's."""

    def __init__(self, w=64, h=48):
        self.calls = []
        self.add("glViewport", x=0, y=0, width=w, height=h, flags=1)   # apitrace's record of the window
        self.add("glMatrixMode", mode="GL_PROJECTION")
        self.add("glOrtho", left=0, right=w, bottom=0, top=h, zNear=-100, zFar=100)
        self.add("glMatrixMode", mode="GL_MODELVIEW")
        self.add("glEnableClientState", array="GL_VERTEX_ARRAY")

    def add(self, fn, ret=None, flags=0, **args):
        """A call of `fn` with `args`, in their order (a reduced capture's
        record must carry its function's every parameter by apitrace's
        names: GLX_CONTEXT_ARGS are glXCreateContextAttribsARB's but its
        attribute list)."""
        self.calls.append((len(self.calls) + 1, fn, list(args.items()), ret, flags))
        return self

    def triangle(self, obj=None):
        if obj is not None:
            self.add("glPushDebugGroup", source="GL_DEBUG_SOURCE_APPLICATION", id=obj, length=-1,
                     message="rbcd-object")
        self.add("glVertexPointer", size=3, type="GL_FLOAT", stride=0, pointer=TRIANGLE)
        self.add("glDrawArrays", mode="GL_TRIANGLES", first=0, count=3)
        if obj is not None:
            self.add("glPopDebugGroup")
        return self

    def swap(self):
        return self.add("glXSwapBuffers", dpy=1, drawable=2, flags=END_FRAME)

    def write(self, path, images=False):
        """The reduced capture; `images`: with texture images, as a
        capture has them (the writer leaves them out)."""
        w = ReducedWriter(str(path))
        for c in self.calls:
            if images:
                w.put(c)
                w.count += 1
            else:
                w.call(c)
        w.commit()
        return str(path)


# ---- the converter run as the hostile-input tests run it: under
# /usr/bin/time (peak memory), timed, with no standard input.

def gl2rbt_timed(tmp_path, *args, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL):
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    t = time.monotonic()
    r = subprocess.run(["/usr/bin/time", "-f", "maxrss %M", "/usr/bin/python3", GL2RBT] + [str(a) for a in args],
                       stdout=stdout, stderr=subprocess.PIPE, stdin=stdin, text=True, env=env, timeout=120)
    r.seconds = time.monotonic() - t
    return r


def lines_of(r):
    return [line for line in r.stderr.strip().splitlines()
            if not line.startswith(("maxrss ", "Command exited with non-zero status"))]   # /usr/bin/time's


def refused(r, *words, status=2):
    lines = lines_of(r)
    assert r.returncode == status and len(lines) == 1 and all(w in lines[0] for w in words), \
        f"exit {r.returncode}, {lines} (wanted {words})"
    return lines[0]


def peak_mb(r):
    return int(re.search(r"maxrss (\d+)", r.stderr).group(1)) / 1024


def left_behind(tmp_path, keep):
    return sorted(set(os.listdir(tmp_path)) - set(keep))


def run(cmd, **kw):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


def capture_path(name="boxes"):
    p = os.path.join(CAPTURES, name + ".trace")
    if not os.path.exists(p):
        pytest.skip("no captures (gl_capture was skipped: scripts/setup.sh --gl installs Xvfb and apitrace)")
    return p


def read_trace(path):
    """{frame: {(x, y): [(depth, id, facing, culled)]}} and the tile records."""
    opener = gzip.open if path.endswith(".gz") else open
    frames, tiles, frame = {}, [], None
    with opener(path, "rt") as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "frame":
                frame = int(t[1])
                frames[frame] = {}
            elif t[0] == "tile":
                tiles.append((frame, line.strip()))
            elif t[0] == "f":
                x, y, depth, obj = (int(v) for v in t[1:5])
                frames[frame].setdefault((x, y), []).append((depth, obj, t[5], len(t) > 6 and t[6] == "c"))
    return frames, tiles


class Converter:
    """rbcd-gl2rbt through its launcher, its temporaries in the test's own
    directory (where what is left behind can be seen)."""

    def __init__(self, tmp):
        self.tmp = str(tmp)
        self.env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=self.tmp)

    def __call__(self, *args):
        return run(["/usr/bin/python3", GL2RBT] + [str(a) for a in args], env=self.env)

    def convert(self, *extra, name="boxes", out="boxes.rbt"):
        path = os.path.join(self.tmp, out)
        r = self(capture_path(name), "-o", path, *extra)
        assert r.returncode == 0, f"conversion failed ({r.returncode}): {r.stderr.strip()}"
        return path, r

    def path(self, *names):
        return os.path.join(self.tmp, *names)


def pairs_per_frame(trace, collisions):
    """rbcd-sim on a converted trace: {frame: {(a, b): hits}}."""
    r = run([program("rbcd-sim"), "--trace", trace, "--collisions", collisions, "-q"])
    assert r.returncode == 0, f"rbcd-sim failed: {r.stderr.strip()}"
    hits, frame = {}, None
    with open(collisions) as f:
        for line in f:
            t = line.split()
            if t[0] == "frame":
                frame = int(t[1])
                hits[frame] = {}
            elif t[0] == "hit":
                k = (int(t[3]), int(t[4]))
                hits[frame][k] = hits[frame].get(k, 0) + 1
    return hits


def alive(pid):
    """Whether process pid runs (a zombie does not)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
