#!/usr/bin/env bash
# Install what is missing, check the formatting, build everything, run the whole test suite with
# CTest; then the sanitizer stage: a second build (./build-asan, AddressSanitizer + UndefinedBehaviorSanitizer,
# every report fatal) of the library stages and the tests listed in scripts/asan-tests.txt, run
# with CTest. OMMA_SANITIZE=0 skips the sanitizer stage. Extra arguments go to the first ctest.
# The build configures every time (scripts/build.sh), so tools installed above since an earlier
# configure (Verilator: the RTL tests) are used, never silently skipped.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --test
scripts/format.sh --check  # every C++ file as .clang-format says (scripts/format.sh fixes it)
# Under CI, compiler warnings in omma's own code fail the build (CMake OMMA_WERROR).
[ "${CI:-}" = true ] && export OMMA_WERROR="${OMMA_WERROR:-ON}"
OMMA_PYTHON=ON scripts/build.sh  # the tests include the Python bindings' (python/tests)
(cd build && ctest --output-on-failure -j"$(nproc)" --timeout 600 "$@")
[ "${OMMA_SANITIZE:-1}" = 0 ] && exit 0
scripts/test-asan.sh
