#!/usr/bin/env bash
# Configures and builds omma (Release) in ./build. Extra arguments go to `cmake --build`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
# OMMA_PYTHON=ON|OFF|AUTO: the Python bindings (default AUTO: built when pybind11 is found).
[ -f build/CMakeCache.txt ] || cmake -S . -B build "${gen[@]}" -DCMAKE_BUILD_TYPE=Release \
  -DOMMA_PYTHON="${OMMA_PYTHON:-AUTO}" >&2
cmake --build build -j"$(nproc)" "$@" >&2
