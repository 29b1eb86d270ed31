# Distributed rendering under mpirun (issue 29, cli/cluster.c): -np 2 and -np 3 give images byte
# for byte those of -np 1 and of a one-process render with the same --sample-block, for
# path, light, bdpt and vcm, and sppm's those of one process; what cannot be split is
# refused (exit 2); states written under mpirun are one process's byte for byte and resume
# under another number of ranks; SIGINT to mpirun writes the image and the state; a rank
# killed with SIGKILL fails the whole run within seconds, with mpirun's message. Skipped
# (with the reason) when mpirun or this caustic's MPI is missing.
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
mpi_run "$d" 60 2 render "${SMALL[@]}" --integrator sppm --time 1 -o x.pfm
expect "sppm with a time limit under mpirun: refused" 2 "expected --spp without --time"
mpi_run "$d" 60 2 render "${SMALL[@]}" --spp 2 --crop 0,8,0,8 --checkpoint s.state -o x.pfm
expect "--checkpoint of a crop under mpirun: refused" 2 "expected no --crop with --checkpoint or --resume"
check "no image from a refused run" test ! -e "$d/x.pfm"

# ------------------------------------------------------------ --time under mpirun
# Blocks are handed out until the time has passed; the image is then a one-process render of
# as many samples with the same --sample-block, byte for byte (whatever that count is).
d=$TMP/time
mpi_run "$d" 120 2 render "${SMALL[@]}" --time 1 --sample-block 2 --json=t.json -o np2.pfm
n=$(sed -n 's/.*"spp": *\([0-9]*\).*/\1/p' "$d/t.json" | head -n1)
if [ "$RC" -eq 0 ] && [ -n "$n" ] && [ "$n" -ge 2 ] && [ $((n % 2)) -eq 0 ]; then
    harness_run "$d" 120 render "${SMALL[@]}" --spp "$n" --sample-block 2 -o one.pfm
    check "--time 1 under -np 2: $n spp, byte for byte one process's --spp $n" cmp -s "$d/one.pfm" "$d/np2.pfm"
else
    fail "--time 1 under -np 2: a render of whole blocks" "exit $RC, spp '${n}'"
fi

# ------------------------------------------------------------ checkpoints and resume
# same_files A B [C D ...]: A = B, C = D, ... byte for byte.
same_files() {
    while [ $# -ge 2 ]; do cmp -s "$1" "$2" || return 1; shift 2; done
}
# Rank 0's state is byte for byte a one-process render's at the same sample count, and it
# resumes under another number of ranks to the image of one uninterrupted render.
d=$TMP/ckpt
R=(render "${SMALL[@]}")
harness_run "$d" 120 "${R[@]}" --spp 4 --checkpoint one4.state -o one4.pfm
harness_run "$d" 120 "${R[@]}" --spp 8 -o one8.pfm
mpi_run "$d" 180 2 "${R[@]}" --spp 4 --checkpoint np2.state -o np2-4.pfm
check "path: -np 2's state and image = one process's, byte for byte" \
    same_files "$d/one4.state" "$d/np2.state" "$d/one4.pfm" "$d/np2-4.pfm"
mpi_run "$d" 180 3 "${R[@]}" --spp 8 --resume np2.state -o np3-8.pfm
check "path: -np 2's state resumed by -np 3 = one uninterrupted process, byte for byte" \
    cmp -s "$d/one8.pfm" "$d/np3-8.pfm"

# sppm: rank 0 renders, the others trace their photon chunks, gathered in photon order, so
# -np 2 = one process, image and state (SPPM's radii and flux), and the state resumes under
# -np 3. 48 x 32 = 1536 photons per iteration: two chunks of 1024 (-np 3 leaves rank 0
# none).
d=$TMP/sppm
P=(render --integrator sppm "${SMALL[@]}")
harness_run "$d" 120 "${P[@]}" --spp 6 -o one.pfm
harness_run "$d" 120 "${P[@]}" --spp 3 --checkpoint one3.state -o one3.pfm
mpi_run "$d" 180 2 "${P[@]}" --spp 3 --checkpoint np2.state -o np2-3.pfm
check "sppm: mpirun -np 2's image and state = one process's, byte for byte" \
    same_files "$d/one3.pfm" "$d/np2-3.pfm" "$d/one3.state" "$d/np2.state"
mpi_run "$d" 180 3 "${P[@]}" --spp 6 --resume np2.state -o np3-6.pfm
check "sppm: -np 2's state resumed by -np 3 = one uninterrupted process, byte for byte" \
    cmp -s "$d/one.pfm" "$d/np3-6.pfm"

# ------------------------------------------------------------ SIGINT to mpirun
# mpirun (Open MPI 4.1) answers SIGINT with SIGTERM to every rank a second later, SIGKILL a
# second after that: rank 0 stops at once, writes the image and the state of the blocks
# added and ends the job (MPI_Abort). Signalled once a first state is on disk; the state
# resumes (one process, nothing left to render) to the same image, byte for byte.
d=$TMP/sigint
mkdir -p "$d"
(cd "$d" && exec timeout -k 5 120 "${MPIRUN[@]}" 2 "$BIN" render "${SMALL[@]}" --spp 1000000 --checkpoint s.state \
    --checkpoint-every 0.05 -o cut.pfm >"$OUT" 2>"$ERR" </dev/null) &
runner=$!
for _ in $(seq 300); do [ -e "$d/s.state" ] && break; sleep 0.05; done
t0=$(date +%s%N)
pkill -INT -P "$runner" -x mpirun
{ wait "$runner"; } 2>/dev/null
RC=$?
ms=$((($(date +%s%N) - t0) / 1000000))
n=$(sed -n 's/.*interrupted (SIG[A-Z]*) after \([0-9]*\) spp: wrote cut.pfm and s.state.*/\1/p' "$ERR" | head -n 1)
if [ -n "$n" ] && [ "$RC" -ne 124 ] && [ "$ms" -lt 5000 ] && [ -s "$d/cut.pfm" ]; then
    pass "SIGINT to mpirun: rank 0 wrote the image and the state of $n spp; mpirun exit $RC after $ms ms"
    harness_run "$d" 120 render "${SMALL[@]}" --spp "$n" --resume s.state -o res.pfm
    check "SIGINT to mpirun: the state holds the image's $n spp" cmp -s "$d/cut.pfm" "$d/res.pfm"
else
    fail "SIGINT to mpirun: rank 0 writes the image and the state within 5 s" \
        "exit $RC after $ms ms; spp '$n'; files: $(ls -A "$d" | tr '\n' ' '); $(tail -n 3 "$ERR" | tr '\n' ' ')"
fi

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
    # mpirun ends the others with SIGTERM, which rank 0 takes as a stop: the image of the
    # blocks it has added (and the state, with --checkpoint) is written, and says so.
    if [ "$RC" -ne 0 ] && [ "$RC" -ne 124 ] && [ "$ms" -lt 10000 ] && grep -q "exited on signal 9" "$ERR" &&
        { [ ! -e "$d/big.pfm" ] || grep -Eq "interrupted \(SIGTERM\) after [0-9]+ spp: wrote big.pfm" "$ERR"; }; then
        pass "a rank killed by SIGKILL: the run fails in $ms ms (exit $RC) with mpirun's message"
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
