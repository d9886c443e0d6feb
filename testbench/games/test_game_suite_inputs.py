"""game-suite held to the project's rule for bad input (docs/games.md): an
entry's capture.toml nested too deep or with a key of too many dotted
parts, or whose selection file is missing or not a file, is one line
naming the file and key (or line), exit 2, as is a
summary.jsonl not as the converter writes it (CR LF line ends); expand
never writes into an entry's inputs (or anywhere else) through a link or
another name for them in its output folder: refused before anything is
opened, nothing changed."""
import os
import shutil
import signal
import subprocess
import time

import pytest

from conftest import ROOT, program

GAME_SUITE = os.path.join(ROOT, "scripts", "game-suite")
SOURCE = os.path.join(ROOT, "workloads", "games", "neverball-locks")
NAME = "neverball-locks"


@pytest.fixture
def entry(tmp_path):
    """A copy of neverball-locks (its selection file stays the repository's)."""
    d = tmp_path / "entries" / NAME
    shutil.copytree(SOURCE, d)
    return d


def game_suite(tmp_path, *args):
    env = dict(os.environ, TMPDIR=str(tmp_path))
    try:
        env["RBCD_GL_RASTER"] = program("rbcd-gl-raster")
    except pytest.skip.Exception:
        pass   # the refusals come before any conversion
    return subprocess.run(["/usr/bin/python3", GAME_SUITE] + [str(a) for a in args], capture_output=True,
                          text=True, env=env, stdin=subprocess.DEVNULL, timeout=600)


def refused(r, *words):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and all(w in lines[0] for w in words), \
        f"exit {r.returncode}, {lines} (wanted {words})"


def snapshot(d):
    return {p: open(os.path.join(d, p), "rb").read() for p in sorted(os.listdir(d))}


@pytest.mark.parametrize("options, words", [
    (["--frames", "\u0661"], "argument --frames: invalid integer"),       # ARABIC-INDIC DIGIT ONE
    (["--frames", "\uff11"], "argument --frames: invalid integer"),       # FULLWIDTH DIGIT ONE
    (["--frames", "1_0"], "argument --frames: invalid integer"),
    (["--frames", " 1 "], "argument --frames: invalid integer"),
    (["--frames", "1", "-j", "\u0662"], "argument -j/--jobs: invalid integer"),
    (["--frames", "1", "--jobs", "1_0"], "argument -j/--jobs: invalid integer"),
    (["--frames", "1", "--jobs", " 1 "], "argument -j/--jobs: invalid integer"),
    (["--frames", "1", "--frames", "1"], "--frames is given twice"),
    (["--frames", "1", "-j", "1", "--jobs", "2"], "--jobs is given twice"),
    (["--frames", "1", "-j1", "-j1"], "-j is given twice"),
    (["--frames", "1", "-o", "OTHER"], "-o is given twice"),
    (["--frames", "1", "--out", "OTHER"], "--out is given twice"),
    (["--fram", "1"], "unrecognized arguments: --fram"),
], ids=["frames_arabic_indic", "frames_fullwidth", "frames_underscore", "frames_spaces", "jobs_arabic_indic",
        "jobs_underscore", "jobs_spaces", "frames_twice", "jobs_twice", "jobs_attached_twice", "out_twice",
        "out_long_twice", "frames_abbreviated"])
def test_expand_takes_each_option_once_and_ascii_numbers(tmp_path, options, words):
    """expand's command line as the converter's (R17-8): a number in ASCII
    digits (int() took '\u0661', '1_0' and ' 1 ': --frames \u0661 converted
    a frame), each option at most once (a second -o or --frames replaced
    the first, exit 0), its name whole (--fram had been --frames). One line
    naming the option, exit 2, before anything is made or converted."""
    out = tmp_path / "out"
    options = [str(tmp_path / "other") if o == "OTHER" else o for o in options]
    r = game_suite(tmp_path, "expand", "-o", out, *options, SOURCE)
    refused(r, f"game-suite: {words}")
    assert os.listdir(tmp_path) == [], "something was made"


