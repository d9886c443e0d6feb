"""The captured game-frame suite (docs/games.md): its committed entries
(workloads/games/NAME/: calls.xz, the reduced capture; capture.toml, how it was
captured and the checksums of what it converts into) checked, and expanded into
the fragment traces and geometry the figures run on.

    game-suite check [ENTRY...]                 the committed files against capture.toml, summary.jsonl's form
    game-suite expand -o DIR [-j N] [--frames K] [ENTRY...]
        DIR/NAME.rbt.zst, DIR/NAME.geo, DIR/NAME.summary.jsonl and
        DIR/NAME.capture (the entry's capture.toml) for each
        entry (default: every workloads/games/*/ with a capture.toml), by
        scripts/rbcd-gl2rbt, then checked against the recorded checksums. An
        entry whose outputs are already there and match is not converted
        again. --frames K converts only the first K frames (no checksum:
        the tests' cut-down inputs; K of all an entry's frames or more is
        the whole entry, checked). No output may be an input of an entry
        or a symlink (check_expand_outputs).

Exit 2 with one line on a malformed entry or argument (naming the file and
key; an option given twice or a number not in ASCII digits, naming the
option), 1 when a regenerated file does not match its checksum or the
converter fails; the outputs of a failed entry are removed.
"""
import concurrent.futures
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time
import tomllib

from rbcd.cli import (ArgumentParser, Once, UsageError, ascii_int, check_outputs, check_standard_output, escape,
                      main_wrapper, open_trace, parse_toml, read_input_text, say, remove_left_temporaries,
                      temporary_folder, trace_errors, unregister_temporary, write_output)

# The repository (python/rbcd/ -> ../..): the entries (workloads/games/), their
# selection rules (paths in capture.toml are relative to it) and the converter
# scripts/rbcd-gl2rbt. An entry's calls.xz is not installed, so game-suite runs
# from a source checkout only.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))

PROG = "game-suite"
MAX_TOML = 1 << 16
# A frame's line of the converter's summary, key by key in its order: what
# rbcd-gl-raster writes (gl/gl_raster_main.cpp, json_line), then, for a frame
# with draws under a program, the four counts rbcd-gl2rbt adds
# (rbcd.gl2rbt.raster.with_fragment_effects, glstate.draws.FRAGMENT_EFFECT_KEYS).
SUMMARY_KEYS = ("frame", "end_call", "draws", "tiles", "fragments", "culled", "other", "prims", "cprims", "objects")
EFFECT_KEYS = ("discard_draws", "discard_collisionable", "frag_depth_draws", "frag_depth_collisionable")


def reject_constant(name):
    raise ValueError(f"{name} is no figure")


class Mismatch(Exception):
    """A regenerated file differs from its recorded checksum, or the converter
    failed on a well-formed entry: exit 1."""


class Conversions:
    """The converters expand's workers run. When expand is interrupted
    (SIGINT, SIGTERM, SIGHUP) they are stopped at once (SIGTERM: each
    removes its temporaries) and the entries they were making are removed,
    so that nothing an interrupted run made looks complete."""

    def __init__(self):
        self.lock = threading.Lock()
        self.running = set()
        self.stopped = False

    def run(self, cmd, env=None):
        with self.lock:
            if self.stopped:
                raise Stopped()
            p = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 text=True, errors="replace", env=env)
            self.running.add(p)
        try:
            _, err = p.communicate()
        finally:
            with self.lock:
                self.running.discard(p)
        return p.returncode, err

    def stop(self):
        with self.lock:
            self.stopped = True
            for p in self.running:
                try:
                    p.terminate()
                except OSError:
                    pass


class Stopped(Exception):
    """A worker's entry abandoned: expand was interrupted."""


CONVERSIONS = Conversions()


def sha256_file(path, decompress=False):
    """The file's SHA-256; with decompress, of the trace's text (gzip or zstd)."""
    h = hashlib.sha256()
    with (open_trace(path) if decompress else open(path, "rb")) as f:
        while True:
            b = f.read(1 << 20)
            if not b:
                break
            h.update(b)
    return h.hexdigest()


