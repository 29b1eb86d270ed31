# caustic merge and --sample-block (issue 29): renders of [0, 8) and [8, 16) merged are byte
# for byte one 16-sample render with the same block, for every integrator that keeps film
# sums; the block changes nothing at 1; mismatched, overlapping, gapped and multi-block
# states are refused with exit 2 and a message naming what differs.
# usage: bash merge_tests.sh <caustic> <source-dir>
. "$(dirname "${BASH_SOURCE[0]}")/harness.sh"
harness_init merge_tests "$@"

SMALL=(--width 40 --height 32 --threads 2 --quiet)

# ------------------------------------------------------------ [0,8) + [8,16) = 16
for integ in path light bdpt vcm; do
    d=$TMP/$integ
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 16 --sample-block 8 -o full.pfm
    [ "$RC" -eq 0 ] || { fail "$integ: 16 spp in blocks of 8" "exit $RC"; continue; }
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 8 --sample-block 8 -o a.pfm \
        --checkpoint a.state
    harness_run "$d" 120 render --integrator "$integ" "${SMALL[@]}" --spp 8 --sample-block 8 --first-sample 8 \
        -o b.pfm --checkpoint b.state
    [ "$RC" -eq 0 ] && [ -s "$d/a.state" ] && [ -s "$d/b.state" ] || { fail "$integ: the two halves" "exit $RC"; continue; }
    # The order on the command line does not matter.
    harness_run "$d" 60 merge b.state a.state -o merged.pfm
    if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/merged.pfm"; then
        pass "$integ: merge of [0, 8) and [8, 16) = 16 spp, byte for byte"
    else
        fail "$integ: merge of [0, 8) and [8, 16) = 16 spp, byte for byte" "exit $RC"
    fi
done

# Three parts, the first of two blocks, the last a partial block: [0, 8) [8, 12) [12, 14) with
# blocks of 4 = one render of 14 spp in blocks of 4.
d=$TMP/three
harness_run "$d" 120 render "${SMALL[@]}" --spp 14 --sample-block 4 -o full.pfm
harness_run "$d" 120 render "${SMALL[@]}" --spp 8 --sample-block 4 -o x.pfm --checkpoint a.state
harness_run "$d" 120 render "${SMALL[@]}" --spp 4 --first-sample 8 --sample-block 4 -o x.pfm --checkpoint b.state
harness_run "$d" 120 render "${SMALL[@]}" --spp 2 --first-sample 12 --sample-block 4 -o x.pfm --checkpoint c.state
harness_run "$d" 60 merge a.state b.state c.state -o merged.pfm
if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/merged.pfm"; then pass "[0, 8) + [8, 12) + [12, 14), blocks of 4 = 14 spp"
else fail "[0, 8) + [8, 12) + [12, 14), blocks of 4 = 14 spp" "exit $RC"; fi
harness_run "$d" 60 merge a.state b.state c.state -o merged.png
expect "merge's summary line" 0 "merged 3 states, samples \[0, 14\) of 40x32 pixels, into merged.png"

# A block of 1 is what a render always did: same image as without --sample-block.
d=$TMP/one
harness_run "$d" 120 render "${SMALL[@]}" --spp 5 -o plain.pfm
harness_run "$d" 120 render "${SMALL[@]}" --spp 5 --sample-block 1 -o one.pfm
if [ "$RC" -eq 0 ] && cmp -s "$d/plain.pfm" "$d/one.pfm"; then pass "--sample-block 1 = the plain render"
else fail "--sample-block 1 = the plain render" "exit $RC"; fi
# A resume in blocks continues as the uninterrupted render in blocks.
harness_run "$d" 120 render "${SMALL[@]}" --spp 12 --sample-block 4 -o full.pfm
harness_run "$d" 120 render "${SMALL[@]}" --spp 8 --sample-block 4 -o x.pfm --checkpoint r.state
harness_run "$d" 120 render "${SMALL[@]}" --spp 12 --sample-block 4 -o resumed.pfm --resume r.state
if [ "$RC" -eq 0 ] && cmp -s "$d/full.pfm" "$d/resumed.pfm"; then pass "blocks of 4: 8 spp + resume to 12 = 12 spp"
else fail "blocks of 4: 8 spp + resume to 12 = 12 spp" "exit $RC"; fi

# ------------------------------------------------------------ refusals
d=$TMP/refuse
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 4 -o x.pfm --checkpoint a.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 4 --first-sample 4 -o x.pfm --checkpoint b.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 4 --first-sample 4 --seed 3 -o x.pfm --checkpoint seed.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 4 --first-sample 2 -o x.pfm --checkpoint over.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 4 --first-sample 8 -o x.pfm --checkpoint gap.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 8 --sample-block 4 --first-sample 4 -o x.pfm --checkpoint two.state
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sample-block 2 --first-sample 4 -o x.pfm --checkpoint blk.state
harness_run "$d" 60 merge a.state seed.state -o m.pfm
expect "another seed: refused" 2 "were made for different renders" "seed: 0 in a.state, 3 in seed.state" &&
    check "no image for a refused merge" test ! -e "$d/m.pfm"
harness_run "$d" 60 merge a.state blk.state -o m.pfm
expect "another block size: refused" 2 "sample_block: 4 in a.state, 2 in blk.state"
harness_run "$d" 60 merge a.state over.state -o m.pfm
expect "overlapping ranges: refused" 2 "a.state holds samples \[0, 4\) and over.state \[2, 6\): they overlap"
harness_run "$d" 60 merge a.state gap.state -o m.pfm
expect "a gap: refused" 2 "samples \[4, 8\) are in none of the states"
harness_run "$d" 60 merge a.state two.state -o m.pfm
expect "two blocks after the first state: refused" 2 "two.state holds samples \[4, 12\), more than one block of 4"
harness_run "$d" 60 render "${SMALL[@]}" --spp 4 --sampler stratified -o x.pfm --checkpoint st.state
harness_run "$d" 60 merge st.state -o m.pfm
expect "the stratified sampler: refused" 2 "stratified sampler lays its strata out"
head -c 100 "$d/a.state" >"$d/trunc.state"
harness_run "$d" 60 merge trunc.state b.state -o m.pfm
expect "a truncated state: refused" 2 "trunc.state: truncated"
harness_run "$d" 60 merge a.state b.state
expect "no -o: usage error" 2 "merge: expected state files and -o IMAGE"
harness_run "$d" 60 merge a.state b.state -o m.txt
expect "an unknown image extension: refused" 2
harness_run "$d" 60 merge a.state b.state -o m.pfm
if [ "$RC" -eq 0 ] && [ -s "$d/m.pfm" ]; then pass "a good pair merges"; else fail "a good pair merges" "exit $RC"; fi
harness_run "$d" 60 render "${SMALL[@]}" --spp 2 --integrator sppm --sample-block 2 -o x.pfm
expect "sppm refuses blocks" 2 "SPPM's film is one estimate"

harness_finish
