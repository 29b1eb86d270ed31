#!/usr/bin/env bash
# caustic against SmallVCM (Davidovič's reference implementation of the VCM paper) on
# SmallVCM's own Cornell box, scenes/smallvcm-box.json (issue 32): whole-process wall time.
#
# Usage: bench/smallvcm.sh [--smallvcm DIR] [--caustic BIN] [--rounds N] [--iterations N]
#                          [--threads N] [--algorithms pt,lt,bpt,vcm,ppm] [--keep DIR]
#   --smallvcm DIR  SmallVCM's source tree (also $SMALLVCM_DIR); default ../SmallVCM beside
#                   the repository root. It is the developer's own clone and is never copied
#                   into this repository. Absent: caustic's figures are printed alone.
#   --caustic BIN   default build/caustic of this repository
#   --rounds N      alternating rounds (default 3); each round runs SmallVCM then caustic
#                   on every algorithm, the order of the two flipped every other round
#   --keep DIR      keep the images (SmallVCM .hdr, caustic .pfm) of the last round in DIR
#   --scene-roulette  run path, light and bdpt at the scene's rr_depth (3) too (see below)
#
# SmallVCM is built from a copy of its tree in a temporary directory with its own Makefile
# (g++ -O3 -std=c++0x -fopenmp). Two configuration lines of the copy are changed, nothing
# of its algorithms: its scene table (g_SceneConfigs, config.hxx) gains the scene
# kLightCeiling | kBothSmallSpheres (its LoadCornellBox default, which the table lacks)
# as scene 4, and its thread count (mNumThreads, 0 = every processor) is set to --threads.
# SmallVCM's maximum path length of 10 segments is caustic's max_depth 9 (bounces).
#
# Pairs: pt/path, lt/light, bpt/bdpt, vcm/vcm, ppm/sppm; one SmallVCM iteration is one
# caustic spp (sppm: one camera pass and 512 x 512 photons each). Printed per algorithm:
# the minimum and maximum wall seconds and CPU seconds (user + sys, the steadier figure
# on a shared machine) of each renderer over the rounds, and the ratios of the minima
# (SmallVCM / caustic: > 1 means caustic is faster).
#
# Russian roulette: SmallVCM plays it from the first bounce in every algorithm (continuation
# probability = the hit's albedo); caustic's default starts at bounce 3. path and light run
# here at rr_depth 1 (a copy of the scene with that key), where their equal-time relMSE on
# this scene is lower than at 3 (path 6-10%, light 2-5%; docs/benchmarks-history.md,
# issue 32); bdpt and vcm keep the scene's 3, since at 1 theirs is 30-70% higher. bdpt's
# light subpaths alone play it from the first bounce (light_rr_depth 1), where its
# equal-time relMSE is 5% lower than at 3 (history, 2026-12-07, branch bdpt-speed).
# --scene-roulette runs path, light and bdpt at 3 for all subpaths.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
svcm_dir=${SMALLVCM_DIR:-$root/../SmallVCM}
caustic=$root/build/caustic
rounds=3 iterations=16 threads=2 algorithms=pt,lt,bpt,vcm,ppm keep= scene_rr=0
while [ $# -gt 0 ]; do
    case $1 in
        --smallvcm) svcm_dir=$2; shift 2 ;;
        --caustic) caustic=$2; shift 2 ;;
        --rounds) rounds=$2; shift 2 ;;
        --iterations) iterations=$2; shift 2 ;;
        --threads) threads=$2; shift 2 ;;
        --algorithms) algorithms=$2; shift 2 ;;
        --keep) keep=$2; shift 2 ;;
        --scene-roulette) scene_rr=1; shift ;;
        -h|--help) sed -n '2,37p' "$0"; exit 0 ;;
        *) echo "bench/smallvcm.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
    esac
