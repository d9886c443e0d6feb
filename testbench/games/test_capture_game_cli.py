"""scripts/capture-game.sh's refusals (docs/games.md): an output folder it
cannot use (empty, a symlink, dangling or not, a missing folder or a file
in its place) or an
unusable TMPDIR is one line, exit 2, before any game runs or any conversion
starts; a capture holding fewer frames than asked for, or an empty one, is
one line, exit 2.
capture.toml records any map path and any TMPDIR as TOML reads them back;
a map path TOML cannot hold (not UTF-8) is refused before the work.
Run with --from-trace (no game needed); nothing is left."""
import os
import shutil
import signal
import subprocess
import time
import tomllib

import pytest

from conftest import ROOT, program

CAPTURE_GAME = os.path.join(ROOT, "scripts", "capture-game.sh")


def capture_game(tmp_path, *args, tmpdir=None, raster=True):
    """The script's run; raster=False for a refusal that comes before it
    looks for rbcd-gl-raster (the test then needs no build)."""
    env = dict(os.environ, TMPDIR=str(tmpdir or tmp_path))
    if raster:
        env["RBCD_GL_RASTER"] = program("rbcd-gl-raster")
    return subprocess.run(["bash", CAPTURE_GAME] + [str(a) for a in args], capture_output=True, text=True,
                          env=env, stdin=subprocess.DEVNULL, timeout=600)


def refused(r, *words):
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and all(w in lines[0] for w in words), \
        f"exit {r.returncode}, {lines} (wanted {words})"
    assert "converting" not in r.stdout and "capturing" not in r.stdout, "refused only after the work started"


def test_an_unusable_output_folder_is_refused_before_the_work(tmp_path):
    for tool in ("apitrace", "gzip", "sha256sum"):
        if subprocess.run(["bash", "-c", f"command -v {tool}"], capture_output=True).returncode:
            pytest.skip(f"{tool} is missing (scripts/setup.sh --gl --games)")
    cap = tmp_path / "not-looked-at.trace"
    cap.write_bytes(b"refused before the converter reads it, or by it")
    os.symlink(tmp_path / "nowhere" / "x", tmp_path / "dangling")
    os.symlink(tmp_path, tmp_path / "to-a-folder")
    base = ["openarena", "oa_dm1", "3"]
    refused(capture_game(tmp_path, *base, "", "--from-trace", cap), "OUT_DIR is empty")
    refused(capture_game(tmp_path, *base, tmp_path / "dangling", "--from-trace", cap), "is a symlink")
    refused(capture_game(tmp_path, *base, tmp_path / "to-a-folder", "--from-trace", cap), "is a symlink")
    refused(capture_game(tmp_path, *base, tmp_path / "no" / "x", "--from-trace", cap), "does not exist")
    # A file where the entry's folder should be (it was said not to exist).
    for out in (cap / "x", cap / "a" / "x"):
        refused(capture_game(tmp_path, *base, out, "--from-trace", cap),
                f"{out}: {cap} is not a directory: the entry needs a folder there")
    # A leading zero (bash would read 08 as octal) and an output folder
    # that reads as an option to dirname.
    refused(capture_game(tmp_path, *base, tmp_path / "out", "--from-trace", cap, "--skip", "08"),
            "--skip '08' is not a number")
    # An empty value is no value: it had been taken as the option left out
    # (a game captured afresh, the default skip; R23-5).
    refused(capture_game(tmp_path, *base, tmp_path / "out", "--from-trace", ""), "--from-trace needs a capture")
    refused(capture_game(tmp_path, *base, tmp_path / "out", "--from-trace", cap, "--skip", ""),
            "--skip needs a number")
    os.chdir(tmp_path)
    r = capture_game(tmp_path, *base, "-x", "--from-trace", cap, "--skip", "0")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "dirname" not in lines[0] and "not-looked-at" in lines[0], \
        f"an output folder named -x: exit {r.returncode}, {lines} (its capture is the one refused)"
    refused(capture_game(tmp_path, *base, tmp_path / "out", "--from-trace", cap, tmpdir=tmp_path / "missing"),
            "cannot create a work directory", "TMPDIR")
    assert sorted(os.listdir(tmp_path)) == ["dangling", "not-looked-at.trace", "to-a-folder"], "something was left"


