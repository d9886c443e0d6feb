#!/usr/bin/python3
"""The figures' sweep files (workloads/sweeps/*.toml, docs/results.md): each one
is a valid sweep of the workload suite (rbcd-sweep list: every point checked
by rbcd-sim's own configuration code, nothing runs), and what
scripts/reproduce.sh runs over another --workloads folder (evaluate.py
--sweep-file) is the same sweep: over workloads/ it plans the very runs of the
committed file, so the committed zeb.id_bits of each scene is the one its ids
need.

    test_sweep_files.py --sim build/bin/rbcd-sim
"""
import argparse
import glob
import os
import subprocess
import sys
import tempfile
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SWEEP = os.path.join(ROOT, "scripts", "rbcd-sweep")
EVALUATE = os.path.join(ROOT, "scripts", "evaluate.py")
failures = []


def check(cond, what):
    if not cond:
        failures.append(what)
        print("FAILED:", what)


def listing(sim, path):
    """rbcd-sweep list: [(point, input, args)]."""
    r = subprocess.run(["/usr/bin/python3", SWEEP, "list", path, "--rbcd-sim", sim], capture_output=True, text=True)
    check(r.returncode == 0, f"rbcd-sweep list {path}: exit {r.returncode}: {r.stderr.strip()}")
    return [(l.split("\t")[0], l.split("\t")[1], l.split("\t")[4]) for l in r.stdout.splitlines()]


def derive(template, suite, dest):
    r = subprocess.run(["/usr/bin/python3", EVALUATE, "--sweep-file", template, suite, dest],
                       capture_output=True, text=True)
    check(r.returncode == 0, f"evaluate.py --sweep-file {template} {suite}: {r.stderr.strip()}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sim", required=True)
    sim = os.path.abspath(ap.parse_args().sim)
    suite = os.path.join(ROOT, "workloads")
    scenes = sorted(glob.glob(os.path.join(suite, "*.toml")))
    files = sorted(glob.glob(os.path.join(suite, "sweeps", "*.toml")))
    check([os.path.basename(f) for f in files] == ["fig9.toml", "table3.toml"], f"the figures' sweeps: {files}")
    axes = {"table3.toml": ("zeb.list_length", ["4", "8", "16"]), "fig9.toml": ("zeb.banks", ["1", "2"])}
    with tempfile.TemporaryDirectory(prefix="rbcd_sweep_files.") as tmp:
        for f in files:
            name = os.path.basename(f)
            runs = listing(sim, f)
            key, values = axes.get(name, ("", []))
            check(len(runs) == len(values) * len(scenes), f"{name}: {len(runs)} runs, expected "
                  f"{len(values)} values x {len(scenes)} scenes")
            for point, label, args in runs:
                check(f"--set {key}={values[int(point)]}" in args, f"{name}: point {point} is {key} = "
                      f"{values[int(point)]}: {args}")
            # Over workloads/ itself, the derived sweep plans the committed file's runs.
            dest = os.path.join(tmp, name)
            derive(f, suite, dest)
            check([(p, a) for p, _, a in listing(sim, dest)] == [(p, a) for p, _, a in runs],
                  f"{name}: the sweep reproduce.sh derives over workloads/ runs other runs than the committed one")
            with open(f, "rb") as g, open(dest, "rb") as h:
                a, b = tomllib.load(g), tomllib.load(h)
            check(a["axes"] == b["axes"] and a["results"] == b["results"], f"{name}: axes or results differ")
        # Another suite: its own scenes, with the id bits they need (ids up to 300: 9 bits).
        other = os.path.join(tmp, "suite")
        os.mkdir(other)
        with open(os.path.join(ROOT, "testbench", "eval", "mini", "mini.toml")) as g:
            mini = g.read()
        for n, top in (("a", 5), ("b", 300)):
            with open(os.path.join(other, f"{n}.toml"), "w") as g:
                g.write(mini.replace("id = 1\n", f"id = {top}\n", 1))
        dest = os.path.join(tmp, "other.toml")
        derive(os.path.join(suite, "sweeps", "table3.toml"), other, dest)
        runs = listing(sim, dest)
        check(len(runs) == 6, f"3 points x 2 scenes, got {len(runs)}")
        for _, label, args in runs:
            check(("--set zeb.id_bits=9" in args) == label.endswith("/b.toml"), f"{label}: {args}")
    print("test_sweep_files:", "FAILED" if failures else "ok", f"({len(failures)} failures)")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
