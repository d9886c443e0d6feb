"""rbcd-sweep and rbcd-plot as users run them: the launchers in scripts/ with
/usr/bin/python3, as subprocesses, against the built rbcd-sim and
rbcd-config-check (docs/sweeps.md; docs/testing.md). One CTest entry per test
(sweep_expand, ...; cmake/pytest.cmake); by hand:

    python3 -m pytest testbench/sweep -q
"""
import csv
import difflib
import json
import os
import random
import re
import shlex
import shutil
import signal
import subprocess
import time

import pytest

import rbcd.plot
import rbcd.sweep
from conftest import ROOT, program

SWEEP = os.path.join(ROOT, "scripts", "rbcd-sweep")
PLOT = os.path.join(ROOT, "scripts", "rbcd-plot")
VEC = os.path.join(ROOT, "vectors")


def run(cmd, **kw):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, **kw)


@pytest.fixture
def sim():
    return os.path.abspath(program("rbcd-sim"))


@pytest.fixture
def checker():
    return os.path.abspath(program("rbcd-config-check"))


class Case:
    """A test's directory (tmp) and the programs it runs: rbcd-sweep through its launcher."""

    def __init__(self, sim, checker, tmp):
        self.sim, self.checker, self.tmp = sim, checker, tmp

    def sweep_file(self, name, text):
        p = os.path.join(self.tmp, name)
        with open(p, "w") as f:
            f.write(text)
        return p

    def sweep(self, *args, checker=None):
        """checker: rbcd-config-check's path, or "none" (one rbcd-sim --dump-config a point)."""
        env = dict(os.environ, RBCD_CONFIG_CHECK=checker or self.checker)
        return run(["/usr/bin/python3", SWEEP] + [a for a in args] + ["--rbcd-sim", self.sim]
                   if args[0] in ("run", "list", "slurm") else ["/usr/bin/python3", SWEEP] + list(args), env=env)

    def rows(self, out):
        with open(os.path.join(out, "results.csv"), newline="") as f:
            return list(csv.DictReader(f))

    def read(self, p, mode="r"):
        with open(p, mode) as f:
            return f.read()


def leak_checker_crashed(tmp, text):
    """Sanitizer builds only: LeakSanitizer's tracer now and then faults at a process's exit
    (google/sanitizers#1353; testbench/sim/cli_util.h says more), after the program's own
    work. Its two lines, in the failure or in any run's saved stderr of the case."""
    def crashed(t):
        return "Tracer caught signal" in t and "LeakSanitizer has encountered a fatal error" in t
    if crashed(text):
        return True
    for d, _, files in os.walk(tmp):
        for f in files:
            if f in ("stderr.txt", "result.json") or f.endswith((".err", ".log")):
                try:
                    with open(os.path.join(d, f), errors="replace") as fh:
                        if crashed(fh.read(1 << 20)):
                            return True
                except OSError:
                    pass
    return False


def sweep_case(body):
    """The test `body(c)`, c a Case in a directory of its own. A case that failed because
    LeakSanitizer's tracer crashed in one of its rbcd-sim runs is run again, up to three
    times more (each time in a new directory), as the C++ CLI tests run such a program
    again; a real leak is reported as a leak, not as this."""
    def test(sim, checker, tmp_path_factory):
        for attempt in range(4):
            tmp = str(tmp_path_factory.mktemp(f"rbcd_sweep_{body.__name__.removeprefix('test_')}."))
            try:
                body(Case(sim, checker, tmp))
                return
            except Exception as e:   # a failed assert, or what a crashed run broke in the case itself
                if attempt < 3 and leak_checker_crashed(tmp, str(e)):
                    print(f"warning: LeakSanitizer's tracer crashed at an rbcd-sim exit (a sanitizer runtime "
                          f"bug); the case runs again: {e}")
                    continue
                raise
    test.__name__, test.__qualname__, test.__doc__ = body.__name__, body.__qualname__, body.__doc__
    return test


TRACES = f'traces = ["{VEC}/default.rbt", "{VEC}/multi-frame-mixed.rbt"]'


@sweep_case
def test_expand(c):
    """Grid x zip x inputs x repeats, first axis slowest; zipped keys move together."""
    s = c.sweep_file("s.toml", f"""
[axes]
zeb.banks = [1, 2]
"zeb.list_length" = [4, 6, 8]
[[zip]]
tester.stack_depth = [4, 8]
tester.output = ["raw", "tile"]
[inputs]
{TRACES}
[repeats]
count = 2
first_seed = 7
""")
    r = c.sweep("list", s)
    assert r.returncode == 0, f"list failed: {r.stderr}"
    r2 = c.sweep("list", s, checker="none")
    assert r2.stdout == r.stdout, "rbcd-config-check and rbcd-sim --dump-config plan different runs"
    lines = [l.split("\t") for l in r.stdout.splitlines()]
    assert len(lines) == 2 * 3 * 2 * 2 * 2, f"expected 48 runs, got {len(lines)}"
    pts = []
    for point, label, rep, frames, args in lines:
        sets = dict(a.split("=", 1) for a in shlex.split(args) if "=" in a and not a.startswith("--"))
        assert frames == "-", "no frame ranges without [split]"
        assert sets["memory.seed"] == str(7 + int(rep)), f"repeat {rep} has seed {sets['memory.seed']}"
        pair = (sets["tester.stack_depth"], sets["tester.output"])
        assert pair in (("4", '"raw"'), ("8", '"tile"')), f"zip keys did not move together: {pair}"
        pts.append((int(point), sets["zeb.banks"], sets["zeb.list_length"], pair[0]))
    uniq = sorted(set(pts))
    assert [p[0] for p in uniq] == list(range(12)), "points numbered 0..11"
    assert [p[1:] for p in uniq][:4] == [("1", "4", "4"), ("1", "4", "8"), ("1", "6", "4"), ("1", "6", "8")], \
        f"grid order (first axis slowest, zip last): {uniq[:4]}"
    assert uniq[6][1] == "2", "banks=2 from point 6"
    # A workload suite: the folder's scenes and traces, by name; other files ignored.
    suite = os.path.join(c.tmp, "suite")
    os.mkdir(suite)
    for name in ("b.rbt", "a.toml", "notes.txt"):
        shutil.copy(os.path.join(VEC, "default.rbt") if name.endswith((".rbt", ".txt")) else
                    os.path.join(ROOT, "scene", "default_scene.toml"), os.path.join(suite, name))
    s = c.sweep_file("suite.toml", '[inputs]\nsuites = ["suite"]\ndefault = true\n')
    r = c.sweep("list", s)
    got = [(l.split("\t")[1], l.split("\t")[4].split()[-2:]) for l in r.stdout.splitlines()]
    assert got == [("default", []), ("suite/a.toml", ["--scene", f"{suite}/a.toml"]),
                   ("suite/b.rbt", ["--trace", f"{suite}/b.rbt"])], f"suite inputs: {got} {r.stderr}"
    r = c.sweep("list", os.path.join(ROOT, "docs", "sweep-example.toml"))
    assert r.returncode == 0 and len(r.stdout.splitlines()) == 24, f"docs/sweep-example.toml: {r.stderr}"


