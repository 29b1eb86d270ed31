#!/usr/bin/env bash
# Tests of the caustic command-line tool: usage errors and exit codes, strict option
# parsing, scene diagnostics (file:line:col, no image written), tiny renders to each
# format, and progress output. Run by CTest:
#   bash cli_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init cli_tests "$@"

# run DIR ARGS...: runs caustic in DIR; sets RC, OUT, ERR. The timeout guards against an
# option silently accepted and a full render started.
run() { local dir=$1; shift; harness_run "$dir" 300 "$@"; }

# no_images DIR: true when DIR holds no image (nor a temporary left by a writer).
no_images() {
    [ -z "$(find "$1" -maxdepth 2 -type f \( -name '*.png' -o -name '*.exr' -o -name '*.pfm' \
        -o -name '*.tmp*' -o -name '*.png.*' -o -name '*.exr.*' -o -name '*.pfm.*' \) -print -quit)" ]
}

# magic FILE: the first bytes as hex.
magic() { od -An -tx1 -N"$2" "$1" | tr -d ' \n'; }

# --------------------------------------------------------------- help and version
run "$TMP/help" --help
expect "--help exits 0" 0
if [ -s "$ERR" ]; then fail "--help writes nothing to stderr"; else pass "--help writes nothing to stderr"; fi
missing=""
for opt in render SCENE -o --output --spp --time --threads --seed --integrator --filter \
           --sampler --max-depth --subsurface --exposure --png-linear --aov --crop --width --height --quiet --help --version \
           path path-nee path-bsdf box tent .png .exr .pfm cornell-box.png "Exit status"; do
    grep -qF -- "$opt" "$OUT" || missing="$missing $opt"
done
if [ -z "$missing" ]; then pass "--help mentions every option, value and exit codes"
else fail "--help mentions every option, value and exit codes" "missing:$missing"; fi
for code in 0 1 2; do
    if grep -Eq "^ +$code +[a-z]" "$OUT"; then pass "--help documents exit code $code"
    else fail "--help documents exit code $code"; fi
done

run "$TMP/help" -h
expect "-h exits 0" 0 && { grep -q -- "--spp" "$OUT" || fail "-h prints the usage"; }
run "$TMP/help" render --help
expect "render --help exits 0" 0 && { grep -q -- "--integrator" "$OUT" || fail "render --help prints the usage"; }

run "$TMP/version" --version
if [ "$RC" -eq 0 ] && [ "$(head -1 "$OUT")" = "caustic 0.1.0" ]; then pass "--version prints 'caustic 0.1.0'"
else fail "--version prints 'caustic 0.1.0'" "exit $RC"; fi

# --------------------------------------------------------------- usage errors
run "$TMP/usage"
expect "no command: exit 2 with a hint" 2 "see caustic --help"
run "$TMP/usage" frobnicate
expect "unknown command: exit 2 with a hint" 2 "frobnicate" "see caustic --help"
run "$TMP/usage" --bogus
expect "unknown top-level option: exit 2 with a hint" 2 "'--bogus'" "see caustic --help"
run "$TMP/usage" render --bogus
expect "unknown render option: exit 2 with a hint" 2 "unknown option '--bogus'" "see caustic --help"
run "$TMP/usage" render --sp 4
expect "misspelt option: suggests the right one" 2 "did you mean --spp" "see caustic --help"
run "$TMP/usage" render -x
expect "unknown short option: exit 2" 2 "'-x'" "see caustic --help"
run "$TMP/usage" render --spp
expect "option without its value: exit 2" 2 "--spp: missing value"
run "$TMP/usage" render --quiet=yes
expect "flag given a value: exit 2" 2 "--quiet"
run "$TMP/usage" render a.json b.json
expect "two scenes: exit 2" 2 "b.json"
if no_images "$TMP/usage"; then pass "usage errors write no image"; else fail "usage errors write no image"; fi

