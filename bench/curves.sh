#!/bin/sh
# The curve benchmark of issue 28: caustic binaries (and pbrt-v4) on the hair-ball stand-in
# (bench/hair_ball.py), alternating rounds, CPU time (user + sys) of the whole process at
# 1 spp and at SPP spp; render CPU per spp = (T(SPP) - T(1)) / (SPP - 1), load = T(1) - that.
#   sh bench/curves.sh SCENE THREADS SPP ROUNDS PBRT|- CAUSTIC...
set -eu
scene=$1; threads=$2; spp=$3; rounds=$4; pbrt=$5; shift 5
cpu() { # prints user+sys seconds and max RSS MB of "$@"
    /usr/bin/time -f '%U %S %M' -o /tmp/curves-time.$$ "$@" >/dev/null 2>&1
    awk '{printf "%.2f %.0f", $1 + $2, $3 / 1024}' /tmp/curves-time.$$
}
run() { # name command...
    name=$1; shift
    a=$(cpu "$@" 1); b=$(cpu "$@" "$spp")
    echo "$name $a $b" | awk -v s="$spp" '{per = ($4 - $2) / (s - 1);
        printf "%-28s load %6.2f s  render %7.3f s/spp  whole(%d spp) %6.2f s  RSS %d MB\n", $1, $2 - per, per, s, $4, $5}'
}
i=0
while [ "$i" -lt "$rounds" ]; do
    for c in "$@"; do
        run "$(basename "$c")" "$c" render "$scene" --threads "$threads" -o /tmp/curves-out.$$.pfm --spp
    done
    [ "$pbrt" = - ] || run pbrt-v4 "$pbrt" --nthreads "$threads" "$scene" --outfile /tmp/curves-out.$$.exr --spp
    i=$((i + 1))
done
rm -f /tmp/curves-time.$$ /tmp/curves-out.$$.pfm /tmp/curves-out.$$.exr
