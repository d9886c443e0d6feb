#!/usr/bin/env bash
# rbcd-cpucd --count-instructions (docs/cpucd.md, "Counted work"): the same
# input gives the same counts run after run, wherever the input and outputs
# lie (the paths change the heap's history), for a scene and for a format-2
# geometry file; a scene and its format-1 geometry file count alike; the
# counted run finds the timed run's pairs; a counted run that would write
# more than its counts is refused (exit 2, one line, nothing left); one
# stopped by SIGTERM leaves nothing, in TMPDIR neither. Exit 77
# (skipped) without valgrind or valgrind/callgrind.h, or in a sanitizer build
# (valgrind cannot run ASan's binaries).
#   count_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$1 build=$2
cpucd=$build/bin/rbcd-cpucd
command -v valgrind >/dev/null || { echo "valgrind missing (scripts/setup.sh --eval): counting tests skipped"; exit 77; }
d=$(mktemp -d)
trap 'rm -rf "$d"' EXIT
fail() { echo "count_test.sh: $*" >&2; exit 1; }

set +e
msg=$("$cpucd" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --frames "$d/probe.csv" -q 2>&1)
rc=$?
set -e
if [ "$rc" -eq 2 ] && [[ $msg == *"built without valgrind/callgrind.h"* || $msg == *"built with AddressSanitizer"* ]]; then
  echo "${msg#rbcd-cpucd: }: counting tests skipped"; exit 77
fi
[ "$rc" -eq 0 ] || fail "counted run failed ($rc): $msg"

# A format-2 file: a box part moving along x, and each frame a mesh of its
# own (a tetrahedron, object 2) that the box reaches in frame 1.
{
  echo "rbcd-geometry 2"
  echo "part 1 8 12 box"
  for i in 0 1 2 3 4 5 6 7; do echo "v $(( (i & 1) * 2 - 1 )) $(( (i >> 1 & 1) * 2 - 1 )) $(( (i >> 2 & 1) * 2 - 1 ))"; done
  printf 't 0 2 1\nt 1 2 3\nt 4 5 6\nt 5 7 6\nt 0 1 4\nt 1 5 4\nt 2 6 3\nt 3 6 7\nt 0 4 2\nt 2 4 6\nt 1 3 5\nt 3 7 5\n'
  for f in 0 1 2; do
    echo "frame $f"
    echo "m 0 1 0 0 $((f * 2)) 0 1 0 0 0 0 1 0"
    printf 'mesh 2 4 4 tet\nv 3 0 0\nv 5 0 0\nv 4 2 0\nv 4 1 2\nt 0 2 1\nt 0 1 3\nt 1 2 3\nt 2 0 3\n'
  done
} > "$d/game.geo"

counts() { cut -d, -f1-4,9-11,14-18 "$1"; }
mkdir -p "$d/a/much/longer/directory/name/than/the/other/one"
cp "$src/testbench/eval/mini/mini.toml" "$d/a/much/longer/directory/name/than/the/other/one/"
cp "$d/game.geo" "$d/a/much/longer/directory/name/than/the/other/one/"
for input in "--scene $src/testbench/eval/mini/mini.toml" "--geometry $d/game.geo"; do
  set -- $input
  name=$(basename "$2")
  far=$d/a/much/longer/directory/name/than/the/other/one/$name
  "$cpucd" "$1" "$2" --count-instructions --frames "$d/1.csv" -q
  "$cpucd" "$1" "$2" --count-instructions --frames "$d/2.csv" -q
  "$cpucd" "$1" "$far" --count-instructions --frames "$d/a/much/longer/directory/name/than/the/other/one/3.csv" -q
  cmp -s <(counts "$d/1.csv") <(counts "$d/2.csv") || { diff <(counts "$d/1.csv") <(counts "$d/2.csv"); fail "$name: counts differ between two runs"; }
  cmp -s <(counts "$d/1.csv") <(counts "$d/a/much/longer/directory/name/than/the/other/one/3.csv") ||
    fail "$name: counts differ with the input in another directory"
  # Every counted section executed something; times and the exact phase left empty.
  awk -F, -v n="$name" 'NR > 1 { for (k = 15; k <= 18; ++k) if ($k !~ /^[1-9][0-9]*$/) { print n ": frame " $1 " column " k ": " $k; exit 1 }
                                  if ($5 != "" || $6 != "" || $12 != "") { print n ": frame " $1 ": a counted run wrote times"; exit 1 } }' "$d/1.csv" ||
    fail "$name: bad counts"
  # The timed run finds the same pairs (aabb, gjk, world aabb, world).
  "$cpucd" "$1" "$2" --repeat 1 --frames "$d/t.csv" -q
  cmp -s <(cut -d, -f1-4,10,11 "$d/1.csv") <(cut -d, -f1-4,10,11 "$d/t.csv") || fail "$name: counted and timed pairs differ"
