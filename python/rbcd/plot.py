"""rbcd-plot: a PNG of one metric of a sweep's results.csv against one axis,
one line per value of another axis (docs/sweeps.md, "Plots").

    rbcd-plot OUT/results.csv --y gpu.overhead_pct --x zeb.banks --lines input -o banks.png
    rbcd-plot OUT/results.csv --y totals.overflows --x zeb.list_length --lines input \\
              --where tester.output=raw -o overflows.png

Rows whose status is not 0 are left out. Rows that share an x and a line
value (repeats, or axes neither plotted nor fixed with --where) are averaged,
and the averaged columns are named on stderr. matplotlib draws the plot;
without it (or with --backend gnuplot) gnuplot does.
Exit status: 0 written; 2 bad command line or table, 1 anything else (one line
on stderr). Axes are labelled with the columns' units; a legend of inputs
shows them without the directories they share.

    rbcd-plot heatmap run.sqlite -o maps/ [--frame N] [--metric stall] [--values maps/v.csv]

draws per-tile heat maps of the screen from rbcd-sim's --db database
(docs/tile-database.md): stall cycles, fragments dropped (overflow),
collisionable depth complexity and hits, summed over the run or for one frame,
one PNG each (DIR/run_stall.png, DIR/frame_00012_stall.png), with a colour
scale and its legend; matplotlib only.
"""
import argparse
import csv
import io
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

from rbcd.cli import (ArgumentParser, Once, UsageError, ascii_int, check_outputs, main_wrapper, read_input_text, say,
                      write_output)

PROG = "rbcd-plot"
META = {"point", "repeat", "status", "error", "run"}

# A results table is a page per thousand runs; larger is refused before it is parsed.
MAX_TABLE_BYTES = 256 << 20


class PlotError(UsageError):
    pass


# Units of the stats and configuration columns, by the name's ending
# (docs/stats.md, docs/config.md): axis labels say what the numbers are.
UNITS = [("_pct", "%"), ("_nj", "nJ"), ("_pj", "pJ"), ("_us", "µs"), ("wall_s", "s"), ("_seconds", "s"),
         ("cycles", "cycles"), ("_cycle", "cycle"), (".mhz", "MHz"), ("_bytes", "bytes"), ("latency_min", "cycles"),
         ("latency_max", "cycles"), ("list_length", "elements a list"), ("zeb.banks", "banks"),
         ("tile.width", "pixels"), ("tile.height", "pixels"), ("per_second", "1/s")]
COUNTS = ("totals.", "blocks.")


def label(col):
    """A column name with its unit: "gpu.overhead_pct (%)", "totals.hits (count)"."""
    for end, unit in UNITS:
        if col.endswith(end):
            return f"{col} ({unit})"
    if col.startswith(COUNTS):
        return f"{col} (count)"
    return col


def legend_names(values):
    """Line values as the legend shows them: inputs given as paths without the
    directories they share (no absolute path in a figure meant for a paper)."""
    if not values or not all("/" in v for v in values):
        return {v: v for v in values}
    if len(values) == 1:
        return {values[0]: os.path.basename(values[0])}
    common = os.path.commonpath(values) if all(v.startswith("/") == values[0].startswith("/") for v in values) else ""
    return {v: os.path.relpath(v, common) if common else v for v in values}


# A number as rbcd-sweep writes one (and as the other tools read numbers):
# ASCII digits, a sign, a point, an exponent; not float()'s underscores,
# other scripts' digits or spaces around it.
NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|[+-]?(inf|infinity|nan)", re.ASCII | re.IGNORECASE)


def number(s):
    if not NUMBER.fullmatch(s):
        return None
    v = float(s)
    return v if math.isfinite(v) else None


def order(values):
    """Numeric values in numeric order, otherwise in order of first appearance."""
    seen = list(dict.fromkeys(values))
    if all(number(v) is not None for v in seen):
        return sorted(seen, key=number)
    return seen


# A record's line as csv reads a file opened with newline="": ended by
# "\r\n", "\r" or "\n", the ending kept (a quoted field may hold one).
LINE = re.compile(r"[^\r\n]*(?:\r\n|\r|\n)|[^\r\n]+$")


