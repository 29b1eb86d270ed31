#!/usr/bin/env bash
# Speed of two builds of caustic on the same renders, runs alternating (before, after,
# before, ...) so that machine drift hits both alike: the Cornell box with `path`,
# cornell-spheres with light/bdpt/vcm/sppm, and `bench rays` on the dragon (BVH).
# Usage: scripts/bench-compare.sh BEFORE_BIN AFTER_BIN [ROUNDS]   (default 3 rounds)
# Prints one line per case: the median seconds (renders) or Mrays/s (rays) of each
# build and after/before. Needs ../shared/meshes/dragon.ply for the ray case (skipped
# with a message otherwise).
set -euo pipefail
before=$1 after=$2 rounds=${3:-3}
root=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# seconds of one render, from the CLI's summary line "... 2 threads, 1.23 s, ..."
render_seconds() {
    "$1" render "${@:2}" -o "$tmp/out.pfm" 2>&1 | sed -n 's/.* threads, \([0-9.]*\) s,.*/\1/p' | tail -1
}
# the BVH's 2-thread primary Mrays/s
rays_mrays() {
    "$1" bench rays "$2" --accel bvh --threads 2 2>&1 | awk '$1 == "bvh" && $4 == "primary" && $5 == 2 {print $7}'
}
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }

case_run() { # name, kind (render|rays), args...
    local name=$1 kind=$2; shift 2
    : >"$tmp/b"; : >"$tmp/a"
    for _ in $(seq "$rounds"); do
        for side in b a; do
            bin=$before; [ "$side" = a ] && bin=$after
            if [ "$kind" = rays ]; then rays_mrays "$bin" "$@" >>"$tmp/$side"
            else render_seconds "$bin" "$@" >>"$tmp/$side"; fi
        done
    done
    local mb ma
    mb=$(median <"$tmp/b"); ma=$(median <"$tmp/a")
    awk -v n="$name" -v k="$kind" -v b="$mb" -v a="$ma" 'BEGIN {
        u = (k == "rays") ? "Mrays/s" : "s";
        printf "%-28s before %8.3f %s  after %8.3f %s  after/before %.3f\n", n, b, u, a, u, a / b }'
}

echo "# $(date -u +%F) $(lscpu | sed -n 's/^Model name: *//p'), $rounds alternating rounds, medians"
case_run "cornell-box path (16 spp)" render --spp 16 --threads 2
for i in light bdpt vcm sppm; do
    case_run "cornell-spheres $i (4 spp)" render "$root/scenes/cornell-spheres.json" --integrator "$i" --spp 4 --threads 2
done
if [ -f "$root/../shared/meshes/dragon.ply" ]; then
    case_run "bench rays dragon (bvh, 2t)" rays "$root/../shared/meshes/dragon.ply"
else
    echo "bench rays dragon: skipped (../shared/meshes/dragon.ply not found)"
fi
