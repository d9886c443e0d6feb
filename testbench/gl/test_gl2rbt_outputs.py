"""rbcd-gl2rbt held to the project's rule for bad input where the outside
probes of issue 39 found it was not (docs/gl-capture.md, "Bad input"):
messages built from input values bounded in time and memory, calls carrying
more values than the limit refused before a handler walks them, the rest of
a reduced capture checked when --frames stops before its end, and the hidden
outputs (--stream-out, --depth-out) and late output failures under the same
discipline as every other output. Captures are written here as reduced
captures (no Xvfb, no apitrace)."""
import lzma
import os
import pathlib
import pickle
import shutil
import signal
import subprocess
import time

import pytest

from conftest import program
from gl_captures import GL2RBT, Calls as SharedCalls, capture_path, gl2rbt_timed as gl2rbt, left_behind, peak_mb, refused
from rbcd.cli import describe
from rbcd.gl2rbt.apitrace import MAX_RECORD_VALUES
from rbcd.gl2rbt.errors import printable
from rbcd.gl2rbt.reduced import REDUCED_END, REDUCED_EXPANSION, REDUCED_HEADER

# A pickle of shared references: a 10^9-element list in a few kilobytes (its
# repr would take gigabytes and minutes).
BOMB = [[[0] * 1000] * 1000] * 1000


class Calls(SharedCalls):
    """The shared test captures, with a frame of one triangle and a writer
    of their own."""

    def frame(self):
        return self.triangle().swap()

    def write(self, path, end=True):
        """As ReducedWriter writes it, each record pickled on its own (its
        copy of the arguments would expand BOMB); without the end record
        when not `end`."""
        z = lzma.LZMACompressor(preset=6)
        data = z.compress(pickle.dumps(REDUCED_HEADER, protocol=4))
        for c in self.calls:
            data += z.compress(pickle.dumps(c, protocol=4))
        if end:
            data += z.compress(pickle.dumps((REDUCED_END, len(self.calls)), protocol=4))
        with open(path, "wb") as f:
            f.write(data + z.flush())
        return str(path)


# ---- messages built from input values

def test_a_described_value_is_bounded():
    t = time.monotonic()
    assert describe(BOMB) == "a list of 1000 elements"
    assert describe([1, [2, "x"]]) == "[1, [2, 'x']]" and describe("12") == "'12'"
    assert describe(10 ** 5000) == "an integer of 16610 bits", "str() of it fails past 4300 digits"
    assert describe(bytes(1 << 20)) == "1048576 bytes" and describe({"a": BOMB}) == "a dict of 1 entries"
    assert describe("\x1b" * 10 ** 6).startswith("'\\x1b\\x1b") and len(describe("\x1b" * 10 ** 6)) <= 60
    assert printable(KeyError(BOMB)) == "a list of 1000 elements", "a KeyError's str() is its key's repr"
    assert printable(BOMB) == "a list of 1000 elements" and printable("\x00" * 10 ** 7, 20) == "\\x00" * 5 + "..."
    assert printable(TypeError("unhashable type: 'list'")) == "unhashable type: 'list'"
    assert printable(OSError(28, "No space left on device")) == "[Errno 28] No space left on device"
    assert printable(MemoryError()) == "MemoryError", "an exception of no words is named by its type"
    assert time.monotonic() - t < 10, "a walk of the value's every element (minutes, not milliseconds)"


@pytest.mark.parametrize("fn, words", [
    ("glViewport", "a viewport value: a list of 100 elements is not an integer"),
    ("glOrtho", "a bound: a list of 100 elements is not a number"),
    ("glClearDepth", "the clear depth: a list of 100 elements is not a number"),
], ids=["integer", "real", "clear_depth"])
@pytest.mark.parametrize("size", [100, 1000])
def test_a_value_of_shared_references_is_named_at_once(tmp_path, fn, words, size):
    """A 1.2 KB reduced capture whose argument is [[[0] * N] * N] * N: at
    N = 1000 (10^9 references) refused as too many values, at N = 100
    (within MAX_RECORD_VALUES) described in the message, never written out
    (N = 1000 took minutes and gigabytes, written as a repr before it was
    cut)."""
    value = [[[0] * size] * size] * size
    c = Calls()
    if fn == "glViewport":
        c.add("glViewport", x=0, y=0, width=value, height=4)
    elif fn == "glOrtho":
        c.add("glOrtho", left=value, right=1, bottom=0, top=1, zNear=-1, zFar=1)
    else:
        c.add("glClearDepth", depth=value)
    cap = c.frame().write(tmp_path / "c.xz")
    assert os.path.getsize(cap) < 4096
    r = gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt")
    refused(r, "c.xz: call 6", words if size == 100 else f"more than {MAX_RECORD_VALUES} values in one call")
    assert peak_mb(r) < 200 and r.seconds < 30, f"{peak_mb(r):.0f} MB, {r.seconds:.1f} s"
    assert left_behind(tmp_path, ["c.xz"]) == []


