#!/usr/bin/env bash
# rbcd-cpucd as a command: (1) a scene's geometry exported to a geometry file
# and its fragments to a trace give the same pairs as the scene itself;
# (2) bad input exits 2 with one line naming file:line and leaves no output.
#   cli_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
cpucd=$build/bin/rbcd-cpucd sim=$build/bin/rbcd-sim
scene=$src/testbench/eval/mini/mini.toml
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
fail() { echo "cli_test.sh: $*" >&2; exit 1; }

"$cpucd" --scene "$scene" --pixels --repeat 1 -q --pairs "$d/scene.csv" --write-geometry "$d/mini.geo"
"$sim" --scene "$scene" --write-trace "$d/mini.rbt" -q
"$cpucd" --geometry "$d/mini.geo" --trace "$d/mini.rbt" --pixels --repeat 1 -q --pairs "$d/geo.csv"
cmp -s "$d/scene.csv" "$d/geo.csv" || { diff "$d/scene.csv" "$d/geo.csv" | head; fail "geometry file + trace differ from the scene"; }
grep -q '^2,1,2,1,1,1,' "$d/scene.csv" || fail "the balls' contact in frame 2 is missing"

printf 'rbcd-geometry 1\npart 1 3 1\nv 0 0 0\nv 1 0 0\nv 0 1 x\n' > "$d/bad.geo"
set +e
msg=$("$cpucd" --geometry "$d/bad.geo" --pairs "$d/out.csv" 2>&1 >/dev/null)
rc=$?
set -e
[ "$rc" -eq 2 ] || fail "bad geometry: exit $rc, expected 2"
[[ $msg == "rbcd-cpucd: $d/bad.geo:5: "* ]] || fail "bad geometry: message '$msg' does not name the line"
[ "$(printf '%s\n' "$msg" | wc -l)" -eq 1 ] || fail "bad geometry: more than one line"
[ ! -e "$d/out.csv" ] || fail "bad geometry: output left behind"
echo "cli_test.sh: ok"