@pytest.mark.parametrize("game, map_, options, option", [
    ("openarena", "oa_dm1", ["--bots", "2", "--bots", "3"], "--bots"),
    ("openarena", "oa_dm1", ["--bots", "2", "--skip", "0", "--bots", "2"], "--bots"),
    ("supertuxkart", "lighthouse", ["--karts", "2", "--karts", "3"], "--karts"),
    ("openarena", "oa_dm1", ["--skip", "0", "--skip", "1"], "--skip"),
    ("openarena", "oa_dm1", ["--keep-trace", "--keep-trace"], "--keep-trace"),
    ("openarena", "oa_dm1", ["--from-trace", "other.trace"], "--from-trace"),
], ids=["bots", "bots_same_value", "karts", "skip", "keep_trace", "from_trace"])
def test_an_option_given_twice_is_refused_before_the_work(tmp_path, monkeypatch, game, map_, options, option):
    """Every option at most once, as the converter takes its own (R17-8:
    --bots 2 --bots 3 captured with 3 bots, exit 0): one line naming it,
    exit 2, before anything is looked for, started or made. The capture
    given (--from-trace) is no capture: had the option passed, no game ran
    and the converter refused it, with another line."""
    for name in ("not-a-capture.trace", "other.trace"):
        (tmp_path / name).write_bytes(b"not a capture\n")
    monkeypatch.chdir(tmp_path)
    r = capture_game(tmp_path, game, map_, "2", tmp_path / "out", "--from-trace", "not-a-capture.trace", *options,
                     raster=False)
    refused(r, f"capture-game.sh: {option} is given twice")
    assert sorted(os.listdir(tmp_path)) == ["not-a-capture.trace", "other.trace"], "something was made"


def boxes_capture():
    """The test program's capture (testbench/gl/test_gl_capture.py makes it)."""
    for d in (os.environ.get("RBCD_GL_CAPTURES"),
              os.environ.get("RBCD_BIN") and os.path.join(os.environ["RBCD_BIN"], "..", "testbench", "gl", "captures"),
              os.path.join(ROOT, "build", "testbench", "gl", "captures")):
        if d and os.path.isfile(os.path.join(d, "boxes.trace")):
            return os.path.join(d, "boxes.trace")
    pytest.skip("no capture of testbench/gl/gl_boxes.c (the gl tests make it: ctest -R gl_capture)")


def test_more_frames_than_the_capture_holds(tmp_path):
    cap = boxes_capture()
    r = capture_game(tmp_path, "openarena", "oa_dm1", "500", tmp_path / "out", "--from-trace", cap, "--skip", "0")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "frames asked for" in lines[0], (r.returncode, lines)
    assert os.listdir(tmp_path) == [], "something was left"


@pytest.mark.parametrize("game, map_", [("neverball", "demo.nbr"), ("openarena", "oa_dm1"),
                                         ("supertuxkart", "lighthouse")])
def test_an_empty_capture_is_bad_input(tmp_path, game, map_):
    """--from-trace of an empty file: one line naming it, exit 2 (it had
    been 'the game or its capture failed (exit 0); its log:' and tail's
    complaint that the game's log, never made, was missing: exit 1);
    nothing left."""
    cap = tmp_path / "empty.trace"
    cap.write_bytes(b"")
    if game == "neverball":
        map_ = tmp_path / map_
        map_.write_bytes(b"")
    r = capture_game(tmp_path, game, map_, "1", tmp_path / "out", "--from-trace", cap, "--skip", "0")
    refused(r, f"capture-game.sh: {cap}: an empty file, not a capture")
    assert sorted(os.listdir(tmp_path)) == sorted(["empty.trace"] + (["demo.nbr"] if game == "neverball" else []))


def test_a_capture_without_the_race_is_bad_input(tmp_path):
    """--from-trace supertuxkart with a capture that never draws the race
    (the test program's): one line naming it, exit 2."""
    cap = boxes_capture()
    r = capture_game(tmp_path, "supertuxkart", "lighthouse", "2", tmp_path / "out", "--from-trace", cap)
    lines = [line for line in r.stderr.strip().splitlines()]
    assert r.returncode == 2 and len(lines) == 1 and "no frame draws the race" in lines[0], (r.returncode, lines)
    assert not (tmp_path / "out").exists()


def test_names_that_read_as_options(tmp_path):
    """An output folder and a capture whose names begin with '-' are
    files like any other: the entry is made (mv had taken the folder
    '--keep-trace' for an option after the work, exit 1 and two lines; the
    converter, the capture '-boxes.trace')."""
    os.chdir(tmp_path)
    os.symlink(boxes_capture(), tmp_path / "-boxes.trace")
    r = capture_game(tmp_path, "openarena", "oa_dm1", "2", "--keep-trace", "--from-trace", "-boxes.trace",
                     "--skip", "0")
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert sorted(os.listdir(tmp_path / "--keep-trace")) == ["calls.xz", "capture.toml", "summary.jsonl"]
    assert sorted(os.listdir(tmp_path)) == ["--keep-trace", "-boxes.trace"], "something else was left"


