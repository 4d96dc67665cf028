#!/usr/bin/env bash
# omma as a library of another project: installs the build (`cmake --install`) into a temporary
# prefix, then builds examples/cmake_consumer against it with find_package(omma) and runs it, and
# checks the pkg-config file (version, flags, and a link of the same program with its flags alone).
#   tests/install_consumer_test.sh SOURCE_DIR BUILD_DIR
set -euo pipefail
src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
version=$(head -n1 "$src/VERSION")

cmake --install "$build" --prefix "$work/prefix" >"$work/install.log"
test -x "$work/prefix/bin/omma"
[ "$("$work/prefix/bin/omma" --version | sed -n 1p)" = "omma $version" ] || { echo "installed omma --version is wrong"; exit 1; }
# Man pages (when help2man made them) and bash completion, where man and bash-completion look.
if command -v help2man >/dev/null; then
  for page in omma omma-stitch omma-render; do
    test -f "$work/prefix/share/man/man1/$page.1" || { echo "man page $page.1 not installed"; exit 1; }
  done
  MANPATH="$work/prefix/share/man" man -w omma-stitch | grep -q "/prefix/share/man/man1/omma-stitch.1" ||
    { echo "man does not find omma-stitch"; exit 1; }
fi
grep -q "complete -o filenames -o bashdefault -F _omma omma" "$work/prefix/share/bash-completion/completions/omma" ||
  { echo "bash completion not installed"; exit 1; }
test -f "$work/prefix/include/omma/core/conventions.h"

# CMake: find_package(omma) and omma::omma.
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
cmake -S "$src/examples/cmake_consumer" -B "$work/consumer" "${gen[@]}" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_CXX_COMPILER_LAUNCHER="$(command -v ccache || true)" >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; exit 1; }
cmake --build "$work/consumer" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
line=$("$work/consumer/omma_consumer")
echo "find_package(omma): $line"
case "$line" in "omma $version: 24 cameras, 270x270 vr180 panorama,"*) ;; *) echo "unexpected output"; exit 1 ;; esac

# pkg-config: the same program with the flags of omma.pc alone.
export PKG_CONFIG_PATH="$work/prefix/lib/pkgconfig"
[ "$(pkg-config --modversion omma)" = "$version" ] || { echo "pkg-config --modversion is wrong"; exit 1; }
# shellcheck disable=SC2046
g++ -O1 "$src/examples/cmake_consumer/main.cc" -o "$work/pc_consumer" $(pkg-config --cflags --libs omma) 2>"$work/pc.log" ||
  { cat "$work/pc.log"; exit 1; }
line=$("$work/pc_consumer")
echo "pkg-config omma: $line"
case "$line" in "omma $version: 24 cameras"*) ;; *) echo "unexpected output"; exit 1 ;; esac
