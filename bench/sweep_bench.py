#!/usr/bin/python3
"""Benchmark of scripts/rbcd-sweep (docs/sweeps.md, "Speed"): a sweep of 200
short points (4 axes over the first 5 frames of the default scene written as a
trace, about 0.1 s a run) with 1 worker and with 2, each into a fresh output
directory. Prints the runner's overhead against the runs' own wall time and
the speed-up of 2 workers over 1.

    bench/sweep_bench.py build/bin/rbcd-sim [--points 200] [--frames 5]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SWEEP = os.path.join(ROOT, "scripts", "rbcd-sweep")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("sim")
    ap.add_argument("--points", type=int, default=200, choices=[50, 100, 200])
    ap.add_argument("--frames", type=int, default=5, help="frames of the default scene per run")
    ap.add_argument("--keep", action="store_true")
    a = ap.parse_args()
    sim = os.path.abspath(a.sim)
    tmp = tempfile.mkdtemp(prefix="rbcd_sweep_bench.")
    try:
        full = os.path.join(tmp, "full.rbt")
        subprocess.run([sim, "-q", "--write-trace", full], check=True)
        short = os.path.join(tmp, "short.rbt")
        with open(full) as f, open(short, "w") as o:
            for line in f:
                if line.startswith(f"frame {a.frames}"):
                    break
                o.write(line)
        outputs = ["raw", "pixel"] if a.points == 200 else ["raw"]
        stacks = [2, 4, 8, 16, 32] if a.points >= 100 else [2, 4, 8, 16, 32][:5]
        lists = [2, 4, 6, 8, 10]
        banks = [1, 2, 3, 4][: a.points // (len(outputs) * len(stacks) * len(lists))]
        sweep = os.path.join(tmp, "bench.toml")
        with open(sweep, "w") as f:
            f.write(f"[axes]\nzeb.list_length = {lists}\nzeb.banks = {banks}\ntester.stack_depth = {stacks}\n"
                    f"tester.output = {json.dumps(outputs)}\n[inputs]\ntraces = [\"{short}\"]\n")
        res = {}
        for j in (1, 2):
            out = os.path.join(tmp, f"out{j}")
            t0 = time.monotonic()
            r = subprocess.run(["/usr/bin/python3", SWEEP, "run", sweep, "-o", out, "-j", str(j), "-q", "--timing",
                                "--rbcd-sim", sim], stdout=subprocess.PIPE, text=True)
            total = time.monotonic() - t0
            if r.returncode != 0:
                sys.exit(f"sweep -j{j} failed ({r.returncode})")
            t = json.loads(r.stdout)
            t["total_s"] = total
            res[j] = t
        load = os.getloadavg()[0]
        one, two = res[1], res[2]
        runs = one["runs"]
        print(f"sweep of {runs} points, one {a.frames}-frame trace, {os.cpu_count()} cores, load average {load:.1f}")
        for j, t in res.items():
            ov_run = (t["run_s"] * j - t["sum_run_wall_s"]) / t["sum_run_wall_s"] * 100
            print(f"  -j{j}: total {t['total_s']:.2f} s = validation {t['validate_s']:.2f} s + runs {t['run_s']:.2f} s; "
                  f"sum of run wall {t['sum_run_wall_s']:.2f} s ({t['sum_run_wall_s'] / runs * 1000:.0f} ms a run)")
            print(f"        runner overhead while running: {ov_run:.1f}% "
                  f"(workers x run phase vs sum of run wall); with validation: "
                  f"{((t['total_s'] * j) - t['sum_run_wall_s']) / t['sum_run_wall_s'] * 100:.1f}%")
        for j, t in res.items():
            print(f"  -j{j}: CPU time: runner {t['runner_cpu_s']:.2f} s, rbcd-sim processes {t['children_cpu_s']:.2f} s "
                  f"({t['runner_cpu_s'] / t['children_cpu_s'] * 100:.1f}% of theirs)")
        print(f"  speed-up 2 workers vs 1: {one['total_s'] / two['total_s']:.2f}x total, "
              f"{one['run_s'] / two['run_s']:.2f}x run phase")
        same = open(os.path.join(tmp, "out1", "results.csv"), "rb").read() == \
            open(os.path.join(tmp, "out2", "results.csv"), "rb").read()
        print(f"  results.csv identical for -j1 and -j2: {same}")
    finally:
        if a.keep:
            print(f"kept {tmp}")
        else:
            shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