done
grep -q '^1,2,1,1,,' "$d/1.csv" || fail "game.geo: the box should reach the tetrahedron in frame 1"
# --frame-step K: frames 0, K, 2K, ... only (fig8's sample of a large game),
# frame 0 counted as in the whole run.
"$cpucd" --geometry "$d/game.geo" --count-instructions --frame-step 2 --frames "$d/step.csv" -q
[ "$(cut -d, -f1 "$d/step.csv" | tr '\n' ' ')" = "frame 0 2 " ] ||
  fail "--frame-step 2: frames $(cut -d, -f1 "$d/step.csv" | tr '\n' ' ')"
[ "$(grep '^0,' "$d/step.csv")" = "$(grep '^0,' "$d/1.csv")" ] || fail "--frame-step 2: frame 0 counted otherwise"

# A scene and its geometry file (format 1, the same numbers) are one input: one count.
"$cpucd" --scene "$src/testbench/eval/mini/mini.toml" --repeat 1 -q --write-geometry "$d/mini.geo"
"$cpucd" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --frames "$d/s.csv" -q
"$cpucd" --geometry "$d/mini.geo" --count-instructions --frames "$d/g.csv" -q
cmp -s <(counts "$d/s.csv") <(counts "$d/g.csv") || fail "mini: the scene and its geometry file count differently"

# Refusals: one line, exit 2, no output left.
refuse() {
  local what=$1; shift
  set +e
  msg=$("$cpucd" "$@" 2>&1 >/dev/null)
  rc=$?
  set -e
  [ "$rc" -eq 2 ] || fail "$what: exit $rc, expected 2"
  [ "$(printf '%s\n' "$msg" | wc -l)" -eq 1 ] || fail "$what: more than one line: $msg"
  [[ $msg == "rbcd-cpucd: "* ]] || fail "$what: message '$msg'"
  [ ! -e "$d/out.csv" ] && [ ! -e "$d/f.csv" ] || fail "$what: output left behind"
}
refuse "--pairs with counting" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --frames "$d/f.csv" --pairs "$d/out.csv"
refuse "--repeat with counting" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --repeat 3 --frames "$d/f.csv"
refuse "--frame-step 0" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --frame-step 0 --frames "$d/f.csv"
printf 'rbcd-geometry 2\npart 1 3 1\nv 0 0 0\nv 1 0 0\nv 0 1 x\n' > "$d/bad.geo"
refuse "bad geometry under counting" --geometry "$d/bad.geo" --count-instructions --frames "$d/f.csv"
[[ $msg == "rbcd-cpucd: $d/bad.geo:5: "* ]] || fail "bad geometry: '$msg' does not name the line"
# Without valgrind: a message naming the package, before anything is read or written.
set +e
msg=$(PATH=/nonexistent "$cpucd" --scene "$src/testbench/eval/mini/mini.toml" --count-instructions --frames "$d/f.csv" 2>&1)
rc=$?
set -e
[ "$rc" -eq 2 ] && [[ $msg == "rbcd-cpucd: --count-instructions: valgrind not found"* ]] && [ ! -e "$d/f.csv" ] ||
  fail "without valgrind: exit $rc, '$msg'"
# SIGTERM to a counting run (to rbcd-cpucd, which forwards it to valgrind's
# child): no output, no temporary directory left. Sent once the output's
# temporary exists, so the run is under way; the input (the mini scene's last
# frame held for 4000 frames) is long enough to still be.
mkdir -p "$d/tmp" "$d/sig"
awk '/^frame 3$/ { last = 1 } { print } last && /^m / { held = held $0 "\n" }
     END { for (f = 4; f < 4000; ++f) printf "frame %d\n%s", f, held }' "$d/mini.geo" > "$d/long.geo"
TMPDIR=$d/tmp "$cpucd" --geometry "$d/long.geo" --count-instructions --frames "$d/sig/f.csv" -q 2>/dev/null &
pid=$!
until compgen -G "$d/sig/.f.csv.*" >/dev/null; do
  kill -0 "$pid" 2>/dev/null || fail "SIGTERM: the run ended before its output was opened"
  sleep 0.2
done
kill -TERM "$pid"
set +e
wait "$pid"
rc=$?
set -e
[ "$rc" -ne 0 ] || fail "SIGTERM: exit 0"
[ -z "$(ls -A "$d/sig")" ] || fail "SIGTERM: left $(ls -A "$d/sig")"
[ -z "$(ls -A "$d/tmp")" ] || fail "SIGTERM: left $(ls -A "$d/tmp") in TMPDIR"
echo "count_test.sh: ok"
