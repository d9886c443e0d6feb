#!/usr/bin/env bash
# Captures a game headless and turns it into a game-suite entry (docs/games.md):
#
#   scripts/capture-game.sh openarena MAP FRAMES OUT_DIR [--bots N] [--skip K] [--keep-trace] [--from-trace T]
#   scripts/capture-game.sh neverball REPLAY.nbr|LEVEL.sol FRAMES OUT_DIR [--skip K] [--keep-trace] [--from-trace T]
#   scripts/capture-game.sh supertuxkart TRACK FRAMES OUT_DIR [--karts N] [--skip K] [--keep-trace] [--from-trace T]
#
# The game runs under Xvfb at 800x480 with Mesa (llvmpipe) and apitrace, from
# a fresh home directory (no user configuration can leak in). The capture is
# converted by scripts/rbcd-gl2rbt with the game's selection rules
# (workloads/games/GAME-select.toml): FRAMES frames after the first K, which
# the warm-up takes (loading, bots joining, the camera reaching its player).
# SuperTuxKart's race starts at once (--race-now): its warm-up is counted in
# the capture, as the frames before the first that draws the race (its
# "Solid Pass" marker), and K more are skipped after it.
# OUT_DIR receives the entry in its committed form: the reduced capture
# (calls.xz: the calls that can change the unit's input, a few per cent of the
# capture), the settings used and the checksums of the converted trace and
# geometry (capture.toml), and the converter's per-frame figures
# (summary.jsonl). scripts/game-suite regenerates the trace and the
# geometry from it. --keep-trace also keeps the capture and both outputs;
# --from-trace T makes the entry from T, a capture this script kept, with the
# same arguments, without running the game again.
#
# Exit 2 with one line on a bad argument (an option given twice, an OUT_DIR
# that is empty, exists, is a symlink or cannot be created, an unusable
# TMPDIR, a MAP whose path is not UTF-8, which capture.toml cannot record:
# said before the game runs), on a capture that holds fewer frames than
# asked for, on an empty --from-trace capture, or on a capture the converter
# refuses; 1 when the game, Xvfb, apitrace or the conversion otherwise
# fails. OUT_DIR is written only at the end, complete.
set -euo pipefail
# SIGINT, SIGTERM or SIGHUP until the entry goes into place: one line,
# exit 130, the work directory and the staged entry removed (the EXIT trap). The converter, run in the same
# process group, says "interrupted" itself and exits 130: not said twice.
# A signal ignored when the script started stays ignored (bash keeps it so).
# The script's short helpers run under quiet (below): bash's "Terminated"
# for a command the signal killed, or a Python helper's KeyboardInterrupt
# traceback, would be a second line.
interrupted() {
  local rc=$?
  trap '' INT TERM HUP
  [ "$rc" -eq 130 ] && [ -n "${converting:-}" ] || echo "capture-game.sh: interrupted" >&2
  if [ -n "${game_pid:-}" ]; then   # the game's run (timeout passes SIGTERM on to it)
    kill -TERM "$game_pid" 2>/dev/null || true
    wait "$game_pid" 2>/dev/null || true
  fi
  exit 130
}
trap interrupted INT TERM HUP
# SIGTERM and SIGHUP ignored, SIGINT at its default: bash acts on a SIGINT
# only once the command it waited for has died of it (a helper that ignored
# it had had the script's Ctrl-C dropped). A Python helper takes SIGINT at
# its default too (held blocked until then: no KeyboardInterrupt traceback).
quiet() { ( trap '' TERM HUP; exec "$@" ); }
quiet_py() {
  local code=$1; shift
  quiet env --block-signal=INT /usr/bin/python3 -c "import signal
signal.signal(signal.SIGINT, signal.SIG_DFL)
signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])
$code" "$@"
}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
# One line, whatever the arguments hold: control characters as \xNN.
oneline() { LC_ALL=C sed 's/[^[:print:]]/?/g' <<<"$1" | tr '\n' '?' | sed 's/?$//'; }
usage() { echo "capture-game.sh: $(oneline "$1") (usage: capture-game.sh openarena|neverball|supertuxkart MAP FRAMES OUT_DIR [--bots N] [--karts N] [--skip K] [--keep-trace] [--from-trace T])" >&2; exit 2; }

