# caustic explain (issue 30): the text and JSON of one pixel sample, with the sum checked
# against the render's value (exit 0); bad arguments and integrators explain cannot follow
# refused with exit 2 and a message.
# usage: bash explain_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init explain_tests "$@"

SMALL=(--width 24 --height 20)
d=$TMP/run

HARNESS_EXPECT_STDOUT=1
harness_run "$d" 60 explain --pixel 12,10 --sample 3 "${SMALL[@]}"
expect "path: text, sum equal bit for bit" 0 '^vertex 1: surface at' 'NEE: light [0-9]+' 'MIS w' 'largest contribution: ' \
    'equal, bit for bit'
harness_run "$d" 60 explain --pixel 12,10 --sample 1 --integrator bdpt "${SMALL[@]}" --json
expect "bdpt: JSON, exact" 0 '"exact": true' '"kind": "connect"' '"w_light"' '"splat_value"'
harness_run "$d" 60 explain --pixel=3,4 --integrator path-bsdf "${SMALL[@]}" --json=out.json
if [ "$RC" -eq 0 ] && grep -q '"exact": true' "$d/out.json"; then pass "--json=FILE"; else fail "--json=FILE" "exit $RC"; fi
harness_run "$d" 60 explain --help
expect "explain --help" 0 'caustic explain \[SCENE\] --pixel X,Y'
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
harness_run "$d" 30 explain --pixel 1,1 --integrator vcm "${SMALL[@]}"
expect "vcm refused" 2 'explain supports: path, path-nee, path-bsdf, bdpt; not vcm'
harness_run "$d" 30 explain --pixel 1,1 --integrator light "${SMALL[@]}"
expect "light refused" 2 'explain supports: '
harness_run "$d" 30 explain missing.json --pixel 1,1
expect "missing scene" 2 'cannot open scene'
harness_run "$d" 30 render --pixel 1,1 "${SMALL[@]}" -o x.png
expect "--pixel is explain's" 2 "--pixel is an option of 'explain'"

harness_finish