# --------------------------------------------------------------- strict numbers
# check_value NAME ARGS... -- ERE: exit 2, message matching ERE, nothing rendered.
check_value() {
    local name=$1
    shift
    local args=()
    while [ "$1" != "--" ]; do args+=("$1"); shift; done
    run "$TMP/values" render "${args[@]}" -o v.png
    expect "$name" 2 "$2"
}
check_value "--spp 0 rejected"        --spp 0         -- "^caustic: --spp: expected a positive integer, got '0'$"
check_value "--spp abc rejected"      --spp abc       -- "^caustic: --spp: expected a positive integer, got 'abc'$"
check_value "--spp=abc rejected"      --spp=abc       -- "^caustic: --spp: expected a positive integer, got 'abc'$"
check_value "--spp 4x rejected"       --spp 4x        -- "--spp: .*got '4x'"
check_value "--spp -3 rejected"       --spp -3        -- "--spp: .*got '-3'"
check_value "--spp 2.5 rejected"      --spp 2.5       -- "--spp: .*got '2.5'"
check_value "--spp '' rejected"       --spp=          -- "--spp: .*got ''"
check_value "--spp overflow rejected" --spp 99999999999999999999 -- "--spp: .*got '99999999999999999999'"
check_value "--threads -1 rejected"   --threads -1    -- "^caustic: --threads: expected .*got '-1'$"
check_value "--threads 1025 rejected" --threads 1025  -- "--threads: .*got '1025'"
check_value "--width 0 rejected"      --width 0       -- "^caustic: --width: expected an integer from 1 to 65536, got '0'$"
check_value "--height 65537 rejected" --height 65537  -- "--height: .*got '65537'"
check_value "--width ' 8' rejected"   --width " 8"    -- "--width: .*got ' 8'"
check_value "--time 0 rejected"       --time 0        -- "^caustic: --time: expected .*got '0'$"
check_value "--time -1 rejected"      --time -1       -- "--time: .*got '-1'"
check_value "--time nan rejected"     --time nan      -- "--time: .*got 'nan'"
check_value "--time inf rejected"     --time inf      -- "--time: .*got 'inf'"
check_value "--time 1e999 rejected"   --time 1e999    -- "--time: .*got '1e999'"
check_value "--time 5s rejected"      --time 5s       -- "--time: .*got '5s'"
check_value "--seed -1 rejected"      --seed -1       -- "^caustic: --seed: expected .*got '-1'$"
check_value "--seed 2^64 rejected"    --seed 18446744073709551616 -- "--seed: .*got '18446744073709551616'"
check_value "--seed 0x rejected"      --seed 0x       -- "--seed: .*got '0x'"
check_value "unknown integrator lists the valid ones" --integrator metropolis -- \
    "--integrator: .*'metropolis'.*path, path-nee, path-bsdf"
check_value "unknown filter lists the valid ones"     --filter lanczos -- \
    "--filter: .*'lanczos'.*box, tent, gaussian, mitchell"
check_value "unknown sampler lists the valid ones"    --sampler halton -- \
    "--sampler: .*'halton'.*independent, stratified, sobol"
check_value "--exposure abc rejected" --exposure abc  -- "^caustic: --exposure: expected .*got 'abc'$"
check_value "--exposure 100 rejected" --exposure 100  -- "--exposure: .*got '100'"
check_value "unknown AOV lists the valid ones"        --aov albedo,uv -- \
    "--aov: unknown AOV 'uv'.*albedo, normal, depth, variance"
check_value "--crop with three numbers rejected"      --crop 1,2,3 -- \
    "^caustic: --crop: expected X0,X1,Y0,Y1: four integers .*got '1,2,3'$"
check_value "--crop empty rejected"                   --crop 4,4,0,8 -- "--crop: expected X0 < X1 and Y0 < Y1"
check_value "--crop outside the image rejected"       --crop 0,8,0,900 -- "error: crop .0, 8. x .0, 900.: expected 0 <= x0"
check_value "--aov with a PNG output rejected"        --aov depth -- \
    "output 'v\.png': AOVs .*expected an output ending in \.exr"
if no_images "$TMP/values"; then pass "rejected values write no image"; else fail "rejected values write no image"; fi

# --------------------------------------------------------------- output path checks
run "$TMP/badout" render --spp 1 -o out.jpg
expect "bad output extension: exit 2 naming the formats" 2 "out.jpg" "\.png" "\.exr" "\.pfm"
[ -e "$TMP/badout/out.jpg" ] && fail "bad output extension: no file created" || pass "bad output extension: no file created"
run "$TMP/badout" render --spp 1 -o out
expect "output without extension: exit 2" 2 "'out'"
run "$TMP/badout" render --spp 1 -o nodir/out.png
expect "output in a missing directory: exit 2 before rendering" 2 "nodir"
if grep -q "rendering" "$ERR"; then fail "missing output directory is caught before rendering"
else pass "missing output directory is caught before rendering"; fi
if no_images "$TMP/badout"; then pass "bad outputs write no image"; else fail "bad outputs write no image"; fi

# --------------------------------------------------------------- scene files
run "$TMP/scenes" render scene.obj
expect "unsupported scene format: exit 2 naming .json" 2 "scene.obj" "\.json"
run "$TMP/scenes" render no-such-scene.json
expect "missing scene file: exit 2 naming the file" 2 "^caustic: error: .*no-such-scene\.json"
mkdir -p "$TMP/scenes/dir.json"
run "$TMP/scenes" render dir.json
expect "directory as scene: exit 2" 2 "dir\.json"

