#!/usr/bin/env bash
# Two builds of the CLI, one by GCC and one by Clang, must render every committed scene with
# every integrator bit for bit alike (scripts/render-hashes.sh). A difference is a bug: an
# order of evaluation C leaves unspecified (two random draws in one call's arguments), a
# contracted multiply-add (the build uses -ffp-contract=off), uninitialised memory, or a
# libm function that rounds differently. Run by .ci/run:
#   tests/render/compiler_identity.sh build/caustic build-clang/caustic
# Exit 0 when every line matches, 1 (printing the differing lines) otherwise.
set -euo pipefail
gcc_bin=${1:?usage: compiler_identity.sh GCC_BIN CLANG_BIN}
clang_bin=${2:?usage: compiler_identity.sh GCC_BIN CLANG_BIN}
here=$(dirname "$0")
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
bash "$here/../../scripts/render-hashes.sh" "$gcc_bin" >"$out/gcc.txt"
bash "$here/../../scripts/render-hashes.sh" "$clang_bin" >"$out/clang.txt"
renders=$(wc -l <"$out/gcc.txt")
if [ "$renders" -eq 0 ] || grep -q FAILED "$out/gcc.txt" "$out/clang.txt"; then
  echo "compiler_identity: a render failed or nothing was rendered:"
  grep -h FAILED "$out/gcc.txt" "$out/clang.txt" || true
  exit 1
fi
if ! diff "$out/gcc.txt" "$out/clang.txt" >"$out/diff.txt"; then
  echo "compiler_identity: renders differ between GCC (<) and Clang (>), scene integrator hash:"
  grep '^[<>]' "$out/diff.txt"
  exit 1
fi
echo "compiler_identity: all $renders renders identical with GCC and Clang"
