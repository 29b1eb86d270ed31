#!/usr/bin/env bash
# caustic view (cli/view.c) driven by scripts under Xvfb: modes switched by key, each
# mode's screenshot after N passes equal to `caustic render --spp N` of the same camera
# (bit for bit: the passes reproduce the render's samples through first_sample), an orbit
# restarting the accumulation, the camera as JSON, script errors located; without SDL2 in
# the build, the one message and exit 2. Usage: view_tests.sh CAUSTIC SOURCE-DIR
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init view_tests "$@"

# ------------------------------------------------------------ a build without SDL2
if ! "$BIN" --version | grep -Eq '^sdl2: +yes'; then
    harness_run "$TMP/nosdl" 20 view
    expect "view without SDL2: the message, exit 2" 2 "built without a window system \(SDL2\)"
    skip "every window test: this caustic was built without SDL2 (libsdl2-dev, cmake -DCST_VIEWER=ON)"
    harness_finish
    exit $?
fi

harness_display

# view DIR SECONDS ARGS...: caustic view ARGS in DIR under the X server; sets RC, OUT, ERR.
view() {
    local dir=$1 limit=$2
    shift 2
    mkdir -p "$dir"
    # Under CI's sanitizer pass, no leak check for the window: SDL_Quit dlcloses the X11
    # libraries it loaded, so LSan sees their lifetime allocations from "<unknown module>"
    # and no suppression (view_lsan.supp, for those it can name) can match them (measured:
    # 240 bytes in 3 allocations at exit). ASan's and UBSan's other checks stay on. The slow
    # unwinder (fast_unwind_on_malloc=0) deadlocks in libgcc's unwinder here: not used.
    (cd "$dir" && LSAN_OPTIONS=suppressions=$SRC/tests/cli/view_lsan.supp${LSAN_OPTIONS:+:$LSAN_OPTIONS} \
        ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 \
        timeout -k 5 "$limit" "${RUNNER[@]}" "$BIN" view "$@" >"$OUT" 2>"$ERR" </dev/null)
    RC=$?
}

# same NAME A B: caustic compare finds A and B equal in every pixel (rmse 0).
same() {
    local json
    json=$("$BIN" compare "$2" "$3" --json 2>&1)
    if echo "$json" | grep -q '"rmse":0.0,"relmse":0.0,'; then pass "$1"; else fail "$1" "$json"; fi
}

SIZE=(--width 96 --height 96 --threads 2)

# ------------------------------------------------------------ every mode against render
dir=$TMP/modes
cat >"$TMP/modes.txt" <<'EOF'
# the first mode is path (the Cornell box's integrator)
wait-spp 3
save path.exr
key 2
wait-spp 2
save whitted.exr
key 4
wait-spp 2
save light.exr
key 5
wait-spp 2
save photon.exr
key 6
wait-spp 4
save sppm.exr
key 7
wait-spp 2
save bdpt.exr
key 8
wait-spp 3
save vcm.exr
key 1
wait-spp 1
save preview.png
key tab
save normals.png
key 3
wait-spp 2
key 9
save error.png
status
quit
EOF
view "$dir" 600 "${SIZE[@]}" --script "$TMP/modes.txt"
if HARNESS_EXPECT_STDOUT=1 expect "view: the mode script runs to quit" 0 "saved vcm.exr \(vcm, 3 spp\)" \
    "saved sppm.exr \(sppm, 4 iterations\)" "first image [0-9]+ ms after loading" \
    "mode path \(relative error\) spp 2"; then
    grep -o "first image.*" "$ERR" | sed 's/^/      (96x96) /'