[ $# -ge 4 ] || usage "four arguments needed"
game=$1 map=$2 frames=$3 out=$4
shift 4
bots=4 karts=4 skip= keep=no from=
# Every option at most once, as the converter (rbcd-gl2rbt) takes its own:
# a second one had silently replaced the first (--bots 2 --bots 3 captured
# with 3 bots). Refused here, before anything is checked, started or made.
given=" "
once() { [[ "$given" != *" $1 "* ]] || usage "$1 is given twice"; given+="$1 "; }
while [ $# -gt 0 ]; do
  case "$1" in
    --bots) once "$1"; [ $# -ge 2 ] || usage "--bots needs a number"; bots=$2; shift 2 ;;
    --karts) once "$1"; [ $# -ge 2 ] || usage "--karts needs a number"; karts=$2; shift 2 ;;
    --skip) once "$1"; [ $# -ge 2 ] && [ -n "$2" ] || usage "--skip needs a number"; skip=$2; shift 2 ;;
    --keep-trace) once "$1"; keep=yes; shift ;;
    --from-trace) once "$1"; [ $# -ge 2 ] && [ -n "$2" ] || usage "--from-trace needs a capture"; from=$2; shift 2 ;;
    *) usage "unknown option '$1'" ;;
  esac
done
case "$game" in openarena|neverball|supertuxkart) ;; *) usage "unknown game '$game'" ;; esac
[[ "$frames" =~ ^[1-9][0-9]{0,4}$ ]] || usage "FRAMES '$frames' is not a number from 1 to 99999"
[[ "$bots" =~ ^[1-9]$ ]] || usage "--bots '$bots' is not a number from 1 to 9"
# The shipped SuperTuxKart rules know four kart models (below).
[[ "$karts" =~ ^[1-4]$ ]] || usage "--karts '$karts' is not a number from 1 to 4"
# Without leading zeros: bash's arithmetic would read 08 as octal, and the
# value goes into capture.toml as written.
[ -z "$skip" ] || [[ "$skip" =~ ^(0|[1-9][0-9]{0,3})$ ]] || usage "--skip '$skip' is not a number below 10000"
[ -n "$out" ] || usage "OUT_DIR is empty"
[ ! -L "$out" ] || usage "$out is a symlink: the entry is written only into a new directory"
[ ! -e "$out" ] || usage "$out exists: the entry is written only into a new directory"
[ -z "$from" ] || [ -f "$from" ] || usage "--from-trace $from: not a file"
# The capture is read more than once, by its path: a name of an open
# descriptor (/dev/stdin, /proc/self/fd/N), which each read would take on
# from where the last left it, is replaced by the file it names.
[ -z "$from" ] || from=$(readlink -f -- "$from")
# Standard output opened by the shell onto the capture (1<>T) would take
# this script's progress lines: refused, as the converter refuses it.
[ -z "$from" ] || ! [ /dev/stdout -ef "$from" ] || \
  { echo "capture-game.sh: $(oneline "$from"): standard output is the capture: what goes there would be written into it" >&2; exit 2; }
# The given capture is the input: an empty one is said as such (no game ran,
# so there is no game log to show).
empty_capture() { echo "capture-game.sh: $(oneline "$from"): an empty file, not a capture" >&2; exit 2; }
[ -z "$from" ] || [ -s "$from" ] || empty_capture
# A capture whose name begins with '-' is passed on as ./-NAME: the tools
# that read it (the converter, apitrace, cp) would take it for an option.
case "$from" in -*) from=./$from ;; esac
# Games and tools: scripts/setup.sh --games (and --gl for the converter).
need=(apitrace gzip sha256sum)
if [ -z "$from" ]; then
  need+=(xvfb-run)
  need+=("/usr/games/$game")
fi
for t in "${need[@]}"; do
  option=--games
  [ "$t" = /usr/games/supertuxkart ] && option=--supertuxkart
  command -v "$t" >/dev/null || { echo "capture-game.sh: $t is missing (scripts/setup.sh --gl $option installs it)" >&2; exit 1; }
