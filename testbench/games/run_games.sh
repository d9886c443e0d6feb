#!/usr/bin/env bash
# CTest entries for the captured game-frame suite (docs/games.md):
#   run_games.sh SOURCE_DIR BUILD_DIR check          the committed entries match their checksums
#   run_games.sh SOURCE_DIR BUILD_DIR capture        scripts/capture-game.sh on a few frames of
#                                                    OpenArena (skipped without the game)
#   run_games.sh SOURCE_DIR BUILD_DIR capture_stk    the same on SuperTuxKart
#   run_games.sh SOURCE_DIR BUILD_DIR TARGET         scripts/reproduce.sh TARGET on one entry cut
#                                                    to a few frames (workloads table3 fig9 fig8 accuracy)
# Exit 77 (skipped, saying why) when what the case needs is missing.
set -euo pipefail
src=$1 build=$2 what=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "run_games.sh $what: $*" >&2; exit 1; }
skip() { echo "skipped: $*"; exit 77; }
export RBCD_GL_RASTER=$build/bin/rbcd-gl-raster
/usr/bin/python3 -c "import numpy" 2>/dev/null || skip "numpy is missing (scripts/setup.sh --gl)"
[ -x "$RBCD_GL_RASTER" ] || skip "rbcd-gl-raster is not built"
entry=$src/workloads/games/openarena-oa_dm1

