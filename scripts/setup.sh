#!/usr/bin/env bash
# Installs the Debian bookworm packages the build needs, only those missing:
# as root directly, otherwise through sudo. When neither works it lists the
# missing packages and the command an administrator should run, and exits 1.
set -euo pipefail
pkgs=(g++ cmake ninja-build pkg-config libsystemc-dev catch2 libtomlplusplus-dev
      nlohmann-json3-dev libcli11-dev zlib1g-dev libeigen3-dev libassimp-dev libpng-dev
      libxxhash-dev libzstd-dev)
# Optional, only when asked for (their tests are skipped with a message without them):
#   --slurm  slurm-wlm and munge, for the SLURM sweep backend's test (docs/sweeps.md)
#   --plots  python3-matplotlib for scripts/rbcd-plot (gnuplot-nox also does)
#   --eval   libbullet-dev and libfcl-dev (rbcd-cpucd), assimp-testmodels (the meshes
#            of workloads/), python3-matplotlib, and valgrind (rbcd-cpucd
#            --count-instructions: Figure 8's counted CPU side), for scripts/reproduce.sh
#   --fuzz   clang-14, libclang-rt-14-dev (libFuzzer) and assimp-testmodels (mesh
#            seeds), for scripts/fuzz.sh
#   --gl     apitrace, Xvfb and Mesa (llvmpipe) to capture OpenGL programs, numpy for
#            scripts/rbcd-gl2rbt, PyOpenGL and Mesa's EGL for its shader path (Mesa
#            runs the captures' vertex shaders headless), and the GL, EGL, GLES and
#            X11 headers for the test programs (docs/gl-capture.md), python3-zstandard
#            (scripts/game-suite checks the zstd traces it expands), and glmark2-es2-x11
#            (an OpenGL ES 2.0 program the tests capture, testbench/gl/test_glmark2.py)
#   --waves  verilator (its copy of GTKWave's fstapi sources: rbcd-sim --fst),
#            gtkwave (fst2vcd for the FST test; the viewer) and libsqlite3-dev
#            (rbcd-sim --db), docs/waveforms.md and docs/tile-database.md
#   --games  openarena and neverball, the games scripts/capture-game.sh captures for
#            the game-frame suite (docs/games.md; with --gl for the capture tools)
#   --supertuxkart  supertuxkart (a 659 MB download), only to capture new SuperTuxKart
#            entries: the committed entries expand without it
#   --list   print the packages (with the options given) one a line, install nothing
# Besides the build: what the test suite runs that a minimal Debian lacks
# (testbench/scripts/check_test_programs.sh checks the list against the suite).
pkgs+=(time python3 python3-pytest python3-hypothesis)
list=no
for opt in "$@"; do
  case "$opt" in
    --list) list=yes ;;
    --slurm) pkgs+=(slurm-wlm munge) ;;
    --plots) pkgs+=(python3-matplotlib) ;;
    --eval) pkgs+=(libbullet-dev libfcl-dev assimp-testmodels python3-matplotlib valgrind) ;;
    --fuzz) pkgs+=(clang-14 libclang-rt-14-dev assimp-testmodels) ;;
    --gl) pkgs+=(apitrace xvfb xauth libgl1-mesa-dri libglx-mesa0 libgl-dev libx11-dev python3-numpy
               python3-opengl libegl1 libegl-mesa0 libopengl0 libegl-dev libgles-dev python3-zstandard khronos-api
               glmark2-es2-x11) ;;
    --waves) pkgs+=(verilator gtkwave libsqlite3-dev) ;;
    --games) pkgs+=(openarena neverball) ;;
    --supertuxkart) pkgs+=(supertuxkart) ;;
    *) echo "setup: unknown option $opt (known: --slurm --plots --eval --fuzz --gl --waves --games --supertuxkart --list)" >&2; exit 2 ;;
  esac
done
if [ "$list" = yes ]; then
  printf '%s\n' "${pkgs[@]}"
  exit 0
fi

# Exit 1 with the list of what is missing and how to install it.
cannot_install() {
  printf 'setup: %s\n' "$1" >&2
  printf 'setup: missing Debian packages: %s\n' "${missing[*]}" >&2
  printf 'setup: install them as root, then run this script again:\n' >&2
  printf '    apt-get install --no-install-recommends %s\n' "${missing[*]}" >&2
  exit 1
}

if ! command -v dpkg-query >/dev/null 2>&1; then
  missing=("${pkgs[@]}")
  cannot_install "dpkg-query not found: this script expects Debian bookworm"
fi
missing=()
for p in "${pkgs[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [ "$status" = "install ok installed" ] || missing+=("$p")
done
((${#missing[@]})) || exit 0

sudo_cmd=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null 2>&1 || cannot_install "not root and no sudo: cannot install packages"
  sudo_cmd=(sudo)
fi
echo "setup: installing ${missing[*]}" >&2
"${sudo_cmd[@]}" apt-get update -qq || cannot_install "apt-get update failed"
"${sudo_cmd[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" ||
  cannot_install "apt-get install failed"
