# The harness the CLI test scripts (tests/cli/*_tests.sh) share: their arguments, a scratch
# directory removed at exit, PASS/FAIL/SKIP counts, caustic run under a time limit, checks of
# exit status and messages. Each script starts with
#   . "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
#   harness_init NAME "$@"
# and ends with harness_finish.

# harness_init NAME BINARY SOURCE-DIR [...]: sets BIN and SRC (absolute), TMP (a new
# directory, removed at exit), OUT and ERR (caustic's stdout and stderr of the last run),
# RC and the counters; exits 2 on a usage error. Further arguments are the script's own.
harness_init() {
    HARNESS_NAME=$1
    shift
    if [ $# -lt 2 ]; then
        echo "usage: bash ${HARNESS_NAME}.sh <path-to-caustic-binary> <source-dir> ..." >&2
        exit 2
    fi
    BIN=$(realpath "$1")
    SRC=$(realpath "$2")
    if [ ! -x "$BIN" ]; then
        echo "$HARNESS_NAME: not an executable: $BIN" >&2
        exit 2
    fi
    TMP=$(mktemp -d "${TMPDIR:-/tmp}/caustic-$HARNESS_NAME.XXXXXX")
    trap 'rm -rf "$TMP"' EXIT
    OUT=$TMP/.stdout
    ERR=$TMP/.stderr
    : >"$OUT"
    : >"$ERR"
    RC=0
    passed=0
    failed=0
    skipped=0
}

# harness_display: sets RUNNER, the command prefix for a program that opens a window. One
# Xvfb server for the whole script (Debian's xvfb, installed by scripts/install-deps.sh),
# on a display it picks itself (-displayfd), stopped at exit: xvfb-run per window started a
# server each time (1-3 s) and, on a loaded machine, could fail its own clean-up (exit 5)
# after the program had ended well. Without Xvfb, SDL's dummy video driver runs the same
# code without a display.
harness_display() {
    RUNNER=(env SDL_VIDEODRIVER=dummy)
    command -v Xvfb >/dev/null 2>&1 || { echo "$HARNESS_NAME: no Xvfb: SDL's dummy video driver"; return 0; }
    Xvfb -displayfd 3 -screen 0 1024x768x24 -nolisten tcp 3>"$TMP/.display" >"$TMP/.xvfb.log" 2>&1 &
    HARNESS_XVFB=$!
    trap 'kill "$HARNESS_XVFB" 2>/dev/null; wait "$HARNESS_XVFB" 2>/dev/null; rm -rf "$TMP"' EXIT
    local i
    for i in $(seq 300); do
        [ -s "$TMP/.display" ] && break
        kill -0 "$HARNESS_XVFB" 2>/dev/null || break
        sleep 0.1
    done
    if [ ! -s "$TMP/.display" ]; then
        echo "$HARNESS_NAME: Xvfb did not start ($(tail -n 1 "$TMP/.xvfb.log")): SDL's dummy video driver"
        return 0
    fi
    local display=":$(head -n 1 "$TMP/.display")"
    RUNNER=(env DISPLAY="$display")
    echo "$HARNESS_NAME: under Xvfb, display $display"
}

pass() { echo "PASS: $1"; passed=$((passed + 1)); }
skip() { echo "SKIP: $1"; skipped=$((skipped + 1)); }

# fail NAME [LINE ...]: a FAIL line, the given lines, then the last run's output (control
# bytes shown by cat -v, so a message with escapes cannot garble the log).
fail() {
    echo "FAIL: $1"
    shift
    local line
    for line in "$@"; do echo "      $line"; done
    if [ -s "$OUT" ]; then echo "      stdout: $(head -c 600 "$OUT" | cat -v)"; fi
    if [ -s "$ERR" ]; then echo "      stderr: $(head -c 1200 "$ERR" | cat -v)"; fi
    failed=$((failed + 1))
}

# check NAME COMMAND...: PASS when COMMAND succeeds.
check() {
    local name=$1
    shift
    if "$@"; then pass "$name"; else fail "$name"; fi
}

# harness_run DIR SECONDS ARGS...: caustic ARGS in DIR (created if missing), stdin from
# /dev/null, killed after SECONDS (so a read without end or a render that does not stop
# fails its test instead of hanging the suite); sets RC, OUT, ERR.
harness_run() {
    local dir=$1 limit=$2
    shift 2
    mkdir -p "$dir"
    (cd "$dir" && timeout -k 5 "$limit" "$BIN" "$@" >"$OUT" 2>"$ERR" </dev/null)
    RC=$?
}

# expect NAME RC [ERE ...]: the last run exited with RC and every ERE is found in its stderr
# (and in its stdout too when HARNESS_EXPECT_STDOUT=1).
expect() {
    local name=$1 want=$2
    shift 2
    if [ "$RC" -ne "$want" ]; then
        local why=""
        [ "$RC" -eq 124 ] && why=" (timed out)"
        [ "$RC" -gt 128 ] && why=" (killed by signal $((RC - 128)))"
        fail "$name" "exit code $RC$why, expected $want"
        return 1
    fi
    local re where=stderr
    [ "${HARNESS_EXPECT_STDOUT:-0}" = 1 ] && where="stdout or stderr"
    for re in "$@"; do
        if [ "${HARNESS_EXPECT_STDOUT:-0}" = 1 ]; then
            cat "$OUT" "$ERR" | grep -Eq -- "$re" && continue
        else
            grep -Eq -- "$re" "$ERR" && continue
        fi
        fail "$name" "$where does not match /$re/"
        return 1
    done
    pass "$name"
}

# harness_finish: the summary line; the script's exit status is 0 when nothing failed.
harness_finish() {
    if [ "$skipped" -gt 0 ]; then
        echo "$passed passed, $failed failed, $skipped skipped"
    else
        echo "$passed passed, $failed failed"
    fi
    [ "$failed" -eq 0 ]
}