case $what in
  check)
    /usr/bin/python3 "$src/scripts/game-suite" check >"$tmp/out" || fail "$(cat "$tmp/out")"
    n=$(ls -d "$src"/workloads/games/*/capture.toml | wc -l)
    [ "$(grep -c 'matches capture.toml' "$tmp/out")" = "$n" ] || fail "not every entry was checked"
    [ "$n" -ge 4 ] || fail "$n entries: the suite has three OpenArena maps and a Neverball level"
    # A changed byte is caught, naming the file.
    cp -r "$entry" "$tmp/e"
    printf 'x' | dd of="$tmp/e/calls.xz" bs=1 seek=1000 conv=notrunc 2>/dev/null
    set +e; /usr/bin/python3 "$src/scripts/game-suite" check "$tmp/e" 2>"$tmp/err"; rc=$?; set -e
    [ $rc = 2 ] || fail "a changed capture: exit $rc, not 2 (bad input)"
    grep -q "calls.xz: checksum" "$tmp/err" || fail "message: $(cat "$tmp/err")"
    # A malformed description: one line naming the file and the key, exit 2.
    sed -i 's/^frames = .*/frames = "many"/' "$tmp/e/capture.toml"
    set +e; /usr/bin/python3 "$src/scripts/game-suite" check "$tmp/e" 2>"$tmp/err"; rc=$?; set -e
    [ $rc = 2 ] && [ "$(wc -l <"$tmp/err")" = 1 ] && grep -q "capture.toml: frames" "$tmp/err" ||
      fail "malformed capture.toml: exit $rc, $(cat "$tmp/err")"
    ;;
  cli)
    # Bad arguments to both commands: exit 2, one line naming what is wrong, nothing written.
    expect2() {   # WORD COMMAND...: exit 2, one line on stderr containing WORD
      local word=$1 rc; shift
      set +e; "$@" >"$tmp/o" 2>"$tmp/err"; rc=$?; set -e
      [ $rc = 2 ] || fail "$* exited $rc, not 2: $(head -c 300 "$tmp/err")"
      [ "$(wc -l <"$tmp/err")" = 1 ] || fail "$*: not one line: $(cat "$tmp/err")"
      grep -q -- "$word" "$tmp/err" || fail "$*: message lacks '$word': $(cat "$tmp/err")"
    }
    cg=$src/scripts/capture-game.sh gs=$src/scripts/game-suite
    expect2 "unknown game" "$cg" quake oa_dm1 3 "$tmp/n1"
    expect2 "FRAMES" "$cg" openarena oa_dm1 many "$tmp/n2"
    expect2 "FRAMES" "$cg" openarena oa_dm1 0 "$tmp/n3"
    expect2 "bots" "$cg" openarena oa_dm1 3 "$tmp/n4" --bots 0
    expect2 "skip" "$cg" openarena oa_dm1 3 "$tmp/n5" --skip -1
    expect2 "unknown option" "$cg" openarena oa_dm1 3 "$tmp/n6" --fast
    expect2 "four arguments" "$cg" openarena oa_dm1 3
    mkdir "$tmp/exists"; touch "$tmp/exists/keep"
    expect2 "exists" "$cg" openarena oa_dm1 3 "$tmp/exists"
    [ -f "$tmp/exists/keep" ] || fail "an existing OUT_DIR was touched"
    expect2 "not a map name" "$cg" openarena "../x" 3 "$tmp/n7"
    expect2 "not a file" "$cg" neverball /nonexistent.nbr 3 "$tmp/n8"
    expect2 "not a file" "$cg" openarena oa_dm1 3 "$tmp/n9" --from-trace /nonexistent.trace
    expect2 "karts" "$cg" supertuxkart lighthouse 3 "$tmp/n9" --karts 5
    expect2 "not a track name" "$cg" supertuxkart "Light House" 3 "$tmp/n9"
    if [ -d /usr/share/games/supertuxkart/data/tracks ]; then
      expect2 "race tracks" "$cg" supertuxkart soccer_field 3 "$tmp/n9"
    fi
    if [ -d /usr/share/games/openarena/baseoa ]; then
      expect2 "not one of OpenArena's maps" "$cg" openarena nosuchmap 3 "$tmp/n10"
    fi
    # An output folder that cannot take the entry is said before any game runs.
    expect2 "does not exist" "$cg" openarena oa_dm1 3 "$tmp/no/such/n11"
    chmod 555 "$tmp/exists"
    if [ "$(id -u)" != 0 ]; then expect2 "cannot create the entry" "$cg" openarena oa_dm1 3 "$tmp/exists/n12"; fi
    chmod 755 "$tmp/exists"
    for n in n1 n2 n3 n4 n5 n6 n7 n8 n9 n10; do [ ! -e "$tmp/$n" ] || fail "$n was created"; done
    touch "$tmp/a-file"
    expect2 "not a directory" /usr/bin/python3 "$gs" expand -o "$tmp/a-file" "$entry"
    expect2 "not a game-suite entry" /usr/bin/python3 "$gs" check "$tmp/nonexistent"
    expect2 "capture.toml" /usr/bin/python3 "$gs" check "$tmp/exists"
    expect2 "jobs" /usr/bin/python3 "$gs" expand -o "$tmp/x1" -j 0 "$entry"
    expect2 "frames" /usr/bin/python3 "$gs" expand -o "$tmp/x2" --frames 0 "$entry"
    expect2 "out" /usr/bin/python3 "$gs" expand "$entry"
    ;;
  capture)
    for t in /usr/games/openarena xvfb-run apitrace; do
      command -v "$t" >/dev/null || skip "$t is missing (scripts/setup.sh --gl --games installs the capture tools and games)"
    done
    # The warm-up is cut short: the settings are what is checked, not the bots.
    "$src/scripts/capture-game.sh" openarena oa_dm1 3 "$tmp/e" --skip 20 >"$tmp/log" 2>&1 ||
      fail "capture failed: $(tail -5 "$tmp/log")"
    t=$tmp/e/capture.toml
    for k in 'game = "openarena"' 'map = "oa_dm1"' 'frames = 3' 'first_frame = 20' 'screen = \[800, 480\]' \
             'fixed_time_ms = 33' 'set fixedtime 33' 'follow 1' '"cl_renderer", "opengl1"' '"cg_draw2D", "0"' \
             '"cg_drawGun", "0"' '"cg_thirdPerson", "1"' '"r_customwidth", "800"'; do
      grep -q "$k" "$t" || fail "capture.toml lacks $k"
    done
    [ "$(wc -l <"$tmp/e/summary.jsonl")" = 3 ] || fail "not 3 frames"
    # The entry regenerates into the recorded checksums.
    /usr/bin/python3 "$src/scripts/game-suite" expand -o "$tmp/x" "$tmp/e" >/dev/null || fail "expand failed"
    [ -s "$tmp/x/e.rbt.zst" ] && [ -s "$tmp/x/e.geo" ] || fail "no trace or geometry"
    ;;
  capture_stk)
    # Under ASan the converter's rasterizer takes minutes over the loading
    # frames; the release suite runs this case, the sanitizers see the same
    # code on the other GL cases.
    ! grep -q '^RBCD_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null ||
      skip "sanitizer build: the SuperTuxKart capture runs in the release suite"
    for t in /usr/games/supertuxkart xvfb-run apitrace; do
      command -v "$t" >/dev/null || skip "$t is missing (scripts/setup.sh --gl --supertuxkart installs the capture tools and the game)"
    done
    "$src/scripts/capture-game.sh" supertuxkart lighthouse 3 "$tmp/e" --karts 2 --skip 1 >"$tmp/log" 2>&1 ||
      fail "capture failed: $(tail -5 "$tmp/log")"
    t=$tmp/e/capture.toml
    start=$(sed -n 's/^race_start = \([0-9]*\).*/\1/p' "$t")
    [ -n "$start" ] && [ "$start" -gt 0 ] || fail "capture.toml has no race_start"
    grep -q "^first_frame = $((start + 1)) " "$t" || fail "first_frame is not race_start + --skip"
    for k in 'game = "supertuxkart"' 'map = "lighthouse"' 'frames = 3' 'karts = 2' 'screen = \[800, 480\]' \
             '"--race-now"' '"--kart=tux"' '"--ai=kiki"' '"--disable-dynamic-lights"' 'game_config = "game-config.xml"'; do
      grep -q -- "$k" "$t" || fail "capture.toml lacks $k"
    done
    grep -q '<stkconfig' "$tmp/e/game-config.xml" || fail "the game's configuration is not kept"
    [ "$(wc -l <"$tmp/e/summary.jsonl")" = 3 ] || fail "not 3 frames"
    # The two karts are found by the shipped rules in every frame.
    /usr/bin/python3 - "$tmp/e/summary.jsonl" <<'EOF' || fail "the karts are not all found"