fi
for m in path:3 whitted:2 light:2 photon:2 sppm:4 bdpt:2 vcm:3; do
    name=${m%%:*}
    spp=${m##*:}
    harness_run "$dir" 300 render "${SIZE[@]}" --integrator "$name" --spp "$spp" -q -o "ref-$name.exr"
    if [ "$RC" -ne 0 ]; then fail "render $name for the comparison"; continue; fi
    same "view $name at $spp equals render --spp $spp bit for bit" "$dir/$name.exr" "$dir/ref-$name.exr"
done
for f in preview.png normals.png error.png; do
    check "view: $f saved" test -s "$dir/$f"
done
# The preview and the error map are images of the scene, not black frames.
check "view: the preview is not black" eval \
    "'$BIN' compare '$dir/preview.png' '$dir/normals.png' --json | grep -q '\"mean_a\":0\.[0-9]*[1-9]'"

# ------------------------------------------------------------ the status line's estimated error
# The root mean square of the pixels' relative errors (view_error_estimate): none before two
# passes (-1), then positive, and smaller after 16 passes than after 4 (fixed seed).
dir=$TMP/error
printf 'key 3\nwait-spp 1\nstatus\nwait-spp 4\nstatus\nwait-spp 16\nstatus\nquit\n' >"$TMP/error.txt"
view "$dir" 300 "${SIZE[@]}" --script "$TMP/error.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: the error script runs" 0 "view: mode path spp 16 "
check "view: the status line's error: none at 1 spp, then positive and falling (4 -> 16 spp)" eval \
    "grep '^view: mode path spp' '$OUT' | sed 's/.* error //' | tr '\n' ' ' | \
     awk '{ exit !(\$1 == -1 && \$2 > 0 && \$3 > 0 && \$3 < \$2) }'"
grep '^view: mode path spp' "$OUT" | sed 's/^/      /'

# ------------------------------------------------------------ k: a checkpoint render --resume continues
# The path mode's 3 passes and BDPT's 2 iterations written as state files (view_state.c);
# `render --resume` continues each to 5 (4) bit for bit as an uninterrupted render; the
# preview and a moved camera are refused (a state has no camera).
dir=$TMP/checkpoint
printf 'key 3\nwait-spp 3\nkey k\nkey 7\nwait-spp 2\nkey k\nkey 1\nkey k\nkey 3\norbit 10 0\nwait-spp 1\nkey k\nquit\n' \
    >"$TMP/checkpoint.txt"
view "$dir" 300 "${SIZE[@]}" --script "$TMP/checkpoint.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: k writes checkpoints" 0 "view: checkpoint caustic-view-000.state \(path, 3 passes\)" \
    "view: checkpoint caustic-view-001.state \(bdpt, 2 passes\)"
check "view: k refuses the preview and a moved camera" eval \
    "grep -q 'no checkpoint: not in the preview' '$ERR' && grep -q 'no checkpoint: the camera has moved' '$ERR'"
harness_run "$dir" 300 render "${SIZE[@]}" --integrator path --resume caustic-view-000.state --spp 2 -q -o two.pfm
expect "view: the path checkpoint holds its 3 passes (a resume to 2 is refused)" 2 "holds 3 samples per pixel"
for m in path:000:5 bdpt:001:4; do
    IFS=: read -r integ n spp <<<"$m"
    harness_run "$dir" 300 render "${SIZE[@]}" --integrator "$integ" --resume "caustic-view-$n.state" --spp "$spp" -q \
        -o "resumed-$integ.pfm"
    harness_run "$dir" 300 render "${SIZE[@]}" --integrator "$integ" --spp "$spp" -q -o "whole-$integ.pfm"
    check "view: the $integ checkpoint resumed to $spp equals the uninterrupted render bit for bit" \
        cmp -s "$dir/resumed-$integ.pfm" "$dir/whole-$integ.pfm"
done

# ------------------------------------------------------------ the camera: orbit restarts
dir=$TMP/orbit
cat >"$TMP/orbit.txt" <<'EOF'
wait-spp 2
save before.exr
key c
orbit 30 -10
status
wait-spp 1
status
save after.exr
key c
dolly 2
key ]
status
key s
quit
EOF
view "$dir" 300 "${SIZE[@]}" --script "$TMP/orbit.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: orbit script runs" 0 "saved after.exr"
check "view: an orbit restarts the accumulation (spp 0, then the first pass)" eval \
    "grep '^view: mode' '$OUT' | sed -n 1,2p | tr '\n' '|' | grep -Eq '^view: mode path spp 0 .*\|view: mode path spp 1 '"
check "view: a dolly and a field-of-view change restart too" eval \
    "grep '^view: mode' '$OUT' | sed -n 3p | grep -q 'spp 0 '"
check "view: s saves caustic-view-000.exr and .png in the current directory" \
    test -s "$dir/caustic-view-000.exr" -a -s "$dir/caustic-view-000.png"
check "view: the orbited image differs" eval "! '$BIN' compare '$dir/before.exr' '$dir/after.exr' --json | grep -q '\"rmse\":0.0,'"
check "view: c prints the camera as JSON, and the orbit moved it" eval \
    "test \$(grep -c '^\"camera\": {\"type\": \"pinhole\", \"position\": \[' '$OUT') -eq 2 && \
     test \"\$(grep '^\"camera\"' '$OUT' | sed -n 1p)\" != \"\$(grep '^\"camera\"' '$OUT' | sed -n 2p)\""
# The printed camera is the JSON scene format's camera section.
if python3 - "$OUT" <<'EOF'
import json, sys
lines = [l for l in open(sys.argv[1]) if l.startswith('"camera"')]
cam = json.loads("{" + lines[1] + "}")["camera"]
assert cam["type"] == "pinhole" and len(cam["position"]) == 3 and cam["fov"] > 0
EOF
then pass "view: the printed camera is valid JSON"; else fail "view: the printed camera is valid JSON"; fi

