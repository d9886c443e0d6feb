#!/usr/bin/env bash
# Installs the Debian bookworm packages the build needs, only those missing.
set -euo pipefail
pkgs=(g++ cmake ninja-build pkg-config libsystemc-dev catch2 libtomlplusplus-dev
      nlohmann-json3-dev libcli11-dev zlib1g-dev libeigen3-dev libassimp-dev libpng-dev
      clang-14 libclang-rt-14-dev assimp-testmodels)   # the last three: scripts/fuzz.sh (libFuzzer, mesh seeds)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}" >&2
  sudo_cmd=""
  [ "$(id -u)" -eq 0 ] || sudo_cmd="sudo"
  $sudo_cmd apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