import json, sys
for line in open(sys.argv[1]):
    ids = set(json.loads(line)["objects"])
    assert {1, 2} <= ids, ids
EOF
    /usr/bin/python3 "$src/scripts/game-suite" expand -o "$tmp/x" "$tmp/e" >/dev/null || fail "expand failed"
    [ -s "$tmp/x/e.rbt.zst" ] && [ -s "$tmp/x/e.geo" ] || fail "no trace or geometry"
    ;;
  workloads|table3|fig9|fig8|accuracy)
    case $what in
      workloads|fig8|accuracy) [ -x "$build/bin/rbcd-cpucd" ] || skip "rbcd-cpucd not built (scripts/setup.sh --eval)" ;;
    esac
    if [ "$what" = fig8 ]; then
      # fig8 counts instructions under valgrind, which cannot run ASan's binaries.
      command -v valgrind >/dev/null || skip "valgrind missing (scripts/setup.sh --eval): fig8 counts under it"
      ! grep -q '^RBCD_SANITIZE:BOOL=ON' "$build/CMakeCache.txt" 2>/dev/null ||
        skip "sanitizer build: valgrind cannot run it, fig8 skipped"
    fi
    /usr/bin/python3 "$src/scripts/game-suite" expand -o "$tmp/in" --frames 3 "$entry" >/dev/null ||
      fail "expand failed"
    "$src/scripts/reproduce.sh" --no-build --build "$build" --workloads "$tmp/in" --out "$tmp/out" \
      --repeat 1 --jobs 1 "$what" >"$tmp/log" 2>&1 || fail "reproduce.sh failed: $(tail -5 "$tmp/log")"
    for f in "$what.csv" "$what.md"; do [ -s "$tmp/out/$f" ] || fail "$f missing or empty"; done
    name=$(basename "$entry")
    grep -q "^$name," "$tmp/out/$what.csv" || grep -q ",$name," "$tmp/out/$what.csv" ||
      fail "$what.csv has no row for $name"
    if [ "$what" = workloads ]; then
      # What collides, by object class: a row per class pair (or "(none)") of this capture.
      grep -qE "^$name,(player|item/projectile|\(none\))" "$tmp/out/pairs.csv" ||
        fail "pairs.csv has no row for $name: $(cat "$tmp/out/pairs.csv" 2>/dev/null)"
    fi
    ;;
  *) fail "unknown case" ;;
esac
echo "run_games.sh $what: ok"
