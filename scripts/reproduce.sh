#!/usr/bin/env bash
# One command per figure of the paper's evaluation (docs/results.md):
#
#   scripts/reproduce.sh [options] TARGET...
#     TARGET: workloads | table3 | fig8 | fig9 | accuracy | all
#   --out DIR          results directory (default results/, gitignored)
#   --workloads DIR    inputs to run (default workloads/): every scene (*.toml) in it, and
#                      every converted game capture (NAME.rbt.zst or .rbt.gz with NAME.geo and
#                      NAME.summary.jsonl beside it, as scripts/game-suite writes them)
#   --games [ENTRY]    the captured game-frame suite instead (docs/games.md): every entry
#                      of workloads/games/ (or the entries given, comma-separated),
#                      expanded by scripts/game-suite into OUT/inputs/ and run as above
#   --build DIR        build directory (default build/); built first unless --no-build
#   --no-build         use the binaries as they are
#   --repeat N         rbcd-cpucd's timed repeats per frame (default 5)
#   --jobs N           rbcd-sim runs at once (default: number of cores)
#   --update-docs      copy the tables into docs/results.md and docs/workloads.md
#                      and the scene pictures into docs/img/workloads/ (with --games:
#                      the games-NAME blocks of docs/results.md, docs/games.md and docs/workloads.md)
#
# Every run starts from scratch: OUT/runs/ and OUT/sweep/ are emptied first,
# then each target runs what it needs: the sweeps workloads/sweeps/table3.toml
# (table3, accuracy) and fig9.toml (fig9, fig8, workloads) by scripts/rbcd-sweep
# into OUT/sweep/, the accuracy's other rbcd-sim runs, rbcd-cpucd once per
# input for the ground truth (timed alone, the host figures), and for fig8 once
# more under callgrind (--count-instructions: the counted CPU side, $jobs at a
# time; a game whose geometry passes 128 MiB, every 3rd frame: docs/results.md,
# Figure 8); then python/rbcd/evaluate.py writes OUT/TARGET.csv, .png and .md. Targets
# needing rbcd-cpucd are skipped with a message when it was not built (Bullet
# or FCL missing); fig8 also needs valgrind.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
# The evaluation's arithmetic is the package's rbcd.evaluate (python/rbcd/evaluate.py).
export PYTHONPATH="$root/python${PYTHONPATH:+:$PYTHONPATH}"
out=results workloads=$root/workloads build=$root/build repeat=5 jobs=$(nproc) do_build=1 update_docs=0
targets=()
usage() { sed -n '2,30p' "$0" | sed 's/^# \{0,1\}//'; }
games=0 game_entries=()
while (($#)); do
  case $1 in
    --out) out=$2; shift 2 ;;
    --workloads) workloads=$2; shift 2 ;;
    --build) build=$2; shift 2 ;;
    --no-build) do_build=0; shift ;;
    --repeat) repeat=$2; shift 2 ;;
    --jobs) jobs=$2; shift 2 ;;
    --update-docs) update_docs=1; shift ;;
    --games) games=1
             if [ $# -ge 2 ] && [[ $2 != -* ]] && [[ ! $2 =~ ^(workloads|table3|fig8|fig9|accuracy|all)$ ]]; then
               IFS=, read -r -a game_entries <<<"$2"; shift
             fi
             shift ;;
    -h|--help) usage; exit 0 ;;
    workloads|table3|fig8|fig9|accuracy) targets+=("$1"); shift ;;
    all) targets+=(workloads table3 fig9 fig8 accuracy); shift ;;
    *) echo "reproduce.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