def toml_string(text):
    """`text` as a TOML basic string, for capture-game.sh's capture.toml:
    quoted, with `"` and `\\` escaped and control characters (C0, DEL, C1)
    written as \\uXXXX, so that any Unicode text reads back as it was. Text
    that is not Unicode (a path of bytes that are not UTF-8, read through
    surrogateescape) has no TOML form: ValueError."""
    out = []
    for ch in text:
        cp = ord(ch)
        if 0xd800 <= cp <= 0xdfff:
            raise ValueError("not UTF-8 text")
        if ch in '"\\':
            out.append("\\" + ch)
        elif cp < 0x20 or 0x7f <= cp <= 0x9f:
            out.append(f"\\u{cp:04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def capture_strings(argv):
    """capture-game.sh's strings for capture.toml, each a TOML basic string
    on a line of its own (stdout, UTF-8): argv is WORK VALUE... -- COMMAND...;
    the values one a line, then the command as a TOML array, its work
    directory WORK written TMP (replaced as text, whatever the path holds).
    A string with no TOML form is one line on stderr naming it, exit 2."""
    work, rest = argv[0], argv[1:]
    sep = rest.index("--")

    def quoted(v):
        try:
            return toml_string(v)
        except ValueError as e:
            raise UsageError(f"'{escape(v)}': {e}: capture.toml (TOML) cannot record it") from None
    try:
        lines = [quoted(v) for v in rest[:sep]]
        lines.append("[" + ", ".join(quoted(a.replace(work, "TMP")) for a in rest[sep + 1:]) + "]")
    except UsageError as e:
        say("capture-game.sh", str(e))
        return 2
    sys.stdout.buffer.write("".join(line + "\n" for line in lines).encode("utf-8"))
    return 0


def summary_line_problem(obj, line):
    """What keeps `obj` (line, parsed) from being a frame's line as the
    converter writes it, or None."""
    keys = tuple(obj)
    if keys not in (SUMMARY_KEYS, SUMMARY_KEYS + EFFECT_KEYS):
        return "its keys are not " + ", ".join(SUMMARY_KEYS) + " and optionally " + ", ".join(EFFECT_KEYS) + \
            ", in that order"
    for k, v in obj.items():
        if k == "objects":
            if not (isinstance(v, list) and all(type(x) is int and 0 <= x < 1 << 32 for x in v)
                    and all(a < b for a, b in zip(v, v[1:]))):
                return "objects: not object ids (0 to 2^32 - 1) in increasing order, each once"
        elif not (type(v) is int and 0 <= v < 1 << 64):
            return f"{k}: not a count (an integer from 0 to 2^64 - 1)"
    if json.dumps(obj, separators=(",", ":")) != line:
        return "not compact JSON"
    return None


class Entry:
    def __init__(self, path):
        self.dir = path.rstrip("/")
        # The entry's name names its outputs: a folder's own name, not "",
        # "." or ".." (the root, or a path that ends there).
        self.name = os.path.basename(os.path.abspath(path))
        if self.name in ("", ".", "..") or not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.+-]{0,127}", self.name):
            raise UsageError(f"{escape(path)[:200]}: an entry is a folder with a name of letters, digits and "
                             "_.+- (its outputs are named after it)")
        self.toml = os.path.join(self.dir, "capture.toml")
        self.calls = os.path.join(self.dir, "calls.xz")
        text = read_input_text(self.toml, "the capture description", MAX_TOML)
        try:
            doc = parse_toml(self.toml, text)
        except tomllib.TOMLDecodeError as e:
            raise UsageError(f"{self.toml}: {e}")
        except RecursionError:   # tomllib parses nested arrays and tables recursively
            raise UsageError(f"{self.toml}: nested too deep to read") from None

        def key(k, kind, table=doc, prefix=""):
            if k not in table:
                raise UsageError(f"{self.toml}: {prefix}{k}: missing")
            v = table[k]
            if not isinstance(v, kind) or isinstance(v, bool):
                raise UsageError(f"{self.toml}: {prefix}{k}: must be {kind.__name__}")
            return v
        self.frames = key("frames", int)
        self.first = key("first_frame", int)
        if not 1 <= self.frames <= 100000 or not 0 <= self.first <= 100000:
            raise UsageError(f"{self.toml}: frames (1..100000) or first_frame (0..100000) out of range")
        screen = key("screen", list)
        if len(screen) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= 8192
                                       for v in screen):
            raise UsageError(f"{self.toml}: screen: must be [W, H], 1..8192")
        self.screen = screen
        sel = key("selection", str)
        if os.path.isabs(sel) or ".." in sel.split("/") or "\0" in sel:
            raise UsageError(f"{self.toml}: selection: must be a path inside the repository")
        self.selection = os.path.join(ROOT, sel)
        self.summary = os.path.join(self.dir, "summary.jsonl")
        sums = key("sha256", dict)
        self.sha = {}
        for k in ("calls", "trace", "geometry"):
            v = key(k, str, sums, "sha256.")
            if len(v) != 64 or any(c not in "0123456789abcdef" for c in v):
                raise UsageError(f"{self.toml}: sha256.{k}: not a SHA-256 in hex")
            self.sha[k] = v
        self.doc = doc

    def check(self):
        if not os.path.isfile(self.calls):
            raise UsageError(f"{self.calls}: cannot read the reduced capture: "
                             + ("not a regular file" if os.path.lexists(self.calls) else "missing"))
        if not os.path.isfile(self.selection):
            raise UsageError(f"{self.toml}: selection: {self.selection}: "
                             + ("not a regular file" if os.path.exists(self.selection) else "missing"))
        got = sha256_file(self.calls)
        if got != self.sha["calls"]:   # the input changed: bad input, exit 2
            raise UsageError(f"{self.calls}: checksum {got[:16]}... is not capture.toml's "
                             f"{self.sha['calls'][:16]}...: the file changed since it was captured")

    def outputs(self, out):
        base = os.path.join(out, self.name)
        # zstd (docs/formats.md): rbcd-sim decompresses it at several times
        # gzip's speed, and --jobs passes over the frames before a worker's.
        return base + ".rbt.zst", base + ".geo", base + ".summary.jsonl"

    def inputs(self):
        """What expand reads of the entry (the checksums are capture.toml's)."""
        return [("the reduced capture", self.calls), ("capture.toml", self.toml),
                ("summary.jsonl", self.summary), ("the selection file", self.selection)]

    def all_outputs(self, out):
        return self.outputs(out) + (os.path.join(out, self.name + ".capture"),)

    def describe(self, out):
        """OUT/NAME.capture: the entry's capture.toml beside its trace (the
        evaluation reads the game from it), named so that nothing takes it
        for a scene (*.toml in a suite folder is one)."""
        with open(self.toml, "rb") as src:
            write_output(os.path.join(out, self.name + ".capture"), src.read(), "capture description")

    def committed_summary(self, frames=None):
        """The entry's summary.jsonl as committed, its first `frames` lines."""
        text = read_input_text(self.summary, "the entry's summary", 64 << 20)
        # A line a frame: counted before the text is split, so a file of
        # many short lines costs no more than its bytes.
        if text.count("\n") != self.frames or not text.endswith("\n"):
            raise UsageError(f"{self.summary}: not a line for each of the entry's {self.frames} frames")
        # Each line as the converter writes it: a JSON object ended by LF
        # alone. Anything else (CR LF line ends) is the input's fault, said
        # before the conversion: it could never match the regenerated one.
        lines = text.split("\n")[:-1]
        for i, line in enumerate(lines, 1):
            if "\r" in line:
                raise UsageError(f"{self.summary}: line {i} " + ("ends in CR LF" if line.endswith("\r") else
                                 "holds a CR") + ": the converter's lines end in LF alone")
            try:
                obj = json.loads(line, parse_constant=reject_constant)
            except (ValueError, RecursionError):
                obj = None
            if not isinstance(obj, dict):
                raise UsageError(f"{self.summary}: line {i}: not a JSON object (the converter's figures "
                                 "for a frame)")
            # As the converter writes it: its keys in its order, compact,
            # its figures counts, the objects ids in increasing order.
            problem = summary_line_problem(obj, line)
            if problem:
                raise UsageError(f"{self.summary}: line {i}: not as the converter writes a frame's figures "
                                 f"({problem})")
            if obj.get("frame") != i - 1:
                raise UsageError(f"{self.summary}: line {i}: not frame {i - 1}'s figures")
        return "".join(line + "\n" for line in (lines[:frames] if frames else lines))

    def summary_matches(self, summary, frames=None):
        try:
            with open(summary, encoding="utf-8") as f:
                return f.read() == self.committed_summary(frames)
        except (OSError, UnicodeDecodeError):
            return False

    def up_to_date(self, out):
        trace, geo, summary = self.outputs(out)
        if not all(os.path.isfile(p) for p in (trace, geo, summary)):
            return False
        try:
            return (sha256_file(trace, decompress=True) == self.sha["trace"]
                    and sha256_file(geo) == self.sha["geometry"] and self.summary_matches(summary))
        except (OSError, EOFError, UsageError) + trace_errors():
            return False

    def expand(self, out, frames=None):
        try:
            return self.expand_in(out, frames)
        except Stopped:
            self.remove_outputs(out)
            raise

    def remove_outputs(self, out):
        for p in self.all_outputs(out):
            try:
                os.unlink(p)
            except OSError:
                pass

    def expand_in(self, out, frames):
        if frames is not None and frames >= self.frames:
            frames = None   # the whole entry: converted and checked as without --frames
        if frames is None and self.up_to_date(out):
            self.describe(out)
            return f"{self.name}: up to date"
        trace, geo, summary = self.outputs(out)
        last = self.first + (frames or self.frames) - 1
        # Through its own interpreter line (Debian's python3, which has numpy),
        # not this one's: a python3 earlier on PATH may lack it.
        cmd = [os.path.join(ROOT, "scripts", "rbcd-gl2rbt"), self.calls, "-o", trace, "--geometry", geo,
               "--summary", summary, "--frames", f"{self.first}:{last}",
               "--screen", str(self.screen[0]), str(self.screen[1]), "--select", self.selection, "-q"]
        # The converter's temporary folders in one of expand's own, removed
        # whatever becomes of it; if it is killed outright (SIGKILL, no
        # handler of its own ran), the temporaries it wrote its outputs
        # through beside them are removed too.
        tmp = temporary_folder("game-suite-convert.")
        started = time.time()
        try:
            returncode, stderr = CONVERSIONS.run(cmd, env=dict(os.environ, TMPDIR=tmp))
        finally:
            shutil.rmtree(tmp, ignore_errors=True)
            unregister_temporary(tmp)
        if returncode < 0:
            for path in (trace, geo, summary):
                remove_left_temporaries(path, started)
        if CONVERSIONS.stopped:
            raise Stopped()
        if returncode != 0:
            msg = (stderr.strip().splitlines() or [f"exit {returncode}"])[0]
            raise (UsageError if returncode == 2 else Mismatch)(f"{self.name}: conversion failed: {msg}")
        problem = None
        if frames is None:
            for path, k, gz in ((trace, "trace", True), (geo, "geometry", False)):
                got = sha256_file(path, decompress=gz)
                if got != self.sha[k] and problem is None:
                    problem = (f"the regenerated {k} differs from capture.toml's checksum "
                               f"({got[:16]}... against {self.sha[k][:16]}...)")
        if problem is None and not self.summary_matches(summary, frames):
            problem = "the regenerated summary differs from the entry's summary.jsonl"
        if problem:
            for p in (trace, geo, summary):
                try:
                    os.unlink(p)
                except OSError:
                    pass
            raise Mismatch(f"{self.name}: {problem}")
        if CONVERSIONS.stopped:
            raise Stopped()
        self.describe(out)
        return f"{self.name}: {frames or self.frames} frames"


