#!/usr/bin/env bash
# Time to quality against Blender Cycles (issue 29): how long caustic takes to reach the
# relMSE that Cycles reaches at SPP samples per pixel on the Cornell box, both measured
# against one long caustic reference render, in the same run.
#   bench/cycles.sh [--size N] [--spp N] [--ref-spp N] [--samplers LIST] [--threads N] [--caustic BIN]
# Needs Debian's `blender` (Cycles, 3.4 in Debian 12): `apt-get install blender`; it is a
# benchmark anchor only, not a dependency of caustic. Cycles renders the same scene built by
# bench/cycles_cornell.py (box filter, no denoising or adaptive sampling, no clamping,
# unbounded bounces, one-sided emitter). Times are CPU seconds (user + sys, /usr/bin/time)
# so that a loaded machine still gives comparable figures; Blender's start-up and scene
# build are removed by subtracting the CPU time of a 1-spp render of the same size.
# For caustic, the spp is raised in steps of about 6 % (from a prediction) until its relMSE
# is at most Cycles'; its CPU time at that spp is the time to quality.
set -euo pipefail
cd "$(dirname "$0")/.."
size=128 spp=256 ref_spp=8192 samplers=zsobol,independent threads=2 caustic=build/caustic
scene=scenes/cornell-box.json
while [ $# -gt 0 ]; do
  case $1 in
    --size) size=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --ref-spp) ref_spp=$2; shift 2 ;;
    --samplers) samplers=$2; shift 2 ;;
    --threads) threads=$2; shift 2 ;;
    --caustic) caustic=$2; shift 2 ;;
    -h|--help) sed -n 2,13p "$0"; exit 0 ;;
    *) echo "cycles.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
command -v blender >/dev/null || { echo "cycles.sh: blender is not installed (apt-get install blender)" >&2; exit 2; }
[ -x "$caustic" ] || { echo "cycles.sh: $caustic is not built" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

cpu() { # cpu OUTFILE CMD...: runs CMD, appends its user + sys CPU seconds to OUTFILE
  local out=$1; shift
  /usr/bin/time -f "%U %S" -o "$tmp/t" "$@" >"$tmp/log" 2>&1 || { cat "$tmp/log" >&2; exit 1; }
  awk '{printf "%.3f\n", $1 + $2}' "$tmp/t" >"$out"
}
relmse() { # relmse IMAGE: relMSE over all channels against the reference
  "$caustic" compare "$1" "$tmp/ref.exr" | awk '$1 == "all" {print $3}'
}
cycles() { # cycles SPP OUT.exr CPUFILE
  cpu "$3" blender -b --factory-startup -P bench/cycles_cornell.py -- "$scene" "$2" "$size" "$1" 1 "$threads"
}

echo "cycles.sh: $(blender --version 2>/dev/null | head -n1), $("$caustic" --version | head -n1)"
echo "cycles.sh: $scene at ${size}x${size}, $threads threads; reference: caustic independent $ref_spp spp, seed 99"
cpu "$tmp/ref.cpu" "$caustic" render "$scene" --width "$size" --height "$size" --spp "$ref_spp" --seed 99 \
  --sampler independent --threads "$threads" -q -o "$tmp/ref.exr"
echo "reference: $(cat "$tmp/ref.cpu") CPU s"

cycles 1 "$tmp/cy1.exr" "$tmp/cy1.cpu"
cycles "$spp" "$tmp/cy.exr" "$tmp/cy.cpu"
cy_err=$(relmse "$tmp/cy.exr")
cy_cpu=$(awk -v a="$(cat "$tmp/cy.cpu")" -v b="$(cat "$tmp/cy1.cpu")" 'BEGIN {printf "%.3f", a - b}')
printf "%-12s %6s spp  relMSE %-10s CPU %7s s (whole process %s s, 1-spp start-up %s s)\n" cycles "$spp" \
  "$cy_err" "$cy_cpu" "$(cat "$tmp/cy.cpu")" "$(cat "$tmp/cy1.cpu")"

for s in ${samplers//,/ }; do
  # relMSE falls about as 1/spp: a render at spp/2 predicts the crossing; start 10 % below
  # the prediction and go up in steps of about 6 %.
  n=$((spp / 2)); [ $n -ge 1 ] || n=1
  "$caustic" render "$scene" --width "$size" --height "$size" --spp "$n" --seed 1 --sampler "$s" \
    --threads "$threads" -q -o "$tmp/c.exr"
  n=$(awk -v n="$n" -v a="$(relmse "$tmp/c.exr")" -v b="$cy_err" 'BEGIN {m = int(0.9 * n * a / b); print (m > 0 ? m : 1)}')
  while :; do
    cpu "$tmp/c.cpu" "$caustic" render "$scene" --width "$size" --height "$size" --spp "$n" --seed 1 \
      --sampler "$s" --threads "$threads" -q -o "$tmp/c.exr"
    err=$(relmse "$tmp/c.exr")
    if awk -v a="$err" -v b="$cy_err" 'BEGIN {exit !(a <= b)}'; then break; fi
    if [ $n -ge $((spp * 64)) ]; then echo "$s: did not reach Cycles' relMSE by $n spp" >&2; break; fi
    n=$(( n + (n + 15) / 16 ))
  done
  c_cpu=$(cat "$tmp/c.cpu")
  printf "%-12s %6s spp  relMSE %-10s CPU %7s s  time to Cycles' quality: %.3f x Cycles\n" "caustic-$s" "$n" \
    "$err" "$c_cpu" "$(awk -v a="$c_cpu" -v b="$cy_cpu" 'BEGIN {print a / b}')"
done
