"""The evaluation's arithmetic (docs/results.md, docs/accuracy.md): reads the
runs scripts/reproduce.sh made (the sweeps' tables OUT/sweep/NAME.csv and the
other runs under OUT/runs/) and writes each figure's CSV, PNG and Markdown
table into OUT. scripts/reproduce.sh runs it as `python3 -m rbcd.evaluate`
(python/ on PYTHONPATH):

    evaluate.py --out DIR TARGET...     TARGET: workloads table3 fig9 fig8 accuracy
    evaluate.py --splice OUT DOC        copy OUT's tables into DOC between its markers
    evaluate.py --sweep-file SWEEP SUITE DEST
                                        SWEEP (workloads/sweeps/) over another suite
    evaluate.py --id-bits SCENE         the zeb.id_bits a scene's ids need

Every input it needs is named in the target's function; a missing one is an
error naming the file (exit 2).
"""
import argparse
import csv
import json
import math
import os
import re
import subprocess
import sys
import tomllib

from rbcd.cli import ArgumentParser, Once, main_wrapper, parse_toml, say  # (one-line messages, no tracebacks)

# The CPU model of Figure 8 (instructions to time and energy, each constant
# with its source) is rbcd/cpu_model.py.
from rbcd import cpu_model

PROG = "evaluate.py"

PAPER = {
    "table3": {4: 3.68, 8: 0.08, 16: 0.0},
    "fig9_time": {1: 5.4, 2: 3.0},
    "fig9_energy": {1: 5.1, 2: 3.5},
    "fig8": {("broad", 1): (250, 273), ("broad", 2): (600, 448), ("gjk", 1): (1400, 1750), ("gjk", 2): (3400, 2875)},
}

MISS_CLASSES = ["list_overflow", "stack_overflow", "off_screen", "depth_quantization", "open_surface", "sub_pixel",
                "unexplained"]


class InputMissing(Exception):
    pass


def need(path):
    if not os.path.exists(path):
        raise InputMissing(f"{path}: missing (run scripts/reproduce.sh for this target)")
    return path


def load_toml(path):
    """A TOML file (a scene, a sweep template, a capture's description), its
    keys of at most 64 dotted parts (rbcd.cli.parse_toml: tomllib's
    memory grows with the square of a key's parts)."""
    with open(path, "rb") as f:
        return parse_toml(path, f.read().decode())


def read_collisions(path):
    """frame -> set of (a, b); frame -> lists overflowed; total lists overflowed."""
    pairs, lists = {}, {}
    frame = None
    with open(need(path)) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "frame":
                frame = int(t[1])
                pairs[frame] = set()
                lists[frame] = 0
            elif t[0] == "hit":
                pairs[frame].add((int(t[3]), int(t[4])))
            elif t[0] == "overflow":
                lists[frame] += int(t[3])
    return pairs, lists


def read_csv(path):
    with open(need(path)) as f:
        return list(csv.DictReader(f))


def write_csv(path, header, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        w.writerows(rows)


def pct(a, b):
    return 100.0 * a / b if b else 0.0


def fmt(v, nd=2):
    if v is None:
        return "n/a"
    if isinstance(v, float) and math.isinf(v):
        return "inf"
    return f"{v:.{nd}f}"


def share(part, whole):
    """A percentage for a histogram cell: 2 decimals, or '<0.01%' for a nonzero sliver."""
    p = pct(part, whole)
    return "<0.01%" if 0 < p < 0.005 else f"{p:.2f}%"


def sig(v, digits=3):
    """A ratio to `digits` significant digits (0.42, 3.1, 250)."""
    if v is None:
        return "n/a"
    if math.isinf(v):
        return "inf"
    return f"{v:.{digits}g}" if v < 10 ** digits else f"{v:.0f}"


def md_table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out) + "\n"


def plot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


SCENE_PATHS = {}


def scenes_of(out):
    """OUT/runs/scenes.txt: one "NAME PATH" a line, as reproduce.sh ran them
    (OUT's scenes only: those of an OUT read before are forgotten)."""
    SCENE_PATHS.clear()
    with open(need(os.path.join(out, "runs", "scenes.txt"))) as f:
        for line in f:
            if line.strip():
                name, path = line.split(None, 1)
                SCENE_PATHS[name] = path.strip()
    return list(SCENE_PATHS)


TRACE_SUFFIXES = (".rbt.zst", ".rbt.gz", ".rbt")


def trace_base(path):
    """A trace's path without its suffix: where its NAME.geo, NAME.summary.jsonl
    and NAME.capture lie."""
    return next(path[:-len(s)] for s in TRACE_SUFFIXES if path.endswith(s))


def input_name(path):
    """A suite input's name: its file name without .toml, .rbt, .rbt.gz or .rbt.zst."""
    base = os.path.basename(path)
    for suf in TRACE_SUFFIXES + (".toml",):
        if base.endswith(suf):
            return base[:-len(suf)]
    return base


def is_trace(path):
    return path.endswith(TRACE_SUFFIXES)


def scene_objects(name):
    """(collisionable ids, scenery objects) of a scene file; for a converted game
    capture (a trace with NAME.summary.jsonl beside it, scripts/game-suite), the
    mean collisionable objects a frame and "-"."""
    path = SCENE_PATHS[name]
    if is_trace(path):
        summary = trace_base(path) + ".summary.jsonl"
        with open(need(summary)) as f:
            frames = [json.loads(line) for line in f if line.strip()]
        return fmt(sum(len(fr["objects"]) for fr in frames) / max(1, len(frames)), 1), "-"
    sc = load_toml(need(path))
    objs = sc.get("object", [])
    return len({o["id"] for o in objs if "id" in o}), sum(1 for o in objs if "id" not in o)


