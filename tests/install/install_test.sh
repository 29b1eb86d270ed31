#!/usr/bin/env bash
# The installed library as a consumer sees it: `cmake --install` into a prefix inside the
# build tree, then examples/embed.c compiled with only `pkg-config --cflags --libs
# caustic` (and once through find_package(caustic) in a tiny CMake project), run, and
# its EXR checked. Run by CTest:
#   bash install_test.sh <build-dir> <source-dir> [extra cc flags, e.g. sanitizers]
set -euo pipefail
build=$(realpath "$1"); src=$(realpath "$2"); shift 2
extra=(); for a in "$@"; do [ -n "$a" ] && extra+=("$a"); done # CTest passes "" for none
prefix=$build/install-test
work=$(mktemp -d "${TMPDIR:-/tmp}/caustic-install-test.XXXXXX")
trap 'rm -rf "$work" "$prefix"' EXIT

cmake --install "$build" --prefix "$prefix" >/dev/null
for f in include/caustic/caustic.h lib/libcaustic.a lib/libcaustic.so bin/caustic \
         lib/pkgconfig/caustic.pc lib/cmake/caustic/causticConfig.cmake \
         lib/cmake/caustic/causticConfigVersion.cmake; do
  [ -e "$prefix/$f" ] || { echo "FAIL: $f not installed"; exit 1; }
done
echo "PASS: headers, both libraries, the CLI, caustic.pc and the CMake package installed"

# The consumer gets no ISA or floating-point flags from the package.
flags=$(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --cflags --libs caustic)
case "$flags" in *-march*|*-ffp-contract*|*-fsanitize*) echo "FAIL: pkg-config exports build flags: $flags"; exit 1;; esac
# shellcheck disable=SC2086
cc -std=c17 -Wall -Wextra -Werror "${extra[@]}" "$src/examples/embed.c" $flags -o "$work/embed"
LD_LIBRARY_PATH=$prefix/lib "$work/embed" "$work/embed.exr"
[ -s "$work/embed.exr" ] || { echo "FAIL: embed wrote no EXR"; exit 1; }
echo "PASS: examples/embed.c built with pkg-config against the installed library, ran, wrote an EXR"

# find_package(caustic): caustic::caustic links and carries the include directory.
mkdir -p "$work/cmake"
cat >"$work/cmake/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.25)
project(embed_consumer C)
find_package(caustic 0.1 REQUIRED CONFIG)
add_executable(embed "$src/examples/embed.c")
target_link_libraries(embed PRIVATE caustic::caustic)
CMAKE
CFLAGS="${extra[*]}" cmake -S "$work/cmake" -B "$work/cmake/build" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build "$work/cmake/build" >/dev/null
LD_LIBRARY_PATH=$prefix/lib "$work/cmake/build/embed" "$work/embed2.exr" >/dev/null
[ -s "$work/embed2.exr" ] || { echo "FAIL: the find_package build wrote no EXR"; exit 1; }
echo "PASS: examples/embed.c built with find_package(caustic) / caustic::caustic and ran"
