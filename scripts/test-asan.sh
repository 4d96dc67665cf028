#!/usr/bin/env bash
# The sanitizer stage of scripts/test.sh: builds ./build-asan (-O1 -g1 -DNDEBUG: the optimisation
# AddressSanitizer recommends, and line tables, enough for symbolised reports and faster to compile
# than full debug information; -fsanitize=address,undefined, no recovery: the first report fails)
# with only the targets the selected tests need, and runs the tests that scripts/asan-tests.txt
# selects (one CTest regular expression per line; chosen so that the stage fits CI's time). Leak
# detection is on.
set -euo pipefail
cd "$(dirname "$0")/.."
gen=()
command -v ninja >/dev/null && gen=(-G Ninja)
san="-fsanitize=address,undefined -fno-sanitize-recover=all -fno-omit-frame-pointer"
[ -f build-asan/CMakeCache.txt ] || cmake -S . -B build-asan "${gen[@]}" -DCMAKE_BUILD_TYPE=None \
  -DOMMA_BUILD_BENCH=OFF -DOMMA_PYTHON=OFF -DCMAKE_CXX_FLAGS="-O1 -g1 -DNDEBUG $san" -DCMAKE_EXE_LINKER_FLAGS="$san" >&2
regex=$(grep -v '^#' scripts/asan-tests.txt | grep -v '^$' | paste -sd'|')
targets=$(grep '^# targets:' scripts/asan-tests.txt | cut -d: -f2)
# shellcheck disable=SC2086
cmake --build build-asan -j"$(nproc)" --target $targets >&2
export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1:detect_stack_use_after_return=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
cd build-asan
ctest --output-on-failure -j"$(nproc)" --timeout 600 -R "$regex"