done
raster=${RBCD_GL_RASTER:-}
[ -n "$raster" ] || raster=$(command -v rbcd-gl-raster || true)
[ -n "$raster" ] || [ ! -x "$root/build/bin/rbcd-gl-raster" ] || raster=$root/build/bin/rbcd-gl-raster
[ -n "$raster" ] || { echo "capture-game.sh: rbcd-gl-raster not found (build the project, or set RBCD_GL_RASTER)" >&2; exit 1; }

# The entry is staged beside OUT_DIR under an unpredictable name (no planted
# link to follow) and renamed into place complete: made first, so that an
# output folder that cannot take it is said before the game runs.
parent=$(dirname -- "$out")
if [ ! -d "$parent" ]; then
  # The nearest part of the path that exists says why: a file where a
  # folder is needed, or nothing there.
  p=$parent
  while [ ! -e "$p" ] && [ ! -L "$p" ] && [ "$p" != "$(dirname -- "$p")" ]; do p=$(dirname -- "$p"); done
  [ ! -e "$p" ] || [ -d "$p" ] || usage "$out: $p is not a directory: the entry needs a folder there"
  usage "$out: its folder $parent does not exist"
fi
# A signal while the two folders are made is taken once both are named
# (and so removed by the EXIT trap): one between a folder made and its name
# kept had left it behind. (mktemp itself ignores the three: killed, it had
# made the folder unnamed; a SIGINT in its milliseconds is lost, as bash
# drops a SIGINT its command survived.)
pending= staged= work=
trap 'pending=1' INT TERM HUP
trap 'rm -rf "${work:-}" "${staged:-}"' EXIT
staged=$(trap '' INT TERM HUP; exec mktemp -d "$parent/.$(basename -- "$out").XXXXXXXX" 2>/dev/null) || [ -n "$pending" ] ||
  usage "$out: cannot create the entry in $parent (not writable?)"
work=$(trap '' INT TERM HUP; exec mktemp -d "${TMPDIR:-/tmp}/capture-game.XXXXXXXX" 2>/dev/null) || [ -n "$pending" ] ||
  { echo "capture-game.sh: cannot create a work directory in $(oneline "${TMPDIR:-/tmp}") (TMPDIR)" >&2; exit 2; }
trap interrupted INT TERM HUP
[ -z "$pending" ] || interrupted
quiet mkdir -p "$work/home" "$work/entry"
width=800 height=480
version=$(dpkg-query -W -f='${Version}' "$game" 2>/dev/null || echo unknown)