def run_file(out, scene, name):
    return os.path.join(out, "runs", scene, name)


# ---------------------------------------------------------------- sweeps
# Table 3 and Figure 9 are sweeps (workloads/sweeps/NAME.toml) run by
# scripts/rbcd-sweep, one after the other, into one output directory OUT/sweep/
# (so the run they share, M = 8 with two ZEBs, runs once); each one's
# results.csv is kept as OUT/sweep/NAME.csv: a row per point and scene, with
# the stats fields the sweep file lists. Their plots are drawn by the
# repository's scripts/rbcd-plot (python/rbcd/ -> ../..): evaluate runs from a
# source checkout only, as scripts/reproduce.sh does.
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def sweep_dir(out):
    return os.path.join(out, "sweep")


def value(row, field):
    """A results.csv cell as the stats JSON held it: int, float, or None (empty)."""
    if field not in row:
        raise InputMissing(f"results.csv: no column {field} (add it to the sweep's results.fields)")
    v = row[field]
    if v == "":
        return None
    try:
        return int(v)
    except ValueError:
        return float(v)


def sweep_rows(out, name, axis, scenes):
    """({(scene, axis value): row}, the axis values in table order) of OUT/sweep/NAME.csv;
    every scene must have a successful row at every value."""
    path = os.path.join(sweep_dir(out), name + ".csv")
    rows = read_csv(path)
    if rows and axis not in rows[0]:
        raise InputMissing(f"{path}: no column {axis} (the sweep must sweep {axis})")
    table, values = {}, []
    for r in rows:
        scene = input_name(r["input"])
        v = value(r, axis)
        if v not in values:
            values.append(v)
        if r["status"] != "0":
            raise InputMissing(f"{path}: {scene} at {axis} = {v}: run failed: {r['error']}")
        table[(scene, v)] = r
    for s in scenes:
        for v in values:
            if (s, v) not in table:
                raise InputMissing(f"{path}: no row for {s} at {axis} = {v}")
    return table, values


def sweep_run_file(out, name, row, file):
    """A file of the row's run: OUT/sweep/runs/ID/FILE."""
    return os.path.join(sweep_dir(out), "runs", row["run"], file)


def rbcd_plot(table, png, y, x, lines, title, logx=False):
    """The figure's PNG by scripts/rbcd-plot, from a table in results.csv form."""
    cmd = ["/usr/bin/python3", os.path.join(ROOT, "scripts", "rbcd-plot"), table, "--y", y, "--x", x, "--lines", lines,
           "--title", title, "-o", png] + (["--logx"] if logx else [])
    r = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise InputMissing(f"rbcd-plot failed on {table}: {r.stderr.strip()}")


def id_bits(scene_path):
    """The smallest zeb.id_bits (at least the paper's 7) holding a scene's object ids
    (a game capture's: 7, its selection rules' max_entity_id = 127)."""
    if is_trace(scene_path):
        return 7
    objs = load_toml(need(scene_path)).get("object", [])
    top = max([o["id"] for o in objs if isinstance(o.get("id"), int)] or [0])
    b = 7
    while top >= 1 << b:
        b += 1
    return b