def check_expand_outputs(entries, out):
    """Before anything is opened: no output of expand is a symlink (it
    writes its outputs as files of their own: a link there could lead into
    an entry's inputs or anywhere else), and none is an input of any entry
    being expanded or another output (device and inode, or the path of a
    file not yet there: rbcd.cli.check_outputs)."""
    for e in entries:
        for p in e.all_outputs(out):
            if os.path.islink(p):
                raise UsageError(f"{p}: a symlink: expand writes its outputs as files of their own, "
                                 "never through a link (remove it)")
    check_outputs([(f"{what} of {e.name}", p) for e in entries for what, p in e.inputs()],
                  [("-o", p) for e in entries for p in e.all_outputs(out)])


def make_folders(out):
    """-o OUT and the folders above it that are missing, made; the ones
    made, outermost first."""
    missing = []
    d = os.path.abspath(out)
    while not os.path.isdir(d):
        missing.append(d)
        d = os.path.dirname(d)
    try:
        os.makedirs(out, exist_ok=True)
    except OSError as e:
        raise UsageError(f"-o {out}: cannot create: {e.strerror}")
    return missing[::-1]


def entries_of(paths):
    if not paths:
        base = os.path.join(ROOT, "workloads", "games")
        paths = sorted(os.path.join(base, d) for d in os.listdir(base)
                       if os.path.isfile(os.path.join(base, d, "capture.toml")))
        if not paths:
            raise UsageError(f"{base}: no game-suite entry (a directory with capture.toml)")
    names = set()
    out = []
    for p in paths:
        if not os.path.isdir(p):
            raise UsageError(f"{p}: not a game-suite entry directory")
        e = Entry(p)
        if e.name in names:
            raise UsageError(f"{p}: two entries named {e.name}")
        names.add(e.name)
        out.append(e)
    return out


