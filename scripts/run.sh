#!/usr/bin/env bash
# Installs what is missing, builds, and runs the main job (rbcd-sim's embedded
# default input). Extra arguments go to rbcd-sim.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build --target rbcd-sim
SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1 ./build/bin/rbcd-sim "$@"
