"""rbcd.evaluate's accuracy arithmetic on constructed runs: one RBCD miss of
each kind (docs/accuracy.md), precision and recall counted by hand; and its
reading of a sweep's results.csv (scripts/rbcd-sweep)."""
import csv
import os

import pytest

from rbcd import evaluate


# ---- classify_miss: each rule of the cascade, on its own input.
ON = {"on_screen": "1", "px_overlap": "0", "px_near": "0"}


def test_accuracy_classification():
    assert evaluate.classify_miss(ON, True, True) == "list_overflow", "found with M = 64: list overflow"
    assert evaluate.classify_miss(ON, False, True) == "stack_overflow", "found only with M = T = 64: stack overflow"
    assert evaluate.classify_miss({**ON, "on_screen": "0"}, False, False) == "off_screen", \
        "no contact point in view: off-screen"
    assert evaluate.classify_miss({**ON, "px_near": "3"}, False, False) == "depth_quantization", \
        "intervals within one depth unit at some pixel: depth quantization"
    assert evaluate.classify_miss(ON, False, False) == "sub_pixel", "on screen, no pixel sees the overlap: sub-pixel"
    assert evaluate.classify_miss({**ON, "open": "1"}, False, False) == "open_surface", \
        "no pixel sees the overlap, an object is not closed: open surface"
    assert evaluate.classify_miss({**ON, "px_overlap": "5"}, False, False) == "unexplained", \
        "pixels overlap yet unlimited lists miss it: unexplained"
    # List overflow wins over off-screen: being found with longer lists proves it visible.
    assert evaluate.classify_miss({**ON, "on_screen": "0"}, True, True) == "list_overflow", "cascade order"


# ---- target_accuracy end to end on constructed run files.
# Ground truth, frame 0: six true pairs, one per miss kind, plus (1,2) found by
# everyone; (8,9) a concave near-miss: AABB and GJK positive, not true.
GROUND_TRUTH = [
    # frame, a, b, aabb, gjk, exact, contained, on_screen, contacts, px_overlap, px_near, open
    (0, 1, 2, 1, 1, 1, 0, 1, 4, 30, 0, 0),
    (0, 1, 3, 1, 1, 1, 0, 1, 4, 10, 0, 0),    # list overflow
    (0, 1, 4, 1, 1, 1, 0, 1, 4, 10, 0, 0),    # stack overflow
    (0, 1, 5, 1, 1, 1, 0, 0, 4, 0, 0, 0),     # off-screen
    (0, 1, 6, 1, 1, 1, 0, 1, 1, 0, 2, 0),     # depth quantization
    (0, 1, 7, 1, 1, 1, 0, 1, 1, 0, 0, 0),     # sub-pixel
    (0, 1, 10, 1, 1, 1, 0, 1, 1, 0, 0, 1),    # open surface
    (0, 8, 9, 1, 1, 0, 0, 0, 0, 0, 0, 0),     # near-miss
]


def write_col(path, pairs):
    """A collisions file of frame 0 with the given hits."""
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        f.write("rbcd-collisions 1\nframe 0\n")
        for a, b in pairs:
            f.write(f"hit 3 4 {a} {b} 100\n")
        f.write("overflow 0 0 1 1\n")