def records(text):
    """The table's records (lists of fields), read without copying the
    text: the header, then each row (csv.DictReader's blank rows left out)."""
    reader = csv.reader(m.group(0) for m in LINE.finditer(text))
    head = next(reader, None)
    yield head
    for row in reader:
        if row:
            yield row


class Table:
    """What a plot needs of a results table, gathered in passes over its
    text, no row kept (a dict a row had taken about 60 bytes of memory a
    byte of table): the columns, the distinct x and line values in order of
    first appearance, each (line, x)'s sum and count of --y, and which
    other axis columns vary."""

    def __init__(self, path, args):
        text = read_input_text(path, "results table", MAX_TABLE_BYTES)
        try:
            rows = records(text)
            header = next(rows)
            count, uneven = 0, False
            for row in rows:
                uneven = uneven or len(row) != len(header)   # (named after the whole table is read, as csv errors)
                count += 1
        except csv.Error as e:
            raise PlotError(f"{path}: not a results table: {e}")
        if uneven:
            raise PlotError(f"{path}: not a results table: rows of another length than the header")
        if not count:
            raise PlotError(f"{path}: no rows")
        # (A column named twice is read from its last place, as DictReader does.)
        at = {c: i for i, c in enumerate(header)}
        self.head = list(at)
        for col, what in ((args.y, "--y"), (args.x, "--x")) + (((args.lines, "--lines"),) if args.lines else ()):
            if col not in at:
                raise PlotError(f"{what} {col}: no such column in {path} (columns: {', '.join(self.head)})")
        where = []
        for w in args.where:
            k, sep, v = w.partition("=")
            if not sep or k not in at:
                raise PlotError(f"--where {w}: expected COLUMN=VALUE with a column of {path}")
            where.append((at[k], v))
        fixed = {args.x, args.y} | ({args.lines} if args.lines else set()) | {k for k, _ in
                                                                              (w.partition("=")[::2] for w in args.where)}
        # Columns before the first metric column are axes; those that vary are averaged.
        axes = [c for c in self.head if c not in fixed and c not in META
                and not c.startswith(("totals.", "gpu.", "energy."))] + (["repeat"] if "repeat" in at else [])
        first, varies = {}, set()
        status, y, x, ln = at.get("status"), at[args.y], at[args.x], at.get(args.lines) if args.lines else None
        self.xs, self.lines, self.sums = {}, {}, {}
        successful, bad = 0, None
        rows = records(text)
        next(rows)   # (the header)
        for row in rows:
            if status is not None and row[status] != "0" or not all(row[k] == v for k, v in where):
                continue
            successful += 1
            for c in axes:
                v = row[at[c]]
                if first.setdefault(c, v) != v:
                    varies.add(c)
            if number(row[y]) is None:
                bad = row[y] if bad is None else bad
                continue
            line = row[ln] if ln is not None else ""
            self.xs.setdefault(row[x], None)
            self.lines.setdefault(line, None)
            if len(self.lines) > MAX_LINES:
                continue   # (refused by check_lines: no more sums kept)
            acc = self.sums.setdefault((line, row[x]), [0.0, 0])
            acc[0] += float(row[y])
            acc[1] += 1
        if not successful:
            raise PlotError(f"{path}: no successful rows{' match --where' if where else ''}")
        if bad is not None:
            raise PlotError(f"--y {args.y}: not a number in some rows (e.g. \"{bad}\")")
        self.varying = [c for c in axes if c in varies]


def series(table, args):
    """{line: [(x, mean y)]} and the columns averaged over."""
    xs = order(list(table.xs))
    lines = order(list(table.lines)) if args.lines else [""]
    check_lines(lines, args)
    sums = table.sums
    out = {ln: [(x, sums[ln, x][0] / sums[ln, x][1]) for x in xs if (ln, x) in sums] for ln in lines}
    return xs, out, table.varying