# ---- calls carrying more values than the limit

@pytest.mark.parametrize("fn, args", [
    ("glDeleteBuffers", lambda n: dict(n=n, buffers=[5] * n)),
    ("glClear", lambda n: dict(mask=["GL_COLOR_BUFFER_BIT"] * n)),
    ("glLoadMatrixf", lambda n: dict(m=BOMB)),
], ids=["delete_buffers", "clear_mask", "shared_references"])
def test_a_call_of_too_many_values_is_refused_before_it_is_walked(tmp_path, fn, args):
    """30 million references in an 11 KB file took 12 s through
    glDeleteBuffers (275 MB): a call carries at most MAX_RECORD_VALUES."""
    n = MAX_RECORD_VALUES + 1
    cap = Calls().add(fn, **args(n)).frame().write(tmp_path / "c.xz")
    r = gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt")
    refused(r, "c.xz: call 6", f"more than {MAX_RECORD_VALUES} values in one call")
    assert r.seconds < 30, f"{r.seconds:.1f} s"
    assert left_behind(tmp_path, ["c.xz"]) == []


# ---- the rest of a reduced capture, when --frames stops before it

def frame(body):
    return b"\x95" + len(body).to_bytes(8, "little") + body


@pytest.mark.parametrize("framed", [True, False], ids=["framed", "unframed"])
def test_a_record_of_tiny_objects_is_refused_in_bounded_memory(tmp_path, framed):
    """A 9 KB reduced capture expanding to its limit (65 MB) in one record of
    empty lists, 80 bytes of memory each from one byte: framed as the
    writer frames records, its opcodes are counted before they are
    unpickled; unframed, it is refused at once (16 million of them had
    peaked at 1.3 GB; 65 million would take 5 GB). Run under a 2 GB address
    space, so that the machine is spared when the limit fails."""
    n = 60_000_000
    chunk = (1 << 20) - 16
    if framed:
        record = b"\x80\x04" + frame(b"(" + b"]" * (chunk - 1)) + frame(b"]" * chunk) * (n // chunk) + frame(b"l.")
        words = "does not decode (a record of more than 3145728 pickle opcodes"
    else:
        record = b"\x80\x04(" + b"]" * n + b"l."
        words = "does not decode (a record not framed as the writer frames it)"
    z = lzma.LZMACompressor(preset=6)
    data = z.compress(pickle.dumps(REDUCED_HEADER, protocol=4)) + z.compress(record) + z.flush()
    (tmp_path / "c.xz").write_bytes(data)
    assert len(data) < 1 << 16 and len(record) < REDUCED_EXPANSION << 16, "not a capture at the expansion limit"
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = subprocess.run(["/usr/bin/time", "-f", "maxrss %M", "prlimit", f"--as={2 << 30}", "/usr/bin/python3", GL2RBT,
                        tmp_path / "c.xz", "-o", tmp_path / "c.rbt"], capture_output=True, text=True, env=env,
                       stdin=subprocess.DEVNULL, timeout=120)
    refused(r, "c.xz: before its first call: the reduced capture " + words)
    assert peak_mb(r) < 300, f"{peak_mb(r):.0f} MB"
    assert left_behind(tmp_path, ["c.xz"]) == []


def test_the_rest_of_a_reduced_capture_is_checked(tmp_path):
    """--frames 0:0 of a two-frame reduced capture reads on to the end of
    its xz stream: junk after it, a stream cut short or one without its end
    record are refused as without --frames (game-suite expand --frames K
    takes this path)."""
    good = Calls().frame().frame().write(tmp_path / "good.xz")
    r = gl2rbt(tmp_path, good, "-o", tmp_path / "g.rbt", "--frames", "0:0")
    assert r.returncode == 0 and "1 frames:" in r.stdout, r.stderr
    data = open(good, "rb").read()
    (tmp_path / "junk.xz").write_bytes(data + b"JUNK")
    (tmp_path / "cut.xz").write_bytes(data[:-40])
    Calls().frame().frame().write(tmp_path / "noend.xz", end=False)
    for name, words in (("junk.xz", "bytes after the xz stream"), ("cut.xz", "cut short"),
                        ("noend.xz", "no end record")):
        refused(gl2rbt(tmp_path, tmp_path / name, "-o", tmp_path / "o.rbt", "--frames", "0:0"), name, words)
    assert left_behind(tmp_path, ["good.xz", "g.rbt", "junk.xz", "cut.xz", "noend.xz"]) == []


# ---- the hidden outputs and late write failures

def test_hidden_outputs_never_destroy_inputs(tmp_path):
    """--stream-out and --depth-out are checked against the inputs and the
    other outputs as every output is (--stream-out naming the selection file
    had emptied it before it was read, with exit 0)."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    rules = tmp_path / "rules.toml"
    rules.write_text('[[object]]\nid = 3\nvertex_count = [3, 3]\n')
    before = {p: open(p, "rb").read() for p in (cap, rules)}
    out = ["-o", tmp_path / "c.rbt"]
    refused(gl2rbt(tmp_path, cap, *out, "--stream-out", cap), "--stream-out", "is also the capture")
    refused(gl2rbt(tmp_path, cap, *out, "--select", rules, "--stream-out", rules), "is also the selection file")
    refused(gl2rbt(tmp_path, cap, *out, "--stream-out", tmp_path / "c.rbt"), "is also -o's output")
    os.mkdir(tmp_path / "d")
    depth_cap = tmp_path / "d" / "x.0.depth"
    os.link(cap, depth_cap)   # a capture named as --depth-out's first file
    refused(gl2rbt(tmp_path, depth_cap, *out, "--depth-out", tmp_path / "d" / "x", "--snapshot-calls", "7"),
            "--depth-out")
    os.symlink(cap, tmp_path / "d" / "y.0.depth")   # one of its files a link to the capture
    refused(gl2rbt(tmp_path, cap, *out, "--depth-out", tmp_path / "d" / "y", "--snapshot-calls", "7"),
            "is also the capture")
    refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "d" / "z.0.depth", "--depth-out", tmp_path / "d" / "z"),
            "--depth-out")
    for p, data in before.items():
        assert open(p, "rb").read() == data, f"{p} was changed"
    assert left_behind(tmp_path, ["c.xz", "rules.toml", "d"]) == []
    assert sorted(os.listdir(tmp_path / "d")) == ["x.0.depth", "y.0.depth"]


@pytest.mark.parametrize("mode, args", [
    ("r+b", ["-o", "c.rbt"]), ("ab", ["-o", "c.rbt"]), ("r+b", ["--list-draws", "0"]),
    ("ab", ["-o", "c.rbt", "--select", "RULES"]),
], ids=["read_write", "append", "listing", "selection_appended"])
def test_standard_output_onto_an_input_is_refused(tmp_path, mode, args):
    """Standard output opened by the shell onto an input (1<>c.xz, >>c.xz,
    >>rules.toml) takes the report or the listing whatever the outputs
    are: refused before anything is written, as GNU cat refuses it (the
    report had been written over the capture's first bytes, exit 0;
    R18-11)."""
    cap = pathlib.Path(Calls().frame().write(tmp_path / "c.xz"))
    rules = tmp_path / "rules.toml"
    rules.write_text('[[object]]\nid = 3\nvertex_count = [3, 3]\n')
    target = rules if "RULES" in args else cap
    args = [str(rules) if a == "RULES" else str(tmp_path / a) if a.endswith(".rbt") else a for a in args]
    before = {q: q.read_bytes() for q in (cap, rules)}
    with open(target, mode) as out:
        r = gl2rbt(tmp_path, cap, *args, stdout=out)
    what = "the selection file" if target == rules else "the capture"
    refused(r, f"{target}: standard output is {what}")
    for q, data in before.items():
        assert q.read_bytes() == data, f"{q} was changed"
    assert left_behind(tmp_path, ["c.xz", "rules.toml"]) == []


def test_a_failed_run_leaves_no_stream_copy(tmp_path):
    cap = Calls().frame().write(tmp_path / "c.xz")
    refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt", "--frames", "7:9", "--stream-out",
                   tmp_path / "stream.bin"), "--frames selects none")
    assert left_behind(tmp_path, ["c.xz"]) == [], "a partial stream copy was left"
    r = gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt", "--stream-out", tmp_path / "stream.bin")
    assert r.returncode == 0, r.stderr
    assert (tmp_path / "stream.bin").read_bytes().startswith(b"RBCDGLD2")
    assert left_behind(tmp_path, ["c.xz", "c.rbt", "stream.bin"]) == []


@pytest.mark.parametrize("args", [["-o", "c.rbt", "--summary", "/dev/full"],
                                  ["--list-draws", "0", "--image", "/dev/full"]], ids=["summary", "image"])
def test_a_full_device_is_named(tmp_path, args):
    """--summary and --image on a full device: "PATH: write failed", exit 1,
    as -o and --geometry (it was "internal error: OSError"), nothing left."""
    pytest.importorskip("PIL")
    cap = Calls().frame().write(tmp_path / "c.xz")
    r = gl2rbt(tmp_path, cap, *[tmp_path / a if a == "c.rbt" else a for a in args])
    refused(r, "/dev/full: write failed: No space left on device", status=1)
    assert left_behind(tmp_path, ["c.xz"]) == []


def test_a_report_standard_output_cannot_take_fails_the_run(tmp_path):
    """Standard output on a full device, or closed: the report is written
    before the outputs are committed, and its failure is the run's, as an
    output's write failure is: one line, exit 1, no output left (they had
    been left whole with exit 1, and with a closed standard output the
    report was lost with exit 0)."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    outputs = ["-o", tmp_path / "c.rbt", "--summary", tmp_path / "s.jsonl", "--geometry", tmp_path / "g.geo"]
    with open("/dev/full", "w") as full:
        r = gl2rbt(tmp_path, cap, *outputs, stdout=full)
    refused(r, "the report: write failed: No space left on device; no output written", status=1)
    assert left_behind(tmp_path, ["c.xz"]) == []
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = subprocess.run(["/usr/bin/python3", GL2RBT, cap] + [str(a) for a in outputs], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, env=env, timeout=120, pass_fds=(),
                       preexec_fn=lambda: os.close(1))
    refused(r, "the report: write failed: standard output is closed; no output written", status=1)
    assert left_behind(tmp_path, ["c.xz"]) == []
    r = gl2rbt(tmp_path, cap, *outputs)
    assert r.returncode == 0 and r.stdout.startswith("1 frames: "), r.stderr


