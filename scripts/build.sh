#!/usr/bin/env bash
# Configures and builds omma (Release) in ./build. Extra arguments go to `cmake --build`.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
[ -f build/CMakeCache.txt ] || cmake -S . -B build "${gen[@]}" -DCMAKE_BUILD_TYPE=Release >&2
cmake --build build -j"$(nproc)" "$@" >&2