def check_lines(lines, args):
    """More lines than a legend shows, or a value longer than an entry
    holds, refused before any line is computed."""
    longest = max((len(str(ln)) for ln in lines), default=0)
    if len(lines) > MAX_LINES or longest > MAX_TITLE_CHARS:
        raise PlotError(f"--lines {args.lines}: {len(lines)} values (the longest of {longest} characters), more "
                        f"than the {MAX_LINES} lines of {MAX_TITLE_CHARS} characters a legend shows")


MAX_AXIS_VALUE = 1e300
MAX_TITLE_CHARS = 1000
MAX_LINES = 100   # lines one plot draws (--lines), each with its legend entry


def check_axes(xs, data, args, numeric_x):
    """What no plot can show, refused: --logx with an x that is not a
    positive number (a log axis would drop it, or fail), values (or means)
    past 1e300 (an axis' limits and margins would overflow a double), and a
    title longer than a plot's raster holds."""
    if args.logx:
        if not numeric_x:
            raise PlotError(f"--logx: --x {args.x} is not numeric")
        bad = [x for x in xs if number(x) <= 0]
        if bad:
            raise PlotError(f"--logx: --x {args.x} has {bad[0]}, not a positive number: a log axis cannot place it")
    ys = [y for pts in data.values() for _, y in pts]
    axes = [("--y", args.y, ys)] + ([("--x", args.x, [number(x) for x in xs])] if numeric_x else [])
    for opt, col, vals in axes:
        # (An axis' limits, margins and ticks are computed from the span:
        # within 1e300 they stay doubles.)
        if not all(math.isfinite(v) and abs(v) <= MAX_AXIS_VALUE for v in vals):
            raise PlotError(f"{opt} {col}: values (or their means) past {MAX_AXIS_VALUE:g}, more than an axis can "
                            f"hold ({min(vals):g} to {max(vals):g})")
    if args.title is not None and len(args.title) > MAX_TITLE_CHARS:
        raise PlotError(f"--title: {len(args.title)} characters, more than the {MAX_TITLE_CHARS} a plot shows")
    # The axes' labels and the legend's entries are column names and values.
    for opt, col in (("--x", args.x), ("--y", args.y), ("--lines", args.lines)):
        if col is not None and len(col) > MAX_TITLE_CHARS:
            raise PlotError(f"{opt}: a column name of {len(col)} characters, more than the {MAX_TITLE_CHARS} "
                            "a plot's label shows")


def plot_matplotlib(xs, data, args, numeric_x):
    """The PNG's bytes. Matplotlib's warnings are not printed: what they
    warn of is refused before (check_axes) or changes nothing drawn."""
    import warnings
    warnings.simplefilter("ignore")
    import matplotlib
    matplotlib.use("Agg")
    # Titles and column names are text, never TeX: a '$' in them is a dollar
    # sign (mathtext would fail on '$\\frac{$').
    matplotlib.rcParams["text.parse_math"] = False
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=100)
    names = legend_names(list(data))
    for ln, pts in data.items():
        px = [number(x) if numeric_x else xs.index(x) for x, _ in pts]
        ax.plot(px, [y for _, y in pts], marker="o", label=f"{args.lines} = {names[ln]}" if args.lines else None)
    if not numeric_x:
        ax.set_xticks(range(len(xs)), xs, rotation=20, ha="right")
    else:
        if args.logx:
            ax.set_xscale("log", base=2)
        if len(xs) <= 16:
            ax.set_xticks([number(x) for x in xs], xs)
    ax.set_xlabel(label(args.x))
    ax.set_ylabel(label(args.y))
    ax.set_title(args.title or f"{args.y} vs {args.x}")
    ax.grid(True, alpha=0.3)
    if args.lines:
        ax.legend(fontsize="small")
    fig.tight_layout()
    buf = io.BytesIO()
    fig.savefig(buf, format="png")
    plt.close(fig)
    return buf.getvalue()


