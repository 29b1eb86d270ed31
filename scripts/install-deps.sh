#!/usr/bin/env bash
# Installs the Debian 12 packages caustic builds against, only those missing.
# Idempotent; run as root (or with sudo available). Embree is optional but installed
# so the comparison back end and benchmarks are available.
set -euo pipefail

PKGS=(
  build-essential cmake pkg-config
  ninja-build         # CI's second and later build trees (.ci/run, scripts/fuzz.sh)
  clang               # the second compiler of CI's render identity check
  libjansson-dev      # JSON scenes with line/column errors
  libpng-dev          # PNG output
  libopenexr-dev      # OpenEXR C API (openexr.h) for EXR output
  libstb-dev          # stb_image for PNG, BMP, TGA and HDR textures
  libjpeg62-turbo-dev # libjpeg-turbo for JPEG textures (src/io/jpeg.c)
  libassimp-dev       # mesh import (OBJ/glTF)
  zlib1g-dev          # gzip-compressed PLY meshes and pbrt includes
  libembree-dev       # optional comparison back end
  libcmocka-dev       # unit test framework, driven by CTest
  python3             # scripts/check-layout.sh (the CTest test "layout")
  libsdl2-dev         # optional: the window of `caustic view` (cli/view.c)
  xvfb                # the view tests' X server (Xvfb), tests/cli/view_tests.sh
  libopenmpi-dev      # optional: distributed rendering under mpirun (cli/cluster.c)
  openmpi-bin         # mpirun, for tests/cli/mpi_tests.sh
)

missing=()
for p in "${PKGS[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PKGS[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