# Each bad scene is the valid one below with one defect; the loader must name
# file:line:col, the CLI must prefix "caustic: error: ", exit 2 and write nothing.
VALID_SCENE='{
  "film": {"width": 16, "height": 16},
  "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
  "materials": {
    "white": {"type": "diffuse", "albedo": [0.8, 0.8, 0.8]}
  },
  "shapes": [
    {"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "white"},
    {"type": "mesh", "vertices": [[-1, 3, -1], [1, 3, -1], [0, 3, 1]], "indices": [[0, 1, 2]],
     "material": "white", "emission": {"radiance": [10, 10, 10]}}
  ]
}'
# bad_scene NAME LINE ERE TEXT: the error is located on LINE and mentions ERE (what is wrong).
bad_scene() {
    local name=$1 line=$2 what=$3 text=$4
    local dir=$TMP/bad-$name
    mkdir -p "$dir"
    printf '%s\n' "$text" >"$dir/$name.json"
    run "$dir" render "$name.json"
    if expect "bad scene ($name): exit 2, file.json:LINE:COL" 2 \
        '\.json:[0-9]+:[0-9]+:' "^caustic: error: $name\.json:$line:[0-9]+: " "$what"; then
        if no_images "$dir"; then pass "bad scene ($name): no image written"
        else fail "bad scene ($name): no image written" "found: $(ls "$dir")"; fi
    fi
}
bad_scene syntax-error 3 "."                "${VALID_SCENE/\"fov\": 40\}/\"fov\": 40,\}}"
bad_scene unknown-key 8 "colour"            "${VALID_SCENE/\"radius\": 1,/\"radius\": 1, \"colour\": 3,}"
bad_scene wrong-type 8 "radius"             "${VALID_SCENE/\"radius\": 1,/\"radius\": \"one\",}"
bad_scene degenerate-triangle 9 "degenerate" "${VALID_SCENE/\[0, 3, 1\]/[2, 3, -1]}"
bad_scene negative-radius 8 "radius"        "${VALID_SCENE/\"radius\": 1,/\"radius\": -1,}"
bad_scene huge-number 8 "1e999|overflow|range" "${VALID_SCENE/\"radius\": 1,/\"radius\": 1e999,}"

# A syntax error is located on its line: a missing comma between two keys on line 3.
dir=$TMP/bad-line
mkdir -p "$dir"
printf '{\n  "film": {"width": 16, "height": 16},\n  "materials": {} "shapes": []\n}\n' >"$dir/line.json"
run "$dir" render line.json
expect "syntax error names line 3" 2 "line\.json:3:[0-9]+:"

# The valid scene renders; default output <stem>.png in the current directory.
dir=$TMP/good-scene
mkdir -p "$dir/sub"
printf '%s\n' "$VALID_SCENE" >"$dir/sub/tiny.scene.json"
run "$dir" render --spp 1 -- sub/tiny.scene.json
if expect "valid scene renders: exit 0" 0 "wrote tiny\.scene\.png"; then
    [ -s "$dir/tiny.scene.png" ] && pass "scene default output is <stem>.png in the current directory" \
        || fail "scene default output is <stem>.png in the current directory" "found: $(ls "$dir")"
fi
# The scene's "output" is used when -o is absent.
printf '%s\n' "${VALID_SCENE/\"film\": \{/\"film\": {\"output\": \"from-scene.pfm\", }" >"$dir/out.json"
run "$dir" render out.json --spp 1
if expect "scene output key: exit 0" 0; then
    if [ -s "$dir/from-scene.pfm" ]; then pass "scene output key names the image"
    else fail "scene output key names the image" "found: $(ls -R "$dir")"; fi
fi
printf '%s\n' "${VALID_SCENE/\"film\": \{/\"film\": {\"output\": \"from-scene.bmp\", }" >"$dir/badext.json"
run "$dir" render badext.json --spp 1
expect "scene output with a bad extension: exit 2 before rendering" 2 "from-scene\.bmp"
[ -e "$dir/from-scene.bmp" ] && fail "scene output with a bad extension: no file" || pass "scene output with a bad extension: no file"

# --------------------------------------------------------------- pbrt scenes
# A pbrt scene renders by extension; what is skipped is a located warning, not an error.
dir=$TMP/pbrt
mkdir -p "$dir"
cat >"$dir/tiny.pbrt" <<'PBRT'
Film "rgb" "integer xresolution" 16 "integer yresolution" 16
LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" 40
WorldBegin
LightSource "sky" "rgb I" [1 1 1]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [10 10 10]
  Shape "trianglemesh" "point3 P" [-1 3 -1  1 3 -1  0 3 1] "integer indices" [0 2 1]
AttributeEnd
Shape "sphere" "float radius" 1
PBRT
run "$dir" render --spp 1 tiny.pbrt
if expect "pbrt scene renders: exit 0, located warning" 0 \
    '^caustic: warning: tiny\.pbrt:5:1: LightSource "sky" is not supported'; then
    [ -s "$dir/tiny.png" ] && pass "pbrt scene default output <stem>.png" \
        || fail "pbrt scene default output <stem>.png" "found: $(ls "$dir")"
