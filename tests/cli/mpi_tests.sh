# Distributed rendering under mpirun (issue 29, cli/cluster.c): -np 2 and -np 3 give images byte
# for byte those of -np 1 and of a one-process render with the same --sample-block, for
# path, light, bdpt and vcm; what cannot be split is refused (exit 2); a rank killed with
# SIGKILL fails the whole run within seconds, with mpirun's message. Skipped (with the
# reason) when mpirun or this caustic's MPI is missing.
# usage: bash mpi_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init mpi_tests "$@"

if ! "$BIN" --version | grep -Eq '^mpi: +yes'; then
    skip "every mpirun test: this caustic was built without MPI (libopenmpi-dev, cmake -DCST_MPI=ON)"
    harness_finish
    exit $?
fi
if ! command -v mpirun >/dev/null 2>&1; then
    skip "every mpirun test: no mpirun on PATH (Debian's openmpi-bin)"
    harness_finish
    exit $?
fi
# CI runs as root; loopback only (one node, shared memory and the self transport).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
export OMPI_MCA_btl=self,vader OMPI_MCA_btl_vader_single_copy_mechanism=none
MPIRUN=(mpirun --oversubscribe -np)

# mpi_run DIR SECONDS NP ARGS...: caustic ARGS under mpirun with NP ranks in DIR; sets RC,
# OUT, ERR.
mpi_run() {
    local dir=$1 limit=$2 np=$3
    shift 3
    mkdir -p "$dir"
    (cd "$dir" && timeout -k 5 "$limit" "${MPIRUN[@]}" "$np" "$BIN" "$@" >"$OUT" 2>"$ERR" </dev/null)
    RC=$?
}

SMALL=(--width 48 --height 32 --threads 1 --quiet)

# ------------------------------------------------------------ -np 1, 2, 3: one image
for integ in path light bdpt vcm; do
    for block in 1 4; do
        d=$TMP/$integ-$block
        harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 10 --sample-block "$block" -o one.pfm
        ok=1
        for np in 1 2 3; do
            mpi_run "$d" 180 "$np" render --integrator "$integ" "${SMALL[@]}" --spp 10 --sample-block "$block" \
                -o "np$np.pfm"
            if [ "$RC" -ne 0 ] || ! cmp -s "$d/one.pfm" "$d/np$np.pfm"; then
                fail "$integ, blocks of $block: mpirun -np $np = one process, byte for byte" "exit $RC"
                ok=0
            fi
        done
        [ "$ok" = 1 ] && pass "$integ, blocks of $block: mpirun -np 1, 2, 3 = one process, byte for byte"
    done
done

# Rank 0 alone writes: one image, no temporary left, its summary line once.
d=$TMP/summary
mpi_run "$d" 120 3 render --width 48 --height 32 --threads 1 --spp 4 -o out.png
if [ "$RC" -eq 0 ] && [ "$(ls -A "$d" | wc -l)" -eq 1 ] && [ "$(grep -c "wrote out.png" "$ERR")" -eq 1 ]; then
    pass "-np 3: one image, one summary line"
else
    fail "-np 3: one image, one summary line" "exit $RC; files: $(ls -A "$d" | tr '\n' ' ')"
fi

# ------------------------------------------------------------ refusals
d=$TMP/refuse
mpi_run "$d" 60 2 render "${SMALL[@]}" --integrator sppm --spp 2 -o x.pfm
expect "sppm under mpirun: refused" 2 "sppm cannot be split across ranks"
mpi_run "$d" 60 2 render "${SMALL[@]}" --time 1 -o x.pfm
expect "a time limit under mpirun: refused" 2 "a time limit cannot be split into fixed blocks"
mpi_run "$d" 60 2 render "${SMALL[@]}" --spp 2 --checkpoint s.state -o x.pfm
expect "--checkpoint under mpirun: refused" 2 "--checkpoint is not supported across ranks yet"
check "no image from a refused run" test ! -e "$d/x.pfm"

# ------------------------------------------------------------ a rank killed
d=$TMP/kill
mkdir -p "$d"
(cd "$d" && exec timeout -k 5 120 "${MPIRUN[@]}" 3 "$BIN" render --width 256 --height 256 --threads 1 --spp 100000 \
    --quiet -o big.pfm >"$OUT" 2>"$ERR" </dev/null) &
runner=$!
# The ranks: caustic processes below the runner (timeout, mpirun), found by parent id.
ranks=""
for _ in $(seq 100); do
    for p in $(pgrep -P "$runner"); do # mpirun
        ranks="$ranks $(pgrep -P "$p" -x caustic | tr '\n' ' ')"
        for q in $(pgrep -P "$p"); do ranks="$ranks $(pgrep -P "$q" -x caustic | tr '\n' ' ')"; done
    done
    [ "$(echo "$ranks" | wc -w)" -ge 3 ] && break
    ranks=""
    sleep 0.1
done
if [ "$(echo "$ranks" | wc -w)" -lt 3 ]; then
    fail "a killed rank: could not find the 3 ranks" "found: $ranks"
    kill "$runner" 2>/dev/null
else
    sleep 1
    victim=$(echo "$ranks" | awk '{print $NF}')
    t0=$(date +%s%N)
    kill -KILL "$victim"
    { wait "$runner"; } 2>/dev/null
    RC=$?
    ms=$((($(date +%s%N) - t0) / 1000000))
    if [ "$RC" -ne 0 ] && [ "$RC" -ne 124 ] && [ "$ms" -lt 10000 ] && grep -q "exited on signal 9" "$ERR" &&
        [ ! -e "$d/big.pfm" ]; then
        pass "a rank killed by SIGKILL: the run fails in $ms ms (exit $RC) with mpirun's message, no image"
    else
        fail "a rank killed by SIGKILL: the run fails within 10 s with a message" "exit $RC after $ms ms"
    fi
    # mpirun ends the other ranks as it exits: give them 5 s.
    for p in $ranks; do
        for _ in $(seq 50); do kill -0 "$p" 2>/dev/null || break; sleep 0.1; done
        kill -0 "$p" 2>/dev/null && fail "rank process $p outlived the run by 5 s"
    done
fi

harness_finish