if [ "$game" = openarena ]; then
  [[ "$map" =~ ^[A-Za-z0-9_]{1,64}$ ]] || usage "MAP '$map' is not a map name"
  # A map the game lacks would leave the engine at its console until the time
  # limit: refuse it now, from the game's own archives.
  if [ -z "$from" ] && [ -d /usr/share/games/openarena/baseoa ]; then
    maps=$(quiet_py '
import glob, sys, zipfile
names = set()
for p in glob.glob("/usr/share/games/openarena/baseoa/*.pk3"):
    try:
        names |= {n[5:-4] for n in zipfile.ZipFile(p).namelist() if n.startswith("maps/") and n.endswith(".bsp")}
    except (OSError, zipfile.BadZipFile):
        pass
print(" ".join(sorted(names)))') || maps=
    if [ -n "$maps" ] && [[ " $maps " != *" $map "* ]]; then
      usage "MAP '$map' is not one of OpenArena's maps ($(wc -w <<<"$maps") installed, e.g. $(tr ' ' '\n' <<<"$maps" | grep -m4 '^oa_' | tr '\n' ' ')...)"
    fi
  fi
  : "${skip:=60}"
  # The engine counts a `wait` about twice a frame; the margin covers the
  # frames the loading screen and the bots' arrival take.
  waits=$(( 2 * (skip + frames) + 100 ))
  names=(sarge grism major kyonshi angelyss arachna beret kyonshi sergei)
  {
    echo "set fixedtime 33"
    for ((i = 0; i < bots; i++)); do echo "addbot ${names[$i]} 3"; done
    echo "wait 30"
    echo "team spectator"
    echo "wait 10"
    echo "follow 1"
    echo "wait $waits"
    echo "quit"
  } >"$work/rbcdcap.cfg"
  quiet mkdir -p "$work/home/baseoa"
  quiet cp "$work/rbcdcap.cfg" "$work/home/baseoa/"
  cmd=(/usr/games/openarena +set fs_homepath "$work/home" +set cl_renderer opengl1
       +set r_mode -1 +set r_customwidth $width +set r_customheight $height +set r_fullscreen 0
       +set s_initsound 0 +set cg_draw2D 0 +set cg_drawGun 0 +set cg_thirdPerson 1
       +set con_notifytime -1 +set com_introplayed 1 +devmap "$map" +exec rbcdcap.cfg)
  rules=$root/workloads/games/openarena-select.toml
  limit=$(( 120 + 2 * (skip + frames) ))
elif [ "$game" = supertuxkart ]; then
  [[ "$map" =~ ^[a-z0-9_]{1,64}$ ]] || usage "TRACK '$map' is not a track name"
  # Race tracks only: arenas, soccer fields and cutscenes have no race.
  tracks=/usr/share/games/supertuxkart/data/tracks
  if [ -z "$from" ] && [ -d "$tracks" ]; then
    races=$(quiet_py '
import glob, os, sys, xml.etree.ElementTree as ET
out = []
for p in sorted(glob.glob(os.path.join(sys.argv[1], "*", "track.xml"))):
    try:
        a = {k.lower(): v.upper() for k, v in ET.parse(p).getroot().attrib.items()}
    except (OSError, ET.ParseError):
        continue
    if not any(a.get(k) == "Y" for k in ("arena", "soccer", "cutscene", "internal")):
        out.append(os.path.basename(os.path.dirname(p)))
print(" ".join(out))' "$tracks") || races=
    if [ -n "$races" ] && [[ " $races " != *" $map "* ]]; then
      usage "TRACK '$map' is not one of SuperTuxKart's race tracks ($races)"
    fi
  fi
  : "${skip:=0}"
  # Four kart models the shipped rules name by their textures' images
  # (workloads/games/supertuxkart-select.toml): the player's first, which
  # the camera follows; in profile mode every kart is driven by the AI.
  ai=(kiki puffy xue)
  kart_args=(--kart=tux --numkarts=$karts)
  [ "$karts" -lt 2 ] || kart_args+=("--ai=$(IFS=,; echo "${ai[*]:0:karts-1}")")
  # Under llvmpipe a frame takes longer than the game's longest step (3/60 s),
  # so each frame advances 0.05 s of the race: the race lasts long enough for
  # the frames asked for, with 2 s to spare (a faster machine gives more
  # frames, of which the first are taken).
  race_s=$(( (skip + frames + 19) / 20 + 2 ))
  cmd=(env HOME="$work/home" /usr/games/supertuxkart --no-start-screen --race-now "--track=$map"
       "${kart_args[@]}" --profile-time=$race_s --seed=1 --screensize=${width}x$height --windowed
       --apitrace --disable-dynamic-lights --disable-ibl --disable-hd-textures --disable-texture-compression)
  rules=$root/workloads/games/supertuxkart-select.toml
  limit=$(( 300 + 2 * (skip + frames) ))
else
  [ -f "$map" ] || usage "$map is not a file"
  # Its name goes into capture.toml as a TOML string: printable, no quote or backslash.
  [[ "$(basename -- "$map")" =~ ^[][A-Za-z0-9\ _.,+=@%:~()-]{1,128}$ ]] ||
    usage "MAP '$map': a file name of letters, digits, spaces and .,_+=@%:~()[]- only"
  case "$map" in
    *.nbr) mode=(-r "$(realpath -- "$map")") ;;
    *.sol) mode=(-l "$map") ;;
    *) usage "MAP '$map' is neither a replay (.nbr) nor a level (.sol)" ;;
  esac
  : "${skip:=30}"
  quiet mkdir -p "$work/home/.neverball"
  printf 'fullscreen 0\nwidth %d\nheight %d\naudio 0\nmultisample 0\nreflection 1\nbackground 1\nshadow 1\nfps 0\n' \
    $width $height >"$work/home/.neverball/neverballrc"
  cmd=(env HOME="$work/home" /usr/games/neverball "${mode[@]}")
  rules=$root/workloads/games/neverball-select.toml
  # A replay ends on a screen that waits for a key: the capture stops on a
  # time limit, and frames past the replay are simply not converted.
  limit=$(( 60 + (skip + frames) / 5 ))