# ------------------------------------------------------------ click focus, camera JSON
# A thin lens (cornell-spheres.json: aperture 8, focus 1000): a click on the back wall moves
# the plane of focus there, restarts the accumulation and changes the image; the camera
# written after it, merged into the scene, renders the view's image bit for bit.
dir=$TMP/focus
cat >"$TMP/focus.txt" <<'EOF2'
orbit 12 -6
wait-spp 2
save before.exr
click 48 30
status
wait-spp 2
status
save after.exr
camera cam.json
key c
click 0 95
status
quit
EOF2
view "$dir" 300 "$SRC/scenes/cornell-spheres.json" "${SIZE[@]}" --integrator path --script "$TMP/focus.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: the click script runs" 0 "view: focus distance [0-9.e+]+ \(click at 48, 30\)" \
    "view: camera saved cam.json" "view: camera saved caustic-view-camera-000.json"
check "view: a click restarts the accumulation (spp 0, then 2)" eval \
    "grep '^view: mode' '$OUT' | sed -n 1,2p | tr '\n' '|' | grep -Eq '^view: mode path spp 0 .*\|view: mode path spp 2 '"
check "view: the click changes the image" eval "! '$BIN' compare '$dir/before.exr' '$dir/after.exr' --json | grep -q '\"rmse\":0.0,'"
check "view: the focus is the back wall's depth (about 800 + 559 along the axis, within the box)" python3 - "$OUT" <<'EOF2'
import re, sys
d = float(re.search(r"focus distance ([0-9.e+]+)", open(sys.argv[1]).read()).group(1))
sys.exit(0 if 900.0 < d < 1500.0 else 1)
EOF2
check "view: c writes the same camera as the camera command" cmp "$dir/cam.json" "$dir/caustic-view-camera-000.json"
if python3 - "$SRC/scenes/cornell-spheres.json" "$dir/cam.json" "$dir/scene.json" <<'EOF2'
import json, sys
scene = json.load(open(sys.argv[1]))
cam = json.load(open(sys.argv[2]))["camera"]
assert cam["type"] == "thinlens" and cam["focus_distance"] != 1000
scene["camera"] = cam
json.dump(scene, open(sys.argv[3], "w"))
EOF2
then
    harness_run "$dir" 300 render scene.json "${SIZE[@]}" --integrator path --spp 2 -q -o ref.exr
    if [ "$RC" -eq 0 ]; then same "view: the written camera renders the view's image bit for bit" "$dir/after.exr" "$dir/ref.exr"
    else fail "view: render of the written camera"; fi
else
    fail "view: the written camera is a thinlens camera section with the clicked focus" "$(cat "$dir/cam.json")"
fi

# ------------------------------------------------------------ click to explain
# A right click (script: explain X Y) prints `caustic explain` of that pixel at the mode's
# last accumulated sample, the same text the explain command prints, and restarts nothing.
dir=$TMP/explain
cat >"$TMP/explain.txt" <<'EOF2'
wait-spp 2
explain 48 60
status
key 2
wait-spp 1
explain 30 20
key 1
explain 30 20
quit
EOF2
view "$dir" 300 "${SIZE[@]}" --spp 2 --script "$TMP/explain.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: explain script runs" 0 "view: explain \(48, 60\), mode path, sample 1:" \
    "view: explain \(30, 20\), mode whitted, sample 0:" "view: explain \(30, 20\) in mode preview: the preview has no paths"
check "view: explaining restarts nothing (spp 2 after it)" grep -q '^view: mode path spp 2 ' "$OUT"
cp "$OUT" "$dir/view.out"
harness_run "$dir" 60 explain --pixel 48,60 --sample 1 "${SIZE[@]}"
line=$(grep '^camera sample the render computed: .*equal, bit for bit' "$OUT" | head -1)
check "view: the click's explanation is caustic explain's" eval '[ -n "$line" ] && grep -qF "$line" "$dir/view.out"'

# ------------------------------------------------------------ the disagreement map
# Key r pins the path tracer's accumulation; key 0 shows another mode's against it block by
# block (verify's test: Sidak-corrected z over 16x16 blocks at alpha 0.01). BDPT agrees with
# the path tracer; Whitted (no diffuse interreflection) does not; an orbit leaves the pinned
# reference behind.
dir=$TMP/diff
cat >"$TMP/diff.txt" <<'EOF2'
key 1
key r
key 3
wait-spp 16
key r
key 7
wait-spp 16
key 0
status
save bdpt-vs-path.png
key 2
wait-spp 16
status
orbit 10 0
wait-spp 2
status
quit
EOF2
view "$dir" 300 "${SIZE[@]}" --script "$TMP/diff.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: the disagreement script runs" 0 \
    "view: nothing to pin: preview has no per-pixel variance" "view: reference pinned: path, 16 spp" \
    "view: bdpt vs path \(16 spp\): agree, largest block \|z\| [0-9.]+" \
    "view: whitted vs path \(16 spp\): DISAGREE" \
    "view: disagreement map: the reference \(path\) was pinned for another camera"
