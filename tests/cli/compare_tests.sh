#!/usr/bin/env bash
# caustic compare A B (issue 26): the table and --json on renders of the built-in Cornell
# box, identical images (zero difference and FLIP 0), LDR-FLIP for two PNGs and HDR-FLIP
# otherwise, z-scores from the variance AOV and from --variance-a/-b, the --map file, and
# the exit codes: 2 for images of different sizes, missing or unreadable files, bad options
# and a map path that cannot be written; nothing partial left behind.
# Run by CTest:
#   bash compare_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init compare_tests "$@"
HARNESS_EXPECT_STDOUT=1

if ! command -v python3 >/dev/null; then
    echo "compare_tests: python3 is needed to read the JSON reports; skipped"
    echo "0 passed, 0 failed"
    exit 0
fi

run() { harness_run "$TMP" 300 "$@"; }

# json_get EXPR: evaluates a Python expression over the JSON on stdout (j).
json_get() {
    python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print($1)" "$OUT"
}

render() { # NAME SEED [SPP] [extra]
    local name=$1 seed=$2 spp=${3:-8}
    shift 3
    (cd "$TMP" && "$BIN" render --width 48 --height 32 --spp "$spp" --seed "$seed" -q -o "$name" "$@" \
        >/dev/null 2>&1)
}

render a.exr 1 8 --aov variance && render b.exr 2 8 --aov variance && render c.exr 3 64 &&
    render a.png 1 8 && render b.png 2 64 && render small.exr 1 8 --width 40 &&
    render a.pfm 1 8 || { echo "compare_tests: could not render the inputs"; exit 1; }

# ---------------------------------------------------------------- the report
run compare a.exr b.exr
expect "two EXRs: table with means, RMSE, relMSE, HDR-FLIP and z from the variance AOVs" 0 \
    '^r +[0-9.e+-]+ +[0-9.e+-]+' 'relMSE: +mean of \(a - b\)\^2 / \(b\^2 \+ 0\.01\)' 'HDR-FLIP: [0-9]+ exposure' \
    "variances of A: A's variance AOV; of B: B's variance AOV" 'max \|z\| [0-9.]+'

run compare a.exr a.exr --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['rmse'], j['relmse'], j['flip']['mean'], j['channels'][1]['diff'], j['z']['max_abs_z']")" = "0.0 0.0 0.0 0.0 0.0" ]; then
    pass "identical images: RMSE, relMSE, FLIP, difference and |z| all 0"
else fail "identical images give zeros" "exit $RC: $(head -c 600 "$OUT")"; fi

run compare a.png b.png --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['flip']['kind'], j['z'] is None, len(j['channels'])")" = "ldr True 3" ]; then
    pass "two PNGs: LDR-FLIP, no variances"
else fail "two PNGs: LDR-FLIP" "exit $RC: $(head -c 600 "$OUT")"; fi

run compare a.png b.png --flip hdr --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['flip']['kind'], j['flip']['exposures'] >= 1")" = "hdr True" ]; then
    pass "--flip hdr forces HDR-FLIP"
else fail "--flip hdr" "exit $RC: $(head -c 600 "$OUT")"; fi

# A noisy render against a converged one: the 8 spp render's own variances are the
# only noise, so |z| stays moderate (a 4-sigma block among 6 x 3 tests: p ~ 1e-3).
run compare a.exr c.exr --json
if [ "$RC" -eq 0 ] && python3 - "$OUT" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
z = j["z"]
assert z["variance_a"] == "A's variance AOV" and z["variance_b"] is None, z
assert z["blocks"] == 3 * 2 and z["max_abs_z"] < 4.5 and z["above"] <= 1, z
assert all(abs(c["rel_diff"]) < 0.2 for c in j["channels"]), j["channels"]
assert 0.0 < j["flip"]["mean"] < 0.5 and j["relmse_eps"] == 0.01
PY
then pass "8 spp against 64 spp of the same scene: block |z| < 4.5, means within 20%"
else fail "8 spp against 64 spp" "exit $RC: $(head -c 600 "$OUT")"; fi

# --variance-b given as the EXR that holds the AOV; a PFM of the variances is read as RGB.
run compare a.pfm c.exr --variance-a a.exr --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['z']['variance_a']")" = "the variance AOV of the file given" ]; then
    pass "--variance-a names an EXR: its variance AOV is read"
else fail "--variance-a EXR" "exit $RC: $(head -c 600 "$OUT")"; fi
run compare a.pfm c.exr --variance-a a.pfm --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['z']['variance_a']")" = "the image given" ]; then
    pass "--variance-a names a plain image: its RGB are the variances"
else fail "--variance-a plain image" "exit $RC: $(head -c 600 "$OUT")"; fi

