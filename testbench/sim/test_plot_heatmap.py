#!/usr/bin/python3
"""scripts/rbcd-plot heatmap against the database it draws from: every map
written, its values (--values) the per-tile sums of the tiles table, one
frame's maps that frame's sums, a missing database one line and exit 2.
Exit 77 (skipped) without python3-matplotlib.
    test_plot_heatmap.py RBCD_SIM RBCD_PLOT VECTORS_DIR
"""
import csv
import os
import sqlite3
import subprocess
import sys
import tempfile

sim, plot, vectors = sys.argv[1:4]
try:
    import matplotlib  # noqa: F401
except ImportError:
    print("python3-matplotlib is not installed (scripts/setup.sh --plots): skipped")
    sys.exit(77)

fails = []
with tempfile.TemporaryDirectory() as d:
    db = os.path.join(d, "run.sqlite")
    env = dict(os.environ, SYSTEMC_DISABLE_COPYRIGHT_MESSAGE="1")
    subprocess.run([sim, "--trace", f"{vectors}/multi-frame-mixed.rbt", "--config",
                    f"{vectors}/multi-frame-mixed.toml", "--db", db, "-q"], check=True, env=env)
    con = sqlite3.connect(db)
    frames = con.execute("SELECT count(*) FROM frames").fetchone()[0]
    pixels = int(dict(con.execute("SELECT key, value FROM run"))["tile_width"]) * \
        int(dict(con.execute("SELECT key, value FROM run"))["tile_height"])
    exprs = {"stall": "stall_no_bank + stall_queue_full + stall_fragment_queue + stall_output",
             "overflow": "fragments_dropped", "depth": "fragments", "hits": "hits"}
    for frame in (None, 2):
        out = os.path.join(d, "maps")
        values = os.path.join(d, "v.csv")
        args = [plot, "heatmap", db, "-o", out, "--values", values]
        if frame is not None:
            args += ["--frame", str(frame)]
        r = subprocess.run(args, capture_output=True, text=True)
        if r.returncode != 0:
            fails.append(f"rbcd-plot heatmap failed: {r.stderr}")
            continue
        stem = "run" if frame is None else f"frame_{frame:05d}"
        for m in exprs:
            p = os.path.join(out, f"{stem}_{m}.png")
            if not os.path.exists(p) or open(p, "rb").read(8) != b"\x89PNG\r\n\x1a\n":
                fails.append(f"{p}: not written")
        got = {(row["metric"], int(row["col"]), int(row["row"])): float(row["value"])
               for row in csv.DictReader(open(values))}
        where = "" if frame is None else f" WHERE frame = {frame}"
        for m, e in exprs.items():
            want = {(m, c, r): v for c, r, v in
                    con.execute(f"SELECT col, row, total({e}) FROM tiles{where} GROUP BY col, row")}
            if m == "depth":
                want = {k: v / (pixels * (frames if frame is None else 1)) for k, v in want.items()}
            mine = {k: v for k, v in got.items() if k[0] == m}
            if set(mine) != set(want):
                fails.append(f"{stem} {m}: tiles differ")
            for k, v in want.items():
                if k in mine and abs(mine[k] - v) > 1e-9 * max(1, abs(v)):
                    fails.append(f"{stem} {m} tile {k[1:]}: map {mine[k]}, database {v}")
    r = subprocess.run([plot, "heatmap", os.path.join(d, "missing.sqlite"), "-o", d], capture_output=True, text=True)
    if r.returncode != 2 or r.stderr.count("\n") != 1 or "missing.sqlite" not in r.stderr:
        fails.append(f"missing database: exit {r.returncode}, stderr {r.stderr!r}")

for f in fails:
    print("FAIL:", f)
sys.exit(1 if fails else 0)
