# Checkpoint and resume (issues 29, 31): a render cut in two by a state file is byte-identical to
# one in a single go, for every integrator (MLT with its chains); SIGINT/SIGTERM stop a render
# after its pass and write the image and the state; mismatched, truncated and corrupted
# states are refused with exit 2 and a message naming what is wrong.
# usage: bash checkpoint_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init checkpoint_tests "$@"

SMALL=(--width 64 --height 48 --threads 2 --quiet)

# ------------------------------------------------------------ N in one go = N/2 + resume
for integ in path path-nee path-bsdf whitted photon light sppm bdpt vcm; do
    d=$TMP/$integ
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 6 -o full.pfm
    [ "$RC" -eq 0 ] || { fail "$integ: render in one go" "exit $RC"; continue; }
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 3 -o half.pfm --checkpoint s.state
    [ "$RC" -eq 0 ] && [ -s "$d/s.state" ] || { fail "$integ: 3 spp with --checkpoint" "exit $RC"; continue; }
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 6 -o resumed.pfm --resume s.state
    if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/resumed.pfm"; then
        pass "$integ: 6 spp = 3 spp + checkpoint + resume to 6, byte for byte"
    else
        fail "$integ: 6 spp = 3 spp + checkpoint + resume to 6, byte for byte" "exit $RC"
    fi
done

# A crop, another filter, the Sobol' and ZSobol' samplers and the spectral mode (AOV sums: test_checkpoint,
# as the EXR they need holds the command line in its metadata).
d=$TMP/variants
for v in "--crop 8,40,4,30" "--filter tent" "--sampler sobol" "--sampler zsobol" "--spectral --filter gaussian" \
         "--sampler zsobol --spectral"; do
    # shellcheck disable=SC2086
    harness_run "$d" 120 render "${SMALL[@]}" $v --spp 4 -o full.pfm
    # shellcheck disable=SC2086
    harness_run "$d" 120 render "${SMALL[@]}" $v --spp 2 -o half.pfm --checkpoint v.state
    # shellcheck disable=SC2086
    harness_run "$d" 120 render "${SMALL[@]}" $v --spp 4 -o resumed.pfm --resume v.state
    if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/resumed.pfm"; then pass "$v: resumed render byte-identical"
    else fail "$v: resumed render byte-identical" "exit $RC"; fi
done

# Resuming a finished state to a higher count extends it; the state grows with it.
d=$TMP/extend
harness_run "$d" 120 render "${SMALL[@]}" --spp 5 -o five.pfm
harness_run "$d" 120 render "${SMALL[@]}" --spp 2 -o a.pfm --checkpoint e.state
harness_run "$d" 120 render "${SMALL[@]}" --spp 4 -o a.pfm --resume e.state --checkpoint e.state
harness_run "$d" 120 render "${SMALL[@]}" --spp 5 -o b.pfm --resume e.state
if [ "$RC" -eq 0 ] && cmp -s "$d/five.pfm" "$d/b.pfm"; then pass "2 + 2 + 1 spp through two states = 5 spp"
else fail "2 + 2 + 1 spp through two states = 5 spp" "exit $RC"; fi

# ------------------------------------------------------------ refusals
d=$TMP/refuse
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 -o ref.pfm --checkpoint ok.state
# MLT (state version 4: the chains): 4 mutations per pixel in one go = 2 + state + resume, with a
# small bootstrap and few chains from the scene file; a state of one MLT resumed by the other,
# or by path, and a corrupted one are refused.
sed 's/"integrator": {"type": "path"}/"integrator": {"type": "mmlt", "max_depth": 4, "bootstrap_samples": 512, "chains": 16}/' \
    "$SRC/scenes/cornell-box.json" >"$d/mlt.json"
for integ in pssmlt mmlt; do
    harness_run "$d" 60 render mlt.json --integrator "$integ" "${SMALL[@]}" --spp 4 -o full.pfm
    harness_run "$d" 60 render mlt.json --integrator "$integ" "${SMALL[@]}" --spp 2 -o half.pfm --checkpoint "$integ.state"
    harness_run "$d" 60 render mlt.json --integrator "$integ" "${SMALL[@]}" --spp 4 -o resumed.pfm --resume "$integ.state"
    if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/resumed.pfm"; then pass "$integ: 4 = 2 + checkpoint + resume, byte for byte"
    else fail "$integ: 4 = 2 + checkpoint + resume, byte for byte" "exit $RC"; fi