def test_a_listing_standard_output_cannot_take_fails_the_run(tmp_path):
    """--list-draws with standard output full or closed: one line, exit 1,
    and no image (it had been an internal error, and with a closed
    standard output the listing was lost with exit 0)."""
    pytest.importorskip("PIL", reason="python3-pil is missing (installed with apitrace: scripts/setup.sh --gl)")
    cap = Calls().frame().write(tmp_path / "c.xz")
    args = [cap, "--list-draws", "0", "--image", tmp_path / "f.png"]
    with open("/dev/full", "w") as full:
        refused(gl2rbt(tmp_path, *args, stdout=full), "the listing: write failed: No space left on device", status=1)
    assert left_behind(tmp_path, ["c.xz"]) == []
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = subprocess.run(["/usr/bin/python3", GL2RBT] + [str(a) for a in args], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, env=env, timeout=120, preexec_fn=lambda: os.close(1))
    refused(r, "the listing: write failed: standard output is closed", status=1)
    assert left_behind(tmp_path, ["c.xz"]) == []


def run_or_fail(cmd, env, timeout, why):
    """cmd's result; pytest.fail(why) when it runs past `timeout`, its
    whole process group (the converter's rasterizer too) killed."""
    p = subprocess.Popen([str(a) for a in cmd], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         stdin=subprocess.DEVNULL, start_new_session=True)
    try:
        out, err = p.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        p.communicate()
        pytest.fail(why)
    return subprocess.CompletedProcess(p.args, p.returncode, out, err)