def write_sweep(out, name, axis, table):
    """OUT/sweep/NAME.csv, the sweep's results.csv: table = [(input, axis value, run id)]."""
    os.makedirs(os.path.join(out, "sweep"), exist_ok=True)
    with open(os.path.join(out, "sweep", name + ".csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["point", "input", "repeat", axis, "status", "error", "run"])
        w.writerows([i, inp, 0, v, 0, "", rid] for i, (inp, v, rid) in enumerate(table))


@pytest.fixture
def accuracy_out(tmp_path):
    """OUT of target_accuracy over the constructed runs of scene s."""
    out = str(tmp_path)
    runs = os.path.join(out, "runs", "s")
    os.makedirs(runs)
    with open(os.path.join(out, "runs", "scenes.txt"), "w") as f:
        f.write("s /nonexistent.toml\n")
    with open(os.path.join(runs, "cpucd_pairs.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "id_a", "id_b", "aabb", "gjk", "exact", "contained", "on_screen", "contacts",
                    "px_overlap", "px_near", "open"])
        w.writerows(GROUND_TRUTH)
    # M = 4, 8, 16 are Table 3's sweep; the rest are runs of their own.
    write_sweep(out, "table3", "zeb.list_length", [("../s.toml", m, f"r{m}") for m in (4, 8, 16)])
    for m in (4, 8, 16):
        write_col(os.path.join(out, "sweep", "runs", f"r{m}", "collisions.txt"), [(1, 2)])
    write_col(os.path.join(runs, "m8t2.col"), [(1, 2)])
    write_col(os.path.join(runs, "m64.col"), [(1, 2), (1, 3)])
    write_col(os.path.join(runs, "m64t2.col"), [(1, 2), (1, 3)])
    write_col(os.path.join(runs, "m64t64.col"), [(1, 2), (1, 3), (1, 4)])
    evaluate.target_accuracy(out, evaluate.scenes_of(out))
    return out


def test_accuracy_table(accuracy_out):
    with open(os.path.join(accuracy_out, "accuracy.csv")) as f:
        rows = {(r["scene"], r["method"]): r for r in csv.DictReader(f)}
    r = rows[("s", "RBCD M=8 T=8")]
    assert (r["TP"], r["FP"], r["FN"]) == ("1", "0", "6"), f"RBCD counts {r['TP']} {r['FP']} {r['FN']}"
    for c in evaluate.MISS_CLASSES:
        want = "0" if c == "unexplained" else "1"
        got = r["miss: " + c.replace("_", " ")]
        assert got == want, f"one miss of kind {c}, got {got}"
    assert r["precision %"] == "100.00" and r["recall %"] == "14.29", \
        f"RBCD precision / recall: {r['precision %']} {r['recall %']}"
    assert r["recall of on-screen contacts %"] == "16.67", \
        f"recall of on-screen contacts: {r['recall of on-screen contacts %']}"
    a = rows[("s", "AABB (a)")]
    assert (a["TP"], a["FP"], a["FN"], a["precision %"]) == ("7", "1", "0", "87.50"), \
        f"AABB counts: {a['TP']} {a['FP']} {a['FN']} {a['precision %']}"


def test_accuracy_misses(accuracy_out):
    with open(os.path.join(accuracy_out, "accuracy_misses.csv")) as f:
        kinds = {(m["method"], m["id_b"]): m["class"] for m in csv.DictReader(f)}
    assert kinds[("RBCD M=8 T=8", "3")] == "list_overflow" and kinds[("RBCD M=8 T=8", "7")] == "sub_pixel", \
        f"misses listed with their pair: {kinds}"


# ---- A failed or missing run of the sweep is an error naming the scene and the value.
def test_sweep_run_failed(tmp_path):
    out = str(tmp_path)
    write_sweep(out, "table3", "zeb.list_length", [("../s.toml", 4, "r4"), ("../s.toml", 8, "r8")])
    with open(os.path.join(out, "sweep", "table3.csv"), "a") as f:
        f.write("2,../s.toml,0,16,2,bad scene,r16\n")
    with pytest.raises(evaluate.InputMissing) as e:
        evaluate.sweep_rows(out, "table3", "zeb.list_length", ["s"])
    assert "s at zeb.list_length = 16: run failed: bad scene" in str(e.value), f"failed run named: {e.value}"


def test_sweep_row_missing(tmp_path):
    out = str(tmp_path)
    write_sweep(out, "table3", "zeb.list_length", [("../s.toml", 4, "r4"), ("../t.toml", 8, "r8")])
    with pytest.raises(evaluate.InputMissing) as e:
        evaluate.sweep_rows(out, "table3", "zeb.list_length", ["s", "t"])
    assert "no row for s at zeb.list_length = 8" in str(e.value), f"missing row named: {e.value}"


# ---- results.csv cells back to the stats JSON's values: int, float (shortest round-trip), empty -> None.
def test_results_values():
    row = {"totals.hits": "81424880", "gpu.overhead_pct": "1.2394688208321585", "energy.gpu.overhead_pct": ""}
    v = evaluate.value(row, "totals.hits")
    assert v == 81424880 and isinstance(v, int), f"int: {v!r}"
    assert evaluate.value(row, "gpu.overhead_pct") == 1.2394688208321585, "float, exactly"
    assert evaluate.value(row, "energy.gpu.overhead_pct") is None, "empty: not in this build's stats"
    with pytest.raises(evaluate.InputMissing) as e:
        evaluate.value(row, "totals.cycles")
    assert "results.fields" in str(e.value), f"names results.fields: {e.value}"


# ---- target_fig8: a scene counted on every K-th frame, and one where the unit adds no GPU time.
def fig8_out(tmp_path, b_frames):
    """OUT over scenes a (4 frames, every one counted; the unit adds no time
    with 2 ZEBs) and b (4 frames timed, counted on frames `b_frames`)."""
    out = str(tmp_path)
    os.makedirs(os.path.join(out, "sweep"))
    with open(os.path.join(out, "sweep", "fig9.csv"), "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["point", "input", "repeat", "zeb.banks", "status", "error", "run", "config.clock.mhz",
                    "gpu.baseline_cycles", "gpu.cycles_with_unit", "energy.gpu.baseline_pj", "energy.gpu.with_unit_pj"])
        for k, (s, banks, extra) in enumerate([("a", 1, 400), ("a", 2, 0), ("b", 1, 800), ("b", 2, 400)]):
            w.writerow([k, f"../{s}.toml", 0, banks, 0, "", f"r{k}", 400, 10**6, 10**6 + extra, 1e6, 2e6])
    os.makedirs(os.path.join(out, "runs"))
    with open(os.path.join(out, "runs", "scenes.txt"), "w") as f:
        f.write("a /nonexistent/a.toml\nb /nonexistent/b.toml\n")
    cols = ["broad", "gjk", "world_broad", "world"]
    for s, counted in (("a", [0, 1, 2, 3]), ("b", b_frames)):
        os.makedirs(os.path.join(out, "runs", s))
        with open(os.path.join(out, "runs", s, "cpucd_frames.csv"), "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(["frame"] + [c + "_us" for c in cols])
            w.writerows([fr, 1, 2, 3, 4] for fr in range(4))
        with open(os.path.join(out, "runs", s, "cpucd_counts.csv"), "w", newline="") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(["frame"] + [c + "_instr" for c in cols])
            w.writerows([fr] + [1000 * (fr + 1)] * 4 for fr in counted)
    return out


def test_fig8_sample_and_unbounded(tmp_path):
    out = fig8_out(tmp_path, [0, 2])
    evaluate.target_fig8(out, evaluate.scenes_of(out))
    rows = {(r["scene"], r["CPU version"][:3], r["ZEBs"]): r for r in csv.DictReader(open(f"{out}/fig8.csv"))}
    # b's count per frame is its sample's mean: frames 0 and 2, 1000 and 3000 instructions.
    assert rows[("b", "(a)", "1")]["instructions/frame"] == "2000", rows[("b", "(a)", "1")]
    assert rows[("a", "(a)", "1")]["instructions/frame"] == "2500"
    assert rows[("a", "(a)", "2")]["speed-up"] == "inf"
    md = open(f"{out}/fig8.md").read()
    assert "b: every 2nd frame (2 of 4)" in md, md
    assert "With 2 ZEBs the unit adds no GPU time on a:" in md and "over the other 1 scenes" in md, md
    summary = {(r["CPU version"][:3], r["ZEBs"]): r for r in csv.DictReader(open(f"{out}/fig8_summary.csv"))}
    # The unbounded speed-up is left out of the mean: b's alone.
    assert summary[("(a)", "2")]["speed-up (geo. mean)"] == rows[("b", "(a)", "2")]["speed-up"]


def test_fig8_counted_frames_not_a_sample(tmp_path):
    out = fig8_out(tmp_path, [0, 1, 3])
    with pytest.raises(evaluate.InputMissing) as e:
        evaluate.target_fig8(out, evaluate.scenes_of(out))
    assert "not every frame or every K-th of the 4 timed" in str(e.value), str(e.value)