done
harness_run "$d" 60 render mlt.json --integrator pssmlt "${SMALL[@]}" --spp 4 -o x.pfm --resume mmlt.state
expect "an mmlt state resumed by pssmlt: refused" 2 'integrator: "mmlt" in the state, "pssmlt" here'
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume mmlt.state
expect "an mmlt state resumed by path: refused" 2 "the state was made for another render"
cp "$d/mmlt.state" "$d/badmlt.state"
printf '\x55' | dd of="$d/badmlt.state" bs=1 seek=$(($(wc -c <"$d/mmlt.state") - 100)) conv=notrunc 2>/dev/null
harness_run "$d" 60 render mlt.json --integrator mmlt "${SMALL[@]}" --spp 4 -o x.pfm --resume badmlt.state
expect "a corrupted mmlt state: refused" 2 "badmlt.state: corrupted state file"
rm -f "$d/x.pfm"
# An SPPM state resumed by another integrator, and a path state by sppm: the key names it.
harness_run "$d" 60 render "${SMALL[@]}" --integrator sppm --spp 2 -o y.pfm --checkpoint sppm.state
harness_run "$d" 60 render "${SMALL[@]}" --integrator path --spp 4 -o y.pfm --resume sppm.state
expect "an sppm state resumed by path: refused" 2 'integrator: "sppm" in the state, "path" here'
harness_run "$d" 60 render "${SMALL[@]}" --integrator sppm --spp 4 -o y.pfm --resume ok.state
expect "a path state resumed by sppm: refused" 2 'integrator: "path" in the state, "sppm" here'
harness_run "$d" 60 render "${SMALL[@]}" --spp 2 -o x.pfm --checkpoint no/such/dir/s.state
expect "a checkpoint in a missing directory: refused before rendering" 2 "directory 'no/such/dir' is not writable" &&
    check "no image for a refused checkpoint" test ! -e "$d/x.pfm"
harness_run "$d" 60 render "${SMALL[@]}" --checkpoint-every 5 -o x.pfm
expect "--checkpoint-every without --checkpoint" 2 "needs --checkpoint"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 --seed 3 -o x.pfm --resume ok.state
expect "another seed" 2 "ok.state: the state was made for another render" "seed: 0 in the state, 3 here"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 --width 32 -o x.pfm --resume ok.state
expect "another width" 2 "width: 64 in the state, 32 here"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 --integrator bdpt -o x.pfm --resume ok.state
expect "another integrator" 2 'integrator: "path" in the state, "bdpt" here'
harness_run "$d" 60 render "$SRC/scenes/cornell-box.json" "${SMALL[@]}" --spp 8 -o x.pfm --resume ok.state
expect "another scene" 2 'scene: "builtin:cornell-box" in the state, "sha256:[0-9a-f]{64}" here'
harness_run "$d" 60 render "${SMALL[@]}" --spp 2 --sampler stratified -o x.pfm --checkpoint strat.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sampler stratified -o x.pfm --resume strat.state
expect "stratified: strata laid out for another count" 2 "sampler.spp: 2 in the state, 4 here"
rm -f "$d/x.pfm"
harness_run "$d" 60 render "${SMALL[@]}" --spp 2 -o x.pfm --resume ok.state
expect "fewer samples than the state's" 2 "holds 4 samples per pixel, more than the 2 asked for"
head -c 20000 "$d/ok.state" >"$d/trunc.state"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume trunc.state
expect "truncated state" 2 "trunc.state: truncated state file: 20000 bytes"
head -c 10 "$d/ok.state" >"$d/short.state"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume short.state
expect "truncated header" 2 "short.state: truncated state file: 10 bytes, ending inside the header"
cp "$d/ok.state" "$d/bad.state"
printf '\x55' | dd of="$d/bad.state" bs=1 seek=30000 conv=notrunc 2>/dev/null
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume bad.state
expect "corrupted state (one byte changed)" 2 "bad.state: corrupted state file: CRC-32 [0-9a-f]{8} of its bytes, [0-9a-f]{8} stored"
cp "$d/ok.state" "$d/long.state"
printf 'xyz' >>"$d/long.state"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume long.state
expect "trailing bytes" 2 "long.state: 3 bytes after the end of the state"
printf 'P6\n1 1\n255\nabc' >"$d/img.state"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume img.state
expect "not a state file" 2 "img.state: not a caustic state file"
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 -o x.pfm --resume missing.state
expect "missing state" 2 "missing.state"
check "refused resumes wrote no image" test ! -e "$d/x.pfm"

