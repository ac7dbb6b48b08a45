#!/usr/bin/env bash
# Installs the missing system packages (Debian 12 / Ubuntu 22.04+), configures and builds Release on
# all cores into build/. Safe to run again: installs nothing that is already there.
set -euo pipefail
cd "$(dirname "$0")/.."

packages=(build-essential cmake ninja-build pkg-config libthrust-dev nlohmann-json3-dev libgtest-dev libgmock-dev
          python3 python3-matplotlib libepoxy-dev libglm-dev libglfw3-dev libimgui-dev libstb-dev libegl-dev
          libegl-mesa0 libgl1-mesa-dri xvfb xauth glslang-tools
          libopenxr-dev libopenxr-loader1 openxr-layer-corevalidation libgl-dev libx11-dev libpng-dev
          python3-dev pybind11-dev python3-pybind11 python3-numpy python3-distributed python3-dask python3-pytest
          clang-14 libclang-rt-14-dev libomp-14-dev)  # the last three: scripts/sanitize.sh and fuzz.sh
# (The fifth line: the Python module (python3-dev: Python's headers, which pybind11-dev does not bring
# in), its sweeps on Dask distributed and their tests, for Debian's /usr/bin/python3, which CMake builds
# the module for; docs/user/python.md.)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "sphxr setup: installing ${missing[*]}"
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

cmake --preset release "$@"
cmake --build --preset release -j "$(nproc)"