fi
run "$dir" render --spp 1 -q -o cb.png "$SRC/scenes/cornell-box.pbrt"
expect "scenes/cornell-box.pbrt renders without warnings" 0
if [ -s "$ERR" ]; then fail "scenes/cornell-box.pbrt: no warnings" "stderr: $(cat "$ERR")"
else pass "scenes/cornell-box.pbrt: no warnings"; fi
# A gzip-compressed main file (x.pbrt.gz), which pbrt-v4 reads: render, info and verify
# accept it; the image equals the uncompressed file's; the default output is x.png.
gzip -c "$dir/tiny.pbrt" >"$dir/tinygz.pbrt.gz"
run "$dir" render --spp 1 tinygz.pbrt.gz
if expect "pbrt.gz scene renders: exit 0, warning located in it" 0 \
    '^caustic: warning: tinygz\.pbrt\.gz:5:1: LightSource "sky" is not supported'; then
    [ -s "$dir/tinygz.png" ] && pass "pbrt.gz scene default output <stem>.png (x.pbrt.gz: x.png)" \
        || fail "pbrt.gz scene default output <stem>.png (x.pbrt.gz: x.png)" "found: $(ls "$dir")"
fi
run "$dir" render --spp 2 -q -o plain.pfm tiny.pbrt
run "$dir" render --spp 2 -q -o gz.pfm tinygz.pbrt.gz
if [ "$RC" -eq 0 ] && cmp -s "$dir/plain.pfm" "$dir/gz.pfm"; then pass "pbrt.gz renders as the uncompressed file"
else fail "pbrt.gz renders as the uncompressed file" "exit $RC"; fi
run "$dir" info tinygz.pbrt.gz
expect "info reads a .pbrt.gz scene" 0
run "$dir" verify --integrators path,path-nee --spp 4 --width 16 --height 16 --block 8 --threads 2 tinygz.pbrt.gz
expect "verify reads a .pbrt.gz scene" 0
printf 'not gzip' >"$dir/bad.pbrt.gz"
run "$dir" render --spp 1 bad.pbrt.gz
expect "corrupt .pbrt.gz: exit 2, named" 2 "bad\.pbrt\.gz"

# --max-depth: 2 is the scene's own limit; 0 overrides it with "unbounded".
sed 's/"max_depth": 0/"max_depth": 2/' "$SRC/scenes/cornell-spheres.json" >"$dir/depth2.json"
run "$dir" render --spp 1 --width 32 --height 32 -q -o d-scene.pfm depth2.json
run "$dir" render --spp 1 --width 32 --height 32 -q --max-depth 2 -o d2.pfm depth2.json
run "$dir" render --spp 1 --width 32 --height 32 -q --max-depth 0 -o d0.pfm depth2.json
expect "--max-depth 0 renders" 0
if cmp -s "$dir/d-scene.pfm" "$dir/d2.pfm" && ! cmp -s "$dir/d2.pfm" "$dir/d0.pfm"; then
    pass "--max-depth 2 = the scene's limit; --max-depth 0 overrides it (unbounded)"
else fail "--max-depth 2 = the scene's limit; --max-depth 0 overrides it (unbounded)"; fi
run "$dir" render --max-depth -1 -o x.png
expect "--max-depth -1 is rejected" 2 "--max-depth: expected an integer from 0"
# --subsurface walk|bssrdf (render and verify); a scene without subsurface renders the same.
run "$dir" render --subsurface diffusion -o x.png
expect "--subsurface diffusion is rejected" 2 "--subsurface: expected walk or bssrdf, got 'diffusion'"
run "$dir" render --spp 1 --width 32 --height 32 -q --max-depth 2 --subsurface walk -o d2w.pfm depth2.json
if cmp -s "$dir/d2.pfm" "$dir/d2w.pfm"; then pass "--subsurface walk: a scene without subsurface renders the same"
else fail "--subsurface walk: a scene without subsurface renders the same"; fi
run "$dir" verify --subsurface maybe --integrators path,bdpt
expect "verify --subsurface maybe is rejected" 2 "--subsurface: expected walk or bssrdf"
sed 's/"float fov" 40/"integer fov" 40/' "$dir/tiny.pbrt" >"$dir/badtype.pbrt"
run "$dir" render --spp 1 badtype.pbrt
expect "pbrt wrong parameter type: exit 2, file:line:col" 2 \
    '^caustic: error: badtype\.pbrt:3:22: Camera "perspective": parameter "integer fov" has type integer; expected float'
printf 'WorldBegin\nShape "plymesh" "string filename" "missing.ply"\n' >"$dir/noply.pbrt"
run "$dir" render --spp 1 noply.pbrt
expect "pbrt missing PLY: exit 2, located" 2 '^caustic: error: noply\.pbrt:2:17: Shape "plymesh": .*missing\.ply'
printf 'WorldBegin\nShape "sphere" "float radius" [1\n' >"$dir/open.pbrt"
run "$dir" render --spp 1 open.pbrt
expect "pbrt unbalanced bracket: exit 2, located" 2 '^caustic: error: open\.pbrt:3:1: .*expected .\]. to close'
[ -e "$dir/badtype.png" ] || [ -e "$dir/noply.png" ] || [ -e "$dir/open.png" ] \
    && fail "bad pbrt scenes write no image" || pass "bad pbrt scenes write no image"