fi
# Nor onto the game's selection rules, or a map or replay given as a file.
for input in "$rules" "$map"; do
  [ ! -f "$input" ] || ! [ /dev/stdout -ef "$input" ] || \
    { echo "capture-game.sh: $(oneline "$input"): standard output is an input of the capture: what goes there would be written into it" >&2; exit 2; }
done

# Every string capture.toml records, as a TOML string (escaped: a map's
# path may hold quotes, backslashes or control characters), the work
# directory written TMP in the command line (replaced as text: TMPDIR may
# hold anything). Made before the game runs: a string TOML cannot hold (a
# path that is not UTF-8) is refused first.
apitrace_version=$(dpkg-query -W -f='${Version}' apitrace 2>/dev/null || echo unknown)
mesa_version=$(dpkg-query -W -f='${Version}' libgl1-mesa-dri 2>/dev/null || echo unknown)
strings=$(PYTHONPATH="$root/python" quiet_py '
import sys
from rbcd.game_suite import capture_strings
sys.exit(capture_strings(sys.argv[1:]))' "$work" "$game" "$version" "$(basename -- "$map")" "$apitrace_version" \
  "$mesa_version" "workloads/games/$(basename -- "$rules")" -- "${cmd[@]}") ||
  { rc=$?; [ "$rc" -le 128 ] || interrupted; exit "$rc"; }   # (killed by a signal: taken here, before the exit)
mapfile -t q <<<"$strings"

capture=$work/capture.trace
if [ -n "$from" ]; then
  capture=$from   # read where it is: the converter's messages name the user's file
  rc=0
else
echo "capture-game.sh: capturing $game $map under Xvfb (at most ${limit} s)"
set +e
# xvfb-run's own temporary folder inside the work directory, which goes
# at the end: xvfb-run stopped by the time limit leaves it.
# In the background, waited for: timeout runs the game in a process group of
# its own, out of reach of a signal to the script's, and a signal to the
# script ends the wait at once (interrupted stops the game, then exits).
SDL_AUDIODRIVER=dummy TMPDIR=$work timeout --signal=TERM --kill-after=30 "$limit" \
  xvfb-run -a -s "-screen 0 1024x768x24" apitrace trace -o "$work/capture.trace" "${cmd[@]}" \
  >"$work/game.log" 2>&1 &
game_pid=$!
wait "$game_pid"
rc=$?
game_pid=
set -e
fi
# OpenArena and SuperTuxKart quit by themselves (0); a replay is stopped by
# the time limit (124), after apitrace has flushed the capture on SIGTERM.
if [ ! -s "$capture" ] || { [ $rc -ne 0 ] && [ $rc -ne 124 ]; }; then
  [ -z "$from" ] || empty_capture
  echo "capture-game.sh: the game or its capture failed (exit $rc); its log:" >&2
  quiet tail -n 20 "$work/game.log" >&2
  exit 1
fi
race_start=
if [ "$game" = supertuxkart ]; then
  # The race's first frame: the first that draws the 3D scene (the frames
  # before it are the loading screens).
  race_start=$(apitrace dump --color=never "$capture" 2>/dev/null |
    awk '/ glXSwapBuffers\(| eglSwapBuffers\(/ {f++} /buf = "Solid Pass begin"/ {print f + 0; exit}') || true
  # A capture given with --from-trace is the input, and without the race it
  # is bad input (2); one the game just made failed to reach the race (1).
  [ -n "$race_start" ] || { echo "capture-game.sh: $capture: no frame draws the race (no \"Solid Pass begin\" marker)" >&2; exit $([ -n "$from" ] && echo 2 || echo 1); }
  echo "capture-game.sh: the race starts at frame $race_start of the capture"
  skip=$(( race_start + skip ))
fi

last=$(( skip + frames - 1 ))
# The game's own configuration (the settings its options gave), kept beside
# the entry's other settings.
stk_config=$work/home/.config/supertuxkart/config-0.10/config.xml
[ "$game" != supertuxkart ] || [ ! -f "$stk_config" ] || quiet cp "$stk_config" "$work/entry/game-config.xml"
echo "capture-game.sh: converting frames $skip to $last"
converting=1   # (the converter says "interrupted" itself)
RBCD_GL_RASTER=$raster "$here/rbcd-gl2rbt" "$capture" -o "$work/trace.rbt.zst" --frames "$skip:$last" \
  --screen $width $height --select "$rules" --geometry "$work/geometry.geo" \
  --summary "$work/entry/summary.jsonl" --reduced-out "$work/entry/calls.xz" -q
converting=
got=$(wc -l <"$work/entry/summary.jsonl")
[ "$got" = "$frames" ] || { echo "capture-game.sh: the capture holds only $got of the $frames frames asked for after the first $skip" >&2; exit 2; }
sum() { sha256sum | cut -d' ' -f1; }
{
  echo "# How this game-suite entry was captured (scripts/capture-game.sh; docs/games.md)."
  echo "game = ${q[0]}"
  echo "game_version = ${q[1]}"
  echo "map = ${q[2]}"
  echo "frames = $frames"
  echo "first_frame = $skip      # of the capture: the warm-up before it is emulated, not converted"
  echo "screen = [$width, $height]"
  if [ "$game" = openarena ]; then
    echo "bots = $bots"
    echo "bot_skill = 3"
    echo "fixed_time_ms = 33"
  fi
  if [ "$game" = supertuxkart ]; then
    echo "race_start = $race_start      # the first frame that draws the race; first_frame counts --skip after it"
    echo "karts = $karts"
    echo "race_seconds = $race_s"
  fi
  echo "apitrace_version = ${q[3]}"
  echo "mesa_version = ${q[4]}"
  echo "selection = ${q[5]}"
  echo "command = ${q[6]}"
  if [ "$game" = openarena ]; then echo "config = '''"; quiet cat "$work/rbcdcap.cfg"; echo "'''"; fi
  if [ -f "$work/entry/game-config.xml" ]; then
    echo "game_config = \"game-config.xml\"      # the game's configuration as it wrote it at the end of the run"
  fi
  echo ""
  echo "[sha256]   # scripts/game-suite checks the regenerated files against these"
  echo "calls = \"$(sum <"$work/entry/calls.xz")\""
  echo "trace = \"$(PYTHONPATH="$here/../python" quiet_py '
import sys
from rbcd.game_suite import sha256_file
print(sha256_file(sys.argv[1], decompress=True))' "$work/trace.rbt.zst")\"      # uncompressed"
  echo "geometry = \"$(sum <"$work/geometry.geo")\""
} >"$work/entry/capture.toml"
if [ "$keep" = yes ]; then
  quiet cp -- "$capture" "$work/entry/capture.trace"
  quiet mv "$work/trace.rbt.zst" "$work/geometry.geo" "$work/entry/"
fi
quiet chmod "$(printf '%o' $((0777 & ~0$(umask))))" "$staged"   # mktemp's 0700, made what mkdir would
# Across file systems mv copies: a full device is one line, exit 1 (the
# staged folder goes with the trap).
err=$(mv "$work/entry"/* "$staged"/ 2>&1) ||
  { echo "capture-game.sh: $out: write failed: $(oneline "${err%%$'\n'*}")" >&2; exit 1; }
# The entry goes into place whole: a signal from here changes nothing.
trap true INT TERM HUP
quiet mv -T -- "$staged" "$out"
staged=
echo "capture-game.sh: wrote $out ($(du -sh -- "$out" | cut -f1))"