# A Radiance HDR (RGBE) and a PFM holding the same values (1 and 0.5 per row; rows equal, so
# PFM's bottom-up order does not matter) compare as identical.
python3 - "$TMP" <<'PY'
import struct, sys
d = sys.argv[1]
# RGBE (128, 128, 128, 129) = 1.0, (64, 64, 64, 129) = 0.5: m * 2^(e - 136)
row = bytes([128, 128, 128, 129, 64, 64, 64, 129])
open(f"{d}/t.hdr", "wb").write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n" + row + row)
px = struct.pack("<6f", 1, 1, 1, 0.5, 0.5, 0.5)
open(f"{d}/t.pfm", "wb").write(b"PF\n2 2\n-1.0\n" + px + px)
PY
run compare t.hdr t.pfm --json
if [ "$RC" -eq 0 ] && [ "$(json_get "j['rmse'], j['channels'][0]['mean_a'], j['flip']['mean']")" = "0.0 0.75 0.0" ]; then
    pass "a Radiance HDR file reads as the same values as a PFM"
else fail "Radiance HDR input" "exit $RC: $(head -c 600 "$OUT")"; fi

# ---------------------------------------------------------------- the map
run compare a.exr b.exr --map "$TMP/flip.png"
if [ "$RC" -eq 0 ] && [ -s "$TMP/flip.png" ] && [ -z "$(find "$TMP" -name '*.tmp*')" ]; then
    pass "--map writes the FLIP map (no temporary left)"
else fail "--map writes the map" "exit $RC"; fi
run compare a.exr b.exr --map "$TMP/flip.exr" --json
if [ "$RC" -eq 0 ] && [ -s "$TMP/flip.exr" ] && (cd "$TMP" && "$BIN" compare flip.exr a.exr >/dev/null 2>&1); then
    pass "--map to EXR is a readable image of the same size"
else fail "--map to EXR" "exit $RC"; fi
run compare a.exr b.exr --map "$TMP/no-such-dir/flip.png"
expect "--map into a missing directory: exit 2 before comparing" 2 '--map'
run compare a.exr b.exr --map "$TMP/flip.txt"
expect "--map with an unknown extension: exit 2" 2 '--map'

# ---------------------------------------------------------------- errors
run compare a.exr small.exr
expect "images of different sizes: exit 2 naming both sizes" 2 'differ in size: a\.exr is 48x32, small\.exr is 40x32'
run compare a.exr c.exr --variance-b small.exr
expect "variances of another size: exit 2" 2 'variance-b: small\.exr is 40x32'
run compare a.exr missing.exr
expect "missing image: exit 2" 2 'missing\.exr'
printf 'not an image' >"$TMP/junk.exr"
run compare a.exr junk.exr
expect "unreadable image: exit 2" 2 'junk\.exr'
run compare a.exr
expect "one image only: exit 2" 2 'expected two images'
run compare a.exr b.exr c.exr
expect "three images: exit 2" 2 "unexpected argument 'c\.exr'"
run compare a.exr b.exr --flip sdr
expect "--flip with an unknown kind: exit 2" 2 "--flip: expected ldr, hdr or auto"
run compare a.exr b.exr --blok 8
expect "misspelt option: exit 2 with a suggestion" 2 "did you mean --block"
run compare a.exr b.exr --ppd 0
expect "--ppd 0: exit 2" 2 "--ppd: expected pixels per degree"
run compare --help
expect "compare --help documents the exit codes" 0 'Exit status: 0 the comparison was made' 'relMSE'
run help compare
expect "caustic help compare" 0 'Image comparison: caustic compare A B'

# ---------------------------------------------------------------- the corpus script
# scripts/pbrt-corpus.sh skips cleanly without the collection, and runs end to end on a
# one-scene collection (scenes/cornell-box.pbrt) when pbrt-v4 is there.
SRC=$(realpath "$2")
(cd "$TMP" && python3 "$SRC/scripts/pbrt-corpus.py" --caustic "$BIN" --scenes "$TMP/no-scenes" \
    --cache "$TMP/cache" >"$OUT" 2>"$ERR")
RC=$?
expect "pbrt-corpus.sh without the scene collection: skipped, exit 0" 0 'skipped: no scene collection'
PBRT=${CST_PBRT:-$SRC/../shared/tools/pbrt-v4/pbrt}
if [ -x "$PBRT" ]; then
    mkdir -p "$TMP/corpus/cornell" && cp "$SRC/scenes/cornell-box.pbrt" "$TMP/corpus/cornell/"
    (cd "$TMP" && timeout 600 python3 "$SRC/scripts/pbrt-corpus.py" --caustic "$BIN" --pbrt "$PBRT" \
        --scenes "$TMP/corpus" --cache "$TMP/cache" --size 24 --spp 2 --timeout 120 >"$OUT" 2>"$ERR")
    RC=$?
    row=$(grep '^| cornell/cornell-box.pbrt |' "$OUT")
    if [ "$RC" -eq 0 ] && [ -n "$row" ] && echo "$row" | grep -Eq '\| ok \| ok \| .* \| ok [0-9.]+ s, [^|]* MiB \| .* \| [0-9.]+ \(hdr\) \|$'; then
        pass "pbrt-corpus.sh on the Cornell box: loads, renders in both, compares"
    else fail "pbrt-corpus.sh on the Cornell box" "exit $RC" "row: $row"; fi
else
    echo "SKIP: pbrt-corpus.sh end to end: no pbrt-v4 at $PBRT"
fi

harness_finish