done
scene=$root/scenes/smallvcm-box.json
[ -x "$caustic" ] || { echo "bench/smallvcm.sh: $caustic is not built" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# path and light: the scene with SmallVCM's roulette (see above); fail loudly if the
# integrator block changed shape
scene_rr1=$tmp/smallvcm-box-rr1.json
sed 's/"max_depth": 9,/"max_depth": 9, "rr_depth": 1,/' "$scene" >"$scene_rr1"
grep -q '"rr_depth": 1,' "$scene_rr1" ||
    { echo "bench/smallvcm.sh: $scene has no \"max_depth\": 9 to add rr_depth to" >&2; exit 2; }
scene_lrr1=$tmp/smallvcm-box-lrr1.json
sed 's/"max_depth": 9,/"max_depth": 9, "light_rr_depth": 1,/' "$scene" >"$scene_lrr1"

svcm=
if [ -f "$svcm_dir/src/smallvcm.cxx" ] && [ -f "$svcm_dir/Makefile" ]; then
    cp -r "$svcm_dir/src" "$svcm_dir/Makefile" "$tmp/"
    # the two configuration edits described above; fail loudly if the source changed shape
    sed -i 's/^\(\s*Scene::kGlossyFloor | Scene::kBothSmallSpheres  | Scene::kLightBackground\)$/\1,\n    Scene::kLightCeiling | Scene::kBothSmallSpheres/' "$tmp/src/config.hxx"
    sed -i "s/oConfig.mNumThreads    = 0;/oConfig.mNumThreads    = $threads;/" "$tmp/src/config.hxx"
    grep -q 'Scene::kLightCeiling | Scene::kBothSmallSpheres$' "$tmp/src/config.hxx" &&
        grep -q "mNumThreads    = $threads;" "$tmp/src/config.hxx" ||
        { echo "bench/smallvcm.sh: SmallVCM's config.hxx is not the expected one" >&2; exit 2; }
    echo "building SmallVCM from $svcm_dir in $tmp ..."
    make -s -C "$tmp" all >"$tmp/build.log" 2>&1 ||
        { cat "$tmp/build.log" >&2; echo "bench/smallvcm.sh: SmallVCM build failed" >&2; exit 2; }
    svcm=$tmp/smallvcm
else
    echo "SmallVCM not found at $svcm_dir (set SMALLVCM_DIR or --smallvcm): caustic's figures alone"
fi

caustic_name() {
    case $1 in pt) echo path ;; lt) echo light ;; bpt) echo bdpt ;; vcm) echo vcm ;;
        ppm) echo sppm ;; *) echo "bench/smallvcm.sh: unknown algorithm '$1'" >&2; exit 2 ;; esac
}
# "wall cpu" seconds of one whole process (cpu: user + sys of it and its children)
timed() {
    local TIMEFORMAT='%R %U %S' out
    out=$( { time "$@" >/dev/null 2>&1; } 2>&1 ) || { echo "bench/smallvcm.sh: failed: $*" >&2; exit 2; }
    awk '{printf "%.3f %.3f\n", $1, $2 + $3}' <<<"$out"
}
run_svcm() { (cd "$tmp" && timed ./smallvcm -s 4 -a "$1" -i "$iterations" -o "$tmp/svcm-$1.hdr"); }
run_caustic() {
    local sc=$scene
    case $1 in pt|lt) [ "$scene_rr" = 1 ] || sc=$scene_rr1 ;; bpt) [ "$scene_rr" = 1 ] || sc=$scene_lrr1 ;; esac
    timed "$caustic" render "$sc" --integrator "$(caustic_name "$1")" --spp "$iterations" \
        --threads "$threads" -o "$tmp/caustic-$1.pfm"
}

IFS=, read -r -a algs <<<"$algorithms"
for a in "${algs[@]}"; do caustic_name "$a" >/dev/null; : >"$tmp/s-$a"; : >"$tmp/c-$a"; done
for r in $(seq "$rounds"); do
    for a in "${algs[@]}"; do
        if [ -n "$svcm" ] && [ $((r % 2)) -eq 1 ]; then run_svcm "$a" >>"$tmp/s-$a"; fi
        run_caustic "$a" >>"$tmp/c-$a"
        if [ -n "$svcm" ] && [ $((r % 2)) -eq 0 ]; then run_svcm "$a" >>"$tmp/s-$a"; fi
    done
done

echo "scene $scene, $iterations iterations, $threads threads, $rounds rounds"
[ "$scene_rr" = 1 ] && echo "Russian roulette: the scene's rr_depth for every algorithm" ||
    echo "Russian roulette: path and light at rr_depth 1 (SmallVCM's), bdpt's light subpaths at 1 (light_rr_depth), vcm, sppm and bdpt's camera subpaths at the scene's"
echo "seconds min-max over the rounds; ratios SmallVCM / caustic of the minima (> 1: caustic faster)"
# column 1 of a file: wall, column 2: cpu
mm() { sort -g -k"$2" "$1" | awk -v k="$2" 'NR == 1 {lo = $k} {hi = $k} END {printf "%.2f %.2f", lo, hi}'; }
for a in "${algs[@]}"; do
    c=$(caustic_name "$a")
    read -r cw0 cw1 <<<"$(mm "$tmp/c-$a" 1)"; read -r cc0 cc1 <<<"$(mm "$tmp/c-$a" 2)"
    if [ -n "$svcm" ]; then
        read -r sw0 sw1 <<<"$(mm "$tmp/s-$a" 1)"; read -r sc0 sc1 <<<"$(mm "$tmp/s-$a" 2)"
        awk -v a="$a" -v c="$c" -v sw0="$sw0" -v sw1="$sw1" -v sc0="$sc0" -v sc1="$sc1" \
            -v cw0="$cw0" -v cw1="$cw1" -v cc0="$cc0" -v cc1="$cc1" 'BEGIN {
            printf "%-3s/%-5s wall SmallVCM %7.2f-%-7.2f caustic %7.2f-%-7.2f ratio %5.2fx | cpu SmallVCM %7.2f-%-7.2f caustic %7.2f-%-7.2f ratio %5.2fx\n",
                   a, c, sw0, sw1, cw0, cw1, sw0 / cw0, sc0, sc1, cc0, cc1, sc0 / cc0 }'
    else
        printf '%-5s wall %7.2f-%-7.2f cpu %7.2f-%-7.2f\n' "$c" "$cw0" "$cw1" "$cc0" "$cc1"
    fi
done
if [ -n "$keep" ]; then mkdir -p "$keep"; cp "$tmp"/*.hdr "$tmp"/*.pfm "$keep/" 2>/dev/null || true; fi
