# --noise TARGET (issue 29): bad targets and integrators without per-pixel variances exit 2
# with a message; a render stops within the target and says so on its summary line (the
# estimate against a reference: test_noise); a checkpointed and resumed render is
# byte-identical to one in a single go.
# usage: bash noise_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init noise_tests "$@"

SMALL=(--width 48 --height 32 --threads 2)
d=$TMP/noise

for v in -0.1 0 nan NaN inf 1e999 "" 0.01x; do
    harness_run "$d" 30 render "${SMALL[@]}" --noise "$v" -o x.png
    expect "--noise '$v' refused" 2 "--noise: expected a relative standard error > 0"
done
for integ in sppm pssmlt; do
    harness_run "$d" 30 render "${SMALL[@]}" --noise 0.05 --integrator "$integ" -o x.png
    expect "--noise with $integ refused" 2 "noise target: the $integ integrator"
done

harness_run "$d" 60 render "${SMALL[@]}" --noise 0.05 -o n.pfm
expect "--noise 0.05 stops and reports its estimate" 0 \
    "noise [0-9.e-]+ rms over 6 blocks \(95% CI [0-9.e-]+-[0-9.e-]+\), max 0\.0[0-4][0-9]*, 0 above the target"

harness_run "$d" 60 render "${SMALL[@]}" --noise 0.02 -o full.pfm
harness_run "$d" 60 render "${SMALL[@]}" --noise 0.02 --spp 16 -o part.pfm --checkpoint s.state
harness_run "$d" 60 render "${SMALL[@]}" --noise 0.02 -o resumed.pfm --resume s.state
if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/resumed.pfm"; then pass "--noise: checkpoint at 16 spp + resume, byte for byte"
else fail "--noise: checkpoint at 16 spp + resume, byte for byte" "exit $RC"; fi
harness_run "$d" 60 render "${SMALL[@]}" --noise 0.03 -o other.pfm --resume s.state
expect "--resume with another --noise refused" 2 "noise: 0.02 in the state, 0.0299+ here"

harness_finish
