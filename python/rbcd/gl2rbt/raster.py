"""The raster driver: the converter's draw stream into rbcd-gl-raster, which
rasterizes it through the scene front end's tile rasterizer and writes the
trace; and the run's report."""
import json
import os
import shutil
import struct
import subprocess
import tempfile

from ..cli import write_output
from .capture import check_input_file, read_calls
from .converter import Converter
from .errors import ConvertError, RasterStopped, ToolError, printable
from .glstate.draws import FRAGMENT_EFFECT_KEYS
from .outputs import SafeText
from .reduced import ReducedWriter, is_reduced_capture

# Where rbcd-gl-raster is looked for after RBCD_GL_RASTER: the source tree's
# build (python/rbcd/gl2rbt -> build/bin), the programs installed beside this
# package (P/share/rbcd/python/rbcd/gl2rbt -> P/bin), then PATH.
PACKAGE = os.path.dirname(os.path.abspath(__file__))
RASTER_DIRS = (os.path.join(PACKAGE, "..", "..", "..", "build", "bin"),
               os.path.join(PACKAGE, "..", "..", "..", "..", "..", "bin"))


def raster_program():
    env = os.environ.get("RBCD_GL_RASTER")
    if env:
        if not os.access(env, os.X_OK):
            raise ToolError(f"RBCD_GL_RASTER={printable(env)} is not an executable")
        return env
    for d in RASTER_DIRS:
        exe = os.path.join(d, "rbcd-gl-raster")
        if os.access(exe, os.X_OK):
            return exe
    exe = shutil.which("rbcd-gl-raster")
    if exe:
        return exe
    raise ToolError("rbcd-gl-raster not found (build it: cmake --build build --target rbcd-gl-raster)")


def convert(args, listing=False, ids=None):
    # The temporary directory goes whatever fails, before or after the
    # rasterizer starts (the test suite's refusals used to leave them).
    tmpdir = tempfile.mkdtemp(prefix="rbcd-gl2rbt.")
    try:
        return convert_in(args, tmpdir, listing, ids)
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)


def convert_in(args, tmpdir, listing, ids):
    check_input_file(args.trace)
    out_paths = [p for p in (args.output, args.geometry, args.summary, getattr(args, "reduced_out", None)) if p]
    real_in = os.path.realpath(args.trace)
    for p in out_paths:
        if os.path.realpath(p) == real_in:
            raise ConvertError(f"the output {printable(p)} is the capture itself")
    if len(set(os.path.realpath(p) for p in out_paths)) != len(out_paths):
        raise ConvertError("two outputs name the same file")
    summary_path = os.path.join(tmpdir, "summary.jsonl")
    cmd = [raster_program(), "--trace", args.output, "--summary", summary_path, "--name", args.trace]
    if args.depth_out:
        cmd += ["--depth-out", args.depth_out]
    if ids:
        cmd += ["--ids-out", ids[0], "--ids-frame", str(ids[1])]
    geo = SafeText(args.geometry) if args.geometry else None
    if geo:
        geo.write("rbcd-geometry 2\n")
    reduced = None
    if getattr(args, "reduced_out", None):
        if is_reduced_capture(args.trace):
            raise ConvertError("--reduced-out: the capture is already a reduced capture")
        try:
            reduced = ReducedWriter(args.reduced_out)
        except BaseException:
            if geo:
                geo.abandon()
            raise
    try:
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
    except BaseException:
        for o in (geo, reduced):
            if o:
                o.abandon()
        raise
    conv = Converter(args, proc.stdin, geo)
    if listing:
        conv.listing = []
    ok = False
    try:
        for call in read_calls(args.trace):
            conv.last_call = call[0]
            if reduced:
                reduced.call(call)
            conv.handle(call)
            if conv.last_frame is not None and conv.frame > conv.last_frame:
                break
            if args.snapshots and conv.active and call[0] in args.snapshots:
                conv.open_frame(call[0])
                conv.emit(b"S" + struct.pack("<Q", call[0]))
        if conv.s.begin_mode is not None:
            raise ConvertError("the capture ends between glBegin and glEnd")
        if conv.out_frame < 0:
            raise ConvertError(f"the capture has {conv.frame} frames: --frames selects none" if conv.frame
                               else "the capture has no frame (no buffer swap)")
        if conv.frame_open:
            # A last frame without its swap is not converted (rbcd-gl-raster
            # drops a frame the stream leaves open): the trace ends at the
            # last whole frame.
            conv.partial_frame_dropped = True
        conv.emit(b"Z")
        try:
            proc.stdin.close()
        except BrokenPipeError:
            raise RasterStopped()
        raster_result(proc, args.trace)
        with open(summary_path) as f:
            lines = f.read().splitlines()
        lines = [with_fragment_effects(line, conv.fragment_effects.get(i)) for i, line in enumerate(lines)]
        frames = [json.loads(l) for l in lines]
        if args.summary:
            write_output(args.summary, "".join(line + "\n" for line in lines), "summary")
        if geo:
            geo.commit()
            geo = None
        if reduced:
            reduced.commit()
            reduced = None
        ok = True
        return frames, conv
    except RasterStopped:
        proc.stdin = None
        raster_result(proc, args.trace)
        raise ToolError("rbcd-gl-raster stopped reading without a message")
    finally:
        if conv.stream_copy is not None:
            conv.stream_copy.close()
        if not ok:
            # SIGTERM: rbcd-gl-raster removes its temporaries on it (SIGKILL would leave them).
            if proc.poll() is None:
                proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
            # What is still buffered for the stopped rasterizer is dropped.
            try:
                if proc.stdin:
                    proc.stdin.close()
            except OSError:
                pass
            if geo:
                geo.abandon()
            if reduced:
                reduced.abandon()