def toml_text(doc):
    """A sweep file's tables as TOML (the subset sweep files use)."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        raise ValueError(f"cannot write {v!r} as TOML")

    def table(name, t, lines):
        lines.append(f"[{name}]")
        lines += [f"{json.dumps(k)} = {val(v)}" for k, v in t.items() if not isinstance(v, dict)]
        for k, v in t.items():
            if isinstance(v, dict):
                table(f"{name}.{json.dumps(k)}", v, lines)

    lines = []
    for name, t in doc.items():
        for sub in (t if isinstance(t, list) else [t]):
            if isinstance(t, list):
                lines.append(f"[[{name}]]")
                lines += [f"{json.dumps(k)} = {val(v)}" for k, v in sub.items()]
            else:
                table(name, sub, lines)
    return "\n".join(lines) + "\n"


def sweep_file(template, suite, dest):
    """TEMPLATE (a sweep of workloads/sweeps/) with its inputs replaced by SUITE's scenes, each
    with the id bits it needs, and its paths made absolute: what reproduce.sh --workloads runs."""
    doc = load_toml(template)
    base = doc.setdefault("base", {})
    if "config" in base:
        base["config"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(template)), base["config"]))
    suite = os.path.abspath(suite)
    inputs = {"suites": [suite]}
    sets = {}
    for name in sorted(os.listdir(suite)):
        if name.endswith(".toml") or is_trace(name):
            b = id_bits(os.path.join(suite, name))
            if b != 7:
                sets[os.path.join(suite, name)] = {"zeb.id_bits": b}
    if sets:
        inputs["set"] = sets
    doc["inputs"] = inputs
    with open(dest, "w") as f:
        f.write(f"# {template} over {suite} (rbcd.evaluate --sweep-file)\n")
        f.write(toml_text(doc))


# ---------------------------------------------------------------- workloads
def target_workloads(out, scenes):
    rows = []
    plt = plot()
    fig, axes = plt.subplots(1, len(scenes), figsize=(3.2 * len(scenes), 2.6), squeeze=False)
    # The rasterizer's counts do not depend on the unit: the paper configuration's runs of Figure 9.
    sw, _ = sweep_rows(out, "fig9", "zeb.banks", scenes)
    for k, s in enumerate(scenes):
        r = sw[(s, 2)]
        frames = value(r, "totals.frames")
        feed = {f: value(r, "blocks.rasterizer." + f) for f in ("fragments", "other_fragments", "culled_fragments")}
        pairs = read_csv(run_file(out, s, "cpucd_pairs.csv"))
        n_coll, n_scenery = scene_objects(s)
        hist = read_csv(run_file(out, s, "depth_hist.csv"))
        px = sum(int(h["pixels"]) for h in hist)
        mean = sum(int(h["fragments_per_pixel"].rstrip("+")) * int(h["pixels"]) for h in hist) / px if px else 0
        p4 = pct(sum(int(h["pixels"]) for h in hist if int(h["fragments_per_pixel"].rstrip("+")) > 4), px)
        p8 = pct(sum(int(h["pixels"]) for h in hist if int(h["fragments_per_pixel"].rstrip("+")) > 8), px)
        mx = max(int(h["fragments_per_pixel"].rstrip("+")) for h in hist) if hist else 0
        exact = sum(1 for r in pairs if r["exact"] == "1")
        rows.append([s, n_coll, n_scenery, frames, feed["fragments"] // frames,
                     feed["other_fragments"] // frames, fmt(pct(feed["culled_fragments"], feed["fragments"]), 1),
                     fmt(mean, 2), mx, fmt(p4, 2), fmt(p8, 2), exact])
        ax = axes[0][k]
        xs = [int(h["fragments_per_pixel"].rstrip("+")) for h in hist]
        ax.bar(xs, [int(h["pixels"]) / px * 100 for h in hist], color="#4477aa")
        ax.set_yscale("log")
        ax.set_title(s, fontsize=9)
        ax.set_xlabel("fragments on a pixel", fontsize=8)
        if k == 0:
            ax.set_ylabel("% of covered pixels", fontsize=8)
        ax.tick_params(labelsize=7)
    header = ["scene", "collisionable objects", "scenery objects", "frames", "fragments/frame", "other fragments/frame",
              "culled (c) %", "mean fragments/pixel", "max", "pixels > 4 %", "pixels > 8 %", "contact pair-frames"]
    write_csv(os.path.join(out, "workloads.csv"), header, rows)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "workloads.png"), dpi=80)
    with open(os.path.join(out, "workloads.md"), "w") as f:
        f.write(md_table(header, rows))
        f.write("\nDepth complexity (fragments of collisionable objects per covered pixel, all frames):\n\n")
        for s in scenes:
            hist = read_csv(run_file(out, s, "depth_hist.csv"))
            px = sum(int(h["pixels"]) for h in hist)
            cells = ", ".join(f"{h['fragments_per_pixel']}: {share(int(h['pixels']), px)}" for h in hist)
            f.write(f"- {s}: {cells}\n")
    game_pairs(out, scenes)


# What collides in a captured game (docs/games.md). A game's objects carry no
# names (the GL stream has none), so each object is classed in each frame by
# the size of its surface there, a reading aid that no figure uses:
# (game prefix of the entry's name, [(test on (vertices, box diagonal), class)]).
GAME_CLASSES = {
    # A bot is legs, torso, head and weapon: 700 to 1000 welded vertices; the
    # pickups, projectiles and gibs are tens to a few hundred.
    "openarena": [(lambda nv, d: nv >= 500, "player"), (lambda nv, d: True, "item/projectile")],
    # Neverball (metres): coins 0.3 m, the ball under 1 m, moving platforms and
    # switches' bodies larger.
    "neverball": [(lambda nv, d: d <= 0.5, "coin"), (lambda nv, d: d <= 1.5, "ball"),
                  (lambda nv, d: True, "moving body")],
    # SuperTuxKart (metres): a kart with its driver and wheels is thousands of
    # vertices; a gift box, nitro can or banana is tens to a few hundred.
    "supertuxkart": [(lambda nv, d: nv >= 1000, "kart"), (lambda nv, d: True, "item")],
}


def geometry_classes(path, rules):
    """{(frame, id): class} from a geometry file's mesh records (format 2)."""
    sizes = {}
    with open(need(path)) as f:
        frame = None
        for line in f:
            if line.startswith("frame "):
                frame = int(line.split()[1])
            elif line.startswith("mesh "):
                _, oid, nv, nt = line.split()[:4]
                nv, nt = int(nv), int(nt)
                lo, hi = [math.inf] * 3, [-math.inf] * 3
                for _ in range(nv):
                    v = next(f).split()
                    for k in range(3):
                        x = float(v[1 + k])
                        lo[k], hi[k] = min(lo[k], x), max(hi[k], x)
                for _ in range(nt):
                    next(f)
                key = (frame, int(oid))
                n0, lo0, hi0 = sizes.get(key, (0, [math.inf] * 3, [-math.inf] * 3))
                sizes[key] = (n0 + nv, [min(a, b) for a, b in zip(lo0, lo)], [max(a, b) for a, b in zip(hi0, hi)])
    out = {}
    for key, (nv, lo, hi) in sizes.items():
        d = math.dist(lo, hi)
        out[key] = next(label for test, label in rules if test(nv, d))
    return out