# --------------------------------------------------------------- tiny renders
dir=$TMP/render
run "$dir" render --width 16 --height 16 --spp 2 -o out.png
if expect "render to PNG: exit 0" 0 "^caustic: wrote out\.png: 16x16, 2 spp, "; then
    [ "$(magic "$dir/out.png" 8)" = "89504e470d0a1a0a" ] && pass "PNG file has the PNG signature" \
        || fail "PNG file has the PNG signature" "got $(magic "$dir/out.png" 8)"
    [ "$(magic "$dir/out.png" 24 | cut -c33-48)" = "0000001000000010" ] && pass "PNG is 16x16" \
        || fail "PNG is 16x16" "IHDR $(magic "$dir/out.png" 24)"
fi
run "$dir" render --width 16 --height 16 --spp 2 -o out.exr
if expect "render to EXR: exit 0" 0 "wrote out\.exr"; then
    [ "$(magic "$dir/out.exr" 4)" = "762f3101" ] && pass "EXR file has the OpenEXR magic" \
        || fail "EXR file has the OpenEXR magic" "got $(magic "$dir/out.exr" 4)"
fi
run "$dir" render --width 16 --height 16 --spp 4 --sampler sobol --exposure -1.5 --png-linear \
    --aov albedo,normal,depth,variance -o aov.exr
expect "sobol render with exposure and AOVs to EXR: exit 0" 0 "wrote aov\.exr"
run "$dir" render --width 16 --height 16 --spp 2 --crop 2,12,5,9 -o crop.pfm
if expect "cropped render: exit 0" 0 "wrote crop\.pfm: 10x4"; then
    [ "$(head -c 8 "$dir/crop.pfm" | tr '\n' ' ')" = "PF 10 4 " ] && pass "cropped PFM is 10x4" \
        || fail "cropped PFM is 10x4" "got $(head -c 12 "$dir/crop.pfm" | od -c | head -2)"
fi
run "$dir" render --width 16 --height 16 --spp 2 -o out.pfm
if expect "render to PFM: exit 0" 0 "wrote out\.pfm"; then
    [ "$(head -c 9 "$dir/out.pfm" | tr '\n' ' ')" = "PF 16 16 " ] && pass "PFM header is 'PF 16 16'" \
        || fail "PFM header is 'PF 16 16'" "got $(head -c 12 "$dir/out.pfm" | od -c | head -2)"
fi
run "$dir" render --width=16 --height=16 --spp=2 --output=eq.png --seed=0xffffffffffffffff \
    --threads=1 --integrator=path-nee --filter=tent
if expect "--opt=value forms accepted" 0 "wrote eq\.png: 16x16, 2 spp, path-nee, 1 thread,"; then
    [ -s "$dir/eq.png" ] && pass "--output=FILE writes FILE" || fail "--output=FILE writes FILE"
fi
run "$dir" render --width 8 --height 8 --spp 1 --integrator path-bsdf --seed 18446744073709551615 \
    --threads 0 --filter box -o dash.png
expect "--opt value forms accepted" 0 "wrote dash\.png: 8x8, 1 spp, path-bsdf, "
dir=$TMP/default
run "$dir" render --width 8 --height 8 --spp 1
if expect "built-in scene render: exit 0" 0 "wrote cornell-box\.png"; then
    [ -s "$dir/cornell-box.png" ] && pass "built-in scene default output is cornell-box.png" \
        || fail "built-in scene default output is cornell-box.png" "found: $(ls "$dir")"
fi

# Job line first, summary line last, with throughput.
dir=$TMP/lines
run "$dir" render --width 16 --height 16 --spp 2 --threads 2 -o lines.png
expect "job line names scene, size, spp, integrator, threads" 0 \
    "^caustic: rendering .*Cornell box.*16x16.*2 spp.*path.*2 threads"
if [ "$(tail -n 1 "$ERR" | grep -Ec '^caustic: wrote lines\.png: 16x16, 2 spp, path, 2 threads, [0-9.]+ s(, [0-9.]+ M samples/s, [0-9.]+ M rays/s)?$')" -eq 1 ]; then
    pass "summary line is last and complete"
else fail "summary line is last and complete" "last: $(tail -n 1 "$ERR")"; fi
if [ -s "$OUT" ]; then fail "a render writes nothing to stdout"; else pass "a render writes nothing to stdout"; fi

# --------------------------------------------------------------- progress
dir=$TMP/progress
run "$dir" render --width 32 --height 32 --time 1.5 -o p.png
if expect "timed render: exit 0" 0; then
    n=$(grep -Ec '^caustic: [0-9]+% \(elapsed [0-9]+\.[0-9] s(, ETA [-0-9:]+)?\)$' "$ERR")
    [ "$n" -ge 3 ] && pass "non-TTY progress: plain lines at 10% steps ($n lines)" \
        || fail "non-TTY progress: plain lines at 10% steps" "$n progress lines"
    grep -Eq '^caustic: 100% \(elapsed' "$ERR" && pass "non-TTY progress reaches 100%" \
        || fail "non-TTY progress reaches 100%"
    if grep -q $'\r' "$ERR" || grep -q '\[[#.]' "$ERR"; then fail "non-TTY progress has no bar"
    else pass "non-TTY progress has no bar"; fi