@pytest.mark.parametrize("args", [["-o", "fifo"], ["-o", "c.rbt", "--summary", "fifo"],
                                  ["-o", "c.rbt", "--geometry", "fifo"], ["-o", "c.rbt", "--stream-out", "fifo"],
                                  ["--list-draws", "0", "--image", "fifo"], ["-o", "c.rbt", "--depth-out", "d"]],
                         ids=["trace", "summary", "geometry", "stream", "image", "depth"])
def test_a_fifo_output_is_refused_before_it_is_opened(tmp_path, args):
    """An output that is a FIFO no process reads: one line naming it, exit
    2, at once (opening it had waited for a reader for ever); standard
    output, a pipe, is still an output."""
    os.mkfifo(tmp_path / "fifo")
    os.mkfifo(tmp_path / "d.0.depth")
    cap = Calls().frame().write(tmp_path / "c.xz")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = run_or_fail(["/usr/bin/python3", GL2RBT, cap] + [tmp_path / a if a in ("fifo", "c.rbt", "d") else a
                                                         for a in args], env, 30,
                    f"{args}: waited for a reader of the FIFO")
    fifo = tmp_path / ("d.0.depth" if "--depth-out" in args else "fifo")
    option = args[-2]
    refused(r, f"{option} {fifo}: cannot create: is a FIFO, not a regular file")
    assert left_behind(tmp_path, ["c.xz", "fifo", "d.0.depth"]) == []
    r = subprocess.run(["/usr/bin/python3", GL2RBT, cap, "-o", "/dev/stdout", "-q"], capture_output=True, env=env,
                       stdin=subprocess.DEVNULL, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith(b"rbcd-trace "), r.stderr


def test_a_listing_image_on_standard_output_has_it_to_itself(tmp_path):
    """--list-draws N --image - (or /dev/stdout): the PNG alone on standard
    output, the listing on standard error (they had been mixed, and "-" had
    made a file of that name)."""
    pytest.importorskip("PIL", reason="python3-pil is missing (installed with apitrace: scripts/setup.sh --gl)")
    cap = Calls().frame().write(tmp_path / "c.xz")
    for image in ("-", "/dev/stdout"):
        env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
        r = subprocess.run(["/usr/bin/python3", GL2RBT, cap, "--list-draws", "0", "--image", image],
                           capture_output=True, env=env, timeout=120)
        assert r.returncode == 0 and r.stdout.startswith(b"\x89PNG\r\n\x1a\n"), (image, r.stderr)
        assert b"frame 0:" in r.stderr and b"frame 0:" not in r.stdout
        assert sorted(os.listdir(tmp_path)) == ["c.xz"], os.listdir(tmp_path)


@pytest.mark.parametrize("option, starts", [("--summary", b'{"frame":0,'), ("--geometry", b"rbcd-geometry "),
                                           ("--reduced-out", b"\xfd7zXZ")], ids=["summary", "geometry", "reduced"])
def test_dash_is_standard_output_for_every_output(tmp_path, option, starts):
    """--summary, --geometry or --reduced-out "-": the output alone on
    standard output, the report on standard error (round 33's D4: a file
    named "-" had been written, an existing one replaced, while standard
    output stayed empty)."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    (tmp_path / "-").write_bytes(b"keep")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    args = [GL2RBT, cap, "-o", tmp_path / "c.rbt", option, "-"]
    if option == "--reduced-out":
        capture = capture_path()
        args[1] = capture
    r = subprocess.run(["/usr/bin/python3"] + args, capture_output=True, env=env, cwd=tmp_path, timeout=120)
    assert r.returncode == 0 and r.stdout.startswith(starts), (r.stdout[:40], r.stderr)
    assert (tmp_path / "-").read_bytes() == b"keep"


@pytest.mark.parametrize("option", ["-o", "--summary"])
def test_an_output_on_a_closed_standard_output_fails_the_run(tmp_path, option):
    """An output to standard output when it is closed: one line, exit 1
    (the run's environment, as a write that fails: docs/gl-capture.md),
    nothing left (round 34: "-: cannot create: Bad file descriptor",
    exit 2, as if the command line were wrong)."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    args = [cap, "-o", "-"] if option == "-o" else [cap, "-o", tmp_path / "c.rbt", option, "-"]
    r = subprocess.run(["/usr/bin/python3", GL2RBT] + [str(a) for a in args], stdout=subprocess.DEVNULL,
                       stderr=subprocess.PIPE, text=True, env=env, cwd=tmp_path, timeout=120,
                       preexec_fn=lambda: os.close(1))
    assert r.returncode == 1 and r.stderr.strip().splitlines() == [
        f"rbcd-gl2rbt: {option}: standard output is closed; no output written"], r.stderr
    assert left_behind(tmp_path, ["c.xz"]) == []


def test_a_listing_image_of_a_large_screen_is_built_in_bounded_memory(tmp_path):
    """--image of a 4096 x 4096 frame one draw covers: the label's place
    from counts, not every pixel's coordinates (16 bytes a pixel, 256 MiB
    here; 8192 x 8192 had peaked at 760 MB), and no array kept once the
    next is made. numpy's arrays are what tracemalloc sees (PIL's picture,
    4 bytes a pixel, is not)."""
    pytest.importorskip("PIL", reason="python3-pil is missing (installed with apitrace: scripts/setup.sh --gl)")
    import tracemalloc
    import numpy as np
    from rbcd.gl2rbt.listing import write_draw_image
    side = 4096
    ids = np.zeros((side, side), "<u2")
    ids[:, :100] = 0xFFFF
    ids[:50] = 1
    with open(tmp_path / "ids", "wb") as f:
        f.write(f"rbcd-ids 1 {side} {side}\n".encode())
        ids.tofile(f)
    del ids
    rows = [{"index": 0, "object": 3}, {"index": 1, "object": None}]
    tracemalloc.start()
    try:
        write_draw_image(str(tmp_path / "f.png"), str(tmp_path / "ids"), rows)
        peak = tracemalloc.get_traced_memory()[1] / (1 << 20)
    finally:
        tracemalloc.stop()
    assert (tmp_path / "f.png").read_bytes().startswith(b"\x89PNG")
    assert peak < 120, f"{peak:.0f} MiB of arrays for a {side} x {side} picture"


@pytest.mark.parametrize("args, words", [
    (["--list-draws", "0", "-o", "x.rbt"], "-o goes with a conversion, not with --list-draws"),
    (["--list-draws", "0", "--geometry", "x.geo"], "--geometry goes with a conversion, not with --list-draws"),
    (["--check-depth", "--summary", "x.jsonl"], "--summary goes with a conversion, not with --check-depth"),
    (["--list-draws", "0", "--check-depth"], "two commands"),
], ids=["listing_o", "listing_geometry", "check_summary", "both"])
def test_outputs_a_command_does_not_write_are_refused(tmp_path, args, words):
    """An output the command would pass over (--list-draws and --check-depth
    write no trace, geometry or summary): refused, where it had exited 0
    with no such file."""
    cap = Calls().triangle(obj=1).swap().write(tmp_path / "c.xz")
    refused(gl2rbt(tmp_path, cap, *args), words)
    assert sorted(os.listdir(tmp_path)) == ["c.xz"]


def test_a_selection_file_with_an_integer_python_cannot_convert(tmp_path):
    """An integer of 5,000 digits: one line naming the file and the line
    (it had been "internal error: ValueError: Exceeds the limit", exit 1;
    R20-9)."""
    cap = Calls().triangle(obj=1).swap().write(tmp_path / "c.xz")
    (tmp_path / "r.toml").write_text("[[object]]\nid = " + "1" * 5000 + "\n")
    refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt", "--select", tmp_path / "r.toml"),
            "r.toml", "an integer of more than 4300 digits (at line 2)")
    assert sorted(os.listdir(tmp_path)) == ["c.xz", "r.toml"]


def test_a_selection_file_that_is_not_utf8_says_where(tmp_path):
    cap = Calls().triangle(obj=1).swap().write(tmp_path / "c.xz")
    (tmp_path / "r.toml").write_bytes(b"[[object]]\nid = 1\nname = '\xff'\n")
    refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt", "--select", tmp_path / "r.toml"),
            "r.toml: not UTF-8 text (byte 26)")