@sweep_case
def test_validate(c):
    """Bad keys and values are rejected before anything runs, naming the key, exit 2, nothing written."""
    out = os.path.join(c.tmp, "out")
    bad = [
        ("[axes]\nzeb.banks = [1, 99]\n", "zeb.banks"),
        ("[axes]\nzeb.bnaks = [1, 2]\n", "zeb.bnaks"),
        ("[base]\nset = { \"tester.output\" = \"everything\" }\n", "tester.output"),
        ("[axes]\nmemory.latency_min = [50, 500]\n", "memory.latency_min"),
        ("[axes]\nzeb.banks = [1, 2]\n[[zip]]\nzeb.banks = [3]\n", "zeb.banks"),
        ("[axes]\nzeb.banks = []\n", "zeb.banks"),
        ("[axis]\nzeb.banks = [1]\n", "axis"),
        ("[results]\nfield = [\"totals.hits\"]\n", "results.field"),
        ("[inputs]\ntraces = [\"nope.rbt\"]\n", "nope.rbt"),
        ("[axes]\nzeb.banks = [1, 2\n", "s.toml"),
    ]
    for n, (text, key) in enumerate(bad):
        s = c.sweep_file("s.toml", text)
        r = c.sweep("run", s, "-o", out, "-q")
        msg = r.stderr.strip()
        if n < 4:   # the configuration errors: rbcd-sim itself says the same
            r2 = c.sweep("run", s, "-o", out, "-q", checker="none")
            assert (r2.returncode, r2.stderr.strip()) == (r.returncode, msg), \
                f"{text!r}: rbcd-sim --dump-config says {r2.stderr.strip()!r}, rbcd-config-check {msg!r}"
        assert r.returncode == 2, f"{text!r}: exit {r.returncode}, expected 2 ({msg})"
        assert len(msg.splitlines()) == 1 and msg.startswith("rbcd-sweep: "), f"{text!r}: not one line: {msg!r}"
        assert key in msg, f"{text!r}: message does not name {key}: {msg}"
        assert not os.path.exists(out), f"{text!r}: output directory created"


@sweep_case
def test_input_sets(c):
    """[inputs.set]: keys one input alone runs with; the other inputs' runs (and their ids) are
    unchanged; a bad set is rejected before anything runs, naming it."""
    one, other = f"{VEC}/default.rbt", f"{VEC}/multi-frame-mixed.rbt"
    body = f'[axes]\nzeb.banks = [1, 2]\n[inputs]\ntraces = ["{one}", "{other}"]\n'
    plain = c.sweep_file("plain.toml", body)
    s = c.sweep_file("s.toml", body + f'[inputs.set]\n"{other}" = {{ zeb.id_bits = 8 }}\n')
    r = c.sweep("list", s)
    assert r.returncode == 0, f"list failed: {r.stderr}"
    for line in r.stdout.splitlines():
        label, args = line.split("\t")[1], line.split("\t")[4]
        assert ("--set zeb.id_bits=8" in args) == (label == other), f"{label}: {args}"
    outs = {}
    for name, f in (("plain", plain), ("set", s)):
        outs[name] = os.path.join(c.tmp, name)
        r = c.sweep("run", f, "-o", outs[name], "-q")
        assert r.returncode == 0, f"{name}: {r.stderr}"
    a, b = c.rows(outs["plain"]), c.rows(outs["set"])
    assert len(a) == len(b) == 4, "4 rows each"
    for ra, rb in zip(a, b):
        same = ra["input"] == one
        assert (ra["run"] == rb["run"]) == same, f"{ra['input']}: run ids {ra['run']} / {rb['run']}"
        st = json.load(open(os.path.join(outs["set"], "runs", rb["run"], "stats.json")))
        assert st["config"]["zeb"]["id_bits"] == (7 if same else 8), f"{rb['input']}: id_bits in its stats"
    out = os.path.join(c.tmp, "out")
    for text, key in ((f'"{VEC}/nope.rbt" = {{ zeb.id_bits = 8 }}', "nope.rbt"),
                      (f'"{other}" = {{ zeb.banks = 4 }}', "zeb.banks"),
                      (f'"{other}" = {{ zeb.id_bits = 99 }}', "zeb.id_bits"),
                      (f'"{other}" = 8', other)):
        f = c.sweep_file("bad.toml", body + "[inputs.set]\n" + text + "\n")
        r = c.sweep("run", f, "-o", out, "-q")
        msg = r.stderr.strip()
        assert r.returncode == 2 and len(msg.splitlines()) == 1 and key in msg, f"{text}: exit {r.returncode}: {msg}"
        assert not os.path.exists(out), f"{text}: output directory created"
    f = c.sweep_file("bad.toml", body + f'[repeats]\ncount = 2\n[inputs.set]\n"{other}" = {{ memory.seed = 3 }}\n')
    r = c.sweep("list", f)
    assert r.returncode == 2 and "memory.seed" in r.stderr, f"memory.seed beside [repeats]: {r.stderr}"


@sweep_case
def test_shared_out(c):
    """Two sweeps into one output directory run their common run once (scripts/reproduce.sh's
    Table 3 and Figure 9); a run done without the collisions file the next sweep keeps is rerun."""
    inp = f'[inputs]\ntraces = ["{VEC}/default.rbt"]\n'
    a = c.sweep_file("a.toml", "[axes]\nzeb.banks = [1, 2]\n" + inp)
    b = c.sweep_file("b.toml", "[axes]\nzeb.list_length = [4, 8]\n" + inp + "[results]\ncollisions = true\n")
    out = os.path.join(c.tmp, "out")
    r = c.sweep("run", a, "-o", out)
    assert r.returncode == 0 and "2 runs, 0 already complete" in r.stderr, f"a: {r.stderr}"
    table_a = c.read(os.path.join(out, "results.csv"), "rb")
    shared = c.rows(out)[1]["run"]   # banks = 2: the defaults, as list_length = 8 is
    assert not os.path.exists(os.path.join(out, "runs", shared, "collisions.txt")), "a keeps no collisions"
    r = c.sweep("run", b, "-o", out)
    assert r.returncode == 0 and "2 runs, 0 already complete, 2 to run" in r.stderr, \
        f"b reruns the common run for its collisions file: {r.stderr}"
    rows = c.rows(out)
    assert rows[1]["run"] == shared, "list_length = 8 and banks = 2 are one run (the defaults)"
    assert os.path.isfile(os.path.join(out, "runs", shared, "collisions.txt")), "b's collisions file"
    r = c.sweep("run", a, "-o", out)
    assert r.returncode == 0 and "2 runs, 2 already complete" in r.stderr, f"a again runs nothing: {r.stderr}"
    assert c.read(os.path.join(out, "results.csv"), "rb") == table_a, "a's table is the same again"


