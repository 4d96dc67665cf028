#!/usr/bin/env bash
# Install what is missing, build everything, run the whole test suite with CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
OMMA_PYTHON=ON scripts/build.sh  # the tests include the Python bindings' (python/tests)
cd build
ctest --output-on-failure -j"$(nproc)" --timeout 600 "$@"