@pytest.mark.parametrize("ups", [60, 550], ids=["whole", "middle_cut"])
def test_a_long_refusal_keeps_its_end(tmp_path, ups):
    """A refusal names what it refused at its end: one longer than 400
    characters had lost it (R17-10: "... cannot hold) is not ..."). Up to
    2000 characters it is written whole; past them (a selection file named
    through 3,900 characters of path) its middle is cut, its end kept."""
    cap = Calls().triangle(obj=1).swap().write(tmp_path / "c.xz")
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "r.toml").write_text("x = 1\n")
    rules = str(tmp_path / "sub") + "/../sub" * ups + "/r.toml"
    line = refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "c.rbt", "--select", rules))
    assert line.endswith(f"{rules[-900:]}: unknown table or key 'x'")
    if ups == 60:
        assert line == f"rbcd-gl2rbt: {cap}: {rules}: unknown table or key 'x'"
    else:
        assert " ... " in line and len(line) < 2100
    assert left_behind(tmp_path, ["c.xz", "sub"]) == []


def test_a_long_message_is_cut_in_its_middle_and_escaped():
    """Whole up to 2000 characters, escapes included; past them, cut in its
    middle (before it is escaped, so that a message of 4 MB costs no more),
    its end kept."""
    from rbcd.gl2rbt.cli import message
    from rbcd.gl2rbt.errors import ConvertError
    said = message(ConvertError("call 84: glDrawArrays: " + "a texture whose images \x1b " * 20 + "GL_RGB16"))
    assert said.startswith("call 84: glDrawArrays: a texture") and said.endswith("\\x1b GL_RGB16")
    assert "\x1b" not in said and " ... " not in said
    said = message(ConvertError("call 84: " + "\x1b " * 10 ** 6 + "GL_RGB16"))
    assert said.startswith("call 84: \\x1b") and said.endswith("\\x1b GL_RGB16") and len(said) <= 2005


