# caustic explain (issue 30): the text and JSON of one pixel sample, with the sum checked
# against the render's value (exit 0); bad arguments refused with exit 2 and a message.
# usage: bash explain_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init explain_tests "$@"

SMALL=(--width 24 --height 20)
d=$TMP/run

HARNESS_EXPECT_STDOUT=1
harness_run "$d" 60 explain --pixel 12,10 --sample 3 "${SMALL[@]}"
expect "path: text, sum equal bit for bit" 0 '^vertex 1: surface at' 'NEE: light [0-9]+' 'MIS w' 'largest contribution: ' \
    'equal, bit for bit'
# A spectral camera ray that misses everything (the sky of an environment map): the recorder
# must still get the path's wavelengths (it read MISMATCH before path.c recorded them there).
harness_run "$d" 60 explain "$SRC/scenes/material-showcase.json" --pixel 2,2 --spectral --width 32 --height 18
expect "path: spectral sky pixel, sum equal bit for bit" 0 'escape at vertex 0' 'equal, bit for bit'
harness_run "$d" 60 explain --pixel 12,10 --sample 1 --integrator bdpt "${SMALL[@]}" --json
expect "bdpt: JSON, exact" 0 '"exact": true' '"kind": "connect"' '"w_light"' '"splat_value"'
harness_run "$d" 60 explain --pixel 12,10 --sample 1 --integrator bdpt "${SMALL[@]}"
expect "bdpt: text, explicit MIS check" 0 'explicitly [0-9.e-]+ of [0-9]+ strategies' 'MIS check: [0-9]+ strategies'
# The pixel's light subpath listed before the camera's (not summed): hits, scatters with
# both densities, roulette.
expect "bdpt: text, the light subpath" 0 "^the pixel's light subpath" '^light vertex 1 \(bounces from the emitter\)' \
    'scatter \(diffuse reflection\): non-delta lobes, pdf_w [0-9.e-]+, reverse pdf_w [0-9.e-]+' \
    'roulette: survival probability' '^the camera subpath:'
harness_run "$d" 60 explain --pixel 12,10 --sample 1 --integrator bdpt "${SMALL[@]}" --json
expect "bdpt: JSON, the light subpath" 0 '"depth": -1' '"pdf_rev"' '"exact": true'
# volpath's NEE: the shadow ray's transmittance, and occluded when the block hides the light.
harness_run "$d" 60 explain "$SRC/tests/render/media/cornell-fog.pbrt" --pixel 12,10 "${SMALL[@]}"
expect "path in fog: NEE transmittance and occlusion" 0 'phase pdf_w [0-9.e-]+; MIS w [0-9.e-]+, transmittance \(' \
    'MIS w 1, occluded' 'equal, bit for bit'
harness_run "$d" 60 explain "$SRC/tests/render/media/cornell-fog.pbrt" --pixel 12,10 "${SMALL[@]}" --json
expect "path in fog: JSON transmittance" 0 '"transmittance"' '"occluded": true' '"exact": true'
# VCM with a radius large enough for this small image's light vertices to merge: every merge
# and splat near the pixel checked against the weights computed from the whole path.
mkdir -p "$TMP/vcm"
sed 's/"integrator": {[^}]*}/"integrator": {"type": "vcm", "radius": 20}/' "$SRC/scenes/cornell-spheres.json" \
    > "$TMP/vcm/spheres.json"
harness_run "$d" 60 explain "$TMP/vcm/spheres.json" --pixel 3,17 "${SMALL[@]}"
expect "vcm: text, explicit MIS check of merges and splats" 0 'equal, bit for bit' \
    '  merge \(s=[0-9]+, t=[0-9]+\).*explicitly [0-9.e-]+ of [0-9]+ strategies' \
    'splat \(s=[0-9]+, t=1\) of light path [0-9]+ .*explicitly [0-9.e-]+ of [0-9]+ strategies' \
    'MIS check: [0-9]+ strategies' 'the camera sample and the splats sum to it, bit for bit'