def test_a_capture_named_by_dev_stdin(tmp_path):
    """--from-trace /dev/stdin with the capture redirected: the script reads
    the capture more than once, by the file /dev/stdin names (each read of
    the descriptor had taken on where the last left off: "the capture has
    no frame"; round 22's R22-9)."""
    with open(boxes_capture(), "rb") as cap:
        r = subprocess.run(["bash", CAPTURE_GAME, "openarena", "oa_dm1", "2", str(tmp_path / "out"), "--from-trace",
                            "/dev/stdin", "--skip", "0"], capture_output=True, text=True, stdin=cap, timeout=600,
                           env=dict(os.environ, TMPDIR=str(tmp_path), RBCD_GL_RASTER=program("rbcd-gl-raster")))
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert sorted(os.listdir(tmp_path / "out")) == ["calls.xz", "capture.toml", "summary.jsonl"]


def test_a_full_device_is_one_line(tmp_path):
    """OUT_DIR on a full file system (a 4 KiB tmpfs): one line, exit 1,
    nothing left there (mv had written a line for each file)."""
    if os.geteuid() != 0 or shutil.which("unshare") is None:
        pytest.skip("needs root and unshare to mount a small tmpfs")
    full = tmp_path / "full"
    full.mkdir()
    script = (f"mount -t tmpfs -o size=4k tmpfs {full} || exit 77; "
              f"bash {CAPTURE_GAME} openarena oa_dm1 2 {full}/entry --from-trace {boxes_capture()} --skip 0; "
              f"rc=$?; ls -A {full} >&2; exit $rc")
    env = dict(os.environ, RBCD_GL_RASTER=program("rbcd-gl-raster"), TMPDIR=str(tmp_path))
    r = subprocess.run(["unshare", "-m", "--propagation", "private", "bash", "-c", script], capture_output=True,
                       text=True, env=env, stdin=subprocess.DEVNULL, timeout=600)
    if r.returncode == 77:
        pytest.skip("cannot mount a tmpfs here")
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 1 and len(lines) == 1 and "write failed" in lines[0], (r.returncode, lines)


def toml_of(entry):
    with open(entry / "capture.toml", "rb") as f:
        return tomllib.load(f)


@pytest.mark.parametrize("folder", ['q"d', "b\\q", "n\nl", "de\x7f", "t\tb", "e\u00e9\u0085\\1"],
                         ids=["quote", "backslash", "newline", "del", "tab", "unicode"])
def test_a_map_path_toml_must_escape(tmp_path, folder):
    """A neverball replay in a folder whose name holds a quote, a backslash
    or a control character: its path is written into capture.toml's command
    line escaped, and reads back as it is (it was written raw, and game-suite
    refused the entry capture-game.sh had said it wrote, exit 0)."""
    d = tmp_path / "maps" / folder
    d.mkdir(parents=True)
    (d / "x.nbr").write_text("x\n")
    r = capture_game(tmp_path, "neverball", d / "x.nbr", "1", tmp_path / "entry", "--from-trace",
                     boxes_capture(), "--skip", "0")
    assert r.returncode == 0, (r.returncode, r.stderr)
    assert sorted(os.listdir(tmp_path)) == ["entry", "maps"], "something else was left"
    doc = toml_of(tmp_path / "entry")
    assert doc["command"] == ["env", "HOME=TMP/home", "/usr/games/neverball", "-r", os.path.realpath(d / "x.nbr")]
    assert doc["map"] == "x.nbr" and doc["game"] == "neverball"
    r = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "scripts", "game-suite"), "check",
                        tmp_path / "entry"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr


def test_a_map_path_toml_cannot_hold_is_refused_before_the_work(tmp_path):
    """A path that is not UTF-8 has no TOML form: refused naming it, one
    line, exit 2, before the game (or the conversion), nothing left."""
    d = tmp_path / os.fsdecode(b"u\xffx")
    d.mkdir()
    (d / "x.nbr").write_text("x\n")
    (tmp_path / "tmp").mkdir()
    refused(capture_game(tmp_path, "neverball", d / "x.nbr", "1", tmp_path / "entry", "--from-trace",
                         boxes_capture(), "--skip", "0", tmpdir=tmp_path / "tmp"),
            "u\\xffx/x.nbr", "not UTF-8", "capture.toml")
    assert sorted(os.listdir(tmp_path)) == sorted([os.fsdecode(b"u\xffx"), "tmp"]) and not os.listdir(tmp_path / "tmp")