def test_the_rasterizer_the_run_starts_is_never_an_output(tmp_path):
    """RBCD_GL_RASTER naming a copy of rbcd-gl-raster where -o points: the
    copy had been replaced by the trace, with exit 0."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    tool = tmp_path / "tool"
    shutil.copy(program("rbcd-gl-raster"), tool)
    before = tool.read_bytes()
    env = dict(os.environ, RBCD_GL_RASTER=str(tool), TMPDIR=str(tmp_path))
    r = subprocess.run(["/usr/bin/python3", GL2RBT, cap, "-o", tool], stdout=subprocess.PIPE,
                       stderr=subprocess.PIPE, text=True, env=env, timeout=120)
    refused(r, "-o", "is also rbcd-gl-raster")
    assert tool.read_bytes() == before and left_behind(tmp_path, ["c.xz", "tool"]) == []


def test_an_output_path_with_a_newline_is_named_whole(tmp_path):
    """rbcd-gl-raster's message about an -o it cannot create, relayed whole
    (its first line alone had cut the path at the newline and lost the
    reason), the newline escaped: one line."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    refused(gl2rbt(tmp_path, cap, "-o", tmp_path / "missing" / "a\nb.rbt"), "a\\x0ab.rbt: cannot create")
    assert left_behind(tmp_path, ["c.xz"]) == []


