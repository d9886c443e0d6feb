"""--check-depth: the converted frames' depth against Mesa's (glretrace -D)."""
import base64
import os
import re
import shutil
import subprocess

import numpy as np

from ..cli import temporary_folder, unregister_temporary
from .capture import check_input_file, close_calls, read_calls
from .errors import ConvertError, ToolError, printable
from .glretrace import end_replay, glretrace_command, preload_library, start_replay
from .raster import convert, new_converter
from .reduced import is_reduced_capture

READBACK = "rbcd-es-depth-readback.so"


def es_readback_library():
    """gl/es_depth_readback.c's library."""
    return preload_library(READBACK, "--check-depth on an OpenGL ES capture", "OpenGL ES", "libgles-dev")


def mesa_depth_at(trace, call, timeout, es=False, tmpdir=None):
    """Mesa's depth buffer after `call` (glretrace -D), as (width, height, rows
    from the top of float32 values in [0, 1]). An OpenGL ES capture's is
    read back through gl/es_depth_readback.c, preloaded into glretrace
    alone (not into Xvfb). The replay's processes (xvfb-run's Xvfb too) are
    ended on every path, a signal's included (glretrace.end_replay)."""
    where = f"{printable(trace)}: call {call}: Mesa's replay (glretrace -D {call})"
    cmd = glretrace_command(["-D", str(call), trace], "--check-depth",
                            preload=es_readback_library() if es else None)
    # llvmpipe rasterizes on threads, and its vertex shaders (run at the
    # draw, on the calling thread) do not wait for them: a draw's vertex
    # shader may read a texture level an earlier glGenerateMipmap or render
    # to texture has not written yet (measured: the previous frame's level 1
    # in 7 of 15 replays). With one thread each draw is rasterized before
    # the next starts.
    proc = start_replay(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                        # (xvfb-run's temporary folder in the check's: removed with it)
                        env=dict(os.environ, LP_NUM_THREADS="0", **({"TMPDIR": tmpdir} if tmpdir else {})))
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        raise ToolError(f"{where} did not finish in {timeout} s (--check-timeout)")
    finally:
        end_replay(proc)
        proc.stdout.close()
        proc.stderr.close()
    text = out.decode("utf-8", "replace")
    # A lenient reading: the state is JSON, but the base64 text carries
    # newlines, so the depth image is found by its keys, in the bound draw
    # framebuffer's section: the window's depth buffer, or a framebuffer
    # object's depth (or depth and stencil) attachment.
    section = text.find('"framebuffer": {')
    m = re.search(r'"GL_DEPTH_(?:COMPONENT|ATTACHMENT|STENCIL_ATTACHMENT)"\s*:\s*\{(.*?)"__data__"\s*:\s*"([^"]*)"',
                  text[max(section, 0):], re.S)
    if not m:
        raise ToolError(f"{where} dumped no depth buffer"
                        f" ({printable((err.decode('utf-8', 'replace').strip().splitlines() or ['no message'])[-1])})")
    data = base64.b64decode(re.sub(r"\s+", "", m.group(2)).replace("\\n", ""))
    # PFM: "Pf\nW H\nSCALE\n", then rows from the bottom; the floats are
    # little endian whatever the scale's sign says (as glretrace writes them).
    parts = data.split(b"\n", 3)
    if len(parts) < 4 or parts[0] != b"Pf":
        raise ToolError(f"{where}: the depth image is not a one-channel PFM")
    w, h = (int(x) for x in parts[1].split())
    vals = np.frombuffer(parts[3], dtype="<f4", count=w * h).reshape(h, w)
    return w, h, vals   # rows from the top, as glretrace writes them (not PFM's bottom-up)


def named(trace):
    """A message's start naming the capture, as the converter's others do."""
    return f"{printable(trace)}: " if trace is not None else ""


def window_of(mesa, w, h, frame, trace=None):
    """The screen's w x h pixels of Mesa's depth dump (rows from the top).
    glretrace grows its window to hold every viewport the capture sets
    (glViewport(-10, -20, 84, 94) on a 64x64 window gives 74x74): the
    screen is then its lower left part, GL's origin being the lower left."""
    mh, mw = mesa.shape
    if mw < w or mh < h:
        raise ToolError(f"{named(trace)}frame {frame}: Mesa's depth buffer is {mw}x{mh}, smaller than the screen "
                        f"{w}x{h}")
    return mesa[mh - h:, :w]