def game_of(s):
    """The game a captured input comes from: the capture's description beside
    the trace (scripts/game-suite expand writes it), else the entry's name
    (GAME_CLASSES' prefixes); None for a scene or an unknown game."""
    path = SCENE_PATHS[s]
    if not is_trace(path):
        return None
    game = None
    desc = trace_base(path) + ".capture"
    if os.path.isfile(desc):
        game = load_toml(desc).get("game")
    if game not in GAME_CLASSES:
        game = next((g for g in GAME_CLASSES if s.startswith(g + "-")), None)
    return game


def game_pairs(out, scenes):
    """Per captured game, the pairs in contact (rbcd-cpucd's ground truth) by the
    classes of their two objects: pair-frames, of them on screen, distinct pairs."""
    rows = []
    for s in scenes:
        path = SCENE_PATHS[s]
        if not is_trace(path):
            continue
        game = game_of(s)
        rules = GAME_CLASSES.get(game, [(lambda nv, d: True, "object")])
        classes = geometry_classes(trace_base(path) + ".geo", rules)
        frames = len(read_csv(run_file(out, s, "cpucd_frames.csv")))
        table = {}
        for r in read_csv(run_file(out, s, "cpucd_pairs.csv")):
            if r["exact"] != "1":
                continue
            f, a, b = int(r["frame"]), int(r["id_a"]), int(r["id_b"])
            kind = " - ".join(sorted((classes.get((f, a), "?"), classes.get((f, b), "?"))))
            t = table.setdefault(kind, [0, 0, set(), set()])
            t[0] += 1
            t[1] += r.get("on_screen", "0") == "1"
            t[2].add((a, b))
            t[3].add(f)
        if not table:
            rows.append([s, "(none)", 0, 0, 0, 0, frames])
        for kind, (n, on, ids, fs) in sorted(table.items(), key=lambda kv: -kv[1][0]):
            rows.append([s, kind, n, on, len(ids), len(fs), frames])
    if not rows:
        return
    header = ["capture", "pair (object classes)", "pair-frames in contact", "of them on screen",
              "distinct id pairs", "frames with such a contact", "frames"]
    write_csv(os.path.join(out, "pairs.csv"), header, rows)
    with open(os.path.join(out, "pairs.md"), "w") as f:
        f.write(md_table(header, rows))


# ---------------------------------------------------------------- table3
def target_table3(out, scenes):
    """From the sweep workloads/sweeps/table3.toml (zeb.list_length x scene)."""
    sw, ms = sweep_rows(out, "table3", "zeb.list_length", scenes)
    rows = []
    tot = {m: [0, 0, 0, 0] for m in ms}
    for s in scenes:
        row = [s]
        for m in ms:
            r = sw[(s, m)]
            _, lists = read_collisions(sweep_run_file(out, "table3", r, "collisions.txt"))
            frags, drop = value(r, "totals.fragments"), value(r, "totals.overflows")
            nl, lo = value(r, "blocks.zoverlap_tester.lists"), sum(lists.values())
            t = tot[m]
            t[0] += frags
            t[1] += drop
            t[2] += nl
            t[3] += lo
            row += [fmt(pct(drop, frags), 3), fmt(pct(lo, nl), 3)]
        rows.append(row)
    rows.append(["all (pooled)"] + sum(([fmt(pct(tot[m][1], tot[m][0]), 3), fmt(pct(tot[m][3], tot[m][2]), 3)]
                                        for m in ms), []))
    means = []
    for i in range(2 * len(ms)):
        means.append(fmt(sum(float(r[1 + i]) for r in rows[:-1]) / len(scenes), 3))
    rows.append(["mean of scenes"] + means)
    rows.append(["paper (Table 3)"] + sum(([f"{PAPER['table3'][m]}" if m in PAPER["table3"] else "-", "-"]
                                           for m in ms), []))
    header = ["scene"] + sum(([f"M={m} fragments dropped %", f"M={m} lists overflowed %"] for m in ms), [])
    write_csv(os.path.join(out, "table3.csv"), header, rows)
    with open(os.path.join(out, "table3.md"), "w") as f:
        f.write(md_table(header, rows))
    # The plot: fragments dropped against M, a line per scene, their mean and the paper's.
    y = "fragments dropped %"
    plot_rows = [[r[0], m, r[1 + 2 * k]] for r in rows[:len(scenes)] + [rows[len(scenes) + 1]]
                 for k, m in enumerate(ms)]
    plot_rows += [["paper", m, PAPER["table3"][m]] for m in ms if m in PAPER["table3"]]
    write_csv(os.path.join(out, "table3_plot.csv"), ["scene", "zeb.list_length", y], plot_rows)
    rbcd_plot(os.path.join(out, "table3_plot.csv"), os.path.join(out, "table3.png"), y, "zeb.list_length", "scene",
              "Table 3: fragments dropped by list overflow against M", logx=True)


# ---------------------------------------------------------------- fig9
def zebs(banks):
    return f"{banks} ZEB" + ("" if banks == 1 else "s")