def plot_gnuplot(xs, data, args, numeric_x):
    gp = shutil.which("gnuplot")
    if not gp:
        raise PlotError("neither matplotlib (python3-matplotlib) nor gnuplot (gnuplot-nox) is installed")
    quote = lambda s: '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'
    names = legend_names(list(data))
    with tempfile.TemporaryDirectory(prefix="rbcd-plot.") as tmp:
        png = os.path.join(tmp, "plot.png")
        plots = []
        for i, (ln, pts) in enumerate(data.items()):
            dat = os.path.join(tmp, f"{i}.dat")
            with open(dat, "w", encoding="utf-8") as f:
                for x, y in pts:
                    f.write(f"{number(x) if numeric_x else xs.index(x)} {y!r}\n")
            title = quote(f"{args.lines} = {names[ln]}") if args.lines else "notitle"
            plots.append(f"{quote(dat)} using 1:2 with linespoints {'title ' + title if args.lines else title}")
        script = ["set terminal png size 700,450", f"set output {quote(png)}",
                  f"set xlabel {quote(label(args.x))}", f"set ylabel {quote(label(args.y))}",
                  f"set title {quote(args.title or f'{args.y} vs {args.x}')}", "set grid", "set key outside right"]
        if not numeric_x:
            script.append("set xtics (" + ", ".join(f"{quote(x)} {i}" for i, x in enumerate(xs)) + ")")
        elif args.logx:
            script.append("set logscale x 2")
        script.append("plot " + ", ".join(plots))
        r = subprocess.run([gp], input="\n".join(script) + "\n", text=True, capture_output=True)
        if r.returncode != 0:
            raise RuntimeError(f"gnuplot failed: {r.stderr.strip().splitlines()[-1] if r.stderr.strip() else r.returncode}")
        with open(png, "rb") as f:
            return f.read()


HEAT_METRICS = {
    "stall": ("stall cycles", "stall_no_bank + stall_queue_full + stall_fragment_queue + stall_output"),
    "overflow": ("fragments dropped (overflow)", "fragments_dropped"),
    "depth": ("collisionable depth complexity (fragments per pixel)", "fragments"),
    "hits": ("hits", "hits"),
}


