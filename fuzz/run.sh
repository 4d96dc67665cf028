#!/usr/bin/env bash
# Builds the libFuzzer target for the link decoder with Debian's clang (ASan + UBSan) and runs it
# for a fixed number of executions. Separate from the CMake build; not part of scripts/test.sh.
#   fuzz/run.sh [RUNS]      (default 2000000 executions)
# Exit status is non-zero if the fuzzer finds a crash (the reproducer is left in build-fuzz/).
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-2000000}"
cxx="${CXX_FUZZ:-clang++}"
out=build-fuzz
mkdir -p "$out/corpus"
"$cxx" -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
  -Isrc fuzz/link_fuzz.cc src/omma/isp/link.cc -o "$out/link_fuzz"
# Seed corpus: a valid small stream (first byte 0x00 = 1x1 frames, 4-bit pixels).
if [ ! -s "$out/corpus/seed_valid" ]; then
  "$cxx" -std=c++20 -O1 -Isrc -x c++ - src/omma/isp/link.cc -o "$out/make_seed" <<'SRC'
#include <cstdio>
#include "omma/isp/link.h"
int main(int argc, char** argv) {
  for (int sel : {0, 0x2f, 0x77}) {
    omma::isp::LinkConfig c;
    c.width = 1 + (sel & 7); c.height = 1 + ((sel >> 3) & 3); c.bits = 4 + ((sel >> 5) & 3) * 2;
    c.row_gap_pp = 3; c.eof_pp = 2; c.config_pp = 2; c.resync_pp = 8;
    omma::isp::LinkFrame f; f.width = c.width; f.height = c.height;
    for (int i = 0; i < c.width * c.height; ++i) f.pixels.push_back(uint16_t((i * 7 + 3) % (1 << c.bits)));
    auto s = omma::isp::encode_link({f, f}, c);
    char name[256]; std::snprintf(name, sizeof name, "%s/seed_%02x", argv[1], sel);
    FILE* o = std::fopen(name, "wb"); std::fputc(sel, o);
    std::fwrite(s.bytes.data(), 1, s.bytes.size(), o); std::fclose(o);
  }
}
SRC
  "$out/make_seed" "$out/corpus"
  touch "$out/corpus/seed_valid"
fi
cd "$out"
set +e
./link_fuzz -runs="$runs" -max_len=4096 -timeout=10 -print_final_stats=1 corpus > fuzz.log 2>&1
rc=$?
set -e
grep -E "^#[0-9]+ +(DONE|pulse)|Done [0-9]+ runs|^stat::|ERROR|SUMMARY|crash-|timeout-" fuzz.log | tail -12
crashes=$(ls crash-* leak-* timeout-* oom-* 2>/dev/null | wc -l)
echo "fuzz: exit status $rc, executions requested $runs, crash/leak/timeout/oom files: $crashes (log: $out/fuzz.log)"
exit $rc