def target_fig9(out, scenes):
    """From the sweep workloads/sweeps/fig9.toml (zeb.banks x scene)."""
    sw, banks_list = sweep_rows(out, "fig9", "zeb.banks", scenes)
    rows = []
    agg = {b: [0, 0] for b in banks_list}
    energy_model = True
    for s in scenes:
        row = [s]
        for banks in banks_list:
            r = sw[(s, banks)]
            agg[banks][0] += value(r, "gpu.baseline_cycles")
            agg[banks][1] += value(r, "gpu.cycles_with_unit")
            e = value(r, "energy.gpu.overhead_pct")
            energy_model &= e is not None
            row += [fmt(value(r, "gpu.overhead_pct"), 2), fmt(e, 2),
                    fmt(value(r, "energy.total_nj") / max(1, value(r, "totals.frames")), 1)]
        rows.append(row)
    pooled = ["all (pooled)"]
    for banks in banks_list:
        pooled += [fmt(pct(agg[banks][1] - agg[banks][0], agg[banks][0]), 2), "", ""]
    rows.append(pooled)
    rows.append(["paper (Fig. 9)"] + sum(([PAPER["fig9_time"].get(b, "-"), PAPER["fig9_energy"].get(b, "-"), "-"]
                                          for b in banks_list), []))
    header = ["scene"] + sum(([f"{zebs(b)}: GPU time overhead %", f"{zebs(b)}: GPU energy overhead %",
                               f"{zebs(b)}: unit nJ/frame"] for b in banks_list), [])
    write_csv(os.path.join(out, "fig9.csv"), header, rows)
    with open(os.path.join(out, "fig9.md"), "w") as f:
        f.write(md_table(header, rows))
        if not energy_model:
            f.write("\nGPU energy overhead: n/a in this build (stats.json has no energy.gpu.overhead_pct); "
                    "the unit's own energy per frame is given instead.\n")
    # The plot: GPU time overhead against the ZEB count, a line per scene, pooled and the paper's.
    y = "GPU time overhead %"
    plot_rows = [[r[0], b, r[1 + 3 * k]] for r in rows[:-1] for k, b in enumerate(banks_list)]
    plot_rows += [["paper", b, PAPER["fig9_time"][b]] for b in banks_list if b in PAPER["fig9_time"]]
    write_csv(os.path.join(out, "fig9_plot.csv"), ["scene", "zeb.banks", y], plot_rows)
    rbcd_plot(os.path.join(out, "fig9_plot.csv"), os.path.join(out, "fig9.png"), y, "zeb.banks", "scene",
              "Figure 9: GPU time overhead against the ZEB count")


# ---------------------------------------------------------------- fig8
def host_ghz():
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("cpu MHz"):
                    return float(line.split(":")[1]) / 1000.0
    except OSError:
        pass
    return None


# The CPU versions of Figure 8 (docs/cpucd.md): rbcd-cpucd's column stem, the
# label, and the paper's figure it stands beside (broad phase or broad + GJK).
FIG8_VERSIONS = [("broad", "(a) bare broad phase", "broad"), ("world_broad", "(d) world, broad phase", "broad"),
                 ("gjk", "(b) bare broad + GJK", "gjk"), ("world", "(e) world, broad + narrow", "gjk")]


def ordinal(k):
    """3rd, 11th, 22nd."""
    return f"{k}{'th' if 10 <= k % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(k % 10, 'th')}"


def g3(v):
    """Three significant digits, without an exponent from 1000 up (186000, not 1.86e+05)."""
    return f"{v:.0f}" if abs(v) >= 1000 else f"{v:.3g}"