@pytest.mark.parametrize("name", ["tp|x", "tb[x", "tq\\1x", "ta&x", "td.x", "tn\nx", 't"x'],
                         ids=["pipe", "bracket", "backref", "ampersand", "dot", "newline", "quote"])
@pytest.mark.parametrize("game", ["openarena", "neverball"])
def test_any_tmpdir_works(tmp_path, name, game):
    """TMPDIR is a path like any other: its work directory is written TMP in
    capture.toml's command line, replaced as text (a sed pattern made of the
    path had failed after the conversion, exit 1, with sed's message)."""
    tmpdir = tmp_path / name
    tmpdir.mkdir()
    (tmp_path / "x.nbr").write_text("x\n")
    args = ["oa_dm1", "2"] if game == "openarena" else [tmp_path / "x.nbr", "1"]
    r = capture_game(tmp_path, game, *args, tmp_path / "entry", "--from-trace", boxes_capture(), "--skip", "0",
                     tmpdir=tmpdir)
    assert r.returncode == 0, (r.returncode, r.stderr)
    command = toml_of(tmp_path / "entry")["command"]
    assert ("HOME=TMP/home" if game == "neverball" else "TMP/home") in command, command
    assert not any(name in a for a in command), command
    assert os.listdir(tmpdir) == [], "the work directory was left"


def test_standard_output_onto_the_capture_is_refused_before_a_line(tmp_path):
    """--from-trace T with standard output opened onto T (1<>T): refused
    before the script writes a progress line into it (its first 43 bytes
    had been overwritten before the converter refused it; R19-6)."""
    cap = tmp_path / "kept.trace"
    cap.write_bytes(b"a kept capture's bytes, left as they are" * 4)
    before = cap.read_bytes()
    env = dict(os.environ, TMPDIR=str(tmp_path))
    with open(cap, "r+b") as out:
        r = subprocess.run(["bash", CAPTURE_GAME, "openarena", "oa_dm1", "3", str(tmp_path / "out"),
                            "--from-trace", str(cap)], stdout=out, stderr=subprocess.PIPE, text=True, env=env,
                           stdin=subprocess.DEVNULL, timeout=600)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "standard output is the capture" in lines[0], lines
    assert cap.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["kept.trace"]


@pytest.mark.parametrize("which", ["rules", "map"], ids=["rules", "map"])
def test_standard_output_onto_the_rules_or_a_map_file_is_refused(tmp_path, which):
    """Standard output opened onto the game's selection rules (a copy of
    the tree, so that the committed file is never at stake) or onto a map
    given as a file: refused in one line before the progress line is
    written (it had overwritten the rules' first 43 bytes; R20-8)."""
    tree = tmp_path / "tree"
    (tree / "scripts").mkdir(parents=True)
    shutil.copy(CAPTURE_GAME, tree / "scripts")
    (tree / "workloads" / "games").mkdir(parents=True)
    for f in os.listdir(os.path.join(ROOT, "workloads", "games")):
        if f.endswith("-select.toml"):
            shutil.copy(os.path.join(ROOT, "workloads", "games", f), tree / "workloads" / "games")
    os.symlink(os.path.join(ROOT, "python"), tree / "python")
    cap = tmp_path / "kept.trace"
    cap.write_bytes(b"a kept capture's bytes, left as they are" * 4)
    replay = tmp_path / "r.nbr"
    replay.write_bytes(b"a replay's bytes" * 4)
    game, victim = (("openarena", tree / "workloads" / "games" / "openarena-select.toml") if which == "rules"
                    else ("neverball", replay))
    before = victim.read_bytes()
    env = dict(os.environ, TMPDIR=str(tmp_path), RBCD_GL_RASTER=program("rbcd-gl-raster"))
    with open(victim, "r+b") as out:
        r = subprocess.run(["bash", tree / "scripts" / "capture-game.sh", game,
                            "oa_dm1" if which == "rules" else str(replay), "3", str(tmp_path / "out"),
                            "--from-trace", str(cap)], stdout=out, stderr=subprocess.PIPE, text=True, env=env,
                           stdin=subprocess.DEVNULL, timeout=600)
    lines = r.stderr.strip().splitlines()
    assert r.returncode == 2 and len(lines) == 1 and "standard output is an input of the capture" in lines[0], lines
    assert victim.read_bytes() == before
    assert not (tmp_path / "out").exists()



