"""rbcd-gl2rbt's command line."""
import argparse
import errno
import os
import re
import signal
import sys
import threading

from ..cli import (ArgumentParser, Once, OnceFlag, UsageError, WriteError, ascii_int, escape, exception_text,
                   finite_float, remove_temporaries, to_standard_output)
from ..startup import HANDLED, ignore_signals, kept
from .errors import LAST_WORD, ConvertError, ToolError, printable

PROG = "rbcd-gl2rbt"
# A refusal names what it refused last (the call, then the object, then the
# reason): the converter's own message is written whole, its parts quoting
# input already bounded where it was made; past MESSAGE_LIMIT characters (a
# path may be 4 KB) its middle is cut, its head and its end kept.
MESSAGE_LIMIT = 2000


def message(e):
    """The converter's own error (ConvertError, ToolError, an output's
    UsageError or WriteError) as one escaped line of at most MESSAGE_LIMIT
    characters (and the cut's " ... ")."""
    text, half = exception_text(e, MESSAGE_LIMIT), MESSAGE_LIMIT // 2
    if len(text) > MESSAGE_LIMIT:   # cut before escaping: the work stays bounded
        text = text[:half] + " ... " + text[-half:]
    text = escape(text)
    return text if len(text) <= MESSAGE_LIMIT else text[:half] + " ... " + text[-half:]


def parse_frames(text):
    m = re.fullmatch(r"([0-9]{1,18}):([0-9]{0,18})", text or "")
    if not m:
        raise ConvertError(f"--frames: '{printable(text)}' is not A:B (first and last frame, at most 18 digits "
                           "each; B may be empty)")
    a = int(m.group(1))
    b = int(m.group(2)) if m.group(2) else None
    if b is not None and b < a:
        raise ConvertError(f"--frames: {a}:{b} selects no frame")
    return a, b


def parse_args(argv):
    ap = ArgumentParser(prog=PROG, description="A captured OpenGL stream (apitrace) into the unit's input.")
    ap.add_argument("trace", help="the apitrace capture (.trace)")
    ap.add_argument("-o", "--output", action=Once,
                    help="the fragment trace to write (.rbt; .rbt.zst or .rbt.gz compressed)")
    ap.add_argument("--geometry", action=Once, help="each frame's collisionable geometry for rbcd-cpucd --geometry")
    ap.add_argument("--frames", action=Once, default="0:",
                    help="A:B, the capture's frames to convert (B included; default all)")
    ap.add_argument("--screen", action=Once, nargs=2, type=ascii_int, metavar=("W", "H"),
                    help="the screen (default: the window's size when the first converted frame starts)")
    ap.add_argument("--tile", action=Once, nargs=2, type=ascii_int, default=[16, 16], metavar=("W", "H"))
    ap.add_argument("--depth-bits", action=Once, type=ascii_int, default=24)
    ap.add_argument("--select", action=Once, help="selection rules (TOML) for programs that do not tag their objects")
    ap.add_argument("--summary", action=Once, help="one JSON line of figures per frame")
    ap.add_argument("--reduced-out", action=Once, metavar="FILE.xz",
                    help="also write the reduced capture: the calls that can change the unit's input, "
                         "xz-compressed; converting it gives the same outputs as the capture")
    ap.add_argument("-q", "--quiet", action=OnceFlag, help="no summary on stdout")
    ap.add_argument("--list-draws", action=Once, type=ascii_int, metavar="FRAME",
                    help="list every draw of the capture's frame FRAME and what it became")
    ap.add_argument("--image", action=Once, help="with --list-draws: a PNG of the frame, each visible draw labelled")
    ap.add_argument("--check-depth", action=OnceFlag,
                    help="compare the depth buffer at each checked frame's last 3D draw with Mesa's (glretrace)")
    ap.add_argument("--check-frames", action=Once, type=ascii_int,
                    help="with --check-depth: frames to check, spread over --frames (default 5)")
    ap.add_argument("--check-timeout", action=Once, type=ascii_int, default=600,
                    help="seconds per glretrace replay (default 600)")
    ap.add_argument("--min-agreement", action=Once, type=finite_float,
                    help="with --check-depth: exit 1 below this percentage (default 99)")
    ap.add_argument("--depth-out", action=Once, help=argparse.SUPPRESS)
    # With --check-depth: keep the depth dumps and Mesa's depth buffers in DIR,
    # and take Mesa's from there when present (a replay takes minutes a frame).
    ap.add_argument("--check-keep", action=Once, help=argparse.SUPPRESS)
    ap.add_argument("--stream-out", action=Once, help=argparse.SUPPRESS)   # a copy of the draw stream (fuzz seeds)
    ap.add_argument("--snapshot-calls", action=Once, help=argparse.SUPPRESS)
    return ap.parse_args(argv)