harness_run "$d" 60 explain "$TMP/vcm/spheres.json" --pixel 3,17 "${SMALL[@]}" --json
expect "vcm: JSON, splats exact" 0 '"kind": "merge"' '"mis_explicit"' '"splats_exact": true'
# A path through a subsurface material (path_sss.c): the BSSRDF's exit is printed.
harness_run "$d" 60 explain "$SRC/tests/render/subsurface/sss-spheres.pbrt" --pixel 40,64 --width 128 --height 128
expect "path: subsurface exit, sum equal bit for bit" 0 'subsurface exit at .* probe hits' 'equal, bit for bit'
harness_run "$d" 60 explain --pixel 12,12 --integrator whitted "${SMALL[@]}"
expect "whitted: text, exact" 0 'direct light' 'equal, bit for bit'
harness_run "$d" 60 explain --pixel 12,10 --integrator light "${SMALL[@]}"
expect "light: text, exact" 0 "light path [0-9]+'s connection" 'the splats sum to it, bit for bit'
harness_run "$d" 60 explain --pixel 12,10 --sample 3 --why-bright "${SMALL[@]}"
expect "--why-bright: one line" 0 '^why bright: [a-z]+ at vertex [0-9]+ gives [0-9.]+% of the sample'
harness_run "$d" 60 explain --pixel 12,10 --sample 3 --why-dark "${SMALL[@]}"
expect "--why-dark: one line" 0 '^why dark: value \(' 'the path has [0-9]+ vertices'
harness_run "$d" 60 explain --pixel=3,4 --integrator path-bsdf "${SMALL[@]}" --json=out.json
if [ "$RC" -eq 0 ] && grep -q '"exact": true' "$d/out.json"; then pass "--json=FILE"; else fail "--json=FILE" "exit $RC"; fi
harness_run "$d" 60 explain --help
expect "explain --help" 0 'caustic explain \[SCENE\] --pixel X,Y'
harness_run "$d" 30 explain --pixel 12,10 --integrator photon "${SMALL[@]}"
expect "photon: estimates, sum equal bit for bit" 0 "global .final gather. map's estimate over those [0-9]+ photons" \
    'equal, bit for bit'
# sppm: iteration 2 of the glass sphere's caustic, its photons and update, equal to the film of
# a 3-iteration render bit for bit; --why-bright names the largest photon or the direct light.
harness_run "$d" 60 explain "$SRC/scenes/cornell-spheres.json" --integrator sppm --pixel 21,24 --sample 2 \
    --width 32 --height 32
expect "sppm: text, value equal bit for bit" 0 '^pixel \(21, 24\), iteration 2 of sppm' 'delta lobe, pmf' \
    'photons gathered in the disc of radius' 'progressive update .*: N [0-9.e+-]+ -> ' \
    'state equal to the render.s, bit for bit' 'render with --spp 3 \(iterations 0..2\): .*: equal, bit for bit'
harness_run "$d" 60 explain --integrator sppm --pixel 16,16 --sample 1 --width 32 --height 32 --json
expect "sppm: JSON, exact" 0 '"exact": true' '"kind": "photon"' '"bounces"' '"sppm": \{' '"state_exact": true'
harness_run "$d" 60 explain --integrator sppm --pixel 16,16 --sample 1 --width 32 --height 32 --why-bright
expect "sppm: --why-bright" 0 '^why bright: (photon path [0-9]+|the direct light)'
# pssmlt and mmlt: the Metropolis steps whose splats reach the pixel in iteration 1, re-added
# to the iteration's value (small bootstraps and chains keep it cheap).
mkdir -p "$TMP/mlt"
for integ in pssmlt mmlt; do
    sed "s/\"integrator\": {[^}]*}/\"integrator\": {\"type\": \"$integ\", \"bootstrap_samples\": 2048, \"chains\": 16, \"max_depth\": 4}/" \
        "$SRC/scenes/cornell-box.json" > "$TMP/mlt/$integ.json"