def test_a_capture_description_nested_too_deep(tmp_path, entry):
    toml = entry / "capture.toml"
    toml.write_text(toml.read_text() + "deep = " + "[" * 20000 + "]" * 20000 + "\n")
    refused(game_suite(tmp_path, "check", entry), str(toml), "nested too deep to read")


def test_a_capture_description_with_an_integer_python_cannot_convert(tmp_path, entry):
    """5,000 digits: one line naming the file (it had been an internal
    error, exit 1; R20-9)."""
    toml = entry / "capture.toml"
    toml.write_text(toml.read_text() + "huge = " + "7" * 5000 + "\n")
    refused(game_suite(tmp_path, "check", entry), str(toml), "an integer of more than 4300 digits")


def test_a_capture_description_with_a_key_of_too_many_dotted_parts(tmp_path, entry):
    """tomllib's memory grows with the square of a dotted key's parts (R16-7:
    a 64 KB capture.toml of 32,000 parts took 3.9 GB and 10 s): a key of more
    than 64 parts is refused before it, naming the file and the line."""
    toml = entry / "capture.toml"
    text = toml.read_text()
    toml.write_text(text + "k" + ".k" * 32000 + " = 1\n")
    line = text.count("\n") + 1
    r = game_suite(tmp_path, "check", entry)
    refused(r, f"{toml}:{line}: a key of 32001 dotted parts, more than 64")


@pytest.mark.parametrize("selection, words", [
    ("workloads/games/no-such-select.toml", "missing"),
    ("workloads/games", "not a regular file"),
    ("workloads/games/neverball-select.toml\\u0000x", "must be a path inside the repository"),
], ids=["missing", "directory", "nul"])
def test_check_refuses_an_entry_without_its_selection_file(tmp_path, entry, selection, words):
    toml = entry / "capture.toml"
    text = toml.read_text()
    start = text.index('selection = "')
    end = text.index('"', start + len('selection = "'))
    toml.write_text(text[:start] + f'selection = "{selection}"' + text[end + 1:])
    refused(game_suite(tmp_path, "check", entry), str(toml), "selection", words)


@pytest.mark.parametrize("make", ["fifo", "directory", "device"])
def test_a_reduced_capture_that_is_not_a_file_is_said_to_be_so(tmp_path, entry, make):
    """calls.xz a FIFO, a directory or a symlink to a device: "not a
    regular file", not "missing" (round 14's R14-12), and not opened."""
    calls = entry / "calls.xz"
    calls.unlink()
    if make == "fifo":
        os.mkfifo(calls)
    elif make == "directory":
        calls.mkdir()
    else:
        calls.symlink_to("/dev/zero")
    refused(game_suite(tmp_path, "check", entry), str(calls), "cannot read the reduced capture: not a regular file")


@pytest.mark.parametrize("output, target", [
    (f"{NAME}.summary.jsonl", "summary.jsonl"),
    (f"{NAME}.geo", "capture.toml"),
    (f"{NAME}.rbt.zst", "calls.xz"),
    (f"{NAME}.capture", None),   # a file outside the entry
], ids=["summary", "geometry", "trace", "unrelated"])
@pytest.mark.parametrize("link", ["symlink", "hard link"])
def test_expand_never_writes_through_its_output_folder_into_an_input(tmp_path, entry, output, target, link):
    """A link planted in expand's output folder (its summary.jsonl once
    went from 150 lines to 1 with exit 0; its capture.toml became a
    geometry)."""
    victim = tmp_path / "victim.txt"
    victim.write_text("not expand's\n")
    out = tmp_path / "out"
    out.mkdir()
    dest = entry / target if target else victim
    (os.symlink if link == "symlink" else os.link)(dest, out / output)
    before, kept = snapshot(entry), victim.read_text()
    r = game_suite(tmp_path, "expand", "-o", out, "--frames", "1", "-j", "1", entry)
    if link == "symlink":
        refused(r, str(out / output), "a symlink")
    elif target:
        refused(r, str(out / output), "is also ", f" of {NAME}")
    else:   # a hard link to an unrelated file is a file of expand's output folder: replaced, not written through
        assert r.returncode == 0, r.stderr
        assert victim.read_text() == kept
    assert snapshot(entry) == before, "an input of the entry changed"
    assert victim.read_text() == kept, "a file outside the output folder changed"
    assert not [p for p in os.listdir(out) if p.startswith(".")], "a temporary was left"