def run(args):
    """The command, with the exit status of the module's docstring."""
    try:
        np = require_numpy()
        # Non-finite values are checked where they matter and refused naming
        # the call: numpy's warnings would only repeat them, before the line.
        np.seterr(all="ignore")
        from . import depth_check, listing, raster   # they compute with numpy
        for opt, value in (("-o", args.output), ("--geometry", args.geometry), ("--select", args.select),
                           ("--summary", args.summary), ("--reduced-out", args.reduced_out), ("--image", args.image),
                           ("--depth-out", args.depth_out), ("--check-keep", args.check_keep),
                           ("--stream-out", args.stream_out)):
            if value == "":
                raise ConvertError(f"{opt}: an empty path")
        for attr in ("geometry", "summary", "reduced_out"):
            # "-" is standard output, as for -o and --image (a file named
            # "-" had been written, while the report moved to stderr).
            if getattr(args, attr) == "-":
                setattr(args, attr, "/dev/stdout")
        to_stdout = [opt for opt, value in (("-o", args.output), ("--geometry", args.geometry), ("--summary", args.summary),
                                            ("--reduced-out", args.reduced_out), ("--image", args.image))
                     if value in ("-", "/dev/stdout")]
        if to_stdout:
            try:
                os.fstat(1)
            except OSError:
                # (the run's environment, not its input: as a write that fails)
                raise ToolError(f"{to_stdout[0]}: standard output is closed; no output written") from None
        if not args.check_depth:
            for opt, value in (("--check-frames", args.check_frames), ("--min-agreement", args.min_agreement)):
                if value is not None:
                    raise ConvertError(f"{opt} goes with --check-depth")
        if args.list_draws is not None or args.check_depth:
            # The conversion's outputs are not written there: given, they
            # would be passed over.
            mode = "--list-draws" if args.list_draws is not None else "--check-depth"
            if args.list_draws is not None and args.check_depth:
                raise ConvertError("--list-draws and --check-depth are two commands: give one")
            for opt, value in (("-o", args.output), ("--geometry", args.geometry), ("--summary", args.summary),
                               ("--reduced-out", args.reduced_out)):
                if value is not None:
                    raise ConvertError(f"{opt} goes with a conversion, not with {mode}")
        if args.list_draws is not None:
            if args.list_draws < 0:
                raise ConvertError("--list-draws: FRAME must be a frame number")
            return listing.list_draws(args)
        if args.image:
            raise ConvertError("--image goes with --list-draws")
        # (It bounds the read-back replay of a conversion too.)
        if not 1 <= args.check_timeout <= 1 << 31:
            raise ConvertError("--check-timeout must be from 1 to 2^31 (seconds)")
        if args.check_depth:
            args.frame_range = parse_frames(args.frames)
            args.snapshots = set()
            args.check_frames = 5 if args.check_frames is None else args.check_frames
            args.min_agreement = 99.0 if args.min_agreement is None else args.min_agreement
            if args.check_frames < 1:
                raise ConvertError("--check-frames must be at least 1")
            if not 0.0 <= args.min_agreement <= 100.0:   # NaN fails both
                raise ConvertError("--min-agreement must be a percentage, 0 to 100")
            return depth_check.check_depth(args)
        if not args.output:
            raise ConvertError("-o OUT is required")
        args.frame_range = parse_frames(args.frames)
        if not 1 <= args.depth_bits <= 32:
            raise ConvertError("--depth-bits must be 1..32")
        if args.screen and not all(1 <= v <= 8192 for v in args.screen):
            raise ConvertError("--screen: sides must be 1..8192")
        if not all(1 <= v <= 8192 for v in args.tile):
            raise ConvertError("--tile: sides must be 1..8192")
        try:
            args.snapshots = set(int(x) for x in args.snapshot_calls.split(",")) if args.snapshot_calls else set()
        except ValueError:
            raise ConvertError("--snapshot-calls: not a list of call numbers")
        raster.convert(args, report=None if args.quiet else write_report, last=True)
        return 0
    except ConvertError as e:
        sys.stderr.write(f"{PROG}: {printable(args.trace)}: {message(e)}\n")
        return 2
    except UsageError as e:   # an output rbcd.cli could not write
        sys.stderr.write(f"{PROG}: {message(e)}\n")
        return 2
    except (ToolError, WriteError) as e:   # WriteError: --summary, --image (rbcd.cli.write_output)
        sys.stderr.write(f"{PROG}: {message(e)}\n")
        return 1
    except Exception as e:   # noqa: BLE001: the promise is one line, whatever failed
        if isinstance(e, MemoryError) or isinstance(e, OSError) and e.errno == errno.ENOMEM or \
                isinstance(e, RuntimeError) and "can't start new thread" in str(e):
            # Past the process's memory limit (ulimit -v) before any of the
            # documented bounds (docs/gl-capture.md, limits) refused the
            # input: an allocation or a mapping failed.
            why = printable(e, 200) if str(e).startswith("the address-space limit") else \
                "the process's memory limit is below what the capture needs within the documented limits"
            sys.stderr.write(f"{PROG}: {printable(args.trace)}: out of memory ({why}); no output written\n")
            return 1
        if INTERRUPTED.is_set():
            # A signal's KeyboardInterrupt wrapped by what it was raised in
            # (ctypes converting a PyOpenGL call's arguments: ArgumentError).
            raise KeyboardInterrupt
        sys.stderr.write(f"{PROG}: internal error: {type(e).__name__}: {printable(e, 300)}\n")
        return 1