# ------------------------------------------------------------ signals
# A shell without job control starts background commands with SIGINT ignored; give caustic
# the default so it installs its handler.
launch=("$BIN")
if env --default-signal=INT true 2>/dev/null; then launch=(env --default-signal=INT "$BIN"); fi

# interrupt_test SIG NUM: a long render with a state written after every pass; once the first
# state exists, SIG: exit 128 + NUM after writing the image of the passes done and the
# state; the image equals a render of that many spp, and resuming the state to a few more
# equals a render of that count in one go.
interrupt_test() {
    local sig=$1 num=$2 d=$TMP/int$1
    mkdir -p "$d"
    (cd "$d" && exec "${launch[@]}" render --width 96 --height 72 --threads 2 --spp 100000 -o stop.pfm \
        --checkpoint s.state --checkpoint-every 0.001 >"$OUT" 2>"$ERR" </dev/null) &
    local pid=$! i
    for ((i = 0; i < 600; i++)); do [ -e "$d/s.state" ] && break; sleep 0.05; done
    sleep 0.3
    kill -"$sig" "$pid"
    { wait "$pid"; } 2>/dev/null
    RC=$?
    expect "SIG$sig mid-render: exit $((128 + num)), image and state written" $((128 + num)) \
        "interrupted \\(SIG$sig\\) after [0-9]+ spp: wrote stop.pfm and s.state" || return
    local n
    n=$(sed -nE "s/.*interrupted \\(SIG$sig\\) after ([0-9]+) spp.*/\\1/p" "$ERR")
    harness_run "$d" 300 render --width 96 --height 72 --threads 2 --quiet --spp "$n" -o ref.pfm
    if cmp -s "$d/stop.pfm" "$d/ref.pfm"; then pass "SIG$sig: the image written is the $n-spp render, byte for byte"
    else fail "SIG$sig: the image written is the $n-spp render, byte for byte"; fi
    harness_run "$d" 300 render --width 96 --height 72 --threads 2 --quiet --spp $((n + 3)) -o more.pfm \
        --resume s.state
    local rc1=$RC
    harness_run "$d" 300 render --width 96 --height 72 --threads 2 --quiet --spp $((n + 3)) -o ref2.pfm
    if [ "$rc1" -eq 0 ] && cmp -s "$d/more.pfm" "$d/ref2.pfm"; then
        pass "SIG$sig: the state resumed to $((n + 3)) spp = $((n + 3)) spp in one go"
    else fail "SIG$sig: the state resumed to $((n + 3)) spp = $((n + 3)) spp in one go" "exit $rc1"; fi
}
interrupt_test INT 2
interrupt_test TERM 15

# Two SIGINTs at once: the second aborts, nothing is written, the previous outputs stay.
d=$TMP/twice
mkdir -p "$d"
echo previous >"$d/out.pfm"
echo previous >"$d/s.state"
(cd "$d" && exec "${launch[@]}" render --width 1024 --height 1024 --threads 2 --spp 100000 -o out.pfm \
    --checkpoint s.state --checkpoint-every 1000 --quiet >"$OUT" 2>"$ERR" </dev/null) &
pid=$!
sleep 1
# Two signals sent back to back can coalesce into one pending SIGINT when the process is
# not scheduled in between (a loaded machine): send the second once the first is seen.
kill -INT "$pid"
for _ in $(seq 200); do grep -q "interrupted: stopping" "$ERR" 2>/dev/null && break; sleep 0.02; done
kill -INT "$pid"
{ wait "$pid"; } 2>/dev/null
RC=$?
if [ "$RC" -eq 130 ] && [ "$(cat "$d/out.pfm")" = previous ] && [ "$(cat "$d/s.state")" = previous ] &&
    [ "$(ls -A "$d" | wc -l)" -eq 2 ] && ! grep -q "wrote" "$ERR"; then
    pass "a second SIGINT aborts at once: exit 130, previous image and state untouched, no temporary"
else
    fail "a second SIGINT aborts at once: exit 130, previous image and state untouched, no temporary" \
        "exit $RC; files: $(ls -A "$d" | tr '\n' ' ')"
fi

harness_finish