def test_expand_refuses_a_fifo_among_its_outputs(tmp_path, entry):
    """A FIFO where expand writes an entry's output: one line naming it,
    exit 2, before anything is opened (the converter had waited for a
    reader for ever)."""
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / f"{NAME}.geo")
    p = subprocess.Popen(["/usr/bin/python3", GAME_SUITE, "expand", "-o", out, "--frames", "1", "-j", "1", entry],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, stdin=subprocess.DEVNULL,
                         env=dict(os.environ, TMPDIR=str(tmp_path)), start_new_session=True)
    try:
        stdout, stderr = p.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)   # the converter and its rasterizer too
        p.communicate()
        pytest.fail("expand waited for a reader of the FIFO")
    r = subprocess.CompletedProcess(p.args, p.returncode, stdout, stderr)
    refused(r, f"{out / NAME}.geo: cannot create: is a FIFO, not a regular file")
    assert os.listdir(out) == [f"{NAME}.geo"]


def test_a_summary_of_more_lines_than_frames_is_refused_cheaply(tmp_path, entry):
    """An entry's summary.jsonl holds a line a frame: 30 million short lines
    (60 MB, under the read limit) are refused before being split (they had
    taken 2.2 GB), naming the file."""
    (entry / "summary.jsonl").write_bytes(b"a\n" * (30 << 20))
    r = subprocess.run(["/usr/bin/time", "-f", "maxrss %M", "/usr/bin/python3", GAME_SUITE, "expand", "-o",
                        tmp_path / "out", "--frames", "1", entry], capture_output=True, text=True,
                       env=dict(os.environ, TMPDIR=str(tmp_path)), timeout=600)
    lines = [line for line in r.stderr.splitlines() if not line.startswith(("maxrss", "Command exited"))]
    assert r.returncode == 2 and len(lines) == 1 and "not a line for each of the entry's 150 frames" in lines[0], lines
    peak_mb = int(r.stderr.split("maxrss ")[1].split()[0]) / 1024
    assert peak_mb < 400, f"{peak_mb:.0f} MB for a 60 MB summary"


def test_an_entry_is_a_named_folder_whose_summary_matches_its_frames(tmp_path, entry):
    """The root is no entry (its name would be empty); "." is the folder's
    own name (outputs named after it, not "..rbt.zst"); a capture.toml
    claiming more frames than its summary's lines is refused."""
    refused(game_suite(tmp_path, "check", "/"), "an entry is a folder with a name")
    r = subprocess.run(["/usr/bin/python3", GAME_SUITE, "check", "."], capture_output=True, text=True, cwd=entry,
                       env=dict(os.environ, TMPDIR=str(tmp_path)), timeout=600)
    assert r.returncode == 0 and r.stdout.startswith(f"{NAME}: "), (r.stdout, r.stderr)
    toml = entry / "capture.toml"
    toml.write_text(toml.read_text().replace("frames = 150", "frames = 100000", 1))
    refused(game_suite(tmp_path, "expand", "-o", tmp_path / "out", "--frames", "1", entry),
            "not a line for each of the entry's 100000 frames")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT], ids=["term", "int"])
