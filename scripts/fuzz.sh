#!/usr/bin/env bash
# Builds one libFuzzer target (clang++-14, ASan + UBSan, toml++ header-only)
# and runs it for SECONDS (default 60).
#   scripts/fuzz.sh trace|config|scene|mesh|geometry|merge [SECONDS]
# Seeds: vectors/ (trace), sc_main/configs/ (config), the scene examples
# (scene), a few assimp test models (mesh), a geometry file (geometry:
# rbcd-cpucd's reader), a stats document and a collisions file (merge:
# rbcd-merge's inputs), and every committed finding in
# testbench/fuzz/TARGET/. The growing corpus stays in build-fuzz/corpus/TARGET;
# a crash is written to build-fuzz/findings/TARGET/ and the script exits 1.
# Turn each finding into a regression: fix it, then copy the file into
# testbench/fuzz/TARGET/ (the normal test suite replays that directory).
set -euo pipefail
cd "$(dirname "$0")/.."
target=${1:?usage: scripts/fuzz.sh trace|config|scene|mesh|geometry|merge|draw_stream [SECONDS]}
seconds=${2:-60}
case "$target" in trace|config|scene|mesh|geometry|merge|draw_stream) ;; *) echo "fuzz.sh: unknown target '$target'" >&2; exit 2 ;; esac
# The geometry target reads through rbcd-cpucd's library: Bullet and FCL (--eval).
if [ "$target" = geometry ]; then ./scripts/setup.sh --fuzz --eval; else ./scripts/setup.sh --fuzz; fi
command -v clang++-14 >/dev/null || { echo "fuzz.sh: clang++-14 is missing (scripts/setup.sh --fuzz installs it)" >&2; exit 2; }

dir=build-fuzz
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
if [ ! -f "$dir/CMakeCache.txt" ]; then
  cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER=clang-14 \
    -DCMAKE_CXX_COMPILER=clang++-14 -DRBCD_FUZZ=ON -DRBCD_BUILD_TESTS=OFF "${launcher[@]}" \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG" >/dev/null
fi
cmake --build "$dir" --target "fuzz_$target" >/dev/null

# Seeds carry the target's mode byte where it has one (see fuzz/fuzz_*.cpp).
seeds="$dir/seeds/$target"
rm -rf "$seeds"
mkdir -p "$seeds" "$dir/corpus/$target" "$dir/findings/$target"
add() { # add MODE_BYTE_OCTAL|"" FILE...
  local mode=$1; shift
  for f in "$@"; do
    [ -f "$f" ] || continue
    local out="$seeds/$(echo "$f" | tr '/' '_')${mode:+-$mode}"
    if [ -n "$mode" ]; then { printf "\\$mode"; cat "$f"; } >"$out"; else cat "$f" >"$out"; fi
  done
}
case "$target" in
  trace) add 007 vectors/*.rbt; add 207 vectors/*.rbt; add 000 vectors/*.rbt; add 077 vectors/*.rbt ;;
  config) add 000 sc_main/configs/*.toml vectors/*.toml ;;
  scene) add "" scene/default_scene.toml testbench/golden/determinism/scene.toml ;;
  mesh) add 000 /usr/share/assimp/models/OBJ/box.obj; add 001 /usr/share/assimp/models/PLY/cube.ply
        add 002 /usr/share/assimp/models/STL/triangle.stl /usr/share/assimp/models/STL/Spider_ascii.stl ;;
  geometry|merge) ;;   # their seeds are testbench/fuzz/TARGET/ (below)
esac
cp testbench/fuzz/"$target"/* "$seeds"/ 2>/dev/null || true

export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$(realpath fuzz/lsan-suppressions.txt)"
# Mesh paths in scenes resolve from the working directory: an empty one.
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
bin=$(realpath "$dir/bin/fuzz_$target")
corpus=$(realpath "$dir/corpus/$target")
findings=$(realpath "$dir/findings/$target")
seeds=$(realpath "$seeds")
before=$(find "$findings" -type f | wc -l)
status=0
(cd "$work" && "$bin" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 -max_len=65536 \
   -print_final_stats=1 -artifact_prefix="$findings/" "$corpus" "$seeds") || status=$?
# A child process (the mesh target's loader) can write a finding, e.g. on an
# allocation above the limit, without stopping the fuzzer: it counts too.
if [ "$status" -eq 0 ] && [ "$(find "$findings" -type f | wc -l)" -gt "$before" ]; then
  echo "fuzz.sh: new finding in $findings/ (written by a child process)" >&2
  status=1
fi
exit "$status"