def target_fig8(out, scenes):
    """Speed-up and energy reduction (the paper's equations 1 and 2) per CPU
    version, the CPU side from counted instructions through cpu_model (the
    same on any machine), the host's wall-clock time beside it in the CSV."""
    ghz = host_ghz()
    rows, md_rows, ratios = [], [], {}
    fallback = False
    sampled = {}   # scene: (frame step, frames counted, frames)
    sw, _ = sweep_rows(out, "fig9", "zeb.banks", scenes)
    for s in scenes:
        counted = read_csv(run_file(out, s, "cpucd_counts.csv"))
        timed = read_csv(run_file(out, s, "cpucd_frames.csv"))
        nf = len(timed)
        # Every frame counted, or every K-th (rbcd-cpucd --frame-step K: frames
        # 0, K, 2K, ...): the count per frame is then the sample's mean.
        frames = [int(r["frame"]) for r in counted]
        step = frames[1] - frames[0] if len(frames) > 1 else 1
        if nf == 0 or step < 1 or frames != list(range(0, nf, step)):
            raise InputMissing(f"{run_file(out, s, 'cpucd_counts.csv')}: {len(counted)} frames counted, not every "
                               f"frame or every K-th of the {nf} timed")
        if step > 1:
            sampled[s] = (step, len(counted), nf)
        instr, host_ms = {}, {}
        for col, _, _ in FIG8_VERSIONS:
            try:
                instr[col] = sum(int(r[f"{col}_instr"]) for r in counted) / len(counted)
                host_ms[col] = sum(float(r[f"{col}_us"]) for r in timed) / nf * 1e-3
            except (KeyError, ValueError):
                raise InputMissing(f"{run_file(out, s, 'cpucd_counts.csv')}: no {col}_instr counts "
                                   "(rbcd-cpucd --count-instructions)") from None
        for banks in (1, 2):
            r = sw[(s, banks)]
            # Per frame: the GPU run and rbcd-cpucd cover the same frames.
            t_gpu = (value(r, "gpu.cycles_with_unit") - value(r, "gpu.baseline_cycles")) / \
                (value(r, "config.clock.mhz") * 1e6) / nf
            with_pj, base_pj = value(r, "energy.gpu.with_unit_pj"), value(r, "energy.gpu.baseline_pj")
            if with_pj is not None and base_pj is not None:
                e_gpu = (float(with_pj) - float(base_pj)) * 1e-12 / nf
            else:
                e_gpu = value(r, "energy.total_pj") * 1e-12 / nf
                fallback = True
            for col, label, paper_kind in FIG8_VERSIONS:
                t_cpu = cpu_model.seconds(instr[col])
                e_cpu = cpu_model.joules(instr[col])
                sp = t_cpu / t_gpu if t_gpu > 0 else math.inf
                er = e_cpu / e_gpu if e_gpu > 0 else math.inf
                paper_sp, paper_er = PAPER["fig8"][(paper_kind, banks)]
                implied_ms = paper_sp * t_gpu * 1e3
                ratios.setdefault((col, banks), []).append((sp, er, implied_ms, instr[col]))
                host_cpi = host_ms[col] * 1e-3 * ghz * 1e9 / instr[col] if ghz and instr[col] else None
                common = [s, label, banks, f"{instr[col]:.0f}", g3(t_cpu * 1e3)]
                tail = [g3(t_gpu * 1e3), sig(sp), g3(e_cpu * 1e6), g3(e_gpu * 1e6), sig(er),
                        g3(implied_ms)]
                rows.append(common + [g3(host_ms[col]), fmt(host_cpi)] + tail)
                md_rows.append(common + tail)
    host_cols = ["host CPU ms/frame (wall clock)", "host cycles per instruction"]
    head = ["scene", "CPU version", "ZEBs", "instructions/frame", "modelled CPU ms/frame"]
    tail = ["extra GPU ms/frame", "speed-up", "modelled CPU uJ/frame", "extra GPU uJ/frame", "energy reduction",
            "CPU ms/frame the paper's speed-up implies"]
    write_csv(os.path.join(out, "fig8.csv"), head + host_cols + tail, rows)

    # A scene where the unit adds no GPU time has an unbounded speed-up (and
    # needs no CPU time for the paper's): the geometric means leave it out,
    # and fig8.md names it.
    def gmean(v):
        v = [x for x in v if x > 0 and not math.isinf(x)]
        return math.exp(sum(math.log(x) for x in v) / len(v)) if v else math.inf
    summary = []
    for banks in (1, 2):
        for col, label, paper_kind in FIG8_VERSIONS:
            rs = ratios[(col, banks)]
            paper_sp, paper_er = PAPER["fig8"][(paper_kind, banks)]
            summary.append([label, banks, f"{gmean([r[3] for r in rs]):.0f}",
                            g3(cpu_model.seconds(gmean([r[3] for r in rs])) * 1e3),
                            sig(gmean([r[0] for r in rs])), paper_sp, sig(gmean([r[1] for r in rs])), paper_er,
                            g3(gmean([r[2] for r in rs]))])
    unbounded = {banks: [s for s, r in zip(scenes, ratios[(FIG8_VERSIONS[0][0], banks)]) if math.isinf(r[0])]
                 for banks in (1, 2)}
    # Captures of more than one game: the geometric means of each game's entries too.
    games = {}
    for s in scenes:
        games.setdefault(game_of(s), []).append(s)
    by_game = []
    if len(games) > 1 and None not in games:
        for game, members in sorted(games.items()):
            idx = [scenes.index(m) for m in members]
            for banks in (1, 2):
                for col, label, paper_kind in FIG8_VERSIONS:
                    rs = [ratios[(col, banks)][k] for k in idx]
                    n_inf = sum(math.isinf(r[0]) for r in rs)
                    by_game.append([game, label, banks, f"{gmean([r[3] for r in rs]):.0f}",
                                    g3(cpu_model.seconds(gmean([r[3] for r in rs])) * 1e3),
                                    sig(gmean([r[0] for r in rs])) + (f" ({n_inf} of {len(rs)} unbounded)" if n_inf else ""),
                                    sig(gmean([r[1] for r in rs]))])
    sh = ["CPU version", "ZEBs", "instructions/frame (geo. mean)", "modelled CPU ms/frame", "speed-up (geo. mean)",
          "paper speed-up", "energy reduction (geo. mean)", "paper energy reduction",
          "CPU ms/frame the paper's speed-up implies (geo. mean)"]
    write_csv(os.path.join(out, "fig8_summary.csv"), sh, summary)
    with open(os.path.join(out, "fig8.md"), "w") as f:
        f.write(md_table(sh, summary))
        f.write(f"\n{cpu_model.describe()}; instructions counted by callgrind (rbcd-cpucd --count-instructions), "
                "the same on any machine for the same build. Host wall-clock times: fig8.csv.\n")
        if fallback:
            f.write("GPU energy: this build has no energy.gpu.with_unit_pj / baseline_pj; the unit's own energy "
                    "(energy.total_pj) stands for the extra GPU energy, so the energy ratios are upper bounds.\n")
        if sampled:
            f.write("Counted on a sample of frames (the same frames on every machine): " +
                    "; ".join(f"{s}: every {ordinal(k)} frame ({n} of {nf})" for s, (k, n, nf) in sampled.items()) +
                    ". An entry's instructions per frame are then its sample's mean; the GPU side covers every frame.\n")
        for banks in (1, 2):
            if unbounded[banks]:
                f.write(f"With {banks} ZEB{'s' if banks > 1 else ''} the unit adds no GPU time on "
                        f"{', '.join(unbounded[banks])}: their speed-up is unbounded (inf) and the speed-up's and "
                        "the implied CPU time's geometric means are over the other "
                        f"{len(scenes) - len(unbounded[banks])} scenes.\n")
        if by_game:
            f.write("\nBy game (geometric means over each game's entries):\n\n" +
                    md_table(["game", "CPU version", "ZEBs", "instructions/frame (geo. mean)", "modelled CPU ms/frame",
                              "speed-up (geo. mean)", "energy reduction (geo. mean)"], by_game))
        f.write("\nPer scene:\n\n" + md_table(head + tail, md_rows))
    plt = plot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.2))
    for ax, idx, title in ((axes[0], 0, "speed-up"), (axes[1], 1, "energy reduction")):
        labels, vals, pap = [], [], []
        for banks in (1, 2):
            for col, label, paper_kind in FIG8_VERSIONS:
                labels.append(f"{label.split(' ', 1)[0]}\n{banks} ZEB")
                vals.append(gmean([r[idx] for r in ratios[(col, banks)]]))
                pap.append(PAPER["fig8"][(paper_kind, banks)][idx])
        x = range(len(labels))
        ax.bar([i - 0.2 for i in x], [v if not math.isinf(v) else 0 for v in vals], 0.4, label="this model (counted)")
        ax.bar([i + 0.2 for i in x], pap, 0.4, label="paper")
        ax.set_yscale("log")
        ax.set_xticks(list(x), labels, fontsize=6)
        ax.set_title(title + ": (a) bare broad, (d) world broad, (b) bare GJK, (e) world full", fontsize=8)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fig8.png"), dpi=80)