@sweep_case
def test_workers(c):
    """The same sweep gives byte-identical results.csv with 1 and 2 workers; wall times in wall.csv."""
    s = c.sweep_file("s.toml", f"""
[axes]
zeb.banks = [1, 2]
"zeb.list_length" = [2, 8]
[inputs]
{TRACES}
[repeats]
count = 2
""")
    outs = []
    for j in ("1", "2"):
        out = os.path.join(c.tmp, f"out{j}")
        r = c.sweep("run", s, "-o", out, "-j", j, "-q")
        assert r.returncode == 0, f"-j{j}: {r.stderr}"
        outs.append(out)
    a, b = (c.read(os.path.join(o, "results.csv"), "rb") for o in outs)
    assert a == b, "results.csv differs between 1 and 2 workers"
    rows = c.rows(outs[0])
    assert len(rows) == 16 and all(r["status"] == "0" for r in rows), "16 successful rows"
    assert rows[0]["memory.seed"] == "1" and rows[1]["memory.seed"] == "2", "seed column"
    for r in rows:
        st = json.load(open(os.path.join(outs[0], "runs", r["run"], "stats.json")))
        assert str(st["totals"]["hits"]) == r["totals.hits"], "row matches its stats JSON"
    walls = list(csv.DictReader(open(os.path.join(outs[0], "wall.csv"))))
    assert sorted(w["run"] for w in walls) == sorted(r["run"] for r in rows), "wall.csv has every run"
    assert all(float(w["wall_s"]) > 0 for w in walls), "wall times recorded"


@sweep_case
def test_failing(c):
    """A run that fails is recorded with its status and error; the others run; exit 1."""
    s = c.sweep_file("s.toml", f"""
[axes]
tile.width = [16, 8]
zeb.banks = [1, 2]
[inputs]
traces = ["{VEC}/default.rbt"]
""")
    out = os.path.join(c.tmp, "out")
    r = c.sweep("run", s, "-o", out, "-q")
    assert r.returncode == 1, f"exit {r.returncode}, expected 1"
    rows = c.rows(out)
    assert len(rows) == 4, "every point has its row"
    for row in rows:
        if row["tile.width"] == "16":
            assert row["status"] == "0" and row["error"] == "" and row["totals.hits"] != "", f"ok row: {row}"
        else:
            assert row["status"] == "2" and "tile" in row["error"] and row["totals.hits"] == "", f"failed row: {row}"
    # A rerun retries the failed runs only.
    r = c.sweep("run", s, "-o", out)
    assert "2 already complete, 2 to run" in r.stderr, f"rerun retries the failed: {r.stderr}"


@sweep_case
def test_unstartable(c):
    """rbcd-sim that cannot be started in the middle of a sweep (here: no longer executable
    after its first run): the sweep stops with one line and exit 1, the finished run stays,
    and the run that could not start leaves no folder behind."""
    sim = os.path.join(c.tmp, "rbcd-sim")
    with open(sim, "w") as f:
        f.write(f'#!/bin/sh\nchmod -x "$0"\nexec {shlex.quote(c.sim)} "$@"\n')
    os.chmod(sim, 0o755)
    s = c.sweep_file("s.toml", """
[axes]
zeb.list_length = [4, 8]
[inputs]
traces = ["%s/default.rbt"]
""" % VEC)
    out = os.path.join(c.tmp, "out")
    env = dict(os.environ, RBCD_CONFIG_CHECK=c.checker)
    r = run(["/usr/bin/python3", SWEEP, "run", s, "-o", out, "-j", "1", "-q", "--rbcd-sim", sim], env=env)
    assert r.returncode == 1, f"exit {r.returncode}, expected 1: {r.stderr}"
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "Permission denied" in lines[0], f"one line naming the error: {r.stderr!r}"
    assert not os.path.exists(os.path.join(out, "results.csv")), "no table from a stopped sweep"
    runs = os.path.join(out, "runs")
    left = sorted(os.listdir(runs))
    done = [d for d in left if os.path.exists(os.path.join(runs, d, "result.json"))]
    assert len(done) == 1, f"the first run finished: {left}"
    assert left == done, f"the run that could not start left a folder: {sorted(set(left) - set(done))}"