def read_depth_file(path, trace=None):
    """rbcd-gl-raster's depth dump: the depths, and where they were last
    written by a draw whose fragment shader can discard or write depth."""
    with open(path, "rb") as f:
        head = f.readline().split()
        if len(head) != 5 or head[:2] != [b"rbcd-depth", b"2"]:
            raise ToolError(f"{named(trace)}{printable(path)}: not a depth dump")
        w, h, bits = int(head[2]), int(head[3]), int(head[4])
        vals = np.frombuffer(f.read(4 * w * h), dtype="<u4", count=w * h).reshape(h, w)
        marks = np.frombuffer(f.read(w * h), dtype="u1", count=w * h).reshape(h, w).astype(bool)
    return w, h, bits, vals, marks


def pct(ok, n):
    return 100.0 * ok / n if n else 100.0


def bound_note(counts):
    """Said when a draw under a fragment shader that can discard or write
    depth wrote some pixel's depth last."""
    cov, ok, cov_out, ok_out, bound = (int(c) for c in counts)
    if cov_out == cov:
        return ""
    return (f"; consistent {pct(ok_out + bound, cov):.2f}%: {pct(ok_out, cov_out):.2f}% of the {cov_out} outside "
            f"those a discarding fragment shader wrote last agree, and on {pct(bound, cov - cov_out):.2f}% of "
            f"those {cov - cov_out} Mesa's depth lies at or behind the converter's bound")


def compare(ours, marks, bits, mesa, step):
    """Counts of one frame (ours: `bits`-bit depths; step: one step of the
    buffer Mesa drew into): covered pixels (drawn in either buffer), those
    agreeing within one step; the same outside the marked pixels; the marked
    pixels where Mesa's depth lies at or behind ours (an upper bound there)."""
    ours01 = ours.astype(np.float64) / ((1 << bits) - 1)
    mesa64 = mesa.astype(np.float64)
    covered = (ours < (1 << bits) - 1) | (mesa < 1.0)
    agree = np.abs(ours01 - mesa64) <= step * 1.0001 + 1e-7
    bound = mesa64 >= ours01 - (step * 1.0001 + 1e-7)
    return np.array([covered.sum(), (agree & covered).sum(), (covered & ~marks).sum(),
                     (agree & covered & ~marks).sum(), (bound & covered & marks).sum()], dtype=np.int64)


LLVMPIPE = "with llvmpipe's arithmetic on the converter's geometry"
# The largest window the check lets glretrace grow to (4096 x 4096): a
# window of 4000 x 4000 peaks at 690 MB (glretrace's window and its depth
# dump as text, the comparison's arrays).
MAX_REPLAY_PIXELS = 1 << 24


def drawable_growth(call):
    """The size glretrace (11.1, glretrace.py) grows its window to at this
    call, while no framebuffer object is bound: glViewport's x + width and
    y + height, those of viewport 0 of the array and indexed forms, a
    blit's farther destination corner; None for other calls (and for
    values that are not numbers, which the conversion has refused)."""
    name, d = call[1], dict(call[2])
    try:
        if name == "glViewport":
            return d["x"] + d["width"], d["y"] + d["height"]
        if name in ("glViewportIndexedf", "glViewportIndexedfv") and d.get("index") == 0:
            x, y, w, h = (d["x"], d["y"], d["w"], d["h"]) if name.endswith("f") else d["v"][:4]
            return int(x + w), int(y + h)
        if name == "glViewportArrayv" and d.get("first") == 0 and d.get("count", 0) > 0:
            x, y, w, h = d["v"][:4]
            return int(x + w), int(y + h)
        if name in ("glBlitFramebuffer", "glBlitFramebufferEXT"):
            return max(d["dstX0"], d["dstX1"]), max(d["dstY0"], d["dstY1"])
    except (KeyError, TypeError, ValueError, OverflowError, IndexError):
        return None
    return None


def fixed_attribute(probe):
    """The call that gave an attribute of the bound vertex array object the
    type GL_FIXED while its binding holds a buffer, or None: glretrace's
    state dump (apitrace 11.1, dumpVertexAttributes: desktop GL only)
    asserts on such an attribute of the program in use, so Mesa's depth is
    not to be had at a draw with it bound. Any such attribute counts (the
    check's first pass does not link programs, and does not know which
    attributes the program reads)."""
    vao = probe.current_vao()
    for _, at in sorted(vao.attribs.items()):
        b = vao.bindings.get(at.binding)
        if at.type == "GL_FIXED" and b is not None and b.buffer and at.format_call is not None:
            return at.format_call
    return None


