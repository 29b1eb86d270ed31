#!/usr/bin/env bash
# Tests of how `caustic render` writes its image (issue 25, items 7 and 8 and the
# reproducibility metadata): output names up to NAME_MAX bytes write, unwritable places are
# refused before rendering (exit 2), no temporary file survives SIGTERM, SIGINT, SIGHUP or
# SIGXFSZ during the write, stale temporaries of dead processes are removed, and PNG and
# EXR outputs carry the caustic.* metadata. Run by CTest:
#   bash output_tests.sh <path-to-caustic-binary> <source-dir> [<slow-fsync-shim.so>]
# The shim (tests/cli/slow_fsync.c, LD_PRELOAD) holds the writer in fsync(2) with the
# complete temporary file on disk, so a signal lands mid-write; without it those checks
# are skipped. Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

if [ $# -lt 2 ] || [ $# -gt 3 ]; then
    echo "usage: bash output_tests.sh <path-to-caustic-binary> <source-dir> [<slow-fsync-shim.so>]" >&2
    exit 2
fi
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init output_tests "$@"
SHIM=${3:+$(realpath "$3")}

SMALL=(--width 16 --height 16 --spp 1 --threads 1)
# run DIR ARGS...: caustic in DIR; sets RC; stdout/stderr in OUT/ERR.
run() { local dir=$1; shift; harness_run "$dir" 300 "$@"; }
# temps DIR: the temporary files of a writer left in DIR (both name forms).
temps() { find "$1" -maxdepth 1 -name '*.tmp.*' -printf '%f\n'; }
rendered() { grep -q "^caustic: rendering" "$ERR"; }
name_of() { head -c "$1" /dev/zero | tr '\0' n; }

# --------------------------------------------------------------- item 7: output names
for len in 250 255; do
    d=$TMP/long$len
    name="$(name_of $((len - 4))).png"
    run "$d" render "${SMALL[@]}" -o "$name"
    if [ "$RC" -eq 0 ] && [ -s "$d/$name" ] && [ -z "$(temps "$d")" ]; then
        pass "a $len-byte output name is rendered and written"
    else
        fail "a $len-byte output name is rendered and written" "exit $RC; files: $(ls -A "$d" | head -c 300)"
    fi
done
d=$TMP/long256
run "$d" render "${SMALL[@]}" -o "$(name_of 252).png"
if [ "$RC" -eq 2 ] && ! rendered && grep -q "too long" "$ERR" && [ -z "$(ls -A "$d")" ]; then
    pass "a 256-byte output name is refused before rendering (exit 2)"
else
    fail "a 256-byte output name is refused before rendering (exit 2)" "exit $RC"
fi
# A directory that access(2) calls writable but where no file can be created.
for out in /proc/self/foo.png /sys/foo.png; do
    if [ ! -d "$(dirname "$out")" ]; then skip "$out: no such directory here"; continue; fi
    run "$TMP/pseudo" render "${SMALL[@]}" -o "$out"
    if [ "$RC" -eq 2 ] && ! rendered; then pass "-o $out is refused before rendering (exit 2)"
    else fail "-o $out is refused before rendering (exit 2)" "exit $RC"; fi
done

# --------------------------------------------------------------- item 8: signals
# signal_test SIG: caustic held in fsync on its temporary, sent SIG: dies of SIG, no
# temporary and no image left.
signal_test() {
    local sig=$1 num=$2 d=$TMP/sig$1 mark=$TMP/mark$1
    mkdir -p "$d"
    rm -f "$mark"
    local launch=("$BIN")
    # A shell without job control starts background commands with SIGINT ignored, and a
    # program keeps an ignored SIGINT (as it should); give this one the default.
    if [ "$sig" = INT ]; then launch=(env --default-signal=INT "$BIN"); fi
    (cd "$d" && CST_TEST_FSYNC_MARK=$mark CST_TEST_FSYNC_DELAY_MS=30000 LD_PRELOAD=$SHIM \
        ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}verify_asan_link_order=0 \
        exec "${launch[@]}" render "${SMALL[@]}" -o out.exr --quiet >"$OUT" 2>"$ERR" </dev/null) &
    local pid=$! i
    for ((i = 0; i < 600; i++)); do [ -e "$mark" ] && break; sleep 0.05; done
    if [ ! -e "$mark" ]; then
        kill -KILL "$pid" 2>/dev/null; wait "$pid" 2>/dev/null
        fail "SIG$sig during the write: the writer never reached fsync"
        return
    fi
    local during
    during=$(temps "$d")
    kill -"$sig" "$pid"
    { wait "$pid"; } 2>/dev/null
    local rc=$?
    if [ -z "$during" ]; then
        fail "SIG$sig during the write" "no temporary file existed while writing"
    elif [ "$rc" -eq $((128 + num)) ] && [ -z "$(temps "$d")" ] && [ ! -e "$d/out.exr" ]; then
        pass "SIG$sig during the write: exit $rc, no temporary file left ($during removed)"
    else
        fail "SIG$sig during the write: dies of the signal and leaves no temporary" \
            "exit $rc (expected $((128 + num))); left: $(ls -A "$d")"
    fi
}
if [ -z "$SHIM" ] || [ ! -f "$SHIM" ]; then
    skip "signals during the write: no slow-fsync shim given"
