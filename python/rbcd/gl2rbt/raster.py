"""The raster driver: the converter's draw stream into rbcd-gl-raster, which
rasterizes it through the scene front end's tile rasterizer and writes the
trace; and the run's report."""
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import time

from ..cli import check_outputs, remove_left_temporaries, temporary_folder, unregister_temporary, write_output
from ..startup import ignore_signals
from .capture import check_input_file, check_rest, close_calls, read_calls
from .converter import Converter, swapped_drawable
from .errors import ConvertError, RasterStopped, ToolError, printable
from .gl_tables import CALL_FLAG_END_FRAME, base_name
from .glstate.draws import FRAGMENT_EFFECT_KEYS, DrawCalls
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
        if not os.path.isfile(env) or not os.access(env, os.X_OK):
            raise ToolError(f"RBCD_GL_RASTER={printable(env)} is not an executable file")
        return env
    for d in RASTER_DIRS:
        exe = os.path.join(d, "rbcd-gl-raster")
        if os.path.isfile(exe) and os.access(exe, os.X_OK):
            return exe
    exe = shutil.which("rbcd-gl-raster")
    if exe:
        return exe
    raise ToolError("rbcd-gl-raster not found (build it: cmake --build build --target rbcd-gl-raster)")


def convert(args, listing=False, ids=None, report=None, last=False):
    """The conversion; `report(frames, conv)` writes the run's report
    before the outputs are committed: a report that cannot be written fails
    the run, and no output is left. `last`: the run's last work (not the
    first step of --check-depth or --list-draws), which a signal no longer
    ends once its outputs are committed."""
    # The temporary directory goes whatever fails, before or after the
    # rasterizer starts (the test suite's refusals used to leave them).
    tmpdir = temporary_folder("rbcd-gl2rbt.")
    try:
        return convert_in(args, tmpdir, listing, ids, report, last)
    finally:
        shutil.rmtree(tmpdir, ignore_errors=True)
        unregister_temporary(tmpdir)


def check_paths(args):
    """The outputs against the inputs and each other, before anything is
    opened (rbcd.cli.check_outputs); the hidden ones too (--stream-out, and
    the files --depth-out PREFIX names, PREFIX.N.depth)."""
    outputs = [("-o", args.output), ("--geometry", args.geometry), ("--summary", args.summary),
               ("--reduced-out", getattr(args, "reduced_out", None)), ("--image", getattr(args, "image", None)),
               ("--stream-out", getattr(args, "stream_out", None))]
    depth_out = getattr(args, "depth_out", None)
    if depth_out:
        check_depth_prefix(depth_out, [args.trace, args.select] + [p for _, p in outputs])
        outputs += [("--depth-out", p) for p in depth_files(depth_out)]
    # The rasterizer the run starts is an input too (RBCD_GL_RASTER may name
    # a copy where an output would go).
    try:
        raster = raster_program()
    except ToolError:
        raster = None   # said when the run needs it
    check_outputs([("the capture", args.trace), ("the selection file", args.select), ("rbcd-gl-raster", raster)],
                  outputs)


def depth_pattern(prefix):
    return re.compile(re.escape(os.path.basename(prefix)) + r"\.[0-9]+\.depth")


def depth_files(prefix):
    """The files rbcd-gl-raster's --depth-out PREFIX may replace that exist
    already: PREFIX.N.depth, N an output frame."""
    d = os.path.dirname(prefix) or "."
    try:
        names = os.listdir(d)
    except OSError:
        return []   # rbcd-gl-raster says why it cannot create them
    pattern = depth_pattern(prefix)
    return [os.path.join(d, n) for n in names if pattern.fullmatch(n)]


def check_depth_prefix(prefix, paths):
    """No input or other output is named as one of --depth-out's files
    (by path; depth_files' existing ones are compared as files)."""
    d = os.path.realpath(os.path.dirname(prefix) or ".")
    pattern = depth_pattern(prefix)
    for p in paths:
        if p and p != "-" and pattern.fullmatch(os.path.basename(p)) and \
                os.path.realpath(os.path.dirname(p) or ".") == d:
            raise ConvertError(f"--depth-out {printable(prefix)}: would write {printable(p)}, "
                               "an input or another output")


# The buffer swaps after the first draw first_window reads at most for the
# main window.
FIRST_WINDOW_SWAPS = 64
# The calls that draw (a glBegin's primitive is drawn at its glEnd).
DRAWING = frozenset(DrawCalls.HANDLERS) - {"glPrimitiveRestartNV", "glRenderMode"}


