"""rbcd-plot heatmap (scripts/rbcd-plot, run as users run it) against the
database it draws from: every map written, its values (--values) the per-tile
sums of the tiles table, one frame's maps that frame's sums, a missing
database one line and exit 2. Skipped without python3-matplotlib. CTest:
plot_heatmap (cmake/pytest.cmake)."""
import csv
import os
import sqlite3
import subprocess

import pytest

from conftest import ROOT, program

PLOT = os.path.join(ROOT, "scripts", "rbcd-plot")
VECTORS = os.path.join(ROOT, "vectors")
EXPRS = {"stall": "stall_no_bank + stall_queue_full + stall_fragment_queue + stall_output",
         "overflow": "fragments_dropped", "depth": "fragments", "hits": "hits"}


def plot(*args):
    return subprocess.run(["/usr/bin/python3", PLOT, *args], capture_output=True, text=True)


def test_heatmap(tmp_path):
    if subprocess.run(["/usr/bin/python3", "-c", "import matplotlib"], capture_output=True).returncode != 0:
        pytest.skip("python3-matplotlib is not installed (scripts/setup.sh --plots)")
    sim = program("rbcd-sim")
    d = str(tmp_path)
    db = os.path.join(d, "run.sqlite")
    env = dict(os.environ, SYSTEMC_DISABLE_COPYRIGHT_MESSAGE="1")
    r = subprocess.run([sim, "--trace", f"{VECTORS}/multi-frame-mixed.rbt", "--config",
                        f"{VECTORS}/multi-frame-mixed.toml", "--db", db, "-q"], capture_output=True, text=True, env=env)
    assert r.returncode == 0, f"rbcd-sim --db: exit {r.returncode}: {r.stderr}"
    con = sqlite3.connect(db)
    frames = con.execute("SELECT count(*) FROM frames").fetchone()[0]
    run = dict(con.execute("SELECT key, value FROM run"))
    pixels = int(run["tile_width"]) * int(run["tile_height"])
    for frame in (None, 2):
        out = os.path.join(d, "maps")
        values = os.path.join(d, "v.csv")
        args = ["heatmap", db, "-o", out, "--values", values]
        if frame is not None:
            args += ["--frame", str(frame)]
        r = plot(*args)
        assert r.returncode == 0, f"rbcd-plot heatmap failed: {r.stderr}"
        stem = "run" if frame is None else f"frame_{frame:05d}"
        for m in EXPRS:
            p = os.path.join(out, f"{stem}_{m}.png")
            assert os.path.exists(p), f"{p}: not written"
            with open(p, "rb") as f:
                assert f.read(8) == b"\x89PNG\r\n\x1a\n", f"{p}: not written (not a PNG)"
        with open(values, newline="") as f:
            got = {(row["metric"], int(row["col"]), int(row["row"])): float(row["value"]) for row in csv.DictReader(f)}
        where = "" if frame is None else f" WHERE frame = {frame}"
        for m, e in EXPRS.items():
            want = {(m, c, r): v for c, r, v in
                    con.execute(f"SELECT col, row, total({e}) FROM tiles{where} GROUP BY col, row")}
            if m == "depth":
                want = {k: v / (pixels * (frames if frame is None else 1)) for k, v in want.items()}
            mine = {k: v for k, v in got.items() if k[0] == m}
            assert set(mine) == set(want), f"{stem} {m}: tiles differ"
            wrong = [f"{stem} {m} tile {k[1:]}: map {mine[k]}, database {v}" for k, v in want.items()
                     if k in mine and abs(mine[k] - v) > 1e-9 * max(1, abs(v))]
            assert not wrong, "\n".join(wrong)
    con.close()
    r = plot("heatmap", os.path.join(d, "missing.sqlite"), "-o", d)
    assert r.returncode == 2 and r.stderr.count("\n") == 1 and "missing.sqlite" in r.stderr, \
        f"missing database: exit {r.returncode}, stderr {r.stderr!r}"
