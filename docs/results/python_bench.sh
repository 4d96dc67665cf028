#!/usr/bin/env bash
# Python's Engine.render against the C++ loop (docs/results/python_bench.md): bench/python_render.py
# with the package built into build/python (scripts/build.sh with pybind11 installed).
#   docs/results/python_bench.sh [ARGS...]      (ARGS go to bench/python_render.py, e.g. --rounds 5)
set -euo pipefail
cd "$(dirname "$0")/../.."
PYTHONPATH=build/python /usr/bin/python3 bench/python_render.py "$@"