def new_converter(args, raster_in):
    """The Converter, its --stream-out opened here as every other output
    (SafeText: a temporary, renamed into place at the end, removed on
    failure), not by the Converter (which would open it in place at once).
    Its main window is known from the start (first_window): a splash
    window's clears and swaps before the first draw are another target's,
    not frames, and the screen is the main window's."""
    stream_out, args.stream_out = getattr(args, "stream_out", None), None
    try:
        main = first_window(args)
        conv = Converter(args, raster_in, None)
        conv.main_drawable = main
        return conv
    finally:
        args.stream_out = stream_out


def first_window(args):
    """The main window or surface: the first one drawn into (with no
    framebuffer object bound, not a pbuffer) once it swaps, unless another
    drawn into swaps twice first (a warm-up window never shown); for a
    capture that draws only into framebuffer objects (and blits to the
    window), the first window swapped after a draw. None when a draw comes
    before any MakeCurrent, after FIRST_WINDOW_SWAPS swaps since the first
    draw with none found,
    or where the calls up to there are refused (the conversion then says
    so, as without this scan). The GL state alone, up to there, its draws
    not run and no frame opened. A game's frames are that window's;
    another's draws (a warm-up) and swaps and clears (a splash) before it
    end no frame and set no screen size (round 15's R15-3). The converter
    keeps the rule after that (swaps_main_drawable)."""
    probe = Converter(args, False, None)
    probe.first_frame, probe.last_frame, probe.active = 1 << 62, None, False   # (no frame is converted)
    drawn, swaps, in_begin, any_draw, seen = [], {}, False, False, 0
    calls = read_calls(args.trace)
    try:
        for call in calls:
            name, flags = base_name(call[1]), call[4]
            if in_begin or name in DRAWING:
                if probe.current_drawable is None:
                    return None
                any_draw = True
                if not probe.s.draw_fbo and probe.current_drawable not in probe.pbuffers \
                        and probe.current_drawable not in drawn:
                    drawn.append(probe.current_drawable)
                if not probe.core:   # (glBegin and glEnd are nothing in a core profile)
                    in_begin = name != "glEnd" and (in_begin or name == "glBegin")
            else:
                probe.last_call = call[0]
                probe.handle(call)
            if isinstance(flags, int) and flags & CALL_FLAG_END_FRAME:
                swapped = swapped_drawable(call[1], call[2], call[0])
                if drawn and swapped == drawn[0]:
                    return swapped
                if swapped in drawn:
                    swaps[swapped] = swaps.get(swapped, 0) + 1
                    if swaps[swapped] >= 2:
                        return swapped
                elif any_draw and not drawn and swapped not in probe.pbuffers:
                    return swapped   # drawn into framebuffer objects alone, then shown
                seen += any_draw   # (a splash's clears and swaps, however many, before any draw)
                if seen >= FIRST_WINDOW_SWAPS:
                    return None
    except ConvertError:
        return None
    finally:
        close_calls(calls, probe)
    return None


def convert_in(args, tmpdir, listing, ids, report, last=False):
    check_input_file(args.trace)
    check_paths(args)
    if getattr(args, "reduced_out", None) and is_reduced_capture(args.trace):
        raise ConvertError("--reduced-out: the capture is already a reduced capture")
    conv = new_converter(args, None)   # reads the selection file: refused before any output exists
    if listing:
        conv.listing = []
    summary_path = os.path.join(tmpdir, "summary.jsonl")
    cmd = [raster_program(), "--trace", args.output, "--summary", summary_path, "--name", args.trace]
    if args.depth_out:
        cmd += ["--depth-out", args.depth_out]
        if getattr(args, "llvmpipe_depth_out", None):
            cmd += ["--llvmpipe-depth-out", args.llvmpipe_depth_out]
    if ids:
        cmd += ["--ids-out", ids[0], "--ids-frame", str(ids[1])]
    outputs = []   # streamed outputs: committed at the end, abandoned on any failure
    proc = None
    try:
        if getattr(args, "stream_out", None):
            conv.stream_copy = SafeText(args.stream_out, binary=True)
            outputs.append(conv.stream_copy)
        if args.geometry:
            conv.geo = SafeText(args.geometry)
            outputs.append(conv.geo)
            conv.geo.write("rbcd-geometry 2\n")
        reduced = None
        if getattr(args, "reduced_out", None):
            reduced = ReducedWriter(args.reduced_out, conv.source_bytes)
            outputs.append(reduced)
        started = time.time()
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
        proc.rbcd_outputs = (args.output, started)   # (raster_result: what it leaves if killed outright)
        conv.raster, conv.raster_proc = proc.stdin, proc
        run_calls(args, conv, reduced)
        frames = finish(args, conv, proc, summary_path)   # -o and --summary are in place from here
        try:
            if report is not None:
                report(frames, conv)
            # The trace and summary stand; the other outputs are renamed into
            # place now, and from here a signal ends nothing: the run has
            # succeeded (an interrupt had left them all in place, exit 130).
            if last:
                ignore_signals()
            for o in outputs:
                o.commit()
        except BaseException:
            remove_trace(args.output)
            if args.summary:
                remove_trace(args.summary)
            raise
        outputs = []
        return frames, conv
    except RasterStopped:
        proc.stdin = None
        raster_result(proc, args.trace)
        raise ToolError("rbcd-gl-raster stopped reading without a message")
    finally:
        if outputs:
            stop(proc)
            for o in outputs:
                o.abandon()


