#!/usr/bin/env bash
# Tests of the first-hour friction fixes of issue 25 in the caustic tool: --time without
# --spp renders until the time is up, warnings for a scene without light and a mesh
# whose .mtl is missing, per-command help, --version's build description, `caustic list`,
# progress with an ETA when stderr is not a terminal (photon pass, SPPM iterations, small
# images at high spp), the --json summary, and the memory check before a huge render.
# Run by CTest:
#   bash friction_tests.sh <path-to-caustic-binary> <source-dir>
# Prints one PASS/FAIL line per check and ends with "N passed, M failed".
set -u

. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init friction_tests "$@"

# run DIR ARGS...: runs caustic in DIR; sets RC, OUT, ERR. The timeout guards against a
# render that does not stop.
run() { local dir=$1; shift; harness_run "$dir" 120 "$@"; }
# The spp of the "caustic: wrote ..." summary line.
wrote_spp() { sed -nE 's/^caustic: wrote [^:]*: [0-9]+x[0-9]+, ([0-9]+) spp.*/\1/p' "$ERR"; }

# --------------------------------------------------------------- --time without --spp
# The built-in box asks for 64 spp; --time alone renders until the time is up (README:
# "as many samples as fit").
dir=$TMP/time
run "$dir" render --width 8 --height 8 --time 1 -o t.png
spp=$(wrote_spp)
check "--time alone renders past the scene's 64 spp (got ${spp:-none})" \
    test "$RC" -eq 0 -a "${spp:-0}" -gt 64
grep -q "time limit 1 s" "$ERR" && pass "--time alone: the job line says 'time limit'" \
    || fail "--time alone: the job line says 'time limit'"
run "$dir" render --width 8 --height 8 --time 1 --spp 3 -o t.png
check "--time with --spp: stops at the spp (got $(wrote_spp))" test "$RC" -eq 0 -a "$(wrote_spp)" = 3
run "$dir" render --integrator sppm --width 8 --height 8 --time 1 -o s.png
spp=$(wrote_spp)
check "--time alone: SPPM iterations go on past the scene's 64 (got ${spp:-none})" \
    test "$RC" -eq 0 -a "${spp:-0}" -gt 64
cat >"$dir/spp1.json" <<'JSON'
{"film": {"width": 8, "height": 8}, "sampler": {"spp": 1},
 "camera": {"type": "pinhole", "position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
 "materials": {"w": {"type": "diffuse"}},
 "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "w",
             "emission": {"radiance": [1, 1, 1]}}]}
JSON
run "$dir" render spp1.json --time 0.5 -o j.png
spp=$(wrote_spp)
check "--time alone overrides a scene file's spp 1 (got ${spp:-none})" test "$RC" -eq 0 -a "${spp:-0}" -gt 1