def write_report(frames, conv):
    """The run's report, written before the outputs are committed: one that
    cannot be written (standard output full or closed) fails the run as an
    output's write does, and no output is left."""
    from . import raster
    outputs = [conv.args.output, conv.args.geometry, conv.args.summary, conv.args.reduced_out]
    stream = sys.stderr if to_standard_output(outputs) else sys.stdout
    if stream is None:   # closed when the program started
        raise ToolError("the report: write failed: standard output is closed; no output written")
    try:
        raster.report(frames, conv, stream)
        stream.flush()
    except OSError as e:
        raise ToolError(f"the report: write failed: {printable(e.strerror or e)}; no output written")


def require_numpy():
    """The converter's stages compute with numpy: its absence is one line.
    A signal while it loads is taken once it has loaded (HELD)."""
    HELD.set()
    try:
        import numpy
    except ImportError:
        numpy = None
    finally:
        HELD.clear()
    if INTERRUPTED.is_set():   # whether numpy loaded or not
        raise KeyboardInterrupt
    if numpy is None:
        raise ToolError("numpy is not installed (Debian: python3-numpy)")
    return numpy


INTERRUPTED = threading.Event()   # a handled signal came
# Set while numpy loads. Its C modules import one another from C (numpy's
# import_array), which prints a KeyboardInterrupt raised there as a
# traceback before it turns it into an ImportError: a signal then only
# marks the run interrupted, and require_numpy raises it once numpy has
# loaded (a fraction of a second).
HELD = threading.Event()


def on_signal(signum, frame):
    """SIGINT, SIGTERM or SIGHUP: the run unwinds through its finally blocks
    (temporaries and outputs removed, rbcd-gl-raster and the shading child
    stopped) and main says so; another signal then changes nothing (it had
    cut that clean-up short, or ended the process as Python finished).
    While Mesa works the watchdog thread ends the run (mesa.py); while
    numpy loads, require_numpy once it has loaded (HELD)."""
    ignore_signals()
    INTERRUPTED.set()
    if not HELD.is_set():
        raise KeyboardInterrupt


def main(argv=None):
    from .shading import stop_children   # here, not in the clean-up, where memory may have run out
    for sig in HANDLED:
        # SIGINT or SIGHUP ignored when the program started (a script's
        # background job, nohup) stays ignored, here and in the children
        # (rbcd-gl-raster keeps it so too).
        if kept(sig):
            signal.signal(sig, on_signal)
    trace = None
    try:
        try:
            args = parse_args(sys.argv[1:] if argv is None else argv)
        except UsageError as e:
            sys.stderr.write(f"{PROG}: {printable(str(e))}\n")
            return 2
        except WriteError as e:   # (--help onto a full device)
            sys.stderr.write(f"{PROG}: {printable(str(e))}\n")
            return 1
        trace = args.trace
        return run(args)
    except KeyboardInterrupt:
        if not LAST_WORD.acquire(blocking=False):
            threading.Event().wait(60)   # the watchdog says it and ends the process
        sys.stderr.write(f"{PROG}: {printable(trace) + ': ' if trace is not None else ''}interrupted\n")
        return 130
    finally:
        ignore_signals()   # the run has ended: a signal from here changes nothing
        stop_children()
        remove_temporaries()


if __name__ == "__main__":
    sys.exit(main())