def run_calls(args, conv, reduced):
    """Every call of the capture into the converter, to the last frame asked for."""
    calls = read_calls(args.trace)
    conv.writes_reduced = reduced is not None
    try:
        for call in calls:
            conv.last_call = call[0]
            conv.handle(call)
            if reduced:
                # After the call: a draw carries the textures its vertex shader read.
                reduced.call(call, conv.take_reduced_textures())
            if conv.last_frame is not None and conv.frame > conv.last_frame:
                check_rest(calls)
                break
            if args.snapshots and conv.active and call[0] in args.snapshots:
                conv.open_frame(call[0])
                conv.emit(b"S" + struct.pack("<Q", call[0]))
    finally:
        close_calls(calls, conv)
    if conv.s.begin_mode is not None:
        raise ConvertError("the capture ends between glBegin and glEnd")
    if conv.out_frame < 0:
        raise ConvertError(f"the capture has {conv.frame} frames: --frames selects none" if conv.frame
                           else "the capture has no frame (no buffer swap)")
    if conv.frame_open:
        # A last frame without its swap is not converted (rbcd-gl-raster
        # drops a frame the stream leaves open): the trace ends at the last
        # whole frame.
        conv.partial_frame_dropped = True
        if conv.out_frame == 0:
            raise ConvertError("the capture draws but never swaps buffers: no whole frame to convert")


def finish(args, conv, proc, summary_path):
    """The rasterizer's end and its summary (with the converter's counts),
    written to --summary."""
    conv.emit(b"Z")
    try:
        proc.stdin.close()
    except BrokenPipeError:
        raise RasterStopped()
    raster_result(proc, args.trace)
    with open(summary_path) as f:
        lines = f.read().splitlines()
    lines = [with_fragment_effects(line, conv.fragment_effects.get(i)) for i, line in enumerate(lines)]
    frames = [json.loads(line) for line in lines]
    if args.summary:
        try:
            write_output(args.summary, "".join(line + "\n" for line in lines), "summary")
        except BaseException:
            remove_trace(args.output)   # nothing left that looks complete
            raise
    return frames


def remove_trace(path):
    """The trace rbcd-gl-raster committed (or the summary written after it),
    when a later output or the report fails: a regular file only (a device
    or FIFO is never unlinked)."""
    try:
        if os.path.isfile(path) and not os.path.islink(path):
            os.unlink(path)
    except OSError:
        pass


def stop(proc):
    """A failed run's rasterizer: SIGTERM (it removes its temporaries on it;
    SIGKILL would leave them), then what is still buffered for it dropped."""
    if proc is None:
        return
    if proc.poll() is None:
        proc.terminate()
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    try:
        if proc.stdin:
            proc.stdin.close()
    except OSError:
        pass


def with_fragment_effects(line, effects):
    """A frame's summary line with the counts of its draws under fragment
    shaders that can discard or write gl_FragDepth (docs/gl-capture.md),
    added at its end; a frame without draws under a program is left as
    rbcd-gl-raster wrote it."""
    if not effects or not line.endswith("}"):
        return line
    extra = ",".join(f'"{k}":{effects[k]}' for k in FRAGMENT_EFFECT_KEYS)
    return line[:-1] + "," + extra + "}"