else
    signal_test TERM 15
    if env --default-signal=INT true 2>/dev/null; then signal_test INT 2
    else skip "SIGINT during the write: env --default-signal not available"; fi
    signal_test HUP 1
fi

# SIGXFSZ: the file size limit is reached while writing; a clear error, exit 1, nothing left.
d=$TMP/xfsz
mkdir -p "$d"
{ (cd "$d" && ulimit -f 8 && exec "$BIN" render --width 128 --height 128 --spp 1 --threads 1 \
    -o out.pfm --quiet >"$OUT" 2>"$ERR" </dev/null); } 2>/dev/null
RC=$?
if [ "$RC" -eq 1 ] && grep -q "File too large" "$ERR" && [ -z "$(ls -A "$d")" ]; then
    pass "SIGXFSZ (ulimit -f) during the write: exit 1, 'File too large', no temporary left"
else
    fail "SIGXFSZ (ulimit -f) during the write: exit 1, 'File too large', no temporary left" \
        "exit $RC; left: $(ls -A "$d")"
fi

# Stale temporaries: only those of this output name whose process is gone are removed.
d=$TMP/stale
mkdir -p "$d"
sh -c 'exit 0' &
dead=$!
wait "$dead"
if kill -0 "$dead" 2>/dev/null; then
    skip "stale temporaries: pid $dead was reused at once"
else
    gone=("out.png.tmp.$dead.0" "out.png.tmp.$dead")
    kept=("out.png.tmp.$$.0" "out.png.tmp.$dead.x" "other.png.tmp.$dead.0" "out.png.tmp.$dead.0.bak"
          "xout.png.tmp.$dead.0" "out.png.tmp..0" "out.png.tmp.$dead.0.1")
    for f in "${gone[@]}" "${kept[@]}"; do echo stale >"$d/$f"; done
    run "$d" render "${SMALL[@]}" -o out.png --quiet
    left=""
    for f in "${gone[@]}"; do [ -e "$d/$f" ] && left="$left $f"; done
    lost=""
    for f in "${kept[@]}"; do [ -e "$d/$f" ] || lost="$lost $f"; done
    if [ "$RC" -eq 0 ] && [ -s "$d/out.png" ] && [ -z "$left" ] && [ -z "$lost" ]; then
        pass "a write of out.png removes out.png.tmp.<dead pid>[.n] and nothing else"
    else
        fail "a write of out.png removes out.png.tmp.<dead pid>[.n] and nothing else" \
            "exit $RC; still there:$left; wrongly removed:$lost"
    fi
fi

# --------------------------------------------------------------- metadata
scene=$SRC/scenes/cornell-box.json
if [ ! -f "$scene" ]; then
    skip "metadata: $scene not found"
else
    sum=$(sha256sum "$scene" | cut -c1-64)
    for ext in png exr; do
        d=$TMP/meta
        run "$d" render "$scene" "${SMALL[@]}" --seed 42 --sampler sobol -o "m.$ext" --quiet
        missing=""
        for s in caustic.version caustic.command caustic.scene_sha256 "$sum" caustic.integrator \
                 caustic.sampler sobol caustic.seed caustic.spp caustic.render_seconds \
                 "render $scene --width 16"; do
            grep -aqF -- "$s" "$d/m.$ext" || missing="$missing '$s'"
        done
        if [ "$RC" -eq 0 ] && [ -z "$missing" ]; then pass "$ext output carries the caustic.* metadata and the scene's SHA-256"
        else fail "$ext output carries the caustic.* metadata and the scene's SHA-256" "exit $RC; missing:$missing"; fi
    done
fi

harness_finish