((${#targets[@]})) || { usage >&2; exit 2; }
[[ $repeat =~ ^[1-9][0-9]*$ ]] || { echo "reproduce.sh: --repeat: '$repeat' is not a positive integer" >&2; exit 2; }
[[ $jobs =~ ^[1-9][0-9]*$ ]] || { echo "reproduce.sh: --jobs: '$jobs' is not a positive integer" >&2; exit 2; }
shopt -s nullglob
# A converted capture's path without .rbt.zst or .rbt.gz: where its NAME.geo,
# NAME.summary.jsonl and NAME.capture lie.
trace_base() { local p=${1%.rbt.zst}; echo "${p%.rbt.gz}"; }
if ((games)); then
  # The game suite's traces and geometry, regenerated from the committed
  # reduced captures and checked against their recorded checksums.
  mkdir -p "$out"
  # An entry named by itself is the suite's (workloads/games/NAME).
  for i in "${!game_entries[@]}"; do
    e=${game_entries[$i]}
    [ -d "$e" ] || [ ! -d "$root/workloads/games/$e" ] || game_entries[$i]=$root/workloads/games/$e
  done
  echo "reproduce.sh: scripts/game-suite expand -o $out/inputs ${game_entries[*]}" >&2
  /usr/bin/python3 "$root/scripts/game-suite" expand -o "$out/inputs" -j "$jobs" "${game_entries[@]}" >&2 ||
    { echo "reproduce.sh: the game suite could not be expanded" >&2; exit 1; }
  workloads=$out/inputs
  for f in "$workloads"/*.rbt.zst "$workloads"/*.rbt.gz; do
    keep=0 base=$(trace_base "$f")
    if ((${#game_entries[@]})); then
      for e in "${game_entries[@]}"; do [ "$(basename "${e%/}")" = "$(basename "$base")" ] && keep=1; done
    else
      [ -f "$root/workloads/games/$(basename "$base")/capture.toml" ] && keep=1
    fi
    ((keep)) || rm -f "$f" "$base".{geo,summary.jsonl,capture}   # an entry not asked for this time
  done
fi
scenes=("$workloads"/*.toml "$workloads"/*.rbt.zst "$workloads"/*.rbt.gz)
((${#scenes[@]})) || { echo "reproduce.sh: $workloads: no scene (*.toml) and no converted capture (*.rbt.zst, *.rbt.gz)" >&2; exit 2; }
# A scene's name is its file name without .toml; a capture's without .rbt.zst or .rbt.gz.
input_name() { local b; b=$(basename "$1"); b=${b%.toml}; basename "$(trace_base "$b")"; }
is_trace() { [[ $1 == *.rbt.zst || $1 == *.rbt.gz ]]; }
for s in "${scenes[@]}"; do
  if is_trace "$s" && [ ! -f "$(trace_base "$s").geo" ]; then
    echo "reproduce.sh: $s: no geometry $(trace_base "$s").geo beside the trace (scripts/game-suite writes both)" >&2; exit 2
  fi
done

if ((do_build)); then
  if [ ! -f "$build/CMakeCache.txt" ]; then
    cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  fi
  cmake --build "$build" --target rbcd-sim rbcd-config-check >/dev/null
  cmake --build "$build" --target rbcd-cpucd >/dev/null 2>&1 || true   # absent without Bullet/FCL
fi
sim=$build/bin/rbcd-sim cpucd=$build/bin/rbcd-cpucd
[ -x "$sim" ] || { echo "reproduce.sh: $sim not built" >&2; exit 2; }
have_cpucd=0
[ -x "$cpucd" ] && have_cpucd=1

mkdir -p "$out"
rm -rf "$out/runs" "$out/sweep"
mkdir -p "$out/runs"
: > "$out/runs/scenes.txt"
for s in "${scenes[@]}"; do
  echo "$(input_name "$s") $s" >> "$out/runs/scenes.txt"
  mkdir -p "$out/runs/$(input_name "$s")"
done

# Object ids above 127 need more than the default 7 id bits (docs/workloads.md).
declare -A idb
for s in "${scenes[@]}"; do idb[$s]=$(/usr/bin/python3 -m rbcd.evaluate --id-bits "$s"); done

# The accuracy's runs that are no figure's sweep, on top of sc_main/configs/paper.toml
# (the paper's Table 1); its M = 4, 8, 16 runs are Table 3's sweep.
declare -A cfg=(
  [m8t2]="tester.stack_depth=2 tester.output=tile"
  [m64]="zeb.list_length=64 tester.output=tile" [m64t2]="zeb.list_length=64 tester.stack_depth=2 tester.output=tile"
  [m64t64]="zeb.list_length=64 tester.stack_depth=64 tester.output=tile")
needed_cfgs=() needed_sweeps=() need_cpucd=0 need_images=0 need_count=0
for t in "${targets[@]}"; do
  case $t in
    workloads) needed_sweeps+=(fig9); need_cpucd=1; need_images=1 ;;
    table3) needed_sweeps+=(table3) ;;
    fig9) needed_sweeps+=(fig9) ;;
    fig8) needed_sweeps+=(fig9); need_cpucd=1 need_count=1 ;;
    accuracy) needed_sweeps+=(table3); needed_cfgs+=(m8t2 m64 m64t2 m64t64); need_cpucd=1 ;;
  esac
done
if ((need_cpucd && !have_cpucd)); then
  echo "reproduce.sh: rbcd-cpucd not built (needs libbullet-dev and libfcl-dev: scripts/setup.sh --eval): skipping workloads, fig8, accuracy" >&2
  kept=()
  for t in "${targets[@]}"; do [[ $t == workloads || $t == fig8 || $t == accuracy ]] || kept+=("$t"); done
  targets=("${kept[@]}")
  need_cpucd=0 need_images=0 needed_cfgs=() needed_sweeps=()
  for t in "${targets[@]}"; do needed_sweeps+=("$t"); done   # what is left: table3, fig9
fi
# fig8's CPU side is counted under valgrind (docs/results.md, "CPU model").
if ((need_count)) && [[ " ${targets[*]} " == *" fig8 "* ]] && ! command -v valgrind >/dev/null; then
  echo "reproduce.sh: valgrind not found (Debian's valgrind: scripts/setup.sh --eval): skipping fig8" >&2
  kept=()
  for t in "${targets[@]}"; do [[ $t == fig8 ]] || kept+=("$t"); done
  targets=("${kept[@]}")
  need_count=0
  ((${#targets[@]})) || exit 0
fi
mapfile -t needed_cfgs < <(printf '%s\n' "${needed_cfgs[@]}" | sed '/^$/d' | sort -u)
# table3 first: fig9 then finds its M = 8 runs done (with the collisions files table3 keeps).
mapfile -t needed_sweeps < <(printf '%s\n' "${needed_sweeps[@]}" | sed '/^$/d' | sort -ru)

# ---- The figures that are sweeps: workloads/sweeps/NAME.toml by scripts/rbcd-sweep's local
# runner ($jobs workers), all into OUT/sweep/ so that a run two sweeps share (a run's id is
# its configuration and input) runs once; each sweep's results.csv is kept as OUT/sweep/NAME.csv.
# Over another --workloads folder, the same sweep with that folder's scenes (and the id bits
# they need): OUT/NAME.sweep.toml.
same_dir() { [ "$(cd "$1" && pwd -P)" = "$(cd "$2" && pwd -P)" ]; }
for sw in "${needed_sweeps[@]}"; do
  file=$root/workloads/sweeps/$sw.toml
  if ! same_dir "$workloads" "$root/workloads"; then
    /usr/bin/python3 -m rbcd.evaluate --sweep-file "$file" "$workloads" "$out/$sw.sweep.toml"
    file=$out/$sw.sweep.toml
  fi
  echo "reproduce.sh: sweep $sw: scripts/rbcd-sweep run $file -o $out/sweep" >&2
  /usr/bin/python3 "$root/scripts/rbcd-sweep" run "$file" -o "$out/sweep" -j "$jobs" --rbcd-sim "$sim" || {
    echo "reproduce.sh: sweep $sw failed (its failed runs: $out/sweep/results.csv)" >&2
    exit 1
  }
  cp "$out/sweep/results.csv" "$out/sweep/$sw.csv"
done

# ---- rbcd-sim runs, $jobs at a time, with a progress line.
jobs_list=()
for s in "${scenes[@]}"; do
  for c in "${needed_cfgs[@]}"; do jobs_list+=("$s|$c"); done
done
n=${#jobs_list[@]} k=0 failed=0
progress() { printf '\rreproduce.sh: %s %d/%d %-40s' "$1" "$2" "$3" "$4" >&2; }
run_sim() {
  local s=${1%%|*} c=${1##*|} name d sets=() input=(--scene "$s")
  name=$(input_name "$s")
  is_trace "$s" && input=(--trace "$s")
  d=$out/runs/$name
  mkdir -p "$d"
  for kv in ${cfg[$c]}; do sets+=(--set "$kv"); done
  "$sim" --config "$root/sc_main/configs/paper.toml" --set "zeb.id_bits=${idb[$s]}" "${sets[@]}" \
    "${input[@]}" --stats "$d/$c.json" --collisions "$d/$c.col" -q 2> "$d/$c.err" ||
    { echo; echo "reproduce.sh: rbcd-sim failed on $name ($c):" >&2; cat "$d/$c.err" >&2; return 1; }
}
for j in "${jobs_list[@]}"; do
  while (($(jobs -rp | wc -l) >= jobs)); do wait -n || failed=1; done
  k=$((k + 1))
  progress "rbcd-sim" "$k" "$n" "$(input_name "${j%%|*}") ${j##*|}"
  run_sim "$j" &
done
while (($(jobs -rp | wc -l))); do wait -n || failed=1; done
((n)) && echo >&2
((failed)) && exit 1

# ---- Pictures: one frame of each scene (the middle one).
if ((need_images)); then
  k=0
  for s in "${scenes[@]}"; do
    name=$(input_name "$s") k=$((k + 1))
    # A game capture's picture is the converter's (docs/games.md), not rbcd-sim's.
    is_trace "$s" && continue
    progress "images" "$k" "${#scenes[@]}" "$name"
    rm -rf "$out/runs/$name/images"
    "$sim" --config "$root/sc_main/configs/paper.toml" --set "zeb.id_bits=${idb[$s]}" --scene "$s" \
      --images "$out/runs/$name/images" -q
    frames=$(ls "$out/runs/$name/images" | wc -l)
    cp "$out/runs/$name/images/$(printf 'frame_%05d.png' $((frames / 2)))" "$out/$name.png"
    rm -rf "$out/runs/$name/images"
  done
  echo >&2
fi

# A game capture's geometry (skinned karts: a few hundred MB for 300 frames)
# may pass rbcd-cpucd's default bound on a file's size, which is there for
# files of unknown origin; these were regenerated and checked here.
geometry_limit() {
  local g size
  g=$(trace_base "$1").geo
  size=$(stat -c %s "$g" 2>/dev/null || echo 0)
  ((size < 268435456)) || echo "--max-geometry-bytes $((size + 1))"
}
# fig8 counts a game whose geometry passes 128 MiB (SuperTuxKart's skinned
# karts: 263 to 357 MB for 300 frames) on frames 0, 3, 6, ... only: under
# valgrind each frame's hulls and trees take a third of a second to build, a
# quarter of an hour for three such entries counted whole. The same frames on
# every machine; fig8.md names the sampled entries (docs/results.md, Figure 8).
count_sample() {
  local g size
  g=$(trace_base "$1").geo
  size=$(stat -c %s "$g" 2>/dev/null || echo 0)
  ((size <= 134217728)) || echo "--frame-step 3"
}

# ---- rbcd-cpucd, one scene at a time and nothing else running: it is timed.
if ((need_cpucd)); then
  k=0
  for s in "${scenes[@]}"; do
    name=$(input_name "$s") k=$((k + 1))
    progress "rbcd-cpucd" "$k" "${#scenes[@]}" "$name"
    input=(--scene "$s")
    is_trace "$s" && input=(--geometry "$(trace_base "$s").geo" --trace "$s" $(geometry_limit "$s"))
    "$cpucd" "${input[@]}" --pixels --repeat "$repeat" -q --pairs "$out/runs/$name/cpucd_pairs.csv" \
      --frames "$out/runs/$name/cpucd_frames.csv" --depth-histogram "$out/runs/$name/depth_hist.csv"
  done
  echo >&2
fi

# ---- fig8: each scene's detection counted in instructions (rbcd-cpucd
# --count-instructions, under valgrind: loading about 8 times slower than
# timed, the detection about 50 times; a count does not depend on what else
# runs, so $jobs at a time, the largest input first: a SuperTuxKart entry's
# count takes minutes, and started last it would run alone). cpucd_count
# NAME INPUT-OPTIONS... writes OUT/runs/NAME/cpucd_counts.csv.
cpucd_count() {
  local name=$1; shift
  "$cpucd" "$@" --count-instructions -q --frames "$out/runs/$name/cpucd_counts.csv" 2> "$out/runs/$name/count.err" ||
    { echo; echo "reproduce.sh: rbcd-cpucd --count-instructions failed on $name:" >&2; cat "$out/runs/$name/count.err" >&2; return 1; }
}
if ((need_count)); then
  k=0 failed=0
  # A trace's size is its geometry's (what the count reads and builds); a scene's, its file's.
  mapfile -t by_size < <(for s in "${scenes[@]}"; do
    f=$s; is_trace "$s" && f=$(trace_base "$s").geo
    printf '%s\t%s\n' "$(stat -c %s "$f")" "$s"
  done | sort -s -k1,1nr | cut -f2-)
  for s in "${by_size[@]}"; do
    while (($(jobs -rp | wc -l) >= jobs)); do wait -n || failed=1; done
    k=$((k + 1))
    name=$(input_name "$s")
    progress "rbcd-cpucd --count-instructions" "$k" "${#scenes[@]}" "$name"
    if is_trace "$s"; then
      cpucd_count "$name" --geometry "$(trace_base "$s").geo" $(geometry_limit "$s") $(count_sample "$s") &
    else
      cpucd_count "$name" --scene "$s" &
    fi
  done
  while (($(jobs -rp | wc -l))); do wait -n || failed=1; done
  echo >&2
  ((failed)) && exit 1
fi

/usr/bin/python3 -m rbcd.evaluate --out "$out" "${targets[@]}"
{
  what=${targets[*]}
  ((games)) && what="--games${game_entries[*]:+ $(IFS=,; echo "${game_entries[*]}")} $what"
  echo "Generated by \`scripts/reproduce.sh $what\` on $(date -u +%Y-%m-%d) at commit" \
       "$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$root" diff --quiet HEAD 2>/dev/null || echo ' (with local changes)');" \
       "host: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), $(nproc) cores."
} > "$out/provenance.md"
for t in "${targets[@]}"; do
  for f in "$out/$t.csv" "$out/$t.png"; do [ -f "$f" ] && echo "reproduce.sh: wrote $f"; done
done

if ((update_docs && games)); then
  # The game suite's tables: the games-NAME blocks of docs/results.md and docs/games.md.
  /usr/bin/python3 -m rbcd.evaluate --splice "$out" "$root/docs/results.md" --splice-prefix games-
  /usr/bin/python3 -m rbcd.evaluate --splice "$out" "$root/docs/games.md" --splice-prefix games-
  /usr/bin/python3 -m rbcd.evaluate --splice "$out" "$root/docs/workloads.md" --splice-prefix games-
  mkdir -p "$root/docs/img/games"
  for t in table3 fig9 fig8 accuracy workloads; do
    [[ " ${targets[*]} " == *" $t "* ]] && cp "$out/$t.png" "$root/docs/img/games/$t.png"
  done
  echo "reproduce.sh: updated the game suite's tables in docs/results.md and docs/games.md"
elif ((update_docs)); then
  /usr/bin/python3 -m rbcd.evaluate --splice "$out" "$root/docs/results.md"
  mkdir -p "$root/docs/img/results"
  for t in table3 fig9 fig8 accuracy; do
    [[ " ${targets[*]} " == *" $t "* ]] && cp "$out/$t.png" "$root/docs/img/results/$t.png"
  done
  if [[ " ${targets[*]} " == *" workloads "* ]]; then
    /usr/bin/python3 -m rbcd.evaluate --splice "$out" "$root/docs/workloads.md"
    mkdir -p "$root/docs/img/workloads"
    cp "$out/workloads.png" "$root/docs/img/workloads/depth.png"
    for s in "${scenes[@]}"; do
      name=$(input_name "$s")
      /usr/bin/python3 -m rbcd.evaluate --thumbnail "$out/$name.png" "$root/docs/img/workloads/$name.png"
    done
  fi
  echo "reproduce.sh: updated docs/results.md (and docs/workloads.md with the workloads target)"
fi