# rbcd-gl-raster's exit status when a signal ended it: 128 + the signal.
INTERRUPTED = {128 + signal.SIGINT, 128 + signal.SIGTERM, 128 + signal.SIGHUP}


def raster_result(proc, trace):
    """Raises rbcd-gl-raster's own message once it has exited non-zero: bad
    input (exit 2) as ConvertError, anything else as ToolError."""
    err = proc.stderr.read().decode("utf-8", "replace")
    rc = proc.wait()
    if rc == 0:
        return
    if rc in INTERRUPTED or -rc in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP):
        # A signal to the process group (Ctrl-C) ended it first: the run
        # was interrupted, not the rasterizer broken.
        raise KeyboardInterrupt
    if rc < 0:
        if getattr(proc, "rbcd_outputs", None):
            remove_left_temporaries(*proc.rbcd_outputs)   # (the one it wrote -o through)
        raise ToolError(f"{printable(trace)}: rbcd-gl-raster was ended by signal {-rc}; no output written")
    # Its one message whole: a path it names may hold a newline (escaped
    # when the message is printed; its first line alone had cut the path).
    line = err.strip()[:4096] or f"rbcd-gl-raster exited {rc}"
    line = line.removeprefix("rbcd-gl-raster: ").removeprefix(trace + ": ")
    if rc == 2:
        raise ConvertError(line)
    raise ToolError(line)


def report(frames, conv, out):
    """The run's figures, on `out`: standard error when an output is standard output."""
    n = len(frames)
    frags = sum(f["fragments"] for f in frames)
    culled = sum(f["culled"] for f in frames)
    other = sum(f["other"] for f in frames)
    objs = sum(len(f["objects"]) for f in frames)
    print(f"{n} frames: {objs / max(n, 1):.1f} collisionable objects, {frags / max(n, 1):.0f} collisionable "
          f"fragments ({100.0 * culled / max(frags, 1):.1f}% tagged c) and {other / max(n, 1):.0f} other "
          f"fragments a frame", file=out)
    if conv.last_frame is not None and conv.frame <= conv.last_frame:
        # (round 37's N4: --frames 0:99 of a one-frame capture said nothing)
        print(f"--frames {conv.first_frame}:{conv.last_frame} reaches past the capture's last frame "
              f"({conv.frame - 1}): {n} converted", file=out)
    if conv.partial_frame_dropped:
        print("the capture stops before its last buffer swap: that frame is not converted", file=out)
    if conv.ignored_prims:
        print(f"{conv.ignored_prims} point and line draws not rasterized (no area)", file=out)
    fx = conv.fragment_effects.values()
    if any(e["discard_draws"] or e["frag_depth_draws"] for e in fx):
        print(f"draws whose fragment shader can discard: {sum(e['discard_draws'] for e in fx)} "
              f"({sum(e['discard_collisionable'] for e in fx)} collisionable); writing gl_FragDepth: "
              f"{sum(e['frag_depth_draws'] for e in fx)} ({sum(e['frag_depth_collisionable'] for e in fx)} "
              "collisionable); all their fragments are kept", file=out)
    if conv.rejected_draws:
        no, why = conv.rejected_draws[0]
        print(f"{len(conv.rejected_draws)} draws are GL errors as the capture set them up and draw nothing "
              f"(the first: call {no}, {why})", file=out)
    wrong = [(c, why) for _, c, call, why, _ in conv.last_3d_draws if why is not None]
    if wrong:
        print(f"{len(wrong)} frames whose camera-pass depth buffer the converter's cannot be compared with (their "
              f"trace is whole; --check-depth leaves them out): the first, frame {wrong[0][0]}: {wrong[0][1]}",
              file=out)
    if conv.viewport_past[0]:
        n, no, (vx, vy, vw, vh) = conv.viewport_past
        w, h = conv.screen
        print(f"{n} draws with a viewport reaching past the {w} x {h} screen, cut to it as GL cuts them for a "
              f"window of that size (the first: call {no}, viewport {vx}, {vy}, {vw} x {vh}); a window resized, or "
              "made anew with the same context, keeps no size in the capture: give --screen W H if it had another",
              file=out)
    if conv.offscreen_draws:
        print(f"{conv.offscreen_draws} draws into other targets than the camera pass left out (docs/gl-capture.md)", file=out)


# ---------------------------------------------------------------- listing a frame's draws