@sweep_case
def test_resume(c):
    """A sweep killed mid-way keeps its finished runs; the rerun runs only the rest and gives
    the table an uninterrupted sweep gives."""
    s = c.sweep_file("s.toml", """
[axes]
zeb.list_length = [2, 4, 8]
zeb.banks = [1, 2]
[results]
fields = ["totals.hits", "totals.overflows", "totals.cycles", "gpu.overhead_pct"]
""")   # the default scene: about 0.4 s a run
    out = os.path.join(c.tmp, "killed")
    runs = os.path.join(out, "runs")
    p = subprocess.Popen(["/usr/bin/python3", SWEEP, "run", s, "-o", out, "-j", "1", "-q", "--rbcd-sim", c.sim],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    done = []
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and p.poll() is None:
        done = [d for d in (os.listdir(runs) if os.path.isdir(runs) else [])
                if os.path.exists(os.path.join(runs, d, "result.json"))]
        if len(done) >= 2:
            break
        time.sleep(0.02)
    assert p.poll() is None, "the sweep ended before it could be killed"
    p.send_signal(signal.SIGTERM)
    err = p.communicate()[1]
    assert p.returncode != 0, "a killed sweep does not exit 0"
    assert not os.path.exists(os.path.join(out, "results.csv")), "no table from a killed sweep"
    done = sorted(d for d in os.listdir(runs) if os.path.exists(os.path.join(runs, d, "result.json")))
    assert 2 <= len(done) < 6, f"{len(done)} runs finished before the kill"
    # The interrupted run's folder is gone: only finished runs stay (issue 19).
    assert sorted(os.listdir(runs)) == done, f"partial run folders left: {sorted(set(os.listdir(runs)) - set(done))}"
    stamps = {d: os.stat(os.path.join(runs, d, "result.json")).st_mtime_ns for d in done}
    for d in done:
        assert json.load(open(os.path.join(runs, d, "result.json")))["status"] == 0, "a finished run is complete"
    r = c.sweep("run", s, "-o", out, "-j", "2")
    assert r.returncode == 0, f"resume failed: {r.stderr}"
    assert f"{len(done)} already complete, {6 - len(done)} to run" in r.stderr, f"resume skips finished: {r.stderr}"
    for d, t in stamps.items():
        assert os.stat(os.path.join(runs, d, "result.json")).st_mtime_ns == t, "a finished run was rerun"
    ref = os.path.join(c.tmp, "whole")
    r = c.sweep("run", s, "-o", ref, "-j", "2", "-q")
    assert r.returncode == 0, f"reference sweep failed: {r.stderr}"
    assert c.read(os.path.join(out, "results.csv"), "rb") == c.read(os.path.join(ref, "results.csv"), "rb"), \
        "resumed table differs from the uninterrupted one"


@sweep_case
def test_plot(c):
    """rbcd-plot writes a PNG with matplotlib and with gnuplot; bad columns exit 2."""
    table = os.path.join(c.tmp, "results.csv")
    with open(table, "w") as f:
        f.write("point,input,repeat,zeb.banks,zeb.list_length,totals.overflows,gpu.overhead_pct,status,error,run\n")
        i = 0
        for inp in ("a.rbt", "b.rbt"):
            for banks in (1, 2, 4):
                for m in (4, 8):
                    f.write(f"{i},{inp},0,{banks},{m},{10 * banks // m},{3.5 / banks + m / 10},0,,r{i}\n")
                    i += 1
        f.write(f"{i},a.rbt,0,8,8,,,2,bad input,r{i}\n")
    backends = ["matplotlib", "gnuplot"]
    if run(["/usr/bin/python3", "-c", "import matplotlib"]).returncode != 0:
        print("note: python3-matplotlib missing, only gnuplot tried")
        backends.remove("matplotlib")
    if not shutil.which("gnuplot"):
        print("note: gnuplot missing, only matplotlib tried")
        backends.remove("gnuplot")
    if not backends:
        pytest.skip("neither python3-matplotlib nor gnuplot is installed")
    for b in backends:
        png = os.path.join(c.tmp, f"{b}.png")
        r = run(["/usr/bin/python3", PLOT, table, "--y", "gpu.overhead_pct", "--x", "zeb.banks", "--lines", "input",
                 "-o", png, "--backend", b])
        assert r.returncode == 0, f"{b}: {r.stderr}"
        assert "averaging over zeb.list_length" in r.stderr, f"{b}: names the averaged axis: {r.stderr}"
        data = c.read(png, "rb")
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 1000, f"{b}: not a PNG"
        assert not [f for f in os.listdir(c.tmp) if ".tmp." in f], f"{b}: temporary left behind"
    r = run(["/usr/bin/python3", PLOT, table, "--y", "totals.nope", "--x", "zeb.banks", "-o",
             os.path.join(c.tmp, "x.png")])
    assert r.returncode == 2 and "totals.nope" in r.stderr and not os.path.exists(os.path.join(c.tmp, "x.png")), \
        f"a missing column is an error naming it: {r.stderr}"
    # Axis labels with units, legends without absolute paths (issue 19).
    mod = rbcd.plot
    assert (mod.label("gpu.overhead_pct") == "gpu.overhead_pct (%)" and mod.label("energy.total_nj") == "energy.total_nj (nJ)"
            and mod.label("totals.hits") == "totals.hits (count)" and mod.label("clock.mhz") == "clock.mhz (MHz)"), \
        "axis labels carry units"
    assert (mod.legend_names(["/w/suite/a.rbt", "/w/suite/b.rbt"]) == {"/w/suite/a.rbt": "a.rbt", "/w/suite/b.rbt": "b.rbt"}
            and mod.legend_names(["/w/x/a.toml"]) == {"/w/x/a.toml": "a.toml"}
            and mod.legend_names(["default", "b"]) == {"default": "default", "b": "b"}), \
        "legends without the directories the inputs share"
    # Hostile input (issue 22): a FIFO table is refused, -o naming the table is refused.
    fifo = os.path.join(c.tmp, "t.fifo")
    os.mkfifo(fifo)
    r = run(["/usr/bin/python3", PLOT, fifo, "--y", "gpu.overhead_pct", "--x", "zeb.banks", "-o", os.path.join(c.tmp, "f.png")])
    assert r.returncode == 2 and "is a FIFO" in r.stderr and len(r.stderr.splitlines()) == 1, f"FIFO table: {r.stderr}"
    # A FIFO as -o: one line before any work, not a wait for a reader (R22-7).
    r = run(["/usr/bin/python3", PLOT, table, "--y", "gpu.overhead_pct", "--x", "zeb.banks", "-o", fifo], timeout=60)
    assert r.returncode == 2 and "-o " + fifo + ": cannot create: is a FIFO" in r.stderr \
        and len(r.stderr.splitlines()) == 1, f"FIFO -o: {r.stderr}"
    before = c.read(table)
    r = run(["/usr/bin/python3", PLOT, table, "--y", "gpu.overhead_pct", "--x", "zeb.banks", "-o", table])
    assert r.returncode == 2 and "is the input table" in r.stderr and c.read(table) == before, f"-o = table: {r.stderr}"
    # What no plot can show: one line, no PNG, no warnings (matplotlib's
    # had been printed before "internal error", exit 1; R20-11, R21-5).
    for text, args, needle in (("a,b\n-1,2\n0,3\n", ["--logx"], "--logx: --x a has -1, not a positive number"),
                               ("a,b\nx,2\ny,3\n", ["--logx"], "--logx: --x a is not numeric"),
                               ("a,b\n1,1e308\n2,-1e308\n", [], "--y b: values (or their means) past 1e+300"),
                               ("a,b\n1,8.9e307\n2,-8.9e307\n", [], "--y b: values (or their means) past 1e+300"),
                               ("a,b\n1,1e308\n1,1e308\n", [], "--y b: values (or their means) past 1e+300"),
                               ("a,b\n1,2\n2,3\n", ["--title", "t" * 100000], "--title: 100000 characters"),
                               # Labels and legends past what a plot shows, and
                               # numbers the other tools do not read (R22-8, R22-10).
                               ("a," + "y" * 100000 + "\n1,2\n2,3\n", ["--y", "y" * 100000],
                                "--y: a column name of 100000 characters"),
                               ("a,b,c\n" + "".join(f"1,2,{i}\n" for i in range(101)), ["--lines", "c"],
                                "--lines c: 101 values"),
                               # Refused before a line is computed (a pass per line and x had run for
                               # hours; R23-4).
                               ("a,b,c\n" + "".join(f"{i},2,{i}\n" for i in range(20000)), ["--lines", "c"],
                                "--lines c: 20000 values"),
                               ("a,b\n1,1_000\n2,3\n", [], '--y b: not a number in some rows (e.g. "1_000")'),
                               ("a,b\n1,\u0661\n2,3\n", [], '--y b: not a number in some rows (e.g. "\u0661")')):
        odd, png = c.sweep_file("odd.csv", text), os.path.join(c.tmp, "odd.png")
        for b in backends:
            y = [] if "--y" in args else ["--y", "b"]
            r = run(["/usr/bin/python3", PLOT, odd, *y, "--x", "a", "-o", png, "--backend", b] + args, timeout=120)
            lines = r.stderr.splitlines()
            assert r.returncode == 2 and len(lines) == 1 and lines[0].startswith(f"rbcd-plot: {needle}"), \
                f"{b} {text!r}: {r.stderr}"
            assert not os.path.exists(png)
    # Means in one pass over the rows: 30,000 values of x, each its own
    # point (a pass per x had taken an hour; R23-4).
    wide, png = c.sweep_file("wide.csv", "a,b\n" + "".join(f"{i},{i % 7}\n" for i in range(30000))), \
        os.path.join(c.tmp, "wide.png")
    r = run(["/usr/bin/python3", PLOT, wide, "--y", "b", "--x", "a", "-o", png], timeout=120)
    assert r.returncode == 0 and r.stderr == "" and c.read(png, "rb")[:4] == b"\x89PNG", r.stderr
    # A '$' in a title or a column name is a dollar sign, not TeX (mathtext
    # had failed: internal error, exit 1; R21-6).
    odd, png = c.sweep_file("odd.csv", "$\\sqrt{$,b\n1,2\n2,3\n"), os.path.join(c.tmp, "odd.png")
    for b in backends:
        r = run(["/usr/bin/python3", PLOT, odd, "--y", "b", "--x", "$\\sqrt{$", "-o", png, "--backend", b,
                 "--title", "$\\frac{$"])
        assert r.returncode == 0 and r.stderr == "" and c.read(png, "rb")[:4] == b"\x89PNG", f"{b}: {r.stderr}"
        os.unlink(png)


@sweep_case
def test_frames(c):
    """A long input split in frame ranges (rbcd-sim --frames, [split] in the sweep) merges (rbcd-merge)
    into the collisions file and stats JSON of one whole run, byte for byte, wall time aside."""
    trace = os.path.join(c.tmp, "default.rbt")
    whole_c, whole_s = os.path.join(c.tmp, "whole.txt"), os.path.join(c.tmp, "whole.json")
    r = run([c.sim, "-q", "--write-trace", trace, "--collisions", whole_c, "--stats", whole_s])
    assert r.returncode == 0, f"default scene: {r.stderr}"
    whole = c.read(whole_c)
    # rbcd-sim alone: frames 10..19 are exactly the whole run's lines of those frames.
    part = os.path.join(c.tmp, "part.txt")
    r = run([c.sim, "-q", "--trace", trace, "--frames", "10:19", "--collisions", part])
    assert r.returncode == 0, f"--frames: {r.stderr}"
    body = whole.split("frame 10\n", 1)[1].split("frame 20\n", 1)[0]
    assert c.read(part) == "rbcd-collisions 1\nframe 10\n" + body, "--frames 10:19 differs from the whole run's frames"
    for bad in ("9:3", "x", "1:2:3"):
        r = run([c.sim, "-q", "--trace", trace, "--frames", bad, "--collisions", part])
        assert r.returncode == 2 and r.stderr.startswith("rbcd-sim: --frames: ") and not os.path.exists(part), \
            f"--frames {bad}: exit 2 naming --frames, no output left: {r.stderr}"

    # inputs.frames: a window of every input, run as rbcd-sim --frames.
    s = c.sweep_file("w.toml", f"""
[axes]
zeb.banks = [1, 2]
[inputs]
traces = ["{trace}"]
frames = "10:19"
[results]
fields = ["totals.frames", "totals.hits"]
""")
    r = c.sweep("run", s, "-o", os.path.join(c.tmp, "window"), "-q")
    rows = c.rows(os.path.join(c.tmp, "window"))
    assert r.returncode == 0 and len(rows) == 2 and all(x["totals.frames"] == "10" for x in rows), \
        f"inputs.frames = 10:19: two rows of 10 frames: {rows} {r.stderr}"
    assert rows[1]["totals.hits"] == str(body.count("hit ")), "the window's hits are the whole run's of those frames"
    for bad, needle in (('frames = "9:3"', "inputs.frames"), ('frames = 3', "inputs.frames"),
                        ('frames = "0:9"\n[split]\nframes_per_run = 5', "cannot be combined with inputs.frames")):
        s = c.sweep_file("bad.toml", f'[inputs]\ntraces = ["{trace}"]\n{bad}\n')
        r = c.sweep("list", s)
        assert r.returncode == 2 and needle in r.stderr and len(r.stderr.splitlines()) == 1, \
            f"{bad!r}: exit 2 naming {needle}: {r.returncode} {r.stderr}"

    s = c.sweep_file("s.toml", f"""
[inputs]
traces = ["{trace}"]
[split]
frames_per_run = 25
[results]
fields = ["totals.frames", "totals.hits", "totals.cycles"]
""")
    out = os.path.join(c.tmp, "out")
    r = c.sweep("list", s)
    assert r.returncode == 0 and [l.split("\t")[3] for l in r.stdout.splitlines()] == ["0:24", "25:49", "50:59"], \
        f"60 frames in ranges of 25: {r.stdout}"
    r = c.sweep("run", s, "-o", out, "-q")
    rows = c.rows(out)
    assert len(rows) == 1 and rows[0]["status"] == "0", f"one merged row: {rows} {r.stderr}"
    merged = os.path.join(out, "runs", rows[0]["run"])
    assert c.read(os.path.join(merged, "collisions.txt")) == whole, "merged collisions differ from the whole run's"
    parts = json.load(open(os.path.join(merged, "merged_from.json")))
    assert len(parts) == 3 and all(os.path.isdir(os.path.join(out, "runs", p)) for p in parts), \
        f"merged_from.json names the three ranges' runs: {parts}"
    # The merged stats are the whole run's, byte for byte, wall time aside, once
    # the whole run is given the command line the merge records (its own outputs).
    ms_text = c.read(os.path.join(merged, "stats.json"))
    argv = json.loads(ms_text)["provenance"]["argv"]
    assert "--frames" not in argv, f"merged provenance keeps --frames: {argv}"
    mc = os.path.join(merged, "collisions.txt")
    os.rename(os.path.join(merged, "stats.json"), os.path.join(c.tmp, "merged.json"))
    os.rename(mc, os.path.join(c.tmp, "merged.txt"))
    r = run(argv, cwd=json.loads(ms_text)["provenance"]["working_directory"])
    assert r.returncode == 0, f"the merged provenance's command line: {r.stderr}"
    mask = lambda t: re.sub(r'"(wall_seconds|fragments_per_second)": [^,\n]+', r'"\1": 0', t)
    whole_text = c.read(os.path.join(merged, "stats.json"))
    assert mask(ms_text) == mask(whole_text), "merged stats JSON differs from the whole run's (wall time aside):\n" + \
        "".join(difflib.unified_diff(mask(whole_text).splitlines(True), mask(ms_text).splitlines(True), "whole", "merged"))
    assert c.read(mc) == whole, "whole run by the merged provenance's command differs in collisions"


def one_error_line(r, needle, what):
    """Exit 2, one escaped line holding `needle`, no traceback."""
    assert r.returncode == 2, f"{what}: exit {r.returncode}, expected 2: {r.stderr!r}"
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("rbcd-sweep: "), \
        f"{what}: not one line: {r.stderr!r}"
    assert "Traceback" not in r.stderr and "\x1b" not in r.stderr, f"{what}: traceback or raw ESC: {r.stderr!r}"
    assert needle in r.stderr, f"{what}: {needle!r} not in {r.stderr!r}"


@sweep_case
def test_hostile(c):
    """Issue 22: hostile sweep files and output directories; each failed before."""
    ok = c.sweep_file("ok.toml", "[axes]\nzeb.banks = [1, 2]\n[inputs]\ndefault = true\n")
    # OUT/runs a file: refused before .lock or plan.json is written.
    out = os.path.join(c.tmp, "o1")
    os.makedirs(out)
    with open(os.path.join(out, "plan.json"), "w") as f:
        f.write("{}")
    with open(os.path.join(out, "runs"), "w") as f:
        f.write("")
    r = c.sweep("run", ok, "-o", out, "-q")
    one_error_line(r, "runs exists and is not a directory", "OUT/runs a file")
    assert sorted(os.listdir(out)) == ["plan.json", "runs"] and c.read(os.path.join(out, "plan.json")) == "{}", \
        f"OUT touched: {os.listdir(out)}"
    # -o a dangling symlink: one line, not [Errno 17].
    dangling = os.path.join(c.tmp, "dangling")
    os.symlink(os.path.join(c.tmp, "nowhere"), dangling)
    one_error_line(c.sweep("run", ok, "-o", dangling, "-q"), "exists and is not a directory", "dangling -o")
    # A FIFO as the sweep file: refused, not waited on.
    fifo = os.path.join(c.tmp, "s.fifo")
    os.mkfifo(fifo)
    one_error_line(c.sweep("list", fifo), "cannot read sweep file: is a FIFO", "FIFO sweep file")
    # A FIFO as an input: "not a regular file" (it had been "no such file").
    r = c.sweep("list", c.sweep_file("fifoin.toml", f'[inputs]\ntraces = ["{fifo}"]\n'))
    one_error_line(r, "s.fifo: not a regular file", "FIFO input")
    # Nested 5,000 deep: exit 2 naming the file, not "maximum recursion depth".
    deep = c.sweep_file("deep.toml", "[axes]\nx = " + "[" * 5000 + "]" * 5000 + "\n")
    one_error_line(c.sweep("list", deep), "deep.toml: nested too deep", "5000-deep arrays")
    # An integer of more digits than Python converts (it had been an
    # internal error, ValueError, naming no file; R20-9).
    huge = c.sweep_file("huge.toml", "[axes]\nzeb.banks = [1]\n[repeats]\ncount = " + "9" * 5000 + "\n")
    one_error_line(c.sweep("list", huge), "huge.toml: an integer of more than 4300 digits (at line 4)", "huge int")
    # Run counts capped before expansion (each took minutes or all memory).
    for name, text, needle in (
            ("count.toml", "[repeats]\ncount = 100000000\n", "repeats.count: 100000000"),
            ("axes.toml", "[axes]\n" + "".join(f"k{i}.x = [{', '.join(map(str, range(1000)))}]\n" for i in range(3)),
             "1000000000 runs"),
            ("wide.toml", "[axes]\nk.x = [" + ", ".join(map(str, range(200000))) + "]\n", "200000 runs")):
        t0 = time.monotonic()
        one_error_line(c.sweep("list", c.sweep_file(name, text)), needle, name)
        assert time.monotonic() - t0 < 30, f"{name}: took {time.monotonic() - t0:.0f} s"
    r = c.sweep("list", c.sweep_file("count2.toml", "[repeats]\ncount = 3\n"), "--max-runs", "2")
    one_error_line(r, "3 runs", "--max-runs")
    # Values the checks let through before.
    for text, needle in (('[inputs]\nframes = "0:18446744073709551616"\n', "beyond 2^64 - 1"),
                         ("[slurm]\nmax_parallel = -1\n", "slurm.max_parallel: must be at least 1"),
                         ('[axes]\n"zeb.banks" = [1, 2]\nzeb.banks = [1, 4]\n', "zeb.banks: given twice"),
                         ('[base.set]\n"zeb.banks" = 1\nzeb.banks = 2\n', "zeb.banks: given twice"),
                         ('[[zip]]\n"zeb.banks" = [1]\nzeb.banks = [2]\n', "zeb.banks: given twice")):
        one_error_line(c.sweep("list", c.sweep_file("v.toml", text)), needle, text)
    # Keys with ESC and LF are escaped in messages and in list's output.
    r = c.sweep("list", c.sweep_file("esc.toml", '[axes]\n"a\\u001b[31m\\nb" = [1]\n'))
    one_error_line(r, "a\\x1b[31m\\x0ab", "ESC in a key")
    # A sweep file that is not UTF-8: one line, no traceback.
    bad = os.path.join(c.tmp, "bin.toml")
    with open(bad, "wb") as f:
        f.write(b"[axes]\nx = [\xff\xfe]\n")
    one_error_line(c.sweep("list", bad), "not UTF-8", "binary sweep file")
    # list catches a typo in results.fields (a warning: exit 0).
    r = c.sweep("list", c.sweep_file("typo.toml", '[results]\nfields = ["totls.hits", "totals.hits"]\n'))
    assert (r.returncode == 0 and "results.fields: totls.hits: not a key" in r.stderr
            and "totals.hits:" not in r.stderr), f"typo in results.fields: {r.returncode} {r.stderr}"


@sweep_case
def test_links_planted_in_out_write_nothing_through(c):
    """The sweep's own files in OUT are replaced through a temporary, never
    written through what is planted at their names: a .lock, results.csv or
    wall.csv that is a symlink or a hard link to the sweep's base
    configuration, sweep file or trace had been emptied or overwritten
    (exit 0; round 22's R22-5). A .lock that is not the sweep's own, and a
    runs/ that is a symbolic link, are refused in one line; a run's
    stats.json planted as a symlink is removed before rbcd-sim writes."""
    cfg = c.sweep_file("cfg.toml", "[zeb]\nbanks = 2\n")
    sweep = c.sweep_file("s.toml", f'[base]\nconfig = "{cfg}"\n[axes]\nzeb.list_length = [2, 4]\n'
                         f'[inputs]\ndefault = false\ntraces = ["{VEC}/default.rbt"]\n')
    kept = {p: c.read(p, "rb") for p in (cfg, sweep, f"{VEC}/default.rbt")}

    def intact():
        for p, data in kept.items():
            assert c.read(p, "rb") == data, f"{p} changed"

    for i, plant in enumerate((os.symlink, os.link)):
        out = os.path.join(c.tmp, f"lock{i}")
        os.makedirs(out)
        plant(cfg, os.path.join(out, ".lock"))
        one_error_line(c.sweep("run", sweep, "-o", out, "-q"), "not the sweep's own", f".lock by {plant.__name__}")
        intact()
    out = os.path.join(c.tmp, "o")
    assert c.sweep("run", sweep, "-o", out, "-q").returncode == 0
    for name, target in (("results.csv", cfg), ("wall.csv", f"{VEC}/default.rbt"), ("plan.json", sweep)):
        os.unlink(os.path.join(out, name))
        os.symlink(target, os.path.join(out, name))
    r = c.sweep("run", sweep, "-o", out, "-q")
    assert r.returncode == 0, r.stderr
    assert c.sweep("merge", out).returncode == 0
    intact()
    for name in ("results.csv", "wall.csv", "plan.json"):
        assert not os.path.islink(os.path.join(out, name)), f"{name} still a link"
    assert len(c.rows(out)) == 2
    # A run to do again, its stats.json a link to the sweep file.
    rid = sorted(os.listdir(os.path.join(out, "runs")))[0]
    os.unlink(os.path.join(out, "runs", rid, "result.json"))
    os.unlink(os.path.join(out, "runs", rid, "stats.json"))
    os.symlink(sweep, os.path.join(out, "runs", rid, "stats.json"))
    assert c.sweep("run", sweep, "-o", out, "-q").returncode == 0
    intact()
    assert not os.path.islink(os.path.join(out, "runs", rid, "stats.json"))
    elsewhere = os.path.join(c.tmp, "elsewhere")
    os.makedirs(elsewhere)
    shutil.rmtree(os.path.join(out, "runs"))
    os.symlink(elsewhere, os.path.join(out, "runs"))
    one_error_line(c.sweep("run", sweep, "-o", out, "-q"), "runs exists and is not a directory of its own",
                   "runs a symlink")
    assert os.listdir(elsewhere) == []


@sweep_case
def test_command_lines(c):
    """rbcd-sweep's and rbcd-plot's command lines as the converter's
    (rbcd.cli.ArgumentParser): an option given twice, an abbreviated one,
    a number in other scripts' digits or with '_', a NaN number: one line,
    exit 2, nothing made (each had been taken: the second option replacing
    the first, --max-run as --max-runs, '١' as 1, --poll nan waiting
    forever between polls)."""
    ok = c.sweep_file("ok.toml", "[axes]\nzeb.banks = [1, 2]\n[inputs]\ndefault = true\n")
    out = os.path.join(c.tmp, "out")
    for args, needle in ((["run", ok, "-o", out, "--out", out], "--out is given twice"),
                         (["run", ok, "-o", out, "-j", "1", "--jobs", "2"], "--jobs is given twice"),
                         (["list", ok, "--rbcd-sim", c.sim], "--rbcd-sim is given twice"),
                         (["list", ok, "--max-run", "3"], "unrecognized arguments: --max-run"),
                         (["run", ok, "-o", out, "-j", "\u0661"], "-j/--jobs: invalid integer"),
                         (["list", ok, "--max-runs", "1_0"], "--max-runs: invalid integer"),
                         (["slurm", ok, "-o", out, "--poll", "nan"], "--poll: invalid number"),
                         (["slurm", ok, "-o", out, "--poll", "1e999"], "--poll: invalid number")):
        one_error_line(c.sweep(*args), needle, " ".join(args[2:]))
        assert not os.path.exists(out), args
    # Standard output opened onto the sweep file or a file of the output
    # directory (the listing or the status had been written into it; R19-7).
    before = c.read(ok)
    with open(ok, "r+") as f:
        r = subprocess.run(["/usr/bin/python3", SWEEP, "list", ok, "--rbcd-sim", c.sim], stdout=f,
                           stderr=subprocess.PIPE, text=True, env=dict(os.environ, RBCD_CONFIG_CHECK=c.checker))
    one_error_line(r, "standard output is the sweep file", "list 1<>sweep file")
    assert c.read(ok) == before
    os.makedirs(out)
    with open(os.path.join(out, "plan.json"), "w") as f:
        f.write("{}")
    with open(os.path.join(out, "plan.json"), "r+") as f:
        r = subprocess.run(["/usr/bin/python3", SWEEP, "status", out], stdout=f, stderr=subprocess.PIPE, text=True)
    one_error_line(r, "a file of the output directory", "status 1<>OUT/plan.json")
    assert c.read(os.path.join(out, "plan.json")) == "{}"
    # ... a hard link to it outside the directory, the sweep's base
    # configuration or one of its traces (each had been written over; R20-7).
    link = os.path.join(c.tmp, "plan-link.json")
    os.link(os.path.join(out, "plan.json"), link)
    with open(link, "r+") as f:
        r = subprocess.run(["/usr/bin/python3", SWEEP, "status", out], stdout=f, stderr=subprocess.PIPE, text=True)
    one_error_line(r, "a file of the output directory", "status 1<>hard link to OUT/plan.json")
    assert c.read(os.path.join(out, "plan.json")) == "{}"
    shutil.rmtree(out)
    os.unlink(link)
    cfg = c.sweep_file("cfg.toml", "[zeb]\nlist_length = 8\n")
    trace = os.path.join(c.tmp, "t.rbt")
    shutil.copy(os.path.join(ROOT, "vectors", "multi-frame-mixed.rbt"), trace)
    inputs = c.sweep_file("in.toml", '[base]\nconfig = "cfg.toml"\n[axes]\nzeb.banks = [1, 2]\n'
                                     '[inputs]\ntraces = ["t.rbt"]\n')
    for victim, what in ((cfg, "base.config"), (trace, "input t.rbt")):
        before = open(victim, "rb").read()
        with open(victim, "r+b") as f:
            r = subprocess.run(["/usr/bin/python3", SWEEP, "list", inputs, "--rbcd-sim", c.sim], stdout=f,
                               stderr=subprocess.PIPE, text=True, env=dict(os.environ, RBCD_CONFIG_CHECK=c.checker))
        one_error_line(r, f"standard output is {what}", f"list 1<>{what}")
        assert open(victim, "rb").read() == before
    # The sweep file where the sweep writes in OUT (plan.json): refused, kept
    # (it had been written over by the plan, exit 0; R21-7).
    os.makedirs(os.path.join(c.tmp, "d1"))
    inside = c.sweep_file(os.path.join("d1", "plan.json"), "[axes]\nzeb.banks = [1, 2]\n[inputs]\ndefault = true\n")
    before = c.read(inside)
    one_error_line(c.sweep("run", inside, "-o", os.path.join(c.tmp, "d1"), "-q"), "the sweep writes",
                   "sweep file as OUT/plan.json")
    assert c.read(inside) == before and os.listdir(os.path.join(c.tmp, "d1")) == ["plan.json"]
    table = c.sweep_file("t.csv", "zeb.banks,gpu.cycles\n1,10\n2,20\n")
    png = os.path.join(c.tmp, "p.png")
    for args, needle in ((["--y", "gpu.cycles", "--x", "zeb.banks", "-o", png, "--y", "x"], "--y is given twice"),
                         (["--y", "gpu.cycles", "--x", "zeb.banks", "-o", png, "--logx", "--tit", "t"], "unrecognized arguments: --tit"),
                         (["heatmap", "d.db", "-o", c.tmp, "--frame", "\u0661"], "--frame: invalid integer")):
        r = run(["/usr/bin/python3", PLOT] + ([] if args[0] == "heatmap" else [table]) + args)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1 and needle in r.stderr, (args, r.stderr)
        assert not os.path.exists(png), args


@sweep_case
def test_parser_property(c):
    """Property of the sweep file reader: whatever the file, `list` ends with exit 0 and
    one line per run, or exit 2 and one escaped line; never a traceback or another
    status. Files are drawn at random (fixed seed) from valid pieces, broken pieces and
    random bytes; the reader is imported (rbcd.sweep), in this process, to keep it fast."""
    mod = rbcd.sweep
    rnd = random.Random(22)
    keys = ["zeb.banks", '"zeb.banks"', "zeb.list_length", "clock.mhz", "a.b", "x", '"\\u001b"', "memory.seed"]
    values = ["1", "2", "4", '"s"', "1.5", "true", "-1", "1e400", "[]", "[1, [2]]", "{a = 1}", "99999999999999999999"]
    tables = ["[axes]", "[base.set]", "[[zip]]", "[repeats]", "[inputs]", "[slurm]", "[results]", "[split]",
              "[bogus]", "[axes.zeb]", "[inputs.set]"]
    scalars = ["count", "first_seed", "seeds", "frames", "default", "max_parallel", "runs_per_task", "fields",
               "frames_per_run", "collisions"]

    def piece():
        k = rnd.random()
        if k < 0.3:
            return rnd.choice(tables)
        if k < 0.6:
            vals = ", ".join(rnd.choice(values) for _ in range(rnd.randint(0, 4)))
            return f"{rnd.choice(keys)} = [{vals}]"
        if k < 0.85:
            return rnd.choice(scalars) + " = " + rnd.choice(values + ["[1, 2, 3]", '"0:3"', '"3:1"'])
        return "".join(chr(rnd.randint(0, 0x2fff)) for _ in range(rnd.randint(1, 12)))

    path = os.path.join(c.tmp, "p.toml")
    statuses = {0: 0, 2: 0}
    for i in range(400):
        text = "\n".join(piece() for _ in range(rnd.randint(0, 8))) + "\n"
        with open(path, "w", encoding="utf-8", errors="surrogatepass") as f:
            f.write(text)
        try:
            sw = mod.Sweep(path)
        except mod.SweepError as e:
            msg = mod.escape(str(e))
            assert "\n" not in msg and "\x1b" not in msg and msg.startswith(path), f"file {i}: message {msg!r}"
            statuses[2] += 1
            continue
        except Exception as e:   # the property: nothing else escapes the reader
            raise AssertionError(f"file {i}: {type(e).__name__}: {e}\n{text!r}") from e
        n = len(sw.inputs) * len(sw.seeds)
        for _, vals in sw.dims:
            n *= len(vals)
        assert n <= sw.max_runs, f"file {i}: {n} runs past the cap"
        assert len(sw.points()) * len(sw.inputs) * len(sw.seeds) == n, f"file {i}: points do not multiply out"
        statuses[0] += 1
    assert statuses[0] > 10 and statuses[2] > 10, f"both outcomes drawn: {statuses}"


@sweep_case
def test_warnings(c):
    """rbcd-sim's warnings are kept per run (runs/ID/stderr.txt) and summarized
    (OUT/warnings.txt, one line on stderr); wall.csv says which frames each run ran;
    progress in a log comes at least every tenth of the runs (issue 19)."""
    mesh = os.path.join(c.tmp, "open.obj")
    with open(mesh, "w") as f:   # one triangle: an open mesh, which rbcd-sim warns about
        f.write("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    scene = os.path.join(c.tmp, "scene.toml")
    with open(scene, "w") as f:
        f.write('format = "rbcd-scene 1"\nframes = 2\n[screen]\nwidth = 64\nheight = 48\n'
                '[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\nfov_y = 45.0\nnear = 0.5\nfar = 60.0\n'
                '[[object]]\nid = 1\nmesh = "open.obj"\n')
    s = c.sweep_file("s.toml", f'[axes]\nzeb.banks = [1, 2, 4, 8]\n[inputs]\nscenes = ["{scene}"]\n')
    out = os.path.join(c.tmp, "out")
    r = c.sweep("run", s, "-o", out, "-j", "2")
    assert r.returncode == 0, f"sweep failed: {r.stderr}"
    rows = c.rows(out)
    for row in rows:
        err = c.read(os.path.join(out, "runs", row["run"], "stderr.txt"))
        assert ": warning: " in err and "open" in err, f"run {row['run']}: stderr.txt lacks the warning: {err!r}"
    summary = c.read(os.path.join(out, "warnings.txt"))
    assert summary.startswith("4 runs (") and "open" in summary and len(summary.splitlines()) == 1, \
        f"warnings.txt: {summary!r}"
    assert "4 runs printed 1 distinct rbcd-sim warnings" in r.stderr, f"no summary on stderr: {r.stderr}"
    with open(os.path.join(out, "wall.csv"), newline="") as f:
        frames = [w["frames"] for w in csv.DictReader(f)]
    assert frames == ["0:1"] * 4, f"wall.csv frames column: {frames}"
    # Progress in a log (not a terminal): a line at every tenth of the runs at least.
    progress = [l for l in r.stderr.splitlines() if " runs, " in l and " failed, " in l]
    assert len(progress) >= 4, f"sparse progress: {progress}"


@sweep_case
def test_plot_reads_a_table_in_bounded_memory(c):
    """rbcd-plot keeps no row of its table: a 20 MB table of 25 columns
    plots within 160 MB of peak memory, matplotlib included (a dict a row
    had taken 333 MB for it, and about 15 GB at the 256 MiB limit; R23-4);
    and what it reads is what csv.DictReader reads: CR LF and CR line
    ends, a quoted field across lines, blank lines, a column named twice
    (its last place); and its errors in the same order."""
    rng = random.Random(1)
    cols = ["point", "input", "repeat", "zeb.banks", "zeb.list_length"] + [f"totals.c{i}" for i in range(15)] \
        + ["gpu.overhead_pct", "status", "error", "run"]
    big = os.path.join(c.tmp, "big.csv")
    with open(big, "w") as f:
        f.write(",".join(cols) + "\n")
        i = 0
        while f.tell() < 20_000_000:
            f.write(",".join([str(i), f"in{i % 5}.rbt", "0", str(1 << i % 3), str(4 << i % 3)]
                             + [str(rng.randint(0, 10 ** 9)) for _ in range(15)]
                             + [f"{rng.random() * 10:.6f}", "0", "", f"r{i}"]) + "\n")
            i += 1
    png = os.path.join(c.tmp, "big.png")
    peak = ("import resource, subprocess, sys; r = subprocess.run(sys.argv[1:]); "
            "print('maxrss', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr); "
            "sys.exit(r.returncode)")
    r = run(["/usr/bin/python3", "-c", peak, "/usr/bin/python3", PLOT, big, "--y", "gpu.overhead_pct", "--x",
             "zeb.banks", "--lines", "input", "-o", png], timeout=300)
    assert r.returncode == 0 and c.read(png, "rb")[:4] == b"\x89PNG", r.stderr
    mb = int(re.search(r"maxrss (\d+)", r.stderr).group(1)) / 1024
    print(f"rbcd-plot: {os.path.getsize(big) / 1e6:.1f} MB table, {mb:.0f} MB peak")
    assert mb < 160, f"{mb:.0f} MB peak for a 20 MB table"
    odd = ('a,b,c,b\r\n1,2,"x\r\ny",5\r\n\r\n2,3,z,6\r3,4,z,7\n1,8,"q,r",9\n')
    path = c.sweep_file("odd.csv", odd)
    import argparse
    import io
    for lines in (None, "c"):
        args = argparse.Namespace(y="b", x="a", lines=lines, where=[])
        xs, data, _ = rbcd.plot.series(rbcd.plot.Table(path, args), args)
        rows = list(csv.DictReader(io.StringIO(odd, newline="")))
        want = {}
        for ln in dict.fromkeys(r[lines] if lines else "" for r in rows):
            pts = {}
            for r in rows:
                if (r[lines] if lines else "") == ln:
                    pts.setdefault(r["a"], []).append(float(r["b"]))
            want[ln] = [(x, sum(v) / len(v)) for x, v in sorted(pts.items())]
        assert xs == ["1", "2", "3"] and data == want, (data, want)
    # A row of another length, then a field past csv's limit: the table is
    # read whole before its rows' lengths are named, as DictReader read it
    # (R25-10).
    bad = c.sweep_file("bad.csv", "a,b,c\n1,2\n1,2,\"" + "x" * 200000 + "\"\n")
    r = run(["/usr/bin/python3", PLOT, bad, "--y", "b", "--x", "a", "-o", png])
    assert r.returncode == 2 and r.stderr.splitlines() == [
        f"rbcd-plot: {bad}: not a results table: field larger than field limit (131072)"], r.stderr