def test_a_temporary_is_the_run_s_from_the_moment_it_exists(tmp_path):
    """A temporary is registered before it is made: a signal taken as soon
    as it exists (an interrupted game-suite expand had left a converter's
    `.NAME.geo.*` behind under load) leaves it to the run's clean-up."""
    from rbcd import cli

    def made_then_interrupted(path):
        open(path, "w").close()
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        cli._new_temporary(str(tmp_path), ".out.geo.", made_then_interrupted)
    left = os.listdir(tmp_path)
    assert len(left) == 1 and left[0].startswith(".out.geo.")
    cli.remove_temporaries()
    assert os.listdir(tmp_path) == []
    fd, path = cli.temporary_file(str(tmp_path), ".x.")
    os.close(fd)
    with pytest.raises(OSError):
        cli.temporary_file(str(tmp_path / "absent"), ".x.")
    cli.remove_temporaries()
    assert os.listdir(tmp_path) == []


# ---- a signal while numpy loads

def test_a_signal_while_numpy_loads_is_taken_once_it_has_loaded(monkeypatch, capsys):
    """numpy's C modules import its core from C (numpy's import_array),
    which prints a KeyboardInterrupt raised there as a traceback before it
    turns it into an ImportError (R17-6: a traceback, then "interrupted").
    A signal while numpy loads now only marks the run interrupted; it is
    taken when numpy has loaded. Here an import of numpy that does what
    those modules do, the signal sent from inside it."""
    import builtins
    import traceback

    from rbcd.gl2rbt import cli
    real_import = builtins.__import__

    def numpy_like(name, *args, **kw):
        if name == "numpy":
            try:
                os.kill(os.getpid(), signal.SIGTERM)
                sum(range(1000))   # Python code: the handler runs here
            except BaseException:   # as import_array: PyErr_Print, then ImportError
                traceback.print_exc()
                raise ImportError("numpy.core.multiarray failed to import")
        return real_import(name, *args, **kw)
    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    monkeypatch.setattr(builtins, "__import__", numpy_like)
    signal.signal(signal.SIGTERM, cli.on_signal)
    try:
        with pytest.raises(KeyboardInterrupt):
            cli.require_numpy()
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)
        cli.INTERRUPTED.clear()
    assert capsys.readouterr().err == ""


def test_a_signal_at_any_moment_of_numpy_s_loading_is_one_line(tmp_path):
    """R17-6 as the probe saw it: rbcd-gl2rbt signalled with SIGTERM at
    many moments of its first second, among them the loading of numpy's
    linear algebra and FFT modules (the signal sent as soon as their
    library is mapped: it is taken at the first Python they run, in
    import_array, where 8 runs in 10 printed a traceback), says one line,
    "interrupted", exit 130, and leaves nothing; or, signalled too late, has
    converted (before the converter's handlers, the start-up's line names
    no capture). The child starts with the signal blocked (the launcher
    takes it from its first statement on), so that none lands in Python's
    own start-up, before any line of the converter."""
    cap = Calls().frame().write(tmp_path / "c.xz")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))

    def start(i):
        out = tmp_path / f"c{i}.rbt"
        p = subprocess.Popen(["/usr/bin/python3", GL2RBT, cap, "-o", out, "-q"], stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True, env=env,
                             preexec_fn=lambda: (signal.signal(signal.SIGTERM, signal.SIG_DFL),
                                                 signal.pthread_sigmask(signal.SIG_BLOCK, [signal.SIGTERM])))
        p.out = out
        return p

    def mapped(pid, name):
        try:
            with open(f"/proc/{pid}/maps") as f:
                return name in f.read()
        except OSError:   # (it has ended)
            return True

    def ended(p):
        err = p.communicate(timeout=120)[1]
        if p.returncode == 0 and err == "":
            p.out.unlink()
            return "converted"
        assert p.returncode == 130 and err.splitlines() in ([f"rbcd-gl2rbt: {cap}: interrupted"],
                                                            ["rbcd-gl2rbt: interrupted"]), (p.returncode, err)
        return "interrupted"
    said = []
    for i, module in enumerate(["_umath_linalg"] * 5 + ["_pocketfft"] * 2):
        p = start(i)
        t = time.monotonic()
        while p.poll() is None and not mapped(p.pid, module) and time.monotonic() - t < 60:
            time.sleep(0.0005)
        p.send_signal(signal.SIGTERM)
        said.append(ended(p))
    # Then at moments 0 to 0.9 s from the start, the runs side by side.
    runs = [start(i) for i in range(10)]
    t = time.monotonic()
    for i, p in enumerate(runs):
        time.sleep(max(0.0, t + 0.1 * i - time.monotonic()))
        p.send_signal(signal.SIGTERM)
    said += [ended(p) for p in runs]
    assert said.count("interrupted") >= 7, said
    assert left_behind(tmp_path, ["c.xz"]) == []