def check_depth(args):
    """Converts the selected frames with a depth snapshot at each frame's last
    draw with the depth test on, replays the capture to the same call with
    Mesa (glretrace -D) and prints, per frame, the share of covered pixels
    (drawn in either buffer) where the two depths agree within one step of
    depth_bits: with the converter's depths (GL's exact values), and with
    the depths llvmpipe's float32 arithmetic gives the converter's vertices
    and state on the same covered pixels (rbcd-gl-raster
    --llvmpipe-depth-out), which tells the driver's rounding from a
    difference of geometry or state."""
    check_input_file(args.trace)
    if is_reduced_capture(args.trace):
        raise ConvertError("--check-depth replays the capture with Mesa: give the capture itself, "
                           "not a reduced capture")
    # Pass 1: the calls, from the GL state alone, and the window glretrace
    # will grow to (refused past MAX_REPLAY_PIXELS before it runs).
    probe = new_converter(args, False)
    fixed = {}   # a depth-tested draw -> the GL_FIXED attribute's call it has bound (fixed_attribute)
    calls = read_calls(args.trace)
    try:
        for call in calls:
            probe.last_call = call[0]
            probe.handle(call)
            if probe.last_depth_draw == call[0] and not probe.es:
                at = fixed_attribute(probe)
                if at is not None:
                    fixed[call[0]] = at
            grown = drawable_growth(call) if not probe.s.draw_fbo else None
            if grown and grown[0] * grown[1] > MAX_REPLAY_PIXELS:
                raise ConvertError(f"call {call[0]}: {printable(call[1])} would make glretrace's window "
                                   f"{grown[0]} x {grown[1]} pixels, more than the check's {MAX_REPLAY_PIXELS} "
                                   "(docs/gl-capture.md, the check against Mesa)")
            if probe.last_frame is not None and probe.frame > probe.last_frame:
                break
    finally:
        close_calls(calls, probe)
    try:   # missing: said before the conversion, not after it
        glretrace_command([], "--check-depth")
        if probe.es:
            es_readback_library()
    except ToolError as e:
        raise ToolError(f"{named(args.trace)}{e}") from None
    frames = [(o, c, call, bits) for o, c, call, wrong, bits in probe.last_3d_draws
              if call is not None and wrong is None and call not in probe.read_elsewhere and call not in fixed]
    elsewhere = [c for _, c, call, wrong, _ in probe.last_3d_draws if call in probe.read_elsewhere and wrong is None]
    if elsewhere:
        # Mesa's depth of such a frame is not to be had: glretrace reads a
        # window's depth through the context's read drawable, which
        # glXMakeContextCurrent or eglMakeCurrent made another window.
        print(f"{len(elsewhere)} frames not checked: their last depth-tested draw's context reads from another "
              f"window than it draws into, and Mesa's replay reads the depth through it (the first, frame "
              f"{elsewhere[0]})")
    unreadable = [(c, fixed[call]) for _, c, call, wrong, _ in probe.last_3d_draws
                  if call in fixed and wrong is None and call not in probe.read_elsewhere]
    if unreadable:
        print(f"{len(unreadable)} frames not checked: their last depth-tested draw has a GL_FIXED vertex attribute "
              f"bound, on which glretrace's state dump aborts (the first, frame {unreadable[0][0]}: call "
              f"{unreadable[0][1][0]}: {printable(unreadable[0][1][1])})")
    unfollowed = [(c, wrong) for _, c, call, wrong, _ in probe.last_3d_draws if call is not None and wrong is not None]
    if unfollowed:
        # The converter's one camera-pass depth buffer did not hold what
        # the frame's last depth-tested draw's buffer held, or that buffer
        # is multisampled (camera_depth.py): the frame is not checked.
        print(f"{len(unfollowed)} frames not checked: the converter's depth buffer cannot be compared with their "
              f"camera pass's (the first, frame {unfollowed[0][0]}: {unfollowed[0][1]})")
    # glretrace replays a capture's first frame wrongly at times (seen: the
    # test program's first frame replays without its clear): it is checked
    # only when it is the one frame asked for (--frames 0:0), not in place
    # of later frames left out.
    first_only = False
    if frames and frames[0][1] == 0 and tuple(getattr(args, "frame_range", (0, None)) or (0, None)) != (0, 0):
        frames = frames[1:]
        first_only = not frames
    if not frames and unreadable:
        no, name = unreadable[0][1]
        raise ConvertError(f"call {no}: {printable(name)}: a GL_FIXED vertex attribute, bound at frame "
                           f"{unreadable[0][0]}'s last depth-tested draw: glretrace's state dump of a desktop GL "
                           "context aborts on it, and no selected frame is left to check (docs/gl-capture.md, the "
                           "check against Mesa)")
    if first_only:
        raise ConvertError("only frame 0 draws with the depth test on into a depth buffer the converter follows "
                           "and Mesa's replay reads back, and glretrace replays a capture's first frame wrongly at "
                           "times, so its agreement may mean nothing: --frames 0:0 checks it all the same "
                           "(docs/gl-capture.md, the check against Mesa)")
    if not frames:
        raise ConvertError("no selected frame draws with the depth test on into a depth buffer the converter "
                           "follows and Mesa's replay reads back: nothing to check")
    if len(frames) > args.check_frames:
        step = len(frames) / args.check_frames
        frames = [frames[int(i * step)] for i in range(args.check_frames)]
    keep = getattr(args, "check_keep", None)
    if keep:
        os.makedirs(keep, exist_ok=True)
    tmp = keep or temporary_folder("rbcd-gl2rbt-check.")
    try:
        args.output = os.path.join(tmp, "check.rbt")
        args.geometry = args.summary = None
        args.depth_out = os.path.join(tmp, "depth")
        args.llvmpipe_depth_out = os.path.join(tmp, "llvmpipe")
        args.snapshots = {call for _, _, call, _ in frames}
        convert(args)
        total = np.zeros(5, dtype=np.int64)   # covered, agreeing; the same outside marked pixels; bound holds
        total_lp = np.zeros(5, dtype=np.int64)   # the same against the llvmpipe emulation
        for out_frame, cap_frame, call, depth_bits in frames:
            w, h, bits, ours, marks = read_depth_file(f"{args.depth_out}.{out_frame}.depth", args.trace)
            _, _, _, lp, lp_marks = read_depth_file(f"{args.llvmpipe_depth_out}.{out_frame}.depth", args.trace)
            cached = os.path.join(keep, f"mesa.{call}.npy") if keep else None
            if cached and os.path.exists(cached):
                mesa = np.load(cached)
            else:
                _, _, mesa = mesa_depth_at(args.trace, call, args.check_timeout, probe.es, tmp)
                if cached:
                    np.save(cached, mesa)
            mesa = window_of(mesa, w, h, cap_frame, args.trace)
            # Where a draw under a discarding fragment shader wrote our depth
            # last, ours is an upper bound: Mesa's lies at it or behind it.
            # One step of the buffer Mesa drew into (a 16-bit attachment's
            # values are rounded to its bits, the trace's to its own).
            step = 1.0 / ((1 << depth_bits) - 1)
            counts = compare(ours, marks, bits, mesa, step)
            counts_lp = compare(lp, lp_marks, bits, mesa, step)
            total += counts
            total_lp += counts_lp
            print(f"frame {cap_frame} (call {call}): {pct(counts[1], counts[0]):.2f}% of {counts[0]} covered "
                  f"pixels agree with Mesa{bound_note(counts)}")
            print(f"  {LLVMPIPE}: {pct(counts_lp[1], counts_lp[0]):.2f}% of {counts_lp[0]} covered pixels "
                  f"agree{bound_note(counts_lp)}")
        print(f"agreement: {pct(total[1], total[0]):.2f}% of {total[0]} covered pixels in {len(frames)} frames"
              f"{bound_note(total)}")
        print(f"agreement {LLVMPIPE}: {pct(total_lp[1], total_lp[0]):.2f}% of {total_lp[0]} covered pixels"
              f"{bound_note(total_lp)}")
        # Passes when the depths agree outside the pixels a draw under a
        # fragment shader that can discard or write depth wrote last, and
        # Mesa's lies at or behind the converter's (an upper bound by design,
        # docs/gl-capture.md) on those, on --min-agreement of all covered:
        # with GL's exact values, or with llvmpipe's rounding replayed (each
        # shows the converter's geometry and state to be the driver's; only
        # where both fall short is some of it not followed).
        best = max(pct(total[3] + total[4], total[0]), pct(total_lp[3] + total_lp[4], total_lp[0]))
        return 0 if best >= args.min_agreement else 1
    finally:
        if not keep:
            shutil.rmtree(tmp, ignore_errors=True)
            unregister_temporary(tmp)
