"""The figures' sweep files (workloads/sweeps/*.toml, docs/results.md): each one
is a valid sweep of the workload suite (rbcd-sweep list: every point checked
by rbcd-sim's own configuration code, nothing runs), and what
scripts/reproduce.sh runs over another --workloads folder (rbcd.evaluate
--sweep-file) is the same sweep: over workloads/ it plans the very runs of the
committed file, so the committed zeb.id_bits of each scene is the one its ids
need."""
import glob
import os
import subprocess
import tomllib

import pytest

import conftest
from rbcd import evaluate

SWEEP = os.path.join(conftest.ROOT, "scripts", "rbcd-sweep")
SUITE = os.path.join(conftest.ROOT, "workloads")


@pytest.fixture
def sim():
    return conftest.program("rbcd-sim")


def listing(sim, path):
    """rbcd-sweep list: [(point, input, args)]."""
    r = subprocess.run(["/usr/bin/python3", SWEEP, "list", path, "--rbcd-sim", sim], capture_output=True, text=True)
    assert r.returncode == 0, f"rbcd-sweep list {path}: exit {r.returncode}: {r.stderr.strip()}"
    return [(line.split("\t")[0], line.split("\t")[1], line.split("\t")[4]) for line in r.stdout.splitlines()]


def derive(template, suite, dest):
    """What reproduce.sh runs: evaluate.py --sweep-file TEMPLATE SUITE DEST."""
    rc = evaluate.run(["--sweep-file", template, suite, dest])
    assert rc == 0, f"evaluate.py --sweep-file {template} {suite}: exit {rc} (its message above)"


def test_sweep_files(sim, tmp_path):
    scenes = sorted(glob.glob(os.path.join(SUITE, "*.toml")))
    files = sorted(glob.glob(os.path.join(SUITE, "sweeps", "*.toml")))
    assert [os.path.basename(f) for f in files] == ["fig9.toml", "table3.toml"], f"the figures' sweeps: {files}"
    axes = {"table3.toml": ("zeb.list_length", ["4", "8", "16"]), "fig9.toml": ("zeb.banks", ["1", "2"])}
    for f in files:
        name = os.path.basename(f)
        runs = listing(sim, f)
        key, values = axes.get(name, ("", []))
        assert len(runs) == len(values) * len(scenes), \
            f"{name}: {len(runs)} runs, expected {len(values)} values x {len(scenes)} scenes"
        for point, label, args in runs:
            assert f"--set {key}={values[int(point)]}" in args, \
                f"{name}: point {point} is {key} = {values[int(point)]}: {args}"
        # Over workloads/ itself, the derived sweep plans the committed file's runs.
        dest = str(tmp_path / name)
        derive(f, SUITE, dest)
        assert [(p, a) for p, _, a in listing(sim, dest)] == [(p, a) for p, _, a in runs], \
            f"{name}: the sweep reproduce.sh derives over workloads/ runs other runs than the committed one"
        with open(f, "rb") as g, open(dest, "rb") as h:
            a, b = tomllib.load(g), tomllib.load(h)
        assert a["axes"] == b["axes"] and a["results"] == b["results"], f"{name}: axes or results differ"


def test_sweep_files_other_suite(sim, tmp_path):
    """Another suite: its own scenes, with the id bits they need (ids up to 300: 9 bits)."""
    other = tmp_path / "suite"
    other.mkdir()
    with open(os.path.join(conftest.ROOT, "testbench", "eval", "mini", "mini.toml")) as g:
        mini = g.read()
    for n, top in (("a", 5), ("b", 300)):
        (other / f"{n}.toml").write_text(mini.replace("id = 1\n", f"id = {top}\n", 1))
    dest = str(tmp_path / "other.toml")
    derive(os.path.join(SUITE, "sweeps", "table3.toml"), str(other), dest)
    runs = listing(sim, dest)
    assert len(runs) == 6, f"3 points x 2 scenes, got {len(runs)}"
    for _, label, args in runs:
        assert ("--set zeb.id_bits=9" in args) == label.endswith("/b.toml"), f"{label}: {args}"
