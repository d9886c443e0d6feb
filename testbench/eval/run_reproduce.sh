#!/usr/bin/env bash
# CTest entry: scripts/reproduce.sh TARGET on the cut-down workload (mini/),
# then checks what the target promises to write. Exit 77 (skipped) when the
# target needs rbcd-cpucd and it was not built.
#   run_reproduce.sh SOURCE_DIR BUILD_DIR TARGET
set -euo pipefail
src=$1 build=$2 target=$3
case $target in
  workloads|fig8|accuracy)
    if [ ! -x "$build/bin/rbcd-cpucd" ]; then
      echo "rbcd-cpucd not built (libbullet-dev, libfcl-dev missing): reproduce.sh $target skipped"
      exit 77
    fi
    if [ "$target" = fig8 ] && ! command -v valgrind >/dev/null; then
      echo "valgrind missing (scripts/setup.sh --eval): reproduce.sh fig8 skipped"
      exit 77
    fi
    # fig8 counts under valgrind, which cannot run ASan's binaries.
    if [ "$target" = fig8 ] && grep -q '^RBCD_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null; then
      echo "sanitizer build: valgrind cannot run it, reproduce.sh fig8 skipped"
      exit 77
    fi ;;
esac
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$src/scripts/reproduce.sh" --no-build --build "$build" --workloads "$src/testbench/eval/mini" --out "$out" \
  --repeat 1 --jobs 1 "$target"
fail() { echo "run_reproduce.sh $target: $*" >&2; exit 1; }
for f in "$target.csv" "$target.png" "$target.md" provenance.md; do
  [ -s "$out/$f" ] || fail "$f missing or empty"
done
PYTHONPATH="$src/python${PYTHONPATH:+:$PYTHONPATH}" /usr/bin/python3 - "$out" "$target" "$src" <<'PY' || exit 1
import csv, sys
out, target = sys.argv[1], sys.argv[2]
rows = list(csv.DictReader(open(f"{out}/{target}.csv")))
def fail(msg):
    print(f"run_reproduce.sh {target}: {msg}", file=sys.stderr)
    sys.exit(1)
if target in ("table3", "fig9"):
    # Run as a sweep (workloads/sweeps/TARGET.toml over the mini suite) by rbcd-sweep; plotted by rbcd-plot.
    axis, n = {"table3": ("zeb.list_length", 3), "fig9": ("zeb.banks", 2)}[target]
    runs = list(csv.DictReader(open(f"{out}/sweep/{target}.csv")))
    if len(runs) != n or any(r["status"] != "0" or not r["input"].endswith("/mini.toml") for r in runs):
        fail(f"sweep/{target}.csv: {len(runs)} rows, expected {n} successful runs of mini.toml")
    plot = list(csv.DictReader(open(f"{out}/{target}_plot.csv")))
    if {r[axis] for r in plot} != {r[axis] for r in runs} or "paper" not in {r["scene"] for r in plot}:
        fail(f"{target}_plot.csv: not the sweep's {axis} values with the paper's line")
if target == "table3":
    mini = rows[0]
    # M = 4 overflows in the mini scene (balls in front of the box in front of the backdrop), M = 16 never.
    if not float(mini["M=4 fragments dropped %"]) > 0: fail("M=4 drops nothing")
    if float(mini["M=16 fragments dropped %"]) != 0: fail("M=16 drops fragments")
    if rows[-1]["scene"] != "paper (Table 3)": fail("no paper row")
elif target == "fig9":
    if rows[0]["scene"] != "mini" or rows[-1]["1 ZEB: GPU time overhead %"] != "5.4": fail("rows")
    if not float(rows[0]["1 ZEB: GPU time overhead %"]) >= float(rows[0]["2 ZEBs: GPU time overhead %"]):
        fail("one ZEB cheaper than two")
elif target == "fig8":
    if len(rows) != 8: fail(f"{len(rows)} rows, expected 8 (4 CPU versions x 2 ZEB counts)")
    if not all(float(r["host CPU ms/frame (wall clock)"]) > 0 for r in rows): fail("CPU time not measured")
    if not all(float(r["instructions/frame"]) > 0 for r in rows): fail("CPU work not counted")
    # The counted model: time = instructions x CPI / clock, whatever the host.
    from rbcd import cpu_model
    for r in rows:
        want = cpu_model.seconds(float(r["instructions/frame"])) * 1e3
        if abs(float(r["modelled CPU ms/frame"]) - want) > 5e-3 * want: fail(f"modelled time {r}")
    # The narrow phase adds work to its broad phase.
    by = {(r["CPU version"][:3], r["ZEBs"]): float(r["instructions/frame"]) for r in rows}
    if not (by[("(b)", "1")] > by[("(a)", "1")] and by[("(e)", "1")] > by[("(d)", "1")]):
        fail("broad + narrow counted below its broad phase")
    summary = list(csv.DictReader(open(f"{out}/fig8_summary.csv")))
    if len(summary) != 8 or any(float(r["CPU ms/frame the paper's speed-up implies (geo. mean)"]) <= 0 for r in summary):
        fail("fig8_summary.csv")
elif target == "accuracy":
    got = {r["method"]: r for r in rows if r["scene"] == "mini"}
    # The balls meet in frame 2 only (1 true pair-frame); the rod never touches the ring.
    if got["AABB (a)"]["true pair-frames"] != "1": fail(f"true pair-frames {got['AABB (a)']['true pair-frames']}")
    if got["RBCD M=8 T=8"]["recall %"] != "100.00": fail("RBCD misses a contact of the mini scene")
    if got["GJK on hulls (b)"]["FP"] == "0": fail("the hull of the ring should report the rod")
elif target == "workloads":
    if rows[0]["collisionable objects"] != "5": fail("object count")
PY
echo "run_reproduce.sh $target: ok"
