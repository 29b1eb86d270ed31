#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz, -DCST_FUZZ=ON with clang, in build-fuzz/) and
# runs each for SECONDS (default 60), two at a time, starting from its committed seed
# corpus tests/fuzz/corpus/<target>/ (new inputs go to build-fuzz/corpus/<target>/, the
# repository is not touched). Fails on any finding: a crash, a sanitizer report, a leak,
# an input slower than FUZZ_TIMEOUT seconds or one needing more than 2 GB.
#   scripts/fuzz.sh [SECONDS] [TARGET...]        e.g. scripts/fuzz.sh 600 fuzz_pbrt
# FUZZ_RUNS=N runs each target for N executions instead of a time; FUZZ_JOBS (default 2)
# targets run at once. Reproduce a finding with: build-fuzz/TARGET ARTIFACT. See docs/fuzzing.md.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_scene_json fuzz_pbrt fuzz_mesh fuzz_image fuzz_ply fuzz_spd fuzz_bsdf fuzz_state fuzz_view_script)
jobs=${FUZZ_JOBS:-2}
build=${FUZZ_BUILD_DIR:-build-fuzz}

command -v clang >/dev/null || { echo "fuzz: clang (with libFuzzer) is needed" >&2; exit 2; }
# FUZZ_SPECTRUM_TABLE: a spectrum table another tree solved, copied instead of solved
# (CMakeLists.txt, CST_SPECTRUM_TABLE_FROM). -g1: line tables, all a report needs.
# Ninja where it is installed and the tree is new (Make builds the listed targets one after
# another, each a single source file: .ci/run). An existing tree keeps its generator.
command -v ninja >/dev/null && export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}
CC=clang cmake -S . -B "$build" -DCST_FUZZ=ON -DCST_BUILD_TESTS=OFF -DCST_EMBREE=OFF \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1" \
  ${FUZZ_SPECTRUM_TABLE:+-DCST_SPECTRUM_TABLE_FROM="$FUZZ_SPECTRUM_TABLE"} >/dev/null
cmake --build "$build" -j2 --target "${targets[@]}"

# Per target: the longest input worth mutating, and its dictionary (if any).
declare -A max_len=([fuzz_scene_json]=8192 [fuzz_pbrt]=8192 [fuzz_mesh]=16384 [fuzz_image]=4096 [fuzz_ply]=16384 [fuzz_spd]=4096 [fuzz_state]=4096
                    [fuzz_bsdf]=8192)
declare -A dict=([fuzz_scene_json]=tests/fuzz/scene_json.dict [fuzz_pbrt]=tests/fuzz/pbrt.dict
                 [fuzz_mesh]=tests/fuzz/mesh.dict [fuzz_image]=tests/fuzz/image.dict
                 [fuzz_ply]=tests/fuzz/mesh.dict [fuzz_bsdf]=tests/fuzz/bsdf.dict)

run_one() {
  local t=$1 work="$build/corpus/$1" art="$build/artifacts/$1/" limit
  mkdir -p "$work" "$art"
  if [ -n "${FUZZ_RUNS:-}" ]; then limit="-runs=$FUZZ_RUNS"; else limit="-max_total_time=$seconds"; fi
  # Leaks are findings (detect_leaks is libFuzzer's default under ASan); UB aborts (the
  # build's -fno-sanitize-recover).
  # assimp's own leaks on failed imports are suppressed (tests/fuzz/lsan.supp); the slow
  # unwinder, needed for LSan to see that an allocation was assimp's, only where assimp runs.
  local asan=detect_leaks=1
  [ "$t" = fuzz_mesh ] && asan=$asan:fast_unwind_on_malloc=0
  ASAN_OPTIONS=${ASAN_OPTIONS:-$asan} \
  LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tests/fuzz/lsan.supp:print_suppressions=0} \
  "$build/$t" "$limit" \
    -timeout="${FUZZ_TIMEOUT:-30}" -rss_limit_mb=2048 -max_len="${max_len[$t]:-4096}" \
    ${dict[$t]:+-dict=${dict[$t]}} -artifact_prefix="$art" -print_final_stats=1 \
    "$work" "tests/fuzz/corpus/$t" >"$build/$t.log" 2>&1
}

mkdir -p "$build"
declare -A pid_of=()
status=0
finish() { # finish PID STATUS: report the target that ran under it
  local t=${pid_of[$1]} rc=$2 runs
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$build/$t.log" | tail -n1)
  if [ $rc -eq 0 ]; then
    echo "fuzz: $t: ${runs:-?} executions, no finding"
  elif [ $rc -eq 72 ]; then # libFuzzer's -interrupted_exitcode: SIGINT/SIGTERM, not a finding
    status=1
    echo "fuzz: $t: interrupted after ${runs:-?} executions (no finding; the run did not complete)" >&2
  else
    status=1
    echo "fuzz: $t: FINDING (exit $rc) after ${runs:-?} executions; log $build/$t.log:" >&2
    grep -E "^(==|SUMMARY|.*runtime error|.*Test unit written)" "$build/$t.log" | head -n 20 >&2 || true
  fi
  unset "pid_of[$1]"
}
for t in "${targets[@]}"; do
  [ -d "tests/fuzz/corpus/$t" ] || { echo "fuzz: no seed corpus tests/fuzz/corpus/$t" >&2; exit 2; }
  while [ ${#pid_of[@]} -ge "$jobs" ]; do
    rc=0
    wait -n -p done_pid "${!pid_of[@]}" || rc=$?
    finish "$done_pid" "$rc"
  done
  run_one "$t" &
  pid_of[$!]=$t
done
for p in "${!pid_of[@]}"; do
  rc=0
  wait "$p" || rc=$?
  finish "$p" "$rc"
done
exit $status