# ---------------------------------------------------------------- accuracy
def classify_miss(gt, m64, m64t64):
    """Why RBCD missed a true contact (docs/accuracy.md). gt: the rbcd-cpucd
    pair row (on_screen, px_overlap, px_near, open); m64 / m64t64: whether the pair
    is found in that frame with M = 64 (T as configured) / with M = T = 64."""
    if m64:
        return "list_overflow"
    if m64t64:
        return "stack_overflow"
    if gt.get("on_screen", "0") != "1":
        return "off_screen"
    if int(gt.get("px_overlap", 0)) > 0:
        return "unexplained"
    if int(gt.get("px_near", 0)) > 0:
        return "depth_quantization"
    if gt.get("open", "0") == "1":
        return "open_surface"
    return "sub_pixel"


# RBCD configurations of the accuracy table: name -> (run, run with M = 64, run with M = T = 64)
ACC_CONFIGS = [("M=4 T=8", "m4", "m64", "m64t64"), ("M=8 T=8", "m8", "m64", "m64t64"),
               ("M=16 T=8", "m16", "m64", "m64t64"), ("M=8 T=2", "m8t2", "m64t2", "m64t64")]
# The runs that are Table 3's sweep (zeb.list_length = M); the others are OUT/runs/SCENE/NAME.col.
ACC_FROM_TABLE3 = {"m4": 4, "m8": 8, "m16": 16}


def prf(tp, fp, fn):
    p = 100.0 * tp / (tp + fp) if tp + fp else 100.0
    r = 100.0 * tp / (tp + fn) if tp + fn else 100.0
    return p, r


def target_accuracy(out, scenes):
    rows, miss_rows, fp_rows = [], [], []
    totals = {}
    sw, _ = sweep_rows(out, "table3", "zeb.list_length", scenes)
    for s in scenes:
        gt_rows = read_csv(run_file(out, s, "cpucd_pairs.csv"))
        gt = {(int(r["frame"]), int(r["id_a"]), int(r["id_b"])): r for r in gt_rows}
        truth = {k for k, r in gt.items() if r["exact"] == "1"}
        methods = {"AABB (a)": {k for k, r in gt.items() if r["aabb"] == "1"},
                   "GJK on hulls (b)": {k for k, r in gt.items() if r["gjk"] == "1"}}
        cf = {}
        for label, name, n64, n6464 in ACC_CONFIGS:
            for n in (name, n64, n6464):
                if n not in cf:
                    p, _ = read_collisions(sweep_run_file(out, "table3", sw[(s, ACC_FROM_TABLE3[n])], "collisions.txt")
                                           if n in ACC_FROM_TABLE3 else run_file(out, s, n + ".col"))
                    cf[n] = {(f, a, b) for f, ps in p.items() for a, b in ps}
            methods["RBCD " + label] = cf[name]
        for mname, found in methods.items():
            tp, fp, fn = len(found & truth), len(found - truth), len(truth - found)
            classes = dict.fromkeys(MISS_CLASSES, 0)
            if mname.startswith("RBCD"):
                cfgs = {("RBCD " + c[0]): c for c in ACC_CONFIGS}
                _, _, n64, n6464 = cfgs[mname]
                for k in sorted(truth - found):
                    c = classify_miss(gt[k], k in cf[n64], k in cf[n6464])
                    classes[c] += 1
                    miss_rows.append([s, mname, *k, c])
                for k in sorted(found - truth):
                    r = gt.get(k, {})
                    fp_rows.append([s, mname, *k, r.get("aabb", "0"), r.get("gjk", "0"), r.get("px_overlap", "0")])
            p, r = prf(tp, fp, fn)
            _, rv = prf(tp, 0, fn - classes["off_screen"])
            rows.append([s, mname, len(truth), tp, fp, fn, fmt(p, 2), fmt(r, 2), fmt(rv, 2)] +
                        ([classes[c] for c in MISS_CLASSES] if mname.startswith("RBCD") else [""] * len(MISS_CLASSES)))
            t = totals.setdefault(mname, [0, 0, 0, 0, dict.fromkeys(MISS_CLASSES, 0)])
            t[0] += len(truth)
            t[1] += tp
            t[2] += fp
            t[3] += fn
            for c in MISS_CLASSES:
                t[4][c] += classes[c]
    for mname, t in totals.items():
        p, r = prf(t[1], t[2], t[3])
        _, rv = prf(t[1], 0, t[3] - t[4]["off_screen"])
        rows.append(["all", mname, t[0], t[1], t[2], t[3], fmt(p, 2), fmt(r, 2), fmt(rv, 2)] +
                    ([t[4][c] for c in MISS_CLASSES] if mname.startswith("RBCD") else [""] * len(MISS_CLASSES)))
    header = ["scene", "method", "true pair-frames", "TP", "FP", "FN", "precision %", "recall %",
              "recall of on-screen contacts %"] + \
             ["miss: " + c.replace("_", " ") for c in MISS_CLASSES]
    write_csv(os.path.join(out, "accuracy.csv"), header, rows)
    write_csv(os.path.join(out, "accuracy_misses.csv"), ["scene", "method", "frame", "id_a", "id_b", "class"], miss_rows)
    write_csv(os.path.join(out, "accuracy_false_positives.csv"),
              ["scene", "method", "frame", "id_a", "id_b", "aabb", "gjk", "px_overlap"], fp_rows)
    with open(os.path.join(out, "accuracy.md"), "w") as f:
        f.write("Overall (pair-frames of all scenes):\n\n")
        f.write(md_table(header[1:], [r[1:] for r in rows if r[0] == "all"]))
        f.write("\nPer scene:\n\n")
        f.write(md_table(header, [r for r in rows if r[0] != "all"]))
    plt = plot()
    fig, ax = plt.subplots(figsize=(7, 3.2))
    allrows = [r for r in rows if r[0] == "all"]
    x = range(len(allrows))
    ax.bar([i - 0.27 for i in x], [float(r[6]) for r in allrows], 0.27, label="precision")
    ax.bar(list(x), [float(r[7]) for r in allrows], 0.27, label="recall")
    ax.bar([i + 0.27 for i in x], [float(r[8]) for r in allrows], 0.27, label="recall, on-screen contacts")
    ax.set_xticks(list(x), [r[1].replace(" (", "\n(").replace("RBCD ", "RBCD\n") for r in allrows], fontsize=7)
    ax.set_ylim(0, 105)
    ax.set_ylabel("% (all scenes)")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    fig.savefig(os.path.join(out, "accuracy.png"), dpi=80)