def test_a_signal_in_the_capture_reader_s_clean_up_is_not_lost():
    """A loop over the capture's calls that ends early (--check-depth's
    first pass, the last frame asked for) closes the reader there
    (capture.close_calls), so a signal's KeyboardInterrupt raised in its
    clean-up (apitrace's process ended) reaches the converter, which says
    "interrupted", exit 130, and the replay is closed too. Left to Python's
    collector it was printed as "Exception ignored" and lost: exit 0 and a
    19-line traceback (round 30's R30-4)."""
    from rbcd.gl2rbt.capture import close_calls
    closed = []

    def calls():
        try:
            yield 1
            yield 2
        finally:
            raise KeyboardInterrupt

    class Converter:
        def close_replay(self):
            closed.append(True)

    reader = calls()
    next(reader)
    with pytest.raises(KeyboardInterrupt):
        close_calls(reader, Converter())
    assert closed == [True]


def test_a_replay_outliving_sigterm_is_killed_when_the_converter_dies(monkeypatch):
    """A replay whose process takes no SIGTERM (glretrace's own handler can
    deadlock on malloc's lock) is ended with SIGKILL by the session's
    watcher once the converter is gone (its lifeline closed, as SIGKILL
    closes it): it had lived on under PID 1 (R18-13). The converter's own
    end of a replay is not slowed by the watcher: one that takes SIGTERM
    ends by it, the session with no SIGKILL (which comes only after
    END_SECONDS of waiting; a bound on the seconds themselves had failed
    on a loaded machine)."""
    from rbcd.gl2rbt import glretrace
    proc = glretrace.start_replay(["/bin/sh", "-c", "trap '' TERM; sleep 60 & wait; sleep 60"],
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.3)
    assert len(glretrace.session_left(proc.pid)) >= 2, "the replay did not start"
    os.close(proc.rbcd_lifeline)   # the converter gone, however it went
    proc.rbcd_lifeline = None
    deadline = time.monotonic() + glretrace.END_SECONDS + 3
    while glretrace.session_left(proc.pid, watcher=True) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert glretrace.session_left(proc.pid, watcher=True) == [], "the replay outlived the converter"
    proc.wait()
    proc = glretrace.start_replay(["/bin/sleep", "60"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    time.sleep(0.3)
    sent, killpg = [], os.killpg
    monkeypatch.setattr(glretrace.os, "killpg", lambda pid, sig: (sent.append(sig), killpg(pid, sig))[1])
    glretrace.end_replay(proc)
    assert signal.SIGKILL not in sent and signal.SIGTERM in sent, sent
    assert glretrace.session_left(proc.pid, watcher=True) == []


def test_a_signal_once_every_output_is_in_place_ends_nothing(tmp_path):
    """A signal just after the last output is renamed into place: the run
    has succeeded (exit 0, its outputs kept), not 'interrupted' (exit 130)
    with every output complete (R23-6). The commit of each output sends the
    converter a SIGINT as it returns."""
    capture = Calls().frame().write(tmp_path / "c.xz")
    script = (
        "import os, signal, sys\n"
        f"sys.path.insert(0, {os.path.join(os.path.dirname(GL2RBT), '..', 'python')!r})\n"
        "from rbcd.gl2rbt import cli, outputs\n"
        "commit = outputs.SafeText.commit\n"
        "def signalled(self):\n"
        "    commit(self)\n"
        "    os.kill(os.getpid(), signal.SIGINT)\n"
        "outputs.SafeText.commit = signalled\n"
        f"sys.exit(cli.main([{capture!r}, '-o', {str(tmp_path / 'c.rbt')!r}, '--geometry', "
        f"{str(tmp_path / 'c.geo')!r}]))\n")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = subprocess.run(["/usr/bin/python3", "-c", script], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0 and "interrupted" not in r.stderr, (r.returncode, r.stderr)
    assert (tmp_path / "c.rbt").stat().st_size > 0 and (tmp_path / "c.geo").read_text().startswith("rbcd-geometry")
    assert left_behind(tmp_path, ["c.xz", "c.rbt", "c.geo"]) == []