def test_an_interrupted_expand_leaves_nothing(tmp_path, sig):
    """SIGTERM or SIGINT to expand while an entry converts: the converter is
    stopped with it and nothing is left: no file in the output folder (the
    conversion had run on to its end and left the whole entry, .capture
    included, after 'interrupted'), nor the folders expand made for it
    (they had stayed, empty)."""
    program("rbcd-gl-raster")
    out = tmp_path / "made" / "out"
    env = dict(os.environ, TMPDIR=str(tmp_path), RBCD_GL_RASTER=program("rbcd-gl-raster"))
    p = subprocess.Popen(["/usr/bin/python3", GAME_SUITE, "expand", "-o", out, "--frames", "40", SOURCE],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         stdin=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and not (out.is_dir() and os.listdir(out)):
        time.sleep(0.05)   # until the converter's temporaries are there
    assert p.poll() is None, "expand ended before it was interrupted"
    p.send_signal(sig)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 130 and err.strip().splitlines() == ["game-suite: interrupted"], (p.returncode, err)
    time.sleep(1)
    assert os.listdir(tmp_path) == [], "an interrupted expand left files or folders"


def test_a_converter_killed_outright_leaves_nothing(tmp_path):
    """The converter SIGKILLed while it writes an entry (no handler of its
    own runs): expand says the conversion failed (exit 1) and removes what
    it had begun: the temporaries beside the outputs, the output folder it
    made and the converter's temporary folders (round 14's R14-13: `.NAME.geo.XXXXXXXX` and a folder
    in TMPDIR stayed)."""
    program("rbcd-gl-raster")
    out, tmp = tmp_path / "out", tmp_path / "tmp"
    tmp.mkdir()
    env = dict(os.environ, TMPDIR=str(tmp), RBCD_GL_RASTER=program("rbcd-gl-raster"))
    p = subprocess.Popen(["/usr/bin/python3", GAME_SUITE, "expand", "-o", out, "--frames", "40", SOURCE],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                         stdin=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    converter = None
    while time.monotonic() < deadline and converter is None:
        time.sleep(0.05)
        kids = subprocess.run(["pgrep", "-P", str(p.pid), "-f", "rbcd-gl2rbt"], stdout=subprocess.PIPE,
                              text=True).stdout.split()
        if kids and out.is_dir() and os.listdir(out):   # its temporaries are there
            converter = int(kids[0])
    assert converter is not None, "no converter seen writing"
    os.kill(converter, signal.SIGKILL)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 1 and "conversion failed" in err, (p.returncode, err)
    time.sleep(1)   # (its rasterizer, left without input, ends and removes its own)
    assert not out.exists() and os.listdir(tmp) == [], (os.listdir(tmp_path), os.listdir(tmp))


def test_frames_past_the_entry_expand_the_whole_entry(tmp_path):
    """--frames K of more frames than the entry has: the entry's frames,
    checked against its checksums, and said as many (it reported K frames,
    unchecked)."""
    program("rbcd-gl-raster")
    r = game_suite(tmp_path, "expand", "-o", tmp_path / "out", "--frames", "100000", SOURCE)
    assert r.returncode == 0 and r.stdout.strip() == f"{NAME}: 150 frames", (r.returncode, r.stdout, r.stderr)


@pytest.mark.parametrize("edit, words", [
    (lambda t: t.replace(b"\n", b"\r\n"), "line 1 ends in CR LF"),
    (lambda t: t.replace(b"\n", b"\r\n", 3).replace(b"\r\n", b"\n", 2), "line 3 ends in CR LF"),
    (lambda t: t.replace(b",", b"\r,", 1), "line 1 holds a CR"),
    (lambda t: b"\xef\xbb\xbf" + t, "line 1: not a JSON object"),
    (lambda t: t[:t.index(b"\n", 100)] + b"\nnot json" + t[t.index(b"\n", 100):t.rindex(b"\n", 0, -1) + 1],
     "line 2: not a JSON object"),
    (lambda t: t + b"x", "not a line for each"),
    # JSON, but not as the converter writes a frame's figures.
    (lambda t: t.replace(b",", b", ", 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'"frame":0,', b'"frame":0.0,', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'"draws":', b'"draws":NaN,"x":', 1), "line 1: not a JSON object"),
    (lambda t: t.replace(b'"draws":', b'"draws":"1","x":', 1), "line 1: not as the converter writes"),
    (lambda t: t[:t.index(b"\n") + 1] * 2 + t[t.index(b"\n", t.index(b"\n") + 1) + 1:], "line 2: not frame 1"),
    # Compact JSON of integers, but not the converter's line (these had
    # passed, then converted: exit 1 'the regenerated summary differs').
    (lambda t: t.replace(b'"frame":0,"end_call":70077,', b'"end_call":70077,"frame":0,', 1),
     "line 1: not as the converter writes a frame's figures (its keys are not frame, end_call"),
    (lambda t: t.replace(b',"cprims":', b',"x":2,"cprims":', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'}\n', b',"x":2}\n', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b',"tiles":1500', b'', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'"objects":[11,13,', b'"objects":[13,11,', 1), "line 1: not as the converter writes a "
     "frame's figures (objects: not object ids (0 to 2^32 - 1) in increasing order, each once)"),
    (lambda t: t.replace(b'"objects":[11,13,', b'"objects":[11,11,', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'"objects":[11,', b'"objects":[-1,', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'"draws":136,', b'"draws":-136,', 1), "line 1: not as the converter writes a frame's "
     "figures (draws: not a count (an integer from 0 to 2^64 - 1))"),
    (lambda t: t.replace(b'"culled":', b'"culled":18446744073709551616,"y":', 1), "line 1: not as the converter"),
    (lambda t: t.replace(b'"culled":237184', b'"culled":18446744073709551616', 1), "(culled: not a count"),
    (lambda t: t.replace(b'"draws":136', b'"draws":1e2', 1), "line 1: not as the converter writes"),
    (lambda t: t.replace(b'}\n', b',"discard_draws":0,"discard_collisionable":0}\n', 1),
     "line 1: not as the converter writes"),
    # Past --frames 1: the whole file is checked (it had not been: exit 0).
    (lambda t: t.replace(b'"frame":1,', b'"frame":1,"x":2,', 1), "line 2: not as the converter writes"),
    (lambda t: t.replace(b'"frame":149,"end_call":', b'"end_call":', 1), "line 150: not as the converter writes"),
], ids=["crlf", "crlf_line3", "cr", "bom", "not_json", "unterminated", "spaces", "float", "nan", "string",
        "frame_twice", "key_order", "extra_key", "extra_key_last", "missing_key", "objects_unsorted",
        "objects_twice", "object_negative", "negative_count", "count_2_64_other_key", "count_2_64", "exponent",
        "effects_half", "line2_extra_key", "last_line_missing_key"])
def test_a_summary_not_as_the_converter_writes_it_is_the_entrys_error(tmp_path, entry, edit, words):
    """An entry's summary.jsonl that no conversion can match (CR LF line
    ends; a line that is not a JSON object) is bad input, one line naming
    the file and line, exit 2, before any conversion, nothing written (with
    CR LF ends the entry had been converted, then 'the regenerated summary
    differs', exit 1)."""
    summary = entry / "summary.jsonl"
    text = summary.read_bytes()
    summary.write_bytes(edit(text))
    assert summary.read_bytes().count(b"\n") == text.count(b"\n")
    out = tmp_path / "out"
    r = game_suite(tmp_path, "expand", "-o", out, "--frames", "1", "-j", "1", entry)
    refused(r, str(summary), words)
    assert not out.exists() or os.listdir(out) == [], "something was written"
    refused(game_suite(tmp_path, "check", entry), str(summary), words)


def test_every_entry_is_checked_before_any_conversion(tmp_path, entry):
    """A bad summary.jsonl in the second entry given: refused before the
    first entry converts (it had converted, -j 1, before the second was
    read), nothing written."""
    other = tmp_path / "more" / "neverball-copy"
    shutil.copytree(entry, other)
    summary = other / "summary.jsonl"
    summary.write_bytes(summary.read_bytes().replace(b'"frame":2,', b'"frame":2,"x":0,', 1))
    out = tmp_path / "out"
    r = game_suite(tmp_path, "expand", "-o", out, "--frames", "1", "-j", "1", entry, other)
    refused(r, str(summary), "line 3: not as the converter writes")
    assert not out.exists() or os.listdir(out) == [], "something was written"


def test_the_committed_summaries_are_as_the_converter_writes_them():
    """game-suite's form of a summary line is the converter's: the fragment
    effects' keys its own, and every committed entry passes check."""
    from rbcd import game_suite
    from rbcd.gl2rbt.glstate.draws import FRAGMENT_EFFECT_KEYS
    assert game_suite.EFFECT_KEYS == FRAGMENT_EFFECT_KEYS
    entries = sorted(os.path.join(os.path.dirname(SOURCE), d) for d in os.listdir(os.path.dirname(SOURCE))
                     if os.path.isdir(os.path.join(os.path.dirname(SOURCE), d)))
    r = subprocess.run(["/usr/bin/python3", GAME_SUITE, "check"] + entries, capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0 and r.stderr == "" and r.stdout.count("summary.jsonl is as the converter writes it") \
        == len(entries) > 0, (r.returncode, r.stdout, r.stderr)


@pytest.mark.parametrize("tool", ["game-suite", "rbcd-sweep", "rbcd-plot"])
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["int", "term"])
def test_a_signal_at_start_up_is_an_interruption(tmp_path, tool, sig):
    """A signal before the tool's own handlers are in place (Python still
    loading its modules) ends it in one line, "interrupted", exit 130
    (round 14's R14-3: a traceback, or a silent death by SIGTERM). Sent
    while the child still blocks it (its mask taken from here), it arrives
    at the launcher's first moment (rbcd.startup)."""
    p = subprocess.Popen(["/usr/bin/python3", os.path.join(ROOT, "scripts", tool), "--help"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: (signal.signal(sig, signal.SIG_DFL),
                                             signal.pthread_sigmask(signal.SIG_BLOCK, [sig])))
    os.kill(p.pid, sig)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 130 and err.splitlines() == [f"{tool}: interrupted"] and out == "", (p.returncode, err)


@pytest.mark.parametrize("tool", ["game-suite", "rbcd-sweep", "rbcd-plot", "rbcd-gl2rbt"])
def test_a_signal_at_any_moment_of_start_up_is_one_line_or_none(tool):
    """The launcher run as a user runs it (its interpreter line), sent
    SIGINT every 4 ms from the start to 100 ms (and later, until a run gets
    past Python's start-up on a loaded machine): the run ends in
    "interrupted", exit 130, or finishes, or dies of the signal saying
    nothing (before env blocks it: microseconds); never in a traceback
    (round 19's R19-10: Python's "Fatal Python error: init_import_site" in
    15 of 30 runs signalled 30 to 70 ms in, while Python imported its site
    module before the launcher's first line; round 15's R15-8: a
    KeyboardInterrupt through the launcher's imports). Standard output has
    the whole help or nothing."""
    launcher = os.path.join(ROOT, "scripts", tool)
    whole = subprocess.run([launcher, "--help"], capture_output=True, text=True, timeout=60).stdout
    assert whole.startswith("usage:")
    seen = set()
    for ms in list(range(0, 101, 4)) + [160, 240, 320, 480, 640, 960, 1280, 1920, 2560]:
        if ms > 100 and seen & {0, 130}:
            break
        p = subprocess.Popen([launcher, "--help"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        time.sleep(ms / 1000)
        try:
            p.send_signal(signal.SIGINT)
        except ProcessLookupError:
            pass
        out, err = p.communicate(timeout=60)
        if p.returncode == 130:
            assert err.splitlines() == [f"{tool}: interrupted"] and out == "", (ms, err)
        elif p.returncode == 0:
            assert err == "" and out == whole, (ms, out, err)
        else:   # (the help written, then the signal at Python's exit: the same)
            assert p.returncode == -signal.SIGINT and err == "" and out in ("", whole), (ms, p.returncode, err)
        seen.add(p.returncode)
    assert seen & {0, 130}, seen


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_signal_once_the_work_is_done_changes_nothing(sig):
    """A signal that comes after a tool's work has ended, as Python
    finishes, changes nothing: the exit status is the work's, with no
    message (rbcd-sweep run had exited 143 or 129 with its results
    complete, its handler gone and the default action taken; round 21's
    R21-11). Sent to itself by a program whose work returned 0, right after
    the tools' common wrapper (rbcd.cli.main_wrapper) returns."""
    script = ("import os, signal, sys\n"
              f"sys.path.insert(0, {os.path.join(ROOT, 'python')!r})\n"
              "from rbcd.cli import main_wrapper\n"
              "status = main_wrapper('tool', lambda argv: 0, [])\n"
              f"os.kill(os.getpid(), signal.{sig})\n"
              "sys.exit(status)\n")
    r = subprocess.run(["/usr/bin/python3", "-c", script], capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout, r.stderr) == (0, "", ""), r


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_signal_while_help_is_written_leaves_the_whole_help_and_exit_0(sig):
    """A signal that comes while --help is written (sent by standard
    output's own write, so it cannot miss the moment): the whole help, exit
    0, nothing on standard error. The tools' parser (rbcd.cli.ArgumentParser)
    holds the signals while it writes and drops them at its exit (CI's run
    of the start-up test above had "interrupted", exit 130, after the whole
    help: the signal came between the write and argparse's exit)."""
    script = ("import io, os, signal, sys\n"
              f"sys.path.insert(0, {os.path.join(ROOT, 'python')!r})\n"
              "from rbcd.cli import ArgumentParser, main_wrapper\n"
              "class Signalling(io.TextIOWrapper):\n"
              "    def write(self, text):\n"
              f"        os.kill(os.getpid(), signal.{sig})\n"
              "        return super().write(text)\n"
              "sys.stdout = Signalling(open(1, 'wb', closefd=False), encoding='utf-8')\n"
              "def fn(argv):\n"
              "    ArgumentParser(prog='tool').parse_args(argv)\n"
              "    return 3\n"
              "sys.exit(main_wrapper('tool', fn, ['--help']))\n")
    r = subprocess.run(["/usr/bin/python3", "-c", script], capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout, r.stderr) == (0, "usage: tool [-h]\n\noptions:\n"
                                                     "  -h, --help  show this help message and exit\n", ""), r


@pytest.mark.parametrize("tool", ["game-suite", "rbcd-sweep", "rbcd-plot", "rbcd-gl2rbt"])
def test_help_onto_a_full_device_is_one_line(tool):
    """--help onto /dev/full: one line naming standard output, exit 1 (the
    converter's had ended in a traceback, the others' in "internal error")."""
    with open("/dev/full", "w") as full:
        r = subprocess.run([os.path.join(ROOT, "scripts", tool), "--help"], stdout=full, stderr=subprocess.PIPE,
                           text=True, timeout=60)
    assert (r.returncode, r.stderr) == (1, f"{tool}: standard output: write failed: No space left on device\n"), r


@pytest.mark.parametrize("which, mode", [("calls.xz", "r+b"), ("summary.jsonl", "r+b"), ("capture.toml", "ab")],
                         ids=["calls_read_write", "summary_read_write", "toml_append"])
def test_check_with_standard_output_onto_an_entry_s_file_is_refused(tmp_path, entry, which, mode):
    """`check` writes its report to standard output: opened onto one of the
    entry's files (1<>calls.xz, >>capture.toml), refused before a line is
    written (the report had overwritten the reduced capture, exit 0; R19-5)."""
    before = {p: p.read_bytes() for p in entry.iterdir()}
    with open(entry / which, mode) as out:
        env = dict(os.environ, TMPDIR=str(tmp_path))
        r = subprocess.run(["/usr/bin/python3", GAME_SUITE, "check", str(entry)], stdout=out, stderr=subprocess.PIPE,
                           text=True, env=env, stdin=subprocess.DEVNULL, timeout=600)
    what = {"calls.xz": "the reduced capture"}.get(which, which)
    refused(r, f"{entry / which}: standard output is {what} of {NAME}: ")
    assert {p: p.read_bytes() for p in entry.iterdir()} == before