def session_process(sid, marker):
    """A process of session `sid` whose command line holds `marker`, or None."""
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open(f"/proc/{d}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            with open(f"/proc/{d}/cmdline", "rb") as f:
                cmd = f.read()
        except OSError:
            continue
        if int(fields[3]) == sid and fields[0] != "Z" and marker in cmd:
            return int(d)
    return None


@pytest.mark.parametrize("moment", ["helper", "conversion"])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT], ids=["term", "hup", "int"])
def test_a_signal_is_one_line_and_exit_130(tmp_path, sig, moment):
    """SIGINT, SIGTERM or SIGHUP to the script's process group while its
    Python helper makes capture.toml's strings or while the converter works
    (the helper, or the converter's rasterizer, held stopped meanwhile, as a
    busy machine may hold it): exit 130, one
    line saying "interrupted" (the script's or the converter's, not both),
    nothing left (round 33's D5 and D6: a BrokenPipeError traceback, or
    death by the signal with nothing said)."""
    # The converter's rasterizer: the converter has its handlers by then.
    marker = b"capture_strings" if moment == "helper" else b"rbcd-gl-raster"

    def stop_it(p):
        found = session_process(p.pid, marker)
        try:
            if found:
                os.kill(found, signal.SIGSTOP)
        except ProcessLookupError:   # gone between the two
            found = None
        return found
    interrupted_while_stopped(tmp_path, dict(os.environ, TMPDIR=str(tmp_path)), sig, stop_it)
    assert os.listdir(tmp_path) == [], os.listdir(tmp_path)


def interrupted_while_stopped(tmp_path, env, sig, stopped):
    """The script run on the boxes capture into tmp_path/out; `sig` to its
    process group while the process `stopped(p)` finds is held stopped,
    which then goes on: the script says "interrupted" in one line and exits
    130."""
    p = subprocess.Popen(["bash", CAPTURE_GAME, "openarena", "oa_dm1", "2", str(tmp_path / "out"), "--from-trace",
                          boxes_capture(), "--skip", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                         text=True, env=dict(env, RBCD_GL_RASTER=program("rbcd-gl-raster")), stdin=subprocess.DEVNULL,
                         start_new_session=True, preexec_fn=lambda: signal.signal(sig, signal.SIG_DFL))
    try:
        found, t = None, time.monotonic()
        while found is None and p.poll() is None and time.monotonic() - t < 60:
            found = stopped(p)
        assert found, "the process to stop was never seen"
        os.killpg(p.pid, sig)
        time.sleep(0.3)
        try:
            os.kill(found, signal.SIGCONT)
        except ProcessLookupError:   # the converter stopped its rasterizer
            pass
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
        p.wait()
    lines = err.strip().splitlines()
    assert p.returncode == 130 and len(lines) == 1 and lines[0].endswith("interrupted"), (p.returncode, lines)


@pytest.mark.parametrize("folder", ["staged", "work"])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP], ids=["term", "hup"])
def test_a_signal_while_the_folders_are_made_leaves_neither(tmp_path, sig, folder):
    """SIGTERM or SIGHUP to the script's process group while mktemp makes
    the staged entry or the work folder (a mktemp first in PATH that stops
    itself once the folder exists, as a busy machine may hold it there):
    exit 130, one line, neither folder left (round 34's D4: the folder mktemp
    had made was left, unnamed, when the signal killed it)."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    marker = ".out." if folder == "staged" else "capture-game."
    (bin_dir / "mktemp").write_text(f'#!/bin/sh\nd=$(/usr/bin/mktemp "$@") || exit 1\n'
                                    f'case "$d" in *{marker}*) kill -STOP $$;; esac\nprintf "%s\\n" "$d"\n')
    (bin_dir / "mktemp").chmod(0o755)
    work = tmp_path / "w"
    work.mkdir()

    def stopped_mktemp(p):
        pid = session_process(p.pid, str(bin_dir / "mktemp").encode())
        try:
            with open(f"/proc/{pid}/stat") as f:
                return pid if f.read().rsplit(")", 1)[1].split()[0] == "T" else None
        except (OSError, TypeError):
            return None
    interrupted_while_stopped(work, dict(os.environ, TMPDIR=str(work), PATH=f"{bin_dir}:{os.environ['PATH']}"), sig,
                              stopped_mktemp)
    assert os.listdir(work) == [], os.listdir(work)
