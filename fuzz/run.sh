#!/usr/bin/env bash
# Builds the libFuzzer targets with Debian's clang (ASan + UBSan) and runs each for a fixed number
# of executions. Separate from the CMake build; not part of scripts/test.sh's default run.
#   fuzz/run.sh [RUNS] [TARGET...]   (default 2000000 executions; targets: link rig pto map recording)
# Targets: link (sensor-link decoder), rig (rig JSON parser), pto (Hugin PTO importer), map
# (compiled-map loader), recording (recording reader: a manifest or an HDF5 stream). The map target's
# seeds come from build/omma (scripts/build.sh) if present; the recording target writes its own.
# -timeout=60: a wall-clock limit per input; on the loaded shared 2-core machine a 0.1 s input once
# took more than 10 s.
# Exit status is non-zero if a fuzzer finds a crash (the reproducer is left in build-fuzz/TARGET/).
set -euo pipefail
cd "$(dirname "$0")/.."
runs="${1:-2000000}"
shift || true
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(link rig pto map recording)
cxx="${CXX_FUZZ:-clang++}"
root=$PWD
out=build-fuzz
flags=(-std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined -Isrc
       -isystem /usr/include/eigen3 -isystem /usr/include/opencv4)
core=(src/omma/core/{rig,camera,geometry,io,limits,frames,checksum,photometric}.cc)
libs=(-lfmt -lopencv_core -lopencv_imgproc -lopencv_imgcodecs -lz -lxxhash)
mkdir -p "$out"

seed_link() {
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
  "$out/make_seed" "$1"
}

seed_rig() {
  cat > "$1/seed_rig.json" <<'JSON'
{"format": "omma-rig", "version": 1, "name": "two", "dome": {"radius_mm": 5, "sphere": false, "method": "x"},
 "cameras": [
  {"id": 0, "t": [0,0,1], "u": [0,1,0], "v": [-1,0,0], "position_mm": [0,0,5],
   "intrinsics": {"width": 250, "height": 250, "fu": 200, "fv": 200, "cu": 125, "cv": 125, "k": [0.01,-0.002,0,0,0], "aov_deg": 64}},
  {"id": 1, "ypr_deg": [40, 60, 10], "position_mm": [1,2,4],
   "intrinsics": {"width": 320, "height": 240, "fu": 250, "fv": 251, "cu": 160, "cv": 120, "aov_deg": 70}}]}
JSON
}

seed_pto() {
  cat > "$1/seed.pto" <<'PTO'
# hugin project file written by omma
#-omma rig name "two" radius_mm 5 sphere 0 cameras 2
p f2 w1440 h720 v360 E0 R0 S0,1440,0,360 n"PNG"
m g1 i0 f0 m2 p0.00784314
#-omma camera id 0 position_mm 0 0 5 aov_deg 64 fv_over_fu 1 k 0.01 -0.002 0 0 0 f 200
i w250 h250 f0 v64.01 Ra0 Rb0 Rc0 Rd0 Re0 Eev0 Er1 Eb1 r0 p90 y0 TrX0 TrY0 TrZ0 j0 a0 b-0.01 c0 d0 e0 g0 t0 Va1 Vb0 Vc0 Vd0 Vx0 Vy0 Vm5 n"cam_00.png"
i w320 h240 f0 v=0 r10 p60 y40 a=0 b0.002 c=0 d1.5 e-2 n"cam_01.png"
v y1 p1 r1
c n0 N1 x10 y20 X30 Y40 t0
PTO
}

seed_map() {
  [ -x build/omma ] || { echo "fuzz: build/omma missing (scripts/build.sh): map target without seeds" >&2; return; }
  local tmp
  tmp=$(mktemp -d)
  build/omma design --method max-volume --aov 64 --r-phys 5 --cam-size 1x1x2 --out "$tmp/rig.json" >/dev/null 2>&1
  for m in mrf sad nn; do
    build/omma run --rig "$tmp/rig.json" --source "pano:../shared/data/lake.jpg" --frames 1 --size 66x34 \
      --method "$m" --cache "$tmp/cache-$m" --sink "png:$tmp/out-$m" >/dev/null 2>&1 || true
    for f in "$tmp/cache-$m"/omma-map-*.bin; do
      [ -f "$f" ] && head -c $(( $(stat -c %s "$f") - 4 )) "$f" > "$1/seed_$m"  # without the CRC
    done
  done
  rm -rf "$tmp"
}

# The recording target writes its seeds itself (from one valid recording, one seed per mode).
seed_recording() { RECORDING_FUZZ_SEEDS="$1" "$out/recording/recording_fuzz"; }

rc_all=0
for t in "${targets[@]}"; do
  dir="$out/$t"
  mkdir -p "$dir/corpus"
  extra=()
  lsan=""
  case "$t" in
    link) srcs=(src/omma/isp/link.cc); max_len=4096 ;;
    rig) srcs=("${core[@]}"); max_len=4096 ;;
    pto) srcs=(src/omma/calib/pto.cc "${core[@]}"); max_len=1024 ;;  # a few image lines: each is a lens fit
    map) srcs=(src/omma/render/map_file.cc "${core[@]}"); max_len=131072 ;;
    # A stream of the seed recording is about 70 kB (two 4096-entry chunks of seq and t_ns).
    # HDF5 itself leaks a few hundred bytes on some damaged files (also with every id closed and
    # H5close): leaks inside libhdf5 are suppressed; the target checks that no HDF5 object stays open.
    recording) srcs=(src/omma/io/recording.cc "${core[@]}"); extra=($(pkg-config --cflags --libs hdf5)); max_len=131072
      printf 'leak:libhdf5_serial.so\n' > "$dir/lsan.supp"; lsan="suppressions=$root/$dir/lsan.supp" ;;
    *) echo "fuzz: unknown target $t" >&2; exit 2 ;;
  esac
  echo "fuzz: building $t" >&2
  "$cxx" "${flags[@]}" "fuzz/${t}_fuzz.cc" "${srcs[@]}" "${extra[@]}" "${libs[@]}" -o "$dir/${t}_fuzz"
  [ -n "$(ls -A "$dir/corpus")" ] || "seed_$t" "$dir/corpus"
  cd "$dir"
  set +e
  LSAN_OPTIONS="$lsan" "./${t}_fuzz" -runs="$runs" -max_len=$max_len -timeout=60 -rss_limit_mb=4096 -print_final_stats=1 corpus \
    > fuzz.log 2>&1
  rc=$?
  set -e
  grep -E "Done [0-9]+ runs|^stat::number_of_executed_units|ERROR|SUMMARY|crash-|timeout-" fuzz.log | tail -6
  crashes=$( (ls crash-* leak-* timeout-* oom-* 2>/dev/null || true) | wc -l)
  echo "fuzz $t: exit status $rc, executions requested $runs, crash/leak/timeout/oom files: $crashes (log: $dir/fuzz.log)"
  [ $rc -eq 0 ] || rc_all=$rc
  cd "$root"
done
exit $rc_all
