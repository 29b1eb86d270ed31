#!/usr/bin/env bash
# Numeric robustness of the caustic CLI (issue 25, items 5, 6, 9 and 11): products of values
# that overflow float are refused at load; a render that loses more than CST_NONFINITE_LIMIT
# (1e-4) of its samples to NaN/Inf fails with exit 1 (the image still written), fewer stay a
# warning; photon/SPPM/VCM radii that cannot give finite estimates are refused; the
# stratified sampler's strata are found once per render; rough plastics load quickly.
# Run by CTest:
#   bash numeric_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init numeric_tests "$@"
if ! command -v python3 >/dev/null; then
    echo "numeric_tests: python3 is needed to write the test scenes; skipped"
    echo "0 passed, 0 failed"
    exit 0
fi

# run ARGS...: caustic in $TMP; sets RC, OUT, ERR.
run() { harness_run "$TMP" 300 "$@"; }

# The scenes: scenes/cornell-spheres.json at 32x32, 8 spp, with one change each.
python3 - "$SRC/scenes/cornell-spheres.json" "$TMP" <<'PY'
import json, struct, sys
src, tmp = sys.argv[1], sys.argv[2]
base = json.load(open(src))
base["film"] = {"width": 32, "height": 32}
base["sampler"] = {"spp": 8, "seed": 1}
base["camera"]["aperture_radius"] = 0
def scene(name, change):
    s = json.loads(json.dumps(base))
    change(s)
    json.dump(s, open(f"{tmp}/{name}.json", "w"))
def tex_times_scale(s):
    s["textures"] = {"hot": {"type": "checkerboard", "even": [1e30] * 3, "odd": [1e30] * 3}}
    s["shapes"][0]["emission"] = {"radiance": "hot", "scale": 1e30}
scene("tex_scale", tex_times_scale)
scene("rad_scale", lambda s: s["shapes"][0].update(emission={"radiance": [1e30] * 3, "scale": 1e30}))
scene("sphere_power", lambda s: s["shapes"][6].update(emission={"radiance": [1e37] * 3}))
scene("quad_power", lambda s: s["shapes"][0].update(emission={"radiance": [3e38] * 3}))
scene("point_power", lambda s: s.update(lights=[{"type": "point", "position": [278, 500, 278], "intensity": [3e38] * 3}]))
scene("point_ok", lambda s: s.update(lights=[{"type": "point", "position": [278, 500, 278], "intensity": [1e37] * 3}]))
scene("env_const", lambda s: s.update(environment={"radiance": [3e38] * 3}))
scene("env_image", lambda s: s.update(environment={"file": "hot.pfm", "scale": 1e30}))
open(f"{tmp}/hot.pfm", "wb").write(b"PF\n4 2\n-1.0\n" + struct.pack("<24f", *([1e30] * 24)))
# In range for every load check, but the light tracer's splats overflow now and then: 3
# of 8192 samples at 32x32 (> 1e-4: the render fails), 5 of 131072 at 128x128 (< 1e-4).
scene("rare_nan", lambda s: s["shapes"][6].update(emission={"radiance": [6e32] * 3}))
for integ in ("photon", "sppm", "vcm"):
    for r in (1e-30, 1e-8, 1e-3, 1e30):
        scene(f"radius_{integ}_{r:g}", lambda s: s.update(integrator={"type": integ, "radius": r}))