fi
run "$dir" render --width 8 --height 8 --spp 1 -o q.png --quiet
if [ "$RC" -eq 0 ] && [ ! -s "$ERR" ] && [ -s "$dir/q.png" ]; then pass "--quiet: silent on success"
else fail "--quiet: silent on success" "exit $RC"; fi

# A terminal gets the redrawn bar ('script' provides a pseudo-terminal).
if command -v script >/dev/null 2>&1; then
    (cd "$dir" && timeout 300 script -qec "'$BIN' render --width 32 --height 32 --time 1 -o tty.png" /dev/null \
        >"$OUT" 2>"$ERR" </dev/null)
    RC=$?
    if [ "$RC" -eq 0 ] && grep -Eq $'\r\\[[#.]{30}\\] +[0-9]+%  ETA [-0-9:]+  elapsed [0-9:]+' "$OUT"; then
        pass "TTY progress: redrawn bar with ETA and elapsed time"
    else fail "TTY progress: redrawn bar with ETA and elapsed time" "exit $RC"; fi
else
    echo "SKIP: TTY progress ('script' not installed)"
fi

# --------------------------------------------------------------- verify
# 64x64 at 64 spp in 32x32 blocks: 65536 samples per block, where the z-scores of
# path-bsdf are close enough to normal (0 false alarms in 100 seeds, docs/cli.md); the seed
# is fixed, so a pass stays one until the renders change.
dir=$TMP/verify
VERIFY=(verify --integrators path,path-nee,path-bsdf --spp 64 --width 64 --height 64 --block 32 --threads 2)
run "$dir" "${VERIFY[@]}" --map z.png
if expect "verify: consistent integrators agree, exit 0" 0; then
    missing=""
    for re in "^path vs path-nee " "^path vs path-bsdf " "^path-nee vs path-bsdf " "z_crit = [0-9]+\.[0-9]+" \
              "m = 45 tests \(3 pairs x 3 channels x \(1 \+ 4\)\)" "^result: +all pairs agree$"; do
        grep -Eq -- "$re" "$OUT" || missing="$missing /$re/"
    done
    if [ -z "$missing" ]; then pass "verify: report names every pair, m and z_crit"
    else fail "verify: report names every pair, m and z_crit" "stdout lacks:$missing"; fi
    [ "$(grep -Ec '^path[-a-z]* vs .* agree$' "$OUT")" -eq 3 ] && pass "verify: three rows, each 'agree'" \
        || fail "verify: three rows, each 'agree'"
    if [ "$(magic "$dir/z.png" 8)" = "89504e470d0a1a0a" ] && \
       [ "$(magic "$dir/z.png" 24 | cut -c33-48)" = "0000004000000040" ]; then
        pass "verify --map writes a 64x64 PNG"
    else fail "verify --map writes a 64x64 PNG" "found: $(ls "$dir")"; fi
fi
run "$dir" "${VERIFY[@]}" --json
if expect "verify --json: exit 0" 0; then
    if python3 - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert len(rows) == 3, rows
keys = {"a", "b", "spp_a", "spp_b", "z_mean", "max_abs_block_z", "blocks", "blocks_failing",
        "z_crit", "tests", "pass"}
for r in rows:
    assert keys <= r.keys(), keys - r.keys()
    assert len(r["z_mean"]) == 3 and r["pass"] is True and r["blocks"] == 4 and r["tests"] == 45
assert [(r["a"], r["b"]) for r in rows] == [("path", "path-nee"), ("path", "path-bsdf"), ("path-nee", "path-bsdf")]
PY
    then pass "verify --json: one parseable object per pair with the documented keys"
    else fail "verify --json: one parseable object per pair with the documented keys"; fi
fi
# alpha close to 1 makes z_crit tiny: some |z| exceeds it, and that is a disagreement.
run "$dir" verify --integrators path,path-nee --spp 4 --width 16 --height 16 --threads 2 --alpha 0.9999 -q
expect "verify: a disagreement exits 1" 1 "^caustic: verify: 1 of 1 pair disagree"
grep -q "DISAGREE" "$OUT" && pass "verify: disagreement reported as DISAGREE" \
    || fail "verify: disagreement reported as DISAGREE"
grep -q "^caustic: warning: verify: 1024 samples per block" "$ERR" \
    && pass "verify: warns about too few samples per block" \
    || fail "verify: warns about too few samples per block"
run "$dir" verify --integrators path,frobnicate --spp 2
expect "verify: unknown integrator exits 2 listing the valid ones" 2 \
    "--integrators: unknown integrator 'frobnicate' \(valid: path, path-nee, path-bsdf"