check "view: the disagreement map is saved" test -s "$dir/bdpt-vs-path.png"

# ------------------------------------------------------------ photon mode: maps kept, points
# The maps are built once (status: photon_maps_built 1) and reused by every pass and after
# an orbit, each image still equal to a render's bit for bit (the orbit's: its automatic
# radius from the new camera); key o draws the photons over the shown image (PNG), not
# into the linear EXR.
dir=$TMP/photon
cat >"$TMP/photon.txt" <<'EOF2'
wait-spp 2
status
save p2.exr
save nopoints.png
key o
save points.png
save points.exr
orbit 20 -4
wait-spp 2
status
save orbit.exr
camera cam.json
quit
EOF2
view "$dir" 300 "$SRC/scenes/cornell-box.json" "${SIZE[@]}" --integrator photon --script "$TMP/photon.txt"
HARNESS_EXPECT_STDOUT=1 expect "view: the photon script runs" 0 "saved orbit.exr"
check "view: photon maps built once for two passes, an orbit and two more" eval \
    "test \$(grep -c '^view: mode photon spp 2 .* photon_maps_built 1 error ' '$OUT') -eq 2"
check "view: key o draws the photons (the PNG changes)" eval \
    "! '$BIN' compare '$dir/nopoints.png' '$dir/points.png' --json | grep -q '\"rmse\":0.0,'"
same "view: the photons are not drawn into the linear EXR" "$dir/p2.exr" "$dir/points.exr"
harness_run "$dir" 300 render "$SRC/scenes/cornell-box.json" "${SIZE[@]}" --integrator photon --spp 2 -q -o ref2.exr
same "view: photon with kept maps equals render --spp 2 bit for bit" "$dir/p2.exr" "$dir/ref2.exr"
if python3 - "$SRC/scenes/cornell-box.json" "$dir/cam.json" "$dir/scene.json" <<'EOF2'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["camera"] = json.load(open(sys.argv[2]))["camera"]
json.dump(scene, open(sys.argv[3], "w"))
EOF2
then
    harness_run "$dir" 300 render scene.json "${SIZE[@]}" --integrator photon --spp 2 -q -o ref-orbit.exr
    same "view: photon after an orbit (maps kept, radius from the new camera) equals render bit for bit" \
        "$dir/orbit.exr" "$dir/ref-orbit.exr"
else
    fail "view: the photon run's camera file" "$(cat "$dir/cam.json")"
fi

# ------------------------------------------------------------ --spp stops refining
dir=$TMP/limit
printf 'wait-spp 2\nstatus\nquit\n' >"$TMP/limit.txt"
view "$dir" 120 "${SIZE[@]}" --spp 2 --script "$TMP/limit.txt"
HARNESS_EXPECT_STDOUT=1 expect "view --spp 2: stops at 2" 0 "mode path spp 2 "

# ------------------------------------------------------------ errors
printf 'key 3\nwait-spp 1\nfrobnicate 3\n' >"$TMP/bad.txt"
view "$TMP/bad" 60 --script "$TMP/bad.txt"
expect "view: an unknown script command is located, exit 2" 2 "bad.txt:3:1: unknown command 'frobnicate'; expected one of key"
printf 'wait-spp many\n' >"$TMP/bad2.txt"
view "$TMP/bad" 60 --script "$TMP/bad2.txt"
expect "view: a bad wait-spp count is located" 2 "bad2.txt:1:10: wait-spp 'many': expected a whole number"
printf 'key ?!\n' >"$TMP/bad3.txt"
view "$TMP/bad" 60 --script "$TMP/bad3.txt"
expect "view: a bad key is located" 2 "bad3.txt:1:5: key '\?!'"
view "$TMP/bad" 60 --script "$TMP/missing.txt"
expect "view: a missing script, exit 2" 2 "missing.txt: cannot open the script"
view "$TMP/bad" 60 "$TMP/nope.json"
expect "view: a missing scene, exit 2" 2 "cannot open scene"
harness_run "$TMP/bad" 60 render --script "$TMP/bad.txt"
expect "render --script: an option of view only, exit 2" 2 "--script is an option of 'view'"
printf 'save out.txt\nquit\n' >"$TMP/bad4.txt"
view "$TMP/bad" 60 --width 32 --height 32 --script "$TMP/bad4.txt"
expect "view: save to an unknown format fails, exit 1" 1 "save 'out.txt': expected a name ending in .png, .exr or .pfm"

harness_finish