done
harness_run "$d" 60 explain "$TMP/mlt/pssmlt.json" --pixel 12,3 --sample 1 --width 16 --height 16
expect "pssmlt: text, splats exact" 0 'integrator pssmlt' 'chain [0-9]+, step [0-9]+ \((large|small) step, a [0-9.e-]+' \
    'b \(the bootstrap.s normalisation\)' 'the splats sum to the iteration.s value, bit for bit' \
    'sample evaluated again from its primary sample vector: L .*the splatted L, bit for bit' '^    \| vertex 1: surface at' \
    '^    \|   (NEE|emission)'
harness_run "$d" 60 explain "$TMP/mlt/mmlt.json" --pixel 8,2 --width 16 --height 16 --json
expect "mmlt: JSON, exact" 0 '"kind": "mutation"' '"path_length": [0-9]' '"mlt_b"' '"exact": true' '"path": \[' \
    '"replay_exact": true' '"mlt_replay_exact": [1-9]'
harness_run "$d" 60 explain "$TMP/mlt/mmlt.json" --pixel 8,2 --width 16 --height 16
expect "mmlt: text, the strategies' paths" 0 '^    \| +(emission \(s=0|NEE \(s=1|connect \(s=[0-9]+|splat \(s=[0-9]+, t=1\)).*MIS w' \
    'the splatted L, bit for bit'
# photon with a moving instance: the kernel printed is the time window's scaled one.
harness_run "$d" 60 explain "$SRC/tests/render/explain/moving-box.json" --pixel 12,10
expect "photon, moving box: the windowed kernel" 0 'box kernel s/\(pi r\^2\) [0-9.e-]+ \(photons of times \[[0-9.e-]+, [0-9.e-]+\] only, s = shutter / window = [0-9.]+\)' \
    'equal, bit for bit'
harness_run "$d" 60 explain "$TMP/mlt/mmlt.json" --pixel 8,2 --width 16 --height 16 --why-bright
expect "mmlt: --why-bright" 0 '^why bright: the (proposal|current state).s splat of chain [0-9]+'
HARNESS_EXPECT_STDOUT=0

harness_run "$d" 30 explain "${SMALL[@]}"
expect "no --pixel" 2 'expected --pixel X,Y'
harness_run "$d" 30 explain --pixel 12 "${SMALL[@]}"
expect "--pixel without Y" 2 '--pixel: expected X,Y'
harness_run "$d" 30 explain --pixel 1,-2 "${SMALL[@]}"
expect "--pixel negative" 2 '--pixel: expected X,Y'
harness_run "$d" 30 explain --pixel 24,0 "${SMALL[@]}"
expect "--pixel off the image" 2 'pixel 24,0: expected 0 <= x < 24'
harness_run "$d" 30 explain --pixel 1,1 --sample x "${SMALL[@]}"
expect "--sample not a number" 2 '--sample: expected an integer'
# photon through fog (the pbrt scene is spectral): the flight to a medium vertex, its NEE, the
# volume map's photons and estimate, the sample's wavelengths and photon set; sum exact
HARNESS_EXPECT_STDOUT=1
harness_run "$d" 60 explain "$SRC/tests/render/media/cornell-fog.pbrt" --pixel 20,20 --integrator photon \
    --width 48 --height 48
expect "photon in fog, spectral: volume estimate, sum equal bit for bit" 0 'photon set [0-9]+' \
    '^wavelengths \([0-9.]+, ' 'distance in medium 0: scatters after' '^vertex 1: in medium 0 at' \
    "volume map's estimate over those [0-9]+ photons" 'equal, bit for bit'
HARNESS_EXPECT_STDOUT=0
# bad pixels and samples are refused with a reason (every integrator is explained)
harness_run "$d" 30 explain missing.json --pixel 1,1
expect "missing scene" 2 'cannot open scene'
harness_run "$d" 30 render --why-dark "${SMALL[@]}" -o x.png
expect "--why-dark is explain's" 2 "--why-dark is an option of 'explain'"
harness_run "$d" 30 render --pixel 1,1 "${SMALL[@]}" -o x.png
expect "--pixel is explain's" 2 "--pixel is an option of 'explain'"

harness_finish