run "$dir" verify --integrators path --spp 2
expect "verify: one integrator exits 2" 2 "at least two integrators"
run "$dir" verify --integrators path,,path-nee
expect "verify: empty integrator name exits 2" 2 "empty name"
run "$dir" verify --spp 2
expect "verify: --integrators is required" 2 "--integrators is required" "see caustic --help"
run "$dir" verify --integrators path,path-nee --alpha 1
expect "verify: --alpha 1 rejected" 2 "^caustic: --alpha: expected a number between 0 and 1"
run "$dir" verify --integrators path,path-nee --alpha nan
expect "verify: --alpha nan rejected" 2 "--alpha: .*got 'nan'"
run "$dir" verify --integrators path,path-nee --block 0
expect "verify: --block 0 rejected" 2 "^caustic: --block: expected an integer from 1 to 65536, got '0'$"
run "$dir" verify --integrators path,path-nee --spp 2x
expect "verify: --spp is parsed strictly" 2 "^caustic: --spp: expected a positive integer, got '2x'$"
run "$dir" verify --integrators path,path-nee --integrator path
expect "verify: unknown option suggests one" 2 "did you mean --integrators"
run "$dir" verify --integrators path,path-nee --spp 1 --width 8 --height 8
expect "verify: 1 spp (no variance) exits 2" 2 "at least 2"
run "$dir" verify --integrators path,path-nee --map z.jpg
expect "verify: bad --map extension exits 2 before rendering" 2 "z\.jpg"
grep -q "rendering" "$ERR" && fail "verify: bad --map caught before rendering" \
    || pass "verify: bad --map caught before rendering"
run "$dir" verify no-such.json --integrators path,path-nee
expect "verify: missing scene exits 2" 2 "no-such\.json"
# Consistent integrators: judged by convergence against the first unbiased one (docs/cli.md).
CONV=(--spp 8 --width 32 --height 32 --block 8 --threads 2)
run "$dir" verify --integrators path,sppm "${CONV[@]}"
if expect "verify: sppm converges to path, exit 0" 0; then
    grep -q "^convergence: sppm against path$" "$OUT" && grep -Eq "^  result: converges" "$OUT" \
        && [ "$(grep -Ec '^  [0-2] +(8|32|128) +0x' "$OUT")" -eq 3 ] \
        && pass "verify: sppm convergence report, levels of 8, 32 and 128 iterations" \
        || fail "verify: sppm convergence report, levels of 8, 32 and 128 iterations"
fi
# whitted leaves out indirect light: against it as the reference, sppm's bias stays.
run "$dir" verify --integrators whitted,sppm "${CONV[@]}"
if expect "verify: sppm against a biased reference exits 1" 1 "1 of 1 consistent integrator not shown to converge"; then
    grep -q "^  result: DISAGREE" "$OUT" && pass "verify: non-convergence reported as DISAGREE" \
        || fail "verify: non-convergence reported as DISAGREE"
fi
sed 's/"integrator": {"type": "path"}/"integrator": {"type": "path", "photons": 4000}/' \
    "$SRC/scenes/cornell-box.json" >"$dir/box-photons.json"
run "$dir" verify box-photons.json --integrators path,photon "${CONV[@]}" --json
if expect "verify --json: photon converges, exit 0" 0; then
    if python3 - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert len(rows) == 1, rows
r = rows[0]
assert r["convergence"] == "photon" and r["reference"] == "path" and r["work"] == "photons", r
assert [l["work"] for l in r["levels"]] == [4000, 16000, 64000], r["levels"]
assert len(r["steps"]) == 2 and r["pass"] is True and r["verdict"] in ("within-noise", "shrinks")
assert r["tests"] == 6 and r["blocks"] == 16
for l in r["levels"]:
    assert {"d2", "d2_se", "mean_diff", "mean_z", "seeds"} <= l.keys()
PY
    then pass "verify --json: one convergence object with levels, steps and verdict"
    else fail "verify --json: one convergence object with levels, steps and verdict"; fi
fi
run "$dir" verify --integrators sppm,photon --spp 2
expect "verify: convergence without an unbiased reference exits 2" 2 "unbiased reference"
run "$dir" verify --integrators path,sppm --time 1
expect "verify: convergence with --time exits 2" 2 "needs a sample count"
run "$dir" verify --integrators path,sppm --spp 2 --width 8 --height 8 --block 8
expect "verify: convergence over one block exits 2" 2 "at least 2 blocks"
run "$dir" verify --integrators path,sppm --convergence 1
expect "verify: --convergence 1 rejected" 2 "^caustic: --convergence: expected a number of levels from 2 to 6, got '1'$"
run "$dir" verify --integrators path,sppm --spp 1000000000 --convergence 6
expect "verify: too many iterations exits 2" 2 "too many"

run "$dir" verify --help
if expect "verify --help exits 0" 0; then
    grep -q -- "--integrators" "$OUT" && grep -q -- "--alpha" "$OUT" && grep -q -- "--map" "$OUT" \
        && pass "verify --help prints the verify options" || fail "verify --help prints the verify options"
fi