def heat_grid(db, metric, frame):
    """{(col, row): value} and the grid's size, from the tiles table."""
    import sqlite3
    try:
        con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
        run = dict(con.execute("SELECT key, value FROM run"))
        where = "" if frame is None else f" WHERE frame = {int(frame)}"
        rows = con.execute(f"SELECT col, row, total({HEAT_METRICS[metric][1]}) FROM tiles{where} "
                           "GROUP BY col, row").fetchall()
        frames = 1 if frame is not None else con.execute("SELECT count(*) FROM frames").fetchone()[0]
        con.close()
    except sqlite3.Error as e:
        raise PlotError(f"{db}: not a tile database: {e}")
    try:
        tw, th = int(run["tile_width"]), int(run["tile_height"])
        cols = -(-int(run["screen_width"]) // tw)
        nrows = -(-int(run["screen_height"]) // th)
    except (KeyError, ValueError):
        raise PlotError(f"{db}: its run table lacks the screen and tile sizes")
    if not rows:
        raise PlotError(f"{db}: no tiles" + ("" if frame is None else f" in frame {frame}"))
    cols = max([cols] + [c + 1 for c, _, _ in rows])
    nrows = max([nrows] + [r + 1 for _, r, _ in rows])
    scale = tw * th * max(frames, 1) if metric == "depth" else 1
    return {(c, r): v / scale for c, r, v in rows}, cols, nrows


def heatmap_main(argv):
    ap = ArgumentParser(prog=f"{PROG} heatmap", description="per-tile heat maps from rbcd-sim --db")
    ap.add_argument("db", help="the database rbcd-sim --db wrote")
    ap.add_argument("-o", "--output", action=Once, required=True, help="directory for the PNGs")
    ap.add_argument("--frame", action=Once, type=ascii_int, help="one frame (default: summed over the run)")
    ap.add_argument("--metric", choices=sorted(HEAT_METRICS), action="append", help="default: all four")
    ap.add_argument("--values", action=Once, help="also write the grids as CSV (metric,col,row,value)")
    args = ap.parse_args(argv)
    try:
        if not os.path.isfile(args.db):
            raise PlotError(f"{args.db}: no such database")
        try:
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            import numpy as np
        except ImportError:
            raise PlotError("heat maps need python3-matplotlib (scripts/setup.sh --plots)")
        os.makedirs(args.output, exist_ok=True)
        stem = "run" if args.frame is None else f"frame_{args.frame:05d}"
        csv_rows = []
        for metric in args.metric or ["stall", "overflow", "depth", "hits"]:
            grid, cols, nrows = heat_grid(args.db, metric, args.frame)
            a = np.full((nrows, cols), np.nan)
            for (c, r), v in grid.items():
                a[r, c] = v
                csv_rows.append((metric, c, r, v))
            fig, ax = plt.subplots(figsize=(max(4, cols / 5), max(3, nrows / 5) + 0.6))
            cmap = plt.get_cmap("inferno").copy()
            cmap.set_bad("#c8c8c8")
            im = ax.imshow(a, cmap=cmap, vmin=0, interpolation="nearest")
            bar = fig.colorbar(im, ax=ax)
            bar.set_label(HEAT_METRICS[metric][0])
            ax.set_xlabel("tile column")
            ax.set_ylabel("tile row")
            what = "run" if args.frame is None else f"frame {args.frame}"
            ax.set_title(f"{os.path.basename(args.db)}, {what}: {HEAT_METRICS[metric][0]}")
            # Rendered in memory, written as every output is (rbcd.cli.write_output).
            png = io.BytesIO()
            try:
                fig.savefig(png, format="png", dpi=100, bbox_inches="tight")
            finally:
                plt.close(fig)
            write_output(os.path.join(args.output, f"{stem}_{metric}.png"), png.getvalue(), "heat map")
        if args.values:
            text = io.StringIO()
            w = csv.writer(text)
            w.writerow(["metric", "col", "row", "value"])
            w.writerows(csv_rows)
            write_output(args.values, text.getvalue(), "values")
    except PlotError as e:
        sys.stderr.write(f"{PROG}: {e}\n")
        return 2
    except OSError as e:
        sys.stderr.write(f"{PROG}: {e.filename or args.output}: {e.strerror}\n")
        return 2
    return 0


def run(argv):
    if argv[:1] == ["heatmap"]:
        return heatmap_main(argv[1:])
    ap = ArgumentParser(prog=PROG, description=__doc__.split("\n")[0],
                        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("table", help="results.csv of rbcd-sweep")
    ap.add_argument("--y", action=Once, required=True, help="metric column, e.g. gpu.overhead_pct")
    ap.add_argument("--x", action=Once, required=True, help="axis column for the x axis, e.g. zeb.banks")
    ap.add_argument("--lines", action=Once, help="column whose values get one line each, e.g. input")
    ap.add_argument("--where", action="append", default=[], metavar="COLUMN=VALUE", help="keep only these rows")
    ap.add_argument("-o", "--output", action=Once, required=True, help="PNG file to write")
    ap.add_argument("--title", action=Once)
    ap.add_argument("--logx", action="store_true", help="log2 x axis (numeric x only)")
    ap.add_argument("--backend", action=Once, choices=["auto", "matplotlib", "gnuplot"], default="auto")
    args = ap.parse_args(argv)
    if same_path(args.output, args.table):
        raise PlotError(f"-o {args.output}: is the input table {args.table}")
    # (A FIFO or socket as -o would be waited on for a reader: refused, as
    # every tool refuses it.)
    check_outputs([("the input table", args.table)], [("-o", args.output)])
    xs, data, varying = series(Table(args.table, args), args)
    if varying:
        say(PROG, f"averaging over {', '.join(varying)} (fix them with --where)")
    numeric_x = all(number(x) is not None for x in xs)
    check_axes(xs, data, args, numeric_x)
    backend = args.backend
    if backend == "auto":
        try:
            import matplotlib  # noqa: F401
            backend = "matplotlib"
        except ImportError:
            backend = "gnuplot"
    png = (plot_matplotlib if backend == "matplotlib" else plot_gnuplot)(xs, data, args, numeric_x)
    # As rbcd-sim writes its outputs: complete or absent, no planted symlink followed.
    write_output(args.output, png)
    return 0


def same_path(a, b):
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def main(argv=None):
    return main_wrapper(PROG, run, sys.argv[1:] if argv is None else argv)


if __name__ == "__main__":
    sys.exit(main())