# --------------------------------------------------------------- warnings
dir=$TMP/warn
mkdir -p "$dir"
cat >"$dir/dark.json" <<'JSON'
{"film": {"width": 8, "height": 8}, "sampler": {"spp": 1},
 "camera": {"type": "pinhole", "position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
 "materials": {"w": {"type": "diffuse"}},
 "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "w"}]}
JSON
run "$dir" render dark.json -o d.png
check "a scene without light: warned, still rendered" \
    grep -Eq "^caustic: warning: .*no light" "$ERR"
check "a scene without light: exit 0" test "$RC" -eq 0 -a -s "$dir/d.png"
run "$dir" render dark.json -o d.png --quiet
check "a scene without light: warned even with --quiet" grep -q "no light" "$ERR"
run "$dir" render --width 8 --height 8 --spp 1 -o box.png
if grep -q "no light" "$ERR"; then fail "the built-in box (lit) draws no light warning"
else pass "the built-in box (lit) draws no light warning"; fi
# Lit by an emitting medium alone (the camera's): not "no light".
cat >"$dir/glow.json" <<'JSON'
{"film": {"width": 8, "height": 8}, "sampler": {"spp": 1},
 "camera": {"type": "pinhole", "position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
 "media": {"glow": {"type": "homogeneous", "sigma_a": 0.5, "sigma_s": 0.1, "Le": [1, 1, 1]}},
 "camera_medium": "glow",
 "materials": {"w": {"type": "diffuse"}},
 "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "w"}]}
JSON
run "$dir" render glow.json -o g.png
if [ "$RC" -eq 0 ] && ! grep -q "no light" "$ERR"; then pass "a scene lit by an emitting medium alone: no light warning"
else fail "a scene lit by an emitting medium alone: no light warning (exit $RC)"; fi

OBJ=$SRC/scenes/meshes/torus-on-plinth.obj
if [ -f "$OBJ" ]; then
    cp "$OBJ" "$dir/"
    cat >"$dir/mesh.json" <<'JSON'
{"film": {"width": 8, "height": 8}, "sampler": {"spp": 1},
 "camera": {"type": "pinhole", "position": [0, 1, 6], "look_at": [0, 1, 0], "fov": 40},
 "materials": {"w": {"type": "diffuse"}},
 "shapes": [{"type": "meshfile", "file": "torus-on-plinth.obj", "material": "w"},
            {"type": "sphere", "center": [0, 5, 0], "radius": 1, "material": "w",
             "emission": {"radiance": [1, 1, 1]}}]}
JSON
    run "$dir" render mesh.json -o m.png
    check "an OBJ whose .mtl is missing: warned (names the .mtl)" \
        grep -Eq "^caustic: warning: .*torus-on-plinth.obj:[0-9]+: material library 'torus-on-plinth.mtl' not found" "$ERR"
    check "an OBJ whose .mtl is missing: still loads (exit 0)" test "$RC" -eq 0
    cp "$SRC/scenes/meshes/torus-on-plinth.mtl" "$dir/"
    run "$dir" render mesh.json -o m.png
    if grep -q "material library" "$ERR"; then fail "an OBJ with its .mtl: no warning"
    else pass "an OBJ with its .mtl: no warning"; fi
else
    echo "SKIP: .mtl warning ($OBJ not found)"
fi

# --------------------------------------------------------------- per-command help
dir=$TMP/help
run "$dir" render --help
check "render --help: exit 0, render's options" \
    eval 'test "$RC" -eq 0 && grep -q -- "--integrator" "$OUT" && grep -q -- "--json" "$OUT"'
check "render --help: not verify's or bench's options" \
    eval '! grep -Eq -- "--integrators|--alpha|--stadium|--convergence" "$OUT"'
run "$dir" verify --help
check "verify --help: verify's options only" \
    eval 'test "$RC" -eq 0 && grep -q -- "--alpha" "$OUT" && ! grep -Eq -- "--png-linear|--stadium" "$OUT"'
run "$dir" bench rays --help
check "bench rays --help: bench's options only" \
    eval 'test "$RC" -eq 0 && grep -q -- "--stadium" "$OUT" && ! grep -Eq -- "--png-linear|--alpha" "$OUT"'
run "$dir" info --help
check "info --help: info's options only" \
    eval 'test "$RC" -eq 0 && grep -q -- "--accel" "$OUT" && ! grep -Eq -- "--png-linear|--alpha|--stadium" "$OUT"'
run "$dir" help verify
check "help verify = verify --help" eval 'test "$RC" -eq 0 && grep -q -- "--alpha" "$OUT" && ! grep -q -- "--png-linear" "$OUT"'
run "$dir" list --help
check "list --help: exit 0" eval 'test "$RC" -eq 0 && grep -q "caustic list" "$OUT"'
run "$dir" --help
check "--help: every command" eval 'test "$RC" -eq 0 && grep -q -- "--png-linear" "$OUT" && grep -q -- "--alpha" "$OUT" && grep -q -- "--stadium" "$OUT" && grep -q "caustic list" "$OUT"'

# --------------------------------------------------------------- --version
run "$dir" --version
check "--version: first line 'caustic <version>'" eval 'test "$RC" -eq 0 && head -1 "$OUT" | grep -Eq "^caustic [0-9]+\.[0-9]+\.[0-9]+$"'
for key in build compiler isa embree mpi sdl2; do
    check "--version states $key" grep -Eq "^$key: +[^ ]" "$OUT"
done
check "--version: the ISA is a known level" grep -Eq "^isa: +(AVX-512|AVX2|AVX|SSE4\.2|SSE2|generic)" "$OUT"

# --------------------------------------------------------------- caustic list
dir=$TMP/list
run "$dir" list
check "list: exit 0, every kind" eval 'test "$RC" -eq 0 && for k in integrators samplers filters accels materials lights formats metals; do grep -q "^$k" "$OUT" || exit 1; done'
run "$dir" list integrators
names=$(cat "$OUT")
check "list integrators: path ... vcm, one per line" eval 'echo "$names" | grep -qx path && echo "$names" | grep -qx vcm && echo "$names" | grep -qx bdpt'
ok=1
for n in $names; do
    run "$dir" render --integrator "$n" --width 4 --height 4 --spp 1 -o i.png -q
    [ "$RC" -eq 0 ] || { ok=0; fail "list integrators: '$n' renders" "exit $RC"; }
done
[ $ok -eq 1 ] && pass "list integrators: every name renders"
run "$dir" list accels
ok=1
for n in $(cat "$OUT"); do
    run "$dir" info --accel "$n"
    [ "$RC" -eq 0 ] || { ok=0; fail "list accels: '$n' builds" "exit $RC"; }
done
[ $ok -eq 1 ] && pass "list accels: every back end builds"
# `info` counts the lights of every kind: an environment-lit scene has no emitting shape
# but is lit (it printed only "emitters: 0" before).
cat >"$dir/env.json" <<'JSON'
{"camera": {"type": "pinhole", "position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
 "materials": {"w": {"type": "diffuse"}},
 "environment": {"radiance": [1, 1, 1]},
 "shapes": [{"type": "sphere", "center": [0, 0, 0], "radius": 1, "material": "w"}]}
JSON
run "$dir" info env.json
check "info: an environment-only scene has 0 emitters and 1 light" \
    eval 'test "$RC" -eq 0 && grep -q "^emitters: *0 " "$OUT" && grep -q "^lights: *1 " "$OUT"'
run "$dir" list formats
ok=1
for n in $(cat "$OUT"); do
    run "$dir" render --width 4 --height 4 --spp 1 -o "f.$n" -q
    [ "$RC" -eq 0 ] && [ -s "$dir/f.$n" ] || { ok=0; fail "list formats: '.$n' is written" "exit $RC"; }
done
[ $ok -eq 1 ] && pass "list formats: every format is written"
run "$dir" list bogus
check "list bogus: exit 2 naming the kinds" eval 'test "$RC" -eq 2 && grep -q "kinds:" "$ERR"'

# --------------------------------------------------------------- progress with an ETA
dir=$TMP/progress
# 16 x 16 is one tile: the render is cut into passes so that progress moves.
run "$dir" render --width 16 --height 16 --spp 3000 -o p.png
n=$(grep -Ec '^caustic: [0-9]+% \(elapsed [0-9]+\.[0-9] s, ETA [0-9]+:[0-9]{2}\)$' "$ERR")
check "high spp, one tile: plain lines with an ETA ($n)" test "$RC" -eq 0 -a "$n" -ge 3
check "non-TTY progress: no carriage return" eval '! grep -q $'"'"'\r'"'"' "$ERR"'
run "$dir" render --integrator sppm --width 8 --height 8 --spp 300 -o s.png
n=$(grep -Ec '^caustic: [0-9]+% \(elapsed .*, ETA [0-9]+:[0-9]{2}\)$' "$ERR")
check "SPPM iterations: plain lines with an ETA ($n)" test "$RC" -eq 0 -a "$n" -ge 3
run "$dir" render --integrator photon --width 8 --height 8 --spp 1 -o ph.png
check "photon pass: its own progress lines, to 100%" \
    eval 'test "$RC" -eq 0 && grep -Eq "^caustic: photons 100% \(elapsed" "$ERR" && grep -Eq "^caustic: 100% \(elapsed" "$ERR"'

# --------------------------------------------------------------- --json summary
dir=$TMP/json
run "$dir" render --width 8 --height 8 --spp 2 -o j.png --json
ok=1
for re in '"output": ?"j.png"' '"seconds": ?\{"load": ?[0-9.e-]+, ?"accel": ?[0-9.e-]+, ?"render": ?[0-9.e-]+, ?"write": ?[0-9.e-]+' \
          '"rays": ?[1-9]' '"samples": ?128[,}]' '"samples_per_second": ?[0-9]' '"nonfinite_discarded": ?0' \
          '"peak_rss_bytes": ?[1-9]' '"image_memory_estimate_bytes": ?[1-9]'; do
    grep -Eq -- "$re" "$OUT" || { ok=0; fail "--json: stdout has /$re/"; }
done
[ $ok -eq 1 ] && [ "$RC" -eq 0 ] && [ "$(wc -l <"$OUT")" -eq 1 ] && pass "--json: one object on stdout with times, work and memory"
if command -v python3 >/dev/null 2>&1; then
    check "--json: valid JSON" python3 -c 'import json,sys; json.load(open(sys.argv[1]))' "$OUT"
fi
run "$dir" render --width 8 --height 8 --spp 2 -o k.png --json=sum.json
check "--json=FILE: the summary in FILE, stdout empty" \
    eval 'test "$RC" -eq 0 -a ! -s "$OUT" && grep -q "\"output\":\"k.png\"" "$dir/sum.json"'
run "$dir" render --width 8 --height 8 --spp 2 -o l.png --json=no/such/dir/sum.json
check "--json=FILE in a missing directory: exit 2 before rendering" \
    eval 'test "$RC" -eq 2 -a ! -e "$dir/l.png"'

# --------------------------------------------------------------- the memory check
dir=$TMP/memory
avail_kb=$(sed -nE 's/^MemAvailable: +([0-9]+) kB/\1/p' /proc/meminfo 2>/dev/null)
# 65536 x 65536 pixels need about 257 GB (60 bytes each).
if [ -n "$avail_kb" ] && [ "$avail_kb" -lt 200000000 ]; then
    run "$dir" render --width 65536 --height 65536 --spp 1 -o big.png
    check "a render larger than the memory: refused (exit 2) naming --force" \
        eval 'test "$RC" -eq 2 && grep -Eq "error: .*GB.*available.*--force" "$ERR" && test ! -e "$dir/big.png"'
    run "$dir" render --width 65536 --height 65536 --crop 0,8,0,8 --spp 1 -o big.png --quiet
    check "the check counts the whole film, also with a crop (refused)" test "$RC" -eq 2
else
    echo "SKIP: memory check (MemAvailable unknown or above 200 GB)"
fi
run "$dir" render --width 8 --height 8 --spp 1 -o small.png --force -q
check "--force on a render that fits: exit 0" test "$RC" -eq 0 -a -s "$dir/small.png"

harness_finish