# info on a scene with mesh files: 676 triangles (6 quads, and twice the OBJ's 166 quads),
# the same with every back end, with the loader's time, the build time and bytes per
# primitive; an unknown back end exits 2.
dir=$TMP/info
for accel in bvh kdtree grid list octree; do
    run "$dir" info "$SRC/scenes/mesh-example.json" --accel "$accel"
    if expect "info --accel $accel exits 0" 0; then
        grep -Eq "^accel: +$accel\$" "$OUT" && grep -Eq "^load: +[0-9.]+ ms" "$OUT" \
            && grep -Eq "^triangles: +676\$" "$OUT" && grep -Eq "^build: +[0-9.]+ ms\$" "$OUT" \
            && grep -Eq "^memory: +[0-9]+ bytes \([0-9.]+ bytes per primitive\)\$" "$OUT" \
            && pass "info --accel $accel prints load, 676 triangles, build and bytes per primitive" \
            || fail "info --accel $accel prints load, 676 triangles, build and bytes per primitive"
    fi
done
run "$dir" info --accel bih
expect "info: unknown back end exits 2" 2 "unknown acceleration structure 'bih'"

# bench rays: back-end names, and the ratio columns (the built-in Cornell box, no ../shared).
dir=$TMP/bench
run "$dir" bench rays --cornell --accel bvh,bih
expect "bench rays: unknown back end exits 2 and lists the valid ones" 2 "unknown acceleration structure 'bih'" "embree, octree, embree-robust\)"
run "$dir" bench rays --cornell --accel bvh,bvh
expect "bench rays: a back end listed twice exits 2" 2 "'bvh' listed twice"
run "$dir" bench rays --cornell --accel bvh,kdtree --threads 2 --json
if expect "bench rays --json without Embree exits 0" 0; then
    if python3 - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert len(rows) == 12, len(rows)  # 2 back ends x 3 sets x 2 thread counts
assert [r["accel"] for r in rows] == ["bvh"] * 6 + ["kdtree"] * 6
assert all(r["check"] == "OK" and r["vs_embree"] is None and r["vs_embree_robust"] is None for r in rows)
PY
    then pass "bench rays --json: checked rows, no Embree ratios without Embree"
    else fail "bench rays --json: checked rows, no Embree ratios without Embree"; fi
fi
# Without reference checksums (a stadium around the Cornell box), the first back end is the
# basis and every other one is compared with it ray by ray, inside the interleaved rounds.
run "$dir" bench rays --cornell --stadium --accel bvh,kdtree --threads 1 --json
if expect "bench rays --stadium exits 0" 0; then
    if python3 - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert [(r["accel"], r["set"]) for r in rows] == [(a, s) for a in ("bvh", "kdtree")
                                                  for s in ("primary", "secondary", "occlusion")], rows
for r in rows[:3]:
    assert r["check"] is None and r["rays_differing"] is None, r
for r in rows[3:]:
    assert r["check"] == "OK" and r["checked_against"] == "bvh" and isinstance(r["rays_differing"], int), r
    assert r["rays_differing"] <= 16, r
for r in rows:
    assert r["grazing_ties"] is None, r
PY
    then pass "bench rays --stadium: the first back end is the basis, the others compared ray by ray"
    else fail "bench rays --stadium: the first back end is the basis, the others compared ray by ray"; fi
fi
run "$dir" bench rays --cornell --accel embree-robust --threads 1 --json
if [ "$RC" -eq 2 ] && grep -q "not available in this build" "$ERR"; then
    pass "bench rays: embree-robust refused in a build without Embree"
elif expect "bench rays: embree-robust alone exits 0" 0; then
    run "$dir" bench rays --cornell --accel bvh,embree,embree-robust --threads 2 --json
    if expect "bench rays with both Embree modes exits 0" 0; then
        if python3 - "$OUT" <<'PY'
import json, sys
rows = [json.loads(l) for l in open(sys.argv[1])]
assert [r["accel"] for r in rows] == ["bvh"] * 6 + ["embree"] * 6 + ["embree-robust"] * 6
assert all(r["check"] == "OK" for r in rows)
# Every closest-hit row counts its grazing ties against Embree's default mode.
assert all((r["grazing_ties"] is None) == (r["set"] == "occlusion") for r in rows), rows
assert all(r["grazing_ties"] == 0 for r in rows if r["accel"] == "embree" and r["set"] != "occlusion")
rate = {(r["accel"], r["set"], r["threads"]): r["mrays_per_s"] for r in rows}
for r in rows:
    k = (r["set"], r["threads"])
    for field, anchor in (("vs_embree", "embree"), ("vs_embree_robust", "embree-robust")):
        want = r["mrays_per_s"] / rate[(anchor,) + k]
        assert abs(r[field] - want) <= 1e-9 * want, (r, field, want)
PY
        then pass "bench rays: every row's ratio to Embree's default and to its robust mode"
        else fail "bench rays: every row's ratio to Embree's default and to its robust mode"; fi
    fi
    run "$dir" bench rays --cornell --accel bvh,embree-robust --threads 1
    expect "bench rays table exits 0" 0 && { grep -Eq "vs embree +vs robust" "$OUT" && grep -Eq "^embree-robust " "$OUT" \
        && pass "bench rays table: a vs robust column and embree-robust rows" \
        || fail "bench rays table: a vs robust column and embree-robust rows"; }
fi

harness_finish
