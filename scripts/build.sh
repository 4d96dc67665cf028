#!/usr/bin/env bash
# Configures and builds omma (Release) in ./build. Extra arguments go to `cmake --build`.
# Configures every time (a few seconds): optional parts whose tools were installed since the last
# configure (Verilator for the RTL tests, MPI; CMake options OMMA_RTL / OMMA_MPI = AUTO) are then
# picked up instead of staying off, and CMake warns about each one it skips.
# OMMA_PYTHON=ON|OFF|AUTO: the Python bindings (default AUTO: built when pybind11 is found).
# OMMA_WERROR=ON: compiler warnings in omma's own code are errors (scripts/test.sh sets it under CI).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
args=(-DOMMA_PYTHON="${OMMA_PYTHON:-AUTO}")
[ -n "${OMMA_WERROR:-}" ] && args+=(-DOMMA_WERROR="$OMMA_WERROR")
if [ -f build/CMakeCache.txt ]; then
  cmake -S . -B build "${args[@]}" >&2
else
  gen=()
  command -v ninja >/dev/null && gen=(-G Ninja)
  cmake -S . -B build "${gen[@]}" -DCMAKE_BUILD_TYPE=Release "${args[@]}" >&2
fi
cmake --build build -j"$(nproc)" "$@" >&2
