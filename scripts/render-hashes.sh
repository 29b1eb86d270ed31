#!/usr/bin/env bash
# Renders every committed scene with every integrator (small, few samples) and prints one
# line per render: "scene integrator sha256-of-the-PFM". Two builds that print the same
# lines render bit-identically. Used by tests/render/compiler_identity.sh (GCC vs Clang)
# and by hand before and after a refactoring:
#   scripts/render-hashes.sh build/caustic > before.txt
set -euo pipefail
bin=${1:?usage: render-hashes.sh CAUSTIC_BINARY [SCENES_DIR]}
dir=${2:-"$(dirname "$0")/../scenes"}
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
# Each integrator, and the path tracer with the other samplers and filters.
runs=(path path-nee path-bsdf light whitted photon sppm bdpt vcm
      "path --sampler sobol --filter mitchell" "path --sampler stratified --filter gaussian"
      "light --filter tent" "vcm --filter gaussian")
scenes=("" "$dir"/*.json "$dir"/*.pbrt)
for scene in "${scenes[@]}"; do
  name=${scene:+$(basename "$scene")}
  for run in "${runs[@]}"; do
    "$bin" render $scene --integrator $run --width 48 --height 36 --spp 2 --threads 2 \
      --seed 7 -o "$out/img.pfm" --quiet >"$out/log" 2>&1 || {
        echo "${name:-builtin} $run FAILED: $(tail -1 "$out/log")"; continue; }
    echo "${name:-builtin} ${run// /_} $(sha256sum "$out/img.pfm" | cut -c1-16)"
  done
done