# 1,000 distinct rough plastics (item 11).
mats, shapes = {}, []
for i in range(1000):
    mats[f"p{i}"] = {"type": "plastic", "albedo": [0.5, 0.4, 0.3], "ior": 1.05 + 1.45 * i / 999,
                     "roughness": 0.05 + 0.95 * ((i * 7919) % 1000) / 999}
    shapes.append({"type": "sphere", "material": f"p{i}", "center": [2 * (i % 40), 2 * (i // 40), 0], "radius": 0.8})
shapes.append({"type": "sphere", "material": "p0", "center": [40, 25, 30], "radius": 5, "emission": {"radiance": [5, 5, 5]}})
json.dump({"film": {"width": 16, "height": 16}, "sampler": {"spp": 1},
           "camera": {"position": [40, 25, -80], "look_at": [40, 25, 0], "up": [0, 1, 0], "fov": 40},
           "materials": mats, "shapes": shapes}, open(f"{tmp}/plastics.json", "w"))
PY
cat >"$TMP/point_power.pbrt" <<'PBRT'
LookAt 0 0 -5  0 0 0  0 1 0
Camera "perspective" "float fov" [40]
Film "rgb" "integer xresolution" [16] "integer yresolution" [16]
WorldBegin
LightSource "point" "rgb I" [3e38 3e38 3e38]
Material "diffuse"
Shape "sphere" "float radius" [1]
PBRT
sed 's/^WorldBegin/Integrator "sppm" "float radius" [1e-30]\nWorldBegin/; s/3e38 3e38 3e38/1 1 1/' \
    "$TMP/point_power.pbrt" >"$TMP/radius_sppm.pbrt"

# ------------------------------------------------ 5a: products that overflow, at load
OVERFLOW="overflows a float"
run render tex_scale.json -o a.pfm
expect "emission texture 1e30 x scale 1e30 refused at load (it rendered black, exit 0)" 2 "$OVERFLOW" "texture"
run render rad_scale.json -o a.pfm
expect "emission radiance 1e30 x scale 1e30 refused, at the scale, naming both" 2 \
    "emission\.scale: radiance 1e\+30 x scale 1e\+30 = 1e\+60 $OVERFLOW"
run render sphere_power.json -o a.pfm
expect "emitting sphere whose power overflows refused (shapes[6])" 2 "shapes\[6\].*power.*$OVERFLOW"
run render quad_power.json -o a.pfm
expect "emitting quad of radiance 3e38 refused (power overflows)" 2 "shapes\[0\].*power.*$OVERFLOW"
run render point_power.json -o a.pfm
expect "point light 3e38: power 4 pi I overflows, refused at its location" 2 "lights\[0\].*4 pi x intensity.*$OVERFLOW"
run render env_const.json -o a.pfm
expect "constant environment 3e38 refused" 2 "environment.*$OVERFLOW"
run render env_image.json -o a.pfm
expect "environment image 1e30 x scale 1e30 refused" 2 "environment\.file.*scale.*$OVERFLOW"
run render point_power.pbrt -o a.pfm
# Since the pbrt loader builds through the public API, cst_scene_add_light refuses it at the
# directive (located), before the commit-time check.
expect "pbrt point light 3e38 refused" 2 "point_power.pbrt:5:1: .*power.*$OVERFLOW"
run render point_ok.json -o ok.pfm
expect "point light 1e37 (power 1.3e38, finite) still renders" 0
if [ -f "$TMP/a.pfm" ]; then fail "refused scenes write no image"; else pass "refused scenes write no image"; fi

# ------------------------------------------------ 5b: a render losing samples fails
run render rare_nan.json --integrator light -o lost.pfm --threads 2
expect "3 of 8192 samples NaN/Inf (> 1e-4): exit 1 with a clear message" 1 \
    "error: 3 of 8192 samples .* NaN or infinite .*more than the 0\.01%" "lost\.pfm was written for inspection"
if [ -s "$TMP/lost.pfm" ]; then pass "the failed render's image is written for inspection"
else fail "the failed render's image is written for inspection"; fi
run render rare_nan.json --integrator light --width 128 --height 128 -o few.pfm --threads 2
expect "5 of 131072 samples NaN/Inf (< 1e-4): exit 0, a warning" 0 "warning: 5 NaN/Inf samples discarded"

# ------------------------------------------------ 6: photon, SPPM and VCM radii
for integ in photon sppm vcm; do
    run render "radius_${integ}_1e-30.json" -o r.pfm
    expect "$integ radius 1e-30 refused at load (7-92% NaN samples)" 2 "radius 1e-30 is below 1e-18"
    run render "radius_${integ}_1e-08.json" -o r.pfm
    expect "$integ radius 1e-8 (1e-11 of the scene) refused at render, naming the scale" 2 \
        "radius 1e-08: expected 0\.00096.* bounding-box diagonal"
    run render "radius_${integ}_1e+30.json" -o r.pfm
    expect "$integ radius 1e30 refused" 2 "radius.*1e\+30"
    run render "radius_${integ}_0.001.json" -o r.pfm --threads 2
    if expect "$integ radius 1e-3 (the smallest accepted here) renders" 0 && grep -q "NaN" "$ERR"; then
        fail "$integ radius 1e-3: no NaN/Inf sample"
    fi
done
run render radius_sppm.pbrt -o r.pfm
expect "pbrt SPPM radius 1e-30 refused at its location" 2 "radius_sppm\.pbrt:[0-9]+:[0-9]+: .*radius 1e-30"

# ------------------------------------------------ 9: stratified strata once per render
# spp 2^31 - 1 (prime: a 1 x spp grid) took 46,000 divisor steps per sample: 2-3 spp in 2 s
# where the fix completes ~1000 on one thread. Measured against the independent sampler in
# the same run, so that a loaded or sanitized machine (42 spp under ASan at load 40) cannot
# fail it: the fixed sampler reaches about the same count, the bug a few hundredths of it.
run render --sampler independent --spp 2147483647 --time 2 --width 32 --height 32 --threads 1 -o i.png
ind=$(grep -Eo '[0-9]+ spp,' "$ERR" | tail -1 | grep -Eo '^[0-9]+')
run render --sampler stratified --spp 2147483647 --time 2 --width 32 --height 32 --threads 1 -o s.png
spp=$(grep -Eo '[0-9]+ spp,' "$ERR" | tail -1 | grep -Eo '^[0-9]+')
if [ "$RC" -eq 0 ] && [ -n "$spp" ] && [ -n "$ind" ] && [ $((spp * 8)) -ge "$ind" ]; then
    pass "stratified, --spp 2147483647 --time 2: $spp spp (independent: $ind; at least an eighth: passes double, so counts differ by 2x steps)"
else fail "stratified, --spp 2147483647 --time 2: at least an eighth of independent's spp" "exit $RC, ${spp:-no} spp against ${ind:-no}"; fi

# ------------------------------------------------ 11: rough plastics load quickly
# CPU time, not wall time (the machine may be shared): 13 s before the SIMD quadrature,
# about 0.9 s after (release build); 6 s leaves room for sanitizer builds.
TIMEFORMAT=%U
cpu=$( { time (cd "$TMP" && "$BIN" info plastics.json >"$OUT" 2>"$ERR"); } 2>&1 )
RC=$?
if [ "$RC" -eq 0 ] && grep -q "materials: *1000" "$OUT" && awk -v t="$cpu" 'BEGIN { exit !(t < 6.0) }'; then
    pass "info on 1,000 distinct rough plastics: ${cpu} s of CPU (< 6)"
else fail "info on 1,000 distinct rough plastics in < 6 s of CPU" "exit $RC, ${cpu} s"; fi

harness_finish
