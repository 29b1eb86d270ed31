#!/usr/bin/env bash
# The installed static library links from pkg-config alone: examples/embed.c built against
# libcaustic.a with `pkg-config --static --cflags --libs caustic` (Libs.private and
# Requires.private must name every private dependency, Embree included when it is built
# in), run, and its EXR checked. Run by CTest:
#   bash static_link_test.sh <build-dir> <source-dir> [extra cc flags, e.g. sanitizers]
set -euo pipefail
build=$(realpath "$1"); src=$(realpath "$2"); shift 2
extra=(); for a in "$@"; do [ -n "$a" ] && extra+=("$a"); done # CTest passes "" for none
prefix=$build/install-static-test # not install_test.sh's prefix: CTest may run both at once
work=$(mktemp -d "${TMPDIR:-/tmp}/caustic-static-test.XXXXXX")
trap 'rm -rf "$work" "$prefix"' EXIT

cmake --install "$build" --prefix "$prefix" >/dev/null
flags=$(PKG_CONFIG_PATH=$prefix/lib/pkgconfig pkg-config --static --cflags --libs caustic)
# -l:libcaustic.a: the archive, not the shared library beside it.
flags=${flags/-lcaustic/-l:libcaustic.a}
# shellcheck disable=SC2086
if ! cc -std=c17 "${extra[@]}" "$src/examples/embed.c" $flags -o "$work/embed" 2>"$work/link.log"; then
  echo "FAIL: a static link with pkg-config --static failed ($flags):"; tail -5 "$work/link.log"; exit 1
fi
if ldd "$work/embed" | grep -q 'libcaustic\.so'; then echo "FAIL: linked libcaustic.so, not the archive"; exit 1; fi
"$work/embed" "$work/embed.exr" >/dev/null
[ -s "$work/embed.exr" ] || { echo "FAIL: the statically linked embed wrote no EXR"; exit 1; }
echo "PASS: examples/embed.c linked against libcaustic.a with pkg-config --static, ran, wrote an EXR"