def run(argv):
    ap = ArgumentParser(prog=PROG)
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("check")
    c.add_argument("entries", nargs="*")
    x = sub.add_parser("expand")
    # Each option at most once, each number in ASCII digits, as the
    # converter takes its own (a second -o or --frames had replaced the
    # first; --frames ١ had converted one frame).
    x.add_argument("-o", "--out", action=Once, required=True)
    x.add_argument("-j", "--jobs", action=Once, type=ascii_int, default=os.cpu_count() or 1)
    x.add_argument("--frames", action=Once, type=ascii_int)
    x.add_argument("entries", nargs="*")
    args = ap.parse_args(argv)
    entries = entries_of(args.entries)
    try:
        if args.cmd == "check":
            check_standard_output([(f"{what} of {e.name}", p) for e in entries for what, p in e.inputs()])
            for e in entries:
                e.check()
                e.committed_summary()
                print(f"{e.name}: calls.xz matches capture.toml, summary.jsonl is as the converter writes it")
            return 0
        if args.jobs < 1:
            raise UsageError("--jobs must be at least 1")
        if args.frames is not None and args.frames < 1:
            raise UsageError("--frames must be at least 1")
        if os.path.exists(args.out) and not os.path.isdir(args.out):
            raise UsageError(f"-o {args.out}: not a directory")
        check_expand_outputs(entries, args.out)
        for e in entries:
            # Every entry's inputs, summary.jsonl whole (--frames or not),
            # before any conversion: a bad one leaves nothing.
            e.check()
            e.committed_summary()
        created = make_folders(args.out)
        try:
            with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
                try:
                    futs = [pool.submit(e.expand, args.out, args.frames) for e in entries]
                    for f in futs:
                        print(f.result())
                except KeyboardInterrupt:
                    # The workers' converters stopped and their entries removed
                    # before the pool is waited for.
                    CONVERSIONS.stop()
                    pool.shutdown(wait=True, cancel_futures=True)
                    raise
        except BaseException:
            # The folders this run made, if no entry was written into them.
            for d in reversed(created):
                try:
                    os.rmdir(d)
                except OSError:
                    break
            raise
        return 0
    except Mismatch as e:
        say(PROG, str(e))
        return 1


def main(argv=None):
    return main_wrapper(PROG, run, sys.argv[1:] if argv is None else argv)


if __name__ == "__main__":
    sys.exit(main())