# ---------------------------------------------------------------- splice
def splice(out, doc, prefix=""):
    """Replaces every <!-- PREFIXNAME:begin --> ... <!-- PREFIXNAME:end --> block of doc by
    OUT/NAME.md (the game suite's tables sit in blocks named games-NAME)."""
    with open(doc) as f:
        text = f.read()

    def repl(m):
        name = m.group(1)
        if not name.startswith(prefix) or (not prefix and name.startswith("games-")):
            return m.group(0)
        path = os.path.join(out, name[len(prefix):] + ".md")
        if not os.path.exists(path):
            return m.group(0)   # a target not run this time keeps its last table
        with open(path) as g:
            body = g.read()
        return f"<!-- {name}:begin -->\n{body}<!-- {name}:end -->"
    text = re.sub(r"<!-- ([\w-]+):begin -->.*?<!-- \1:end -->", repl, text, flags=re.S)
    with open(doc, "w") as f:
        f.write(text)


def thumbnail(src, dst):
    """Half-size copy of a picture: small enough to commit."""
    import matplotlib.image as mpimg
    img = mpimg.imread(need(src))
    mpimg.imsave(dst, img[::2, ::2])


TARGETS = {"workloads": target_workloads, "table3": target_table3, "fig9": target_fig9, "fig8": target_fig8,
           "accuracy": target_accuracy}


def run(argv):
    ap = ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", action=Once, default="results")
    ap.add_argument("--splice", action=Once, nargs=2, metavar=("OUT", "DOC"))
    ap.add_argument("--splice-prefix", action=Once, default="", help="with --splice: the blocks' name prefix (games-)")
    ap.add_argument("--thumbnail", action=Once, nargs=2, metavar=("SRC", "DST"))
    ap.add_argument("--sweep-file", action=Once, nargs=3, metavar=("SWEEP", "SUITE", "DEST"))
    ap.add_argument("--id-bits", action=Once, metavar="SCENE")
    ap.add_argument("targets", nargs="*")
    a = ap.parse_args(argv)
    try:
        if a.splice:
            splice(*a.splice, prefix=a.splice_prefix)
            return 0
        if a.thumbnail:
            thumbnail(*a.thumbnail)
            return 0
        if a.sweep_file:
            sweep_file(*a.sweep_file)
            return 0
        if a.id_bits:
            print(id_bits(a.id_bits))
            return 0
        scenes = scenes_of(a.out)
        for t in a.targets:
            if t not in TARGETS:
                say(PROG, f"unknown target '{t}' (known: {', '.join(TARGETS)})")
                return 2
            TARGETS[t](a.out, scenes)
    except InputMissing as e:
        say(PROG, str(e))
        return 2
    except tomllib.TOMLDecodeError as e:
        say(PROG, str(e))
        return 2
    except OSError as e:
        say(PROG, f"{e.filename}: {e.strerror}")
        return 2
    return 0


def main(argv=None):
    return main_wrapper(PROG, run, sys.argv[1:] if argv is None else argv)


if __name__ == "__main__":
    sys.exit(main())