def with_fragment_effects(line, effects):
    """A frame's summary line with the counts of its draws under fragment
    shaders that can discard or write gl_FragDepth (docs/gl-capture.md),
    added at its end; a frame without draws under a program is left as
    rbcd-gl-raster wrote it."""
    if not effects or not line.endswith("}"):
        return line
    extra = ",".join(f'"{k}":{effects[k]}' for k in FRAGMENT_EFFECT_KEYS)
    return line[:-1] + "," + extra + "}"


def raster_result(proc, trace):
    """Raises rbcd-gl-raster's own message once it has exited non-zero: bad
    input (exit 2) as ConvertError, anything else as ToolError."""
    err = proc.stderr.read().decode("utf-8", "replace")
    rc = proc.wait()
    if rc == 0:
        return
    line = (err.strip().splitlines() or [f"rbcd-gl-raster exited {rc}"])[0]
    line = line.removeprefix("rbcd-gl-raster: ").removeprefix(trace + ": ")
    if rc == 2:
        raise ConvertError(line)
    raise ToolError(line)


def report(frames, conv):
    n = len(frames)
    frags = sum(f["fragments"] for f in frames)
    culled = sum(f["culled"] for f in frames)
    other = sum(f["other"] for f in frames)
    objs = sum(len(f["objects"]) for f in frames)
    print(f"{n} frames: {objs / max(n, 1):.1f} collisionable objects, {frags / max(n, 1):.0f} collisionable "
          f"fragments ({100.0 * culled / max(frags, 1):.1f}% tagged c) and {other / max(n, 1):.0f} other "
          f"fragments a frame")
    if conv.partial_frame_dropped:
        print("the capture stops before its last buffer swap: that frame is not converted")
    if conv.ignored_prims:
        print(f"{conv.ignored_prims} point and line draws not rasterized (no area)")
    fx = conv.fragment_effects.values()
    if any(e["discard_draws"] or e["frag_depth_draws"] for e in fx):
        print(f"draws whose fragment shader can discard: {sum(e['discard_draws'] for e in fx)} "
              f"({sum(e['discard_collisionable'] for e in fx)} collisionable); writing gl_FragDepth: "
              f"{sum(e['frag_depth_draws'] for e in fx)} ({sum(e['frag_depth_collisionable'] for e in fx)} "
              "collisionable); all their fragments are kept")
    if conv.offscreen_draws:
        print(f"{conv.offscreen_draws} draws into other targets than the camera pass left out (docs/gl-capture.md)")


# ---------------------------------------------------------------- listing a frame's draws
